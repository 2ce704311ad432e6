//! The typed reports of an avalanche job: `report.json` of `snowscape avalanche`
//! ([`AvalancheReport`], its keys a contract) and the flat summary the Python package returns
//! ([`AvalancheSummary`]).

use crate::report::InputSummary;
use serde::Serialize;
use snowscape_avalanche::comparison::PathComparison;
use snowscape_avalanche::validation::ThicknessConvention;
use snowscape_avalanche::{AvalancheParams, MapMatch, RestOutcome, RunOptions, RunSummary};

/// `snowscape avalanche`'s report.json.
#[derive(Debug, Clone, Serialize)]
pub struct AvalancheReport {
    pub snowscape_version: &'static str,
    /// `avalanche`.
    pub command: &'static str,
    /// The DEM the flow ran on.
    pub input: InputSummary,
    /// Where the release came from.
    pub release: ReleaseReport,
    /// Released cells.
    pub release_cells: usize,
    /// Their area, m².
    pub release_area_m2: f64,
    /// What the release's reader warned of (a CRS, cells outside the DEM...).
    pub release_warnings: Vec<String>,
    /// The friction rasters (`null` without either).
    pub friction_maps: Option<FrictionReport>,
    pub parameters: RunParameters,
    /// Recorded only: the flow is deterministic.
    pub seed: u64,
    /// Worker threads (results do not depend on them).
    pub threads: usize,
    /// m³.
    pub released_volume_m3: f64,
    /// m³.
    pub entrained_volume_m3: f64,
    /// Loose snow laid outside the release, m.
    pub snow_cover_m: f64,
    /// The snow at rest on the grid at the end, m³ (the summary's `final_volume_m3`).
    pub deposited_volume_m3: f64,
    /// m³ that left the grid.
    pub border_outflow_m3: f64,
    /// Relative volume closure.
    pub volume_closure_rel: f64,
    /// m.
    pub runout_length_m: f64,
    /// Degrees.
    pub alpha_angle_deg: f64,
    /// Degrees.
    pub travel_angle_deg: f64,
    /// The run's figures.
    pub summary: RunSummary,
    /// Simulated seconds.
    pub simulated_s: f64,
    /// Wall seconds of the flow and its frames.
    pub wall_s: f64,
    pub timings: Timings,
    /// The comparison with a reference run (`--compare`).
    pub comparison: Option<PathComparison>,
    /// Files written, relative to the output folder.
    pub outputs: Vec<String>,
    /// Files an earlier job wrote into the folder that this one did not write again (removed).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub removed_stale: Vec<String>,
}

/// Where the release came from.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ReleaseReport {
    /// A rupture point, map coordinates.
    Point { point: [f64; 2] },
    /// A shapefile or a raster mask.
    File { file: String },
    /// A mask of the DEM's cells given in memory.
    Mask { mask: bool },
}

/// The flow and run parameters and the release thickness.
#[derive(Debug, Clone, Serialize)]
pub struct RunParameters {
    pub flow: AvalancheParams,
    pub run: RunOptions,
    /// As given (`None`: the shapefile's field, else 1 m).
    pub thickness_m: Option<f64>,
    /// `slope-normal` or `vertical`.
    pub thickness_measured: Option<String>,
}

/// The command line's name of a thickness convention.
pub fn convention_name(c: ThicknessConvention) -> &'static str {
    match c {
        ThicknessConvention::Vertical => "vertical",
        ThicknessConvention::SlopeNormal => "slope-normal",
    }
}

/// Wall seconds of the flow and of the frames.
#[derive(Debug, Clone, Serialize)]
pub struct Timings {
    pub flow_s: f64,
    pub frames_s: f64,
}

/// A friction raster as report.json tells it: its file and how it was matched.
#[derive(Debug, Clone, Serialize)]
pub struct FrictionRasterReport {
    pub file: Option<String>,
    pub matched: MapMatch,
}

/// The friction rasters of a run (`null` in report.json without either).
#[derive(Debug, Clone, Serialize)]
pub struct FrictionReport {
    pub mu: Option<FrictionRasterReport>,
    pub xi: Option<FrictionRasterReport>,
}

/// One flat summary of a run (the Python package's `summary`): the run's figures
/// ([`RunSummary`]) with the volumes of the [`RestOutcome`], the release and the flow
/// parameters.
#[derive(Debug, Clone, Serialize)]
pub struct AvalancheSummary {
    #[serde(flatten)]
    pub run: RunSummary,
    /// m³ (the outcome's, over the summary's of the same name).
    pub released_volume_m3: f64,
    /// m³.
    pub entrained_volume_m3: f64,
    /// m³ laid down on the terrain.
    pub deposited_volume_m3: f64,
    pub release_cells: usize,
    pub release_area_m2: f64,
    pub parameters: AvalancheParams,
}

impl AvalancheSummary {
    /// The summary of `rest` for a release of `release_cells` cells over `release_area_m2`.
    pub fn new(
        rest: &RestOutcome,
        release_cells: usize,
        release_area_m2: f64,
        parameters: &AvalancheParams,
    ) -> Self {
        Self {
            run: rest.summary.clone(),
            released_volume_m3: rest.released_m3,
            entrained_volume_m3: rest.entrained_m3,
            deposited_volume_m3: rest.deposited_m3,
            release_cells,
            release_area_m2,
            parameters: parameters.clone(),
        }
    }

    /// As one JSON object: the figures' keys that the volumes repeat hold the outcome's values.
    pub fn to_json(&self) -> Result<serde_json::Value, serde_json::Error> {
        serde_json::to_value(self)
    }
}
