//! One avalanche from release to rest on a DEM: the job of `snowscape avalanche` and of the
//! Python package's `snowscape.avalanche`, so that the same inputs give the same bytes from
//! each front end.
//!
//! The job checks every user value first ([`AvalancheSettings::check`]: the flow parameters,
//! the run options, the release thickness and snow cover, the frame interval, the corridor),
//! then releases the snow ([`crate::avalanche_release`]), matches the friction rasters
//! ([`friction_maps`]), reads the comparison's reference ([`compare`]), and runs the flow to
//! rest ([`snowscape_avalanche::AvalancheWorkspace::run_to_rest`]: the pipe-model flow of
//! Cordonnier et al. 2018 with the Coulomb, Voellmy or samosAT law). With an output folder it
//! writes the maps practitioners compare (peak thickness and velocity, deposit, footprint,
//! entrainment), playback frames and their GIF, the comparison's profile and `report.json`
//! ([`AvalancheReport`]; the file names and keys are a contract).

use crate::avalanche_release::{ReleaseError, ReleaseSpec, check_release_values, release_terrain};
use crate::control::Control;
use crate::outputs::OutputError;
use crate::report::InputSummary;
use snowscape_avalanche::validation::ThicknessConvention;
use snowscape_avalanche::{
    AvalancheError, AvalancheParams, AvalancheWorkspace, RestOutcome, RunOptions,
};
use snowscape_io::ReadOptions;
use snowscape_render::PreviewOptions;
use snowscape_terrain::Grid;
use std::path::PathBuf;

pub mod compare;
mod friction;
mod outputs;
mod report;
pub use compare::{CompareSpec, MAX_CORRIDOR_M};
pub use friction::{FrictionRasterError, FrictionRasters, friction_maps};
pub use report::{
    AvalancheReport, AvalancheSummary, FrictionRasterReport, FrictionReport, ReleaseReport,
    RunParameters, Timings, convention_name,
};

/// Shortest and longest simulated time between two playback frames, s.
pub const FRAME_INTERVAL_S: (f64, f64) = (0.01, 3600.0);

/// One avalanche to run: the DEM and what the user set.
#[derive(Debug, Clone)]
pub struct AvalancheJob {
    /// Where the DEM came from, for the report.
    pub source: String,
    /// The avalanche bed.
    pub dem: Grid,
    pub settings: AvalancheSettings,
}

/// Everything a user sets for an avalanche, checked by [`AvalancheSettings::check`] before
/// any work.
#[derive(Debug, Clone)]
pub struct AvalancheSettings {
    /// What is released: a file, a mask or a rupture point.
    pub release: ReleaseSpec,
    /// Release thickness, m, in (0, 50] (`None`: a shapefile's `thickness` field, else 1 m).
    pub thickness_m: Option<f64>,
    /// How the thickness is measured (slope-normal as AvaFrame's, or vertical).
    pub thickness_measured: ThicknessConvention,
    /// Loose snow laid outside the release for the flow to entrain, m, in [0, 50].
    pub snow_cover_m: f64,
    /// How a raster release mask is read (the DEM's options).
    pub dem_options: ReadOptions,
    /// The flow's law and parameters.
    pub flow: AvalancheParams,
    /// How long and how finely the flow runs, and when it stops.
    pub run: RunOptions,
    /// Per-cell friction rasters.
    pub friction_rasters: FrictionRasters,
    /// A reference run to compare with.
    pub compare: Option<CompareSpec>,
    /// Recorded in the report (the flow is deterministic).
    pub seed: u64,
    /// The output folder and its frames; `None`: nothing is written (the Python package).
    pub output: Option<OutputSpec>,
}

impl AvalancheSettings {
    /// The defaults of `snowscape avalanche` for `release`: AvaFrame's samosATSmall law, the
    /// slope-projected gravity, a slope-normal thickness, a bare DEM, no output folder.
    pub fn new(release: ReleaseSpec) -> Self {
        Self {
            release,
            thickness_m: None,
            thickness_measured: ThicknessConvention::SlopeNormal,
            snow_cover_m: 0.0,
            dem_options: ReadOptions::default(),
            flow: AvalancheParams::default(),
            run: RunOptions::default(),
            friction_rasters: FrictionRasters::default(),
            compare: None,
            seed: 1,
            output: None,
        }
    }
}

/// Where and how a job writes its files.
#[derive(Debug, Clone)]
pub struct OutputSpec {
    /// The output folder (created if missing).
    pub folder: PathBuf,
    /// Simulated seconds between playback frames, in [`FRAME_INTERVAL_S`].
    pub frame_interval_s: f64,
    /// How the frames are drawn.
    pub view: PreviewOptions,
}

/// Why an avalanche job was refused or failed.
#[derive(Debug, thiserror::Error)]
pub enum AvalancheJobError {
    /// A flow parameter out of its range.
    #[error(transparent)]
    FlowParameters(AvalancheError),
    /// A run option (duration, settle thickness, stop energy) out of its range.
    #[error(transparent)]
    RunOptions(AvalancheError),
    /// The front end cancelled the run at simulated second `time_s`.
    #[error("cancelled at t = {time_s:.1} s of the flow; nothing was written")]
    Cancelled { time_s: f64 },
    #[error("frame interval {0} s must be within [0.01, 3600]")]
    FrameInterval(f64),
    #[error("comparison corridor {0} m must be within (0, 100000]")]
    Corridor(f64),
    #[error(transparent)]
    Release(#[from] ReleaseError),
    #[error("release {}: no such file", .0.display())]
    NoReleaseFile(PathBuf),
    #[error("release mask has {cells} cells, the DEM {width} x {height}")]
    MaskSize {
        cells: usize,
        width: usize,
        height: usize,
    },
    /// The DEM is no terrain (cell size, size, nodata).
    #[error(transparent)]
    Terrain(#[from] snowscape_terrain::TerrainError),
    #[error(transparent)]
    FrictionRasters(#[from] FrictionRasterError),
    #[error("comparison reference {}: {source}", path.display())]
    CompareReference {
        path: PathBuf,
        #[source]
        source: Box<snowscape_io::RasterError>,
    },
    #[error("comparison path {}: {source}", path.display())]
    ComparePath {
        path: PathBuf,
        #[source]
        source: Box<snowscape_avalanche::validation::ValidationError>,
    },
    #[error("comparison path {}: the line has {vertices} vertices, it needs at least 2", path.display())]
    PathTooShort { path: PathBuf, vertices: usize },
    /// The output folder cannot be opened (nothing was run).
    #[error(transparent)]
    OutputFolder(OutputError),
    #[error("cannot create {}: {source}", path.display())]
    CreateFrames {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The flow failed while it ran.
    #[error(transparent)]
    Flow(AvalancheError),
    /// An output could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error("cannot encode the avalanche report: {0}")]
    Report(#[source] serde_json::Error),
}

impl AvalancheJobError {
    /// Whether the job was refused for its input (nothing was run) rather than failing while
    /// it ran or wrote.
    pub fn is_bad_input(&self) -> bool {
        !matches!(
            self,
            Self::CreateFrames { .. }
                | Self::Flow(_)
                | Self::Output(_)
                | Self::Report(_)
                | Self::Cancelled { .. }
        )
    }
}

impl AvalancheSettings {
    /// Checks every value against its range, before any file is read: the flow parameters,
    /// the run options, the release thickness and snow cover, a release point (finite) or file
    /// (existing), the frame interval and the comparison's corridor.
    pub fn check(&self) -> Result<(), AvalancheJobError> {
        self.flow
            .validate()
            .map_err(AvalancheJobError::FlowParameters)?;
        self.run.validate().map_err(AvalancheJobError::RunOptions)?;
        check_release_values(self.thickness_m, self.snow_cover_m)?;
        match &self.release {
            ReleaseSpec::Point(x, y) if !(x.is_finite() && y.is_finite()) => {
                return Err(ReleaseError::NonFinitePoint(format!("{x},{y}")).into());
            }
            ReleaseSpec::File(p) if !p.exists() => {
                return Err(AvalancheJobError::NoReleaseFile(p.clone()));
            }
            _ => {}
        }
        if let Some(o) = &self.output {
            let (lo, hi) = FRAME_INTERVAL_S;
            let t = o.frame_interval_s;
            if !(t.is_finite() && (lo..=hi).contains(&t)) {
                return Err(AvalancheJobError::FrameInterval(t));
            }
        }
        if let Some(c) = &self.compare
            && !(c.corridor_m.is_finite() && c.corridor_m > 0.0 && c.corridor_m <= MAX_CORRIDOR_M)
        {
            return Err(AvalancheJobError::Corridor(c.corridor_m));
        }
        Ok(())
    }
}

impl AvalancheJob {
    /// [`AvalancheSettings::check`], the DEM as a terrain and a release mask's size.
    pub fn check(&self) -> Result<(), AvalancheJobError> {
        self.settings.check()?;
        self.dem.check_terrain()?;
        let g = self.dem.geometry();
        if let ReleaseSpec::Mask(m) = &self.settings.release
            && m.len() != g.len()
        {
            return Err(AvalancheJobError::MaskSize {
                cells: m.len(),
                width: g.width(),
                height: g.height(),
            });
        }
        Ok(())
    }
}

/// A finished job: its report (as written to `report.json` when there is a folder) and the
/// flow's outcome.
#[derive(Debug)]
pub struct AvalancheOutcome {
    pub report: AvalancheReport,
    /// The per-cell results (peak maps, deposit, entrainment) and the volumes.
    pub rest: RestOutcome,
    /// Cells of the DEM.
    pub cells: usize,
}

impl AvalancheOutcome {
    /// The run's maps over the DEM's cells, row-major (0 where the flow did not reach):
    /// `peak_thickness` (m), `peak_velocity` (m/s), `deposit` (m) and `entrained` (m).
    pub fn maps(&self) -> [(&'static str, Vec<f32>); 4] {
        let dense = |cells: &[(u32, f64)]| to_f32(&RestOutcome::dense(cells, self.cells));
        let dense32 = |cells: &[(u32, f32)]| to_f32(&RestOutcome::dense(cells, self.cells));
        [
            ("peak_thickness", dense(&self.rest.peak_thickness)),
            ("peak_velocity", dense(&self.rest.peak_speed)),
            ("deposit", dense32(&self.rest.deposited)),
            ("entrained", dense32(&self.rest.entrained)),
        ]
    }

    /// The flat summary of the run (the Python package's).
    pub fn summary(&self) -> AvalancheSummary {
        AvalancheSummary::new(
            &self.rest,
            self.report.release_cells,
            self.report.release_area_m2,
            &self.report.parameters.flow,
        )
    }
}

fn to_f32(v: &[f64]) -> Vec<f32> {
    v.iter().map(|&x| x as f32).collect()
}

/// Runs the job: checks it, releases the snow, runs the flow to rest and, with an output
/// folder, writes every file and `report.json`.
///
/// `control` hears the simulated time of the flow (of `RunOptions::duration_s`) and a status
/// line at every record; a cancel is honoured between records and ends the job with
/// [`AvalancheJobError::Cancelled`], nothing written (the staging folder is removed).
pub fn run(
    job: &AvalancheJob,
    control: &mut dyn Control,
) -> Result<AvalancheOutcome, AvalancheJobError> {
    job.check()?;
    let s = &job.settings;
    let (terrain, cells, area) = release_terrain(
        &job.dem,
        &s.release,
        s.thickness_m,
        s.thickness_measured,
        &s.dem_options,
        s.snow_cover_m,
    )?;
    let (maps, friction_report) = friction_maps(&s.friction_rasters, &job.dem, &s.flow)?;
    let compare_inputs = s.compare.as_ref().map(compare::read_inputs).transpose()?;
    let mut workspace = AvalancheWorkspace::new();
    workspace.set_friction_maps(maps);
    let released = outputs::Released {
        terrain,
        cells,
        area,
    };
    let staged = match &s.output {
        Some(o) => Some(outputs::Staged::open(o)?),
        None => None,
    };
    let flow = outputs::run_flow(job, &mut workspace, released, staged, control)?;
    let report_base = ReportBase {
        input: InputSummary::of(&job.source, &job.dem),
        friction_report,
    };
    outputs::finish(job, flow, compare_inputs.as_ref(), report_base)
}

/// What the report takes from before the run.
struct ReportBase {
    input: InputSummary,
    friction_report: Option<FrictionReport>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_value_is_checked_before_any_work() {
        let mut s = AvalancheSettings::new(ReleaseSpec::Point(0.0, 0.0));
        assert!(s.check().is_ok());
        s.thickness_m = Some(1e9);
        assert!(matches!(
            s.check(),
            Err(AvalancheJobError::Release(ReleaseError::Thickness(_)))
        ));
        s.thickness_m = None;
        s.snow_cover_m = -1.0;
        let e = s.check().unwrap_err();
        assert!(e.to_string().contains("snow cover -1"), "{e}");
        assert!(e.is_bad_input());
        s.snow_cover_m = 0.0;
        s.flow.voellmy_mu = 1e9;
        assert!(matches!(
            s.check(),
            Err(AvalancheJobError::FlowParameters(_))
        ));
        s.flow = AvalancheParams::default();
        s.run.duration_s = -1.0;
        assert!(matches!(s.check(), Err(AvalancheJobError::RunOptions(_))));
        s.run = RunOptions::default();
        s.release = ReleaseSpec::Point(f64::NAN, 0.0);
        assert!(s.check().is_err());
        s.release = ReleaseSpec::File("no/such/release.shp".into());
        let e = s.check().unwrap_err();
        assert!(e.to_string().contains("no/such/release.shp"), "{e}");
        s.release = ReleaseSpec::Point(0.0, 0.0);
        s.output = Some(OutputSpec {
            folder: "unused".into(),
            frame_interval_s: 0.0,
            view: PreviewOptions::default(),
        });
        assert!(matches!(
            s.check(),
            Err(AvalancheJobError::FrameInterval(_))
        ));
        s.output = None;
        s.compare = Some(CompareSpec {
            reference: "unused".into(),
            path: None,
            corridor_m: f64::INFINITY,
        });
        assert!(matches!(s.check(), Err(AvalancheJobError::Corridor(_))));
    }
}
