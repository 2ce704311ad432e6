//! Typed errors of the terrain model. Each variant carries the offending values.

use thiserror::Error;

/// An invalid grid, geometry or layer operation.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum TerrainError {
    /// A cell size that is zero, negative, NaN or infinite.
    #[error("invalid cell size {value} m along {axis}: it must be a finite positive number")]
    InvalidCellSize { axis: char, value: f64 },
    /// A grid with zero columns or rows, or more cells than addressable.
    #[error("invalid grid size {width}x{height}: {reason}")]
    InvalidSize {
        width: usize,
        height: usize,
        reason: &'static str,
    },
    /// Data whose length does not match the geometry.
    #[error("data has {actual} values but a {width}x{height} grid needs {expected}")]
    LengthMismatch {
        width: usize,
        height: usize,
        expected: usize,
        actual: usize,
    },
    /// A NaN or infinite value in a cell that is not masked as nodata.
    #[error("non-finite value {value} at cell (col {col}, row {row}) of {what}")]
    NonFinite {
        what: String,
        col: usize,
        row: usize,
        value: f32,
    },
    /// A non-finite georeferencing value (origin or pixel size).
    #[error("invalid georeferencing: {what} = {value}")]
    InvalidTransform { what: &'static str, value: f64 },
    /// A parameter outside its valid range.
    #[error("invalid parameter {name} = {value}: must be within {lo}..={hi}")]
    InvalidParameter {
        name: &'static str,
        value: f64,
        lo: f64,
        hi: f64,
    },
    /// A terrain with fewer than 2x2 cells: slopes, normals and flow need neighbours.
    #[error("a {width}x{height} grid is too small for a terrain: at least 2x2 cells are needed")]
    TerrainTooSmall { width: usize, height: usize },
    /// A terrain without a single 2x2 block of cells of which at least three are valid, so
    /// there is no surface (all nodata, or isolated valid cells).
    #[error(
        "the {width}x{height} terrain has {valid} valid cells but no 2x2 block with at least 3 \
         valid cells: there is no surface to simulate on"
    )]
    NoTerrainSurface {
        width: usize,
        height: usize,
        valid: usize,
    },
    /// A valid cell whose altitude is not finite or beyond the altitude limit.
    #[error(
        "altitude {} m at cell (col {col}, row {row}) is beyond the limit of +-{limit} m \
         (a spike or a wrong unit or nodata value?)",
        altitude_text(*value)
    )]
    AltitudeOutOfRange {
        col: usize,
        row: usize,
        value: f32,
        limit: f32,
    },
    /// A terrain whose metric cell size is beyond what the model can mean (absurd geometry).
    #[error(
        "cell size {value:e} m along {axis} is outside {lo}..={hi} m that a terrain cell may \
         have (a wrong unit, or degrees without a CRS?)"
    )]
    TerrainCellSize {
        axis: char,
        value: f64,
        lo: f64,
        hi: f64,
    },
    /// Two grids that must share a geometry do not.
    #[error("geometry mismatch: {0}")]
    GeometryMismatch(String),
}

/// An altitude as a user reads it: plain below a million, in exponent form above (`1e30`).
fn altitude_text(v: f32) -> String {
    if v.is_finite() && v.abs() < 1e6 {
        v.to_string()
    } else {
        format!("{v:e}")
    }
}
