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
//! each attribute in its own tightly packed buffer view (assembled by `snowscape_io::glb`, the
//! project's one GLB writer).

use crate::RenderError;
use crate::mesh::{HeightSource, choose_step, surface_mesh};
use snowscape_io::glb::{GlbDocument, GlbError, f32_bytes, gltf_json as json, u32_bytes};
use snowscape_mesh::TriMesh;
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
    let mut doc = GlbDocument::default();
    add_surface(
        &mut doc,
        "terrain",
        &rock,
        "rock",
        ROCK_BASE_COLOUR,
        ROCK_ROUGHNESS,
    );
    if let Some(snow) = &snow {
        add_surface(
            &mut doc,
            "snow",
            snow,
            "snow",
            SNOW_BASE_COLOUR,
            SNOW_ROUGHNESS,
        );
    }
    doc.finish(
        format!("snowscape terrain (y = 0 at {base} m altitude)"),
        format!("snowscape-render {}", env!("CARGO_PKG_VERSION")),
    )
    .map_err(|e| match e {
        GlbError::TooLarge { bytes } => RenderError::GlbTooLarge { bytes },
        GlbError::Json(e) => RenderError::Json(e),
    })
}

/// Adds `mesh` with its material (named, coloured, rough) and a node, all under `name`.
fn add_surface(
    doc: &mut GlbDocument,
    name: &str,
    mesh: &TriMesh,
    material_name: &str,
    colour: [f32; 4],
    roughness: f32,
) {
    use json::accessor::{ComponentType as C, Type as T};
    let n = mesh.positions.len();
    let positions = doc.push_accessor(
        &f32_bytes(mesh.positions.as_flattened()),
        n,
        (C::F32, T::Vec3),
        mesh.bounds().map(|b| (b.min, b.max)),
    );
    let normals = doc.push_accessor(
        &f32_bytes(mesh.normals.as_deref().unwrap_or_default().as_flattened()),
        n,
        (C::F32, T::Vec3),
        None,
    );
    let indices = doc.push_accessor(
        &u32_bytes(mesh.triangles.as_flattened()),
        3 * mesh.triangles.len(),
        (C::U32, T::Scalar),
        None,
    );
    let material = doc.root.push(json::Material {
        name: Some(material_name.to_string()),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            base_color_factor: json::material::PbrBaseColorFactor(colour),
            metallic_factor: json::material::StrengthFactor(0.0),
            roughness_factor: json::material::StrengthFactor(roughness),
            ..Default::default()
        },
        ..Default::default()
    });
    doc.push_mesh_node(
        name,
        vec![
            (json::mesh::Semantic::Positions, positions),
            (json::mesh::Semantic::Normals, normals),
        ],
        indices,
        material,
    );
}
