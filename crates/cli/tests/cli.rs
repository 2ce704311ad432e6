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
        "validate",
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
    assert!(report["timings"]["environment"].as_f64().unwrap() >= 0.0);
    assert!(report["timings"]["season"].as_f64().unwrap() >= 0.0);
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
    for k in 2..6 {
        assert!(
            depth[k] == depth[k % 2],
            "output {k} differs across thread counts"
        );
    }
}

#[test]
fn info_and_render_work_on_every_real_dem() {
    let d = tempfile::tempdir().unwrap();
    for (k, dem) in real_dems().iter().enumerate() {
        // The Jacksboro grid is in degrees but has no CRS: only a geographic CRS makes
        // degrees (issue 19 item 6), so it is given as a user would.
        let crs: &[&str] = if dem.to_string_lossy().contains("_deg") {
            &["--crs", "EPSG:4326"]
        } else {
            &[]
        };
        let mut args = vec!["info", "--json", dem.to_str().unwrap()];
        args.extend_from_slice(crs);
        let o = run(&args);
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
        // A DEM in degrees without its CRS is refused as a terrain (naming --crs EPSG:4326).
        let mut args = vec![
            "render",
            dem.to_str().unwrap(),
            "--out",
            png.to_str().unwrap(),
        ];
        if !crs.is_empty() {
            let o = run(&args);
            assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
            assert!(stderr(&o).contains("--crs EPSG:4326"), "{}", stderr(&o));
        }
        args.extend_from_slice(crs);
        let o = run(&args);
        assert!(
            o.status.success(),
            "render {}: {}",
            dem.display(),
            stderr(&o)
        );
        let img = image::open(&png).unwrap();
        let w = info["width"].as_u64().unwrap() as u32;
        assert!(
            img.width() >= 16 && img.width() <= w.max(16),
            "{}: {} px",
            dem.display(),
            img.width()
        );
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

/// A small real DEM for season runs (Reynolds Mountain East, 19x18 cells of 50 m).
fn idaho() -> PathBuf {
    let p = data_dir().join("rme_idaho_50m/dem.asc");
    assert!(p.is_file(), "missing {}", p.display());
    p
}

#[test]
fn run_on_a_real_dem_writes_the_season_outputs() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("run");
    let dem = data_dir().join("avaframe_synthetic_avaDamBreak/DEM_IP_Topo.asc");
    let o = run(&[
        "--quiet",
        "run",
        "--dem",
        dem.to_str().unwrap(),
        "--days",
        "20",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "depth.tif",
        "layers.exr",
        "layers_powder.tif",
        "sun.tif",
        "temperature.tif",
        "wind.tif",
        "splat.png",
        "preview.png",
        "terrain.glb",
        "timelapse.gif",
        "frames/frame_0000.png",
        "report.json",
        "scenario.toml",
        "checkpoint.bin",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert!(report["mass_budget"]["closure_error"].as_f64().unwrap() < 1e-5);
    assert!(report["event_counts"]["wind_transport"].as_u64().unwrap() > 10);
    assert!(
        report["timings"]["phenomena"]["melt_and_stability"]
            .as_f64()
            .is_some()
    );
    // wind.tif has two bands: east and north components.
    let mut dec =
        tiff::decoder::Decoder::new(std::fs::File::open(out.join("wind.tif")).unwrap()).unwrap();
    assert_eq!(
        dec.colortype().unwrap(),
        tiff::ColorType::Gray(32).into_multiband(2)
    );
}

trait Bands {
    fn into_multiband(self, n: u16) -> tiff::ColorType;
}
impl Bands for tiff::ColorType {
    fn into_multiband(self, n: u16) -> tiff::ColorType {
        match self {
            tiff::ColorType::Gray(b) => tiff::ColorType::Multiband {
                bit_depth: b,
                num_samples: n,
            },
            other => other,
        }
    }
}

#[test]
fn a_stopped_and_resumed_run_is_bit_identical() {
    let d = tempfile::tempdir().unwrap();
    let dem = idaho();
    let full = d.path().join("full");
    let parts = d.path().join("parts");
    let args = |out: &Path| {
        vec![
            "--quiet".to_string(),
            "run".into(),
            "--dem".into(),
            dem.display().to_string(),
            "--days".into(),
            "30".into(),
            "--seed".into(),
            "4".into(),
            "--out".into(),
            out.display().to_string(),
        ]
    };
    let o = bin().args(args(&full)).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let mut stop = args(&parts);
    stop.extend(["--stop-at".into(), "13".into()]);
    let o = bin().args(&stop).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        !parts.join("depth.tif").exists(),
        "a stopped run writes no final outputs"
    );
    let o = run(&[
        "--quiet",
        "--threads",
        "1",
        "run",
        "--dem",
        dem.to_str().unwrap(),
        "--resume",
        parts.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "depth.tif",
        "layers.exr",
        "frames/frame_0000.png",
        "frames/frame_0002.png",
    ] {
        assert!(
            std::fs::read(full.join(f)).unwrap() == std::fs::read(parts.join(f)).unwrap(),
            "{f} differs between the uninterrupted and the resumed run"
        );
    }
}

#[test]
fn ctrl_c_writes_a_checkpoint_and_resume_finishes_identically() {
    let d = tempfile::tempdir().unwrap();
    let dem = idaho();
    let out = d.path().join("interrupted");
    let reference = d.path().join("reference");
    // A long season, so the interrupt arrives mid-run.
    let base = |o: &Path| {
        vec![
            "--quiet".to_string(),
            "run".into(),
            "--dem".into(),
            dem.display().to_string(),
            "--days".into(),
            "3000".into(),
            "--out".into(),
            o.display().to_string(),
        ]
    };
    let mut child = bin().args(base(&out)).spawn().unwrap();
    // Wait until the run is under way (its resolved scenario is written first).
    let t0 = std::time::Instant::now();
    while !out.join("scenario.toml").exists() && t0.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    std::thread::sleep(std::time::Duration::from_millis(500));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert_eq!(
        status.code(),
        Some(130),
        "the run finished before the interrupt arrived"
    );
    assert!(out.join("checkpoint.bin").is_file());
    assert!(!out.join("depth.tif").exists());
    let o = run(&[
        "--quiet",
        "run",
        "--dem",
        dem.to_str().unwrap(),
        "--resume",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = bin().args(base(&reference)).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        std::fs::read(out.join("layers.exr")).unwrap()
            == std::fs::read(reference.join("layers.exr")).unwrap(),
        "the interrupted and resumed run differs from the uninterrupted one"
    );
}

#[test]
fn malformed_scenario_names_the_key_and_line() {
    let d = tempfile::tempdir().unwrap();
    let sc = d.path().join("bad.toml");
    std::fs::write(&sc, "days = 20\n[parameters.melt]\nk_melt = \"fast\"\n").unwrap();
    let o = run(&[
        "run",
        "--dem",
        idaho().to_str().unwrap(),
        "--scenario",
        sc.to_str().unwrap(),
        "--out",
        d.path().join("o").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("bad.toml") && e.contains("line 3") && e.contains("k_melt"),
        "{e}"
    );
}

#[test]
fn parameters_lists_help_defaults_ranges_and_choices() {
    let o = run(&["parameters", "slope_shedding", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let list: Vec<serde_json::Value> = serde_json::from_slice(&o.stdout).unwrap();
    let find = |path: &str| {
        list.iter()
            .find(|p| p["path"] == path)
            .unwrap_or_else(|| panic!("no {path}"))
    };
    let p = find("slope_shedding.min_slope_deg");
    assert_eq!(
        (p["min"].as_f64(), p["max"].as_f64()),
        (Some(0.0), Some(90.0))
    );
    assert_eq!(p["default"], 60.0);
    assert!(p["help"].as_str().unwrap().starts_with("Slope below which"));
    assert_eq!(
        find("slope_shedding.law")["choices"],
        serde_json::json!(["exponential", "power_law"])
    );
    assert!(
        list.iter()
            .all(|p| p["path"].as_str().unwrap().starts_with("slope_shedding"))
    );
    let text = run(&["parameters", "melt.enhanced"]);
    assert!(text.status.success());
    assert!(String::from_utf8_lossy(&text.stdout).contains("melt.enhanced.min_window_hours = 24"));
    let bad = run(&["parameters", "no_such_section"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("no scenario parameter starts with"));
}

/// Runs `args` with stdout a pipe whose reading end is closed before the program writes
/// (`snowscape parameters | head` once head has gone): every write meets EPIPE.
fn with_stdout_closed(args: &[&str]) -> Output {
    use std::process::Stdio;
    let mut child = bin()
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the snowscape binary runs");
    drop(child.stdout.take());
    child.wait_with_output().unwrap()
}

#[test]
fn a_closed_stdout_pipe_ends_quietly() {
    // Issue 46 item 2: `println!` panicked ("failed printing to stdout: Broken pipe", exit 101).
    let dem = data_dir().join("rme_idaho_50m/dem.asc");
    let d = tempfile::tempdir().unwrap();
    let tif = d.path().join("out.tif");
    let png = d.path().join("out.png");
    for args in [
        vec!["parameters"],
        vec!["parameters", "--json"],
        vec!["info", dem.to_str().unwrap()],
        vec!["info", "--json", dem.to_str().unwrap()],
        vec!["convert", dem.to_str().unwrap(), tif.to_str().unwrap()],
        vec![
            "render",
            dem.to_str().unwrap(),
            "--out",
            png.to_str().unwrap(),
        ],
    ] {
        let o = with_stdout_closed(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
        assert!(
            !err.contains("panicked") && !err.contains("Broken pipe"),
            "{args:?}: {err}"
        );
    }
    // The work itself was done.
    assert!(tif.is_file() && png.is_file());
    // A reader that takes the first line and goes (`| head -1`) does not make it fail either.
    use std::io::BufRead;
    let mut child = bin()
        .args(["parameters"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    assert!(first.contains(" = "), "{first}");
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).is_empty(), "{}", stderr(&o));
}

#[test]
fn warnings_into_a_pipe_have_no_colour_codes_and_name_the_file_once() {
    // Issue 46 item 4: the tiny-cell warning went out as `\x1b[33m WARN\x1b[0m ...` into a
    // pipe. The Jacksboro grid is in degrees with no CRS: the warning is the one a user meets.
    let dem = data_dir().join("matplotlib_jacksboro/jacksboro_fault_dem_deg.asc");
    let o = run(&["info", dem.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("WARN"), "no warning: {err}");
    assert!(!err.contains('\x1b'), "colour codes into a pipe: {err:?}");
    for line in err.lines().filter(|l| l.contains("WARN")) {
        assert_eq!(
            line.matches("jacksboro_fault_dem_deg.asc").count(),
            1,
            "the path said more or less than once: {line}"
        );
    }
}

#[test]
fn avalanche_warnings_name_the_release_file_once_and_the_stop_reads_in_words() {
    // Issue 46 items 3 and 4: `relKot.shp: /…/relKot.shp: the release area is in EPSG:31287…`
    // and `ran 5.0 s (Some(Duration))`. avaKot's release polygon carries a CRS, its DEM none.
    let dem = data_dir().join("avaframe_avaKot/avaKot.asc");
    let rel = data_dir().join("avaframe_avaKot/REL/relKot.shp");
    let d = tempfile::tempdir().unwrap();
    let o = run(&[
        "avalanche",
        "--dem",
        dem.to_str().unwrap(),
        "--release",
        rel.to_str().unwrap(),
        "--duration",
        "1",
        "--out",
        d.path().join("av").to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    let warnings: Vec<&str> = err.lines().filter(|l| l.contains("WARN")).collect();
    assert!(!warnings.is_empty(), "{err}");
    for line in warnings {
        assert_eq!(line.matches("relKot.shp").count(), 1, "{line}");
        assert!(!line.contains('\x1b'), "{line:?}");
    }
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("(stopped: duration reached)"), "{out}");
    assert!(!out.contains("Some("), "{out}");
}

#[test]
fn convert_and_render_say_what_they_wrote_unless_quiet() {
    // Issue 46 item 5: both printed nothing on success.
    let dem = data_dir().join("rme_idaho_50m/dem.asc");
    let d = tempfile::tempdir().unwrap();
    let tif = d.path().join("idaho.tif");
    let o = run(&["convert", dem.to_str().unwrap(), tif.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let size = std::fs::metadata(&tif).unwrap().len();
    assert_eq!(out.lines().count(), 1, "{out}");
    assert!(
        out.starts_with(&format!("wrote {}", tif.display()))
            && out.contains("GeoTIFF")
            && out.contains("18 x 19 cells"),
        "{out}"
    );
    assert!(
        out.contains(&format!("{size} B")) || out.contains("KiB"),
        "{out}"
    );
    let png = d.path().join("idaho.png");
    let o = run(&[
        "render",
        dem.to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    let img = image::open(&png).unwrap();
    assert_eq!(out.lines().count(), 1, "{out}");
    assert!(
        out.starts_with(&format!("wrote {}", png.display()))
            && out.contains("PNG")
            && out.contains(&format!("{} x {} px", img.width(), img.height())),
        "{out}"
    );
    for args in [
        vec![
            "--quiet",
            "convert",
            dem.to_str().unwrap(),
            tif.to_str().unwrap(),
        ],
        vec![
            "--quiet",
            "render",
            dem.to_str().unwrap(),
            "--out",
            png.to_str().unwrap(),
        ],
    ] {
        let o = run(&args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        assert!(
            o.stdout.is_empty(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stdout)
        );
    }
}

#[test]
fn huge_and_deeply_nested_scenario_values_are_refused_briefly_with_their_place() {
    // Issue 46 item 6: messages echoed 10 MB values whole, and keys nested thousands deep
    // gave "recursion limit" with no line.
    let dem = data_dir().join("rme_idaho_50m/dem.asc");
    let d = tempfile::tempdir().unwrap();
    // 3 MB: under the 4 MiB a scenario may hold (a larger text is refused by size first).
    let huge = "x".repeat(3_000_000);
    let cases = [
        (
            "huge_value.toml",
            format!("days = 2\nstart_date = \"{huge}\"\n"),
            "start_date",
        ),
        ("huge_key.toml", format!("days = 2\n{huge} = 1\n"), "line 2"),
        (
            "too_big.toml",
            format!("days = 2\nstart_date = \"{huge}{huge}\"\n"),
            "a scenario may hold",
        ),
        (
            "deep.toml",
            format!("days = 2\n{} = 1\n", vec!["a"; 5000].join(".")),
            "line 2",
        ),
    ];
    for (name, text, needle) in cases {
        let f = d.path().join(name);
        std::fs::write(&f, text).unwrap();
        let out = d.path().join(format!("out_{name}"));
        let o = run(&[
            "run",
            "--dem",
            dem.to_str().unwrap(),
            "--scenario",
            f.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let err = stderr(&o);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{name}: {}",
            &err[..err.len().min(500)]
        );
        assert!(err.len() < 3000, "{name}: {} bytes of message", err.len());
        assert!(err.contains(name) && err.contains(needle), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
    }
}
