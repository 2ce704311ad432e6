//! Criterion benchmarks of the environment precompute, whole and per stage.
//!
//! `cargo bench -p snowscape-environment`; the grid side comes from `SNOWSCAPE_BENCH_SIZE`
//! (default 256; the target is the whole precompute at 1024² in <= 2 s on 2 cores, see
//! `examples/environment_timing.rs` for a one-off measurement with per-stage times).

use criterion::{Criterion, criterion_group, criterion_main};
use snowscape_environment::{
    EnvironmentParams, direct_sun, indirect_bounce, precompute, sky_exposure, wind,
};
use snowscape_terrain::{GridGeometry, NodataMask};
use std::hint::black_box;
use std::time::Duration;

/// Grid side used when `SNOWSCAPE_BENCH_SIZE` is unset or not a number.
const DEFAULT_SIZE: usize = 256;

fn bench_size() -> usize {
    std::env::var("SNOWSCAPE_BENCH_SIZE")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(DEFAULT_SIZE)
        .clamp(16, 8192)
}

/// Mountainous test terrain: ridges and valleys over ~1.5 km of relief, 10 m cells.
fn terrain(n: usize) -> (Vec<f32>, GridGeometry) {
    let g = GridGeometry::square(n, n, 10.0).expect("valid size");
    let z = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f64 * 10.0, (i / n) as f64 * 10.0);
            (1500.0
                + 600.0 * (x * 0.0021).sin() * (y * 0.0017).cos()
                + 250.0 * (x * 0.007 + y * 0.004).sin()
                + 60.0 * (x * 0.031).cos() * (y * 0.027).sin()) as f32
        })
        .collect();
    (z, g)
}

fn stages(c: &mut Criterion) {
    let n = bench_size();
    let (z, g) = terrain(n);
    let mask = NodataMask::all_valid();
    let p = EnvironmentParams::default();
    let sun = direct_sun(&z, &g, &mask, &p.sun).expect("valid input");
    let mut group = c.benchmark_group(format!("environment {n}x{n}"));
    group.bench_function("precompute", |b| {
        b.iter(|| black_box(precompute(&z, &g, &mask, &p).expect("valid input")))
    });
    group.bench_function("sun", |b| {
        b.iter(|| black_box(direct_sun(&z, &g, &mask, &p.sun).expect("valid input")))
    });
    group.bench_function("sky", |b| {
        b.iter(|| black_box(sky_exposure(&z, &g, &mask, &p.sky).expect("valid input")))
    });
    group.bench_function("bounce", |b| {
        b.iter(|| black_box(indirect_bounce(&z, &g, &mask, &sun, &p.bounce).expect("valid input")))
    });
    group.bench_function("wind", |b| {
        b.iter(|| black_box(wind(&z, &g, &mask, &p.wind).expect("valid input")))
    });
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
    targets = stages
}
criterion_main!(benches);
