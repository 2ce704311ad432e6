//! What skiers do to the snow (Cordonnier et al. 2018, Section 6.2, last paragraph): they pack
//! it, and on unstable snow they load it and may release it.
//!
//! **Compaction.** "Once a skier enters a cell it transforms a fixed amount of snow from
//! unstable to stable, or from stable to compacted if no more unstable snow remains." The fixed
//! amount is made independent of the grid: a pass with `L` metres of refined track in a cell of
//! `dx·dy` m² packs the cell-average thickness
//!
//! ```text
//! q = compaction_depth · track_width · L / (dx·dy)
//! ```
//!
//! of loose snow. It is taken from the unstable layer first, `u = min(U, q)`, and the rest from
//! the stable layer as it was before the pass, `s = min(S, q − u)` (one class per pass: snow
//! stabilised by this pass is not compacted by it). **Mass (snow water equivalent) is kept and
//! volume is not**: `u` metres of unstable snow become `u·ρ_U/ρ_S` of stable snow and `s` metres
//! of stable snow become `s·ρ_S/ρ_C` of compacted snow, so `ρ_U·U + ρ_S·S + ρ_C·C` is unchanged
//! and the thickness lost, `u(1 − ρ_U/ρ_S) + s(1 − ρ_S/ρ_C)`, is reported as
//! `densification_m3`. Powder is left alone (the paper's rule names only the unstable, stable
//! and compacted layers; the season ages powder into the pack).
//!
//! **Recent skiers.** Each pass adds 1 to a per-cell count that decays as `exp(−Δt/τ)`,
//! `τ = recent_decay_s`. It is stored as (value, time of last pass) and decayed when read, so
//! keeping it costs nothing per grid cell and step.
//!
//! **Triggers.** A pass with `L` metres of refined track over a cell holding unstable snow
//! `U > 0` whose surface slope is at least `trigger_min_slope_deg` triggers it with probability
//!
//! ```text
//! p10 = min(1, trigger_probability · min(1, U / trigger_unstable_ref_m) · (1 + gain · r))
//! p   = 1 − (1 − p10)^(L / 10 m)
//! ```
//!
//! with `r` the recent-skier count before this pass: `p10` is the probability per 10 m of track
//! (the paper's cell size), and the exponent makes the chance of crossing a slope unharmed
//! independent of the grid resolution. The draw is the keyed uniform
//! `uniform(seed ^ TRIGGER, skier id, pass index) < p`. The unstable depth and slope are read
//! before this pass packs the cell. A triggered cell is reported as a [`TriggerCandidate`] for
//! the season to start an avalanche there; the skier carries on.

use crate::SkiParams;
use serde::{Deserialize, Serialize};
use snowscape_terrain::{LayeredTerrain, SnowLayer};

/// Key purpose of trigger draws.
pub(crate) const TRIGGER: u64 = 0x0054_5249_4747_4552;

/// Snow moved between layers by skiers, m³ of the source layer.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Compaction {
    /// Unstable snow turned into stable snow, m³ (unstable thickness × area).
    pub unstable_to_stable_m3: f64,
    /// Stable snow turned into compacted snow, m³ (stable thickness × area).
    pub stable_to_compacted_m3: f64,
    /// Volume lost to densification, m³ (the only volume the skiers remove; mass is kept).
    pub densification_m3: f64,
}

impl std::ops::AddAssign for Compaction {
    fn add_assign(&mut self, o: Self) {
        self.unstable_to_stable_m3 += o.unstable_to_stable_m3;
        self.stable_to_compacted_m3 += o.stable_to_compacted_m3;
        self.densification_m3 += o.densification_m3;
    }
}

/// Packs the cell-average thickness `amount_m` of loose snow in cell `i` (see the module
/// docs); returns what moved, in m³ for a cell of `cell_area` m².
pub fn compact_cell(
    params: &SkiParams,
    terrain: &mut LayeredTerrain,
    i: usize,
    amount_m: f64,
    cell_area: f64,
) -> Compaction {
    if amount_m <= 0.0 || !terrain.mask().is_valid(i) {
        return Compaction::default();
    }
    let r_us = params.density_unstable_kg_m3 / params.density_stable_kg_m3;
    let r_sc = params.density_stable_kg_m3 / params.density_compacted_kg_m3;
    let unstable = f64::from(terrain.layer(SnowLayer::Unstable)[i]);
    let stable = f64::from(terrain.layer(SnowLayer::Stable)[i]);
    let u = unstable.min(amount_m);
    let s = stable.min(amount_m - u);
    terrain.layer_mut(SnowLayer::Unstable)[i] = (unstable - u).max(0.0) as f32;
    terrain.layer_mut(SnowLayer::Stable)[i] = (stable - s + u * r_us).max(0.0) as f32;
    terrain.layer_mut(SnowLayer::Compacted)[i] += (s * r_sc) as f32;
    Compaction {
        unstable_to_stable_m3: u * cell_area,
        stable_to_compacted_m3: s * cell_area,
        densification_m3: (u * (1.0 - r_us) + s * (1.0 - r_sc)) * cell_area,
    }
}

/// Snow water equivalent of the unstable, stable and compacted layers (the ones skiers
/// change), m³ of water: `Σ (ρ_U·U + ρ_S·S + ρ_C·C) / 1000 · dx·dy` over valid cells.
pub fn snow_water_equivalent(params: &SkiParams, terrain: &LayeredTerrain) -> f64 {
    let (u, s, c) = (
        terrain.layer(SnowLayer::Unstable),
        terrain.layer(SnowLayer::Stable),
        terrain.layer(SnowLayer::Compacted),
    );
    let mask = terrain.mask();
    let sum: f64 = (0..u.len())
        .filter(|&i| mask.is_valid(i))
        .map(|i| {
            params.density_unstable_kg_m3 * f64::from(u[i])
                + params.density_stable_kg_m3 * f64::from(s[i])
                + params.density_compacted_kg_m3 * f64::from(c[i])
        })
        .sum();
    sum / 1000.0 * terrain.geometry().cell_area()
}

/// Track length the trigger probability is given for, m (the paper's 10 m cell).
pub const TRIGGER_REFERENCE_LENGTH_M: f64 = 10.0;

/// The probability that a pass with `length_m` of track triggers the unstable snow of a cell
/// (see the module docs): `unstable_m` of unstable snow, surface slope `slope_rad`, `recent`
/// passes before this one.
pub fn trigger_probability(
    params: &SkiParams,
    unstable_m: f64,
    slope_rad: f64,
    recent: f64,
    length_m: f64,
) -> f64 {
    if unstable_m <= 0.0 || length_m <= 0.0 || slope_rad < params.trigger_min_slope_deg.to_radians()
    {
        return 0.0;
    }
    let load = (unstable_m / params.trigger_unstable_ref_m).min(1.0);
    let p10 =
        (params.trigger_probability * load * (1.0 + params.trigger_recent_gain * recent.max(0.0)))
            .min(1.0);
    if p10 >= 1.0 {
        return 1.0;
    }
    1.0 - (1.0 - p10).powf(length_m / TRIGGER_REFERENCE_LENGTH_M)
}

/// A cell where a skier released unstable snow: where the season may start an avalanche.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TriggerCandidate {
    /// Cell index, row-major.
    pub cell: usize,
    /// Column.
    pub col: usize,
    /// Row.
    pub row: usize,
    /// Map x of the cell centre, CRS units.
    pub x: f64,
    /// Map y of the cell centre, CRS units.
    pub y: f64,
    /// The skier who triggered it.
    pub skier: u64,
    /// Simulation time of the pass, s.
    pub time_s: f64,
    /// The probability the draw was made with.
    pub probability: f64,
    /// Unstable snow in the cell before the pass, m.
    pub unstable_m: f64,
    /// Surface slope of the cell, degrees.
    pub slope_deg: f64,
}

/// The per-cell "recent skier" count, decayed lazily.
#[derive(Debug, Clone, PartialEq)]
pub struct RecentSkiers {
    value: Vec<f32>,
    time: Vec<f32>,
}

impl RecentSkiers {
    /// An empty map over `cells` cells.
    pub fn new(cells: usize) -> Self {
        Self {
            value: vec![0.0; cells],
            time: vec![0.0; cells],
        }
    }
    /// A map from its counts and the times of their last passes (a checkpoint's).
    pub fn from_arrays(value: Vec<f32>, time: Vec<f32>) -> Self {
        Self { value, time }
    }
    /// The counts at their last passes and the times of those passes, s.
    pub fn arrays(&self) -> (&[f32], &[f32]) {
        (&self.value, &self.time)
    }
    /// The decayed count of cell `i` at time `t` (s), with e-folding time `tau` (s).
    #[inline]
    pub fn at(&self, i: usize, t: f64, tau: f64) -> f64 {
        let v = f64::from(self.value[i]);
        if v == 0.0 {
            return 0.0;
        }
        let age = (t - f64::from(self.time[i])).max(0.0);
        v * (-age / tau).exp()
    }
    /// Records a pass through cell `i` at time `t`.
    pub fn record(&mut self, i: usize, t: f64, tau: f64) {
        let v = self.at(i, t, tau) + 1.0;
        self.value[i] = v as f32;
        self.time[i] = t as f32;
    }
    /// The whole map at time `t`.
    pub fn map(&self, t: f64, tau: f64) -> Vec<f32> {
        (0..self.value.len())
            .map(|i| self.at(i, t, tau) as f32)
            .collect()
    }
}
