//! Throughput of the snow diffusion kernel (von Festenberg & Gumhold 2011, Section 5.2) in
//! snow sites per second, and of the whole cover (map, bridges, kernel, mesh, texture
//! coordinates), on a synthetic scene of `SNOWSCAPE_FESTENBERG_SIDE`² columns (default 256,
//! about 70 k sites; the target is 1000², about 1 M sites, in <= 10 s on 2 cores; the
//! paper: 344 k sites in 654 s). The scene: a wavy ground with boxes standing on it and
//! tables over it (two and three layers where the tables are), 10 cm columns, kernel radius
//! 1 m (10 columns, 317 columns per kernel: the paper's 5 % of a 200-column scene), h0 = 0.3 m.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use snowscape_festenberg::kernel::evaluate;
use snowscape_festenberg::{CoverParams, cover, prepare_sites};
use snowscape_mesh::terrain::grid_object;
use snowscape_mesh::{Scene, SceneObject, SourceFrame};
use snowscape_terrain::{Grid, GridGeometry};
use std::hint::black_box;

fn side() -> usize {
    std::env::var("SNOWSCAPE_FESTENBERG_SIDE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(256)
}

fn cube(name: String, min: [f32; 3], max: [f32; 3]) -> SceneObject {
    let p = |i: usize| {
        [
            if i & 1 == 0 { min[0] } else { max[0] },
            if i & 2 == 0 { min[1] } else { max[1] },
            if i & 4 == 0 { min[2] } else { max[2] },
        ]
    };
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    SceneObject {
        frame: Default::default(),
        name,
        positions: (0..8).map(p).collect(),
        normals: None,
        triangles: quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect(),
        uvs: None,
    }
}

/// `side` x `side` columns of 10 cm: ground, boxes on it, tables above it.
fn scene(side: usize) -> Scene {
    let metres = side as f64 * 0.1;
    let n = (metres as usize).max(2) + 1;
    let g = GridGeometry::new(n, n, 1.0, 1.0).expect("ground grid");
    let ground = Grid::from_fn(g, |c, r| {
        0.3 * ((c as f32 * 0.7).sin() * (r as f32 * 0.5).cos()) + 0.02 * r as f32
    });
    let mut objects = vec![grid_object(&ground, "ground").expect("ground mesh")];
    let mut k = 0;
    let mut y = 2.0;
    while y + 3.0 < metres as f32 {
        let mut x = 2.0;
        while x + 3.0 < metres as f32 {
            if k % 2 == 0 {
                objects.push(cube(
                    format!("box {k}"),
                    [x, y, -1.0],
                    [x + 1.0, y + 1.5, 1.2],
                ));
            } else {
                objects.push(cube(
                    format!("table {k}"),
                    [x, y, 1.0],
                    [x + 2.0, y + 2.0, 1.1],
                ));
            }
            k += 1;
            x += 4.0;
        }
        y += 4.0;
    }
    Scene {
        objects,
        frame: SourceFrame::default(),
    }
}

/// Kernel radius, metres: `SNOWSCAPE_FESTENBERG_RADIUS` (default 1 m, 10 columns; 7 m is the
/// issue's 70-column kernel).
fn radius() -> f64 {
    std::env::var("SNOWSCAPE_FESTENBERG_RADIUS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0)
}

fn params(side: usize) -> CoverParams {
    let m = side as f64 * 0.1;
    CoverParams {
        depth_m: Some(0.3),
        radius_m: Some(radius()),
        bridge_m: Some(0.5),
        resolution_m: Some(0.1),
        extent_m: Some([0.5, 0.5, 0.5 + m, 0.5 + m]),
        ..Default::default()
    }
}

fn bench(c: &mut Criterion) {
    let n = side();
    let s = scene(n);
    let p = params(n);
    let (r, _, field) = prepare_sites(&s, &p, true).expect("sites");
    eprintln!(
        "festenberg kernel: {n}x{n} columns, {} sites ({} bridge), radius {} m",
        field.len(),
        field.bridge_count(),
        r.radius_m
    );
    let mut group = c.benchmark_group("festenberg");
    group.sample_size(10);
    group.throughput(Throughput::Elements(field.len() as u64));
    group.bench_function("kernel_sites", |b| {
        b.iter(|| black_box(evaluate(black_box(&field), r.radius_m)))
    });
    group.bench_function("cover_sites", |b| {
        b.iter(|| black_box(cover(black_box(&s), &p).expect("cover")))
    });
    group.finish();
    let t = std::time::Instant::now();
    let k = evaluate(&field, r.radius_m);
    let secs = t.elapsed().as_secs_f64();
    eprintln!(
        "festenberg kernel: {} sites in {secs:.3} s = {:.3e} sites/s ({:.3e} members/s), {} threads",
        field.len(),
        field.len() as f64 / secs,
        k.members_visited as f64 / secs,
        rayon::current_num_threads()
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
