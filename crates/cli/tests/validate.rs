//! End-to-end tests of `snowscape validate`: a tiny demo run compared with "observed" rasters
//! made from its own depth (resampled onto other cells and origins: ρ ≈ 1; shuffled: ρ ≈ 0),
//! and bad input refused with exit code 2 and a message naming the flag, file or value.

mod common;

use common::{snowscape, stderr};
use snowscape_io::{RasterFormat, ReadOptions, read_dem, write_raster};
use snowscape_terrain::{GeoTransform, Grid, GridGeometry, NodataMask};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// One demo run shared by the tests of this file (128² cells of 20 m, 10 days).
fn demo_run() -> &'static Path {
    static RUN: OnceLock<PathBuf> = OnceLock::new();
    RUN.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("validate_demo");
        let _ = std::fs::remove_dir_all(&dir);
        let o = snowscape(&[
            "demo",
            "--quiet",
            "--size",
            "128",
            "--days",
            "10",
            "--frames",
            "1",
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "demo failed: {}", stderr(&o));
        dir
    })
}

fn run_depth() -> Grid {
    read_dem(&demo_run().join("depth.tif"), &ReadOptions::default()).unwrap()
}

/// The run's depth bilinearly resampled onto `pixel`-metre cells whose grid starts `shift`
/// metres from the run's corner (nodata where the run does not reach).
fn resampled(pixel: f64, shift: (f64, f64), cols: usize, rows: usize) -> Grid {
    let depth = run_depth();
    let t = depth.geometry().transform();
    let g = GridGeometry::from_transform(
        cols,
        rows,
        GeoTransform {
            origin_x: t.origin_x + shift.0,
            origin_y: t.origin_y + shift.1,
            pixel_width: pixel,
            pixel_height: pixel,
        },
        None,
    )
    .unwrap();
    let mut invalid = vec![false; g.len()];
    let mut data = vec![0.0f32; g.len()];
    for r in 0..rows {
        for c in 0..cols {
            let (x, y) = g.cell_centre(c, r);
            match depth.sample_map(x, y) {
                Some(v) => data[g.index(c, r)] = v,
                None => invalid[g.index(c, r)] = true,
            }
        }
    }
    Grid::new(g, data, NodataMask::from_invalid(invalid)).unwrap()
}

/// The valid values of `grid` in a fixed pseudo-random order.
fn shuffled(grid: &Grid) -> Grid {
    let mut values = grid.data().to_vec();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    for i in (1..values.len()).rev() {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        values.swap(i, (state >> 33) as usize % (i + 1));
    }
    Grid::new(grid.geometry().clone(), values, NodataMask::all_valid()).unwrap()
}

/// Runs `validate` on the demo run into a fresh output folder (removed when dropped).
fn validate(
    args: &[&str],
) -> (
    std::process::Output,
    Option<serde_json::Value>,
    tempfile::TempDir,
) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path();
    let run = demo_run().to_str().unwrap().to_string();
    let mut all = vec!["validate", "--run", &run, "--out", out.to_str().unwrap()];
    all.extend_from_slice(args);
    let o = snowscape(&all);
    let json = std::fs::read(out.join("validation.json"))
        .ok()
        .map(|b| serde_json::from_slice(&b).unwrap());
    (o, json, dir)
}

fn f(v: &serde_json::Value, pointer: &str) -> f64 {
    v.pointer(pointer)
        .and_then(|x| x.as_f64())
        .unwrap_or_else(|| panic!("{pointer} missing in {v:#}"))
}

#[test]
fn resampled_own_depth_agrees_and_a_shuffled_one_does_not() {
    let tmp = tempfile::tempdir().unwrap();
    // Finer (13 m, block-averaged), shifted 37 m west and 23 m north, reaching past the run.
    let fine = tmp.path().join("fine.asc");
    write_raster(
        &fine,
        &resampled(13.0, (-37.0, 23.0), 200, 200),
        RasterFormat::Asc,
    )
    .unwrap();
    let (o, json, out) = validate(&["--observed", fine.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v = json.unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    println!("{stdout}");
    assert!(stdout.contains("cells compared") && stdout.contains("altitude+northness"));
    assert_eq!(v["matching"]["sampling"], "block_average");
    assert!(f(&v, "/cells_compared") > 0.95 * 128.0 * 128.0, "{v:#}");
    assert!(f(&v, "/simulation/spearman") > 0.97, "{v:#}");
    assert!(f(&v, "/simulation/pearson") > 0.97, "{v:#}");
    assert!(f(&v, "/simulation/bias_m").abs() < 0.02, "{v:#}");
    assert!(f(&v, "/simulation/snow_cover/accuracy") > 0.95, "{v:#}");
    assert!(
        v["wind_from_source"]
            .as_str()
            .unwrap()
            .contains("report.json")
    );
    // The demo's weather blows from 250..300 degrees.
    let w = f(&v, "/ratios/wind_from_deg");
    assert!((250.0..=300.0).contains(&w), "{w}");
    // Same depth on both sides: the class ratios match.
    let ns = &v["ratios"]["north_south"];
    assert!(ns["cells_a"].as_u64().unwrap() > 0 && ns["cells_b"].as_u64().unwrap() > 0);
    if let (Some(s), Some(b)) = (ns["simulated"].as_f64(), ns["observed"].as_f64()) {
        assert!((s - b).abs() < 0.1 * b.abs().max(0.1), "{ns:#}");
    }
    // The baselines are there, and the altitude one has the observed distribution (up to
    // the interpolation between tied altitudes).
    assert!(
        f(&v, "/baselines/altitude_rank/metrics/bias_m").abs() < 1e-3,
        "{v:#}"
    );
    assert!(v["baselines"]["altitude_northness"]["fit"]["per_m_altitude"].is_number());
    for png in ["validation.png", "scatter.png"] {
        let img = image::open(out.path().join(png)).unwrap();
        assert!(img.width() > 200 && img.height() > 200, "{png}");
    }

    // Coarser (31 m, bilinear) GeoTIFF with another offset.
    let coarse = tmp.path().join("coarse.tif");
    write_raster(
        &coarse,
        &resampled(31.0, (11.0, -5.0), 80, 80),
        RasterFormat::GeoTiff,
    )
    .unwrap();
    let (o, json, _) = validate(&["--observed", coarse.to_str().unwrap(), "--wind-from", "0"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v = json.unwrap();
    assert_eq!(v["matching"]["sampling"], "bilinear");
    assert!(f(&v, "/simulation/spearman") > 0.9, "{v:#}");
    assert_eq!(v["wind_from_source"], "--wind-from");
    assert_eq!(f(&v, "/ratios/wind_from_deg"), 0.0);

    // Shuffled: no rank agreement left.
    let shuffled_path = tmp.path().join("shuffled.asc");
    let fine_grid = resampled(13.0, (-37.0, 23.0), 200, 200);
    let fine_valid = Grid::from_fn(fine_grid.geometry().clone(), |c, r| {
        fine_grid.get(c, r).unwrap_or(0.0)
    });
    write_raster(&shuffled_path, &shuffled(&fine_valid), RasterFormat::Asc).unwrap();
    let (o, json, _) = validate(&["--observed", shuffled_path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    println!("{}", String::from_utf8_lossy(&o.stdout));
    let v = json.unwrap();
    assert!(f(&v, "/simulation/spearman").abs() < 0.1, "{v:#}");

    // A mask keeping the western half only.
    let mask_path = tmp.path().join("mask.asc");
    let g = run_depth().geometry().clone();
    let half = Grid::from_fn(g, |c, _| if c < 64 { 1.0 } else { 0.0 });
    write_raster(&mask_path, &half, RasterFormat::Asc).unwrap();
    let (o, json, _) = validate(&[
        "--observed",
        fine.to_str().unwrap(),
        "--mask",
        mask_path.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v = json.unwrap();
    assert_eq!(
        f(&v, "/cells_compared") + f(&v, "/excluded/masked_out"),
        128.0 * 128.0
    );
    assert_eq!(f(&v, "/excluded/masked_out"), 64.0 * 128.0);
}

#[test]
fn bad_input_exits_2_naming_the_file_flag_or_value() {
    let tmp = tempfile::tempdir().unwrap();
    let check = |args: &[&str], needles: &[&str]| {
        let (o, json, _) = validate(args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        for n in needles {
            assert!(e.contains(n), "{args:?}: {n:?} not in {e}");
        }
        assert!(json.is_none(), "{args:?} wrote validation.json");
    };
    let missing = tmp.path().join("nope.tif");
    check(
        &["--observed", missing.to_str().unwrap()],
        &["--observed", "nope.tif"],
    );

    // Far away: both extents in the message.
    let far = tmp.path().join("far.asc");
    write_raster(
        &far,
        &resampled(20.0, (1.0e5, 0.0), 10, 10),
        RasterFormat::Asc,
    )
    .unwrap();
    check(
        &["--observed", far.to_str().unwrap()],
        &[
            "does not overlap",
            "far.asc",
            "x 100000..100200",
            "x 0..2560",
        ],
    );

    let fine = tmp.path().join("ok.asc");
    write_raster(
        &fine,
        &resampled(20.0, (0.0, 0.0), 128, 128),
        RasterFormat::Asc,
    )
    .unwrap();
    check(
        &[
            "--observed",
            fine.to_str().unwrap(),
            "--snow-threshold",
            "-0.1",
        ],
        &["--snow-threshold", "-0.1"],
    );
    // A mask that keeps nothing: no valid cells.
    let zero = tmp.path().join("zero.asc");
    let g = run_depth().geometry().clone();
    write_raster(&zero, &Grid::filled(g, 0.0), RasterFormat::Asc).unwrap();
    check(
        &[
            "--observed",
            fine.to_str().unwrap(),
            "--mask",
            zero.to_str().unwrap(),
        ],
        &["no cell to compare", "16384 are masked out"],
    );
    // A folder that is not a run.
    let o = snowscape(&[
        "validate",
        "--run",
        tmp.path().to_str().unwrap(),
        "--observed",
        fine.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("no depth.tif"), "{}", stderr(&o));
}
