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
    /// Two grids that must share a geometry do not.
    #[error("geometry mismatch: {0}")]
    GeometryMismatch(String),
}
