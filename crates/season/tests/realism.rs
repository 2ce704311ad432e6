//! The season on real terrain behaves like snow (issue: "snow that follows the sun, the wind
//! and the slope"): within 200 m elevation bands of avaMal (5 m, 47° N) and of its 50 m
//! resample, after a default winter with a spring period, north faces hold more snow than
//! south faces, faces steeper than 60° shed theirs, and lee slopes load under a westerly wind.

mod support;

use snowscape_season::scenario::Scenario;
use snowscape_season::winter::Winter;
use snowscape_terrain::{Grid, LayeredTerrain};
use support::{band_ratio, block_average, facing, shared_dem, slope_aspect};

/// The default winter from 1 November to 30 April (a spring period with the sun high), no
/// natural avalanches (they are not the phenomenon under test, and cost most of the time).
fn default_winter_on(bedrock: Grid) -> Winter {
    let mut s = Scenario {
        days: 181.0,
        start_date: "11-01".into(),
        ..Scenario::default()
    };
    s.parameters.avalanche.natural = false;
    let mut w = Winter::new(s, LayeredTerrain::from_bedrock(bedrock)).unwrap();
    w.run_until(181.0).unwrap();
    let b = w.budget();
    let store = w.terrain.snow_volume();
    assert!(
        (store - b.expected_store()).abs() <= 1e-5 * (b.initial_store + b.snowfall + b.refreeze),
        "budget: store {store} expected {} ({b:?})",
        b.expected_store()
    );
    assert!(
        b.water.closure_error().abs() <= 1e-5 * (b.water.rain + b.water.melt),
        "{:?}",
        b.water
    );
    w.terrain.check_invariants().unwrap();
    w
}

fn check_aspects(bedrock: Grid, label: &str) {
    let classes = slope_aspect(&bedrock);
    let w = default_winter_on(bedrock.clone());
    let depth = w.terrain.total_depth();
    let (ns, detail) = band_ratio(
        &depth,
        &bedrock,
        &classes,
        |s, a| s > 15.0 && facing(a, 0.0, 45.0),
        |s, a| s > 15.0 && facing(a, 180.0, 45.0),
        10,
    );
    eprintln!("{label}: north/south {ns:.3} {detail:?}");
    assert!(
        ns >= 1.3,
        "{label}: north/south depth ratio {ns} < 1.3: {detail:?}"
    );
}

#[test]
fn north_faces_hold_more_snow_than_south_faces_on_avamal() {
    check_aspects(shared_dem("avaframe_avaMal/avaMal.asc"), "avaMal 5 m");
}

#[test]
fn north_faces_hold_more_snow_than_south_faces_on_avamal_at_50_m() {
    let mal = shared_dem("avaframe_avaMal/avaMal.asc");
    check_aspects(block_average(&mal, 10), "avaMal 50 m");
}
