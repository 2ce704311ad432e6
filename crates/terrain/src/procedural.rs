//! The deterministic procedural alpine terrain bundled as snowscape's default input.
//!
//! [`alpine`] computes a square bedrock height field, in metres, that looks like a glaciated
//! mountain range: a dendritic network of valleys with flat floors, carved by stream-power
//! erosion with uplift on a coarse grid ([`erosion`]); sharp ridges, couloirs and rock ribs
//! from gradient-warped ridged noise ([`noise::SwissTurbulence`]); plateaus; and cliff bands
//! where the ground is already steep ([`cliffs`]). [`landform`] describes the composition.
//!
//! **Scale.** Features scale with the grid: the drainage network is resolved on a coarse grid
//! of about one cell per 8 terrain cells (24..=256 per side) covering the whole extent, so
//! every size from 128² to 8192² shows several ridges and valleys. The relief is capped at
//! [`MAX_RELIEF_PER_EXTENT`] times the extent (180 m per km), so a small extent gets less
//! relief instead of vertical walls: at 10 m cells the full default relief of 1800 m is reached
//! from 1000² cells up, a 128² grid spans about 230 m.
//!
//! **Determinism.** Every random number comes from [`crate::random`], keyed by (seed, layer,
//! lattice point or node); the erosion runs sequentially in a fixed order; the parallel passes
//! write each cell from inputs that do not depend on the visiting order. The bytes are
//! identical for any rayon thread count and across calls.

pub mod cliffs;
pub mod erosion;
pub mod landform;
pub mod noise;

#[cfg(test)]
mod tests;

use crate::{Grid, GridGeometry, NodataMask, TerrainError};
use landform::AlpineLandform;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Smallest accepted grid side, cells.
pub const MIN_SIZE: usize = 2;
/// Largest accepted grid side, cells (16384² f32 = 1 GiB).
pub const MAX_SIZE: usize = 16_384;
/// Largest relief per metre of extent (0.18: 1800 m over 10 km, the steepness of a real
/// alpine range at the scale of its main valleys).
pub const MAX_RELIEF_PER_EXTENT: f64 = 0.18;

/// Parameters of the procedural alpine terrain.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct AlpineParams {
    /// Cells per side of the square grid. Default 1024; accepted 2..=16384, designed for
    /// 128..=8192.
    pub size: usize,
    /// Random seed: the same seed (and parameters) gives the same bytes. Default 1.
    pub seed: u64,
    /// Cell size, metres. Default 10 (a common alpine DEM resolution).
    pub cell_size: f64,
    /// Height between the lowest valley floors and the highest summits, metres, 0..=9000.
    /// Default 1800 (valley floors near 1200 m, summits near 3000 m: the central Alps).
    /// Capped at [`MAX_RELIEF_PER_EXTENT`] times the extent.
    pub relief: f64,
    /// Altitude of the lowest valley floor, metres, -11000..=9000. Default 1200.
    pub base_altitude: f64,
    /// Approximate share of the mountain area cut into plateaus, 0..=1. Default 0.15.
    pub plateau_share: f64,
    /// Height of one cliff band (a rock step and its ledge) on steep ground, metres; 0 turns
    /// cliff bands off. Default 100.
    pub cliff_band_height: f64,
}

impl Default for AlpineParams {
    fn default() -> Self {
        Self {
            size: 1024,
            seed: 1,
            cell_size: 10.0,
            relief: 1800.0,
            base_altitude: 1200.0,
            plateau_share: 0.15,
            cliff_band_height: 100.0,
        }
    }
}

/// Checks `value` is finite and within `[lo, hi]`; the error names the parameter and carries
/// the value.
fn check_finite_in(name: &'static str, value: f64, lo: f64, hi: f64) -> Result<(), TerrainError> {
    if value.is_finite() && (lo..=hi).contains(&value) {
        Ok(())
    } else {
        Err(TerrainError::InvalidParameter {
            name,
            value,
            lo,
            hi,
        })
    }
}

impl AlpineParams {
    /// Checks every parameter; the error carries the offending value.
    pub fn validate(&self) -> Result<(), TerrainError> {
        if !(MIN_SIZE..=MAX_SIZE).contains(&self.size) {
            return Err(TerrainError::InvalidSize {
                width: self.size,
                height: self.size,
                reason: "the procedural terrain needs 2..=16384 cells per side",
            });
        }
        if !(self.cell_size.is_finite() && self.cell_size > 0.0) {
            return Err(TerrainError::InvalidCellSize {
                axis: 'x',
                value: self.cell_size,
            });
        }
        check_finite_in("alpine relief (m)", self.relief, 0.0, 9000.0)?;
        check_finite_in(
            "alpine base altitude (m)",
            self.base_altitude,
            -11_000.0,
            9000.0,
        )?;
        check_finite_in("alpine plateau share", self.plateau_share, 0.0, 1.0)?;
        check_finite_in(
            "alpine cliff band height (m)",
            self.cliff_band_height,
            0.0,
            10_000.0,
        )
    }

    /// The relief actually built, metres: [`Self::relief`] capped at
    /// [`MAX_RELIEF_PER_EXTENT`] times the extent.
    pub fn effective_relief(&self) -> f64 {
        let extent = self.size as f64 * self.cell_size;
        self.relief.min(MAX_RELIEF_PER_EXTENT * extent)
    }
}

/// The procedural alpine terrain of `params`: a `size`² grid of bedrock altitudes (m) with
/// `cell_size` m cells, every cell valid, altitudes within
/// `[base_altitude, base_altitude + relief]`.
pub fn alpine(params: &AlpineParams) -> Result<Grid, TerrainError> {
    params.validate()?;
    let geometry = GridGeometry::square(params.size, params.size, params.cell_size)?;
    let field = AlpineLandform::new(params);
    let heights = landform_heights(&field, params);
    let cell = params.cell_size;
    let heights = cliffs::add_cliff_bands(
        heights,
        params.size,
        params.cell_size,
        params.cliff_band_height,
        |col, row| field.rock_band((col as f64 + 0.5) * cell, (row as f64 + 0.5) * cell),
    );
    let heights = clamp_to_range(heights, params);
    Grid::new(geometry, heights, NodataMask::all_valid())
}

/// Altitudes (m) of the landform, row by row in parallel.
fn landform_heights(field: &AlpineLandform, params: &AlpineParams) -> Vec<f32> {
    let relief = params.effective_relief();
    let (size, cell) = (params.size, params.cell_size);
    let mut z = vec![0.0f32; size * size];
    z.par_chunks_mut(size).enumerate().for_each(|(row, line)| {
        let y = (row as f64 + 0.5) * cell;
        for (col, h) in line.iter_mut().enumerate() {
            let x = (col as f64 + 0.5) * cell;
            *h = (params.base_altitude + relief * field.height(x, y).clamp(0.0, 1.0)) as f32;
        }
    });
    z
}

/// Keeps every altitude within `[base_altitude, base_altitude + relief]` after the cliff pass.
fn clamp_to_range(mut z: Vec<f32>, params: &AlpineParams) -> Vec<f32> {
    let lo = params.base_altitude as f32;
    let hi = (params.base_altitude + params.effective_relief()) as f32;
    z.par_iter_mut().for_each(|h| *h = h.clamp(lo, hi));
    z
}
