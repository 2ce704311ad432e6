//! The scene of a transport run as a height map: a DEM (its nodata cells filled with the lowest
//! valid altitude for the wind, kept nodata in the outputs), a mesh alone (its top view on flat
//! ground at its lowest point, with open ground around it), a mesh standing on a DEM (placed as
//! one piece, as the cover places it), or the scenario's own scene; and its summary, the
//! report's `input`.

use super::{TransportJob, TransportJobError, TransportMesh, dem_heights};
use crate::dem_source::DemSource;
use serde::Serialize;
use snowscape_mesh::terrain::{map_to_scene, place_scene_on_grid};
use snowscape_mesh::top_view::{frame_scene, highest_surface};
use snowscape_mesh::{SceneBvh, SourceFrame, UpAxis, read_scene};
use snowscape_terrain::{Grid, GridGeometry, NodataMask};
use snowscape_transport::scenario::{Scenario, SceneSpec};

/// The scene's height map, its nodata cells and what it was made of.
#[derive(Debug, Clone)]
pub struct SceneInput {
    pub geometry: GridGeometry,
    /// Surface heights, m, row-major (nodata cells filled).
    pub heights: Vec<f32>,
    /// Cells outside the input (a DEM's nodata), written as nodata.
    pub mask: NodataMask,
    pub summary: SceneSummary,
}

/// What a run's scene was made of (`report.json`'s `input`).
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum SceneSummary {
    /// A DEM.
    Dem(DemSummary),
    /// A mesh, alone or standing on a DEM.
    Mesh(MeshSummary),
    /// The scenario's own scene.
    Scenario { scene: SceneSpec },
}

/// A DEM as the scene.
#[derive(Debug, Clone, Serialize)]
pub struct DemSummary {
    /// The DEM file.
    pub dem: String,
    /// Nodata cells filled with the lowest valid altitude for the wind.
    pub nodata_cells_filled: usize,
}

/// A mesh as the scene: its file, its check, where it stands.
#[derive(Debug, Clone, Serialize)]
pub struct MeshSummary {
    pub mesh: String,
    pub triangles: usize,
    pub degenerate_dropped: usize,
    pub open_edges: usize,
    /// Cells whose top surface is the mesh, not the ground.
    pub cells_above_ground: usize,
    /// A mesh alone: the top view's cell size and the open ground around it, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub resolution_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub margin_m: Option<f64>,
    /// A mesh on a DEM: the DEM and where the mesh stands (scene metres).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dem: Option<DemSummary>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub placed_at_m: Option<[f64; 2]>,
}

/// The job's scene: its DEM and mesh, or the scenario's own scene (the scenario then takes
/// the input as its scene).
pub(super) fn build(
    job: &TransportJob,
    scenario: &mut Scenario,
) -> Result<SceneInput, TransportJobError> {
    let dem = job.dem.as_ref().map(dem_scene).transpose()?;
    let input = match (&job.mesh, dem) {
        (Some(m), dem) => Some(mesh_scene(m, dem)?),
        (None, Some(dem)) => Some(dem),
        (None, None) => None,
    };
    if let Some(input) = input {
        if !matches!(scenario.scene, SceneSpec::Input) {
            tracing::warn!("the scenario's own [scene] is replaced by the input");
            scenario.scene = SceneSpec::Input;
        }
        return Ok(input);
    }
    match scenario
        .build_scene()
        .map_err(TransportJobError::Transport)?
    {
        Some((geometry, heights)) => Ok(SceneInput {
            geometry,
            heights,
            mask: NodataMask::all_valid(),
            summary: SceneSummary::Scenario {
                scene: scenario.scene.clone(),
            },
        }),
        None => Err(TransportJobError::NoScene),
    }
}

/// A DEM with its nodata cells filled by the lowest valid altitude (the wind needs a surface
/// everywhere); the mask keeps them nodata in the outputs.
fn dem_scene(source: &DemSource) -> Result<SceneInput, TransportJobError> {
    let name = source.name();
    let grid = source.read().map_err(TransportJobError::Dem)?;
    let (heights, filled) = dem_heights(&grid, &name)?;
    Ok(SceneInput {
        geometry: grid.geometry().clone(),
        heights,
        mask: grid.mask().clone(),
        summary: SceneSummary::Dem(DemSummary {
            dem: name,
            nodata_cells_filled: filled,
        }),
    })
}

/// A mesh alone (on flat ground at its lowest point, with open ground around it) or standing
/// on the DEM at its anchor (default: the DEM's centre), as its top view.
fn mesh_scene(m: &TransportMesh, dem: Option<SceneInput>) -> Result<SceneInput, TransportJobError> {
    let up: UpAxis = m.up.parse().map_err(|source| TransportJobError::Up {
        up: m.up.clone(),
        source: Box::new(source),
    })?;
    let frame = SourceFrame::new(up, m.scale).map_err(TransportJobError::Scale)?;
    let (mut scene, report) = read_scene(&m.path, &frame).map_err(TransportJobError::Mesh)?;
    let mut summary = MeshSummary {
        mesh: m.path.display().to_string(),
        triangles: report.triangles(),
        degenerate_dropped: report.degenerate_dropped(),
        open_edges: report.open_edges(),
        cells_above_ground: 0,
        resolution_m: None,
        margin_m: None,
        dem: None,
        placed_at_m: None,
    };
    let Some(dem) = dem else {
        let b = scene
            .bounds()
            .ok_or_else(|| TransportJobError::NoTriangles(m.path.display().to_string()))?;
        let size = b.size();
        let longest = f64::from(size[0].max(size[1]));
        let cell = m.resolution_m.unwrap_or(longest / 100.0);
        let margin = m.margin_m.unwrap_or(longest);
        let (geometry, ground) =
            frame_scene(&mut scene, cell, margin).map_err(TransportJobError::Mesh)?;
        let bvh = SceneBvh::new(&scene);
        let top = b.max[2] + 1.0;
        let heights = highest_surface(&bvh, &geometry, top, &vec![ground; geometry.len()])
            .map_err(TransportJobError::Mesh)?;
        summary.cells_above_ground = heights.iter().filter(|&&z| z > ground + 1e-3).count();
        summary.resolution_m = Some(cell);
        summary.margin_m = Some(margin);
        return Ok(SceneInput {
            geometry,
            heights,
            mask: NodataMask::all_valid(),
            summary: SceneSummary::Mesh(summary),
        });
    };
    let grid = Grid::new(
        dem.geometry.clone(),
        dem.heights.clone(),
        NodataMask::all_valid(),
    )?;
    let (ex, ey) = dem.geometry.extent_m();
    let (x, y) = match m.at {
        Some(at) => map_to_scene(&dem.geometry, at[0], at[1])
            .ok_or(TransportJobError::AtOutsideDem { at })?,
        None => (ex / 2.0, ey / 2.0),
    };
    // The scene as one piece, as the cover places it.
    place_scene_on_grid(&mut scene, &grid, x, y).map_err(TransportJobError::Mesh)?;
    let bvh = SceneBvh::new(&scene);
    let top = scene.bounds().map_or(0.0, |b| b.max[2]) + 1.0;
    let heights =
        highest_surface(&bvh, &dem.geometry, top, &dem.heights).map_err(TransportJobError::Mesh)?;
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
