//! The GLB export read back: container layout, glTF validity, accessor bounds and counts,
//! geometry (orientation, centring, normals), snow mesh, nodata holes, decimation, errors.

use gltf_json as json;
use json::validation::Validate;
use snowscape_render::{GlbOptions, RenderError, terrain_glb};
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, NodataMask, SnowLayer};

/// A parsed GLB: the glTF document and the BIN chunk.
struct Glb {
    root: json::Root,
    bin: Vec<u8>,
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap())
}

/// Parses a GLB, checking the header and chunk layout of the spec on the way.
fn parse(bytes: &[u8]) -> Glb {
    assert_eq!(&bytes[0..4], b"glTF");
    assert_eq!(u32_at(bytes, 4), 2, "version");
    assert_eq!(u32_at(bytes, 8) as usize, bytes.len(), "total length");
    let json_len = u32_at(bytes, 12) as usize;
    assert_eq!(u32_at(bytes, 16), 0x4E4F_534A, "JSON chunk type");
    assert_eq!(json_len % 4, 0, "JSON chunk padded to 4 bytes");
    let json_bytes = &bytes[20..20 + json_len];
    let bin_at = 20 + json_len;
    let bin_len = u32_at(bytes, bin_at) as usize;
    assert_eq!(u32_at(bytes, bin_at + 4), 0x004E_4942, "BIN chunk type");
    assert_eq!(bin_len % 4, 0, "BIN chunk padded to 4 bytes");
    assert_eq!(
        bin_at + 8 + bin_len,
        bytes.len(),
        "no bytes after the BIN chunk"
    );
    let root = json::Root::from_slice(json_bytes).expect("JSON chunk parses as glTF");
    let mut errors = Vec::new();
    root.validate(&root, json::Path::new, &mut |path, err| {
        errors.push(format!("{}: {err:?}", path()))
    });
    assert!(errors.is_empty(), "invalid glTF: {errors:?}");
    assert_eq!(root.buffers.len(), 1);
    assert!(root.buffers[0].uri.is_none());
    assert!(root.buffers[0].byte_length.0 as usize <= bin_len);
    Glb {
        root,
        bin: bytes[bin_at + 8..].to_vec(),
    }
}

impl Glb {
    fn accessor_bytes(&self, index: json::Index<json::Accessor>) -> (&json::Accessor, &[u8]) {
        let a = &self.root.accessors[index.value()];
        let view = &self.root.buffer_views[a.buffer_view.unwrap().value()];
        let start = view.byte_offset.map_or(0, |o| o.0 as usize)
            + a.byte_offset.map_or(0, |o| o.0 as usize);
        assert_eq!(start % 4, 0, "accessor aligned to 4 bytes");
        (
            a,
            &self.bin
                [start..view.byte_offset.map_or(0, |o| o.0 as usize) + view.byte_length.0 as usize],
        )
    }

    fn vec3s(&self, index: json::Index<json::Accessor>) -> Vec<[f32; 3]> {
        let (a, bytes) = self.accessor_bytes(index);
        let count = a.count.0 as usize;
        assert_eq!(bytes.len(), count * 12);
        bytes
            .chunks_exact(12)
            .map(|c| {
                std::array::from_fn(|k| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap()))
            })
            .collect()
    }

    fn u32s(&self, index: json::Index<json::Accessor>) -> Vec<u32> {
        let (a, bytes) = self.accessor_bytes(index);
        assert_eq!(bytes.len(), a.count.0 as usize * 4);
        bytes
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect()
    }

    /// Positions, normals and indices of the mesh of the node named `name`.
    fn mesh(&self, name: &str) -> Option<Mesh> {
        let node = self
            .root
            .nodes
            .iter()
            .find(|n| n.name.as_deref() == Some(name))?;
        let mesh = &self.root.meshes[node.mesh?.value()];
        assert_eq!(mesh.name.as_deref(), Some(name));
        let p = &mesh.primitives[0];
        let attr = |s| {
            *p.attributes
                .get(&json::validation::Checked::Valid(s))
                .unwrap()
        };
        let positions_index = attr(json::mesh::Semantic::Positions);
        let positions = self.vec3s(positions_index);
        let a = &self.root.accessors[positions_index.value()];
        let bounds: [[f32; 3]; 2] = [a.min.clone().unwrap(), a.max.clone().unwrap()]
            .map(|v| serde_json::from_value(v).unwrap());
        Some(Mesh {
            positions,
            normals: self.vec3s(attr(json::mesh::Semantic::Normals)),
            indices: self.u32s(p.indices.unwrap()),
            bounds,
            material: self.root.materials[p.material.unwrap().value()]
                .name
                .clone()
                .unwrap(),
        })
    }
}

struct Mesh {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    indices: Vec<u32>,
    bounds: [[f32; 3]; 2],
    material: String,
}

impl Mesh {
    /// The spec's and our invariants: finite positions inside the declared bounds (which are
    /// tight), unit normals, indices in range, upward-facing triangles.
    fn check(&self) {
        assert_eq!(self.positions.len(), self.normals.len());
        assert_eq!(self.indices.len() % 3, 0);
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for p in &self.positions {
            assert!(p.iter().all(|v| v.is_finite()), "{p:?}");
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        assert_eq!([lo, hi], self.bounds, "accessor min/max match the data");
        for n in &self.normals {
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            assert!((len - 1.0).abs() < 1e-5, "normal {n:?} has length {len}");
            assert!(n[1] > 0.0, "normal {n:?} points down");
        }
        let count = self.positions.len() as u32;
        assert!(self.indices.iter().all(|&i| i < count));
        let mut used = vec![false; self.positions.len()];
        for t in self.indices.chunks_exact(3) {
            let p: [[f32; 3]; 3] = std::array::from_fn(|k| self.positions[t[k] as usize]);
            let e1 = [p[1][0] - p[0][0], p[1][2] - p[0][2]];
            let e2 = [p[2][0] - p[0][0], p[2][2] - p[0][2]];
            // y component of e1 x e2 (counter-clockwise seen from +y).
            assert!(
                e1[1] * e2[0] - e1[0] * e2[1] > 0.0,
                "triangle {t:?} faces down"
            );
            t.iter().for_each(|&i| used[i as usize] = true);
        }
        assert!(
            used.iter().all(|&u| u),
            "every emitted vertex belongs to a triangle"
        );
    }
}

fn terrain(
    w: usize,
    h: usize,
    dx: f64,
    dy: f64,
    z: impl FnMut(usize, usize) -> f32,
) -> LayeredTerrain {
    LayeredTerrain::from_bedrock(Grid::from_fn(GridGeometry::new(w, h, dx, dy).unwrap(), z))
}

#[test]
fn full_resolution_export_round_trips() {
    // 12 x 8 cells of 5 m x 2 m; bedrock rises 0.2 m per metre east and 0.5 m per metre
    // north, from 1000 m; 40 cm of snow on the eastern half.
    let mut t = terrain(12, 8, 5.0, 2.0, |c, r| 1000.0 + c as f32 + (7 - r) as f32);
    for r in 0..8 {
        for c in 6..12 {
            t.layer_mut(SnowLayer::Stable)[r * 12 + c] = 0.4;
        }
    }
    let glb = parse(&terrain_glb(&t, &GlbOptions::default()).unwrap());
    assert_eq!(glb.root.nodes.len(), 2);
    assert_eq!(
        glb.root.scenes[glb.root.scene.unwrap().value()].nodes.len(),
        2
    );
    let rock = glb.mesh("terrain").unwrap();
    rock.check();
    assert_eq!(rock.material, "rock");
    assert_eq!(rock.positions.len(), 96);
    assert_eq!(rock.indices.len(), 11 * 7 * 6);
    // Centred on the grid centre: x in [-30 + 2.5, 30 - 2.5], z in [-8 + 1, 8 - 1];
    // y = 0 at the lowest bedrock (1000 m, south-west), 18 m at the north-east corner.
    assert_eq!(rock.bounds, [[-27.5, 0.0, -7.0], [27.5, 18.0, 7.0]]);
    // x east, z south: the north-east corner (max x, min z) is the highest vertex.
    let top = rock
        .positions
        .iter()
        .cloned()
        .fold([0.0f32; 3], |a, p| if p[1] > a[1] { p } else { a });
    assert_eq!(top, [27.5, 18.0, -7.0]);
    // Uphill is east and north: the normal leans west (-x) and south (+z).
    let n = rock.normals[5 * 12 + 5];
    let len = (1.0f32 + 0.04 + 0.25).sqrt();
    assert!(
        (n[0] + 0.2 / len).abs() < 1e-5 && (n[2] - 0.5 / len).abs() < 1e-5,
        "{n:?}"
    );
    let snow = glb.mesh("snow").unwrap();
    snow.check();
    assert_eq!(snow.material, "snow");
    assert_eq!(snow.positions.len(), 6 * 8);
    assert_eq!(snow.indices.len(), 5 * 7 * 6);
    for p in &snow.positions {
        assert!(p[0] > 0.0, "snow only on the eastern half: {p:?}");
        let under = rock
            .positions
            .iter()
            .find(|q| q[0] == p[0] && q[2] == p[2])
            .unwrap();
        assert!(
            (p[1] - under[1] - 0.4).abs() < 1e-4,
            "snow surface = bedrock + depth"
        );
    }
}

#[test]
fn nodata_cells_leave_holes() {
    let g = GridGeometry::square(4, 4, 1.0).unwrap();
    let mut invalid = vec![false; 16];
    invalid[5] = true; // (col 1, row 1): corner of 6 triangles
    let dem = Grid::new(g, vec![10.0; 16], NodataMask::from_invalid(invalid)).unwrap();
    let t = LayeredTerrain::from_bedrock(dem);
    let glb = parse(&terrain_glb(&t, &GlbOptions::default()).unwrap());
    let rock = glb.mesh("terrain").unwrap();
    rock.check();
    assert_eq!(rock.positions.len(), 15);
    assert_eq!(rock.indices.len(), (18 - 6) * 3);
    assert!(glb.mesh("snow").is_none(), "no snow, no snow mesh");
}

#[test]
fn decimation_keeps_the_outline_and_the_budget_is_met() {
    let t = terrain(10, 7, 1.0, 1.0, |c, r| (c * r) as f32 * 0.1);
    let opts = GlbOptions {
        decimation: 3,
        include_snow: false,
        ..Default::default()
    };
    let rock = parse(&terrain_glb(&t, &opts).unwrap())
        .mesh("terrain")
        .unwrap();
    rock.check();
    // Columns 0, 3, 6, 9 and rows 0, 3, 6.
    assert_eq!(rock.positions.len(), 12);
    assert_eq!([rock.bounds[0][0], rock.bounds[1][0]], [-4.5, 4.5]);
    assert_eq!([rock.bounds[0][2], rock.bounds[1][2]], [-3.0, 3.0]);
    let mut t = terrain(101, 77, 2.0, 2.0, |c, r| {
        ((c as f32) * 0.1).sin() * 5.0 + r as f32
    });
    t.layer_mut(SnowLayer::Powder).fill(1.0);
    for budget in [8, 100, 1000, 5000] {
        let opts = GlbOptions {
            max_vertices: Some(budget),
            ..Default::default()
        };
        let glb = parse(&terrain_glb(&t, &opts).unwrap());
        let total: usize = ["terrain", "snow"]
            .iter()
            .map(|n| glb.mesh(n).unwrap().positions.len())
            .sum();
        assert!(
            total <= budget,
            "{total} vertices over a budget of {budget}"
        );
        glb.mesh("snow").unwrap().check();
    }
}

#[test]
fn vertical_exaggeration_scales_heights() {
    let t = terrain(3, 3, 1.0, 1.0, |c, _| 100.0 + c as f32);
    let opts = GlbOptions {
        vertical_exaggeration: 2.5,
        ..Default::default()
    };
    let rock = parse(&terrain_glb(&t, &opts).unwrap())
        .mesh("terrain")
        .unwrap();
    assert_eq!(rock.bounds[1][1], 5.0);
}

#[test]
fn bad_input_is_a_typed_error() {
    let t = terrain(3, 3, 1.0, 1.0, |_, _| 0.0);
    let zero = GlbOptions {
        decimation: 0,
        ..Default::default()
    };
    assert!(matches!(
        terrain_glb(&t, &zero),
        Err(RenderError::InvalidCount {
            name: "decimation",
            ..
        })
    ));
    let flat = GlbOptions {
        vertical_exaggeration: 0.0,
        ..Default::default()
    };
    assert!(matches!(
        terrain_glb(&t, &flat),
        Err(RenderError::InvalidOption { .. })
    ));
    let mut nan = t.clone();
    nan.bedrock[4] = f32::NAN;
    match terrain_glb(&nan, &GlbOptions::default()) {
        Err(RenderError::NonFinite { col: 1, row: 1, .. }) => {}
        other => panic!("{other:?}"),
    }
    let line = terrain(5, 1, 1.0, 1.0, |_, _| 0.0);
    assert!(matches!(
        terrain_glb(&line, &GlbOptions::default()),
        Err(RenderError::EmptyMesh { .. })
    ));
}
