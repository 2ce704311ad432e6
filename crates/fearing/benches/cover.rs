//! Fearing 2000 cover throughput: the Stanford bunny (about 1 m tall) and the ~100k-triangle
//! scene of bunnies and teapots on a ground grid, default snow parameters; prints sites, flakes,
//! flakes/s and seconds of one run, then lets criterion time whole covers.
//! `cargo bench -p snowscape-fearing` runs the full size; `cargo test --all-targets` (no
//! `--bench` argument) runs a reduced size once. Needs ../shared/data/meshes beside the checkout.

mod common;
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use snowscape_fearing::{FearingParams, cover};
use std::hint::black_box;
use std::time::Duration;

fn bench(c: &mut Criterion) {
    let full = std::env::args().any(|a| a == "--bench");
    let (scenes, params) = if full {
        (
            vec![
                ("bunny", common::mesh("bunny_npm.obj", 0.1)),
                ("100k", common::big_scene()),
            ],
            FearingParams::default(),
        )
    } else {
        (
            vec![
                ("bunny", common::mesh("bunny_npm.obj", 0.1)),
                ("20k", common::scene_of(20_000)),
            ],
            FearingParams {
                target_sites: 1500,
                flakes_per_site: 4,
                passes: 1,
                // Stability on the fine bunny drains its steep flanks slowly: bound its work.
                stability: snowscape_fearing::StabilityPhaseParams {
                    max_tests_per_site: 20,
                    ..Default::default()
                },
                ..Default::default()
            },
        )
    };
    let mut group = c.benchmark_group("fearing_cover");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(if full { 60 } else { 1 }))
        .warm_up_time(Duration::from_millis(1));
    for (name, scene) in &scenes {
        let first = cover(scene, &params).expect("cover");
        let r = &first.report;
        let stopped = r.passes.iter().any(|p| p.accumulation.stopped_by_time);
        println!(
            "fearing_cover/{name}: {} triangles, {} sites, {} flakes in {:.2} s of accumulation ({:.0} flakes/s{}), stability {:.2} s, total {:.2} s",
            r.triangles,
            r.sites_final,
            r.flakes_shot,
            r.timings.accumulation_s,
            r.flakes_per_s,
            if stopped {
                ", stopped by the time budget"
            } else {
                ""
            },
            r.timings.stability_s,
            r.timings.total_s
        );
        group.throughput(Throughput::Elements(r.flakes_shot));
        group.bench_function(BenchmarkId::new("cover", name), |b| {
            b.iter(|| black_box(cover(black_box(scene), &params).expect("cover")))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
