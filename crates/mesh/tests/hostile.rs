//! Hostile inputs: every one is a typed error naming the file (or a handled, reported case),
//! never a panic.

mod common;
use snowscape_mesh::{MeshError, SourceFrame, read_scene};
use std::path::{Path, PathBuf};

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn read(p: &Path) -> Result<snowscape_mesh::Scene, MeshError> {
    read_scene(p, &SourceFrame::default()).map(|(s, _)| s)
}

const TETRA: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";

#[test]
fn obj_nan_vertex_names_file_and_vertex() {
    let d = tempfile::tempdir().unwrap();
    let p = write(
        d.path(),
        "nan.obj",
        TETRA.replace("v 0 1 0", "v 0 nan 0").as_bytes(),
    );
    match read(&p) {
        Err(e @ MeshError::NonFiniteVertex { vertex: 2, .. }) => {
            assert!(e.to_string().contains("nan.obj"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    let p = write(
        d.path(),
        "inf.obj",
        TETRA.replace("v 1 0 0", "v inf 0 0").as_bytes(),
    );
    assert!(matches!(
        read(&p),
        Err(MeshError::NonFiniteVertex { vertex: 1, .. })
    ));
}

#[test]
fn obj_index_out_of_range_names_face_and_index() {
    let d = tempfile::tempdir().unwrap();
    let p = write(
        d.path(),
        "idx.obj",
        TETRA.replace("f 2 3 4", "f 2 3 9").as_bytes(),
    );
    match read(&p) {
        Err(
            e @ MeshError::IndexOutOfRange {
                face: 2,
                index: 9,
                vertex_count: 4,
                ..
            },
        ) => {
            assert!(e.to_string().contains("idx.obj"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    let p = write(
        d.path(),
        "zero.obj",
        TETRA.replace("f 1 2 4", "f 0 2 4").as_bytes(),
    );
    assert!(matches!(
        read(&p),
        Err(MeshError::IndexOutOfRange {
            face: 1,
            index: 0,
            ..
        })
    ));
}

#[test]
fn empty_and_flat_meshes_are_empty_mesh_errors() {
    let d = tempfile::tempdir().unwrap();
    for (name, text) in [
        ("empty.obj", ""),
        ("points.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\n"),
        ("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n"),
    ] {
        let p = write(d.path(), name, text.as_bytes());
        match read(&p) {
            Err(MeshError::EmptyMesh { path, .. }) => assert_eq!(path, p),
            other => panic!("{name}: {other:?}"),
        }
    }
}

#[test]
fn zero_area_triangles_are_dropped_and_counted() {
    let d = tempfile::tempdir().unwrap();
    let text = format!("{TETRA}v 2 0 0\nf 1 2 5\nf 4 4 4\n");
    let p = write(d.path(), "zero_area.obj", text.as_bytes());
    let (scene, report) = read_scene(&p, &SourceFrame::default()).unwrap();
    assert_eq!(scene.triangle_count(), 4);
    assert_eq!(report.degenerate_dropped(), 2);
    assert_eq!(report.open_edges(), 0);
}

#[test]
fn truncated_files_never_panic() {
    let d = tempfile::tempdir().unwrap();
    for name in ["bunny_npm.obj", "ant.ply", "airplane.ply", "spider.obj"] {
        let bytes = std::fs::read(common::mesh_path(name)).unwrap();
        for cut in [
            1,
            10,
            200,
            bytes.len() / 3,
            bytes.len() / 2,
            bytes.len() - 7,
        ] {
            let p = write(d.path(), name, &bytes[..cut]);
            // A text file cut at a line end may still be a valid (smaller) mesh; anything else
            // must be a typed error naming the file.
            if let Err(e) = read(&p) {
                assert!(e.to_string().contains(name), "{name} cut at {cut}: {e}");
            }
        }
    }
    // Binary PLY cut in its data: the parser must say so.
    let bytes = std::fs::read(common::mesh_path("ant.ply")).unwrap();
    let p = write(d.path(), "cut.ply", &bytes[..bytes.len() / 2]);
    assert!(matches!(
        read(&p),
        Err(MeshError::Parse { format: "PLY", .. })
    ));
    // OBJ cut in the middle of a vertex line: the line is named.
    let p = write(d.path(), "cut.obj", b"v 0 0 0\nv 1 0 0\nv 0 1");
    match read(&p) {
        Err(MeshError::Parse { line: Some(3), .. }) => {}
        other => panic!("{other:?}"),
    }
}

fn ascii_ply(vertices: &[&str], faces: &[&str]) -> String {
    format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n{}\n{}\n",
        vertices.len(),
        faces.len(),
        vertices.join("\n"),
        faces.join("\n")
    )
}

#[test]
fn ply_nan_bad_index_and_quads() {
    let d = tempfile::tempdir().unwrap();
    let v = ["0 0 0", "1 0 0", "1 1 0", "0 1 0"];
    let p = write(
        d.path(),
        "quad.ply",
        ascii_ply(&v, &["4 0 1 2 3"]).as_bytes(),
    );
    let (s, r) = read_scene(&p, &SourceFrame::default()).unwrap();
    assert_eq!((s.triangle_count(), r.objects[0].polygons_split), (2, 1));
    let p = write(
        d.path(),
        "nan.ply",
        ascii_ply(&["0 0 0", "nan 0 0", "1 1 0"], &["3 0 1 2"]).as_bytes(),
    );
    // ply-rs-bw's ASCII grammar has no NaN: a parse error naming the line.
    let r = read(&p);
    assert!(
        matches!(r, Err(MeshError::Parse { line: Some(11), .. })),
        "{r:?}"
    );
    // In a binary file a NaN is a plain float: the checker names the vertex.
    let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
        property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n\
        end_header\n"
        .to_vec();
    for v in [[0.0f32, 0.0, 0.0], [1.0, f32::NAN, 0.0], [1.0, 1.0, 0.0]] {
        bin.extend(v.iter().flat_map(|c| c.to_le_bytes()));
    }
    bin.push(3);
    bin.extend([0i32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    let p = write(d.path(), "nan_bin.ply", &bin);
    let r = read(&p);
    assert!(
        matches!(r, Err(MeshError::NonFiniteVertex { vertex: 1, .. })),
        "{r:?}"
    );
    let p = write(
        d.path(),
        "idx.ply",
        ascii_ply(&v, &["3 0 1 2", "3 0 2 -1"]).as_bytes(),
    );
    assert!(matches!(
        read(&p),
        Err(MeshError::IndexOutOfRange {
            face: 1,
            index: -1,
            ..
        })
    ));
    let p = write(d.path(), "noface.ply", ascii_ply(&v, &[]).as_bytes());
    assert!(matches!(read(&p), Err(MeshError::EmptyMesh { .. })));
}

#[test]
fn broken_gltf_and_glb_are_parse_errors() {
    let d = tempfile::tempdir().unwrap();
    // A GLB header claiming more bytes than the file has, one claiming fewer than a header.
    let mut glb = b"glTF".to_vec();
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&1000u32.to_le_bytes());
    glb.extend_from_slice(&[0u8; 20]);
    let p = write(d.path(), "long.glb", &glb);
    assert!(matches!(read(&p), Err(MeshError::Parse { .. })));
    glb[8..12].copy_from_slice(&4u32.to_le_bytes());
    let p = write(d.path(), "short.glb", &glb);
    assert!(matches!(read(&p), Err(MeshError::Parse { .. })));
    let p = write(d.path(), "junk.gltf", b"{ not json");
    assert!(matches!(read(&p), Err(MeshError::Parse { .. })));
    // An accessor running past its buffer.
    let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
      "nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
      "accessors":[{"bufferView":0,"componentType":5126,"count":30,"type":"VEC3",
                    "min":[0,0,0],"max":[1,1,1]}],
      "bufferViews":[{"buffer":0,"byteLength":36}],
      "buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}]}"#;
    let p = write(d.path(), "short_accessor.gltf", json.as_bytes());
    match read(&p) {
        Err(MeshError::Parse { message, .. }) => {
            assert!(message.contains("accessor 0"), "{message}")
        }
        other => panic!("{other:?}"),
    }
    // The same with a correct count reads one triangle, moved by its node's transform.
    let ok = json.replace("\"count\":30", "\"count\":3").replace(
        "{\"mesh\":0}",
        "{\"mesh\":0,\"name\":\"roof\",\"translation\":[0,5,0],\"scale\":[2,2,2]}",
    );
    let p = write(d.path(), "ok.gltf", ok.as_bytes());
    let s = read(&p).unwrap();
    assert_eq!(s.triangle_count(), 1);
    let o = &s.objects[0];
    assert_eq!(o.name, "roof");
    // File y-up: (0, 5, 0) + 2 (x, y, z) is scene (2x, -2z, 5 + 2y).
    assert_eq!(
        o.corners(0),
        [[0.0, 0.0, 5.0], [2.0, 0.0, 5.0], [0.0, 0.0, 7.0]]
    );
    // A POSITION naming an accessor the file lacks: the gltf crate's validation indexed it
    // unchecked and panicked (found by the mutation tests).
    let p = write(
        d.path(),
        "no_accessor.gltf",
        ok.replace("\"POSITION\":0", "\"POSITION\":255").as_bytes(),
    );
    match read(&p) {
        Err(MeshError::Parse { message, .. }) => {
            assert!(message.contains("accessor 255"), "{message}")
        }
        other => panic!("{other:?}"),
    }
    // A node graph with a cycle (node 0 its own child) is refused, not walked forever.
    let cyclic = ok.replace("\"name\":\"roof\"", "\"name\":\"roof\",\"children\":[0]");
    let p = write(d.path(), "cycle.gltf", cyclic.as_bytes());
    assert!(matches!(read(&p), Err(MeshError::Parse { .. })));
    // The buffer as an external file beside the .gltf reads the same.
    let bin = [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        .as_flattened()
        .iter()
        .flat_map(|c| c.to_le_bytes())
        .collect::<Vec<u8>>();
    write(d.path(), "tri.bin", &bin);
    let external = ok.replace(
        "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA",
        "tri.bin",
    );
    let p = write(d.path(), "external.gltf", external.as_bytes());
    assert_eq!(read(&p).unwrap().objects[0].corners(0), o.corners(0));
    // A missing external buffer is an I/O error naming it.
    let p = write(
        d.path(),
        "ext.gltf",
        json.replace(
            "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA",
            "missing.bin",
        )
        .as_bytes(),
    );
    match read(&p) {
        Err(MeshError::Io { path, .. }) => assert!(path.ends_with("missing.bin")),
        other => panic!("{other:?}"),
    }
}

#[test]
fn missing_files_and_unknown_formats() {
    let d = tempfile::tempdir().unwrap();
    assert!(matches!(
        read(&d.path().join("none.obj")),
        Err(MeshError::Io { .. })
    ));
    let p = write(d.path(), "mesh.stl", b"solid x");
    assert!(matches!(read(&p), Err(MeshError::UnknownFormat { .. })));
}

/// A minimal glTF whose one buffer (one triangle, 36 bytes) is at `uri`.
fn gltf_with_buffer(uri: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
      "nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
      "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
                    "min":[0,0,0],"max":[1,1,0]}}],
      "bufferViews":[{{"buffer":0,"byteLength":36}}],
      "buffers":[{{"byteLength":36,"uri":"{uri}"}}]}}"#
    )
}

/// Buffer URIs may not leave the glTF file's folder (issue 19 item 7: `../../etc/passwd` was
/// read as vertex data).
#[test]
fn gltf_buffers_outside_the_folder_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let inner = d.path().join("scene");
    std::fs::create_dir(&inner).unwrap();
    let bin = [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        .as_flattened()
        .iter()
        .flat_map(|c| c.to_le_bytes())
        .collect::<Vec<u8>>();
    write(d.path(), "outside.bin", &bin);
    write(&inner, "inside.bin", &bin);
    std::fs::create_dir(inner.join("sub")).unwrap();
    write(&inner.join("sub"), "deeper.bin", &bin);
    for uri in [
        "../outside.bin",
        "../../etc/passwd",
        "sub/../../outside.bin",
        "%2e%2e/outside.bin",
        "/etc/passwd",
        "file:///etc/passwd",
        "C:/x.bin",
    ] {
        let p = write(&inner, "m.gltf", gltf_with_buffer(uri).as_bytes());
        match read(&p) {
            Err(e @ MeshError::BufferOutsideFolder { buffer: 0, .. }) => {
                assert!(e.to_string().contains(uri), "{uri}: {e}")
            }
            other => panic!("{uri}: {other:?}"),
        }
    }
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(d.path().join("outside.bin"), inner.join("link.bin")).unwrap();
        let p = write(&inner, "m.gltf", gltf_with_buffer("link.bin").as_bytes());
        assert!(
            matches!(read(&p), Err(MeshError::BufferOutsideFolder { .. })),
            "symlink"
        );
    }
    for uri in [
        "inside.bin",
        "./inside.bin",
        "sub/deeper.bin",
        "sub%2Fdeeper.bin",
    ] {
        let p = write(&inner, "m.gltf", gltf_with_buffer(uri).as_bytes());
        assert_eq!(read(&p).unwrap().triangle_count(), 1, "{uri}");
    }
}

/// Devices and FIFOs are refused by every mesh reader before anything is read or opened.
#[test]
fn devices_and_fifos_are_not_meshes() {
    let d = tempfile::tempdir().unwrap();
    for ext in ["obj", "ply", "gltf", "glb"] {
        let zero = d.path().join(format!("zero.{ext}"));
        std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
        match read(&zero) {
            Err(e @ MeshError::Input(_)) => {
                assert!(e.to_string().contains("character device"), "{ext}: {e}")
            }
            other => panic!("{ext}: {other:?}"),
        }
        let fifo = d.path().join(format!("pipe.{ext}"));
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success());
        if made {
            let e = read(&fifo).unwrap_err();
            assert!(e.to_string().contains("FIFO"), "{ext}: {e}");
        }
    }
}

/// Issue 46: an OBJ of one triangle pasted 100,000 times (the issue's 8 MB file had a million:
/// the covers' neighbour searches went quadratic and the process grew to 5 GB) is one triangle.
#[test]
fn repeated_triangle_is_one_triangle_and_duplicates_are_counted() {
    let d = tempfile::tempdir().unwrap();
    let text = format!(
        "v 0 0 0\nv 1 0 0\nv 0 0 -1\n{}",
        "f 1 2 3\n".repeat(100_000)
    );
    let p = write(d.path(), "repeated.obj", text.as_bytes());
    let t = std::time::Instant::now();
    let (scene, report) = read_scene(&p, &SourceFrame::default()).unwrap();
    assert!(t.elapsed().as_secs_f64() < 5.0, "{:?}", t.elapsed());
    assert_eq!(scene.triangle_count(), 1);
    assert_eq!(report.duplicates_dropped(), 99_999);
    // The same corners in the other order face the other way: a second triangle, kept.
    let p = write(
        d.path(),
        "two_sided.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\nf 2 3 1\nf 1 3 2\n",
    );
    let (scene, report) = read_scene(&p, &SourceFrame::default()).unwrap();
    assert_eq!(
        (scene.triangle_count(), report.duplicates_dropped()),
        (2, 1)
    );
}

/// Issue 46: a 2 MB OBJ with one face of a million corners ran past a minute at 3.8 GB; a face
/// beyond MAX_FACE_CORNERS is refused by the pre-scan, naming the line and the corner count.
#[test]
fn huge_face_is_refused_before_loading_naming_line_and_count() {
    use snowscape_mesh::read::MAX_FACE_CORNERS;
    let d = tempfile::tempdir().unwrap();
    let corners: Vec<String> = (0..1_000_000).map(|i| (1 + i % 4).to_string()).collect();
    let text = format!(
        "v 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nf {}\n",
        corners.join(" ")
    );
    let p = write(d.path(), "huge_face.obj", text.as_bytes());
    let t = std::time::Instant::now();
    match read(&p) {
        Err(
            e @ MeshError::TooLarge {
                line: Some(5),
                value: 1_000_000,
                ..
            },
        ) => {
            let s = e.to_string();
            assert!(s.contains("huge_face.obj") && s.contains("line 5"), "{s}");
        }
        other => panic!("{other:?}"),
    }
    assert!(t.elapsed().as_secs_f64() < 2.0, "{:?}", t.elapsed());
    // At the limit the polygon is a fan.
    let corners: Vec<String> = (0..MAX_FACE_CORNERS).map(|i| (i + 1).to_string()).collect();
    let ring: String = (0..MAX_FACE_CORNERS)
        .map(|i| {
            let a = i as f64 / MAX_FACE_CORNERS as f64 * std::f64::consts::TAU;
            format!("v {} 0 {}\n", a.cos(), -a.sin())
        })
        .collect();
    let p = write(
        d.path(),
        "disc.obj",
        format!("{ring}f {}\n", corners.join(" ")).as_bytes(),
    );
    let (scene, _) = read_scene(&p, &SourceFrame::default()).unwrap();
    assert_eq!(scene.triangle_count() as u64, MAX_FACE_CORNERS - 2);
}

/// A PLY header announcing four billion vertices is refused before the body is parsed.
#[test]
fn ply_header_beyond_the_limits_is_refused_naming_the_line() {
    let d = tempfile::tempdir().unwrap();
    let text = ascii_ply(&["0 0 0", "1 0 0", "0 1 0"], &["3 0 1 2"])
        .replace("element vertex 3", "element vertex 4000000000");
    let p = write(d.path(), "huge.ply", text.as_bytes());
    match read(&p) {
        Err(MeshError::TooLarge {
            line: Some(3),
            value: 4_000_000_000,
            what: "vertex count",
            ..
        }) => {}
        other => panic!("{other:?}"),
    }
}

/// Issue 46: a 1e30 triangle beside a 1 m one (a panic in the BVH crate) and 1e18 coordinates
/// (the Fearing cover spun past its budget) are refused at read time, naming the value and line.
#[test]
fn absurd_coordinates_are_refused_naming_value_and_line() {
    let d = tempfile::tempdir().unwrap();
    for (exp, value) in [(30, 1e30f32), (18, 1e18)] {
        let text = format!(
            "v 0 0 0\nv 1 0 0\nv 0 0 -1\no far\nv 1e{exp} 0 0\nv 2e{exp} 0 0\nv 1e{exp} 0 -1e{exp}\n\
             f 1 2 3\nf 4 5 6\n"
        );
        let p = write(d.path(), "far.obj", text.as_bytes());
        match read(&p) {
            Err(
                e @ MeshError::CoordinateTooLarge {
                    line: Some(5),
                    vertex: 3,
                    ..
                },
            ) => {
                let s = e.to_string();
                assert!(s.contains("far.obj") && s.contains("line 5"), "{s}");
                if let MeshError::CoordinateTooLarge { value: v, .. } = e {
                    assert_eq!(v[0], value);
                }
            }
            other => panic!("1e{exp}: {other:?}"),
        }
    }
    // The limit is in scene metres, after the scale: 2e6 units of 10 m is 2e7 m.
    let text = "v 0 0 0\nv 2e6 0 0\nv 0 0 -2e6\nf 1 2 3\n";
    let p = write(d.path(), "scaled.obj", text.as_bytes());
    assert!(read_scene(&p, &SourceFrame::default()).is_ok());
    let ten = SourceFrame::new(snowscape_mesh::UpAxis::Y, 10.0).unwrap();
    assert!(matches!(
        read_scene(&p, &ten),
        Err(MeshError::CoordinateTooLarge { line: Some(2), .. })
    ));
    // PLY (no line): the vertex is named.
    let text = ascii_ply(&["0 0 0", "1 0 0", "0 1e20 0"], &["3 0 1 2"]);
    let p = write(d.path(), "far.ply", text.as_bytes());
    assert!(matches!(
        read(&p),
        Err(MeshError::CoordinateTooLarge { vertex: 2, .. })
    ));
}

/// A 1 mm triangle beside a 10 km one: 32-bit coordinates and the covers' grids cannot hold
/// both, refused naming the small triangle and the ratio.
#[test]
fn extent_to_smallest_triangle_ratio_is_limited() {
    let d = tempfile::tempdir().unwrap();
    let text = "v 0 0 0\nv 1e4 0 0\nv 0 0 -1e4\nv 5 0 -5\nv 5.001 0 -5\nv 5 0 -5.001\n\
                f 1 2 3\nf 4 5 6\n";
    let p = write(d.path(), "ratio.obj", text.as_bytes());
    match read(&p) {
        Err(e @ MeshError::ExtentTooLarge { triangle: 1, .. }) => {
            assert!(e.to_string().contains("ratio.obj"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    // A 1 m triangle in the same 10 km scene is fine.
    let p = write(
        d.path(),
        "ok.obj",
        text.replace("5.001", "6")
            .replace("-5.001", "-6")
            .as_bytes(),
    );
    assert!(read(&p).is_ok());
}
