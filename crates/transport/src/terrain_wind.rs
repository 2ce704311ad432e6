//! Terrain modification of the wind at `z_r` (Jubert 2018, Section 5.4, Eqs. 5.1-5.15,
//! after Liston & Sturm 1998 and Liston & Elder's MicroMet).
//!
//! From the height map `z` and the wind `(u, v)` at height `z_r` (east and north
//! components, m s⁻¹):
//!
//! - speed and direction `W = √(u² + v²)`, `θ` the direction the wind blows *from*,
//!   clockwise from north, so `u = −W sin θ`, `v = −W cos θ` (5.1-5.4; 5.4 is written here
//!   as `θ = atan2(−u, −v)`, which is `3π/2 − atan2(v, u)` without the quadrant ambiguity
//!   of the printed `arctan(v/u)`);
//! - slope `β = atan |∇z|` (5.5-5.7, central differences, one-sided at the border) and the
//!   azimuth the slope faces `ξ = atan2(−∂z/∂x, −∂z/∂y)` (5.8, same remark);
//! - the curvature weight (5.9) `Ωc = ¼ [(z − ½(z_W + z_E))/(2η) + (z − ½(z_S + z_N))/(2η) +
//!   (z − ½(z_SW + z_NE))/(2√2 η) + (z − ½(z_NW + z_SE))/(2√2 η)]`. As in MicroMet, the
//!   neighbours are taken at the curvature length `η` from the cell (`max(1, round(η/Δ))`
//!   cells away; the thesis's figure reads them as adjacent cells, which makes `η` a mere
//!   scale). `Ωc` is normalised into `[−0.5, 0.5]` by dividing by twice its largest
//!   magnitude over the grid (MicroMet's scaling; it keeps flat ground at 0, which a
//!   min-max stretch would not);
//! - the slope weight `Ωp = β cos(θ − ξ)` (5.10), positive on windward slopes;
//! - `W_w = 1 + γp Ωp + γc Ωc` (5.11, floored at 0), `W_t = W_w W` (5.13),
//!   `θ_d = −0.5 Ωp sin(2(ξ − θ))` (5.14), `θ_t = θ + θ_d` (5.15), back to `(u, v)` by 5.1-5.2.

use crate::error::TransportError;
use crate::params::TransportParams;
use rayon::prelude::*;
use snowscape_terrain::{GridGeometry, operators};

/// Checks a map's length against the grid.
pub(crate) fn check_len(
    map: &'static str,
    values: &[f32],
    geometry: &GridGeometry,
) -> Result<(), TransportError> {
    if values.len() == geometry.len() {
        Ok(())
    } else {
        Err(TransportError::MapLength {
            map,
            width: geometry.width(),
            height: geometry.height(),
            expected: geometry.len(),
            actual: values.len(),
        })
    }
}

/// Wind speed and the direction it blows from (Eqs. 5.3-5.4).
#[inline]
pub fn speed_and_direction(u: f64, v: f64) -> (f64, f64) {
    ((u * u + v * v).sqrt(), (-u).atan2(-v))
}

/// East and north components of a wind of speed `w` from direction `theta` (Eqs. 5.1-5.2).
#[inline]
pub fn components(w: f64, theta: f64) -> (f64, f64) {
    (-w * theta.sin(), -w * theta.cos())
}

/// Slope `β` and facing azimuth `ξ` from the height gradient (east, north) (Eqs. 5.7-5.8).
#[inline]
pub fn slope_and_azimuth(dz_dx: f64, dz_dy: f64) -> (f64, f64) {
    (
        operators::slope_angle(dz_dx, dz_dy),
        operators::aspect(dz_dx, dz_dy),
    )
}

/// The modified wind (Eqs. 5.10-5.15) for slope `beta`, azimuth `xi`, normalised curvature
/// weight `omega_c` and the user weights.
#[inline]
pub fn modified_wind(
    u: f64,
    v: f64,
    beta: f64,
    xi: f64,
    omega_c: f64,
    slope_weight: f64,
    curvature_weight: f64,
) -> (f64, f64) {
    let (w, theta) = speed_and_direction(u, v);
    if w == 0.0 {
        return (0.0, 0.0);
    }
    let omega_p = beta * (theta - xi).cos();
    let factor = (1.0 + slope_weight * omega_p + curvature_weight * omega_c).max(0.0);
    let theta_d = -0.5 * omega_p * (2.0 * (xi - theta)).sin();
    components(factor * w, theta + theta_d)
}

/// Height of cell `(c, r)` offset by `(dc, dr)`, clamped to the grid.
#[inline]
fn z_at(z: &[f32], g: &GridGeometry, c: usize, r: usize, dc: isize, dr: isize) -> f64 {
    let cc = (c as isize + dc).clamp(0, g.width() as isize - 1) as usize;
    let rr = (r as isize + dr).clamp(0, g.height() as isize - 1) as usize;
    f64::from(z[rr * g.width() + cc])
}

/// Height gradient (east, north) at a cell by central differences (Eqs. 5.5-5.6),
/// one-sided at the border ([`operators::gradient`]). Row 0 is the northern edge.
fn gradient(z: &[f32], g: &GridGeometry, c: usize, r: usize) -> (f64, f64) {
    let at = |dc: isize, dr: isize| g.neighbour(c, r, dc, dr).map(|j| f64::from(z[j]));
    let z0 = f64::from(z[g.index(c, r)]);
    operators::gradient(z0, at, g.cell_size_x(), g.cell_size_y())
}

/// Raw curvature weight of Eq. 5.9 at a cell, neighbours `k` cells away (clamped to the
/// grid): [`operators::directional_curvature`].
fn raw_curvature(z: &[f32], g: &GridGeometry, c: usize, r: usize, k: isize, eta: f64) -> f64 {
    let at = |dc, dr| z_at(z, g, c, r, dc, dr);
    operators::directional_curvature(at(0, 0), at, k, eta)
}

/// Applies the terrain modification (Section 5.4) to the wind `(u, v)` at `z_r` over the
/// height map `z`; returns the modified `(u, v)`.
pub fn modify_wind(
    params: &TransportParams,
    geometry: &GridGeometry,
    z: &[f32],
    u: &[f32],
    v: &[f32],
) -> Result<(Vec<f32>, Vec<f32>), TransportError> {
    params.validate()?;
    check_len("height", z, geometry)?;
    check_len("wind_u", u, geometry)?;
    check_len("wind_v", v, geometry)?;
    let w = geometry.width();
    let cell = geometry.cell_size_x().min(geometry.cell_size_y());
    let k = ((params.curvature_length_m / cell).round() as isize).max(1);
    let eta = params.curvature_length_m;
    let mut omega_c = vec![0.0f64; geometry.len()];
    omega_c.par_chunks_mut(w).enumerate().for_each(|(r, row)| {
        for (c, o) in row.iter_mut().enumerate() {
            *o = raw_curvature(z, geometry, c, r, k, eta);
        }
    });
    let max_abs = omega_c.iter().fold(0.0f64, |m, o| m.max(o.abs()));
    let scale = if max_abs > 0.0 { 0.5 / max_abs } else { 0.0 };
    let mut out_u = vec![0.0f32; geometry.len()];
    let mut out_v = vec![0.0f32; geometry.len()];
    out_u
        .par_chunks_mut(w)
        .zip(out_v.par_chunks_mut(w))
        .enumerate()
        .for_each(|(r, (ou, ov))| {
            for c in 0..w {
                let i = r * w + c;
                let (gx, gy) = gradient(z, geometry, c, r);
                let (beta, xi) = slope_and_azimuth(gx, gy);
                let (mu, mv) = modified_wind(
                    f64::from(u[i]),
                    f64::from(v[i]),
                    beta,
                    xi,
                    omega_c[i] * scale,
                    params.slope_weight,
                    params.curvature_weight,
                );
                ou[c] = mu as f32;
                ov[c] = mv as f32;
            }
        });
    Ok((out_u, out_v))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn polar_conversions_follow_eqs_5_1_to_5_4() {
        // A west wind (blowing east, u > 0) comes from 270°; a north wind from 0°.
        let (w, t) = speed_and_direction(3.0, 0.0);
        assert!((w - 3.0).abs() < 1e-12 && (t.rem_euclid(2.0 * PI) - 1.5 * PI).abs() < 1e-12);
        let (_, t) = speed_and_direction(0.0, -2.0);
        assert!(t.abs() < 1e-12);
        let (u, v) = components(5.0, 1.5 * PI);
        assert!((u - 5.0).abs() < 1e-12 && v.abs() < 1e-12);
        // A slope descending to the east faces east (90°), one descending north faces 0°.
        let (b, xi) = slope_and_azimuth(-1.0, 0.0);
        assert!((b - PI / 4.0).abs() < 1e-12 && (xi - PI / 2.0).abs() < 1e-12);
        assert!(slope_and_azimuth(0.0, -0.5).1.abs() < 1e-12);
    }

    #[test]
    fn flat_terrain_leaves_the_wind_unchanged() {
        let g = GridGeometry::square(32, 24, 10.0).unwrap();
        let z = vec![1234.0f32; g.len()];
        let u: Vec<f32> = (0..g.len()).map(|i| 3.0 + (i % 5) as f32).collect();
        let v: Vec<f32> = (0..g.len()).map(|i| (i % 3) as f32 - 1.0).collect();
        let (mu, mv) = modify_wind(&TransportParams::default(), &g, &z, &u, &v).unwrap();
        for i in 0..g.len() {
            assert!(
                (mu[i] - u[i]).abs() < 1e-5 && (mv[i] - v[i]).abs() < 1e-5,
                "cell {i}"
            );
        }
    }

    #[test]
    fn windward_slopes_speed_up_and_lee_slopes_slow_down() {
        // A north-south ridge at column 32 (Gaussian, 100 m high, 5 m cells) under a west
        // wind of 10 m/s.
        let g = GridGeometry::square(64, 16, 5.0).unwrap();
        let z: Vec<f32> = (0..g.len())
            .map(|i| {
                let x = (i % 64) as f32 - 32.0;
                100.0 * (-(x * x) / 120.0).exp()
            })
            .collect();
        let u = vec![10.0f32; g.len()];
        let v = vec![0.0f32; g.len()];
        let (mu, mv) = modify_wind(&TransportParams::default(), &g, &z, &u, &v).unwrap();
        let row = 8 * 64;
        let speed = |c: usize| mu[row + c].hypot(mv[row + c]);
        assert!(speed(26) > 10.5, "windward {}", speed(26)); // west flank
        assert!(speed(38) < 9.5, "lee {}", speed(38)); // east flank
        assert!(speed(26) > speed(38));
        assert!(speed(32) > 10.0, "crest {}", speed(32)); // convex crest
        // Along the ridge axis (slope normal to the wind) the direction barely turns.
        assert!(mv[row + 26].abs() < 1e-3 && mv[row + 38].abs() < 1e-3);
    }

    #[test]
    fn wrong_map_length_is_an_error() {
        let g = GridGeometry::square(4, 4, 1.0).unwrap();
        let z = vec![0.0f32; 15];
        let u = vec![0.0f32; 16];
        let err = modify_wind(&TransportParams::default(), &g, &z, &u, &u).unwrap_err();
        assert!(matches!(
            err,
            TransportError::MapLength {
                map: "height",
                actual: 15,
                ..
            }
        ));
    }
}
