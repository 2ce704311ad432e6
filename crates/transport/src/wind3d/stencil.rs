//! The 7-point pressure stencil of the projection and its multigrid levels, evaluated a
//! grid row at a time without branches in the inner loop.
//!
//! Every vector the solver handles is zero in inactive (solid) voxels, and the stencil
//! reads zero beyond the grid. Then the masked operator of [`super::project`],
//! `(A x)_c = d_c x_c − Σ_{fluid neighbours} x_n`, is the plain
//! `d_c x_c − Σ_{6 neighbours} w_n x_n` with unit weights on the finest level: a neighbour
//! in a solid contributes its zero, one beyond an open outflow face the `φ = 0` of the
//! Dirichlet boundary, one beyond a closed face (ground, lid, inflow) zero too, and the
//! closed and inflow faces are simply left out of `d_c`. Coarse levels carry explicit
//! weights, zero across closed faces.

use std::ops::{Add, Mul, Sub};

/// The scalar types the stencil runs in: `f32` in the iterative solver, `f64` for the
/// exact residual of the outer refinement.
pub trait Real:
    Copy
    + Default
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Send
    + Sync
{
    /// The value of an `f32`.
    fn of(v: f32) -> Self;
}

impl Real for f32 {
    #[inline(always)]
    fn of(v: f32) -> Self {
        v
    }
}

impl Real for f64 {
    #[inline(always)]
    fn of(v: f32) -> Self {
        f64::from(v)
    }
}

/// One row of a grid vector and the four rows around it (zeros beyond the grid).
pub struct Rows<'a, T> {
    pub centre: &'a [T],
    pub south: &'a [T],
    pub north: &'a [T],
    pub down: &'a [T],
    pub up: &'a [T],
}

/// The rows around row `j` of slice `k` of `x`, on a grid of `dims`; `zeros` is a row of
/// zeros of length `dims[0]`.
#[inline]
pub fn rows<'a, T>(
    x: &'a [T],
    dims: [usize; 3],
    j: usize,
    k: usize,
    zeros: &'a [T],
) -> Rows<'a, T> {
    let [nx, ny, nz] = dims;
    let row = |jj: usize, kk: usize| {
        let s = (kk * ny + jj) * nx;
        &x[s..s + nx]
    };
    Rows {
        centre: row(j, k),
        south: if j > 0 { row(j - 1, k) } else { zeros },
        north: if j + 1 < ny { row(j + 1, k) } else { zeros },
        down: if k > 0 { row(j, k - 1) } else { zeros },
        up: if k + 1 < nz { row(j, k + 1) } else { zeros },
    }
}

/// `out_i = (A x)_i` along one row, for the diagonal `diag` of the row and, on coarse
/// levels, its neighbour weights `off` (−x, +x, −y, +y, −z, +z); `None` means unit
/// weights. Inactive voxels get whatever the formula gives: callers mask them.
#[inline(always)]
pub fn apply_row<T: Real>(diag: &[f32], off: Option<&[[f32; 6]]>, r: &Rows<T>, out: &mut [T]) {
    let n = r.centre.len();
    let (c, s, no, dn, up) = (r.centre, r.south, r.north, r.down, r.up);
    assert!(diag.len() == n && s.len() == n && no.len() == n && dn.len() == n && up.len() == n);
    assert!(out.len() == n && n > 0);
    let zero = T::default();
    let west = |i: usize| if i > 0 { c[i - 1] } else { zero };
    let east = |i: usize| if i + 1 < n { c[i + 1] } else { zero };
    match off {
        None => {
            let at = |i: usize, west: T, east: T| {
                T::of(diag[i]) * c[i] - west - east - s[i] - no[i] - dn[i] - up[i]
            };
            for i in 1..n.saturating_sub(1) {
                out[i] = at(i, c[i - 1], c[i + 1]);
            }
            out[0] = at(0, zero, east(0));
            out[n - 1] = at(n - 1, west(n - 1), zero);
        }
        Some(w) => {
            assert!(w.len() == n);
            let at = |i: usize, west: T, east: T| {
                let w = &w[i];
                T::of(diag[i]) * c[i]
                    - T::of(w[0]) * west
                    - T::of(w[1]) * east
                    - T::of(w[2]) * s[i]
                    - T::of(w[3]) * no[i]
                    - T::of(w[4]) * dn[i]
                    - T::of(w[5]) * up[i]
            };
            for i in 1..n.saturating_sub(1) {
                out[i] = at(i, c[i - 1], c[i + 1]);
            }
            out[0] = at(0, zero, east(0));
            out[n - 1] = at(n - 1, west(n - 1), zero);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_row_matches_the_masked_operator() {
        // A 3 × 2 × 2 grid, all active with x = index; row j = 0, k = 0.
        let dims = [3, 2, 2];
        let x: Vec<f64> = (0..12).map(f64::from).collect();
        let zeros = vec![0.0; 3];
        let r = rows(&x, dims, 0, 0, &zeros);
        let diag = [6.0f32; 3];
        let mut got = [0.0; 3];
        apply_row(&diag, None, &r, &mut got);
        // cell 1: 6·1 − x0 − x2 − x4 (north) − x7 (up) = 6 − 0 − 2 − 4 − 7 = −7
        assert_eq!(got[1], -7.0);
        // cell 0: 6·0 − x1 − x3 − x6 = −10
        assert_eq!(got[0], -10.0);
        let w = [[0.5f32; 6]; 3];
        apply_row(&diag, Some(&w), &r, &mut got);
        assert_eq!(got[1], 6.0 - 0.5 * (2.0 + 4.0 + 7.0));
    }
}
