//! Snowfall (Cordonnier et al. 2018, Section 5.1).
//!
//! Depth added per precipitation step (Foehn rule):
//! `ΔD = δt_p · k_snow · max(0, A − A0_precip)`, with `A = B + D` the snow-surface altitude.
//!
//! The new snow is split between layers:
//! - powder share `x_P = k_powdery (‖∇A‖ − s_c)`, clamped to [0, 1], with the critical slope
//!   rising as the ground gets colder: `s_c = s_c0 + k_sc · max(0, T0_powdery − T)`;
//! - of the rest, the unstable share `x_U = k_unstable (s − s_U)`, clamped to [0, 1], where `s`
//!   is the slope angle; the remainder is stable snow.
//!
//! The paper leaves `k_powdery`, `s_c0`, `k_sc`, `k_unstable` and `s_U` to the user; the
//! defaults below are ours, chosen so that snow bonds on slopes up to ~35° at −10 °C
//! (steeper faces hold mostly powder that later diffuses and blows away), and that new snow
//! on slopes between 25° and 45° is increasingly unstable — the slopes where slab avalanches
//! start in practice. The tests check the behaviour these values produce.

use crate::phenomenon::{
    PhenomenonError, Validity, check_at_least, check_dt, check_finite, check_map, fill_surface,
    row_gradient_norm, with_validity,
};
use crate::{VolumeChange, ordered_sum};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use snowscape_terrain::LayeredTerrain;

/// Parameters of snowfall.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SnowfallParams {
    /// Snowfall rate per metre of altitude above `a0_precip`, m of snow per day per m
    /// (1/day). Cordonnier 2018 Table 2: k_snow = 1e-4.
    pub k_snow: f64,
    /// Rain-snow limit: altitude below which precipitation falls as rain, m. User-set in the
    /// paper (Table 2, A0precip); our default puts it at a typical mid-winter 800 m.
    pub a0_precip: f64,
    /// Powder share per unit of surface gradient above the critical slope (dimensionless).
    /// Chosen here: 1.0 (all powder once the gradient exceeds s_c by 1, i.e. ~35° → ~60°).
    pub k_powdery: f64,
    /// Critical gradient ‖∇A‖ above which new snow stays powder, at or above T0_powdery
    /// (dimensionless, tan of the slope). Chosen here: 0.7 (35°).
    pub sc0: f64,
    /// Rise of the critical gradient per °C below T0_powdery, 1/°C. Chosen here: 0.02.
    pub k_sc_powdery: f64,
    /// Temperature below which the critical slope rises, °C. Cordonnier 2018 Table 2: −10.
    pub t0_powdery: f64,
    /// Unstable share per degree of slope above `s_u`, 1/degree. Chosen here: 1/20.
    pub k_unstable: f64,
    /// Slope below which new snow is stable, degrees. Chosen here: 25.
    pub s_u_deg: f64,
}

impl Default for SnowfallParams {
    fn default() -> Self {
        Self {
            k_snow: 1e-4,
            a0_precip: 800.0,
            k_powdery: 1.0,
            sc0: 0.7,
            k_sc_powdery: 0.02,
            t0_powdery: -10.0,
            k_unstable: 1.0 / 20.0,
            s_u_deg: 25.0,
        }
    }
}

impl SnowfallParams {
    /// Checks the parameters are finite and the rates non-negative.
    pub fn validate(&self) -> Result<(), PhenomenonError> {
        check_at_least("snowfall", "k_snow", self.k_snow, 0.0)?;
        check_finite("snowfall", "a0_precip", self.a0_precip)?;
        check_at_least("snowfall", "k_powdery", self.k_powdery, 0.0)?;
        check_finite("snowfall", "sc0", self.sc0)?;
        check_at_least("snowfall", "k_sc_powdery", self.k_sc_powdery, 0.0)?;
        check_finite("snowfall", "t0_powdery", self.t0_powdery)?;
        check_at_least("snowfall", "k_unstable", self.k_unstable, 0.0)?;
        check_finite("snowfall", "s_u_deg", self.s_u_deg)
    }
}

/// Reusable buffers of the snowfall step.
#[derive(Debug, Clone, Default)]
pub struct SnowfallScratch {
    surface: Vec<f32>,
}

/// How new snow at one cell is shared between layers: (powder, unstable, stable), summing to 1.
pub fn layer_shares(
    params: &SnowfallParams,
    gradient_norm: f64,
    temperature: f64,
) -> (f64, f64, f64) {
    let (p, u, s) = ShareCoefficients::new(params).shares(gradient_norm as f32, temperature as f32);
    (p as f64, u as f64, s as f64)
}

/// The parameters of [`layer_shares`] in the f32 form the per-cell loop uses.
#[derive(Debug, Clone, Copy)]
struct ShareCoefficients {
    sc0: f32,
    k_sc: f32,
    t0_powdery: f32,
    k_powdery: f32,
    k_unstable: f32,
    s_u_deg: f32,
}

impl ShareCoefficients {
    fn new(p: &SnowfallParams) -> Self {
        Self {
            sc0: p.sc0 as f32,
            k_sc: p.k_sc_powdery as f32,
            t0_powdery: p.t0_powdery as f32,
            k_powdery: p.k_powdery as f32,
            k_unstable: p.k_unstable as f32,
            s_u_deg: p.s_u_deg as f32,
        }
    }

    #[inline(always)]
    fn shares(&self, gradient_norm: f32, temperature: f32) -> (f32, f32, f32) {
        let sc = self.sc0 + self.k_sc * (self.t0_powdery - temperature).max(0.0);
        let x_p = (self.k_powdery * (gradient_norm - sc)).clamp(0.0, 1.0);
        let slope_deg = gradient_norm.atan().to_degrees();
        let x_u = (self.k_unstable * (slope_deg - self.s_u_deg)).clamp(0.0, 1.0);
        let rest = 1.0 - x_p;
        (x_p, rest * x_u, rest * (1.0 - x_u))
    }
}

/// Adds `dt_days` of snowfall. `temperature` is the per-cell air temperature, °C.
pub fn step(
    params: &SnowfallParams,
    terrain: &mut LayeredTerrain,
    temperature: &[f32],
    scratch: &mut SnowfallScratch,
    dt_days: f64,
) -> Result<VolumeChange, PhenomenonError> {
    params.validate()?;
    check_dt(dt_days)?;
    let geometry = terrain.geometry().clone();
    check_map("temperature", temperature, &geometry)?;
    let mask = terrain.mask().clone();
    let w = geometry.width();
    fill_surface(terrain, &mut scratch.surface);
    let surf = &scratch.surface;
    let rate = (dt_days * params.k_snow) as f32;
    let a0 = params.a0_precip as f32;
    let k = ShareCoefficients::new(params);
    let [_, stable, unstable, powder] = &mut terrain.snow;
    let row_added: Vec<f64> = with_validity!(mask, |valid| {
        stable
            .par_chunks_mut(w)
            .zip(unstable.par_chunks_mut(w))
            .zip(powder.par_chunks_mut(w))
            .enumerate()
            .map_init(
                || vec![0.0f32; w],
                |gradient, (row, ((st, un), pw))| {
                    row_gradient_norm(surf, &geometry, &mask, valid, row, gradient);
                    let mut added = 0.0f64;
                    for col in 0..w {
                        let i = row * w + col;
                        let depth = rate * (surf[i] - a0).max(0.0);
                        if depth <= 0.0 || !valid.at(i) {
                            continue;
                        }
                        let (xp, xu, _) = k.shares(gradient[col], temperature[i]);
                        let (dp, du) = (depth * xp, depth * xu);
                        // The stable share takes the remainder (never below 0 after rounding).
                        let ds = (depth - dp - du).max(0.0);
                        pw[col] += dp;
                        un[col] += du;
                        st[col] += ds;
                        added += dp as f64 + du as f64 + ds as f64;
                    }
                    added
                },
            )
            .collect()
    });
    Ok(VolumeChange {
        added: ordered_sum(&row_added) * geometry.cell_area(),
        removed: 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_terrain::{Grid, GridGeometry, SnowLayer};

    fn plane(alt: f32) -> LayeredTerrain {
        LayeredTerrain::from_bedrock(Grid::filled(GridGeometry::square(8, 8, 10.0).unwrap(), alt))
    }

    #[test]
    fn flat_plane_gets_uniform_stable_snow_above_the_rain_limit() {
        let p = SnowfallParams::default();
        let mut t = plane(1800.0);
        let temp = vec![-8.0f32; 64];
        let v = step(&p, &mut t, &temp, &mut SnowfallScratch::default(), 1.0).unwrap();
        let expect = 1e-4 * 1000.0;
        for i in 0..64 {
            assert!((t.layer(SnowLayer::Stable)[i] as f64 - expect).abs() < 1e-6);
            assert_eq!(t.layer(SnowLayer::Powder)[i], 0.0);
            assert_eq!(t.layer(SnowLayer::Unstable)[i], 0.0);
        }
        assert!(
            (v.added - expect * 6400.0).abs() < 1e-6 * expect * 6400.0,
            "{}",
            v.added
        );
    }

    #[test]
    fn no_snow_below_the_rain_limit() {
        let mut t = plane(500.0);
        let v = step(
            &SnowfallParams::default(),
            &mut t,
            &[0.0; 64],
            &mut SnowfallScratch::default(),
            1.0,
        )
        .unwrap();
        assert_eq!(v.added, 0.0);
        assert_eq!(t.total_depth().iter().sum::<f32>(), 0.0);
    }

    #[test]
    fn steep_slopes_get_powder_and_unstable_snow() {
        let p = SnowfallParams::default();
        let (xp_flat, xu_flat, _) = layer_shares(&p, 0.0, -5.0);
        assert_eq!((xp_flat, xu_flat), (0.0, 0.0));
        let (_, xu_40, _) = layer_shares(&p, 40f64.to_radians().tan(), -5.0);
        assert!(xu_40 > 0.5, "{xu_40}");
        let (xp_60, _, _) = layer_shares(&p, 60f64.to_radians().tan(), -5.0);
        assert!(xp_60 > 0.9, "{xp_60}");
        // Colder ground holds snow on steeper slopes.
        let (xp_cold, _, _) = layer_shares(&p, 45f64.to_radians().tan(), -30.0);
        let (xp_mild, _, _) = layer_shares(&p, 45f64.to_radians().tan(), -5.0);
        assert!(xp_cold < xp_mild);
        let (a, b, c) = layer_shares(&p, 0.9, -12.0);
        assert!((a + b + c - 1.0).abs() < 1e-6);
    }
}
