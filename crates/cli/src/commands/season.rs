//! The season pipeline shared by `snowscape run` (a DEM file) and `snowscape demo` (the
//! procedural terrain): environment precompute, the Poisson event loop with snapshots and
//! checkpoints, then every output and `report.json`.

use crate::failure::{ExitCodeExt, Failure};
use crate::outputs::{
    Written, earlier_outputs, prepare_dir, remove_stale, stale_outputs, write_all_staged, write_png,
};
use crate::progress::Stages;
use crate::report::{InputSummary, MassBudget, Report, timings_object};
use anyhow::{Context, anyhow};
use image::RgbaImage;
use serde_json::json;
use snowscape_io::{write_atomic, write_bytes_atomic, write_geotiff, write_geotiff_bands};
use snowscape_render::{PreviewOptions, render_preview};
use snowscape_season::scenario::Scenario;
use snowscape_season::winter::{Winter, phenomenon_name};
use snowscape_terrain::{Grid, LayeredTerrain};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Name of the checkpoint file inside the output folder.
pub const CHECKPOINT: &str = "checkpoint.bin";
/// Exit code of a run stopped by Ctrl-C after writing its checkpoint (128 + SIGINT).
const INTERRUPTED: u8 = 130;
/// Longest stretch of simulated days between two checks of the interrupt flag.
const CHUNK_DAYS: f64 = 0.25;

/// One season to run and write.
pub struct SeasonJob {
    /// `run` or `demo`.
    pub command: &'static str,
    /// Where the terrain came from, for the report.
    pub source: String,
    pub bedrock: Grid,
    pub scenario: Scenario,
    /// Extra parameters for the report (terrain generator, scenario file...).
    pub extra_parameters: serde_json::Value,
    pub out: PathBuf,
    /// Resume from the checkpoint in this folder.
    pub resume: Option<PathBuf>,
    /// Stop at this day with a checkpoint, before the season ends.
    pub stop_at: Option<f64>,
    /// Station forcing driving the season.
    pub forcing: Option<snowscape_season::forcing::StationForcing>,
    pub view: PreviewOptions,
    pub quiet: bool,
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

fn write_checkpoint(dir: &Path, winter: &Winter) -> anyhow::Result<()> {
    let path = dir.join(CHECKPOINT);
    write_atomic(&path, |w| -> anyhow::Result<()> {
        winter.write_checkpoint(w)?;
        Ok(())
    })
    .with_context(|| format!("cannot write checkpoint {}", path.display()))
}

fn install_interrupt_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    // A second install (tests running several jobs in one process) keeps the first handler.
    let _ = ctrlc::set_handler(move || f.store(true, Ordering::SeqCst));
    flag
}

/// Runs the season and writes every output.
pub fn run_season(job: SeasonJob) -> Result<(), Failure> {
    let earlier = earlier_outputs(&job.out);
    prepare_dir(&job.out).bad_input()?;
    std::fs::create_dir_all(job.out.join("frames"))
        .with_context(|| format!("cannot create {}/frames", job.out.display()))
        .job_failed()?;
    let input = InputSummary::of(&job.source, &job.bedrock);
    let mut stages = Stages::new(5, job.quiet);
    let terrain = LayeredTerrain::from_bedrock(job.bedrock);
    let mut winter = stages.run("environment", || -> Result<Winter, Failure> {
        match &job.resume {
            None => Winter::with_forcing(job.scenario.clone(), terrain, job.forcing.clone())
                .job_failed(),
            Some(dir) => {
                let path = dir.join(CHECKPOINT);
                let bytes = std::fs::read(&path)
                    .with_context(|| format!("cannot read checkpoint {}", path.display()))
                    .bad_input()?;
                Winter::resume_with_forcing(
                    job.scenario.clone(),
                    terrain,
                    job.forcing.clone(),
                    &mut bytes.as_slice(),
                )
                .with_context(|| format!("cannot resume from {}", path.display()))
                .bad_input()
            }
        }
    })?;
    for w in season_warnings(&winter) {
        tracing::warn!("{w}");
    }

    let snaps = snapshot_days(winter.scenario());
    let checkpoints = checkpoint_days(winter.scenario());
    let mut frames: Vec<Option<RgbaImage>> = vec![None; snaps.len()];
    if let Some(dir) = &job.resume {
        for (k, &d) in snaps.iter().enumerate() {
            if d <= winter.day() {
                let p = dir.join(frame_name(k));
                let img = image::open(&p)
                    .with_context(|| format!("cannot read the earlier frame {}", p.display()))
                    .bad_input()?;
                frames[k] = Some(img.to_rgba8());
            }
        }
    }
    let frame_view = PreviewOptions {
        max_size: Some(512),
        ..job.view.clone()
    };
    let interrupted = install_interrupt_flag();
    let days = winter.scenario().days;
    let bar = crate::progress::day_bar(days, job.quiet);
    let t_season = std::time::Instant::now();
    let stop_at = job.stop_at.filter(|&d| d < days);
    let mut milestones: Vec<f64> = snaps
        .iter()
        .chain(checkpoints.iter())
        .chain(stop_at.iter())
        .copied()
        .collect();
    milestones.sort_by(f64::total_cmp);
    milestones.dedup();
    let start_day = winter.day();
    for &m in milestones.iter().filter(|&&m| m > start_day) {
        while winter.day() < m {
            let next = (winter.day() + CHUNK_DAYS).min(m);
            winter.run_until_unless(next, &interrupted).job_failed()?;
            bar.set_position((winter.day() * 10.0) as u64);
            if interrupted.load(Ordering::SeqCst) {
                // A chunk that reached a snapshot day writes its frame before the checkpoint:
                // a resume reads every frame up to the checkpoint's day.
                if winter.day() >= m
                    && let Some(k) = snaps.iter().position(|&d| d == m)
                {
                    let img = render_preview(&winter.terrain, &frame_view).job_failed()?;
                    write_png(&job.out.join(frame_name(k)), &img).job_failed()?;
                }
                write_checkpoint(&job.out, &winter).job_failed()?;
                bar.abandon();
                return Err(Failure {
                    code: INTERRUPTED,
                    error: anyhow!(
                        "interrupted at day {:.2}; checkpoint written; continue with --resume {}",
                        winter.day(),
                        job.out.display()
                    ),
                });
            }
            if winter.finished() {
                break;
            }
        }
        if let Some(k) = snaps.iter().position(|&d| d == m) {
            let img = render_preview(&winter.terrain, &frame_view).job_failed()?;
            write_png(&job.out.join(frame_name(k)), &img).job_failed()?;
            frames[k] = Some(img);
        }
        if checkpoints.contains(&m) {
            write_checkpoint(&job.out, &winter).job_failed()?;
        }
        if stop_at == Some(m) {
            write_checkpoint(&job.out, &winter).job_failed()?;
            bar.finish_and_clear();
            if !job.quiet {
                println!(
                    "stopped at day {:.2} as asked; continue with --resume {}",
                    winter.day(),
                    job.out.display()
                );
            }
            return Ok(());
        }
    }
    bar.finish_and_clear();
    stages.record("season", t_season.elapsed().as_secs_f64());
    winter.terrain.check_invariants().job_failed()?;

    // Ctrl-C while the outputs are written stops between two of them (each file is written
    // whole or not at all); the final checkpoint lets `--resume` write them again.
    let stop_if_interrupted = || -> Result<(), Failure> {
        if !interrupted.load(Ordering::SeqCst) {
            return Ok(());
        }
        write_checkpoint(&job.out, &winter).job_failed()?;
        Err(Failure {
            code: INTERRUPTED,
            error: anyhow!(
                "interrupted while writing the outputs; the season is complete: write them with --resume {}",
                job.out.display()
            ),
        })
    };
    let mut out = Written::new(&job.out);
    let frames: Vec<RgbaImage> = frames.into_iter().flatten().collect();
    out.files.extend((0..frames.len()).map(frame_name));
    stop_if_interrupted()?;
    write_all_staged(&mut out, &winter.terrain, &frames, &job.view, &mut stages).job_failed()?;
    stop_if_interrupted()?;
    stages
        .run("write_environment", || {
            write_environment(&mut out, &winter.terrain)
        })
        .job_failed()?;
    stop_if_interrupted()?;
    stages
        .run("write_avalanches", || {
            write_avalanche_maps(&mut out, &winter)
        })
        .job_failed()?;
    stop_if_interrupted()?;
    stages
        .run("write_ski_tracks", || write_ski_tracks(&mut out, &winter))
        .job_failed()?;
    write_checkpoint(&job.out, &winter).job_failed()?;
    out.files.push(CHECKPOINT.into());

    let mut report = season_report(
        job.command,
        &job.extra_parameters,
        input,
        &winter,
        stages.finish(),
        out.files,
    );
    report.removed_stale = stale_outputs(&earlier, &report.outputs);
    let text = serde_json::to_vec_pretty(&report).job_failed()?;
    write_bytes_atomic(&job.out.join("report.json"), &text).job_failed()?;
    remove_stale(&job.out, &report.removed_stale);
    if !job.quiet {
        let b = &report.mass_budget;
        println!(
            "{}: {:.0} days on {}x{} cells; snowfall {:.3e} m³, final store {:.3e} m³ (closure error {:.1e}); {} files in {}",
            report.command,
            days,
            report.input.width,
            report.input.height,
            b.inputs.get("snowfall").copied().unwrap_or(0.0),
            b.final_store,
            b.closure_error,
            report.outputs.len(),
            job.out.display()
        );
    }
    Ok(())
}

/// Writes the environment maps: `sun.tif`, `sky.tif`, `irradiance.tif`, `temperature.tif`,
/// `wind.tif` (2 bands: east and north components, m/s) and `wind_shadow.tif`.
fn write_environment(out: &mut Written, terrain: &LayeredTerrain) -> anyhow::Result<()> {
    use snowscape_environment::map_names as m;
    let map = |name: &str| {
        terrain
            .maps
            .get(name)
            .ok_or_else(|| anyhow!("environment map {name} is missing"))
    };
    for (name, file) in [
        (m::SUN, "sun.tif"),
        (m::SKY, "sky.tif"),
        (m::IRRADIANCE, "irradiance.tif"),
        (m::TEMPERATURE, "temperature.tif"),
        (m::WIND_SHADOW, "wind_shadow.tif"),
    ] {
        write_geotiff(&out.path(file), &terrain.to_grid(map(name)?.clone())?)?;
    }
    write_geotiff_bands(
        &out.path("wind.tif"),
        terrain.geometry(),
        terrain.mask(),
        &[map(m::WIND_U)?, map(m::WIND_V)?],
    )?;
    Ok(())
}

/// Writes `avalanche_scour.tif` and `avalanche_deposit.tif`: snow thickness the season's
/// avalanches took away and laid down, m.
fn write_avalanche_maps(out: &mut Written, winter: &Winter) -> anyhow::Result<()> {
    let m = winter.avalanche_maps();
    let t = &winter.terrain;
    write_geotiff(
        &out.path("avalanche_scour.tif"),
        &t.to_grid(m.scour.clone())?,
    )?;
    write_geotiff(
        &out.path("avalanche_deposit.tif"),
        &t.to_grid(m.deposit.clone())?,
    )?;
    Ok(())
}

/// Writes `ski_tracks.png` (16-bit track texture, finer than the grid, with a JSON sidecar
/// and a world file) and `ski_tracks.geojson` (polylines in the DEM's CRS) when skiers came.
fn write_ski_tracks(out: &mut Written, winter: &Winter) -> anyhow::Result<()> {
    let Some(area) = winter.ski_area() else {
        return Ok(());
    };
    snowscape_skiers::write_track_png(
        &out.path("ski_tracks.png"),
        area.texture(),
        winter.terrain.geometry(),
        snowscape_skiers::PngDepth::Sixteen,
    )?;
    out.files.push("ski_tracks.png.json".into());
    out.files.push("ski_tracks.pgw".into());
    snowscape_skiers::write_tracks_geojson(&out.path("ski_tracks.geojson"), area)?;
    Ok(())
}

fn season_report(
    command: &'static str,
    extra_parameters: &serde_json::Value,
    input: InputSummary,
    winter: &Winter,
    timings: Vec<(String, f64)>,
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
    budget.outputs.insert("melt".into(), b.melt);
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
    let phenomena: serde_json::Map<String, serde_json::Value> = winter
        .wall_seconds
        .iter()
        .map(|(k, v)| (k.to_string(), json!((v * 1e6).round() / 1e6)))
        .collect();
    timings_json.insert("phenomena".into(), serde_json::Value::Object(phenomena));
    let counts: serde_json::Map<String, serde_json::Value> = winter
        .event_counts()
        .iter()
        .map(|(k, v)| (phenomenon_name(*k).to_string(), json!(v)))
        .collect();
    Report {
        snowscape_version: env!("CARGO_PKG_VERSION"),
        command: command.into(),
        input,
        parameters: json!({
            "scenario": winter.scenario(),
            "weather": winter.weather(),
            "latitude_deg": winter.latitude_deg(),
            "latitude_source": winter.latitude_source(),
            "extra": extra_parameters,
        }),
        seed: winter.scenario().seed,
        threads: rayon::current_num_threads(),
        timings: timings_json,
        event_counts: Some(counts),
        avalanches: Some(winter.avalanches().to_vec()),
        skiers: Some(winter.ski_stats().clone()),
        mass_budget: budget.close(),
        water_budget: Some(b.water.clone()),
        warnings: season_warnings(winter),
        outputs,
        removed_stale: Vec::new(),
    }
}

/// What a user must be told about a season: an assumed latitude names the flag that sets it.
pub fn season_warnings(winter: &Winter) -> Vec<String> {
    let mut w = Vec::new();
    if winter.latitude_source() == snowscape_season::winter::LatitudeSource::Assumed {
        w.push(format!(
            "the DEM's georeferencing gives no latitude: the sun and the climatology assume {:.1}° N; set it with --latitude DEG (or latitude_deg in the scenario)",
            winter.latitude_deg()
        ));
    }
    w
}
