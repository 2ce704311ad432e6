//! One 3D transport run (Jubert 2018, `snowscape::transport`: a 3D wind, the precipitation
//! map, SnowTran-3D saltation, suspension, sublimation and melt through a weather timeline):
//! the job of `snowscape transport` and of the Python package's `snowscape.transport`, so that
//! the same inputs give the same bytes from each front end.
//!
//! The job ([`run`], [`TransportJob`]) is prepared first ([`prepare`]: every refusal before any
//! work or file): which scenario (a file, a shipped one, or the Table 7.I weather on the input
//! scene, [`load_scenario`]), the scene as a height map (a DEM, [`dem_heights`]; a mesh's top
//! view, alone or standing on the DEM; or the scenario's own scene), the wind grid fitted to the
//! scene when no scenario file sets it ([`fit_to_scene`]) and the front end's [`Overrides`].
//! Then it runs the pipeline and, with an output folder, writes the maps, the mean 3D wind, a
//! preview and `report.json` ([`write_outputs`], the typed [`TransportReport`]; the file names
//! and keys are a contract), staged and committed together through
//! [`crate::output_folder::OutputFolder`].

use snowscape_terrain::{Grid, GridGeometry};
use snowscape_transport::scenario::{Scenario, SceneSpec, fit_voxels, shipped_scenario};
use std::path::Path;

mod job;
mod outputs;
mod scene;
pub use job::{PreparedTransport, TransportJob, TransportMesh, TransportOutcome, prepare, run};
pub use outputs::{
    DepthStats, FlakeCounts, GridSize, KgBudget, OutputError as TransportOutputError, RunContext,
    TransportReport, TransportTimings, VoxelSize, WindSolve, write_outputs,
};
pub use scene::{DemSummary, MeshSummary, SceneInput, SceneSummary};

/// Columns of the wind grid fitted to a scene without a scenario file.
pub const FITTED_COLUMNS: usize = 128;

/// Why a transport job was refused or failed.
#[derive(Debug, thiserror::Error)]
pub enum TransportJobError {
    #[error("cannot read scenario {path}: {source}")]
    Read {
        path: String,
        #[source]
        source: snowscape_io::InputError,
    },
    /// Not TOML, or keys the scenario does not have.
    #[error("scenario {name}: {message}")]
    Parse { name: String, message: String },
    #[error("scenario {name}: {source}")]
    Invalid {
        name: String,
        #[source]
        source: snowscape_transport::TransportError,
    },
    #[error("scenario {0:?} is neither a file nor a shipped scenario (castle, valley)")]
    Unknown(String),
    #[error("{0}: every cell is nodata")]
    AllNodata(String),
    /// The scenario with the front end's overrides is out of range.
    #[error("scenario after the overrides: {source}")]
    Overridden {
        #[source]
        source: snowscape_transport::TransportError,
    },
    /// Neither a DEM, a mesh nor a scenario with a scene.
    #[error("no scene: give a DEM, a mesh, or a scenario with a [scene] (e.g. castle)")]
    NoScene,
    /// The DEM cannot be read.
    #[error(transparent)]
    Dem(snowscape_io::RasterError),
    /// The mesh cannot be read or seen from above.
    #[error(transparent)]
    Mesh(snowscape_mesh::MeshError),
    #[error("up {up:?}: {source}")]
    Up {
        up: String,
        #[source]
        source: Box<snowscape_mesh::MeshError>,
    },
    #[error("scale: {0}")]
    Scale(#[source] snowscape_mesh::MeshError),
    #[error("{0}: no valid triangle")]
    NoTriangles(String),
    /// A top view's cell size or margin given for a mesh on a DEM.
    #[error("the resolution and margin apply to a mesh alone: on a DEM the DEM's grid is used")]
    MeshGridOnDem,
    #[error("{at:?} lies outside the DEM")]
    AtOutsideDem { at: [f64; 2] },
    /// The DEM is no grid.
    #[error(transparent)]
    Terrain(#[from] snowscape_terrain::TerrainError),
    /// The transport refused the scene or the scenario (its sizes, its scene), or failed.
    #[error(transparent)]
    Transport(snowscape_transport::TransportError),
    /// The output folder cannot be opened (nothing was run).
    #[error(transparent)]
    OutputFolder(crate::outputs::OutputError),
    /// The front end cancelled the job before the stage named.
    #[error("cancelled before {stage}; nothing was written")]
    Cancelled { stage: &'static str },
    #[error("the scene summary: {0}")]
    Summary(#[source] serde_json::Error),
    /// An output could not be written.
    #[error(transparent)]
    Output(TransportOutputError),
    /// The outputs could not be moved into place.
    #[error(transparent)]
    Commit(crate::outputs::OutputError),
}

impl From<crate::control::StageCancelled> for TransportJobError {
    fn from(c: crate::control::StageCancelled) -> Self {
        Self::Cancelled { stage: c.0 }
    }
}

impl TransportJobError {
    /// Whether the job was refused for its input (the scenario, the scene, the overrides, the
    /// folder, sizes the transport refuses) rather than failing while it wrote.
    pub fn is_bad_input(&self) -> bool {
        !matches!(
            self,
            Self::Cancelled { .. } | Self::Summary(_) | Self::Output(_) | Self::Commit(_)
        )
    }
}

/// The scenario of a run and whether the user named it (a file or a shipped scenario's name);
/// `None`: the weather of Table 7.I (12 h of snowfall at −5 °C, then 24 h at +10 °C, a west
/// wind of 11 m/s) on the input scene.
pub fn load_scenario(text: Option<&str>) -> Result<(Scenario, bool), TransportJobError> {
    let parse = |source: &str, name: String| {
        let s = Scenario::from_toml(source).map_err(|e| TransportJobError::Parse {
            name: name.clone(),
            message: e.to_string(),
        })?;
        s.validate()
            .map_err(|source| TransportJobError::Invalid { name, source })?;
        Ok::<_, TransportJobError>(s)
    };
    let Some(text) = text else {
        let castle = shipped_scenario("castle").unwrap_or_default();
        let mut s = parse(castle, "shipped castle".into())?;
        s.name = "table_7_1_weather".into();
        s.scene = SceneSpec::Input;
        s.wind_iterations = 20;
        return Ok((s, false));
    };
    let path = Path::new(text);
    let (source, name) = if path.exists() {
        let s = snowscape_io::input::read_regular_text(path).map_err(|source| {
            TransportJobError::Read {
                path: path.display().to_string(),
                source,
            }
        })?;
        (s, path.display().to_string())
    } else if let Some(s) = shipped_scenario(text) {
        (s.to_string(), format!("shipped scenario {text}"))
    } else {
        return Err(TransportJobError::Unknown(text.to_string()));
    };
    Ok((parse(&source, name)?, true))
}

/// A DEM as the scene's heights: nodata cells at the lowest valid altitude (solid ground
/// everywhere; the mask keeps them nodata in the outputs), and how many were filled. `what`
/// names the DEM in the error.
pub fn dem_heights(grid: &Grid, what: &str) -> Result<(Vec<f32>, usize), TransportJobError> {
    let mask = grid.mask();
    let lowest = (0..grid.data().len())
        .filter(|&i| mask.is_valid(i))
        .map(|i| grid.data()[i])
        .fold(f32::INFINITY, f32::min);
    if !lowest.is_finite() {
        return Err(TransportJobError::AllNodata(what.to_string()));
    }
    let filled = (0..grid.data().len())
        .filter(|&i| !mask.is_valid(i))
        .count();
    let heights = grid
        .data()
        .iter()
        .enumerate()
        .map(|(i, &z)| if mask.is_valid(i) { z } else { lowest })
        .collect();
    Ok((heights, filled))
}

/// Fits the scenario's wind grid (voxel size and layers) to the scene: what a run without a
/// scenario file uses ([`FITTED_COLUMNS`] columns over the scene).
pub fn fit_to_scene(scenario: &mut Scenario, geometry: &GridGeometry, heights: &[f32]) {
    let lowest = heights.iter().fold(f32::INFINITY, |m, &z| m.min(z));
    let highest = heights.iter().fold(f32::NEG_INFINITY, |m, &z| m.max(z));
    let (size, layers) = fit_voxels(
        geometry,
        f64::from(lowest),
        f64::from(highest),
        geometry.cell_size_x().max(geometry.cell_size_y()),
        FITTED_COLUMNS,
    );
    scenario.voxel_size_m = size;
    scenario.voxel_layers = layers;
}

/// What a front end may override in a scenario (`--hours`, `--flakes`, ... of `snowscape
/// transport`, the keywords of the Python package).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overrides {
    /// Simulated duration, hours.
    pub hours: Option<f64>,
    /// Precipitation flakes.
    pub flakes: Option<usize>,
    /// Seed of the flakes.
    pub seed: Option<u64>,
    /// Wind solver iterations.
    pub wind_iterations: Option<usize>,
    /// Horizontal voxel size, m.
    pub voxel_size: Option<f64>,
    /// Voxel layers.
    pub voxel_layers: Option<usize>,
    /// Uniform precipitation instead of the flakes' map.
    pub uniform_precipitation: bool,
}

impl Overrides {
    /// Whether the wind grid is set (then it is not fitted to the scene).
    pub fn sets_voxels(&self) -> bool {
        self.voxel_size.is_some() || self.voxel_layers.is_some()
    }

    /// Applies the overrides and checks the scenario.
    pub fn apply(&self, s: &mut Scenario) -> Result<(), TransportJobError> {
        if let Some(h) = self.hours {
            s.duration_h = h;
        }
        if let Some(n) = self.flakes {
            s.flakes.count = n;
        }
        if let Some(n) = self.wind_iterations {
            s.wind_iterations = n;
        }
        if let Some(seed) = self.seed {
            s.flakes.seed = seed;
        }
        if let Some(v) = self.voxel_size {
            s.voxel_size_m = v;
        }
        if let Some(n) = self.voxel_layers {
            s.voxel_layers = n;
        }
        if self.uniform_precipitation {
            s.uniform_precipitation = true;
        }
        s.validate()
            .map_err(|source| TransportJobError::Overridden { source })
    }
}
