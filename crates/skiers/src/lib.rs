//! # snowscape-skiers: ski tracks
//!
//! Cordonnier et al. 2018, Section 6.2 (and 7.3 for the cell-by-cell movement): skiers are
//! agents that descend the snow cover, pack it, may release unstable snow, and leave tracks
//! that fade under new snow.
//!
//! - [`terminus`]: the distance-to-terminus map, a cellular automaton propagating the distance
//!   up from the end points of runs (local minima and the terrain edge, a valley floor, or
//!   caller-given cells) over cells with enough snow.
//! - [`steering`]: the paper's Eq. 4, `P(n) = 1[snow_n > threshold] · f(|s_n − s_t|) · w_d`
//!   over the look-ahead cells, with `f` a Gaussian preference for the target slope and `w_d`
//!   a turn weight (no reversal) times the terminus guide (no dead-ends).
//! - [`skier`]: one agent: smooth heading changes, cell-by-cell re-planning, staying on snow,
//!   stopping at a terminus or when stuck.
//! - [`refine`]: the refined track, sine waves of amplitude `a` and frequency
//!   `f = sqrt(sin²s − sin²st)/(4a·sin st)` around the coarse path.
//! - [`texture`]: the high-resolution track texture (sparse tiles, anti-aliased lines, fading
//!   by `exp(−added/fade_depth)`).
//! - [`effects`]: compaction (unstable → stable → compacted, mass kept), the decaying
//!   recent-skier map, trigger candidates drawn from the keyed random numbers.
//! - [`area`]: the state [`SkiArea`] and the pure [`step`]; [`snapshot`]: the area as plain
//!   data for a season's checkpoint, validated when restored; [`output`]: the PNG (with JSON
//!   sidecar and world file) and GeoJSON outputs.
//!
//! Units: metres, seconds, radians inside, degrees in [`SkiParams`]. Positions are local metres
//! (x east, y south of the grid's north-west corner, [`frame`]); outputs are in the DEM's map
//! coordinates.

pub mod area;
pub mod effects;
pub mod encode;
pub mod error;
pub mod frame;
pub mod params;
pub mod refine;
pub mod skier;
pub mod snapshot;
pub mod steering;
pub mod terminus;
pub mod texture;

pub use area::{FinishedSkier, SkiArea, SkiScratch, SkierReport, step};
pub use effects::{
    Compaction, TriggerCandidate, compact_cell, snow_water_equivalent, trigger_probability,
};
pub use encode::{PngDepth, TrackPng, TrackSidecar, encode_track_png, tracks_geojson};
pub use error::SkiError;
pub use params::SkiParams;
pub use refine::{effective_slope, turn_frequency};
pub use skier::{Skier, SteeringChoice, StopReason, Track};
pub use snapshot::{SkiAreaHeader, SkiAreaMaps, SkiTracks};
pub use terminus::{Terminus, TerminusMap};
pub use texture::TrackTexture;

use snowscape_terrain::procedural::{AlpineParams, alpine};
use snowscape_terrain::{LayeredTerrain, SnowLayer};

/// A ready-to-step scene for benchmarks (the criterion bench and the `snowscape bench`
/// registry): the procedural alpine terrain of `size`² cells (seed 1, 10 m cells) under a
/// uniform snow cover of 1 m stable and 0.5 m unstable snow, local minima and the edge as
/// termini, and `skiers` skiers spawned by the distance-weighted rule with `seed`.
pub fn bench_setup(
    size: usize,
    skiers: usize,
    seed: u64,
) -> Result<(SkiParams, SkiArea, LayeredTerrain), SkiError> {
    let bedrock = alpine(&AlpineParams {
        size,
        ..AlpineParams::default()
    })
    .map_err(|e| SkiError::InvalidParameter {
        name: "bench terrain size",
        value: size as f64,
        expected: if matches!(e, snowscape_terrain::TerrainError::InvalidSize { .. }) {
            "in 2..=16384"
        } else {
            "a valid procedural terrain"
        },
    })?;
    let mut terrain = LayeredTerrain::from_bedrock(bedrock);
    terrain.layer_mut(SnowLayer::Stable).fill(1.0);
    terrain.layer_mut(SnowLayer::Unstable).fill(0.5);
    let params = SkiParams::default();
    let mut area = SkiArea::new(&params, &terrain, Terminus::LocalMinima, seed)?;
    area.spawn_weighted(&params, &terrain, skiers)?;
    Ok((params, area, terrain))
}
