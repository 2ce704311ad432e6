//! One-off timing of the whole precompute with per-stage times.
//!
//! `cargo run --release -p snowscape-environment --example environment_timing -- [SIZE] [REPEATS]`
//! (default 1024, 3): mountainous synthetic terrain with 10 m cells, default parameters.

use snowscape_environment::{EnvironmentParams, precompute};
use snowscape_terrain::{GridGeometry, NodataMask};

fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(1024);
    let repeats: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(3);
    let g = GridGeometry::square(n, n, 10.0).expect("valid size");
    let z: Vec<f32> = (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f64 * 10.0, (i / n) as f64 * 10.0);
            (1500.0
                + 600.0 * (x * 0.0021).sin() * (y * 0.0017).cos()
                + 250.0 * (x * 0.007 + y * 0.004).sin()
                + 60.0 * (x * 0.031).cos() * (y * 0.027).sin()) as f32
        })
        .collect();
    let p = EnvironmentParams::default();
    let samples = snowscape_environment::sun::schedule(&p.sun).expect("valid parameters");
    println!(
        "{n}x{n}, {} threads, {} sun positions, {} horizon directions, {} bounce samples/cell",
        rayon::current_num_threads(),
        samples.len(),
        p.sky.directions,
        p.bounce.directions * p.bounce.radii
    );
    for run in 0..repeats {
        let m = precompute(&z, &g, &NodataMask::all_valid(), &p).expect("valid input");
        let t = m.timings;
        let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
        println!(
            "run {run}: total {:.0} ms = prepare {:.0} + sun {:.0} + sky {:.0} + bounce {:.0} + temperature {:.0} + wind {:.0} (red-black iterations {}); {:.1} Mcells/s",
            ms(t.total),
            ms(t.prepare),
            ms(t.sun),
            ms(t.sky),
            ms(t.bounce),
            ms(t.temperature),
            ms(t.wind),
            m.wind_stats.iterations,
            (n * n) as f64 / t.total.as_secs_f64() / 1e6
        );
    }
}
