use super::*;
use std::fs;

fn names(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

/// A job that writes `files` (each containing `content`) and commits them with a report.
fn job(root: &Path, files: &[&str], content: &str) -> Result<(), OutputError> {
    let folder = OutputFolder::open(root)?;
    for f in files {
        fs::write(folder.staged(f)?, content).unwrap();
    }
    folder.commit(&names(files), Some(b"{}"))
}

#[test]
fn a_commit_moves_the_outputs_into_place_and_records_them() {
    let d = tempfile::tempdir().unwrap();
    let root = d.path().join("out");
    job(&root, &["a.tif", "frames/frame_0000.png"], "one").unwrap();
    assert_eq!(fs::read_to_string(root.join("a.tif")).unwrap(), "one");
    assert!(root.join("frames/frame_0000.png").is_file());
    assert!(root.join(REPORT).is_file());
    assert!(!root.join(STAGING).exists(), "the staging folder is gone");
    let folder = OutputFolder::open(&root).unwrap();
    let mut earlier = folder.earlier();
    earlier.sort();
    assert_eq!(earlier, names(&["a.tif", "frames/frame_0000.png", REPORT]));
}

#[test]
fn only_recorded_unchanged_outputs_are_removed_as_stale() {
    let d = tempfile::tempdir().unwrap();
    let root = d.path();
    job(root, &["a.tif", "b.tif", "c.tif"], "one").unwrap();
    // The user edits c.tif after the run: it is theirs now.
    fs::write(root.join("c.tif"), "edited by the user").unwrap();
    // A file of the user's the program never wrote.
    fs::write(root.join("notes.txt"), "mine").unwrap();
    job(root, &["a.tif"], "two").unwrap();
    assert_eq!(fs::read_to_string(root.join("a.tif")).unwrap(), "two");
    assert!(
        !root.join("b.tif").exists(),
        "b.tif was this program's and stale"
    );
    assert!(root.join("c.tif").exists(), "a changed file is not removed");
    assert!(
        root.join("notes.txt").exists(),
        "an unrecorded file is not removed"
    );
}

#[test]
fn a_prepared_report_cannot_make_a_run_delete_anything() {
    let d = tempfile::tempdir().unwrap();
    let outside = d.path().join("home");
    fs::create_dir(&outside).unwrap();
    fs::write(outside.join("thesis.tex"), "years of work").unwrap();
    let root = d.path().join("downloaded_run");
    fs::create_dir(&root).unwrap();
    fs::write(root.join("data.csv"), "the user's").unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(&outside, root.join("link")).unwrap();
    // The outputs list of a report.json (what the previous version trusted) and a forged
    // manifest naming files through a linked folder and the user's own file.
    fs::write(
        root.join(REPORT),
        r#"{"outputs": ["link/thesis.tex", "data.csv", "../home/thesis.tex"]}"#,
    )
    .unwrap();
    let forged = serde_json::json!({"format": "snowscape-outputs", "files": [
        {"name": "link/thesis.tex", "bytes": 13, "modified_ns": 0},
        {"name": "../home/thesis.tex", "bytes": 13, "modified_ns": 0},
        {"name": "data.csv", "bytes": 1, "modified_ns": 0},
    ]});
    fs::write(root.join(MANIFEST), forged.to_string()).unwrap();
    job(&root, &["a.tif"], "x").unwrap();
    assert_eq!(
        fs::read_to_string(outside.join("thesis.tex")).unwrap(),
        "years of work"
    );
    assert_eq!(
        fs::read_to_string(root.join("data.csv")).unwrap(),
        "the user's"
    );
}

#[cfg(unix)]
#[test]
fn a_linked_subfolder_is_refused_and_nothing_is_written_through_it() {
    let d = tempfile::tempdir().unwrap();
    let outside = d.path().join("elsewhere");
    fs::create_dir(&outside).unwrap();
    let root = d.path().join("out");
    fs::create_dir(&root).unwrap();
    std::os::unix::fs::symlink(&outside, root.join("frames")).unwrap();
    let e = job(&root, &["a.tif", "frames/frame_0000.png"], "x").unwrap_err();
    assert!(
        matches!(e, OutputError::UnsafePath { .. }),
        "{e}: a linked frames/ is refused"
    );
    assert_eq!(fs::read_dir(&outside).unwrap().count(), 0);
    assert!(
        !root.join("a.tif").exists(),
        "nothing moved before the check"
    );
}

#[test]
fn a_failed_job_leaves_the_previous_outputs_whole() {
    let d = tempfile::tempdir().unwrap();
    let root = d.path();
    job(root, &["a.tif", "b.tif"], "one").unwrap();
    {
        // A second job writes half its files and fails (is dropped without a commit).
        let folder = OutputFolder::open(root).unwrap();
        fs::write(folder.staged("a.tif").unwrap(), "two").unwrap();
    }
    assert_eq!(fs::read_to_string(root.join("a.tif")).unwrap(), "one");
    assert_eq!(fs::read_to_string(root.join("b.tif")).unwrap(), "one");
    assert!(root.join(REPORT).is_file());
    assert!(!root.join(STAGING).exists());
}

#[test]
fn a_listed_output_that_was_not_written_fails_the_commit_before_anything_moves() {
    let d = tempfile::tempdir().unwrap();
    let root = d.path();
    job(root, &["a.tif"], "one").unwrap();
    let folder = OutputFolder::open(root).unwrap();
    fs::write(folder.staged("a.tif").unwrap(), "two").unwrap();
    let e = folder
        .commit(&names(&["a.tif", "missing.tif"]), Some(b"{}"))
        .unwrap_err();
    assert!(matches!(e, OutputError::NotStaged { .. }), "{e}");
    assert_eq!(fs::read_to_string(root.join("a.tif")).unwrap(), "one");
    assert!(root.join(REPORT).is_file());
}

#[test]
fn one_job_at_a_time_in_a_folder() {
    let d = tempfile::tempdir().unwrap();
    let first = OutputFolder::open(d.path()).unwrap();
    let e = OutputFolder::open(d.path()).unwrap_err();
    assert!(matches!(e, OutputError::Busy { .. }), "{e}");
    drop(first);
    OutputFolder::open(d.path()).unwrap();
}

#[test]
fn placing_early_retires_the_previous_run() {
    let d = tempfile::tempdir().unwrap();
    let root = d.path();
    job(root, &["a.tif", "b.tif"], "one").unwrap();
    let mut folder = OutputFolder::open(root).unwrap();
    fs::write(folder.staged("checkpoint.bin").unwrap(), "state").unwrap();
    folder.place(&names(&["checkpoint.bin"])).unwrap();
    // Killed here (no commit): the folder holds this run's checkpoint and nothing of the
    // previous run.
    drop(folder);
    assert!(root.join("checkpoint.bin").is_file());
    assert!(!root.join("a.tif").exists() && !root.join("b.tif").exists());
    assert!(!root.join(REPORT).exists());
    // The next job knows the checkpoint as this program's.
    let folder = OutputFolder::open(root).unwrap();
    assert_eq!(folder.earlier(), names(&["checkpoint.bin"]));
}

#[test]
fn names_that_leave_the_folder_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let folder = OutputFolder::open(d.path()).unwrap();
    for bad in ["../x", "/etc/passwd", "", "a/../../b", "./."] {
        assert!(
            matches!(folder.staged(bad), Err(OutputError::UnsafePath { .. })),
            "{bad:?}"
        );
    }
}
