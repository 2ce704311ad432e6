//! Whole-season tests: budget closure, determinism across thread counts, checkpoint/resume
//! bit-identical to an uninterrupted run, and snow that follows altitude.

use snowscape_season::scenario::Scenario;
use snowscape_season::scheduler::EventKind;
use snowscape_season::winter::Winter;
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain};

/// A 96x96 terrain of 20 m cells: a mountain rising from 600 m to 2600 m, with a ridge.
fn mountain() -> LayeredTerrain {
    let n = 96;
    let g = GridGeometry::square(n, n, 20.0).unwrap();
    LayeredTerrain::from_bedrock(Grid::from_fn(g, |c, r| {
        let (x, y) = (c as f32 / n as f32 - 0.5, r as f32 / n as f32 - 0.5);
        let d = (x * x + y * y).sqrt();
        let ridge = (-(x * 8.0).powi(2)).exp() * 300.0;
        600.0 + 2000.0 * (1.0 - 2.0 * d).max(0.0).powf(1.5) + ridge
    }))
}

fn scenario(days: f64) -> Scenario {
    let mut s = Scenario {
        days,
        ..Scenario::default()
    };
    s.parameters.environment.sky.directions = 8;
    s.parameters.environment.sun.day_step = 30;
    // The cone's upper flanks are steeper than 60°: slope shedding would carry their snow to
    // the foot, which is not what the altitude test below is about (realism.rs tests it).
    s.parameters.slope_shedding.enabled = false;
    s
}

fn run(days: f64, threads: usize) -> Winter {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut w = Winter::new(scenario(days), mountain()).unwrap();
        w.run_until(days).unwrap();
        w
    })
}

#[test]
fn budget_closes_and_snow_follows_altitude() {
    let w = run(60.0, 2);
    let b = w.budget();
    let store = w.terrain.snow_volume();
    let rel = (store - b.expected_store()).abs() / b.snowfall.max(1.0);
    assert!(b.snowfall > 0.0);
    // The drifting snow of the Sx redistribution sublimates (its own budget term, issue 47).
    assert!(b.wind_sublimation > 0.0, "{b:?}");
    assert!(
        rel < 1e-5,
        "closure error {rel}: store {store}, budget {b:?}"
    );
    w.terrain.check_invariants().unwrap();
    let counts = w.event_counts();
    assert!(counts[&EventKind::WindTransportStep] > 60);
    assert!(counts[&EventKind::MeltAndStateStep] > 60);
    // Deeper up high: mean depth of the top quarter of altitudes beats the bottom quarter.
    let depth = w.terrain.total_depth();
    let mut idx: Vec<usize> = (0..depth.len()).collect();
    idx.sort_by(|&a, &b| w.terrain.bedrock[a].total_cmp(&w.terrain.bedrock[b]));
    let q = idx.len() / 4;
    let mean = |s: &[usize]| s.iter().map(|&i| depth[i] as f64).sum::<f64>() / s.len() as f64;
    let (low, high) = (mean(&idx[..q]), mean(&idx[idx.len() - q..]));
    assert!(high > 2.0 * low + 0.05, "high {high} low {low}");
}

/// The drifting snow sublimates in the climate's air (issue 47): saturated fair and storm
/// air sublimates none of it, drier fair air more, and a set humidity overrides the climate.
#[test]
fn drifting_snow_sublimates_in_the_climates_air() {
    let with = |fair: f64, storm: f64, set: Option<f64>| {
        let mut s = scenario(30.0);
        s.parameters.climate.fair_relative_humidity = fair;
        s.parameters.climate.storm_relative_humidity = storm;
        s.parameters
            .wind_transport
            .sx_redistribution
            .sublimation
            .relative_humidity_pct = set;
        let mut w = Winter::new(s, mountain()).unwrap();
        w.run_until(30.0).unwrap();
        w.budget().wind_sublimation
    };
    let saturated = with(1.0, 1.0, None);
    let (moist, dry) = (with(0.8, 0.9, None), with(0.4, 0.9, None));
    assert!(saturated == 0.0, "saturated air sublimated {saturated}");
    assert!(dry > 1.2 * moist && moist > 0.0, "dry {dry} moist {moist}");
    // A humidity set for the drift replaces the climate's saturated air.
    let set = with(1.0, 1.0, Some(40.0));
    assert!(set > 0.0, "a set 40 % sublimated {set}");
}

#[test]
fn bit_identical_for_any_thread_count() {
    let a = run(20.0, 1);
    for threads in [2, 4] {
        let b = run(20.0, threads);
        assert_eq!(a.terrain, b.terrain, "{threads} threads differ from 1");
        assert_eq!(a.budget(), b.budget());
        assert_eq!(a.altitude_bands(), b.altitude_bands());
    }
}

#[test]
fn resumed_run_ends_bit_identical() {
    let full = run(30.0, 2);
    let mut first = Winter::new(scenario(30.0), mountain()).unwrap();
    first.run_until(12.0).unwrap();
    let mut bytes = Vec::new();
    first.write_checkpoint(&mut bytes).unwrap();
    drop(first);
    let mut resumed = Winter::resume(scenario(30.0), mountain(), &mut bytes.as_slice()).unwrap();
    resumed.run_until(30.0).unwrap();
    assert_eq!(resumed.terrain, full.terrain);
    assert_eq!(resumed.budget(), full.budget());
    assert_eq!(resumed.event_counts(), full.event_counts());
    assert_eq!(resumed.altitude_bands(), full.altitude_bands());
    // A checkpoint of another scenario is refused.
    let mut other = scenario(30.0);
    other.seed = 99;
    assert!(Winter::resume(other, mountain(), &mut bytes.as_slice()).is_err());
}

/// The mountain under 0.5 m of settled snow.
fn snowy_mountain() -> LayeredTerrain {
    let mut t = mountain();
    t.layer_mut(snowscape_terrain::SnowLayer::Stable).fill(0.5);
    t
}

/// The scenario with slope shedding on (the cone's flanks steeper than 60° shed), once per
/// `interval_days`.
fn shedding_scenario(days: f64, interval_days: f64) -> Scenario {
    let mut s = scenario(days);
    s.parameters.slope_shedding.enabled = true;
    s.parameters.slope_shedding.interval_days = interval_days;
    s
}

#[test]
fn slope_shedding_runs_at_most_once_per_interval_and_resumes_bit_identical() {
    // An interval longer than the run: the first melt-and-state event sheds, no later one.
    let mut w = Winter::new(shedding_scenario(20.0, 30.0), snowy_mountain()).unwrap();
    w.run_until(2.0).unwrap();
    let first = w.budget().shedding_moved;
    assert!(first > 0.0, "the first step sheds the flanks' snow");
    w.run_until(20.0).unwrap();
    assert_eq!(w.budget().shedding_moved, first);
    // Daily: later snowfall sheds too.
    let mut daily = Winter::new(shedding_scenario(20.0, 1.0), snowy_mountain()).unwrap();
    daily.run_until(20.0).unwrap();
    assert!(daily.budget().shedding_moved > first);
    // A checkpoint in the middle of an interval restores the shedding clock.
    let mut part = Winter::new(shedding_scenario(20.0, 1.0), snowy_mountain()).unwrap();
    part.run_until(7.3).unwrap();
    let mut bytes = Vec::new();
    part.write_checkpoint(&mut bytes).unwrap();
    let mut resumed = Winter::resume(
        shedding_scenario(20.0, 1.0),
        snowy_mountain(),
        &mut bytes.as_slice(),
    )
    .unwrap();
    resumed.run_until(20.0).unwrap();
    assert_eq!(resumed.terrain, daily.terrain);
    assert_eq!(resumed.budget(), daily.budget());
}
