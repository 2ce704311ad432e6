//! Throughput of the Section 5 phenomena (cells per second) on a synthetic mountain of
//! `SNOWSCAPE_BENCH_SIZE`² cells (default 256). Each phenomenon steps its own copy of the
//! snow-covered terrain over and over; every step visits every cell with the same stencils,
//! so the work per step does not depend on how far the snow has evolved.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use snowscape_season::{melt, powder_diffusion, snowfall, stability, wind_transport};
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, SnowLayer};
use std::hint::black_box;

struct Scene {
    terrain: LayeredTerrain,
    temperature: Vec<f32>,
    u: Vec<f32>,
    v: Vec<f32>,
    shadow: Vec<f32>,
    wz: Vec<f32>,
}

fn size() -> usize {
    std::env::var("SNOWSCAPE_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(256)
}

/// Ridges and valleys, 5 m cells, with a metre of mixed snow and melting low ground.
fn scene(n: usize) -> Scene {
    let geo = GridGeometry::square(n, n, 5.0).unwrap();
    let bed = Grid::from_fn(geo, |c, r| {
        let (x, y) = (c as f32 / n as f32, r as f32 / n as f32);
        let ridges = (x * 19.0 + (y * 7.0).sin()).sin() * (y * 13.0).cos();
        1500.0 + 400.0 * ridges + 300.0 * y
    });
    let mut terrain = LayeredTerrain::from_bedrock(bed);
    for (k, layer) in SnowLayer::ALL.into_iter().enumerate() {
        let d = 0.1 + 0.1 * k as f32;
        terrain.layer_mut(layer).fill(d);
    }
    let temperature = terrain
        .bedrock
        .iter()
        .map(|b| 4.0 - 0.01 * (b - 1200.0))
        .collect();
    let cells = n * n;
    let u = (0..cells).map(|i| 6.0 + (i % 7) as f32).collect();
    let v = (0..cells).map(|i| ((i / n) % 5) as f32 - 2.0).collect();
    let wz = terrain.bedrock.clone();
    let shadow = (0..cells)
        .map(|i| ((i % n) % 11 < 3) as u8 as f32)
        .collect();
    Scene {
        terrain,
        temperature,
        u,
        v,
        shadow,
        wz,
    }
}

fn phenomena(c: &mut Criterion) {
    let n = size();
    let s = scene(n);
    let mut group = c.benchmark_group(format!("phenomena_{n}"));
    group.throughput(Throughput::Elements((n * n) as u64));
    group.sample_size(20);

    let mut scratch = snowfall::SnowfallScratch::default();
    let params = snowfall::SnowfallParams::default();
    group.bench_function("snowfall", |b| {
        let mut t = s.terrain.clone();
        b.iter(|| {
            let t = &mut t;
            black_box(snowfall::step(
                &params,
                t,
                &s.temperature,
                &mut scratch,
                1.0,
            ))
        })
    });
    let params = melt::MeltParams::default();
    group.bench_function("melt", |b| {
        let mut t = s.terrain.clone();
        b.iter(|| {
            let t = &mut t;
            black_box(melt::step(&params, t, &s.temperature, 0.5).unwrap())
        })
    });
    let mut scratch = stability::StabilityScratch::default();
    let params = stability::StabilityParams::default();
    group.bench_function("stability", |b| {
        let mut t = s.terrain.clone();
        b.iter(|| {
            let t = &mut t;
            black_box(stability::step(&params, t, &s.temperature, &mut scratch, 0.5).unwrap())
        })
    });
    let mut scratch = powder_diffusion::DiffusionScratch::default();
    let params = powder_diffusion::DiffusionParams::default();
    group.bench_function("powder_diffusion", |b| {
        let mut t = s.terrain.clone();
        b.iter(|| {
            let t = &mut t;
            black_box(powder_diffusion::step(&params, t, &mut scratch, 0.5).unwrap())
        })
    });
    let mut scratch = wind_transport::WindScratch::default();
    let params = wind_transport::WindTransportParams::default();
    let maps = wind_transport::WindMaps {
        u: &s.u,
        v: &s.v,
        shadow: &s.shadow,
        effect_surface: &s.wz,
        sx: None,
        terms: None,
        air_temperature: None,
    };
    group.bench_function("wind_transport", |b| {
        let mut t = s.terrain.clone();
        b.iter(|| {
            let t = &mut t;
            black_box(wind_transport::step(&params, t, &maps, &mut scratch, 0.5).unwrap())
        })
    });
    group.finish();
    black_box(&s.terrain);
}

criterion_group!(benches, phenomena);
criterion_main!(benches);
