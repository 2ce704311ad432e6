//! Ray casting throughput (rays/s) and BVH build throughput (triangles/s) on the Stanford bunny
//! and on a ~100k-triangle scene (bunnies and teapot pairs standing on a ground grid).
//! Needs ../shared/data/meshes beside the checkout.

mod common;
use common::{big_scene, mesh};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use snowscape_mesh::{Ray, Scene, SceneBvh};
use std::hint::black_box;

/// Deterministic numbers in [0, 1) (splitmix64).
fn uniform(seed: u64) -> impl FnMut() -> f32 {
    let mut s = seed;
    move || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Rays falling straight down from above the scene (a height-span / top view), and rays shot
/// upward in random directions from random points of the scene's box (Fearing's flakes).
fn rays(scene: &Scene, n: usize) -> (Vec<Ray>, Vec<Ray>) {
    let b = scene.bounds().unwrap();
    let mut r = uniform(7);
    let point =
        |r: &mut dyn FnMut() -> f32| [0, 1, 2].map(|k| b.min[k] + r() * (b.max[k] - b.min[k]));
    let down = (0..n)
        .map(|_| {
            let [x, y, _] = point(&mut r);
            Ray::new([x, y, b.max[2] + 1.0], [0.0, 0.0, -1.0])
        })
        .collect();
    let up = (0..n)
        .map(|_| {
            let o = point(&mut r);
            let (a, c) = (std::f32::consts::TAU * r(), 0.5 + 0.5 * r());
            let s = (1.0 - c * c).sqrt();
            Ray::new(o, [s * a.cos(), s * a.sin(), c])
        })
        .collect();
    (down, up)
}

fn bench(c: &mut Criterion) {
    let scenes = [("bunny", mesh("bunny_npm.obj", 0.1)), ("100k", big_scene())];
    let n = 20_000;
    let mut group = c.benchmark_group("ray_cast");
    group.sample_size(10);
    for (name, scene) in &scenes {
        let bvh = SceneBvh::new(scene);
        let (down, up) = rays(scene, n);
        group.throughput(Throughput::Elements(n as u64));
        group.bench_function(BenchmarkId::new("first_hits_down", name), |b| {
            b.iter(|| black_box(bvh.first_hits(black_box(&down))))
        });
        group.bench_function(BenchmarkId::new("first_hits_up_random", name), |b| {
            b.iter(|| black_box(bvh.first_hits(black_box(&up))))
        });
        let points: Vec<[f32; 3]> = up.iter().map(|r| r.origin).collect();
        group.bench_function(BenchmarkId::new("anything_above", name), |b| {
            b.iter(|| black_box(bvh.anything_above_many(black_box(&points), 1e-4)))
        });
        group.throughput(Throughput::Elements(scene.triangle_count() as u64));
        group.bench_function(BenchmarkId::new("bvh_build", name), |b| {
            b.iter(|| black_box(SceneBvh::new(black_box(scene))))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
