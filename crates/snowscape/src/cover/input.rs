//! The front part of a cover, shared by both methods: the mesh read into scene metres (z up)
//! and, on a DEM, placed on it as one piece with the terrain around it added to the scene
//! (a quarter of the object's size on each side), and the summary of what was read.

use super::job::{CoverDem, CoverJob, CoverJobError};
use super::report::{DemPlacement, MeshInputSummary};
use crate::report::InputSummary;
use snowscape_mesh::terrain::{grid_object, map_to_scene, place_scene_on_grid};
use snowscape_mesh::{Scene, SceneObject, SourceFrame, UpAxis, read_scene};
use std::time::Instant;

/// What the front part read: the scene (mesh, and terrain when on a DEM) and its summary.
pub(super) struct CoverInput {
    pub scene: Scene,
    /// What was read: the mesh, the DEM it stands on, the parameter file.
    pub summary: MeshInputSummary,
    /// The region to cover, scene metres (`None`: the scene's bounds).
    pub extent_m: Option<[f64; 4]>,
    pub read_s: f64,
}

/// The mesh in scene metres (z up), standing on the DEM if the job has one.
pub(super) fn read(job: &CoverJob) -> Result<CoverInput, CoverJobError> {
    let t0 = Instant::now();
    let up: UpAxis = job.up.parse().map_err(|source| CoverJobError::Up {
        up: job.up.clone(),
        source: Box::new(source),
    })?;
    let frame = SourceFrame::new(up, job.scale).map_err(CoverJobError::Mesh)?;
    let (mut scene, mesh_report) = read_scene(&job.mesh, &frame).map_err(CoverJobError::Mesh)?;
    let (mut extent_m, mut dem) = (None, None);
    if let Some(d) = &job.dem {
        let (e, placement) = stand_on_dem(job, d, &mut scene)?;
        extent_m = Some(e);
        dem = Some(placement);
    }
    let mut summary = MeshInputSummary::new(&job.mesh, &job.up, job.scale, &mesh_report, &scene);
    summary.dem = dem;
    summary.parameters_file = job
        .parameters_file
        .as_ref()
        .map(|p| p.display().to_string());
    Ok(CoverInput {
        scene,
        summary,
        extent_m,
        read_s: t0.elapsed().as_secs_f64(),
    })
}

/// Places `scene` on the DEM (every object moved by the same offset) and adds the terrain
/// around it; returns the region to cover and the placement.
fn stand_on_dem(
    job: &CoverJob,
    d: &CoverDem,
    scene: &mut Scene,
) -> Result<([f64; 4], DemPlacement), CoverJobError> {
    let name = d.dem.name();
    let grid = d.dem.read().map_err(CoverJobError::Dem)?;
    let g = grid.geometry();
    let (x, y) = match d.at {
        None => (0.5 * g.extent_m().0, 0.5 * g.extent_m().1),
        Some(at) => map_to_scene(g, at[0], at[1]).ok_or_else(|| CoverJobError::AtOutsideDem {
            at,
            dem: name.clone(),
        })?,
    };
    let (ground, _) =
        place_scene_on_grid(scene, &grid, x, y).map_err(|source| CoverJobError::Placement {
            mesh: job.mesh.clone(),
            dem: name.clone(),
            source: Box::new(source),
        })?;
    let after = scene.bounds().ok_or(CoverJobError::NoTriangles)?;
    // Cover the object and the ground around it: a quarter of its size on each side.
    let margin = 0.25 * after.size()[0].max(after.size()[1]) as f64;
    let e = [
        after.min[0] as f64 - margin,
        after.min[1] as f64 - margin,
        after.max[0] as f64 + margin,
        after.max[1] as f64 + margin,
    ];
    let terrain = crop(
        grid_object(&grid, "terrain").map_err(CoverJobError::Mesh)?,
        e,
        margin,
    );
    if terrain.triangles.is_empty() {
        return Err(CoverJobError::NoDemCells(name));
    }
    scene.objects.push(terrain);
    let placement = DemPlacement {
        terrain: InputSummary::of(&name, &grid),
        at_scene_m: [x, y],
        ground_m: ground,
    };
    Ok((e, placement))
}

/// The triangles of `o` within `margin` of the extent `e`.
fn crop(mut o: SceneObject, e: [f64; 4], margin: f64) -> SceneObject {
    let inside = |p: &[f32; 3]| {
        (p[0] as f64) >= e[0] - margin
            && (p[0] as f64) <= e[2] + margin
            && (p[1] as f64) >= e[1] - margin
            && (p[1] as f64) <= e[3] + margin
    };
    let pos = &o.positions;
    o.triangles
        .retain(|t| t.iter().any(|&i| inside(&pos[i as usize])));
    o
}
