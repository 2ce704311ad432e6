//! Snow state changes (Cordonnier et al. 2018, Section 5.2, after the melt equation).
//!
//! The paper gives the ingredients but not the equations; this module is our design.
//! Per cell and step of `δt` days, in this order:
//!
//! 1. **Powder ageing.** Powder does not stay powder: a share `x/(1+x)` with
//!    `x = k_age · δt` of it bonds into the pack. Of the aged powder, the share `σ` (the
//!    steepness below) becomes unstable snow and the rest stable snow, the same tendency as
//!    the unstable share of new snow in Section 5.1.
//! 2. **Stability exchange.** A rate `r(T)` (1/day) is interpolated linearly in temperature
//!    between `(T_warm, −k_w)`, `(T_cool, +k_c)` and `(T_freeze, 0)`, clamped outside
//!    (`−k_w` above `T_warm`, 0 below `T_freeze`): warm snow becomes unstable, snow near
//!    freezing is cemented by melt-freeze cycles, cold snow does not change. Slope modulates
//!    it as the paper says ("instability increases slower on gentle slopes, stability
//!    increases slower on steeper slopes") through the steepness
//!    `σ = min(1, ‖∇A‖ / tan θ_ref)`: with a floor `m`, destabilisation runs at
//!    `m + (1 − m) σ` of its rate and stabilisation at `m + (1 − m)(1 − σ)`. A positive rate
//!    moves the share `x/(1+x)` of the unstable layer into the stable one, with
//!    `x = r · factor · δt`; a negative rate moves stable snow into the unstable layer.
//! 3. **Compaction.** Stable snow turns into compacted snow under its own overburden. The
//!    load on the middle of the stable layer is `L = P + U + S/2` (m of snow); the share
//!    `x/(1+x)` with `x = k_compaction · L · δt` of the stable layer is compacted. Mass is
//!    kept and volume is not: compacted snow is denser, so a thickness `ΔS` of stable snow
//!    becomes `ΔS · ρ_S/ρ_C` of compacted snow. The lost thickness `ΔS (1 − ρ_S/ρ_C)` is
//!    reported as `densification`, the only volume this step removes.
//!
//! Every transfer is the implicit-Euler share `x/(1+x)` of a first-order law `dX/dt = −k X`:
//! it lies in [0, 1) for any time step, so no layer can go negative, and it matches
//! `1 − e^(−x)` to first order without a per-cell exponential. Layer depths left below
//! [`crate::phenomenon::NEGLIGIBLE_DEPTH_M`] (1e-20 m) are set to 0: shares of shares of a
//! layer would otherwise decay into subnormal floats.

use crate::phenomenon::{
    PhenomenonError, Validity, check_dt, check_map, check_range, fill_surface, row_gradient_norm,
    with_validity,
};
use crate::{VolumeChange, ordered_sum};
use serde::{Deserialize, Serialize};
use snowscape_terrain::{GridGeometry, LayeredTerrain, NodataMask, parallel};

/// Parameters of the snow state changes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct StabilityParams {
    /// Temperature at and above which snow destabilises at the full rate `k_warm`, °C.
    /// Cordonnier 2018 Table 2: T_warm = 5 °C.
    pub t_warm: f64,
    /// Temperature of the fastest stabilisation (melt-freeze cementing), °C.
    /// Cordonnier 2018 Table 2: T_cool = −5 °C.
    pub t_cool: f64,
    /// Temperature at and below which stability no longer changes, °C.
    /// Cordonnier 2018 Table 2: T_freeze = −20 °C.
    pub t_freeze: f64,
    /// Destabilisation rate at `t_warm`, 1/day (share of the stable layer per day).
    /// Chosen here: 0.2 (warm spells load slopes with unstable snow within days). Table 2's
    /// entry for k_w is garbled in the text (a thickness rate of order 1e-4 m/day, which would
    /// change 1 cm of snow per 100 days); we use a share per day instead, so the rate does
    /// not depend on the snow depth.
    pub k_warm: f64,
    /// Stabilisation rate at `t_cool`, 1/day (share of the unstable layer per day).
    /// Chosen here: 0.1 (a week or two of cool weather bonds most unstable snow).
    pub k_cool: f64,
    /// Reference slope at which the steepness `σ` reaches 1, degrees. Chosen here: 45°
    /// (slab avalanches start on 30–45° slopes; above 45° snow barely bonds).
    pub slope_ref_deg: f64,
    /// Floor `m` of the slope factors, in [0, 1]: the fraction of the rate that remains on
    /// flat ground (destabilisation) or at `slope_ref_deg` (stabilisation). Chosen here: 0.1.
    pub min_slope_factor: f64,
    /// Powder ageing rate, 1/day. Chosen here: 0.15 (fresh powder bonds into the pack over
    /// about a week; faster than the diffusion and wind events would leave no powder to move).
    pub k_age: f64,
    /// Compaction rate per metre of overburden, 1/(day·m). Chosen here: 0.005, so the base
    /// of a 2 m snowpack turns about half its stable snow into compacted snow over a
    /// 100-day season.
    pub k_compaction: f64,
    /// Density ratio ρ_stable / ρ_compacted in (0, 1]: thickness of compacted snow per unit
    /// thickness of stable snow compacted. Chosen here: 0.6 (settled snow ≈ 300 kg/m³ into
    /// 500 kg/m³, Table 2's snow density ρ = 0.5 g/cm³). 1 keeps volume.
    pub compacted_density_ratio: f64,
}

impl Default for StabilityParams {
    fn default() -> Self {
        Self {
            t_warm: 5.0,
            t_cool: -5.0,
            t_freeze: -20.0,
            k_warm: 0.2,
            k_cool: 0.1,
            slope_ref_deg: 45.0,
            min_slope_factor: 0.1,
            k_age: 0.15,
            k_compaction: 0.005,
            compacted_density_ratio: 0.6,
        }
    }
}

impl StabilityParams {
    /// Checks ranges: temperatures ordered `t_freeze < t_cool < t_warm`, rates non-negative,
    /// `slope_ref_deg` in (0, 90), `min_slope_factor` in [0, 1], density ratio in (0, 1].
    /// Each temperature lies in [−60, 30] °C and the rates in [0, 10] 1/day (1/(day·m) for
    /// `k_compaction`).
    pub fn validate(&self) -> Result<(), PhenomenonError> {
        const P: &str = "stability";
        for (name, t) in [
            ("t_freeze", self.t_freeze),
            ("t_cool", self.t_cool),
            ("t_warm", self.t_warm),
        ] {
            check_range(P, name, t, [-60.0, 30.0], " °C")?;
        }
        for (name, v) in [
            ("k_warm", self.k_warm),
            ("k_cool", self.k_cool),
            ("k_age", self.k_age),
            ("k_compaction", self.k_compaction),
        ] {
            check_range(P, name, v, [0.0, 10.0], " 1/day")?;
        }
        if self.t_cool <= self.t_freeze || self.t_warm <= self.t_cool {
            return Err(PhenomenonError::InvalidParameter {
                phenomenon: P,
                name: "t_cool",
                value: self.t_cool,
                reason: "temperatures must be strictly ordered t_freeze < t_cool < t_warm",
            });
        }
        let in_range = |v: f64, lo: f64, hi: f64| v.is_finite() && v >= lo && v <= hi;
        for (name, v, lo, hi, ok) in [
            (
                "slope_ref_deg",
                self.slope_ref_deg,
                0.0,
                90.0,
                self.slope_ref_deg > 0.0 && self.slope_ref_deg < 90.0,
            ),
            ("min_slope_factor", self.min_slope_factor, 0.0, 1.0, true),
            (
                "compacted_density_ratio",
                self.compacted_density_ratio,
                0.0,
                1.0,
                self.compacted_density_ratio > 0.0,
            ),
        ] {
            if !(ok && in_range(v, lo, hi)) {
                return Err(PhenomenonError::InvalidParameter {
                    phenomenon: P,
                    name,
                    value: v,
                    reason: "outside its range (see the parameter's documentation)",
                });
            }
        }
        Ok(())
    }

    /// The stability rate `r(T)`, 1/day: positive stabilises, negative destabilises.
    pub fn rate(&self, temperature: f32) -> f32 {
        RateCurve::new(self).at(temperature)
    }
}

/// The piecewise-linear `r(T)` in a branch-free form:
/// `r = k_c (T_c − T_freeze)/(T_cool − T_freeze) + (T_w − T_cool) (−k_w − k_c)/(T_warm − T_cool)`
/// with `T_c = clamp(T, T_freeze, T_cool)` and `T_w = clamp(T, T_cool, T_warm)`. A NaN
/// temperature clamps to a finite rate.
#[derive(Debug, Clone, Copy)]
struct RateCurve {
    t_freeze: f32,
    t_cool: f32,
    t_warm: f32,
    cold_slope: f32,
    warm_slope: f32,
}

impl RateCurve {
    fn new(p: &StabilityParams) -> Self {
        Self {
            t_freeze: p.t_freeze as f32,
            t_cool: p.t_cool as f32,
            t_warm: p.t_warm as f32,
            cold_slope: (p.k_cool / (p.t_cool - p.t_freeze)) as f32,
            warm_slope: ((-p.k_warm - p.k_cool) / (p.t_warm - p.t_cool)) as f32,
        }
    }

    #[inline(always)]
    fn at(&self, t: f32) -> f32 {
        let tc = t.max(self.t_freeze).min(self.t_cool);
        let tw = t.max(self.t_cool).min(self.t_warm);
        (tc - self.t_freeze) * self.cold_slope + (tw - self.t_cool) * self.warm_slope
    }
}

/// Implicit-Euler share of a first-order decay over one step: `x / (1 + x)`, in [0, 1).
#[inline(always)]
pub fn implicit_share(x: f32) -> f32 {
    x / (1.0 + x)
}

/// Volumes moved between layers by one step, m³ of snow.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StabilityReport {
    /// Powder aged into stable snow.
    pub aged_to_stable: f64,
    /// Powder aged into unstable snow.
    pub aged_to_unstable: f64,
    /// Unstable snow turned stable.
    pub stabilised: f64,
    /// Stable snow turned unstable.
    pub destabilised: f64,
    /// Stable snow compacted (thickness before densification).
    pub compacted: f64,
    /// Volume lost to densification: `compacted · (1 − ρ_S/ρ_C)`. Mass is kept.
    pub densification: f64,
}

impl StabilityReport {
    /// The step's volume budget: densification is the only volume removed.
    pub fn volume_change(&self) -> VolumeChange {
        VolumeChange {
            added: 0.0,
            removed: self.densification,
        }
    }
}

/// Reusable buffers of the stability step.
#[derive(Debug, Clone, Default)]
pub struct StabilityScratch {
    surface: Vec<f32>,
}

impl StabilityScratch {
    /// The surface buffer, for the step before [`step_on_filled_surface`] to fill.
    pub(crate) fn surface_to_fill(&mut self) -> &mut Vec<f32> {
        &mut self.surface
    }
}

/// Per-cell constants of one step, precomputed from the parameters.
struct Coefficients {
    rate: RateCurve,
    age_share: f32,
    inv_tan_ref: f32,
    floor: f32,
    dt: f32,
    k_compaction_dt: f32,
    density_ratio: f32,
}

/// Per-thread row buffers of the thicknesses each cell transferred, m.
#[derive(Default)]
struct RowTransfers {
    gradient: Vec<f32>,
    aged_stable: Vec<f32>,
    aged_unstable: Vec<f32>,
    /// Unstable → stable (> 0) or stable → unstable (< 0).
    exchanged: Vec<f32>,
    compacted: Vec<f32>,
}

impl RowTransfers {
    fn new(w: usize) -> Self {
        let z = || vec![0.0f32; w];
        Self {
            gradient: z(),
            aged_stable: z(),
            aged_unstable: z(),
            exchanged: z(),
            compacted: z(),
        }
    }

    /// Row totals in the order of [`StabilityReport`]'s first five fields, m (each a
    /// [`crate::row_sum`]; the exchange split into its two directions in place).
    fn sums(&self) -> [f64; 5] {
        let stabilised = crate::row_sum_by(&self.exchanged, |e| e.max(0.0));
        let destabilised = crate::row_sum_by(&self.exchanged, |e| (-e).max(0.0));
        [
            crate::row_sum(&self.aged_stable),
            crate::row_sum(&self.aged_unstable),
            stabilised,
            destabilised,
            crate::row_sum(&self.compacted),
        ]
    }
}

/// Applies the three transfers to one row of cells (branch-free, so it vectorises: AVX2 where
/// the CPU has it, the same bits as SSE since Rust does not fuse multiply-adds) and records
/// them in `out`. Nodata cells hold no snow and a zero gradient, so every transfer there is a
/// share of nothing: they need no test (and a NaN temperature clamps to a finite rate).
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn row_update(
    k: &Coefficients,
    [c, s, u, p]: [&mut [f32]; 4],
    temp: &[f32],
    out: &mut RowTransfers,
) {
    let w = temp.len();
    let (c, s, u, p) = (&mut c[..w], &mut s[..w], &mut u[..w], &mut p[..w]);
    let grad = &out.gradient[..w];
    let aged_stable = &mut out.aged_stable[..w];
    let aged_unstable = &mut out.aged_unstable[..w];
    let exchanged = &mut out.exchanged[..w];
    let compacted = &mut out.compacted[..w];
    for i in 0..w {
        let steep = (grad[i] * k.inv_tan_ref).min(1.0);
        // 1. Powder ageing.
        let aged = p[i] * k.age_share;
        let aged_u = aged * steep;
        let aged_s = aged - aged_u;
        p[i] -= aged;
        u[i] += aged_u;
        s[i] += aged_s;
        // 2. Stability exchange (one of the two shares is zero).
        let rate = k.rate.at(temp[i]);
        let x_stab = rate.max(0.0) * (k.floor + (1.0 - k.floor) * (1.0 - steep)) * k.dt;
        let x_destab = (-rate).max(0.0) * (k.floor + (1.0 - k.floor) * steep) * k.dt;
        let e = u[i] * implicit_share(x_stab) - s[i] * implicit_share(x_destab);
        u[i] -= e;
        s[i] += e;
        // 3. Compaction under the overburden.
        let load = p[i] + u[i] + 0.5 * s[i];
        let d = s[i] * implicit_share(k.k_compaction_dt * load);
        s[i] -= d;
        c[i] += d * k.density_ratio;
        use crate::phenomenon::flush_negligible as f;
        (c[i], s[i], u[i], p[i]) = (f(c[i]), f(s[i]), f(u[i]), f(p[i]));
        aged_stable[i] = aged_s;
        aged_unstable[i] = aged_u;
        exchanged[i] = e;
        compacted[i] = d;
    }
}

/// Ages powder, exchanges stable and unstable snow and compacts stable snow over `dt_days`,
/// at the per-cell air temperature `temperature` (°C).
pub fn step(
    params: &StabilityParams,
    terrain: &mut LayeredTerrain,
    temperature: &[f32],
    scratch: &mut StabilityScratch,
    dt_days: f64,
) -> Result<StabilityReport, PhenomenonError> {
    params.validate()?;
    check_dt(dt_days)?;
    check_map("temperature", temperature, terrain.geometry())?;
    fill_surface(terrain, &mut scratch.surface);
    step_on_filled_surface(params, terrain, temperature, scratch, dt_days)
}

/// [`step`] on the surface already in `scratch` ([`StabilityScratch::surface_to_fill`]),
/// which must be `bedrock + Σ layers` of `terrain` as it is now, cell by cell (the enhanced
/// melt fills it: [`crate::melt::enhanced::step_filling_surface`]).
pub(crate) fn step_on_filled_surface(
    params: &StabilityParams,
    terrain: &mut LayeredTerrain,
    temperature: &[f32],
    scratch: &mut StabilityScratch,
    dt_days: f64,
) -> Result<StabilityReport, PhenomenonError> {
    params.validate()?;
    check_dt(dt_days)?;
    let geometry = terrain.geometry().clone();
    check_map("temperature", temperature, &geometry)?;
    debug_assert!({
        let mut fresh = Vec::new();
        fill_surface(terrain, &mut fresh);
        fresh
            .iter()
            .map(|v| v.to_bits())
            .eq(scratch.surface.iter().map(|v| v.to_bits()))
    });
    let mask = terrain.mask().clone();
    let k = Coefficients {
        rate: RateCurve::new(params),
        age_share: implicit_share((params.k_age * dt_days) as f32),
        inv_tan_ref: (1.0 / params.slope_ref_deg.to_radians().tan()) as f32,
        floor: params.min_slope_factor as f32,
        dt: dt_days as f32,
        k_compaction_dt: (params.k_compaction * dt_days) as f32,
        density_ratio: params.compacted_density_ratio as f32,
    };
    let rows = with_validity!(mask, |valid| run_rows(
        &k,
        terrain,
        &scratch.surface,
        temperature,
        &geometry,
        &mask,
        valid
    ));
    let area = geometry.cell_area();
    let total = |f: usize| ordered_sum(&rows.iter().map(|r| r[f]).collect::<Vec<_>>()) * area;
    let compacted = total(4);
    Ok(StabilityReport {
        aged_to_stable: total(0),
        aged_to_unstable: total(1),
        stabilised: total(2),
        destabilised: total(3),
        compacted,
        densification: compacted * (1.0 - k.density_ratio as f64),
    })
}

fn run_rows<V: Validity>(
    k: &Coefficients,
    terrain: &mut LayeredTerrain,
    surf: &[f32],
    temperature: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    valid: &V,
) -> Vec<[f64; 5]> {
    let w = geometry.width();
    let [compacted, stable, unstable, powder] = &mut terrain.snow;
    parallel::map_rows_with(
        w,
        (compacted, stable, unstable, powder, temperature),
        || RowTransfers::new(w),
        |buf, row, (c, s, u, p, t)| {
            // Without stable, unstable or powder snow nothing ages, exchanges or compacts:
            // skip the row (bit-identical: every transfer would be an exact 0).
            let idle = |layer: &[f32]| layer.iter().all(|&v| v == 0.0);
            if idle(s) && idle(u) && idle(p) {
                return [0.0; 5];
            }
            row_gradient_norm(surf, geometry, mask, valid, row, &mut buf.gradient);
            row_update(k, [c, s, u, p], t, buf);
            buf.sums()
        },
    )
}

#[cfg(test)]
mod tests;
