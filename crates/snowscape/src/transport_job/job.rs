//! The transport job: what a front end asks for ([`TransportJob`]), its preparation with every
//! refusal before any work or file ([`prepare`]: the scenario, the scene, the wind grid, the
//! overrides, the run's own size checks), the run itself ([`PreparedTransport::run`]: the
//! pipeline of `snowscape::transport::scenario::run`, then the files) and its outcome
//! ([`TransportOutcome`]: the maps and the typed report of `report.json`).
//!
//! The transport's pipeline has no step callback, so the front end hears the job's stages
//! (reading the scene, the transport, the files); a cancel asked between two stages ends the
//! job with [`TransportJobError::Cancelled`] and nothing written.

use super::outputs::{RunContext, TransportReport, write_outputs};
use super::scene::{self, SceneInput, SceneSummary};
use super::{Overrides, TransportJobError, fit_to_scene, load_scenario};
use crate::control::{Control, Stages};
use crate::dem_source::DemSource;
use crate::output_folder::OutputFolder;
use snowscape_terrain::{GridGeometry, NodataMask};
use snowscape_transport::scenario::{
    RunOutputs, Scenario, check_voxel_height, run as run_pipeline,
};
use snowscape_transport::wind3d::voxel::VoxelGrid;
use std::path::PathBuf;
use std::time::Instant;

/// The stages of a transport job: reading the scene, the transport, the files.
const STAGES: usize = 3;

/// A mesh as the transport's scene, alone or standing on the job's DEM.
#[derive(Debug, Clone)]
pub struct TransportMesh {
    /// The triangle mesh (.obj, .gltf/.glb, .ply).
    pub path: PathBuf,
    /// Its up axis (`y` or `z`).
    pub up: String,
    /// Metres per mesh unit.
    pub scale: f64,
    /// A mesh alone: the top view's cell size, m (default: its longer side / 100).
    pub resolution_m: Option<f64>,
    /// A mesh alone: the open ground around it, m (default: its longer side).
    pub margin_m: Option<f64>,
    /// A mesh on a DEM: its anchor in map coordinates (default: the DEM's centre).
    pub at: Option<[f64; 2]>,
}

impl TransportMesh {
    /// `path`, y up, in metres, with the default grid and anchor.
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            up: "y".into(),
            scale: 1.0,
            resolution_m: None,
            margin_m: None,
            at: None,
        }
    }
}

/// One transport run to do: the scenario, the scene, the overrides and where to write.
#[derive(Debug, Clone, Default)]
pub struct TransportJob {
    /// A scenario file or a shipped scenario's name (`castle`, `valley`); `None`: 36 h of the
    /// Table 7.I weather on the input, with a wind grid fitted to it ([`load_scenario`]).
    pub scenario: Option<String>,
    /// The scene, or the ground the mesh stands on.
    pub dem: Option<DemSource>,
    /// A mesh as the scene, alone or on the DEM.
    pub mesh: Option<TransportMesh>,
    /// What the front end overrides in the scenario.
    pub overrides: Overrides,
    /// The output folder (created if missing); `None`: nothing is written (the Python package).
    pub output: Option<PathBuf>,
}

/// A job with its scenario and scene ready: nothing has been run or written yet.
#[derive(Debug)]
pub struct PreparedTransport {
    scenario: Scenario,
    scene: SceneInput,
    output: Option<PathBuf>,
    started: Instant,
}

/// A finished run: its report (as written to `report.json` when there is a folder), the scene
/// and the run's maps.
#[derive(Debug)]
pub struct TransportOutcome {
    pub report: TransportReport,
    /// The scene the run stood on (heights, nodata cells, its summary).
    pub scene: SceneInput,
    /// Everything the run produced.
    pub run: RunOutputs,
    /// Files written, relative to the output folder (empty without one).
    pub files: Vec<String>,
}

impl TransportOutcome {
    /// The run's maps over the transport grid, row-major: `depth` and `density` of the snow,
    /// the last step's fluxes `q_salt`, `q_susp`, `q_subl`, the `precipitation` ratio and the
    /// wind at the reference height, `wind_u` (east) and `wind_v` (north).
    pub fn maps(&self) -> [(&'static str, Vec<f32>); 8] {
        let r = &self.run;
        [
            ("depth", r.state.depth()),
            ("density", r.state.density.clone()),
            ("q_salt", r.q_salt.clone()),
            ("q_susp", r.q_susp.clone()),
            ("q_subl", r.q_subl.clone()),
            ("precipitation", r.precipitation_ratio.clone()),
            ("wind_u", r.wind_u.clone()),
            ("wind_v", r.wind_v.clone()),
        ]
    }

    /// The cells of the input that are nodata in the maps.
    pub fn mask(&self) -> &NodataMask {
        &self.scene.mask
    }
}

impl TransportJob {
    /// Checks the values that need no file: a mesh's top-view grid applies to a mesh alone.
    pub fn check(&self) -> Result<(), TransportJobError> {
        if let Some(m) = &self.mesh
            && self.dem.is_some()
            && (m.resolution_m.is_some() || m.margin_m.is_some())
        {
            return Err(TransportJobError::MeshGridOnDem);
        }
        Ok(())
    }
}

/// Prepares the job, refusing it before any work or file: checks it, loads the scenario,
/// builds the scene (the DEM, the mesh, or the scenario's own), fits the wind grid to the
/// scene unless a scenario file or an override sets it, applies the overrides and checks the
/// run's sizes (the wind grid's cells and its top above the scene).
pub fn prepare(job: &TransportJob) -> Result<PreparedTransport, TransportJobError> {
    let started = Instant::now();
    job.check()?;
    let (mut scenario, from_file) = load_scenario(job.scenario.as_deref())?;
    let scene = scene::build(job, &mut scenario)?;
    if !from_file && !job.overrides.sets_voxels() {
        // No scenario file: a wind grid fitted to the scene.
        fit_to_scene(&mut scenario, &scene.geometry, &scene.heights);
    }
    job.overrides.apply(&mut scenario)?;
    check_sizes(&scenario, &scene.geometry, &scene.heights)?;
    Ok(PreparedTransport {
        scenario,
        scene,
        output: job.output.clone(),
        started,
    })
}

/// The run's own checks of its sizes, made before any file is written (the run makes them
/// again): the wind grid's cell count and its top clearing the scene.
fn check_sizes(
    scenario: &Scenario,
    geometry: &GridGeometry,
    heights: &[f32],
) -> Result<(), TransportJobError> {
    VoxelGrid::dimensions(geometry, scenario.voxel_size_m, scenario.voxel_layers)
        .map_err(TransportJobError::Transport)?;
    let lowest = heights.iter().fold(f32::INFINITY, |m, &z| m.min(z));
    let highest = heights.iter().fold(f32::NEG_INFINITY, |m, &z| m.max(z));
    check_voxel_height(scenario, f64::from(lowest), f64::from(highest))
        .map_err(TransportJobError::Transport)
}

impl PreparedTransport {
    /// The scenario as it will run (overrides applied, wind grid fitted).
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The scene's grid.
    pub fn geometry(&self) -> &GridGeometry {
        &self.scene.geometry
    }

    /// What the scene was made of.
    pub fn summary(&self) -> &SceneSummary {
        &self.scene.summary
    }

    /// Runs the transport and, with an output folder, writes every file and `report.json`
    /// (staged, then committed together). `control` hears the stages after the reading (the
    /// transport, the files) of the job's three; a cancel between them ends the job with
    /// [`TransportJobError::Cancelled`], nothing written.
    pub fn run(self, control: &mut dyn Control) -> Result<TransportOutcome, TransportJobError> {
        let mut stages = Stages::new(control, STAGES);
        stages.begin("reading the scene")?;
        self.run_stages(&mut stages)
    }

    fn run_stages(self, stages: &mut Stages) -> Result<TransportOutcome, TransportJobError> {
        stages.begin("transport")?;
        let folder = match &self.output {
            Some(dir) => Some(OutputFolder::open(dir).map_err(TransportJobError::OutputFolder)?),
            None => None,
        };
        let (scenario, scene) = (self.scenario, self.scene);
        let out = run_pipeline(&scenario, &scene.geometry, &scene.heights)
            .map_err(TransportJobError::Transport)?;
        let input = serde_json::to_value(&scene.summary).map_err(TransportJobError::Summary)?;
        let wall_s = self.started.elapsed().as_secs_f64();
        let mut files = Vec::new();
        if let Some(folder) = &folder {
            stages.begin("writing outputs")?;
            let context = RunContext {
                input: input.clone(),
                mask: Some(&scene.mask),
                wall_s,
            };
            let written =
                write_outputs(folder.staging(), &scenario, &scene.heights, &out, &context)
                    .map_err(TransportJobError::Output)?;
            files = written
                .iter()
                .filter_map(|p| p.strip_prefix(folder.staging()).ok())
                .map(|p| p.to_string_lossy().into_owned())
                .collect();
        }
        stages.finish()?;
        if let Some(folder) = folder {
            folder
                .commit(&files, None)
                .map_err(TransportJobError::Commit)?;
        }
        Ok(TransportOutcome {
            report: TransportReport::new(&scenario, &out, input, wall_s),
            scene,
            run: out,
            files,
        })
    }
}

/// Runs the job: [`prepare`] (every refusal before any work), then
/// [`PreparedTransport::run`]. `control` hears the three stages (reading the scene, the
/// transport, the files) as `progress(done, 3)` and a status line each.
pub fn run(
    job: &TransportJob,
    control: &mut dyn Control,
) -> Result<TransportOutcome, TransportJobError> {
    let mut stages = Stages::new(control, STAGES);
    stages.begin("reading the scene")?;
    let prepared = prepare(job)?;
    prepared.run_stages(&mut stages)
}
