//! The air a season runs in: a climatological default winter from latitude and dates, the
//! diurnal temperature cycle, the lapse rate, the orographic precipitation gradient and the
//! rain/snow phase (beyond Cordonnier 2018, whose weather is a constant `T0` per period and a
//! snowfall ramp `k_snow · (A − A0)`; `default_winter = "cordonnier"` keeps that).
//!
//! - **Air temperature** at a cell and hour: `T = T_sl(day) + Γ · z + a · cos(2π (h − h_max)/24)`
//!   with the standard-atmosphere lapse rate `Γ` = −6.5 °C/km (ICAO 1993), the diurnal
//!   half-range `a` (5 °C: a diurnal range of 10 °C, typical of clear mountain days) peaking
//!   at `h_max` = 15 h solar time. Station forcing replaces `T_sl + a cos(...)` by the
//!   station's hourly record moved to sea level with the same `Γ`.
//! - **Climatology** (no `[[weather]]`, no forcing): the sea-level-equivalent daily mean
//!   `T_sl = T̄(φ) − A(φ) cos(2π (d − d_min)/365)` with `T̄ = 45.95 − 0.65 |φ|`,
//!   `A = 11.35 − 0.05 |φ|` (°C, φ in degrees) and the coldest day `d_min` = 20 January
//!   (20 July south of the equator). The coefficients are our fit to 1991-2020 January and
//!   July normals of mountain stations reduced to sea level with `Γ` (Säntis and Davos
//!   at 47 °N: January ≈ 6 °C, July ≈ 23 °C; Sierra Nevada stations at 37-38 °N: ≈ 12 and
//!   31 °C; Finse at 60 °N: ≈ −1 and 15 °C), not tuned to any snow observation.
//! - **Precipitation** during a snowfall period: `P = P_ref · clamp(1 + g · (z − z_ref)/100 m)`
//!   with `g` = 0.05 per 100 m, the linearised orographic adjustment of MicroMet (Liston &
//!   Elder 2006, J. Hydrometeorol. 7, Eq. 33, χ ≈ 0.27 km⁻¹ after Thornton et al. 1997),
//!   `P_ref` the storm rate at `z_ref` = 1500 m: 10 mm/day by default (chosen here: about
//!   90 mm a month over the snowfall periods of three days in ten, a mid-altitude winter
//!   month in the Alps or the Sierra Nevada), a scenario's rate, or the rate that gives its
//!   `annual_precipitation_mm` or `monthly_precipitation_mm` ([`crate::storms`]).
//! - **Storms** are colder than fair weather, with a damped diurnal cycle, and their phase
//!   comes from the hydrometeor temperature of Harder & Pomeroy 2013 with the storm's
//!   humidity ([`crate::storms`]).
//! - **Phase** by air temperature alone (`rain_snow_phase = "air_temperature"`): the snow
//!   share falls linearly from 1 at `T50 − r/2` to 0 at `T50 + r/2`, with the 50 % rain-snow
//!   temperature `T50` = 1.0 °C (Jennings et al. 2018, Nat. Commun. 9, 1148: the Northern
//!   Hemisphere mean) and a 2 °C transition.
//! - **Clouds**: the shortwave is the clear sky times 0.8 on fair days and 0.25 during
//!   snowfall periods (our choice: overcast skies pass about a quarter of the clear-sky
//!   shortwave, Kasten & Czeplak 1980's cloud law at 8/8 cover gives 0.25).
//! - **Humidity, cloud cover and wind** of the energy-balance melt ([`crate::melt::energy_balance`]):
//!   relative humidity 0.6 on fair days and 0.95 during snowfall periods (chosen here: winter
//!   means of mountain stations lie around 0.5-0.8; precipitating cloud is near saturation);
//!   the cloud cover `N` that gives the shortwave share `c` above by Kasten & Czeplak 1980's
//!   law `c = 1 − 0.75 N^3.4` (`N` = 0.68 for 0.8, 1 for 0.25), unless set; a wind speed of
//!   3 m/s at the wind measurement height (chosen here: a light breeze over snow). Station
//!   forcing's records replace them where it has them.

use crate::scenario::WeatherPeriod;
use serde::{Deserialize, Serialize};
use snowscape_environment::ClearSkyParams;

/// Which default weather a scenario without `[[weather]]` gets.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum DefaultWinter {
    /// From latitude and dates with the standard lapse rate (module docs). The default.
    #[default]
    Climatology,
    /// The earlier default fitted to the DEM's altitude percentiles (Cordonnier-style periods).
    Cordonnier,
}

/// Parameters of the air (`[parameters.climate]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct ClimateParams {
    /// The default weather when the scenario gives none.
    pub default_winter: DefaultWinter,
    /// Lapse rate Γ, °C per km. ICAO standard atmosphere: −6.5.
    pub lapse_rate_c_per_km: f64,
    /// Half the diurnal temperature range a, °C. Chosen here: 5 (module docs). Station
    /// forcing carries its own cycle.
    pub diurnal_amplitude_c: f64,
    /// Solar hour of the daily maximum temperature. Chosen here: 15.
    pub warmest_solar_hour: f64,
    /// Added to the climatology's temperatures, °C (a warmer or colder winter). Default 0.
    pub temperature_offset_c: f64,
    /// Precipitation during snowfall periods at `reference_altitude_m`, mm of water per day.
    /// Unset: 10 (module docs), or the rate a season total gives. Not with a season total.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub precipitation_mm_per_day: Option<f64>,
    /// A year's precipitation at `reference_altitude_m`, mm of water, spread evenly over the
    /// year and falling in the season's storms ([`crate::storms`]). Unset by default; not
    /// with `precipitation_mm_per_day` or `monthly_precipitation_mm`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub annual_precipitation_mm: Option<f64>,
    /// Each calendar month's precipitation at `reference_altitude_m` (January first), mm of
    /// water, falling in that month's storms ([`crate::storms`]). Unset by default; not with
    /// `precipitation_mm_per_day` or `annual_precipitation_mm`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub monthly_precipitation_mm: Option<[f64; 12]>,
    /// Altitude of `precipitation_mm_per_day`, m (a station's altitude replaces it). Default 1500.
    pub reference_altitude_m: f64,
    /// Orographic precipitation gradient, fraction per 100 m. Liston & Elder 2006: 0.05.
    pub orographic_gradient_per_100m: f64,
    /// Bounds of the orographic factor `[min, max]`. Chosen here: [0.2, 3].
    pub orographic_factor_range: [f64; 2],
    /// 50 % rain-snow air temperature T50, °C. Jennings et al. 2018: 1.0.
    pub rain_snow_t50_c: f64,
    /// Width of the rain-snow transition, °C. Chosen here: 2.
    pub rain_snow_range_c: f64,
    /// How precipitation splits into rain and snow: `psychrometric` (Harder & Pomeroy 2013,
    /// from air temperature and humidity; the default) or `air_temperature` (the ramp of
    /// `rain_snow_t50_c` and `rain_snow_range_c`).
    pub rain_snow_phase: crate::storms::RainSnowPhase,
    /// Relative humidity of the air during snowfall periods, 0..1 (with respect to water).
    /// Anderson 2006 (SNOW-17's rain-on-snow air): 0.9. A station's record replaces it.
    pub storm_relative_humidity: f64,
    /// `b` of the psychrometric rain share `1 / (1 + b c^T_i)`. Harder & Pomeroy 2013
    /// (hourly data): 2.630006.
    pub psychrometric_b: f64,
    /// `c` of the psychrometric rain share. Harder & Pomeroy 2013 (hourly data): 0.09336.
    pub psychrometric_c: f64,
    /// Diurnal amplitude of snowfall periods over the fair-weather one, k. Dai et al. 1999
    /// (clouds and precipitation cut the diurnal range by 25-50 %): 0.5.
    pub storm_diurnal_factor: f64,
    /// Added to the air of snowfall periods, °C, beyond the damped cycle (which keeps the
    /// fair night's minimum, Richardson 1981). Default 0.
    pub storm_temperature_offset_c: f64,
    /// Clear-sky shortwave.
    pub clear_sky: ClearSkyParams,
    /// Shortwave share of the clear sky on fair days. Chosen here: 0.8.
    pub fair_cloud_factor: f64,
    /// Shortwave share of the clear sky during snowfall periods. Kasten & Czeplak 1980: 0.25.
    pub storm_cloud_factor: f64,
    /// Relative humidity on fair days, 0..=1 (energy-balance melt). Chosen here: 0.6.
    pub fair_relative_humidity: f64,
    /// Cloud cover on fair days, 0..=1. Default: Kasten & Czeplak 1980's cover for
    /// `fair_cloud_factor` (0.68 for 0.8).
    pub fair_cloud_cover: Option<f64>,
    /// Cloud cover during snowfall periods, 0..=1. Default: Kasten & Czeplak 1980's cover for
    /// `storm_cloud_factor` (1 for 0.25).
    pub storm_cloud_cover: Option<f64>,
    /// Wind speed at the energy balance's wind height, m/s. Chosen here: 3.
    pub wind_speed_m_s: f64,
}

impl Default for ClimateParams {
    fn default() -> Self {
        Self {
            default_winter: DefaultWinter::default(),
            lapse_rate_c_per_km: -6.5,
            diurnal_amplitude_c: 5.0,
            warmest_solar_hour: 15.0,
            temperature_offset_c: 0.0,
            precipitation_mm_per_day: None,
            annual_precipitation_mm: None,
            monthly_precipitation_mm: None,
            reference_altitude_m: 1500.0,
            orographic_gradient_per_100m: 0.05,
            orographic_factor_range: [0.2, 3.0],
            rain_snow_t50_c: 1.0,
            rain_snow_range_c: 2.0,
            rain_snow_phase: crate::storms::RainSnowPhase::Psychrometric,
            storm_relative_humidity: 0.9,
            psychrometric_b: 2.630006,
            psychrometric_c: 0.09336,
            storm_diurnal_factor: 0.5,
            storm_temperature_offset_c: 0.0,
            clear_sky: ClearSkyParams::default(),
            fair_cloud_factor: 0.8,
            storm_cloud_factor: 0.25,
            fair_relative_humidity: 0.6,
            fair_cloud_cover: None,
            storm_cloud_cover: None,
            wind_speed_m_s: 3.0,
        }
    }
}

/// Why climate parameters were refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClimateError {
    /// A value out of its range.
    #[error("{key} = {value}: {reason}")]
    OutOfRange {
        /// `climate.<field>`.
        key: String,
        value: f64,
        reason: &'static str,
    },
    /// Two settings that say the same thing differently.
    #[error("{first} and {second} are both set: {reason}")]
    Conflict {
        first: &'static str,
        second: &'static str,
        reason: &'static str,
    },
}

/// `Ok` when `value` is finite and `ok`, else the error naming `climate.<name>`.
fn check(name: &str, value: f64, ok: bool, reason: &'static str) -> Result<(), ClimateError> {
    if value.is_finite() && ok {
        return Ok(());
    }
    Err(ClimateError::OutOfRange {
        key: format!("climate.{name}"),
        value,
        reason,
    })
}

/// The default storm rate, mm/day at the reference altitude (module docs).
pub const DEFAULT_PRECIPITATION_MM_PER_DAY: f64 = 10.0;

impl ClimateParams {
    /// Checks every field and that at most one of the storm rate and the season totals is
    /// given; the error names the key (`climate.<field>`) and its value, or both keys.
    pub fn validate(&self) -> Result<(), ClimateError> {
        self.check_precipitation()?;
        let mut fixed: Vec<(&str, f64, bool, &'static str)> = vec![
            (
                "lapse_rate_c_per_km",
                self.lapse_rate_c_per_km,
                (-15.0..=5.0).contains(&self.lapse_rate_c_per_km),
                "must be within [-15, 5] °C/km",
            ),
            (
                "diurnal_amplitude_c",
                self.diurnal_amplitude_c,
                (0.0..=20.0).contains(&self.diurnal_amplitude_c),
                "must be within [0, 20] °C",
            ),
            (
                "warmest_solar_hour",
                self.warmest_solar_hour,
                (0.0..24.0).contains(&self.warmest_solar_hour),
                "must be within [0, 24)",
            ),
            (
                "temperature_offset_c",
                self.temperature_offset_c,
                self.temperature_offset_c.abs() <= 30.0,
                "must be within [-30, 30] °C",
            ),
            (
                "reference_altitude_m",
                self.reference_altitude_m,
                self.reference_altitude_m.abs() <= 9000.0,
                "must be a plausible altitude (|z| <= 9000 m)",
            ),
            (
                "orographic_gradient_per_100m",
                self.orographic_gradient_per_100m,
                (-0.5..=0.5).contains(&self.orographic_gradient_per_100m),
                "must be within [-0.5, 0.5] per 100 m",
            ),
            (
                "rain_snow_t50_c",
                self.rain_snow_t50_c,
                self.rain_snow_t50_c.abs() <= 10.0,
                "must be within [-10, 10] °C",
            ),
            (
                "rain_snow_range_c",
                self.rain_snow_range_c,
                (0.0..=10.0).contains(&self.rain_snow_range_c),
                "must be within [0, 10] °C",
            ),
            (
                "fair_cloud_factor",
                self.fair_cloud_factor,
                (0.0..=1.0).contains(&self.fair_cloud_factor),
                "must be within [0, 1]",
            ),
            (
                "storm_cloud_factor",
                self.storm_cloud_factor,
                (0.0..=1.0).contains(&self.storm_cloud_factor),
                "must be within [0, 1]",
            ),
        ];
        for (name, v) in [
            ("fair_relative_humidity", self.fair_relative_humidity),
            ("fair_cloud_cover", self.fair_cloud_cover.unwrap_or(0.0)),
            ("storm_cloud_cover", self.storm_cloud_cover.unwrap_or(0.0)),
        ] {
            fixed.push((name, v, (0.0..=1.0).contains(&v), "must be within [0, 1]"));
        }
        fixed.push((
            "wind_speed_m_s",
            self.wind_speed_m_s,
            (0.0..=50.0).contains(&self.wind_speed_m_s),
            "must be within [0, 50] m/s",
        ));
        let [lo, hi] = self.orographic_factor_range;
        fixed.push((
            "orographic_factor_range[0]",
            lo,
            (0.0..=1.0).contains(&lo),
            "must be within [0, 1]",
        ));
        fixed.push((
            "orographic_factor_range[1]",
            hi,
            (1.0..=10.0).contains(&hi),
            "must be within [1, 10]",
        ));
        fixed.push((
            "clear_sky.transmissivity",
            self.clear_sky.transmissivity,
            self.clear_sky.transmissivity > 0.0 && self.clear_sky.transmissivity <= 1.0,
            "must be within (0, 1]",
        ));
        fixed.push((
            "clear_sky.diffuse_share",
            self.clear_sky.diffuse_share,
            (0.0..=1.0).contains(&self.clear_sky.diffuse_share),
            "must be within [0, 1]",
        ));
        fixed.extend(self.storm_checks());
        for (name, value, ok, reason) in fixed {
            check(name, value, ok, reason)?;
        }
        Ok(())
    }

    /// At most one of the storm rate and the season totals, each within its range.
    fn check_precipitation(&self) -> Result<(), ClimateError> {
        let given = [
            (
                "climate.precipitation_mm_per_day",
                self.precipitation_mm_per_day.is_some(),
            ),
            (
                "climate.annual_precipitation_mm",
                self.annual_precipitation_mm.is_some(),
            ),
            (
                "climate.monthly_precipitation_mm",
                self.monthly_precipitation_mm.is_some(),
            ),
        ];
        let mut set = given.iter().filter(|g| g.1).map(|g| g.0);
        if let (Some(first), Some(second)) = (set.next(), set.next()) {
            return Err(ClimateError::Conflict {
                first,
                second,
                reason: "give one of the storm rate, the annual total and the monthly totals",
            });
        }
        if let Some(v) = self.precipitation_mm_per_day {
            check(
                "precipitation_mm_per_day",
                v,
                (0.0..=500.0).contains(&v),
                "must be within [0, 500] mm/day",
            )?;
        }
        if let Some(v) = self.annual_precipitation_mm {
            check(
                "annual_precipitation_mm",
                v,
                (0.0..=20_000.0).contains(&v),
                "must be within [0, 20000] mm (the wettest places get about 12000 a year)",
            )?;
        }
        for (m, &v) in self.monthly_precipitation_mm.iter().flatten().enumerate() {
            if !(v.is_finite() && (0.0..=5000.0).contains(&v)) {
                return Err(ClimateError::OutOfRange {
                    key: format!("climate.monthly_precipitation_mm[{m}]"),
                    value: v,
                    reason: "must be within [0, 5000] mm (the wettest month on record is about 9300)",
                });
            }
        }
        Ok(())
    }

    /// The ranges of the storm parameters ([`crate::storms`]).
    fn storm_checks(&self) -> [(&'static str, f64, bool, &'static str); 5] {
        [
            (
                "storm_relative_humidity",
                self.storm_relative_humidity,
                (0.0..=1.0).contains(&self.storm_relative_humidity),
                "must be within [0, 1] (a fraction, not percent)",
            ),
            (
                "psychrometric_b",
                self.psychrometric_b,
                self.psychrometric_b > 0.0 && self.psychrometric_b <= 100.0,
                "must be within (0, 100]",
            ),
            (
                "psychrometric_c",
                self.psychrometric_c,
                self.psychrometric_c > 0.0 && self.psychrometric_c < 1.0,
                "must be within (0, 1): rain must grow with temperature",
            ),
            (
                "storm_diurnal_factor",
                self.storm_diurnal_factor,
                (0.0..=1.0).contains(&self.storm_diurnal_factor),
                "must be within [0, 1]",
            ),
            (
                "storm_temperature_offset_c",
                self.storm_temperature_offset_c,
                self.storm_temperature_offset_c.abs() <= 20.0,
                "must be within [-20, 20] °C",
            ),
        ]
    }

    /// The storm rate the climate sets, mm/day at the reference altitude, when no season
    /// total is given.
    pub fn storm_precipitation_mm_per_day(&self) -> f64 {
        self.precipitation_mm_per_day
            .unwrap_or(DEFAULT_PRECIPITATION_MM_PER_DAY)
    }

    /// Whether a season total sets the storm rates ([`crate::storms::StormRates`]).
    pub fn has_season_total(&self) -> bool {
        self.annual_precipitation_mm.is_some() || self.monthly_precipitation_mm.is_some()
    }

    /// Lapse rate, °C per m.
    pub fn lapse_c_per_m(&self) -> f64 {
        self.lapse_rate_c_per_km * 1e-3
    }

    /// The diurnal term at solar hour `hour` (0..24), °C.
    pub fn diurnal_c(&self, hour: f64) -> f64 {
        self.diurnal_amplitude_c
            * (std::f64::consts::TAU * (hour - self.warmest_solar_hour) / 24.0).cos()
    }

    /// The diurnal term of an hour of a snowfall period, °C ([`crate::storms`]): the
    /// fair-weather cycle damped by `k` about the same night-time minimum, plus the storm
    /// offset, `ΔT_s − a (1 − k) + k a cos(...)`.
    pub fn storm_diurnal_c(&self, hour: f64) -> f64 {
        let k = self.storm_diurnal_factor;
        self.storm_temperature_offset_c - self.diurnal_amplitude_c * (1.0 - k)
            + k * self.diurnal_c(hour)
    }

    /// The humidity, cloud cover and wind of a fair (`storm` false) or snowfall hour
    /// (module docs), without a recorded longwave.
    pub fn hour_air(&self, storm: bool) -> crate::melt::HourAir {
        let (rh, cover, factor) = if storm {
            (
                self.storm_relative_humidity,
                self.storm_cloud_cover,
                self.storm_cloud_factor,
            )
        } else {
            (
                self.fair_relative_humidity,
                self.fair_cloud_cover,
                self.fair_cloud_factor,
            )
        };
        crate::melt::HourAir {
            relative_humidity: rh as f32,
            cloud_cover: cover.unwrap_or_else(|| cloud_cover_of_factor(factor)) as f32,
            wind_speed_m_s: self.wind_speed_m_s as f32,
            longwave_in_w_m2: None,
        }
    }

    /// Share of precipitation falling as snow in air at `t` °C and relative humidity
    /// `relative_humidity` (0..1), by [`ClimateParams::rain_snow_phase`].
    #[inline]
    pub fn snow_share(&self, t: f32, relative_humidity: f32) -> f32 {
        match self.rain_snow_phase {
            crate::storms::RainSnowPhase::Psychrometric => crate::storms::psychrometric_snow_share(
                t as f64,
                relative_humidity as f64,
                self.psychrometric_b,
                self.psychrometric_c,
            ) as f32,
            crate::storms::RainSnowPhase::AirTemperature => self.ramp_snow_share(t),
        }
    }

    /// Share of precipitation falling as snow at air temperature `t` °C by the linear ramp
    /// around `T50`.
    fn ramp_snow_share(&self, t: f32) -> f32 {
        let r = self.rain_snow_range_c as f32;
        if r <= 0.0 {
            return if t <= self.rain_snow_t50_c as f32 {
                1.0
            } else {
                0.0
            };
        }
        ((self.rain_snow_t50_c as f32 + 0.5 * r - t) / r).clamp(0.0, 1.0)
    }

    /// Orographic precipitation factor at altitude `z` for precipitation given at `z_ref`.
    #[inline]
    pub fn orographic_factor(&self, z: f32, z_ref: f64) -> f32 {
        let f = 1.0 + self.orographic_gradient_per_100m * (z as f64 - z_ref) / 100.0;
        let [lo, hi] = self.orographic_factor_range;
        f.clamp(lo, hi) as f32
    }
}

/// The cloud cover `N` whose shortwave share of the clear sky is `factor` by Kasten &
/// Czeplak 1980's law `factor = 1 − 0.75 N^3.4`, clamped to [0, 1].
pub fn cloud_cover_of_factor(factor: f64) -> f64 {
    ((1.0 - factor).max(0.0) / 0.75)
        .powf(1.0 / 3.4)
        .clamp(0.0, 1.0)
}

/// Sea-level-equivalent daily mean air temperature of the climatology, °C (module docs).
pub fn climatology_sea_level_c(latitude_deg: f64, day_of_year: f64) -> f64 {
    let phi = latitude_deg.abs().min(90.0);
    let mean = 45.95 - 0.65 * phi;
    let amplitude = (11.35 - 0.05 * phi).max(0.0);
    let coldest = if latitude_deg >= 0.0 { 20.0 } else { 201.0 };
    mean - amplitude * (std::f64::consts::TAU * (day_of_year - coldest) / 365.0).cos()
}

/// The climatological winter: one weather period per calendar month of the season (its
/// temperature at mid-month, for the maps that need one; the hourly temperature follows
/// [`climatology_sea_level_c`] day by day), westerly to north-westerly winds, one snowfall
/// period a week (Cordonnier 2018 §5.1's frequency), with the rain-snow limit of the
/// paper's snowfall where the mid-month air reaches `T50`.
pub fn climatology_winter(
    params: &ClimateParams,
    latitude_deg: f64,
    start_day_of_year: u32,
    days: f64,
) -> Vec<WeatherPeriod> {
    let mut periods = Vec::new();
    let mut day = 0.0f64;
    let mut k = 0usize;
    while day < days.max(1.0) {
        let doy = (start_day_of_year as f64 - 1.0 + day).rem_euclid(365.0) + 1.0;
        let month = snowscape_environment::insolation::month_of(doy as u32);
        // Days to the end of this calendar month.
        let month_end =
            [31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334, 365][month as usize - 1] as f64;
        let length = (month_end - doy + 1.0).max(1.0);
        let mid = doy + 0.5 * length;
        let t = climatology_sea_level_c(latitude_deg, mid) + params.temperature_offset_c;
        let (dir, speed) = [(300.0, 10.0), (280.0, 12.0), (270.0, 10.0), (290.0, 8.0)][k % 4];
        periods.push(WeatherPeriod {
            from_day: day,
            sea_level_temperature_c: t,
            wind_from_deg: dir,
            wind_speed_m_s: speed,
            rain_snow_altitude_m: ((t - params.rain_snow_t50_c)
                / -params.lapse_c_per_m().min(-1e-4))
            .clamp(-1000.0, 9000.0),
            snowfall_per_week: 1.0,
            precipitation_mm_per_day: None,
        });
        day += length;
        k += 1;
    }
    periods
}

/// The weather periods of a station-forced season: one per 30 days of the record, with the
/// record's mean wind (its direction the vector mean of the recorded directions, 270° when
/// none are recorded) and sea-level temperature for the maps that need one; no Poisson
/// snowfall (the record's precipitation falls hour by hour).
pub fn station_winter(forcing: &crate::forcing::StationForcing, days: f64) -> Vec<WeatherPeriod> {
    let per_day = (24.0 / forcing.step_hours.max(1e-6)).max(1.0);
    let lapse = ClimateParams::default().lapse_c_per_m();
    let z = forcing.station_altitude_m.unwrap_or(0.0);
    let mut periods = Vec::new();
    let mut day = 0.0;
    while day < days.max(1.0) {
        let (a, b) = (
            (day * per_day) as usize,
            (((day + 30.0) * per_day) as usize).min(forcing.records.len()),
        );
        let recs = forcing.records.get(a..b.max(a)).unwrap_or(&[]);
        let n = recs.len().max(1) as f64;
        let t = recs.iter().map(|r| r.air_temperature_c as f64).sum::<f64>() / n - lapse * z;
        let speed = recs.iter().map(|r| r.wind_speed_m_s as f64).sum::<f64>() / n;
        let (mut e, mut nn) = (0.0f64, 0.0f64);
        for r in recs {
            if let Some(d) = r.wind_from_deg {
                let (s, c) = (d as f64).to_radians().sin_cos();
                e += s * r.wind_speed_m_s as f64;
                nn += c * r.wind_speed_m_s as f64;
            }
        }
        let dir = if e == 0.0 && nn == 0.0 {
            270.0
        } else {
            e.atan2(nn).to_degrees().rem_euclid(360.0)
        };
        periods.push(WeatherPeriod {
            from_day: day,
            sea_level_temperature_c: t.clamp(-79.0, 79.0),
            wind_from_deg: dir,
            wind_speed_m_s: speed.clamp(0.0, 100.0),
            rain_snow_altitude_m: 0.0,
            snowfall_per_week: 0.0,
            precipitation_mm_per_day: None,
        });
        day += 30.0;
    }
    periods
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn climatology_differs_by_latitude_and_is_plausible() {
        let p = ClimateParams::default();
        let lapse = p.lapse_c_per_m();
        // 47 °N, mid-January at 2000 m: about −7 °C; 37.6 °N at 3000 m: about −8 °C.
        let alps = climatology_sea_level_c(47.0, 20.0) + lapse * 2000.0;
        let sierra = climatology_sea_level_c(37.6, 20.0) + lapse * 3000.0;
        assert!((-10.0..-4.0).contains(&alps), "{alps}");
        assert!((-11.0..-4.0).contains(&sierra), "{sierra}");
        // April is warmer than January; the south's seasons are shifted.
        assert!(climatology_sea_level_c(47.0, 105.0) > alps - lapse * 2000.0 + 3.0);
        assert!(climatology_sea_level_c(-45.0, 20.0) > climatology_sea_level_c(45.0, 20.0));
        let w = climatology_winter(&p, 47.0, 335, 180.0);
        assert_eq!(w.len(), 6);
        assert_eq!(w[0].from_day, 0.0);
        assert_eq!(w[1].from_day, 31.0);
        assert!(w[5].sea_level_temperature_c > w[1].sea_level_temperature_c);
    }

    #[test]
    fn phase_and_orography() {
        let p = ClimateParams {
            rain_snow_phase: crate::storms::RainSnowPhase::AirTemperature,
            ..ClimateParams::default()
        };
        assert_eq!(p.snow_share(-3.0, 0.9), 1.0);
        assert_eq!(p.snow_share(3.0, 0.9), 0.0);
        assert!((p.snow_share(1.0, 0.9) - 0.5).abs() < 1e-6);
        assert!((p.orographic_factor(2500.0, 1500.0) - 1.5).abs() < 1e-6);
        assert!((p.orographic_factor(1000.0, 1500.0) - 0.75).abs() < 1e-6);
        assert_eq!(p.orographic_factor(9000.0, 0.0), 3.0);
        assert!((p.diurnal_c(15.0) - 5.0).abs() < 1e-12);
        assert!((p.diurnal_c(3.0) + 5.0).abs() < 1e-12);
        assert!(p.validate().is_ok());
        // Kasten & Czeplak's covers for the default shortwave shares.
        assert!((cloud_cover_of_factor(0.8) - 0.678).abs() < 1e-3);
        assert_eq!(cloud_cover_of_factor(0.25), 1.0);
        assert_eq!(cloud_cover_of_factor(1.0), 0.0);
        let storm = p.hour_air(true);
        assert!(storm.cloud_cover == 1.0 && storm.relative_humidity >= 0.9);
        let bad = ClimateParams {
            fair_relative_humidity: 1.5,
            ..ClimateParams::default()
        };
        assert!(
            matches!(bad.validate(), Err(ClimateError::OutOfRange { key, .. }) if key == "climate.fair_relative_humidity")
        );
        let bad = ClimateParams {
            lapse_rate_c_per_km: f64::NAN,
            ..ClimateParams::default()
        };
        assert!(
            matches!(bad.validate(), Err(ClimateError::OutOfRange { key, .. }) if key == "climate.lapse_rate_c_per_km")
        );
    }

    #[test]
    fn storm_hours_are_colder_than_fair_hours_of_the_same_day() {
        let p = ClimateParams::default();
        for h in 0..24 {
            let (fair, storm) = (p.diurnal_c(h as f64), p.storm_diurnal_c(h as f64));
            assert!(storm <= fair + 1e-12, "hour {h}: storm {storm} fair {fair}");
        }
        // The afternoon is 5 °C colder, the night's minimum the same, the day 2.5 °C colder.
        assert!((p.diurnal_c(15.0) - p.storm_diurnal_c(15.0) - 5.0).abs() < 1e-12);
        assert!((p.diurnal_c(3.0) - p.storm_diurnal_c(3.0)).abs() < 1e-12);
        let mean = |f: &dyn Fn(f64) -> f64| (0..24).map(|h| f(h as f64)).sum::<f64>() / 24.0;
        let cooler = mean(&|h| p.diurnal_c(h)) - mean(&|h| p.storm_diurnal_c(h));
        assert!((cooler - 2.5).abs() < 1e-9, "{cooler}");
    }

    #[test]
    fn a_rate_and_a_season_total_are_refused_together_naming_both() {
        let both = ClimateParams {
            precipitation_mm_per_day: Some(20.0),
            annual_precipitation_mm: Some(1500.0),
            ..ClimateParams::default()
        };
        let e = both.validate().unwrap_err().to_string();
        assert!(
            e.contains("climate.precipitation_mm_per_day")
                && e.contains("climate.annual_precipitation_mm"),
            "{e}"
        );
        let both = ClimateParams {
            annual_precipitation_mm: Some(1500.0),
            monthly_precipitation_mm: Some([100.0; 12]),
            ..ClimateParams::default()
        };
        assert!(matches!(
            both.validate(),
            Err(ClimateError::Conflict {
                first: "climate.annual_precipitation_mm",
                second: "climate.monthly_precipitation_mm",
                ..
            })
        ));
        let mut months = [100.0; 12];
        months[3] = -1.0;
        let bad = ClimateParams {
            monthly_precipitation_mm: Some(months),
            ..ClimateParams::default()
        };
        assert!(
            bad.validate()
                .unwrap_err()
                .to_string()
                .contains("climate.monthly_precipitation_mm[3] = -1")
        );
        for (rh, ok) in [(0.9, true), (1.0, true), (90.0, false), (f64::NAN, false)] {
            let p = ClimateParams {
                storm_relative_humidity: rh,
                ..ClimateParams::default()
            };
            assert_eq!(p.validate().is_ok(), ok, "{rh}");
        }
    }
}
