//! Height-span map build throughput: columns/s and triangles/s, on the bunny (1 cm columns)
//! and on the ~100k-triangle scene (5 cm columns). Needs ../shared/data/meshes.

mod common;
use common::{big_scene, mesh};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use snowscape_mesh::{HeightSpanMap, HeightSpanOptions};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let cases = [
        ("bunny", mesh("bunny_npm.obj", 0.1), 0.01),
        ("100k", big_scene(), 0.05),
    ];
    let mut group = c.benchmark_group("height_span");
    group.sample_size(10);
    for (name, scene, cell) in &cases {
        let opts = HeightSpanOptions {
            cell_size_m: *cell,
            ..Default::default()
        };
        let map = HeightSpanMap::build(scene, &opts).unwrap();
        eprintln!(
            "{name}: {}x{} columns, {} triangles, {} sites, {} layers",
            map.width,
            map.height,
            scene.triangle_count(),
            map.site_count(),
            map.layer_count()
        );
        group.throughput(Throughput::Elements((map.width * map.height) as u64));
        group.bench_function(BenchmarkId::new("build_columns", name), |b| {
            b.iter(|| black_box(HeightSpanMap::build(black_box(scene), &opts).unwrap()))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
