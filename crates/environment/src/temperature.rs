//! Temperature from altitude and sun exposure (Cordonnier et al. 2018, Section 4.1):
//!
//! `T = T0 + kt·A + ki·I`
//!
//! with `A` the altitude (m), `I = I_sun + I_sky + I_ind` the total exposure (hours of sun per
//! day), `T0` the sea-level temperature (°C), `kt` the lapse rate (°C/m, −0.01) and `ki` the
//! warming per daylight hour of sun (°C per h/day, 0.41 = 10 °C per 24 h). Nodata cells get 0.

use crate::{EnvironmentError, TemperatureParams};
use rayon::prelude::*;
use snowscape_terrain::NodataMask;

/// Temperature of one cell, °C.
#[inline(always)]
pub fn temperature_at(params: &TemperatureParams, altitude_m: f32, exposure_h: f32) -> f32 {
    (params.t0_c + params.kt * altitude_m as f64 + params.ki * exposure_h as f64) as f32
}

/// Temperature map, °C, from altitude (m) and total exposure (h/day).
pub fn temperature(
    altitude: &[f32],
    exposure: &[f32],
    mask: &NodataMask,
    params: &TemperatureParams,
) -> Result<Vec<f32>, EnvironmentError> {
    params.validate()?;
    if exposure.len() != altitude.len() {
        return Err(EnvironmentError::LengthMismatch {
            what: "exposure map",
            width: altitude.len(),
            height: 1,
            expected: altitude.len(),
            actual: exposure.len(),
        });
    }
    Ok(altitude
        .par_iter()
        .zip(exposure.par_iter())
        .enumerate()
        .map(|(i, (&a, &e))| {
            if mask.is_valid(i) {
                temperature_at(params, a, e)
            } else {
                0.0
            }
        })
        .collect())
}
