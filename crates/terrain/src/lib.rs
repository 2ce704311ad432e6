//! # snowscape-terrain: the terrain model
//!
//! Everything downstream of raster I/O works on the types defined here:
//!
//! - [`GridGeometry`]: the size of a raster, its cell size in metres (x and y may differ), its
//!   georeferencing (an affine north-up transform in CRS units plus an optional [`Crs`]), and the
//!   index / coordinate helpers every kernel uses. Row 0 is the northern edge, as in GeoTIFF and
//!   ESRI ASCII grids.
//! - [`Grid`]: a flat `Vec<f32>` (struct of arrays, the layout rayon, SIMD and wgpu kernels share)
//!   that owns its geometry and a [`NodataMask`], with bilinear sampling.
//! - [`LayeredTerrain`]: bedrock plus the four snow layers of Cordonnier et al. 2018, Section 3
//!   (compacted, stable, unstable, powder), all in metres of snow depth, and named auxiliary maps
//!   (sun exposure, temperature, wind...) that the simulation adds.
//! - [`random`]: counter-based random numbers keyed by (seed, stream, index), so a run is a pure
//!   function of its inputs and seed whatever the thread count.
//! - [`procedural`]: the deterministic procedural alpine terrain bundled as the default input.
//! - [`operators`]: the one family of finite-difference stencils (gradient, slope, aspect,
//!   normal, curvature) in f32 and f64, with the grid's axes stated once; [`surface`]: those
//!   stencils per cell of a grid, shared by the renderer, the mesh exporter and the phenomena.
//! - [`parallel`]: the one dispatch point for per-cell work (after pbrt-v4's `ParallelFor`):
//!   rows of several arrays handed to a kernel, each row to exactly one call, results in row
//!   order, so every phenomenon is deterministic for any thread count.

pub mod crs_facts;
pub mod crs_latitude;
pub mod error;
pub mod geometry;
pub mod grid;
pub mod lattice;
pub mod layers;
pub mod materials;
pub mod operators;
pub mod parallel;
pub mod procedural;
pub mod random;
pub mod solar;
pub mod surface;
pub mod timeline;

pub use error::TerrainError;
pub use geometry::{Crs, GeoTransform, GridGeometry};
pub use grid::{Grid, MAX_ABS_ALTITUDE_M, MAX_TERRAIN_CELL_M, MIN_TERRAIN_CELL_M, NodataMask};
pub use layers::{LayeredTerrain, SnowLayer};
