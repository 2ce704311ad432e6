//! Scenario files: a season described in TOML, mapping 1:1 onto the parameter structs.
//!
//! ```toml
//! seed = 7
//! days = 100
//! start_date = "12-01"          # MM-DD (or YYYY-MM-DD): the first day, for the sun
//! latitude_deg = 47.0           # default: from the DEM's georeferencing, else 45
//! snapshot_every_days = 10
//! checkpoint_every_days = 10
//!
//! [[weather]]                   # piecewise constant, from `from_day` until the next entry
//! from_day = 0
//! sea_level_temperature_c = 8.0 # T0
//! wind_from_deg = 300           # meteorological: the direction the wind blows FROM
//! wind_speed_m_s = 10
//! rain_snow_altitude_m = 900    # A0precip
//! snowfall_per_week = 1.0       # Snowfall-Start frequency
//!
//! [[snowfall_period]]           # forced snowfall, on top of the Poisson ones
//! start_day = 3
//! days = 2
//!
//! [events]                      # EventFrequencies (per day)
//! wind_transport = 2.0
//!
//! [parameters.snowfall]         # any field of SnowfallParams, MeltParams, ...
//! k_snow = 1.5e-4
//! [parameters.environment.sky]
//! directions = 32
//! ```
//!
//! Unknown keys are errors, reported with the key, line and column by the TOML parser.
//!
//! # Limits
//!
//! A scenario is small: its text is at most [`MAX_SCENARIO_BYTES`] (4 MiB, refused before it
//! is parsed), the season at most [`MAX_SEASON_DAYS`] days, and each repeated table at most
//! one entry per day of that longest season, checked by [`Scenario::validate`]:
//! [`MAX_WEATHER_PERIODS`] `[[weather]]`, [`MAX_SNOWFALL_PERIODS`] `[[snowfall_period]]`,
//! [`MAX_USER_AVALANCHES`] `[[avalanche]]`, [`MAX_SKIER_STARTS`] `skiers.starts`, and
//! [`MAX_SNAPSHOTS`] `snapshot_days`; `skiers.terminus` lists at most [`MAX_TERMINUS_CELLS`]
//! cells. Each refusal is a [`ScenarioError::TooMany`] naming the key, the count and the cap.
//! An error repeats at most [`crate::MAX_ECHO_CHARS`] characters of any value from the file.

use crate::melt::MeltParams;
use crate::powder_diffusion::DiffusionParams;
use crate::scheduler::EventFrequencies;
use crate::snowfall::SnowfallParams;
use crate::stability::StabilityParams;
use crate::wind_transport::WindTransportParams;
use serde::{Deserialize, Serialize};
use snowscape_environment::EnvironmentParams;
use snowscape_terrain::timeline::{TimeUnit, TimelinePeriod};
use thiserror::Error;

mod validate;

pub use validate::{
    MAX_CHECKPOINTS, MAX_SCENARIO_BYTES, MAX_SEASON_DAYS, MAX_SKIER_STARTS, MAX_SNAPSHOTS,
    MAX_SNOWFALL_PERIODS, MAX_TERMINUS_CELLS, MAX_USER_AVALANCHES, MAX_WEATHER_PERIODS,
};

/// A malformed or inconsistent scenario.
#[derive(Debug, Error)]
pub enum ScenarioError {
    /// TOML syntax or a wrong key/type; the message names the key, line and column.
    #[error("scenario {source_name}: {message}")]
    Parse {
        source_name: String,
        message: String,
    },
    /// A phenomenon's parameter out of its documented range; `message` names the field, its
    /// value and the range.
    #[error("scenario {source_name}: [{section}] {message}")]
    Parameter {
        source_name: String,
        section: &'static str,
        message: String,
    },
    /// The text is larger than [`MAX_SCENARIO_BYTES`].
    #[error("scenario {source_name}: {bytes} bytes, more than the {max} bytes a scenario may hold")]
    TooLarge {
        source_name: String,
        bytes: usize,
        max: usize,
    },
    /// A repeated table or list with more entries than its cap.
    #[error(
        "scenario {source_name}: {count} {key} entries, more than the {max} a scenario may have"
    )]
    TooMany {
        source_name: String,
        key: &'static str,
        count: usize,
        max: usize,
    },
    /// Two settings that cannot be given together; both are named.
    #[error("scenario {source_name}: {first} and {second} are both set: {reason}")]
    Conflict {
        source_name: String,
        first: String,
        second: String,
        reason: &'static str,
    },
    /// A value out of range.
    #[error("scenario {source_name}: {key} = {value}: {reason}")]
    Invalid {
        source_name: String,
        key: String,
        value: String,
        reason: std::borrow::Cow<'static, str>,
    },
}

/// The weather from one day until the next period starts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WeatherPeriod {
    /// First day of the period, days since the season start.
    pub from_day: f64,
    /// Sea-level temperature T0, °C (Cordonnier 2018 §4.1).
    pub sea_level_temperature_c: f64,
    /// Direction the wind blows from, degrees clockwise from north (270 = westerly).
    pub wind_from_deg: f64,
    /// Sea-level wind speed |W|, m/s. Cordonnier 2018 Table 2: 10.
    pub wind_speed_m_s: f64,
    /// Rain-snow limit A0precip, m (the `cordonnier` snowfall model only; the default model
    /// takes the phase from the air temperature).
    #[serde(default)]
    pub rain_snow_altitude_m: f64,
    /// Mean number of snowfall periods starting per week. Cordonnier 2018 §5.1: 1.
    pub snowfall_per_week: f64,
    /// Precipitation during this period's snowfall periods at the climate's reference
    /// altitude, mm of water per day, within [0, 500]; `None`: the climate's storm rate
    /// ([`crate::storms`]). Not with a season total (`annual_precipitation_mm`,
    /// `monthly_precipitation_mm`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub precipitation_mm_per_day: Option<f64>,
}

impl TimelinePeriod for WeatherPeriod {
    const UNIT: TimeUnit = TimeUnit::Days;
    const START_KEY: &'static str = "from_day";
    fn start(&self) -> f64 {
        self.from_day
    }
}

/// A forced snowfall period.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SnowfallPeriod {
    /// Day the period starts.
    pub start_day: f64,
    /// Length, days.
    pub days: f64,
}

/// An avalanche the user triggers: a rupture at a map position on a given day.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UserAvalanche {
    /// Season day of the rupture.
    pub day: f64,
    /// Map x of the rupture point (CRS units).
    pub x: f64,
    /// Map y of the rupture point (CRS units).
    pub y: f64,
}

/// Every phenomenon's parameters.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct Parameters {
    pub environment: EnvironmentParams,
    /// The air: lapse rate, diurnal cycle, precipitation, phase, clouds, default winter.
    pub climate: crate::climate::ClimateParams,
    pub snowfall: SnowfallParams,
    pub melt: MeltParams,
    pub stability: StabilityParams,
    pub powder_diffusion: DiffusionParams,
    pub wind_transport: WindTransportParams,
    /// Gravitational shedding off steep slopes (SnowSlide).
    pub slope_shedding: crate::slope_shedding::SheddingParams,
    /// The physical wind transport, used when `wind_transport.model = "snowtran"`.
    pub snowtran: crate::snowtran_transport::SnowTranParams,
    pub avalanche: crate::avalanches::AvalancheParameters,
}

/// A whole season.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Scenario {
    /// Random seed: same seed, same bytes.
    pub seed: u64,
    /// Length of the season, days.
    pub days: f64,
    /// First day, `MM-DD` or `YYYY-MM-DD`.
    pub start_date: String,
    /// Latitude, degrees north; `None`: from the DEM's georeferencing, else 45 (with a
    /// warning in the log and report.json).
    pub latitude_deg: Option<f64>,
    /// Station forcing (CSV, see [`crate::forcing`]), relative to the scenario file: the
    /// season then follows the station's record, from its first hour.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub forcing: Option<std::path::PathBuf>,
    /// Altitude of the forcing station, m (overrides the file's `# station_altitude_m`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub station_altitude_m: Option<f64>,
    /// Take a snapshot (frame) every this many days; 0 = none.
    pub snapshot_every_days: f64,
    /// Explicit snapshot days (added to the regular ones).
    pub snapshot_days: Vec<f64>,
    /// Write a checkpoint every this many days; 0 = never.
    pub checkpoint_every_days: f64,
    /// The weather timeline; empty = the default winter for the terrain's altitudes.
    pub weather: Vec<WeatherPeriod>,
    /// Forced snowfall periods.
    #[serde(rename = "snowfall_period")]
    pub snowfall_periods: Vec<SnowfallPeriod>,
    /// Skiers: how often they come and where they start (`[skiers]`).
    pub skiers: crate::skiing::SkierParameters,
    /// Avalanches the user triggers at given days and map positions.
    #[serde(rename = "avalanche")]
    pub avalanches: Vec<UserAvalanche>,
    /// Mean event frequencies.
    pub events: EventFrequencies,
    /// Parameter overrides.
    pub parameters: Parameters,
}

impl Default for Scenario {
    fn default() -> Self {
        Self {
            seed: 1,
            days: 100.0,
            start_date: "12-01".into(),
            latitude_deg: None,
            forcing: None,
            station_altitude_m: None,
            snapshot_every_days: 10.0,
            snapshot_days: Vec::new(),
            checkpoint_every_days: 10.0,
            weather: Vec::new(),
            snowfall_periods: Vec::new(),
            avalanches: Vec::new(),
            skiers: crate::skiing::SkierParameters::default(),
            events: EventFrequencies::default(),
            parameters: Parameters::default(),
        }
    }
}

/// The 1-based line of `text` (TOML) that nests deepest, and its depth: the dots of dotted
/// keys and the opening brackets and braces on the line, outside strings and comments. For
/// error messages only (the parser's own errors name the place when it has one).
fn deepest_line(text: &str) -> Option<(usize, usize)> {
    let mut best: Option<(usize, usize)> = None;
    // The multi-line string a line starts in, if any (`"""` or `'''`).
    let mut open_multiline: Option<&str> = None;
    for (k, line) in text.lines().enumerate() {
        let mut depth = 0;
        let mut rest = line;
        while !rest.is_empty() {
            if let Some(delim) = open_multiline {
                match rest.find(delim) {
                    Some(end) => {
                        rest = &rest[end + delim.len()..];
                        open_multiline = None;
                    }
                    None => break,
                }
                continue;
            }
            let c = rest.chars().next().unwrap_or(' ');
            if rest.starts_with("\"\"\"") || rest.starts_with("\'\'\'") {
                open_multiline = Some(&rest[..3]);
                rest = &rest[3..];
            } else if c == '"' || c == '\'' {
                // A one-line string: to its closing quote (a basic string's escapes skipped).
                let body = &rest[1..];
                let mut end = body.len();
                let mut escaped = false;
                for (i, ch) in body.char_indices() {
                    if escaped {
                        escaped = false;
                    } else if ch == '\\' && c == '"' {
                        escaped = true;
                    } else if ch == c {
                        end = i + 1;
                        break;
                    }
                }
                rest = &body[end.min(body.len())..];
            } else if c == '#' {
                break;
            } else {
                if matches!(c, '.' | '[' | '{') {
                    depth += 1;
                }
                rest = &rest[c.len_utf8()..];
            }
        }
        if best.is_none_or(|(_, d)| depth > d) {
            best = Some((k + 1, depth));
        }
    }
    best
}

/// Day of year (1..=365) of `MM-DD` or `YYYY-MM-DD` (no leap day: Feb 29 counts as Mar 1).
pub fn day_of_year(date: &str) -> Option<u32> {
    let parts: Vec<&str> = date.trim().split('-').collect();
    let (m, d) = match parts.as_slice() {
        [m, d] => (m, d),
        [y, m, d] if y.len() == 4 && y.parse::<u32>().is_ok() => (m, d),
        _ => return None,
    };
    let (m, d): (u32, u32) = (m.parse().ok()?, d.parse().ok()?);
    const DAYS: [u32; 12] = [31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31];
    if !(1..=12).contains(&m) || d == 0 || d > DAYS[m as usize - 1] + u32::from(m == 2) {
        return None;
    }
    let before: u32 = DAYS[..m as usize - 1].iter().sum();
    Some((before + d).min(365))
}

impl Scenario {
    /// Parses a scenario; `source_name` (a file path) goes into error messages.
    /// A text over [`MAX_SCENARIO_BYTES`] is refused before it is parsed.
    pub fn from_toml(text: &str, source_name: &str) -> Result<Self, ScenarioError> {
        if text.len() > MAX_SCENARIO_BYTES {
            return Err(ScenarioError::TooLarge {
                source_name: source_name.to_string(),
                bytes: text.len(),
                max: MAX_SCENARIO_BYTES,
            });
        }
        let s: Scenario = toml::from_str(text).map_err(|e| {
            let mut message = clip_parse_message(&e.to_string());
            // The parser's "recursion limit" (keys of thousands of dotted parts) comes with no
            // place: the line that nests deepest is the one.
            if e.span().is_none()
                && let Some((line, depth)) = deepest_line(text)
            {
                message = format!(
                    "line {line}: {} (a key, table or array nested {depth} levels deep)",
                    message.trim_end()
                );
            }
            ScenarioError::Parse {
                source_name: source_name.to_string(),
                message,
            }
        })?;
        s.validate(source_name)?;
        Ok(s)
    }

    /// The weather timeline, or the default winter (`[parameters.climate] default_winter`:
    /// the climatology at `latitude_deg`, or the paper-style winter fitted to these valid
    /// altitudes).
    pub fn weather_or_default(&self, altitudes: &[f32], latitude_deg: f64) -> Vec<WeatherPeriod> {
        if !self.weather.is_empty() {
            return self.weather.clone();
        }
        let c = &self.parameters.climate;
        match c.default_winter {
            crate::climate::DefaultWinter::Climatology => crate::climate::climatology_winter(
                c,
                latitude_deg,
                day_of_year(&self.start_date).unwrap_or(335),
                self.days,
            ),
            crate::climate::DefaultWinter::Cordonnier => default_winter(altitudes, self.days),
        }
    }
}

/// A TOML parser's message with every value of the file it repeats cut to
/// [`crate::MAX_ECHO_CHARS`] characters: the quoted parts (`` `...` `` and `"..."`) of its
/// lines and the source excerpt (`3 | key = value`, and the caret line under it).
fn clip_parse_message(message: &str) -> String {
    /// Longest line kept whole, characters (a list of the expected keys is about 300).
    const MAX_LINE_CHARS: usize = 1000;
    let clip_line = |line: &str| -> String {
        // The excerpt: ` 3 | text` or `   | ^^^`.
        if let Some((gutter, text)) = line.split_once('|')
            && gutter.trim().bytes().all(|b| b.is_ascii_digit())
        {
            return format!("{gutter}|{}", crate::clip_for_message(text));
        }
        // Quoted parts: the odd pieces between quote characters.
        let mut out = String::new();
        let mut quoted = false;
        for piece in line.split_inclusive(['`', '"']) {
            let (body, quote) = match piece.char_indices().last() {
                Some((at, q @ ('`' | '"'))) => (&piece[..at], Some(q)),
                _ => (piece, None),
            };
            if quoted {
                out.push_str(&crate::clip_for_message(body));
            } else {
                out.push_str(body);
            }
            if let Some(q) = quote {
                out.push(q);
                quoted = !quoted;
            }
        }
        if out.chars().nth(MAX_LINE_CHARS).is_some() {
            let head: String = out.chars().take(MAX_LINE_CHARS).collect();
            return format!("{head}... ({} bytes)", out.len());
        }
        out
    };
    message
        .lines()
        .map(clip_line)
        .collect::<Vec<_>>()
        .join("\n")
}

/// Altitude at quantile `q` (0..1) of `altitudes`.
fn quantile(altitudes: &[f32], q: f64) -> f64 {
    if altitudes.is_empty() {
        return 0.0;
    }
    let mut v: Vec<f32> = altitudes.to_vec();
    v.sort_by(f32::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize] as f64
}

/// A plausible winter for any terrain: four periods (early winter, deep winter, late winter,
/// spring) whose temperatures are set at the terrain's median altitude (−2, −6, −3, +3 °C:
/// the snow line hovers around the median altitude, higher on sunny slopes)
/// with the Table 2 lapse rate (−0.01 °C/m), and whose rain-snow limit sits at the 15th, 5th,
/// 10th and 45th altitude percentile, so snow always lies deeper up high, whatever the DEM's
/// altitude range. Westerly to north-westerly winds of 8-14 m/s, one snowfall a week.
pub fn default_winter(altitudes: &[f32], days: f64) -> Vec<WeatherPeriod> {
    let median = quantile(altitudes, 0.5);
    let t0 = |t_median: f64| t_median + 0.01 * median;
    let periods = [
        (0.0, -2.0, 300.0, 10.0, 0.15, 1.0),
        (0.3, -6.0, 280.0, 14.0, 0.05, 1.2),
        (0.6, -3.0, 300.0, 8.0, 0.10, 0.8),
        (0.85, 3.0, 250.0, 10.0, 0.45, 0.5),
    ];
    periods
        .iter()
        .map(|&(f, t, dir, speed, q, per_week)| WeatherPeriod {
            from_day: (f * days).round(),
            sea_level_temperature_c: t0(t),
            wind_from_deg: dir,
            wind_speed_m_s: speed,
            rain_snow_altitude_m: quantile(altitudes, q),
            snowfall_per_week: per_week,
            precipitation_mm_per_day: None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn too_deep_keys_are_refused_with_their_line() {
        // Issue 46: thousands of dotted parts gave "recursion limit" and no place.
        let deep = vec!["a"; 5000].join(".");
        for text in [
            format!("days = 10\n# a.b.c.d\nname = \"x.y.z\"\n{deep} = 1\n"),
            format!("days = 10\n\n[{deep}]\n"),
        ] {
            let e = Scenario::from_toml(&text, "deep.toml")
                .unwrap_err()
                .to_string();
            assert!(e.contains("deep.toml") && e.contains("line "), "{e}");
            let line = if text.contains('[') {
                "line 3"
            } else {
                "line 4"
            };
            assert!(e.contains(line) && e.contains("recursion"), "{e}");
        }
        // Deep arrays: the parser names the line itself.
        let arrays = format!("days = 10\nx = {}{}\n", "[".repeat(300), "]".repeat(300));
        let e = Scenario::from_toml(&arrays, "deep.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 2"), "{e}");
        // Strings and comments do not count.
        let text = "a = \"[[[.{{\" # ...[[\nb.c = '...'\nd = \"\"\"\n[[[[....\n\"\"\"\n";
        assert_eq!(deepest_line(text), Some((2, 1)));
    }

    #[test]
    fn full_scenario_parses() {
        let text = r#"
seed = 7
days = 60
start_date = "2026-12-15"
latitude_deg = 46.5
[[weather]]
from_day = 0
sea_level_temperature_c = 8.0
wind_from_deg = 300
wind_speed_m_s = 10
rain_snow_altitude_m = 900
snowfall_per_week = 1.0
[[weather]]
from_day = 30
sea_level_temperature_c = 12.0
wind_from_deg = 270
wind_speed_m_s = 5
rain_snow_altitude_m = 1500
snowfall_per_week = 0.5
[[snowfall_period]]
start_day = 2
days = 3
[events]
wind_transport = 3.0
[parameters.snowfall]
k_snow = 2e-4
[parameters.environment.sky]
directions = 8
[parameters.avalanche.flow]
slope_gravity = "projected"
"#;
        let s = Scenario::from_toml(text, "test.toml").unwrap();
        assert_eq!(
            s.parameters.avalanche.flow.slope_gravity,
            snowscape_avalanche::SlopeGravity::Projected
        );
        assert_eq!(s.seed, 7);
        assert_eq!(s.weather.len(), 2);
        assert_eq!(s.parameters.snowfall.k_snow, 2e-4);
        assert_eq!(s.parameters.environment.sky.directions, 8);
        assert_eq!(s.events.wind_transport, 3.0);
        assert_eq!(s.events.melt_and_state, 2.0);
        assert_eq!(day_of_year(&s.start_date), Some(349));
    }

    #[test]
    fn errors_name_the_key_and_line() {
        let e = Scenario::from_toml("days = 10\n[parameters.melt]\nk_mlet = 0.1\n", "s.toml")
            .unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains("s.toml") && m.contains("k_mlet") && m.contains("line 3"),
            "{m}"
        );
        let e = Scenario::from_toml(
            "[parameters.avalanche.flow]\nslope_gravity = \"steep\"\n",
            "s.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("slope_gravity") || e.contains("steep"), "{e}");
        let e = Scenario::from_toml("days = \"ten\"\n", "s.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 1") && e.contains("days"), "{e}");
        let e = Scenario::from_toml("days = -3\n", "s.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("days = -3"), "{e}");
        let e = Scenario::from_toml(
            "[[weather]]\nfrom_day = 0\nsea_level_temperature_c = 5\nwind_from_deg = 0\nwind_speed_m_s = 500\nrain_snow_altitude_m = 0\nsnowfall_per_week = 1\n",
            "s.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("weather[0].wind_speed_m_s = 500"), "{e}");
        assert!(Scenario::from_toml("start_date = \"02-30\"\n", "s").is_err());
    }

    #[test]
    fn a_text_over_the_size_cap_is_refused_before_it_is_parsed() {
        // 10^6 periods (150 MB): refused at once, nothing parsed.
        let one = "[[weather]]\nfrom_day = 0\nsea_level_temperature_c = 5\nwind_from_deg = 0\nwind_speed_m_s = 5\nsnowfall_per_week = 1\n";
        let text = one.repeat(MAX_SCENARIO_BYTES / one.len() + 1);
        let t = std::time::Instant::now();
        let e = Scenario::from_toml(&text, "s.toml").unwrap_err();
        assert!(
            matches!(e, ScenarioError::TooLarge { bytes, max: MAX_SCENARIO_BYTES, .. } if bytes == text.len()),
            "{e:?}"
        );
        assert!(t.elapsed().as_secs_f64() < 0.5, "{:?}", t.elapsed());
    }

    #[test]
    fn string_values_in_errors_are_cut() {
        let long = "9".repeat(100_000);
        // A validation error.
        let e = Scenario::from_toml(&format!("start_date = \"{long}\"\n"), "s.toml").unwrap_err();
        assert!(matches!(e, ScenarioError::Invalid { .. }), "{e:?}");
        assert!(e.to_string().len() < 300, "{e}");
        // Parse errors: a string where a number belongs, an unknown key, a bad value's line.
        for text in [
            format!("days = \"{long}\"\n"),
            format!("k{long} = 1\n"),
            format!("[parameters.melt]\nk_{long} = 0.1\n"),
            format!("days = 1{long}x\n"),
        ] {
            let e = Scenario::from_toml(&text, "s.toml").unwrap_err();
            let m = e.to_string();
            assert!(matches!(e, ScenarioError::Parse { .. }), "{e:?}");
            assert!(
                m.len() < 1500,
                "{} bytes: {}",
                m.len(),
                &m[..2000.min(m.len())]
            );
            assert!(m.contains("line 1") || m.contains("line 2"), "{m}");
        }
    }

    #[test]
    fn default_winter_follows_the_terrain() {
        let alts: Vec<f32> = (0..1000).map(|i| 200.0 + i as f32).collect();
        let w = default_winter(&alts, 100.0);
        assert_eq!(w.len(), 4);
        assert_eq!(w[0].from_day, 0.0);
        // −2 °C at the median altitude (700 m) with −0.01 °C/m.
        assert!((w[0].sea_level_temperature_c - 5.0).abs() < 0.01);
        assert!(w[0].rain_snow_altitude_m > 200.0 && w[0].rain_snow_altitude_m < 700.0);
        assert!(w[3].rain_snow_altitude_m > w[1].rain_snow_altitude_m);
    }

    #[test]
    fn dates() {
        assert_eq!(day_of_year("01-01"), Some(1));
        assert_eq!(day_of_year("12-31"), Some(365));
        assert_eq!(day_of_year("03-01"), Some(60));
        assert_eq!(day_of_year("13-01"), None);
        assert_eq!(day_of_year("x"), None);
    }
}
