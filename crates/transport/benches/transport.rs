//! Throughput of the transport step (Jubert 2018, Eq. 5.16) in cells per second, on a
//! synthetic mountain of `SNOWSCAPE_BENCH_SIZE`² cells (default 256; the target is
//! 1000², ≤ 25 ms per step; the thesis: 242 ms on a GTX 970). The wind is a west wind of
//! 11 m/s (Table 7.I) modified by the terrain (Section 5.4); the snow is 30 cm deep with
//! snowfall, so every phenomenon runs in most cells.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use snowscape_terrain::GridGeometry;
use snowscape_transport::step::{SceneMaps, SnowState, StepScratch, step};
use snowscape_transport::terrain_wind::modify_wind;
use snowscape_transport::{TransportParams, Weather};
use std::hint::black_box;

fn size() -> usize {
    std::env::var("SNOWSCAPE_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(256)
}

fn transport(c: &mut Criterion) {
    let n = size();
    let g = GridGeometry::square(n, n, 1.0).unwrap();
    let z: Vec<f32> = (0..g.len())
        .map(|i| {
            let (x, y) = ((i % n) as f32 / n as f32, (i / n) as f32 / n as f32);
            200.0 * ((x * 9.0).sin() * (y * 7.0).cos()) + 100.0 * y
        })
        .collect();
    let params = TransportParams::default();
    let u0 = vec![11.0f32; g.len()];
    let v0 = vec![0.0f32; g.len()];
    let (u, v) = modify_wind(&params, &g, &z, &u0, &v0).unwrap();
    let scene = SceneMaps {
        geometry: &g,
        wind_u: &u,
        wind_v: &v,
        precipitation_ratio: None,
    };
    let weather = Weather {
        precipitation_mm_per_h: 7.5,
        relative_humidity_pct: 40.0,
        ..Default::default()
    };
    let mut group = c.benchmark_group(format!("transport_{n}"));
    group.throughput(Throughput::Elements((n * n) as u64));
    group.sample_size(10);
    let mut scratch = StepScratch::default();
    let mut state = SnowState::uniform(&g, 0.3, 150.0);
    group.bench_function("step", |b| {
        b.iter(|| {
            let s = &mut state;
            black_box(step(&params, &weather, &scene, s, &mut scratch, 300.0).unwrap())
        })
    });
    group.finish();
}

criterion_group!(benches, transport);
criterion_main!(benches);
