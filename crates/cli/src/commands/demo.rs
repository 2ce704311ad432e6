//! `snowscape demo`: the main job on the embedded default terrain, no input file needed.
//!
//! Generates the procedural alpine terrain and runs the default winter on it (the same season
//! pipeline as `snowscape run`), writing every output.

use crate::cli::{DemoArgs, GlobalArgs, ViewArgs};
use crate::commands::render::preview_options;
use crate::commands::season::{SeasonJob, run_season};
use crate::failure::{ExitCodeExt, Failure};
use anyhow::{Context, anyhow};
use snowscape::season_run::{ExtraParameters, GeneratedTerrain};
use snowscape_render::ColourMode;
use snowscape_season::scenario::Scenario;
use snowscape_terrain::procedural::{AlpineParams, alpine};

pub fn run(args: &DemoArgs, global: &GlobalArgs) -> Result<(), Failure> {
    if !(128..=8192).contains(&args.size) {
        return Err(anyhow!(
            "--size must be within 128..=8192 cells, got {}",
            args.size
        ))
        .bad_input();
    }
    let (lo, hi) = (
        snowscape_terrain::MIN_TERRAIN_CELL_M,
        snowscape_terrain::MAX_TERRAIN_CELL_M,
    );
    if !(lo..=hi).contains(&args.cell_size) {
        return Err(anyhow!(
            "--cell-size must be within {lo}..={hi} m, got {}",
            args.cell_size
        ))
        .bad_input();
    }
    if !(args.days.is_finite() && args.days > 0.0 && args.days <= 3650.0) {
        return Err(anyhow!(
            "--days must be within (0, 3650], got {}",
            args.days
        ))
        .bad_input();
    }
    // Refused before the terrain is generated, as run_season would refuse it after.
    snowscape::memory::check_season(args.size * args.size, args.memory_budget).bad_input()?;
    let view = preview_options(&ViewArgs::default(), ColourMode::Snow).job_failed()?;
    let params = AlpineParams {
        size: args.size,
        seed: args.seed,
        cell_size: args.cell_size,
        ..AlpineParams::default()
    };
    let t = std::time::Instant::now();
    let bedrock = alpine(&params).job_failed()?;
    let terrain_seconds = t.elapsed().as_secs_f64();
    let scenario = Scenario {
        seed: args.seed,
        days: args.days,
        snapshot_every_days: args.days / args.frames.max(1) as f64,
        checkpoint_every_days: 0.0,
        latitude_deg: Some(args.latitude),
        ..Scenario::default()
    };
    scenario
        .validate("the command line")
        .context("--latitude/--days")
        .bad_input()?;
    run_season(
        SeasonJob {
            command: "demo".into(),
            source: "procedural alpine terrain".into(),
            bedrock,
            scenario,
            extra_parameters: ExtraParameters::Demo {
                terrain: GeneratedTerrain {
                    size: params.size,
                    seed: params.seed,
                    cell_size_m: params.cell_size,
                    relief_m: params.relief,
                    base_altitude_m: params.base_altitude,
                    generation_seconds: terrain_seconds,
                },
            },
            out: args.out.clone(),
            resume: None,
            write_scenario: false,
            memory_budget: args.memory_budget,
            forcing: None,
            stop_at: None,
            view,
            cog: args.cog,
            friction_maps: Default::default(),
        },
        global.quiet,
    )
}
