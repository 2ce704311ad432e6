//! Regression tests of issue 19 items 8 and 9: a damaged, truncated or foreign checkpoint is
//! refused with exit 2 and a message saying which (a flipped bit once resumed to exit 0 with
//! other outputs), and an output folder keeps no leftovers of an earlier run.

mod common;

use common::{report, snowscape, stderr};
use std::path::Path;

fn dem(dir: &Path) -> String {
    common::slope_dem(dir)
}

/// A run stopped at day 3 of 8 in `dir/run`; returns the DEM path and the checkpoint's bytes.
fn stopped_run(dir: &Path) -> (String, Vec<u8>) {
    let dem = dem(dir);
    let out = dir.join("run");
    let o = snowscape(&[
        "--quiet",
        "run",
        "--dem",
        &dem,
        "--days",
        "8",
        "--stop-at",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(out.join("checkpoint.bin")).unwrap();
    (dem, bytes)
}

fn resume(dir: &Path, dem: &str, extra: &[&str]) -> std::process::Output {
    let out = dir.join("run");
    let mut args = vec![
        "--quiet",
        "run",
        "--dem",
        dem,
        "--resume",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    snowscape(&args)
}

#[test]
fn damaged_checkpoints_are_refused_saying_how() {
    let d = tempfile::tempdir().unwrap();
    let (dem, bytes) = stopped_run(d.path());
    let ckpt = d.path().join("run/checkpoint.bin");
    for at in [bytes.len() / 3, bytes.len() / 2, bytes.len() - 8] {
        let mut flipped = bytes.clone();
        flipped[at] ^= 0x10;
        std::fs::write(&ckpt, &flipped).unwrap();
        let o = resume(d.path(), &dem, &[]);
        assert_eq!(o.status.code(), Some(2), "flip at {at}: {}", stderr(&o));
        assert!(stderr(&o).contains("corrupt"), "{}", stderr(&o));
        assert!(!d.path().join("run/depth.tif").exists());
    }
    std::fs::write(&ckpt, &bytes[..bytes.len() - 1000]).unwrap();
    let o = resume(d.path(), &dem, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert_eq!(err.matches("truncated").count(), 1, "{err}");
    assert!(
        err.contains(&format!("{} bytes", bytes.len() - 1000)),
        "{err}"
    );
    std::fs::write(&ckpt, b"SNOWCKPT").unwrap();
    let o = resume(d.path(), &dem, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("truncated"), "{}", stderr(&o));
    // Intact again: the resume finishes.
    std::fs::write(&ckpt, &bytes).unwrap();
    let o = resume(d.path(), &dem, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn a_resume_with_other_options_names_the_one_that_changed() {
    let d = tempfile::tempdir().unwrap();
    let (dem, _) = stopped_run(d.path());
    let o = resume(d.path(), &dem, &["--days", "12"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("days = 8.0") && err.contains("days = 12.0"),
        "{err}"
    );
    let o = resume(d.path(), &dem, &["--seed", "9"]);
    assert!(stderr(&o).contains("seed = 1") && stderr(&o).contains("seed = 9"));
    // Another terrain of the same size: the message says the altitudes differ.
    let other = d.path().join("other.asc");
    let text = std::fs::read_to_string(&dem)
        .unwrap()
        .replace("1800", "1700");
    std::fs::write(&other, text).unwrap();
    let o = resume(d.path(), other.to_str().unwrap(), &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("another terrain") && stderr(&o).contains("other altitudes"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn an_output_folder_keeps_nothing_of_an_earlier_run() {
    let d = tempfile::tempdir().unwrap();
    let dem = dem(d.path());
    let out = d.path().join("out");
    let o_str = out.to_str().unwrap();
    let sc = d.path().join("many_frames.toml");
    // Storms heavy enough for the skiers' 0.3 m of skiable snow within the four days.
    std::fs::write(
        &sc,
        "snapshot_every_days = 1\n[parameters.climate]\nprecipitation_mm_per_day = 40\n",
    )
    .unwrap();
    let o = snowscape(&[
        "--quiet",
        "run",
        "--dem",
        &dem,
        "--days",
        "4",
        "--skiers",
        "12",
        "--scenario",
        sc.to_str().unwrap(),
        "--out",
        o_str,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("ski_tracks.geojson").is_file());
    let frames_before = std::fs::read_dir(out.join("frames")).unwrap().count();
    // Leftovers of an interrupted write, and a file of the user's own.
    std::fs::write(out.join(".snowscape-AbC123.partial"), b"half").unwrap();
    std::fs::write(out.join("frames/.snowscape-x.partial"), b"half").unwrap();
    std::fs::write(out.join("notes.txt"), b"mine").unwrap();
    let o = snowscape(&[
        "--quiet", "run", "--dem", &dem, "--days", "4", "--out", o_str,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!out.join("ski_tracks.geojson").exists());
    assert!(!out.join(".snowscape-AbC123.partial").exists());
    assert!(!out.join("frames/.snowscape-x.partial").exists());
    assert!(
        out.join("notes.txt").is_file(),
        "a file of the user's was removed"
    );
    let r = report(&out);
    let removed: Vec<&str> = r["removed_stale"]
        .as_array()
        .expect("removed_stale is listed")
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(removed.contains(&"ski_tracks.geojson"), "{removed:?}");
    // Every file the report lists exists, and every frame on disk is listed.
    for f in r["outputs"].as_array().unwrap() {
        assert!(out.join(f.as_str().unwrap()).is_file(), "{f} is listed");
    }
    let frames_now: Vec<String> = std::fs::read_dir(out.join("frames"))
        .unwrap()
        .map(|e| format!("frames/{}", e.unwrap().file_name().to_string_lossy()))
        .collect();
    assert!(frames_now.len() < frames_before, "{frames_now:?}");
    for f in &frames_now {
        assert!(
            r["outputs"].as_array().unwrap().iter().any(|o| o == f),
            "{f} stayed but is not listed"
        );
    }
}
