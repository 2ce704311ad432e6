//! Storm meteorology: the air of the hours it snows or rains, the phase of their
//! precipitation, and how hard it falls (beyond Cordonnier 2018, whose snowfall is a ramp in
//! altitude). The parameters are [`crate::climate::ClimateParams`]'.
//!
//! - **Storm temperature** (climatology and `[[weather]]` periods; a station's record keeps
//!   its own): an hour of a snowfall period has the sea-level air
//!   `T = T_sl(day) + ΔT_s − a (1 − k) + k · a · cos(2π (h − h_max)/24)`,
//!   the fair-weather cycle `T_sl + a cos(...)` with its diurnal amplitude damped by `k` and
//!   its night-time minimum kept. Clouds, with the damping of precipitation, reduce the
//!   diurnal temperature range by 25-50 % against clear-sky days over most land (Dai,
//!   Trenberth & Karl 1999, J. Climate 12, 2451-2473): `k` = 0.5, the overcast, precipitating
//!   end. They do it by cutting the afternoon maximum: daily weather generators condition the
//!   maximum temperature on a wet day and leave the minimum alone (Richardson 1981, Water
//!   Resour. Res. 17(1), 182-190, WGEN), so a storm day is `a (1 − k)` colder on average
//!   (2.5 °C by default) and its warmest hour `2 a (1 − k)` (5 °C) colder than a fair day's.
//!   `ΔT_s` (`storm_temperature_offset_c`, default 0) moves storms further for a range whose
//!   storms run colder (post-frontal air) or warmer (atmospheric rivers) than that.
//! - **Phase** (default `rain_snow_phase = "psychrometric"`): the hydrometeor temperature
//!   `T_i` of Harder & Pomeroy 2013 (Hydrol. Process. 27, 1901-1914, Eq. A.5), the
//!   psychrometric balance of a falling particle,
//!   `T_i = T_a + (D λ_t⁻¹) L (ρ_a − ρ_sat(T_i))`,
//!   with the diffusivity of water vapour `D = 2.06e-5 (T_a/273.15)^1.75` m²/s (A.6), the
//!   thermal conductivity of air `λ_t = 6.3e-5 T_a + 6.73e-3` W m⁻¹ K⁻¹ (A.9, `T_a` in K),
//!   the latent heat of sublimation below 0 °C `L = 1000 (2834.1 − 0.29 T − 0.004 T²)` J/kg
//!   (A.10) and of vaporisation above `L = 1000 (2501 − 2.361 T)` (A.11), and vapour densities
//!   `ρ = m_w e / (R T)` (`m_w` = 0.01801528 kg/mol, `R` = 8.31441 J mol⁻¹ K⁻¹; `e` = RH ·
//!   e_s(T_a) for the air and e_s(T_i) at the particle, e_s the Magnus formula over water of
//!   [`crate::forcing::saturation_vapour_pressure_pa`]). The rain share is
//!   `f_r = 1 / (1 + b c^T_i)` with the fit for hourly data `b` = 2.630006, `c` = 0.09336
//!   (Harder & Pomeroy 2013; the defaults of its implementation in the Cold Regions
//!   Hydrological Model). In saturated air `T_i = T_a` and the 50 % point lies at
//!   0.41 °C; drier air cools the particle and moves it up. The relative humidity of storms
//!   is `storm_relative_humidity`, 0.9 by default: SNOW-17's rain-on-snow melt takes the
//!   air's vapour pressure as `0.9 e_sat` (Anderson 2006, Snow Accumulation and Ablation
//!   Model - SNOW-17, NWSRFS User Manual). A station's record gives its own relative humidity (its vapour
//!   pressure for a snobal file), hour by hour, with the storm value where it is missing;
//!   its `percent_snow` is not used, being the phase at the station's altitude only.
//!   Below −8 °C air the rain share (< 3e-9) is taken as 0. `rain_snow_phase =
//!   "air_temperature"` keeps the linear ramp of [`crate::climate`] around `T50`.
//! - **How much** (climatology and periods): a storm's precipitation at the reference
//!   altitude falls at a constant rate over its hours, laid hour by hour from the storm's
//!   start to its end whatever the events' timing (each Snowfall-Step lays the hours since
//!   the last, the first melt event after the storm those after its last step), so that its
//!   total is `rate × length`.
//!   The rate is, in this order of precedence, the `[[weather]]` period's
//!   `precipitation_mm_per_day`, the rate that gives a season total
//!   (`annual_precipitation_mm` or `monthly_precipitation_mm`, below), the climate's
//!   `precipitation_mm_per_day`, or 10 mm/day. A season total and a rate may not be given
//!   together (the scenario is refused naming both).
//! - **Season totals**: `monthly_precipitation_mm[m]` is the precipitation of calendar month
//!   `m` at the reference altitude (the normals a station or a gridded climatology gives);
//!   `annual_precipitation_mm` is a year's, spread evenly over the year (a season of `D` days
//!   receives `D/365` of it; give months for a range whose precipitation has a season). Each
//!   calendar month of the season (or the part of it the season covers) gets its share, and
//!   its storms fall at `P_month / E[storm days]`, where a day's expected storm share is 1
//!   inside a forced `[[snowfall_period]]` and else `r L / (1 + r L)`: the share of time of
//!   an alternating process of dry spells ending at the Poisson rate `r` of the period's
//!   `snowfall_per_week` and storms of mean length `L` (`events.snowfall_mean_days`). The
//!   drawn storms make a season's total vary about the target as real years do; forced
//!   periods alone (`snowfall_per_week = 0`) meet it exactly. A month in which no storm can
//!   fall (no Poisson storms, no forced period) loses its share, with a warning.

use crate::scenario::{Scenario, ScenarioError, SnowfallPeriod, WeatherPeriod};
use serde::{Deserialize, Serialize};

/// How precipitation is split into rain and snow.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum RainSnowPhase {
    /// The hydrometeor temperature of Harder & Pomeroy 2013 from air temperature and
    /// humidity (module docs). The default.
    #[default]
    Psychrometric,
    /// A linear ramp in air temperature around `rain_snow_t50_c` (Jennings et al. 2018).
    AirTemperature,
}

/// Molar mass of water, kg/mol (Harder & Pomeroy 2013).
const WATER_MOLAR_MASS: f64 = 0.01801528;
/// Universal gas constant, J mol⁻¹ K⁻¹ (Harder & Pomeroy 2013).
const GAS_CONSTANT: f64 = 8.31441;
/// Air colder than this, °C, gives a rain share below 3e-9 (`T_i ≤ T_a`): taken as snow.
const ALL_SNOW_BELOW_C: f64 = -8.0;

/// Water vapour density at vapour pressure `e_pa` and temperature `t_c`, kg/m³.
fn vapour_density(e_pa: f64, t_c: f64) -> f64 {
    WATER_MOLAR_MASS * e_pa / (GAS_CONSTANT * (t_c + 273.15))
}

/// The hydrometeor temperature of Harder & Pomeroy 2013 (Eq. A.5-A.11), °C, for air at
/// `t_air_c` °C and relative humidity `relative_humidity` (0..1, with respect to water):
/// solved by Newton's method from `T_i = T_a` (the balance is concave and decreasing in
/// `T_i`, so the iterates fall monotonically onto the root).
pub fn hydrometeor_temperature_c(t_air_c: f64, relative_humidity: f64) -> f64 {
    let t_k = t_air_c + 273.15;
    let diffusivity = 2.06e-5 * (t_k / 273.15).powf(1.75);
    let conductivity = 6.3e-5 * t_k + 6.73e-3;
    let latent = if t_air_c < 0.0 {
        1000.0 * (2834.1 - 0.29 * t_air_c - 0.004 * t_air_c * t_air_c)
    } else {
        1000.0 * (2501.0 - 2.361 * t_air_c)
    };
    let k = diffusivity * latent / conductivity;
    let rh = relative_humidity.clamp(0.0, 1.0);
    let rho_air = vapour_density(
        rh * crate::forcing::saturation_vapour_pressure_pa(t_air_c),
        t_air_c,
    );
    let mut t_i = t_air_c;
    for _ in 0..50 {
        let e_s = crate::forcing::saturation_vapour_pressure_pa(t_i);
        let rho_sat = vapour_density(e_s, t_i);
        let f = t_air_c + k * (rho_air - rho_sat) - t_i;
        // d(ρ_sat)/dT: the Magnus slope over the ideal-gas factor.
        let de_dt = e_s * 17.62 * 243.12 / ((243.12 + t_i) * (243.12 + t_i));
        let drho = WATER_MOLAR_MASS / GAS_CONSTANT
            * (de_dt / (t_i + 273.15) - e_s / ((t_i + 273.15) * (t_i + 273.15)));
        let step = f / (-k * drho - 1.0);
        t_i -= step;
        if step.abs() < 1e-7 {
            break;
        }
    }
    t_i
}

/// Share of precipitation falling as snow by the psychrometric phase (module docs), for air
/// at `t_air_c` °C and relative humidity `relative_humidity`, with the fit's `b` and `c`.
pub fn psychrometric_snow_share(t_air_c: f64, relative_humidity: f64, b: f64, c: f64) -> f64 {
    if t_air_c <= ALL_SNOW_BELOW_C {
        return 1.0;
    }
    let t_i = hydrometeor_temperature_c(t_air_c, relative_humidity);
    1.0 - 1.0 / (1.0 + b * c.powf(t_i))
}

/// Expected share of time in a snowfall period under a Poisson start rate `per_day` and mean
/// storm length `mean_days`: `r L / (1 + r L)` (module docs).
pub fn expected_storm_share(per_day: f64, mean_days: f64) -> f64 {
    let rl = per_day.max(0.0) * mean_days.max(0.0);
    rl / (1.0 + rl)
}

/// Days of each calendar month (no leap day).
const MONTH_DAYS: [f64; 12] = [
    31.0, 28.0, 31.0, 30.0, 31.0, 30.0, 31.0, 31.0, 30.0, 31.0, 30.0, 31.0,
];

/// The storm rate of each calendar month of a season, from a season total (module docs).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StormRates {
    /// First season day of each month segment, increasing.
    from_day: Vec<f64>,
    /// Precipitation during that segment's storms at the reference altitude, mm/day.
    mm_per_day: Vec<f64>,
    /// The total of the segments in which no storm can fall (no Poisson storms, no forced
    /// period), mm at the reference altitude: it does not fall.
    stranded_mm: f64,
}

/// What [`StormRates::new`] reads besides the climate.
pub struct SeasonStorms<'a> {
    /// The weather timeline (each period's `snowfall_per_week`).
    pub weather: &'a [WeatherPeriod],
    /// Forced snowfall periods.
    pub forced: &'a [SnowfallPeriod],
    /// Mean storm length, days.
    pub mean_storm_days: f64,
    /// Day of year (1..=365) of season day 0.
    pub start_day_of_year: u32,
    /// Length of the season, days.
    pub days: f64,
}

impl StormRates {
    /// The rates that give the climate's season total, or `None` when it sets none.
    pub fn new(climate: &crate::climate::ClimateParams, s: &SeasonStorms) -> Option<Self> {
        let monthly: [f64; 12] = match (
            climate.monthly_precipitation_mm,
            climate.annual_precipitation_mm,
        ) {
            (Some(m), _) => m,
            (None, Some(a)) => MONTH_DAYS.map(|d| a * d / 365.0),
            (None, None) => return None,
        };
        let mut rates = Self::default();
        // (month, season days covered, expected storm days) of the current segment.
        let mut segment: Option<(usize, f64, f64)> = None;
        let close = |rates: &mut Self, seg: (usize, f64, f64)| {
            let (m, covered, storm_days) = seg;
            let total = monthly[m] * covered / MONTH_DAYS[m];
            let rate = if storm_days > 0.0 {
                total / storm_days
            } else {
                rates.stranded_mm += total;
                0.0
            };
            rates.mm_per_day.push(rate);
        };
        let mut day = 0.0f64;
        while day < s.days {
            let width = (s.days - day).min(1.0);
            let doy = (s.start_day_of_year as f64 - 1.0 + day).rem_euclid(365.0) as u32 + 1;
            let m = snowscape_environment::insolation::month_of(doy) as usize - 1;
            let share = storm_share_of_day(s, day, width);
            match segment {
                Some((sm, covered, storms)) if sm == m => {
                    segment = Some((sm, covered + width, storms + share * width));
                }
                _ => {
                    if let Some(seg) = segment.take() {
                        close(&mut rates, seg);
                    }
                    rates.from_day.push(day);
                    segment = Some((m, width, share * width));
                }
            }
            day += 1.0;
        }
        if let Some(seg) = segment {
            close(&mut rates, seg);
        }
        Some(rates)
    }

    /// The part of the season total that falls in months without storms, mm at the
    /// reference altitude (it does not fall: a warning for the user).
    pub fn stranded_mm(&self) -> f64 {
        self.stranded_mm
    }

    /// The storm rate at season day `day`, mm/day at the reference altitude.
    pub fn at(&self, day: f64) -> f64 {
        let k = self
            .from_day
            .partition_point(|&d| d <= day)
            .saturating_sub(1);
        self.mm_per_day.get(k).copied().unwrap_or(0.0)
    }
}

/// Expected share of `[day, day + width)` in a storm: the forced periods' cover, and the
/// Poisson share of the weather period in force over the rest.
fn storm_share_of_day(s: &SeasonStorms, day: f64, width: f64) -> f64 {
    let end = day + width;
    let forced: f64 = s
        .forced
        .iter()
        .map(|p| ((p.start_day + p.days).min(end) - p.start_day.max(day)).max(0.0))
        .sum::<f64>()
        / width;
    let forced = forced.min(1.0);
    let per_week = snowscape_terrain::timeline::period_index_at(s.weather, day)
        .map_or(0.0, |k| s.weather[k].snowfall_per_week);
    forced + (1.0 - forced) * expected_storm_share(per_week / 7.0, s.mean_storm_days)
}

/// A season total of precipitation (`[parameters.climate]`) is given alone: not with a
/// weather period's storm rate, nor with a station's record ([`crate::storms`]).
pub(crate) fn check_precipitation_sources(
    scenario: &Scenario,
    source_name: &str,
) -> Result<(), ScenarioError> {
    let c = &scenario.parameters.climate;
    let total = if c.annual_precipitation_mm.is_some() {
        "parameters.climate.annual_precipitation_mm"
    } else if c.monthly_precipitation_mm.is_some() {
        "parameters.climate.monthly_precipitation_mm"
    } else {
        return Ok(());
    };
    let conflict = |first: String, reason: &'static str| ScenarioError::Conflict {
        source_name: source_name.to_string(),
        first,
        second: total.to_string(),
        reason,
    };
    if let Some(k) = scenario
        .weather
        .iter()
        .position(|w| w.precipitation_mm_per_day.is_some())
    {
        return Err(conflict(
            format!("weather[{k}].precipitation_mm_per_day"),
            "a period's storm rate and a season total both say how much falls: give one",
        ));
    }
    if scenario.forcing.is_some() {
        return Err(conflict(
            "forcing".into(),
            "the station's record gives the precipitation",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::climate::ClimateParams;

    #[test]
    fn saturated_air_gives_the_air_temperature_and_dry_air_cools_the_particle() {
        for t in [-5.0, 0.0, 2.0, 6.0] {
            assert!((hydrometeor_temperature_c(t, 1.0) - t).abs() < 1e-6, "{t}");
        }
        // 90 % at +1 °C: under a degree of evaporative cooling.
        let t_i = hydrometeor_temperature_c(1.0, 0.9);
        assert!((-0.3..0.6).contains(&t_i), "{t_i}");
        // Half-saturated air at +5 °C: the particle is about 4 °C colder.
        let dry = hydrometeor_temperature_c(5.0, 0.5);
        assert!((0.5..1.5).contains(&dry), "{dry}");
        // Monotone in both arguments.
        assert!(hydrometeor_temperature_c(2.0, 0.8) < hydrometeor_temperature_c(2.0, 0.9));
        assert!(hydrometeor_temperature_c(2.0, 0.9) < hydrometeor_temperature_c(2.1, 0.9));
    }

    #[test]
    fn a_storm_at_minus_one_snows_and_at_plus_three_rains() {
        let p = ClimateParams::default();
        assert_eq!(p.rain_snow_phase, RainSnowPhase::Psychrometric);
        let rh = p.storm_relative_humidity as f32;
        let cold = p.snow_share(-1.0, rh);
        let warm = p.snow_share(3.0, rh);
        assert!(cold > 0.95, "snow share at −1 °C: {cold}");
        assert!(warm < 0.05, "snow share at +3 °C: {warm}");
        // The 50 % point lies between; drier air snows at warmer air.
        let half = p.snow_share(1.0, rh);
        assert!((0.3..0.9).contains(&half), "{half}");
        assert!(p.snow_share(1.5, 0.6) > p.snow_share(1.5, 0.95));
        // Below −8 °C: all snow.
        assert_eq!(p.snow_share(-8.5, 0.1), 1.0);
        // The linear ramp is still there by name.
        let linear = ClimateParams {
            rain_snow_phase: RainSnowPhase::AirTemperature,
            ..ClimateParams::default()
        };
        assert_eq!(linear.snow_share(-1.0, 0.2), 1.0);
        assert_eq!(linear.snow_share(3.0, 1.0), 0.0);
    }

    #[test]
    fn season_totals_give_rates_over_the_expected_storm_days() {
        let weather = [WeatherPeriod {
            from_day: 0.0,
            sea_level_temperature_c: 5.0,
            wind_from_deg: 270.0,
            wind_speed_m_s: 5.0,
            rain_snow_altitude_m: 0.0,
            snowfall_per_week: 0.0,
            precipitation_mm_per_day: None,
        }];
        // December 1 to January 30: a storm of 4 days in each month.
        let forced = [
            SnowfallPeriod {
                start_day: 2.0,
                days: 4.0,
            },
            SnowfallPeriod {
                start_day: 40.0,
                days: 4.0,
            },
        ];
        let s = SeasonStorms {
            weather: &weather,
            forced: &forced,
            mean_storm_days: 3.0,
            start_day_of_year: 335,
            days: 61.0,
        };
        let mut c = ClimateParams {
            monthly_precipitation_mm: Some([
                200.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 310.0,
            ]),
            ..ClimateParams::default()
        };
        let r = StormRates::new(&c, &s).unwrap();
        // December: 310 mm over 4 storm days; January (30 of its 31 days): 200·30/31 over 4.
        assert!((r.at(3.0) - 77.5).abs() < 1e-9, "{}", r.at(3.0));
        assert!((r.at(41.0) - 200.0 * 30.0 / 31.0 / 4.0).abs() < 1e-9);
        c.monthly_precipitation_mm = None;
        c.annual_precipitation_mm = Some(365.0);
        let r = StormRates::new(&c, &s).unwrap();
        assert!((r.at(3.0) - 31.0 / 4.0).abs() < 1e-9);
        assert_eq!(r.stranded_mm(), 0.0);
        // Without the January storm, January's 30 days of rain have no storm to fall in.
        let r = StormRates::new(
            &c,
            &SeasonStorms {
                forced: &forced[..1],
                ..s
            },
        )
        .unwrap();
        assert!((r.stranded_mm() - 30.0).abs() < 1e-9, "{}", r.stranded_mm());
        // Poisson storms: one a week of three days is storming 30 % of the time.
        assert!((expected_storm_share(1.0 / 7.0, 3.0) - 0.3).abs() < 1e-12);
        c.annual_precipitation_mm = None;
        assert!(StormRates::new(&c, &s).is_none());
    }
}
