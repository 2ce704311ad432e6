//! Criterion benchmarks of the same kernel registry as `snowscape bench`.
//!
//! `cargo bench -p snowscape-bench`; the grid side comes from `SNOWSCAPE_BENCH_SIZE` (default
//! 256), and the sample sizes are small so the whole suite takes a couple of minutes.

use criterion::{Criterion, criterion_group, criterion_main};
use snowscape_bench::registry::all_kernels;
use std::time::Duration;

/// Grid side used when `SNOWSCAPE_BENCH_SIZE` is unset or not a number.
const DEFAULT_SIZE: usize = 256;

fn bench_size() -> usize {
    std::env::var("SNOWSCAPE_BENCH_SIZE")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(DEFAULT_SIZE)
        .clamp(snowscape_bench::MIN_SIZE, snowscape_bench::MAX_SIZE)
}

fn kernels(c: &mut Criterion) {
    let size = bench_size();
    let kernels = match all_kernels(size) {
        Ok(k) => k,
        Err(e) => {
            eprintln!("cannot set up the kernels at {size}x{size}: {e}");
            return;
        }
    };
    let mut group = c.benchmark_group(format!("{size}x{size}"));
    for mut kernel in kernels {
        group.bench_function(kernel.name.clone(), |b| {
            b.iter(|| {
                if let Err(e) = (kernel.run)() {
                    eprintln!("{} failed: {e}", kernel.name);
                }
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
    targets = kernels
}
criterion_main!(benches);
