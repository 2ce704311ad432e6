//! 3D wind by Stable Fluids on the voxel grid (Jubert 2018, Chapter 3 and Section 6.3;
//! Stam 1999).
//!
//! Each iteration applies, over a time step `Δt`:
//!
//! 1. **Forces**: the inflow boundary holds the wind (Section 6.3: "vent initial"); no
//!    body force is needed for a steady wind.
//! 2. **Advection** (3.12-3.14): semi-Lagrangian, each face value is the velocity found at
//!    the point its particle came from, back-traced with fourth-order Runge-Kutta through
//!    the current field (Fig. 3.1). The RK4 trace runs from every voxel centre; a face's
//!    departure point is its position minus the mean displacement of its two voxels
//!    (second-order accurate in the smooth displacement field, a third of the traces).
//! 3. **Viscosity** (3.15-3.16): implicit, `(I − ν Δt ∇²) u_new = u`, by Jacobi sweeps
//!    (the system is strongly diagonally dominant for the small `ν Δt / Δ²` of a wind).
//! 4. **Projection** (3.20-3.24): [`project`], multigrid-preconditioned conjugate gradients
//!    instead of Jacobi, to the loose `tolerance` in each iteration; the mean wind the
//!    later stages use is projected again to `mean_tolerance` ([`WindSolver::project_mean`]).
//!
//! The velocity is stored on the voxel faces ([`field`]). Faces touching a solid voxel carry
//! no flow (no flow into solids, Section 3.5.2), the ground and the lid are closed, faces on
//! the upwind sides of the domain hold the inflow profile, and the downwind sides are open
//! (zero-gradient velocity, `φ = 0`). Sides the inflow runs parallel to (a wind from a
//! multiple of 90°) are symmetry planes, closed: left open, the air lifted by the relief
//! under the lid leaves sideways, and the snow with it (a valley lost its snow over the
//! 400 m along both sides), where in the wider world the neighbouring air pushes back.
//! The mean wind is the average of the fields after each iteration (Section 6.3: "une
//! texture 3D qui conserve la moyenne des itérations").
//!
//! The inflow profile is the log law `U(z) = U_r ln(z'/z0) / ln(z_r/z0)` of the height `z'`
//! above the ground of the boundary column (uniform `U_r` when `inflow_roughness_m` is 0).

pub mod field;
pub mod multigrid;
pub mod project;
pub mod stencil;
pub mod voxel;

use crate::error::{TransportError, check_positive, check_range};
use field::{Centred, Component, Velocity};
use project::{Poisson, SolverWork};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use voxel::VoxelGrid;

/// Parameters of the wind simulation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Wind3dParams {
    /// Inflow wind speed at `reference_height_m` above the ground, m s⁻¹. Table 7.I: 11.
    pub speed_m_s: f64,
    /// Direction the wind blows from, degrees clockwise from north. Table 7.I: 270 (west).
    pub from_deg: f64,
    /// Height of the inflow speed above the ground, m (the `z_r` of Table 6.I: 5 m).
    pub reference_height_m: f64,
    /// Roughness of the inflow log profile, m; 0 gives a uniform inflow. Chosen here: 0.1 m.
    pub inflow_roughness_m: f64,
    /// Kinematic (eddy) viscosity `ν`, m² s⁻¹ (3.15). Chosen here: 0.05, a smooth laminar
    /// mean flow (Section 3.1: turbulence is not sought).
    pub viscosity_m2_s: f64,
    /// Courant number of the time step, `Δt = courant · Δ / U`. Chosen here: 1.
    pub courant: f64,
    /// Relative residual of the pressure solve of each iteration. Chosen here: 1e-3: the
    /// iterations relax towards a steady wind and their mean is projected again at
    /// `mean_tolerance`, so each needs only to keep its own divergence small.
    pub tolerance: f64,
    /// Relative residual of the final projection of the mean wind ([`WindSolver::project_mean`]).
    /// Chosen here: 1e-6.
    pub mean_tolerance: f64,
    /// Most conjugate-gradient iterations per projection. Chosen here: 500.
    pub max_solver_iterations: usize,
}

impl Default for Wind3dParams {
    fn default() -> Self {
        Self {
            speed_m_s: 11.0,
            from_deg: 270.0,
            reference_height_m: 5.0,
            inflow_roughness_m: 0.1,
            viscosity_m2_s: 0.05,
            courant: 1.0,
            tolerance: 1e-3,
            mean_tolerance: 1e-6,
            max_solver_iterations: 500,
        }
    }
}

impl Wind3dParams {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), TransportError> {
        check_range("speed_m_s", self.speed_m_s, 0.0, 100.0)?;
        check_range("from_deg", self.from_deg, -360.0, 360.0)?;
        check_positive("reference_height_m", self.reference_height_m)?;
        check_range("inflow_roughness_m", self.inflow_roughness_m, 0.0, 10.0)?;
        check_range("viscosity_m2_s", self.viscosity_m2_s, 0.0, 1e3)?;
        check_range("courant", self.courant, 1e-3, 10.0)?;
        check_range("tolerance", self.tolerance, 1e-14, 1.0)?;
        check_range("mean_tolerance", self.mean_tolerance, 1e-14, 1.0)?;
        check_range(
            "max_solver_iterations",
            self.max_solver_iterations as f64,
            1.0,
            1e6,
        )?;
        Ok(())
    }

    /// The inflow wind (east, north) at the reference height, m s⁻¹ (Eqs. 5.1-5.2). A
    /// component below 1e-9 of the speed (the rounding of `sin` and `cos` at multiples of
    /// 90°) is exactly 0: the wind runs parallel to those sides.
    pub fn inflow(&self) -> [f64; 2] {
        let t = self.from_deg.to_radians();
        [t.sin(), t.cos()].map(|c| {
            if c.abs() < 1e-9 {
                0.0
            } else {
                -self.speed_m_s * c
            }
        })
    }
}

/// What a face's velocity obeys.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Face {
    /// Between two fluid voxels: advected, diffused, projected.
    Fluid,
    /// Touching a solid voxel, the ground or the lid, or on a side the inflow runs parallel
    /// to (a symmetry plane): always 0.
    Closed,
    /// Upwind domain boundary: holds the inflow profile.
    Inflow,
    /// Downwind domain boundary: zero-gradient, `φ = 0` beyond.
    Outflow,
}

/// Report of one iteration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IterationReport {
    /// Conjugate-gradient iterations of the projection.
    pub solver_iterations: usize,
    /// Largest divergence of a fluid voxel after the projection, s⁻¹ (for an iteration,
    /// the residual of its pressure solve; for [`WindSolver::project_mean`], measured on
    /// the projected mean).
    pub max_divergence: f64,
    /// The same relative to `U / Δ` (the divergence scale of the flow).
    pub relative_divergence: f64,
}

/// The wind solver over a voxel grid.
#[derive(Debug, Clone)]
pub struct WindSolver {
    grid: VoxelGrid,
    params: Wind3dParams,
    kinds: [Vec<Face>; 3],
    /// Outflow faces and the inner face each copies, per component.
    outflow: [Vec<(usize, usize)>; 3],
    /// Current velocity.
    pub velocity: Velocity,
    previous: Velocity,
    centred: Centred,
    /// RK4 displacement of each voxel centre over a step, voxel units.
    displacement: Vec<[f32; 4]>,
    mean_sum: [Vec<f64>; 3],
    /// The mean wind projected by [`Self::project_mean`], until the next iteration.
    projected_mean: Option<Velocity>,
    iterations: usize,
    poisson: Poisson,
    phi: Vec<f64>,
    rhs: Vec<f64>,
    work: SolverWork,
    dt: f64,
}

mod steps;

impl WindSolver {
    /// Sets up the faces, the inflow and a projected initial field.
    pub fn new(grid: VoxelGrid, params: Wind3dParams) -> Result<Self, TransportError> {
        params.validate()?;
        check_positive("voxel_layers", grid.len() as f64)?;
        let velocity = Velocity::zeros(grid.nx, grid.ny, grid.nz);
        let speed = params.speed_m_s.max(1e-3);
        let dt = params.courant * grid.cell / speed;
        let kinds = steps::face_kinds(&grid, &params);
        let mut s = Self {
            outflow: steps::outflow_faces(&grid, &kinds),
            kinds,
            previous: velocity.clone(),
            centred: Centred::default(),
            displacement: Vec::new(),
            mean_sum: [
                vec![0.0; velocity.u.data.len()],
                vec![0.0; velocity.v.data.len()],
                vec![0.0; velocity.w.data.len()],
            ],
            velocity,
            projected_mean: None,
            iterations: 0,
            poisson: Poisson::default(),
            phi: vec![0.0; grid.len()],
            rhs: vec![0.0; grid.len()],
            work: SolverWork::default(),
            dt,
            grid,
            params,
        };
        s.poisson = steps::poisson(&s.grid, &s.kinds);
        steps::initialise(&mut s);
        let tolerance = s.params.mean_tolerance;
        s.project(tolerance);
        // Both buffers hold the fixed faces (advection swaps them).
        s.previous = s.velocity.clone();
        Ok(s)
    }

    /// The voxel grid.
    pub fn grid(&self) -> &VoxelGrid {
        &self.grid
    }

    /// Time step of an iteration, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// One Stable Fluids iteration (advection, viscosity, projection), accumulated into the
    /// mean wind.
    pub fn iterate(&mut self) -> IterationReport {
        steps::advect(self);
        steps::diffuse(self);
        let report = self.project(self.params.tolerance);
        self.projected_mean = None;
        for (sum, c) in self.mean_sum.iter_mut().zip(self.velocity.components()) {
            sum.par_iter_mut()
                .zip(c.data.par_iter())
                .for_each(|(s, v)| *s += f64::from(*v));
        }
        self.iterations += 1;
        report
    }

    fn project(&mut self, tolerance: f64) -> IterationReport {
        let mut velocity = std::mem::replace(&mut self.velocity, Velocity::zeros(0, 0, 0));
        let mut phi = std::mem::take(&mut self.phi);
        let report = self.project_field(&mut velocity, &mut phi, tolerance, false);
        self.velocity = velocity;
        self.phi = phi;
        report
    }

    /// Makes `vel` divergence-free to `tolerance`, warm-starting the potential from `phi`.
    /// The report gives the divergence of the projected field, measured on it when
    /// `measured`, else the residual of the pressure solve (`max |b − A φ| / Δ²`, the same
    /// but for the `f32` rounding of the velocity update).
    fn project_field(
        &mut self,
        vel: &mut Velocity,
        phi: &mut [f64],
        tolerance: f64,
        measured: bool,
    ) -> IterationReport {
        let area = self.grid.cell * self.grid.cell;
        steps::divergence(&self.grid, vel, -area, &mut self.rhs);
        let (its, residual) = self.poisson.solve(
            &self.rhs,
            phi,
            tolerance,
            self.params.max_solver_iterations,
            &mut self.work,
        );
        steps::subtract_gradient(&self.grid, &self.kinds, phi, vel);
        let max_div = if measured {
            steps::divergence(&self.grid, vel, 1.0, &mut self.rhs);
            self.rhs
                .par_iter()
                .map(|d| d.abs())
                .reduce(|| 0.0, f64::max)
        } else {
            residual / area
        };
        IterationReport {
            solver_iterations: its,
            max_divergence: max_div,
            relative_divergence: max_div * self.grid.cell / self.params.speed_m_s.max(1e-9),
        }
    }

    /// Projects the mean wind of the iterations so far to `mean_tolerance` (each iteration
    /// is projected only to `tolerance`); [`Self::mean_velocity`] returns it until the next
    /// iteration. Returns the residual divergence of the mean.
    pub fn project_mean(&mut self) -> IterationReport {
        let mut mean = self.raw_mean();
        let mut phi = self.phi.clone();
        let report = self.project_field(&mut mean, &mut phi, self.params.mean_tolerance, true);
        self.projected_mean = Some(mean);
        report
    }

    /// The mean face velocity over the iterations so far (the current one before any),
    /// projected if [`Self::project_mean`] ran since the last iteration.
    pub fn mean_velocity(&self) -> Velocity {
        match &self.projected_mean {
            Some(m) => m.clone(),
            None => self.raw_mean(),
        }
    }

    fn raw_mean(&self) -> Velocity {
        if self.iterations == 0 {
            return self.velocity.clone();
        }
        let n = self.iterations as f64;
        let mut m = self.velocity.clone();
        for (c, sum) in [&mut m.u, &mut m.v, &mut m.w]
            .into_iter()
            .zip(&self.mean_sum)
        {
            for (d, s) in c.data.iter_mut().zip(sum) {
                *d = (s / n) as f32;
            }
        }
        m
    }

    /// Largest speed on any face touching a solid voxel (0 when no flow enters solids).
    pub fn max_flow_into_solids(&self) -> f32 {
        let mut m = 0.0f32;
        for (c, kinds) in self.velocity.components().into_iter().zip(&self.kinds) {
            for (v, k) in c.data.iter().zip(kinds) {
                if *k == Face::Closed {
                    m = m.max(v.abs());
                }
            }
        }
        m
    }

    /// The mean wind `(east, north)` at `height` m above the ground of each voxel column,
    /// on an `nx × ny` grid with row 0 at the north (Section 5.4.1: the 2D wind at `z_r`).
    pub fn wind_at_height(&self, height: f64) -> (Vec<f32>, Vec<f32>) {
        let m = self.mean_velocity();
        let g = &self.grid;
        let mut u = vec![0.0f32; g.nx * g.ny];
        let mut v = vec![0.0f32; g.nx * g.ny];
        for j in 0..g.ny {
            for i in 0..g.nx {
                let top = f64::from(g.column_top[j * g.nx + i]).max(g.base);
                let z = (top + height - g.base) / g.cell;
                let p = [i as f64 + 0.5, j as f64 + 0.5, z];
                let row = g.ny - 1 - j;
                u[row * g.nx + i] = m.u.sample(p) as f32;
                v[row * g.nx + i] = m.v.sample(p) as f32;
            }
        }
        (u, v)
    }

    /// The mean wind encoded as `wind3d.bin` (see [`mean_wind_bytes`]).
    pub fn mean_wind_bytes(&self) -> Vec<u8> {
        mean_wind_bytes(&self.grid, &self.mean_velocity())
    }
}

/// A mean wind `m` on `g` at the voxel centres encoded as a compact little-endian binary file
/// (`wind3d.bin`, written by the output layer): the 8 bytes `SNOWWIND`, `nx ny nz` (u32),
/// voxel size and base altitude (f64), then `u`, `v`, `w` (f32, index `(k ny + j) nx + i`).
pub fn mean_wind_bytes(g: &VoxelGrid, m: &Velocity) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(40 + 12 * g.len());
    bytes.extend_from_slice(b"SNOWWIND");
    for d in [g.nx, g.ny, g.nz] {
        bytes.extend_from_slice(&(d as u32).to_le_bytes());
    }
    bytes.extend_from_slice(&g.cell.to_le_bytes());
    bytes.extend_from_slice(&g.base.to_le_bytes());
    let centre = |c: &Component, axis: usize, i: usize, j: usize, k: usize| {
        let a = c.index(i, j, k);
        let o = [1, c.dims[0], c.dims[0] * c.dims[1]][axis];
        0.5 * (c.data[a] + c.data[a + o])
    };
    for (axis, c) in m.components().into_iter().enumerate() {
        for k in 0..g.nz {
            for j in 0..g.ny {
                for i in 0..g.nx {
                    bytes.extend_from_slice(&centre(c, axis, i, j, k).to_le_bytes());
                }
            }
        }
    }
    bytes
}

#[cfg(test)]
mod tests;
