//! Typed errors of the Fearing 2000 cover: every variant names the offending value.

use thiserror::Error;

/// Why a Fearing cover could not be computed or written.
#[derive(Debug, Error)]
pub enum FearingError {
    /// A parameter outside its valid range.
    #[error("invalid {name} {value}: expected {expected}")]
    InvalidParameter {
        name: &'static str,
        value: String,
        expected: &'static str,
    },
    /// The scene has no upward-facing triangle to launch flakes from.
    #[error(
        "the scene has no upward-facing triangle (of {triangles} triangles, none has a normal \
         with z above {min_normal_z}); check the up axis"
    )]
    NoLaunchSites { triangles: usize, min_normal_z: f64 },
    /// The scene holds a non-finite vertex.
    #[error("object {object:?} vertex {vertex} is not finite: {value:?}")]
    NonFiniteVertex {
        object: String,
        vertex: usize,
        value: [f32; 3],
    },
    /// The snow weighting image ("snow writing") cannot be used.
    #[error("sky weight image {what}")]
    SkyWeight { what: String },
    /// The wall-clock safety net ([`crate::FearingParams::budget_s`]) ran out before the work
    /// (the flake budget, the stability passes) was done: an error rather than a cover that
    /// would depend on the machine's speed.
    #[error(
        "the cover ran past its wall-clock safety net of {budget_s} s ({elapsed_s:.1} s, in \
         {stage}); its work is set by flakes_per_site, target_sites and the stability passes, \
         not the clock: raise --budget or lower the work"
    )]
    BudgetExceeded {
        budget_s: f64,
        elapsed_s: f64,
        stage: String,
    },
    /// No snow lies deep enough to make a surface.
    #[error("no snow settled: none of the {sites} launch sites holds {min_depth_m} m or more")]
    NoSnow { sites: usize, min_depth_m: f64 },
}

/// Shorthand for a [`FearingError::InvalidParameter`].
pub(crate) fn invalid(
    name: &'static str,
    value: impl ToString,
    expected: &'static str,
) -> FearingError {
    FearingError::InvalidParameter {
        name,
        value: value.to_string(),
        expected,
    }
}
