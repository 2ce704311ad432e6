//! Multigrid preconditioner of the pressure solve (McAdams, Sifakis & Teran 2010, "A
//! parallel multigrid Poisson solver for fluids simulation on large grids"): a symmetric
//! V-cycle with damped Jacobi smoothing on a hierarchy of 2×2×2 aggregates, in `f32`.
//!
//! Each coarse voxel aggregates up to eight fine ones; the coarse operator is the Galerkin
//! product `Pᵀ A P` for the piecewise-constant prolongation `P` (exact for the masked
//! operator: solid voxels drop out, open outflow faces stay on the diagonal, couplings
//! inside an aggregate cancel). The coarse correction is scaled by `CORRECTION` (the
//! piecewise-constant prolongation under-corrects smooth errors). Pre- and post-smoothing
//! use the same sweeps and the cycle starts from zero, so the preconditioner is symmetric
//! and conjugate gradients stay valid. The stencils run a row at a time ([`super::stencil`]);
//! the first sweep from zero is the diagonal scaling alone, and the fine residual is
//! restricted as it is computed.

use super::stencil::{apply_row, rows};
use rayon::prelude::*;

/// Damping of the Jacobi smoother (6/7, the usual choice for the 7-point Laplacian).
const OMEGA: f32 = 6.0 / 7.0;
/// Smoothing sweeps before and after the coarse correction.
const SWEEPS: usize = 2;
/// Sweeps on the coarsest level.
const COARSEST_SWEEPS: usize = 40;
/// Scale of the coarse-grid correction.
const CORRECTION: f32 = 1.6;
/// Stop coarsening below this many voxels.
const COARSEST_CELLS: usize = 512;

/// One level: a 7-point symmetric operator with per-face weights.
#[derive(Debug, Clone, Default)]
struct Level {
    dims: [usize; 3],
    diag: Vec<f32>,
    /// `ω / d`, 0 for inactive voxels.
    scaled_inverse: Vec<f32>,
    /// Coupling weights to the −x, +x, −y, +y, −z, +z neighbours (matrix entry `−w`);
    /// empty on the finest level, whose weights are all 1 (see [`super::stencil`]).
    off: Vec<[f32; 6]>,
    /// Right-hand side and solution (empty on the finest level: the caller's vectors).
    x: Vec<f32>,
    b: Vec<f32>,
    /// Ping-pong buffer of the smoother.
    tmp: Vec<f32>,
    zeros: Vec<f32>,
}

impl Level {
    fn new(dims: [usize; 3], diag: Vec<f32>, off: Vec<[f32; 6]>) -> Self {
        let n = dims[0] * dims[1] * dims[2];
        // The finest level (unit couplings, `off` empty) works on the caller's vectors.
        let vectors = if off.is_empty() { 0 } else { n };
        Self {
            scaled_inverse: diag
                .iter()
                .map(|&d| if d > 0.0 { OMEGA / d } else { 0.0 })
                .collect(),
            dims,
            diag,
            off,
            x: vec![0.0; vectors],
            b: vec![0.0; vectors],
            tmp: vec![0.0; n],
            zeros: vec![0.0; dims[0]],
        }
    }

    fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    fn slice(&self) -> usize {
        self.dims[0] * self.dims[1]
    }

    fn weights(&self, start: usize, len: usize) -> Option<&[[f32; 6]]> {
        (!self.off.is_empty()).then(|| &self.off[start..start + len])
    }

    /// One damped Jacobi sweep `out = x + ω (b − A x) / d`.
    fn sweep(&self, b: &[f32], x: &[f32], out: &mut [f32]) {
        let [nx, ny, _] = self.dims;
        out.par_chunks_mut(self.slice())
            .enumerate()
            .for_each(|(k, o)| {
                for j in 0..ny {
                    let s = (k * ny + j) * nx;
                    let r = rows(x, self.dims, j, k, &self.zeros);
                    let (bb, inv) = (&b[s..s + nx], &self.scaled_inverse[s..s + nx]);
                    let orow = &mut o[j * nx..(j + 1) * nx];
                    apply_row(&self.diag[s..s + nx], self.weights(s, nx), &r, orow);
                    let xr = &x[s..s + nx];
                    for (((o, x), b), inv) in orow.iter_mut().zip(xr).zip(bb).zip(inv) {
                        *o = x + inv * (b - *o);
                    }
                }
            });
    }

    /// `sweeps` Jacobi sweeps on `A x = b` from `x = 0` (the first is `x = ω b / d`),
    /// leaving the result in `x`.
    fn smooth_from_zero(&mut self, b: &[f32], x: &mut [f32], sweeps: usize) {
        let mut tmp = std::mem::take(&mut self.tmp);
        let (first, rest): (&mut [f32], &mut [f32]) = if sweeps % 2 == 1 {
            (x, &mut tmp)
        } else {
            (&mut tmp, x)
        };
        first
            .par_iter_mut()
            .zip(b.par_iter().zip(self.scaled_inverse.par_iter()))
            .for_each(|(x, (b, s))| *x = s * b);
        for n in 1..sweeps {
            if n % 2 == 1 {
                self.sweep(b, first, rest);
            } else {
                self.sweep(b, rest, first);
            }
        }
        self.tmp = tmp;
    }

    /// `sweeps` Jacobi sweeps on `A x = b` from the current `x`.
    fn smooth(&mut self, b: &[f32], x: &mut [f32], sweeps: usize) {
        let mut tmp = std::mem::take(&mut self.tmp);
        for _ in 0..sweeps / 2 {
            self.sweep(b, x, &mut tmp);
            self.sweep(b, &tmp, x);
        }
        if sweeps % 2 == 1 {
            self.sweep(b, x, &mut tmp);
            x.par_iter_mut()
                .zip(tmp.par_iter())
                .for_each(|(x, t)| *x = *t);
        }
        self.tmp = tmp;
    }

    /// `b_c = Pᵀ (b − A x)`: each coarse slice sums the residuals of its two fine slices.
    fn restrict_residual(&self, b: &[f32], x: &[f32], coarse_dims: [usize; 3], out: &mut [f32]) {
        let [nx, ny, nz] = self.dims;
        let cx = coarse_dims[0];
        out.par_chunks_mut(cx * coarse_dims[1])
            .enumerate()
            .for_each(|(ck, o)| {
                o.iter_mut().for_each(|v| *v = 0.0);
                let mut ax = vec![0.0f32; nx];
                for k in (2 * ck..2 * ck + 2).filter(|&k| k < nz) {
                    for j in 0..ny {
                        let s = (k * ny + j) * nx;
                        let r = rows(x, self.dims, j, k, &self.zeros);
                        let (bb, d) = (&b[s..s + nx], &self.diag[s..s + nx]);
                        apply_row(d, self.weights(s, nx), &r, &mut ax);
                        let orow = &mut o[(j / 2) * cx..(j / 2 + 1) * cx];
                        for (i, ((ax, b), d)) in ax.iter().zip(bb).zip(d).enumerate() {
                            if *d > 0.0 {
                                orow[i / 2] += b - ax;
                            }
                        }
                    }
                }
            });
    }

    /// `x += CORRECTION · P x_c` on the active voxels.
    fn prolong(&self, coarse_x: &[f32], coarse_dims: [usize; 3], x: &mut [f32]) {
        let [nx, ny, _] = self.dims;
        let cd = coarse_dims;
        x.par_chunks_mut(self.slice())
            .enumerate()
            .for_each(|(k, out)| {
                for j in 0..ny {
                    let s = (k * ny + j) * nx;
                    let c = ((k / 2) * cd[1] + j / 2) * cd[0];
                    let crow = &coarse_x[c..c + cd[0]];
                    let d = &self.diag[s..s + nx];
                    for (i, v) in out[j * nx..(j + 1) * nx].iter_mut().enumerate() {
                        if d[i] > 0.0 {
                            *v += CORRECTION * crow[i / 2];
                        }
                    }
                }
            });
    }

    /// The Galerkin coarse level `Pᵀ A P` over 2×2×2 aggregates.
    fn coarsen(&self) -> Level {
        let [nx, ny, nz] = self.dims;
        let cd = [nx.div_ceil(2), ny.div_ceil(2), nz.div_ceil(2)];
        let n = cd[0] * cd[1] * cd[2];
        let mut diag = vec![0.0f32; n];
        let mut off = vec![[0.0f32; 6]; n];
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let f = (k * ny + j) * nx + i;
                    if self.diag[f] == 0.0 {
                        continue;
                    }
                    let c = ((k / 2) * cd[1] + j / 2) * cd[0] + i / 2;
                    diag[c] += self.diag[f];
                    let pos = [i, j, k];
                    for (d, slot) in off[c].iter_mut().enumerate() {
                        let axis = d / 2;
                        let q = if d.is_multiple_of(2) {
                            pos[axis].checked_sub(1)
                        } else {
                            Some(pos[axis] + 1).filter(|&q| q < self.dims[axis])
                        };
                        let Some(q) = q else { continue };
                        let mut nb = pos;
                        nb[axis] = q;
                        let nf = (nb[2] * ny + nb[1]) * nx + nb[0];
                        let w = if self.off.is_empty() {
                            // Unit weights between two active voxels.
                            if self.diag[nf] > 0.0 { 1.0 } else { 0.0 }
                        } else {
                            self.off[f][d]
                        };
                        if w == 0.0 {
                            continue;
                        }
                        if q / 2 == pos[axis] / 2 {
                            diag[c] -= w; // coupling inside the aggregate
                        } else {
                            *slot += w;
                        }
                    }
                }
            }
        }
        Level::new(cd, diag, off)
    }
}

/// The level hierarchy.
#[derive(Debug, Clone, Default)]
pub struct Multigrid {
    levels: Vec<Level>,
}

impl Multigrid {
    /// Builds the hierarchy from the fine operator (`diag` = number of open faces of each
    /// fluid voxel, 0 in solids; unit couplings between active neighbours).
    pub fn new(dims: [usize; 3], diag: &[f32]) -> Self {
        let mut levels = vec![Level::new(dims, diag.to_vec(), Vec::new())];
        while levels
            .last()
            .is_some_and(|l| l.len() > COARSEST_CELLS && l.dims.iter().any(|&d| d > 2))
        {
            let next = levels.last().expect("non-empty").coarsen();
            levels.push(next);
        }
        Self { levels }
    }

    /// `z = M⁻¹ r`: one V-cycle from zero.
    pub fn apply(&mut self, r: &[f32], z: &mut [f32]) {
        vcycle(&mut self.levels, r, z);
    }
}

/// One V-cycle on `levels[0] x = b` from `x = 0`.
fn vcycle(levels: &mut [Level], b: &[f32], x: &mut [f32]) {
    let Some((lv, coarser)) = levels.split_first_mut() else {
        return;
    };
    if coarser.is_empty() {
        lv.smooth_from_zero(b, x, COARSEST_SWEEPS);
        return;
    }
    lv.smooth_from_zero(b, x, SWEEPS);
    let coarse = &mut coarser[0];
    let (cdims, mut cb, mut cx) = (
        coarse.dims,
        std::mem::take(&mut coarse.b),
        std::mem::take(&mut coarse.x),
    );
    lv.restrict_residual(b, x, cdims, &mut cb);
    vcycle(coarser, &cb, &mut cx);
    lv.prolong(&cx, cdims, x);
    let coarse = &mut coarser[0];
    coarse.b = cb;
    coarse.x = cx;
    lv.smooth(b, x, SWEEPS);
}
