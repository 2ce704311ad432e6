//! The report of a cover (Section 4 of the issue: sites, flakes shot, time, mass in and out of
//! the scene), written as `report.json`.

use crate::accumulation::AccumulationReport;
use crate::params::FearingParams;
use crate::stability::StabilityReport;
use serde::Serialize;

/// One accumulation pass and the stability phase after it.
#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct PassReport {
    pub accumulation: AccumulationReport,
    pub smoothing_iterations: u32,
    pub stability: StabilityReport,
}

/// The mass budget, m³ of snow: what fell from the sky over the scene, what no surface caught,
/// what left the scene during stability, and what lies on the sites at the end.
#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct MassBudget {
    pub sky_m3: f64,
    pub allocated_m3: f64,
    pub unclaimed_m3: f64,
    pub left_scene_m3: f64,
    pub final_m3: f64,
    /// allocated - left - final: zero up to rounding when the budget closes.
    pub closure_error_m3: f64,
}

/// Seconds per stage.
#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct Timings {
    pub launch_sites_s: f64,
    pub accumulation_s: f64,
    pub stability_s: f64,
    pub surface_s: f64,
    pub total_s: f64,
}

/// Everything a cover reports.
#[derive(Debug, Clone, Default, Serialize, PartialEq)]
pub struct FearingReport {
    pub method: &'static str,
    pub triangles: usize,
    pub upward_triangles: usize,
    pub site_spacing_m: f64,
    pub sites_initial: usize,
    pub sites_final: usize,
    pub edge_groups: usize,
    pub flakes_shot: u64,
    pub flakes_to_sky: u64,
    pub flakes_per_s: f64,
    pub rays: u64,
    pub passes: Vec<PassReport>,
    pub mass: MassBudget,
    pub timings: Timings,
    pub surface_vertices: usize,
    pub surface_triangles: usize,
    pub max_depth_m: f64,
    /// Mean depth over the upward-facing area, m.
    pub mean_depth_m: f64,
    pub threads: usize,
    pub params: Option<FearingParams>,
}
