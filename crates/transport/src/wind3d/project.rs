//! Pressure projection (Jubert 2018, Eqs. 3.20-3.24; Stam 1999): the velocity is made
//! divergence-free by subtracting the gradient of `φ` (pressure × Δt / ρ), where
//! `Σ_faces (φ_c − φ_n) = −Δ² div_c` over each fluid voxel `c`. A face to another fluid voxel
//! couples the two; a face to the open outflow boundary sees `φ = 0` (Dirichlet); faces to
//! solids, inflow faces, the ground and the lid are closed (Neumann: their velocity is
//! imposed). The thesis solves this with Jacobi iterations, its bottleneck (Table 7.II);
//! here it is solved by conjugate gradients preconditioned by a multigrid V-cycle
//! ([`super::multigrid`]), warm-started from the previous iteration's `φ`, to a relative
//! residual `tolerance`.
//!
//! **Precision.** The conjugate gradients run in `f32` (half the memory traffic) on the
//! correction `e` of an outer iterative refinement in `f64`: `r = b − A φ` is computed
//! exactly from the `f64` potential, `A e = r` is solved in `f32` to a relative `1e-4`, and
//! `φ += e`, until the `f64` residual meets the tolerance. So the tolerance is met in `f64`
//! arithmetic whatever `f32` rounding the inner solve makes.
//!
//! Inner products are summed per z-slice and then in slice order, so the solution is the
//! same for any thread count.

use super::multigrid::Multigrid;
use super::stencil::{apply_row, rows};
use rayon::prelude::*;

/// Residual reduction asked of one inner `f32` solve (well above `f32` rounding).
const INNER_REDUCTION: f64 = 1e-4;

/// The Poisson operator on the voxel grid.
#[derive(Debug, Clone, Default)]
pub struct Poisson {
    /// Voxels along x, y, z.
    pub dims: [usize; 3],
    /// Number of open (fluid or outflow) faces of each fluid voxel; 0 for solid voxels.
    pub diag: Vec<f32>,
    /// The V-cycle preconditioner.
    pub multigrid: Multigrid,
}

impl Poisson {
    /// The operator for the open-face counts `diag` (0 in solids) on a grid of `dims`.
    pub fn new(dims: [usize; 3], diag: Vec<f32>) -> Self {
        Self {
            multigrid: Multigrid::new(dims, &diag),
            dims,
            diag,
        }
    }

    fn slice(&self) -> usize {
        self.dims[0] * self.dims[1]
    }

    /// `out = A x` (0 in solids), a row at a time; `f(start, row)` is called on each
    /// finished row of `out` (`start` its first index) and its results are summed per
    /// z-slice, returned in slice order.
    fn for_rows(
        &self,
        x: &[f32],
        out: &mut [f32],
        f: impl Fn(usize, &mut [f32]) -> f64 + Sync,
    ) -> Vec<f64> {
        let [nx, ny, _] = self.dims;
        let zeros = vec![0.0f32; nx];
        out.par_chunks_mut(self.slice())
            .enumerate()
            .map(|(k, o)| {
                let mut acc = 0.0;
                for j in 0..ny {
                    let s = (k * ny + j) * nx;
                    let r = rows(x, self.dims, j, k, &zeros);
                    let d = &self.diag[s..s + nx];
                    let orow = &mut o[j * nx..(j + 1) * nx];
                    apply_row(d, None, &r, orow);
                    for (o, d) in orow.iter_mut().zip(d) {
                        if *d <= 0.0 {
                            *o = 0.0;
                        }
                    }
                    acc += f(s, orow);
                }
                acc
            })
            .collect()
    }

    /// `out = b − A φ` in `f64`, stored as `f32` (0 in solids); returns `max |b − A φ|`.
    fn exact_residual(&self, b: &[f64], phi: &[f64], out: &mut [f32]) -> f64 {
        let [nx, ny, _] = self.dims;
        let zeros = vec![0.0f64; nx];
        out.par_chunks_mut(self.slice())
            .enumerate()
            .map(|(k, o)| {
                let mut ax = vec![0.0f64; nx];
                let mut worst = 0.0f64;
                for j in 0..ny {
                    let s = (k * ny + j) * nx;
                    let d = &self.diag[s..s + nx];
                    apply_row(d, None, &rows(phi, self.dims, j, k, &zeros), &mut ax);
                    let orow = &mut o[j * nx..(j + 1) * nx];
                    for (((o, ax), b), d) in orow.iter_mut().zip(&ax).zip(&b[s..s + nx]).zip(d) {
                        let r = if *d > 0.0 { b - ax } else { 0.0 };
                        *o = r as f32;
                        worst = worst.max(r.abs());
                    }
                }
                worst
            })
            .reduce(|| 0.0, f64::max)
    }

    /// Solves `A φ = b` from the initial `phi` until `max |b − A φ| ≤ tolerance · max |b|`
    /// or `max_iterations` inner iterations. Returns the inner iterations used and the final
    /// `max |b − A φ|`.
    pub fn solve(
        &mut self,
        b: &[f64],
        phi: &mut [f64],
        tolerance: f64,
        max_iterations: usize,
        work: &mut SolverWork,
    ) -> (usize, f64) {
        let n = b.len();
        for v in [
            &mut work.r,
            &mut work.z,
            &mut work.p,
            &mut work.q,
            &mut work.e,
        ] {
            v.resize(n, 0.0);
        }
        let target = tolerance * b.par_iter().map(|v| v.abs()).reduce(|| 0.0, f64::max);
        let mut its = 0;
        loop {
            let residual = self.exact_residual(b, phi, &mut work.r);
            if residual <= target || its >= max_iterations {
                return (its, residual);
            }
            let inner_target = (0.5 * target).max(INNER_REDUCTION * residual) as f32;
            let used = self.inner_solve(work, inner_target, max_iterations - its);
            if used == 0 {
                return (its, residual);
            }
            its += used;
            phi.par_iter_mut()
                .zip(work.e.par_iter())
                .for_each(|(x, e)| *x += f64::from(*e));
        }
    }

    /// Multigrid-preconditioned conjugate gradients on `A e = r` from `e = 0`, in `f32`,
    /// until `max |r| ≤ target`. Returns the iterations.
    fn inner_solve(&mut self, w: &mut SolverWork, target: f32, max_iterations: usize) -> usize {
        let SolverWork { r, z, p, q, e, .. } = w;
        e.par_iter_mut().for_each(|v| *v = 0.0);
        let mut mg = std::mem::take(&mut self.multigrid);
        mg.apply(r, z);
        p.copy_from_slice(z);
        let mut rz = dot(self.slice(), r, z);
        let mut it = 0;
        while it < max_iterations {
            // q = A p and p·q in one pass.
            let pq: f64 = self
                .for_rows(p, q, |s, qrow| {
                    let prow = &p[s..s + qrow.len()];
                    prow.iter()
                        .zip(qrow.iter())
                        .map(|(a, b)| f64::from(a * b))
                        .sum()
                })
                .iter()
                .sum();
            if pq <= 0.0 {
                break;
            }
            let alpha = (rz / pq) as f32;
            // e += α p, r −= α q, and max |r|, in one pass.
            let residual = e
                .par_chunks_mut(self.slice())
                .zip(r.par_chunks_mut(self.slice()))
                .zip(p.par_chunks(self.slice()).zip(q.par_chunks(self.slice())))
                .map(|((e, r), (p, q))| {
                    let mut m = 0.0f32;
                    for (((e, r), p), q) in e.iter_mut().zip(r.iter_mut()).zip(p).zip(q) {
                        *e += alpha * p;
                        *r -= alpha * q;
                        let a = r.abs();
                        m = if a > m { a } else { m }; // vectorises, unlike f32::max
                    }
                    m
                })
                .reduce(|| 0.0, f32::max);
            it += 1;
            if residual <= target {
                break;
            }
            mg.apply(r, z);
            let rz_new = dot(self.slice(), r, z);
            let beta = (rz_new / rz) as f32;
            rz = rz_new;
            p.par_iter_mut()
                .zip(z.par_iter())
                .for_each(|(p, z)| *p = z + beta * *p);
        }
        self.multigrid = mg;
        it
    }
}

/// `a · b` summed in `f64` per slice of `slice` values, then in slice order.
fn dot(slice: usize, a: &[f32], b: &[f32]) -> f64 {
    let parts: Vec<f64> = a
        .par_chunks(slice)
        .zip(b.par_chunks(slice))
        .map(|(x, y)| x.iter().zip(y).map(|(p, q)| f64::from(p * q)).sum())
        .collect();
    parts.iter().sum()
}

/// Reusable vectors of the solver.
#[derive(Debug, Clone, Default)]
pub struct SolverWork {
    r: Vec<f32>,
    z: Vec<f32>,
    p: Vec<f32>,
    q: Vec<f32>,
    e: Vec<f32>,
}
