//! Scenes shared by the benchmarks (need ../shared/data/meshes beside the checkout).

use snowscape_mesh::terrain::{grid_object, place_on_grid};
use snowscape_mesh::{Scene, SourceFrame, UpAxis, read_scene};
use snowscape_terrain::{Grid, GridGeometry};
use std::path::PathBuf;

/// A shared mesh, y-up, `metres_per_unit` metres per file unit.
pub fn mesh(name: &str, metres_per_unit: f64) -> Scene {
    let p = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/meshes"
    ))
    .join(name);
    assert!(
        p.is_file(),
        "{} is missing (needs ../shared/data)",
        p.display()
    );
    let frame = SourceFrame::new(UpAxis::Y, metres_per_unit).unwrap();
    read_scene(&p, &frame).unwrap().0
}

/// Bunnies (about 1 m tall) and teapot pairs in a grid on a gently sloping ground of
/// 2 x 72 x 72 triangles: about 100k triangles.
pub fn big_scene() -> Scene {
    let bunny = mesh("bunny_npm.obj", 0.1);
    let teapots = mesh("teapot_assimp.obj", 0.01);
    let g = GridGeometry::new(73, 73, 1.0, 1.0).unwrap();
    let ground = Grid::from_fn(g, |c, r| 0.02 * c as f32 + 0.01 * r as f32);
    let mut scene = Scene {
        objects: vec![grid_object(&ground, "ground").expect("ground mesh")],
        frame: SourceFrame::default(),
    };
    let mut k = 0;
    while scene.triangle_count() < 100_000 {
        let (i, j) = (k % 5, k / 5);
        let source = if k % 3 == 2 { &teapots } else { &bunny };
        let mut o = source.objects[0].clone();
        o.name = format!("{}_{k}", o.name);
        let (x, y) = (8.0 + 14.0 * i as f64, 8.0 + 6.5 * j as f64);
        place_on_grid(&mut o, &ground, x, y).unwrap();
        scene.objects.push(o);
        k += 1;
    }
    scene
}
