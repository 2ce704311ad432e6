//! Kernels of `snowscape-transport` (Jubert 2018, Chapters 3-5).
//!
//! Bytes per cell are the compulsory traffic of one call, the floor a perfect kernel would
//! move:
//! - `transport/step`: one SnowTran-3D step (Eq. 5.16, 300 s, every phenomenon on, snowfall)
//!   on the `size`² terrain under a west wind of 11 m s⁻¹ modified by the terrain (Section
//!   5.4); 36 B/cell: wind (2 maps), water equivalent and density read, water equivalent,
//!   density and the three flux maps written, f32 each.
//! - `transport/wind_iteration`: one Stable Fluids iteration (Chapter 3) over the castle
//!   scene on an `n³` voxel grid, `n = size / 8` (128³ at 1024²: the size), after
//!   warm-up iterations; cells = voxels; 108 B/voxel: the three face components read and
//!   written by advection and by the projection (4 × 12 B), the mean's three f64 sums read
//!   and written and the components read (60 B).
//! - `transport/flakes`: a precipitation map (Chapter 4) from `size²` flakes (1 M at 1024²)
//!   through the mean wind of the castle on 48 × 48 × 24 voxels; cells = flakes; no
//!   bandwidth model (each flake's flight is a chain of dependent wind samples).

use crate::kernel::{Kernel, KernelError};
use snowscape_terrain::{Grid, GridGeometry};
use snowscape_transport::precipitation::{FlakeParams, precipitation_map};
use snowscape_transport::step::{SceneMaps, SnowState, StepScratch, step};
use snowscape_transport::terrain_wind::modify_wind;
use snowscape_transport::wind3d::voxel::{VoxelGrid, castle_heights};
use snowscape_transport::wind3d::{Wind3dParams, WindSolver};
use snowscape_transport::{TransportError, TransportParams, Weather};
use std::hint::black_box;

impl From<TransportError> for KernelError {
    fn from(e: TransportError) -> Self {
        KernelError::Transport(Box::new(e))
    }
}

/// The castle scene voxelised on `n × n × layers` voxels over 850 m.
fn castle(n: usize, layers: usize) -> Result<VoxelGrid, KernelError> {
    let cell = 850.0 / n as f64;
    let g = GridGeometry::square(n, n, cell)?;
    Ok(VoxelGrid::from_heights(
        &g,
        &castle_heights(n, cell),
        cell,
        layers,
        -cell,
    )?)
}

/// The transport step, the wind iteration and the flakes at `size`.
pub fn transport_kernels(terrain: &Grid, size: usize) -> Result<Vec<Kernel>, KernelError> {
    let g = terrain.geometry().clone();
    let z = terrain.data().to_vec();
    let params = TransportParams::default();
    let (u, v) = modify_wind(&params, &g, &z, &vec![11.0; g.len()], &vec![0.0; g.len()])?;
    let weather = Weather {
        precipitation_mm_per_h: 7.5,
        relative_humidity_pct: 40.0,
        ..Default::default()
    };
    let mut state = SnowState::uniform(&g, 0.3, 150.0);
    let mut scratch = StepScratch::default();
    let cells = g.len();
    let step_kernel = Kernel::new("transport/step", cells, 36.0, move || {
        let scene = SceneMaps {
            geometry: &g,
            wind_u: &u,
            wind_v: &v,
            precipitation_ratio: None,
        };
        black_box(step(
            &params,
            &weather,
            &scene,
            &mut state,
            &mut scratch,
            300.0,
        )?);
        Ok(())
    });

    let n = (size / 8).max(8);
    let mut solver = WindSolver::new(castle(n, n)?, Wind3dParams::default())?;
    for _ in 0..3 {
        solver.iterate();
    }
    let wind_kernel = Kernel::new("transport/wind_iteration", n * n * n, 108.0, move || {
        black_box(solver.iterate());
        Ok(())
    });

    let voxels = castle(48, 24)?;
    let mut flake_wind = WindSolver::new(voxels.clone(), Wind3dParams::default())?;
    for _ in 0..5 {
        flake_wind.iterate();
    }
    flake_wind.project_mean();
    let mean = flake_wind.mean_velocity();
    let inflow = Wind3dParams::default().inflow();
    let flakes = FlakeParams {
        count: (size * size).max(20_000),
        ..Default::default()
    };
    let flake_kernel = Kernel::new("transport/flakes", flakes.count, 0.0, move || {
        black_box(precipitation_map(&voxels, &mean, inflow, &flakes)?);
        Ok(())
    });
    Ok(vec![step_kernel, wind_kernel, flake_kernel])
}
