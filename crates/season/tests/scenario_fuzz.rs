//! Property tests of scenario files (issue 19): any TOML document, built from the default
//! scenario with hostile values put into any of its keys, is either accepted or refused
//! with a message naming the offending key; it never panics, and what is accepted keeps
//! every cost-bounding limit (so no accepted scenario can abort or hang a run).

use proptest::prelude::*;
use snowscape_season::scenario::{MAX_CHECKPOINTS, MAX_SNAPSHOTS, Scenario, ScenarioError};
use snowscape_season::scheduler::MAX_EVENTS_PER_DAY;
use snowscape_season::skiing::MAX_SKIERS_PER_DAY;
use toml::Value;

/// Every leaf of `v`, as (path, value).
fn leaves(prefix: &[String], v: &Value, out: &mut Vec<Vec<String>>) {
    match v {
        Value::Table(t) => {
            for (k, x) in t {
                let mut p = prefix.to_vec();
                p.push(k.clone());
                leaves(&p, x, out);
            }
        }
        _ => out.push(prefix.to_vec()),
    }
}

fn set(doc: &mut Value, path: &[String], value: Value) {
    let mut at = doc;
    for k in &path[..path.len() - 1] {
        at = at
            .as_table_mut()
            .and_then(|t| t.get_mut(k))
            .expect("the path exists");
    }
    if let Some(t) = at.as_table_mut() {
        t.insert(path[path.len() - 1].clone(), value);
    }
}

/// The leaves of the default scenario, plus the array-of-table entries it lacks.
fn default_document() -> (Value, Vec<Vec<String>>) {
    let mut doc = Value::try_from(Scenario::default()).unwrap();
    let extra: Value = toml::from_str(
        r#"
        latitude_deg = 45.0
        station_altitude_m = 1500.0
        [[weather]]
        from_day = 0.0
        sea_level_temperature_c = 5.0
        wind_from_deg = 270.0
        wind_speed_m_s = 10.0
        snowfall_per_week = 1.0
        [[snowfall_period]]
        start_day = 1.0
        days = 2.0
        [[avalanche]]
        day = 2.0
        x = 100.0
        y = 100.0
        "#,
    )
    .unwrap();
    for (k, v) in extra.as_table().unwrap() {
        doc.as_table_mut().unwrap().insert(k.clone(), v.clone());
    }
    let mut paths = Vec::new();
    leaves(&[], &doc, &mut paths);
    (doc, paths)
}

fn hostile_value() -> impl Strategy<Value = Value> {
    prop_oneof![
        prop::sample::select(vec![
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.0,
            -0.0,
            -1.0,
            1e-300,
            1e-9,
            1e9,
            1e20,
            1e308,
            -1e308,
            0.5,
            90.0,
            365.0,
        ])
        .prop_map(Value::Float),
        prop::sample::select(vec![0i64, -1, 1, 2, 1_000_000_000, i64::MAX, i64::MIN])
            .prop_map(Value::Integer),
        any::<f64>().prop_map(Value::Float),
        "[a-z_]{0,8}".prop_map(Value::String),
        any::<bool>().prop_map(Value::Boolean),
        Just(Value::Array(vec![
            Value::Float(f64::NAN),
            Value::Integer(-1)
        ])),
        Just(Value::Array(Vec::new())),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, .. ProptestConfig::default() })]

    #[test]
    fn any_scenario_is_accepted_within_limits_or_refused_naming_a_key(
        picks in prop::collection::vec((any::<prop::sample::Index>(), hostile_value()), 1..5),
        unknown in prop::option::of("[a-z]{1,6}"),
    ) {
        let (mut doc, paths) = default_document();
        let mut keys = Vec::new();
        for (index, value) in picks {
            let path = index.get(&paths).clone();
            keys.push(path.last().unwrap().clone());
            set(&mut doc, &path, value);
        }
        if let Some(k) = &unknown {
            doc.as_table_mut().unwrap().insert(format!("zz_{k}"), Value::Integer(1));
            keys.push(format!("zz_{k}"));
        }
        // A value TOML cannot write (NaN is written as `nan`, which it reads back) is a
        // document no user can produce: skip it.
        let Ok(text) = toml::to_string(&doc) else { return Ok(()); };
        match Scenario::from_toml(&text, "fuzz.toml") {
            Ok(s) => {
                prop_assert!(s.days > 0.0 && s.days <= 3650.0);
                for f in [
                    s.events.snowfall_step,
                    s.events.melt_and_state,
                    s.events.powder_diffusion,
                    s.events.wind_transport,
                ] {
                    prop_assert!((0.0..=MAX_EVENTS_PER_DAY).contains(&f));
                }
                prop_assert!(s.skiers.per_day <= MAX_SKIERS_PER_DAY);
                if s.snapshot_every_days > 0.0 {
                    prop_assert!(s.days / s.snapshot_every_days <= MAX_SNAPSHOTS);
                }
                if s.checkpoint_every_days > 0.0 {
                    prop_assert!(s.days / s.checkpoint_every_days <= MAX_CHECKPOINTS);
                }
                prop_assert!(s.parameters.powder_diffusion.k_m <= 100.0);
                prop_assert!(s.parameters.validate().is_ok());
                // What is accepted survives a round trip through the editor's JSON.
                let json = serde_json::to_value(&s).unwrap();
                let back: Scenario = serde_json::from_value(json).unwrap();
                prop_assert!(back.validate("round trip").is_ok());
            }
            Err(e) => {
                let msg = e.to_string();
                prop_assert!(msg.contains("fuzz.toml"), "{msg}");
                // It names a key: one it was given, or one whose check the change upset
                // (a shorter season puts a listed day outside it).
                let named = keys.iter().any(|k| msg.contains(k.as_str()))
                    || paths.iter().any(|p| msg.contains(p.last().unwrap().as_str()))
                    || matches!(e, ScenarioError::Parse { .. });
                prop_assert!(named, "{msg} names none of {keys:?}");
            }
        }
    }
}
