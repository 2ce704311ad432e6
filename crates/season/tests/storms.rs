//! Storm meteorology in a whole season: a season total of precipitation falls at the
//! reference altitude, the altitude bands add up to the water budget, and storms snow where
//! the fair-weather cycle would have rained.

use snowscape_season::scenario::{Scenario, SnowfallPeriod, WeatherPeriod};
use snowscape_season::storms::RainSnowPhase;
use snowscape_season::winter::Winter;
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain};

/// One weather period with no Poisson storms, and three forced ones (9 storm days).
fn scenario(sea_level_c: f64, days: f64) -> Scenario {
    let mut s = Scenario {
        days,
        start_date: "12-01".into(),
        latitude_deg: Some(45.0),
        snapshot_every_days: 0.0,
        checkpoint_every_days: 0.0,
        weather: vec![WeatherPeriod {
            from_day: 0.0,
            sea_level_temperature_c: sea_level_c,
            wind_from_deg: 270.0,
            wind_speed_m_s: 5.0,
            rain_snow_altitude_m: 0.0,
            snowfall_per_week: 0.0,
            precipitation_mm_per_day: None,
        }],
        snowfall_periods: vec![
            SnowfallPeriod {
                start_day: 3.5,
                days: 3.0,
            },
            SnowfallPeriod {
                start_day: 20.25,
                days: 2.0,
            },
            SnowfallPeriod {
                start_day: 44.0,
                days: 4.0,
            },
        ],
        ..Scenario::default()
    };
    s.parameters.environment.sky.directions = 8;
    s
}

/// A 24 x 20 grid of `cell` m cells of altitude `z(col, row)`.
fn terrain(cell: f64, z: impl Fn(usize, usize) -> f32) -> LayeredTerrain {
    let g = GridGeometry::square(24, 20, cell).unwrap();
    LayeredTerrain::from_bedrock(Grid::from_fn(g, z))
}

#[test]
fn annual_precipitation_falls_as_its_total_at_the_reference_altitude() {
    // Flat ground at the reference altitude (orographic factor 1), cold enough for snow.
    let mut s = scenario(0.0, 60.0);
    s.parameters.climate.annual_precipitation_mm = Some(730.0);
    s.validate("test").unwrap();
    let mut w = Winter::new(s, terrain(25.0, |_, _| 1500.0)).unwrap();
    w.run_until(60.0).unwrap();
    let bands = w.altitude_bands();
    assert_eq!(bands.len(), 1);
    let b = &bands[0];
    // 60 days of 730 mm a year: 120 mm, all in the forced storms.
    let want = 730.0 * 60.0 / 365.0;
    assert!(
        (b.precipitation_mm - want).abs() < 1e-4 * want,
        "{} mm, want {want}",
        b.precipitation_mm
    );
    assert_eq!(b.rain_share, 0.0);
    assert!(b.peak_swe_mm > 0.5 * want, "{}", b.peak_swe_mm);

    // The same by months: December's and January's totals, 30 of January's 31 days.
    let mut s = scenario(0.0, 61.0);
    let mut months = [0.0; 12];
    (months[11], months[0]) = (90.0, 62.0);
    s.parameters.climate.monthly_precipitation_mm = Some(months);
    let mut w = Winter::new(s, terrain(25.0, |_, _| 1500.0)).unwrap();
    w.run_until(61.0).unwrap();
    let got = w.altitude_bands()[0].precipitation_mm;
    let want = 90.0 + 62.0 * 30.0 / 31.0;
    assert!((got - want).abs() < 1e-4 * want, "{got} mm, want {want}");
}

#[test]
fn the_bands_add_up_to_the_water_budget_with_rain_below_and_snow_above() {
    // A 27° slope from 300 to 2200 m (bands 200-400 to 2200-2400 m) with a mild sea level:
    // rain low, snow high.
    let mut s = scenario(10.0, 50.0);
    s.parameters.climate.precipitation_mm_per_day = Some(20.0);
    let mut w = Winter::new(s, terrain(200.0, |_, r| 300.0 + 100.0 * r as f32)).unwrap();
    w.run_until(50.0).unwrap();
    let bands = w.altitude_bands();
    assert_eq!(bands.len(), 11);
    let cell = 200.0 * 200.0;
    let water: f64 = bands
        .iter()
        .map(|b| b.precipitation_mm * 1e-3 * b.cells as f64 * cell)
        .sum();
    let rain: f64 = bands
        .iter()
        .map(|b| b.rain_share * b.precipitation_mm * 1e-3 * b.cells as f64 * cell)
        .sum();
    let budget = &w.budget().water;
    let total = budget.snowfall_water + budget.rain;
    assert!(
        (water - total).abs() < 1e-9 * total,
        "bands {water} m³, budget {total} m³"
    );
    assert!(
        (rain - budget.rain).abs() < 1e-9 * total,
        "{rain} {}",
        budget.rain
    );
    // Rain low, snow high, the share falling with altitude; precipitation rising with it.
    assert!(bands[0].rain_share > 0.9, "{:?}", bands[0]);
    assert!(bands[10].rain_share < 1e-5, "{:?}", bands[10]);
    for pair in bands.windows(2) {
        assert!(pair[1].rain_share <= pair[0].rain_share, "{pair:?}");
        assert!(
            pair[1].precipitation_mm > pair[0].precipitation_mm,
            "{pair:?}"
        );
    }
    assert!(bands[10].peak_swe_mm > bands[0].peak_swe_mm);
}

#[test]
fn storms_snow_lower_than_the_fair_weather_cycle_would() {
    // The earlier storms (the fair cycle, phase by air temperature) against the default.
    let rain_share_low = |storm: bool| {
        let mut s = scenario(10.0, 50.0);
        let c = &mut s.parameters.climate;
        if !storm {
            c.storm_diurnal_factor = 1.0;
            c.rain_snow_phase = RainSnowPhase::AirTemperature;
        }
        let mut w = Winter::new(s, terrain(200.0, |_, r| 300.0 + 100.0 * r as f32)).unwrap();
        w.run_until(50.0).unwrap();
        let b = w.altitude_bands();
        // The bands around the fair-weather snow line (1400-2000 m at 10 °C sea level).
        b[6..9].iter().map(|b| b.rain_share).sum::<f64>() / 3.0
    };
    let (before, after) = (rain_share_low(false), rain_share_low(true));
    assert!(after < before - 0.05, "rain share {before} → {after}");
}

#[test]
fn a_run_resumed_inside_a_storm_lays_the_same_precipitation() {
    let mut s = scenario(0.0, 30.0);
    s.parameters.climate.annual_precipitation_mm = Some(1000.0);
    let slope = |_: usize, r: usize| 1200.0 + 40.0 * r as f32;
    let mut full = Winter::new(s.clone(), terrain(100.0, slope)).unwrap();
    full.run_until(30.0).unwrap();
    let mut first = Winter::new(s.clone(), terrain(100.0, slope)).unwrap();
    // Inside the storm of days 20.25-22.25.
    first.run_until(21.0).unwrap();
    let mut bytes = Vec::new();
    first.write_checkpoint(&mut bytes).unwrap();
    let mut resumed = Winter::resume(s, terrain(100.0, slope), &mut bytes.as_slice()).unwrap();
    resumed.run_until(30.0).unwrap();
    assert_eq!(resumed.terrain, full.terrain);
    assert_eq!(resumed.budget(), full.budget());
    assert_eq!(resumed.altitude_bands(), full.altitude_bands());
}

#[test]
fn conflicting_precipitation_settings_are_refused_naming_both() {
    use snowscape_season::scenario::ScenarioError;
    let period = "[[weather]]\nfrom_day = 0\nsea_level_temperature_c = 5\nwind_from_deg = 270\nwind_speed_m_s = 5\nsnowfall_per_week = 1\nprecipitation_mm_per_day = 30\n";
    let text = format!("{period}[parameters.climate]\nannual_precipitation_mm = 1500\n");
    let e = Scenario::from_toml(&text, "s.toml").unwrap_err();
    assert!(
        matches!(&e, ScenarioError::Conflict { first, second, .. }
            if first == "weather[0].precipitation_mm_per_day"
                && second == "parameters.climate.annual_precipitation_mm"),
        "{e}"
    );
    let e = Scenario::from_toml(
        "forcing = \"station.csv\"\n[parameters.climate]\nmonthly_precipitation_mm = [1,2,3,4,5,6,7,8,9,10,11,12]\n",
        "s.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("forcing and parameters.climate.monthly_precipitation_mm are both set"),
        "{e}"
    );
    let e = Scenario::from_toml(
        "[parameters.climate]\nprecipitation_mm_per_day = 12\nannual_precipitation_mm = 900\n",
        "s.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("climate.precipitation_mm_per_day")
            && e.contains("climate.annual_precipitation_mm"),
        "{e}"
    );
    // One of them alone is fine; a period's rate is range-checked.
    assert!(Scenario::from_toml(period, "s.toml").is_ok());
    let e = Scenario::from_toml(&period.replace("= 30", "= -3"), "s.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("weather[0].precipitation_mm_per_day = -3"),
        "{e}"
    );
}
