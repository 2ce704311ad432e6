//! Every validation number of the avalanche flow in one table.
//!
//! ```text
//! cargo run --release -p snowscape-avalanche --example validation
//! ```
//!
//! Analytic cases (Ritter's dam break, the poured pile's rest angle, the travel angle of a block
//! run out from a plane) need nothing; the real paths (avaWog, avaKot against AvaFrame's
//! reference) read the shared data folder (`../shared/data` beside the project root, or the
//! folder named by `SNOWSCAPE_DATA`) and are reported as missing, with a non-zero exit, when it
//! is absent. The tests in `tests/` assert the tolerances; this prints the numbers. An argument
//! runs only the groups whose name contains it: `ritter`, `pile`, `plane`, `avawog`, `avakot`
//! (`-- avawog` times the avaWog release alone).

use snowscape_avalanche::validation::{
    ThicknessConvention, dam_break, distance_to_polyline, footprint_overlap, plane_runout,
    poured_pile, read_polyline, run_release,
};
use snowscape_avalanche::{AvalancheParams, Border, RunOptions};
use snowscape_io::{ReadOptions, read_dem};
use std::path::PathBuf;
use std::time::Instant;

struct Table {
    rows: Vec<[String; 4]>,
}

impl Table {
    fn row(&mut self, case: &str, what: &str, measured: String, reference: String) {
        self.rows
            .push([case.into(), what.into(), measured, reference]);
        // Print as we go: the real paths take a while.
        let r = self.rows.last().unwrap();
        println!("{:<28} {:<34} {:>18}   {}", r[0], r[1], r[2], r[3]);
    }
}

fn data_dir() -> PathBuf {
    std::env::var_os("SNOWSCAPE_DATA").map_or_else(
        || PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data")),
        PathBuf::from,
    )
}

/// Ritter's dam break: the profile's L1 error and the front against the exact solution.
fn ritter(t: &mut Table) -> Result<(), Box<dyn std::error::Error>> {
    let frictionless = AvalancheParams {
        alpha: 0.0,
        k_viscous: 0.0,
        border: Border::Closed,
        ..AvalancheParams::paper()
    };
    let d = dam_break(&frictionless)?;
    let case = "Ritter dam break (t=15 s)";
    t.row(
        case,
        "L1 profile error (relative)",
        format!("{:.2} %", 100.0 * d.l1_rel),
        "test: < 2 %".into(),
    );
    t.row(
        case,
        "L1 error, rarefaction x <= x0",
        format!("{:.2} %", 100.0 * d.l1_rarefaction_rel),
        "test: < 1 %".into(),
    );
    t.row(
        case,
        "front (h > 1 cm) past the dam",
        format!("{:.1} m", d.front_m),
        format!(
            "exact {:.1} m ({:+.1} %; test: 15 %), tip {:.1} m",
            d.front_exact_1cm_m,
            100.0 * (d.front_m - d.front_exact_1cm_m) / d.front_exact_1cm_m,
            d.front_exact_m
        ),
    );
    let no_adv = dam_break(&AvalancheParams {
        momentum_advection: false,
        ..frictionless.clone()
    })?;
    t.row(
        case,
        "front without momentum advection",
        format!("{:.1} m", no_adv.front_m),
        format!("lags: exact {:.1} m", no_adv.front_exact_1cm_m),
    );
    Ok(())
}

/// The poured pile: its flank slope against the rest angle.
fn pile(t: &mut Table) -> Result<(), Box<dyn std::error::Error>> {
    let p = poured_pile(&AvalancheParams::paper())?;
    let case = "Poured pile (150 m³, θc=30°)";
    t.row(
        case,
        "mean flank slope",
        format!("{:.2}°", p.mean_flank_deg),
        "θc = 30° (test: ±2°)".into(),
    );
    t.row(
        case,
        "height",
        format!("{:.2} m", p.height_m),
        format!("30° cone {:.2} m (test: ±10 %)", p.cone_height_m),
    );
    Ok(())
}

/// A block run out from a 35° plane: the travel angle of its mass centre.
fn plane(t: &mut Table) -> Result<(), Box<dyn std::error::Error>> {
    for (theta, cell, stop) in [(30.0, 2.0, 0.0), (30.0, 1.0, 0.0), (25.0, 2.0, 0.01)] {
        let params = AvalancheParams {
            rest_angle_deg: theta,
            ..AvalancheParams::paper()
        };
        let options = RunOptions {
            stop_energy_fraction: stop,
            duration_s: 300.0,
            ..RunOptions::default()
        };
        let r = plane_runout(35.0, &params, cell, &options)?;
        let s = &r.summary;
        let case = format!("35° plane→flat θc={theta}° {cell} m");
        t.row(
            &case,
            "travel angle of the mass centre",
            format!("{:.2}°", s.travel_angle_deg),
            format!(
                "θc = {theta}° (test: ±1°); stop {:?} at {:.0} s",
                s.stop.unwrap(),
                s.simulated_s
            ),
        );
    }

    Ok(())
}

/// avaWog's release (`wog`: DEM, release, path line) on the paper's parameters.
fn avawog(t: &mut Table, wog: &[PathBuf; 3]) -> Result<(), Box<dyn std::error::Error>> {
    let r = run_release(
        &wog[0],
        &wog[1],
        1.0,
        ThicknessConvention::Vertical,
        &AvalancheParams::paper(),
        &RunOptions::default(),
    )?;
    let line = read_polyline(&wog[2])?;
    let s = &r.summary;
    let case = "avaWog relWog.shp (1 m)";
    t.row(
        case,
        "released",
        format!("{:.0} m³", s.released_volume_m3),
        format!("{} cells", r.release.count()),
    );
    t.row(
        case,
        "simulated time to stop",
        format!("{:.1} s", s.simulated_s),
        format!("{:?}, {} sub-steps", s.stop.unwrap(), s.substeps),
    );
    t.row(
        case,
        "wall time to stop",
        format!("{:.1} s", r.wall_s),
        "issue target ≤ 5 s".into(),
    );
    t.row(
        case,
        "runout length (release top)",
        format!("{:.0} m", s.runout_length_m),
        format!("alpha angle {:.2}°", s.alpha_angle_deg),
    );
    t.row(
        case,
        "travel angle of the mass centre",
        format!("{:.2}°", s.travel_angle_deg),
        format!(
            "{:.0} m over {:.0} m; θc = 30°",
            s.centre_drop_m, s.centre_travel_m
        ),
    );
    t.row(
        case,
        "footprint (peak > 1 cm)",
        format!("{:.0} m²", s.footprint_area_m2),
        String::new(),
    );
    let (x, y) = r.deposit_centre();
    t.row(
        case,
        "deposit centre to path line",
        format!("{:.1} m", distance_to_polyline(&line, x, y).0),
        "LINES/path_aimec.shp (test: < 50 m)".into(),
    );
    t.row(
        case,
        "volume closure",
        format!("{:.1e}", s.volume_closure_rel),
        "test: < 1e-6".into(),
    );
    t.row(
        case,
        "max speed / max thickness",
        format!("{:.1} m/s", s.max_speed_m_s),
        format!("{:.2} m", s.max_thickness_m),
    );
    Ok(())
}

/// avaKot's release (`kot`: DEM, release, AvaFrame's peak thickness) against AvaFrame.
fn avakot(t: &mut Table, kot: &[PathBuf; 3]) -> Result<(), Box<dyn std::error::Error>> {
    let r = run_release(
        &kot[0],
        &kot[1],
        1.0,
        ThicknessConvention::SlopeNormal,
        &AvalancheParams::paper(),
        &RunOptions::default(),
    )?;
    let reference = read_dem(&kot[2], &ReadOptions::default())?;
    let o = footprint_overlap(r.dem.geometry(), &r.peak_thickness, &reference, 0.01);
    let s = &r.summary;
    let case = "avaKot relKot.shp vs AvaFrame";
    t.row(
        case,
        "released (1 m slope-normal)",
        format!("{:.0} m³", s.released_volume_m3),
        format!("AvaFrame {:.0} m³", 4_328_073.727009 / 200.0),
    );
    t.row(
        case,
        "simulated / wall time to stop",
        format!("{:.1} s", s.simulated_s),
        format!("wall {:.1} s; AvaFrame 117.6 s", r.wall_s),
    );
    t.row(
        case,
        "footprint (peak > 1 cm)",
        format!("{:.0} m²", o.ours_m2),
        format!("AvaFrame {:.0} m²", o.reference_m2),
    );
    t.row(
        case,
        "Jaccard index of footprints",
        format!("{:.3}", o.jaccard),
        "test: ≥ 0.1".into(),
    );
    t.row(
        case,
        "share of AvaFrame's covered",
        format!("{:.3}", o.recall),
        "test: ≥ 0.9".into(),
    );
    t.row(
        case,
        "share of ours in AvaFrame's",
        format!("{:.3}", o.precision),
        String::new(),
    );
    t.row(
        case,
        "travel angle / alpha angle",
        format!("{:.2}°", s.travel_angle_deg),
        format!("alpha {:.2}°", s.alpha_angle_deg),
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let t_all = Instant::now();
    let mut t = Table { rows: Vec::new() };
    // Optional filter: run only the groups whose name contains it (ritter, pile, plane,
    // avawog, avakot).
    let only = std::env::args().nth(1).map(|a| a.to_ascii_lowercase());
    let want = |group: &str| only.as_deref().is_none_or(|o| group.contains(o));
    println!(
        "{:<28} {:<34} {:>18}   reference / expected",
        "case", "quantity", "measured"
    );
    println!("{}", "-".repeat(110));
    if want("ritter") {
        ritter(&mut t)?;
    }
    if want("pile") {
        pile(&mut t)?;
    }
    if want("plane") {
        plane(&mut t)?;
    }

    // Real paths.
    let dir = data_dir();
    let mut missing = Vec::new();
    let need = |rel: &str, missing: &mut Vec<PathBuf>| {
        let p = dir.join(rel);
        if !p.is_file() {
            missing.push(p.clone());
        }
        p
    };
    let wog = [
        need("dem/avaframe_avaWog/avaWog.asc", &mut missing),
        need("dem/avaframe_avaWog/REL/relWog.shp", &mut missing),
        need("dem/avaframe_avaWog/LINES/path_aimec.shp", &mut missing),
    ];
    if want("avawog") && wog.iter().all(|p| p.is_file()) {
        avawog(&mut t, &wog)?;
    }
    let kot = [
        need("dem/avaframe_avaKot/avaKot.asc", &mut missing),
        need("dem/avaframe_avaKot/REL/relKot.shp", &mut missing),
        need(
            "reference/avaframe_benchmarks/avaKotNullTest/relKot_989874a9be_C_S_null_dfa_pft.asc",
            &mut missing,
        ),
    ];
    if want("avakot") && kot.iter().all(|p| p.is_file()) {
        avakot(&mut t, &kot)?;
    }
    println!("{}", "-".repeat(110));
    println!(
        "{} rows in {:.1} s ({} rayon threads)",
        t.rows.len(),
        t_all.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
    if !missing.is_empty() {
        for m in &missing {
            eprintln!("missing real data: {}", m.display());
        }
        eprintln!("the real-path rows need the shared data folder (set SNOWSCAPE_DATA to it)");
        std::process::exit(2);
    }
    Ok(())
}
