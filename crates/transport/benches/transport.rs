//! Throughput of the transport step (Jubert 2018, Eq. 5.16) in cells per second, on a
//! synthetic mountain of `SNOWSCAPE_BENCH_SIZE`² cells (default 256; the target is
//! 1000², ≤ 25 ms per step; the thesis: 242 ms on a GTX 970). The wind is a west wind of
//! 11 m/s (Table 7.I) modified by the terrain (Section 5.4); the snow is 30 cm deep with
//! snowfall, so every phenomenon runs in most cells.
//!
//! The wind benchmark times one Stable Fluids iteration (Chapter 3) on an `n³` voxel grid,
//! `n` = `SNOWSCAPE_WIND_BENCH_SIZE` (default 24; the target is 128³ ≤ 300 ms, the
//! thesis: 1.8 s), over the castle scene, after a few warm-up iterations.
//!
//! The flake benchmark builds a precipitation map (Chapter 4) from `SNOWSCAPE_FLAKES` flakes
//! (default 20 000; the target is 1 M flakes ≤ 3 s, the thesis: 90 s) through the
//! mean wind of the castle scene on a 48 × 48 × 24 grid.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use snowscape_terrain::GridGeometry;
use snowscape_transport::precipitation::{FlakeParams, precipitation_map};
use snowscape_transport::step::{SceneMaps, SnowState, StepScratch, step};
use snowscape_transport::terrain_wind::modify_wind;
use snowscape_transport::wind3d::voxel::{VoxelGrid, castle_heights};
use snowscape_transport::wind3d::{Wind3dParams, WindSolver};
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

fn wind(c: &mut Criterion) {
    let n: usize = std::env::var("SNOWSCAPE_WIND_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(24);
    let cell = 850.0 / n as f64;
    let g = GridGeometry::square(n, n, cell).unwrap();
    let z = castle_heights(n, cell);
    let vox = VoxelGrid::from_heights(&g, &z, cell, n, -cell).unwrap();
    let mut solver = WindSolver::new(vox, Wind3dParams::default()).unwrap();
    for _ in 0..3 {
        solver.iterate();
    }
    let r = solver.iterate();
    eprintln!(
        "wind {n}^3: {} CG iterations, relative divergence {:.2e}",
        r.solver_iterations, r.relative_divergence
    );
    let mut group = c.benchmark_group(format!("wind_{n}"));
    group.throughput(Throughput::Elements((n * n * n) as u64));
    group.sample_size(10);
    group.bench_function("iteration", |b| b.iter(|| black_box(solver.iterate())));
    group.finish();
}

fn flakes(c: &mut Criterion) {
    let count: usize = std::env::var("SNOWSCAPE_FLAKES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20_000);
    let (n, cell) = (48, 850.0 / 48.0);
    let g = GridGeometry::square(n, n, cell).unwrap();
    let z = castle_heights(n, cell);
    let vox = VoxelGrid::from_heights(&g, &z, cell, 24, -cell).unwrap();
    let mut solver = WindSolver::new(vox.clone(), Wind3dParams::default()).unwrap();
    for _ in 0..5 {
        solver.iterate();
    }
    let wind = solver.mean_velocity();
    let inflow = Wind3dParams::default().inflow();
    let params = FlakeParams {
        count,
        ..Default::default()
    };
    let map = precipitation_map(&vox, &wind, inflow, &params).unwrap();
    eprintln!(
        "flakes: {} landed, {} lost, {:.0} % through the sides",
        map.flakes.landed,
        map.flakes.lost,
        100.0 * map.flakes.side_share
    );
    let mut group = c.benchmark_group("flakes");
    group.throughput(Throughput::Elements(count as u64));
    group.sample_size(10);
    group.bench_function(format!("map_{count}"), |b| {
        b.iter(|| black_box(precipitation_map(&vox, &wind, inflow, &params).unwrap()))
    });
    group.finish();
}

criterion_group!(benches, transport, wind, flakes);
criterion_main!(benches);
