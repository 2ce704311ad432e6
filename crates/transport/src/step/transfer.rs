//! Passes 3 and 4 of [`super::step`], fused: each cell's suspension, sublimation and melt
//! (5.40-5.48) and its outflows scaled so it never sends more than it holds, then the
//! update of every cell from its own outflows and what its four neighbours send it, plus
//! snowfall and border inflow, with the density of 5.18-5.22.
//!
//! Rayon works on blocks of rows. A block computes the outflows of its rows and of the row
//! on either side of it (those rows are recomputed by the neighbouring blocks too, from the
//! same state, to the same bits) into a three-row ring, and updates each row once its
//! southern neighbour's outflows are known. The new state goes to separate buffers, so
//! every outflow reads the state at the start of the step.

use super::cells::Context;
use super::{MAX_DENSITY, ShearCells, SnowState};
use crate::float_ops::{at_least, at_most};
use multiversion::multiversion;
use rayon::prelude::*;

/// Rows per rayon task.
const BLOCK_ROWS: usize = 32;

/// What the cells of one row send and lose in the step, kg m⁻², after the positivity
/// limiter, one array per quantity so the loops over them vectorise.
#[derive(Debug, Clone, Default)]
struct Outflows {
    /// Sent east (positive) or west (negative).
    send_x: Vec<f32>,
    /// Sent north (positive) or south (negative).
    send_y: Vec<f32>,
    /// Everything leaving the cell: both sends, sublimation and melt.
    lost: Vec<f32>,
    /// Lost to sublimation.
    sublimation: Vec<f32>,
    /// Lost to melt.
    melt: Vec<f32>,
}

impl Outflows {
    fn new(w: usize) -> Self {
        let row = vec![0.0; w];
        Self {
            send_x: row.clone(),
            send_y: row.clone(),
            lost: row.clone(),
            sublimation: row.clone(),
            melt: row,
        }
    }
}

/// Budget of one row, kg m⁻² summed over its cells in column order.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct RowBudget {
    pub precipitation: f64,
    pub border_in: f64,
    pub border_out: f64,
    pub sublimation: f64,
    pub melt: f64,
    pub transported: f64,
    /// Stored snow at the start and at the end of the step.
    pub initial_mass: f64,
    pub final_mass: f64,
    pub non_finite: Option<(usize, usize, f32)>,
}

/// The saltation fluxes of the step, kg m⁻¹ s⁻¹.
#[derive(Debug, Clone, Copy)]
pub(super) struct Saltation<'a> {
    pub shear: ShearCells<'a>,
    pub q_x: &'a [f32],
    pub q_y: &'a [f32],
}

/// The per-cell results published in [`super::StepScratch`]: saltation and suspension
/// flux magnitudes, sublimation rate.
pub(super) struct Blowing<'a> {
    pub q_salt: &'a mut [f32],
    pub q_susp: &'a mut [f32],
    pub q_subl: &'a mut [f32],
}

/// The rows a block works in: the three-row ring of outflows and the update's rows.
struct Rows {
    ring: [Outflows; 3],
    /// Sent outflows of the missing row beyond the northern or southern border.
    none: Vec<f32>,
    /// Snowfall, received mass, kept and drifted mass of the row being updated.
    snowfall: Vec<f32>,
    gain: Vec<f32>,
    kept: Vec<f32>,
    drifted: Vec<f32>,
    /// The published results (saltation, suspension, sublimation) of a row outside the
    /// block, whose outflows alone the block needs.
    halo: Vec<f32>,
}

impl Rows {
    fn new(w: usize) -> Self {
        let row = vec![0.0f32; w];
        Self {
            ring: [0, 1, 2].map(|_| Outflows::new(w)),
            none: row.clone(),
            snowfall: row.clone(),
            gain: row.clone(),
            kept: row.clone(),
            drifted: row,
            halo: vec![0.0; 3 * w],
        }
    }

    /// The outflows of row `k`, outside the block, into the ring.
    fn halo_row(&mut self, ctx: &Context, state: &SnowState, salt: Saltation, k: usize) {
        let w = ctx.width;
        let [a, b, c] = [0, 1, 2].map(|j| j * w..(j + 1) * w);
        let [sa, su, sb] = self
            .halo
            .get_disjoint_mut([a, b, c])
            .expect("disjoint rows");
        outflow_row(ctx, state, salt, k, &mut self.ring[k % 3], [sa, su, sb]);
    }
}

/// Passes 3 and 4: writes the state at the end of the step into `next` (water equivalent,
/// density) and returns the budget of each row, in row order.
pub(super) fn transfer_pass(
    ctx: &Context,
    state: &SnowState,
    salt: Saltation,
    blowing: Blowing,
    (next_swe, next_rho): (&mut [f32], &mut [f32]),
) -> Vec<RowBudget> {
    let (w, h) = (ctx.width, ctx.height);
    let block = BLOCK_ROWS * w;
    let blocks: Vec<Vec<RowBudget>> = next_swe
        .par_chunks_mut(block)
        .zip(next_rho.par_chunks_mut(block))
        .zip(blowing.q_salt.par_chunks_mut(block))
        .zip(blowing.q_susp.par_chunks_mut(block))
        .zip(blowing.q_subl.par_chunks_mut(block))
        .enumerate()
        // Row buffers are reused by the blocks a rayon task runs in turn; every row of
        // them is written before it is read.
        .map_init(
            || Rows::new(w),
            |rows, (b, ((((swe, rho), q_salt), q_susp), q_subl))| {
                let r0 = b * BLOCK_ROWS;
                let r1 = r0 + swe.len() / w;
                if r0 > 0 {
                    rows.halo_row(ctx, state, salt, r0 - 1);
                }
                // Cells of row `k` in the block's chunks.
                let local = |k: usize| (k - r0) * w..(k - r0 + 1) * w;
                let own = [
                    &mut q_salt[local(r0)],
                    &mut q_susp[local(r0)],
                    &mut q_subl[local(r0)],
                ];
                let mut budget = outflow_row(ctx, state, salt, r0, &mut rows.ring[r0 % 3], own);
                let mut budgets = Vec::with_capacity(r1 - r0);
                for r in r0..r1 {
                    let k = r + 1;
                    let mut next_budget = RowBudget::default();
                    if k < r1 {
                        let own = [
                            &mut q_salt[local(k)],
                            &mut q_susp[local(k)],
                            &mut q_subl[local(k)],
                        ];
                        next_budget = outflow_row(ctx, state, salt, k, &mut rows.ring[k % 3], own);
                    } else if k < h {
                        rows.halo_row(ctx, state, salt, k);
                    }
                    let next = (&mut swe[local(r)], &mut rho[local(r)]);
                    update_row(ctx, state, salt.shear, rows, r, next, &mut budget);
                    budgets.push(budget);
                    budget = next_budget;
                }
                budgets
            },
        )
        .collect();
    blocks.into_iter().flatten().collect()
}

/// The outflows of row `r` into `out`, and its saltation flux magnitude, suspension flux
/// and sublimation rate into `blowing`; returns the row's budget of sublimation, melt and
/// transport. Short loops: the table lookups apart, so the processor overlaps many cells,
/// the limiter branch-free so it vectorises, the sums in column order.
#[multiversion(targets("x86_64+avx2"))]
fn outflow_row(
    ctx: &Context,
    state: &SnowState,
    salt: Saltation,
    r: usize,
    out: &mut Outflows,
    blowing: [&mut [f32]; 3],
) -> RowBudget {
    let [q_salt, q_susp, q_subl] = blowing;
    let w = ctx.width;
    let on = ctx.params.phenomena;
    let holding = ctx.params.vegetation_snow_depth_m as f32;
    let saltation = if on.saltation { 1.0 } else { 0.0 };
    let (step_x, step_y) = (ctx.dt * ctx.inv_dx, ctx.dt * ctx.inv_dy);
    let cells = r * w..(r + 1) * w;
    let shear = salt.shear.cells(cells.clone());
    let (q_x, q_y) = (&salt.q_x[cells.clone()], &salt.q_y[cells.clone()]);
    let (u_star, u_star_t) = (&shear.u_star[..w], &shear.u_star_t[..w]);
    let (q_max, q_x, q_y) = (&shear.q_max_per_speed[..w], &q_x[..w], &q_y[..w]);
    let (q_salt, q_susp, q_subl) = (&mut q_salt[..w], &mut q_susp[..w], &mut q_subl[..w]);
    for c in 0..w {
        let flux = (q_x[c] * q_x[c] + q_y[c] * q_y[c]).sqrt();
        let (mut susp, mut subl) = (0.0f32, 0.0f32);
        if q_max[c] > 0.0 && flux > 0.0 {
            let per_up = flux / (2.8 * u_star_t[c]); // φr h* = Qsalt / u_p (5.44-5.45)
            let (s, v) = ctx.blowing_table.per_flux(u_star[c], u_star_t[c]);
            susp = per_up * s;
            subl = at_most(per_up * v, 0.0);
        }
        (q_salt[c], q_susp[c], q_subl[c]) = (flux, susp, subl);
    }
    let (wind_u, wind_v) = (
        &ctx.scene.wind_u[cells.clone()],
        &ctx.scene.wind_v[cells.clone()],
    );
    let (swe, density) = (&state.swe[cells.clone()], &state.density[cells]);
    let (q_susp, q_subl) = (&q_susp[..w], &q_subl[..w]);
    let Outflows {
        send_x,
        send_y,
        lost,
        sublimation,
        melt,
    } = out;
    let (send_x, send_y, lost) = (&mut send_x[..w], &mut send_y[..w], &mut lost[..w]);
    let (sublimation, melt) = (&mut sublimation[..w], &mut melt[..w]);
    let (suspension, sublimates) = (on.suspension, on.sublimation);
    for c in 0..w {
        let (speed, u, v) = (shear.speed[c], wind_u[c], wind_v[c]);
        let (susp_x, susp_y) = if suspension && speed > 0.0 {
            (q_susp[c] * u / speed, q_susp[c] * v / speed)
        } else {
            (0.0, 0.0)
        };
        let ox = step_x * (saltation * q_x[c] + susp_x);
        let oy = step_y * (saltation * q_y[c] + susp_y);
        let subl = if sublimates { -ctx.dt * q_subl[c] } else { 0.0 };
        let wanted = ox.abs() + oy.abs() + subl;
        let (mass, rho) = (swe[c], density[c]);
        let erodible = at_least(mass - holding * rho, 0.0);
        let scale = if wanted > erodible {
            erodible / wanted
        } else {
            1.0
        };
        let left = at_least(mass - scale * wanted, 0.0);
        (send_x[c], send_y[c]) = (scale * ox, scale * oy);
        sublimation[c] = scale * subl;
        melt[c] = at_most(ctx.melt_rate * rho * ctx.dt, left);
        lost[c] = send_x[c].abs() + send_y[c].abs() + sublimation[c] + melt[c];
    }
    let mut b = RowBudget::default();
    for c in 0..w {
        b.sublimation += f64::from(sublimation[c]);
        b.melt += f64::from(melt[c]);
        b.transported += f64::from(send_x[c].abs() + send_y[c].abs());
    }
    b
}

/// What a cell receives from its four neighbours' sends (0 where a neighbour is missing).
#[inline]
fn received(west: f32, east: f32, north: f32, south: f32) -> f32 {
    let mut gain = 0.0f32;
    gain += if west > 0.0 { west } else { 0.0 };
    gain -= if east < 0.0 { east } else { 0.0 };
    gain -= if north < 0.0 { north } else { 0.0 };
    gain + if south > 0.0 { south } else { 0.0 }
}

/// Updates row `r` from the outflows of rows `r − 1 ..= r + 1` in `rows.ring` into `next`
/// and completes its budget `b`: the mass first, branch-free over the row, then what
/// enters or leaves across the grid border in the border cells, then the density, in a
/// loop of its own for its table lookups and divisions.
#[multiversion(targets("x86_64+avx2"))]
fn update_row(
    ctx: &Context,
    state: &SnowState,
    shear: ShearCells,
    rows: &mut Rows,
    r: usize,
    next: (&mut [f32], &mut [f32]),
    b: &mut RowBudget,
) {
    let (next_swe, next_rho) = next;
    let (w, h) = (ctx.width, ctx.height);
    let on = ctx.params.phenomena;
    let border_inflow = ctx.params.saturated_inflow && on.saltation;
    let scene = ctx.scene;
    let Rows {
        ring,
        none,
        snowfall,
        gain,
        kept,
        drifted,
        ..
    } = rows;
    let row = &ring[r % 3];
    // The sends of the rows to the north (r − 1) and to the south (r + 1).
    let north = if r > 0 {
        &ring[(r - 1) % 3].send_y
    } else {
        &*none
    };
    let south = if r + 1 < h {
        &ring[(r + 1) % 3].send_y
    } else {
        &*none
    };
    let cells = r * w..(r + 1) * w;
    let shear = shear.cells(cells.clone());
    let (wind_u, wind_v) = (&scene.wind_u[cells.clone()], &scene.wind_v[cells.clone()]);
    let (swe, density) = (&state.swe[cells.clone()], &state.density[cells.clone()]);
    let (send_x, send_y, lost) = (&row.send_x[..w], &row.send_y[..w], &row.lost[..w]);
    let (north, south) = (&north[..w], &south[..w]);
    let (snowfall, gain) = (&mut snowfall[..w], &mut gain[..w]);
    let (kept, drifted, next_swe) = (&mut kept[..w], &mut drifted[..w], &mut next_swe[..w]);
    match scene.precipitation_ratio {
        Some(p) => {
            for (f, &p) in snowfall.iter_mut().zip(&p[cells]) {
                *f = ctx.snowfall * at_least(p, 0.0);
            }
        }
        None => snowfall.fill(ctx.snowfall),
    }
    for c in 1..w.saturating_sub(1) {
        gain[c] = received(send_x[c - 1], send_x[c + 1], north[c], south[c]);
    }
    let east = |c: usize| if c + 1 < w { send_x[c + 1] } else { 0.0 };
    gain[0] = received(0.0, east(0), north[0], south[0]);
    if w > 1 {
        gain[w - 1] = received(send_x[w - 2], 0.0, north[w - 1], south[w - 1]);
    }
    for c in 0..w {
        kept[c] = at_least(swe[c] - lost[c], 0.0);
        drifted[c] = gain[c];
        next_swe[c] = kept[c] + drifted[c] + snowfall[c];
    }
    // Border inflow at saturation and border outflow: only border cells have any, so
    // summing them alone in column order gives the sums over the row.
    let border_row = r == 0 || r + 1 == h;
    let border_cells = (0..w).filter(|&c| border_row || c == 0 || c + 1 == w);
    for c in border_cells {
        let (u, v, speed) = (wind_u[c], wind_v[c], shear.speed[c]);
        let mut inflow = 0.0f32;
        if border_inflow && speed > 0.0 {
            let cap = shear.q_max_per_speed[c] * ctx.dt;
            let edge_x = (c == 0 && u > 0.0) || (c + 1 == w && u < 0.0);
            let edge_y = (r + 1 == h && v > 0.0) || (r == 0 && v < 0.0);
            if edge_x {
                inflow += cap * u.abs() * ctx.inv_dx;
            }
            if edge_y {
                inflow += cap * v.abs() * ctx.inv_dy;
            }
        }
        let (sx, sy) = (send_x[c], send_y[c]);
        let mut leaving = 0.0f32;
        if (c + 1 == w && sx > 0.0) || (c == 0 && sx < 0.0) {
            leaving += sx.abs();
        }
        if (r == 0 && sy > 0.0) || (r + 1 == h && sy < 0.0) {
            leaving += sy.abs();
        }
        drifted[c] = gain[c] + inflow;
        next_swe[c] = kept[c] + drifted[c] + snowfall[c];
        b.border_in += f64::from(inflow);
        b.border_out += f64::from(leaving);
    }
    for c in 0..w {
        let new_mass = next_swe[c];
        if !new_mass.is_finite() && b.non_finite.is_none() {
            b.non_finite = Some((c, r, new_mass));
        }
        b.precipitation += f64::from(snowfall[c]);
        b.initial_mass += f64::from(swe[c]);
        b.final_mass += f64::from(new_mass);
    }
    let rho_drift_floor = ctx.rates.new_snow.at(super::DRIFT_PACKING_WIND as f32);
    for c in 0..w {
        let (kept, drifted, snowfall) = (kept[c], drifted[c], snowfall[c]);
        let (rho, new_mass) = (density[c], next_swe[c]);
        // The new-snow and densification wind tables share their sampling.
        let wind = ctx.rates.new_snow.axis().locate(shear.speed[c]);
        let mut new_rho = rho;
        if drifted > 0.0 || snowfall > 0.0 {
            let rho_fall = ctx.rates.new_snow.at_point(wind);
            let rho_drift = at_least(rho_fall, rho_drift_floor);
            let volume = kept / rho + drifted / rho_drift + snowfall / rho_fall;
            if volume > 0.0 {
                new_rho = new_mass / volume;
            }
        }
        if ctx.densify && new_mass > 0.0 && new_rho < MAX_DENSITY {
            let rate =
                ctx.rates.densify_wind.at_point(wind) * ctx.rates.densify_density.at(new_rho);
            new_rho = at_most(new_rho + ctx.dt * rate, MAX_DENSITY);
        }
        next_rho[c] = new_rho;
    }
}
