//! Terrain builders shared by the integration tests.
#![allow(dead_code)]

use snowscape_terrain::GridGeometry;

/// A `w`×`h` grid of square `cell` m cells with heights `f(x_east_m, y_north_m)` at the cell
/// centres (x from the western edge, y from the southern edge).
pub fn terrain(
    w: usize,
    h: usize,
    cell: f64,
    f: impl Fn(f64, f64) -> f64,
) -> (Vec<f32>, GridGeometry) {
    let g = GridGeometry::square(w, h, cell).unwrap();
    let z = (0..w * h)
        .map(|i| {
            let (c, r) = (i % w, i / w);
            let x = (c as f64 + 0.5) * cell;
            let y = (h as f64 - r as f64 - 0.5) * cell;
            f(x, y) as f32
        })
        .collect();
    (z, g)
}

/// Rough deterministic terrain: a sum of sines with a ridge, 100..1600 m.
pub fn rough(x: f64, y: f64) -> f64 {
    800.0
        + 300.0 * (x * 0.004).sin() * (y * 0.003).cos()
        + 120.0 * (x * 0.013 + y * 0.007).sin()
        + 40.0 * (x * 0.05).cos() * (y * 0.043).sin()
        + 200.0 * (-((x - 400.0) / 120.0).powi(2)).exp()
}
