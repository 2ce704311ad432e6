//! Issue 46 item 4: a season that cannot fit in memory is refused before any work, with the
//! estimate and what is available (exit 2); and the estimate covers what seasons really take.
//! (Before: `demo --size 8192` on a 24 GiB machine allocated until it aborted.)

mod common;

use common::{shared, snowscape, stderr};
use std::process::Command;

/// Runs `snowscape args` under `/usr/bin/time` and returns (success, peak resident KiB).
fn peak_kib(args: &[&str]) -> (bool, u64, String) {
    let time = std::path::Path::new("/usr/bin/time");
    assert!(
        time.exists(),
        "/usr/bin/time is missing (apt install time): this test measures peak memory with it"
    );
    let d = tempfile::tempdir().unwrap();
    let log = d.path().join("peak");
    let o = Command::new(time)
        .arg("-f")
        .arg("%M")
        .arg("-o")
        .arg(&log)
        .arg(env!("CARGO_BIN_EXE_snowscape"))
        .args(args)
        .output()
        .unwrap();
    let kib = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .last()
        .and_then(|l| l.trim().parse().ok())
        .expect("a peak in KiB");
    (o.status.success(), kib, stderr(&o))
}

#[test]
fn a_season_larger_than_the_budget_is_refused_before_any_work() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let o = snowscape(&[
        "demo",
        "--size",
        "8192",
        "--memory-budget",
        "4",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("67108864 cells") && e.contains("4.0 GiB") && e.contains("--memory-budget"),
        "{e}"
    );
    assert!(!out.exists(), "nothing written: {}", out.display());
    // A budget that is not a positive number of GiB is refused by name.
    let o = snowscape(&["demo", "--memory-budget", "0", "--out", "x"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--memory-budget"), "{}", stderr(&o));
}

#[test]
#[cfg(target_os = "linux")]
fn an_address_space_limit_is_seen_before_the_season_starts() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    // 3 GiB of address space: a 4096² season (estimate ~11 GiB) cannot fit.
    let o = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v 3145728 && exec '{}' demo --size 4096 --out '{}'",
            env!("CARGO_BIN_EXE_snowscape"),
            out.display()
        ))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("ulimit -v"), "{}", stderr(&o));
    assert!(!out.exists());
}

#[test]
fn the_estimate_covers_the_peak_of_real_seasons() {
    let d = tempfile::tempdir().unwrap();
    let out = |name: &str| d.path().join(name).to_str().unwrap().to_owned();
    let dem = shared("dem/avaframe_avaMal/avaMal.asc");
    let (demo_ok, demo_kib, e) = peak_kib(&["--quiet", "demo", "--out", &out("demo")]);
    assert!(demo_ok, "{e}");
    let (run_ok, run_kib, e) = peak_kib(&[
        "--quiet",
        "run",
        "--dem",
        dem.to_str().unwrap(),
        "--days",
        "60",
        "--out",
        &out("mal"),
    ]);
    assert!(run_ok, "{e}");
    for (what, cells, kib) in [
        ("demo 512²", 512 * 512, demo_kib),
        ("avaMal 567x787, 60 days", 567 * 787, run_kib),
    ] {
        let estimate = snowscape::memory::season_estimate_bytes(cells);
        let peak = kib * 1024;
        // Covers the peak, and not by so much that it would refuse seasons that fit.
        assert!(
            peak <= estimate && estimate <= 4 * peak,
            "{what}: peak {peak} B, estimate {estimate} B"
        );
    }
}
