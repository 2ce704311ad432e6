//! Multigrid preconditioner of the pressure solve (McAdams, Sifakis & Teran 2010, "A
//! parallel multigrid Poisson solver for fluids simulation on large grids"): a symmetric
//! V-cycle with damped Jacobi smoothing on a hierarchy of 2×2×2 aggregates.
//!
//! Each coarse voxel aggregates up to eight fine ones; the coarse operator is the Galerkin
//! product `Pᵀ A P` for the piecewise-constant prolongation `P` (exact for the masked
//! operator: solid voxels drop out, open outflow faces stay on the diagonal, couplings
//! inside an aggregate cancel). The coarse correction is scaled by `CORRECTION` (the
//! piecewise-constant prolongation under-corrects smooth errors). Pre- and post-smoothing
//! use the same sweeps and the cycle starts from zero, so the preconditioner is symmetric
//! and conjugate gradients stay valid.

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
    /// Coupling weights to the −x, +x, −y, +y, −z, +z neighbours (matrix entry `−w`);
    /// empty on the finest level, whose weights are 0 or 1 and read from `mask`.
    off: Vec<[f32; 6]>,
    /// Finest level: bit `d` set for a unit coupling in direction `d`.
    mask: Vec<u8>,
    x: Vec<f32>,
    b: Vec<f32>,
    r: Vec<f32>,
    tmp: Vec<f32>,
}

impl Level {
    fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    fn slice(&self) -> usize {
        self.dims[0] * self.dims[1]
    }

    #[inline]
    fn neighbour(&self, i: usize, d: usize) -> usize {
        let s = [1, self.dims[0], self.slice()][d / 2];
        if d.is_multiple_of(2) { i - s } else { i + s }
    }

    /// `(b − A x)_i` at an active voxel.
    #[inline]
    fn residual_at(&self, x: &[f32], b: &[f32], i: usize) -> f32 {
        let mut ax = self.diag[i] * x[i];
        if self.off.is_empty() {
            let m = self.mask[i];
            for d in 0..6 {
                if m & (1 << d) != 0 {
                    ax -= x[self.neighbour(i, d)];
                }
            }
        } else {
            for (d, w) in self.off[i].iter().enumerate() {
                if *w != 0.0 {
                    ax -= w * x[self.neighbour(i, d)];
                }
            }
        }
        b[i] - ax
    }

    /// `out = b − A x`.
    fn residual(&self, x: &[f32], b: &[f32], out: &mut [f32]) {
        let s = self.slice();
        out.par_chunks_mut(s).enumerate().for_each(|(k, o)| {
            for (t, ov) in o.iter_mut().enumerate() {
                let i = k * s + t;
                *ov = if self.diag[i] == 0.0 {
                    0.0
                } else {
                    self.residual_at(x, b, i)
                };
            }
        });
    }

    /// `sweeps` damped Jacobi sweeps on `A x = b`, each one fused pass into `r`, swapped.
    fn smooth(&mut self, sweeps: usize) {
        let mut next = std::mem::take(&mut self.r);
        let s = self.slice();
        for _ in 0..sweeps {
            let (x, b) = (&self.x, &self.b);
            next.par_chunks_mut(s).enumerate().for_each(|(k, o)| {
                for (t, ov) in o.iter_mut().enumerate() {
                    let i = k * s + t;
                    let d = self.diag[i];
                    *ov = if d == 0.0 {
                        0.0
                    } else {
                        x[i] + OMEGA * self.residual_at(x, b, i) / d
                    };
                }
            });
            std::mem::swap(&mut self.x, &mut next);
        }
        self.r = next;
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
                    let weights: [f32; 6] = if self.off.is_empty() {
                        std::array::from_fn(|d| f32::from((self.mask[f] >> d) & 1))
                    } else {
                        self.off[f]
                    };
                    for (d, &w) in weights.iter().enumerate() {
                        if w == 0.0 {
                            continue;
                        }
                        let axis = d / 2;
                        let q = if d.is_multiple_of(2) {
                            pos[axis] - 1
                        } else {
                            pos[axis] + 1
                        };
                        if q / 2 == pos[axis] / 2 {
                            diag[c] -= w; // coupling inside the aggregate
                        } else {
                            off[c][d] += w;
                        }
                    }
                }
            }
        }
        Level {
            dims: cd,
            diag,
            off,
            mask: Vec::new(),
            x: vec![0.0; n],
            b: vec![0.0; n],
            r: vec![0.0; n],
            tmp: vec![0.0; n],
        }
    }
}

/// The level hierarchy.
#[derive(Debug, Clone, Default)]
pub struct Multigrid {
    levels: Vec<Level>,
}

impl Multigrid {
    /// Builds the hierarchy from the fine operator (`diag` = number of open faces, `couple`
    /// = bit mask of the fluid neighbours in −x, +x, −y, +y, −z, +z order).
    pub fn new(dims: [usize; 3], diag: &[u8], couple: &[u8]) -> Self {
        let n = dims[0] * dims[1] * dims[2];
        let fine = Level {
            dims,
            diag: diag.iter().map(|&d| f32::from(d)).collect(),
            off: Vec::new(),
            mask: couple.to_vec(),
            x: vec![0.0; n],
            b: vec![0.0; n],
            r: vec![0.0; n],
            tmp: vec![0.0; n],
        };
        let mut levels = vec![fine];
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
    pub fn apply(&mut self, r: &[f64], z: &mut [f64]) {
        {
            let fine = &mut self.levels[0];
            fine.b
                .par_iter_mut()
                .zip(r.par_iter())
                .for_each(|(b, r)| *b = *r as f32);
        }
        self.cycle(0);
        z.par_iter_mut()
            .zip(self.levels[0].x.par_iter())
            .for_each(|(z, x)| *z = f64::from(*x));
    }

    fn cycle(&mut self, l: usize) {
        let last = self.levels.len() - 1;
        {
            let lv = &mut self.levels[l];
            lv.x.par_iter_mut().for_each(|x| *x = 0.0);
            if l == last {
                lv.smooth(COARSEST_SWEEPS);
                return;
            }
            lv.smooth(SWEEPS);
            let mut tmp = std::mem::take(&mut lv.tmp);
            lv.residual(&lv.x, &lv.b, &mut tmp);
            lv.tmp = tmp;
        }
        // Restrict: sum of the children's residuals.
        let (fine_part, coarse_part) = self.levels.split_at_mut(l + 1);
        let (fine, coarse) = (&fine_part[l], &mut coarse_part[0]);
        restrict(fine, coarse);
        self.cycle(l + 1);
        let (fine_part, coarse_part) = self.levels.split_at_mut(l + 1);
        let (fine, coarse) = (&mut fine_part[l], &coarse_part[0]);
        prolong(coarse, fine);
        fine.smooth(SWEEPS);
    }
}

/// `b_c = Pᵀ r_f` (the fine residual is in `fine.tmp`).
fn restrict(fine: &Level, coarse: &mut Level) {
    let [nx, ny, _] = fine.dims;
    let cd = coarse.dims;
    let cs = cd[0] * cd[1];
    coarse
        .b
        .par_chunks_mut(cs)
        .enumerate()
        .for_each(|(ck, out)| {
            out.iter_mut().for_each(|v| *v = 0.0);
            for k in [2 * ck, 2 * ck + 1] {
                if k >= fine.dims[2] {
                    continue;
                }
                for j in 0..ny {
                    for i in 0..nx {
                        out[(j / 2) * cd[0] + i / 2] += fine.tmp[(k * ny + j) * nx + i];
                    }
                }
            }
        });
}

/// `x_f += CORRECTION · P x_c` on the active fine voxels.
fn prolong(coarse: &Level, fine: &mut Level) {
    let [nx, ny, _] = fine.dims;
    let cd = coarse.dims;
    let s = nx * ny;
    let diag = &fine.diag;
    fine.x.par_chunks_mut(s).enumerate().for_each(|(k, out)| {
        for j in 0..ny {
            for i in 0..nx {
                let f = j * nx + i;
                if diag[k * s + f] > 0.0 {
                    out[f] += CORRECTION * coarse.x[((k / 2) * cd[1] + j / 2) * cd[0] + i / 2];
                }
            }
        }
    });
}
