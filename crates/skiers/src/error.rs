//! Typed errors of the ski-track module. Each variant carries the offending values.

use thiserror::Error;

/// A bad input to the ski tracks, or an output that could not be written.
#[derive(Debug, Error)]
pub enum SkiError {
    /// A parameter outside its valid range.
    #[error("ski parameter {name} = {value} must be {expected}")]
    InvalidParameter {
        /// Field name.
        name: &'static str,
        /// Offending value.
        value: f64,
        /// The valid range.
        expected: &'static str,
    },
    /// A time step that is negative, NaN or infinite.
    #[error("ski time step {0} s must be finite and >= 0")]
    InvalidTimeStep(f64),
    /// A map position outside the grid's extent.
    #[error(
        "{what} ({x}, {y}) lies outside the grid, which spans x {x_min}..{x_max}, y {y_min}..{y_max}"
    )]
    OutsideGrid {
        /// What the position is (start point, terminus point).
        what: &'static str,
        /// Map x, CRS units.
        x: f64,
        /// Map y, CRS units.
        y: f64,
        /// Western edge.
        x_min: f64,
        /// Eastern edge.
        x_max: f64,
        /// Southern edge.
        y_min: f64,
        /// Northern edge.
        y_max: f64,
    },
    /// A position or cell on nodata.
    #[error("{what} at cell (col {col}, row {row}) lies on nodata")]
    OnNodata {
        /// What the position is.
        what: &'static str,
        /// Column.
        col: usize,
        /// Row.
        row: usize,
    },
    /// A start position whose cell holds too little snow to ski on.
    #[error(
        "start point at cell (col {col}, row {row}) has {depth_m} m of snow, below the {threshold_m} m needed to ski"
    )]
    NotEnoughSnow {
        /// Column.
        col: usize,
        /// Row.
        row: usize,
        /// Snow depth there, m.
        depth_m: f64,
        /// The skiing threshold, m.
        threshold_m: f64,
    },
    /// A cell index beyond the grid.
    #[error("{what} cell index {index} is beyond the {cells} cells of the grid")]
    CellOutOfRange {
        /// What the index is.
        what: &'static str,
        /// Offending index.
        index: usize,
        /// Number of cells.
        cells: usize,
    },
    /// No cell qualifies as a terminus.
    #[error("no terminus cell: {0}")]
    NoTerminus(String),
    /// A per-cell input whose length does not match the grid.
    #[error("{what} has {got} values, the grid has {expected} cells")]
    LengthMismatch {
        /// What was passed.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The number of grid cells.
        expected: usize,
    },
    /// A per-cell value that must be finite is not.
    #[error("{what} at cell {index} is {value}, must be finite")]
    BadValue {
        /// What was passed.
        what: &'static str,
        /// Cell index, row-major.
        index: usize,
        /// Offending value.
        value: f64,
    },
    /// The terrain does not have the ski area's geometry.
    #[error("terrain is {terrain_width}x{terrain_height}, the ski area {width}x{height}")]
    GeometryMismatch {
        /// Ski area width.
        width: usize,
        /// Ski area height.
        height: usize,
        /// Terrain width.
        terrain_width: usize,
        /// Terrain height.
        terrain_height: usize,
    },
    /// The track texture is too large for the requested output.
    #[error("track texture {width}x{height} texels is too large: {reason}")]
    TextureTooLarge {
        /// Texels along x.
        width: usize,
        /// Texels along y.
        height: usize,
        /// Why.
        reason: &'static str,
    },
    /// A decoded value of a ski area (a checkpoint's) out of range.
    #[error("{field} = {value} is implausible: {expected}")]
    Implausible {
        /// What the value is.
        field: String,
        /// The value.
        value: String,
        /// What it should be.
        expected: String,
    },
    /// The PNG encoder failed.
    #[error("cannot encode the track PNG: {source}")]
    Png {
        /// Encoder error.
        #[source]
        source: image::ImageError,
    },
}
