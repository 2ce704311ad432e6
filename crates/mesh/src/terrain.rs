//! Scenes on a DEM: a [`Grid`] as a triangle-mesh object, and objects standing on it.
//!
//! Frame: scene x and y are metres east and north of the grid's south-west corner (cell
//! `(col, row)` has its centre at `x = (col + 0.5)·dx`, `y = (height - row - 0.5)·dy`), z is
//! the grid's value (altitude, metres). Nodata cells give no triangle.

use crate::MeshError;
use crate::scene::{Scene, SceneObject};
use snowscape_terrain::{Grid, GridGeometry};

/// Scene (x, y) of the centre of cell `(col, row)`.
pub fn cell_centre_xy(grid: &Grid, col: usize, row: usize) -> [f64; 2] {
    let g = grid.geometry();
    [
        (col as f64 + 0.5) * g.cell_size_x(),
        (g.height() as f64 - row as f64 - 0.5) * g.cell_size_y(),
    ]
}

/// The terrain height at scene `(x, y)`, bilinear between cell centres; `None` outside the
/// grid or over nodata.
pub fn height_at(grid: &Grid, x: f64, y: f64) -> Option<f32> {
    let g = grid.geometry();
    let col = x / g.cell_size_x() - 0.5;
    let row = g.height() as f64 - y / g.cell_size_y() - 0.5;
    grid.sample(col, row)
}

/// The grid as one object: a vertex per cell centre and the triangles of the project's one
/// triangulation of a height field ([`snowscape_terrain::lattice`]: two per square of four
/// cells, a triangle kept where its three cells are valid; counter-clockwise seen from above,
/// so normals point up). An error for a grid of more than 2^32 cells.
pub fn grid_object(grid: &Grid, name: &str) -> Result<SceneObject, MeshError> {
    let g = grid.geometry();
    let (w, h) = (g.width(), g.height());
    let mask = grid.mask();
    let data = grid.data();
    let mut positions = Vec::with_capacity(w * h);
    for row in 0..h {
        for col in 0..w {
            let [x, y] = cell_centre_xy(grid, col, row);
            positions.push([x as f32, y as f32, data[g.index(col, row)]]);
        }
    }
    let usable: Vec<bool> = (0..w * h)
        .map(|i| mask.is_valid(i) && data[i].is_finite())
        .collect();
    let triangles = snowscape_terrain::lattice::lattice_triangles(&usable, w, h)?;
    Ok(SceneObject {
        frame: Default::default(),
        name: name.to_string(),
        positions,
        normals: None,
        triangles,
        uvs: None,
    })
}

/// Moves `object` so that the centre of its horizontal bounds is at scene `(x, y)` and its
/// lowest point is at the lowest terrain height under its vertices: the object stands on the
/// terrain and never floats over a slope (its uphill side sinks in). Returns that ground height.
pub fn place_on_grid(
    object: &mut SceneObject,
    grid: &Grid,
    x: f64,
    y: f64,
) -> Result<f32, MeshError> {
    let bounds = object.bounds().ok_or_else(|| MeshError::InvalidOption {
        name: "object to place",
        value: object.name.clone(),
        expected: "an object with triangles",
    })?;
    let c = bounds.centre();
    let dx = (x - c[0] as f64) as f32;
    let dy = (y - c[1] as f64) as f32;
    let mut ground = f32::INFINITY;
    for p in &object.positions {
        let (px, py) = ((p[0] + dx) as f64, (p[1] + dy) as f64);
        let h = height_at(grid, px, py).ok_or_else(|| MeshError::InvalidOption {
            name: "placement",
            value: format!(
                "{} at ({x}, {y}): vertex at ({px:.2}, {py:.2})",
                object.name
            ),
            expected: "every vertex over a valid cell of the terrain",
        })?;
        ground = ground.min(h);
    }
    object.translate([dx, dy, ground - bounds.min[2]]);
    Ok(ground)
}

/// Scene metres `(x, y)` (from the grid's south-west corner, z up; [`grid_object`]'s frame) of
/// map position `(mx, my)` (CRS units), or `None` outside the grid: where `--at X,Y` puts a
/// mesh on a DEM.
pub fn map_to_scene(geometry: &GridGeometry, mx: f64, my: f64) -> Option<(f64, f64)> {
    // `map_to_cell` counts cell centres as whole numbers.
    let (col, row) = geometry.map_to_cell(mx, my)?;
    Some((
        (col + 0.5) * geometry.cell_size_x(),
        (geometry.height() as f64 - row - 0.5) * geometry.cell_size_y(),
    ))
}

/// Places a whole scene on the terrain as one piece, with [`place_on_grid`]'s rule applied to
/// all its objects together (the centre of their joint horizontal bounds at scene `(x, y)`,
/// their lowest point on the lowest ground under any of their vertices): every object moves by
/// the same offset, so a model made of several objects keeps its layout. Used by `snowscape
/// cover` and `snowscape transport` alike. Returns the ground height and the offset applied.
pub fn place_scene_on_grid(
    scene: &mut Scene,
    grid: &Grid,
    x: f64,
    y: f64,
) -> Result<(f32, [f32; 3]), MeshError> {
    // The vertices of every triangle as one object (one point-triangle per vertex, so the
    // bounds count only vertices that triangles use).
    let mut all = SceneObject {
        frame: Default::default(),
        name: scene
            .objects
            .first()
            .map_or("mesh".into(), |o| o.name.clone()),
        ..Default::default()
    };
    for o in &scene.objects {
        all.positions.extend(
            o.triangles
                .iter()
                .flatten()
                .map(|&i| o.positions[i as usize]),
        );
    }
    all.triangles = (0..all.positions.len() as u32).map(|i| [i, i, i]).collect();
    let before = all.bounds().ok_or_else(|| MeshError::InvalidOption {
        name: "scene to place",
        value: all.name.clone(),
        expected: "a scene with triangles",
    })?;
    let ground = place_on_grid(&mut all, grid, x, y)?;
    let after = all.bounds().unwrap_or(before);
    let d = [0, 1, 2].map(|k| after.min[k] - before.min[k]);
    for o in &mut scene.objects {
        o.translate(d);
    }
    Ok((ground, d))
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_terrain::{GridGeometry, NodataMask};

    fn slope() -> Grid {
        // 5 x 4 cells of 2 m, rising 1 m per column eastwards.
        Grid::from_fn(GridGeometry::new(5, 4, 2.0, 2.0).unwrap(), |c, _| c as f32)
    }

    #[test]
    fn a_scene_is_placed_as_one_piece_and_at_map_positions() {
        let g = slope();
        let cube = |x0: f32| SceneObject {
            frame: Default::default(),
            name: "c".into(),
            positions: vec![[x0, 0.0, 0.0], [x0 + 1.0, 0.0, 0.0], [x0, 1.0, 1.0]],
            normals: None,
            triangles: vec![[0, 1, 2]],
            uvs: None,
        };
        let mut scene = Scene {
            objects: vec![cube(0.0), cube(3.0)],
            frame: Default::default(),
        };
        let gap = scene.objects[1].positions[0][0] - scene.objects[0].positions[0][0];
        let (ground, d) = place_scene_on_grid(&mut scene, &g, 5.0, 4.0).unwrap();
        // Joint bounds x 0..4 centred at 5: both moved by 3, the layout kept.
        assert_eq!(d[0], 3.0);
        assert_eq!(
            scene.objects[1].positions[0][0] - scene.objects[0].positions[0][0],
            gap
        );
        // The lowest point on the lowest ground under the vertices (x = 3 m: column 1, 1 m).
        assert_eq!(ground, height_at(&g, 3.0, 3.5).unwrap().min(ground));
        let lowest = scene
            .objects
            .iter()
            .flat_map(|o| o.positions.iter())
            .map(|p| p[2])
            .fold(f32::INFINITY, f32::min);
        assert_eq!(lowest, ground);
        // A map position 5.2 m east and 2.9 m south of the north-west corner: 5.2 m east and
        // 8 - 2.9 m north of the south-west one.
        let t = g.geometry().transform();
        let (mx, my) = (t.origin_x + 5.2, t.origin_y - 2.9);
        let (sx, sy) = map_to_scene(g.geometry(), mx, my).unwrap();
        assert!(
            (sx - 5.2).abs() < 1e-9 && (sy - 5.1).abs() < 1e-9,
            "{sx} {sy}"
        );
        assert_eq!(map_to_scene(g.geometry(), t.origin_x - 1.0, my), None);
    }

    #[test]
    fn grid_mesh_faces_up_and_skips_nodata() {
        let g = slope();
        let o = grid_object(&g, "terrain").unwrap();
        assert_eq!(o.triangles.len(), 2 * 4 * 3);
        for t in 0..o.triangles.len() {
            assert!(o.triangle_normal(t)[2] > 0.0);
        }
        let b = o.bounds().unwrap();
        assert_eq!((b.min, b.max), ([1.0, 1.0, 0.0], [9.0, 7.0, 4.0]));
        // Cell (0, 0) is the north-west one: highest y.
        assert_eq!(o.positions[0], [1.0, 7.0, 0.0]);
        let mut invalid = vec![false; 20];
        invalid[6] = true; // (1, 1): four squares touch it
        let holed = Grid::new(
            g.geometry().clone(),
            g.data().to_vec(),
            NodataMask::from_invalid(invalid),
        )
        .unwrap();
        // Of the four squares around the hole, those that have it at their north-west or
        // south-east corner keep the triangle opposite it (the diagonal runs south-west to
        // north-east).
        let o = grid_object(&holed, "t").unwrap();
        assert_eq!(o.triangles.len(), 2 * (12 - 4) + 2);
        assert!(o.triangles.iter().all(|t| !t.contains(&6)));
    }

    #[test]
    fn placed_objects_stand_on_the_lowest_ground_under_them() {
        let g = slope();
        let mut cube = SceneObject {
            frame: Default::default(),
            name: "box".into(),
            positions: vec![[0., 0., 5.], [2., 0., 5.], [2., 2., 5.], [0., 2., 6.]],
            normals: None,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            uvs: None,
        };
        let ground = place_on_grid(&mut cube, &g, 5.0, 4.0).unwrap();
        // Footprint x in [4, 6]: cell-centre coordinate 1.5..2.5, terrain 1.5..2.5.
        assert!((ground - 1.5).abs() < 1e-5, "{ground}");
        let b = cube.bounds().unwrap();
        assert!((b.min[2] - 1.5).abs() < 1e-5 && (b.centre()[0] - 5.0).abs() < 1e-5);
        // Off the grid: a typed error, the object untouched.
        let before = cube.clone();
        assert!(place_on_grid(&mut cube, &g, 100.0, 4.0).is_err());
        assert_eq!(cube, before);
    }
}
