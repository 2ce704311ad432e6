//! `snowscape avalanche --mu-raster/--xi-raster` on the real avaWog path: rasters of another
//! cell size matched by map coordinates, a raster of the law's own values giving the same bytes
//! as none, a rougher raster shortening the runout, and bad rasters refused (exit code 2,
//! nothing written) with the value or the flag named; a season's avalanches take the same rasters
//! (`run --mu-raster/--xi-raster`).

mod common;

use common::{shared, snowscape};
use std::path::{Path, PathBuf};

fn wog() -> (PathBuf, PathBuf) {
    (
        shared("dem/avaframe_avaWog/avaWog.asc"),
        shared("dem/avaframe_avaWog/REL/relWog.shp"),
    )
}

/// An ESRI ASCII grid of 20 m cells over avaWog's extent (x 167453-169902, y 361953-364727)
/// whose cell `(col, row)` holds `value(col, row)`, at `x0, y0` (lower-left corner).
fn write_asc(path: &Path, x0: f64, y0: f64, value: impl Fn(usize, usize) -> f64) {
    let (cols, rows) = (130, 150);
    let mut s = format!(
        "ncols {cols}\nnrows {rows}\nxllcorner {x0}\nyllcorner {y0}\ncellsize 20\nNODATA_value -9999\n"
    );
    for r in 0..rows {
        let line: Vec<String> = (0..cols).map(|c| value(c, r).to_string()).collect();
        s.push_str(&line.join(" "));
        s.push('\n');
    }
    std::fs::write(path, s).unwrap();
}

/// A 15 s Voellmy run of avaWog (μ = 0.25, ξ = 4096: both exact in the rasters' f32) with
/// `extra` flags into `dir`; its report.
fn run(dir: &Path, extra: &[&str]) -> serde_json::Value {
    let (dem, rel) = wog();
    let mut a = vec![
        "avalanche",
        "--dem",
        dem.to_str().unwrap(),
        "--release",
        rel.to_str().unwrap(),
        "--friction-model",
        "voellmy",
        "--mu",
        "0.25",
        "--xi",
        "4096",
        "--duration",
        "15",
        "--frame-interval",
        "15",
        "--out",
        dir.to_str().unwrap(),
        "-q",
    ];
    a.extend(extra);
    let o = snowscape(&a);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap()
}

#[test]
fn friction_rasters_match_by_coordinates_and_change_the_run() {
    let t = tempfile::tempdir().unwrap();
    let (mu_same, xi_same, mu_rough) = (
        t.path().join("mu_same.asc"),
        t.path().join("xi_same.asc"),
        t.path().join("mu_rough.asc"),
    );
    write_asc(&mu_same, 167400.0, 361900.0, |_, _| 0.25);
    write_asc(&xi_same, 167400.0, 361900.0, |_, _| 4096.0);
    // Rougher in the southern (lower) half of the raster, the law's value elsewhere.
    write_asc(&mu_rough, 167400.0, 361900.0, |_, r| {
        if r >= 75 { 0.5 } else { 0.25 }
    });
    let plain = run(&t.path().join("plain"), &[]);
    assert!(plain["friction_maps"].is_null());
    let same = run(
        &t.path().join("same"),
        &[
            "--mu-raster",
            mu_same.to_str().unwrap(),
            "--xi-raster",
            xi_same.to_str().unwrap(),
        ],
    );
    for name in ["peak_thickness.tif", "thickness.tif", "peak_velocity.tif"] {
        assert!(
            std::fs::read(t.path().join("plain").join(name)).unwrap()
                == std::fs::read(t.path().join("same").join(name)).unwrap(),
            "{name}: a raster of the law's own values changes no byte"
        );
    }
    let m = &same["friction_maps"]["mu"]["matched"];
    assert_eq!(m["defaulted_cells"].as_u64(), Some(0), "{m}");
    assert!(m["raster_cells"].as_u64().unwrap() > 100_000, "{m}");
    assert_eq!(m["min"].as_f64(), Some(0.25));
    assert_eq!(
        same["friction_maps"]["xi"]["matched"]["max"].as_f64(),
        Some(4096.0)
    );
    let rough = run(
        &t.path().join("rough"),
        &["--mu-raster", mu_rough.to_str().unwrap()],
    );
    let area = |r: &serde_json::Value| r["summary"]["footprint_area_m2"].as_f64().unwrap();
    let speed = |r: &serde_json::Value| r["summary"]["max_speed_m_s"].as_f64().unwrap();
    assert!(
        area(&rough) < area(&plain) && speed(&rough) < speed(&plain),
        "footprint {} against {} m², speed {} against {} m/s",
        area(&rough),
        area(&plain),
        speed(&rough),
        speed(&plain)
    );
    assert_eq!(
        rough["friction_maps"]["mu"]["matched"]["max"].as_f64(),
        Some(0.5)
    );
}

#[test]
fn bad_friction_rasters_exit_2_and_write_nothing() {
    let (dem, rel) = wog();
    let t = tempfile::tempdir().unwrap();
    let good = t.path().join("mu.asc");
    write_asc(&good, 167400.0, 361900.0, |_, _| 0.3);
    let far = t.path().join("far.asc");
    write_asc(&far, 0.0, 0.0, |_, _| 0.3);
    let wild = t.path().join("wild.asc");
    write_asc(&wild, 167400.0, 361900.0, |c, r| {
        if (c, r) == (60, 70) { 7.5 } else { 0.3 }
    });
    let dir = t.path().join("out");
    for (args, needle) in [
        // ξ belongs to Voellmy.
        (vec!["--xi-raster", good.to_str().unwrap()], "--xi-raster"),
        (vec!["--mu-raster", far.to_str().unwrap()], "covers none"),
        (vec!["--mu-raster", wild.to_str().unwrap()], "7.5"),
        (vec!["--mu-raster", "no/such/mu.tif"], "no/such/mu.tif"),
    ] {
        let mut a = vec![
            "avalanche",
            "--dem",
            dem.to_str().unwrap(),
            "--release",
            rel.to_str().unwrap(),
            "--out",
            dir.to_str().unwrap(),
        ];
        a.extend(args.iter().copied());
        let o = snowscape(&a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{a:?}: {err}");
        assert!(err.contains(needle), "{a:?}: {err}");
        assert!(!dir.exists(), "{a:?} wrote {}", dir.display());
    }
}

/// A 40-day season on avaWog (three natural avalanches by day 40) under the Voellmy law of
/// `run` above, with `extra` flags; the bytes of its depth and avalanche deposit.
fn season(dir: &Path, extra: &[&str]) -> (Vec<u8>, Vec<u8>) {
    let (dem, _) = wog();
    let scenario = dir.with_extension("toml");
    std::fs::write(
        &scenario,
        "days = 40\n[parameters.avalanche.flow]\nfriction = \"voellmy\"\nvoellmy_mu = 0.25\nvoellmy_xi_m_s2 = 4096\n",
    )
    .unwrap();
    let mut a = vec![
        "run",
        "--dem",
        dem.to_str().unwrap(),
        "--scenario",
        scenario.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
        "-q",
    ];
    a.extend(extra);
    let o = snowscape(&a);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("report.json")).unwrap()).unwrap();
    let named = |flag: &str, key: &str| {
        let given = extra.iter().position(|a| *a == flag).map(|k| extra[k + 1]);
        assert_eq!(report["parameters"]["extra"][key].as_str(), given, "{key}");
    };
    named("--mu-raster", "mu_raster");
    named("--xi-raster", "xi_raster");
    assert!(
        report["event_counts"]["avalanche_start"].as_u64().unwrap() > 0,
        "no avalanche: {}",
        report["event_counts"]
    );
    (
        std::fs::read(dir.join("depth.tif")).unwrap(),
        std::fs::read(dir.join("avalanche_deposit.tif")).unwrap(),
    )
}

/// Issue 47: a season's avalanches take the μ and ξ rasters as `snowscape avalanche` does:
/// rasters of the law's own values give the same bytes as none, a rougher μ changes where the
/// avalanches stop, and a ξ raster under the season's default Coulomb law is refused.
#[test]
fn a_seasons_avalanches_take_the_friction_rasters() {
    let d = tempfile::tempdir().unwrap();
    let (mu_same, xi_same, mu_rough) = (
        d.path().join("mu_same.asc"),
        d.path().join("xi_same.asc"),
        d.path().join("mu_rough.asc"),
    );
    write_asc(&mu_same, 167400.0, 361900.0, |_, _| 0.25);
    write_asc(&xi_same, 167400.0, 361900.0, |_, _| 4096.0);
    write_asc(&mu_rough, 167400.0, 361900.0, |_, _| 1.0);
    let plain = season(&d.path().join("plain"), &[]);
    let same = season(
        &d.path().join("same"),
        &[
            "--mu-raster",
            mu_same.to_str().unwrap(),
            "--xi-raster",
            xi_same.to_str().unwrap(),
        ],
    );
    assert!(
        plain == same,
        "rasters of the law's values changed the season"
    );
    let rough = season(
        &d.path().join("rough"),
        &["--mu-raster", mu_rough.to_str().unwrap()],
    );
    assert!(
        rough.1 != plain.1,
        "a μ of 1 left the deposits as they were"
    );
    // Under the default (Coulomb) law no term reads ξ: refused before any work.
    let (dem, _) = wog();
    let out = d.path().join("refused");
    let o = snowscape(&[
        "run",
        "--dem",
        dem.to_str().unwrap(),
        "--days",
        "5",
        "--xi-raster",
        xi_same.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--xi-raster") && err.contains("xi map"),
        "{err}"
    );
    assert!(!out.join("report.json").exists());
}
