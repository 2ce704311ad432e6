//! Helpers shared by the command-line tests: running the binary, the shared data folder, reports.
#![allow(dead_code)] // each test crate uses some of them

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `snowscape` with `args`.
pub fn snowscape(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_snowscape"))
        .args(args)
        .output()
        .expect("the snowscape binary runs")
}

/// A path under ../shared/data; fails loudly when it is missing (these tests exist to check
/// the program on real files).
pub fn shared(rel: &str) -> PathBuf {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(rel);
    assert!(
        p.exists(),
        "{} is missing: these tests need the shared data folder ../shared/data beside the checkout",
        p.display()
    );
    p
}

/// The `report.json` of an output folder.
pub fn report(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap()
}

/// A process's standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Width and height of a GeoTIFF written by snowscape.
pub fn tiff_size(path: &Path) -> (u32, u32) {
    let f = std::fs::File::open(path).unwrap();
    let mut d = tiff::decoder::Decoder::new(std::io::BufReader::new(f)).unwrap();
    d.dimensions().unwrap()
}

/// Checks that `o` (the run of `args`) was refused as a usage error: exit 2, each needle in
/// its message, and nothing in `out` (when given). Returns the message.
#[allow(dead_code)]
pub fn assert_refused(o: &Output, args: &[&str], out: Option<&Path>, needles: &[&str]) -> String {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: expected exit 2: {err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: expected {n:?} in: {err}");
    }
    if let Some(out) = out {
        assert!(
            !out.exists() || std::fs::read_dir(out).unwrap().next().is_none(),
            "{args:?}: outputs were written before the refusal"
        );
    }
    err
}

/// A 40x30 ESRI ASCII slope of 20 m cells written as `dir/dem.asc` (a small terrain for the
/// output-folder and checkpoint tests); returns its path.
pub fn slope_dem(dir: &Path) -> String {
    let path = dir.join("dem.asc");
    let mut text = String::from(
        "ncols 40\nnrows 30\nxllcorner 0\nyllcorner 0\ncellsize 20\nNODATA_value -9999\n",
    );
    for r in 0..30 {
        let row: Vec<String> = (0..40)
            .map(|c| format!("{:.1}", 1800.0 + 25.0 * c as f64 - 3.0 * r as f64))
            .collect();
        text.push_str(&row.join(" "));
        text.push('\n');
    }
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}
