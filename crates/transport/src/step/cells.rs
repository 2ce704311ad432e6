//! The per-cell passes of [`super::step`]: shear (pass 1), outflows (pass 3) and the
//! gathering update (pass 4).

use super::{Fields, MAX_DENSITY, Outflows, SceneMaps, SnowState};
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
/// the Newton-Raphson table.
pub(super) fn shear_pass(ctx: &Context, state: &SnowState, fields: &mut Fields) {
    let w = ctx.width;
    let site = ctx.site;
    let z_r = site.z_r as f32;
    let (z0_snow, z0_veg) = (site.z0_snow as f32, site.z0_veg as f32);
    let holding = site.holding_depth as f32;
    let snow_log = (VON_KARMAN / (site.z_r / site.z0_snow).ln()) as f32;
    // Qs_max = 0.68 (ρa/g) u*t (u*² − u*t²) / u* (5.37).
    let capacity = (0.68 * ctx.params.air_density / GRAVITY) as f32;
    let kappa = VON_KARMAN as f32;
    fields
        .speed
        .par_chunks_mut(w)
        .zip(fields.u_star.par_chunks_mut(w))
        .zip(fields.u_star_t.par_chunks_mut(w))
        .zip(fields.q_max.par_chunks_mut(w))
        .enumerate()
        .for_each(|(r, (((sp_row, us_row), ut_row), qm_row))| {
            for c in 0..w {
                let i = r * w + c;
                let rho = state.density[i];
                let depth = if rho > 0.0 { state.swe[i] / rho } else { 0.0 };
                let (u, v) = (ctx.scene.wind_u[i], ctx.scene.wind_v[i]);
                let speed = (u * u + v * v).sqrt();
                let ut = ctx.rates.threshold.at(rho);
                let (us, q_max) = if depth <= holding {
                    // Vegetation not yet filled (5.27-5.28, 5.26).
                    let fs = if holding > 0.0 { depth / holding } else { 1.0 };
                    let z0 = fs * z0_snow + (1.0 - fs) * z0_veg;
                    (speed * kappa / (z_r / z0).ln(), 0.0)
                } else {
                    let salt = ctx.shear_table.saltating_u_star(speed.min(ctx.max_wind));
                    if salt > ut {
                        (salt, capacity * ut * (salt * salt - ut * ut) / salt)
                    } else {
                        (speed * snow_log, 0.0)
                    }
                };
                sp_row[c] = speed;
                us_row[c] = us;
                ut_row[c] = ut;
                qm_row[c] = q_max;
            }
        });
}

/// Pass 3: suspension and sublimation from the saltation flux (5.40-5.47), melt (5.48),
/// and each cell's outflows scaled so it never sends more than it holds.
pub(super) fn outflow_pass(
    ctx: &Context,
    state: &SnowState,
    (fields, q_x, q_y): (&Fields, &[f32], &[f32]),
    out: &mut Outflows,
    (q_salt, q_susp, q_subl): (&mut [f32], &mut [f32], &mut [f32]),
) {
    let w = ctx.width;
    let on = ctx.params.phenomena;
    let holding = ctx.params.vegetation_snow_depth_m as f32;
    out.send_x
        .par_chunks_mut(w)
        .zip(out.send_y.par_chunks_mut(w))
        .zip(out.sublimation.par_chunks_mut(w))
        .zip(out.melt.par_chunks_mut(w))
        .zip(q_salt.par_chunks_mut(w))
        .zip(q_susp.par_chunks_mut(w))
        .zip(q_subl.par_chunks_mut(w))
        .enumerate()
        .for_each(|(r, ((((((sx, sy), ls), lm), qsa), qsu), qsb))| {
            for c in 0..w {
                let i = r * w + c;
                let (u, v) = (ctx.scene.wind_u[i], ctx.scene.wind_v[i]);
                let speed = fields.speed[i];
                let q_salt = (q_x[i] * q_x[i] + q_y[i] * q_y[i]).sqrt();
                let (mut q_susp, mut q_subl) = (0.0f32, 0.0f32);
                if fields.q_max[i] > 0.0 && q_salt > 0.0 {
                    let (us, ut) = (fields.u_star[i], fields.u_star_t[i]);
                    let per_up = q_salt / (2.8 * ut); // φr h* = Qsalt / u_p (5.44-5.45)
                    let (susp, subl) = ctx.blowing_table.per_flux(us, ut);
                    q_susp = per_up * susp;
                    q_subl = (per_up * subl).min(0.0);
                }
                qsa[c] = q_salt;
                qsu[c] = q_susp;
                qsb[c] = q_subl;
                let (susp_x, susp_y) = if on.suspension && speed > 0.0 {
                    (q_susp * u / speed, q_susp * v / speed)
                } else {
                    (0.0, 0.0)
                };
                let salt = if on.saltation { 1.0 } else { 0.0 };
                let ox = ctx.dt * ctx.inv_dx * (salt * q_x[i] + susp_x);
                let oy = ctx.dt * ctx.inv_dy * (salt * q_y[i] + susp_y);
                let subl = if on.sublimation {
                    -ctx.dt * q_subl
                } else {
                    0.0
                };
                let wanted = ox.abs() + oy.abs() + subl;
                let mass = state.swe[i];
                let rho = state.density[i];
                let erodible = (mass - holding * rho).max(0.0);
                let scale = if wanted > erodible {
                    erodible / wanted
                } else {
                    1.0
                };
                sx[c] = scale * ox;
                sy[c] = scale * oy;
                ls[c] = scale * subl;
                let left = (mass - scale * wanted).max(0.0);
                lm[c] = (ctx.melt_rate * rho * ctx.dt).min(left);
            }
        });
}

/// Pass 4: every cell removes its own outflows and gathers what its four neighbours send
/// it, plus snowfall and border inflow; updates the density (5.18-5.22).
pub(super) fn update_pass(
    ctx: &Context,
    state: &mut SnowState,
    fields: &Fields,
    outflows: &Outflows,
) -> Vec<RowBudget> {
    let (w, h) = (ctx.width, ctx.height);
    let (send_x, send_y) = (&outflows.send_x, &outflows.send_y);
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
            let mut b = RowBudget::default();
            for c in 0..w {
                let i = r * w + c;
                let (u, v) = (scene.wind_u[i], scene.wind_v[i]);
                let speed = fields.speed[i];
                // The new-snow and densification wind tables share their sampling.
                let wind = ctx.rates.new_snow.axis().locate(speed);
                let out =
                    send_x[i].abs() + send_y[i].abs() + outflows.sublimation[i] + outflows.melt[i];
                let mut gain = 0.0f32;
                if c > 0 && send_x[i - 1] > 0.0 {
                    gain += send_x[i - 1];
                }
                if c + 1 < w && send_x[i + 1] < 0.0 {
                    gain -= send_x[i + 1];
                }
                if r > 0 && send_y[i - w] < 0.0 {
                    gain -= send_y[i - w];
                }
                if r + 1 < h && send_y[i + w] > 0.0 {
                    gain += send_y[i + w];
                }
                // Border inflow at saturation and border outflow.
                let mut inflow = 0.0f32;
                if border_inflow && speed > 0.0 {
                    let cap = fields.q_max[i] * ctx.dt / speed;
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
                if (c + 1 == w && send_x[i] > 0.0) || (c == 0 && send_x[i] < 0.0) {
                    leaving += send_x[i].abs();
                }
                if (r == 0 && send_y[i] > 0.0) || (r + 1 == h && send_y[i] < 0.0) {
                    leaving += send_y[i].abs();
                }
                let snowfall =
                    ctx.snowfall * scene.precipitation_ratio.map_or(1.0, |p| p[i].max(0.0));
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
                b.sublimation += f64::from(outflows.sublimation[i]);
                b.melt += f64::from(outflows.melt[i]);
                b.transported += f64::from(send_x[i].abs() + send_y[i].abs());
            }
            b
        })
        .collect()
}
