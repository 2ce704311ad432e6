//! The height-span map (von Festenberg & Gumhold 2011, Section 5) on a table scene with known
//! capacities, and on the bunny against the BVH's downward rays.

mod common;
use snowscape_mesh::{
    HeightSpanMap, HeightSpanOptions, MeshError, Ray, Scene, SceneBvh, SceneObject, SourceFrame,
    read_scene,
};

/// A horizontal quad over [x0, x1] x [y0, y1] at height z, facing up (two triangles sharing the
/// diagonal from (x0, y0) to (x1, y1)).
fn quad(name: &str, [x0, y0, x1, y1]: [f32; 4], z: f32) -> SceneObject {
    SceneObject {
        frame: Default::default(),
        name: name.into(),
        positions: vec![[x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]],
        normals: None,
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        uvs: None,
    }
}

/// A closed axis-aligned box with outward-facing triangles.
fn cube(name: &str, min: [f32; 3], max: [f32; 3]) -> SceneObject {
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

fn table_scene() -> Scene {
    Scene {
        objects: vec![
            quad("floor", [0.0, 0.0, 10.0, 10.0], 0.0),
            quad("table top", [3.0, 3.0, 7.0, 7.0], 1.0),
            cube("box on the floor", [1.0, 1.0, 0.0], [2.0, 2.0, 0.5]),
            cube("floating box", [8.0, 8.0, 2.0], [9.0, 9.0, 3.0]),
        ],
        frame: SourceFrame::default(),
    }
}

fn opts(cell: f64) -> HeightSpanOptions {
    HeightSpanOptions {
        cell_size_m: cell,
        ..Default::default()
    }
}

/// The column whose centre is (x, y).
fn column_at(map: &HeightSpanMap, x: f64, y: f64) -> (usize, usize) {
    let col = ((x - map.origin[0]) / map.cell_size) as usize;
    let row = map.height - 1 - ((y - map.origin[1]) / map.cell_size) as usize;
    let c = map.column_centre(col, row);
    assert!((c[0] - x).abs() < 1e-9 && (c[1] - y).abs() < 1e-9, "{c:?}");
    (col, row)
}

#[test]
fn table_capacities() {
    let map = HeightSpanMap::build(&table_scene(), &opts(1.0)).unwrap();
    assert_eq!((map.width, map.height), (10, 10));
    let sites = |x, y| {
        let (c, r) = column_at(&map, x, y);
        map.column(c, r)
            .iter()
            .map(|s| (s.z, s.capacity, s.object))
            .collect::<Vec<_>>()
    };
    // Under the table top: the floor has the table's height of free space; the top, the sky.
    // (5.5, 5.5) lies on the diagonal both quads are split along: one crossing each.
    assert_eq!(sites(5.5, 5.5), [(0.0, 1.0, 0), (1.0, f32::INFINITY, 1)]);
    assert_eq!(sites(3.5, 6.5), [(0.0, 1.0, 0), (1.0, f32::INFINITY, 1)]);
    // Open floor.
    assert_eq!(sites(0.5, 9.5), [(0.0, f32::INFINITY, 0)]);
    assert_eq!(sites(9.5, 0.5), [(0.0, f32::INFINITY, 0)]);
    // A box standing on the floor covers it: only its top is a site.
    assert_eq!(sites(1.5, 1.5), [(0.5, f32::INFINITY, 2)]);
    // Under a floating box: the floor up to its bottom (not a site: it faces down), its top.
    assert_eq!(sites(8.5, 8.5), [(0.0, 2.0, 0), (3.0, f32::INFINITY, 3)]);
    assert_eq!(map.layer_count(), 2);
    // 100 floor columns, one covered by the standing box; 16 table, 1 + 1 box tops.
    assert_eq!(map.site_count(), 99 + 16 + 1 + 1);
    assert_eq!(map.covered_dropped, 1);
    for s in map.sites() {
        assert!(s.capacity > 0.0, "{s:?}");
    }
}

#[test]
fn finer_grids_and_offsets_keep_capacities_positive_and_sorted() {
    let scene = table_scene();
    for cell in [0.37, 0.25, 0.1] {
        let map = HeightSpanMap::build(&scene, &opts(cell)).unwrap();
        for row in 0..map.height {
            for col in 0..map.width {
                let column = map.column(col, row);
                for w in column.windows(2) {
                    assert!(w[0].z < w[1].z);
                    assert!(w[0].capacity <= w[1].z - w[0].z + 1e-6);
                }
                for s in column {
                    assert!(s.capacity > 0.0 && !s.capacity.is_nan(), "{s:?}");
                }
                // Every column over the floor has exactly one site under the open sky (the
                // grid's last row and column may reach past the scene).
                let [x, y] = map.column_centre(col, row);
                let inside = (0.0..=10.0).contains(&x) && (0.0..=10.0).contains(&y);
                assert_eq!(
                    column.iter().filter(|s| s.capacity.is_infinite()).count(),
                    usize::from(inside),
                    "cell {cell} column ({col}, {row}): {column:?}"
                );
            }
        }
    }
}

#[test]
fn facing_and_two_sided_sites() {
    let mut floor = quad("floor", [0.0, 0.0, 4.0, 4.0], 0.0);
    for t in &mut floor.triangles {
        t.swap(1, 2); // now facing down
    }
    let scene = Scene {
        objects: vec![floor],
        ..Default::default()
    };
    let one_sided = HeightSpanMap::build(&scene, &opts(1.0)).unwrap();
    assert_eq!(one_sided.site_count(), 0);
    let both = HeightSpanOptions {
        two_sided: true,
        ..opts(1.0)
    };
    assert_eq!(
        HeightSpanMap::build(&scene, &both).unwrap().site_count(),
        16
    );
}

#[test]
fn bad_options_are_typed_errors() {
    let scene = table_scene();
    for cell in [0.0, -1.0, f64::NAN] {
        let e = HeightSpanMap::build(&scene, &opts(cell));
        assert!(matches!(e, Err(MeshError::InvalidOption { .. })), "{e:?}");
    }
    let e = HeightSpanMap::build(&scene, &opts(1e-5));
    assert!(matches!(e, Err(MeshError::InvalidOption { .. })), "{e:?}");
    let e = HeightSpanMap::build(&Scene::default(), &opts(1.0));
    assert!(matches!(e, Err(MeshError::InvalidOption { .. })), "{e:?}");
}

#[test]
fn bunny_top_layer_matches_downward_rays() {
    let path = common::mesh_path("bunny_npm.obj");
    let (scene, _) = read_scene(&path, &SourceFrame::default()).unwrap();
    let map = HeightSpanMap::build(&scene, &opts(0.1)).unwrap();
    let bvh = SceneBvh::new(&scene);
    let top = scene.bounds().unwrap().max[2] + 1.0;
    let (mut agree, mut differ) = (0, 0);
    for row in 0..map.height {
        for col in 0..map.width {
            let [x, y] = map.column_centre(col, row);
            let hit = bvh.first_hit(&Ray::new([x as f32, y as f32, top], [0.0, 0.0, -1.0]));
            let highest = map.column(col, row).last();
            match (hit, highest) {
                (Some(h), Some(s)) if s.capacity.is_infinite() => {
                    assert!((top - h.t - s.z).abs() < 1e-3, "column ({col}, {row})");
                    agree += 1;
                }
                (None, None) => agree += 1,
                _ => differ += 1,
            }
            for s in map.column(col, row) {
                assert!(s.capacity > 0.0);
            }
        }
    }
    // Columns grazing the silhouette (or where the top surface faces down) may differ.
    assert!(
        differ * 100 < agree,
        "{differ} columns differ, {agree} agree"
    );
    // The ears and the body overhang: some columns hold several sites.
    assert!(map.layer_count() >= 2, "{}", map.layer_count());
}
