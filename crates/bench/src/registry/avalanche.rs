//! Kernels of `snowscape-avalanche` (Cordonnier 2018 §6.1).
//!
//! `avalanche/substep`: one CFL sub-step of a release of `size/5` square cells (200x200 at
//! 1024², the footprint) sliding down a 35° plane of 2 m cells, two seconds after the
//! release. The state keeps flowing from call to call (a real avalanche's successive
//! sub-steps); cells = the active box after the warm-up. 560 B per active cell: the five passes of a sub-step
//! read and write per cell the thickness, bed, 4 pipe velocities, 6 cell-flow values, 4 new
//! pipe velocities, 4 volumes and an outflow factor (f64), each pass once.

use crate::kernel::{Kernel, KernelError};
use snowscape_avalanche::{AvalancheParams, AvalancheScratch, AvalancheState, cfl_dt, step};
use snowscape_terrain::{GridGeometry, NodataMask};

/// The avalanche flow kernels on a `size`² grid.
pub fn avalanche_kernels(size: usize) -> Result<Vec<Kernel>, KernelError> {
    let geometry = GridGeometry::square(size, size, 2.0)?;
    let tan = 35f64.to_radians().tan();
    let bed: Vec<f64> = (0..size * size)
        .map(|i| -((i / size) as f64) * 2.0 * tan)
        .collect();
    let mut state = AvalancheState::new(&geometry, &NodataMask::all_valid(), &bed)?;
    // The release starts in the northern part so that it stays on the grid for many calls.
    let side = (size / 5).max(4);
    let (r0, c0) = (size / 10, (size - side) / 2);
    let h: Vec<f64> = (0..size * size)
        .map(|i| {
            let (r, c) = (i / size, i % size);
            if (r0..r0 + side).contains(&r) && (c0..c0 + side).contains(&c) {
                1.0
            } else {
                0.0
            }
        })
        .collect();
    state.set_thickness(&h)?;
    let params = AvalancheParams::default();
    let mut scratch = AvalancheScratch::default();
    let warm = step(&params, &mut state, &mut scratch, 2.0)?;
    let cells = warm.active_cells;
    Ok(vec![Kernel::new(
        "avalanche/substep",
        cells,
        560.0,
        move || {
            let dt = cfl_dt(&params, &state);
            step(&params, &mut state, &mut scratch, dt)?;
            Ok(())
        },
    )])
}
