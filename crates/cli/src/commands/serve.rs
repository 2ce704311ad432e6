//! `snowscape serve`: the interactive browser editor (Cordonnier et al. 2018, Section 3) on a
//! DEM or the procedural terrain. The server itself is `snowscape-editor`; this command builds
//! the season, supplies the export of `snowscape run`'s outputs, and prints the URL.

use crate::cli::{GlobalArgs, ServeArgs, ViewArgs};
use crate::commands::render::preview_options;
use crate::failure::{ExitCodeExt, Failure};
use crate::stdout::outln;
use anyhow::{Context, anyhow};
use snowscape_editor::{Assets, BUILD_HINT, ProjectDir, ServeConfig, Session, serve_blocking};
use snowscape_render::ColourMode;
use snowscape_season::scenario::Scenario;
use snowscape_season::winter::Winter;
use snowscape_terrain::LayeredTerrain;
use snowscape_terrain::procedural::{AlpineParams, alpine};
use std::path::Path;
use std::sync::Arc;

/// Writes the rasters (GeoTIFF per layer, EXR, 16-bit PNG, splat map), the previews and the
/// glb of a season state into `dir`, as `snowscape run` does.
fn export(winter: &Winter, dir: &Path) -> Result<Vec<String>, String> {
    let view =
        preview_options(&ViewArgs::default(), ColourMode::Snow).map_err(|e| e.to_string())?;
    snowscape::outputs::write_state(dir, &winter.terrain, &view).map_err(|e| e.to_string())
}

pub fn run(args: &ServeArgs, global: &GlobalArgs) -> Result<(), Failure> {
    let mut scenario = match &args.scenario {
        Some(p) => {
            let text = snowscape_io::input::read_regular_text(p)
                .with_context(|| format!("cannot read scenario {}", p.display()))
                .bad_input()?;
            Scenario::from_toml(&text, &p.display().to_string()).bad_input()?
        }
        None => Scenario {
            seed: args.seed,
            ..Scenario::default()
        },
    };
    scenario.validate("the command line").bad_input()?;
    if args.scenario.is_none() {
        scenario.seed = args.seed;
    }
    let (bedrock, source) = match &args.dem {
        Some(p) => (args.dem_input.read(p).bad_input()?, p.display().to_string()),
        None => {
            if !(128..=4096).contains(&args.size) {
                return Err(anyhow!(
                    "--size must be within 128..=4096 cells, got {}",
                    args.size
                ))
                .bad_input();
            }
            let params = AlpineParams {
                size: args.size,
                seed: args.seed,
                cell_size: args.terrain_cell_size,
                ..AlpineParams::default()
            };
            let g = alpine(&params).bad_input()?;
            (
                g,
                format!(
                    "procedural alpine terrain {0}x{0}, seed {1}",
                    args.size, args.seed
                ),
            )
        }
    };
    if !(1..=1 << 20).contains(&args.snapshot_memory) {
        return Err(anyhow!(
            "--snapshot-memory must be within 1..=1048576 MiB, got {}",
            args.snapshot_memory
        ))
        .bad_input();
    }
    let project = ProjectDir::open(&args.project).bad_input()?;
    let assets = Assets::find(args.web_dir.as_deref());
    if matches!(assets, Assets::Missing) {
        eprintln!("warning: {BUILD_HINT}");
    }
    if !global.quiet {
        eprintln!("preparing the season (environment precompute)…");
    }
    let winter = Winter::new(scenario, LayeredTerrain::from_bedrock(bedrock)).job_failed()?;
    let mut session = Session::new(winter, source);
    session.set_snapshot_budget(args.snapshot_memory << 20);
    let config = ServeConfig {
        session,
        project,
        bind: args.bind,
        port: args.port,
        assets,
        exporter: Some(Arc::new(export)),
        pace: !args.no_pace,
    };
    let root = config.project.root().display().to_string();
    serve_blocking(config, |served| {
        outln!(
            "snowscape editor: {}  (project folder {root}; Ctrl-C stops)",
            served.url()
        );
        if let Some(warning) = served.network_warning() {
            eprintln!("{warning}");
        }
    })
    .job_failed()
}
