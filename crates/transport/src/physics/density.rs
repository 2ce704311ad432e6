//! Snow density (Jubert 2018, Section 5.5.1.1, Eqs. 5.18-5.22; Liston & Sturm 1998, Eqs.
//! 15-18).
//!
//! - Fresh snow `ρns = 50 + 1.7 (T_WB − 258.16)^1.5` (5.18). Below 258.16 K the power of a
//!   negative number is undefined; the formula's floor, 50 kg m⁻³, is used there (as
//!   SnowModel does).
//! - Wind-packed new snow for `W ≥ 5 m s⁻¹`: `ρs = ρns + D1 + D2 [1 − exp(−D3 (W − 5))]`
//!   (5.19-5.20), `D1 = 25`, `D2 = 250` kg m⁻³, `D3 = 0.2` s m⁻¹.
//! - Without snowfall, `∂ρs/∂t = C A1 U ρs exp(−B (T_f − T_s)) exp(−A2 ρs)` (5.21) with
//!   `U = E1 + E2 [1 − exp(−E3 (W − 5))]` for `W ≥ 5`, else 1 (5.22).

use super::FREEZING_K;

/// `D1`, `D2` (kg m⁻³), `D3` (s m⁻¹) of Eq. 5.20.
const D: [f64; 3] = [25.0, 250.0, 0.2];
/// `E1`, `E2`, `E3` of Eq. 5.22.
const E: [f64; 3] = [5.0, 15.0, 0.2];
/// `B`, K⁻¹ (Eq. 5.21).
const B: f64 = 0.08;
/// `A1`, m⁻¹ (Eq. 5.21; with `U` in m s⁻¹ the product `A1 U` is a rate, s⁻¹).
const A1: f64 = 0.0013;
/// `A2`, m³ kg⁻¹ (Eq. 5.21).
const A2: f64 = 0.021;
/// `C` (Eq. 5.21).
const C: f64 = 0.10;
/// Wind speed above which the wind packs the snow, m s⁻¹ (Eqs. 5.19-5.22).
const PACKING_WIND: f64 = 5.0;

/// Fresh-snow density `ρns`, kg m⁻³, at wet-bulb (air) temperature `t_k` (Eq. 5.18).
pub fn fresh_snow_density(t_k: f64) -> f64 {
    50.0 + 1.7 * (t_k - 258.16).max(0.0).powf(1.5)
}

/// Density of snow falling or deposited under a wind of `wind` m s⁻¹, kg m⁻³
/// (Eqs. 5.18-5.20): `ρns`, plus `ρu` when `wind ≥ 5`.
pub fn new_snow_density(t_k: f64, wind: f64) -> f64 {
    let rho_ns = fresh_snow_density(t_k);
    if wind >= PACKING_WIND {
        rho_ns + D[0] + D[1] * (1.0 - (-D[2] * (wind - PACKING_WIND)).exp())
    } else {
        rho_ns
    }
}

/// Wind factor `U` of Eq. 5.22.
pub fn densification_wind_factor(wind: f64) -> f64 {
    if wind >= PACKING_WIND {
        E[0] + E[1] * (1.0 - (-E[2] * (wind - PACKING_WIND)).exp())
    } else {
        1.0
    }
}

/// Densification rate `∂ρs/∂t`, kg m⁻³ s⁻¹ (Eq. 5.21), of snow of density `rho` under a
/// wind `wind` with snow temperature `t_snow_k` (at most the freezing point).
pub fn densification_rate(rho: f64, wind: f64, t_snow_k: f64) -> f64 {
    let ts = t_snow_k.min(FREEZING_K);
    C * A1
        * densification_wind_factor(wind)
        * rho
        * (-B * (FREEZING_K - ts)).exp()
        * (-A2 * rho).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresh_snow_density_matches_hand_values() {
        // 50 + 1.7 (268.15 − 258.16)^1.5 = 50 + 1.7 · 9.99^1.5 = 50 + 1.7 · 31.575 = 103.678
        assert!((fresh_snow_density(268.15) - 103.678).abs() < 1e-3);
        // −15 °C and colder: the floor.
        assert_eq!(fresh_snow_density(258.16), 50.0);
        assert_eq!(fresh_snow_density(250.0), 50.0);
    }

    #[test]
    fn wind_packing_adds_rho_u() {
        // ρu(W = 10) = 25 + 250 (1 − e^(−0.2·5)) = 25 + 250 · 0.632121 = 183.030
        let t = 250.0; // ρns = 50
        assert!((new_snow_density(t, 10.0) - 233.030).abs() < 1e-3);
        assert_eq!(new_snow_density(t, 4.99), 50.0);
        assert!((new_snow_density(t, 5.0) - 75.0).abs() < 1e-12); // ρns + D1
    }

    #[test]
    fn densification_rate_matches_hand_value() {
        // ρ = 100, W = 2 (U = 1), T_s = T_f − 5:
        // 0.1 · 0.0013 · 1 · 100 · e^(−0.4) · e^(−2.1) = 0.013 · 0.670320 · 0.122456
        //   = 1.06710e-3 kg m⁻³ s⁻¹
        let r = densification_rate(100.0, 2.0, FREEZING_K - 5.0);
        assert!((r - 1.067_10e-3).abs() < 1e-8, "{r}");
        // U(W = 10) = 5 + 15 (1 − e^(−1)) = 5 + 15 · 0.632121 = 14.481809
        assert!((densification_wind_factor(10.0) - 14.481_809).abs() < 1e-5);
        // The snow is never warmer than the freezing point.
        assert_eq!(
            densification_rate(100.0, 2.0, FREEZING_K + 10.0),
            densification_rate(100.0, 2.0, FREEZING_K)
        );
    }
}
