//! Issue 46 items 1 and 8: a run touches nothing outside its output folder (no symbolic link
//! is followed out of it, a prepared `report.json` cannot make it delete anything), removes
//! only its own recorded outputs, holds the folder alone, and a run that fails leaves the
//! previous complete outputs as they were, never a mix of two runs.

mod common;

use common::{report, snowscape, stderr};
use std::path::{Path, PathBuf};

fn dem(dir: &Path) -> String {
    common::slope_dem(dir)
}

fn run(dem: &str, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "--quiet",
        "run",
        "--dem",
        dem,
        "--days",
        "3",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    snowscape(&args)
}

/// Every file under `dir`, relative, with its bytes.
fn contents(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut all = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let bytes = std::fs::read(&p).unwrap();
                all.push((p.strip_prefix(dir).unwrap().to_path_buf(), bytes));
            }
        }
    }
    all.sort();
    all
}

#[cfg(unix)]
#[test]
fn a_prepared_folder_cannot_make_a_run_delete_or_write_outside_it() {
    let d = tempfile::tempdir().unwrap();
    let dem = dem(d.path());
    let home = d.path().join("home");
    std::fs::create_dir(&home).unwrap();
    std::fs::write(home.join("thesis.tex"), "years of work").unwrap();
    std::fs::write(home.join("frame_0000.png"), "a user's picture").unwrap();
    // A downloaded run folder: a link to the user's home in the middle of the listed paths,
    // and a report listing them as outputs (what the previous version trusted).
    let out = d.path().join("downloaded");
    std::fs::create_dir(&out).unwrap();
    std::os::unix::fs::symlink(&home, out.join("link")).unwrap();
    std::fs::write(out.join("data.csv"), "the user's").unwrap();
    std::fs::write(
        out.join("report.json"),
        r#"{"outputs": ["link/thesis.tex", "data.csv", "link/frame_0000.png"]}"#,
    )
    .unwrap();
    let o = run(&dem, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(home.join("thesis.tex")).unwrap(),
        "years of work"
    );
    assert_eq!(
        std::fs::read_to_string(home.join("frame_0000.png")).unwrap(),
        "a user's picture"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("data.csv")).unwrap(),
        "the user's"
    );
    assert!(out.join("depth.tif").is_file());
    // A second run removes nothing of the user's either (only its own recorded outputs).
    let o = run(&dem, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(home.join("thesis.tex")).unwrap(),
        "years of work"
    );
    assert!(out.join("data.csv").is_file());
}

#[cfg(unix)]
#[test]
fn a_linked_frames_folder_is_refused_with_exit_2_and_nothing_written_through_it() {
    let d = tempfile::tempdir().unwrap();
    let dem = dem(d.path());
    let elsewhere = d.path().join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    std::fs::write(elsewhere.join("frame_0000.png"), "not a frame").unwrap();
    let out = d.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::os::unix::fs::symlink(&elsewhere, out.join("frames")).unwrap();
    let o = run(&dem, &out, &[]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("symbolic link"), "{err}");
    assert_eq!(
        std::fs::read_to_string(elsewhere.join("frame_0000.png")).unwrap(),
        "not a frame"
    );
    assert_eq!(std::fs::read_dir(&elsewhere).unwrap().count(), 1);
    assert!(
        !out.join("report.json").exists() && !out.join("depth.tif").exists(),
        "nothing is committed when one target is unsafe"
    );
}

#[test]
fn a_failed_rerun_leaves_the_previous_outputs_whole() {
    let d = tempfile::tempdir().unwrap();
    let dem = dem(d.path());
    let out = d.path().join("out");
    let o = run(&dem, &out, &["--seed", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A rerun (another seed: other frames and rasters) whose last output cannot be written:
    // a folder stands where the time-lapse goes.
    std::fs::remove_file(out.join("timelapse.gif")).unwrap();
    std::fs::create_dir(out.join("timelapse.gif")).unwrap();
    let before = contents(&out);
    let o = run(&dem, &out, &["--seed", "2"]);
    assert!(!o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("timelapse.gif"), "{}", stderr(&o));
    assert_eq!(
        contents(&out),
        before,
        "the folder mixes the files of two runs"
    );
    // Once the obstacle is gone the rerun goes through and replaces every output.
    std::fs::remove_dir(out.join("timelapse.gif")).unwrap();
    let o = run(&dem, &out, &["--seed", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(report(&out)["seed"], 2);
}

#[cfg(unix)]
#[test]
fn a_checkpoint_that_is_a_device_is_refused_before_it_is_read() {
    let d = tempfile::tempdir().unwrap();
    let dem = dem(d.path());
    let out = d.path().join("out");
    let o = run(&dem, &out, &["--stop-at", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let ck = out.join("checkpoint.bin");
    std::fs::remove_file(&ck).unwrap();
    std::os::unix::fs::symlink("/dev/zero", &ck).unwrap();
    let t0 = std::time::Instant::now();
    let o = snowscape(&[
        "--quiet",
        "run",
        "--dem",
        &dem,
        "--resume",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("character device"), "{err}");
    assert!(t0.elapsed().as_secs() < 30, "it read the device");
}

#[test]
fn two_runs_into_one_folder_do_not_mix_their_files() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    // A demo long enough to be caught running.
    let mut first = std::process::Command::new(env!("CARGO_BIN_EXE_snowscape"))
        .args(["--quiet", "demo", "--size", "256", "--days", "60", "--out"])
        .arg(&out)
        .spawn()
        .unwrap();
    let staging = out.join(".snowscape-staging");
    let t0 = std::time::Instant::now();
    while !staging.exists() && t0.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let o = snowscape(&[
        "--quiet",
        "demo",
        "--size",
        "128",
        "--days",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    let finished_first = first.wait().unwrap();
    assert!(finished_first.success());
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("in use by another snowscape job"), "{err}");
    // The folder holds the first run's outputs alone.
    let r = report(&out);
    assert_eq!(r["input"]["width"], 256, "{}", r["input"]);
    assert!(!staging.exists());
}
