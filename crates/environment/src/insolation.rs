//! Hour-by-hour shortwave irradiance of a season, month by month (beyond Cordonnier 2018).
//!
//! The enhanced temperature-index melt (Hock 1999, J. Glaciol. 45(149); Pellicciotti et al.
//! 2005, J. Glaciol. 51(175)) needs the incoming shortwave `I_sw` of each hour at each cell,
//! not a season mean. For each calendar month the season touches, the sun is placed at the
//! centre of every solar hour of the month's 15th day; for each hour with the sun up, one
//! shadow sweep gives the direct-beam factor `b_h = s_h · max(0, n·i_h)` (shadow times
//! incidence, in [0, 1]; stored in a byte, error ≤ 0.2 %). Per cell and hour:
//!
//! `I_sw = c · (S_dir,h · b_h + D_h · V + R · S_flat,h)`
//!
//! - `S_dir,h = S0 · E · ψa^(p/p0 / sin e)`: direct normal clear-sky irradiance, W/m², with the
//!   solar constant `S0` = 1367 W/m², the orbital eccentricity factor `E` (Spencer 1971), the
//!   clear-sky transmissivity `ψa` = 0.75 and the pressure ratio `p/p0 = exp(−z/8434.5 m)` of the
//!   air mass (Hock 1999, Eq. 3);
//! - `D_h = 0.3 · (1 − ψa^(m)) · S0 · E · sin e`: clear-sky diffuse irradiance on a horizontal
//!   surface (the Liu & Jordan-type split used by Hock 1999's references and by many
//!   distributed models), times the sky view factor `V` of [`crate::sky`];
//! - `R`: the month's terrain-reflected share, the Cordonnier 2018 §4.1 bounce of that month's
//!   mean direct sun divided by a flat open cell's ([`crate::bounce`]);
//! - `c`: a cloud factor the weather sets (1 = clear sky).
//!
//! The same beam maps give the season-mean direct sun of Cordonnier's `I_sun`, so the
//! precompute sweeps each sun position once.

use crate::bounce::bounce_fields;
use crate::field::TerrainField;
use crate::solar::{SunSample, declination, hour_angle, sun_vector};
use crate::sun::direct_sun_field;
use crate::{BounceParams, DeclinationModel};
use serde::{Deserialize, Serialize};

/// Solar constant, W/m² (Iqbal 1983, "An Introduction to Solar Radiation").
pub const SOLAR_CONSTANT_W_M2: f64 = 1367.0;
/// Scale height of the pressure ratio `p/p0 = exp(−z/H)`, m (Hock 1999).
pub const PRESSURE_SCALE_HEIGHT_M: f64 = 8434.5;

/// Clear-sky radiation parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct ClearSkyParams {
    /// Clear-sky atmospheric transmissivity ψa, dimensionless in (0, 1]. Default 0.75: Hock
    /// 1999, Eq. 3 (after Oke 1987).
    pub transmissivity: f64,
    /// Share of the extinguished beam that reaches the ground as diffuse light, in [0, 1].
    /// Default 0.3: the clear-sky diffuse rule `D = 0.3 (1 − ψa^m) S0 sin e` (Liu & Jordan 1960
    /// form, as in Iqbal 1983 ch. 7).
    pub diffuse_share: f64,
}

impl Default for ClearSkyParams {
    fn default() -> Self {
        Self {
            transmissivity: 0.75,
            diffuse_share: 0.3,
        }
    }
}

impl ClearSkyParams {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<(), crate::EnvironmentError> {
        let t = self.transmissivity;
        crate::error::check_param(
            "clear_sky.transmissivity",
            t,
            t > 0.0 && t <= 1.0,
            "must be in (0, 1]",
        )?;
        let d = self.diffuse_share;
        crate::error::check_param(
            "clear_sky.diffuse_share",
            d,
            (0.0..=1.0).contains(&d),
            "must be in [0, 1]",
        )
    }
}

/// The sun of one solar hour of a month.
#[derive(Debug, Clone, PartialEq)]
pub struct HourSun {
    /// Solar hour at the centre of the hour (0.5 … 23.5).
    pub solar_hour: f32,
    /// Sine of the sun's elevation.
    pub sin_elevation: f32,
    /// Direct-beam factor `s_h · max(0, n·i_h)` per cell, quantised to 0..=255.
    pub beam: Vec<u8>,
}

/// The sun of one month of the season.
#[derive(Debug, Clone, PartialEq)]
pub struct MonthSun {
    /// Calendar month, 1..=12.
    pub month: u32,
    /// Day of year the positions are computed for (the 15th).
    pub day_of_year: u32,
    /// The hours with the sun above the horizon, in order (index = solar hour − 0.5 of
    /// [`MonthSun::hour_index`]).
    pub hours: Vec<HourSun>,
    /// Solar hour of `hours[0]` (its integer part).
    pub first_hour: u32,
    /// Terrain-reflected light per cell as a share of a flat open cell's direct light.
    pub reflected: Vec<f32>,
}

impl MonthSun {
    /// The sun of solar hour `hour` (0..24, integer part), if it is up.
    pub fn hour(&self, hour: u32) -> Option<&HourSun> {
        hour.checked_sub(self.first_hour)
            .and_then(|k| self.hours.get(k as usize))
    }
}

/// The hourly sun of every month a season touches.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SeasonSun {
    /// Latitude, degrees north.
    pub latitude_deg: f64,
    /// The months, in calendar order of the season.
    pub months: Vec<MonthSun>,
    /// Sky view factor per cell (copied from the sky sweeps).
    pub sky_view_factor: Vec<f32>,
}

/// First day of year of each calendar month (no leap day).
const MONTH_START: [u32; 12] = [1, 32, 60, 91, 121, 152, 182, 213, 244, 274, 305, 335];

/// Calendar month (1..=12) of a day of year (1..=365).
pub fn month_of(day_of_year: u32) -> u32 {
    let d = (day_of_year.clamp(1, 365)) as usize;
    MONTH_START
        .iter()
        .rposition(|&s| s as usize <= d)
        .unwrap_or(0) as u32
        + 1
}

/// Eccentricity correction factor `(r0/r)²` of the Earth's orbit (Spencer 1971).
pub fn eccentricity(day_of_year: u32) -> f64 {
    let g = std::f64::consts::TAU * (day_of_year as f64 - 1.0) / 365.0;
    1.000110
        + 0.034221 * g.cos()
        + 0.001280 * g.sin()
        + 0.000719 * (2.0 * g).cos()
        + 0.000077 * (2.0 * g).sin()
}

/// Clear-sky (direct normal, diffuse horizontal) irradiance, W/m², for a sun at
/// `sin_elevation` above a cell at `altitude_m` (module docs).
#[inline]
pub fn clear_sky(
    params: &ClearSkyParams,
    day_of_year: u32,
    sin_elevation: f64,
    altitude_m: f64,
) -> (f64, f64) {
    if sin_elevation <= 0.0 {
        return (0.0, 0.0);
    }
    let top = SOLAR_CONSTANT_W_M2 * eccentricity(day_of_year);
    let mass = (-altitude_m / PRESSURE_SCALE_HEIGHT_M).exp() / sin_elevation.max(0.02);
    let t = params.transmissivity.powf(mass);
    (
        top * t,
        params.diffuse_share * (1.0 - t) * top * sin_elevation,
    )
}

/// The calendar months covering `num_days` days from `start_day` (in season order).
pub fn season_months(start_day: u32, num_days: u32) -> Vec<u32> {
    let mut months: Vec<u32> = Vec::new();
    for j in 0..num_days.max(1) {
        let m = month_of((start_day - 1 + j) % 365 + 1);
        if months.last() != Some(&m) && !months.contains(&m) {
            months.push(m);
        }
    }
    months
}

/// The hourly sun of the months of a season on a prepared field.
pub(crate) fn season_sun_field(
    field: &TerrainField,
    latitude_deg: f64,
    months: &[u32],
    model: DeclinationModel,
    bounce: &BounceParams,
    sky_view_factor: &[f32],
) -> SeasonSun {
    // Each month's hours and daily direct sun, then the reflected share of every month in one
    // pass of the bounce.
    let mut months: Vec<(MonthSun, Vec<f32>, f64)> = months
        .iter()
        .map(|&month| {
            let day = MONTH_START[month as usize - 1] + 14;
            let dec = declination(day, model);
            let mut hours = Vec::new();
            let mut first_hour = 0;
            let mut daily = vec![0.0f32; field.len()];
            let mut flat_daily = 0.0f64;
            for h in 0..24u32 {
                let direction = sun_vector(latitude_deg, dec, hour_angle(h as f64 + 0.5));
                if direction[2] <= 0.0 {
                    continue;
                }
                if hours.is_empty() {
                    first_hour = h;
                }
                let sample = SunSample {
                    direction,
                    weight_h: 1.0,
                };
                let b = direct_sun_field(field, &[sample], 1.0);
                for (d, &v) in daily.iter_mut().zip(&b) {
                    *d += v;
                }
                flat_daily += direction[2];
                hours.push(HourSun {
                    solar_hour: h as f32 + 0.5,
                    sin_elevation: direction[2] as f32,
                    beam: b
                        .iter()
                        .map(|&v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
                        .collect(),
                });
            }
            let sun = MonthSun {
                month,
                day_of_year: day,
                hours,
                first_hour,
                reflected: vec![0.0; field.len()],
            };
            (sun, daily, flat_daily)
        })
        .collect();
    let sunny: Vec<usize> = (0..months.len()).filter(|&k| months[k].2 > 0.0).collect();
    let dailies: Vec<&[f32]> = sunny.iter().map(|&k| &months[k].1[..]).collect();
    let bounced = bounce_fields(field, &dailies, bounce);
    for (&k, reflected) in sunny.iter().zip(bounced) {
        let inv = (1.0 / months[k].2) as f32;
        months[k].0.reflected = reflected.into_iter().map(|r| r * inv).collect();
    }
    let months = months.into_iter().map(|(sun, _, _)| sun).collect();
    SeasonSun {
        latitude_deg,
        months,
        sky_view_factor: sky_view_factor.to_vec(),
    }
}

/// The hourly sun of every month of the season `params.sun` describes (its latitude,
/// `start_day` and `num_days`), with `params.bounce` for the reflected share;
/// `sky_view_factor` comes from [`crate::precompute`].
pub fn season_sun(
    surface: &[f32],
    geometry: &snowscape_terrain::GridGeometry,
    mask: &snowscape_terrain::NodataMask,
    params: &crate::EnvironmentParams,
    sky_view_factor: &[f32],
) -> Result<SeasonSun, crate::EnvironmentError> {
    params.validate()?;
    let field = TerrainField::new(surface, geometry, mask)?;
    if sky_view_factor.len() != field.len() {
        return Err(crate::EnvironmentError::LengthMismatch {
            what: "sky view factor",
            width: geometry.width(),
            height: geometry.height(),
            expected: field.len(),
            actual: sky_view_factor.len(),
        });
    }
    let months = season_months(params.sun.start_day, params.sun.num_days);
    Ok(season_sun_field(
        &field,
        params.sun.latitude_deg,
        &months,
        params.sun.declination,
        &params.bounce,
        sky_view_factor,
    ))
}

impl SeasonSun {
    /// The month holding `day_of_year`, or the nearest month of the season.
    pub fn month_for(&self, day_of_year: u32) -> Option<&MonthSun> {
        let m = month_of(day_of_year);
        self.months.iter().find(|s| s.month == m).or_else(|| {
            self.months.iter().min_by_key(|s| {
                let d = (s.month as i32 - m as i32).rem_euclid(12);
                d.min(12 - d)
            })
        })
    }

    /// Bytes held by the beam and reflection maps.
    pub fn memory_bytes(&self) -> usize {
        self.months
            .iter()
            .map(|m| m.hours.iter().map(|h| h.beam.len()).sum::<usize>() + 4 * m.reflected.len())
            .sum::<usize>()
            + 4 * self.sky_view_factor.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn months_and_days() {
        assert_eq!(month_of(1), 1);
        assert_eq!(month_of(31), 1);
        assert_eq!(month_of(32), 2);
        assert_eq!(month_of(335), 12);
        assert_eq!(month_of(365), 12);
        assert_eq!(season_months(335, 100), vec![12, 1, 2, 3]);
        assert_eq!(season_months(274, 365).len(), 12);
    }

    #[test]
    fn clear_sky_is_plausible() {
        let p = ClearSkyParams::default();
        // Sun at 60° in March at 2000 m: ~ 900-1100 W/m² direct normal, ~ 50-100 diffuse.
        let (dir, dif) = clear_sky(&p, 80, 60f64.to_radians().sin(), 2000.0);
        assert!((850.0..1120.0).contains(&dir), "{dir}");
        assert!((40.0..120.0).contains(&dif), "{dif}");
        assert_eq!(clear_sky(&p, 80, -0.1, 0.0), (0.0, 0.0));
        // Higher cells get more sun (thinner air).
        assert!(clear_sky(&p, 80, 0.5, 3000.0).0 > clear_sky(&p, 80, 0.5, 0.0).0);
        assert!((eccentricity(3) - 1.034).abs() < 0.002);
    }
}
