//! Shared test set-up: a small procedural terrain and its season.
#![allow(dead_code)] // each test crate uses some of the helpers

use snowscape_editor::Session;
use snowscape_season::scenario::Scenario;
use snowscape_season::winter::Winter;
use snowscape_terrain::LayeredTerrain;
use snowscape_terrain::procedural::{AlpineParams, alpine};

/// A session on a `size`² alpine terrain of 20 m cells, a `days`-day season.
pub fn session(size: usize, days: f64) -> Session {
    let bedrock = alpine(&AlpineParams {
        size,
        seed: 3,
        cell_size: 20.0,
        ..AlpineParams::default()
    })
    .expect("terrain");
    let scenario = Scenario {
        seed: 3,
        days,
        ..Scenario::default()
    };
    let winter = Winter::new(scenario, LayeredTerrain::from_bedrock(bedrock)).expect("winter");
    Session::new(winter, "test terrain")
}

/// The cell with the steepest bedrock slope (away from the border).
pub fn steepest_cell(s: &Session) -> (usize, usize) {
    let t = s.terrain();
    let g = t.geometry();
    let (w, h) = (g.width(), g.height());
    let mut best = (0.0f32, (w / 2, h / 2));
    for r in 8..h - 8 {
        for c in 8..w - 8 {
            let dz = (t.bedrock[g.index(c + 1, r)] - t.bedrock[g.index(c - 1, r)]).abs()
                + (t.bedrock[g.index(c, r + 1)] - t.bedrock[g.index(c, r - 1)]).abs();
            if dz > best.0 {
                best = (dz, (c, r));
            }
        }
    }
    best.1
}

/// Depth-weighted mean bedrock altitude of the snow, m.
pub fn snow_mean_altitude(s: &Session) -> f64 {
    let t = s.terrain();
    let (mut a, mut m) = (0.0, 0.0);
    for i in 0..t.geometry().len() {
        let d = t.depth_at(i) as f64;
        a += d * t.bedrock[i] as f64;
        m += d;
    }
    a / m
}
