//! Raster I/O throughput: GeoTIFF write + read, ESRI ASCII parse, PNG16 write.
//! The grid side is `SNOWSCAPE_BENCH_SIZE` (default 512, small enough for CI; use 4096 for
//! figures worth quoting).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use snowscape_io::{RasterFormat, ReadOptions, read_dem, write_geotiff, write_png16, write_raster};
use snowscape_terrain::{Crs, GeoTransform, Grid, GridGeometry};
use std::hint::black_box;

fn side() -> usize {
    std::env::var("SNOWSCAPE_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(512)
}

fn terrain(n: usize) -> Grid {
    let t = GeoTransform {
        origin_x: 100_000.0,
        origin_y: 400_000.0,
        pixel_width: 5.0,
        pixel_height: 5.0,
    };
    let geo = GridGeometry::from_transform(n, n, t, Some(Crs::Epsg(31287))).unwrap();
    Grid::from_fn(geo, |c, r| {
        let (x, y) = (c as f32 * 0.01, r as f32 * 0.013);
        1500.0 + 300.0 * x.sin() * y.cos() + 40.0 * (7.0 * x + 3.0 * y).sin()
    })
}

fn bench(c: &mut Criterion) {
    let n = side();
    let g = terrain(n);
    let d = tempfile::tempdir().unwrap();
    let mut group = c.benchmark_group(format!("raster_io_{n}"));
    group.sample_size(10);
    group.throughput(Throughput::Elements((n * n) as u64));
    let tif = d.path().join("t.tif");
    group.bench_function("geotiff_write", |b| {
        b.iter(|| write_geotiff(&tif, &g).unwrap())
    });
    group.bench_function("geotiff_read", |b| {
        b.iter(|| black_box(read_dem(&tif, &ReadOptions::default()).unwrap()))
    });
    let asc = d.path().join("t.asc");
    write_raster(&asc, &g, RasterFormat::Asc).unwrap();
    group.bench_function("asc_read", |b| {
        b.iter(|| black_box(read_dem(&asc, &ReadOptions::default()).unwrap()))
    });
    let png = d.path().join("t.png");
    group.bench_function("png16_write", |b| b.iter(|| write_png16(&png, &g).unwrap()));
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
