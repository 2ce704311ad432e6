//! `snowscape transport --dem FILE | --mesh FILE [--scenario FILE] [--out DIR]`: the
//! physical snow transport of Jubert 2018 (3D wind, precipitation map, SnowTran-3D
//! saltation, suspension, sublimation and melt) over a DEM, a mesh scene, or a mesh
//! standing on a DEM, through a scenario's weather timeline.

use crate::cli::{GlobalArgs, TransportArgs};
use crate::failure::{ExitCodeExt, Failure};
use crate::outputs::prepare_dir;
use anyhow::{Context, anyhow, bail};
use serde_json::json;
use snowscape_mesh::top_view::{frame_scene, highest_surface};
use snowscape_mesh::{SceneBvh, SourceFrame, UpAxis, read_scene};
use snowscape_terrain::{Grid, GridGeometry, NodataMask};
use snowscape_transport::outputs::{RunContext, write_outputs};
use snowscape_transport::scenario::{Scenario, SceneSpec, fit_voxels, run, shipped_scenario};
use std::path::Path;
use std::time::Instant;

/// Longest side of an automatically fitted wind grid, voxels.
const FITTED_COLUMNS: usize = 128;

/// The scene of a run: its grid, heights and the cells outside the input.
struct SceneInput {
    geometry: GridGeometry,
    heights: Vec<f32>,
    mask: NodataMask,
    summary: serde_json::Value,
}

/// The scenario named by `--scenario`: a shipped one (`castle`, `valley`) or a TOML file.
fn load_scenario(text: Option<&str>) -> anyhow::Result<(Scenario, bool)> {
    let Some(text) = text else {
        // The weather of Table 7.I (12 h of snowfall at −5 °C, then 24 h at +10 °C, a
        // west wind of 11 m/s) on the input scene.
        let castle = shipped_scenario("castle").expect("shipped");
        let mut s = Scenario::from_toml(castle).map_err(|e| anyhow!("shipped castle: {e}"))?;
        s.name = "table_7_1_weather".into();
        s.scene = SceneSpec::Input;
        s.wind_iterations = 20;
        return Ok((s, false));
    };
    let path = Path::new(text);
    let (source, name) = if path.exists() {
        let s = snowscape_io::input::read_regular_text(path)
            .with_context(|| format!("cannot read scenario {}", path.display()))?;
        (s, path.display().to_string())
    } else if let Some(s) = shipped_scenario(text) {
        (s.to_string(), format!("shipped scenario {text}"))
    } else {
        bail!("--scenario {text:?} is neither a file nor a shipped scenario (castle, valley)");
    };
    let scenario = Scenario::from_toml(&source).map_err(|e| anyhow!("scenario {name}: {e}"))?;
    scenario
        .validate()
        .map_err(|e| anyhow!("scenario {name}: {e}"))?;
    Ok((scenario, true))
}

/// A DEM with its nodata cells filled by the lowest valid altitude (the wind needs a
/// surface everywhere); the mask keeps them nodata in the outputs.
fn dem_scene(args: &TransportArgs, path: &Path) -> anyhow::Result<SceneInput> {
    let grid = args.dem_input.read(path)?;
    let mask = grid.mask().clone();
    let valid = |i: usize| mask.is_valid(i);
    let lowest = (0..grid.data().len())
        .filter(|&i| valid(i))
        .map(|i| grid.data()[i])
        .fold(f32::INFINITY, f32::min);
    if !lowest.is_finite() {
        bail!("{}: every cell is nodata", path.display());
    }
    let filled = (0..grid.data().len()).filter(|&i| !valid(i)).count();
    let heights = grid
        .data()
        .iter()
        .enumerate()
        .map(|(i, &z)| if valid(i) { z } else { lowest })
        .collect();
    Ok(SceneInput {
        geometry: grid.geometry().clone(),
        heights,
        mask,
        summary: json!({"dem": path.display().to_string(), "nodata_cells_filled": filled}),
    })
}

/// A mesh alone (on flat ground at its lowest point, with open ground around it) or
/// standing on the DEM at `--at` (default: the DEM's centre), as its top view.
fn mesh_scene(
    args: &TransportArgs,
    path: &Path,
    dem: Option<SceneInput>,
) -> anyhow::Result<SceneInput> {
    let up: UpAxis = args
        .up
        .parse()
        .map_err(|e| anyhow!("--up {:?}: {e}", args.up))?;
    let frame = SourceFrame::new(up, args.scale).map_err(|e| anyhow!("--scale: {e}"))?;
    let (mut scene, report) = read_scene(path, &frame)?;
    let summary = json!({
        "mesh": path.display().to_string(),
        "triangles": report.triangles(),
        "degenerate_dropped": report.degenerate_dropped(),
        "open_edges": report.open_edges(),
    });
    match dem {
        None => {
            let b = scene
                .bounds()
                .ok_or_else(|| anyhow!("{}: no valid triangle", path.display()))?;
            let size = b.size();
            let longest = f64::from(size[0].max(size[1]));
            let cell = args.resolution.unwrap_or(longest / 100.0);
            let margin = args.margin.unwrap_or(longest);
            let (geometry, ground) = frame_scene(&mut scene, cell, margin)?;
            let bvh = SceneBvh::new(&scene);
            let top = b.max[2] + 1.0;
            let heights = highest_surface(&bvh, &geometry, top, &vec![ground; geometry.len()])?;
            let mut summary = summary;
            summary["cells_above_ground"] =
                json!(heights.iter().filter(|&&z| z > ground + 1e-3).count());
            summary["resolution_m"] = json!(cell);
            summary["margin_m"] = json!(margin);
            Ok(SceneInput {
                geometry,
                heights,
                mask: NodataMask::all_valid(),
                summary,
            })
        }
        Some(dem) => {
            if args.resolution.is_some() || args.margin.is_some() {
                bail!(
                    "--resolution and --margin apply to a mesh alone: on a DEM the DEM's grid is used"
                );
            }
            let grid = Grid::new(
                dem.geometry.clone(),
                dem.heights.clone(),
                NodataMask::all_valid(),
            )?;
            let (ex, ey) = dem.geometry.extent_m();
            let (x, y) = match &args.at {
                Some(text) => parse_at(text, &dem.geometry)?,
                None => (ex / 2.0, ey / 2.0),
            };
            for o in &mut scene.objects {
                snowscape_mesh::terrain::place_on_grid(o, &grid, x, y)?;
            }
            let bvh = SceneBvh::new(&scene);
            let top = scene.bounds().map_or(0.0, |b| b.max[2]) + 1.0;
            let heights = highest_surface(&bvh, &dem.geometry, top, &dem.heights)?;
            let mut summary = summary;
            summary["cells_above_ground"] = json!(
                heights
                    .iter()
                    .zip(&dem.heights)
                    .filter(|(z, d)| **z > **d + 1e-3)
                    .count()
            );
            summary["dem"] = dem.summary;
            summary["placed_at_m"] = json!([x, y]);
            Ok(SceneInput {
                geometry: dem.geometry,
                heights,
                mask: dem.mask,
                summary,
            })
        }
    }
}

/// `--at X,Y` in map coordinates, as scene metres from the DEM's south-west corner.
fn parse_at(text: &str, g: &GridGeometry) -> anyhow::Result<(f64, f64)> {
    let (x, y) = crate::pairs::parse_xy("--at", text)?;
    let Some((col, row)) = g.map_to_cell(x, y) else {
        bail!("--at {text:?} lies outside the DEM");
    };
    Ok((
        (col + 0.5) * g.cell_size_x(),
        (g.height() as f64 - row - 0.5) * g.cell_size_y(),
    ))
}

/// Applies the command-line overrides to the scenario.
fn apply_overrides(args: &TransportArgs, s: &mut Scenario) -> anyhow::Result<()> {
    if let Some(h) = args.hours {
        s.duration_h = h;
    }
    if let Some(n) = args.flakes {
        s.flakes.count = n;
    }
    if let Some(n) = args.wind_iterations {
        s.wind_iterations = n;
    }
    if let Some(seed) = args.seed {
        s.flakes.seed = seed;
    }
    if let Some(v) = args.voxel_size {
        s.voxel_size_m = v;
    }
    if let Some(n) = args.voxel_layers {
        s.voxel_layers = n;
    }
    if args.uniform_precipitation {
        s.uniform_precipitation = true;
    }
    s.validate()
        .context("the scenario after the command-line overrides")?;
    Ok(())
}

pub fn run_command(args: &TransportArgs, global: &GlobalArgs) -> Result<(), Failure> {
    let started = Instant::now();
    let (mut scenario, from_file) = load_scenario(args.scenario.as_deref()).bad_input()?;
    let dem = match &args.dem {
        Some(p) => Some(dem_scene(args, p).bad_input()?),
        None => None,
    };
    let input = match (&args.mesh, dem) {
        (Some(m), dem) => Some(mesh_scene(args, m, dem).bad_input()?),
        (None, Some(dem)) => Some(dem),
        (None, None) => None,
    };
    let input = match input {
        Some(input) => {
            if !matches!(scenario.scene, SceneSpec::Input) {
                tracing::warn!("the scenario's own [scene] is replaced by the input");
                scenario.scene = SceneSpec::Input;
            }
            input
        }
        None => match scenario.build_scene().bad_input()? {
            Some((geometry, heights)) => SceneInput {
                geometry,
                heights,
                mask: NodataMask::all_valid(),
                summary: json!({"scene": scenario.scene}),
            },
            None => {
                return Err(anyhow!(
                    "no scene: give --dem FILE, --mesh FILE, or a scenario with a [scene] (e.g. --scenario castle)"
                ))
                .bad_input();
            }
        },
    };
    let lowest = input.heights.iter().fold(f32::INFINITY, |m, &z| m.min(z));
    let highest = input
        .heights
        .iter()
        .fold(f32::NEG_INFINITY, |m, &z| m.max(z));
    if !from_file && args.voxel_size.is_none() && args.voxel_layers.is_none() {
        // No scenario file: a wind grid fitted to the scene.
        let (size, layers) = fit_voxels(
            &input.geometry,
            f64::from(lowest),
            f64::from(highest),
            input
                .geometry
                .cell_size_x()
                .max(input.geometry.cell_size_y()),
            FITTED_COLUMNS,
        );
        scenario.voxel_size_m = size;
        scenario.voxel_layers = layers;
    }
    apply_overrides(args, &mut scenario).bad_input()?;
    prepare_dir(&args.out).job_failed()?;
    if !global.quiet {
        let g = &input.geometry;
        eprintln!(
            "transport: {}x{} cells of {:.2} m, wind on {:.2} m voxels x {} layers, {} h",
            g.width(),
            g.height(),
            g.cell_size_x(),
            scenario.voxel_size_m,
            scenario.voxel_layers,
            scenario.duration_h
        );
    }
    let out = run(&scenario, &input.geometry, &input.heights).bad_input()?;
    let context = RunContext {
        input: input.summary,
        mask: Some(&input.mask),
        wall_s: started.elapsed().as_secs_f64(),
    };
    let files = write_outputs(&args.out, &scenario, &input.heights, &out, &context).job_failed()?;
    if !global.quiet {
        let b = &out.budget;
        eprintln!(
            "wrote {} files to {} in {:.1} s: {} steps, residual divergence {:.2e} /s, mass budget closure {:.2e} kg of {:.3e} kg",
            files.len(),
            args.out.display(),
            started.elapsed().as_secs_f64(),
            out.steps,
            out.wind_report.mean.max_divergence,
            b.closure_error,
            b.final_mass
        );
    }
    Ok(())
}
