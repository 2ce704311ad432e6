//! The per-cell passes of [`super::step`]: shear with the x sweep (pass 1), outflows
//! (pass 3) and the gathering update (pass 4).

use super::sweep::{self, Sweep};
use super::{MAX_DENSITY, Outflow, SceneMaps, Shear, SnowState};
use crate::params::TransportParams;
use crate::physics::density::{densification_rate, new_snow_density};
use crate::physics::shear::{ShearSite, threshold_friction_velocity};
use crate::physics::{FREEZING_K, GRAVITY, VON_KARMAN};
use crate::tables::{BlowingSnowTable, ShearTable, Table1};
use rayon::prelude::*;

/// Densities tabulated for `u*t` and densification, kg m⁻³.
const MAX_TABLE_DENSITY: f64 = 1000.0;
/// Winds tabulated for the new-snow density and the densification factor, m s⁻¹.
const MAX_TABLE_WIND: f64 = 80.0;

/// Tables of the cheap but transcendental per-cell formulas, so the passes run on `f32`
/// lookups: `u*t(ρs)` (5.25), new-snow density `ρ(W)` (5.18-5.20) and the densification
/// rate `∂ρs/∂t(ρs, W)` (5.21-5.22) factored as `f(W) · g(ρs)`. They depend on the air
/// temperature alone and are rebuilt when it changes.
#[derive(Debug, Clone)]
pub(super) struct CellRates {
    /// Air temperature the tables were built for, K.
    t_k: f64,
    threshold: Table1,
    new_snow: Table1,
    densify_wind: Table1,
    densify_density: Table1,
}

impl CellRates {
    /// The rates for an air temperature of `t_k` K, rebuilding `cached` if it is stale.
    pub(super) fn update(cached: &mut Option<Self>, t_k: f64) -> &Self {
        if !cached.as_ref().is_some_and(|r| r.t_k == t_k) {
            *cached = Some(Self::new(t_k));
        }
        cached.as_ref().expect("just built")
    }

    fn new(t_k: f64) -> Self {
        let t_snow = t_k.min(FREEZING_K);
        // densification_rate(ρ, W, T) = U(W) · [C A1 ρ e^(−B(Tf−Ts)) e^(−A2 ρ)]:
        // tabulate the two factors (U(W) = rate(ρ = 1, W) / rate(ρ = 1, W = 0)).
        let base = densification_rate(1.0, 0.0, t_snow);
        Self {
            t_k,
            threshold: Table1::new(0.0, MAX_TABLE_DENSITY, 4096, threshold_friction_velocity),
            new_snow: Table1::new(0.0, MAX_TABLE_WIND, 2048, |w| new_snow_density(t_k, w)),
            densify_wind: Table1::new(0.0, MAX_TABLE_WIND, 2048, |w| {
                densification_rate(1.0, w, t_snow) / base
            }),
            densify_density: Table1::new(0.0, MAX_TABLE_DENSITY, 4096, |r| {
                densification_rate(r, 0.0, t_snow)
            }),
        }
    }
}

/// What every pass reads.
pub(super) struct Context<'a> {
    pub rates: &'a CellRates,
    pub width: usize,
    pub height: usize,
    pub params: &'a TransportParams,
    pub scene: &'a SceneMaps<'a>,
    pub site: ShearSite,
    pub shear_table: &'a ShearTable,
    pub blowing_table: &'a BlowingSnowTable,
    pub dt: f32,
    pub inv_dx: f32,
    pub inv_dy: f32,
    /// Melt, m of snow depth per second (0 when switched off).
    pub melt_rate: f32,
    /// Snowfall of the step, kg m⁻² (before the precipitation ratio).
    pub snowfall: f32,
    pub densify: bool,
    pub max_wind: f32,
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
    pub non_finite: Option<(usize, usize, f32)>,
}

/// Pass 1: `u*t` (5.25), `u*` (5.26-5.36) and `Qs_max` (5.37) per cell, in `f32`: the
/// same branches as [`crate::physics::shear::surface_shear`], with the saltating `u*` from
/// the Newton-Raphson table. Each row is then swept along x while it is in cache.
pub(super) fn shear_pass(
    ctx: &Context,
    state: &SnowState,
    along_x: &Sweep,
    shear: &mut [Shear],
    q_x: &mut [f32],
) {
    let w = ctx.width;
    let site = ctx.site;
    let z_r = site.z_r as f32;
    let (z0_snow, z0_veg) = (site.z0_snow as f32, site.z0_veg as f32);
    let holding = site.holding_depth as f32;
    let snow_log = (VON_KARMAN / (site.z_r / site.z0_snow).ln()) as f32;
    // Qs_max = 0.68 (ρa/g) u*t (u*² − u*t²) / u* (5.37).
    let capacity = (0.68 * ctx.params.air_density / GRAVITY) as f32;
    let kappa = VON_KARMAN as f32;
    let cell = |rho: f32, swe: f32, u: f32, v: f32| {
        let depth = if rho > 0.0 { swe / rho } else { 0.0 };
        let speed = (u * u + v * v).sqrt();
        let u_star_t = ctx.rates.threshold.at(rho);
        let (u_star, q_max) = if depth <= holding {
            // Vegetation not yet filled (5.27-5.28, 5.26).
            let fs = if holding > 0.0 { depth / holding } else { 1.0 };
            let z0 = fs * z0_snow + (1.0 - fs) * z0_veg;
            (speed * kappa / (z_r / z0).ln(), 0.0)
        } else {
            let salt = ctx.shear_table.saltating_u_star(speed.min(ctx.max_wind));
            if salt > u_star_t {
                let q_max = capacity * u_star_t * (salt * salt - u_star_t * u_star_t) / salt;
                (salt, q_max)
            } else {
                (speed * snow_log, 0.0)
            }
        };
        Shear {
            speed,
            u_star,
            u_star_t,
            q_max,
        }
    };
    let scene = ctx.scene;
    shear
        .par_chunks_mut(w)
        .zip(q_x.par_chunks_mut(w))
        .enumerate()
        .for_each(|(r, (shear_row, q_row))| {
            let cells = r * w..(r + 1) * w;
            let u = &scene.wind_u[cells.clone()];
            let inputs = state.density[cells.clone()]
                .iter()
                .zip(&state.swe[cells.clone()])
                .zip(u)
                .zip(&scene.wind_v[cells]);
            for (s, (((&rho, &swe), &u), &v)) in shear_row.iter_mut().zip(inputs) {
                *s = cell(rho, swe, u, v);
            }
            sweep::sweep_line(along_x, shear_row, u, q_row);
        });
}

/// The public per-cell results of pass 3: saltation, suspension and sublimation.
#[derive(Debug, Clone, Copy)]
struct BlowingSnow {
    q_salt: f32,
    q_susp: f32,
    q_subl: f32,
}

/// Pass 3: suspension and sublimation from the saltation flux (5.40-5.47), melt (5.48),
/// and each cell's outflows scaled so it never sends more than it holds.
pub(super) fn outflow_pass(
    ctx: &Context,
    state: &SnowState,
    (shear, q_x, q_y): (&[Shear], &[f32], &[f32]),
    outflows: &mut [Outflow],
    (q_salt, q_susp, q_subl): (&mut [f32], &mut [f32], &mut [f32]),
) {
    let w = ctx.width;
    let on = ctx.params.phenomena;
    let holding = ctx.params.vegetation_snow_depth_m as f32;
    let salt = if on.saltation { 1.0 } else { 0.0 };
    let (step_x, step_y) = (ctx.dt * ctx.inv_dx, ctx.dt * ctx.inv_dy);
    let cell = |s: &Shear, q_x: f32, q_y: f32, u: f32, v: f32, mass: f32, rho: f32| {
        let q_salt = (q_x * q_x + q_y * q_y).sqrt();
        let (mut q_susp, mut q_subl) = (0.0f32, 0.0f32);
        if s.q_max > 0.0 && q_salt > 0.0 {
            let per_up = q_salt / (2.8 * s.u_star_t); // φr h* = Qsalt / u_p (5.44-5.45)
            let (susp, subl) = ctx.blowing_table.per_flux(s.u_star, s.u_star_t);
            q_susp = per_up * susp;
            q_subl = (per_up * subl).min(0.0);
        }
        let (susp_x, susp_y) = if on.suspension && s.speed > 0.0 {
            (q_susp * u / s.speed, q_susp * v / s.speed)
        } else {
            (0.0, 0.0)
        };
        let ox = step_x * (salt * q_x + susp_x);
        let oy = step_y * (salt * q_y + susp_y);
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
        let outflow = Outflow {
            send_x: scale * ox,
            send_y: scale * oy,
            sublimation: scale * subl,
            melt: (ctx.melt_rate * rho * ctx.dt).min(left),
        };
        let blowing = BlowingSnow {
            q_salt,
            q_susp,
            q_subl,
        };
        (outflow, blowing)
    };
    let scene = ctx.scene;
    outflows
        .par_chunks_mut(w)
        .zip(q_salt.par_chunks_mut(w))
        .zip(q_susp.par_chunks_mut(w))
        .zip(q_subl.par_chunks_mut(w))
        .enumerate()
        .for_each(|(r, (((out_row, salt_row), susp_row), subl_row))| {
            let cells = r * w..(r + 1) * w;
            let inputs = shear[cells.clone()]
                .iter()
                .zip(&q_x[cells.clone()])
                .zip(&q_y[cells.clone()])
                .zip(&scene.wind_u[cells.clone()])
                .zip(&scene.wind_v[cells.clone()])
                .zip(&state.swe[cells.clone()])
                .zip(&state.density[cells]);
            let outputs = out_row
                .iter_mut()
                .zip(salt_row.iter_mut())
                .zip(susp_row.iter_mut())
                .zip(subl_row.iter_mut());
            for ((((o, sa), su), sb), ((((((s, &qx), &qy), &u), &v), &m), &rho)) in
                outputs.zip(inputs)
            {
                let (outflow, blowing) = cell(s, qx, qy, u, v, m, rho);
                *o = outflow;
                (*sa, *su, *sb) = (blowing.q_salt, blowing.q_susp, blowing.q_subl);
            }
        });
}

/// Pass 4: every cell removes its own outflows and gathers what its four neighbours send
/// it, plus snowfall and border inflow; updates the density (5.18-5.22).
pub(super) fn update_pass(
    ctx: &Context,
    state: &mut SnowState,
    shear: &[Shear],
    outflows: &[Outflow],
) -> Vec<RowBudget> {
    let (w, h) = (ctx.width, ctx.height);
    let on = ctx.params.phenomena;
    let border_inflow = ctx.params.saturated_inflow && on.saltation;
    let scene = ctx.scene;
    let rho_drift_floor = ctx.rates.new_snow.at(super::DRIFT_PACKING_WIND as f32);
    state
        .swe
        .par_chunks_mut(w)
        .zip(state.density.par_chunks_mut(w))
        .enumerate()
        .map(|(r, (swe_row, rho_row))| {
            let cells = r * w..(r + 1) * w;
            let row = &outflows[cells.clone()];
            // The rows to the north (r − 1) and to the south (r + 1).
            let north = (r > 0).then(|| &outflows[cells.start - w..cells.start]);
            let south = (r + 1 < h).then(|| &outflows[cells.end..cells.end + w]);
            let shear = &shear[cells.clone()];
            let (wind_u, wind_v) = (&scene.wind_u[cells.clone()], &scene.wind_v[cells.clone()]);
            let ratio = scene.precipitation_ratio.map(|p| &p[cells]);
            let mut b = RowBudget::default();
            for c in 0..w {
                let (u, v) = (wind_u[c], wind_v[c]);
                let speed = shear[c].speed;
                let o = row[c];
                // The new-snow and densification wind tables share their sampling.
                let wind = ctx.rates.new_snow.axis().locate(speed);
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
                let snowfall = ctx.snowfall * ratio.map_or(1.0, |p| p[c].max(0.0));
                let rho = rho_row[c];
                let kept = (swe_row[c] - out).max(0.0);
                let drifted = gain + inflow;
                let new_mass = kept + drifted + snowfall;
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
                    let rate = ctx.rates.densify_wind.at_point(wind)
                        * ctx.rates.densify_density.at(new_rho);
                    new_rho = (new_rho + ctx.dt * rate).min(MAX_DENSITY);
                }
                if !new_mass.is_finite() && b.non_finite.is_none() {
                    b.non_finite = Some((c, r, new_mass));
                }
                swe_row[c] = new_mass;
                rho_row[c] = new_rho;
                b.precipitation += f64::from(snowfall);
                b.border_in += f64::from(inflow);
                b.border_out += f64::from(leaving);
                b.sublimation += f64::from(o.sublimation);
                b.melt += f64::from(o.melt);
                b.transported += f64::from(o.send_x.abs() + o.send_y.abs());
            }
            b
        })
        .collect()
}
