//! The shear pass of [`super::step`] (pass 1, with the x sweep of each block of rows), and what the
//! per-cell passes share: the rate tables and the step's constants.

use super::sweep::{self, Sweep};
use super::{SceneMaps, ShearCells, ShearMaps, SnowState};
use crate::float_ops::at_most;
use crate::params::TransportParams;
use crate::physics::density::{densification_rate, new_snow_density};
use crate::physics::shear::{ShearSite, threshold_friction_velocity};
use crate::physics::{FREEZING_K, GRAVITY, VON_KARMAN};
use crate::tables::{BlowingSnowTable, ShearTable, Table1};
use multiversion::multiversion;
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
    pub new_snow: Table1,
    /// On the sampling of `new_snow`.
    pub densify_wind: Table1,
    pub densify_density: Table1,
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

/// Pass 1: `u*t` (5.25), `u*` (5.26-5.36) and `Qs_max` (5.37) per cell, in `f32`: the
/// same branches as [`crate::physics::shear::surface_shear`], with the saltating `u*` from
/// the Newton-Raphson table. Each block of [`sweep::X_ROWS`] rows is then swept along x
/// while it is in cache.
pub(super) fn shear_pass(
    ctx: &Context,
    state: &SnowState,
    along_x: &Sweep,
    shear: &mut ShearMaps,
    q_x: &mut [f32],
) {
    let block = sweep::X_ROWS * ctx.width;
    let ShearMaps {
        speed,
        u_star,
        u_star_t,
        q_max_per_speed,
    } = shear;
    speed
        .par_chunks_mut(block)
        .zip(u_star.par_chunks_mut(block))
        .zip(u_star_t.par_chunks_mut(block))
        .zip(q_max_per_speed.par_chunks_mut(block))
        .zip(q_x.par_chunks_mut(block))
        .enumerate()
        .for_each(|(b, ((((speed, u_star), u_star_t), q_max), q_x))| {
            let maps = [speed, u_star, u_star_t, q_max, q_x];
            shear_block(ctx, state, along_x, b * block, maps);
        });
}

/// [`shear_pass`] over the cells from `first` on: `maps` are their speed, `u*`, `u*t`,
/// capacity per unit speed and saltation flux along x.
#[multiversion(targets("x86_64+avx2"))]
fn shear_block(
    ctx: &Context,
    state: &SnowState,
    along_x: &Sweep,
    first: usize,
    maps: [&mut [f32]; 5],
) {
    let site = ctx.site;
    let holding = site.holding_depth as f32;
    let snow_log = (VON_KARMAN / (site.z_r / site.z0_snow).ln()) as f32;
    // Qs_max = 0.68 (ρa/g) u*t (u*² − u*t²) / u* (5.37).
    let capacity = (0.68 * ctx.params.air_density / GRAVITY) as f32;
    let [speed, u_star, u_star_t, q_max, q_x] = maps;
    let n = speed.len();
    let cells = first..first + n;
    let scene = ctx.scene;
    let (u, v) = (&scene.wind_u[cells.clone()], &scene.wind_v[cells.clone()]);
    let (swe, density) = (&state.swe[cells.clone()], &state.density[cells]);
    let (u_star, u_star_t, q_max) = (&mut u_star[..n], &mut u_star_t[..n], &mut q_max[..n]);
    let (u, v, swe, density) = (&u[..n], &v[..n], &swe[..n], &density[..n]);
    // The table lookups first, in a loop of their own so that the processor overlaps
    // many cells: `u*t`, and `u*` as if the surface saltated.
    for i in 0..n {
        speed[i] = (u[i] * u[i] + v[i] * v[i]).sqrt();
        u_star[i] = ctx
            .shear_table
            .saltating_u_star(at_most(speed[i], ctx.max_wind));
        u_star_t[i] = ctx.rates.threshold.at(density[i]);
    }
    for i in 0..n {
        let (rho, speed) = (density[i], speed[i]);
        let depth = if rho > 0.0 { swe[i] / rho } else { 0.0 };
        let (salt, u_star_t) = (u_star[i], u_star_t[i]);
        (u_star[i], q_max[i]) = if depth <= holding {
            (vegetation_u_star(site, depth, speed), 0.0)
        } else if salt > u_star_t {
            // Qs_max / W; W > 0 here, since u*(W) > u*t ≥ 0.
            let q = capacity * u_star_t * (salt * salt - u_star_t * u_star_t);
            (salt, q / (salt * speed))
        } else {
            (speed * snow_log, 0.0)
        };
    }
    let cells = ShearCells {
        speed,
        u_star,
        u_star_t,
        q_max_per_speed: q_max,
    };
    sweep::sweep_rows(along_x, ctx.width, cells, u, q_x);
}

/// `u*` over vegetation not yet filled with snow of `depth` m, in a wind of `speed` m s⁻¹
/// (5.26-5.28). Out of line: few cells take it, and the vectorised loop of
/// [`shear_block`] would otherwise evaluate its logarithm for every cell.
#[inline(never)]
fn vegetation_u_star(site: ShearSite, depth: f32, speed: f32) -> f32 {
    let (z_r, holding) = (site.z_r as f32, site.holding_depth as f32);
    let (z0_snow, z0_veg) = (site.z0_snow as f32, site.z0_veg as f32);
    let fs = if holding > 0.0 { depth / holding } else { 1.0 };
    let z0 = fs * z0_snow + (1.0 - fs) * z0_veg;
    speed * VON_KARMAN as f32 / (z_r / z0).ln()
}
