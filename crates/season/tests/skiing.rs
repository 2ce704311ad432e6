//! Skiers inside the season: runs, compaction in the budget, tracks, fading under snowfall,
//! skier-triggered avalanches.

use snowscape_season::scenario::Scenario;
use snowscape_season::winter::Winter;
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, SnowLayer};

/// 80 x 160 cells of 5 m: a 38° slope (rows 0..100) onto flat ground, with 1 m of stable snow
/// and `unstable` m of unstable snow everywhere.
fn snowy_slope(unstable: f32) -> LayeredTerrain {
    let g = GridGeometry::square(80, 160, 5.0).unwrap();
    let tan = 38f32.to_radians().tan();
    let mut t = LayeredTerrain::from_bedrock(Grid::from_fn(g, |c, r| {
        1500.0 + tan * 5.0 * (100.0 - r as f32).max(0.0) + 0.5 * (c as f32 - 40.0).abs()
    }));
    t.layer_mut(SnowLayer::Stable).fill(1.0);
    t.layer_mut(SnowLayer::Unstable).fill(unstable);
    t
}

fn scenario(days: f64, per_day: f64) -> Scenario {
    let mut s = Scenario {
        days,
        ..Scenario::default()
    };
    s.parameters.environment.sky.directions = 8;
    s.parameters.environment.sun.day_step = 30;
    s.parameters.avalanche.natural = false;
    s.skiers.per_day = per_day;
    s
}

#[test]
fn skiers_ski_compact_and_leave_tracks_and_the_budget_closes() {
    let mut w = Winter::new(scenario(1.0, 48.0), snowy_slope(0.0)).unwrap();
    w.run_until(1.0).unwrap();
    let st = w.ski_stats().clone();
    eprintln!("{st:?}");
    assert!(st.runs >= 30, "{st:?}");
    assert!(st.finished >= st.runs / 2, "{st:?}");
    assert!(st.distance_m > 100.0 * st.runs as f64, "{st:?}");
    let compacted: f32 = w.terrain.layer(SnowLayer::Compacted).iter().sum();
    assert!(compacted > 0.0, "no compaction");
    let area = w.ski_area().expect("ski area");
    assert!(area.texture().texels_per_cell() >= 2);
    assert!(area.tracks().count() > 0);
    let b = w.budget();
    let store = w.terrain.snow_volume();
    assert!(
        (store - b.expected_store()).abs() < 1e-5 * b.initial_store,
        "closure: store {store}, expected {}",
        b.expected_store()
    );
    w.terrain.check_invariants().unwrap();
}

#[test]
fn skiers_on_unstable_snow_trigger_avalanches() {
    let mut s = scenario(1.0, 48.0);
    s.skiers.starts = vec![];
    let mut w = Winter::new(s, snowy_slope(0.6)).unwrap();
    w.run_until(1.0).unwrap();
    let st = w.ski_stats();
    let by_skiers = w
        .avalanches()
        .iter()
        .filter(|a| a.trigger == snowscape_season::avalanches::Trigger::Skier)
        .count();
    eprintln!("{st:?}, {by_skiers} skier avalanches");
    assert!(by_skiers >= 1, "{st:?}");
    assert_eq!(by_skiers as u64, st.avalanches_triggered);
}

#[test]
fn bad_skier_parameters_are_named() {
    let mut s = scenario(1.0, -3.0);
    let e = s.validate("t.toml").unwrap_err().to_string();
    assert!(e.contains("per_day"), "{e}");
    s.skiers.per_day = 1.0;
    s.skiers.starts = vec![[f64::NAN, 1.0]];
    let e = s.validate("t.toml").unwrap_err().to_string();
    assert!(e.contains("starts[0]"), "{e}");
}
