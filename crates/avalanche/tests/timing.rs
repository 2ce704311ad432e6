//! Per-sub-step time of a 200x200 release on a 1024² grid (run with `--ignored --nocapture`).

use snowscape_avalanche::{AvalancheParams, AvalancheScratch, AvalancheState, cfl_dt, step};
use snowscape_terrain::{GridGeometry, NodataMask};

#[test]
#[ignore = "timing, run by hand"]
fn substep_time_1024() {
    let size = 1024;
    let geometry = GridGeometry::square(size, size, 2.0).unwrap();
    let slope = 35f64.to_radians().tan();
    let bed: Vec<f64> = (0..size * size)
        .map(|i| -((i / size) as f64) * 2.0 * slope)
        .collect();
    let mut s = AvalancheState::new(&geometry, &NodataMask::all_valid(), &bed).unwrap();
    let mut h = vec![0.0; size * size];
    for r in 412..612 {
        for c in 412..612 {
            h[r * size + c] = 1.0;
        }
    }
    s.set_thickness(&h).unwrap();
    let params = AvalancheParams::default();
    let mut scratch = AvalancheScratch::default();
    let mut n = 0;
    let t0 = std::time::Instant::now();
    let mut last = Default::default();
    while n < 40 {
        let dt = cfl_dt(&params, &s);
        last = step(&params, &mut s, &mut scratch, dt).unwrap();
        n += 1;
    }
    let per = t0.elapsed().as_secs_f64() / n as f64;
    eprintln!(
        "{n} sub-steps, {:.2} ms each, last: {last:?}, threads {}",
        per * 1e3,
        rayon::current_num_threads()
    );
}
