//! The avalanche job of the library (`snowscape::avalanche_job`) on the real avaKot DEM and
//! release (AvaFrame's test case, ../shared/data beside the checkout): the files and the typed
//! report of a run into a folder, the maps and summary of a run in memory (the Python
//! package's), and its typed refusals before any work.

use snowscape::avalanche_job::{
    self, AvalancheJob, AvalancheJobError, AvalancheSettings, OutputSpec, ReleaseReport,
};
use snowscape::avalanche_release::{ReleaseError, ReleaseSpec};
use snowscape::control::Unattended;
use snowscape::io::{ReadOptions, read_terrain};
use snowscape::render::PreviewOptions;
use std::path::{Path, PathBuf};

fn kot() -> (PathBuf, PathBuf) {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/dem/avaframe_avaKot");
    let (dem, rel) = (d.join("avaKot.asc"), d.join("REL/relKot.shp"));
    assert!(
        dem.is_file() && rel.is_file(),
        "the avaKot DEM and release are missing: expected {} and {} (shared data folder beside the checkout)",
        dem.display(),
        rel.display()
    );
    (dem, rel)
}

fn job(release: ReleaseSpec, output: Option<OutputSpec>) -> AvalancheJob {
    let (dem, _) = kot();
    let mut settings = AvalancheSettings::new(release);
    settings.run.duration_s = 2.0;
    settings.output = output;
    AvalancheJob {
        source: dem.display().to_string(),
        dem: read_terrain(&dem, &ReadOptions::default()).unwrap(),
        settings,
    }
}

#[test]
fn a_run_into_a_folder_writes_its_files_and_the_typed_report() {
    let (_, rel) = kot();
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("kot");
    let j = job(
        ReleaseSpec::File(rel.clone()),
        Some(OutputSpec {
            folder: out.clone(),
            frame_interval_s: 1.0,
            view: PreviewOptions::default(),
        }),
    );
    let o = avalanche_job::run(&j, &mut Unattended).unwrap();
    let r = &o.report;
    assert_eq!(r.command, "avalanche");
    assert_eq!(
        r.release,
        ReleaseReport::File {
            file: rel.display().to_string()
        }
    );
    assert!(r.release_cells > 0 && r.release_area_m2 > 0.0);
    assert!(r.released_volume_m3 > 0.0);
    assert!(r.simulated_s > 0.0 && r.simulated_s <= 2.0 + 1e-9);
    assert_eq!(
        r.parameters.thickness_measured.as_deref(),
        Some("slope-normal")
    );
    for name in [
        "frames/frame_0000.png",
        "peak_thickness.tif",
        "peak_velocity.tif",
        "thickness.tif",
        "footprint.tif",
        "avalanche.gif",
        "report.json",
    ] {
        assert!(
            r.outputs.iter().any(|f| f == name),
            "{name}: {:?}",
            r.outputs
        );
        assert!(out.join(name).is_file(), "{name}");
    }
    // The file is the typed report, key for key.
    let written: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(written, serde_json::to_value(r).unwrap());
}

#[test]
fn a_run_in_memory_gives_the_maps_and_the_flat_summary() {
    let (_, rel) = kot();
    let j = job(ReleaseSpec::File(rel), None);
    let o = avalanche_job::run(&j, &mut Unattended).unwrap();
    assert!(o.report.outputs.is_empty());
    let n = j.dem.geometry().len();
    let maps = o.maps();
    let names: Vec<&str> = maps.iter().map(|(n, _)| *n).collect();
    assert_eq!(
        names,
        ["peak_thickness", "peak_velocity", "deposit", "entrained"]
    );
    assert!(maps.iter().all(|(_, v)| v.len() == n));
    assert!(maps[0].1.iter().any(|&h| h > 0.0));
    let s = o.summary().to_json().unwrap();
    for key in [
        "released_volume_m3",
        "entrained_volume_m3",
        "deposited_volume_m3",
        "border_outflow_m3",
        "runout_length_m",
        "travel_angle_deg",
        "footprint_area_m2",
        "stop",
        "release_cells",
        "release_area_m2",
        "parameters",
    ] {
        assert!(s.get(key).is_some(), "{key}: {s}");
    }
    assert!(s.get("summary").is_none());
    assert_eq!(s["released_volume_m3"].as_f64(), Some(o.rest.released_m3));
}

#[test]
fn bad_values_are_refused_typed_before_any_work() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("never");
    let output = Some(OutputSpec {
        folder: out.clone(),
        frame_interval_s: 1.0,
        view: PreviewOptions::default(),
    });
    let e = avalanche_job::run(
        &job(ReleaseSpec::File("no/such/rel.shp".into()), output.clone()),
        &mut Unattended,
    )
    .unwrap_err();
    assert!(matches!(e, AvalancheJobError::NoReleaseFile(_)), "{e}");
    assert!(e.is_bad_input());
    let e = avalanche_job::run(
        &job(ReleaseSpec::Mask(vec![true; 10]), output.clone()),
        &mut Unattended,
    )
    .unwrap_err();
    assert!(
        matches!(e, AvalancheJobError::MaskSize { cells: 10, .. }),
        "{e}"
    );
    let mut j = job(ReleaseSpec::Point(0.0, 0.0), output.clone());
    j.settings.thickness_m = Some(51.0);
    let e = avalanche_job::run(&j, &mut Unattended).unwrap_err();
    assert!(
        matches!(e, AvalancheJobError::Release(ReleaseError::Thickness(t)) if t == 51.0),
        "{e}"
    );
    // A point off the DEM: the release is refused, nothing is written.
    let e = avalanche_job::run(&job(ReleaseSpec::Point(0.0, 0.0), output), &mut Unattended)
        .unwrap_err();
    assert!(matches!(e, AvalancheJobError::Release(_)), "{e}");
    assert!(!out.exists());
}

/// A front end that hears the flow and cancels it after a second of simulated time.
#[derive(Default)]
struct CancelAfterOneSecond {
    heard: Vec<(f64, f64)>,
    statuses: usize,
}

impl snowscape::control::Control for CancelAfterOneSecond {
    fn progress(&mut self, done: f64, total: f64) {
        self.heard.push((done, total));
    }
    fn status(&mut self, _line: &str) {
        self.statuses += 1;
    }
    fn cancelled(&mut self) -> bool {
        self.heard.last().is_some_and(|&(t, _)| t >= 1.0)
    }
}

#[test]
fn a_cancelled_run_stops_between_records_and_writes_nothing() {
    let (_, rel) = kot();
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("kot");
    let j = job(
        ReleaseSpec::File(rel),
        Some(OutputSpec {
            folder: out.clone(),
            frame_interval_s: 0.5,
            view: PreviewOptions::default(),
        }),
    );
    let mut control = CancelAfterOneSecond::default();
    let e = avalanche_job::run(&j, &mut control).unwrap_err();
    let AvalancheJobError::Cancelled { time_s } = e else {
        panic!("{e}")
    };
    assert!((1.0..1.5).contains(&time_s), "cancelled at {time_s} s");
    assert!(!e.is_bad_input());
    // The progress counted simulated seconds of the run's duration, with a status each time.
    assert!(control.heard.iter().all(|&(_, total)| total == 2.0));
    assert!(control.heard.windows(2).all(|w| w[0].0 <= w[1].0));
    assert_eq!(control.statuses, control.heard.len());
    // Nothing of the run is left: the folder it opened is empty (no output, no frames, no
    // staging folder, no lock), and nothing was written beside it.
    let left: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(left.is_empty(), "{left:?}");
    assert_eq!(std::fs::read_dir(t.path()).unwrap().count(), 1);
}
