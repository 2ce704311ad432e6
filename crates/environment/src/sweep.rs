//! Directional sweeps over the grid: every cell served once per direction, in O(cells).
//!
//! For a horizontal direction `d` (east/north, metres) the sweeps run in the layout whose rows
//! follow the grid axis closest to `d` (the grid itself, or its transpose), where `d` has the
//! index-space slope `m = Δy/Δx`, `|m| <= 1`. Line `k` (an integer) is the exact straight
//! line `y = k + x·m`: one sample point per column `x`, evenly spaced by `step` metres along
//! `d`, whose height is interpolated linearly between the two cells of column `x` that
//! bracket it (nodata or outside-grid cells are left out and the weights renormalised; a point
//! whose valid weight is under 1/2 is missing, i.e. transparent). The terrain seen along a
//! line is thus the bilinear-in-the-cross-direction interpolant of the grid, and on a plane
//! every sample lies exactly on the plane.
//!
//! A pass walks each line from the far end of `d` backwards (points ahead first), in parallel
//! over lines, and writes one value per sample into a sheared buffer (row `k`, column `x`).
//! Un-shearing gives cell `(x, y)` the blend of the two lines that bracket it
//! (`k0 = floor(y − x·m)`, weight `1 − f` and `f` with `f = y − x·m − k0`): linear
//! interpolation across lines, exact for planes. Lines write disjoint rows and cells read two
//! fixed rows, so results do not depend on the thread count.
//!
//! Approximation (documented and tested against analytic pits, walls and planes): the horizon
//! or shadow of a cell is the linear blend of those of two parallel rays at most one cell
//! apart that bracket the cell; sharp features narrower than a cell are smoothed over one cell.

use crate::field::{Layout, TerrainField};
use rayon::prelude::*;

/// Marks a missing sample (no valid terrain) in a sheared buffer.
pub(crate) const MISSING: f32 = f32::NAN;

/// The straight lines of one direction in one layout.
#[derive(Debug, Clone)]
pub(crate) struct LineFrame {
    /// Whether the lines run over the transposed layout.
    pub transposed: bool,
    /// Cells per layout row (the line's main axis).
    pub w: usize,
    /// Layout rows.
    pub h: usize,
    /// `floor(x·m)` per column.
    fl: Vec<i32>,
    /// `x·m − floor(x·m)` per column.
    frac: Vec<f32>,
    /// Metres along `d` from one sample of a line to the next (sign: along +x).
    pub step: f32,
    /// Offset `k` of the first line.
    kmin: i32,
    /// Number of lines.
    nlines: usize,
}

impl LineFrame {
    /// The lines of horizontal direction `(de, dn)` (east, north; need not be normalised, must
    /// not be zero) over `field`.
    pub fn new(field: &TerrainField, de: f64, dn: f64) -> Self {
        let (csx, csy) = (field.csx, field.csy);
        // Direction in grid index units: columns grow east, rows grow south.
        let (dcol, drow) = (de / csx, -dn / csy);
        let transposed = drow.abs() > dcol.abs();
        let (fast, slow) = if transposed {
            (drow, dcol)
        } else {
            (dcol, drow)
        };
        let m = slow / fast;
        // Metres along d per unit step of layout x and of layout y.
        let norm = (de * de + dn * dn).sqrt();
        let (ue, un) = (de / norm, dn / norm);
        let (a_fast, a_slow) = if transposed {
            (-csy * un, csx * ue)
        } else {
            (csx * ue, -csy * un)
        };
        let layout = field.layout(transposed);
        let (w, h) = (layout.w, layout.h);
        let fl: Vec<i32> = (0..w).map(|x| (x as f64 * m).floor() as i32).collect();
        let frac: Vec<f32> = (0..w)
            .map(|x| (x as f64 * m - fl[x] as f64) as f32)
            .collect();
        let flmin = *fl.iter().min().unwrap_or(&0);
        let flmax = *fl.iter().max().unwrap_or(&0);
        let kmin = -flmax - 1;
        let kmax = h as i32 - flmin;
        Self {
            transposed,
            w,
            h,
            fl,
            frac,
            step: (a_fast + m * a_slow) as f32,
            kmin,
            nlines: (kmax - kmin + 1) as usize,
        }
    }

    /// Size of the sheared buffer a pass writes (`nlines` rows of `w`).
    pub fn sheared_len(&self) -> usize {
        self.nlines * self.w
    }

    /// Height of line `k`'s sample in column `x`, interpolated between the two bracketing
    /// cells; `None` when their valid weight is below 1/2.
    #[inline(always)]
    pub fn sample(&self, layout: &Layout, k: i32, x: usize) -> Option<f32> {
        let y0 = k + self.fl[x];
        let t = self.frac[x];
        let h = self.h as i32;
        let at = |y: i32| -> Option<f32> {
            if y < 0 || y >= h {
                return None;
            }
            let z = layout.z[y as usize * self.w + x];
            (z != f32::NEG_INFINITY).then_some(z)
        };
        match (at(y0), if t > 0.0 { at(y0 + 1) } else { None }) {
            (Some(a), Some(b)) => Some(a + t * (b - a)),
            (Some(a), None) if t <= 0.5 => Some(a),
            (None, Some(b)) if t >= 0.5 => Some(b),
            _ => None,
        }
    }

    /// Columns `[lo, hi)` of line `k` whose lower bracketing row `k + floor(x·m)` lies in
    /// `[-1, h-1]` (contiguous, as `floor(x·m)` is monotone); samples outside are never read.
    fn line_range(&self, k: i32) -> (usize, usize) {
        let (lo_fl, hi_fl) = (-1 - k, self.h as i32 - 1 - k);
        if self.fl.last().copied().unwrap_or(0) >= self.fl[0] {
            let lo = self.fl.partition_point(|&f| f < lo_fl);
            let hi = self.fl.partition_point(|&f| f <= hi_fl);
            (lo, hi.max(lo))
        } else {
            let lo = self.fl.partition_point(|&f| f > hi_fl);
            let hi = self.fl.partition_point(|&f| f >= lo_fl);
            (lo, hi.max(lo))
        }
    }

    /// Runs `visit(scratch, k, lo, hi, out)` for every line `k` in parallel, with `[lo, hi)`
    /// its useful columns and `out` its row of the sheared buffer (indexed by column; every
    /// useful column must be written). `init` makes per-thread scratch. Passes visit the
    /// columns ahead first: `x = hi − 1 − n` when [`LineFrame::backwards`], else `lo + n`.
    pub fn for_each_line<S, I, F>(&self, sheared: &mut Vec<f32>, init: I, visit: F)
    where
        I: Fn() -> S + Sync + Send,
        F: Fn(&mut S, i32, usize, usize, &mut [f32]) + Sync + Send,
    {
        // Entries outside the useful columns are never read: the buffer is not cleared.
        let len = self.sheared_len();
        if sheared.len() < len {
            sheared.resize(len, MISSING);
        }
        sheared[..len]
            .par_chunks_mut(self.w)
            .enumerate()
            .for_each_init(init, |scratch, (li, out)| {
                let k = li as i32 + self.kmin;
                let (lo, hi) = self.line_range(k);
                visit(scratch, k, lo, hi, out);
            });
    }

    /// Whether cells ahead along `d` have larger `x` (lines are then walked backwards).
    #[inline(always)]
    pub fn backwards(&self) -> bool {
        self.step > 0.0
    }

    /// Un-shears into `out` (the frame's layout): every cell gets [`blend`] of the values of
    /// the two lines bracketing it, or `fill` when both are [`MISSING`] (nodata cells);
    /// parallel over rows.
    pub fn unshear(&self, sheared: &[f32], out: &mut [f32], fill: f32) {
        let w = self.w;
        out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let t = self.frac[x];
                // y − x·m = y − fl − t: on line y − fl when t = 0, else between y − fl − 1
                // (weight t) and y − fl (weight 1 − t).
                let k_on = (y as i32 - self.fl[x] - self.kmin) as usize;
                let v_on = sheared[k_on * w + x];
                let v = if t == 0.0 {
                    v_on
                } else {
                    blend(sheared[(k_on - 1) * w + x], v_on, 1.0 - t)
                };
                *o = if v.is_nan() { fill } else { v };
            }
        });
    }
}

/// Blends two line values for a cell (`f` = weight of `v1`): missing values (and, for horizon
/// tangents, `-inf` = open) defer to the other one; otherwise linear interpolation.
#[inline(always)]
pub(crate) fn blend(v0: f32, v1: f32, f: f32) -> f32 {
    if !v0.is_finite() {
        if v1.is_nan() { v0 } else { v1 }
    } else if !v1.is_finite() {
        v0
    } else {
        v0 + f * (v1 - v0)
    }
}

/// Horizon pass: writes, for every sample, the tangent of the elevation angle of its horizon
/// ahead along the frame's direction, `max_j (z_j − z_i) / (s_j − s_i)` over the samples `j`
/// ahead on its line, `-inf` when none is valid, [`MISSING`] for missing samples.
///
/// The maximum is found on the upper convex hull of the profile ahead, kept on a stack (the
/// monotone-chain hull): a vertex under the chord from the new point to the vertex behind it
/// is never a tangent point for this or any later point, so it is popped; each point is pushed
/// and popped at most once, amortised O(1) (Stewart 1998, "Fast horizon computation at all
/// points of a terrain with visibility and shading applications", IEEE TVCG 4(1)).
pub(crate) fn horizon_pass(frame: &LineFrame, layout: &Layout, sheared: &mut Vec<f32>) {
    let step = frame.step;
    let backwards = frame.backwards();
    frame.for_each_line(sheared, Vec::<(f32, f32)>::new, |hull, k, lo, hi, out| {
        hull.clear();
        for n in 0..hi - lo {
            let x = if backwards { hi - 1 - n } else { lo + n };
            match frame.sample(layout, k, x) {
                // Position along d: x·step grows towards the points ahead.
                Some(z) => {
                    let s = x as f32 * step;
                    out[x] = hull_tangent(hull, s, z);
                    hull.push((s, z));
                }
                None => out[x] = MISSING,
            }
        }
    });
}

/// Pops the hull vertices under the chord from `(s, z)` to the vertex behind them and returns
/// the slope to the remaining nearest vertex (the tangent), `-inf` for an empty hull.
#[inline(always)]
fn hull_tangent(hull: &mut Vec<(f32, f32)>, s: f32, z: f32) -> f32 {
    let slope = |p: (f32, f32)| (p.1 - z) / (p.0 - s);
    while hull.len() >= 2 {
        let top = hull[hull.len() - 1];
        let below = hull[hull.len() - 2];
        if slope(top) <= slope(below) {
            hull.pop();
        } else {
            break;
        }
    }
    hull.last().map_or(f32::NEG_INFINITY, |&p| slope(p))
}

/// Shadow pass for a light source whose rays climb at `tan_elevation` towards the frame's
/// direction: writes 1 for samples with a clear line to the source, 0 for shadowed ones.
///
/// A sample `i` is shadowed iff a sample `j` ahead rises above its ray,
/// `z_j − (s_j − s_i)·tanα > z_i`, i.e. iff `max_j (z_j − s_j tanα) > z_i − s_i tanα`: one
/// running maximum per line, O(1) per sample.
pub(crate) fn shadow_pass(
    frame: &LineFrame,
    layout: &Layout,
    tan_elevation: f32,
    sheared: &mut Vec<f32>,
) {
    let rise = frame.step * tan_elevation;
    let backwards = frame.backwards();
    frame.for_each_line(
        sheared,
        || (),
        |_, k, lo, hi, out| {
            let mut highest = f32::NEG_INFINITY;
            for n in 0..hi - lo {
                let x = if backwards { hi - 1 - n } else { lo + n };
                match frame.sample(layout, k, x) {
                    Some(z) => {
                        // z − s·tanα with s = x·step.
                        let v = z - x as f32 * rise;
                        out[x] = if v >= highest { 1.0 } else { 0.0 };
                        highest = highest.max(v);
                    }
                    None => out[x] = MISSING,
                }
            }
        },
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use snowscape_terrain::{GridGeometry, NodataMask};

    fn field(w: usize, h: usize, csx: f64, csy: f64, z: &[f32]) -> TerrainField {
        let g = GridGeometry::new(w, h, csx, csy).unwrap();
        TerrainField::new(z, &g, &NodataMask::all_valid()).unwrap()
    }

    #[test]
    fn every_cell_is_bracketed_by_valid_lines_for_any_direction() {
        let z = vec![0.0f32; 23 * 17];
        let f = field(23, 17, 2.0, 3.0, &z);
        for k in 0..40 {
            let a = k as f64 * std::f64::consts::TAU / 40.0 + 0.013;
            let frame = LineFrame::new(&f, a.sin(), a.cos());
            let layout = f.layout(frame.transposed);
            let mut sheared = Vec::new();
            horizon_pass(&frame, layout, &mut sheared);
            let mut acc = vec![0.0f32; layout.z.len()];
            frame.unshear(&sheared, &mut acc, f32::NAN);
            for (i, v) in acc.iter().enumerate() {
                // Flat ground: the horizon is 0 or open (−inf at the far edge), never missing.
                assert!(
                    *v == 0.0 || *v == f32::NEG_INFINITY,
                    "cell {i}: {v}, dir {a}"
                );
            }
        }
    }

    proptest! {
        #[test]
        fn hull_matches_brute_force_on_every_line(
            z in proptest::collection::vec(0.0f32..100.0, 12 * 9),
            angle in 0.0f64..std::f64::consts::TAU,
        ) {
            let f = field(12, 9, 5.0, 4.0, &z);
            let frame = LineFrame::new(&f, angle.sin(), angle.cos());
            let layout = f.layout(frame.transposed);
            let mut sheared = Vec::new();
            horizon_pass(&frame, layout, &mut sheared);
            for li in 0..frame.nlines {
                let k = li as i32 + frame.kmin;
                let (lo, hi) = frame.line_range(k);
                for x in lo..hi {
                    let Some(zi) = frame.sample(layout, k, x) else { continue };
                    let mut best = f32::NEG_INFINITY;
                    for xj in lo..hi {
                        let ahead = (xj as f32 - x as f32) * frame.step;
                        if ahead > 0.0 && let Some(zj) = frame.sample(layout, k, xj) {
                            best = best.max((zj - zi) / ahead);
                        }
                    }
                    let got = sheared[li * frame.w + x];
                    prop_assert!(
                        got == best || (got - best).abs() <= 1e-4 * best.abs().max(1.0),
                        "line {k} col {x}: {got} vs {best}"
                    );
                }
            }

        }
    }
}
