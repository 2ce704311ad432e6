//! Binary glTF 2.0 (GLB) output of snow meshes, in the style of `snowscape-render`'s terrain
//! GLB: one scene, one node and mesh per [`SnowMesh`], one triangle primitive each (POSITION
//! with min/max, NORMAL, optional TEXCOORD_0, u32 indices), one buffer in the BIN chunk with
//! each attribute in its own tightly packed, 4-byte aligned buffer view. A mesh's texture is
//! embedded as a PNG buffer view and used as the base colour texture, alpha mode MASK (cut at
//! 0.5); without a texture the material is plain snow white.
//!
//! Coordinates are the input's own (see [`SourceFrame`]): for a y-up file in centimetres the
//! GLB is y-up in centimetres, so it drops onto the input scene in any tool.

use super::{SnowMesh, png_bytes};
use crate::MeshError;
use crate::scene::{Bounds, SourceFrame};
use gltf_json as json;
use json::validation::{Checked::Valid, USize64};
use std::path::Path;

/// Snow material base colour (linear RGBA), as in the terrain GLB.
pub const SNOW_BASE_COLOUR: [f32; 4] = [0.92, 0.94, 0.97, 1.0];
/// Snow material roughness.
pub const SNOW_ROUGHNESS: f32 = 0.7;

/// Writes `meshes` to `path` as a GLB, atomically, in `frame`'s axes and units.
pub fn write_glb(path: &Path, meshes: &[SnowMesh], frame: &SourceFrame) -> Result<(), MeshError> {
    let bytes = glb_bytes(meshes, frame, path)?;
    snowscape_io::write_bytes_atomic(path, &bytes)?;
    Ok(())
}

/// The GLB file of `meshes` (`path` only names the output in errors).
pub fn glb_bytes(
    meshes: &[SnowMesh],
    frame: &SourceFrame,
    path: &Path,
) -> Result<Vec<u8>, MeshError> {
    let mut doc = Document::default();
    for mesh in meshes {
        let mesh = mesh.checked()?;
        doc.add_mesh(&mesh, frame, path)?;
    }
    doc.finish(path)
}

#[derive(Default)]
struct Document {
    root: json::Root,
    bin: Vec<u8>,
    nodes: Vec<json::Index<json::Node>>,
}

impl Document {
    fn push_view(
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
        // Keep every view 4-byte aligned.
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
        self.root.push(view)
    }

    fn push_accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        shape: (json::accessor::ComponentType, json::accessor::Type),
        bounds: Option<Bounds>,
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
            min: bounds.map(|b| json::Value::from(b.min.to_vec())),
            max: bounds.map(|b| json::Value::from(b.max.to_vec())),
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    fn add_mesh(
        &mut self,
        mesh: &SnowMesh,
        frame: &SourceFrame,
        path: &Path,
    ) -> Result<(), MeshError> {
        use json::accessor::{ComponentType as C, Type as T};
        let positions: Vec<[f32; 3]> = mesh.positions.iter().map(|p| frame.to_file(*p)).collect();
        let normals: Vec<[f32; 3]> = mesh
            .normals
            .iter()
            .map(|n| frame.direction_to_file(*n))
            .collect();
        let n = positions.len();
        let bounds = Bounds::of_points(&positions);
        let pos = self.push_accessor(
            &f32_bytes(positions.as_flattened()),
            n,
            (C::F32, T::Vec3),
            bounds,
        );
        let nor = self.push_accessor(
            &f32_bytes(normals.as_flattened()),
            n,
            (C::F32, T::Vec3),
            None,
        );
        let mut attributes = vec![
            (Valid(json::mesh::Semantic::Positions), pos),
            (Valid(json::mesh::Semantic::Normals), nor),
        ];
        if let Some(uvs) = &mesh.uvs {
            let uv = self.push_accessor(&f32_bytes(uvs.as_flattened()), n, (C::F32, T::Vec2), None);
            attributes.push((Valid(json::mesh::Semantic::TexCoords(0)), uv));
        }
        let index_bytes: Vec<u8> = mesh
            .triangles
            .as_flattened()
            .iter()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let indices = self.push_accessor(
            &index_bytes,
            mesh.triangles.len() * 3,
            (C::U32, T::Scalar),
            None,
        );
        let texture = match &mesh.texture {
            Some(img) if mesh.uvs.is_some() => Some(self.push_texture(img, &mesh.name, path)?),
            _ => None,
        };
        let material = self.root.push(json::Material {
            name: Some(format!("{} snow", mesh.name)),
            alpha_mode: Valid(match texture {
                Some(_) => json::material::AlphaMode::Mask,
                None => json::material::AlphaMode::Opaque,
            }),
            alpha_cutoff: texture.map(|_| json::material::AlphaCutoff(0.5)),
            double_sided: true,
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor(match texture {
                    Some(_) => [1.0; 4],
                    None => SNOW_BASE_COLOUR,
                }),
                base_color_texture: texture.map(|index| json::texture::Info {
                    index,
                    tex_coord: 0,
                    extensions: None,
                    extras: Default::default(),
                }),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(SNOW_ROUGHNESS),
                ..Default::default()
            },
            ..Default::default()
        });
        let gl_mesh = self.root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some(mesh.name.clone()),
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
            mesh: Some(gl_mesh),
            name: Some(mesh.name.clone()),
            ..Default::default()
        });
        self.nodes.push(node);
        Ok(())
    }

    fn push_texture(
        &mut self,
        img: &image::RgbaImage,
        name: &str,
        path: &Path,
    ) -> Result<json::Index<json::Texture>, MeshError> {
        let png = png_bytes(img, path)?;
        let view = self.push_view(&png, None);
        let image = self.root.push(json::Image {
            buffer_view: Some(view),
            mime_type: Some(json::image::MimeType("image/png".into())),
            name: Some(format!("{name} texture")),
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
        let sampler = self.root.push(json::texture::Sampler::default());
        Ok(self.root.push(json::Texture {
            name: None,
            sampler: Some(sampler),
            source: image,
            extensions: None,
            extras: Default::default(),
        }))
    }

    fn finish(mut self, path: &Path) -> Result<Vec<u8>, MeshError> {
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
            name: Some("snowscape snow".into()),
            nodes: std::mem::take(&mut self.nodes),
        });
        self.root.scene = Some(scene);
        self.root.asset.generator = Some(format!("snowscape-mesh {}", env!("CARGO_PKG_VERSION")));
        let encode = |message: String| MeshError::Encode {
            path: path.to_path_buf(),
            message,
        };
        let json = self.root.to_vec().map_err(|e| encode(e.to_string()))?;
        glb_container(&json, &self.bin).map_err(encode)
    }
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|c| c.to_le_bytes()).collect()
}

/// A GLB: 12-byte header, the JSON chunk padded with spaces, the BIN chunk padded with zeros.
fn glb_container(json: &[u8], bin: &[u8]) -> Result<Vec<u8>, String> {
    let json_len = json.len().next_multiple_of(4);
    let bin_len = bin.len().next_multiple_of(4);
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin_len };
    let total = 12 + 8 + json_len + bin_chunk;
    let total32 =
        u32::try_from(total).map_err(|_| format!("{total} bytes is over the 4 GiB GLB limit"))?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(json_len as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(json);
    out.resize(20 + json_len, b' ');
    if !bin.is_empty() {
        out.extend_from_slice(&(bin_len as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(bin);
        out.resize(total, 0);
    }
    Ok(out)
}
