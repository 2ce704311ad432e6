//! Ambient (sky) light from horizon angles (Cordonnier et al. 2018, Section 4.1), and the sky
//! view factor as SAGA GIS defines it.
//!
//! For `N` directions `θ_i = 2πi/N` (clockwise from north) the horizon of every cell is found
//! by one sweep per direction (`sweep::horizon_pass`, O(N·cells) in all; the horizon tangent
//! of a cell is the linear blend of those of the two straight rays bracketing it, exact on
//! planes). Let `e_i` be
//! the elevation angle of the horizon above the horizontal, and `γ_i = atan(∇A·d_i)` the
//! elevation of the terrain's tangent plane along `d_i`.
//!
//! - **Sky exposure** (the paper): `φ_i` is the angle between the tangent to the terrain and
//!   the line to the highest visible point, `φ_i = clamp(e_i − γ_i, 0, π/2)`, and
//!   `I_sky = k_sky · π/N · Σ_i cos² φ_i`, the discrete form of
//!   `dI_sky,i = k_sky ∫_{φ_i}^{π/2} cos x sin x dx dθ = k_sky cos²φ_i / 2 dθ`.
//!   An open flat cell gets `k_sky·π`. Units: those of `k_sky` (hours per day).
//! - **Sky view factor** (Häntzschel, Goldberg & Bernhofer 2005, "GIS-based regionalisation of
//!   radiation, temperature and coupling measures in complex terrain for low mountain ranges",
//!   Meteorol. Appl. 12; the formula of SAGA's `ta_lighting` "Sky View Factor" tool), with
//!   `φ_i = max(0, e_i)` measured from the horizontal, slope `β` and aspect `α`:
//!   `SVF = 1/N Σ_i [cos β cos² φ_i + sin β cos(θ_i − α)(π/2 − φ_i − sin φ_i cos φ_i)]`.
//!   A flat open cell has SVF = 1; a cell under horizon `φ` all round has `cos² φ`.
//!
//! A direction with no valid cell ahead (the grid edge, or only nodata) is open: `e_i = −π/2`
//! for the paper's term (no obstruction above the tangent plane) and `φ_i = 0` for the SVF,
//! as in SAGA. Nodata cells are transparent and get 0 in both maps.

use crate::field::{TerrainField, transpose};
use crate::sweep::{LineFrame, horizon_pass};
use crate::{EnvironmentError, SkyParams};
use rayon::prelude::*;
use snowscape_terrain::{GridGeometry, NodataMask};

/// The sky maps.
#[derive(Debug, Clone, PartialEq)]
pub struct SkyMaps {
    /// Ambient exposure `I_sky`, units of `k_sky` (hours per day).
    pub sky: Vec<f32>,
    /// Sky view factor (Häntzschel 2005 / SAGA), dimensionless, 1 for an open flat cell.
    pub sky_view_factor: Vec<f32>,
}

/// Unit horizontal vector `[east, north]` of azimuth `azimuth_rad` (clockwise from north).
fn azimuth_vector(azimuth_rad: f64) -> [f64; 2] {
    [azimuth_rad.sin(), azimuth_rad.cos()]
}

/// Horizon elevation angle (radians above the horizontal) of every cell looking towards
/// `azimuth_deg` (clockwise from north); `-π/2` where no valid cell lies ahead, 0 on nodata.
pub fn horizon_angles(
    surface: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    azimuth_deg: f64,
) -> Result<Vec<f32>, EnvironmentError> {
    let field = TerrainField::new(surface, geometry, mask)?;
    let [de, dn] = azimuth_vector(azimuth_deg.to_radians());
    let frame = LineFrame::new(&field, de, dn);
    let layout = field.layout(frame.transposed);
    let mut sheared = Vec::new();
    horizon_pass(&frame, layout, &mut sheared);
    let mut out = vec![0.0f32; field.len()];
    frame.unshear(&sheared, &mut out, 0.0);
    for (o, &z) in out.iter_mut().zip(&layout.z) {
        *o = if z == f32::NEG_INFINITY {
            0.0
        } else {
            o.atan()
        };
    }
    Ok(if frame.transposed {
        transpose(&out, field.height, field.width)
    } else {
        out
    })
}

/// The paper's `cos² φ` for horizon tangent `tau` and tangent-plane rise `g = tan γ`:
/// `cos²(e − γ) = (1 + τg)² / ((1 + τ²)(1 + g²))` when `e > γ`, 1 when the horizon is below
/// the tangent plane, 0 when `e − γ` exceeds π/2.
#[inline(always)]
pub(crate) fn paper_cos2(tau: f32, g: f32) -> f32 {
    if tau <= g {
        return 1.0;
    }
    let c = 1.0 + tau * g;
    if c <= 0.0 {
        0.0
    } else {
        c * c / ((1.0 + tau * tau) * (1.0 + g * g))
    }
}

/// `atan(t)` for `t >= 0` (including `+inf`), within 2e-5 rad: a minimax polynomial on
/// [0, 1] and `atan t = π/2 − atan(1/t)` above.
#[inline(always)]
pub(crate) fn atan_nonneg(t: f32) -> f32 {
    let (x, flip) = if t > 1.0 { (1.0 / t, true) } else { (t, false) };
    let x2 = x * x;
    let p = x
        * (0.999_866
            + x2 * (-0.330_299_5 + x2 * (0.180_141 + x2 * (-0.085_133 + x2 * 0.020_835_1))));
    if flip {
        std::f32::consts::FRAC_PI_2 - p
    } else {
        p
    }
}

/// The SVF term of one direction (Häntzschel 2005): `tau` horizon tangent, `grad` the height
/// gradient, `d` the unit direction.
#[inline(always)]
pub(crate) fn svf_term(tau: f32, grad: [f32; 2], d: [f32; 2]) -> f32 {
    let t = tau.max(0.0);
    let phi = atan_nonneg(t);
    let inv = 1.0 / (1.0 + t * t);
    let cos_slope = 1.0 / (1.0 + grad[0] * grad[0] + grad[1] * grad[1]).sqrt();
    // sin β cos(θ − α) with α the downslope azimuth: −(∇A·d) cos β.
    let tilt = -(grad[0] * d[0] + grad[1] * d[1]) * cos_slope;
    cos_slope * inv + tilt * (std::f32::consts::FRAC_PI_2 - phi - t * inv)
}

/// Sky exposure and sky view factor with `params.directions` directions.
pub fn sky_exposure(
    surface: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    params: &SkyParams,
) -> Result<SkyMaps, EnvironmentError> {
    params.validate()?;
    let field = TerrainField::new(surface, geometry, mask)?;
    Ok(sky_field(&field, params))
}

/// `acc += [paper cos² φ, SVF term]` for one direction over a layout, in parallel.
fn accumulate(acc: &mut [[f32; 2]], tau: &[f32], z: &[f32], grad: &[[f32; 2]], d: [f32; 2]) {
    acc.par_chunks_mut(4096)
        .zip(tau.par_chunks(4096))
        .zip(z.par_chunks(4096).zip(grad.par_chunks(4096)))
        .for_each(|((a, t), (z, g))| {
            for (((a, &tau), &z), &grad) in a.iter_mut().zip(t).zip(z).zip(g) {
                if z == f32::NEG_INFINITY {
                    continue;
                }
                let rise = grad[0] * d[0] + grad[1] * d[1];
                a[0] += paper_cos2(tau, rise);
                a[1] += svf_term(tau, grad, d);
            }
        });
}

/// The sweeps on a prepared field.
pub(crate) fn sky_field(field: &TerrainField, params: &SkyParams) -> SkyMaps {
    let n = params.directions;
    let mut acc_rows = vec![[0.0f32; 2]; field.len()];
    let mut acc_cols = vec![[0.0f32; 2]; field.len()];
    let mut tau = vec![0.0f32; field.len()];
    let mut sheared = Vec::new();
    for i in 0..n {
        let [de, dn] = azimuth_vector(std::f64::consts::TAU * i as f64 / n as f64);
        let frame = LineFrame::new(field, de, dn);
        let layout = field.layout(frame.transposed);
        horizon_pass(&frame, layout, &mut sheared);
        frame.unshear(&sheared, &mut tau, f32::NEG_INFINITY);
        let acc = if frame.transposed {
            &mut acc_cols
        } else {
            &mut acc_rows
        };
        accumulate(acc, &tau, &layout.z, &layout.grad, [de as f32, dn as f32]);
    }
    field.add_transposed(&mut acc_rows, &acc_cols, |a, b| {
        a[0] += b[0];
        a[1] += b[1];
    });
    let k = (params.k_sky * std::f64::consts::PI / n as f64) as f32;
    let inv_n = 1.0 / n as f32;
    SkyMaps {
        sky: acc_rows.iter().map(|a| a[0] * k).collect(),
        sky_view_factor: acc_rows.iter().map(|a| a[1] * inv_n).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_atan_is_accurate() {
        for k in 0..=4000 {
            let t = k as f32 * 0.005;
            assert!((atan_nonneg(t) - t.atan()).abs() < 2e-5, "{t}");
            assert!((atan_nonneg(1.0 / (t + 1e-3)) - (1.0 / (t + 1e-3)).atan()).abs() < 2e-5);
        }
        assert_eq!(atan_nonneg(f32::INFINITY), std::f32::consts::FRAC_PI_2);
    }

    #[test]
    fn cos2_limits() {
        assert_eq!(paper_cos2(f32::NEG_INFINITY, 0.3), 1.0);
        assert!((paper_cos2(1.0, 0.0) - 0.5).abs() < 1e-6);
        // Horizon 45° above a tangent plane rising at 45°: φ = 0.
        assert_eq!(paper_cos2(1.0, 1.0), 1.0);
        // Horizon 60° above a plane falling at 45°: φ = 105° > 90°: fully blocked.
        assert_eq!(paper_cos2(3.0f32.sqrt(), -1.0), 0.0);
        // SVF on flat open ground is 1 per direction; under a 45° horizon, 1/2.
        assert_eq!(svf_term(f32::NEG_INFINITY, [0.0, 0.0], [1.0, 0.0]), 1.0);
        assert!((svf_term(1.0, [0.0, 0.0], [0.0, 1.0]) - 0.5).abs() < 1e-6);
    }
}
