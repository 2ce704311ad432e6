//! The files of a transport run (issue 6, item 7): `depth.tif`, `density.tif`,
//! `q_salt.tif`, `q_susp.tif`, `q_subl.tif`, `precipitation.tif`, `wind2d.tif` (2 bands:
//! east, north m s⁻¹), `wind3d.bin` (the mean 3D wind, [`snowscape_transport::wind3d::mean_wind_bytes`]),
//! `preview.png` (shaded relief with the snow) and `report.json` (scenario, wind and flake
//! statistics, the mass budget with its closure error, timings). Every file is written
//! atomically through `snowscape-io` (a synced temporary sibling renamed over the name).

use serde::Serialize;
use snowscape_io::{write_bytes_atomic, write_geotiff_bands};
use snowscape_render::{PreviewOptions, encode_png, render_preview};
use snowscape_terrain::{Grid, LayeredTerrain, NodataMask, SnowLayer};
use snowscape_transport::scenario::{RunOutputs, Scenario, WindReport};
use snowscape_transport::step::MassBudget;
use snowscape_transport::wind3d::{IterationReport, mean_wind_bytes};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// A file of a transport run that could not be written.
#[derive(Debug, Error)]
#[error("cannot write {path}: {message}")]
pub struct OutputError {
    /// The file.
    pub path: PathBuf,
    /// Why.
    pub message: String,
}

fn fail(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// What the report says of the run besides its results.
#[derive(Debug, Clone, Default)]
pub struct RunContext<'a> {
    /// Where the scene came from (file names, options), recorded as `input`.
    pub input: serde_json::Value,
    /// Cells outside the input (a DEM's nodata, filled for the wind): written as nodata.
    pub mask: Option<&'a NodataMask>,
    /// Wall-clock time of the whole command, s.
    pub wall_s: f64,
}

/// Writes every output of `out` into `dir` (created if missing); `heights` is the scene's
/// height map. Returns the paths written.
pub fn write_outputs(
    dir: &Path,
    scenario: &Scenario,
    heights: &[f32],
    out: &RunOutputs,
    context: &RunContext,
) -> Result<Vec<PathBuf>, OutputError> {
    std::fs::create_dir_all(dir).map_err(|e| fail(dir, e))?;
    let g = &out.geometry;
    let all_valid = NodataMask::all_valid();
    let mask = context.mask.unwrap_or(&all_valid);
    let mut written = Vec::new();
    let depth = out.state.depth();
    let maps: [(&str, Vec<&[f32]>); 7] = [
        ("depth.tif", vec![&depth]),
        ("density.tif", vec![&out.state.density]),
        ("q_salt.tif", vec![&out.q_salt]),
        ("q_susp.tif", vec![&out.q_susp]),
        ("q_subl.tif", vec![&out.q_subl]),
        ("precipitation.tif", vec![&out.precipitation_ratio]),
        ("wind2d.tif", vec![&out.wind_u, &out.wind_v]),
    ];
    for (name, bands) in maps {
        let path = dir.join(name);
        write_geotiff_bands(&path, g, mask, &bands).map_err(|e| fail(&path, e))?;
        written.push(path);
    }
    let path = dir.join("wind3d.bin");
    snowscape_io::write_bytes_atomic(&path, &mean_wind_bytes(&out.voxels, &out.mean_wind))
        .map_err(|e| fail(&path, e))?;
    written.push(path);
    let path = dir.join("preview.png");
    let bedrock =
        Grid::new(g.clone(), heights.to_vec(), mask.clone()).map_err(|e| fail(&path, e))?;
    let mut terrain = LayeredTerrain::from_bedrock(bedrock);
    terrain.layer_mut(SnowLayer::Powder).copy_from_slice(&depth);
    let image = render_preview(&terrain, &PreviewOptions::default()).map_err(|e| fail(&path, e))?;
    let png = encode_png(&image).map_err(|e| fail(&path, e))?;
    write_bytes_atomic(&path, &png).map_err(|e| fail(&path, e))?;
    written.push(path);
    let path = dir.join(crate::output_folder::REPORT);
    let report = TransportReport::new(scenario, out, context.input.clone(), context.wall_s);
    let text = serde_json::to_string_pretty(&report).map_err(|e| fail(&path, e))?;
    write_bytes_atomic(&path, text.as_bytes()).map_err(|e| fail(&path, e))?;
    written.push(path);
    Ok(written)
}

/// A transport run's `report.json`: the scenario, the grids, the wind solve, the flakes, the
/// depth reached, the mass budget (kg) and the timings. `write_outputs` writes it; the Python
/// package returns it.
#[derive(Debug, Clone, Serialize)]
pub struct TransportReport {
    /// Every parameter of the run, as the scenario file would spell it.
    pub scenario: Scenario,
    pub grid: GridSize,
    pub voxels: VoxelSize,
    pub wind: WindSolve,
    pub flakes: FlakeCounts,
    /// Time steps of the transport.
    pub steps: usize,
    pub depth_m: DepthStats,
    pub mass_budget: KgBudget,
    /// Where the scene came from (file names, options).
    pub input: serde_json::Value,
    pub timings_s: TransportTimings,
}

/// The height grid.
#[derive(Debug, Clone, Serialize)]
pub struct GridSize {
    pub width: usize,
    pub height: usize,
    pub cell_size_m: f64,
}

/// The voxel grid of the wind.
#[derive(Debug, Clone, Serialize)]
pub struct VoxelSize {
    pub nx: usize,
    pub ny: usize,
    pub nz: usize,
    pub size_m: f64,
}

/// The wind solve: its last iteration and the projection of the mean wind.
#[derive(Debug, Clone, Serialize)]
pub struct WindSolve {
    pub last_iteration: IterationReport,
    pub mean_projection: IterationReport,
    /// Largest divergence left in the mean wind, s⁻¹.
    pub residual_divergence_per_s: f64,
    /// The same relative to `U / Δ`.
    pub relative_divergence: f64,
}

impl From<WindReport> for WindSolve {
    fn from(w: WindReport) -> Self {
        Self {
            last_iteration: w.last_iteration,
            mean_projection: w.mean,
            residual_divergence_per_s: w.mean.max_divergence,
            relative_divergence: w.mean.relative_divergence,
        }
    }
}

/// The precipitation flakes.
#[derive(Debug, Clone, Serialize)]
pub struct FlakeCounts {
    pub landed: u64,
    pub lost: u64,
    /// Share of the flakes that left through the sides.
    pub side_share: f64,
    /// Whether the precipitation fell back to a uniform map.
    pub uniform_fallback: bool,
}

/// Mean and deepest snow, m.
#[derive(Debug, Clone, Serialize)]
pub struct DepthStats {
    pub mean: f64,
    pub max: f32,
}

/// The mass budget with its unit (kg), closing on `closure_error`.
#[derive(Debug, Clone, Serialize)]
pub struct KgBudget {
    pub unit: &'static str,
    #[serde(flatten)]
    pub budget: MassBudget,
}

/// Seconds per stage and of the whole command.
#[derive(Debug, Clone, Serialize)]
pub struct TransportTimings {
    pub voxelise: f64,
    pub wind: f64,
    pub terrain_wind: f64,
    pub precipitation: f64,
    pub transport: f64,
    pub wall: f64,
}

impl TransportReport {
    /// The report of run `out` of `scenario`; `input` says where the scene came from, `wall_s`
    /// is the whole job's time.
    pub fn new(
        scenario: &Scenario,
        out: &RunOutputs,
        input: serde_json::Value,
        wall_s: f64,
    ) -> Self {
        let g = &out.geometry;
        let depth = out.state.depth();
        let n = depth.len().max(1) as f64;
        Self {
            scenario: scenario.clone(),
            grid: GridSize {
                width: g.width(),
                height: g.height(),
                cell_size_m: g.cell_size_x(),
            },
            voxels: VoxelSize {
                nx: out.voxels.nx,
                ny: out.voxels.ny,
                nz: out.voxels.nz,
                size_m: out.voxels.cell,
            },
            wind: out.wind_report.into(),
            flakes: FlakeCounts {
                landed: out.flakes.landed,
                lost: out.flakes.lost,
                side_share: out.flakes.side_share,
                uniform_fallback: out.precipitation_fallback,
            },
            steps: out.steps,
            depth_m: DepthStats {
                mean: depth.iter().map(|&d| f64::from(d)).sum::<f64>() / n,
                max: depth.iter().fold(0.0f32, |m, &d| m.max(d)),
            },
            mass_budget: KgBudget {
                unit: "kg",
                budget: out.budget,
            },
            input,
            timings_s: TransportTimings {
                voxelise: out.times.voxelise_s,
                wind: out.times.wind_s,
                terrain_wind: out.times.terrain_wind_s,
                precipitation: out.times.precipitation_s,
                transport: out.times.transport_s,
                wall: wall_s,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_transport::scenario::{SceneSpec, run, shipped_scenario};

    /// The castle on a coarse grid for two hours: every file is written and the report carries
    /// the run's budget.
    #[test]
    fn every_file_is_written_and_the_report_carries_the_budget() {
        let mut s = Scenario::from_toml(shipped_scenario("castle").unwrap()).unwrap();
        s.scene = SceneSpec::Castle {
            size_m: 850.0,
            cell_m: 25.0,
        };
        s.voxel_size_m = 34.0;
        s.voxel_layers = 8;
        s.wind_iterations = 2;
        s.flakes.count = 5_000;
        s.duration_h = 2.0;
        s.transport.time_step_s = 1800.0;
        s.validate().unwrap();
        let (g, z) = s.build_scene().unwrap().unwrap();
        let out = run(&s, &g, &z).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let files = write_outputs(dir.path(), &s, &z, &out, &RunContext::default()).unwrap();
        assert_eq!(files.len(), 10);
        for f in &files {
            assert!(
                f.is_file() && std::fs::metadata(f).unwrap().len() > 0,
                "{f:?}"
            );
        }
        let report: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join("report.json")).unwrap())
                .unwrap();
        let b = &report["mass_budget"];
        assert_eq!(
            b["closure_error"].as_f64().unwrap(),
            out.budget.closure_error
        );
        assert_eq!(b["final"].as_f64().unwrap(), out.budget.final_mass);
        assert_eq!(report["steps"], out.steps);
        assert_eq!(report["grid"]["width"], g.width());
    }
}
