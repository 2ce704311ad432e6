//! One season run to its end and written: the path `snowscape run` and `snowscape demo` take
//! (and the Python package will), so that the same terrain, scenario and seed give the same
//! bytes from each front end.
//!
//! The job is the output folder's setup, one [`Simulation`] run and the writing of its
//! outputs. The simulation fires a preview frame at each snapshot day
//! (`frames/frame_NNNN.png`) and the whole state at each checkpoint day (`checkpoint.bin`, put
//! in place at once, from which [`SeasonJob::resume`] continues bit-identically); a stop at
//! `stop_at`, or a cancel from the front end's [`Control`] (Ctrl-C: the season stops between
//! two events, where its state is consistent), ends the job with a checkpoint. At the end every
//! output of [`crate::outputs::write_all`] is written, then the environment maps, the
//! avalanche scour and deposit, the ski tracks, the final checkpoint and `report.json`; an
//! earlier run's outputs that this one did not write again are removed.

use crate::output_folder::OutputFolder;
use crate::outputs::{OutputError, Written, write_all, write_png};
use crate::report::{InputSummary, MassBudget, Report, timings_object};
use crate::simulation::{
    Control, Schedule, Simulation, SimulationError, StopReason, cancel_requested,
};
use image::RgbaImage;
use snowscape_io::{AtomicWriteError, write_atomic, write_bytes_atomic};
use snowscape_render::{PreviewOptions, render_preview};
use snowscape_season::scenario::Scenario;
use snowscape_season::winter::{LatitudeSource, SeasonError, Winter, phenomenon_name};
use snowscape_terrain::{Grid, LayeredTerrain};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Name of the checkpoint file inside the output folder.
pub const CHECKPOINT: &str = "checkpoint.bin";

/// Name of the resolved scenario written beside the outputs (what `--resume` reuses).
pub const RESOLVED_SCENARIO: &str = "scenario.toml";

/// The largest earlier frame read back on a resume (a 512-pixel RGBA PNG is at most ~1 MiB).
const MAX_FRAME_BYTES: u64 = 64 << 20;

/// What a front end adds to a season report's `parameters.extra`.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(untagged)]
pub enum ExtraParameters {
    /// `demo`: the procedural terrain it generated.
    Demo {
        /// The generator's parameters and its time.
        terrain: GeneratedTerrain,
    },
    /// `run`: the scenario file, if one was given.
    Run {
        /// Its path as given.
        scenario_file: Option<String>,
        /// The avalanches' μ raster (`--mu-raster`), as given.
        #[serde(skip_serializing_if = "Option::is_none")]
        mu_raster: Option<String>,
        /// The avalanches' ξ raster (`--xi-raster`), as given.
        #[serde(skip_serializing_if = "Option::is_none")]
        xi_raster: Option<String>,
    },
}

/// A season report's `parameters`: the scenario as run, the weather periods it resolved to,
/// the latitude and where it came from, and what the front end adds.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SeasonParameters<'a> {
    /// Every parameter, as the scenario file would spell it.
    pub scenario: &'a Scenario,
    /// The weather periods the season ran (the climatology's, or the scenario's).
    pub weather: &'a [snowscape_season::scenario::WeatherPeriod],
    /// The latitude of the sun and the climatology, degrees north.
    pub latitude_deg: f64,
    /// Where the latitude came from.
    pub latitude_source: LatitudeSource,
    /// What the front end adds.
    pub extra: &'a ExtraParameters,
}

/// The procedural terrain of a `demo` (`snowscape_terrain::procedural::AlpineParams`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct GeneratedTerrain {
    /// Cells per side.
    pub size: usize,
    /// The generator's seed.
    pub seed: u64,
    /// Cell size, m.
    pub cell_size_m: f64,
    /// Relief (highest minus lowest altitude), m.
    pub relief_m: f64,
    /// Lowest altitude, m.
    pub base_altitude_m: f64,
    /// Wall time of the generation, s.
    pub generation_seconds: f64,
}

/// One season to run and write.
pub struct SeasonJob {
    /// The front end's name for the job (`run`, `demo`), for the report.
    pub command: String,
    /// Where the terrain came from, for the report.
    pub source: String,
    pub bedrock: Grid,
    pub scenario: Scenario,
    /// What the front end adds to the report's `parameters.extra` (the generated terrain,
    /// the scenario file).
    pub extra_parameters: ExtraParameters,
    /// The output folder (created if missing).
    pub out: PathBuf,
    /// Resume from the checkpoint in this folder.
    pub resume: Option<PathBuf>,
    /// Stop at this day with a checkpoint, before the season ends.
    pub stop_at: Option<f64>,
    /// Station forcing driving the season.
    pub forcing: Option<snowscape_season::forcing::StationForcing>,
    /// How the previews and frames are drawn.
    pub view: PreviewOptions,
    /// Write the single-band GeoTIFFs Cloud-Optimized (`--cog`; `wind.tif`, two bands, stays
    /// a plain GeoTIFF).
    pub cog: bool,
    /// Write the resolved scenario ([`RESOLVED_SCENARIO`]) beside the outputs (`run`).
    pub write_scenario: bool,
    /// The memory the season may take, bytes (`--memory-budget`); `None`: what the machine
    /// has available ([`crate::memory`]).
    pub memory_budget: Option<u64>,
    /// Per-cell friction of the season's avalanches (`run --mu-raster/--xi-raster`; empty:
    /// the law's scalars), set on a fresh or a resumed season alike.
    pub friction_maps: snowscape_avalanche::FrictionMaps,
}

/// How a season job ended.
#[derive(Debug)]
pub enum SeasonOutcome {
    /// The season ran to its end and every output and `report.json` were written.
    Finished(Box<Report>),
    /// It stopped at `stop_at` as asked, with a checkpoint.
    Stopped { day: f64 },
    /// The interrupt flag stopped it at `day` with a checkpoint; `outputs_pending`: the season
    /// was complete and only its outputs were still to write.
    Interrupted { day: f64, outputs_pending: bool },
}

/// Why a season job failed.
#[derive(Debug, thiserror::Error)]
pub enum SeasonJobError {
    /// The output folder cannot be created or written into (bad input: nothing was run).
    #[error(transparent)]
    OutputFolder(OutputError),
    #[error("cannot resume from {path}: {source}")]
    Resume {
        path: PathBuf,
        #[source]
        source: Box<SeasonError>,
    },
    #[error("cannot read an earlier frame to resume with: {0}")]
    EarlierFrameFile(Box<snowscape_io::InputError>),
    #[error("cannot encode the resolved scenario: {0}")]
    EncodeScenario(#[source] toml::ser::Error),
    #[error("cannot read the earlier frame {path}: {source}")]
    EarlierFrame {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    #[error("cannot write checkpoint {path}: {source}")]
    WriteCheckpoint {
        path: PathBuf,
        #[source]
        source: Box<SeasonError>,
    },
    #[error(transparent)]
    Season(Box<SeasonError>),
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error("environment map {0} is missing")]
    MissingMap(&'static str),
    /// The season would not fit in memory (refused before any work).
    #[error(transparent)]
    NotEnoughMemory(#[from] crate::memory::NotEnoughMemory),
}

impl SeasonJobError {
    /// Whether the job was refused for its input (a folder, a checkpoint, a frame of the run
    /// to resume) rather than failing while it ran.
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            Self::OutputFolder(_)
                | Self::EarlierFrameFile(_)
                | Self::Resume { .. }
                | Self::EarlierFrame { .. }
                | Self::NotEnoughMemory(_)
        )
    }
}

impl From<SeasonError> for SeasonJobError {
    fn from(e: SeasonError) -> Self {
        Self::Season(Box::new(e))
    }
}

impl From<AtomicWriteError> for SeasonJobError {
    fn from(e: AtomicWriteError) -> Self {
        Self::Output(OutputError::Write(e))
    }
}

impl From<snowscape_io::RasterError> for SeasonJobError {
    fn from(e: snowscape_io::RasterError) -> Self {
        Self::Output(OutputError::Raster(e))
    }
}

impl From<snowscape_render::RenderError> for SeasonJobError {
    fn from(e: snowscape_render::RenderError) -> Self {
        Self::Output(OutputError::Render(e))
    }
}

impl From<snowscape_terrain::TerrainError> for SeasonJobError {
    fn from(e: snowscape_terrain::TerrainError) -> Self {
        Self::Output(OutputError::Terrain(e))
    }
}

/// The days at which snapshots are taken: every `every` days and the explicit ones, within
/// the season, sorted, plus the last day.
pub fn snapshot_days(s: &Scenario) -> Vec<f64> {
    let mut days: Vec<f64> = s
        .snapshot_days
        .iter()
        .copied()
        .filter(|&d| d > 0.0 && d <= s.days)
        .collect();
    if s.snapshot_every_days > 0.0 {
        let n = (s.days / s.snapshot_every_days).floor() as usize;
        days.extend((1..=n).map(|k| k as f64 * s.snapshot_every_days));
    }
    days.push(s.days);
    days.sort_by(f64::total_cmp);
    days.dedup();
    days
}

fn checkpoint_days(s: &Scenario) -> Vec<f64> {
    if s.checkpoint_every_days <= 0.0 {
        return Vec::new();
    }
    let n = (s.days / s.checkpoint_every_days).floor() as usize;
    (1..=n)
        .map(|k| k as f64 * s.checkpoint_every_days)
        .filter(|&d| d < s.days)
        .collect()
}

fn frame_name(k: usize) -> String {
    format!("frames/frame_{k:04}.png")
}

/// Writes `checkpoint.bin` into `dir`, atomically.
pub fn write_checkpoint(dir: &Path, winter: &Winter) -> Result<(), SeasonJobError> {
    let path = dir.join(CHECKPOINT);
    write_atomic(&path, |w| {
        winter
            .write_checkpoint(w)
            .map_err(|source| SeasonJobError::WriteCheckpoint {
                path: path.clone(),
                source: Box::new(source),
            })
    })
}

/// Stage timings, in the order the stages first ran.
#[derive(Default)]
struct Stages {
    timings: Vec<(String, f64)>,
}

impl Stages {
    fn record(&mut self, name: &str, seconds: f64) {
        match self.timings.iter_mut().find(|(n, _)| n == name) {
            Some((_, s)) => *s += seconds,
            None => self.timings.push((name.to_string(), seconds)),
        }
    }

    fn run<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let t0 = Instant::now();
        let out = f();
        self.record(name, t0.elapsed().as_secs_f64());
        out
    }
}

/// The outputs the season fires while it runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SeasonOutput {
    /// A preview frame at a snapshot day.
    Frame,
    /// `checkpoint.bin` at a checkpoint day, put in place at once.
    Checkpoint,
}

/// This run's own files so far in the staging folder (the resolved scenario, frames, the
/// checkpoint), for a commit that ends it before its outputs (a cancel, `--stop-at`) and for
/// a periodic checkpoint; and the frames of the time-lapse.
struct Staged {
    dir: PathBuf,
    files: Vec<String>,
    /// One per snapshot day, drawn (or read back from the run resumed) once reached.
    frames: Vec<Option<RgbaImage>>,
    frame_view: PreviewOptions,
}

impl Staged {
    /// Draws and writes frame `k` of the season as it stands.
    fn frame(&mut self, k: usize, winter: &Winter) -> Result<(), SeasonJobError> {
        let img = render_preview(&winter.terrain, &self.frame_view)?;
        write_png(&self.dir.join(frame_name(k)), &img)?;
        self.files.push(frame_name(k));
        self.frames[k] = Some(img);
        Ok(())
    }

    /// Writes the season's checkpoint.
    fn checkpoint(&mut self, winter: &Winter) -> Result<(), SeasonJobError> {
        write_checkpoint(&self.dir, winter)?;
        self.files.push(CHECKPOINT.into());
        Ok(())
    }

    /// Reads back, and stages again, the frames of the resumed run `dir` up to `day`: a
    /// resume reads every frame up to its checkpoint's day.
    fn read_earlier_frames(
        &mut self,
        dir: &Path,
        snaps: &[f64],
        day: f64,
    ) -> Result<(), SeasonJobError> {
        for (k, _) in snaps.iter().enumerate().filter(|&(_, &d)| d <= day) {
            let path = dir.join(frame_name(k));
            let bytes = snowscape_io::input::read_regular(&path, MAX_FRAME_BYTES)
                .map_err(|e| SeasonJobError::EarlierFrameFile(Box::new(e)))?;
            let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
                .map_err(|source| SeasonJobError::EarlierFrame {
                    path: path.clone(),
                    source,
                })?;
            // The frame is this run's too: it goes into the folder with the others.
            write_bytes_atomic(&self.dir.join(frame_name(k)), &bytes)?;
            self.files.push(frame_name(k));
            self.frames[k] = Some(img.to_rgba8());
        }
        Ok(())
    }
}

/// Opens the output folder of a season and creates the staging folder's `frames/`.
fn open_folder(out: &Path) -> Result<OutputFolder, SeasonJobError> {
    let folder = OutputFolder::open(out).map_err(SeasonJobError::OutputFolder)?;
    folder
        .check_subfolder("frames")
        .map_err(SeasonJobError::OutputFolder)?;
    let frames = folder.staging().join("frames");
    std::fs::create_dir(&frames).map_err(|source| {
        SeasonJobError::Output(OutputError::CreateFolder {
            path: frames,
            source,
        })
    })?;
    Ok(folder)
}

/// The season of `job`: a fresh one on its bedrock, or the one its checkpoint in `resume`
/// continues.
fn start_winter(
    scenario: &Scenario,
    forcing: &Option<snowscape_season::forcing::StationForcing>,
    resume: &Option<PathBuf>,
    terrain: LayeredTerrain,
) -> Result<Winter, SeasonJobError> {
    match resume {
        None => Ok(Winter::with_forcing(
            scenario.clone(),
            terrain,
            forcing.clone(),
        )?),
        Some(dir) => {
            let path = dir.join(CHECKPOINT);
            // Only a regular file of at most the terrain's largest checkpoint is read (a
            // symbolic link to /dev/zero or a FIFO is refused before any read).
            Winter::resume_from_file(scenario.clone(), terrain, forcing.clone(), &path).map_err(
                |source| SeasonJobError::Resume {
                    path,
                    source: Box::new(source),
                },
            )
        }
    }
}

/// Runs the season of `job` and writes every output (module docs). `control` hears the
/// season's days; its interrupt flag (Ctrl-C) or its cancel stops the job with a checkpoint
/// at the next chance.
pub fn run_season(
    job: SeasonJob,
    control: &mut dyn Control,
) -> Result<SeasonOutcome, SeasonJobError> {
    let started = Instant::now();
    crate::memory::check_season(job.bedrock.geometry().len(), job.memory_budget)?;
    let mut folder = open_folder(&job.out)?;
    let mut staged = Staged {
        dir: folder.staging().to_path_buf(),
        files: Vec::new(),
        frames: Vec::new(),
        frame_view: PreviewOptions {
            max_size: Some(512),
            ..job.view.clone()
        },
    };
    if job.write_scenario {
        let text = toml::to_string(&job.scenario).map_err(SeasonJobError::EncodeScenario)?;
        write_bytes_atomic(&staged.dir.join(RESOLVED_SCENARIO), text.as_bytes())?;
        staged.files.push(RESOLVED_SCENARIO.into());
    }
    let input = InputSummary::of(&job.source, &job.bedrock);
    let mut stages = Stages::default();
    let terrain = LayeredTerrain::from_bedrock(job.bedrock);
    let mut winter = stages.run("environment", || {
        start_winter(&job.scenario, &job.forcing, &job.resume, terrain)
    })?;
    winter.set_friction_maps(job.friction_maps)?;
    for w in season_warnings(&winter) {
        tracing::warn!("{w}");
    }

    let snaps = snapshot_days(winter.scenario());
    staged.frames = vec![None; snaps.len()];
    if let Some(dir) = &job.resume {
        staged.read_earlier_frames(dir, &snaps, winter.day())?;
    }
    let t_season = Instant::now();
    let days = winter.scenario().days;
    // A stop at or before the resumed day is no stop: the season runs to its end.
    let stop_time = job
        .stop_at
        .filter(|&d| d < days && d > winter.day())
        .unwrap_or(days);
    let checkpoints = checkpoint_days(winter.scenario());
    let reason = Simulation::new(&mut winter, stop_time)
        .output(SeasonOutput::Frame, Schedule::SpecificTimes(snaps))
        .output(
            SeasonOutput::Checkpoint,
            Schedule::SpecificTimes(checkpoints),
        )
        .run_with(control, |output, at, winter| match output {
            SeasonOutput::Frame => staged.frame(at.index, winter),
            // In place at once, with the frames so far: a run killed later resumes from it.
            SeasonOutput::Checkpoint => {
                staged.checkpoint(winter)?;
                Ok(folder.place(&staged.files)?)
            }
        })
        .map_err(|e| match e {
            SimulationError::Season(e) => SeasonJobError::Season(e),
            SimulationError::Output(e) => e,
        })?;
    match reason {
        StopReason::StopTime { day } | StopReason::WallTimeLimit { day, .. } => {
            return commit_stopped(folder, staged, &winter, SeasonOutcome::Stopped { day });
        }
        StopReason::Cancelled { day } => {
            let outcome = SeasonOutcome::Interrupted {
                day,
                outputs_pending: false,
            };
            return commit_stopped(folder, staged, &winter, outcome);
        }
        StopReason::Stalled { day } => {
            tracing::warn!("no event can happen after day {day:.2}: the season ends there");
        }
        StopReason::SeasonEnded { .. } => {}
    }
    stages.record("season", t_season.elapsed().as_secs_f64());
    winter.terrain.check_invariants()?;

    // An interrupt that came once the season was complete stops before its outputs, with the
    // final checkpoint: a resume writes them.
    if cancel_requested(control) {
        let outcome = SeasonOutcome::Interrupted {
            day: winter.day(),
            outputs_pending: true,
        };
        return commit_stopped(folder, staged, &winter, outcome);
    }
    let files = write_outputs(&winter, (&job.view, job.cog), staged, &mut stages)?;
    let mut report = season_report(
        &job.command,
        &job.extra_parameters,
        input,
        &winter,
        (stages.timings, started.elapsed().as_secs_f64()),
        files,
    );
    report.removed_stale = folder.stale(&report.outputs);
    let text = serde_json::to_vec_pretty(&report).map_err(OutputError::Report)?;
    folder.commit(&report.outputs, Some(&text))?;
    Ok(SeasonOutcome::Finished(Box::new(report)))
}

/// Ends a job stopped before its outputs: the season's checkpoint, then the run's files so
/// far committed into the folder.
fn commit_stopped(
    folder: OutputFolder,
    mut staged: Staged,
    winter: &Winter,
    outcome: SeasonOutcome,
) -> Result<SeasonOutcome, SeasonJobError> {
    staged.checkpoint(winter)?;
    folder.commit(&staged.files, None)?;
    Ok(outcome)
}

/// Writes every output of the finished season into the staging folder; the files written (the
/// run's staged files first), each stage's time recorded.
///
/// Every output at once (different files; the state no longer changes): the rasters, previews,
/// glb and time-lapse, the environment and avalanche maps, the ski tracks and the final
/// checkpoint. Files are listed in that order, and the first error in that order is returned
/// once all have finished.
fn write_outputs(
    winter: &Winter,
    (view, cog): (&PreviewOptions, bool),
    staged: Staged,
    stages: &mut Stages,
) -> Result<Vec<String>, SeasonJobError> {
    let dir = staged.dir;
    let mut files = staged.files;
    let frames: Vec<RgbaImage> = staged.frames.into_iter().flatten().collect();
    let written = |write: &(dyn Fn(&mut Written) -> Result<(), SeasonJobError> + Sync)| {
        let mut files = Written::new(&dir);
        files.cog = cog;
        let t0 = Instant::now();
        let result = write(&mut files);
        (files, t0.elapsed().as_secs_f64(), result)
    };
    let (all, (maps, checkpoint)) = rayon::join(
        || {
            let mut files = Written::new(&dir);
            files.cog = cog;
            let result = write_all(&mut files, &winter.terrain, &frames, view);
            (files, result)
        },
        || {
            rayon::join(
                || {
                    [
                        (
                            "write_environment",
                            written(&|w| write_environment(w, &winter.terrain)),
                        ),
                        (
                            "write_avalanches",
                            written(&|w| write_avalanche_maps(w, winter)),
                        ),
                        (
                            "write_ski_tracks",
                            written(&|w| write_ski_tracks(w, winter)),
                        ),
                    ]
                },
                || {
                    let t0 = Instant::now();
                    (write_checkpoint(&dir, winter), t0.elapsed().as_secs_f64())
                },
            )
        },
    );
    let mut first_error: Option<SeasonJobError> = None;
    let (all_files, result) = all;
    files.extend(all_files.files);
    match result {
        Ok(stage_seconds) => {
            for (name, seconds) in stage_seconds {
                stages.record(name, seconds);
            }
        }
        Err(e) => {
            first_error.get_or_insert(e.into());
        }
    }
    for (name, (written, seconds, result)) in maps {
        stages.record(name, seconds);
        files.extend(written.files);
        if let Err(e) = result {
            first_error.get_or_insert(e);
        }
    }
    let (result, seconds) = checkpoint;
    stages.record("write_checkpoint", seconds);
    if let Err(e) = result {
        first_error.get_or_insert(e);
    }
    if let Some(e) = first_error {
        return Err(e);
    }
    files.push(CHECKPOINT.into());
    Ok(files)
}

/// Writes the environment maps: `sun.tif`, `sky.tif`, `irradiance.tif`, `temperature.tif`,
/// `wind_shadow.tif` and `wind.tif` (2 bands: east and north components, m/s). The files are
/// independent and written at the same time; they are listed in that order, and the first
/// error in that order is returned once all have finished.
fn write_environment(out: &mut Written, terrain: &LayeredTerrain) -> Result<(), SeasonJobError> {
    use rayon::prelude::*;
    use snowscape_environment::map_names as m;
    let map = |name: &'static str| {
        terrain
            .maps
            .get(name)
            .ok_or(SeasonJobError::MissingMap(name))
    };
    let single = [
        (m::SUN, "sun.tif"),
        (m::SKY, "sky.tif"),
        (m::IRRADIANCE, "irradiance.tif"),
        (m::TEMPERATURE, "temperature.tif"),
        (m::WIND_SHADOW, "wind_shadow.tif"),
    ]
    .into_iter()
    .map(|(name, file)| Ok((file, map(name)?)))
    .collect::<Result<Vec<_>, SeasonJobError>>()?;
    let wind: [&[f32]; 2] = [map(m::WIND_U)?, map(m::WIND_V)?];
    let (dir, cog) = (out.dir.clone(), out.cog);
    let written: Vec<(Written, Result<(), SeasonJobError>)> = (0..=single.len())
        .into_par_iter()
        .map(|k| {
            let mut files = Written::new(&dir);
            files.cog = cog;
            let result = match single.get(k) {
                Some(&(file, values)) => terrain
                    .to_grid(values.clone())
                    .map_err(SeasonJobError::from)
                    .and_then(|grid| Ok(files.geotiff(file, &grid)?)),
                None => snowscape_io::write_geotiff_bands(
                    &files.path("wind.tif"),
                    terrain.geometry(),
                    terrain.mask(),
                    &wind,
                )
                .map_err(SeasonJobError::from),
            };
            (files, result)
        })
        .collect();
    let mut first_error = None;
    for (files, result) in written {
        out.files.extend(files.files);
        if let Err(e) = result {
            first_error.get_or_insert(e);
        }
    }
    first_error.map_or(Ok(()), Err)
}

/// Writes `avalanche_scour.tif` and `avalanche_deposit.tif`: snow thickness the season's
/// avalanches took away and laid down, m.
fn write_avalanche_maps(out: &mut Written, winter: &Winter) -> Result<(), SeasonJobError> {
    let m = winter.avalanche_maps();
    let t = &winter.terrain;
    out.geotiff("avalanche_scour.tif", &t.to_grid(m.scour.clone())?)?;
    out.geotiff("avalanche_deposit.tif", &t.to_grid(m.deposit.clone())?)?;
    Ok(())
}

/// Writes `ski_tracks.png` (16-bit track texture, finer than the grid, with a JSON sidecar
/// and a world file) and `ski_tracks.geojson` (polylines in the DEM's CRS) when skiers came.
fn write_ski_tracks(out: &mut Written, winter: &Winter) -> Result<(), SeasonJobError> {
    let Some(area) = winter.ski_area() else {
        return Ok(());
    };
    crate::outputs::write_track_png(
        &out.path("ski_tracks.png"),
        area.texture(),
        winter.terrain.geometry(),
        snowscape_skiers::PngDepth::Sixteen,
    )?;
    out.files.push("ski_tracks.png.json".into());
    out.files.push("ski_tracks.pgw".into());
    crate::outputs::write_tracks_geojson(&out.path("ski_tracks.geojson"), area)?;
    Ok(())
}

/// The season's `report.json`.
fn season_report(
    command: &str,
    extra_parameters: &ExtraParameters,
    input: InputSummary,
    winter: &Winter,
    (timings, wall): (Vec<(String, f64)>, f64),
    outputs: Vec<String>,
) -> Report {
    let b = winter.budget();
    let mut budget = MassBudget {
        initial_store: b.initial_store,
        final_store: winter.terrain.snow_volume(),
        ..MassBudget::default()
    };
    budget.inputs.insert("snowfall".into(), b.snowfall);
    budget.inputs.insert("refreeze".into(), b.refreeze);
    budget.inputs.insert("deposition".into(), b.deposition);
    budget.outputs.insert("melt".into(), b.melt);
    budget.outputs.insert("sublimation".into(), b.sublimation);
    budget
        .outputs
        .insert("wind_sublimation".into(), b.wind_sublimation);
    budget
        .outputs
        .insert("densification".into(), b.densification);
    budget.outputs.insert(
        "border_outflow".into(),
        b.diffusion_outflow + b.wind_outflow + b.avalanche_outflow + b.shedding_outflow,
    );
    let mut timings_json = timings_object(&timings);
    // Stages that ran at the same time (the outputs) overlap in `total`, their sum: `wall` is
    // the job's own wall time, up to its report.
    timings_json.insert("wall".into(), ((wall * 1e6).round() / 1e6).into());
    let phenomena: serde_json::Map<String, serde_json::Value> = winter
        .wall_seconds
        .iter()
        .map(|(k, v)| (k.to_string(), ((v * 1e6).round() / 1e6).into()))
        .collect();
    timings_json.insert("phenomena".into(), serde_json::Value::Object(phenomena));
    let counts: serde_json::Map<String, serde_json::Value> = winter
        .event_counts()
        .iter()
        .map(|(k, v)| (phenomenon_name(*k).to_string(), (*v).into()))
        .collect();
    Report {
        snowscape_version: env!("CARGO_PKG_VERSION"),
        command: command.into(),
        input,
        parameters: serde_json::to_value(SeasonParameters {
            scenario: winter.scenario(),
            weather: winter.weather(),
            latitude_deg: winter.latitude_deg(),
            latitude_source: winter.latitude_source(),
            extra: extra_parameters,
        })
        .unwrap_or_default(),
        seed: winter.scenario().seed,
        threads: rayon::current_num_threads(),
        timings: timings_json,
        event_counts: Some(counts),
        avalanches: Some(winter.avalanches().to_vec()),
        skiers: Some(winter.ski_stats().clone()),
        mass_budget: budget.close(),
        water_budget: Some(b.water.clone()),
        bands: Some(winter.altitude_bands()),
        warnings: season_warnings(winter),
        outputs,
        removed_stale: Vec::new(),
    }
}

/// What a user must be told about a season: an assumed latitude names the flag that sets it.
pub fn season_warnings(winter: &Winter) -> Vec<String> {
    let mut w = Vec::new();
    if winter.latitude_source() == LatitudeSource::Assumed {
        w.push(format!(
            "the DEM's georeferencing gives no latitude: the sun and the climatology assume {:.1}° N; set it with --latitude DEG (or latitude_deg in the scenario)",
            winter.latitude_deg()
        ));
    }
    if let Some(mm) = winter
        .air()
        .storm_rates()
        .map(|r| r.stranded_mm())
        .filter(|&mm| mm > 0.0)
    {
        w.push(format!(
            "{mm:.0} mm of the season's precipitation total fall in months with no snowfall period (snowfall_per_week = 0 and no [[snowfall_period]]): they do not fall"
        ));
    }
    w
}
