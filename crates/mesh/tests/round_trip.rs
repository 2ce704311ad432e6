//! Snow-mesh output: written GLB and OBJ files read back give the same triangles, in the
//! input's axes and units; writes are atomic; textures travel with the mesh.

mod common;
use snowscape_mesh::write::{glb_bytes, write_glb, write_obj};
use snowscape_mesh::{MeshError, Scene, SnowObject, SourceFrame, TriMesh, UpAxis, read_scene};
use std::path::Path;

/// Each triangle's three corner positions, in order.
fn corner_list(scene: &Scene) -> Vec<[[f32; 3]; 3]> {
    scene
        .objects
        .iter()
        .flat_map(|o| (0..o.triangles.len()).map(|t| o.corners(t)))
        .collect()
}

fn assert_same_triangles(a: &Scene, b: &Scene, tolerance: f32) {
    let (ca, cb) = (corner_list(a), corner_list(b));
    assert_eq!(ca.len(), cb.len());
    for (t, (x, y)) in ca.iter().zip(&cb).enumerate() {
        for k in 0..3 {
            for c in 0..3 {
                assert!(
                    (x[k][c] - y[k][c]).abs() <= tolerance,
                    "triangle {t}: {x:?} vs {y:?}"
                );
            }
        }
    }
}

fn only_files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn glb_and_obj_round_trip_in_the_input_frame() {
    for (file, frame) in [
        ("bunny_npm.obj", SourceFrame::new(UpAxis::Y, 0.1).unwrap()),
        ("spider.obj", SourceFrame::new(UpAxis::Z, 0.01).unwrap()),
        ("airplane.ply", SourceFrame::default()),
    ] {
        let (scene, _) = read_scene(&common::mesh_path(file), &frame).unwrap();
        let meshes: Vec<SnowObject> = scene.objects.iter().map(SnowObject::from_object).collect();
        let d = tempfile::tempdir().unwrap();
        let glb = d.path().join("snow.glb");
        let obj = d.path().join("snow.obj");
        write_glb(&glb, &meshes, &frame).unwrap();
        write_obj(&obj, &meshes, &frame).unwrap();
        assert_eq!(
            only_files(d.path()),
            ["snow.glb", "snow.mtl", "snow.obj"],
            "{file}"
        );
        // Read back with the same frame: the same triangles (f32 round trips through the
        // frame's scale, hence a relative tolerance).
        let tol = 1e-5 * scene.bounds().unwrap().diagonal();
        for out in [&glb, &obj] {
            let (back, report) = read_scene(out, &frame).unwrap();
            assert_eq!(back.objects.len(), scene.objects.len(), "{file} -> {out:?}");
            assert_eq!(report.degenerate_dropped(), 0);
            assert_same_triangles(&scene, &back, tol);
            for (o, b) in scene.objects.iter().zip(&back.objects) {
                assert_eq!(b.normals.as_ref().map(Vec::len), Some(b.positions.len()));
                assert!(o.name.is_empty() || b.name.starts_with(&o.name.replace(' ', "_")));
            }
        }
    }
}

#[test]
fn files_are_in_the_input_units_not_the_scene_metres() {
    let frame = SourceFrame::new(UpAxis::Y, 0.01).unwrap();
    let mesh = SnowObject {
        mesh: TriMesh {
            name: "cap".into(),
            // 1 m up in the scene.
            positions: vec![[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 1.0]],
            triangles: vec![[0, 1, 2]],
            ..Default::default()
        },
        ..Default::default()
    };
    let d = tempfile::tempdir().unwrap();
    let obj = d.path().join("cap.obj");
    write_obj(&obj, std::slice::from_ref(&mesh), &frame).unwrap();
    let text = std::fs::read_to_string(&obj).unwrap();
    // y-up centimetres: scene (1, 0, 1) m is file (100, 100, -0).
    assert!(
        text.contains("v 100 100 -0\n") || text.contains("v 100 100 0\n"),
        "{text}"
    );
    // Computed normals face up: file +y.
    assert!(
        text.contains("vn 0 1 -0\n") || text.contains("vn 0 1 0\n"),
        "{text}"
    );
}

#[test]
fn textures_and_uvs_are_written_with_the_mesh() {
    let mut img = image::RgbaImage::new(4, 4);
    for (x, _, p) in img.enumerate_pixels_mut() {
        *p = image::Rgba([255, 255, 255, if x < 2 { 255 } else { 0 }]);
    }
    let mesh = SnowObject {
        mesh: TriMesh {
            name: "masked snow".into(),
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            uvs: Some(vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]),
            ..Default::default()
        },
        texture: Some(img.clone()),
    };
    let frame = SourceFrame::default();
    let d = tempfile::tempdir().unwrap();
    write_obj(&d.path().join("s.obj"), std::slice::from_ref(&mesh), &frame).unwrap();
    assert_eq!(only_files(d.path()), ["s.mtl", "s.obj", "s_0.png"]);
    let png = image::open(d.path().join("s_0.png")).unwrap().into_rgba8();
    assert_eq!(png, img);
    let mtl = std::fs::read_to_string(d.path().join("s.mtl")).unwrap();
    assert!(
        mtl.contains("map_Kd s_0.png") && mtl.contains("map_d"),
        "{mtl}"
    );
    let text = std::fs::read_to_string(d.path().join("s.obj")).unwrap();
    // OBJ's v runs upwards: glTF v = 1 (bottom row) is OBJ v = 0.
    assert!(
        text.contains("vt 0 0\n") && text.contains("f 1/1/1 2/2/2 3/3/3"),
        "{text}"
    );

    let glb = glb_bytes(std::slice::from_ref(&mesh), &frame, Path::new("s.glb")).unwrap();
    let g = gltf::Gltf::from_slice(&glb).unwrap();
    let doc = &g.document;
    assert_eq!(doc.images().count(), 1);
    let material = doc.materials().next().unwrap();
    assert_eq!(material.alpha_mode(), gltf::material::AlphaMode::Mask);
    assert!(
        material
            .pbr_metallic_roughness()
            .base_color_texture()
            .is_some()
    );
    let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
    let blob = g.blob.as_deref().unwrap();
    let uvs: Vec<[f32; 2]> = prim
        .reader(|_| Some(blob))
        .read_tex_coords(0)
        .unwrap()
        .into_f32()
        .collect();
    assert_eq!(uvs, mesh.mesh.uvs.unwrap());
}

#[test]
fn inconsistent_meshes_are_refused_and_leave_nothing() {
    let d = tempfile::tempdir().unwrap();
    let bad = SnowObject::new(TriMesh {
        name: "bad".into(),
        positions: vec![[0.0; 3], [1.0, 0.0, 0.0]],
        triangles: vec![[0, 1, 2]],
        ..Default::default()
    });
    let frame = SourceFrame::default();
    let e = write_glb(
        &d.path().join("bad.glb"),
        std::slice::from_ref(&bad),
        &frame,
    );
    assert!(matches!(e, Err(MeshError::InvalidMesh { .. })), "{e:?}");
    let mut nan = bad.clone();
    nan.positions = vec![[0.0; 3], [1.0, 0.0, 0.0], [f32::NAN, 1.0, 0.0]];
    let e = write_obj(&d.path().join("nan.obj"), &[nan], &frame);
    assert!(matches!(e, Err(MeshError::InvalidMesh { .. })), "{e:?}");
    assert!(only_files(d.path()).is_empty());
    // A folder that does not exist: a write error naming it.
    let e = write_glb(&d.path().join("no/such/dir/x.glb"), &[], &frame);
    assert!(matches!(e, Err(MeshError::Write(_))), "{e:?}");
}

/// Issue 46: the diffusion cover wrote `vt NaN NaN`. A NaN or infinite texture coordinate or
/// normal is refused by both writers, and nothing is left behind.
#[test]
fn non_finite_uvs_and_normals_are_never_written() {
    let d = tempfile::tempdir().unwrap();
    let frame = SourceFrame::default();
    let good = SnowObject {
        mesh: TriMesh {
            name: "uv".into(),
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            triangles: vec![[0, 1, 2]],
            uvs: Some(vec![[0.0, 0.5]; 3]),
            ..Default::default()
        },
        texture: Some(image::RgbaImage::new(2, 2)),
    };
    let mut nan_uv = good.clone();
    nan_uv.uvs = Some(vec![[0.0, 0.5], [f32::NAN, f32::NAN], [0.0, 0.5]]);
    let mut inf_normal = good.clone();
    inf_normal.mesh.normals = Some(vec![[0.0, 0.0, 1.0], [0.0, 0.0, f32::INFINITY], [0.0; 3]]);
    for m in [nan_uv, inf_normal] {
        let e = write_obj(&d.path().join("s.obj"), std::slice::from_ref(&m), &frame);
        assert!(matches!(e, Err(MeshError::InvalidMesh { .. })), "{e:?}");
        let e = write_glb(&d.path().join("s.glb"), std::slice::from_ref(&m), &frame);
        assert!(matches!(e, Err(MeshError::InvalidMesh { .. })), "{e:?}");
    }
    assert!(only_files(d.path()).is_empty());
}
