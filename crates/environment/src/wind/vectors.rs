//! The horizontal wind field (Cordonnier et al. 2018, Section 4.2):
//!
//! 1. Venturi speed-up with altitude: `W_venturi = (1 + kventuri·A)·Wd` (the factor is clamped
//!    at 0, so terrain far below sea level cannot reverse the wind; `A` is measured from
//!    `WindParams::venturi_base_m`: the terrain's lowest altitude by default, sea level in the paper);
//! 2. slope redirection (paper Eq. 2): `W = W_venturi (1 − |n_xy|) + kterrain |W_venturi| n⊥_xy`,
//!    with `n_xy` the horizontal part of the unit normal and `n⊥_xy` its 90° rotation chosen
//!    on the side of the wind (`W_venturi · n⊥_xy >= 0`): on steep slopes the wind turns to
//!    follow the contour lines.
//!
//! `Wd` comes from the meteorological direction the wind blows FROM (clockwise from north):
//! `Wd = −|Wd| (sin θ, cos θ)` in (east, north).

use crate::WindParams;

/// The dominant wind vector `[east, north]`, m/s, of `params`.
pub fn dominant_wind(params: &WindParams) -> [f64; 2] {
    let t = params.direction_deg.to_radians();
    [-params.speed_m_s * t.sin(), -params.speed_m_s * t.cos()]
}

/// Venturi-scaled wind at altitude `altitude_m`: `max(0, 1 + kventuri·A)·Wd`.
#[inline(always)]
pub fn venturi(wd: [f32; 2], altitude_m: f32, k_venturi: f32) -> [f32; 2] {
    let f = (1.0 + k_venturi * altitude_m).max(0.0);
    [f * wd[0], f * wd[1]]
}

/// Paper Eq. 2: the wind `wv` redirected by a surface of unit normal `normal`.
#[inline(always)]
pub fn redirect(wv: [f32; 2], normal: [f32; 3], k_terrain: f32) -> [f32; 2] {
    let (nx, ny) = (normal[0], normal[1]);
    let len = (nx * nx + ny * ny).sqrt();
    // The two 90° rotations of n_xy; keep the one on the wind's side.
    let mut perp = [-ny, nx];
    if wv[0] * perp[0] + wv[1] * perp[1] < 0.0 {
        perp = [ny, -nx];
    }
    let speed = (wv[0] * wv[0] + wv[1] * wv[1]).sqrt();
    [
        wv[0] * (1.0 - len) + k_terrain * speed * perp[0],
        wv[1] * (1.0 - len) + k_terrain * speed * perp[1],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn westerly_blows_east_and_flat_ground_keeps_it() {
        let p = WindParams {
            direction_deg: 270.0,
            speed_m_s: 10.0,
            ..WindParams::default()
        };
        let wd = dominant_wind(&p);
        assert!((wd[0] - 10.0).abs() < 1e-9 && wd[1].abs() < 1e-9);
        let w = redirect([10.0, 0.0], [0.0, 0.0, 1.0], 0.5);
        assert_eq!(w, [10.0, 0.0]);
        // Venturi: +100 % at 1000 m with kventuri = 1e-3.
        let v = venturi([10.0, 0.0], 1000.0, 1e-3);
        assert!((v[0] - 20.0).abs() < 1e-4);
    }

    #[test]
    fn wind_turns_along_a_steep_slope() {
        // A 45° slope facing west (normal points west-up), wind from the west hits it head on.
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let w = redirect([10.0, 0.0], [-s, 0.0, s], 0.5);
        // Head-on: both rotations are perpendicular to the wind; the along-wind part shrinks
        // to (1 − sin 45°) and a contour-parallel part of 0.5·10·sin 45° appears.
        assert!((w[0] - 10.0 * (1.0 - s)).abs() < 1e-5);
        assert!((w[1].abs() - 5.0 * s).abs() < 1e-5);
        // Oblique wind from the south-west: the turn goes to the wind's side (north).
        let w = redirect([8.0, 6.0], [-s, 0.0, s], 0.5);
        assert!(w[1] > 6.0 * (1.0 - s));
    }
}
