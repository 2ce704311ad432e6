//! One explicit step of the snow mass balance (Jubert 2018, Section 5.5, Eqs. 5.16-5.17):
//!
//! `d(ρs ζ)/dt = ρw P − ∇·(Qsalt + Qsusp) + Qsubl − ρs M`
//!
//! integrated by forward Euler over `Δt` (5.17), per cell, in mass per area (kg m⁻²).
//! The order follows Section 5.5: threshold `u*t` from the density (5.18-5.25), surface
//! shear `u*` (5.26-5.36), saltation capacity and the fetch-limited flux along the wind
//! (5.37-5.39, [`sweep`]), suspension and sublimation from the saltation layer
//! (5.40-5.47, Annex I), degree-day melt (5.48).
//!
//! **Divergence.** The thesis takes central differences of the fluxes (6.2). Here the flux
//! each cell sends downwind is exactly what its downwind neighbour receives (an upwind,
//! flux-form scheme, as SnowTran-3D does), so transport conserves mass to rounding. Flux
//! blown across the grid border leaves the domain and is reported; saturated inflow
//! (`saturated_inflow`) enters at upwind borders and is reported too.
//!
//! **Positivity.** A cell cannot send more snow than it holds: its wind-driven losses
//! (transport out and sublimation) are scaled by `min(1, erodible / wanted)`, where the
//! erodible mass is the snow above the vegetation's holding depth `C_v` (5.27), and melt by
//! what is left. Receivers read the scaled amounts, so the scheme stays conservative and no
//! cell goes negative, whatever `Δt`.
//!
//! **Density.** Kept snow keeps its density; snowfall arrives at the new-snow density
//! (5.18-5.20) and drifted snow at the wind-packed density of 5.19-5.20 for a wind of at
//! least 5 m s⁻¹ (chosen here: drifted grains are broken and pack densely). Without
//! snowfall the snow densifies by 5.21-5.22, capped at 550 kg m⁻³ (SnowModel's cap).
//!
//! **Parallelism.** Every pass computes each cell from the previous state or from its
//! upwind chain, and budgets are summed per row then in row order: results are
//! bit-identical for any number of threads.
//!
//! **Vector units.** The per-row kernels are compiled for the x86-64 baseline and for AVX2,
//! chosen at run time ([`multiversion`]); their loops are written branch-free over
//! structure-of-arrays maps so that they vectorise. Neither version contracts multiplies
//! and adds, so both give the same bits on any processor.

mod sweep;

use crate::error::TransportError;
use crate::params::{TransportParams, Weather};
use crate::physics::WATER_DENSITY;
use crate::physics::melt::melt_rate;
use crate::physics::shear::ShearSite;
use crate::tables::Tables;
use crate::terrain_wind::check_len;
use rayon::prelude::*;
use snowscape_terrain::GridGeometry;
use sweep::Sweep;

/// Highest density reached by densification, kg m⁻³ (SnowModel's `ro_snowmax`).
pub const MAX_DENSITY: f32 = 550.0;
/// Lowest density drifted snow lands at: new snow packed by a 5 m s⁻¹ wind (Eq. 5.19).
const DRIFT_PACKING_WIND: f64 = 5.0;

/// The snow cover: water equivalent and density per cell.
#[derive(Debug, Clone, PartialEq)]
pub struct SnowState {
    /// Snow water equivalent `ρs ζ`, kg m⁻².
    pub swe: Vec<f32>,
    /// Snow density `ρs`, kg m⁻³ (kept where there is no snow, for the next snowfall).
    pub density: Vec<f32>,
}

impl SnowState {
    /// No snow, with a nominal density of 100 kg m⁻³.
    pub fn bare(geometry: &GridGeometry) -> Self {
        Self {
            swe: vec![0.0; geometry.len()],
            density: vec![100.0; geometry.len()],
        }
    }

    /// A uniform snow cover of `depth` m at `density` kg m⁻³.
    pub fn uniform(geometry: &GridGeometry, depth: f32, density: f32) -> Self {
        Self {
            swe: vec![depth * density; geometry.len()],
            density: vec![density; geometry.len()],
        }
    }

    /// Snow depth `ζ`, m, per cell.
    pub fn depth(&self) -> Vec<f32> {
        self.swe
            .iter()
            .zip(&self.density)
            .map(|(m, r)| if *r > 0.0 { m / r } else { 0.0 })
            .collect()
    }

    /// Total snow mass over the grid, kg.
    pub fn total_mass(&self, geometry: &GridGeometry) -> f64 {
        let rows: Vec<f64> = self
            .swe
            .par_chunks(geometry.width())
            .map(|r| r.iter().map(|&m| f64::from(m)).sum())
            .collect();
        rows.iter().sum::<f64>() * geometry.cell_area()
    }
}

/// The maps a step reads: the wind at `z_r` (after Section 5.4) and the precipitation ratio
/// map of Chapter 4 (1 everywhere when absent).
#[derive(Debug, Clone, Copy)]
pub struct SceneMaps<'a> {
    /// Grid of every map.
    pub geometry: &'a GridGeometry,
    /// Wind towards the east at `z_r`, m s⁻¹.
    pub wind_u: &'a [f32],
    /// Wind towards the north at `z_r`, m s⁻¹.
    pub wind_v: &'a [f32],
    /// Share of the mean snowfall each cell receives (Section 6.4), or `None` for uniform.
    pub precipitation_ratio: Option<&'a [f32]>,
}

/// The mass budget of one step or a run, kg (Eq. 5.16 integrated over the grid).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct MassBudget {
    /// Snowfall `ρw P` received.
    pub precipitation_in: f64,
    /// Saltation entering through upwind borders (`saturated_inflow`).
    pub border_in: f64,
    /// Saltation and suspension blown out of the grid.
    pub border_out: f64,
    /// Snow lost to sublimation of blowing snow (`−Qsubl`).
    pub sublimation_out: f64,
    /// Snow lost to melt.
    pub melt_out: f64,
    /// Snow moved between cells by saltation and suspension (sent downwind).
    pub transported: f64,
    /// Stored snow at the start (`initial` in a report).
    #[serde(rename = "initial")]
    pub initial_mass: f64,
    /// Stored snow at the end (`final` in a report).
    #[serde(rename = "final")]
    pub final_mass: f64,
    /// `final − initial − (in − out)`: rounding only.
    pub closure_error: f64,
}

impl MassBudget {
    /// Appends a later budget (a following step).
    pub fn accumulate(&mut self, later: &MassBudget) {
        if self.initial_mass == 0.0 && self.final_mass == 0.0 && self.precipitation_in == 0.0 {
            self.initial_mass = later.initial_mass;
        }
        self.precipitation_in += later.precipitation_in;
        self.border_in += later.border_in;
        self.border_out += later.border_out;
        self.sublimation_out += later.sublimation_out;
        self.melt_out += later.melt_out;
        self.transported += later.transported;
        self.final_mass = later.final_mass;
        self.closure_error = self.final_mass
            - self.initial_mass
            - (self.precipitation_in + self.border_in
                - self.border_out
                - self.sublimation_out
                - self.melt_out);
    }
}

/// Per-cell results of the last step, plus reusable buffers.
#[derive(Debug, Clone, Default)]
pub struct StepScratch {
    tables: Tables,
    rates: Option<cells::CellRates>,
    shear: ShearMaps,
    q_x: Vec<f32>,
    q_y: Vec<f32>,
    /// The state at the end of the step, swapped into the [`SnowState`].
    next_swe: Vec<f32>,
    next_density: Vec<f32>,
    /// Saltation flux magnitude of the last step, kg m⁻¹ s⁻¹.
    pub q_salt: Vec<f32>,
    /// Suspension flux magnitude of the last step, kg m⁻¹ s⁻¹.
    pub q_susp: Vec<f32>,
    /// Sublimation rate of the last step, kg m⁻² s⁻¹ (≤ 0, Eq. 5.47).
    pub q_subl: Vec<f32>,
}

/// Shear state of every cell in the current step, one map per quantity, so that each pass
/// reads only what it uses and its loops vectorise.
#[derive(Debug, Clone, Default)]
pub(crate) struct ShearMaps {
    /// Wind speed `W` at `z_r`, m s⁻¹.
    pub speed: Vec<f32>,
    /// Friction velocity `u*`, m s⁻¹.
    pub u_star: Vec<f32>,
    /// Threshold friction velocity `u*t`, m s⁻¹.
    pub u_star_t: Vec<f32>,
    /// Saltation capacity magnitude per unit wind speed, `Qs_max / W`, kg m⁻² (0 where no
    /// saltation): the capacity along an axis is this times the wind component.
    pub q_max_per_speed: Vec<f32>,
}

impl ShearMaps {
    fn resize(&mut self, n: usize) {
        for v in [
            &mut self.speed,
            &mut self.u_star,
            &mut self.u_star_t,
            &mut self.q_max_per_speed,
        ] {
            resize(v, n);
        }
    }

    /// Every map over all cells.
    pub(crate) fn all(&self) -> ShearCells<'_> {
        ShearCells {
            speed: &self.speed,
            u_star: &self.u_star,
            u_star_t: &self.u_star_t,
            q_max_per_speed: &self.q_max_per_speed,
        }
    }
}

/// The [`ShearMaps`] over a run of cells.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ShearCells<'a> {
    pub speed: &'a [f32],
    pub u_star: &'a [f32],
    pub u_star_t: &'a [f32],
    pub q_max_per_speed: &'a [f32],
}

impl<'a> ShearCells<'a> {
    /// The cells `range` of these.
    pub(crate) fn cells(&self, range: std::ops::Range<usize>) -> ShearCells<'a> {
        ShearCells {
            speed: &self.speed[range.clone()],
            u_star: &self.u_star[range.clone()],
            u_star_t: &self.u_star_t[range.clone()],
            q_max_per_speed: &self.q_max_per_speed[range],
        }
    }
}

/// Sizes a buffer; every pass overwrites all its cells, so no clearing is needed.
fn resize<T: Copy + Default>(v: &mut Vec<T>, n: usize) {
    if v.len() != n {
        v.clear();
        v.resize(n, T::default());
    }
}

mod cells;
mod transfer;

/// Advances the snow cover by `dt_s` seconds under `weather` (Eqs. 5.16-5.17).
pub fn step(
    params: &TransportParams,
    weather: &Weather,
    scene: &SceneMaps,
    state: &mut SnowState,
    scratch: &mut StepScratch,
    dt_s: f64,
) -> Result<MassBudget, TransportError> {
    params.validate()?;
    weather.validate()?;
    if !(dt_s.is_finite() && dt_s >= 0.0) {
        return Err(TransportError::InvalidTimeStep { dt_s });
    }
    let g = scene.geometry;
    check_len("wind_u", scene.wind_u, g)?;
    check_len("wind_v", scene.wind_v, g)?;
    check_len("swe", &state.swe, g)?;
    check_len("density", &state.density, g)?;
    if let Some(p) = scene.precipitation_ratio {
        check_len("precipitation_ratio", p, g)?;
    }
    let n = g.len();
    scratch.shear.resize(n);
    for v in [
        &mut scratch.next_swe,
        &mut scratch.next_density,
        &mut scratch.q_x,
        &mut scratch.q_y,
        &mut scratch.q_salt,
        &mut scratch.q_susp,
        &mut scratch.q_subl,
    ] {
        resize(v, n);
    }
    let (shear_table, blowing_table) = scratch.tables.update(params, weather);
    let ctx = cells::Context {
        rates: cells::CellRates::update(&mut scratch.rates, weather.air_temperature_k()),
        width: g.width(),
        height: g.height(),
        params,
        scene,
        site: ShearSite {
            z_r: params.reference_height_m,
            z0_snow: params.snow_roughness_m,
            z0_veg: params.vegetation_roughness_m,
            holding_depth: params.vegetation_snow_depth_m,
        },
        shear_table,
        blowing_table,
        dt: dt_s as f32,
        inv_dx: (1.0 / g.cell_size_x()) as f32,
        inv_dy: (1.0 / g.cell_size_y()) as f32,
        melt_rate: if params.phenomena.melt {
            melt_rate(
                params.melt_factor_mm_per_degc_day,
                weather.air_temperature_c,
                params.melt_base_temperature_c,
            ) as f32
        } else {
            0.0
        },
        snowfall: if params.phenomena.precipitation {
            (WATER_DENSITY * weather.precipitation_m_per_s() * dt_s) as f32
        } else {
            0.0
        },
        densify: params.phenomena.densification && weather.precipitation_mm_per_h == 0.0,
        max_wind: shear_table.max_wind() as f32,
    };
    let relax = |d: f64| ((params.fetch_scale * d / params.fetch_m) as f32).min(1.0);
    let along = |d: f64| Sweep {
        relax: relax(d),
        saturated_inflow: params.saturated_inflow,
    };
    // Pass 1: threshold, shear and capacity per cell, and the fetch-limited saltation
    // along x.
    cells::shear_pass(
        &ctx,
        state,
        &along(g.cell_size_x()),
        &mut scratch.shear,
        &mut scratch.q_x,
    );
    // Pass 2: fetch-limited saltation along y.
    let along_y = along(g.cell_size_y());
    sweep::sweep_y(
        &along_y,
        g.width(),
        scratch.shear.all(),
        scene.wind_v,
        &mut scratch.q_y,
    );
    // Passes 3 and 4: suspension, sublimation, melt and the limited outflows; gather the
    // inflows, update mass and density.
    let salt = transfer::Saltation {
        shear: scratch.shear.all(),
        q_x: &scratch.q_x,
        q_y: &scratch.q_y,
    };
    let blowing = transfer::Blowing {
        q_salt: &mut scratch.q_salt,
        q_susp: &mut scratch.q_susp,
        q_subl: &mut scratch.q_subl,
    };
    let next = (&mut scratch.next_swe[..], &mut scratch.next_density[..]);
    let rows = transfer::transfer_pass(&ctx, state, salt, blowing, next);
    std::mem::swap(&mut state.swe, &mut scratch.next_swe);
    std::mem::swap(&mut state.density, &mut scratch.next_density);
    let area = g.cell_area();
    let mut budget = MassBudget::default();
    for r in &rows {
        if let Some((col, row, value)) = r.non_finite {
            return Err(TransportError::NonFinite {
                phenomenon: "transport",
                what: "snow water equivalent",
                col,
                row,
                value: f64::from(value),
            });
        }
        budget.precipitation_in += r.precipitation * area;
        budget.border_in += r.border_in * area;
        budget.border_out += r.border_out * area;
        budget.sublimation_out += r.sublimation * area;
        budget.melt_out += r.melt * area;
        budget.transported += r.transported * area;
        budget.initial_mass += r.initial_mass;
        budget.final_mass += r.final_mass;
    }
    // As `SnowState::total_mass`: summed per row, then in row order, then times the area.
    budget.initial_mass *= area;
    budget.final_mass *= area;
    budget.closure_error = budget.final_mass
        - budget.initial_mass
        - (budget.precipitation_in + budget.border_in
            - budget.border_out
            - budget.sublimation_out
            - budget.melt_out);
    Ok(budget)
}

#[cfg(test)]
mod tests;
