//! Typed errors of the transport crate: each carries the offending value.

use thiserror::Error;

/// A bad input to a transport computation.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum TransportError {
    /// A parameter outside its valid range.
    #[error("invalid transport parameter {name} = {value}: {reason}")]
    InvalidParameter {
        /// The parameter's name as in the scenario file.
        name: &'static str,
        /// Its value.
        value: f64,
        /// Why it is rejected.
        reason: &'static str,
    },
    /// A per-cell map whose length does not match the grid.
    #[error("{map} map has {actual} values but the {width}x{height} grid needs {expected}")]
    MapLength {
        /// Which map.
        map: &'static str,
        /// Grid width.
        width: usize,
        /// Grid height.
        height: usize,
        /// `width * height`.
        expected: usize,
        /// The map's length.
        actual: usize,
    },
    /// A time step that is negative, NaN or infinite.
    #[error("invalid time step {dt_s} s: it must be finite and non-negative")]
    InvalidTimeStep {
        /// The step, s.
        dt_s: f64,
    },
    /// A NaN or infinite value produced or met by a step.
    #[error("{phenomenon}: non-finite {what} = {value} at cell ({col}, {row})")]
    NonFinite {
        /// The phenomenon that met it.
        phenomenon: &'static str,
        /// Which quantity.
        what: &'static str,
        /// Column of the cell.
        col: usize,
        /// Row of the cell.
        row: usize,
        /// The value.
        value: f64,
    },
    /// A wind voxel grid larger than [`crate::wind3d::voxel::MAX_VOXELS`], refused before
    /// anything is allocated.
    #[error(
        "the wind grid of {nx} x {ny} x {nz} voxels (voxel_size_m = {voxel_size_m} over a \
         {extent_x_m} x {extent_y_m} m scene, voxel_layers = {nz}) is more than the {max} \
         voxels allowed: raise voxel_size_m or lower voxel_layers"
    )]
    TooManyVoxels {
        /// Voxels along x (saturated at `u64::MAX`).
        nx: u64,
        /// Voxels along y (saturated at `u64::MAX`).
        ny: u64,
        /// Voxel layers.
        nz: u64,
        /// The voxel side, m.
        voxel_size_m: f64,
        /// The scene's extent east-west, m.
        extent_x_m: f64,
        /// The scene's extent north-south, m.
        extent_y_m: f64,
        /// The cap, [`crate::wind3d::voxel::MAX_VOXELS`].
        max: u64,
    },
    /// A scene grid the terrain model rejects (its message names the value).
    #[error("invalid scene grid: {0}")]
    Scene(String),
    /// A weather timeline that is empty or not sorted by start time.
    #[error("invalid weather timeline: {reason} (period {index}, from_hour = {from_hour})")]
    Timeline {
        /// Index of the offending period.
        index: usize,
        /// Its start, h.
        from_hour: f64,
        /// What is wrong.
        reason: String,
    },
}

/// Checks that `value` is finite and within `[min, max]`.
pub(crate) fn check_range(
    name: &'static str,
    value: f64,
    min: f64,
    max: f64,
) -> Result<(), TransportError> {
    if value.is_finite() && value >= min && value <= max {
        Ok(())
    } else {
        Err(TransportError::InvalidParameter {
            name,
            value,
            reason: if value.is_finite() {
                "out of its valid range"
            } else {
                "must be finite"
            },
        })
    }
}

/// Checks that `value` is finite and strictly positive.
pub(crate) fn check_positive(name: &'static str, value: f64) -> Result<(), TransportError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(TransportError::InvalidParameter {
            name,
            value,
            reason: "must be finite and > 0",
        })
    }
}
