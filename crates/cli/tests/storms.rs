//! `run`'s altitude bands: a season total of precipitation set in the scenario is what the
//! report's bands received, the bands add up to the water budget, and the log shows the
//! table unless `--quiet`.

mod common;

use common::{report, slope_dem, snowscape, stderr};

#[test]
fn the_report_bands_receive_the_annual_precipitation_and_close_the_water_budget() {
    let d = tempfile::tempdir().unwrap();
    let dem = slope_dem(d.path());
    // No Poisson storms, two forced ones; no orographic gradient: every cell receives the
    // reference altitude's precipitation.
    let scenario = d.path().join("storms.toml");
    std::fs::write(
        &scenario,
        "days = 31\nstart_date = \"01-01\"\nlatitude_deg = 46\n\
         [[weather]]\nfrom_day = 0\nsea_level_temperature_c = 12\nwind_from_deg = 270\nwind_speed_m_s = 5\nsnowfall_per_week = 0\n\
         [[snowfall_period]]\nstart_day = 5.5\ndays = 3\n\
         [[snowfall_period]]\nstart_day = 21\ndays = 2\n\
         [parameters.climate]\nannual_precipitation_mm = 1460\norographic_gradient_per_100m = 0\n",
    )
    .unwrap();
    let out = d.path().join("run");
    let o = snowscape(&[
        "run",
        "--dem",
        &dem,
        "--scenario",
        scenario.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let log = String::from_utf8_lossy(&o.stdout);
    assert!(
        log.contains("altitude band") && log.contains("peak SWE"),
        "{log}"
    );
    let r = report(&out);
    let bands = r["bands"].as_array().expect("report.json has bands");
    // The slope spans 1713-2775 m: bands 1600-1800 to 2600-2800.
    assert_eq!(bands.len(), 6, "{bands:?}");
    assert_eq!(bands[0]["from_m"].as_f64(), Some(1600.0));
    // January of 1460 mm a year: 124 mm in every band.
    let want = 1460.0 * 31.0 / 365.0;
    let cell = 20.0 * 20.0;
    let (mut water, mut rain) = (0.0, 0.0);
    for b in bands {
        let p = b["precipitation_mm"].as_f64().unwrap();
        assert!((p - want).abs() < 1e-4 * want, "{b}: want {want} mm");
        let cells = b["cells"].as_f64().unwrap();
        water += p * 1e-3 * cells * cell;
        rain += b["rain_share"].as_f64().unwrap() * p * 1e-3 * cells * cell;
        assert!(b["peak_swe_mm"].as_f64().unwrap() >= 0.0);
    }
    // Lower bands get some rain in a mild January; the top none to speak of.
    let share = |k: usize| bands[k]["rain_share"].as_f64().unwrap();
    assert!(share(0) > share(5), "{bands:?}");
    let w = &r["water_budget"];
    let total = w["snowfall_water"].as_f64().unwrap() + w["rain"].as_f64().unwrap();
    assert!((water - total).abs() < 1e-9 * total, "{water} {total}");
    assert!((rain - w["rain"].as_f64().unwrap()).abs() < 1e-9 * total);

    // --quiet: no table.
    let out = d.path().join("quiet");
    let o = snowscape(&[
        "--quiet",
        "run",
        "--dem",
        &dem,
        "--scenario",
        scenario.to_str().unwrap(),
        "--days",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        o.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
}
