//! Solar geometry, one module for every crate: the declination, the hour angle and the unit
//! vector towards the sun.
//!
//! - Declination δ from the day of year `d` (1 = 1 January):
//!   - Spencer 1971 (the environment's default), the Fourier series
//!     `δ = 0.006918 − 0.399912 cos Γ + 0.070257 sin Γ − 0.006758 cos 2Γ + 0.000907 sin 2Γ
//!          − 0.002697 cos 3Γ + 0.00148 sin 3Γ`, `Γ = 2π(d − 1)/365`
//!     (J. W. Spencer, "Fourier series representation of the position of the sun", Search
//!     2(5), 1971);
//!   - Cooper 1969, `δ = 23.45° · sin(2π(284 + d)/365)` (P. I. Cooper, "The absorption of
//!     radiation in solar stills", Solar Energy 12(3), 1969);
//!   - the cosine about the June solstice, `δ = 23.45° · cos(2π(d − 173)/365.25)` (Jubert
//!     2018, Eq. I.22, after Liston & Sturm 1998; the 3D transport's blowing-snow sublimation),
//!     which takes fractional days.
//! - Hour angle from local *solar* time `t` (hours): `ω = 15°·(t − 12)` (no equation of time:
//!   a day's sun path is sampled in solar time, so it is not needed).
//! - Sun vector in local east/north/up coordinates at latitude φ:
//!   `e = −cos δ sin ω`, `n = sin δ cos φ − cos δ sin φ cos ω`, `u = sin δ sin φ + cos δ cos φ cos ω`,
//!   so the elevation is `asin(u)` (the classic `sin α = sin φ sin δ + cos φ cos δ cos ω`) and the
//!   azimuth, clockwise from north, `atan2(e, n)` (Iqbal 1983, "An Introduction to Solar
//!   Radiation", ch. 1).

use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Which declination formula to use.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum DeclinationModel {
    /// Spencer 1971 Fourier series (error < 0.0006 rad).
    #[default]
    Spencer,
    /// Cooper 1969 sine approximation (error up to ~1°).
    Cooper,
    /// The cosine about the June solstice (Jubert 2018, Eq. I.22; error up to ~1.5°).
    Cosine,
}

/// Latitude of the Tropic of Cancer, degrees (Cooper's and the cosine's amplitude).
const TROPIC_DEG: f64 = 23.45;
/// Day of the June solstice of the cosine formula (Jubert 2018, Eq. I.22).
const SOLSTICE_DAY: f64 = 173.0;
/// Mean length of a year of the cosine formula, days.
const YEAR_DAYS: f64 = 365.25;

/// Solar declination in radians on day `day_of_year` (1..=366).
pub fn declination(day_of_year: u32, model: DeclinationModel) -> f64 {
    declination_at(day_of_year as f64, model)
}

/// Solar declination in radians at day `day` of the year (fractional days allowed).
pub fn declination_at(day: f64, model: DeclinationModel) -> f64 {
    match model {
        DeclinationModel::Spencer => {
            let g = TAU * (day - 1.0) / 365.0;
            0.006918 - 0.399912 * g.cos() + 0.070257 * g.sin() - 0.006758 * (2.0 * g).cos()
                + 0.000907 * (2.0 * g).sin()
                - 0.002697 * (3.0 * g).cos()
                + 0.00148 * (3.0 * g).sin()
        }
        DeclinationModel::Cooper => TROPIC_DEG.to_radians() * (TAU * (284.0 + day) / 365.0).sin(),
        DeclinationModel::Cosine => {
            TROPIC_DEG.to_radians() * (TAU * (day - SOLSTICE_DAY) / YEAR_DAYS).cos()
        }
    }
}

/// Hour angle in radians at local solar time `solar_hour` (0..24; noon = 0, morning < 0).
pub fn hour_angle(solar_hour: f64) -> f64 {
    (15.0 * (solar_hour - 12.0)).to_radians()
}

/// Unit vector towards the sun, `[east, north, up]`, at `latitude_deg` for declination
/// `declination` and hour angle `hour_angle` (radians).
pub fn sun_vector(latitude_deg: f64, declination: f64, hour_angle: f64) -> [f64; 3] {
    let (sp, cp) = latitude_deg.to_radians().sin_cos();
    let (sd, cd) = declination.sin_cos();
    let (sw, cw) = hour_angle.sin_cos();
    [-cd * sw, sd * cp - cd * sp * cw, sd * sp + cd * cp * cw]
}

/// Sine of the sun's elevation, `sin φ sin δ + cos φ cos δ cos ω`, at `latitude_deg` for
/// declination `declination` and hour angle `hour_angle` (radians).
pub fn sin_elevation(latitude_deg: f64, declination: f64, hour_angle: f64) -> f64 {
    let phi = latitude_deg.to_radians();
    declination.sin() * phi.sin() + declination.cos() * phi.cos() * hour_angle.cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_three_declinations_agree_within_one_and_a_half_degrees_and_peak_at_the_solstice() {
        for d in 1..=365u32 {
            let s = declination(d, DeclinationModel::Spencer);
            for m in [DeclinationModel::Cooper, DeclinationModel::Cosine] {
                let diff = (declination(d, m) - s).abs().to_degrees();
                assert!(diff < 1.5, "day {d} {m:?}: {diff}°");
            }
        }
        let june = declination_at(SOLSTICE_DAY, DeclinationModel::Cosine).to_degrees();
        assert!((june - TROPIC_DEG).abs() < 1e-12, "{june}");
        // The elevation's sine is the sun vector's up component.
        let (lat, dec, w) = (46.5, 0.3, 0.7);
        assert!((sin_elevation(lat, dec, w) - sun_vector(lat, dec, w)[2]).abs() < 1e-15);
    }
}
