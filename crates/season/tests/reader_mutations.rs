//! Property tests of the season's readers under a memory bound (issue 46, CI item 7): the
//! forcing CSV reader, the scenario TOML reader and the checkpoint reader take valid files
//! (written by the program itself, or small hand-written samples), mutated byte by byte
//! (flipped bits, huge numbers, inserted tokens, duplicated, repeated or removed sections,
//! splices, truncations), and must read them or refuse them with a typed error naming the
//! file or the field: never a panic, and the reading thread's peak allocation (counting
//! allocator) within a bound linear in the file's length, whatever the file claims.
//! Checkpoints are mutated twice over: raw (the checksum refuses nearly all) and forged (the
//! header's JSON or the maps mutated, lengths and CRC computed anew), so the checks of the
//! decoded values are what stands between the mutant and a resumed season.

#[path = "../../io/tests/common/counting.rs"]
mod counting;
#[path = "support/forge.rs"]
mod forge;
#[path = "../../io/tests/common/mutate.rs"]
mod mutate;

use counting::peak_of;
use proptest::prelude::*;
use snowscape_season::forcing::{
    AIR_TEMPERATURE_RANGE_C, MAX_PRECIPITATION_MM_PER_STEP, MAX_RECORDS, StationForcing,
    WIND_SPEED_RANGE_M_S, from_path,
};
use snowscape_season::scenario::{
    MAX_SEASON_DAYS, MAX_SNOWFALL_PERIODS, MAX_USER_AVALANCHES, MAX_WEATHER_PERIODS, Scenario,
    SnowfallPeriod, UserAvalanche, WeatherPeriod,
};
use snowscape_season::winter::Winter;
use std::path::Path;
use std::sync::OnceLock;

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

// ----------------------------------------------------------------------------------------
// Forcing CSV

/// Tokens of the CSV formats, inserted by the mutations beside the huge numbers.
const FORCING_TOKENS: &[&str] = &[
    "\n# station_altitude_m = 1e999\n",
    "\n# station_altitude_m: 2061\n",
    ",extra",
    ",,,,,,,,",
    "\"quoted,\nfield\"",
    "\"",
    "2000-02-30T00:00",
    "1999-12-31 23:00",
    "2000-01-01T25:61",
    "\n\n",
    "\r\n",
    "time,",
    "air_temp,precip_mass,",
    "\u{feff}",
];

/// A hand-written hourly series with every column of the generic format.
const HOURLY: &str = "# station_altitude_m = 2061\n\
time,air_temperature_c,precipitation_mm,wind_speed_m_s,wind_from_deg,shortwave_in_w_m2,relative_humidity,net_shortwave_w_m2,longwave_in_w_m2,snow_fraction\n\
2000-01-01T00:00,-4.5,0,2.3,270,0,0.65,0,240,1\n\
2000-01-01T01:00,-4.1,0.2,2.5,265,-3,0.66,,241,0.9\n\
2000-01-01T02:00,-3.9,1.4,3.1,260,15,1.02,10,,\n\
2000-01-01T03:00,-3.0,0,4.0,250,120,0.7,90,250,0\n";

/// Valid forcing files: the hourly sample as the program writes it back, a daily series with
/// comments and blank lines, and two snobal inputs (with and without a time column).
fn forcing_seeds() -> &'static Vec<Vec<u8>> {
    static SEEDS: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let hourly = StationForcing::from_text(HOURLY, Path::new("hourly.csv"), None).unwrap();
        vec![
            hourly.to_csv().into_bytes(),
            b"# a daily series\n\ntime,air_temperature_c,precipitation_mm,wind_speed_m_s\n\
              1983-10-01,4.0,0.0,2.3\n# a gap in the comments\n1983-10-02,1.5,12.5,6\n\
              1983-10-03,-2,30,8.5\n"
                .to_vec(),
            b"date_time,net_solar,incoming_thermal,air_temp,vapor_pressure,wind_speed,soil_temp,precip_mass,percent_snow,rho_snow,precip_temp\n\
              1983-10-01 00:00,0,237,4,496.16,2.3,10.3,0,1,150,-2.5\n\
              1983-10-01 01:00,120.5,237,-10,200,2.3,10.3,1.2,0.75,150,-2.6\n\
              1983-10-01 02:00,300,250,-8,250,4.1,10.1,0.4,1,120,-3\n"
                .to_vec(),
            b"net_solar,air_temp,wind_speed,precip_mass\n0,1,2,0\n0,1,2,0.5\n10,-1,3,0\n".to_vec(),
        ]
    })
}

/// Reads `bytes` as a forcing file through [`from_path`], as `snowscape run --forcing` does.
fn read_forcing(bytes: &[u8]) -> Result<(), TestCaseError> {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("station.csv");
    std::fs::write(&p, bytes).unwrap();
    let (r, peak) = peak_of(|| from_path(&p, None));
    // The text, a copy without comments, the records (a string and field ends each) and
    // their times: a few times the file (5,000 cases peaked at 14 times a 12 KB file); a
    // fixed part for the CSV reader's buffers.
    let bound = (1 << 20) + 32 * bytes.len();
    prop_assert!(
        peak <= bound,
        "peak {peak} bytes for a {}-byte file ({:?})",
        bytes.len(),
        r.as_ref().err()
    );
    match r {
        Ok(f) => {
            prop_assert!(!f.records.is_empty() && f.records.len() <= MAX_RECORDS);
            prop_assert!(f.step_hours.is_finite() && f.step_hours > 0.0);
            for r in &f.records {
                let t = f64::from(r.air_temperature_c);
                prop_assert!((AIR_TEMPERATURE_RANGE_C.0..=AIR_TEMPERATURE_RANGE_C.1).contains(&t));
                let p = f64::from(r.precipitation_mm);
                prop_assert!((0.0..=MAX_PRECIPITATION_MM_PER_STEP).contains(&p));
                let w = f64::from(r.wind_speed_m_s);
                prop_assert!((WIND_SPEED_RANGE_M_S.0..=WIND_SPEED_RANGE_M_S.1).contains(&w));
                for v in [
                    r.wind_from_deg,
                    r.shortwave_in_w_m2,
                    r.relative_humidity,
                    r.net_shortwave_w_m2,
                    r.longwave_in_w_m2,
                    r.snow_fraction,
                ]
                .into_iter()
                .flatten()
                {
                    prop_assert!(v.is_finite() && v >= 0.0, "{r:?}");
                }
            }
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(msg.contains("station.csv"), "{msg}");
            prop_assert!(msg.len() < 1000, "{} bytes: {msg}", msg.len());
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(1000))]

    #[test]
    fn mutated_forcing_files_are_read_or_refused_within_the_memory_bound(
        seed in any::<prop::sample::Index>(),
        edits in mutate::text_edits(FORCING_TOKENS),
    ) {
        let all = forcing_seeds();
        let others: Vec<&[u8]> = all.iter().map(Vec::as_slice).collect();
        let valid: &Vec<u8> = seed.get(all);
        read_forcing(&mutate::mutated(valid, &edits, &others))?;
    }
}

#[test]
fn forcing_seeds_are_valid() {
    for (k, bytes) in forcing_seeds().iter().enumerate() {
        let text = std::str::from_utf8(bytes).unwrap();
        StationForcing::from_text(text, Path::new("seed.csv"), Some(1000.0))
            .unwrap_or_else(|e| panic!("seed {k}: {e}"));
    }
}

// ----------------------------------------------------------------------------------------
// Scenario TOML

/// Tokens of scenario files, inserted by the mutations beside the huge numbers.
const SCENARIO_TOKENS: &[&str] = &[
    "\n[[weather]]\n",
    "\n[[snowfall_period]]\nstart_day = 1\ndays = 1e9\n",
    "\n[[avalanche]]\nday = 1\nx = 1e300\ny = nan\n",
    "\n[parameters.environment.sky]\ndirections = 4294967296\n",
    "\n[events]\nwind_transport = 1e9\n",
    "\n[skiers]\nper_day = 1e12\n",
    "\nsnapshot_every_days = 1e-300\n",
    "\nstart_date = \"02-30\"\n",
    "a.b.c.d.e.f.g.h = 1\n",
    "[[[[",
    "{ x = [[[[",
    "\"\"\"",
    "'",
    "= =",
];

/// The scenario of the module documentation, by hand.
const HAND_SCENARIO: &str = r#"seed = 7
days = 100
start_date = "12-01"
latitude_deg = 47.0
snapshot_every_days = 10
checkpoint_every_days = 10
snapshot_days = [5.5, 50]

[[weather]]
from_day = 0
sea_level_temperature_c = 8.0
wind_from_deg = 300
wind_speed_m_s = 10
rain_snow_altitude_m = 900
snowfall_per_week = 1.0

[[weather]]
from_day = 40
sea_level_temperature_c = 2.0
wind_from_deg = 270
wind_speed_m_s = 14
snowfall_per_week = 1.5
precipitation_mm_per_day = 12

[[snowfall_period]]
start_day = 3
days = 2

[[avalanche]]
day = 20
x = 150.0
y = 250.0

[skiers]
per_day = 24
starts = [[10.0, 20.0], [30.0, 40.0]]

[events]
wind_transport = 2.0

[parameters.snowfall]
k_snow = 1.5e-4
[parameters.environment.sky]
directions = 32
[parameters.avalanche.flow]
slope_gravity = "projected"
"#;

/// Valid scenarios: one written by the program (every parameter, three weather periods,
/// snowfall periods, an avalanche, snapshot days) and the hand-written one.
fn scenario_seeds() -> &'static Vec<Vec<u8>> {
    static SEEDS: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let period = |from_day, t, speed| WeatherPeriod {
            from_day,
            sea_level_temperature_c: t,
            wind_from_deg: 290.0,
            wind_speed_m_s: speed,
            rain_snow_altitude_m: 1200.0,
            snowfall_per_week: 1.2,
            precipitation_mm_per_day: None,
        };
        let mut s = Scenario {
            days: 60.0,
            seed: 11,
            latitude_deg: Some(46.5),
            snapshot_days: vec![1.0, 30.5],
            weather: vec![
                period(0.0, 4.0, 8.0),
                period(20.0, -2.0, 14.0),
                period(45.0, 6.0, 5.0),
            ],
            snowfall_periods: vec![SnowfallPeriod {
                start_day: 2.0,
                days: 1.5,
            }],
            avalanches: vec![UserAvalanche {
                day: 10.0,
                x: 120.0,
                y: 80.0,
            }],
            ..Scenario::default()
        };
        s.skiers.per_day = 12.0;
        s.skiers.starts = vec![[100.0, 100.0]];
        vec![
            toml::to_string(&s).unwrap().into_bytes(),
            HAND_SCENARIO.as_bytes().to_vec(),
        ]
    })
}

/// Parses `bytes` (UTF-8, as the CLI reads the file; a mutant that is not is read lossily).
fn read_scenario(bytes: &[u8]) -> Result<(), TestCaseError> {
    let text = String::from_utf8_lossy(bytes);
    let (r, peak) = peak_of(|| Scenario::from_toml(&text, "mutant.toml"));
    // The TOML parser's document (tables, keys and spans), the scenario and the messages:
    // 5,000 cases peaked at 27 times a 28 KB scenario.
    let bound = (2 << 20) + 64 * bytes.len();
    prop_assert!(
        peak <= bound,
        "peak {peak} bytes for a {}-byte scenario ({:?})",
        bytes.len(),
        r.as_ref().err()
    );
    match r {
        Ok(s) => {
            prop_assert!(s.validate("again").is_ok());
            prop_assert!(s.days > 0.0 && s.days <= MAX_SEASON_DAYS);
            prop_assert!(s.weather.len() <= MAX_WEATHER_PERIODS);
            prop_assert!(s.snowfall_periods.len() <= MAX_SNOWFALL_PERIODS);
            prop_assert!(s.avalanches.len() <= MAX_USER_AVALANCHES);
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(msg.contains("mutant.toml"), "{msg}");
            // The parser's excerpt of the line is cut; a list of the expected keys is long.
            prop_assert!(msg.len() < 2000, "{} bytes: {msg}", msg.len());
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(1000))]

    #[test]
    fn mutated_scenarios_are_read_or_refused_within_the_memory_bound(
        seed in any::<prop::sample::Index>(),
        edits in mutate::text_edits(SCENARIO_TOKENS),
    ) {
        let all = scenario_seeds();
        let others: Vec<&[u8]> = all.iter().map(Vec::as_slice).collect();
        let valid: &Vec<u8> = seed.get(all);
        read_scenario(&mutate::mutated(valid, &edits, &others))?;
    }
}

#[test]
fn scenario_seeds_are_valid() {
    for (k, bytes) in scenario_seeds().iter().enumerate() {
        let text = std::str::from_utf8(bytes).unwrap();
        Scenario::from_toml(text, "seed.toml").unwrap_or_else(|e| panic!("seed {k}: {e}"));
    }
}

// ----------------------------------------------------------------------------------------
// Checkpoints

/// Tokens of the checkpoint's JSON header, inserted by the mutations beside the huge numbers.
const HEADER_TOKENS: &[&str] = &[
    "null",
    "[]",
    "{}",
    "\"x\"",
    "-0.0",
    "1e-400",
    "[1e308,1e308]",
    "{\"day\":1e300}",
    ",",
    "\"",
];

/// A genuine checkpoint of the 6-day test season stopped at day 2.5.
fn checkpoint_seed() -> &'static Vec<u8> {
    static SEED: OnceLock<Vec<u8>> = OnceLock::new();
    SEED.get_or_init(|| forge::checkpoint_at(2.5))
}

/// Resumes the test season from `bytes` written as a file, as `snowscape run --resume` does.
fn resume_bounded(bytes: &[u8]) -> Result<(), TestCaseError> {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("checkpoint.bin");
    std::fs::write(&p, bytes).unwrap();
    let (scenario, terrain) = (forge::scenario(), forge::terrain());
    let (r, peak) = peak_of(|| Winter::resume_from_file(scenario, terrain, None, &p));
    // Building the season (its per-cell maps, 480 cells) and the decoded file, a few times
    // its length: a resumed genuine checkpoint of 27.8 KB peaks at 235 KB.
    let bound = (2 << 20) + 16 * bytes.len();
    prop_assert!(
        peak <= bound,
        "peak {peak} bytes for a {}-byte checkpoint ({:?})",
        bytes.len(),
        r.as_ref().err()
    );
    match r {
        Ok(w) => {
            prop_assert!(w.day().is_finite() && (0.0..=6.0).contains(&w.day()));
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(msg.len() < 1000, "{} bytes: {msg}", msg.len());
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(500))]

    #[test]
    fn mutated_checkpoints_are_resumed_or_refused_within_the_memory_bound(
        edits in mutate::edits(HEADER_TOKENS),
    ) {
        let seed = checkpoint_seed();
        resume_bounded(&mutate::mutated(seed, &edits, &[seed]))?;
    }

    #[test]
    fn forged_checkpoints_are_resumed_or_refused_within_the_memory_bound(
        header_edits in mutate::text_edits(HEADER_TOKENS),
        map_words in prop::collection::vec(
            (any::<prop::sample::Index>(), prop::sample::select(vec![
                f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -1.0, -0.0, 1e30, f32::MAX, 1e-45,
            ])),
            0..3,
        ),
    ) {
        let (header, mut maps) = forge::split_raw(checkpoint_seed());
        let header = mutate::mutated(&header, &header_edits, &[]);
        for (at, v) in map_words {
            let i = 4 * at.index(maps.len() / 4);
            maps[i..i + 4].copy_from_slice(&v.to_le_bytes());
        }
        resume_bounded(&forge::assemble_raw(&header, &maps))?;
    }
}

#[test]
fn the_checkpoint_seed_resumes() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("checkpoint.bin");
    std::fs::write(&p, checkpoint_seed()).unwrap();
    let w = Winter::resume_from_file(forge::scenario(), forge::terrain(), None, &p).unwrap();
    assert!(w.day() >= 2.5);
}
