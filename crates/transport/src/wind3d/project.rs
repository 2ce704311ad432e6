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
//! Inner products are summed per z-slice and then in slice order, so the solution is the
//! same for any thread count.

use super::multigrid::Multigrid;
use rayon::prelude::*;

/// The Poisson operator on the voxel grid.
#[derive(Debug, Clone, Default)]
pub struct Poisson {
    /// Voxels per x row and per z slice.
    pub nx: usize,
    pub slice: usize,
    /// Number of open (fluid or outflow) faces of each fluid voxel; 0 for solid voxels.
    pub diag: Vec<u8>,
    /// Bit `d` set when face `d` (−x, +x, −y, +y, −z, +z) couples to a fluid voxel.
    pub couple: Vec<u8>,
    /// The V-cycle preconditioner.
    pub multigrid: Multigrid,
}

/// Offsets of the six neighbours, in face order (−x, +x, −y, +y, −z, +z).
#[inline]
fn neighbour(p: &Poisson, i: usize, d: usize) -> usize {
    match d {
        0 => i - 1,
        1 => i + 1,
        2 => i - p.nx,
        3 => i + p.nx,
        4 => i - p.slice,
        _ => i + p.slice,
    }
}

impl Poisson {
    /// `y = A x`.
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        y.par_chunks_mut(self.slice)
            .enumerate()
            .for_each(|(k, ys)| {
                let base = k * self.slice;
                for (o, yv) in ys.iter_mut().enumerate() {
                    let i = base + o;
                    let d = self.diag[i];
                    if d == 0 {
                        *yv = 0.0;
                        continue;
                    }
                    let mut s = f64::from(d) * x[i];
                    let m = self.couple[i];
                    for dir in 0..6 {
                        if m & (1 << dir) != 0 {
                            s -= x[neighbour(self, i, dir)];
                        }
                    }
                    *yv = s;
                }
            });
    }

    fn dot(&self, a: &[f64], b: &[f64]) -> f64 {
        let parts: Vec<f64> = a
            .par_chunks(self.slice)
            .zip(b.par_chunks(self.slice))
            .map(|(x, y)| x.iter().zip(y).map(|(p, q)| p * q).sum())
            .collect();
        parts.iter().sum()
    }

    fn max_abs(&self, a: &[f64]) -> f64 {
        a.par_chunks(self.slice)
            .map(|x| x.iter().fold(0.0f64, |m, v| m.max(v.abs())))
            .reduce(|| 0.0, f64::max)
    }

    /// Solves `A φ = b` by multigrid-preconditioned conjugate gradients from the initial `phi`,
    /// until `max |r| ≤ tolerance · max |b|` or `max_iterations`. Returns the iterations
    /// used and the final `max |r|`.
    pub fn solve(
        &mut self,
        b: &[f64],
        phi: &mut [f64],
        tolerance: f64,
        max_iterations: usize,
        work: &mut SolverWork,
    ) -> (usize, f64) {
        let n = b.len();
        for v in [&mut work.r, &mut work.z, &mut work.p, &mut work.q] {
            v.clear();
            v.resize(n, 0.0);
        }
        let SolverWork { r, z, p, q } = work;
        self.apply(phi, q);
        r.par_iter_mut()
            .zip(b.par_iter().zip(q.par_iter()))
            .for_each(|(r, (b, q))| *r = b - q);
        let target = tolerance * self.max_abs(b);
        let mut mg = std::mem::take(&mut self.multigrid);
        mg.apply(r, z);
        p.copy_from_slice(z);
        let mut rz = self.dot(r, z);
        let mut residual = self.max_abs(r);
        let mut it = 0;
        while residual > target && it < max_iterations {
            self.apply(p, q);
            let pq = self.dot(p, q);
            if pq <= 0.0 {
                break;
            }
            let alpha = rz / pq;
            phi.par_iter_mut()
                .zip(p.par_iter())
                .for_each(|(x, p)| *x += alpha * p);
            r.par_iter_mut()
                .zip(q.par_iter())
                .for_each(|(r, q)| *r -= alpha * q);
            mg.apply(r, z);
            let rz_new = self.dot(r, z);
            let beta = rz_new / rz;
            rz = rz_new;
            p.par_iter_mut()
                .zip(z.par_iter())
                .for_each(|(p, z)| *p = z + beta * *p);
            residual = self.max_abs(r);
            it += 1;
        }
        self.multigrid = mg;
        (it, residual)
    }
}

/// Reusable vectors of the solver.
#[derive(Debug, Clone, Default)]
pub struct SolverWork {
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
}
