//! The orthographic top view of a scene: the highest surface over every cell of a grid.
//!
//! Jubert 2018, Section 6.3 (Fig. 6.3) voxelises a scene by filling every cell below the
//! highest occupied one, and its transport runs on the 2D height map of that top view
//! (Section 5.3, Fig. 5.1). Here one ray per cell centre is cast straight down from above
//! the scene through the BVH; the first hit is the highest surface. A cell no triangle
//! covers keeps its floor (the DEM under a placed object, or the ground level of a mesh
//! given alone).
//!
//! Frame: as [`crate::terrain`], scene `x` and `y` are metres east and north of the grid's
//! south-west corner, so cell `(col, row)` has its centre at `x = (col + 0.5)·dx`,
//! `y = (height − row − 0.5)·dy`.

use crate::MeshError;
use crate::raycast::{Ray, SceneBvh};
use crate::scene::Scene;
use snowscape_terrain::GridGeometry;

/// Most cells of a top-view grid (4096²): a finer `cell_m` is refused before any allocation.
pub const MAX_TOP_VIEW_CELLS: usize = 1 << 24;

/// The highest surface of `bvh`'s scene over each cell of `geometry`, or `floor[i]` where
/// that is higher or nothing is hit. `top` is an altitude above every triangle.
pub fn highest_surface(
    bvh: &SceneBvh,
    geometry: &GridGeometry,
    top: f32,
    floor: &[f32],
) -> Result<Vec<f32>, MeshError> {
    if floor.len() != geometry.len() {
        return Err(MeshError::InvalidOption {
            name: "top-view floor",
            value: format!(
                "{} values for a {}x{} grid",
                floor.len(),
                geometry.width(),
                geometry.height()
            ),
            expected: "one value per grid cell",
        });
    }
    let (w, h) = (geometry.width(), geometry.height());
    let (dx, dy) = (geometry.cell_size_x(), geometry.cell_size_y());
    let rays: Vec<Ray> = (0..w * h)
        .map(|i| {
            let (col, row) = (i % w, i / w);
            let x = (col as f64 + 0.5) * dx;
            let y = (h as f64 - row as f64 - 0.5) * dy;
            Ray::new([x as f32, y as f32, top], [0.0, 0.0, -1.0])
        })
        .collect();
    let hits = bvh.first_hits(&rays);
    Ok(hits
        .iter()
        .zip(floor)
        .map(|(hit, &f)| match hit {
            Some(hit) => (top - hit.t).max(f),
            None => f,
        })
        .collect())
}

/// A grid of `cell_m` cells around `scene`'s horizontal bounds with `margin_m` of open
/// ground on every side; moves the scene so the grid's south-west corner is the origin.
/// Returns the geometry and the scene's lowest altitude (the ground level).
pub fn frame_scene(
    scene: &mut Scene,
    cell_m: f64,
    margin_m: f64,
) -> Result<(GridGeometry, f32), MeshError> {
    if !(cell_m.is_finite() && cell_m > 0.0) {
        return Err(MeshError::InvalidOption {
            name: "resolution",
            value: cell_m.to_string(),
            expected: "a positive number of metres",
        });
    }
    if !(margin_m.is_finite() && margin_m >= 0.0) {
        return Err(MeshError::InvalidOption {
            name: "margin",
            value: margin_m.to_string(),
            expected: "a non-negative number of metres",
        });
    }
    let b = scene.bounds().ok_or_else(|| MeshError::InvalidOption {
        name: "scene",
        value: "no triangle".into(),
        expected: "at least one valid triangle",
    })?;
    let size = b.size();
    let ex = f64::from(size[0]) + 2.0 * margin_m;
    let ey = f64::from(size[1]) + 2.0 * margin_m;
    let w = (ex / cell_m).ceil().max(2.0);
    let h = (ey / cell_m).ceil().max(2.0);
    if w * h > MAX_TOP_VIEW_CELLS as f64 {
        return Err(MeshError::InvalidOption {
            name: "resolution",
            value: format!("{cell_m} m gives {w}x{h} cells over {ex:.1} x {ey:.1} m"),
            expected: "at most 4096² cells: a coarser resolution",
        });
    }
    let (w, h) = (w as usize, h as usize);
    // Centre the scene in the grid.
    let dx = ((w as f64 * cell_m - f64::from(size[0])) / 2.0 - f64::from(b.min[0])) as f32;
    let dy = ((h as f64 * cell_m - f64::from(size[1])) / 2.0 - f64::from(b.min[1])) as f32;
    for o in &mut scene.objects {
        o.translate([dx, dy, 0.0]);
    }
    let geometry = GridGeometry::square(w, h, cell_m).map_err(|e| MeshError::InvalidOption {
        name: "resolution",
        value: format!("{cell_m} m ({e})"),
        expected: "a valid grid",
    })?;
    Ok((geometry, b.min[2]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SceneObject;

    fn quad(z: f32, x0: f32, x1: f32) -> SceneObject {
        SceneObject {
            frame: Default::default(),
            name: format!("quad{z}"),
            positions: vec![[x0, 0.0, z], [x1, 0.0, z], [x1, 4.0, z], [x0, 4.0, z]],
            normals: None,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            uvs: None,
        }
    }

    #[test]
    fn the_highest_surface_wins_and_the_floor_fills_the_rest() {
        let mut scene = Scene {
            objects: vec![quad(1.0, 0.0, 4.0), quad(3.0, 0.0, 2.0)],
            ..Default::default()
        };
        let (g, ground) = frame_scene(&mut scene, 1.0, 2.0).unwrap();
        assert_eq!((g.width(), g.height(), ground), (8, 8, 1.0));
        let bvh = SceneBvh::new(&scene);
        let z = highest_surface(&bvh, &g, 10.0, &vec![0.5; g.len()]).unwrap();
        // Row 4 (y = 3.5 m) crosses the quads' middle: the margin, the high quad over the
        // low one's west half, the low quad, the margin.
        let row: Vec<f32> = (0..8).map(|c| z[g.index(c, 4)]).collect();
        assert_eq!(row, [0.5, 0.5, 3.0, 3.0, 1.0, 1.0, 0.5, 0.5]);
        assert!(highest_surface(&bvh, &g, 10.0, &[0.0; 3]).is_err());
    }

    #[test]
    fn bad_resolutions_are_refused() {
        let mut scene = Scene {
            objects: vec![quad(1.0, 0.0, 4.0)],
            ..Default::default()
        };
        assert!(frame_scene(&mut scene, -1.0, 0.0).is_err());
        assert!(frame_scene(&mut scene, 1e-6, 0.0).is_err());
        assert!(frame_scene(&mut scene, 1.0, f64::NAN).is_err());
        assert!(frame_scene(&mut Scene::default(), 1.0, 0.0).is_err());
    }
}
