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
use super::{MAX_DENSITY, Shear, SnowState};
use rayon::prelude::*;

/// Rows per rayon task.
const BLOCK_ROWS: usize = 32;

/// What a cell sends and loses in the step, kg m⁻², after the positivity limiter.
#[derive(Debug, Clone, Copy, Default)]
struct Outflow {
    /// Sent east (positive) or west (negative).
    send_x: f32,
    /// Sent north (positive) or south (negative).
    send_y: f32,
    /// Lost to sublimation.
    sublimation: f32,
    /// Lost to melt.
    melt: f32,
}

/// Budget of one row, kg m⁻² summed over its cells.
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
    pub shear: &'a [Shear],
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
        .map(|(b, ((((swe, rho), q_salt), q_susp), q_subl))| {
            let r0 = b * BLOCK_ROWS;
            let r1 = r0 + swe.len() / w;
            let mut ring = vec![Outflow::default(); 3 * w];
            let slot = |r: usize| (r % 3) * w..(r % 3 + 1) * w;
            // The published results of the rows on either side go to `halo`.
            let mut halo = vec![0.0f32; 3 * w];
            let mut halo_row = |ring: &mut [Outflow], k: usize| {
                let [a, b, c] = [0, 1, 2].map(|j| j * w..(j + 1) * w);
                let [sa, su, sb] = halo.get_disjoint_mut([a, b, c]).expect("disjoint rows");
                outflow_row(ctx, state, salt, k, &mut ring[slot(k)], [sa, su, sb]);
            };
            if r0 > 0 {
                halo_row(&mut ring, r0 - 1);
            }
            // Cells of row `k` in the block's chunks.
            let local = |k: usize| (k - r0) * w..(k - r0 + 1) * w;
            let own = [
                &mut q_salt[local(r0)],
                &mut q_susp[local(r0)],
                &mut q_subl[local(r0)],
            ];
            outflow_row(ctx, state, salt, r0, &mut ring[slot(r0)], own);
            let mut gathered = vec![0.0f32; 2 * w];
            let mut rows = Vec::with_capacity(r1 - r0);
            for r in r0..r1 {
                let k = r + 1;
                if k < r1 {
                    let own = [
                        &mut q_salt[local(k)],
                        &mut q_susp[local(k)],
                        &mut q_subl[local(k)],
                    ];
                    outflow_row(ctx, state, salt, k, &mut ring[slot(k)], own);
                } else if k < h {
                    halo_row(&mut ring, k);
                }
                let next = (&mut swe[local(r)], &mut rho[local(r)]);
                let g = &mut gathered;
                rows.push(update_row(ctx, state, salt.shear, &ring, r, next, g));
            }
            rows
        })
        .collect();
    blocks.into_iter().flatten().collect()
}

/// The outflows of row `r` into `out`, and its saltation flux magnitude, suspension flux
/// and sublimation rate into `blowing`. Two loops with short bodies, so the processor
/// overlaps the table lookups of many cells.
fn outflow_row(
    ctx: &Context,
    state: &SnowState,
    salt: Saltation,
    r: usize,
    out: &mut [Outflow],
    [q_salt, q_susp, q_subl]: [&mut [f32]; 3],
) {
    let w = ctx.width;
    let on = ctx.params.phenomena;
    let holding = ctx.params.vegetation_snow_depth_m as f32;
    let saltation = if on.saltation { 1.0 } else { 0.0 };
    let (step_x, step_y) = (ctx.dt * ctx.inv_dx, ctx.dt * ctx.inv_dy);
    let cells = r * w..(r + 1) * w;
    let (shear, q_x, q_y) = (
        &salt.shear[cells.clone()],
        &salt.q_x[cells.clone()],
        &salt.q_y[cells.clone()],
    );
    let blowing = q_salt
        .iter_mut()
        .zip(q_susp.iter_mut())
        .zip(q_subl.iter_mut());
    for (((sa, su, sb), s), (&q_x, &q_y)) in blowing
        .map(|((a, b), c)| (a, b, c))
        .zip(shear)
        .zip(q_x.iter().zip(q_y))
    {
        let q_salt = (q_x * q_x + q_y * q_y).sqrt();
        let (mut q_susp, mut q_subl) = (0.0f32, 0.0f32);
        if s.q_max > 0.0 && q_salt > 0.0 {
            let per_up = q_salt / (2.8 * s.u_star_t); // φr h* = Qsalt / u_p (5.44-5.45)
            let (susp, subl) = ctx.blowing_table.per_flux(s.u_star, s.u_star_t);
            q_susp = per_up * susp;
            q_subl = (per_up * subl).min(0.0);
        }
        (*sa, *su, *sb) = (q_salt, q_susp, q_subl);
    }
    let inputs = shear
        .iter()
        .zip(q_x.iter().zip(q_y))
        .zip(q_susp.iter().zip(q_subl.iter()))
        .zip(
            ctx.scene.wind_u[cells.clone()]
                .iter()
                .zip(&ctx.scene.wind_v[cells.clone()]),
        )
        .zip(state.swe[cells.clone()].iter().zip(&state.density[cells]));
    for (o, ((((s, (&q_x, &q_y)), (&q_susp, &q_subl)), (&u, &v)), (&mass, &rho))) in
        out.iter_mut().zip(inputs)
    {
        let (susp_x, susp_y) = if on.suspension && s.speed > 0.0 {
            (q_susp * u / s.speed, q_susp * v / s.speed)
        } else {
            (0.0, 0.0)
        };
        let ox = step_x * (saltation * q_x + susp_x);
        let oy = step_y * (saltation * q_y + susp_y);
        let subl = if on.sublimation {
            -ctx.dt * q_subl
        } else {
            0.0
        };
        let wanted = ox.abs() + oy.abs() + subl;
        let erodible = (mass - holding * rho).max(0.0);
        let scale = if wanted > erodible {
            erodible / wanted
        } else {
            1.0
        };
        let left = (mass - scale * wanted).max(0.0);
        *o = Outflow {
            send_x: scale * ox,
            send_y: scale * oy,
            sublimation: scale * subl,
            melt: (ctx.melt_rate * rho * ctx.dt).min(left),
        };
    }
}

/// Updates row `r` from the outflows of rows `r − 1 ..= r + 1` in `ring` into `next`: the
/// mass first, keeping the kept and drifted masses in `gathered` (two rows), then the
/// density, in a loop of its own for its table lookups and divisions.
fn update_row(
    ctx: &Context,
    state: &SnowState,
    shear: &[Shear],
    ring: &[Outflow],
    r: usize,
    (next_swe, next_rho): (&mut [f32], &mut [f32]),
    gathered: &mut [f32],
) -> RowBudget {
    let (w, h) = (ctx.width, ctx.height);
    let on = ctx.params.phenomena;
    let border_inflow = ctx.params.saturated_inflow && on.saltation;
    let scene = ctx.scene;
    let slot = |k: usize| &ring[(k % 3) * w..(k % 3 + 1) * w];
    let row = slot(r);
    // The rows to the north (r − 1) and to the south (r + 1).
    let north = (r > 0).then(|| slot(r - 1));
    let south = (r + 1 < h).then(|| slot(r + 1));
    let cells = r * w..(r + 1) * w;
    let shear = &shear[cells.clone()];
    let (wind_u, wind_v) = (&scene.wind_u[cells.clone()], &scene.wind_v[cells.clone()]);
    let (swe, density) = (&state.swe[cells.clone()], &state.density[cells.clone()]);
    let ratio = scene.precipitation_ratio.map(|p| &p[cells]);
    let snowfall = |c: usize| ctx.snowfall * ratio.map_or(1.0, |p| p[c].max(0.0));
    let (kept_row, drifted_row) = gathered.split_at_mut(w);
    let mut b = RowBudget::default();
    for c in 0..w {
        let (u, v) = (wind_u[c], wind_v[c]);
        let speed = shear[c].speed;
        let o = row[c];
        let out = o.send_x.abs() + o.send_y.abs() + o.sublimation + o.melt;
        let mut gain = 0.0f32;
        if c > 0 && row[c - 1].send_x > 0.0 {
            gain += row[c - 1].send_x;
        }
        if c + 1 < w && row[c + 1].send_x < 0.0 {
            gain -= row[c + 1].send_x;
        }
        if let Some(n) = north
            && n[c].send_y < 0.0
        {
            gain -= n[c].send_y;
        }
        if let Some(s) = south
            && s[c].send_y > 0.0
        {
            gain += s[c].send_y;
        }
        // Border inflow at saturation and border outflow.
        let mut inflow = 0.0f32;
        if border_inflow && speed > 0.0 {
            let cap = shear[c].q_max * ctx.dt / speed;
            let edge_x = (c == 0 && u > 0.0) || (c + 1 == w && u < 0.0);
            let edge_y = (r + 1 == h && v > 0.0) || (r == 0 && v < 0.0);
            if edge_x {
                inflow += cap * u.abs() * ctx.inv_dx;
            }
            if edge_y {
                inflow += cap * v.abs() * ctx.inv_dy;
            }
        }
        let mut leaving = 0.0f32;
        if (c + 1 == w && o.send_x > 0.0) || (c == 0 && o.send_x < 0.0) {
            leaving += o.send_x.abs();
        }
        if (r == 0 && o.send_y > 0.0) || (r + 1 == h && o.send_y < 0.0) {
            leaving += o.send_y.abs();
        }
        let snowfall = snowfall(c);
        let kept = (swe[c] - out).max(0.0);
        let drifted = gain + inflow;
        let new_mass = kept + drifted + snowfall;
        if !new_mass.is_finite() && b.non_finite.is_none() {
            b.non_finite = Some((c, r, new_mass));
        }
        (next_swe[c], kept_row[c], drifted_row[c]) = (new_mass, kept, drifted);
        b.initial_mass += f64::from(swe[c]);
        b.final_mass += f64::from(new_mass);
        b.precipitation += f64::from(snowfall);
        b.border_in += f64::from(inflow);
        b.border_out += f64::from(leaving);
        b.sublimation += f64::from(o.sublimation);
        b.melt += f64::from(o.melt);
        b.transported += f64::from(o.send_x.abs() + o.send_y.abs());
    }
    let rho_drift_floor = ctx.rates.new_snow.at(super::DRIFT_PACKING_WIND as f32);
    for c in 0..w {
        let (kept, drifted, snowfall) = (kept_row[c], drifted_row[c], snowfall(c));
        let (rho, new_mass) = (density[c], next_swe[c]);
        // The new-snow and densification wind tables share their sampling.
        let wind = ctx.rates.new_snow.axis().locate(shear[c].speed);
        let mut new_rho = rho;
        if drifted > 0.0 || snowfall > 0.0 {
            let rho_fall = ctx.rates.new_snow.at_point(wind);
            let rho_drift = rho_fall.max(rho_drift_floor);
            let volume = kept / rho + drifted / rho_drift + snowfall / rho_fall;
            if volume > 0.0 {
                new_rho = new_mass / volume;
            }
        }
        if ctx.densify && new_mass > 0.0 && new_rho < MAX_DENSITY {
            let rate =
                ctx.rates.densify_wind.at_point(wind) * ctx.rates.densify_density.at(new_rho);
            new_rho = (new_rho + ctx.dt * rate).min(MAX_DENSITY);
        }
        next_rho[c] = new_rho;
    }
    b
}
