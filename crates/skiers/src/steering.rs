//! Steering: where a skier aims next (Cordonnier et al. 2018, Section 6.2, Eq. 4).
//!
//! A skier in cell `c` at position `p` with unit heading `h` considers the cells `n` of its
//! look-ahead window (Chebyshev distance ≤ [`SkiParams::lookahead_cells`], `c` excluded) and
//! aims at one of them with probability proportional to
//!
//! ```text
//! P(n) = 1[snow_n > threshold] · f(|s_n − s_t|) · w_d(n)
//! f(Δ)  = exp(−Δ² / (2σ²))                                   σ = slope_tolerance_deg
//! s_n   = atan( (A_c − A_n) / ℓ(c, n) )                      downhill positive, ℓ horizontal
//! w_d(n) = w_turn(n) · w_route(n)
//! w_turn = max(0, cos Δθ)^κ                                  Δθ = angle(h, centre(n) − p)
//! w_route = 0 if D(n) = ∞ and D(c) < ∞ (never enter a dead-end)
//!           1 if D(n) < D(c) or D(c) = ∞ (progress towards the terminus)
//!           no_progress_weight otherwise
//! ```
//!
//! `A` is the snow surface and `D` the distance-to-terminus map. The paper's `w_d` is "a weight
//! related to the distance to a terminus" that keeps skiers out of dead-ends; it also asks for
//! smooth changes of direction. Both are folded into `w_d`: `w_turn` gives a 45° turn half the
//! weight of going straight and forbids turns of 90° or more (no reversal); `w_route` is the
//! terminus guide. A terminus cell is always enterable, snow or not (the run ends there). The
//! draw uses one keyed uniform number, so the choice is a pure function of (seed, skier,
//! decision index).

use crate::SkiParams;
use crate::frame::SnowView;
use crate::terminus::TerminusMap;

/// Constants of the steering rule, derived once per step from [`SkiParams`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct SteeringRule {
    pub target: f64,
    pub inv_two_sigma2: f64,
    pub kappa: f64,
    pub no_progress: f64,
    pub radius: isize,
}

impl SteeringRule {
    pub fn new(params: &SkiParams) -> Self {
        let sigma = params.slope_tolerance_deg.to_radians();
        Self {
            target: params.target_slope_rad(),
            inv_two_sigma2: 1.0 / (2.0 * sigma * sigma),
            kappa: params.turn_exponent,
            no_progress: params.no_progress_weight,
            radius: params.lookahead_cells as isize,
        }
    }
}

/// The slope preference `f(Δ) = exp(−Δ²/(2σ²))` for a slope difference `Δ` (rad), `σ` in
/// radians.
pub fn slope_weight(delta_rad: f64, sigma_rad: f64) -> f64 {
    (-delta_rad * delta_rad / (2.0 * sigma_rad * sigma_rad)).exp()
}

/// The turn weight `max(0, cos Δθ)^κ` for the cosine of the turn angle.
pub fn turn_weight(cos_turn: f64, kappa: f64) -> f64 {
    if cos_turn <= 1e-9 {
        0.0
    } else {
        cos_turn.min(1.0).powf(kappa)
    }
}

/// The route weight: 0 into a dead-end from a cell with a route, 1 for progress (or from a
/// cell without a route), `no_progress` otherwise.
pub fn route_weight(d_here: f32, d_there: f32, no_progress: f64) -> f64 {
    if !d_here.is_finite() {
        1.0
    } else if !d_there.is_finite() {
        0.0
    } else if d_there < d_here {
        1.0
    } else {
        no_progress
    }
}

/// A steering decision.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Aim {
    /// Target cell `(col, row)`.
    pub cell: (usize, usize),
    /// Slope `s_n` from the current cell to the target, rad (downhill positive).
    pub slope: f64,
}

/// Where a skier is and where it heads.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pose {
    /// Its cell `(col, row)`.
    pub cell: (usize, usize),
    /// Its position `(x, y)` in the grid's frame, m.
    pub pos: (f64, f64),
    /// Its unit heading `(x, y)`.
    pub heading: (f64, f64),
}

/// Where the skier at `pose` aims, drawn with the uniform `u`; `orthogonal_only` restricts
/// the window to the 4 edge neighbours (used after a blocked move, see `skier`). `None` when
/// every candidate has zero weight (the skier is stuck).
pub(crate) fn choose(
    rule: &SteeringRule,
    view: &SnowView,
    map: &TerminusMap,
    pose: &Pose,
    u: f64,
    orthogonal_only: bool,
) -> Option<Aim> {
    let Pose {
        cell,
        pos,
        heading: h,
    } = *pose;
    const MAX: usize = (2 * crate::params::MAX_LOOKAHEAD + 1).pow(2);
    let mut weights = [0.0f64; MAX];
    let mut cells = [(0usize, 0usize, 0.0f64); MAX];
    let mut count = 0;
    let mut total = 0.0;
    let (w, hgt) = (view.width as isize, view.height as isize);
    let i = cell.1 * view.width + cell.0;
    let a_here = f64::from(view.surface(i));
    let d_here = map.distance_at(i);
    let r = if orthogonal_only { 1 } else { rule.radius };
    for dr in -r..=r {
        for dc in -r..=r {
            if (dc == 0 && dr == 0) || (orthogonal_only && dc != 0 && dr != 0) {
                continue;
            }
            let (c, rr) = (cell.0 as isize + dc, cell.1 as isize + dr);
            if c < 0 || rr < 0 || c >= w || rr >= hgt {
                continue;
            }
            let (c, rr) = (c as usize, rr as usize);
            let j = rr * view.width + c;
            let d_there = map.distance_at(j);
            if !(view.skiable(j) || d_there == 0.0) {
                continue;
            }
            let wr = route_weight(d_here, d_there, rule.no_progress);
            if wr == 0.0 {
                continue;
            }
            let (cx, cy) = view.centre(c, rr);
            let (vx, vy) = (cx - pos.0, cy - pos.1);
            let len = (vx * vx + vy * vy).sqrt();
            if len <= 0.0 {
                continue;
            }
            let wt = turn_weight((vx * h.0 + vy * h.1) / len, rule.kappa);
            if wt == 0.0 {
                continue;
            }
            let (rx, ry) = (dc as f64 * view.dx, dr as f64 * view.dy);
            let run = (rx * rx + ry * ry).sqrt();
            let slope = ((a_here - f64::from(view.surface(j))) / run).atan();
            let delta = (slope - rule.target).abs();
            let p = (-delta * delta * rule.inv_two_sigma2).exp() * wt * wr;
            if p > 0.0 {
                weights[count] = p;
                cells[count] = (c, rr, slope);
                total += p;
                count += 1;
            }
        }
    }
    if count == 0 || total <= 0.0 {
        return None;
    }
    let target = u * total;
    let mut acc = 0.0;
    let mut pick = count - 1;
    for (k, &p) in weights[..count].iter().enumerate() {
        acc += p;
        if target < acc {
            pick = k;
            break;
        }
    }
    let (c, rr, slope) = cells[pick];
    Some(Aim {
        cell: (c, rr),
        slope,
    })
}
