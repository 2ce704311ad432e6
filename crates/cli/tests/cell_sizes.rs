//! Issue 46 item 3: work and memory are bounded by the cells, never by a distance in metres
//! divided by the cell size. A DEM in degrees without a CRS once aborted allocating 215 GB;
//! 1 mm cells aborted (149 GB), 1 cm cells took 1.5 GB for 32×32 cells, 1e-320 m panicked and
//! 1e300 m ran with budgets of `null`.

mod common;

use common::{shared, snowscape, stderr};
use std::path::Path;

/// A 32×32 ESRI ASCII terrain of `cell` metres.
fn terrain(dir: &Path, cell: &str) -> String {
    let path = dir.join(format!("t_{cell}.asc"));
    let mut text = format!(
        "ncols 32\nnrows 32\nxllcorner 0\nyllcorner 0\ncellsize {cell}\nNODATA_value -9999\n"
    );
    for r in 0..32 {
        let row: Vec<String> = (0..32)
            .map(|c| {
                format!(
                    "{:.2}",
                    1800.0 + 5.0 * (c as f64 * 0.3).sin() + 3.0 * r as f64
                )
            })
            .collect();
        text.push_str(&row.join(" "));
        text.push('\n');
    }
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

fn run(dem: &str, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "--quiet",
        "run",
        "--dem",
        dem,
        "--days",
        "2",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    snowscape(&args)
}

#[test]
fn absurd_cell_sizes_are_refused_naming_the_value() {
    let d = tempfile::tempdir().unwrap();
    for cell in ["1e-320", "1e-6", "1e300", "1e6"] {
        let out = d.path().join(format!("out_{cell}"));
        let o = run(&terrain(d.path(), cell), &out, &[]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{cell}: {err}");
        assert!(err.contains("cell size"), "{cell}: {err}");
        assert!(!out.exists(), "{cell}: an output folder was made");
    }
    let o = snowscape(&[
        "--quiet",
        "demo",
        "--cell-size",
        "1e-9",
        "--out",
        "/nonexistent/x",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--cell-size"), "{}", stderr(&o));
}

#[test]
fn tiny_cells_run_in_memory_bounded_by_the_cells() {
    // 1 mm and 1 cm cells: within the terrain range, they run; the neighbourhoods are capped
    // in cells (the Sx search once padded the grid by 100 m / 1 cm = 10 000 cells a side).
    let d = tempfile::tempdir().unwrap();
    for cell in ["0.001", "0.01"] {
        let out = d.path().join(format!("out_{cell}"));
        let o = run(&terrain(d.path(), cell), &out, &[]);
        assert!(o.status.success(), "{cell}: {}", stderr(&o));
        let r = common::report(&out);
        assert!(
            r["mass_budget"]["closure_error"].is_number(),
            "{cell}: {}",
            r["mass_budget"]
        );
    }
}

#[test]
fn a_dem_in_degrees_without_a_crs_is_refused_with_the_flag_to_set() {
    let dem = shared("dem/matplotlib_jacksboro/jacksboro_fault_dem_deg.asc");
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let dem = dem.to_str().unwrap();
    for cmd in ["run", "avalanche"] {
        let mut args = vec!["--quiet", cmd, "--dem", dem, "--out", out.to_str().unwrap()];
        if cmd == "avalanche" {
            args.extend(["--release", "-84.25,36.6"]);
        }
        let o = snowscape(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{cmd}: {err}");
        assert!(
            err.contains("look like degrees") && err.contains("--crs EPSG:4326"),
            "{err}"
        );
        assert!(!out.exists());
    }
    // With the CRS it runs (metric cells from the latitude).
    let o = run(dem, &out, &["--crs", "EPSG:4326"]);
    assert!(o.status.success(), "{}", stderr(&o));
}
