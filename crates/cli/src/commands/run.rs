//! `snowscape run --dem FILE`: a season on a real terrain.

use crate::cli::{GlobalArgs, RunArgs, SkierArgs};
use crate::commands::render::preview_options;
use crate::commands::season::{SeasonJob, run_season};
use crate::failure::{ExitCodeExt, Failure};
use anyhow::{Context, bail};
use snowscape::season_run::{ExtraParameters, RESOLVED_SCENARIO};
use snowscape_render::ColourMode;
use snowscape_season::scenario::Scenario;
use std::path::Path;

fn load_scenario(path: &Path) -> anyhow::Result<Scenario> {
    let text = snowscape_io::input::read_regular_text(path)
        .with_context(|| format!("cannot read scenario {}", path.display()))?;
    Ok(Scenario::from_toml(&text, &path.display().to_string())?)
}

/// Sets the scenario's skiers from `--skiers`, `--skier-frequency` and `--skier-start`.
fn apply_skier_args(scenario: &mut Scenario, args: &SkierArgs) -> anyhow::Result<()> {
    if let Some(n) = args.skiers {
        scenario.skiers.per_day = n as f64 / scenario.days;
    }
    if let Some(f) = args.skier_frequency {
        if !(f.is_finite() && f >= 0.0) {
            bail!("--skier-frequency must be a number of runs per day >= 0, got {f}");
        }
        scenario.skiers.per_day = f;
    }
    for text in &args.skier_start {
        let (x, y) = crate::pairs::parse_xy("--skier-start", text)?;
        scenario.skiers.starts.push([x, y]);
    }
    if !args.skier_start.is_empty() && scenario.skiers.per_day == 0.0 {
        scenario.skiers.per_day = 24.0;
    }
    Ok(())
}

pub fn run(args: &RunArgs, global: &GlobalArgs) -> Result<(), Failure> {
    let out = args
        .out
        .clone()
        .or_else(|| args.resume.clone())
        .unwrap_or_else(|| "out/run".into());
    let scenario_path = match (&args.scenario, &args.resume) {
        (Some(p), _) => Some(p.clone()),
        (None, Some(dir)) => Some(dir.join(RESOLVED_SCENARIO)),
        (None, None) => None,
    };
    let mut scenario = match &scenario_path {
        Some(p) => load_scenario(p).bad_input()?,
        None => Scenario::default(),
    };
    if let Some(d) = args.days {
        scenario.days = d;
    }
    if let Some(s) = args.seed {
        scenario.seed = s;
    }
    apply_skier_args(&mut scenario, &args.skiers).bad_input()?;
    if let Some(l) = args.latitude {
        scenario.latitude_deg = Some(l);
    }
    if let Some(z) = args.station_altitude {
        scenario.station_altitude_m = Some(z);
    }
    // The forcing file: the flag's path, or the scenario's relative to the scenario file.
    let days = args.days.map(|_| scenario.days);
    let forcing = snowscape::station::forcing_path(
        args.forcing.as_deref(),
        &scenario,
        scenario_path.as_deref(),
    )
    .map(|p| {
        snowscape::station::adopt_station_forcing(&mut scenario, &p, days).context("--forcing")
    })
    .transpose()
    .bad_input()?;
    scenario
        .validate("the command line")
        .context("--days/--seed/--skiers")
        .bad_input()?;
    let bedrock = args.dem_input.read(&args.dem).bad_input()?;
    let scenario_name = scenario_path
        .as_ref()
        .map_or("the command line".to_string(), |p| p.display().to_string());
    scenario
        .validate_on(bedrock.geometry(), &scenario_name)
        .with_context(|| format!("on the terrain {}", args.dem.display()))
        .bad_input()?;
    let view = preview_options(&args.view, ColourMode::Snow).bad_input()?;
    let (friction_maps, _) = super::avalanche::friction_maps(
        &args.mu_raster,
        &args.xi_raster,
        &bedrock,
        &scenario.parameters.avalanche.flow,
    )
    .bad_input()?;
    run_season(
        SeasonJob {
            command: "run".into(),
            source: args.dem.display().to_string(),
            bedrock,
            scenario,
            extra_parameters: ExtraParameters::Run {
                scenario_file: scenario_path.map(|p| p.display().to_string()),
                mu_raster: args.mu_raster.as_ref().map(|p| p.display().to_string()),
                xi_raster: args.xi_raster.as_ref().map(|p| p.display().to_string()),
            },
            out,
            resume: args.resume.clone(),
            stop_at: args.stop_at,
            forcing,
            view,
            cog: args.cog,
            write_scenario: true,
            memory_budget: args.memory_budget,
            friction_maps,
        },
        global.quiet,
    )
}
