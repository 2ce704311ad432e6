//! Wind redistribution at the scale of a range (issue 47): a ridge under a westerly.
//! With the two-scale sheltering index (100 m and 1 km searches), the scour of settled snow and
//! the sublimation of the drifting snow, the exposed crest ends with less snow than its lee
//! slope and less than with the 100 m search alone, lossless and on loose snow only (the
//! redistribution before issue 47); the budget closes with the sublimation as its own term,
//! and the result is the same on one and two threads.

use snowscape_environment::{ShelteringParams, WindParams, sheltering_index, wind};
use snowscape_season::wind_transport::{
    self, DriftSublimationParams, SxParams, WindMaps, WindScratch, WindTransportParams,
};
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, SnowLayer};

/// Columns and rows of 10 m cells: 3 km west-east, 600 m north-south.
const W: usize = 300;
const H: usize = 60;
/// The crest's column.
const CREST: usize = 150;

/// A ridge 400 m high with 26.6° flanks (1:2) and a sharp crest, 1.6 km wide at its foot,
/// uniform north-south, with 0.4 m of stable snow and 0.1 m of powder everywhere.
fn massif() -> LayeredTerrain {
    let geo = GridGeometry::square(W, H, 10.0).unwrap();
    let bed = Grid::from_fn(geo, |c, _| {
        let x = (c as f32 - CREST as f32) * 10.0;
        1500.0 + 400.0 * (1.0 - x.abs() / 800.0).max(0.0)
    });
    let mut t = LayeredTerrain::from_bedrock(bed);
    t.layer_mut(SnowLayer::Stable).fill(0.4);
    t.layer_mut(SnowLayer::Powder).fill(0.1);
    t
}

/// Mean depth of columns `cols` over the middle rows.
fn depth(t: &LayeredTerrain, cols: std::ops::Range<usize>) -> f64 {
    let rows = 20..40;
    let n = (cols.len() * rows.len()) as f64;
    rows.flat_map(|r| cols.clone().map(move |c| r * W + c))
        .map(|i| f64::from(t.depth_at(i)))
        .sum::<f64>()
        / n
}

/// What ten days of westerly left.
struct Outcome {
    terrain: LayeredTerrain,
    sublimated: f64,
    outflow: f64,
}

/// Ten days of a 10 m/s westerly at −8 °C (twenty half-day steps) with `sheltering` and `sx`.
fn blow(sheltering: &ShelteringParams, sx: SxParams) -> Outcome {
    let mut t = massif();
    let (geo, mask) = (t.geometry().clone(), t.mask().clone());
    let maps = wind(&t.bedrock, &geo, &mask, &WindParams::default()).unwrap();
    let index = sheltering_index(&t.bedrock, &geo, &mask, 270.0, sheltering).unwrap();
    let air = vec![-8.0f32; geo.len()];
    let m = WindMaps {
        u: &maps.u,
        v: &maps.v,
        shadow: &maps.shadow,
        effect_surface: &maps.effect_surface,
        sx: Some(&index),
        terms: None,
        air_temperature: Some(&air),
    };
    let p = WindTransportParams {
        sx_redistribution: sx,
        ..Default::default()
    };
    let before = t.snow_volume();
    let mut scratch = WindScratch::default();
    let (mut sublimated, mut outflow) = (0.0, 0.0);
    for _ in 0..20 {
        let r = wind_transport::step(&p, &mut t, &m, &mut scratch, 0.5).unwrap();
        let moved = r.eroded - r.deposited - r.border_outflow - r.sublimated;
        assert!(moved.abs() <= 1e-6 * before, "{r:?}");
        sublimated += r.sublimated;
        outflow += r.border_outflow;
    }
    t.check_invariants().unwrap();
    let closure = before - outflow - sublimated - t.snow_volume();
    assert!(
        closure.abs() <= 1e-5 * before,
        "closure {closure} of {before}"
    );
    Outcome {
        terrain: t,
        sublimated,
        outflow,
    }
}

/// The redistribution before issue 47: the 100 m search alone, loose snow only, lossless,
/// drift settling on exposed ground too.
fn before_issue_47() -> (ShelteringParams, SxParams) {
    (
        ShelteringParams {
            long_range_weight: 0.0,
            ..Default::default()
        },
        SxParams {
            erode_stable: false,
            sublimation: DriftSublimationParams {
                enabled: false,
                ..Default::default()
            },
            deposit_on_exposed: true,
            ..Default::default()
        },
    )
}

#[test]
fn the_exposed_crest_ends_with_less_snow_than_its_lee_and_than_before() {
    let now = blow(&ShelteringParams::default(), SxParams::default());
    let (old_sheltering, old_sx) = before_issue_47();
    let old = blow(&old_sheltering, old_sx);
    let crest = CREST - 3..CREST + 1;
    let lee = CREST + 20..CREST + 50;
    let (crest_now, lee_now) = (depth(&now.terrain, crest.clone()), depth(&now.terrain, lee));
    let crest_old = depth(&old.terrain, crest);
    // Measured (10 days of 10 m/s at −8 °C): crest 0.087 m (0.437 m before issue 47), lee
    // slope 0.500 m, 35 800 m³ sublimated.
    eprintln!(
        "crest {crest_now:.3} m (before issue 47: {crest_old:.3} m), lee {lee_now:.3} m; \
         sublimated {:.0} m³, border outflow {:.0} m³",
        now.sublimated, now.outflow
    );
    assert!(
        crest_now < 0.5 * lee_now,
        "crest {crest_now} m, lee slope {lee_now} m"
    );
    assert!(
        crest_now < crest_old - 0.1,
        "crest {crest_now} m against {crest_old} m before"
    );
    // The drifting snow sublimates; before, nothing did.
    assert!(now.sublimated > 0.0 && old.sublimated == 0.0);
}

#[test]
fn saturated_air_sublimates_nothing_and_the_same_on_one_and_two_threads() {
    let wet = SxParams {
        sublimation: DriftSublimationParams {
            relative_humidity_pct: Some(100.0),
            ..Default::default()
        },
        ..Default::default()
    };
    assert_eq!(blow(&ShelteringParams::default(), wet).sublimated, 0.0);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| blow(&ShelteringParams::default(), SxParams::default()))
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.terrain, b.terrain);
    assert_eq!(a.sublimated.to_bits(), b.sublimated.to_bits());
}
