//! Wind (Cordonnier et al. 2018, Section 4.2): the horizontal wind field ([`vectors`]) and the
//! wind-effect surface with its binary wind shadows ([`effect_surface`]); and, beyond the
//! paper, Winstral et al. 2002's maximum upwind slope `Sx` ([`sheltering`]), a sheltering
//! index defined over a search distance in metres, so it means the same at any cell size.
//!
//! Transport wind of the wind-effect surface: the paper advects `Wz` along Eq. 2's `W`. Its
//! contour-following part turns the wind in opposite directions on facing slopes, so cells
//! become each other's upwind neighbours; with the attach/detach switch the paper's red-black
//! iteration then has no fixed point (we observed a period-6 limit cycle on rough terrain).
//! We advect `Wz` along the dominant direction `Ŵd` at the local along-wind speed
//! `max(0, W·Ŵd)` (Eq. 2 keeps `W·Ŵd >= 0`; Venturi and the `1 − |n_xy|` slow-down are kept,
//! the cross-wind deflection is not): the upwind graph is then acyclic, one ordered sweep
//! solves it and red-black converges.
//!
//! Outputs, per cell: the wind vector `W` of paper Eq. 2 (u east, v north, m/s; it is the wind
//! at the wind-effect surface, not zeroed in shadows), the wind-effect surface `Wz` (m), and
//! the wind shadow (1 where `Wz > A + shadow_epsilon_m`: no wind at the ground, leeward of
//! ridges; 0 elsewhere). Consumers that need the wind at the ground multiply by `1 − shadow`.
//! Nodata cells get 0 everywhere.

pub mod effect_surface;
pub mod sheltering;
pub mod vectors;

use crate::field::TerrainField;
use crate::{EnvironmentError, WindParams};
pub use effect_surface::WindSolveStats;
use effect_surface::{SolveSettings, build_cells, solve};
use rayon::prelude::*;
pub use sheltering::{
    LongRangePlan, ShelteringParams, long_range_upwind_slope, max_upwind_slope, sheltering_index,
};
use snowscape_terrain::{GridGeometry, NodataMask};
use vectors::{dominant_wind, redirect, venturi};

/// The wind maps.
#[derive(Debug, Clone, PartialEq)]
pub struct WindMaps {
    /// East component of the wind, m/s.
    pub u: Vec<f32>,
    /// North component of the wind, m/s.
    pub v: Vec<f32>,
    /// Wind shadow, 1 or 0.
    pub shadow: Vec<f32>,
    /// Wind-effect surface altitude `Wz`, m.
    pub effect_surface: Vec<f32>,
    /// Vertical speed of the wind-effect surface `Wsz`, m/s.
    pub vertical_speed: Vec<f32>,
    /// Gauss-Seidel statistics.
    pub stats: WindSolveStats,
}

/// The wind maps of `surface` for `params`.
pub fn wind(
    surface: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    params: &WindParams,
) -> Result<WindMaps, EnvironmentError> {
    params.validate()?;
    let field = TerrainField::new(surface, geometry, mask)?;
    Ok(wind_field(&field, params))
}

/// The wind on a prepared field.
pub(crate) fn wind_field(field: &TerrainField, params: &WindParams) -> WindMaps {
    let layout = &field.rows;
    let wd = dominant_wind(params);
    let wd32 = [wd[0] as f32, wd[1] as f32];
    let (kv, kt) = (params.k_venturi as f32, params.k_terrain as f32);
    let base = params.venturi_base_m.map_or_else(
        || {
            layout
                .z
                .iter()
                .copied()
                .filter(|z| z.is_finite())
                .fold(f32::INFINITY, f32::min)
        },
        |b| b as f32,
    );
    let base = if base.is_finite() { base } else { 0.0 };
    let wind: Vec<[f32; 2]> = layout
        .z
        .par_iter()
        .zip(layout.normal.par_iter())
        .map(|(&a, &n)| {
            if a == f32::NEG_INFINITY {
                [0.0, 0.0]
            } else {
                redirect(venturi(wd32, a - base, kv), n, kt)
            }
        })
        .collect();
    let speed = (wd[0] * wd[0] + wd[1] * wd[1]).sqrt();
    let dir = if speed > 0.0 {
        [(wd[0] / speed) as f32, (wd[1] / speed) as f32]
    } else {
        [0.0, 0.0]
    };
    let transport: Vec<[f32; 2]> = wind
        .par_iter()
        .map(|w| {
            let along = (w[0] * dir[0] + w[1] * dir[1]).max(0.0);
            [along * dir[0], along * dir[1]]
        })
        .collect();
    let cells = build_cells(
        &layout.z,
        &layout.grad,
        &transport,
        field.width,
        field.height,
        field.csx as f32,
        field.csy as f32,
    );
    let settings = SolveSettings {
        c: params.c_m_s2 as f32,
        ordered_sweeps: params.ordered_sweeps,
        max_iterations: params.max_iterations,
        tolerance_m: params.tolerance_m as f32,
        dominant: wd32,
    };
    let solved = solve(&cells, field.width, field.height, &settings);
    let eps = params.shadow_epsilon_m as f32;
    let shadow = solved
        .wz
        .par_iter()
        .zip(layout.z.par_iter())
        .map(|(&wz, &a)| {
            if a != f32::NEG_INFINITY && wz > a + eps {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    WindMaps {
        u: wind.iter().map(|w| w[0]).collect(),
        v: wind.iter().map(|w| w[1]).collect(),
        shadow,
        effect_surface: solved.wz,
        vertical_speed: solved.wsz,
        stats: solved.stats,
    }
}
