//! Cornice formation with the real wind precompute (snowscape-environment, Section 4.2)
//! driving wind transport (Section 5.4): a north-south ridge under a westerly wind.

use snowscape_environment::{WindParams, wind};
use snowscape_season::wind_transport::{self, WindMaps, WindScratch, WindTransportParams};
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, SnowLayer};

const W: usize = 64;
const CREST: usize = 32;

fn ridge() -> LayeredTerrain {
    let geo = GridGeometry::square(W, 16, 5.0).unwrap();
    let bed = Grid::from_fn(geo, |c, _| {
        let x = (c as f32 - CREST as f32) * 5.0;
        1000.0 + 40.0 * (-(x / 30.0).powi(2)).exp()
    });
    let mut t = LayeredTerrain::from_bedrock(bed);
    t.layer_mut(SnowLayer::Powder).fill(0.5);
    t
}

/// Mean snow depth of column `c` over the middle rows (away from the north/south borders).
fn column_depth(t: &LayeredTerrain, c: usize) -> f32 {
    (4..12).map(|r| t.depth_at(r * W + c)).sum::<f32>() / 8.0
}

#[test]
fn a_westerly_wind_over_a_ridge_builds_a_cornice_on_its_lee_side() {
    let mut t = ridge();
    let maps = wind(&t.bedrock, t.geometry(), t.mask(), &WindParams::default()).unwrap();
    // The precompute puts the lee of the crest in the wind shadow and the windward side not.
    let raw = maps;
    let shadow_at = |c: usize| raw.shadow[8 * W + c];
    assert_eq!(shadow_at(CREST - 3), 0.0);
    assert!((CREST..CREST + 4).any(|c| shadow_at(c) == 1.0));
    let maps = WindMaps {
        u: &raw.u,
        v: &raw.v,
        shadow: &raw.shadow,
        effect_surface: &raw.effect_surface,
        sx: None,
        terms: None,
        air_temperature: None,
    };
    let before = t.snow_volume();
    let mut scratch = WindScratch::default();
    let mut outflow = 0.0;
    for _ in 0..40 {
        let r = wind_transport::step(
            &WindTransportParams::default(),
            &mut t,
            &maps,
            &mut scratch,
            0.5,
        )
        .unwrap();
        outflow += r.border_outflow;
        t.check_invariants().unwrap();
    }
    assert!((before - outflow - t.snow_volume()).abs() < 1e-5 * before);
    // Windward of the crest the snow is scoured; the deepest snow lies at the top of the lee:
    // the first shadowed cell, at or just past the crest.
    let windward: f32 = (CREST - 4..CREST).map(|c| column_depth(&t, c)).sum::<f32>() / 4.0;
    assert!(
        windward < 0.4,
        "windward {windward}: the crest should lose a fifth of its 0.5 m"
    );
    let deepest = (0..W)
        .max_by(|&a, &b| column_depth(&t, a).total_cmp(&column_depth(&t, b)))
        .unwrap();
    assert!(
        (CREST..=CREST + 3).contains(&deepest),
        "deepest at {deepest}"
    );
    assert!(shadow_at(deepest) == 1.0 && shadow_at(deepest - 1) == 0.0);
    assert!(
        column_depth(&t, deepest) > 1.0,
        "{}",
        column_depth(&t, deepest)
    );
}
