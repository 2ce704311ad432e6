//! # snowscape-avalanche: the avalanche flow core
//!
//! Cordonnier et al. 2018, Section 6.1 move released snow with a hydrostatic *virtual pipe*
//! model (O'Brien & Hodgins 1995, Šťava et al. 2008) on the 8-neighbour (Moore) stencil, with a
//! Coulomb yield term `g·tanθc` (static friction), a viscous term `−kv·U·φ` and a dry/wet mix
//! `α`. [`flow`] holds the flowing state and the pure [`flow::step`]; [`convert`] turns snow
//! layers into flowing snow ([`convert::release`]) and back ([`convert::deposit`]).
//! [`release_area`] says where an avalanche starts (shapefile polygons, raster masks, the
//! paper's rupture at a point); [`validation`] runs the validation cases that
//! `examples/validation.rs` tabulates.
//!
//! The scheme departs from the paper where it must (`docs/src/model.md#flow-model`) (a depth-dependent face
//! cross-section and momentum advection, so that waves travel at `sqrt(g·h)` and the dam-break
//! front follows Ritter's `2·sqrt(g·h0)`); [`flow`]'s module documentation states the equations.

pub mod comparison;
pub mod convert;
pub mod entrainment;
pub mod flow;
pub mod friction_maps;
pub mod release_area;
pub mod rest;
pub mod run;
pub mod validation;

pub use convert::{deposit, release, release_cells};
pub use entrainment::{EntrainmentParams, basal_shear_per_density};
pub use flow::{
    AvalancheError, AvalancheParams, AvalancheReport, AvalancheScratch, AvalancheState, BedSource,
    Border, FrictionLaw, SamosAtParams, SlopeGravity, cfl_dt, step, step_at_least, step_on,
};
pub use friction_maps::{FrictionMaps, MapMatch};
pub use release_area::{
    MapExtent, RasterRelease, ReleaseAreaError, ReleaseMask, Rupture, RuptureCells, RuptureParams,
    release_at_point, release_from_raster, release_from_shapefile, rupture_at_point,
};
pub use rest::{AvalancheWorkspace, ReleasedCells, RestOutcome};
pub use run::{AvalancheRun, RecordTiming, RunBuffers, RunOptions, RunSummary, StopReason};
