//! Property tests: the message decoder never panics on random or hostile input (random
//! bytes, every message type with any field names and arbitrary nested JSON values), every
//! message it accepts is valid and re-encodes to a message it accepts again, every refusal
//! is an error with a message; and a session handles any accepted message, plausible or
//! extreme, with a reply or a refusal, never a panic, its timeline keeping its first snapshot.

mod common;

use proptest::prelude::*;
use serde_json::Value;
use snowscape_editor::Session;
use snowscape_editor::protocol::{ClientMessage, MAX_MESSAGE_BYTES, decode};
use std::sync::{Mutex, OnceLock};

const TYPES: &[&str] = &[
    "brush",
    "undo",
    "redo",
    "step",
    "seek",
    "trigger_avalanche",
    "launch_skier",
    "set_scenario",
    "save",
    "load",
    "export",
    "probe",
    "resync",
    "cancel",
    "nope",
    "",
];

fn hostile_value() -> impl Strategy<Value = serde_json::Value> {
    prop_oneof![
        Just(serde_json::json!(null)),
        Just(serde_json::json!(1e308)),
        Just(serde_json::json!(-1e308)),
        Just(serde_json::json!(-1)),
        Just(serde_json::json!(u64::MAX)),
        Just(serde_json::json!("../../etc/passwd")),
        Just(serde_json::json!("/abs")),
        Just(serde_json::json!([1, 2, 3])),
        Just(serde_json::json!({"type": "undo"})),
        any::<f64>().prop_map(|f| serde_json::json!(f)),
        any::<i64>().prop_map(|i| serde_json::json!(i)),
        ".{0,40}".prop_map(|s| serde_json::json!(s)),
    ]
}

fn hostile_object() -> impl Strategy<Value = Vec<u8>> {
    (
        proptest::sample::select(TYPES),
        proptest::collection::vec(
            (
                proptest::sample::select(
                    &[
                        "stroke", "op", "target", "col", "row", "radius_m", "strength", "value",
                        "days", "index", "name", "scenario", "extra",
                    ][..],
                ),
                hostile_value(),
            ),
            0..8,
        ),
    )
        .prop_map(|(t, fields)| {
            let mut m = serde_json::Map::new();
            m.insert("type".into(), serde_json::json!(t));
            for (k, v) in fields {
                m.insert(k.to_string(), v);
            }
            serde_json::to_vec(&m).unwrap_or_default()
        })
}

/// The field names of every message type, and some others.
const FIELDS: &[&str] = &[
    "type", "stroke", "op", "target", "col", "row", "radius_m", "strength", "value", "days",
    "index", "name", "scenario", "extra", "",
];

/// Any JSON value, nested a few levels.
fn arbitrary_json() -> impl Strategy<Value = Value> {
    let leaf = prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::from),
        any::<f64>().prop_map(|f| serde_json::json!(f)),
        any::<i64>().prop_map(Value::from),
        any::<u64>().prop_map(Value::from),
        ".{0,12}".prop_map(Value::from),
        proptest::sample::select(&["add", "smooth", "all", "powder", "ski_area", "p1"][..])
            .prop_map(Value::from),
    ];
    leaf.prop_recursive(4, 48, 6, |inner| {
        prop_oneof![
            proptest::collection::vec(inner.clone(), 0..6).prop_map(Value::Array),
            proptest::collection::btree_map(
                prop_oneof![
                    proptest::sample::select(FIELDS).prop_map(String::from),
                    ".{0,8}"
                ],
                inner,
                0..6
            )
            .prop_map(|m| Value::Object(m.into_iter().collect())),
        ]
    })
}

/// Every message type with any fields holding any values.
fn arbitrary_message() -> impl Strategy<Value = Vec<u8>> {
    (
        proptest::sample::select(TYPES),
        proptest::collection::vec(
            (
                prop_oneof![
                    proptest::sample::select(FIELDS).prop_map(String::from),
                    ".{0,8}"
                ],
                arbitrary_json(),
            ),
            0..9,
        ),
    )
        .prop_map(|(t, fields)| {
            let mut m = serde_json::Map::new();
            for (k, v) in fields {
                m.insert(k, v);
            }
            m.insert("type".into(), Value::from(t));
            serde_json::to_vec(&m).unwrap_or_default()
        })
}

/// Decodes `bytes`: an accepted message is valid and survives a round trip; a refusal is an
/// error with a message. Returns the accepted message.
fn check(bytes: &[u8]) -> Option<ClientMessage> {
    match decode(bytes, MAX_MESSAGE_BYTES) {
        Ok(msg) => {
            assert!(msg.validate().is_ok(), "{msg:?}");
            let again = serde_json::to_vec(&msg).expect("accepted messages encode");
            let back: ClientMessage = decode(&again, MAX_MESSAGE_BYTES).expect("and decode again");
            assert_eq!(back, msg);
            Some(msg)
        }
        Err(e) => {
            assert!(!e.to_string().is_empty());
            let _ = e.code();
            None
        }
    }
}

/// A message of each type with plausible or extreme values (many accepted).
fn plausible_message() -> impl Strategy<Value = Value> {
    let pos = prop_oneof![0.0..130.0f64, -5.0..0.0f64, Just(1e6), Just(127.4)];
    let name = prop_oneof![
        Just("p1".to_string()),
        "[a-z_-]{1,10}",
        Just("../x".to_string())
    ];
    let scenario = prop_oneof![
        Just(serde_json::json!({"days": 2.0, "seed": 5})),
        Just(serde_json::json!({"days": 2.0, "parameters": []})),
        Just(serde_json::json!([])),
        arbitrary_json(),
    ];
    (
        0usize..15,
        (pos.clone(), pos),
        (0.1..2000.0f64, 0.0..3.0f64, 0.0..2.0f64),
        (0.01..3.0f64, 0usize..6, any::<u32>()),
        (name, scenario),
        (
            proptest::sample::select(&["add", "remove", "smooth", "set"][..]),
            proptest::sample::select(
                &["all", "compacted", "stable", "unstable", "powder", "avalanche_probability", "ski_area"][..],
            ),
        ),
    )
        .prop_map(
            |(kind, (col, row), (radius_m, strength, value), (days, index, stroke), (name, scenario), (op, target))| {
                use serde_json::json;
                match kind {
                    0..=3 => json!({"type": "brush", "stroke": stroke % 4, "op": op, "target": target, "col": col, "row": row, "radius_m": radius_m, "strength": strength, "value": value}),
                    4 => json!({"type": "undo"}),
                    5 => json!({"type": "redo"}),
                    6 => json!({"type": "step", "days": days}),
                    7 => json!({"type": "seek", "index": index}),
                    8 => json!({"type": "trigger_avalanche", "col": col, "row": row}),
                    9 => json!({"type": "launch_skier", "col": col, "row": row}),
                    10 => json!({"type": "set_scenario", "scenario": scenario}),
                    11 => json!({"type": (["save", "load", "export"][index % 3]), "name": name}),
                    12 => json!({"type": "probe", "col": col as usize, "row": row as usize}),
                    13 => json!({"type": "cancel"}),
                    _ => json!({"type": "resync"}),
                }
            },
        )
}

/// One session shared by the cases (a 128² terrain, a 3-day season).
fn shared_session() -> &'static Mutex<Session> {
    static S: OnceLock<Mutex<Session>> = OnceLock::new();
    S.get_or_init(|| Mutex::new(common::session(128, 3.0)))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        check(&bytes);
    }

    #[test]
    fn hostile_objects_never_panic(bytes in hostile_object()) {
        check(&bytes);
    }

    #[test]
    fn every_type_with_arbitrary_fields_is_decoded_or_refused(bytes in arbitrary_message()) {
        check(&bytes);
    }

    #[test]
    fn truncated_and_nested_input_never_panics(cut in 0usize..200, depth in 0usize..2000) {
        let good = br#"{"type":"brush","stroke":1,"op":"add","target":"all","col":1,"row":2,"radius_m":30,"strength":0.5}"#;
        check(&good[..cut.min(good.len())]);
        let nested = format!("{}{}", "[".repeat(depth), "]".repeat(depth));
        check(nested.as_bytes());
    }
}

#[test]
fn oversized_messages_are_refused_before_parsing() {
    let big = vec![b'{'; MAX_MESSAGE_BYTES + 1];
    let e = decode(&big, MAX_MESSAGE_BYTES).unwrap_err();
    assert!(e.to_string().contains("larger than the limit"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(150))]

    #[test]
    fn a_session_answers_any_accepted_message(msg in plausible_message()) {
        let bytes = serde_json::to_vec(&msg).unwrap_or_default();
        if let Some(m) = check(&bytes) {
            let mut s = shared_session().lock().unwrap_or_else(|e| e.into_inner());
            let _ = s.handle(m, None, None);
            if s.live() {
                let _ = s.run_live_to_end();
            }
            let st = s.summary();
            prop_assert!(!st.busy);
            prop_assert!(!st.snapshots.is_empty() && st.current < st.snapshots.len());
            prop_assert_eq!(st.snapshots[0], 0.0);
        }
    }
}
