//! The small per-cell formulas of wind transport, each a pure function of a few values (the
//! second differences they read are `snowscape_terrain::operators`').

/// Wind resistance of the snow surface, `curvW = |W_x| ∂²A/∂x² + |W_y| ∂²A/∂y²`, s⁻¹
/// (Cordonnier 2018, Section 5.4).
#[inline(always)]
pub fn erosion_curvature(a_xx: f32, a_yy: f32, u: f32, v: f32) -> f32 {
    u.abs() * a_xx + v.abs() * a_yy
}

/// Depth eroded from a cell, m: `min(available, −k_erosion δt · curvW)` where `curvW < 0` and
/// the cell is out of the wind shadow, else 0. `erosion_dt = k_erosion · δt`.
#[inline(always)]
pub fn eroded_depth(curv_w: f32, in_shadow: bool, available: f32, erosion_dt: f32) -> f32 {
    // Branch-free (the kernels vectorise): max(NaN, 0) is 0.
    let e = (-erosion_dt * curv_w).max(0.0).min(available);
    if in_shadow { 0.0 } else { e }
}

/// Share of a cell's eroded snow sent to its east/west neighbour, `|u| / (|u| + |v|)`; the
/// rest goes to its north/south neighbour. 0 in calm air.
#[inline(always)]
pub fn downwind_split(u: f32, v: f32) -> f32 {
    u.abs() / (u.abs() + v.abs()).max(f32::MIN_POSITIVE)
}

/// Change of the vertical wind speed along the wind, `a_z = W · ∇(W · ∇Wz)` for a locally
/// uniform wind: `u² Wz_xx + 2uv Wz_xy + v² Wz_yy`, m/s² (y north).
#[inline(always)]
pub fn vertical_wind_change(z_xx: f32, z_xy: f32, z_yy: f32, u: f32, v: f32) -> f32 {
    u * u * z_xx + 2.0 * u * v * z_xy + v * v * z_yy
}

/// Share of the powder turned unstable by tamping: `x/(1+x)`, `x = k_tamping δt · max(0, a_z)`.
#[inline(always)]
pub fn tamping_share(a_z: f32, tamping_dt: f32) -> f32 {
    let x = tamping_dt * a_z.max(0.0);
    x / (1.0 + x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_terrain::operators::{one_sided_second_difference, second_difference};

    #[test]
    fn second_differences_are_exact_on_parabolas() {
        // f = 3x² sampled at x = 0, 1, 2, 3: f'' = 6.
        let f = [0.0f32, 3.0, 12.0, 27.0];
        assert_eq!(second_difference(f[0], f[1], f[2]), 6.0);
        assert_eq!(one_sided_second_difference(f[0], f[1], f[2]), 6.0);
        assert_eq!(one_sided_second_difference(f[3], f[2], f[1]), 6.0);
    }

    #[test]
    fn crests_erode_hollows_and_shadows_do_not() {
        // A crest along y (∂²A/∂x² < 0) under a westerly wind.
        let c = erosion_curvature(-0.02, 0.0, 10.0, 0.0);
        assert!((c + 0.2).abs() < 1e-6);
        assert!((eroded_depth(c, false, 1.0, 0.05) - 0.01).abs() < 1e-7);
        // Limited by the snow present (the paper's max is a min).
        assert_eq!(eroded_depth(c, false, 0.004, 0.05), 0.004);
        assert_eq!(eroded_depth(c, true, 1.0, 0.05), 0.0);
        assert_eq!(eroded_depth(-c, false, 1.0, 0.05), 0.0);
        // Wind along the crest does not see it.
        assert_eq!(erosion_curvature(-0.02, 0.0, 0.0, 10.0), 0.0);
    }

    #[test]
    fn deposit_split_follows_the_wind_components() {
        assert!((downwind_split(3.0, 4.0) - 3.0 / 7.0).abs() < 1e-7);
        assert!((downwind_split(-3.0, -4.0) - 3.0 / 7.0).abs() < 1e-7);
        assert_eq!(downwind_split(5.0, 0.0), 1.0);
        assert_eq!(downwind_split(0.0, -2.0), 0.0);
        assert_eq!(downwind_split(0.0, 0.0), 0.0);
    }

    #[test]
    fn vertical_wind_change_is_the_second_derivative_along_the_wind() {
        // Wz = x·y: zero along the axes, +1 along the diagonal (x = y = s/√2: Wz = s²/2).
        assert_eq!(vertical_wind_change(0.0, 1.0, 0.0, 10.0, 0.0), 0.0);
        let (u, v) = (3.0f32, 3.0f32);
        assert!((vertical_wind_change(0.0, 1.0, 0.0, u, v) - 18.0).abs() < 1e-5);
        assert_eq!(tamping_share(-1.0, 0.1), 0.0);
        assert!((tamping_share(10.0, 0.1) - 0.5).abs() < 1e-7);
    }
}
