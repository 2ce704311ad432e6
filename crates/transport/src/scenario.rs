//! Scenarios (Jubert 2018, Tables 6.I and 7.I) and the run driver of the whole pipeline of
//! Fig. 6.1: voxelise the scene, simulate the 3D wind (Chapter 3), take the wind at `z_r`
//! and modify it by the terrain (Section 5.4), build the precipitation map (Chapter 4), then
//! integrate the transport (Section 5.5) through the weather timeline.
//!
//! A scenario file (TOML) maps 1:1 onto [`Scenario`]; unknown keys are errors. The two
//! scenes of Table 7.I ship in `crates/transport/scenarios/` (`castle.toml`, a castle of
//! walls and towers built by [`castle_heights`] on 850 m; `valley.toml`, an 8 km valley
//! from the project's procedural terrain).
//!
//! The 3D wind is simulated once, for the scenario's `[wind]`. Each weather period scales
//! it by `wind_speed_m_s / [wind].speed_m_s` (0 is calm air); a change of direction would
//! need another wind simulation and precipitation map (Section 6.1), which a timeline with
//! one direction, as in Table 7.I, does not.

use crate::error::{TransportError, check_positive, check_range};
use crate::params::{Timeline, TransportParams, Weather};
use crate::precipitation::{FlakeParams, FlakeSummary, precipitation_map};
use crate::step::{MassBudget, SceneMaps, SnowState, StepScratch, step};
use crate::terrain_wind::{check_len, modify_wind};
use crate::wind3d::field::Velocity;
use crate::wind3d::voxel::{VoxelGrid, castle_heights};
use crate::wind3d::{IterationReport, Wind3dParams, WindSolver};
use serde::{Deserialize, Serialize};
use snowscape_terrain::procedural::{AlpineParams, alpine};
use snowscape_terrain::{Grid, GridGeometry, NodataMask};

/// Where the scene's height map comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SceneSpec {
    /// The project's castle of walls and towers ([`castle_heights`]).
    Castle {
        /// Side of the square domain, m. Table 7.I: 850.
        size_m: f64,
        /// Transport cell size, m. Section 7.1.1: 1 m (840²).
        cell_m: f64,
    },
    /// The project's procedural alpine terrain (a valley scene).
    Procedural {
        /// Cells per side.
        size: usize,
        /// Cell size, m. Table 7.I's valley: 8000 m, here 20 m × 400.
        cell_m: f64,
        /// Terrain seed.
        seed: u64,
        /// Relief, m.
        relief_m: f64,
    },
    /// A DEM or mesh supplied by the caller (the command line's `--dem` or `--mesh`).
    Input,
}

/// A complete transport scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Scenario {
    /// Name, for reports.
    pub name: String,
    /// Simulated time, h. Table 7.I: 36 (12 h of snowfall, then 24 h warm).
    pub duration_h: f64,
    /// The scene.
    pub scene: SceneSpec,
    /// Voxel side of the wind grid, m. Table 7.I: 850/200 (castle), 8000/400 (valley).
    pub voxel_size_m: f64,
    /// Voxel layers of the wind grid. Table 7.I: 50 (castle), 100 (valley).
    pub voxel_layers: usize,
    /// Stable Fluids iterations averaged into the mean wind (Section 6.3).
    pub wind_iterations: usize,
    /// Use a uniform snowfall instead of the precipitation map (the comparison of
    /// Fig. 7.10).
    pub uniform_precipitation: bool,
    /// Transport parameters (Table 6.I).
    pub transport: TransportParams,
    /// The 3D wind.
    pub wind: Wind3dParams,
    /// The flakes of the precipitation map.
    pub flakes: FlakeParams,
    /// Initial snow depth, m, and its density, kg m⁻³.
    pub initial_depth_m: f64,
    /// Density of the initial snow, kg m⁻³.
    pub initial_density: f64,
    /// The weather timeline.
    pub weather: Vec<Weather>,
}

impl Default for Scenario {
    fn default() -> Self {
        Self {
            name: "scenario".into(),
            duration_h: 36.0,
            scene: SceneSpec::Input,
            voxel_size_m: 8.0,
            voxel_layers: 32,
            wind_iterations: 20,
            uniform_precipitation: false,
            transport: TransportParams::default(),
            wind: Wind3dParams::default(),
            flakes: FlakeParams::default(),
            initial_depth_m: 0.0,
            initial_density: snowscape_terrain::SnowLayer::Powder.default_density_kg_m3(),
            weather: vec![Weather::default()],
        }
    }
}

impl Scenario {
    /// Parses a scenario file's text; errors name the key, line and column.
    pub fn from_toml(text: &str) -> Result<Self, toml::de::Error> {
        toml::from_str(text)
    }

    /// Checks every part.
    pub fn validate(&self) -> Result<(), TransportError> {
        check_positive("duration_h", self.duration_h)?;
        check_positive("voxel_size_m", self.voxel_size_m)?;
        check_range("voxel_layers", self.voxel_layers as f64, 2.0, 4096.0)?;
        check_range("wind_iterations", self.wind_iterations as f64, 1.0, 1e6)?;
        check_range("initial_depth_m", self.initial_depth_m, 0.0, 100.0)?;
        check_positive("initial_density", self.initial_density)?;
        self.transport.validate()?;
        self.wind.validate()?;
        self.flakes.validate()?;
        Timeline(self.weather.clone()).validate()
    }

    /// The height map the scene builds, or `None` for [`SceneSpec::Input`].
    pub fn build_scene(&self) -> Result<Option<(GridGeometry, Vec<f32>)>, TransportError> {
        let terrain = |e: snowscape_terrain::TerrainError| TransportError::Scene(e.to_string());
        match &self.scene {
            SceneSpec::Castle { size_m, cell_m } => {
                check_positive("scene.size_m", *size_m)?;
                check_positive("scene.cell_m", *cell_m)?;
                let n = ((size_m / cell_m).round() as usize).max(2);
                let g = GridGeometry::square(n, n, *cell_m).map_err(terrain)?;
                Ok(Some((g, castle_heights(n, *cell_m))))
            }
            SceneSpec::Procedural {
                size,
                cell_m,
                seed,
                relief_m,
            } => {
                let grid = alpine(&AlpineParams {
                    size: *size,
                    seed: *seed,
                    cell_size: *cell_m,
                    relief: *relief_m,
                    ..Default::default()
                })
                .map_err(terrain)?;
                Ok(Some((grid.geometry().clone(), grid.into_data())))
            }
            SceneSpec::Input => Ok(None),
        }
    }
}

/// The scenarios of Table 7.I shipped with the project, by name (`castle`, `valley`): the
/// text of `crates/transport/scenarios/NAME.toml`.
pub fn shipped_scenario(name: &str) -> Option<&'static str> {
    match name {
        "castle" => Some(include_str!("../scenarios/castle.toml")),
        "valley" => Some(include_str!("../scenarios/valley.toml")),
        _ => None,
    }
}

/// A voxel grid for a scene of `geometry` whose surface spans `[lowest, highest]` m: voxels
/// of at least `min_voxel_m`, at most `max_columns` along the longer side, and layers for
/// the relief plus open air above it (two thirds of the relief, at least 15 voxels, as the
/// thesis's valley: 2000 m of air column over 1200 m of relief). Returns `(size, layers)`.
pub fn fit_voxels(
    geometry: &GridGeometry,
    lowest: f64,
    highest: f64,
    min_voxel_m: f64,
    max_columns: usize,
) -> (f64, usize) {
    let (ex, ey) = geometry.extent_m();
    let size = min_voxel_m.max(ex.max(ey) / max_columns.max(1) as f64);
    let relief = (highest - lowest).max(0.0);
    let air = (relief * 2.0 / 3.0).max(15.0 * size);
    // One voxel of ground under the lowest point (the grid's base is `lowest - size`).
    let layers = ((relief + air) / size).ceil() as usize + 1;
    (size, layers.clamp(8, 256))
}

/// Checks that the voxel grid of `scenario` holds the scene's surface with air above it:
/// its top must clear the highest point by two voxels.
pub fn check_voxel_height(
    scenario: &Scenario,
    lowest: f64,
    highest: f64,
) -> Result<(), TransportError> {
    let top = lowest - scenario.voxel_size_m + scenario.voxel_size_m * scenario.voxel_layers as f64;
    if top < highest + 2.0 * scenario.voxel_size_m {
        return Err(TransportError::InvalidParameter {
            name: "voxel_layers",
            value: scenario.voxel_layers as f64,
            reason: "the wind grid's top must clear the scene's highest point by two voxels (raise voxel_layers or voxel_size_m)",
        });
    }
    Ok(())
}

/// Wall-clock seconds of each stage of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StageTimes {
    /// Voxelisation.
    pub voxelise_s: f64,
    /// The 3D wind iterations (Chapter 3).
    pub wind_s: f64,
    /// The wind at `z_r` and its terrain modification (Section 5.4).
    pub terrain_wind_s: f64,
    /// The precipitation map (Chapter 4).
    pub precipitation_s: f64,
    /// The transport steps (Section 5.5).
    pub transport_s: f64,
}

/// The wind solver's residual divergence.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WindReport {
    /// The last Stable Fluids iteration (projected to `wind.tolerance`).
    pub last_iteration: IterationReport,
    /// The mean wind, projected to `wind.mean_tolerance`: the wind every later stage uses.
    pub mean: IterationReport,
}

/// Everything a run produces.
#[derive(Debug, Clone)]
pub struct RunOutputs {
    /// The transport grid.
    pub geometry: GridGeometry,
    /// Final snow cover.
    pub state: SnowState,
    /// Mass budget of the whole run, kg.
    pub budget: MassBudget,
    /// Wind at `z_r` after the terrain modification (east, north), m s⁻¹.
    pub wind_u: Vec<f32>,
    /// North component.
    pub wind_v: Vec<f32>,
    /// Precipitation ratio map on the transport grid (mean 1).
    pub precipitation_ratio: Vec<f32>,
    /// Saltation flux of the last step, kg m⁻¹ s⁻¹.
    pub q_salt: Vec<f32>,
    /// Suspension flux of the last step, kg m⁻¹ s⁻¹.
    pub q_susp: Vec<f32>,
    /// Sublimation rate of the last step, kg m⁻² s⁻¹.
    pub q_subl: Vec<f32>,
    /// The last wind iteration's report.
    pub wind_report: WindReport,
    /// The voxel grid of the wind.
    pub voxels: VoxelGrid,
    /// The mean 3D wind (Section 6.3).
    pub mean_wind: Velocity,
    /// What became of the flakes of the precipitation map (zeros with
    /// `uniform_precipitation`).
    pub flakes: FlakeSummary,
    /// Whether the snowfall fell back to uniform because fewer flakes landed than there
    /// are voxel columns (a map that noisy carries no information: too few flakes for the
    /// grid, or a wind that blows most of them across the domain).
    pub precipitation_fallback: bool,
    /// Transport steps taken.
    pub steps: usize,
    /// Wall-clock time of each stage.
    pub times: StageTimes,
}

/// Resamples a map on the wind's column grid onto the transport grid.
fn to_transport(src: GridGeometry, data: Vec<f32>, dst: &GridGeometry) -> Vec<f32> {
    let n = src.len();
    match Grid::new(src, data, NodataMask::all_valid()) {
        Ok(g) => g.resample(dst.clone()).into_data(),
        Err(_) => vec![0.0; n],
    }
}

/// Runs the whole pipeline over `heights` on `geometry`.
pub fn run(
    scenario: &Scenario,
    geometry: &GridGeometry,
    heights: &[f32],
) -> Result<RunOutputs, TransportError> {
    scenario.validate()?;
    check_len("height", heights, geometry)?;
    // The wind grid's size, before anything is allocated (a typed error naming nx, ny, nz).
    VoxelGrid::dimensions(geometry, scenario.voxel_size_m, scenario.voxel_layers)?;
    let timeline = Timeline(scenario.weather.clone());
    let lowest = heights.iter().fold(f32::INFINITY, |m, &z| m.min(z));
    let highest = heights.iter().fold(f32::NEG_INFINITY, |m, &z| m.max(z));
    check_voxel_height(scenario, f64::from(lowest), f64::from(highest))?;
    let mut times = StageTimes::default();
    let clock = std::time::Instant::now();
    let voxels = VoxelGrid::from_heights(
        geometry,
        heights,
        scenario.voxel_size_m,
        scenario.voxel_layers,
        f64::from(lowest) - scenario.voxel_size_m,
    )?;
    let column_geometry = geometry
        .resampled(voxels.nx, voxels.ny)
        .map_err(|e| TransportError::Scene(e.to_string()))?;
    times.voxelise_s = clock.elapsed().as_secs_f64();
    let clock = std::time::Instant::now();
    let mut solver = WindSolver::new(voxels.clone(), scenario.wind.clone())?;
    let mut wind_report = None;
    for _ in 0..scenario.wind_iterations {
        wind_report = Some(solver.iterate());
    }
    let last_iteration = wind_report.expect("at least one iteration (validated)");
    let wind_report = WindReport {
        last_iteration,
        mean: solver.project_mean(),
    };
    times.wind_s = clock.elapsed().as_secs_f64();
    let clock = std::time::Instant::now();
    let z_r = scenario.transport.reference_height_m;
    let (cu, cv) = solver.wind_at_height(z_r);
    let u0 = to_transport(column_geometry.clone(), cu, geometry);
    let v0 = to_transport(column_geometry.clone(), cv, geometry);
    let (wind_u, wind_v) = modify_wind(&scenario.transport, geometry, heights, &u0, &v0)?;
    times.terrain_wind_s = clock.elapsed().as_secs_f64();
    let clock = std::time::Instant::now();
    let (precipitation_ratio, flakes, precipitation_fallback) = if scenario.uniform_precipitation {
        (vec![1.0; geometry.len()], FlakeSummary::default(), false)
    } else {
        let map = precipitation_map(
            &voxels,
            &solver.mean_velocity(),
            scenario.wind.inflow(),
            &scenario.flakes,
        )?;
        if map.flakes.landed < (map.width * map.height) as u64 {
            (vec![1.0; geometry.len()], map.flakes, true)
        } else {
            let mut ratio = to_transport(column_geometry, map.ratio, geometry);
            let mean = ratio.iter().map(|&r| f64::from(r)).sum::<f64>() / ratio.len() as f64;
            if mean > 0.0 {
                ratio
                    .iter_mut()
                    .for_each(|r| *r = (f64::from(*r) / mean) as f32);
            }
            (ratio, map.flakes, false)
        }
    };
    times.precipitation_s = clock.elapsed().as_secs_f64();
    let clock = std::time::Instant::now();
    let mut state = SnowState::uniform(
        geometry,
        scenario.initial_depth_m as f32,
        scenario.initial_density as f32,
    );
    let mut scratch = StepScratch::default();
    let mut budget = MassBudget::default();
    let total_s = scenario.duration_h * 3600.0;
    let mut t = 0.0;
    let mut steps = 0;
    let mut scaled: Option<(f64, Vec<f32>, Vec<f32>)> = None;
    while t < total_s - 1e-9 {
        let weather = timeline.at(t / 3600.0);
        let next_change = timeline
            .next_start_after((t + 1e-9) / 3600.0)
            .map_or(f64::INFINITY, |h| h * 3600.0);
        let dt = scenario
            .transport
            .time_step_s
            .min(total_s - t)
            .min(next_change - t);
        let factor = if scenario.wind.speed_m_s > 0.0 {
            weather.wind_speed_m_s / scenario.wind.speed_m_s
        } else {
            0.0
        };
        if scaled.as_ref().is_none_or(|s| s.0 != factor) {
            let f = factor as f32;
            scaled = Some((
                factor,
                wind_u.iter().map(|u| u * f).collect(),
                wind_v.iter().map(|v| v * f).collect(),
            ));
        }
        let (_, su, sv) = scaled.as_ref().expect("just set");
        let scene = SceneMaps {
            geometry,
            wind_u: su,
            wind_v: sv,
            precipitation_ratio: Some(&precipitation_ratio),
        };
        let b = step(
            &scenario.transport,
            weather,
            &scene,
            &mut state,
            &mut scratch,
            dt,
        )?;
        if steps == 0 {
            budget = b;
        } else {
            budget.accumulate(&b);
        }
        t += dt;
        steps += 1;
    }
    times.transport_s = clock.elapsed().as_secs_f64();
    Ok(RunOutputs {
        geometry: geometry.clone(),
        state,
        budget,
        wind_u,
        wind_v,
        precipitation_ratio,
        q_salt: scratch.q_salt.clone(),
        q_susp: scratch.q_susp.clone(),
        q_subl: scratch.q_subl.clone(),
        wind_report,
        mean_wind: solver.mean_velocity(),
        voxels,
        flakes,
        precipitation_fallback,
        steps,
        times,
    })
}

#[cfg(test)]
mod tests;
