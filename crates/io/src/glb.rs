//! Binary glTF 2.0 (GLB) assembly, the one writer behind every `.glb` the project makes (the
//! terrain and snow of a season, `snowscape-render`; snow on meshes, `snowscape-mesh`): a
//! [`GlbDocument`] collects buffer views (each 4-byte aligned in one BIN buffer), accessors,
//! materials, meshes and nodes, and [`GlbDocument::finish`] adds the buffer and the scene and
//! wraps JSON and BIN in the GLB container ([`glb_container`]; glTF 2.0 §4.4).

use gltf_json as json;
use json::validation::{Checked::Valid, USize64};

pub use gltf_json;

/// GLB chunk type of the JSON chunk ("JSON").
pub const CHUNK_JSON: u32 = 0x4E4F_534A;
/// GLB chunk type of the binary chunk ("BIN\0").
pub const CHUNK_BIN: u32 = 0x004E_4942;

/// Why a GLB cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum GlbError {
    /// Over the 4 GiB a GLB's 32-bit length field can say.
    #[error("{bytes} bytes is over the 4 GiB GLB limit")]
    TooLarge { bytes: u64 },
    /// The JSON chunk could not be serialised.
    #[error("glTF JSON: {0}")]
    Json(#[from] json::Error),
}

/// A glTF document being assembled, with its binary buffer.
#[derive(Default)]
pub struct GlbDocument {
    /// The glTF JSON: push materials, meshes, images and textures to it directly.
    pub root: json::Root,
    bin: Vec<u8>,
    nodes: Vec<json::Index<json::Node>>,
}

impl GlbDocument {
    /// Appends `bytes` as a buffer view for `target` (none: an image), padded to 4 bytes.
    pub fn push_view(
        &mut self,
        bytes: &[u8],
        target: Option<json::buffer::Target>,
    ) -> json::Index<json::buffer::View> {
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        let view = json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64::from(bytes.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: Default::default(),
        };
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        self.root.push(view)
    }

    /// Appends an accessor of `count` elements of `shape` over a fresh buffer view of `bytes`
    /// (an index buffer for scalars, a vertex buffer otherwise), with its `bounds` (min, max).
    pub fn push_accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        shape: (json::accessor::ComponentType, json::accessor::Type),
        bounds: Option<([f32; 3], [f32; 3])>,
    ) -> json::Index<json::Accessor> {
        let target = match shape.1 {
            json::accessor::Type::Scalar => json::buffer::Target::ElementArrayBuffer,
            _ => json::buffer::Target::ArrayBuffer,
        };
        let view = self.push_view(bytes, Some(target));
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Valid(json::accessor::GenericComponentType(shape.0)),
            extensions: None,
            extras: Default::default(),
            type_: Valid(shape.1),
            min: bounds.map(|b| json::Value::from(b.0.to_vec())),
            max: bounds.map(|b| json::Value::from(b.1.to_vec())),
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    /// Adds a triangle mesh of one primitive (its `attributes`, `indices` and `material`) and a
    /// node showing it, both named `name`.
    pub fn push_mesh_node(
        &mut self,
        name: &str,
        attributes: Vec<(json::mesh::Semantic, json::Index<json::Accessor>)>,
        indices: json::Index<json::Accessor>,
        material: json::Index<json::Material>,
    ) {
        let mesh = self.root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some(name.to_string()),
            primitives: vec![json::mesh::Primitive {
                attributes: attributes.into_iter().map(|(s, a)| (Valid(s), a)).collect(),
                extensions: None,
                extras: Default::default(),
                indices: Some(indices),
                material: Some(material),
                mode: Valid(json::mesh::Mode::Triangles),
                targets: None,
            }],
            weights: None,
        });
        let node = self.root.push(json::Node {
            mesh: Some(mesh),
            name: Some(name.to_string()),
            ..Default::default()
        });
        self.nodes.push(node);
    }

    /// Adds the buffer and one scene of every node (named `scene`, the asset's `generator`),
    /// serialises the JSON and wraps both chunks in a GLB.
    pub fn finish(mut self, scene: String, generator: String) -> Result<Vec<u8>, GlbError> {
        self.root.push(json::Buffer {
            byte_length: USize64::from(self.bin.len()),
            name: None,
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
        let scene = self.root.push(json::Scene {
            extensions: None,
            extras: Default::default(),
            name: Some(scene),
            nodes: std::mem::take(&mut self.nodes),
        });
        self.root.scene = Some(scene);
        self.root.asset.generator = Some(generator);
        let json = self.root.to_vec()?;
        glb_container(&json, &self.bin)
    }
}

/// Little-endian bytes of packed f32 values.
pub fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// Little-endian bytes of u32 values.
pub fn u32_bytes(values: &[u32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// A GLB file: 12-byte header ("glTF", version 2, total length), the JSON chunk padded with
/// spaces to 4 bytes, and (when `bin` is not empty) the BIN chunk padded with zeros.
pub fn glb_container(json: &[u8], bin: &[u8]) -> Result<Vec<u8>, GlbError> {
    let json_len = json.len().next_multiple_of(4);
    let bin_len = bin.len().next_multiple_of(4);
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin_len };
    let total = 12 + 8 + json_len as u64 + bin_chunk as u64;
    let Ok(total32) = u32::try_from(total) else {
        return Err(GlbError::TooLarge { bytes: total });
    };
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(json_len as u32).to_le_bytes());
    out.extend_from_slice(&CHUNK_JSON.to_le_bytes());
    out.extend_from_slice(json);
    out.resize(20 + json_len, b' ');
    if !bin.is_empty() {
        out.extend_from_slice(&(bin_len as u32).to_le_bytes());
        out.extend_from_slice(&CHUNK_BIN.to_le_bytes());
        out.extend_from_slice(bin);
        out.resize(total as usize, 0);
    }
    Ok(out)
}
