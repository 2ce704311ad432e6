//! One avalanche step of a 200x200 released area on a size² tilted grid
//! (SNOWSCAPE_BENCH_SIZE, default 256). The step length is one CFL sub-step, so the time is
//! the per-sub-step cost of a footprint of about 200x200 cells.

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use snowscape_avalanche::{AvalancheParams, AvalancheScratch, AvalancheState, cfl_dt, step};
use snowscape_terrain::{GridGeometry, NodataMask};

fn setup(size: usize) -> AvalancheState {
    let geometry = GridGeometry::square(size, size, 2.0).expect("geometry");
    // A plane descending southwards at 35 degrees.
    let slope = 35f64.to_radians().tan();
    let bed: Vec<f64> = (0..size * size)
        .map(|i| -((i / size) as f64) * 2.0 * slope)
        .collect();
    let mut state = AvalancheState::new(&geometry, &NodataMask::all_valid(), &bed).expect("state");
    let side = 200.min(size);
    let start = (size - side) / 2;
    let mut h = vec![0.0; size * size];
    for r in start..start + side {
        for c in start..start + side {
            h[r * size + c] = 1.0;
        }
    }
    state.set_thickness(&h).expect("thickness");
    state
}

fn bench(c: &mut Criterion) {
    let size: usize = std::env::var("SNOWSCAPE_BENCH_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(256);
    let params = AvalancheParams::default();
    let mut state = setup(size);
    let mut scratch = AvalancheScratch::default();
    // Let the release get moving first (a few seconds of flow).
    step(&params, &mut state, &mut scratch, 2.0).expect("warm-up step");
    let dt = cfl_dt(&params, &state);
    c.bench_function(&format!("avalanche_substep_{size}"), |b| {
        b.iter_batched_ref(
            || state.clone(),
            |s| step(&params, s, &mut scratch, dt).expect("step"),
            BatchSize::LargeInput,
        )
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
