//! Typed errors of the environment precompute. Each variant carries the offending values.

use snowscape_terrain::TerrainError;
use thiserror::Error;

/// A bad input or parameter given to the environment precompute.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum EnvironmentError {
    /// A per-cell input whose length does not match the grid.
    #[error("{what} has {actual} values but the {width}x{height} grid needs {expected}")]
    LengthMismatch {
        /// Which input.
        what: &'static str,
        /// Grid width (columns).
        width: usize,
        /// Grid height (rows).
        height: usize,
        /// Number of cells of the grid.
        expected: usize,
        /// Number of values given.
        actual: usize,
    },
    /// A NaN or infinite height in a cell the nodata mask says is valid.
    #[error("non-finite surface height {value} at cell (col {col}, row {row}); mask it as nodata")]
    NonFiniteHeight {
        /// Column of the cell.
        col: usize,
        /// Row of the cell.
        row: usize,
        /// The offending value.
        value: f32,
    },
    /// A parameter outside its valid range.
    #[error("invalid parameter {name} = {value}: {reason}")]
    InvalidParameter {
        /// Dotted name of the parameter, as in a scenario file (e.g. `sun.latitude_deg`).
        name: &'static str,
        /// The offending value.
        value: f64,
        /// What the valid range is.
        reason: &'static str,
    },
    /// Storing the maps into a terrain failed (geometry mismatch).
    #[error("cannot store the environment maps: {0}")]
    Terrain(#[from] TerrainError),
}

/// Checks `value` against `ok`; the error names the parameter and the rule.
pub(crate) fn check_param(
    name: &'static str,
    value: f64,
    ok: bool,
    reason: &'static str,
) -> Result<(), EnvironmentError> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(EnvironmentError::InvalidParameter {
            name,
            value,
            reason,
        })
    }
}
