//! Regression tests of issue 19 item 7: readers refuse what is not a regular file (a device
//! read without end, a FIFO that blocks), glTF buffers outside the glTF's folder, and say
//! plainly what is wrong with a truncated TIFF or an ASC value beyond any height — exit 2,
//! the message naming the file and the value, nothing written, never a hang.

mod common;

use common::stderr;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Runs `snowscape args`, killing it if it runs past 30 s (a reader that blocks on a FIFO or
/// reads a device without end must fail the test, not hang it).
fn snowscape_within(args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_snowscape"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the snowscape binary runs");
    let t = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t.elapsed() > Duration::from_secs(30) {
            child.kill().unwrap();
            panic!("{args:?} still running after 30 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// Checks exit 2, the needles in the message and an empty `out` (when given).
fn refused(args: &[&str], out: Option<&Path>, needles: &[&str]) -> String {
    common::assert_refused(&snowscape_within(args), args, out, needles)
}

#[test]
fn devices_are_refused_not_read() {
    refused(
        &["info", "/dev/zero", "--format", "asc"],
        None,
        &["/dev/zero", "character device", "not a regular file"],
    );
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    refused(
        &[
            "--quiet",
            "run",
            "--dem",
            "/dev/zero",
            "--format",
            "tif",
            "--out",
            out.to_str().unwrap(),
        ],
        Some(&out),
        &["/dev/zero", "character device"],
    );
}

#[test]
fn a_fifo_is_refused_without_blocking() {
    let d = tempfile::tempdir().unwrap();
    for name in ["pipe.asc", "pipe.tif", "pipe.npy"] {
        let fifo = d.path().join(name);
        let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
        assert!(made.success(), "mkfifo {}", fifo.display());
        refused(
            &["info", fifo.to_str().unwrap()],
            None,
            &[name, "FIFO", "not a regular file"],
        );
    }
    // A FIFO as the scenario of a run.
    let dem = d.path().join("dem.asc");
    let rows = ["1500 1510 1520"; 3].join("\n");
    std::fs::write(
        &dem,
        format!("ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 20\n{rows}\n"),
    )
    .unwrap();
    let out = d.path().join("out");
    let fifo = d.path().join("pipe.asc");
    refused(
        &[
            "--quiet",
            "run",
            "--dem",
            dem.to_str().unwrap(),
            "--scenario",
            fifo.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        Some(&out),
        &["pipe.asc", "FIFO"],
    );
}

#[test]
fn gltf_buffer_outside_its_folder_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let scene = d.path().join("scene");
    std::fs::create_dir(&scene).unwrap();
    let bin: Vec<u8> = [0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|c| c.to_le_bytes())
        .collect();
    std::fs::write(d.path().join("outside.bin"), &bin).unwrap();
    let gltf = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
      "nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
                    "min":[0,0,0],"max":[1,1,0]}],
      "bufferViews":[{"buffer":0,"byteLength":36}],
      "buffers":[{"byteLength":36,"uri":"../outside.bin"}]}"#;
    let mesh = scene.join("roof.gltf");
    std::fs::write(&mesh, gltf).unwrap();
    let out = d.path().join("out");
    refused(
        &[
            "--quiet",
            "cover",
            "--mesh",
            mesh.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        Some(&out),
        &["roof.gltf", "../outside.bin", "outside the folder"],
    );
}

#[test]
fn truncated_tiff_says_truncated_once() {
    let d = tempfile::tempdir().unwrap();
    // A TIFF written by the project: a 120x120 ASC converted.
    let asc = d.path().join("dem.asc");
    let mut text = String::from("ncols 120\nnrows 120\nxllcorner 0\nyllcorner 0\ncellsize 10\n");
    for r in 0..120 {
        let row: Vec<String> = (0..120)
            .map(|c| {
                format!(
                    "{:.3}",
                    1500.0 + ((c * 7919 + r * 104_729) % 1000) as f64 * 0.37
                )
            })
            .collect();
        text.push_str(&row.join(" "));
        text.push('\n');
    }
    std::fs::write(&asc, text).unwrap();
    let tif = d.path().join("dem.tif");
    let o = snowscape_within(&["convert", asc.to_str().unwrap(), tif.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let bytes = std::fs::read(&tif).unwrap();
    let cut = d.path().join("cut.tif");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let out = d.path().join("out");
    for args in [
        vec!["info", cut.to_str().unwrap()],
        vec![
            "--quiet",
            "run",
            "--dem",
            cut.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
    ] {
        let err = refused(&args, Some(&out), &["cut.tif", "truncated"]);
        assert_eq!(err.matches("truncated").count(), 1, "{err}");
        assert!(!err.contains("failed to fill"), "{err}");
    }
}

#[test]
fn asc_value_beyond_any_height_is_quoted_as_written() {
    let d = tempfile::tempdir().unwrap();
    let asc = d.path().join("huge.asc");
    std::fs::write(
        &asc,
        "ncols 3\nnrows 3\nxllcorner 0\nyllcorner 0\ncellsize 20\nNODATA_value -9999\n\
         1500 1510 1520\n1500 1e999 1520\n1500 1510 1520\n",
    )
    .unwrap();
    let err = refused(
        &["info", asc.to_str().unwrap()],
        None,
        &["huge.asc:8", "\"1e999\"", "col 1, row 1"],
    );
    assert!(!err.contains("inf"), "{err}");
}
