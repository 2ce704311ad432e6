//! Property tests of the mesh readers under a memory bound (issue 46, CI item 7): valid OBJ,
//! PLY (ASCII and binary) and glTF/GLB files, written by the crate's own writers or by hand,
//! mutated byte by byte (flipped bits, huge numbers, inserted tokens, duplicated or removed
//! sections, splices, truncations) are read as a scene or refused with a typed error naming
//! the file; never a panic, and the reading thread's peak allocation stays within a bound
//! linear in the file's length (counting allocator), whatever the file claims.

#[path = "../../io/tests/common/counting.rs"]
mod counting;
#[path = "../../io/tests/common/mutate.rs"]
mod mutate;

use counting::peak_of;
use proptest::prelude::*;
use snowscape_mesh::read::{MAX_COORDINATE_M, MAX_TRIANGLES, MAX_VERTICES};
use snowscape_mesh::write::{SnowObject, glb_bytes, write_obj};
use snowscape_mesh::{MeshError, SourceFrame, TriMesh, read_scene};
use std::path::Path;
use std::sync::OnceLock;

/// The most one read of a mutated seed may allocate: a fixed part for the parsers' tables
/// and buffers (ply-rs reserves up to 65536 elements of a declared count: 4.7 MB), and a
/// part per byte of the file (a byte of a glTF strip index becomes a triangle of three
/// 64-bit indices in a vector of its own). The reads of 20,000 cases peaked at 4.8 MB.
fn peak_bound(len: usize) -> usize {
    (16 << 20) + 256 * len
}

/// Tokens of the formats, inserted by the mutations beside the huge numbers.
const TOKENS: &[&str] = &[
    "\nv 1e30 0 0\n",
    "\nf 1 2 3 4 5 6 7 8 9 10\n",
    "\nf -9 -1 0\n",
    "\no again\n",
    "\nelement vertex 9999999\n",
    "\nelement face 4000000000\n",
    "property list uint uint vertex_indices\n",
    "\"count\":9999999,",
    "\"mode\":5,",
    "\"children\":[0],",
    "\"byteStride\":1000000,",
    "\"uri\":\"x.bin\",",
    "{",
    "]",
];

/// A 4x3 grid of vertices, 12 triangles, bumpy, in metres.
fn grid_mesh() -> TriMesh {
    let mut positions = Vec::new();
    for r in 0..3 {
        for c in 0..4 {
            let z = ((c * 7 + r * 3) % 5) as f32 * 0.25;
            positions.push([c as f32 * 2.0, r as f32 * 2.0, z]);
        }
    }
    let mut triangles = Vec::new();
    for r in 0..2u32 {
        for c in 0..3u32 {
            let i = r * 4 + c;
            triangles.push([i, i + 1, i + 5]);
            triangles.push([i, i + 5, i + 4]);
        }
    }
    TriMesh {
        name: "grid".into(),
        positions,
        triangles,
        ..TriMesh::default()
    }
}

const HAND_OBJ: &str = "# hand-written\nmtllib none.mtl\no roof\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
vn 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nf 1/1/1 2/2/1 3/3/1 4/1/1\ng walls\nv 0 0 -1\nv 1 0 -1\n\
f -6 -5 -1\nf 1//1 5//1 6//1\nusemtl stone\nl 1 2\np 3\nf 2 3 6\n";

/// An ASCII PLY of a quad and a triangle.
const ASCII_PLY: &str = "ply\nformat ascii 1.0\ncomment by hand\nelement vertex 5\nproperty float x\n\
property float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\n\
end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n4 0 1 2 3\n3 0 1 4\n";

/// A binary PLY (`little` or big endian) with normals: two triangles.
fn binary_ply(little: bool) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat binary_{}_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
         property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
         element face 2\nproperty list uchar uint vertex_indices\nend_header\n",
        if little { "little" } else { "big" }
    )
    .into_bytes();
    let f = |v: f32| {
        if little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    };
    let u = |v: u32| {
        if little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    };
    for p in [
        [0.0f32, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [2.0, 2.0, 0.5],
        [0.0, 2.0, 0.0],
    ] {
        for c in p.into_iter().chain([0.0, 0.0, 1.0]) {
            b.extend(f(c));
        }
    }
    for t in [[0u32, 1, 2], [0, 2, 3]] {
        b.push(3);
        for i in t {
            b.extend(u(i));
        }
    }
    b
}

/// A glTF with an embedded base64 buffer: four positions and six u8 indices, drawn as a
/// triangle strip by a node with a child that reuses the mesh as a list.
fn data_uri_gltf() -> Vec<u8> {
    use base64::Engine;
    let mut buf = Vec::new();
    for p in [
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.5, 1.0],
    ] {
        for c in p {
            buf.extend(c.to_le_bytes());
        }
    }
    buf.extend([0u8, 1, 2, 1, 3, 2, 0, 0]);
    let b64 = base64::engine::general_purpose::STANDARD.encode(&buf);
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0,"name":"strip","translation":[0,2,0],"children":[1]}},{{"mesh":1,"scale":[2,2,2]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":5}}]}},
          {{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,0.5,1]}},
             {{"bufferView":1,"componentType":5121,"count":6,"type":"SCALAR"}}],
"bufferViews":[{{"buffer":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":6}}],
"buffers":[{{"byteLength":56,"uri":"data:application/octet-stream;base64,{b64}"}}]}}"#
    )
    .into_bytes()
}

/// Valid files of every format with their extensions.
fn seeds() -> &'static Vec<(&'static str, Vec<u8>)> {
    static SEEDS: OnceLock<Vec<(&'static str, Vec<u8>)>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let d = tempfile::tempdir().unwrap();
        let mesh = SnowObject::new(grid_mesh());
        let obj = d.path().join("grid.obj");
        write_obj(&obj, std::slice::from_ref(&mesh), &SourceFrame::default()).unwrap();
        let glb = glb_bytes(&[mesh], &SourceFrame::default(), Path::new("grid.glb")).unwrap();
        vec![
            ("obj", std::fs::read(&obj).unwrap()),
            ("obj", HAND_OBJ.as_bytes().to_vec()),
            ("ply", ASCII_PLY.as_bytes().to_vec()),
            ("ply", binary_ply(true)),
            ("ply", binary_ply(false)),
            ("glb", glb),
            ("gltf", data_uri_gltf()),
        ]
    })
}

/// Reads `bytes` as a `ext` file: a scene within every limit, or a typed error naming the
/// file; the peak allocation within [`peak_bound`].
fn read_bounded(ext: &str, bytes: &[u8]) -> Result<(), TestCaseError> {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join(format!("mutant.{ext}"));
    std::fs::write(&p, bytes).unwrap();
    let (r, peak) = peak_of(|| read_scene(&p, &SourceFrame::default()));
    prop_assert!(
        peak <= peak_bound(bytes.len()),
        "{ext}: peak {peak} bytes for a {}-byte file ({:?})",
        bytes.len(),
        r.as_ref().err()
    );
    match r {
        Ok((scene, _report)) => {
            prop_assert!(scene.triangle_count() as u64 <= MAX_TRIANGLES);
            prop_assert!(scene.vertex_count() as u64 <= MAX_VERTICES);
            for o in &scene.objects {
                for p in &o.positions {
                    prop_assert!(
                        p.iter()
                            .all(|c| c.is_finite() && f64::from(c.abs()) <= MAX_COORDINATE_M),
                        "{p:?}"
                    );
                }
                for t in &o.triangles {
                    prop_assert!(t.iter().all(|&i| (i as usize) < o.positions.len()));
                }
            }
        }
        Err(e) => {
            let msg = e.to_string();
            // An external buffer the mutation named is an I/O error naming that file.
            let names_file = msg.contains("mutant.") || matches!(e, MeshError::Io { .. });
            prop_assert!(names_file, "{msg}");
            // Text from the file is quoted cut short (a duplicated section makes long lines).
            prop_assert!(msg.len() < 1000, "{} bytes: {msg}", msg.len());
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mutated_meshes_are_read_or_refused_within_the_memory_bound(
        seed in any::<prop::sample::Index>(),
        edits in prop_oneof![mutate::edits(TOKENS), mutate::text_edits(TOKENS)],
    ) {
        let all = seeds();
        let (ext, valid) = seed.get(all);
        let others: Vec<&[u8]> = all.iter().map(|(_, b)| b.as_slice()).collect();
        let bytes = mutate::mutated(valid, &edits, &others);
        read_bounded(ext, &bytes)?;
    }
}

#[test]
fn seeds_are_valid_meshes() {
    let d = tempfile::tempdir().unwrap();
    for (k, (ext, bytes)) in seeds().iter().enumerate() {
        let p = d.path().join(format!("seed{k}.{ext}"));
        std::fs::write(&p, bytes).unwrap();
        let (scene, _) =
            read_scene(&p, &SourceFrame::default()).unwrap_or_else(|e| panic!("seed {k}: {e}"));
        assert!(scene.triangle_count() >= 2, "seed {k}");
    }
}

/// A GLB of `json` and a BIN chunk of `bin`.
fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    json.resize(json.len().next_multiple_of(4), b' ');
    let mut bin = bin.to_vec();
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// A 100 KB GLB whose one mesh (a triangle strip of 100,000 triangles) 101 nodes reuse:
/// 10.1 million triangles, past the limit. Refused before any mesh is read (it loaded ten
/// million triangles, 556 MB, before the count passed the limit).
#[test]
fn a_mesh_reused_past_the_triangle_limit_is_refused_before_reading() {
    let strip = 100_002usize;
    let mut bin = Vec::new();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]] {
        for c in p {
            bin.extend(c.to_le_bytes());
        }
    }
    bin.extend((0..strip).map(|k| (k % 3) as u8));
    let nodes = vec![r#"{"mesh":0}"#; 101].join(",");
    let roots: Vec<String> = (0..101).map(|k| k.to_string()).collect();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":[{nodes}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":5}}]}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,0,1]}},
             {{"bufferView":1,"componentType":5121,"count":{strip},"type":"SCALAR"}}],
"bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":{strip}}}],
"buffers":[{{"byteLength":{}}}]}}"#,
        roots.join(","),
        36 + strip
    );
    let bytes = glb(&json, &bin);
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("reused.glb");
    std::fs::write(&p, &bytes).unwrap();
    let (r, peak) = peak_of(|| read_scene(&p, &SourceFrame::default()));
    match r {
        Err(
            e @ MeshError::TooLarge {
                what: "triangle count",
                value: 10_100_000,
                ..
            },
        ) => assert!(e.to_string().contains("reused.glb"), "{e}"),
        other => panic!("{:?}", other.map(|_| ())),
    }
    assert!(peak < 2 * bytes.len() + (1 << 20), "peak {peak} bytes");
}
