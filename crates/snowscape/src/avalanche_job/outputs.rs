//! The run of an avalanche job and its files: the flow to rest with its playback frames
//! (`frames/frame_NNNN.png`, drawn on the relief shaded once), then the maps
//! (`peak_thickness.tif`, `peak_velocity.tif`, `thickness.tif` (the deposit), `footprint.tif`,
//! `entrained.tif` with entrainment), `avalanche.gif`, the comparison's files and
//! `report.json`, staged in the output folder and committed together.

use super::report::{AvalancheReport, ReleaseReport, RunParameters, Timings, convention_name};
use super::{AvalancheJob, AvalancheJobError, OutputSpec, ReportBase, compare};
use crate::avalanche_release::ReleaseSpec;
use crate::control::{Control, cancel_requested};
use crate::output_folder::{OutputFolder, REPORT};
use crate::outputs::{OutputError, Written, write_png, write_report};
use image::RgbaImage;
use snowscape_avalanche::release_area::ReleaseMask;
use snowscape_avalanche::{
    AvalancheError, AvalancheRun, AvalancheWorkspace, ReleasedCells, RestOutcome,
};
use snowscape_io::{write_bytes_atomic, write_geotiff};
use snowscape_render::{ReliefFrames, encode_gif};
use snowscape_terrain::{Grid, LayeredTerrain, SnowLayer};
use std::path::PathBuf;
use std::time::Instant;

/// The terrain carrying the release, the released cells and their mask.
pub(super) struct Released {
    pub terrain: LayeredTerrain,
    pub cells: Vec<usize>,
    pub area: ReleaseMask,
}

/// The output folder, opened (and locked) before the run, its staging folder holding
/// `frames/`.
pub(super) struct Staged {
    folder: OutputFolder,
    stage: PathBuf,
    frame_interval_s: f64,
    view: snowscape_render::PreviewOptions,
}

impl Staged {
    /// Opens the folder and creates the frames' folder in its staging folder.
    pub fn open(o: &OutputSpec) -> Result<Self, AvalancheJobError> {
        let folder = OutputFolder::open(&o.folder).map_err(AvalancheJobError::OutputFolder)?;
        folder
            .check_subfolder("frames")
            .map_err(AvalancheJobError::OutputFolder)?;
        let stage = folder.staging().to_path_buf();
        let frames = stage.join("frames");
        std::fs::create_dir(&frames).map_err(|source| AvalancheJobError::CreateFrames {
            path: frames,
            source,
        })?;
        Ok(Self {
            folder,
            stage,
            frame_interval_s: o.frame_interval_s,
            view: o.view.clone(),
        })
    }
}

/// The playback frames drawn while the flow runs.
struct FrameRecorder<'a> {
    relief: ReliefFrames<'a>,
    stage: PathBuf,
    interval_s: f64,
    next_s: f64,
    frames: Vec<RgbaImage>,
    files: Vec<String>,
    render_s: f64,
    error: Option<OutputError>,
}

impl FrameRecorder<'_> {
    /// Draws and writes a frame when its time has come (and at the run's end).
    fn record(&mut self, r: &AvalancheRun) {
        if !(r.time() + 1e-9 >= self.next_s || r.stop_reason().is_some()) {
            return;
        }
        let tf = Instant::now();
        let name = format!("frames/frame_{:04}.png", self.frames.len());
        match render_frame(&self.relief, r).and_then(|img| {
            write_png(&self.stage.join(&name), &img)?;
            Ok(img)
        }) {
            Ok(img) => {
                self.files.push(name);
                self.frames.push(img);
            }
            Err(e) if self.error.is_none() => self.error = Some(e),
            Err(_) => {}
        }
        self.render_s += tf.elapsed().as_secs_f64();
        self.next_s += self.interval_s;
    }
}

/// A frame of the run: its snow (flowing and settled, orange-red as unstable snow) on the
/// relief shaded once.
fn render_frame(frames: &ReliefFrames, run: &AvalancheRun) -> Result<RgbaImage, OutputError> {
    let snow_box = run
        .touched_cells()
        .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1), a.2.min(b.2), a.3.max(b.3)));
    Ok(frames.frame(SnowLayer::Unstable, snow_box, |c, r| {
        run.state.snow_at(c, r) as f32
    })?)
}

/// Why the flow stopped short: its own error, or the front end's cancel (at that second).
enum FlowStop {
    Flow(AvalancheError),
    Cancelled(f64),
}

impl From<AvalancheError> for FlowStop {
    fn from(e: AvalancheError) -> Self {
        FlowStop::Flow(e)
    }
}

/// The flow at rest and what its run left to write.
pub(super) struct Flow {
    released: Released,
    rest: RestOutcome,
    staged: Option<(Staged, Written, Vec<RgbaImage>)>,
    wall_s: f64,
    render_s: f64,
}

/// Runs the flow to rest, drawing the frames into the staging folder when there is one.
pub(super) fn run_flow(
    job: &AvalancheJob,
    workspace: &mut AvalancheWorkspace,
    mut released: Released,
    staged: Option<Staged>,
    control: &mut dyn Control,
) -> Result<Flow, AvalancheJobError> {
    let s = &job.settings;
    let mut recorder = match &staged {
        Some(st) => Some(FrameRecorder {
            relief: ReliefFrames::new(&job.dem, &st.view).map_err(OutputError::from)?,
            stage: st.stage.clone(),
            interval_s: st.frame_interval_s,
            next_s: 0.0,
            frames: Vec::new(),
            files: Vec::new(),
            render_s: 0.0,
            error: None,
        }),
        None => None,
    };
    let t0 = Instant::now();
    let rest = workspace
        .run_to_rest::<FlowStop>(
            &mut released.terrain,
            ReleasedCells::new(&released.cells, None),
            &s.flow,
            &s.run,
            SnowLayer::Stable,
            |r| {
                control.progress(r.time(), s.run.duration_s);
                control.status(&format!(
                    "t = {:.1} s, {:.0} m³ moving, energy {:.3e} J",
                    r.time(),
                    r.state.flowing_volume(),
                    r.kinetic_energy()
                ));
                if cancel_requested(control) {
                    return Err(FlowStop::Cancelled(r.time()));
                }
                if let Some(f) = recorder.as_mut() {
                    f.record(r);
                }
                Ok(())
            },
        )
        .map_err(|e| match e {
            FlowStop::Flow(e) => AvalancheJobError::Flow(e),
            FlowStop::Cancelled(time_s) => AvalancheJobError::Cancelled { time_s },
        })?;
    control.status("writing outputs");
    let mut render_s = 0.0;
    let staged = match (staged, recorder) {
        (Some(st), Some(mut f)) => {
            if let Some(e) = f.error.take() {
                return Err(e.into());
            }
            render_s = f.render_s;
            let mut out = Written::new(&st.stage);
            out.files = f.files;
            Some((st, out, f.frames))
        }
        _ => None,
    };
    Ok(Flow {
        released,
        rest,
        staged,
        wall_s: t0.elapsed().as_secs_f64(),
        render_s,
    })
}

/// Writes a map of the DEM's grid (its geometry and nodata) as a GeoTIFF.
fn write_map(
    out: &mut Written,
    name: &str,
    dem: &Grid,
    values: Vec<f32>,
) -> Result<(), OutputError> {
    let grid = Grid::new(dem.geometry().clone(), values, dem.mask().clone())?;
    write_geotiff(&out.path(name), &grid)?;
    Ok(())
}

/// The maps and the GIF of the frames.
fn write_maps(
    out: &mut Written,
    job: &AvalancheJob,
    rest: &RestOutcome,
    frames: &[RgbaImage],
) -> Result<(), OutputError> {
    let dem = &job.dem;
    let n = dem.geometry().len();
    let to_f32 = |v: Vec<f64>| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
    write_map(
        out,
        "peak_thickness.tif",
        dem,
        to_f32(RestOutcome::dense(&rest.peak_thickness, n)),
    )?;
    write_map(
        out,
        "peak_velocity.tif",
        dem,
        to_f32(RestOutcome::dense(&rest.peak_speed, n)),
    )?;
    write_map(
        out,
        "thickness.tif",
        dem,
        to_f32(RestOutcome::dense(&rest.deposited, n)),
    )?;
    let threshold = job.settings.run.footprint_threshold_m;
    let footprint = RestOutcome::dense(&rest.peak_thickness, n)
        .iter()
        .map(|&h| if h > threshold { 1.0 } else { 0.0 })
        .collect();
    write_map(out, "footprint.tif", dem, footprint)?;
    if job.settings.flow.entrainment.enabled {
        write_map(
            out,
            "entrained.tif",
            dem,
            to_f32(RestOutcome::dense(&rest.entrained, n)),
        )?;
    }
    let gif = encode_gif(frames, 100)?;
    write_bytes_atomic(&out.path("avalanche.gif"), &gif)?;
    Ok(())
}

/// Writes the maps, compares with the reference, and writes `report.json`: the job's end.
pub(super) fn finish(
    job: &AvalancheJob,
    mut flow: Flow,
    compare_inputs: Option<&compare::CompareInputs>,
    base: ReportBase,
) -> Result<super::AvalancheOutcome, AvalancheJobError> {
    let n = job.dem.geometry().len();
    if let Some((_, out, frames)) = flow.staged.as_mut() {
        write_maps(out, job, &flow.rest, frames)?;
    }
    let comparison = match (compare_inputs, &job.settings.compare) {
        (Some(inputs), Some(spec)) => {
            let c = compare::compare(
                inputs,
                &job.dem,
                &RestOutcome::dense(&flow.rest.peak_thickness, n),
                &RestOutcome::dense(&flow.rest.peak_speed, n),
                job.settings.run.footprint_threshold_m,
                spec.corridor_m,
            );
            if let Some((_, out, _)) = flow.staged.as_mut() {
                compare::write(out, &c)?;
            }
            Some(c)
        }
        _ => None,
    };
    let mut report = report(job, &flow, base, comparison);
    if let Some((staged, mut out, _)) = flow.staged.take() {
        out.files.push(REPORT.into());
        report.outputs = out.files;
        report.removed_stale = staged.folder.stale(&report.outputs);
        let value = serde_json::to_value(&report).map_err(AvalancheJobError::Report)?;
        write_report(staged.folder, value)?;
    }
    Ok(super::AvalancheOutcome {
        report,
        rest: flow.rest,
        cells: n,
    })
}

/// The report of a run (without its files).
fn report(
    job: &AvalancheJob,
    flow: &Flow,
    base: ReportBase,
    comparison: Option<snowscape_avalanche::comparison::PathComparison>,
) -> AvalancheReport {
    let s = &job.settings;
    let summary = flow.rest.summary.clone();
    let area = &flow.released.area;
    AvalancheReport {
        snowscape_version: env!("CARGO_PKG_VERSION"),
        command: "avalanche",
        input: base.input,
        release: match &s.release {
            ReleaseSpec::Point(x, y) => ReleaseReport::Point { point: [*x, *y] },
            ReleaseSpec::File(p) => ReleaseReport::File {
                file: p.display().to_string(),
            },
            ReleaseSpec::Mask(_) => ReleaseReport::Mask { mask: true },
        },
        release_cells: area.count(),
        release_area_m2: area.area_m2(),
        release_warnings: area.warnings.clone(),
        friction_maps: base.friction_report,
        parameters: RunParameters {
            flow: s.flow.clone(),
            run: s.run.clone(),
            thickness_m: s.thickness_m,
            thickness_measured: Some(convention_name(s.thickness_measured).to_string()),
        },
        seed: s.seed,
        threads: rayon::current_num_threads(),
        released_volume_m3: summary.released_volume_m3,
        entrained_volume_m3: summary.entrained_volume_m3,
        snow_cover_m: s.snow_cover_m,
        deposited_volume_m3: summary.final_volume_m3,
        border_outflow_m3: summary.border_outflow_m3,
        volume_closure_rel: summary.volume_closure_rel,
        runout_length_m: summary.runout_length_m,
        alpha_angle_deg: summary.alpha_angle_deg,
        travel_angle_deg: summary.travel_angle_deg,
        simulated_s: summary.simulated_s,
        summary,
        wall_s: flow.wall_s,
        timings: Timings {
            flow_s: flow.wall_s - flow.render_s,
            frames_s: flow.render_s,
        },
        comparison,
        outputs: Vec::new(),
        removed_stale: Vec::new(),
    }
}
