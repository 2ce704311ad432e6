//! The constants of one sub-step, from the parameters, the pipe geometry and its length.

use super::*;

/// The samosAT law's constants of one sub-step.
#[derive(Clone, Copy)]
pub(super) struct Samos {
    /// `μ·g·dt`: the dry friction's speed change at high speed.
    pub(super) mu_g_dt: f64,
    pub(super) rs0: f64,
    pub(super) inv_kappa: f64,
    pub(super) b: f64,
    /// `1/R`.
    pub(super) inv_r: f64,
}

impl Samos {
    /// The dry friction's speed change over the sub-step at squared speed `speed2` (the
    /// sub-step's start) on depth `depth`, for a pipe whose `μ·g·dt` is `mu_g_dt` (the law's
    /// [`Samos::mu_g_dt`] or, with friction maps, the pipe's):
    /// `μ·g·dt·(1 + Rs0/(Rs0 + u²/(g·h)))`, computed as `μ·g·dt·(1 + Rs0·g·h/(Rs0·g·h + u²))`
    /// (one division).
    #[inline(always)]
    pub(super) fn yield_dt(&self, mu_g_dt: f64, speed2: f64, depth: f64) -> f64 {
        let rgh = self.rs0 * (G * depth);
        mu_g_dt * (1.0 + rgh / (rgh + speed2))
    }

    /// The turbulent drag's `h·div²` with `div = ln(max(h/R, 1))/κ + B`: the drag slows a pipe
    /// by the factor `1/(1 + dt·|u|/(h·div²))`, applied as `h·div²/(h·div² + dt·|u|)`.
    #[inline(always)]
    pub(super) fn drag_depth(&self, depth: f64) -> f64 {
        let div = lanes::ln_at_least_one((depth * self.inv_r).max(1.0)) * self.inv_kappa + self.b;
        depth * div * div
    }
}

/// Constants of one sub-step.
pub(super) struct Consts {
    pub(super) dt: f64,
    /// `dt·g`.
    pub(super) dtg: f64,
    /// Coulomb yield speed change `α·g·tanθc·dt`.
    pub(super) yield_dt: f64,
    pub(super) coulomb: bool,
    /// Viscous coefficient `dt·(1 − α)·kv/2` (0: no viscous term).
    pub(super) visc: f64,
    /// Voellmy turbulent-drag coefficient `dt·g/ξ` (0: Coulomb law).
    pub(super) turb: f64,
    /// The samosAT law's constants (`None`: another law).
    pub(super) samos: Option<Samos>,
    pub(super) adv: bool,
    /// [`SlopeGravity::Projected`].
    pub(super) projected: bool,
    /// [`SlopeGravity::Projected`] with [`AvalancheParams::curvature`]: the bed's load
    /// carries the centrifugal term (`pipes::curvature_load`) and momentum is advected along
    /// the bed (`update::advection`).
    pub(super) curvature: bool,
    /// `1/(3·dx²)`, `1/(3·dy²)`, `1/(4·dx·dy)`: the bed Hessian's divisors, as factors.
    pub(super) inv_dx2: f64,
    pub(super) inv_dy2: f64,
    pub(super) inv_four_dxdy: f64,
    pub(super) closed: bool,
    pub(super) alpha: f64,
    pub(super) pw: usize,
    pub(super) ph: usize,
    /// `−g/L` per owned direction: the pressure term's factor.
    pub(super) neg_g_over_len: [f64; 4],
    pub(super) width: [f64; 4],
    pub(super) e: [[f64; 2]; 4],
    pub(super) dx: f64,
    pub(super) dy: f64,
    pub(super) square: bool,
    pub(super) area: f64,
    /// `1/(dx·dy)`.
    pub(super) inv_area: f64,
    /// `1/(2·e_SE,x)`, `1/(2·e_SE,y)`, `1/(2·dx)`, `1/(2·dy)`: the velocity's and the
    /// gradient's constant divisors, as factors (a multiplication costs a fraction of a
    /// division).
    pub(super) inv_den_x: f64,
    pub(super) inv_den_y: f64,
    pub(super) inv_two_dx: f64,
    pub(super) inv_two_dy: f64,
    /// Padded index offset of the neighbour of each owned pipe.
    pub(super) off: [usize; 4],
}

impl Consts {
    pub(super) fn new(
        params: &AvalancheParams,
        pg: &PipeGeometry,
        pw: usize,
        ph: usize,
        dt: f64,
    ) -> Self {
        let mu_g = params.dry_friction() * G;
        let alpha = params.dry_weight();
        let voellmy = params.friction == FrictionLaw::Voellmy;
        let samos = (params.friction == FrictionLaw::SamosAt).then(|| {
            let s = &params.samos_at;
            Samos {
                mu_g_dt: s.mu * G * dt,
                rs0: s.rs0,
                inv_kappa: 1.0 / s.kappa,
                b: s.b,
                inv_r: 1.0 / s.roughness_m,
            }
        });
        Self {
            dt,
            dtg: dt * G,
            yield_dt: alpha * mu_g * dt,
            coulomb: alpha > 0.0,
            visc: if voellmy || samos.is_some() {
                0.0
            } else {
                dt * (1.0 - alpha) * params.k_viscous * 0.5
            },
            turb: if voellmy {
                dt * G / params.voellmy_xi_m_s2
            } else {
                0.0
            },
            samos,
            adv: params.momentum_advection,
            projected: params.slope_gravity == SlopeGravity::Projected,
            curvature: params.slope_gravity == SlopeGravity::Projected && params.curvature,
            inv_dx2: 1.0 / (3.0 * pg.dx * pg.dx),
            inv_dy2: 1.0 / (3.0 * pg.dy * pg.dy),
            inv_four_dxdy: 1.0 / (4.0 * pg.dx * pg.dy),
            closed: params.border == Border::Closed,
            alpha,
            pw,
            ph,
            width: pg.width,
            e: pg.e,
            dx: pg.dx,
            dy: pg.dy,
            square: pg.dx == pg.dy,
            area: pg.area,
            inv_den_x: 1.0 / (2.0 * pg.e[2][0]),
            inv_den_y: 1.0 / (2.0 * pg.e[2][1]),
            inv_two_dx: pg.inv_two_dx,
            inv_two_dy: pg.inv_two_dy,
            neg_g_over_len: pg.neg_g_over_len,
            inv_area: pg.inv_area,
            off: [1, pw, pw + 1, pw - 1],
        }
    }

    /// Whether padded cell `k` at `(c, r)` is a wall (pipes to it carry nothing): with
    /// [`Border::Closed`] the ghost ring and nodata cells, with [`Border::Open`] none.
    pub(super) fn is_wall(&self, nodata: &[bool], k: usize, c: usize, r: usize) -> bool {
        self.closed && (nodata[k] || r == 0 || c == 0 || r == self.ph - 1 || c == self.pw - 1)
    }

    /// Padded index of the neighbour of `(c, r)` along owned direction `d`.
    pub(super) fn neighbour(&self, c: usize, r: usize, d: usize) -> Option<usize> {
        let (dc, dr) = DIRS[d];
        let cc = c as isize + dc;
        let rr = r as isize + dr;
        if cc < 0 || rr < 0 || cc >= self.pw as isize || rr >= self.ph as isize {
            None
        } else {
            Some(rr as usize * self.pw + cc as usize)
        }
    }

    /// Padded index of the owner of the pipe reaching `(c, r)` along direction `d`.
    pub(super) fn back(&self, c: usize, r: usize, d: usize) -> Option<usize> {
        let (dc, dr) = DIRS[d];
        let cc = c as isize - dc;
        let rr = r as isize - dr;
        if cc < 0 || rr < 0 || cc >= self.pw as isize || rr >= self.ph as isize {
            None
        } else {
            Some(rr as usize * self.pw + cc as usize)
        }
    }
}
