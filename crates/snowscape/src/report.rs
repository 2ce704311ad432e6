//! `report.json`: what a run read, how it was set up, how long each stage took, and whether
//! the snow mass budget closes.

use serde::Serialize;
use snowscape_terrain::{Grid, GridGeometry};
use std::collections::BTreeMap;

/// Summary of the terrain a job ran on.
#[derive(Debug, Clone, Serialize)]
pub struct InputSummary {
    /// File path, or `procedural alpine terrain` for the embedded default.
    pub source: String,
    pub width: usize,
    pub height: usize,
    /// Metres.
    pub cell_size_x: f64,
    /// Metres.
    pub cell_size_y: f64,
    /// `EPSG:nnnn`, a WKT excerpt, or null.
    pub crs: Option<String>,
    /// Map coordinates of the north-west corner, CRS units.
    pub origin: [f64; 2],
    /// Latitude of the grid centre, degrees north, when the georeferencing tells it.
    pub latitude_deg: Option<f64>,
    /// Lowest and highest valid altitude, metres.
    pub altitude_range: Option<[f32; 2]>,
    /// Share of cells that are nodata, 0..1.
    pub nodata_fraction: f64,
}

impl InputSummary {
    /// Summarises a terrain grid.
    pub fn of(source: &str, grid: &Grid) -> Self {
        let g: &GridGeometry = grid.geometry();
        let t = g.transform();
        Self {
            source: source.to_string(),
            width: g.width(),
            height: g.height(),
            cell_size_x: g.cell_size_x(),
            cell_size_y: g.cell_size_y(),
            crs: g.crs().map(|c| c.to_string()),
            origin: [t.origin_x, t.origin_y],
            latitude_deg: g.latitude_deg(),
            altitude_range: grid.value_range().map(|(a, b)| [a, b]),
            nodata_fraction: grid.mask().count_nodata() as f64 / g.len() as f64,
        }
    }
}

/// The snow budget of a run, in cubic metres of snow: what came in and went out must equal
/// the change of the store, up to `closure_error` (relative to the larger of the flows).
#[derive(Debug, Clone, Serialize, Default)]
pub struct MassBudget {
    /// m³ of snow added, by source (e.g. `snowfall`).
    pub inputs: BTreeMap<String, f64>,
    /// m³ of snow removed, by sink (e.g. `melt`, `border_outflow`).
    pub outputs: BTreeMap<String, f64>,
    /// m³ of snow on the terrain at the start.
    pub initial_store: f64,
    /// m³ of snow on the terrain at the end.
    pub final_store: f64,
    /// |initial + inputs - outputs - final| / max(initial + inputs, final, 1 m³).
    pub closure_error: f64,
}

impl MassBudget {
    /// Computes `closure_error` from the other fields.
    pub fn close(mut self) -> Self {
        let input: f64 = self.inputs.values().sum();
        let output: f64 = self.outputs.values().sum();
        let residual = self.initial_store + input - output - self.final_store;
        let scale = (self.initial_store + input).max(self.final_store).max(1.0);
        self.closure_error = residual.abs() / scale;
        self
    }
}

/// The whole `report.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    pub snowscape_version: &'static str,
    pub command: String,
    pub input: InputSummary,
    /// Every parameter of the run, as the scenario file would spell it.
    pub parameters: serde_json::Value,
    pub seed: u64,
    /// Worker threads the run used (results do not depend on it).
    pub threads: usize,
    /// Seconds per stage, in the order the stages ran.
    pub timings: serde_json::Map<String, serde_json::Value>,
    /// Events of each kind the scheduler drew (season runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub event_counts: Option<serde_json::Map<String, serde_json::Value>>,
    /// Every avalanche of the season, in order (season runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub avalanches: Option<Vec<snowscape_season::avalanches::AvalancheRecord>>,
    /// What the season's skiers did (season runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skiers: Option<snowscape_season::skiing::SkiStats>,
    pub mass_budget: MassBudget,
    /// The pack's liquid water, m³ of water (season runs with the enhanced melt).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub water_budget: Option<snowscape_season::winter::WaterBudget>,
    /// The season per 200 m altitude band: precipitation (mm of water), rain share and peak
    /// SWE (mm of water) (season runs; [`snowscape_season::bands`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bands: Option<Vec<snowscape_season::bands::BandSummary>>,
    /// Things the user should know (e.g. an assumed latitude), also logged.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Files written, relative to the output folder.
    pub outputs: Vec<String>,
    /// Files an earlier run wrote into this folder that this run did not write again; they
    /// were removed (they described another run).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub removed_stale: Vec<String>,
}

/// Turns ordered stage timings into a JSON object (keys keep their order).
pub fn timings_object(timings: &[(String, f64)]) -> serde_json::Map<String, serde_json::Value> {
    let mut m = serde_json::Map::new();
    let total: f64 = timings.iter().map(|(_, s)| s).sum();
    for (name, s) in timings {
        m.insert(name.clone(), serde_json::json!(round_us(*s)));
    }
    m.insert("total".into(), serde_json::json!(round_us(total)));
    m
}

fn round_us(s: f64) -> f64 {
    (s * 1e6).round() / 1e6
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budget_closure_is_relative() {
        let mut b = MassBudget::default();
        b.inputs.insert("snowfall".into(), 100.0);
        b.outputs.insert("melt".into(), 30.0);
        b.initial_store = 10.0;
        b.final_store = 80.0;
        assert_eq!(b.clone().close().closure_error, 0.0);
        b.final_store = 79.0;
        assert!((b.close().closure_error - 1.0 / 110.0).abs() < 1e-12);
    }
}
