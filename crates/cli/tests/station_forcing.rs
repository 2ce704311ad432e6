//! `snowscape run --forcing` on the shared Reynolds Mountain East record (snobal's input,
//! 1983-10-01 on, no station altitude in the file): the altitude is required (exit 2, nothing
//! written), the season takes the record's calendar (its start date; its length unless `--days`
//! is shorter), and a scenario's `forcing` is read relative to the scenario file.

mod common;

use common::{report, shared, snowscape, stderr};

#[test]
fn a_station_record_sets_the_seasons_calendar() {
    let d = tempfile::tempdir().unwrap();
    let (dem, rme) = (
        shared("dem/rme_idaho_50m/dem.asc"),
        shared("reference/pysnobal_rme_point/gold.snobal.data.input.short.csv"),
    );
    let (dem, rme) = (dem.to_str().unwrap(), rme.to_str().unwrap());
    let refused = d.path().join("refused");
    let o = snowscape(&[
        "run",
        "--dem",
        dem,
        "--forcing",
        rme,
        "--days",
        "2",
        "--out",
        refused.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("station altitude is unknown"),
        "{}",
        stderr(&o)
    );
    assert!(!refused.join("report.json").exists());

    let flag = d.path().join("flag");
    let o = snowscape(&[
        "run",
        "--dem",
        dem,
        "--forcing",
        rme,
        "--station-altitude",
        "2061",
        "--days",
        "2",
        "--out",
        flag.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = &report(&flag)["parameters"]["scenario"];
    assert_eq!(s["start_date"], "1983-10-01");
    assert_eq!(s["days"], 2.0);

    // The scenario's own forcing, relative to its file, and a length past the record's end:
    // the record's length (--days 2 above was within it).
    let folder = d.path().join("scenario");
    std::fs::create_dir(&folder).unwrap();
    std::fs::copy(rme, folder.join("rme.csv")).unwrap();
    std::fs::write(
        folder.join("season.toml"),
        "forcing = \"rme.csv\"\nstation_altitude_m = 2061\n",
    )
    .unwrap();
    let from_file = d.path().join("from_file");
    let o = snowscape(&[
        "run",
        "--dem",
        dem,
        "--scenario",
        folder.join("season.toml").to_str().unwrap(),
        "--days",
        "3000",
        "--stop-at",
        "1",
        "--out",
        from_file.to_str().unwrap(),
        "-q",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let toml = std::fs::read_to_string(from_file.join("scenario.toml")).unwrap();
    let days: f64 = toml
        .lines()
        .find_map(|l| l.strip_prefix("days = "))
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or_else(|| panic!("no days in {toml}"));
    assert!((300.0..=367.0).contains(&days), "{days} days");
    assert!(toml.contains("rme.csv"), "{toml}");
}
