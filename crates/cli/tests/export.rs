//! `snowscape export --engine unreal|unity|godot` on a demo run: the engines' sizes and file
//! names, tiles sharing their edges, heights that decode back to the run's bedrock within one
//! 16-bit step, weight maps that sum to 255 in every texel, and bad input refused (exit 2).

mod common;

use common::snowscape;
use std::path::{Path, PathBuf};

fn ok(args: &[&str]) {
    let o = snowscape(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A 128² demo run of 60 days (snow on the upper slopes).
fn demo_run(dir: &Path) -> PathBuf {
    let run = dir.join("run");
    ok(&[
        "-q",
        "demo",
        "--size",
        "128",
        "--days",
        "60",
        "--frames",
        "1",
        "--out",
        run.to_str().unwrap(),
    ]);
    run
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// The run's bedrock: values, width, height (through the reader the CLI uses).
fn bedrock(run: &Path) -> (Vec<f32>, usize, usize) {
    let g = snowscape_io::read_dem(&run.join("bedrock.tif"), &Default::default()).unwrap();
    let (w, h) = (g.geometry().width(), g.geometry().height());
    (g.data().to_vec(), w, h)
}

fn gray16(path: &Path) -> (Vec<u16>, usize, usize) {
    let img = image::open(path).unwrap().into_luma16();
    let (w, h) = img.dimensions();
    (img.into_raw(), w as usize, h as usize)
}

#[test]
fn unreal_unity_and_godot_exports() {
    let tmp = tempfile::tempdir().unwrap();
    let run = demo_run(tmp.path());
    let (b, bw, bh) = bedrock(&run);
    // Unreal: 128 cells per axis -> 253 samples; both heightmaps, five weight maps.
    let out = tmp.path().join("unreal");
    ok(&[
        "-q",
        "export",
        "--run",
        run.to_str().unwrap(),
        "--engine",
        "unreal",
        "--with-snow",
        "--out",
        out.to_str().unwrap(),
    ]);
    let r = json(&out.join("unreal_import.json"));
    assert_eq!(r["size"], serde_json::json!([253, 253]));
    let (lo, hi) = (
        r["z_range_m"][0].as_f64().unwrap(),
        r["z_range_m"][1].as_f64().unwrap(),
    );
    let step = (hi - lo) / 65535.0;
    let (codes, w, h) = gray16(&out.join("heightmap_bedrock.png"));
    assert_eq!((w, h), (253, 253));
    let height = |k: usize| lo + f64::from(codes[k]) / 65535.0 * (hi - lo);
    // The corner samples are the corner cells; the centre sample is the bilinear mean of the
    // four central cells (128 cells: sample 126 of 253 lies at cell 63.5).
    assert!(
        (height(0) - f64::from(b[0])).abs() <= step,
        "{} vs {}",
        height(0),
        b[0]
    );
    let last = bw * bh - 1;
    assert!((height(253 * 253 - 1) - f64::from(b[last])).abs() <= step);
    let centre = [63 * bw + 63, 63 * bw + 64, 64 * bw + 63, 64 * bw + 64]
        .iter()
        .map(|&i| f64::from(b[i]))
        .sum::<f64>()
        / 4.0;
    assert!(
        (height(126 * 253 + 126) - centre).abs() <= 1.01 * step + 1e-3,
        "{} vs {centre}",
        height(126 * 253 + 126)
    );
    // Unreal's Z scale and location put code 0 at the lowest height and 65535 at the highest.
    let z = r["import"]["scale_z"].as_f64().unwrap();
    let loc = r["import"]["location_z_cm"].as_f64().unwrap();
    assert!((loc + (0.0 - 32768.0) * z / 128.0 - 100.0 * lo).abs() < 1e-6);
    assert!((loc + (65535.0 - 32768.0) * z / 128.0 - 100.0 * hi).abs() < 1e-6);
    // The snow surface is on the same scale and never below the bedrock.
    let (snow, _, _) = gray16(&out.join("heightmap_snow.png"));
    assert!(snow.iter().zip(&codes).all(|(s, b)| s >= b));
    assert!(snow.iter().zip(&codes).any(|(s, b)| s > b), "some snow");
    let weights: Vec<Vec<u8>> = ["compacted", "stable", "unstable", "powder", "rock"]
        .iter()
        .map(|l| {
            image::open(out.join(format!("weight_{l}.png")))
                .unwrap()
                .into_luma8()
                .into_raw()
        })
        .collect();
    for k in 0..253 * 253 {
        assert_eq!(
            weights.iter().map(|w| u32::from(w[k])).sum::<u32>(),
            255,
            "texel {k}"
        );
    }
    assert!(
        weights[4].iter().any(|&v| v < 255),
        "some snow in the weights"
    );

    // Unity: a 129² 16-bit little-endian RAW and two RGBA splat maps of 128².
    let out = tmp.path().join("unity");
    ok(&[
        "-q",
        "export",
        "--run",
        run.to_str().unwrap(),
        "--engine",
        "unity",
        "--out",
        out.to_str().unwrap(),
    ]);
    let u = json(&out.join("unity_import.json"));
    assert_eq!(u["import"]["heightmap_resolution"], 129);
    let raw = std::fs::read(out.join("heightmap_bedrock.raw")).unwrap();
    assert_eq!(raw.len(), 129 * 129 * 2);
    let (lo, hi) = (
        u["z_range_m"][0].as_f64().unwrap(),
        u["z_range_m"][1].as_f64().unwrap(),
    );
    let first = f64::from(u16::from_le_bytes([raw[0], raw[1]]));
    assert!((lo + first / 65535.0 * (hi - lo) - f64::from(b[0])).abs() <= (hi - lo) / 65535.0);
    let s0 = image::open(out.join("splatmap_0.png"))
        .unwrap()
        .into_rgba8();
    let s1 = image::open(out.join("splatmap_1.png"))
        .unwrap()
        .into_rgba8();
    assert_eq!(s0.dimensions(), (128, 128));
    for (p, q) in s0.pixels().zip(s1.pixels()) {
        let sum: u32 = p.0.iter().chain(q.0.iter()).map(|&v| u32::from(v)).sum();
        assert_eq!(sum, 255);
    }

    // Godot (HTerrain): RAW and EXR heightmaps, one RGBA splat map.
    let out = tmp.path().join("godot");
    ok(&[
        "-q",
        "export",
        "--run",
        run.to_str().unwrap(),
        "--engine",
        "godot",
        "--out",
        out.to_str().unwrap(),
    ]);
    for f in [
        "heightmap_bedrock.raw",
        "heightmap_bedrock.exr",
        "splatmap.png",
        "godot_import.json",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    let s = image::open(out.join("splatmap.png")).unwrap().into_rgba8();
    assert_eq!(s.dimensions(), (129, 129));
    assert!(
        s.pixels()
            .all(|p| p.0.iter().map(|&v| u32::from(v)).sum::<u32>() == 255)
    );
}

#[test]
fn unreal_tiles_share_their_edges() {
    let tmp = tempfile::tempdir().unwrap();
    let run = demo_run(tmp.path());
    let out = tmp.path().join("tiles");
    ok(&[
        "-q",
        "export",
        "--run",
        run.to_str().unwrap(),
        "--engine",
        "unreal",
        "--tile",
        "127",
        "--out",
        out.to_str().unwrap(),
    ]);
    // 253 samples in tiles of 127 sharing an edge: 2 x 2 tiles.
    for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        for f in [
            format!("heightmap_bedrock_x{i}_y{j}.png"),
            format!("weight_rock_x{i}_y{j}.png"),
        ] {
            assert!(out.join(&f).is_file(), "missing {f}");
        }
    }
    assert!(
        !out.join("heightmap_bedrock_x2_y0.png").exists(),
        "{:?}",
        std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect::<Vec<_>>()
    );
    let (a, aw, _) = gray16(&out.join("heightmap_bedrock_x0_y0.png"));
    let (b, bw, _) = gray16(&out.join("heightmap_bedrock_x1_y0.png"));
    assert_eq!((aw, bw), (127, 127));
    for r in 0..127 {
        assert_eq!(a[r * 127 + 126], b[r * 127], "row {r}: the shared edge");
    }
}

#[test]
fn bad_exports_exit_2_and_name_the_problem() {
    let tmp = tempfile::tempdir().unwrap();
    let empty = tmp.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let out = tmp.path().join("out");
    let o = snowscape(&[
        "export",
        "--run",
        empty.to_str().unwrap(),
        "--engine",
        "unity",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("bedrock.tif"), "{err}");
    assert!(!out.exists());
    let o = snowscape(&[
        "export",
        "--run",
        empty.to_str().unwrap(),
        "--engine",
        "unreal",
        "--tile",
        "1",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--tile 1"), "{err}");
}
