//! Staggered (MAC) velocity components and their trilinear sampling.
//!
//! The velocity lives on the faces of the voxels (Harlow & Welch's marker-and-cell layout):
//! `u` on the x faces, `(nx + 1) × ny × nz` values at `(i, j + ½, k + ½) Δ`; `v` on the y
//! faces at `(i + ½, j, k + ½) Δ`; `w` on the z faces at `(i + ½, j + ½, k) Δ`. The
//! divergence of a cell is then the exact sum of its face fluxes, so the projection makes
//! the discrete field divergence-free to the solver tolerance, and a face between a fluid
//! and a solid voxel carries no flow by construction.

use crate::float_ops::{at_least, at_most, truncate};
use rayon::prelude::*;

/// One velocity component on its face grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Component {
    /// Samples along x, y, z.
    pub dims: [usize; 3],
    /// Position of sample `(0, 0, 0)` in voxel units.
    pub offset: [f64; 3],
    /// Values, index `(k dims[1] + j) dims[0] + i`, m s⁻¹.
    pub data: Vec<f32>,
}

impl Component {
    /// A component of the given layout filled with zeros.
    pub fn zeros(dims: [usize; 3], offset: [f64; 3]) -> Self {
        Self {
            dims,
            offset,
            data: vec![0.0; dims[0] * dims[1] * dims[2]],
        }
    }

    /// Index of sample `(i, j, k)`.
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        (k * self.dims[1] + j) * self.dims[0] + i
    }

    /// Position of sample `(i, j, k)` in voxel units.
    #[inline]
    pub fn position(&self, i: usize, j: usize, k: usize) -> [f64; 3] {
        [
            i as f64 + self.offset[0],
            j as f64 + self.offset[1],
            k as f64 + self.offset[2],
        ]
    }

    /// Trilinear interpolation at `p` (voxel units), clamped to the sample grid.
    #[inline]
    pub fn sample(&self, p: [f64; 3]) -> f64 {
        let mut base = [0usize; 3];
        let mut frac = [0.0f64; 3];
        for a in 0..3 {
            let max = (self.dims[a] - 1) as f64;
            let g = (p[a] - self.offset[a]).clamp(0.0, max);
            let b = (g.floor() as usize).min(self.dims[a].saturating_sub(2));
            base[a] = b;
            frac[a] = if self.dims[a] > 1 { g - b as f64 } else { 0.0 };
        }
        let (sx, sy) = (1, self.dims[0]);
        let sz = self.dims[0] * self.dims[1];
        let step = |a: usize, s: usize| if self.dims[a] > 1 { s } else { 0 };
        let (dx, dy, dz) = (step(0, sx), step(1, sy), step(2, sz));
        let i0 = self.index(base[0], base[1], base[2]);
        let v = |o: usize| f64::from(self.data[i0 + o]);
        let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
        let x00 = lerp(v(0), v(dx), frac[0]);
        let x10 = lerp(v(dy), v(dy + dx), frac[0]);
        let x01 = lerp(v(dz), v(dz + dx), frac[0]);
        let x11 = lerp(v(dz + dy), v(dz + dy + dx), frac[0]);
        lerp(lerp(x00, x10, frac[1]), lerp(x01, x11, frac[1]), frac[2])
    }
}

/// Per-axis constants of trilinear sampling on a regular lattice.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Axis {
    /// Position of sample 0, voxel units.
    offset: f32,
    /// Largest lattice coordinate (`n − 1`).
    max: f32,
    /// Largest base index of a cell (`n − 2`, 0 when `n = 1`).
    max_base: usize,
    /// Index stride to the next sample (0 when `n = 1`: the sample is repeated).
    step: usize,
}

impl Axis {
    fn new(n: usize, offset: f64, stride: usize) -> Self {
        Self {
            offset: offset as f32,
            max: n.saturating_sub(1) as f32,
            max_base: n.saturating_sub(2),
            step: if n > 1 { stride } else { 0 },
        }
    }

    /// Base index and weight of the cell holding coordinate `p`, clamped to the lattice.
    #[inline(always)]
    fn locate(&self, p: f32) -> (usize, f32) {
        // Clamped by comparisons (NaN goes to 0), truncated in one instruction.
        let g = at_most(at_least(p - self.offset, 0.0), self.max);
        let b = (truncate(g) as usize).min(self.max_base);
        (b, g - b as f32)
    }
}

/// A lattice of `dims` samples at `offset + (i, j, k)`, for trilinear sampling in `f32`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Lattice {
    axes: [Axis; 3],
    strides: [usize; 3],
    /// Number of samples.
    len: usize,
}

impl Lattice {
    /// The lattice of `dims` samples starting at `offset` (voxel units).
    pub fn new(dims: [usize; 3], offset: [f64; 3]) -> Self {
        let strides = [1, dims[0], dims[0] * dims[1]];
        Self {
            axes: std::array::from_fn(|a| Axis::new(dims[a], offset[a], strides[a])),
            strides,
            len: dims[0] * dims[1] * dims[2],
        }
    }

    /// Index of the lower corner of the cell holding `p`, the index steps to its seven
    /// other corners along x, y, z, and the weights along each axis.
    #[inline(always)]
    fn corners(&self, p: [f32; 3]) -> (usize, [usize; 3], [f32; 3]) {
        let (bx, tx) = self.axes[0].locate(p[0]);
        let (by, ty) = self.axes[1].locate(p[1]);
        let (bz, tz) = self.axes[2].locate(p[2]);
        let i0 = bx + self.strides[1] * by + self.strides[2] * bz;
        let steps = [self.axes[0].step, self.axes[1].step, self.axes[2].step];
        (i0, steps, [tx, ty, tz])
    }

    /// Trilinear interpolation of the scalar samples `data` at `p`.
    ///
    /// Panics if `data` is shorter than the lattice.
    #[inline(always)]
    pub fn sample(&self, data: &[f32], p: [f32; 3]) -> f32 {
        assert!(data.len() >= self.len);
        let (i0, [dx, dy, dz], [tx, ty, tz]) = self.corners(p);
        // SAFETY: `locate` clamps each base to `n − 2` (0 when `n = 1`, where the step is
        // 0), so the farthest corner `i0 + dx + dy + dz` is at most `len − 1 < data.len()`.
        let v = |o: usize| unsafe { *data.get_unchecked(i0 + o) };
        let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
        let x00 = lerp(v(0), v(dx), tx);
        let x10 = lerp(v(dy), v(dy + dx), tx);
        let x01 = lerp(v(dz), v(dz + dx), tx);
        let x11 = lerp(v(dz + dy), v(dz + dy + dx), tx);
        lerp(lerp(x00, x10, ty), lerp(x01, x11, ty), tz)
    }

    /// Trilinear interpolation of the 4-vector samples `data` at `p`.
    ///
    /// Panics if `data` is shorter than the lattice.
    #[inline(always)]
    pub fn sample4(&self, data: &[[f32; 4]], p: [f32; 3]) -> [f32; 4] {
        assert!(data.len() >= self.len);
        let (i0, [dx, dy, dz], [tx, ty, tz]) = self.corners(p);
        // SAFETY: as in `sample`, every corner index is below `len ≤ data.len()`.
        let v = |o: usize| unsafe { *data.get_unchecked(i0 + o) };
        let lerp = |a: [f32; 4], b: [f32; 4], t: f32| -> [f32; 4] {
            [
                a[0] + t * (b[0] - a[0]),
                a[1] + t * (b[1] - a[1]),
                a[2] + t * (b[2] - a[2]),
                a[3] + t * (b[3] - a[3]),
            ]
        };
        let x00 = lerp(v(0), v(dx), tx);
        let x10 = lerp(v(dy), v(dy + dx), tx);
        let x01 = lerp(v(dz), v(dz + dx), tx);
        let x11 = lerp(v(dz + dy), v(dz + dy + dx), tx);
        lerp(lerp(x00, x10, ty), lerp(x01, x11, ty), tz)
    }
}

/// The velocity averaged to the voxel centres, interleaved, for fast back-tracing: one
/// trilinear interpolation of a vector instead of three staggered ones.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Centred {
    /// Voxels along x, y, z.
    pub dims: [usize; 3],
    /// `(u, v, w, 0)` at each voxel centre, index `(k ny + j) nx + i` (padded to four
    /// lanes so a corner is one aligned load).
    pub data: Vec<[f32; 4]>,
    lattice: Lattice,
}

impl Centred {
    /// Averages the face velocities of `vel` to the voxel centres.
    pub fn update(&mut self, vel: &Velocity) {
        let [nx, ny, nz] = [vel.w.dims[0], vel.w.dims[1], vel.u.dims[2]];
        self.dims = [nx, ny, nz];
        self.lattice = Lattice::new(self.dims, [0.5; 3]);
        self.data.resize(nx * ny * nz, [0.0; 4]);
        let s = nx * ny;
        self.data
            .par_chunks_mut(s)
            .enumerate()
            .for_each(|(k, out)| {
                for j in 0..ny {
                    for i in 0..nx {
                        let a = vel.u.index(i, j, k);
                        let b = vel.v.index(i, j, k);
                        let c = vel.w.index(i, j, k);
                        out[j * nx + i] = [
                            0.5 * (vel.u.data[a] + vel.u.data[a + 1]),
                            0.5 * (vel.v.data[b] + vel.v.data[b + nx]),
                            0.5 * (vel.w.data[c] + vel.w.data[c + s]),
                            0.0,
                        ];
                    }
                }
            });
    }

    /// Trilinear interpolation at `p` (voxel units), clamped to the voxel centres.
    #[inline(always)]
    pub fn sample(&self, p: [f32; 3]) -> [f32; 3] {
        let v = self.lattice.sample4(&self.data, p);
        [v[0], v[1], v[2]]
    }

    /// [`Self::sample`] at `(p[0], p[1], p[2])`, as `(u, v, w, 0)`.
    #[inline(always)]
    pub fn sample4(&self, p: [f32; 4]) -> [f32; 4] {
        self.lattice.sample4(&self.data, [p[0], p[1], p[2]])
    }
}

/// The three components.
#[derive(Debug, Clone, PartialEq)]
pub struct Velocity {
    /// East component on x faces.
    pub u: Component,
    /// North component on y faces.
    pub v: Component,
    /// Up component on z faces.
    pub w: Component,
}

impl Velocity {
    /// Zero velocity on an `nx × ny × nz` voxel grid.
    pub fn zeros(nx: usize, ny: usize, nz: usize) -> Self {
        Self {
            u: Component::zeros([nx + 1, ny, nz], [0.0, 0.5, 0.5]),
            v: Component::zeros([nx, ny + 1, nz], [0.5, 0.0, 0.5]),
            w: Component::zeros([nx, ny, nz + 1], [0.5, 0.5, 0.0]),
        }
    }

    /// The velocity at `p` (voxel units), m s⁻¹.
    #[inline]
    pub fn sample(&self, p: [f64; 3]) -> [f64; 3] {
        [self.u.sample(p), self.v.sample(p), self.w.sample(p)]
    }

    /// The components, in axis order.
    pub fn components(&self) -> [&Component; 3] {
        [&self.u, &self.v, &self.w]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trilinear_sampling_reproduces_linear_fields() {
        let mut c = Component::zeros([5, 4, 3], [0.0, 0.5, 0.5]);
        for k in 0..3 {
            for j in 0..4 {
                for i in 0..5 {
                    let [x, y, z] = c.position(i, j, k);
                    let id = c.index(i, j, k);
                    c.data[id] = (1.0 + 2.0 * x - y + 0.5 * z) as f32;
                }
            }
        }
        let f = |p: [f64; 3]| 1.0 + 2.0 * p[0] - p[1] + 0.5 * p[2];
        for p in [[1.3, 2.2, 1.7], [0.0, 0.5, 0.5], [3.99, 1.1, 2.4]] {
            assert!((c.sample(p) - f(p)).abs() < 1e-5, "{p:?}");
        }
        // Outside, the value is clamped to the nearest sample.
        assert!((c.sample([-3.0, 0.5, 0.5]) - f([0.0, 0.5, 0.5])).abs() < 1e-5);
    }
}
