//! `snowscape avalanche --dem FILE --release FILE|X,Y`: one avalanche from release to rest on a
//! terrain, with the maps practitioners compare (peak thickness and velocity, deposit,
//! footprint), playback frames and a report.

use crate::cli::{AvalancheArgs, FrictionArg, GlobalArgs, SlopeGravityArg, ThicknessArg};
use crate::commands::render::preview_options;
use crate::failure::{ExitCodeExt, Failure};
use crate::outputs::{Written, write_png, write_report};
use crate::report::InputSummary;
use crate::stdout::outln;
use anyhow::{Context, anyhow, bail};
use clap::ValueEnum;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;
pub use snowscape::avalanche_release::ReleaseSpec;
use snowscape::avalanche_release::release_terrain;
use snowscape::output_folder::OutputFolder;
use snowscape_avalanche::validation::ThicknessConvention;
use snowscape_avalanche::{
    AvalancheError, AvalancheParams, AvalancheRun, AvalancheWorkspace, FrictionLaw, FrictionMaps,
    MapMatch, ReleasedCells, RestOutcome, RunOptions, SamosAtParams, SlopeGravity, StopReason,
};
use snowscape_io::ReadOptions;
use snowscape_io::{write_bytes_atomic, write_geotiff};
use snowscape_render::{ColourMode, ReliefFrames, encode_gif};
use snowscape_terrain::{Grid, SnowLayer};
use std::time::Instant;

/// Parses `X,Y` as a point, anything else as a file path.
pub fn parse_release(text: &str) -> anyhow::Result<ReleaseSpec> {
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() == 2
        && let (Ok(x), Ok(y)) = (
            parts[0].trim().parse::<f64>(),
            parts[1].trim().parse::<f64>(),
        )
    {
        if !(x.is_finite() && y.is_finite()) {
            bail!("--release {text:?}: the coordinates must be finite");
        }
        return Ok(ReleaseSpec::Point(x, y));
    }
    let path = std::path::PathBuf::from(text);
    if !path.exists() {
        bail!("--release {text:?} is neither X,Y map coordinates nor an existing file");
    }
    Ok(ReleaseSpec::File(path))
}

fn flow_params(args: &AvalancheArgs) -> anyhow::Result<AvalancheParams> {
    let mut p = AvalancheParams::default();
    if let Some(a) = args.friction_angle {
        p.rest_angle_deg = a;
    }
    if let Some(k) = args.viscosity {
        p.k_viscous = k;
    }
    if let Some(a) = args.dry_fraction {
        p.alpha = a;
    }
    p.friction = match args.friction_model {
        FrictionArg::Coulomb => FrictionLaw::Coulomb,
        FrictionArg::Voellmy => FrictionLaw::Voellmy,
        FrictionArg::SamosAt => {
            p.samos_at = SamosAtParams::standard();
            FrictionLaw::SamosAt
        }
        FrictionArg::SamosAtSmall => {
            p.samos_at = SamosAtParams::small();
            FrictionLaw::SamosAt
        }
    };
    p.slope_gravity = match args.slope_gravity {
        SlopeGravityArg::Shallow => SlopeGravity::Shallow,
        SlopeGravityArg::Projected => SlopeGravity::Projected,
    };
    p.curvature = !args.no_curvature;
    if args.no_curvature && p.slope_gravity != SlopeGravity::Projected {
        bail!(
            "--no-curvature acts on --slope-gravity projected only (the shallow form has no curvature term)"
        );
    }
    if p.friction == FrictionLaw::Coulomb && (args.mu.is_some() || args.xi.is_some()) {
        bail!("--mu and --xi are the Voellmy law's: add --friction-model voellmy");
    }
    if p.friction == FrictionLaw::SamosAt && args.xi.is_some() {
        bail!("--xi is the Voellmy law's (samosAT has no ξ): add --friction-model voellmy");
    }
    if p.friction != FrictionLaw::Coulomb {
        for (flag, given) in [
            ("--friction-angle", args.friction_angle.is_some()),
            ("--viscosity", args.viscosity.is_some()),
            ("--dry-fraction", args.dry_fraction.is_some()),
        ] {
            if given {
                bail!(
                    "{flag} is the Coulomb law's (the default law is AvaFrame's samosATSmall): \
                     add --friction-model coulomb"
                );
            }
        }
    }
    if let Some(m) = args.mu {
        p.voellmy_mu = m;
        p.samos_at.mu = m;
    }
    if let Some(x) = args.xi {
        p.voellmy_xi_m_s2 = x;
    }
    p.entrainment.enabled = !args.no_entrainment;
    if let Some(e) = args.erosion_energy {
        p.entrainment.erosion_energy_j_kg = e;
    }
    p.validate().map_err(|e| {
        anyhow!(e).context(
            "--friction-angle / --viscosity / --dry-fraction / --mu / --xi / --erosion-energy",
        )
    })?;
    Ok(p)
}

fn run_options(args: &AvalancheArgs) -> anyhow::Result<RunOptions> {
    let o = RunOptions {
        duration_s: args.duration,
        settle_thickness_m: args.settle_thickness,
        stop_energy_fraction: args.stop_energy,
        ..RunOptions::default()
    };
    o.validate()
        .context("--duration, --settle-thickness or --stop-energy")?;
    if !(args.frame_interval.is_finite() && args.frame_interval > 0.0) {
        bail!(
            "--frame-interval must be a positive number of seconds, got {}",
            args.frame_interval
        );
    }
    if let Some(t) = args.thickness
        && !(t.is_finite() && t > 0.0)
    {
        bail!("--thickness must be a positive number of metres, got {t}");
    }
    Ok(o)
}

/// `snowscape avalanche`'s report.json.
#[derive(Serialize)]
struct AvalancheReport<'a> {
    snowscape_version: &'static str,
    command: &'static str,
    input: InputSummary,
    release: ReleaseReport,
    release_cells: usize,
    release_area_m2: f64,
    release_warnings: &'a [String],
    friction_maps: Option<FrictionReport>,
    parameters: RunParameters<'a>,
    seed: u64,
    threads: usize,
    released_volume_m3: f64,
    entrained_volume_m3: f64,
    snow_cover_m: f64,
    deposited_volume_m3: f64,
    border_outflow_m3: f64,
    volume_closure_rel: f64,
    runout_length_m: f64,
    alpha_angle_deg: f64,
    travel_angle_deg: f64,
    summary: &'a snowscape_avalanche::RunSummary,
    simulated_s: f64,
    wall_s: f64,
    timings: Timings,
    comparison: Option<&'a snowscape_avalanche::comparison::PathComparison>,
    outputs: &'a [String],
}

/// Where the release came from.
#[derive(Serialize)]
#[serde(untagged)]
enum ReleaseReport {
    Point { point: [f64; 2] },
    File { file: String },
    Mask { mask: bool },
}

/// The flow and run parameters and the release thickness.
#[derive(Serialize)]
struct RunParameters<'a> {
    flow: &'a AvalancheParams,
    run: &'a RunOptions,
    thickness_m: Option<f64>,
    thickness_measured: Option<String>,
}

/// Wall seconds of the flow and of the frames.
#[derive(Serialize)]
struct Timings {
    flow_s: f64,
    frames_s: f64,
}

/// A friction raster as report.json tells it: its file and how it was matched.
#[derive(Debug, Serialize)]
struct FrictionRasterReport {
    file: Option<String>,
    matched: MapMatch,
}

/// The friction rasters of a run (`null` in report.json without either).
#[derive(Debug, Serialize)]
pub(crate) struct FrictionReport {
    mu: Option<FrictionRasterReport>,
    xi: Option<FrictionRasterReport>,
}

/// The μ and ξ rasters of `--mu-raster` and `--xi-raster` matched onto the DEM's cells, and
/// what report.json says of them (`None` without either).
pub(crate) fn friction_maps(
    mu_raster: &Option<std::path::PathBuf>,
    xi_raster: &Option<std::path::PathBuf>,
    dem: &Grid,
    params: &AvalancheParams,
) -> anyhow::Result<(FrictionMaps, Option<FrictionReport>)> {
    if mu_raster.is_none() && xi_raster.is_none() {
        return Ok((FrictionMaps::default(), None));
    }
    let read = |flag: &str, path: &Option<std::path::PathBuf>| {
        path.as_deref()
            .map(|p| {
                snowscape_io::read_dem(p, &ReadOptions::default())
                    .with_context(|| format!("{flag} {}", p.display()))
            })
            .transpose()
    };
    let mu = read("--mu-raster", mu_raster)?;
    let xi = read("--xi-raster", xi_raster)?;
    let (maps, mu_match, xi_match) =
        FrictionMaps::from_rasters(dem.geometry(), dem.mask(), params, mu.as_ref(), xi.as_ref())
            .map_err(|e| {
                let flags = match (mu_raster, xi_raster) {
                    (Some(m), Some(x)) => {
                        format!("--mu-raster {}, --xi-raster {}", m.display(), x.display())
                    }
                    (Some(m), None) => format!("--mu-raster {}", m.display()),
                    (None, Some(x)) => format!("--xi-raster {}", x.display()),
                    (None, None) => String::new(),
                };
                anyhow!("{flags}: {e}")
            })?;
    for (flag, m) in [("--mu-raster", &mu_match), ("--xi-raster", &xi_match)] {
        if let Some(m) = m
            && m.defaulted_cells > 0
        {
            tracing::warn!(
                "{flag}: {} of the DEM's cells lie outside the raster or under its nodata and keep the law's value",
                m.defaulted_cells
            );
        }
    }
    let entry = |path: &Option<std::path::PathBuf>, m: Option<MapMatch>| {
        m.map(|matched| FrictionRasterReport {
            file: path.as_ref().map(|p| p.display().to_string()),
            matched,
        })
    };
    let report = FrictionReport {
        mu: entry(mu_raster, mu_match),
        xi: entry(xi_raster, xi_match),
    };
    Ok((maps, Some(report)))
}

fn write_map(out: &mut Written, name: &str, dem: &Grid, values: Vec<f32>) -> anyhow::Result<()> {
    let grid = Grid::new(dem.geometry().clone(), values, dem.mask().clone())?;
    write_geotiff(&out.path(name), &grid)?;
    Ok(())
}

/// Renders the flowing snow (orange-red, as unstable snow) over the shaded terrain.
/// A frame of the run: its snow (flowing and settled) on the relief shaded once.
fn render_frame(frames: &ReliefFrames, run: &AvalancheRun) -> anyhow::Result<image::RgbaImage> {
    let snow_box = run
        .touched_cells()
        .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1), a.2.min(b.2), a.3.max(b.3)));
    Ok(frames.frame(SnowLayer::Unstable, snow_box, |c, r| {
        run.state.snow_at(c, r) as f32
    })?)
}

pub fn run(args: &AvalancheArgs, global: &GlobalArgs) -> Result<(), Failure> {
    let params = flow_params(args).bad_input()?;
    let options = run_options(args).bad_input()?;
    let spec = parse_release(&args.release).bad_input()?;
    let view = preview_options(&args.view, ColourMode::Layers).bad_input()?;
    let dem = args.dem_input.read(&args.dem).bad_input()?;
    let source = args.dem.display().to_string();
    let dem_options = args.dem_input.read_options().bad_input()?;
    let convention = match args.thickness_measured {
        ThicknessArg::Vertical => ThicknessConvention::Vertical,
        ThicknessArg::SlopeNormal => ThicknessConvention::SlopeNormal,
    };
    let (mut terrain, cells, area) = release_terrain(
        &dem,
        &spec,
        args.thickness,
        convention,
        &dem_options,
        args.snow_cover,
    )
    .with_context(|| format!("--release {}", args.release))
    .bad_input()?;
    let (friction_maps, friction_report) =
        friction_maps(&args.mu_raster, &args.xi_raster, &dem, &params).bad_input()?;
    let compare = args
        .compare
        .as_deref()
        .map(|r| super::avalanche_compare::read_inputs(r, args.path.as_deref()))
        .transpose()
        .bad_input()?;
    let folder = OutputFolder::open(&args.out).bad_input()?;
    folder.check_subfolder("frames").bad_input()?;
    let stage = folder.staging().to_path_buf();
    std::fs::create_dir(stage.join("frames"))
        .with_context(|| format!("cannot create {}/frames", stage.display()))
        .job_failed()?;
    let relief = ReliefFrames::new(&dem, &view).job_failed()?;
    let t0 = Instant::now();
    let mut workspace = AvalancheWorkspace::new();
    workspace.set_friction_maps(friction_maps);
    let bar = ProgressBar::new((options.duration_s * 10.0).ceil() as u64);
    if global.quiet {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    if let Ok(style) =
        ProgressStyle::with_template("{elapsed_precise:.dim} avalanche [{bar:30.cyan/blue}] {msg}")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    let mut out = Written::new(&stage);
    let mut frames = Vec::new();
    let mut next_frame = 0.0;
    let mut render_s = 0.0;
    let mut frame_error: Option<anyhow::Error> = None;
    let outcome = workspace
        .run_to_rest::<AvalancheError>(
            &mut terrain,
            ReleasedCells::new(&cells, None),
            &params,
            &options,
            SnowLayer::Stable,
            |r| {
                bar.set_position((r.time() * 10.0).round() as u64);
                bar.set_message(format!(
                    "t = {:.1} s, {:.0} m³ moving energy {:.3e}",
                    r.time(),
                    r.state.flowing_volume(),
                    r.kinetic_energy()
                ));
                if r.time() + 1e-9 >= next_frame || r.stop_reason().is_some() {
                    let tf = Instant::now();
                    let name = format!("frames/frame_{:04}.png", frames.len());
                    match render_frame(&relief, r).and_then(|img| {
                        write_png(&stage.join(&name), &img)
                            .map(|_| img)
                            .map_err(Into::into)
                    }) {
                        Ok(img) => {
                            out.files.push(name);
                            frames.push(img);
                        }
                        Err(e) if frame_error.is_none() => frame_error = Some(e),
                        Err(_) => {}
                    }
                    render_s += tf.elapsed().as_secs_f64();
                    next_frame += args.frame_interval;
                }
                Ok(())
            },
        )
        .job_failed()?;
    let summary = outcome.summary.clone();
    bar.finish_and_clear();
    if let Some(e) = frame_error {
        return Err(e).job_failed();
    }
    let wall = t0.elapsed().as_secs_f64();

    let n = dem.geometry().len();
    let map = |cells: &[(u32, f64)]| {
        RestOutcome::dense(cells, n)
            .iter()
            .map(|&x| x as f32)
            .collect::<Vec<f32>>()
    };
    (|| -> anyhow::Result<()> {
        write_map(
            &mut out,
            "peak_thickness.tif",
            &dem,
            map(&outcome.peak_thickness),
        )?;
        write_map(
            &mut out,
            "peak_velocity.tif",
            &dem,
            map(&outcome.peak_speed),
        )?;
        let deposit = RestOutcome::dense(&outcome.deposited, n);
        write_map(
            &mut out,
            "thickness.tif",
            &dem,
            deposit.iter().map(|&x| x as f32).collect(),
        )?;
        let fp: Vec<bool> = RestOutcome::dense(&outcome.peak_thickness, n)
            .iter()
            .map(|&h| h > options.footprint_threshold_m)
            .collect();
        write_map(
            &mut out,
            "footprint.tif",
            &dem,
            fp.iter().map(|&b| if b { 1.0 } else { 0.0 }).collect(),
        )?;
        if params.entrainment.enabled {
            write_map(
                &mut out,
                "entrained.tif",
                &dem,
                RestOutcome::dense(&outcome.entrained, n)
                    .iter()
                    .map(|&x| x as f32)
                    .collect(),
            )?;
        }
        let gif = encode_gif(&frames, 100)?;
        write_bytes_atomic(&out.path("avalanche.gif"), &gif)?;
        Ok(())
    })()
    .job_failed()?;
    let comparison = compare
        .as_ref()
        .map(|inputs| {
            super::avalanche_compare::compare_and_write(
                &mut out,
                inputs,
                &dem,
                &RestOutcome::dense(&outcome.peak_thickness, n),
                &RestOutcome::dense(&outcome.peak_speed, n),
                options.footprint_threshold_m,
                args.corridor,
            )
        })
        .transpose()
        .job_failed()?;
    out.files.push(snowscape::output_folder::REPORT.into());
    let report = AvalancheReport {
        snowscape_version: env!("CARGO_PKG_VERSION"),
        command: "avalanche",
        input: InputSummary::of(&source, &dem),
        release: match &spec {
            ReleaseSpec::Point(x, y) => ReleaseReport::Point { point: [*x, *y] },
            ReleaseSpec::File(p) => ReleaseReport::File {
                file: p.display().to_string(),
            },
            ReleaseSpec::Mask(_) => ReleaseReport::Mask { mask: true },
        },
        release_cells: area.count(),
        release_area_m2: area.area_m2(),
        release_warnings: &area.warnings,
        friction_maps: friction_report,
        parameters: RunParameters {
            flow: &params,
            run: &options,
            thickness_m: args.thickness,
            thickness_measured: args
                .thickness_measured
                .to_possible_value()
                .map(|v| v.get_name().to_string()),
        },
        seed: args.seed,
        threads: rayon::current_num_threads(),
        released_volume_m3: summary.released_volume_m3,
        entrained_volume_m3: summary.entrained_volume_m3,
        snow_cover_m: args.snow_cover,
        deposited_volume_m3: summary.final_volume_m3,
        border_outflow_m3: summary.border_outflow_m3,
        volume_closure_rel: summary.volume_closure_rel,
        runout_length_m: summary.runout_length_m,
        alpha_angle_deg: summary.alpha_angle_deg,
        travel_angle_deg: summary.travel_angle_deg,
        summary: &summary,
        simulated_s: summary.simulated_s,
        wall_s: wall,
        timings: Timings {
            flow_s: wall - render_s,
            frames_s: render_s,
        },
        comparison: comparison.as_ref(),
        outputs: &out.files,
    };
    let report = serde_json::to_value(&report)
        .context("the avalanche report")
        .job_failed()?;
    write_report(folder, report).job_failed()?;
    if !global.quiet {
        outln!(
            "avalanche: released {:.0} m³, entrained {:.0} m³, ran {:.1} s ({}), runout {:.0} m, travel angle {:.1}°, footprint {:.0} m², {:.2} s wall -> {}",
            summary.released_volume_m3,
            summary.entrained_volume_m3,
            summary.simulated_s,
            stop_words(summary.stop),
            summary.runout_length_m,
            summary.travel_angle_deg,
            summary.footprint_area_m2,
            wall,
            args.out.display()
        );
    }
    Ok(())
}

/// Why the run ended, in words for the summary line (`report.json` keeps the snake_case name).
fn stop_words(stop: Option<StopReason>) -> &'static str {
    match stop {
        Some(StopReason::AtRest) => "stopped at rest",
        Some(StopReason::EnergyCriterion) => {
            "stopped: kinetic energy below the stop fraction of its peak"
        }
        Some(StopReason::Duration) => "stopped: duration reached",
        Some(StopReason::Empty) => "stopped: all the snow left the grid",
        None => "still moving when it ended",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stop_reasons_are_told_in_words() {
        for stop in [
            None,
            Some(StopReason::AtRest),
            Some(StopReason::EnergyCriterion),
            Some(StopReason::Duration),
            Some(StopReason::Empty),
        ] {
            let words = stop_words(stop);
            assert!(
                !words.contains("Some(") && !words.contains("Criterion"),
                "{words}"
            );
        }
        assert!(stop_words(Some(StopReason::EnergyCriterion)).contains("kinetic energy"));
    }

    #[test]
    fn release_points_and_files_are_told_apart() {
        assert_eq!(
            parse_release("631500.5, 212300").unwrap(),
            ReleaseSpec::Point(631500.5, 212300.0)
        );
        assert!(parse_release("nan,3").is_err());
        let e = parse_release("no/such/file.shp").unwrap_err().to_string();
        assert!(e.contains("no/such/file.shp"), "{e}");
    }
}
