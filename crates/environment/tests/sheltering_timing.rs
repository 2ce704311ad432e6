//! Timing of the maximum upwind slope Sx at 1024² (not run by default):
//! `cargo test -p snowscape-environment --test sheltering_timing -- --ignored --nocapture`.

use snowscape_environment::{ShelteringParams, max_upwind_slope};
use snowscape_terrain::{GridGeometry, NodataMask};
use std::time::Instant;

#[test]
#[ignore = "timing"]
fn sx_1024() {
    let n = 1024;
    for cell in [2.0, 5.0, 10.0] {
        let g = GridGeometry::square(n, n, cell).unwrap();
        let z: Vec<f32> = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f64 * cell, (i / n) as f64 * cell);
                (1500.0
                    + 600.0 * (x * 0.0021).sin() * (y * 0.0017).cos()
                    + 60.0 * (x * 0.031).cos() * (y * 0.027).sin()) as f32
            })
            .collect();
        let p = ShelteringParams::default();
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let start = Instant::now();
            let sx = pool
                .install(|| max_upwind_slope(&z, &g, &NodataMask::all_valid(), 270.0, &p))
                .unwrap();
            eprintln!(
                "Sx 1024² at {cell} m ({} samples per ray, 7 rays), {threads} thread(s): {:.3?} (mean {:.2}°)",
                p.steps(&g),
                start.elapsed(),
                sx.iter().map(|&v| v as f64).sum::<f64>() / sx.len() as f64
            );
        }
    }
}
