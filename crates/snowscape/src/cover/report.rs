//! The reports of a mesh cover: what was read (the mesh, and the DEM it stands on) and, for the
//! diffusion cover, the whole `report.json`. The cover job builds them for every front end, so
//! a cover reports the same keys whichever front end ran it.

use crate::report::{InputSummary, timings_object};
use serde::Serialize;
use snowscape_festenberg::{GrowthParams, GrowthReport, Resolved, SnowCover};
use snowscape_mesh::{Bounds, MeshReport, Scene};
use std::path::Path;

/// The mesh a cover read and the DEM it stands on: a cover report's `input`.
#[derive(Debug, Clone, Serialize)]
pub struct MeshInputSummary {
    /// The mesh file.
    pub mesh: String,
    /// Its up axis (`y` or `z`).
    pub up: String,
    /// Metres per mesh unit.
    pub metres_per_unit: f64,
    pub objects: usize,
    pub vertices: usize,
    pub triangles: usize,
    /// Degenerate triangles dropped on reading.
    pub degenerate_dropped: usize,
    /// Triangles repeating an earlier one (same corners, same order) dropped on reading.
    pub duplicates_dropped: usize,
    pub open_edges: usize,
    pub non_manifold_edges: usize,
    /// The scene's box in scene metres (z up), terrain included when on a DEM.
    pub bounds_m: Option<Bounds>,
    /// The DEM the mesh stands on (`null` without one).
    pub dem: Option<DemPlacement>,
    /// The `--parameters` file (`null` without one).
    pub parameters_file: Option<String>,
}

impl MeshInputSummary {
    /// The summary of `mesh` (read with `up` and `metres_per_unit` into `scene`, with `report`).
    pub fn new(
        mesh: &Path,
        up: &str,
        metres_per_unit: f64,
        report: &MeshReport,
        scene: &Scene,
    ) -> Self {
        Self {
            mesh: mesh.display().to_string(),
            up: up.to_string(),
            metres_per_unit,
            objects: report.objects.len(),
            vertices: report.vertices(),
            triangles: report.triangles(),
            degenerate_dropped: report.degenerate_dropped(),
            duplicates_dropped: report.duplicates_dropped(),
            open_edges: report.open_edges(),
            non_manifold_edges: report.non_manifold_edges(),
            bounds_m: scene.bounds(),
            dem: None,
            parameters_file: None,
        }
    }
}

/// Where a mesh stands on a DEM.
#[derive(Debug, Clone, Serialize)]
pub struct DemPlacement {
    /// The DEM.
    pub terrain: InputSummary,
    /// The mesh's anchor in scene metres (the DEM's lower-left corner at 0, 0).
    pub at_scene_m: [f64; 2],
    /// The ground height under the anchor, m.
    pub ground_m: f32,
}

/// The diffusion cover's paper, as reports cite it.
pub const DIFFUSION_PAPER: &str =
    "von Festenberg & Gumhold 2011, Diffusion-Based Snow Cover Generation, Section 5";

/// Fearing's paper, as reports cite it.
pub const FEARING_PAPER: &str = "Fearing 2000, Computer Modelling of Fallen Snow";

/// The height-span map's sites.
#[derive(Debug, Clone, Serialize)]
pub struct SiteCounts {
    /// Columns along x and y.
    pub columns: [usize; 2],
    pub ground_sites: usize,
    pub bridge_sites: usize,
    /// Covered surfaces dropped from the map.
    pub covered_dropped: usize,
    /// Depth layers (most sites in one column).
    pub layers: usize,
    /// Sites holding snow.
    pub snowy_sites: usize,
}

/// The diffusion kernel's work.
#[derive(Debug, Clone, Serialize)]
pub struct KernelWork {
    pub columns_per_kernel: usize,
    pub members_visited: u64,
    pub seconds: f64,
    pub sites_per_s: f64,
}

/// The snow mesh.
#[derive(Debug, Clone, Serialize)]
pub struct SnowMeshCounts {
    /// Snow volume on the sites, m³.
    pub volume_m3: f64,
    pub max_height_m: f32,
    pub vertices: usize,
    pub triangles: usize,
    pub quads: usize,
    pub corner_triangles: usize,
    pub boundary_loops: usize,
    pub uv_propagated_vertices: usize,
    pub uv_seam_copies: usize,
}

/// A growth animation: its parameters and what the run did.
#[derive(Debug, Clone, Serialize)]
pub struct GrowthSummary {
    pub parameters: GrowthParams,
    pub run: GrowthReport,
}

/// The diffusion cover's `report.json`.
#[derive(Debug, Clone, Serialize)]
pub struct DiffusionCoverReport {
    pub snowscape_version: &'static str,
    pub command: &'static str,
    pub method: &'static str,
    pub paper: &'static str,
    pub input: MeshInputSummary,
    /// Every length fixed, m.
    pub parameters: Resolved,
    pub sites: SiteCounts,
    pub kernel: KernelWork,
    pub snow: SnowMeshCounts,
    /// The growth animation (`null` without one).
    pub growth: Option<GrowthSummary>,
    /// Worker threads (results do not depend on it).
    pub threads: usize,
    /// Seconds per stage, in the order the stages ran, and their total.
    pub timings_s: serde_json::Map<String, serde_json::Value>,
    pub wall_s: f64,
    /// Files written, relative to the output folder.
    pub outputs: Vec<String>,
    /// Earlier outputs of the folder this run removed (left out when none).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub removed_stale: Vec<String>,
}

impl DiffusionCoverReport {
    /// The report of cover `c` of the scene `input` describes; `timings` the stages in order
    /// (the cover's own among them), `outputs` the files written.
    pub fn new(
        input: MeshInputSummary,
        c: &SnowCover,
        growth: Option<GrowthSummary>,
        timings: &[(String, f64)],
        wall_s: f64,
        outputs: Vec<String>,
    ) -> Self {
        let s = &c.stats;
        Self {
            snowscape_version: env!("CARGO_PKG_VERSION"),
            command: "cover",
            method: "diffusion",
            paper: DIFFUSION_PAPER,
            input,
            parameters: c.resolved,
            sites: SiteCounts {
                columns: s.columns,
                ground_sites: s.ground_sites,
                bridge_sites: s.bridge_sites,
                covered_dropped: s.covered_dropped,
                layers: s.layers,
                snowy_sites: s.snowy_sites,
            },
            kernel: KernelWork {
                columns_per_kernel: s.kernel_columns,
                members_visited: s.members_visited,
                seconds: s.timing("kernel"),
                sites_per_s: s.kernel_sites_per_s(),
            },
            snow: SnowMeshCounts {
                volume_m3: s.volume_m3,
                max_height_m: s.max_height_m,
                vertices: s.vertices,
                triangles: s.triangles,
                quads: s.quads,
                corner_triangles: s.corner_triangles,
                boundary_loops: s.boundary_loops,
                uv_propagated_vertices: s.uv_propagated,
                uv_seam_copies: s.seam_copies,
            },
            growth,
            threads: rayon::current_num_threads(),
            timings_s: timings_object(timings),
            wall_s,
            outputs,
            removed_stale: Vec::new(),
        }
    }
}

/// What `snowscape cover --method fearing` adds to Fearing's report as its `input`: the mesh
/// summary, the time spent reading and in all, and the turntable written.
#[derive(Debug, Clone, Serialize)]
pub struct FearingInputSummary {
    #[serde(flatten)]
    pub mesh: MeshInputSummary,
    pub read_s: f64,
    pub wall_s: f64,
    /// `turntable.gif` and its frames (`null` without one).
    pub turntable: Option<Turntable>,
}

/// A turntable animation written beside a cover.
#[derive(Debug, Clone, Serialize)]
pub struct Turntable {
    pub file: &'static str,
    pub frames: usize,
}
