//! A scene on a real DEM: the terrain as a mesh object, a bunny standing on it, rays and the
//! height-span map over both. Needs ../shared/data (the tiny Reynolds Mountain East DEM).

mod common;
use snowscape_io::{ReadOptions, read_dem};
use snowscape_mesh::terrain::{grid_object, height_at, place_on_grid};
use snowscape_mesh::{
    HeightSpanMap, HeightSpanOptions, Scene, SceneBvh, SourceFrame, UpAxis, read_scene,
};
use std::path::PathBuf;

#[test]
fn bunny_stands_on_the_rme_dem() {
    let dem = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/dem/rme_idaho_50m/dem.asc"
    ));
    assert!(
        dem.is_file(),
        "{} is missing (needs ../shared/data)",
        dem.display()
    );
    let grid = read_dem(&dem, &ReadOptions::default()).unwrap();
    // The bunny scaled to about 10 m tall.
    let frame = SourceFrame::new(UpAxis::Y, 1.0).unwrap();
    let (mut bunny, _) = read_scene(&common::mesh_path("bunny_npm.obj"), &frame).unwrap();
    let mut object = bunny.objects.remove(0);
    let (x, y) = (400.0, 450.0);
    let ground = place_on_grid(&mut object, &grid, x, y).unwrap();
    let b = object.bounds().unwrap();
    assert!((b.min[2] - ground).abs() < 1e-3);
    let centre = b.centre();
    assert!((centre[0] as f64 - x).abs() < 1e-3 && (centre[1] as f64 - y).abs() < 1e-3);
    // It stands on the lowest ground under it: no vertex is below the terrain by more than
    // the relief under its footprint, and the terrain under its centre is at most that high.
    let under = height_at(&grid, x, y).unwrap();
    assert!(under >= ground && under - ground < 10.0, "{under} {ground}");

    let terrain = grid_object(&grid, "terrain").unwrap();
    let scene = Scene {
        objects: vec![terrain, object],
        frame,
    };
    let bvh = SceneBvh::new(&scene);
    // Straight down onto the bunny's top from above: it is hit before the terrain.
    let hit = bvh
        .first_hit(&snowscape_mesh::Ray::new(
            [centre[0], centre[1], b.max[2] + 50.0],
            [0.0, 0.0, -1.0],
        ))
        .unwrap();
    assert_eq!(hit.object, 1);
    // Away from the bunny, the sky is open over the terrain.
    let [cx, cy] = snowscape_mesh::terrain::cell_centre_xy(&grid, 3, 3);
    let z = height_at(&grid, cx, cy).unwrap();
    assert!(!bvh.anything_above([cx as f32, cy as f32, z], 0.01));
    // Height-span map at 2 m: terrain sites everywhere, the bunny's over its footprint.
    let opts = HeightSpanOptions {
        cell_size_m: 2.0,
        ..Default::default()
    };
    let map = HeightSpanMap::build(&scene, &opts).unwrap();
    let on_bunny = map.sites().iter().filter(|s| s.object == 1).count();
    let on_terrain = map.sites().iter().filter(|s| s.object == 0).count();
    assert!(on_bunny > 5 && on_terrain > 100, "{on_bunny} {on_terrain}");
    assert!(map.sites().iter().all(|s| s.capacity > 0.0));
}
