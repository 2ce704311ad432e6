//! The readers on every mesh of ../shared/data/meshes: counts, checks and axes.

mod common;
use common::mesh_path;
use snowscape_mesh::{MeshReport, Scene, SourceFrame, UpAxis, read_scene};

fn read(name: &str) -> (Scene, MeshReport) {
    read_scene(&mesh_path(name), &SourceFrame::default()).unwrap()
}

/// What the readers find in each shared mesh. Vertex and face counts agree with the files'
/// headers and the data README (bunny 1839 v / 3674 f, teapots 1260 v / 2048 f); the other
/// counts were measured by these readers when written and pin their behaviour (the bunny, ant
/// and nut are closed, the airplane is open; the closed-mesh counts would catch a weld bug).
#[derive(Debug, PartialEq)]
struct Expected {
    objects: usize,
    vertices: usize,
    faces: usize,
    triangles: usize,
    degenerate: usize,
    open_edges: usize,
    non_manifold_edges: usize,
    pieces: usize,
}

const fn expect(c: [usize; 8]) -> Expected {
    Expected {
        objects: c[0],
        vertices: c[1],
        faces: c[2],
        triangles: c[3],
        degenerate: c[4],
        open_edges: c[5],
        non_manifold_edges: c[6],
        pieces: c[7],
    }
}

/// objects, vertices, faces, triangles kept, degenerate, open edges, non-manifold, pieces
const EXPECTED: [(&str, Expected); 6] = [
    ("bunny_npm.obj", expect([1, 1839, 3674, 3674, 0, 0, 0, 1])),
    ("ant.ply", expect([1, 486, 912, 912, 0, 0, 0, 15])),
    ("nut.ply", expect([1, 523, 1046, 1046, 0, 0, 0, 1])),
    ("airplane.ply", expect([1, 1335, 2452, 2452, 0, 223, 1, 7])),
    (
        "teapot_assimp.obj",
        expect([1, 1260, 2048, 1984, 64, 128, 0, 6]),
    ),
    ("spider.obj", expect([19, 974, 1368, 1312, 56, 96, 0, 19])),
];

#[test]
fn every_shared_mesh_reads_with_the_expected_counts() {
    for (file, expected) in EXPECTED {
        let (scene, r) = read(file);
        let got = Expected {
            objects: r.objects.len(),
            vertices: r.vertices(),
            faces: r.faces(),
            triangles: r.triangles(),
            degenerate: r.degenerate_dropped(),
            open_edges: r.open_edges(),
            non_manifold_edges: r.non_manifold_edges(),
            pieces: r.components(),
        };
        assert_eq!(got, expected, "{file}");
        assert_eq!(scene.triangle_count(), expected.triangles, "{file}");
        assert_eq!(scene.objects.len(), expected.objects);
        for o in &scene.objects {
            let areas = o.triangle_areas();
            assert!(areas.iter().all(|&a| a > 0.0), "{file}: degenerate kept");
            for n in o.triangle_normals() {
                let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                assert!((l - 1.0).abs() < 1e-4, "{file}: normal {n:?}");
            }
        }
    }
}

#[test]
fn bunny_is_closed_and_its_area_and_volume_are_plausible() {
    let (scene, r) = read("bunny_npm.obj");
    assert!(r.objects[0].is_closed_manifold());
    let o = &scene.objects[0];
    // Outward normals of a closed mesh enclose a positive volume (divergence theorem).
    let volume: f64 = (0..o.triangles.len())
        .map(|t| {
            let [a, b, c] = o.corners(t).map(|p| p.map(f64::from));
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum();
    let b = o.bounds().unwrap();
    let box_volume = b.size().iter().map(|&s| s as f64).product::<f64>();
    assert!(
        volume > 0.2 * box_volume && volume < box_volume,
        "{volume} vs {box_volume}"
    );
    assert!(o.surface_area() > 0.0);
}

#[test]
fn up_axis_and_scale_set_the_scene_frame() {
    let path = mesh_path("bunny_npm.obj");
    let (y_up, _) = read_scene(&path, &SourceFrame::default()).unwrap();
    let cm = SourceFrame::new(UpAxis::Z, 0.01).unwrap();
    let (z_up, _) = read_scene(&path, &cm).unwrap();
    let (by, bz) = (y_up.bounds().unwrap(), z_up.bounds().unwrap());
    // The npm bunny is y-up (about 9.7 tall, 7.5 deep): read as y-up it stands on z = 0...
    assert!(
        by.size()[2] > 9.0 && by.size()[1] < 8.0 && by.min[2].abs() < 0.01,
        "{by:?}"
    );
    // ...read as z-up in centimetres its file y becomes scene y, a hundredth of the size.
    assert!(
        (bz.size()[1] - 0.01 * by.size()[2]).abs() < 1e-5,
        "{bz:?} {by:?}"
    );
    assert_eq!(z_up.frame, cm);
    assert_eq!(y_up.objects[0].triangles, z_up.objects[0].triangles);
}

#[test]
fn spider_objects_keep_their_names_and_normals() {
    let (scene, r) = read("spider.obj");
    assert!(scene.object("Bein1Li").is_some() && scene.object("Kopf").is_some());
    assert!(scene.objects.iter().all(|o| o.normals.is_some()));
    assert!(r.objects.iter().all(|o| !o.normals_dropped));
    // Scene normals are unit length and rotated with the frame.
    let o = scene.object("HLeib01").unwrap();
    for n in o.normals.as_ref().unwrap() {
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        assert!((l - 1.0).abs() < 1e-3, "{n:?}");
    }
}
