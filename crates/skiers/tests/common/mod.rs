//! Synthetic terrains shared by the tests.
#![allow(dead_code)]

use snowscape_terrain::{Crs, GeoTransform, Grid, GridGeometry, LayeredTerrain, SnowLayer};

/// A `w`×`h` grid of `dx` m cells whose bedrock is `f(col, row)`, under `stable` m of stable
/// and `unstable` m of unstable snow everywhere.
pub fn terrain(
    w: usize,
    h: usize,
    dx: f64,
    stable: f32,
    unstable: f32,
    f: impl Fn(usize, usize) -> f64,
) -> LayeredTerrain {
    let g = GridGeometry::square(w, h, dx).unwrap();
    let mut t = LayeredTerrain::from_bedrock(Grid::from_fn(g, |c, r| f(c, r) as f32));
    t.layer_mut(SnowLayer::Stable).fill(stable);
    t.layer_mut(SnowLayer::Unstable).fill(unstable);
    t
}

/// A plane descending southwards (row grows) at `slope_deg`, plus a gentle east-west tilt
/// `tilt_deg` so the fall line is unique.
pub fn plane(w: usize, h: usize, dx: f64, slope_deg: f64) -> LayeredTerrain {
    let tan = slope_deg.to_radians().tan();
    terrain(w, h, dx, 1.0, 0.5, move |_, r| 1000.0 - tan * dx * r as f64)
}

/// A conical mountain centred in the grid whose slope falls from 55° at the summit to 10° at
/// radius `r_max` (m) and stays 10° beyond: slopes of every steepness, every aspect.
pub fn varied_mountain(size: usize, dx: f64) -> LayeredTerrain {
    let r_max = 0.5 * size as f64 * dx;
    let c = 0.5 * size as f64;
    // z(r) = -∫ tan(θ(r)) dr with θ falling linearly; integrate numerically once per cell.
    let theta = move |r: f64| (55.0 - 45.0 * (r / r_max).min(1.0)).to_radians();
    let height = move |r: f64| {
        let n = 200;
        let h = r / n as f64;
        let mut z = 0.0;
        for k in 0..n {
            z += theta((k as f64 + 0.5) * h).tan() * h;
        }
        3000.0 - z
    };
    terrain(size, size, dx, 1.0, 0.3, move |col, row| {
        let (x, y) = ((col as f64 + 0.5 - c) * dx, (row as f64 + 0.5 - c) * dx);
        height(x.hypot(y))
    })
}

/// The same terrain georeferenced in EPSG:31287 (MGI / Austria Lambert) at a real origin.
pub fn georeferenced(t: &LayeredTerrain) -> LayeredTerrain {
    let g = t.geometry();
    let geo = GridGeometry::from_transform(
        g.width(),
        g.height(),
        GeoTransform {
            origin_x: 166_773.0,
            origin_y: 353_588.0,
            pixel_width: g.cell_size_x(),
            pixel_height: g.cell_size_y(),
        },
        Some(Crs::Epsg(31287)),
    )
    .unwrap();
    let mut out =
        LayeredTerrain::from_bedrock(Grid::new(geo, t.bedrock.clone(), t.mask().clone()).unwrap());
    out.snow = t.snow.clone();
    out
}
