//! The depth a receiving cell keeps, tabulated (see [`Cascade::retained`](super::cascade)).
//!
//! A cell that received snow keeps the depth `d` that equals its holding depth on the slope its
//! surface then has: `d = H(s(d))`, `s(d) = max(s_ghost, max_k (c_k + d) · λ_k)`, with `c_k`
//! the highest rise `base − seen` over the neighbours at distance `1 / λ_k` (east-west,
//! north-south, diagonal) and `s_ghost` the fixed slope past the border. `H` does not increase
//! with the slope, so `g(d) = d − H(s(d))` is the largest of the increasing functions
//! `d − H(s_ghost)` and `d − H((c_k + d) · λ_k)`, and its root is the smallest of theirs:
//!
//! `d* = min(H(s_ghost), ψ_1(c_1), ψ_2(c_2), ψ_3(c_3))`, `ψ_k(c)` the root of `d = H((c + d) λ_k)`.
//!
//! Each `ψ_k` depends on the rise alone; it is tabulated once per parameter set and cell size at
//! [`SEGMENTS`] + 1 evenly spaced rises and interpolated linearly, so a receiving cell costs three
//! lookups instead of a root finding (five holding-depth evaluations on average, most of the
//! cascade's time). `ψ` is 1-Lipschitz and decreasing, from `H(0)` (a rise at which the surface
//! levels out on the neighbour: `c ≤ tan(s_min) / λ − H(0)`) down; the table ends at the rise
//! whose root slope reaches the floor of the holding depth or 80°. Past it (a cliff drop several
//! cells high) three fixed-point steps `d₀ = H(c λ)`, `d_{n+1} = H((c + d_n) λ)` find the root
//! to far below a millimetre (each shrinks the error by `|H'| λ`, below 0.02 on such slopes). The table's error is tested
//! within 0.1 mm, the tolerance of the root finding it replaces.

use super::HoldingTable;

/// Segments of a [`RetainedTable`].
const SEGMENTS: usize = 16384;

/// Root slope (tan) at which the table ends: 80°.
const STEEPEST_TAN: f32 = 5.671_282;

/// `ψ(c)` for one neighbour distance.
#[derive(Debug, Clone)]
pub(super) struct RetainedTable {
    /// The rises of the first and the last point, m, and `1 / spacing`, 1/m.
    c_lo: f32,
    c_hi: f32,
    inv_h: f32,
    /// `1 / distance` of the neighbour, 1/m.
    inv_l: f32,
    /// `ψ` at the points, m.
    depth: Vec<f32>,
    /// The floor of the holding depth, m (applied after the interpolation).
    floor: f32,
}

impl RetainedTable {
    /// The table of a neighbour at `1 / inv_l` metres, for the holding depths of `holding` (of
    /// a cell that received snow).
    pub(super) fn new(holding: &HoldingTable, inv_l: f32) -> Self {
        let hold = |s: f64| f64::from(holding.hold(s as f32, true));
        let inv_l = f64::from(inv_l);
        let h_max = hold(0.0);
        let c_lo = f64::from(holding.min_tan) / inv_l - h_max;
        // The root slope past which the holding depth no longer changes (the floor), or 80°.
        let h_min = hold(f64::from(STEEPEST_TAN));
        let (mut lo, mut hi) = (0.0f64, f64::from(STEEPEST_TAN));
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if hold(mid) <= h_min {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let c_hi = (hi / inv_l - h_min).max(c_lo + 1e-3);
        let h = (c_hi - c_lo) / SEGMENTS as f64;
        // ψ decreases by at most the step in the rise (1-Lipschitz): each root lies within
        // `h` below the previous one, so a short bisection in that bracket finds it.
        let mut prev = h_max;
        let depth = (0..=SEGMENTS)
            .map(|m| {
                let c = c_lo + m as f64 * h;
                let lo = (prev - h - 1e-9).max(h_min);
                prev = root(&hold, c, inv_l, lo, (prev + 1e-9).min(h_max));
                prev as f32
            })
            .collect();
        Self {
            c_lo: c_lo as f32,
            c_hi: c_hi as f32,
            inv_h: (1.0 / h) as f32,
            inv_l: inv_l as f32,
            depth,
            floor: holding.floor,
        }
    }

    /// `ψ(c)`, m: the depth a cell keeps when its steepest descent is a rise `c` (m) to a
    /// neighbour at this table's distance.
    #[inline]
    pub(super) fn keep(&self, holding: &HoldingTable, c: f32) -> f32 {
        if c > self.c_hi {
            let d0 = holding.hold(c * self.inv_l, true);
            let d1 = holding.hold((c + d0) * self.inv_l, true);
            return holding.hold((c + d1) * self.inv_l, true);
        }
        let x = ((c - self.c_lo) * self.inv_h).clamp(0.0, SEGMENTS as f32);
        let k = (x as usize).min(SEGMENTS - 1);
        let f = x - k as f32;
        let (a, b) = (self.depth[k], self.depth[k + 1]);
        (a + f * (b - a)).max(self.floor)
    }
}

/// The root of `d = H((c + d) λ)` by bisection in `[lo, hi]`, which holds it, to 1e-9 of
/// the bracket's width or below.
fn root(hold: &impl Fn(f64) -> f64, c: f64, inv_l: f64, lo: f64, hi: f64) -> f64 {
    let (mut lo, mut hi) = (lo, hi.max(lo));
    let iterations = ((hi - lo) / 1e-10).max(1.0).log2().ceil() as usize;
    for _ in 0..iterations.min(64) {
        let mid = 0.5 * (lo + hi);
        if mid - hold((c + mid) * inv_l) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}
