//! The caps and value checks of a scenario ([`Scenario::validate`], [`Scenario::validate_on`],
//! [`Parameters::validate`]): the limits of the [parent module's docs](super), each refusal a
//! [`ScenarioError`] naming the key, the value (cut to [`crate::MAX_ECHO_CHARS`] characters)
//! and the accepted range or cap.

use super::{Parameters, Scenario, ScenarioError, day_of_year};
use crate::number_for_message;
use snowscape_terrain::timeline::check_timeline;

/// Most frames (`snapshot_every_days` and `snapshot_days` together) one season may take.
pub const MAX_SNAPSHOTS: f64 = 1000.0;
/// Longest season, days (ten winters).
pub const MAX_SEASON_DAYS: f64 = 3650.0;
/// Largest scenario text, bytes (a scenario with every table at its cap is about 1.5 MB).
pub const MAX_SCENARIO_BYTES: usize = 4 << 20;
/// Most `[[weather]]` periods: one a day of the longest season.
pub const MAX_WEATHER_PERIODS: usize = MAX_SEASON_DAYS as usize;
/// Most `[[snowfall_period]]` entries: one a day of the longest season.
pub const MAX_SNOWFALL_PERIODS: usize = MAX_SEASON_DAYS as usize;
/// Most `[[avalanche]]` entries: one a day of the longest season.
pub const MAX_USER_AVALANCHES: usize = MAX_SEASON_DAYS as usize;
/// Most skier start points (`skiers.starts`).
pub const MAX_SKIER_STARTS: usize = MAX_SEASON_DAYS as usize;
/// Most cells a `skiers.terminus` cell list may name.
pub const MAX_TERMINUS_CELLS: usize = 1_000_000;
/// Most checkpoints one season may write.
pub const MAX_CHECKPOINTS: f64 = 1000.0;

impl Parameters {
    /// Checks every section; the error names the section (`parameters.melt`, ...) and the
    /// message the field, its value and its range.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        fn section<E: std::fmt::Display>(
            name: &'static str,
            r: Result<(), E>,
        ) -> Result<(), (&'static str, String)> {
            r.map_err(|e| (name, e.to_string()))
        }
        section("parameters.environment", self.environment.validate())?;
        section("parameters.climate", self.climate.validate())?;
        section("parameters.snowfall", self.snowfall.validate())?;
        section("parameters.melt", self.melt.validate())?;
        section("parameters.stability", self.stability.validate())?;
        section(
            "parameters.powder_diffusion",
            self.powder_diffusion.validate(),
        )?;
        section("parameters.wind_transport", self.wind_transport.validate())?;
        section("parameters.slope_shedding", self.slope_shedding.validate())?;
        section("parameters.snowtran", self.snowtran.validate())?;
        section("parameters.avalanche", self.avalanche.validate())
    }
}

/// A [`ScenarioError::Invalid`]: `key` = `value` and why it is refused.
fn invalid(source_name: &str, key: &str, value: String, reason: &'static str) -> ScenarioError {
    ScenarioError::Invalid {
        source_name: source_name.to_string(),
        key: key.to_string(),
        value,
        reason: reason.into(),
    }
}

impl Scenario {
    /// Checks ranges the types cannot express: the caps of the repeated tables, the season,
    /// its timelines and every section (in that order; the first refusal is returned).
    pub fn validate(&self, source_name: &str) -> Result<(), ScenarioError> {
        self.check_counts(source_name)?;
        self.check_season(source_name)?;
        self.check_timelines(source_name)?;
        self.check_sections(source_name)?;
        crate::storms::check_precipitation_sources(self, source_name)
    }

    /// The repeated tables and lists within their caps.
    fn check_counts(&self, source_name: &str) -> Result<(), ScenarioError> {
        let counts = [
            ("weather", self.weather.len(), MAX_WEATHER_PERIODS),
            (
                "snowfall_period",
                self.snowfall_periods.len(),
                MAX_SNOWFALL_PERIODS,
            ),
            ("avalanche", self.avalanches.len(), MAX_USER_AVALANCHES),
            ("skiers.starts", self.skiers.starts.len(), MAX_SKIER_STARTS),
            (
                "skiers.terminus",
                match &self.skiers.terminus {
                    snowscape_skiers::Terminus::Cells(c) => c.len(),
                    _ => 0,
                },
                MAX_TERMINUS_CELLS,
            ),
            (
                "snapshot_days",
                self.snapshot_days.len(),
                MAX_SNAPSHOTS as usize,
            ),
        ];
        for (key, count, max) in counts {
            if count > max {
                return Err(ScenarioError::TooMany {
                    source_name: source_name.to_string(),
                    key,
                    count,
                    max,
                });
            }
        }
        Ok(())
    }

    /// The season: its length, start, place, snapshot and checkpoint cadences and days.
    fn check_season(&self, source_name: &str) -> Result<(), ScenarioError> {
        let bad = |key: &str, value, reason| invalid(source_name, key, value, reason);
        if !(self.days.is_finite() && self.days > 0.0 && self.days <= MAX_SEASON_DAYS) {
            return Err(bad(
                "days",
                number_for_message(self.days),
                "must be within (0, 3650]",
            ));
        }
        if day_of_year(&self.start_date).is_none() {
            return Err(bad(
                "start_date",
                crate::clip_for_message(&self.start_date),
                "must be MM-DD or YYYY-MM-DD",
            ));
        }
        if let Some(l) = self.latitude_deg
            && !(l.is_finite() && l.abs() <= 90.0)
        {
            return Err(bad(
                "latitude_deg",
                number_for_message(l),
                "must be within [-90, 90]",
            ));
        }
        if let Some(z) = self.station_altitude_m
            && !(z.is_finite() && z.abs() <= 9000.0)
        {
            return Err(bad(
                "station_altitude_m",
                number_for_message(z),
                "must be a plausible altitude (|z| <= 9000 m)",
            ));
        }
        for (key, v, most) in [
            (
                "snapshot_every_days",
                self.snapshot_every_days,
                MAX_SNAPSHOTS,
            ),
            (
                "checkpoint_every_days",
                self.checkpoint_every_days,
                MAX_CHECKPOINTS,
            ),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(
                    key,
                    number_for_message(v),
                    "must be a non-negative number of days (0: never)",
                ));
            }
            if v > 0.0 && self.days / v > most {
                return Err(bad(
                    key,
                    number_for_message(v),
                    "is too frequent: at most 1000 per season (0: never)",
                ));
            }
        }
        for (k, &d) in self.snapshot_days.iter().enumerate() {
            if !(d.is_finite() && d >= 0.0 && d <= self.days) {
                return Err(bad(
                    &format!("snapshot_days[{k}]"),
                    number_for_message(d),
                    "must be a day of the season, within [0, days]",
                ));
            }
        }
        Ok(())
    }

    /// The weather periods, forced snowfall periods and user avalanches.
    fn check_timelines(&self, source_name: &str) -> Result<(), ScenarioError> {
        let bad = |key: &str, value, reason| invalid(source_name, key, value, reason);
        // The periods' starts: the timeline rule a transport run's weather follows too.
        if let Err(e) = check_timeline(&self.weather, true) {
            return Err(ScenarioError::Invalid {
                source_name: source_name.to_string(),
                key: format!("weather[{}].{}", e.index, e.key),
                value: number_for_message(e.start),
                reason: e.reason.into(),
            });
        }
        for (k, w) in self.weather.iter().enumerate() {
            let key = |f: &str| format!("weather[{k}].{f}");
            for (f, v, ok, reason) in [
                (
                    "sea_level_temperature_c",
                    w.sea_level_temperature_c,
                    w.sea_level_temperature_c.abs() < 80.0,
                    "must be a plausible temperature (|T0| < 80 °C)",
                ),
                (
                    "wind_from_deg",
                    w.wind_from_deg,
                    w.wind_from_deg.is_finite(),
                    "must be finite",
                ),
                (
                    "wind_speed_m_s",
                    w.wind_speed_m_s,
                    (0.0..=100.0).contains(&w.wind_speed_m_s),
                    "must be within [0, 100] m/s",
                ),
                (
                    "rain_snow_altitude_m",
                    w.rain_snow_altitude_m,
                    w.rain_snow_altitude_m.abs() < 20_000.0,
                    "must be a plausible altitude",
                ),
                (
                    "snowfall_per_week",
                    w.snowfall_per_week,
                    (0.0..=100.0).contains(&w.snowfall_per_week),
                    "must be within [0, 100]",
                ),
            ] {
                if !(v.is_finite() && ok) {
                    return Err(bad(&key(f), number_for_message(v), reason));
                }
            }
            if let Some(v) = w.precipitation_mm_per_day
                && !(v.is_finite() && (0.0..=500.0).contains(&v))
            {
                return Err(bad(
                    &key("precipitation_mm_per_day"),
                    number_for_message(v),
                    "must be within [0, 500] mm/day",
                ));
            }
        }
        for (k, p) in self.snowfall_periods.iter().enumerate() {
            if !(p.start_day.is_finite()
                && p.start_day >= 0.0
                && p.days.is_finite()
                && p.days > 0.0)
            {
                return Err(bad(
                    &format!("snowfall_period[{k}]"),
                    format!(
                        "start_day {} days {}",
                        number_for_message(p.start_day),
                        number_for_message(p.days)
                    ),
                    "needs start_day >= 0 and days > 0",
                ));
            }
        }
        for (k, a) in self.avalanches.iter().enumerate() {
            if !(a.day.is_finite() && a.x.is_finite() && a.y.is_finite()) {
                return Err(bad(
                    &format!("avalanche[{k}]"),
                    format!(
                        "day {} x {} y {}",
                        number_for_message(a.day),
                        number_for_message(a.x),
                        number_for_message(a.y)
                    ),
                    "needs a finite day and finite map coordinates x, y",
                ));
            }
            if !(0.0..=self.days).contains(&a.day) {
                return Err(bad(
                    &format!("avalanche[{k}].day"),
                    number_for_message(a.day),
                    "must be a day of the season, within [0, days]",
                ));
            }
        }
        Ok(())
    }

    /// The `[events]`, `[skiers]` and `[parameters]` sections.
    fn check_sections(&self, source_name: &str) -> Result<(), ScenarioError> {
        if let Err(e) = self.events.validate() {
            return Err(ScenarioError::Parameter {
                source_name: source_name.to_string(),
                section: "events",
                message: e.to_string(),
            });
        }
        if let Err(message) = self.skiers.validate() {
            return Err(ScenarioError::Parameter {
                source_name: source_name.to_string(),
                section: "skiers",
                message,
            });
        }
        if let Err((section, message)) = self.parameters.validate() {
            return Err(ScenarioError::Parameter {
                source_name: source_name.to_string(),
                section,
                message,
            });
        }
        Ok(())
    }

    /// Checks what needs the terrain: every `[[avalanche]]` and skier start lies on the grid.
    /// Run it with [`Scenario::validate`] before any work starts.
    pub fn validate_on(
        &self,
        geometry: &snowscape_terrain::GridGeometry,
        source_name: &str,
    ) -> Result<(), ScenarioError> {
        let outside = |key: String, x: f64, y: f64| ScenarioError::Invalid {
            source_name: source_name.to_string(),
            key,
            value: format!("x {} y {}", number_for_message(x), number_for_message(y)),
            reason: "lies outside the terrain".into(),
        };
        for (k, a) in self.avalanches.iter().enumerate() {
            if geometry.map_to_cell(a.x, a.y).is_none() {
                return Err(outside(format!("avalanche[{k}]"), a.x, a.y));
            }
        }
        for (k, p) in self.skiers.starts.iter().enumerate() {
            if geometry.map_to_cell(p[0], p[1]).is_none() {
                return Err(outside(format!("skiers.starts[{k}]"), p[0], p[1]));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::{SnowfallPeriod, UserAvalanche};

    /// `n` daily `[[weather]]` periods.
    fn weather_periods(n: usize) -> String {
        let mut text = format!("days = {}\n", MAX_SEASON_DAYS);
        for k in 0..n {
            text.push_str(&format!(
                "[[weather]]\nfrom_day = {k}\nsea_level_temperature_c = 5\nwind_from_deg = 0\nwind_speed_m_s = 5\nsnowfall_per_week = 1\n"
            ));
        }
        text
    }

    #[test]
    fn repeated_tables_over_their_cap_are_refused_naming_count_and_cap() {
        // Issue 46: 10^6 weather periods took 3.6 GB and wrote a 462 MB report. One a day of
        // the longest season is accepted, one more refused.
        let s = Scenario::from_toml(&weather_periods(MAX_WEATHER_PERIODS), "s.toml").unwrap();
        assert_eq!(s.weather.len(), MAX_WEATHER_PERIODS);
        let e =
            Scenario::from_toml(&weather_periods(MAX_WEATHER_PERIODS + 1), "s.toml").unwrap_err();
        assert!(
            matches!(e, ScenarioError::TooMany { key: "weather", count, max: MAX_WEATHER_PERIODS, .. } if count == MAX_WEATHER_PERIODS + 1),
            "{e:?}"
        );
        assert!(e.to_string().contains("3651 weather entries"), "{e}");
        // The other tables, checked by `validate` whoever built the scenario.
        let s = Scenario {
            snowfall_periods: vec![
                SnowfallPeriod {
                    start_day: 1.0,
                    days: 1.0
                };
                MAX_SNOWFALL_PERIODS + 1
            ],
            ..Scenario::default()
        };
        assert!(matches!(
            s.validate("s").unwrap_err(),
            ScenarioError::TooMany {
                key: "snowfall_period",
                ..
            }
        ));
        let s = Scenario {
            avalanches: vec![
                UserAvalanche {
                    day: 1.0,
                    x: 0.0,
                    y: 0.0
                };
                MAX_USER_AVALANCHES + 1
            ],
            ..Scenario::default()
        };
        assert!(matches!(
            s.validate("s").unwrap_err(),
            ScenarioError::TooMany {
                key: "avalanche",
                ..
            }
        ));
        let mut s = Scenario::default();
        s.skiers.starts = vec![[0.0, 0.0]; MAX_SKIER_STARTS + 1];
        assert!(matches!(
            s.validate("s").unwrap_err(),
            ScenarioError::TooMany {
                key: "skiers.starts",
                ..
            }
        ));
        let mut s = Scenario::default();
        s.skiers.terminus = snowscape_skiers::Terminus::Cells(vec![0; MAX_TERMINUS_CELLS + 1]);
        assert!(matches!(
            s.validate("s").unwrap_err(),
            ScenarioError::TooMany {
                key: "skiers.terminus",
                ..
            }
        ));
        let s = Scenario {
            snapshot_days: vec![1.0; MAX_SNAPSHOTS as usize + 1],
            ..Scenario::default()
        };
        assert!(matches!(
            s.validate("s").unwrap_err(),
            ScenarioError::TooMany {
                key: "snapshot_days",
                ..
            }
        ));
    }

    #[test]
    fn huge_and_tiny_values_are_named_with_an_exponent() {
        // 1e308 written out is 309 digits, cut before its value shows.
        for (text, want) in [
            ("days = 1e308\n", "days = 1e308: "),
            ("days = -3\n", "days = -3: "),
            (
                "snapshot_every_days = 1e-300\n",
                "snapshot_every_days = 1e-300: ",
            ),
            ("latitude_deg = 90.5\n", "latitude_deg = 90.5: "),
            (
                "[[avalanche]]\nday = 1\nx = 1e300\ny = -inf\n",
                "avalanche[0] = day 1 x 1e300 y -inf: ",
            ),
        ] {
            let e = Scenario::from_toml(text, "s.toml").unwrap_err().to_string();
            assert!(e.contains(want), "{text}: {e}");
        }
    }
}
