//! `snowscape transport --dem FILE | --mesh FILE [--scenario FILE] [--out DIR]`: the
//! physical snow transport of Jubert 2018 (3D wind, precipitation map, SnowTran-3D
//! saltation, suspension, sublimation and melt) over a DEM, a mesh scene, or a mesh
//! standing on a DEM, through a scenario's weather timeline.

use crate::cli::{GlobalArgs, TransportArgs};
use crate::failure::{ExitCodeExt, Failure};
use anyhow::{Context, anyhow, bail};
use serde::Serialize;
use snowscape::output_folder::OutputFolder;
use snowscape::transport_job::{Overrides, dem_heights, fit_to_scene, load_scenario};
use snowscape::transport_job::{RunContext, write_outputs};
use snowscape_mesh::terrain::{map_to_scene, place_scene_on_grid};
use snowscape_mesh::top_view::{frame_scene, highest_surface};
use snowscape_mesh::{SceneBvh, SourceFrame, UpAxis, read_scene};
use snowscape_terrain::{Grid, GridGeometry, NodataMask};
use snowscape_transport::scenario::{SceneSpec, run};
use std::path::Path;
use std::time::Instant;

struct SceneInput {
    geometry: GridGeometry,
    heights: Vec<f32>,
    mask: NodataMask,
    summary: SceneSummary,
}

/// What the run's scene was made of (`report.json`'s `input`).
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
enum SceneSummary {
    /// A DEM.
    Dem(DemSummary),
    /// A mesh, alone or standing on a DEM.
    Mesh(MeshSummary),
    /// The scenario's own scene.
    Scenario { scene: SceneSpec },
}

/// A DEM as the scene.
#[derive(Debug, Clone, Serialize)]
struct DemSummary {
    /// The DEM file.
    dem: String,
    /// Nodata cells filled with the lowest valid altitude for the wind.
    nodata_cells_filled: usize,
}

/// A mesh as the scene: its file, its check, where it stands.
#[derive(Debug, Clone, Serialize)]
struct MeshSummary {
    mesh: String,
    triangles: usize,
    degenerate_dropped: usize,
    open_edges: usize,
    /// Cells whose top surface is the mesh, not the ground.
    cells_above_ground: usize,
    /// A mesh alone: the top view's cell size and the open ground around it, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    resolution_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    margin_m: Option<f64>,
    /// A mesh on a DEM: the DEM and where the mesh stands (scene metres).
    #[serde(skip_serializing_if = "Option::is_none")]
    dem: Option<DemSummary>,
    #[serde(skip_serializing_if = "Option::is_none")]
    placed_at_m: Option<[f64; 2]>,
}

/// A DEM with its nodata cells filled by the lowest valid altitude (the wind needs a
/// surface everywhere); the mask keeps them nodata in the outputs.
fn dem_scene(args: &TransportArgs, path: &Path) -> anyhow::Result<SceneInput> {
    let grid = args.dem_input.read(path)?;
    let (heights, filled) = dem_heights(&grid, &path.display().to_string())?;
    Ok(SceneInput {
        geometry: grid.geometry().clone(),
        heights,
        mask: grid.mask().clone(),
        summary: SceneSummary::Dem(DemSummary {
            dem: path.display().to_string(),
            nodata_cells_filled: filled,
        }),
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
    let mut summary = MeshSummary {
        mesh: path.display().to_string(),
        triangles: report.triangles(),
        degenerate_dropped: report.degenerate_dropped(),
        open_edges: report.open_edges(),
        cells_above_ground: 0,
        resolution_m: None,
        margin_m: None,
        dem: None,
        placed_at_m: None,
    };
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
            summary.cells_above_ground = heights.iter().filter(|&&z| z > ground + 1e-3).count();
            summary.resolution_m = Some(cell);
            summary.margin_m = Some(margin);
            Ok(SceneInput {
                geometry,
                heights,
                mask: NodataMask::all_valid(),
                summary: SceneSummary::Mesh(summary),
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
                Some(text) => {
                    let (mx, my) = crate::pairs::parse_xy("--at", text)?;
                    map_to_scene(&dem.geometry, mx, my)
                        .ok_or_else(|| anyhow!("--at {text:?} lies outside the DEM"))?
                }
                None => (ex / 2.0, ey / 2.0),
            };
            // The scene as one piece, as `snowscape cover` places it.
            place_scene_on_grid(&mut scene, &grid, x, y)?;
            let bvh = SceneBvh::new(&scene);
            let top = scene.bounds().map_or(0.0, |b| b.max[2]) + 1.0;
            let heights = highest_surface(&bvh, &dem.geometry, top, &dem.heights)?;
            summary.cells_above_ground = heights
                .iter()
                .zip(&dem.heights)
                .filter(|(z, d)| **z > **d + 1e-3)
                .count();
            if let SceneSummary::Dem(d) = dem.summary {
                summary.dem = Some(d);
            }
            summary.placed_at_m = Some([x, y]);
            Ok(SceneInput {
                geometry: dem.geometry,
                heights,
                mask: dem.mask,
                summary: SceneSummary::Mesh(summary),
            })
        }
    }
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
                summary: SceneSummary::Scenario {
                    scene: scenario.scene.clone(),
                },
            },
            None => {
                return Err(anyhow!(
                    "no scene: give --dem FILE, --mesh FILE, or a scenario with a [scene] (e.g. --scenario castle)"
                ))
                .bad_input();
            }
        },
    };
    let overrides = Overrides {
        hours: args.hours,
        flakes: args.flakes,
        seed: args.seed,
        wind_iterations: args.wind_iterations,
        voxel_size: args.voxel_size,
        voxel_layers: args.voxel_layers,
        uniform_precipitation: args.uniform_precipitation,
    };
    if !from_file && !overrides.sets_voxels() {
        // No scenario file: a wind grid fitted to the scene.
        fit_to_scene(&mut scenario, &input.geometry, &input.heights);
    }
    overrides
        .apply(&mut scenario)
        .context("the scenario after the command-line overrides")
        .bad_input()?;
    let folder = OutputFolder::open(&args.out).bad_input()?;
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
        input: serde_json::to_value(&input.summary)
            .context("the scene summary")
            .job_failed()?,
        mask: Some(&input.mask),
        wall_s: started.elapsed().as_secs_f64(),
    };
    let files =
        write_outputs(folder.staging(), &scenario, &input.heights, &out, &context).job_failed()?;
    let names: Vec<String> = files
        .iter()
        .filter_map(|p| p.strip_prefix(folder.staging()).ok())
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    folder.commit(&names, None).job_failed()?;
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
