//! Scenes shared by the integration tests.
#![allow(dead_code)]

use snowscape_mesh::{Scene, SceneObject, SourceFrame};
use std::path::PathBuf;

/// A closed axis-aligned box with outward-facing triangles.
pub fn cube(name: &str, min: [f32; 3], max: [f32; 3]) -> SceneObject {
    let p = |i: usize| {
        [
            if i & 1 == 0 { min[0] } else { max[0] },
            if i & 2 == 0 { min[1] } else { max[1] },
            if i & 4 == 0 { min[2] } else { max[2] },
        ]
    };
    let quads = [
        [0, 2, 3, 1], // bottom, facing down
        [4, 5, 7, 6], // top, facing up
        [0, 1, 5, 4], // south
        [2, 6, 7, 3], // north
        [0, 4, 6, 2], // west
        [1, 3, 7, 5], // east
    ];
    SceneObject {
        frame: Default::default(),
        name: name.into(),
        positions: (0..8).map(p).collect(),
        normals: None,
        triangles: quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect(),
        uvs: None,
    }
}

/// A horizontal quad facing up.
pub fn quad(name: &str, [x0, y0, x1, y1]: [f32; 4], z: f32) -> SceneObject {
    SceneObject {
        frame: Default::default(),
        name: name.into(),
        positions: vec![[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]],
        normals: None,
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        uvs: None,
    }
}

pub fn scene(objects: Vec<SceneObject>) -> Scene {
    Scene {
        objects,
        frame: SourceFrame::default(),
    }
}

/// A mesh of the shared real-data folder; fails the test when it is missing (these tests
/// exist to check the method on real files).
pub fn mesh_path(name: &str) -> PathBuf {
    let p = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/meshes"
    ))
    .join(name);
    assert!(
        p.is_file(),
        "{} is missing: these tests need ../shared/data beside the checkout",
        p.display()
    );
    p
}
