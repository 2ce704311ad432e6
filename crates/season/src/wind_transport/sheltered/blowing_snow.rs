//! Blowing snow in the Sx drift ([`super`]): how readily settled snow is scoured, and how much
//! of the drifting snow sublimates on its way.
//!
//! **Erodibility of settled snow.** The threshold friction velocity of a snow surface grows
//! with its density, `u*t = 0.10 exp(0.003 ρ)` m/s for `ρ ≤ 300` kg/m³ and
//! `0.005 exp(0.013 ρ)` above (Liston & Sturm 1998, J. Glaciol. 44(148), after Kind 1981;
//! Jubert 2018 Eq. 5.25; `snowscape_transport::physics::shear`): 0.157 m/s for powder
//! (150 kg/m³), 0.246 m/s for stable snow (300 kg/m³) and 3.3 m/s for compacted snow
//! (500 kg/m³, beyond any wind). Grains are entrained at a rate that grows with the excess
//! shear stress `τ − τt ∝ u*² − u*t²` (Anderson & Haff 1991, Acta Mech. Suppl. 1; for snow,
//! Doorschot & Lehning 2002, Boundary-Layer Meteorol. 104), so a wind that scours powder at the
//! rate `e` scours stable snow at `f_S · e`,
//!
//! ```text
//! f_S = max(0, u*² − u*t,S²) / (u*² − u*t,P²)      (0 where u* ≤ u*t,P)
//! ```
//!
//! with `u* = κ |W| / ln(z_r / z0)` the log-profile friction velocity of the cell's wind
//! (`z_r` = 5 m, `z0` = 1 mm: `snowscape_transport::TransportParams`' defaults, Jubert 2018
//! Table 6.I). At 10 m/s `f_S` = 0.82, at 6 m/s 0.35, below 5.2 m/s 0. The scour takes powder
//! first, then unstable snow (the paper's Figure 10, at the powder's rate), then stable snow at
//! `f_S` of what is left of `e`. Without it the season's new snow, which the snowfall lays
//! down as stable snow on all but steep slopes, is out of the wind's reach once it lands, and
//! the redistribution saturates (issue 47: five times the scour rate changed nothing).
//!
//! **Sublimation of the drifting snow.** Particles in transport sublimate at the rate `ψ`
//! (s⁻¹) of Liston & Sturm 1998 (Appendix; Jubert 2018 Annex I,
//! `snowscape_transport::physics::sublimation`), proportional to the air's undersaturation
//! with respect to ice `σ = (RH − 1)(...)`. Per unit area the loss `Q_subl = ψs φs h* +
//! ∫ ψt φt dz` and the flux `Q = Q_salt + Q_susp` (Liston & Sturm 1998 Eqs. 12-14 and 19;
//! `snowscape_transport::physics::suspension`) both scale with the saltation layer's
//! concentration, so
//!
//! ```text
//! λ = −Q_subl / (Q_salt + Q_susp)     (m⁻¹)
//! ```
//!
//! is the share of the drifting load that sublimates per metre it travels, a function of the
//! air temperature, the humidity and `u*` alone. At RH 70 % and 10 m/s, `1/λ` is 450 m at
//! −1 °C, 750 m at −10 °C and 1.6 km at −20 °C, within ±10 % from 6 to 15 m/s (so `λ` is
//! taken at the reference wind speed of the Sx parameters): snow drifting 1 km at −10 °C loses
//! three quarters of itself, and as only part of the snowfall drifts that far, this is of the
//! order of the 15-41 % of the seasonal snowfall that Pomeroy & Gray 1995 (NHRI Sci. Rep. 7)
//! find sublimated over 1 km fetches. The radiation the particles absorb (Eq. I.19) is left out,
//! so saturated air sublimates nothing. Of the load reaching a cell, the share `x / (1 + x)`,
//! `x = λ ℓ` with `ℓ` the sweep's advance along the wind per hop, sublimates (the
//! implicit-Euler share of `dQ/ds = −λ Q`, as the stability module: no exponential per
//! cell), before the cell keeps its share and passes on the rest. `λ` is tabulated from −40
//! to 0 °C by 1 K (once per humidity and wind speed), each step turns the table into shares
//! per hop, and each cell reads it at its air temperature, linearly between the kelvins
//! (colder air takes −40 °C, air above freezing 0 °C). Still air moves no snow
//! and sublimates none. A season gives the step the hour-weighted mean of its climate's
//! humidity over the step (the storm humidity inside snowfall periods, the fair one outside,
//! a station's record where it has one) unless `relative_humidity_pct` is set.

use crate::phenomenon::{PhenomenonError, check_range};
use serde::{Deserialize, Serialize};
use snowscape_terrain::SnowLayer;
use snowscape_transport::TransportParams;
use snowscape_transport::physics::shear::{
    saltating_friction_velocity, saltation_height, threshold_friction_velocity,
};
use snowscape_transport::physics::sublimation::Atmosphere;
use snowscape_transport::physics::suspension::{
    blowing_snow_profile, particle_speed, saltation_layer_loss_rate,
};

/// Parameters of the sublimation of the drifting snow.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct DriftSublimationParams {
    /// Whether the drifting snow sublimates (where the step is given the air temperature).
    /// Default true.
    pub enabled: bool,
    /// Relative humidity of the air at 2 m during wind events, % in [0, 100]. Default none:
    /// a season takes, for each wind step, the hour-weighted mean of its climate's humidity
    /// over the step (`[parameters.climate]` `storm_relative_humidity` in the hours of
    /// snowfall periods, `fair_relative_humidity` outside them, a station forcing's recorded
    /// humidity where it has one); a direct call of the step without one takes
    /// [`FALLBACK_RELATIVE_HUMIDITY_PCT`]. A value here overrides both.
    pub relative_humidity_pct: Option<f64>,
}

/// The humidity of a step called without one and outside a season, %: 70, as
/// `[parameters.snowtran]` (chosen there: a winter mean in the Alps).
pub const FALLBACK_RELATIVE_HUMIDITY_PCT: f64 = 70.0;

impl Default for DriftSublimationParams {
    fn default() -> Self {
        Self {
            enabled: true,
            relative_humidity_pct: None,
        }
    }
}

impl DriftSublimationParams {
    /// Checks the humidity, where given, is a percentage.
    pub fn validate(&self) -> Result<(), PhenomenonError> {
        match self.relative_humidity_pct {
            Some(rh) => check_range(
                "wind transport sx_redistribution sublimation",
                "relative_humidity_pct",
                rh,
                [0.0, 100.0],
                " %",
            ),
            None => Ok(()),
        }
    }

    /// The humidity the step uses, %: the one given, else [`FALLBACK_RELATIVE_HUMIDITY_PCT`].
    pub fn relative_humidity_pct(&self) -> f64 {
        self.relative_humidity_pct
            .unwrap_or(FALLBACK_RELATIVE_HUMIDITY_PCT)
    }
}

/// Coldest air of the `λ` table, °C; it runs by 1 K to 0 °C.
const TABLE_FROM_C: f32 = -40.0;
/// Entries of the table (−40 to 0 °C).
const KELVINS: usize = 41;

/// A value per kelvin from [`TABLE_FROM_C`] to 0 °C, read linearly between the kelvins.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct KelvinTable(pub(super) [f32; KELVINS]);

impl KelvinTable {
    /// The table of `f` at each kelvin.
    pub(super) fn new(f: impl Fn(f64) -> f64) -> Self {
        Self(std::array::from_fn(|k| {
            f(f64::from(TABLE_FROM_C) + k as f64) as f32
        }))
    }

    /// The table with `f` applied to every entry.
    pub(super) fn map(&self, f: impl Fn(f32) -> f32) -> Self {
        Self(self.0.map(f))
    }

    /// The value at the air temperature `t_c` (°C): linear between the kelvins, clamped to
    /// the table's range (NaN reads the coldest entry).
    #[cfg(test)]
    pub(super) fn at(&self, t_c: f32) -> f32 {
        let mut out = [0.0];
        self.read(&[t_c], &mut out);
        out[0]
    }

    /// [`KelvinTable::at`] of every temperature of `t_c` into `out`: the positions in the
    /// table in one straight loop (it vectorises), then the reads.
    pub(super) fn read(&self, t_c: &[f32], out: &mut [f32]) {
        let last = (KELVINS - 1) as f32;
        for (o, &t) in out.iter_mut().zip(t_c) {
            *o = (t - TABLE_FROM_C).max(0.0).min(last);
        }
        let slope: [f32; KELVINS - 1] = std::array::from_fn(|k| self.0[k + 1] - self.0[k]);
        for o in out.iter_mut() {
            let x = *o;
            let i = (x as usize).min(KELVINS - 2);
            *o = self.0[i] + (x - i as f32) * slope[i];
        }
    }
}

/// `λ(T)`, m⁻¹ (module docs), kept while the humidity and the wind speed stay the same.
#[derive(Debug, Clone, Default)]
pub(super) struct SublimationTable {
    cached: Option<([u64; 2], KelvinTable)>,
}

impl SublimationTable {
    /// The table for `rh_pct` and a wind of `speed_m_s` at the reference height.
    pub(super) fn for_air(&mut self, rh_pct: f64, speed_m_s: f64) -> KelvinTable {
        let key = [rh_pct.to_bits(), speed_m_s.to_bits()];
        match self.cached {
            Some((k, table)) if k == key => table,
            _ => {
                let table =
                    KelvinTable::new(|t_c| sublimation_per_metre(t_c, rh_pct / 100.0, speed_m_s));
                self.cached = Some((key, table));
                table
            }
        }
    }
}

/// `λ = −Q_subl / (Q_salt + Q_susp)`, m⁻¹ (module docs), in air at `t_c` °C and relative
/// humidity `rh` (fraction) under a wind of `u_r` m/s at the reference height; 0 where the
/// saltation equations have no solution.
pub fn sublimation_per_metre(t_c: f64, rh: f64, u_r: f64) -> f64 {
    let site = TransportParams::default();
    let Some((u_star, _)) =
        saltating_friction_velocity(u_r, site.reference_height_m, site.snow_roughness_m)
    else {
        return 0.0;
    };
    let u_star_t = threshold_friction_velocity(SnowLayer::Powder.default_density_kg_m3());
    let atm = Atmosphere {
        t_k: t_c + 273.15,
        rh,
        z_rh: site.humidity_height_m,
        irradiance: 0.0,
    };
    let h = saltation_height(u_star);
    let profile = blowing_snow_profile(
        u_star,
        site.settling_velocity,
        site.integration_samples,
        &atm,
    );
    let psi_s = saltation_layer_loss_rate(u_star, u_star_t, &atm);
    let lambda =
        -(psi_s * h + profile.sublimation) / (h * particle_speed(u_star_t) + profile.suspension);
    if lambda.is_finite() {
        lambda.max(0.0)
    } else {
        0.0
    }
}

/// The log-profile friction velocity per m/s of wind at the reference height,
/// `κ / ln(z_r / z0)`, and the squared thresholds of powder and stable snow over it, (m/s)²:
/// the wind speeds² at which each starts to move.
#[derive(Debug, Clone, Copy)]
pub(super) struct StableErodibility {
    powder_threshold2: f32,
    stable_threshold2: f32,
}

impl StableErodibility {
    pub(super) fn new() -> Self {
        let site = TransportParams::default();
        let per_m_s = snowscape_transport::physics::shear::log_profile_friction_velocity(
            1.0,
            site.reference_height_m,
            site.snow_roughness_m,
        );
        let wind_at = |layer: SnowLayer| {
            let u = threshold_friction_velocity(layer.default_density_kg_m3()) / per_m_s;
            (u * u) as f32
        };
        Self {
            powder_threshold2: wind_at(SnowLayer::Powder),
            stable_threshold2: wind_at(SnowLayer::Stable),
        }
    }

    /// `f_S` for a wind speed² `speed2` (m/s)² (module docs).
    #[inline]
    pub(super) fn share(&self, speed2: f32) -> f32 {
        let over_powder = speed2 - self.powder_threshold2;
        if over_powder > 0.0 {
            ((speed2 - self.stable_threshold2).max(0.0) / over_powder).min(1.0)
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_sublimation_in_saturated_air_and_more_in_drier_and_warmer_air() {
        for t in [-30.0, -10.0, -1.0] {
            assert_eq!(sublimation_per_metre(t, 1.0, 10.0), 0.0);
        }
        let dry = sublimation_per_metre(-10.0, 0.5, 10.0);
        let moist = sublimation_per_metre(-10.0, 0.7, 10.0);
        // ψ is proportional to the undersaturation: λ(50 %) / λ(70 %) = 0.5 / 0.3.
        assert!((dry / moist - 0.5 / 0.3).abs() < 1e-6, "{dry} {moist}");
        let warm = sublimation_per_metre(-1.0, 0.7, 10.0);
        let cold = sublimation_per_metre(-20.0, 0.7, 10.0);
        assert!(cold < moist && moist < warm);
        // The e-folding fetch of the module docs: 450 m, 750 m and 1.6 km.
        for (l, lo, hi) in [
            (warm, 400.0, 500.0),
            (moist, 700.0, 800.0),
            (cold, 1500.0, 1700.0),
        ] {
            assert!((lo..hi).contains(&(1.0 / l)), "1/λ = {}", 1.0 / l);
        }
        // Nearly independent of the wind speed.
        for u in [6.0, 8.0, 12.0, 15.0] {
            let r = sublimation_per_metre(-10.0, 0.7, u) / moist;
            assert!((0.85..1.15).contains(&r), "{u} m/s: {r}");
        }
    }

    #[test]
    fn the_table_interpolates_and_clamps() {
        let mut t = SublimationTable::default();
        let table = t.for_air(70.0, 10.0);
        assert_eq!(t.for_air(70.0, 10.0), table);
        let exact = sublimation_per_metre(-10.0, 0.7, 10.0) as f32;
        assert!((table.at(-10.0) - exact).abs() <= 1e-6 * exact);
        let mid = table.at(-10.5);
        assert!(mid > table.at(-11.0) && mid < table.at(-10.0));
        assert_eq!(table.at(0.0), table.0[40]);
        assert_eq!(table.at(12.0), table.0[40]);
        assert_eq!(table.at(-80.0), table.0[0]);
        assert_eq!(table.at(f32::NAN), table.0[0]);
    }

    #[test]
    fn stable_snow_erodes_in_strong_winds_only() {
        let e = StableErodibility::new();
        assert_eq!(e.share(0.0), 0.0);
        assert_eq!(e.share(5.0 * 5.0), 0.0);
        let at10 = e.share(100.0);
        let at6 = e.share(36.0);
        assert!((at10 - 0.82).abs() < 0.01, "{at10}");
        assert!((at6 - 0.35).abs() < 0.01, "{at6}");
        assert!(e.share(1e4) < 1.0 && e.share(1e4) > 0.99);
    }
}
