//! # snowscape
//!
//! Snow-covered landscapes from real terrain: a winter of snowfall, melt, sun and wind,
//! powder drifting into cornices, slope shedding, avalanches and skiers on a DEM; snow
//! settling on meshes (von Festenberg & Gumhold 2011 diffusion, Fearing 2000 flakes); 3D wind
//! transport of snow around buildings and relief.
//!
//! This crate is the library users depend on: it re-exports the model crates under short
//! names and holds the paths every front end shares (the command-line program `snowscape`,
//! the browser editor, the Python package), so that the same inputs give the same bytes from
//! each:
//!
//! | module | what it holds |
//! |---|---|
//! | [`terrain`] | the grid that owns its geometry (size, cell size, origin, CRS), the layered snow cover, the bundled procedural terrain |
//! | [`io`] | rasters in and out (GeoTIFF, ESRI ASCII, PNG16, RAW16, NPY, EXR), atomic writes |
//! | [`environment`] | sun (with shadows), sky view, bounce, temperature and wind fields |
//! | [`season`] | the winter: scenario, scheduler of events, every phenomenon's step |
//! | [`avalanche`] | the avalanche flow run to rest, release areas |
//! | [`skiers`] | skier trajectories and tracks |
//! | [`transport`] | 3D wind transport of snow over a voxel grid |
//! | [`festenberg`], [`fearing`], [`mesh`] | snow on meshes (diffusion, flakes), mesh input and output |
//! | [`render`] | previews, glTF, GIF/PNG encoding |
//! | [`outputs`] | the output layer of a season (every file of `snowscape run`) |
//! | [`season_run`] | one season run to its end with snapshots, checkpoints, resume and every output (the path of `snowscape run` and `demo`) |
//! | [`simulation`] | the one driver of a season (chunks to a stop time, outputs on schedules, progress and cancel through a `Control`), for the command line, the editor and Python |
//! | [`report`] | the typed `report.json` of every job |
//! | [`avalanche_job`] | one avalanche from release to rest on a DEM, its range checks, maps, frames, comparison and typed `report.json` (the path of `snowscape avalanche` and the Python package's `avalanche`) |
//! | [`avalanche_release`] | one avalanche's release on a DEM (file, mask or rupture point), as `snowscape avalanche` and the Python package take it |
//! | [`cover`] | snow on a mesh scene, alone or on a DEM, by either method: the parameters from a TOML file, the files, the typed `report.json` (the path of `snowscape cover` and the Python package's `cover`) |
//! | [`dem_source`] | a job's DEM: a file it reads after its checks, or a grid in memory |
//! | [`engine_export`] | a run's terrain and snow for Unreal, Unity or Godot: heightmaps, weight maps, import scales |
//! | [`validation`] | a run's snow depth against a measured depth raster: matching, statistics, baselines, class ratios, figures and the typed `validation.json` (the path of `snowscape validate` and the Python package's `validate`) |
//! | [`transport_job`] | a 3D transport run over a DEM, a mesh, a mesh on a DEM or a scenario's scene: the scenario, the wind grid fitted to the scene, the files and the typed `report.json` (the path of `snowscape transport` and the Python package's `transport`) |
//!
//! Every phenomenon is a module with a pure `step(params, state, scratch, dt)`, its
//! parameters a struct whose fields carry units and cite their source, its errors a typed
//! enum naming the offending value. The equations and their sources are in `docs/src/model.md`,
//! the data flow and the crates in `docs/src/architecture.md`.
//!
//! ## A winter from code
//!
//! ```
//! use snowscape::prelude::*;
//!
//! // The bundled procedural terrain (no input file), 64 x 64 cells of 20 m.
//! let bedrock = alpine(&AlpineParams { size: 64, ..AlpineParams::default() })?;
//! let scenario = Scenario { days: 3.0, seed: 7, latitude_deg: Some(46.5), ..Scenario::default() };
//! let mut winter = Winter::new(scenario, LayeredTerrain::from_bedrock(bedrock))?;
//! winter.run_until(3.0)?;
//! let depth = winter.terrain.total_depth();
//! assert!(depth.iter().all(|d| d.is_finite() && *d >= 0.0));
//! // The season's volume budget closes: the snow on the ground is what fell, less what
//! // melted, densified or left the grid.
//! let (store, budget) = (winter.terrain.snow_volume(), winter.budget());
//! assert!((store - budget.expected_store()).abs() <= 1e-5 * budget.snowfall.max(1.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! The examples in `crates/snowscape/examples` run a season on a DEM and write every output,
//! an avalanche to rest, a mesh cover and a transport run.

pub mod avalanche_job;
pub mod avalanche_release;
pub mod control;
pub mod cover;
pub mod cpu;
pub mod dem_source;
pub mod engine_export;
pub mod memory;
pub mod messages;
pub mod output_folder;
pub mod outputs;
pub mod report;
pub mod season_run;
pub mod simulation;
pub mod station;
pub mod transport_job;
pub mod validation;

pub use snowscape_avalanche as avalanche;
pub use snowscape_environment as environment;
pub use snowscape_fearing as fearing;
pub use snowscape_festenberg as festenberg;
pub use snowscape_io as io;
pub use snowscape_mesh as mesh;
pub use snowscape_render as render;
pub use snowscape_season as season;
pub use snowscape_skiers as skiers;
pub use snowscape_terrain as terrain;
pub use snowscape_transport as transport;

/// The types most programs need.
pub mod prelude {
    pub use snowscape_avalanche::{
        AvalancheParams, AvalancheWorkspace, RestOutcome, RunOptions as AvalancheRunOptions,
    };
    pub use snowscape_io::{ReadOptions, read_terrain, write_geotiff};
    pub use snowscape_season::scenario::Scenario;
    pub use snowscape_season::winter::Winter;
    pub use snowscape_terrain::procedural::{AlpineParams, alpine};
    pub use snowscape_terrain::{Crs, Grid, GridGeometry, LayeredTerrain, SnowLayer};
}
