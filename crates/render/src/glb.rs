//! Binary glTF 2.0 (GLB) export of the bedrock and the snow surface.
//!
//! Layout of the file: one scene with up to two nodes, each with one mesh of one triangle
//! primitive (POSITION with min/max bounds, NORMAL, u32 indices; no vertex colours):
//! - node/mesh "terrain": the bedrock, material "rock" (grey-brown, rough);
//! - node/mesh "snow" (when `include_snow` and some snow lies deeper than
//!   [`SNOW_MESH_MIN_DEPTH_M`]): the snow surface `bedrock + depth` over triangles whose three
//!   corners carry such snow, material "snow" (white). Thinner cover is left to the rock mesh,
//!   so the snow sheet never z-fights with the bedrock.
//!
//! Coordinates (see [`crate::mesh`]): metres, y up, x east, z south, centred horizontally on
//! the grid centre; y = 0 at the lowest valid bedrock altitude (the scene's name records that
//! altitude). Nodata cells produce no triangles. One buffer, stored in the GLB's BIN chunk, holds
//! each attribute in its own tightly packed buffer view.

use crate::RenderError;
use crate::mesh::{HeightSource, SurfaceMesh, choose_step, surface_mesh};
use gltf_json as json;
use json::validation::{Checked::Valid, USize64};
use snowscape_terrain::LayeredTerrain;

/// Snow thinner than this (metres) gets no snow-mesh triangle.
pub const SNOW_MESH_MIN_DEPTH_M: f32 = 0.01;
/// Rock material base colour (linear RGBA).
pub const ROCK_BASE_COLOUR: [f32; 4] = [0.30, 0.25, 0.20, 1.0];
/// Rock material roughness.
pub const ROCK_ROUGHNESS: f32 = 0.9;
/// Snow material base colour (linear RGBA).
pub const SNOW_BASE_COLOUR: [f32; 4] = [0.92, 0.94, 0.97, 1.0];
/// Snow material roughness.
pub const SNOW_ROUGHNESS: f32 = 0.7;

/// Options of [`terrain_glb`].
#[derive(Debug, Clone, PartialEq)]
pub struct GlbOptions {
    /// Keep every n-th grid vertex along each axis (the last row and column are always kept);
    /// 1 keeps every cell.
    pub decimation: usize,
    /// Largest total vertex count of the file (all meshes together); the decimation grows
    /// until each mesh's lattice fits its share. `None` = no limit.
    pub max_vertices: Option<usize>,
    /// Factor applied to heights (> 0; 1 = true relief).
    pub vertical_exaggeration: f64,
    /// Whether to add the snow-surface mesh.
    pub include_snow: bool,
}

impl Default for GlbOptions {
    /// Full resolution up to 4 M vertices (a 8192² grid is decimated by 6: 2 x 1.87 M).
    fn default() -> Self {
        Self {
            decimation: 1,
            max_vertices: Some(4_000_000),
            vertical_exaggeration: 1.0,
            include_snow: true,
        }
    }
}

/// The terrain (and its snow) as one binary glTF 2.0 file.
pub fn terrain_glb(terrain: &LayeredTerrain, opts: &GlbOptions) -> Result<Vec<u8>, RenderError> {
    let ex = opts.vertical_exaggeration;
    if !(ex.is_finite() && ex > 0.0) {
        return Err(RenderError::InvalidOption {
            name: "vertical_exaggeration",
            value: ex,
            expected: "a finite positive factor",
        });
    }
    let g = terrain.geometry();
    crate::planes::check_length("bedrock", &terrain.bedrock, g)?;
    for layer in snowscape_terrain::SnowLayer::ALL {
        let what = format!("{} snow layer", layer.name());
        crate::planes::check_length(&what, terrain.layer(layer), g)?;
    }
    let mesh_count = if opts.include_snow { 2 } else { 1 };
    let step = choose_step(
        g.width(),
        g.height(),
        opts.decimation,
        opts.max_vertices.map(|m| m / mesh_count),
    )?;
    let mask = terrain.mask();
    let valid = |i: usize| mask.is_valid(i);
    let base = (0..g.len())
        .filter(|&i| valid(i) && terrain.bedrock[i].is_finite())
        .map(|i| terrain.bedrock[i])
        .reduce(f32::min)
        .ok_or(RenderError::EmptyMesh {
            width: g.width(),
            height: g.height(),
        })?;
    let bedrock = |i: usize| terrain.bedrock[i];
    let rock_source = HeightSource {
        geometry: g,
        altitude: &bedrock,
        usable: &valid,
        what: "bedrock altitude",
    };
    let snowy = |i: usize| valid(i) && terrain.depth_at(i) > SNOW_MESH_MIN_DEPTH_M;
    let top = |i: usize| terrain.bedrock[i] + terrain.depth_at(i);
    let snow_source = HeightSource {
        geometry: g,
        altitude: &top,
        usable: &snowy,
        what: "snow surface altitude",
    };
    let (rock, snow) = rayon::join(
        || surface_mesh(&rock_source, step, base, ex as f32),
        || match opts.include_snow {
            true => surface_mesh(&snow_source, step, base, ex as f32),
            false => Ok(None),
        },
    );
    let rock = rock?.ok_or(RenderError::EmptyMesh {
        width: g.width(),
        height: g.height(),
    })?;
    let snow = snow?;
    let mut doc = Document::default();
    doc.add_surface("terrain", &rock, "rock", ROCK_BASE_COLOUR, ROCK_ROUGHNESS);
    if let Some(snow) = &snow {
        doc.add_surface("snow", snow, "snow", SNOW_BASE_COLOUR, SNOW_ROUGHNESS);
    }
    doc.finish(base)
}

/// A glTF document being assembled, with its binary buffer.
#[derive(Default)]
struct Document {
    root: json::Root,
    bin: Vec<u8>,
    nodes: Vec<json::Index<json::Node>>,
}

impl Document {
    /// Appends the bytes `write` produces as a buffer view (4-byte aligned) for `target`.
    fn push_view(
        &mut self,
        write: impl FnOnce(&mut Vec<u8>),
        target: json::buffer::Target,
    ) -> json::Index<json::buffer::View> {
        debug_assert!(self.bin.len().is_multiple_of(4));
        let offset = self.bin.len();
        write(&mut self.bin);
        let view = json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64::from(self.bin.len() - offset),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: Some(Valid(target)),
            extensions: None,
            extras: Default::default(),
        };
        self.root.push(view)
    }

    /// Appends an accessor over a fresh buffer view.
    fn push_accessor(
        &mut self,
        write: impl FnOnce(&mut Vec<u8>),
        count: usize,
        shape: (json::accessor::ComponentType, json::accessor::Type),
        bounds: Option<([f32; 3], [f32; 3])>,
    ) -> json::Index<json::Accessor> {
        let target = match shape.1 {
            json::accessor::Type::Scalar => json::buffer::Target::ElementArrayBuffer,
            _ => json::buffer::Target::ArrayBuffer,
        };
        let view = self.push_view(write, target);
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

    /// Adds a mesh with its material and a node.
    fn add_surface(
        &mut self,
        name: &str,
        mesh: &SurfaceMesh,
        material_name: &str,
        colour: [f32; 4],
        roughness: f32,
    ) {
        use json::accessor::{ComponentType as C, Type as T};
        let n = mesh.positions.len();
        let positions = self.push_accessor(
            |bin| write_vec3s(bin, &mesh.positions),
            n,
            (C::F32, T::Vec3),
            Some(mesh.bounds()),
        );
        let normals = self.push_accessor(
            |bin| write_vec3s(bin, &mesh.normals),
            n,
            (C::F32, T::Vec3),
            None,
        );
        let indices = self.push_accessor(
            |bin| write_u32s(bin, &mesh.indices),
            mesh.indices.len(),
            (C::U32, T::Scalar),
            None,
        );
        let material = self.root.push(json::Material {
            name: Some(material_name.to_string()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor(colour),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(roughness),
                ..Default::default()
            },
            ..Default::default()
        });
        let attributes = [
            (Valid(json::mesh::Semantic::Positions), positions),
            (Valid(json::mesh::Semantic::Normals), normals),
        ];
        let mesh = self.root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some(name.to_string()),
            primitives: vec![json::mesh::Primitive {
                attributes: attributes.into_iter().collect(),
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

    /// Adds the buffer and scene, serialises the JSON and wraps both chunks in a GLB.
    fn finish(mut self, base_altitude: f32) -> Result<Vec<u8>, RenderError> {
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
            name: Some(format!(
                "snowscape terrain (y = 0 at {base_altitude} m altitude)"
            )),
            nodes: std::mem::take(&mut self.nodes),
        });
        self.root.scene = Some(scene);
        self.root.asset.generator = Some(format!("snowscape-render {}", env!("CARGO_PKG_VERSION")));
        let json = self.root.to_vec()?;
        glb_container(&json, &self.bin)
    }
}

/// Appends packed f32 triples, little-endian.
fn write_vec3s(bin: &mut Vec<u8>, values: &[[f32; 3]]) {
    bin.reserve(values.len() * 12);
    for v in values {
        for c in v {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
}

/// Appends u32 values, little-endian.
fn write_u32s(bin: &mut Vec<u8>, values: &[u32]) {
    bin.reserve(values.len() * 4);
    for v in values {
        bin.extend_from_slice(&v.to_le_bytes());
    }
}

/// GLB chunk type of the JSON chunk ("JSON").
pub const CHUNK_JSON: u32 = 0x4E4F_534A;
/// GLB chunk type of the binary chunk ("BIN\0").
pub const CHUNK_BIN: u32 = 0x004E_4942;

/// A GLB file: 12-byte header ("glTF", version 2, total length), the JSON chunk padded with
/// spaces to 4 bytes, and (when `bin` is not empty) the BIN chunk padded with zeros.
pub fn glb_container(json: &[u8], bin: &[u8]) -> Result<Vec<u8>, RenderError> {
    let json_len = json.len().next_multiple_of(4);
    let bin_len = bin.len().next_multiple_of(4);
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin_len };
    let total = 12 + 8 + json_len as u64 + bin_chunk as u64;
    let Ok(total32) = u32::try_from(total) else {
        return Err(RenderError::GlbTooLarge { bytes: total });
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
