//! The cover job: what a front end asks for ([`CoverJob`], the flags over a parameter file
//! through [`CoverOverrides`]), its checks before any work ([`CoverJob::check`]), its typed
//! errors ([`CoverJobError`], with [`CoverJobError::is_bad_input`] for the exit code) and its
//! outcome ([`CoverOutcome`]: the snow mesh and the typed report of `report.json`).
//!
//! [`run`] reads the mesh (and the DEM it stands on, [`super::input`]), then runs the chosen
//! method: the diffusion cover ([`super::diffusion`]) or Fearing's ([`super::flakes`]). The
//! front end hears the stages through its [`Control`]; a cancel asked between two stages ends
//! the job with [`CoverJobError::Cancelled`] and nothing written.

use super::report::{DiffusionCoverReport, FearingInputSummary};
use super::{CoverParameters, diffusion, flakes, input};
use crate::control::{Control, StageCancelled, Stages};
use crate::dem_source::DemSource;
use crate::output_folder::OutputFolder;
use crate::outputs::OutputError;
use serde::Serialize;
use snowscape_fearing::{FearingError, FearingReport, Material};
use snowscape_festenberg::FestenbergError;
use snowscape_mesh::{MeshError, Scene, SnowObject};
use std::path::PathBuf;
use std::time::Instant;

/// Frames of a turntable animation.
pub const TURNTABLE_FRAMES: (usize, usize) = (2, 720);

/// Frames of a growth animation.
pub const GROWTH_FRAMES: (usize, usize) = (1, 10_000);

/// The two snow-on-mesh methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CoverMethod {
    /// von Festenberg & Gumhold 2011: diffusion kernel on a height-span map, bridges,
    /// overhangs, boundary texture coordinates.
    Diffusion,
    /// Fearing 2000: flake shooting and angle-of-repose stability.
    Fearing,
}

/// The DEM a mesh stands on, and where.
#[derive(Debug, Clone)]
pub struct CoverDem {
    pub dem: DemSource,
    /// The mesh's anchor in map coordinates (`None`: the DEM's centre).
    pub at: Option<[f64; 2]>,
}

/// One mesh cover to compute: the mesh, how to read it, the method and its parameters, and
/// what to write.
#[derive(Debug, Clone)]
pub struct CoverJob {
    /// The triangle mesh (.obj, .ply, .gltf/.glb).
    pub mesh: PathBuf,
    /// Its up axis as the user gave it (`y` or `z`; recorded as given).
    pub up: String,
    /// Metres per mesh unit, finite and > 0.
    pub scale: f64,
    pub method: CoverMethod,
    /// Both methods' parameters (a file's, with the front end's overrides); the chosen
    /// method's are checked before any work.
    pub parameters: CoverParameters,
    /// The parameter file they came from (recorded in the report).
    pub parameters_file: Option<PathBuf>,
    /// The DEM the mesh stands on: the terrain around it is covered too.
    pub dem: Option<CoverDem>,
    /// The diffusion cover's growth animation: frames in [`GROWTH_FRAMES`] (needs an output
    /// folder; Fearing's cover has none and ignores it).
    pub growth: Option<usize>,
    /// `turntable.gif`: frames in [`TURNTABLE_FRAMES`] (needs an output folder).
    pub turntable: Option<usize>,
    /// The output folder (created if missing); `None`: nothing is written (the Python package).
    pub output: Option<PathBuf>,
}

impl CoverJob {
    /// A cover of `mesh` by `method` with the defaults of `snowscape cover`: y up, metres, the
    /// default parameters, no DEM, nothing written.
    pub fn new(mesh: impl Into<PathBuf>, method: CoverMethod) -> Self {
        Self {
            mesh: mesh.into(),
            up: "y".into(),
            scale: 1.0,
            method,
            parameters: CoverParameters::default(),
            parameters_file: None,
            dem: None,
            growth: None,
            turntable: None,
            output: None,
        }
    }

    /// Whether the job draws a growth animation (the diffusion cover's only).
    pub(super) fn grows(&self) -> bool {
        self.method == CoverMethod::Diffusion && self.growth.is_some()
    }

    /// Checks every value before any file is read: the turntable's and the growth's frames
    /// (and that they have a folder to go to), the scale, the up axis and the chosen method's
    /// parameters (Fearing's depth, when left to the scene, is checked once the scene is read).
    pub fn check(&self) -> Result<(), CoverJobError> {
        if let Some(n) = self.turntable {
            let (lo, hi) = TURNTABLE_FRAMES;
            if !(lo..=hi).contains(&n) {
                return Err(CoverJobError::TurntableFrames(n));
            }
        }
        if self.method == CoverMethod::Diffusion
            && let Some(n) = self.growth
        {
            let (lo, hi) = GROWTH_FRAMES;
            if !(lo..=hi).contains(&n) {
                return Err(CoverJobError::GrowthFrames(n));
            }
        }
        if self.output.is_none() {
            if self.turntable.is_some() {
                return Err(CoverJobError::NeedsOutputFolder("a turntable"));
            }
            if self.grows() {
                return Err(CoverJobError::NeedsOutputFolder("a growth animation"));
            }
        }
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(CoverJobError::Scale(self.scale));
        }
        self.up
            .parse::<snowscape_mesh::UpAxis>()
            .map_err(|source| CoverJobError::Up {
                up: self.up.clone(),
                source: Box::new(source),
            })?;
        match self.method {
            CoverMethod::Diffusion => self
                .parameters
                .diffusion
                .validate()
                .map_err(|e| CoverJobError::Diffusion(Box::new(e))),
            CoverMethod::Fearing => {
                let mut p = self.parameters.fearing.clone();
                if !self.parameters.fearing_depth_set {
                    // The scene's default depth (2 % of its diameter) is not known yet.
                    p.depth_m = 1.0;
                }
                p.validate().map_err(CoverJobError::Fearing)
            }
        }
    }

    /// The stages of the job, in the order they run: reading, the cover, and with a folder the
    /// files, the turntable and the growth animation.
    pub(super) fn stage_count(&self) -> usize {
        let writes = match self.output {
            Some(_) => 1 + usize::from(self.turntable.is_some()) + usize::from(self.grows()),
            None => 0,
        };
        2 + writes
    }
}

/// What a front end's flags set over a parameter file (`snowscape cover --depth ... --seed`):
/// applied by [`CoverOverrides::apply`] to the chosen method's parameters only.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CoverOverrides {
    /// Snow depth on open flat ground, m (both methods).
    pub depth_m: Option<f64>,
    /// Diffusion: the kernel radius R, m.
    pub radius_m: Option<f64>,
    /// Diffusion: the longest gap bridged, m.
    pub bridge_m: Option<f64>,
    /// Diffusion: overhangs (on when the file or the flag sets them).
    pub overhang: bool,
    /// Diffusion: the height-span map's column spacing, m.
    pub resolution_m: Option<f64>,
    /// Fearing: a material preset (snow, flour, sand, water), replacing the file's material.
    pub material: Option<String>,
    /// Fearing: the angle of repose, degrees.
    pub aor_deg: Option<f64>,
    /// Fearing: the wall-clock safety net, s.
    pub budget_s: Option<f64>,
    /// Fearing: the mean flake flutter radius, m. Always applied: `None` is the material's
    /// (as `snowscape cover` has always done, a file's `flutter_m` gives way to the flag).
    pub flutter_m: Option<f64>,
    /// Fearing: the constant wind (east, north), m/s.
    pub wind_m_s: Option<[f64; 2]>,
    /// Fearing: the random seed.
    pub seed: Option<u64>,
    /// Fearing: the launch sites aimed at.
    pub sites: Option<usize>,
    /// Fearing: the accumulation passes.
    pub passes: Option<u32>,
    /// Fearing: the wind's transport share.
    pub wind_transport: Option<f64>,
}

impl CoverOverrides {
    /// `file` with every override of `method`'s parameters applied (the ranges are the job's
    /// to check); an unknown material preset is refused.
    pub fn apply(
        &self,
        method: CoverMethod,
        mut file: CoverParameters,
    ) -> Result<CoverParameters, FearingError> {
        match method {
            CoverMethod::Diffusion => {
                let d = &mut file.diffusion;
                d.depth_m = self.depth_m.or(d.depth_m);
                d.radius_m = self.radius_m.or(d.radius_m);
                d.bridge_m = self.bridge_m.or(d.bridge_m);
                d.overhang |= self.overhang;
                d.resolution_m = self.resolution_m.or(d.resolution_m);
            }
            CoverMethod::Fearing => {
                let f = &mut file.fearing;
                if let Some(m) = &self.material {
                    f.material = Material::preset(m)?;
                }
                if let Some(a) = self.aor_deg {
                    f.material.aor_deg = a;
                }
                if let Some(d) = self.depth_m {
                    f.depth_m = d;
                    file.fearing_depth_set = true;
                }
                if let Some(b) = self.budget_s {
                    f.budget_s = b;
                }
                f.flutter_m = self.flutter_m;
                if let Some(w) = self.wind_m_s {
                    f.wind_m_s = w;
                }
                if let Some(seed) = self.seed {
                    f.seed = seed;
                }
                if let Some(n) = self.sites {
                    f.target_sites = n;
                }
                if let Some(p) = self.passes {
                    f.passes = p;
                }
                if let Some(w) = self.wind_transport {
                    f.wind_transport = w;
                }
            }
        }
        Ok(file)
    }
}

/// Why a cover job was refused or failed.
#[derive(Debug, thiserror::Error)]
pub enum CoverJobError {
    #[error("turntable {0}: 2..=720 frames")]
    TurntableFrames(usize),
    #[error("growth must be 1..=10000 frames, got {0}")]
    GrowthFrames(usize),
    /// A turntable or a growth animation asked of a job that writes nothing.
    #[error("{0} needs an output folder")]
    NeedsOutputFolder(&'static str),
    #[error("scale must be a positive number of metres per mesh unit, got {0}")]
    Scale(f64),
    #[error("up {up:?}: {source}")]
    Up {
        up: String,
        #[source]
        source: Box<MeshError>,
    },
    /// A diffusion parameter out of its range, or the diffusion cover refused the scene.
    #[error(transparent)]
    Diffusion(Box<FestenbergError>),
    /// A Fearing parameter out of its range, or the Fearing cover refused the scene (or ran
    /// past its wall-clock safety net).
    #[error(transparent)]
    Fearing(FearingError),
    /// The mesh cannot be read (or the DEM triangulated).
    #[error(transparent)]
    Mesh(MeshError),
    /// The DEM cannot be read.
    #[error(transparent)]
    Dem(snowscape_io::RasterError),
    #[error("{at:?} lies outside the DEM {dem}")]
    AtOutsideDem { at: [f64; 2], dem: String },
    #[error("placing {} on {dem}", mesh.display())]
    Placement {
        mesh: PathBuf,
        dem: String,
        #[source]
        source: Box<MeshError>,
    },
    #[error("the mesh has no triangles")]
    NoTriangles,
    #[error("the DEM {0} has no valid cells around the mesh")]
    NoDemCells(String),
    /// The output folder cannot be opened (nothing was run).
    #[error(transparent)]
    OutputFolder(OutputError),
    /// The front end cancelled the job before the stage named.
    #[error("cancelled before {stage}; nothing was written")]
    Cancelled { stage: &'static str },
    /// No snow settled on the diffusion cover's sites.
    #[error(
        "no snow settled on {} (every site is an edge at resolution {resolution_m} m: try a finer one)",
        mesh.display()
    )]
    NoDiffusionSnow { mesh: PathBuf, resolution_m: f64 },
    /// No snow settled deep enough for Fearing's surface.
    #[error(transparent)]
    NoFearingSnow(FearingError),
    /// The growth animation failed.
    #[error(transparent)]
    Growth(Box<FestenbergError>),
    /// An output could not be written or committed.
    #[error(transparent)]
    Output(OutputError),
    #[error("cannot encode the cover report: {0}")]
    Report(#[source] serde_json::Error),
}

impl From<StageCancelled> for CoverJobError {
    fn from(c: StageCancelled) -> Self {
        Self::Cancelled { stage: c.0 }
    }
}

impl CoverJobError {
    /// Whether the job was refused for its input (the values, the mesh, the DEM, the folder, a
    /// scene the method cannot cover) rather than failing while it ran or wrote.
    pub fn is_bad_input(&self) -> bool {
        match self {
            Self::Diffusion(e) => !matches!(**e, FestenbergError::Mesh(MeshError::Write(_))),
            Self::Cancelled { .. }
            | Self::NoDiffusionSnow { .. }
            | Self::NoFearingSnow(_)
            | Self::Growth(_)
            | Self::Output(_)
            | Self::Report(_) => false,
            _ => true,
        }
    }
}

/// Fearing's report with what the job read as its `input` (`report.json` of a Fearing cover).
#[derive(Debug, Clone, Serialize)]
pub struct FearingCoverReport {
    #[serde(flatten)]
    pub cover: FearingReport,
    pub input: FearingInputSummary,
}

/// A cover's report, as `report.json` holds it.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum CoverReport {
    Diffusion(DiffusionCoverReport),
    Fearing(FearingCoverReport),
}

/// A finished cover: the scene it covered, its snow and its report.
#[derive(Debug, Clone)]
pub struct CoverOutcome {
    /// The scene in metres, z up (the terrain around the mesh included when on a DEM).
    pub scene: Scene,
    /// The snow surface (the diffusion cover's textured mesh, Fearing's surface).
    pub snow: SnowObject,
    /// Fearing's dusting of the faces too steep to hold snow, if any.
    pub dusting: Option<SnowObject>,
    pub report: CoverReport,
    /// Files written, relative to the output folder (empty without one).
    pub files: Vec<String>,
}

/// Runs the job: checks it, reads the mesh (standing it on the DEM), covers it and, with an
/// output folder, writes every file and `report.json` (staged, then committed together).
///
/// `control` hears the stages (reading, the cover, the files, the turntable, the growth) as
/// `progress(done, total)` and a status line each; a cancel is asked between two stages and
/// before the commit, and ends the job with [`CoverJobError::Cancelled`], nothing written.
pub fn run(job: &CoverJob, control: &mut dyn Control) -> Result<CoverOutcome, CoverJobError> {
    let t0 = Instant::now();
    job.check()?;
    let mut stages = Stages::new(control, job.stage_count());
    stages.begin("reading the mesh")?;
    let input = input::read(job)?;
    stages.begin(match job.method {
        CoverMethod::Diffusion => "covering (diffusion)",
        CoverMethod::Fearing => "covering (fearing)",
    })?;
    let folder = match &job.output {
        Some(dir) => {
            let folder = OutputFolder::open(dir).map_err(CoverJobError::OutputFolder)?;
            folder
                .check_subfolder("growth")
                .map_err(CoverJobError::OutputFolder)?;
            Some(folder)
        }
        None => None,
    };
    match job.method {
        CoverMethod::Diffusion => diffusion::run(job, input, folder, &mut stages, t0),
        CoverMethod::Fearing => flakes::run(job, input, folder, &mut stages, t0),
    }
}
