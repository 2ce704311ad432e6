//! Regression tests of issue 19 items 4 and 5: every scenario value and every numeric flag
//! that sizes the work is refused before any output is written (exit 2, a message naming
//! the file, key or flag, its value and its range). Each case once aborted on allocation,
//! hung, failed after the precompute with exit 1, or was silently accepted.

mod common;

use common::{snowscape, stderr};
use std::path::Path;

/// A small tilted DEM (48×48 cells of 20 m) in `dir`.
fn dem(dir: &Path) -> String {
    let path = dir.join("dem.asc");
    let mut text = String::from(
        "ncols 48\nnrows 48\nxllcorner 0\nyllcorner 0\ncellsize 20\nNODATA_value -9999\n",
    );
    for r in 0..48 {
        let row: Vec<String> = (0..48)
            .map(|c| format!("{:.1}", 1500.0 + 30.0 * c as f64 + 5.0 * r as f64))
            .collect();
        text.push_str(&row.join(" "));
        text.push('\n');
    }
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

/// Runs `snowscape run` on the small DEM with `scenario` (TOML) and `extra` flags, and checks
/// it is refused with exit 2, `needles` in the message and nothing in the output folder.
fn refused(scenario: &str, extra: &[&str], needles: &[&str]) {
    let d = tempfile::tempdir().unwrap();
    let dem = dem(d.path());
    let sc = d.path().join("case.toml");
    std::fs::write(&sc, format!("days = 5\n{scenario}\n")).unwrap();
    let out = d.path().join("out");
    let mut args = vec![
        "--quiet",
        "run",
        "--dem",
        &dem,
        "--scenario",
        sc.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let t = std::time::Instant::now();
    let o = snowscape(&args);
    let err = stderr(&o);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{scenario:?} {extra:?}: expected exit 2, got {:?} after {:.1} s: {err}",
        o.status.code(),
        t.elapsed().as_secs_f64()
    );
    for n in needles {
        assert!(
            err.contains(n),
            "{scenario:?} {extra:?}: expected {n:?} in: {err}"
        );
    }
    assert!(
        !out.exists() || std::fs::read_dir(&out).unwrap().next().is_none(),
        "{scenario:?} {extra:?}: outputs were written before the refusal"
    );
}

#[test]
fn cadences_that_would_allocate_without_end_are_refused() {
    refused(
        "snapshot_every_days = 1e-9",
        &[],
        &["case.toml", "snapshot_every_days", "at most 1000"],
    );
    refused(
        "checkpoint_every_days = 1e-9",
        &[],
        &["checkpoint_every_days", "at most 1000"],
    );
    refused(
        "snapshot_days = [-1, 1e9, nan]",
        &[],
        &["snapshot_days[0] = -1", "within [0, days]"],
    );
    refused("snapshot_days = [2, 1e9]", &[], &["snapshot_days[1]"]);
}

#[test]
fn parameters_out_of_range_name_their_section_key_and_range() {
    for (toml, needles) in [
        (
            "[parameters.powder_diffusion]\nk_m = 1e9",
            &[
                "[parameters.powder_diffusion]",
                "k_m = 1000000000",
                "[0, 100]",
            ][..],
        ),
        (
            "[parameters.melt]\nk_melt = -1",
            &["[parameters.melt]", "k_melt = -1", "[0, 0.1]"][..],
        ),
        ("[parameters.melt]\nk_melt = nan", &["k_melt = NaN"][..]),
        (
            "[parameters.snowfall]\nk_snow = nan",
            &["[parameters.snowfall]", "k_snow = NaN"][..],
        ),
        (
            "[parameters.stability]\nk_warm = nan",
            &["[parameters.stability]", "k_warm = NaN"][..],
        ),
        (
            // Once reported as "t_warm = 5: below its minimum".
            "[parameters.stability]\nt_cool = 1e9",
            &["t_cool = 1000000000", "[-60, 30]"][..],
        ),
        (
            "[parameters.wind_transport]\nk_erosion = nan",
            &["[parameters.wind_transport]", "k_erosion = NaN"][..],
        ),
        (
            "[parameters.powder_diffusion]\nrest_slope = nan",
            &["rest_slope = NaN"][..],
        ),
        (
            "[parameters.environment.sky]\ndirections = 0",
            &["[parameters.environment]", "sky.directions = 0"][..],
        ),
        (
            "[parameters.environment.sun]\nday_step = 0",
            &["sun.day_step = 0"][..],
        ),
        (
            "[parameters.environment.bounce]\nradii = 0",
            &["bounce.radii = 0"][..],
        ),
        (
            "[parameters.environment.wind]\nordered_sweeps = 1000000000",
            &["wind.ordered_sweeps = 1000000000", "0..=16"][..],
        ),
        (
            "[parameters.environment.wind]\nmax_iterations = 4000000000",
            &["wind.max_iterations"][..],
        ),
        (
            "[parameters.environment.sheltering]\ndmax_m = 1e9",
            &["sheltering.dmax_m"][..],
        ),
        (
            "[parameters.avalanche.run]\nrecord_interval_s = 1e-12",
            &["[parameters.avalanche]", "record_interval_s"][..],
        ),
        (
            "[parameters.avalanche]\nrate_per_km2_per_day = 1e9",
            &["rate_per_km2_per_day"][..],
        ),
        (
            "[parameters.snowtran]\nmax_substep_s = 1",
            &["[parameters.snowtran]", "max_substep_s = 1"][..],
        ),
        ("latitude_deg = nan", &["latitude_deg = NaN"][..]),
    ] {
        refused(toml, &[], needles);
    }
}

#[test]
fn event_and_skier_frequencies_are_bounded() {
    refused(
        "[events]\nmelt_and_state = 1e9",
        &[],
        &[
            "[events]",
            "melt_and_state = 1000000000",
            "[0, 100] per day",
        ],
    );
    refused(
        "[events]\nmelt_and_state = -1",
        &[],
        &["melt_and_state = -1"],
    );
    refused(
        "[events]\nsnowfall_start = nan",
        &[],
        &["snowfall_start = NaN"],
    );
    refused("[skiers]\nper_day = 1e9", &[], &["[skiers]", "per_day"]);
    refused("", &["--skier-frequency", "1e9"], &["per_day"]);
}

#[test]
fn avalanches_and_skier_starts_off_the_terrain_or_the_season_are_refused() {
    refused(
        "[[avalanche]]\nday = 3\nx = -5000\ny = 10",
        &[],
        &[
            "avalanche[0]",
            "x -5000 y 10",
            "outside the terrain",
            "dem.asc",
        ],
    );
    refused(
        "[[avalanche]]\nday = 500\nx = 100\ny = 100",
        &[],
        &["avalanche[0].day = 500", "within [0, days]"],
    );
    refused(
        "",
        &["--skier-start", "99999,99999"],
        &["skiers.starts[0]", "outside the terrain"],
    );
}

#[test]
fn numeric_flags_are_bounded_before_any_work() {
    refused("", &["--stop-at", "nan"], &["--stop-at", "nan"]);
    refused("", &["--days", "1e9"], &["--days", "3650"]);
    refused("", &["--days", "0"], &["--days"]);
    refused("", &["--latitude", "91"], &["--latitude"]);
    refused("", &["--threads", "99999999999"], &["--threads"]);
    refused("", &["--threads", "100000"], &["--threads"]);
    refused("", &["--threads", "0"], &["--threads"]);
    let d = tempfile::tempdir().unwrap();
    let dem = dem(d.path());
    let out = d.path().join("o");
    let out = out.to_str().unwrap();
    for (args, needle) in [
        (
            vec!["demo", "--frames", "1000000000", "--out", out],
            "--frames",
        ),
        (vec!["demo", "--days", "1e9", "--out", out], "--days"),
        (
            vec![
                "avalanche",
                "--dem",
                &dem,
                "--release",
                "400,400",
                "--thickness",
                "1e9",
                "--out",
                out,
            ],
            "--thickness",
        ),
        (
            vec![
                "avalanche",
                "--dem",
                &dem,
                "--release",
                "400,400",
                "--frame-interval",
                "1e-9",
                "--out",
                out,
            ],
            "--frame-interval",
        ),
        (
            vec!["transport", "--dem", &dem, "--hours", "1e9", "--out", out],
            "--hours",
        ),
        (
            vec![
                "cover",
                "--mesh",
                "unused.obj",
                "--method",
                "fearing",
                "--budget",
                "1e20",
                "--out",
                out,
            ],
            "--budget",
        ),
    ] {
        let o = snowscape(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
        assert!(!Path::new(out).exists(), "{args:?} wrote outputs");
    }
}
