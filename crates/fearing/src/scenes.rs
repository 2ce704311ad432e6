//! Scenes built in code (z up, metres) for tests, benchmarks and the examples: an open plane,
//! a roof over the ground, a box, a basin (Fig. 13's fountain reduced to one bowl), and the
//! roof-and-basin scene of the issue. Boxes are closed, counter-clockwise seen from outside.

use snowscape_mesh::{Scene, SceneObject, SourceFrame, UpAxis};

/// A frame for scenes made here: z up, metres.
pub fn frame() -> SourceFrame {
    SourceFrame {
        up: UpAxis::Z,
        metres_per_unit: 1.0,
    }
}

/// A horizontal square `size` metres wide centred on the origin at height `z`.
pub fn plane(name: &str, size: f32, z: f32) -> SceneObject {
    let h = 0.5 * size;
    SceneObject {
        frame: Default::default(),
        name: name.into(),
        positions: vec![[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]],
        normals: None,
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        uvs: None,
    }
}

/// A closed box from `lo` to `hi`.
pub fn cuboid(name: &str, lo: [f32; 3], hi: [f32; 3]) -> SceneObject {
    let p = |i: usize| {
        [
            if i & 1 == 0 { lo[0] } else { hi[0] },
            if i & 2 == 0 { lo[1] } else { hi[1] },
            if i & 4 == 0 { lo[2] } else { hi[2] },
        ]
    };
    let positions = (0..8).map(p).collect();
    // Faces as quads (outward, counter-clockwise seen from outside).
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let triangles = quads
        .iter()
        .flat_map(|q: &[u32; 4]| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    SceneObject {
        frame: Default::default(),
        name: name.into(),
        positions,
        normals: None,
        triangles,
        uvs: None,
    }
}

/// An open plane of `size` metres.
pub fn open_plane(size: f32) -> Scene {
    Scene {
        objects: vec![plane("ground", size, 0.0)],
        frame: frame(),
    }
}

/// Ground of `ground` metres with a flat roof `roof` metres wide, `thickness` thick, its
/// underside `height` metres up (floating: no posts, so only the roof shades the ground).
pub fn roof(ground: f32, roof: f32, height: f32, thickness: f32) -> Scene {
    let h = 0.5 * roof;
    Scene {
        objects: vec![
            plane("ground", ground, 0.0),
            cuboid("roof", [-h, -h, height], [h, h, height + thickness]),
        ],
        frame: frame(),
    }
}

/// A 2 m wide face leaning 70° (steeper than snow's 50° angle of repose) over open ground
/// `ground` metres wide: its snow slides off, but it sees the sky (a dusting).
pub fn steep_face(ground: f32) -> Scene {
    let face = SceneObject {
        frame: Default::default(),
        name: "face".into(),
        positions: vec![
            [0.0, -1.0, 0.0],
            [0.0, 1.0, 0.0],
            [-1.0, 1.0, 2.75],
            [-1.0, -1.0, 2.75],
        ],
        normals: None,
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        uvs: None,
    };
    Scene {
        objects: vec![plane("ground", ground, 0.0), face],
        frame: frame(),
    }
}

/// A box `size` wide and `height` tall standing on ground `ground` metres wide.
pub fn box_on_ground(ground: f32, size: f32, height: f32) -> Scene {
    let h = 0.5 * size;
    Scene {
        objects: vec![
            plane("ground", ground, 0.0),
            cuboid("box", [-h, -h, 0.0], [h, h, height]),
        ],
        frame: frame(),
    }
}

/// A square basin centred at (`cx`, `cy`): inner width `inner`, walls `wall` thick and
/// `height` tall, floor `floor` thick (its top is the basin's bottom); returned as objects.
pub fn basin_objects(
    cx: f32,
    cy: f32,
    inner: f32,
    wall: f32,
    height: f32,
    floor: f32,
) -> Vec<SceneObject> {
    let (h, o) = (0.5 * inner, 0.5 * inner + wall);
    let at = |lo: [f32; 3], hi: [f32; 3]| {
        (
            [lo[0] + cx, lo[1] + cy, lo[2]],
            [hi[0] + cx, hi[1] + cy, hi[2]],
        )
    };
    let parts = [
        ("basin_floor", at([-h, -h, 0.0], [h, h, floor])),
        ("basin_wall_s", at([-o, -o, 0.0], [o, -h, height])),
        ("basin_wall_n", at([-o, h, 0.0], [o, o, height])),
        ("basin_wall_w", at([-o, -h, 0.0], [-h, h, height])),
        ("basin_wall_e", at([h, -h, 0.0], [o, h, height])),
    ];
    parts
        .iter()
        .map(|(n, (lo, hi))| cuboid(n, *lo, *hi))
        .collect()
}

/// A basin on the ground (ground `ground` metres wide).
pub fn basin(ground: f32, inner: f32, wall: f32, height: f32, floor: f32) -> Scene {
    let mut objects = vec![plane("ground", ground, 0.0)];
    objects.extend(basin_objects(0.0, 0.0, inner, wall, height, floor));
    Scene {
        objects,
        frame: frame(),
    }
}

/// The scene: a 12 m ground with a 3 m roof 2 m up on one side and a 3 m basin
/// (walls 0.6 m, 0.2 m thick) on the other.
pub fn roof_and_basin() -> Scene {
    let mut objects = vec![
        plane("ground", 12.0, 0.0),
        cuboid("roof", [-4.5, -1.5, 2.0], [-1.5, 1.5, 2.15]),
    ];
    objects.extend(basin_objects(3.0, 0.0, 3.0, 0.2, 0.6, 0.1));
    Scene {
        objects,
        frame: frame(),
    }
}
