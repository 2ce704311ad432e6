//! The season job of the library (`snowscape::season_run::run_season`) and the game-engine
//! export of its folder (`snowscape::engine_export::export_run`), as every front end runs
//! them, on the procedural terrain: the files and the typed report of a season into a folder,
//! its budget closing; a stop with a checkpoint and a cancel from the front end's `Control`,
//! each resumed to the bytes of the uninterrupted run; refusals before any work (nothing
//! written); the export of the finished folder for each engine.

use snowscape::control::{Control, Unattended};
use snowscape::engine_export::{Engine, ExportOptions, export_run};
use snowscape::render::PreviewOptions;
use snowscape::season::scenario::Scenario;
use snowscape::season_run::{
    ExtraParameters, GeneratedTerrain, SeasonJob, SeasonJobError, SeasonOutcome, run_season,
};
use snowscape::terrain::procedural::{AlpineParams, alpine};
use std::path::{Path, PathBuf};

const SIZE: usize = 96;
const DAYS: f64 = 6.0;

fn job(out: &Path) -> SeasonJob {
    let params = AlpineParams {
        size: SIZE,
        seed: 3,
        ..AlpineParams::default()
    };
    SeasonJob {
        command: "demo".into(),
        source: "procedural alpine terrain".into(),
        bedrock: alpine(&params).unwrap(),
        scenario: Scenario {
            seed: 3,
            days: DAYS,
            snapshot_every_days: DAYS / 2.0,
            checkpoint_every_days: 0.0,
            ..Scenario::default()
        },
        extra_parameters: ExtraParameters::Demo {
            terrain: GeneratedTerrain {
                size: params.size,
                seed: params.seed,
                cell_size_m: params.cell_size,
                relief_m: params.relief,
                base_altitude_m: params.base_altitude,
                generation_seconds: 0.0,
            },
        },
        out: out.to_path_buf(),
        resume: None,
        stop_at: None,
        forcing: None,
        view: PreviewOptions::default(),
        cog: false,
        write_scenario: false,
        memory_budget: None,
        friction_maps: Default::default(),
    }
}

fn bytes(dir: &Path, file: &str) -> Vec<u8> {
    std::fs::read(dir.join(file)).unwrap_or_else(|e| panic!("{}: {e}", dir.join(file).display()))
}

/// The folder's files, sorted (the lock and staging folders are gone after a job).
fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn a_season_into_a_folder_writes_its_files_and_a_closing_budget() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("season");
    let SeasonOutcome::Finished(report) = run_season(job(&out), &mut Unattended).unwrap() else {
        panic!("the season did not finish")
    };
    assert_eq!(report.command, "demo");
    assert_eq!(report.seed, 3);
    assert!(
        report.mass_budget.closure_error < 1e-5,
        "{:?}",
        report.mass_budget
    );
    let written = files(&out);
    for f in ["depth.tif", "bedrock.tif", "report.json", "preview.png"] {
        assert!(written.iter().any(|w| w == f), "{f} not in {written:?}");
    }
    // The report's outputs are the folder's files (and report.json itself).
    for f in &report.outputs {
        assert!(out.join(f).exists(), "{f} listed but not written");
    }
    let json: serde_json::Value = serde_json::from_slice(&bytes(&out, "report.json")).unwrap();
    assert_eq!(json["command"], "demo");

    // The finished folder exports for every engine, each into its own folder.
    for engine in [Engine::Unreal, Engine::Unity, Engine::Godot] {
        let dest = t.path().join(format!("{engine:?}"));
        let e = export_run(
            &out,
            &dest,
            &ExportOptions {
                engine,
                tile: None,
                with_snow: true,
            },
        )
        .unwrap();
        assert!(!e.files.is_empty());
        for f in &e.files {
            assert!(dest.join(f).is_file(), "{engine:?}: {f} missing");
        }
        assert!(e.z_range_m[1] > e.z_range_m[0]);
    }
    // Not a run folder: refused, naming the missing file.
    let e = export_run(
        t.path(),
        &t.path().join("x"),
        &ExportOptions {
            engine: Engine::Unreal,
            tile: None,
            with_snow: false,
        },
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("is not a snowscape run folder"),
        "{e}"
    );
}

/// Cancels the season once it has passed `day`.
struct CancelAfter {
    day: f64,
    seen: f64,
}

impl Control for CancelAfter {
    fn progress(&mut self, day: f64, _stop: f64) {
        self.seen = day;
    }
    fn cancelled(&mut self) -> bool {
        self.seen >= self.day
    }
}

/// Resumes the season in `dir` (stopped with a checkpoint) to its end.
fn resume(dir: &Path) -> PathBuf {
    let mut j = job(dir);
    j.resume = Some(dir.to_path_buf());
    let outcome = run_season(j, &mut Unattended).unwrap();
    assert!(matches!(outcome, SeasonOutcome::Finished(_)), "{outcome:?}");
    dir.to_path_buf()
}

#[test]
fn a_stop_and_a_cancel_resume_to_the_bytes_of_the_whole_season() {
    let t = tempfile::tempdir().unwrap();
    let whole = t.path().join("whole");
    run_season(job(&whole), &mut Unattended).unwrap();

    let stopped = t.path().join("stopped");
    let mut j = job(&stopped);
    j.stop_at = Some(2.5);
    let outcome = run_season(j, &mut Unattended).unwrap();
    // It stops at the first event past the day asked for, where the state is consistent.
    assert!(
        matches!(outcome, SeasonOutcome::Stopped { day } if (2.5..DAYS).contains(&day)),
        "{outcome:?}"
    );
    assert!(stopped.join("checkpoint.bin").is_file());

    let cancelled = t.path().join("cancelled");
    let mut control = CancelAfter {
        day: 1.0,
        seen: 0.0,
    };
    let outcome = run_season(job(&cancelled), &mut control).unwrap();
    let SeasonOutcome::Interrupted { day, .. } = outcome else {
        panic!("{outcome:?}")
    };
    assert!((1.0..DAYS).contains(&day), "cancelled at day {day}");
    assert!(cancelled.join("checkpoint.bin").is_file());

    for dir in [resume(&stopped), resume(&cancelled)] {
        for f in ["depth.tif", "layers.exr", "checkpoint.bin"] {
            assert!(
                bytes(&dir, f) == bytes(&whole, f),
                "{f} of {} differs from the whole season's",
                dir.display()
            );
        }
    }
}

#[test]
fn a_season_that_cannot_fit_or_resume_is_refused_before_any_work() {
    let t = tempfile::tempdir().unwrap();
    let out = t.path().join("never");
    let mut j = job(&out);
    j.memory_budget = Some(1 << 20);
    let e = run_season(j, &mut Unattended).unwrap_err();
    assert!(matches!(e, SeasonJobError::NotEnoughMemory(_)), "{e}");
    assert!(e.is_bad_input());
    assert!(!out.exists(), "a refused season created its folder");

    // A resume from a folder with no checkpoint: refused naming it, the folder kept as it was.
    let empty = t.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    std::fs::write(empty.join("mine.txt"), "keep").unwrap();
    let mut j = job(&empty);
    j.resume = Some(empty.clone());
    let e = run_season(j, &mut Unattended).unwrap_err();
    assert!(e.is_bad_input(), "{e}");
    assert!(e.to_string().contains("empty"), "{e}");
    assert_eq!(files(&empty), ["mine.txt"]);
}
