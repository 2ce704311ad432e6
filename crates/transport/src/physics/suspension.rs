//! Suspension and the sublimation of blowing snow (Jubert 2018, Sections 5.5.4-5.5.5, Eqs.
//! 5.40-5.47; Liston & Sturm 1998, Eqs. 12-14 and 19).
//!
//! Above the saltation layer of height `h*` (5.43), the concentration of suspended snow is
//! `φt(z) = φr [(a + 1)(z / h*)^(−s/(κ u*)) − a]`, `a = (φ*/φr) u* / s` (5.41), where the
//! reference concentration at `h*` is the saltation layer's, `φr = Qsalt / (h* u_p)`,
//! `u_p = 2.8 u*t` (5.44-5.45), and `φ*/φr = 0.5 u* / U_r` (5.42). The thesis leaves `U_r`
//! ambiguous; after Liston & Sturm 1998 (Eq. 13) it is the wind at the reference level
//! `h*`, `U_r = (u*/κ) ln(h*/z0)`. The concentration vanishes at
//! `z_t = h* ((a + 1)/a)^(κ u*/s)`, the top of the suspension layer.
//!
//! `Qsusp = ∫_{h*}^{z_t} φt(z) u(z) dz` (5.40) with the log profile `u(z) = (u*/κ) ln(z/z0)`
//! and `Qsubl = ψs φs h* + ∫_{h*}^{z_t} ψt(z) φt(z) dz` (5.47), `φs = φr`, `ψs` taken at
//! mid-height of the saltation layer `h*/2` with the saltation ventilation velocity (as in
//! SnowTran-3D), `ψt` with the suspension one (Annex I). Both integrals are midpoint
//! Riemann sums of `n` samples over `[h*, z_t]` (Eqs. 6.3-6.4).
//!
//! Suspension needs saltation: it is evaluated only where `u* > u*t` over erodible snow,
//! where `z0 = 0.12 u*²/(2g)` and `h* = 1.6 u*²/(2g)` are both functions of `u*`. Then
//! `Qsusp / Qsalt` and the suspension part of `Qsubl / Qsalt` depend on `u*` alone (and the
//! weather), times `1 / u_p`; [`BlowingSnowProfile`] evaluates them per unit saltation flux.

use super::VON_KARMAN;
use super::shear::{log_profile_wind, saltation_height, saltation_roughness};
use super::sublimation::{
    Atmosphere, loss_rate_coefficient, mass_radius, mean_particle_mass, saltation_ventilation,
    suspension_ventilation,
};

/// Horizontal particle speed in the saltation layer `u_p = 2.8 u*t`, m s⁻¹ (Eq. 5.44).
pub fn particle_speed(u_star_t: f64) -> f64 {
    2.8 * u_star_t
}

/// Reference concentration `φr = Qsalt / (h* u_p)`, kg m⁻³ (Eq. 5.45).
pub fn reference_concentration(q_salt: f64, h_star: f64, u_p: f64) -> f64 {
    q_salt / (h_star * u_p)
}

/// Concentration profile of Eq. 5.41 for a saltating surface of friction velocity `u_star`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConcentrationProfile {
    /// Saltation-layer height `h*`, m.
    pub h_star: f64,
    /// Roughness `z0`, m.
    pub z0: f64,
    /// `a = (φ*/φr) u*/s` of Eq. 5.41.
    pub a: f64,
    /// Exponent `s / (κ u*)`.
    pub exponent: f64,
    /// Top of the suspension layer `z_t`, m.
    pub z_top: f64,
    /// Friction velocity, m s⁻¹.
    pub u_star: f64,
}

impl ConcentrationProfile {
    /// The profile over a saltating surface (`z0`, `h*` of Eqs. 5.29 and 5.43).
    pub fn saltating(u_star: f64, settling: f64) -> Self {
        let h_star = saltation_height(u_star);
        let z0 = saltation_roughness(u_star);
        let u_ref = log_profile_wind(u_star, h_star, z0);
        let a = 0.5 * u_star / u_ref * u_star / settling; // Eq. 5.42
        let exponent = settling / (VON_KARMAN * u_star);
        let z_top = h_star * ((a + 1.0) / a).powf(1.0 / exponent);
        Self {
            h_star,
            z0,
            a,
            exponent,
            z_top,
            u_star,
        }
    }

    /// `φt(z) / φr` (Eq. 5.41), zero above `z_t`.
    pub fn relative_concentration(&self, z: f64) -> f64 {
        ((self.a + 1.0) * (z / self.h_star).powf(-self.exponent) - self.a).max(0.0)
    }
}

/// `Qsusp` and `Qsubl` per unit reference concentration `φr`, for one `u*`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlowingSnowProfile {
    /// `∫ (φt/φr) u dz`, m² s⁻¹: `Qsusp = φr` times this (Eq. 5.40).
    pub suspension: f64,
    /// `∫ ψt (φt/φr) dz`, m s⁻¹: the suspension part of `Qsubl` per `φr` (Eq. 5.47).
    pub sublimation: f64,
}

/// Integrates Eqs. 5.40 and 5.47 (suspension part) over `[h*, z_t]` with `n` midpoint
/// samples, per unit reference concentration.
pub fn blowing_snow_profile(
    u_star: f64,
    settling: f64,
    samples: usize,
    atm: &Atmosphere,
) -> BlowingSnowProfile {
    let p = ConcentrationProfile::saltating(u_star, settling);
    let dz = (p.z_top - p.h_star) / samples as f64;
    let mut suspension = 0.0;
    let mut sublimation = 0.0;
    for i in 0..samples {
        let z = p.h_star + (i as f64 + 0.5) * dz;
        let c = p.relative_concentration(z);
        let u = log_profile_wind(u_star, z, p.z0);
        suspension += c * u * dz;
        let v = suspension_ventilation(mass_radius(mean_particle_mass(z)), u);
        sublimation += loss_rate_coefficient(z, v, atm) * c * dz;
    }
    BlowingSnowProfile {
        suspension,
        sublimation,
    }
}

/// Loss-rate coefficient of the saltation layer `ψs`, s⁻¹, at `h*/2` (Eq. 5.47).
pub fn saltation_layer_loss_rate(u_star: f64, u_star_t: f64, atm: &Atmosphere) -> f64 {
    let z = 0.5 * saltation_height(u_star);
    loss_rate_coefficient(z, saltation_ventilation(u_star, u_star_t), atm)
}

/// `(Qsusp, Qsubl)` of a saltating cell carrying `q_salt` kg m⁻¹ s⁻¹ (Eqs. 5.40-5.47),
/// evaluated directly. `Qsubl ≤ 0` is a loss, kg m⁻² s⁻¹.
pub fn blowing_snow_fluxes(
    q_salt: f64,
    u_star: f64,
    u_star_t: f64,
    settling: f64,
    samples: usize,
    atm: &Atmosphere,
) -> (f64, f64) {
    let h_star = saltation_height(u_star);
    let phi_r = reference_concentration(q_salt, h_star, particle_speed(u_star_t));
    let prof = blowing_snow_profile(u_star, settling, samples, atm);
    let psi_s = saltation_layer_loss_rate(u_star, u_star_t, atm);
    (
        phi_r * prof.suspension,
        psi_s * phi_r * h_star + phi_r * prof.sublimation,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    const ATM: Atmosphere = Atmosphere {
        t_k: 263.15,
        rh: 0.4,
        z_rh: 2.0,
        irradiance: 0.0,
    };

    #[test]
    fn profile_matches_hand_values() {
        // u* = 0.5, s = 0.3: h* = 1.6 · 0.25 / 19.62 = 0.0203874 m, z0 = 0.00152905 m,
        // U_r = 0.5/0.4 · ln(h*/z0) = 1.25 · ln(13.3333) = 3.23783 m/s,
        // a = 0.5 · 0.5/3.23783 · 0.5/0.3 = 0.128687, exponent = 0.3/(0.4·0.5) = 1.5,
        // z_t = h* (1.128687/0.128687)^(1/1.5) = 0.0203874 · 4.25298 = 0.0867069 m.
        let p = ConcentrationProfile::saltating(0.5, 0.3);
        assert!((p.a - 0.128_687).abs() < 1e-6, "{}", p.a);
        assert!((p.z_top - 0.086_706_9).abs() < 1e-7, "{}", p.z_top);
        assert!((p.relative_concentration(p.h_star) - 1.0).abs() < 1e-12);
        assert!(p.relative_concentration(p.z_top * 1.0001) == 0.0);
    }

    #[test]
    fn suspension_integral_converges_to_closed_form_check() {
        // The midpoint sum converges as n grows: 40 samples are within 0.1 % of 4000.
        let coarse = blowing_snow_profile(0.5, 0.3, 40, &ATM);
        let fine = blowing_snow_profile(0.5, 0.3, 4000, &ATM);
        assert!((coarse.suspension / fine.suspension - 1.0).abs() < 1e-3);
        assert!((coarse.sublimation / fine.sublimation - 1.0).abs() < 1e-3);
        assert!(fine.suspension > 0.0 && fine.sublimation < 0.0);
    }

    #[test]
    fn fluxes_scale_with_saltation_and_vanish_in_saturated_dark_air() {
        let (qs1, qv1) = blowing_snow_fluxes(0.01, 0.5, 0.25, 0.3, 40, &ATM);
        let (qs2, qv2) = blowing_snow_fluxes(0.02, 0.5, 0.25, 0.3, 40, &ATM);
        assert!((qs2 / qs1 - 2.0).abs() < 1e-12 && (qv2 / qv1 - 2.0).abs() < 1e-12);
        // φr = 0.01 / (0.0203874 · 0.7) = 0.700714 kg/m³; the saltation-layer part of
        // Qsubl is ψs φr h*, with ψs from Annex I at z = h*/2.
        let psi_s = saltation_layer_loss_rate(0.5, 0.25, &ATM);
        let phi_r = reference_concentration(0.01, saltation_height(0.5), particle_speed(0.25));
        assert!((phi_r - 0.700_714).abs() < 1e-5);
        assert!(qv1 < psi_s * phi_r * saltation_height(0.5)); // suspension adds more loss
        let wet = Atmosphere { rh: 1.0, ..ATM };
        assert_eq!(blowing_snow_fluxes(0.01, 0.5, 0.25, 0.3, 40, &wet).1, 0.0);
    }
}
