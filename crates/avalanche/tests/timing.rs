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
    let mut times = Vec::new();
    let mut last = Default::default();
    while times.len() < 40 {
        let dt = cfl_dt(&params, &s);
        let t0 = std::time::Instant::now();
        last = step(&params, &mut s, &mut scratch, dt).unwrap();
        times.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    let n = times.len();
    let mean = times.iter().sum::<f64>() / n as f64;
    times.sort_by(f64::total_cmp);
    eprintln!(
        "{n} sub-steps, {mean:.2} ms each (median {:.2}, best {:.2}), last: {last:?}, threads {}",
        times[n / 2],
        times[0],
        rayon::current_num_threads()
    );
}

/// The avaWog avalanche (AvaFrame test case: 555x490 cells of 5 m, release polygon relWog)
/// run to rest, as `snowscape avalanche` runs it: wall time of the flow, sub-steps, and a
/// fingerprint of the final thickness, peak thickness and peak speed fields (bit patterns), to
/// check that an optimisation leaves the results unchanged. Run with `--ignored --nocapture`;
/// skipped when the data is absent. `SNOWSCAPE_AVAWOG_DUMP=path` writes the final thickness
/// (f64, little endian) there.
#[test]
#[ignore = "timing, run by hand"]
fn avawog_run() {
    use snowscape_avalanche::{AvalancheRun, RunOptions, release_from_shapefile};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/dem");
    let dem_path = root.join("avaframe_avaWog/avaWog.asc");
    let rel_path = root.join("avaframe_avaWog/REL/relWog.shp");
    if !dem_path.exists() || !rel_path.exists() {
        eprintln!("avaWog data not found under {}, skipped", root.display());
        return;
    }
    let dem = snowscape_io::read_dem(&dem_path, &snowscape_io::ReadOptions::default()).unwrap();
    let g = dem.geometry();
    let area = release_from_shapefile(&rel_path, g, dem.mask()).unwrap();
    let h = area.thickness_field(1.0).unwrap();
    let bed: Vec<f64> = dem.data().iter().map(|&z| z as f64).collect();
    let mut state = AvalancheState::new(g, dem.mask(), &bed).unwrap();
    state.set_thickness(&h).unwrap();
    let params = AvalancheParams::default();
    let options = RunOptions::default();
    let t0 = std::time::Instant::now();
    let mut run = AvalancheRun::new(state);
    // Mean over records of the cells visited per sub-step and of the cells holding snow.
    let (mut visited, mut flowing, mut records) = (0.0, 0.0, 0usize);
    while run.stop_reason().is_none() {
        let report = run.advance(&params, &options).unwrap();
        visited += report.active_cells as f64;
        flowing += report.flowing_cells as f64;
        records += 1;
    }
    let wall = t0.elapsed().as_secs_f64();
    let summary = run.summary(&options);
    eprintln!(
        "avaWog: {records} records, mean {:.0} cells visited and {:.0} holding snow per sub-step",
        visited / records as f64,
        flowing / records as f64
    );
    let fingerprint = |v: &[f64]| {
        v.iter().fold(0xcbf2_9ce4_8422_2325u64, |a, x| {
            (a ^ x.to_bits()).wrapping_mul(0x0100_0000_01b3)
        })
    };
    let thick = run.state.thickness();
    eprintln!(
        "avaWog: {:.2} s wall, {} sub-steps, {:.1} s simulated, stop {:?}, closure {:.2e}, \
         runout {:.1} m; fingerprints thickness {:016x} peak_h {:016x} peak_u {:016x}; threads {}",
        wall,
        summary.substeps,
        summary.simulated_s,
        summary.stop,
        summary.volume_closure_rel,
        summary.runout_length_m,
        fingerprint(&thick),
        fingerprint(run.peak_thickness()),
        fingerprint(run.peak_speed()),
        rayon::current_num_threads()
    );
    if let Ok(path) = std::env::var("SNOWSCAPE_AVAWOG_DUMP") {
        let bytes: Vec<u8> = thick.iter().flat_map(|x| x.to_le_bytes()).collect();
        std::fs::write(path, bytes).unwrap();
    }
}
