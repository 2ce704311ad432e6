//! # snowscape-environment: the environment precompute
//!
//! Cordonnier et al. 2018, "Interactive generation of time-evolving, snow-covered landscapes
//! with avalanches", Section 4: the conditions that depend on the terrain's shape and are
//! computed once per terrain and scenario.
//!
//! | module | what | equation |
//! |---|---|---|
//! | [`solar`] | sun positions over a day range | Spencer 1971 / Cooper 1969 declination |
//! | [`sun`] | direct sun with topographic shadows | `I_sun = k_sun Σ_h s_h max(0, n·i_h)` (4.1) |
//! | [`sky`] | horizon angles, sky exposure, sky view factor | `I_sky = k_sky π/N Σ cos² φ_i` (4.1) |
//! | [`bounce`] | one indirect bounce | `I_ind = k_ind/π Σ A_ij I_sun cos φs cos φr / d²` (4.1) |
//! | [`temperature`](mod@temperature) | temperature | `T = T0 + kt·A + ki·I` (4.1) |
//! | [`wind`](mod@wind) | wind vectors, wind-effect surface, shadows | Venturi, Eq. 2, `W·∇Wz = Wsz` (4.2) |
//! | [`insolation`] | hour-by-hour sun of each month, clear-sky irradiance | Hock 1999 Eq. 3 |
//! | [`wind::sheltering`] | maximum upwind slope `Sx`, short and long range | Winstral et al. 2002, 2013 |
//! | [`precompute`](mod@precompute) | all of the above in one call | |
//!
//! Shadows and horizons come from directional sweeps (the internal `sweep` module):
//! O(cells) per sun position or horizon direction, parallel over lines, deterministic for any
//! thread count. Nodata cells are transparent (lowest possible terrain, they never occlude),
//! border for the wind, and get 0 in every output map.
//!
//! ```
//! use snowscape_environment::{precompute, EnvironmentParams};
//! use snowscape_terrain::{GridGeometry, NodataMask};
//!
//! let geometry = GridGeometry::square(64, 64, 10.0).unwrap();
//! let surface: Vec<f32> = (0..64 * 64).map(|i| ((i % 64) as f32 * 0.2).sin() * 50.0 + 1000.0).collect();
//! let maps = precompute(&surface, &geometry, &NodataMask::all_valid(), &EnvironmentParams::default()).unwrap();
//! assert_eq!(maps.temperature.len(), 64 * 64);
//! ```

pub mod bounce;
pub mod error;
mod field;
pub mod insolation;
pub mod params;
pub mod precompute;
pub mod sky;
pub mod solar;
pub mod sun;
mod sweep;
pub mod temperature;
pub mod wind;

pub use bounce::indirect_bounce;
pub use error::EnvironmentError;
pub use insolation::{ClearSkyParams, HourSun, MonthSun, SeasonSun, season_sun};
pub use params::{
    BounceParams, EnvironmentParams, SkyParams, SunParams, TemperatureParams, WindParams,
};
pub use precompute::{EnvironmentMaps, StageTimings, map_names, precompute};
pub use sky::{SkyMaps, horizon_angles, sky_exposure};
pub use solar::{DeclinationModel, SunSample};
pub use sun::{direct_sun, direct_sun_for};
pub use temperature::temperature;
pub use wind::{
    LongRangePlan, ShelteringParams, WindMaps, WindSolveStats, long_range_upwind_slope,
    max_upwind_slope, sheltering_index, wind,
};

/// Stores every map of `maps` into `terrain.maps` under its stable name ([`map_names`]).
pub fn store_maps(
    maps: &EnvironmentMaps,
    terrain: &mut snowscape_terrain::LayeredTerrain,
) -> Result<(), EnvironmentError> {
    maps.store(terrain)
}
