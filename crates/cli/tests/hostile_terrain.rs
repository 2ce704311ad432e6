//! Regression tests of issue 19 item 6: a DEM that cannot be a terrain (1x1, 1xN, Nx1, all
//! nodata, a single valid cell, an altitude spike of 1e30) is refused by every front end
//! before any work or output (exit 2, a message naming the file and the value). Each case once
//! ran the whole season and failed with exit 1 (or succeeded with a closure error of 1.0),
//! leaving outputs behind.

mod common;

use common::{snowscape, stderr};
use std::path::Path;

/// An ESRI ASCII grid of `cols` x `rows` cells of 20 m with the given value rows.
fn asc(dir: &Path, name: &str, cols: usize, rows: usize, values: &str) -> String {
    let path = dir.join(name);
    let text = format!(
        "ncols {cols}\nnrows {rows}\nxllcorner 0\nyllcorner 0\ncellsize 20\nNODATA_value -9999\n{values}\n"
    );
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

/// A tilted 8x8 DEM with `cell` (col, row) set to `value`.
fn tilted_with(dir: &Path, name: &str, cell: (usize, usize), value: &str) -> String {
    let rows: Vec<String> = (0..8)
        .map(|r| {
            (0..8)
                .map(|c| {
                    if (c, r) == cell {
                        value.to_string()
                    } else {
                        format!("{}", 1500 + 30 * c + 5 * r)
                    }
                })
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect();
    asc(dir, name, 8, 8, &rows.join("\n"))
}

/// The bad terrains and what their message must name.
fn bad_terrains(dir: &Path) -> Vec<(String, Vec<&'static str>)> {
    let nodata_row = ["-9999"; 6].join(" ");
    let lone = format!("{nodata_row}\n-9999 -9999 1500 -9999 -9999 -9999\n{nodata_row}");
    vec![
        (
            asc(dir, "one.asc", 1, 1, "1500"),
            vec!["one.asc", "1x1", "at least 2x2"],
        ),
        (
            asc(dir, "row.asc", 6, 1, "1 2 3 4 5 6"),
            vec!["row.asc", "6x1"],
        ),
        (
            asc(dir, "column.asc", 1, 5, "1\n2\n3\n4\n5"),
            vec!["column.asc", "1x5"],
        ),
        (
            asc(dir, "void.asc", 6, 3, &[nodata_row.as_str(); 3].join("\n")),
            vec!["void.asc", "0 valid cells", "no 2x2 block"],
        ),
        (
            asc(dir, "lone.asc", 6, 3, &lone),
            vec!["lone.asc", "1 valid cells"],
        ),
        (
            tilted_with(dir, "spike.asc", (5, 3), "1e30"),
            vec!["spike.asc", "1e30", "col 5, row 3", "100000"],
        ),
        (
            tilted_with(dir, "deep.asc", (0, 7), "-2e5"),
            vec!["deep.asc", "-200000", "col 0, row 7"],
        ),
    ]
}

/// Runs `args` (with `--out OUT` appended where `out` is set) and checks exit 2, the
/// needles in the message and that OUT holds nothing.
fn refused(args: &[&str], out: Option<&Path>, needles: &[&str]) {
    let mut all: Vec<&str> = vec!["--quiet"];
    all.extend_from_slice(args);
    let out_s = out.map(|o| o.display().to_string());
    if let Some(o) = &out_s {
        all.extend_from_slice(&["--out", o]);
    }
    common::assert_refused(&snowscape(&all), args, out, needles);
}

#[test]
fn run_refuses_a_dem_that_cannot_be_a_terrain() {
    let d = tempfile::tempdir().unwrap();
    for (dem, needles) in bad_terrains(d.path()) {
        let out = d.path().join("out-run");
        refused(&["run", "--dem", &dem], Some(&out), &needles);
    }
}

#[test]
fn avalanche_transport_and_render_refuse_it_too() {
    let d = tempfile::tempdir().unwrap();
    for (dem, needles) in bad_terrains(d.path()) {
        let out = d.path().join("out-avalanche");
        refused(
            &["avalanche", "--dem", &dem, "--release", "10,10"],
            Some(&out),
            &needles,
        );
        let out = d.path().join("out-transport");
        refused(&["transport", "--dem", &dem], Some(&out), &needles);
        let out = d.path().join("out-render.png");
        refused(&["render", &dem], Some(&out), &needles);
    }
}

#[test]
fn info_still_describes_a_small_raster() {
    // `info` reads any raster: a 1x1 grid is a file to describe, not a terrain to simulate.
    let d = tempfile::tempdir().unwrap();
    let dem = asc(d.path(), "one.asc", 1, 1, "1500");
    let o = snowscape(&["info", &dem]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

#[test]
fn tiny_cells_without_a_crs_are_metres() {
    // A mesh voxelised at 1 cm, written without a CRS, once read back as 1112 m cells.
    let d = tempfile::tempdir().unwrap();
    let path = d.path().join("voxels.asc");
    let rows: Vec<String> = (0..4)
        .map(|r| {
            (0..4)
                .map(|c| format!("{}", 0.01 * (c + r) as f64))
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect();
    let text = format!(
        "ncols 4\nnrows 4\nxllcorner 0\nyllcorner 0\ncellsize 0.01\n{}\n",
        rows.join("\n")
    );
    std::fs::write(&path, text).unwrap();
    let o = snowscape(&["info", path.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(text.contains("0.0100 m x 0.0100 m"), "{text}");
}
