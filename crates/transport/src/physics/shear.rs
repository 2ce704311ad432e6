//! Threshold and actual surface shear (Jubert 2018, Sections 5.5.1.2-5.5.2, Eqs. 5.23-5.36;
//! Liston & Sturm 1998, Eqs. 3-8).
//!
//! - Hardness `σ = 1.36 exp(0.013 ρs)` kPa (5.23).
//! - Threshold friction velocity (5.25): `u*t = 0.10 exp(0.003 ρs)` for `ρs ≤ 300`,
//!   `0.005 exp(0.013 ρs)` above (the thesis bounds the upper branch at 450 kg m⁻³; denser
//!   snow keeps the same formula, which is already far beyond any wind's reach).
//! - Friction velocity from the log profile `u* = u_r κ / ln(z_r / z0)` (5.26), with
//!   `z0 = F_s z0_snow + (1 − F_s) z0_veg`, `F_s = ζ / C_v`, while the snow is shallower
//!   than the vegetation's holding depth (5.27-5.28).
//! - Over deeper snow, saltation roughens the surface: `z0 = 0.12 u*² / (2g)` (5.29). The
//!   pair (5.26, 5.29) is solved by Newton-Raphson on `f1 = u* − u_r κ / ln(z_r / z0)`,
//!   `f2 = z0 − 0.12 u*² / (2g)` with the Jacobian of Eq. 5.35 (5.30-5.36). If the solution
//!   does not exceed `u*t`, there is no saltation and `z0 = z0_snow` in Eq. 5.26.
//! - The saltation layer height `h* = 1.6 u*² / (2g)` (5.43).

use super::{GRAVITY, VON_KARMAN};

/// Coefficient of Eq. 5.29.
const ROUGHNESS_COEFF: f64 = 0.12;
/// Coefficient of Eq. 5.43.
const SALTATION_HEIGHT_COEFF: f64 = 1.6;

/// Snow hardness `σ`, kPa, of snow of density `rho` (Eq. 5.23).
pub fn hardness(rho: f64) -> f64 {
    1.36 * (0.013 * rho).exp()
}

/// Threshold friction velocity `u*t`, m s⁻¹, of snow of density `rho` kg m⁻³ (Eq. 5.25).
pub fn threshold_friction_velocity(rho: f64) -> f64 {
    if rho > 300.0 {
        0.005 * (0.013 * rho).exp()
    } else {
        0.10 * (0.003 * rho).exp()
    }
}

/// Friction velocity of the log wind profile, m s⁻¹ (Eq. 5.26).
pub fn log_profile_friction_velocity(u_r: f64, z_r: f64, z0: f64) -> f64 {
    u_r * VON_KARMAN / (z_r / z0).ln()
}

/// Wind speed of the log profile at height `z`, m s⁻¹ (inverse of Eq. 5.26).
pub fn log_profile_wind(u_star: f64, z: f64, z0: f64) -> f64 {
    u_star / VON_KARMAN * (z / z0).ln()
}

/// Roughness length under vegetation partly filled with snow, m (Eqs. 5.27-5.28).
pub fn vegetation_roughness(depth: f64, holding_depth: f64, z0_snow: f64, z0_veg: f64) -> f64 {
    let fs = if holding_depth > 0.0 {
        (depth / holding_depth).clamp(0.0, 1.0)
    } else {
        1.0
    };
    fs * z0_snow + (1.0 - fs) * z0_veg
}

/// Roughness of a saltating surface `0.12 u*² / (2g)`, m (Eq. 5.29).
pub fn saltation_roughness(u_star: f64) -> f64 {
    ROUGHNESS_COEFF * u_star * u_star / (2.0 * GRAVITY)
}

/// Height of the saltation layer `h* = 1.6 u*² / (2g)`, m (Eq. 5.43).
pub fn saltation_height(u_star: f64) -> f64 {
    SALTATION_HEIGHT_COEFF * u_star * u_star / (2.0 * GRAVITY)
}

/// Solves Eqs. 5.26 and 5.29 together for `(u*, z0)` by Newton-Raphson (Eqs. 5.30-5.36),
/// for a wind `u_r` m s⁻¹ at height `z_r` m. Starts from the log-profile friction velocity
/// over `z0_start` (the snow roughness) and stops when the update is below 1e-12 relative
/// (at most 40 iterations). Returns `Some((0, 0))` for a calm wind, and `None` where the
/// system has no solution: above about 50 m s⁻¹ at `z_r = 5 m` the saltation roughness
/// would reach the measurement height.
pub fn saltating_friction_velocity(u_r: f64, z_r: f64, z0_start: f64) -> Option<(f64, f64)> {
    if u_r <= 0.0 {
        return Some((0.0, 0.0));
    }
    let mut u_star = log_profile_friction_velocity(u_r, z_r, z0_start);
    let mut z0 = saltation_roughness(u_star);
    // Keep z0 where ln(z_r / z0) is positive and finite.
    let z0_max = 0.5 * z_r;
    let z0_min = 1e-12 * z_r;
    for _ in 0..40 {
        let ln = (z_r / z0).ln();
        let f1 = u_star - u_r * VON_KARMAN / ln;
        let f2 = z0 - saltation_roughness(u_star);
        // Jacobian (Eq. 5.35): [[1, a], [b, 1]].
        let a = -u_r * VON_KARMAN / (z0 * ln * ln);
        let b = -ROUGHNESS_COEFF * u_star / GRAVITY;
        let det = 1.0 - a * b;
        // x ← x − J⁻¹ f (Eqs. 5.33, 5.36).
        let du = (f1 - a * f2) / det;
        let dz = (f2 - b * f1) / det;
        u_star -= du;
        z0 = (z0 - dz).clamp(z0_min, z0_max);
        if du.abs() <= 1e-12 * u_star.abs() {
            let solved = u_star > 0.0
                && z0 > z0_min
                && z0 < z0_max
                && (u_star - log_profile_friction_velocity(u_r, z_r, z0)).abs() < 1e-9 * u_star;
            return solved.then_some((u_star, z0));
        }
    }
    None
}

/// The shear state of one cell's snow surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceShear {
    /// Friction velocity `u*`, m s⁻¹.
    pub u_star: f64,
    /// Roughness length `z0`, m.
    pub z0: f64,
    /// Whether saltation takes place (`u* > u*t` over snow deeper than `C_v`).
    pub saltating: bool,
}

/// Inputs of [`surface_shear`] that do not vary per cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShearSite {
    /// Height of the wind measurement `z_r`, m.
    pub z_r: f64,
    /// Snow roughness `z0_snow`, m.
    pub z0_snow: f64,
    /// Vegetation roughness `z0_veg`, m.
    pub z0_veg: f64,
    /// Vegetation snow-holding depth `C_v`, m.
    pub holding_depth: f64,
}

/// Friction velocity and roughness of a cell with snow depth `depth` m under a wind `u_r`
/// (Section 5.5.2): the vegetation case (5.26-5.28) while `depth ≤ C_v`, otherwise the
/// Newton-Raphson solution (5.30-5.36) if it exceeds `u_star_t`, else Eq. 5.26 over snow.
/// `saltating_u_star` is the solution of [`saltating_friction_velocity`] for `u_r` (the
/// caller may take it from a table, as it depends on `u_r` alone).
pub fn surface_shear(
    site: &ShearSite,
    u_r: f64,
    depth: f64,
    u_star_t: f64,
    saltating_u_star: f64,
) -> SurfaceShear {
    if depth <= site.holding_depth {
        let z0 = vegetation_roughness(depth, site.holding_depth, site.z0_snow, site.z0_veg);
        return SurfaceShear {
            u_star: log_profile_friction_velocity(u_r, site.z_r, z0),
            z0,
            saltating: false,
        };
    }
    if saltating_u_star > u_star_t {
        SurfaceShear {
            u_star: saltating_u_star,
            z0: saltation_roughness(saltating_u_star),
            saltating: true,
        }
    } else {
        SurfaceShear {
            u_star: log_profile_friction_velocity(u_r, site.z_r, site.z0_snow),
            z0: site.z0_snow,
            saltating: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threshold_friction_velocity_matches_hand_values() {
        // ρ = 100: 0.10 e^0.3 = 0.134986;  ρ = 250: 0.10 e^0.75 = 0.211700
        // ρ = 350: 0.005 e^4.55 = 0.473162;  ρ = 450: 0.005 e^5.85 = 1.736172
        for (rho, want) in [
            (100.0, 0.134_986),
            (250.0, 0.211_700),
            (350.0, 0.473_162),
            (450.0, 1.736_172),
        ] {
            let got = threshold_friction_velocity(rho);
            assert!((got - want).abs() < 1e-6, "ρ {rho}: {got} vs {want}");
        }
        // The two branches meet at 300 kg m⁻³: 0.1 e^0.9 = 0.24596, 0.005 e^3.9 = 0.24701.
        let below = threshold_friction_velocity(300.0);
        let above = threshold_friction_velocity(300.0 + 1e-9);
        assert!((below - above).abs() < 2e-3);
    }

    #[test]
    fn hardness_matches_hand_value() {
        // 1.36 e^(0.013 · 350) = 1.36 · 94.6324 = 128.700 kPa, and σ = 267 u*t holds
        // within 2 % in the 300-450 range the thesis gives it for (5.24).
        assert!((hardness(350.0) - 128.700).abs() < 1e-3);
        let ratio = hardness(350.0) / (267.0 * threshold_friction_velocity(350.0));
        assert!((ratio - 1.0).abs() < 0.02, "{ratio}");
    }

    #[test]
    fn newton_raphson_matches_hand_solution() {
        // u_r = 10 m/s at z_r = 5 m. Fixed-point iteration of u* = 4 / ln(5 / (0.12 u*² / 2g))
        // converges to u* = 0.492424, z0 = 0.12 · 0.492424² / 19.62 = 1.48307e-3 m;
        // check: 4 / ln(5 / 1.48307e-3) = 4 / 8.12308 = 0.492424.
        let (u, z0) = saltating_friction_velocity(10.0, 5.0, 0.001).unwrap();
        assert!((u - 0.492_424).abs() < 1e-6, "{u}");
        assert!((z0 - 1.483_07e-3).abs() < 1e-8, "{z0}");
        // Both equations hold at the solution, for other winds too.
        for ur in [2.0, 5.0, 20.0, 30.0] {
            let (u, z0) = saltating_friction_velocity(ur, 5.0, 0.001).unwrap();
            assert!((u - log_profile_friction_velocity(ur, 5.0, z0)).abs() < 1e-10);
            assert!((z0 - saltation_roughness(u)).abs() < 1e-14);
        }
        // u_r = 5: u* = 0.201892, u_r = 20: u* = 1.291409 (same fixed point).
        let u5 = saltating_friction_velocity(5.0, 5.0, 0.001).unwrap().0;
        assert!((u5 - 0.201_892).abs() < 1e-6);
        let u20 = saltating_friction_velocity(20.0, 5.0, 0.001).unwrap().0;
        assert!((u20 - 1.291_409).abs() < 1e-6);
        assert_eq!(
            saltating_friction_velocity(0.0, 5.0, 0.001),
            Some((0.0, 0.0))
        );
        // No solution at 60 m/s: 0.12 u*²/2g would exceed z_r (fixed point diverges).
        assert_eq!(saltating_friction_velocity(60.0, 5.0, 0.001), None);
    }

    #[test]
    fn shear_branches() {
        let site = ShearSite {
            z_r: 5.0,
            z0_snow: 0.001,
            z0_veg: 0.05,
            holding_depth: 0.05,
        };
        // Snow 2 cm deep in 5 cm of vegetation: F_s = 0.4, z0 = 0.4·0.001 + 0.6·0.05 = 0.0304;
        // u* = 10 · 0.4 / ln(5 / 0.0304) = 4 / 5.10275 = 0.783891.
        let s = surface_shear(&site, 10.0, 0.02, 0.1, 0.49);
        assert!(!s.saltating);
        assert!((s.z0 - 0.0304).abs() < 1e-12);
        assert!((s.u_star - 0.783_891).abs() < 1e-6, "{}", s.u_star);
        // Deep snow, strong wind: the Newton-Raphson solution.
        let (us, _) = saltating_friction_velocity(10.0, 5.0, 0.001).unwrap();
        let s = surface_shear(&site, 10.0, 1.0, 0.2, us);
        assert!(s.saltating && s.u_star == us);
        // Hard snow: no saltation, z0 = z0_snow, u* = 4 / ln(5000) = 0.469638.
        let s = surface_shear(&site, 10.0, 1.0, 1.7, us);
        assert!(!s.saltating);
        assert!((s.u_star - 0.469_638).abs() < 1e-6);
        // h* = 1.6 u*² / 2g: u* = 0.5 → 1.6 · 0.25 / 19.62 = 0.020387360 m.
        assert!((saltation_height(0.5) - 0.020_387_360).abs() < 1e-9);
    }
}
