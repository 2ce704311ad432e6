//! # snowscape-transport: physical snow transport after Jubert 2018
//!
//! Jubert's thesis (Université de Montréal, 2018, in French) couples a 3D wind, a
//! precipitation map and the SnowTran-3D transport model of Liston & Sturm (1998) on a 2D
//! height map. This crate implements, module by module:
//!
//! - [`params`]: the user parameters of Table 6.I and a piecewise-constant weather timeline.
//! - [`physics`]: the per-cell formulas of Section 5.5 and Annex I (snow density, threshold
//!   and actual friction velocity by Newton-Raphson, saltation capacity and fetch rule,
//!   suspension profile, sublimation loss rate with solar radiation, degree-day melt).
//! - [`step`]: one explicit step of the mass balance, Eq. 5.16, with a closed budget.
//! - [`terrain_wind`]: the terrain modification of the wind at `z_r` (Section 5.4).
//! - [`wind3d`]: scene voxelisation (a DEM or any height map; a project-built castle scene)
//!   and the 3D wind by Stable Fluids with a conjugate-gradient projection (Chapter 3, 6.3).
//! - [`precipitation`]: the precipitation map of Chapter 4 (flakes through the mean wind,
//!   landing on upward voxel faces, IQR outlier replacement, 11 × 11 Gaussian).
//! - [`scenario`]: scenario files (Tables 6.I, 7.I) and the run driver of the pipeline.
//! - [`tables`]: the per-weather lookup tables that make the per-cell work cheap (the
//!   saltating `u*` depends on the wind alone, the suspension integrals on `u*` alone).

pub mod error;
mod float_ops;
pub mod params;
pub mod physics;
pub mod precipitation;
pub mod scenario;
pub mod step;
pub mod tables;
pub mod terrain_wind;
pub mod wind3d;

pub use error::TransportError;
pub use params::{Phenomena, Timeline, TransportParams, Weather};
