//! End-to-end tests of the `snowscape` binary: the demo's outputs, determinism across thread
//! counts, `info`/`render`/`convert` on every real DEM, and bad input handled with exit code 2
//! and nothing half-written.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_snowscape"))
}

fn run(args: &[&str]) -> Output {
    bin()
        .args(args)
        .output()
        .expect("the snowscape binary runs")
}

fn data_dir() -> PathBuf {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/dem");
    assert!(
        d.is_dir(),
        "the real DEMs are missing: expected {} (the shared data folder beside the checkout)",
        d.display()
    );
    d
}

/// Every DEM file of the shared data (ESRI ASCII and GeoTIFF).
fn real_dems() -> Vec<PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(data_dir()).unwrap() {
        let dir = entry.unwrap().path();
        for f in std::fs::read_dir(&dir).unwrap() {
            let p = f.unwrap().path();
            if matches!(p.extension().and_then(|e| e.to_str()), Some("asc" | "tif")) {
                out.push(p);
            }
        }
    }
    out.sort();
    assert!(
        out.len() >= 10,
        "expected at least 10 real DEM files, found {}",
        out.len()
    );
    out
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn no_partial_files(dir: &Path) {
    for e in walk(dir) {
        let name = e.file_name().unwrap().to_string_lossy().into_owned();
        assert!(
            !name.ends_with(".partial"),
            "half-written file left: {}",
            e.display()
        );
    }
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd {
            let p = e.unwrap().path();
            if p.is_dir() {
                out.extend(walk(&p));
            } else {
                out.push(p);
            }
        }
    }
    out
}

#[test]
fn help_lists_the_verbs_and_examples() {
    let o = run(&["--help"]);
    assert!(o.status.success());
    let s = String::from_utf8_lossy(&o.stdout);
    for verb in [
        "demo",
        "info",
        "render",
        "convert",
        "bench",
        "Examples:",
        "Exit codes",
    ] {
        assert!(s.contains(verb), "--help lacks {verb}:\n{s}");
    }
}

#[test]
fn demo_writes_every_output_and_a_closed_budget() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("demo");
    let o = run(&[
        "--quiet",
        "demo",
        "--size",
        "128",
        "--days",
        "4",
        "--frames",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "demo failed: {}", stderr(&o));
    for f in [
        "depth.tif",
        "bedrock.tif",
        "layers_compacted.tif",
        "layers_stable.tif",
        "layers_unstable.tif",
        "layers_powder.tif",
        "layers.exr",
        "depth.png",
        "depth.png.json",
        "splat.png",
        "preview.png",
        "layers.png",
        "stability.png",
        "terrain.glb",
        "frames/frame_0000.png",
        "frames/frame_0001.png",
        "timelapse.gif",
        "report.json",
    ] {
        let p = out.join(f);
        let len = std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
        assert!(len > 0, "missing or empty output {f}");
    }
    no_partial_files(&out);
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    let budget = &report["mass_budget"];
    assert!(
        budget["inputs"]["snowfall"].as_f64().unwrap() > 0.0,
        "{budget}"
    );
    assert!(budget["closure_error"].as_f64().unwrap() < 1e-5, "{budget}");
    assert!(report["timings"]["terrain"].as_f64().unwrap() >= 0.0);
    assert_eq!(report["seed"], 1);
    assert_eq!(report["input"]["width"], 128);
}

#[test]
fn demo_is_bit_identical_across_thread_counts() {
    let d = tempfile::tempdir().unwrap();
    let mut depth = Vec::new();
    for threads in ["1", "2", "4"] {
        let out = d.path().join(format!("t{threads}"));
        let o = run(&[
            "--quiet",
            "--threads",
            threads,
            "demo",
            "--size",
            "128",
            "--days",
            "3",
            "--frames",
            "1",
            "--seed",
            "9",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        depth.push(std::fs::read(out.join("layers.exr")).unwrap());
        depth.push(std::fs::read(out.join("depth.tif")).unwrap());
    }
    assert_eq!(depth[0], depth[2]);
    assert_eq!(depth[0], depth[4]);
    assert_eq!(depth[1], depth[3]);
    assert_eq!(depth[1], depth[5]);
}

#[test]
fn info_and_render_work_on_every_real_dem() {
    let d = tempfile::tempdir().unwrap();
    for (k, dem) in real_dems().iter().enumerate() {
        let o = run(&["info", "--json", dem.to_str().unwrap()]);
        assert!(o.status.success(), "info {}: {}", dem.display(), stderr(&o));
        let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let cx = info["cell_size_x"].as_f64().unwrap();
        assert!(
            cx > 1.0 && cx < 500.0,
            "{}: metric cell size {cx}",
            dem.display()
        );
        let range = info["altitude_range"].as_array().unwrap();
        assert!(range[0].as_f64().unwrap() > -500.0 && range[1].as_f64().unwrap() < 9000.0);
        let png = d.path().join(format!("dem{k}.png"));
        let o = run(&[
            "render",
            dem.to_str().unwrap(),
            "--out",
            png.to_str().unwrap(),
        ]);
        assert!(
            o.status.success(),
            "render {}: {}",
            dem.display(),
            stderr(&o)
        );
        assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    }
}

#[test]
fn convert_keeps_grid_and_georeferencing() {
    let d = tempfile::tempdir().unwrap();
    let src = data_dir().join("avaframe_avaWog/avaWog.asc");
    let tif = d.path().join("wog.tif");
    let o = run(&["convert", src.to_str().unwrap(), tif.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let a: serde_json::Value =
        serde_json::from_slice(&run(&["info", "--json", src.to_str().unwrap()]).stdout).unwrap();
    let b: serde_json::Value =
        serde_json::from_slice(&run(&["info", "--json", tif.to_str().unwrap()]).stdout).unwrap();
    for key in [
        "width",
        "height",
        "cell_size_x",
        "crs",
        "origin",
        "altitude_range",
        "nodata_fraction",
    ] {
        assert_eq!(a[key], b[key], "{key} changed in conversion");
    }
}

#[test]
fn bad_input_exits_2_with_a_message_naming_it() {
    let d = tempfile::tempdir().unwrap();
    let missing = d.path().join("nope.asc");
    let o = run(&["info", missing.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("nope.asc"), "{}", stderr(&o));

    let nan = d.path().join("nan.asc");
    std::fs::write(
        &nan,
        "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\n1 2\nnan 4\n",
    )
    .unwrap();
    let o = run(&["info", nan.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));

    let neg = d.path().join("neg.asc");
    std::fs::write(
        &neg,
        "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize -10\n1 2\n3 4\n",
    )
    .unwrap();
    let o = run(&["info", neg.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("-10"), "{}", stderr(&o));

    let o = run(&["demo", "--size", "5"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains('5'));

    let o = run(&["render", neg.to_str().unwrap(), "--out", "x.jpg"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn unwritable_output_folder_is_reported_and_nothing_is_written() {
    let d = tempfile::tempdir().unwrap();
    let file = d.path().join("a_file");
    std::fs::write(&file, b"x").unwrap();
    let out = file.join("demo");
    let o = run(&[
        "--quiet",
        "demo",
        "--size",
        "128",
        "--days",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("a_file"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&file).unwrap(), b"x");
    assert_eq!(walk(d.path()).len(), 1);
}
