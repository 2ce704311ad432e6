//! The whole environment precompute of Cordonnier et al. 2018, Section 4, in one call:
//! direct sun, sky, one bounce, total exposure `I = I_sun + I_sky + I_ind`, temperature
//! `T = T0 + kt·A + ki·I`, and wind (vectors, wind-effect surface, shadows), with the time
//! each stage took.

use crate::bounce::bounce_field;
use crate::field::TerrainField;
use crate::sky::sky_field;
use crate::sun::{direct_sun_field, schedule};
use crate::temperature::temperature_at;
use crate::wind::{WindSolveStats, wind_field};
use crate::{EnvironmentError, EnvironmentParams};
use snowscape_terrain::{GridGeometry, LayeredTerrain, NodataMask};
use std::time::{Duration, Instant};

/// Stable names of the maps in [`LayeredTerrain::maps`].
pub mod map_names {
    /// Direct sun exposure, h/day.
    pub const SUN: &str = "sun";
    /// Sky exposure, h/day.
    pub const SKY: &str = "sky";
    /// Indirect (bounced) exposure, h/day.
    pub const BOUNCE: &str = "bounce";
    /// Total exposure `I = sun + sky + bounce`, h/day.
    pub const IRRADIANCE: &str = "irradiance";
    /// Sky view factor (SAGA definition), dimensionless.
    pub const SKY_VIEW_FACTOR: &str = "sky_view_factor";
    /// Temperature, °C.
    pub const TEMPERATURE: &str = "temperature";
    /// Wind east component, m/s.
    pub const WIND_U: &str = "wind_u";
    /// Wind north component, m/s.
    pub const WIND_V: &str = "wind_v";
    /// Wind shadow, 0 or 1.
    pub const WIND_SHADOW: &str = "wind_shadow";
    /// Wind-effect surface altitude, m.
    pub const WIND_EFFECT_SURFACE: &str = "wind_effect_surface";
}

/// Wall-clock time of each stage of [`precompute`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StageTimings {
    /// Validation, gradients, normals, transposed copies.
    pub prepare: Duration,
    /// Direct sun with shadows.
    pub sun: Duration,
    /// Horizon sweeps for sky exposure and sky view factor.
    pub sky: Duration,
    /// Indirect bounce.
    pub bounce: Duration,
    /// Total exposure and temperature.
    pub temperature: Duration,
    /// Wind vectors and wind-effect surface.
    pub wind: Duration,
    /// Everything.
    pub total: Duration,
}

/// Every map of the precompute, row-major over the input grid (0 on nodata cells).
#[derive(Debug, Clone, PartialEq)]
pub struct EnvironmentMaps {
    /// Direct sun exposure `I_sun`, sun-hours per day.
    pub sun: Vec<f32>,
    /// Sky exposure `I_sky`, h/day.
    pub sky: Vec<f32>,
    /// Sky view factor (Häntzschel 2005 / SAGA), dimensionless.
    pub sky_view_factor: Vec<f32>,
    /// Indirect exposure `I_ind`, h/day.
    pub bounce: Vec<f32>,
    /// Total exposure `I = I_sun + I_sky + I_ind`, h/day.
    pub irradiance: Vec<f32>,
    /// Temperature, °C.
    pub temperature: Vec<f32>,
    /// Wind east component, m/s.
    pub wind_u: Vec<f32>,
    /// Wind north component, m/s.
    pub wind_v: Vec<f32>,
    /// Wind shadow, 0 or 1.
    pub wind_shadow: Vec<f32>,
    /// Wind-effect surface `Wz`, m.
    pub wind_effect_surface: Vec<f32>,
    /// Gauss-Seidel statistics of the wind-effect surface.
    pub wind_stats: WindSolveStats,
    /// Time per stage.
    pub timings: StageTimings,
}

/// Runs the whole precompute on `surface` (bedrock + snow, m) over `geometry`, skipping the
/// cells `mask` marks as nodata.
pub fn precompute(
    surface: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    params: &EnvironmentParams,
) -> Result<EnvironmentMaps, EnvironmentError> {
    let start = Instant::now();
    params.validate()?;
    let samples = schedule(&params.sun)?;
    let field = TerrainField::new(surface, geometry, mask)?;
    let mut timings = StageTimings {
        prepare: start.elapsed(),
        ..StageTimings::default()
    };

    let t = Instant::now();
    let sun = direct_sun_field(&field, &samples, params.sun.k_sun);
    timings.sun = t.elapsed();

    let t = Instant::now();
    let sky = sky_field(&field, &params.sky);
    timings.sky = t.elapsed();

    let t = Instant::now();
    let bounce = bounce_field(&field, &sun, &params.bounce);
    timings.bounce = t.elapsed();

    let t = Instant::now();
    let irradiance: Vec<f32> = (0..field.len())
        .map(|i| sun[i] + sky.sky[i] + bounce[i])
        .collect();
    let temperature: Vec<f32> = (0..field.len())
        .map(|i| {
            if mask.is_valid(i) {
                temperature_at(&params.temperature, surface[i], irradiance[i])
            } else {
                0.0
            }
        })
        .collect();
    timings.temperature = t.elapsed();

    let t = Instant::now();
    let wind = wind_field(&field, &params.wind);
    timings.wind = t.elapsed();
    timings.total = start.elapsed();

    Ok(EnvironmentMaps {
        sun,
        sky: sky.sky,
        sky_view_factor: sky.sky_view_factor,
        bounce,
        irradiance,
        temperature,
        wind_u: wind.u,
        wind_v: wind.v,
        wind_shadow: wind.shadow,
        wind_effect_surface: wind.effect_surface,
        wind_stats: wind.stats,
        timings,
    })
}

impl EnvironmentMaps {
    /// The maps with their stable names ([`map_names`]), in a fixed order.
    pub fn named(&self) -> [(&'static str, &[f32]); 10] {
        [
            (map_names::SUN, &self.sun),
            (map_names::SKY, &self.sky),
            (map_names::BOUNCE, &self.bounce),
            (map_names::IRRADIANCE, &self.irradiance),
            (map_names::SKY_VIEW_FACTOR, &self.sky_view_factor),
            (map_names::TEMPERATURE, &self.temperature),
            (map_names::WIND_U, &self.wind_u),
            (map_names::WIND_V, &self.wind_v),
            (map_names::WIND_SHADOW, &self.wind_shadow),
            (map_names::WIND_EFFECT_SURFACE, &self.wind_effect_surface),
        ]
    }

    /// Stores every map into `terrain.maps` under its stable name.
    pub fn store(&self, terrain: &mut LayeredTerrain) -> Result<(), EnvironmentError> {
        for (name, values) in self.named() {
            terrain.set_map(name, values.to_vec())?;
        }
        Ok(())
    }
}
