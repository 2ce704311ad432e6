//! Typed errors of the diffusion snow cover. Every variant names the offending value, so the
//! command line can tell the user what to change.

use snowscape_mesh::MeshError;
use thiserror::Error;

/// Why a snow cover could not be computed.
#[derive(Debug, Error)]
pub enum FestenbergError {
    /// A parameter outside its valid range.
    #[error("invalid {name} {value}: expected {expected}")]
    InvalidParameter {
        name: &'static str,
        value: String,
        expected: &'static str,
    },
    /// The kernel cylinder would hold too many columns for the chosen resolution.
    #[error(
        "kernel radius {radius_m} m spans {columns} columns of {resolution_m} m, more than \
         {max} per kernel: use a coarser --resolution or a smaller --radius"
    )]
    KernelTooLarge {
        radius_m: f64,
        resolution_m: f64,
        columns: usize,
        max: usize,
    },
    /// The scene has nothing that can hold snow.
    #[error(
        "the scene has no upward-facing surface with free space above it: nothing can hold snow"
    )]
    NoSnowSites,
    /// The scene (or its height-span map) is unusable.
    #[error(transparent)]
    Mesh(#[from] MeshError),
}

/// Shorthand for an [`FestenbergError::InvalidParameter`].
pub(crate) fn invalid(name: &'static str, value: f64, expected: &'static str) -> FestenbergError {
    FestenbergError::InvalidParameter {
        name,
        value: value.to_string(),
        expected,
    }
}
