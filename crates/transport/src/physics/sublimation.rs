//! Sublimation loss-rate coefficient `ψ` of blowing snow (Jubert 2018, Annex I, Eqs.
//! I.1-I.23, after Liston & Sturm 1998, Appendix; Schmidt 1972, Pomeroy & Gray 1995).
//!
//! `ψ(z) = (dm̄/dt) / m̄(z)` (I.2), s⁻¹, negative when snow sublimates, with
//!
//! - the particles at height `z`: mean radius `r̄_r = 4.6e-5 z^−0.258` (I.4), shape
//!   `α = 4.08 + 12.6 z` (I.5), mean mass `m̄ = 4/3 π ρi r̄_r³ (1 + 3/α + 2/α²)` (I.3) and
//!   the radius of that mass `r̄ = (3 m̄ / (4 π ρi))^(1/3)` (I.10);
//! - the mass rate (I.6)
//!   `dm̄/dt = [2π r̄ σ − S_p/(λt T Nu) (h_s M/(R T) − 1)] / [h_s/(λt T Nu) (h_s M/(R T) − 1) + 1/(D ρv Sh)]`
//!   with `D = 2.06e-5 (T/273)^1.75` (I.7), `ρv = 0.622 e_s / (R_d T)` (I.8),
//!   `e_s = 610.78 exp(21.875 (T − 273.16)/(T − 7.66))` Pa over ice (I.9);
//! - the undersaturation `σ(z) = σr (Γ + 0.027 ln z)` with `σr = RH − 1` and
//!   `Γ = 1 − 0.027 ln z_rh` (I.11-I.13; the thesis's text garbles these, they are restored
//!   after Liston & Sturm 1998), bounded to `[−1, 0]` as in SnowTran-3D (no deposition);
//! - `Nu = Sh = 1.79 + 0.606 Re^0.5` (I.14), `Re = 2 r̄ V / ν` (I.15), with the ventilation
//!   velocity `V = w̄ + 3 x_r cos(π/4)` in suspension, `w̄ = 1.1e7 r̄^1.8` (I.17),
//!   `x_r = 0.005 u(z)^1.36` (I.18), and `V = 0.68 u* + 2.3 u*t` in saltation (I.16);
//! - the solar radiation absorbed by a particle `S_p = π r̄_r² (1 − αp)(1 + αs) S_i` (I.19),
//!   `S_i = S* Υ sin ω` (I.20), `sin ω = sin δ sin φ + cos δ cos φ cos τ` (I.21),
//!   `δ = 23.45° cos(2π (d − 173) / d_y)` (I.22) and `Υ = (0.6 + 0.2 sin ω)(1 − 0.5 σc)`
//!   (I.23). The thesis prints `0.6 − 0.2 sin ω`; the transmissivity of Burridge & Gadd that
//!   Liston uses grows with the sun's elevation (shorter path through the air), so the sign
//!   is `+` here. At night (`sin ω ≤ 0`) `S_i = 0`.

use super::ICE_DENSITY;
use snowscape_terrain::solar;
use std::f64::consts::PI;

/// Molecular weight of water `M`, kg kmol⁻¹ (Eq. I.6).
const MOLECULAR_WEIGHT: f64 = 18.01;
/// Universal gas constant `R`, J kmol⁻¹ K⁻¹ (Eq. I.6).
const GAS_CONSTANT: f64 = 8313.0;
/// Thermal conductivity of the atmosphere `λt`, J m⁻¹ s⁻¹ K⁻¹ (Eq. I.6).
const THERMAL_CONDUCTIVITY: f64 = 0.024;
/// Latent heat of sublimation `h_s`, J kg⁻¹ (Eq. I.6).
const LATENT_HEAT: f64 = snowscape_terrain::materials::LATENT_HEAT_SUBLIMATION_J_KG;
/// Gas constant of dry air `R_d`, J K⁻¹ kg⁻¹ (Eq. I.8).
const DRY_AIR_GAS_CONSTANT: f64 = 287.0;
/// Kinematic viscosity of air `ν`, m² s⁻¹ (Eq. I.15; Liston & Sturm 1998: 1.3e-5).
const AIR_VISCOSITY: f64 = 1.3e-5;
/// Albedo of a snow particle `αp` (Eq. I.19).
const PARTICLE_ALBEDO: f64 = 0.5;
/// Albedo of the snow surface `αs` (Eq. I.19).
const SURFACE_ALBEDO: f64 = 0.8;
/// Solar constant `S*`, W m⁻² (Eq. I.20).
const SOLAR_CONSTANT: f64 = 1370.0;

/// Saturation vapour pressure over ice `e_s`, Pa, at `t_k` K (Eq. I.9).
pub fn saturation_vapour_pressure(t_k: f64) -> f64 {
    610.78 * (21.875 * (t_k - 273.16) / (t_k - 7.66)).exp()
}

/// Saturation density of water vapour `ρv`, kg m⁻³, at `t_k` K (Eq. I.8).
pub fn saturation_vapour_density(t_k: f64) -> f64 {
    0.622 * saturation_vapour_pressure(t_k) / (DRY_AIR_GAS_CONSTANT * t_k)
}

/// Diffusivity of water vapour in air `D`, m² s⁻¹, at `t_k` K (Eq. I.7).
pub fn vapour_diffusivity(t_k: f64) -> f64 {
    2.06e-5 * (t_k / 273.0).powf(1.75)
}

/// Undersaturation `σ(z)` with respect to ice at height `z` m, for a relative humidity
/// `rh` (fraction) observed at `z_rh` m (Eqs. I.11-I.13), bounded to `[−1, 0]`.
pub fn undersaturation(z: f64, rh: f64, z_rh: f64) -> f64 {
    let gamma = 1.0 - 0.027 * z_rh.ln();
    ((rh - 1.0) * (gamma + 0.027 * z.ln())).clamp(-1.0, 0.0)
}

/// Sine of the solar elevation `sin ω` (Eq. I.21) on day `day` of the year, latitude and hour
/// angle in degrees, with the declination of Eq. I.22 (the cosine about the June solstice:
/// [`snowscape_terrain::solar`], the one solar geometry of every crate).
pub fn sin_solar_elevation(latitude_deg: f64, day: f64, hour_angle_deg: f64) -> f64 {
    let d = solar::declination_at(day, solar::DeclinationModel::Cosine);
    solar::sin_elevation(latitude_deg, d, hour_angle_deg.to_radians())
}

/// Solar radiation reaching the surface `S_i`, W m⁻² (Eqs. I.20, I.23), for a sun at
/// `sin ω` and a cloud cover fraction `cloud`.
pub fn surface_irradiance(sin_elevation: f64, cloud: f64) -> f64 {
    if sin_elevation <= 0.0 {
        return 0.0;
    }
    let transmissivity = (0.6 + 0.2 * sin_elevation) * (1.0 - 0.5 * cloud);
    SOLAR_CONSTANT * transmissivity * sin_elevation
}

/// The air around the blowing snow, fixed for one weather period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Atmosphere {
    /// Air temperature `T_a`, K.
    pub t_k: f64,
    /// Relative humidity at `z_rh`, fraction.
    pub rh: f64,
    /// Height of the humidity observation `z_rh`, m.
    pub z_rh: f64,
    /// Solar radiation at the surface `S_i`, W m⁻².
    pub irradiance: f64,
}

/// Mean particle radius `r̄_r(z)`, m (Eq. I.4).
pub fn mean_particle_radius(z: f64) -> f64 {
    4.6e-5 * z.powf(-0.258)
}

/// Mean particle mass `m̄(z)`, kg (Eqs. I.3-I.5).
pub fn mean_particle_mass(z: f64) -> f64 {
    let r = mean_particle_radius(z);
    let alpha = 4.08 + 12.6 * z;
    4.0 / 3.0 * PI * ICE_DENSITY * r * r * r * (1.0 + 3.0 / alpha + 2.0 / (alpha * alpha))
}

/// Radius of a particle of mass `m`, m (Eq. I.10).
pub fn mass_radius(m: f64) -> f64 {
    (3.0 * m / (4.0 * PI * ICE_DENSITY)).cbrt()
}

/// Ventilation velocity in the suspension layer `V_t`, m s⁻¹ (Eqs. I.16-I.18), for
/// particles of radius `r` in a wind `u_z`.
pub fn suspension_ventilation(r: f64, u_z: f64) -> f64 {
    let fall = 1.1e7 * r.powf(1.8);
    let fluctuation = 0.005 * u_z.max(0.0).powf(1.36);
    fall + 3.0 * fluctuation * (PI / 4.0).cos()
}

/// Ventilation velocity in the saltation layer `V_s = 0.68 u* + 2.3 u*t`, m s⁻¹ (Eq. I.16).
pub fn saltation_ventilation(u_star: f64, u_star_t: f64) -> f64 {
    0.68 * u_star + 2.3 * u_star_t
}

/// Loss-rate coefficient `ψ`, s⁻¹ (Eqs. I.2, I.6), of particles at height `z` m ventilated
/// at `ventilation` m s⁻¹ (from [`suspension_ventilation`] or [`saltation_ventilation`]).
pub fn loss_rate_coefficient(z: f64, ventilation: f64, atm: &Atmosphere) -> f64 {
    let mass = mean_particle_mass(z);
    let r = mass_radius(mass);
    let r_r = mean_particle_radius(z);
    let sigma = undersaturation(z, atm.rh, atm.z_rh);
    let reynolds = 2.0 * r * ventilation / AIR_VISCOSITY;
    let nusselt = 1.79 + 0.606 * reynolds.sqrt(); // = Sherwood (I.14)
    let t = atm.t_k;
    let absorbed =
        PI * r_r * r_r * (1.0 - PARTICLE_ALBEDO) * (1.0 + SURFACE_ALBEDO) * atm.irradiance;
    let k = LATENT_HEAT * MOLECULAR_WEIGHT / (GAS_CONSTANT * t) - 1.0;
    let conduction = THERMAL_CONDUCTIVITY * t * nusselt;
    let top = 2.0 * PI * r * sigma - absorbed / conduction * k;
    let bottom = LATENT_HEAT / conduction * k
        + 1.0 / (vapour_diffusivity(t) * saturation_vapour_density(t) * nusselt);
    top / bottom / mass
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn saturation_vapour_matches_hand_values() {
        // T = 263.16 K: e_s = 610.78 exp(21.875 · (−10) / 255.5) = 610.78 · 0.424782 = 259.452 Pa
        //   ρv = 0.622 · 259.452 / (287 · 263.16) = 2.13671e-3 kg/m³
        // T = 253.16 K: e_s = 102.787 Pa, ρv = 8.79938e-4; T = 273.16 K: e_s = 610.78 Pa.
        assert!((saturation_vapour_pressure(263.16) - 259.452).abs() < 1e-3);
        assert!((saturation_vapour_density(263.16) - 2.136_71e-3).abs() < 1e-8);
        assert!((saturation_vapour_pressure(253.16) - 102.787).abs() < 1e-3);
        assert!((saturation_vapour_density(253.16) - 8.799_38e-4).abs() < 1e-9);
        assert_eq!(saturation_vapour_pressure(273.16), 610.78);
    }

    #[test]
    fn solar_radiation_matches_hand_values() {
        // 1 January (d = 1) at 45.5° N, τ = −35° (Table 6.I), 15 % cloud:
        // δ = 23.45° cos(2π (1 − 173)/365.25) = −23.0594°
        // sin ω = sin δ sin φ + cos δ cos φ cos τ = −0.279370 + 0.528276 = 0.248907;
        // Υ = (0.6 + 0.2 · 0.248907)(1 − 0.075) = 0.601048;
        // S_i = 1370 · 0.601048 · 0.248907 = 204.959 W/m².
        let d = solar::declination_at(1.0, solar::DeclinationModel::Cosine).to_degrees();
        assert!((d + 23.0594).abs() < 1e-3, "{d}");
        let s = sin_solar_elevation(45.5, 1.0, -35.0);
        assert!((s - 0.248_907).abs() < 1e-5, "{s}");
        let si = surface_irradiance(s, 0.15);
        assert!((si - 204.959).abs() < 0.01, "{si}");
        assert_eq!(surface_irradiance(-0.1, 0.0), 0.0);
    }

    fn atmosphere(irradiance: f64, rh: f64) -> Atmosphere {
        Atmosphere {
            t_k: 263.15,
            rh,
            z_rh: 2.0,
            irradiance,
        }
    }

    #[test]
    fn loss_rate_matches_hand_computation() {
        // Suspension at z = 0.5 m in an 8 m/s wind, −10 °C (263.15 K), RH 40 % at 2 m, dark:
        // r̄_r = 4.6e-5 · 0.5^−0.258 = 5.50077e-5 m; α = 10.38; m̄ = 8.35982e-10 kg;
        // r̄ = 6.01515e-5 m; σ = −0.6 (1 − 0.027 ln 2 + 0.027 ln 0.5) = −0.577542;
        // V = 1.1e7 r̄^1.8 + 3 · 0.005 · 8^1.36 · cos(π/4) = 0.457376 m/s;
        // Re = 4.23259, Nu = Sh = 3.03674; D = 1.93169e-5 m²/s; e_s = 259.221 Pa,
        // ρv = 2.13489e-3 kg/m³; h_s M/(R T) − 1 = 22.3650;
        // dm/dt = 2π r̄ σ / (h_s/(λ T Nu) · 22.365 + 1/(D ρv Sh)) = −1.93260e-11 kg/s;
        // ψ = −1.93260e-11 / 8.35982e-10 = −0.0231177 s⁻¹.
        let atm = atmosphere(0.0, 0.4);
        let r = mass_radius(mean_particle_mass(0.5));
        let v = suspension_ventilation(r, 8.0);
        assert!((v - 0.457_376).abs() < 1e-6, "{v}");
        let psi = loss_rate_coefficient(0.5, v, &atm);
        assert!((psi + 0.023_117_7).abs() < 1e-7, "{psi}");
        // With S_i = 300 W/m²: S_p = 2.56662e-6 W, dm/dt = −1.95910e-11, ψ = −0.0234347.
        let psi_sun = loss_rate_coefficient(0.5, v, &atmosphere(300.0, 0.4));
        assert!((psi_sun + 0.023_434_7).abs() < 1e-7, "{psi_sun}");
        // Saltation at z = 0.01 m, u* = 0.5, u*t = 0.25: V = 0.915, Re = 25.9692,
        // Nu = 4.87817, dm/dt = −8.47650e-11, m̄ = 2.41162e-8, ψ = −3.51486e-3 s⁻¹.
        let vs = saltation_ventilation(0.5, 0.25);
        let psi_s = loss_rate_coefficient(0.01, vs, &atm);
        assert!((psi_s + 3.514_86e-3).abs() < 1e-8, "{psi_s}");
        // Saturated air in the dark: no sublimation.
        assert_eq!(loss_rate_coefficient(0.5, v, &atmosphere(0.0, 1.0)), 0.0);
    }
}
