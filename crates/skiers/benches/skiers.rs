//! 1000 skiers stepping on a size² procedural alpine terrain (SNOWSCAPE_BENCH_SIZE, default
//! 1024) under a uniform snow cover. One iteration is 100 steps of 0.1 s (the paper's
//! Ski-Track-Step interval, Section 3.1) from a fresh copy of the scene, so the time per
//! iteration divided by 100 is the cost of one step of all skiers (target: ≥ 100 steps/s on
//! 2 cores). The distance map and the spawn are timed separately.

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use snowscape_skiers::{SkiArea, SkiScratch, Terminus, TerminusMap, bench_setup, step};
use std::time::Duration;

const SKIERS: usize = 1000;
const STEPS: usize = 100;

fn bench(c: &mut Criterion) {
    let size: usize = std::env::var("SNOWSCAPE_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1024);
    let (params, area, terrain) = bench_setup(size, SKIERS, 7).expect("bench scene");
    assert_eq!(area.skiers().len(), SKIERS, "every skier spawned");
    let mut group = c.benchmark_group("skiers");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(10));
    group.bench_function(format!("{SKIERS}_skiers_{STEPS}_steps_{size}"), |b| {
        b.iter_batched(
            || (area.clone(), terrain.clone(), SkiScratch::default()),
            |(mut a, mut t, mut s): (SkiArea, _, SkiScratch)| {
                for _ in 0..STEPS {
                    step(&params, &mut a, &mut t, &mut s, 0.1).expect("step");
                }
                // Returned so that freeing the copies is not timed.
                (a, t, s)
            },
            BatchSize::LargeInput,
        )
    });
    group.bench_function(format!("terminus_map_{size}"), |b| {
        b.iter(|| TerminusMap::compute(&params, &terrain, &Terminus::LocalMinima).expect("map"))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
