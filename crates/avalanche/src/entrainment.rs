//! Entrainment: the flow picks up the snowpack it runs over.
//!
//! **Erosion rate** (AvaFrame com1DFA, "Entrainment", erosion at the bottom; Sovilla et al.
//! 2006): the mass eroded per unit bed area and time is
//!
//! ```text
//! q_ero = τ_b · |u| / e_b        (kg m⁻² s⁻¹)
//! ```
//!
//! with `τ_b` the basal shear stress of the flow (Pa), `|u|` its speed (m/s) and `e_b` the
//! specific erosion energy (J/kg; [`EntrainmentParams::erosion_energy_j_kg`], AvaFrame's
//! `entEroEnergy` = 5000 J/kg). `τ_b = ρ · (τ_b/ρ)` with `ρ` the flow density
//! ([`AvalancheParams::density`]) and `τ_b/ρ` from the run's friction law
//! ([`basal_shear_per_density`]): Coulomb `h (α g tanθc + (1 − α) kv h |u|)`, Voellmy
//! `g h μ + g |u|²/ξ`, samosAT `g h μ (1 + Rs0/(Rs0 + Rs)) + |u|² / (ln(h/R)/κ + B)²` with
//! `Rs = |u|²/(g h)` (the shallow forms, whatever `slope_gravity` says).
//!
//! **What erodes.** The eroded mass is taken from the top of the column down, each layer at
//! its own density ([`snowscape_terrain::SnowLayer::default_density_kg_m3`]): powder and
//! unstable snow in full, then stable snow, at most [`EntrainmentParams::stable_depth_m`] of
//! it per cell and avalanche (AvaFrame's default entrainable thickness, 0.3 m); the compacted
//! layer never erodes. Taking stable snow lowers the flow's bed by as much as it raises the
//! flow, so the surface does not jump; powder and unstable snow lie above the bed, and the flow
//! ploughs into them. The flowing thickness grows by the depth taken (the volume convention of
//! [`crate::convert::release`]).
//!
//! **Momentum.** The entrained snow starts at rest: the cell's momentum `h·v` is kept, so
//! the pipes touching it are slowed by `h / (h + Δh)` (a pipe between two entraining cells
//! by both factors). AvaFrame's extra breaking and deformation resistances
//! (`entShearResistance`, `entDefResistance`) default to 0 there and are left out here.
//!
//! **Numerics and cost.** The erosion is applied after each record interval of the run (an
//! operator split, explicit in time, with the speed at the end of the interval), over the
//! cells holding flowing snow only, in row-major order: deterministic, and the cost follows
//! the flow. Flows thinner than [`EntrainmentParams::min_flow_thickness_m`] do not erode.

use crate::convert::take_from_top;
use crate::flow::{AvalancheError, AvalancheParams, AvalancheState, FrictionLaw, G};
use serde::{Deserialize, Serialize};
use snowscape_terrain::{LayeredTerrain, SnowLayer};

/// Parameters of entrainment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct EntrainmentParams {
    /// Whether the flow entrains the snowpack it runs over. Default true.
    pub enabled: bool,
    /// Specific erosion energy `e_b`, J/kg, in [1, 1e7]. Default 5000: AvaFrame com1DFA's
    /// `entEroEnergy`.
    pub erosion_energy_j_kg: f64,
    /// Deepest stable snow one avalanche erodes from a cell, m, in [0, 100] (powder and unstable
    /// snow erode in full; compacted snow never). Default 0.3 m: AvaFrame com1DFA's
    /// entrainment thickness `entThIfMissingInShp`.
    pub stable_depth_m: f64,
    /// Thinnest flow that erodes, m, in [0, 100]. Default 0.01 m: AvaFrame's footprint threshold
    /// (thinner films are the flow's fringe).
    pub min_flow_thickness_m: f64,
}

impl Default for EntrainmentParams {
    fn default() -> Self {
        Self {
            enabled: true,
            erosion_energy_j_kg: 5000.0,
            stable_depth_m: 0.3,
            min_flow_thickness_m: 0.01,
        }
    }
}

impl EntrainmentParams {
    /// Checks every field, naming the offending one.
    pub fn validate(&self) -> Result<(), AvalancheError> {
        for (name, v, lo, hi, expected) in [
            (
                "entrainment.erosion_energy_j_kg",
                self.erosion_energy_j_kg,
                1.0,
                1e7,
                "in [1, 1e7] J/kg",
            ),
            (
                "entrainment.stable_depth_m",
                self.stable_depth_m,
                0.0,
                100.0,
                "in [0, 100] m",
            ),
            (
                "entrainment.min_flow_thickness_m",
                self.min_flow_thickness_m,
                0.0,
                100.0,
                "in [0, 100] m",
            ),
        ] {
            if !(v.is_finite() && v >= lo && v <= hi) {
                return Err(AvalancheError::InvalidParameter {
                    name,
                    value: v,
                    expected,
                });
            }
        }
        Ok(())
    }
}

/// Basal shear stress per unit flow density `τ_b/ρ`, m²/s², of a flow `h` metres thick moving
/// at `speed` m/s under the run's friction law (module documentation).
pub fn basal_shear_per_density(params: &AvalancheParams, h: f64, speed: f64) -> f64 {
    BasalShear::new(params).per_density(h, speed)
}

/// [`basal_shear_per_density`] with the law's constants worked out once per call of
/// [`entrain`].
enum BasalShear {
    /// `α g tanθc` and `(1 − α) kv`.
    Coulomb {
        dry: f64,
        viscous: f64,
    },
    /// `g μ` and `g / ξ`.
    Voellmy {
        dry: f64,
        turbulent: f64,
    },
    SamosAt(crate::flow::SamosAtParams),
}

impl BasalShear {
    fn new(params: &AvalancheParams) -> Self {
        Self::at_cell(params, None, None)
    }

    /// The law with a cell's μ and ξ from the friction maps (`None`: the law's own).
    fn at_cell(params: &AvalancheParams, mu: Option<f64>, xi: Option<f64>) -> Self {
        match params.friction {
            FrictionLaw::Coulomb => Self::Coulomb {
                dry: params.alpha
                    * G
                    * mu.unwrap_or_else(|| params.rest_angle_deg.to_radians().tan()),
                viscous: (1.0 - params.alpha) * params.k_viscous,
            },
            FrictionLaw::Voellmy => Self::Voellmy {
                dry: G * mu.unwrap_or(params.voellmy_mu),
                turbulent: G / xi.unwrap_or(params.voellmy_xi_m_s2),
            },
            FrictionLaw::SamosAt => Self::SamosAt(crate::flow::SamosAtParams {
                mu: mu.unwrap_or(params.samos_at.mu),
                ..params.samos_at
            }),
        }
    }

    #[inline]
    fn per_density(&self, h: f64, speed: f64) -> f64 {
        let h = h.max(0.0);
        match self {
            Self::Coulomb { dry, viscous } => h * (dry + viscous * h * speed),
            Self::Voellmy { dry, turbulent } => dry * h + turbulent * speed * speed,
            Self::SamosAt(s) => {
                let rs = if h > 0.0 {
                    speed * speed / (G * h)
                } else {
                    f64::INFINITY
                };
                let dry = G * h * s.mu * (1.0 + s.rs0 / (s.rs0 + rs));
                let div = (h / s.roughness_m).max(1.0).ln() / s.kappa + s.b;
                dry + speed * speed / (div * div)
            }
        }
    }
}

/// Per-cell sums of one run's entrainment (grid-sized, row-major), m.
pub(crate) struct EntrainedMaps<'a> {
    /// Depth taken from each cell, all layers.
    pub(crate) total: &'a mut [f64],
    /// Of which stable snow (bounded by `stable_depth_m`).
    pub(crate) stable: &'a mut [f64],
}

/// Erodes the snowpack under the flowing snow of `state` for `dt` seconds (module
/// documentation); returns the volume entrained, m³.
pub(crate) fn entrain(
    params: &AvalancheParams,
    state: &mut AvalancheState,
    terrain: &mut LayeredTerrain,
    maps: EntrainedMaps,
    dt: f64,
) -> f64 {
    let p = &params.entrainment;
    if !p.enabled || dt.is_nan() || dt <= 0.0 {
        return 0.0;
    }
    let w = terrain.geometry().width();
    let area = terrain.geometry().cell_area();
    let mass_per_shear = params.density * dt / p.erosion_energy_j_kg;
    let shear = BasalShear::new(params);
    let mut volume = 0.0;
    for t in 0..state.occupied_tiles() {
        let Some((r0, r1, c0, c1)) = state.content_cells_of(t) else {
            continue;
        };
        for r in r0..=r1 {
            for c in c0..=c1 {
                let k = state.pad(c, r);
                let h = state.h[k];
                if h.is_nan() || h <= p.min_flow_thickness_m {
                    continue;
                }
                let i = r * w + c;
                let stable_left = (p.stable_depth_m - maps.stable[i]).max(0.0);
                // A bare or already scoured column has nothing to give (most of a flow's wet
                // cells after its front has passed).
                let [_, st, u, pw] = &terrain.snow;
                if pw[i] <= 0.0 && u[i] <= 0.0 && (st[i] <= 0.0 || stable_left <= 0.0) {
                    continue;
                }
                let [vx, vy] = state.velocity_at(c, r);
                let speed = vx.hypot(vy);
                if speed.is_nan() || speed <= 0.0 {
                    continue;
                }
                let tau = if state.has_friction_maps() {
                    let at = |m: &[f64]| (!m.is_empty()).then(|| m[k]);
                    BasalShear::at_cell(params, at(&state.mu), at(&state.xi)).per_density(h, speed)
                } else {
                    shear.per_density(h, speed)
                };
                let mut mass = mass_per_shear * tau * speed;
                let taken = take_from_top(terrain, i, |layer, have, _| {
                    if mass.is_nan() || mass <= 0.0 {
                        return 0.0;
                    }
                    let erodible = match layer {
                        SnowLayer::Powder | SnowLayer::Unstable => have,
                        SnowLayer::Stable => have.min(stable_left),
                        SnowLayer::Compacted => 0.0,
                    };
                    let rho = layer.default_density_kg_m3();
                    let depth = (mass / rho).min(erodible);
                    mass -= depth * rho;
                    depth
                });
                if taken.total <= 0.0 {
                    continue;
                }
                maps.total[i] += taken.total;
                maps.stable[i] += taken.from_bed;
                state.bed[k] -= taken.from_bed;
                state.h[k] = h + taken.total;
                state.slow_pipes_around(k, h / (h + taken.total));
                volume += taken.total * area;
            }
        }
    }
    volume
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flow::FrictionLaw;

    #[test]
    fn basal_shear_follows_each_law() {
        let mut p = AvalancheParams::paper();
        // Coulomb, dry: g h tanθc.
        let tan30 = 30f64.to_radians().tan();
        assert!((basal_shear_per_density(&p, 2.0, 10.0) - G * 2.0 * tan30).abs() < 1e-12);
        p.friction = FrictionLaw::Voellmy;
        let v = G * 2.0 * 0.155 + G * 100.0 / 4000.0;
        assert!((basal_shear_per_density(&p, 2.0, 10.0) - v).abs() < 1e-12);
        p.friction = FrictionLaw::SamosAt;
        let s = p.samos_at;
        let rs = 100.0 / (G * 2.0);
        let div = (2.0f64 / s.roughness_m).ln() / s.kappa + s.b;
        let v = G * 2.0 * s.mu * (1.0 + s.rs0 / (s.rs0 + rs)) + 100.0 / (div * div);
        assert!((basal_shear_per_density(&p, 2.0, 10.0) - v).abs() < 1e-12);
        // A flow at rest on no depth has no shear.
        assert_eq!(basal_shear_per_density(&p, 0.0, 0.0), 0.0);
    }

    #[test]
    fn out_of_range_parameters_are_named() {
        for (f, name) in [
            (
                (|p: &mut EntrainmentParams| p.erosion_energy_j_kg = 0.0)
                    as fn(&mut EntrainmentParams),
                "entrainment.erosion_energy_j_kg",
            ),
            (
                |p: &mut EntrainmentParams| p.stable_depth_m = f64::NAN,
                "entrainment.stable_depth_m",
            ),
            (
                |p: &mut EntrainmentParams| p.min_flow_thickness_m = 1e9,
                "entrainment.min_flow_thickness_m",
            ),
        ] {
            let mut p = EntrainmentParams::default();
            f(&mut p);
            match p.validate() {
                Err(AvalancheError::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
                other => panic!("{name}: {other:?}"),
            }
        }
        assert!(EntrainmentParams::default().validate().is_ok());
    }
}
