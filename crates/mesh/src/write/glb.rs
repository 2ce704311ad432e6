//! Binary glTF 2.0 (GLB) output of snow meshes, through the project's one GLB writer
//! (`snowscape_io::glb`, as `snowscape-render`'s terrain GLB): one scene, one node and mesh per [`SnowObject`], one triangle primitive each (POSITION
//! with min/max, NORMAL, optional TEXCOORD_0, u32 indices), one buffer in the BIN chunk with
//! each attribute in its own tightly packed, 4-byte aligned buffer view. A mesh's texture is
//! embedded as a PNG buffer view and used as the base colour texture, alpha mode MASK (cut at
//! 0.5); without a texture the material is plain snow white.
//!
//! Coordinates are the input's own (see [`SourceFrame`]): for a y-up file in centimetres the
//! GLB is y-up in centimetres, so it drops onto the input scene in any tool.

use super::{SnowObject, png_bytes};
use crate::MeshError;
use crate::scene::{Bounds, SourceFrame};
use json::validation::Checked::Valid;
use snowscape_io::glb::{GlbDocument, f32_bytes, gltf_json as json, u32_bytes};
use std::path::Path;

/// Snow material base colour (linear RGBA), as in the terrain GLB.
pub const SNOW_BASE_COLOUR: [f32; 4] = [0.92, 0.94, 0.97, 1.0];
/// Snow material roughness.
pub const SNOW_ROUGHNESS: f32 = 0.7;

/// Writes `meshes` to `path` as a GLB, atomically, in `frame`'s axes and units.
pub fn write_glb(path: &Path, meshes: &[SnowObject], frame: &SourceFrame) -> Result<(), MeshError> {
    let bytes = glb_bytes(meshes, frame, path)?;
    snowscape_io::write_bytes_atomic(path, &bytes)?;
    Ok(())
}

/// The GLB file of `meshes` (`path` only names the output in errors).
pub fn glb_bytes(
    meshes: &[SnowObject],
    frame: &SourceFrame,
    path: &Path,
) -> Result<Vec<u8>, MeshError> {
    let mut doc = GlbDocument::default();
    for mesh in meshes {
        let mesh = mesh.checked()?;
        add_mesh(&mut doc, &mesh, frame, path)?;
    }
    doc.finish(
        "snowscape snow".into(),
        format!("snowscape-mesh {}", env!("CARGO_PKG_VERSION")),
    )
    .map_err(|e| MeshError::Encode {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// Adds `mesh` (in `frame`'s axes and units), its material and texture, and a node.
fn add_mesh(
    doc: &mut GlbDocument,
    mesh: &SnowObject,
    frame: &SourceFrame,
    path: &Path,
) -> Result<(), MeshError> {
    use json::accessor::{ComponentType as C, Type as T};
    let positions: Vec<[f32; 3]> = mesh.positions.iter().map(|p| frame.to_file(*p)).collect();
    let normals: Vec<[f32; 3]> = mesh
        .normals()
        .iter()
        .map(|n| frame.direction_to_file(*n))
        .collect();
    let n = positions.len();
    let bounds = Bounds::of_points(&positions).map(|b| (b.min, b.max));
    let pos = doc.push_accessor(
        &f32_bytes(positions.as_flattened()),
        n,
        (C::F32, T::Vec3),
        bounds,
    );
    let nor = doc.push_accessor(
        &f32_bytes(normals.as_flattened()),
        n,
        (C::F32, T::Vec3),
        None,
    );
    let mut attributes = vec![
        (json::mesh::Semantic::Positions, pos),
        (json::mesh::Semantic::Normals, nor),
    ];
    if let Some(uvs) = &mesh.uvs {
        let uv = doc.push_accessor(&f32_bytes(uvs.as_flattened()), n, (C::F32, T::Vec2), None);
        attributes.push((json::mesh::Semantic::TexCoords(0), uv));
    }
    let indices = doc.push_accessor(
        &u32_bytes(mesh.triangles.as_flattened()),
        mesh.triangles.len() * 3,
        (C::U32, T::Scalar),
        None,
    );
    let texture = match &mesh.texture {
        Some(img) if mesh.uvs.is_some() => Some(push_texture(doc, img, &mesh.name, path)?),
        _ => None,
    };
    let material = doc.root.push(json::Material {
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
    doc.push_mesh_node(&mesh.name, attributes, indices, material);
    Ok(())
}

/// Embeds `img` as a PNG buffer view, with its image, sampler and texture.
fn push_texture(
    doc: &mut GlbDocument,
    img: &image::RgbaImage,
    name: &str,
    path: &Path,
) -> Result<json::Index<json::Texture>, MeshError> {
    let png = png_bytes(img, path)?;
    let view = doc.push_view(&png, None);
    let image = doc.root.push(json::Image {
        buffer_view: Some(view),
        mime_type: Some(json::image::MimeType("image/png".into())),
        name: Some(format!("{name} texture")),
        uri: None,
        extensions: None,
        extras: Default::default(),
    });
    let sampler = doc.root.push(json::texture::Sampler::default());
    Ok(doc.root.push(json::Texture {
        name: None,
        sampler: Some(sampler),
        source: image,
        extensions: None,
        extras: Default::default(),
    }))
}
