//! The validation job of the library (`snowscape::validation::run`) on a run folder made from
//! the real Idaho 50 m DEM (../shared/data): a depth that grows with altitude compared with
//! itself (ρ = 1) and with a mask, its files and typed `validation.json`, and its typed
//! refusals.

use snowscape::io::{ReadOptions, read_dem, write_geotiff};
use snowscape::terrain::Grid;
use snowscape::validation::{Naming, ValidateJob, ValidationError, ValidationInput, run, run_with};
use std::path::{Path, PathBuf};

/// A run folder: the Idaho DEM as `bedrock.tif`, a depth of 0.5 m per 100 m above its lowest
/// cell as `depth.tif`; and that depth as the observed raster.
fn run_folder(dir: &Path) -> (PathBuf, PathBuf) {
    let dem_path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/dem/rme_idaho_50m/dem.asc");
    assert!(
        dem_path.is_file(),
        "the Idaho DEM is missing: expected {} (shared data folder beside the checkout)",
        dem_path.display()
    );
    let dem = read_dem(&dem_path, &ReadOptions::default()).unwrap();
    let (lo, _) = dem.value_range().unwrap();
    let depth: Vec<f32> = dem.data().iter().map(|z| (z - lo) / 200.0).collect();
    let depth = Grid::new(dem.geometry().clone(), depth, dem.mask().clone()).unwrap();
    let run = dir.join("run");
    std::fs::create_dir_all(&run).unwrap();
    write_geotiff(&run.join("bedrock.tif"), &dem).unwrap();
    write_geotiff(&run.join("depth.tif"), &depth).unwrap();
    let observed = dir.join("observed.tif");
    write_geotiff(&observed, &depth).unwrap();
    (run, observed)
}

fn job(run: &Path, observed: &Path) -> ValidateJob {
    ValidateJob {
        run: run.to_path_buf(),
        observed: observed.to_path_buf(),
        mask: None,
        out: None,
        snow_threshold_m: 0.05,
        wind_from_deg: None,
    }
}

#[test]
fn a_run_against_itself_scores_one_and_writes_the_typed_report() {
    let t = tempfile::tempdir().unwrap();
    let (run_dir, observed) = run_folder(t.path());
    let o = run(&job(&run_dir, &observed)).unwrap();
    let r = &o.report;
    assert_eq!(r.command, "validate");
    assert_eq!(o.out, run_dir.join("validation"));
    assert!(
        r.wind_from_source.starts_with("default 270"),
        "{}",
        r.wind_from_source
    );
    let v = &r.validation;
    assert!(v.cells_compared > 100, "{}", v.cells_compared);
    assert!((v.simulation.spearman.unwrap() - 1.0).abs() < 1e-12);
    assert!(v.simulation.rmse_m < 1e-6);
    for name in ["validation.json", "validation.png", "scatter.png"] {
        assert!(o.out.join(name).is_file(), "{name}");
    }
    let written: serde_json::Value =
        serde_json::from_slice(&std::fs::read(o.out.join("validation.json")).unwrap()).unwrap();
    assert_eq!(written, serde_json::to_value(r).unwrap());
    // A mask of the upper half (by altitude) compares fewer cells; a given wind is told.
    let depth = read_dem(&run_dir.join("depth.tif"), &ReadOptions::default()).unwrap();
    let median = {
        let mut d: Vec<f32> = depth.data().to_vec();
        d.sort_by(f32::total_cmp);
        d[d.len() / 2]
    };
    let upper: Vec<f32> = depth
        .data()
        .iter()
        .map(|&d| f32::from(d > median))
        .collect();
    let mask = t.path().join("mask.tif");
    write_geotiff(
        &mask,
        &Grid::new(depth.geometry().clone(), upper, depth.mask().clone()).unwrap(),
    )
    .unwrap();
    let mut j = job(&run_dir, &observed);
    j.mask = Some(mask);
    j.wind_from_deg = Some(180.0);
    j.out = Some(t.path().join("masked"));
    let m = run(&j).unwrap();
    assert!(m.report.validation.cells_compared < v.cells_compared);
    assert_eq!(m.report.wind_from_source, "--wind-from");
    assert_eq!(
        m.report.validation.excluded.masked_out,
        v.cells_compared - m.report.validation.cells_compared
    );
}

#[test]
fn bad_input_is_refused_typed() {
    let t = tempfile::tempdir().unwrap();
    let (run_dir, observed) = run_folder(t.path());
    let mut j = job(&run_dir, &observed);
    j.snow_threshold_m = -1.0;
    let e = run(&j).unwrap_err();
    assert!(
        matches!(
            e,
            ValidationError::BadParameter {
                input: ValidationInput::SnowThreshold,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.is_bad_input());
    // Each front end hears the input by its own name: the flag, or the Python keyword.
    assert_eq!(e.to_string(), e.message(Naming::Flags));
    assert!(e.to_string().starts_with("--snow-threshold -1: "), "{e}");
    assert!(
        e.message(Naming::Parameters)
            .starts_with("snow_threshold=-1: "),
        "{e}"
    );
    let e = run(&job(&run_dir, Path::new("no/such/observed.tif"))).unwrap_err();
    assert!(
        matches!(
            e,
            ValidationError::MissingFile {
                input: ValidationInput::Observed,
                ..
            }
        ),
        "{e}"
    );
    let e = run(&job(&t.path().join("observed.tif"), &observed)).unwrap_err();
    assert!(
        matches!(
            e,
            ValidationError::MissingFile {
                input: ValidationInput::Run,
                ..
            }
        ),
        "{e}"
    );
    assert!(!run_dir.join("validation").exists());
}

/// Hears the stages and cancels once `after` of them have begun.
struct CancelAfter {
    after: usize,
    heard: Vec<String>,
}

impl snowscape::control::Control for CancelAfter {
    fn status(&mut self, line: &str) {
        self.heard.push(line.to_string());
    }
    fn cancelled(&mut self) -> bool {
        self.heard.len() >= self.after
    }
}

#[test]
fn the_stages_are_heard_and_a_cancel_between_them_writes_nothing() {
    let t = tempfile::tempdir().unwrap();
    let (run_dir, observed) = run_folder(t.path());
    for after in [1, 2, 3] {
        let mut control = CancelAfter {
            after,
            heard: Vec::new(),
        };
        let e = run_with(&job(&run_dir, &observed), &mut control).unwrap_err();
        assert!(matches!(e, ValidationError::Cancelled { .. }), "{e}");
        assert!(!e.is_bad_input());
        assert_eq!(control.heard.len(), after);
        let out = run_dir.join("validation");
        assert!(
            !out.join("validation.json").exists(),
            "a cancel after {after} stages wrote its report"
        );
    }
    // Unattended, all three stages run and the files are written.
    let mut control = CancelAfter {
        after: usize::MAX,
        heard: Vec::new(),
    };
    run_with(&job(&run_dir, &observed), &mut control).unwrap();
    assert_eq!(
        control.heard,
        ["reading the rasters", "comparing", "writing outputs"]
    );
    assert!(run_dir.join("validation/validation.json").is_file());
}
