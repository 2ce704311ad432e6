//! Snow-mesh output: [`SnowObject`] (scene metres, z up) written as binary glTF ([`glb`]) or as
//! OBJ + MTL + PNG texture ([`obj`]), converted back into the input's own axes and units with
//! its [`SourceFrame`](crate::SourceFrame), so the snow lies exactly on the user's scene. Every file goes through
//! [`snowscape_io::write_atomic`]: a temporary file renamed when complete.

pub mod glb;
pub mod obj;

pub use glb::{SNOW_BASE_COLOUR, SNOW_ROUGHNESS, glb_bytes, write_glb};
pub use obj::write_obj;

use crate::MeshError;
use crate::scene::{SceneObject, TriMesh, cross, norm};
use image::RgbaImage;

/// What the snow writers write: one [`TriMesh`] in the scene frame (metres, z up; its `normals`
/// `None` to have them computed, area-weighted; its `uvs` mapping the texture) and its
/// material's optional texture. It reads as its mesh (`Deref`): `m.positions`, `m.triangles`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SnowObject {
    /// The mesh: name, positions, normals, texture coordinates, counter-clockwise triangles
    /// (seen from outside).
    pub mesh: TriMesh,
    /// RGBA base colour texture, sampled at the mesh's `uvs`; its alpha is a mask (cut at 0.5):
    /// snow where alpha is high. Ignored when the mesh has no texture coordinates.
    pub texture: Option<RgbaImage>,
}

impl std::ops::Deref for SnowObject {
    type Target = TriMesh;
    fn deref(&self) -> &TriMesh {
        &self.mesh
    }
}

impl std::ops::DerefMut for SnowObject {
    fn deref_mut(&mut self) -> &mut TriMesh {
        &mut self.mesh
    }
}

impl SnowObject {
    /// An untextured object of `mesh` (normals as given: missing ones are computed when it is
    /// written, after its indices are checked).
    pub fn new(mesh: TriMesh) -> Self {
        SnowObject {
            mesh,
            texture: None,
        }
    }

    /// `mesh` with its `texture` (sampled at the mesh's `uvs`).
    pub fn textured(mesh: TriMesh, texture: RgbaImage) -> Self {
        SnowObject {
            mesh,
            texture: Some(texture),
        }
    }

    /// A scene object (checked when it was read) as an object to write: its normals, or computed
    /// ones.
    pub fn from_object(object: &SceneObject) -> Self {
        let mut mesh = object.clone();
        if mesh.normals.as_ref().is_none_or(Vec::is_empty) {
            mesh.normals = Some(vertex_normals(&mesh.positions, &mesh.triangles));
        }
        Self::new(mesh)
    }

    /// The unit vertex normals (empty until computed: see [`SnowObject::checked`]).
    pub fn normals(&self) -> &[[f32; 3]] {
        self.mesh.normals.as_deref().unwrap_or_default()
    }

    /// Checks lengths, indices and finiteness (positions, normals, texture coordinates: no NaN
    /// or infinity is ever written); fills in missing normals.
    pub(crate) fn checked(&self) -> Result<std::borrow::Cow<'_, SnowObject>, MeshError> {
        let bad = |reason: String| MeshError::InvalidMesh {
            mesh: self.name.clone(),
            reason,
        };
        let n = self.positions.len();
        if self.triangles.is_empty() {
            return Err(bad("no triangles".into()));
        }
        if let Some(v) = self
            .positions
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(bad(format!(
                "vertex {v} is not finite: {:?}",
                self.positions[v]
            )));
        }
        if let Some((t, tri)) = self
            .triangles
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&i| i as usize >= n))
        {
            return Err(bad(format!(
                "triangle {t} {tri:?} refers past the {n} vertices"
            )));
        }
        let normals = self.normals();
        if !normals.is_empty() && normals.len() != n {
            return Err(bad(format!("{} normals for {n} vertices", normals.len())));
        }
        if let Some(uvs) = &self.uvs
            && uvs.len() != n
        {
            return Err(bad(format!(
                "{} texture coordinates for {n} vertices",
                uvs.len()
            )));
        }
        if let Some(v) = normals
            .iter()
            .position(|n| !n.iter().all(|c| c.is_finite()))
        {
            return Err(bad(format!("normal {v} is not finite: {:?}", normals[v])));
        }
        if let Some(uvs) = &self.uvs
            && let Some(v) = uvs.iter().position(|t| !t.iter().all(|c| c.is_finite()))
        {
            return Err(bad(format!(
                "texture coordinate {v} is not finite: {:?}",
                uvs[v]
            )));
        }
        if normals.is_empty() {
            let mut m = self.clone();
            m.mesh.normals = Some(vertex_normals(&m.positions, &m.triangles));
            return Ok(std::borrow::Cow::Owned(m));
        }
        Ok(std::borrow::Cow::Borrowed(self))
    }
}

/// Area-weighted unit vertex normals (a vertex used by no triangle gets +z).
pub fn vertex_normals(positions: &[[f32; 3]], triangles: &[[u32; 3]]) -> Vec<[f32; 3]> {
    let mut acc = vec![[0.0f64; 3]; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize].map(f64::from));
        let n = cross(
            [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
            [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
        );
        for &i in t {
            for k in 0..3 {
                acc[i as usize][k] += n[k];
            }
        }
    }
    acc.into_iter()
        .map(|n| {
            let l = norm(n);
            if l > 0.0 {
                n.map(|c| (c / l) as f32)
            } else {
                [0.0, 0.0, 1.0]
            }
        })
        .collect()
}

/// PNG bytes of an RGBA image.
pub(crate) fn png_bytes(img: &RgbaImage, path: &std::path::Path) -> Result<Vec<u8>, MeshError> {
    use image::ImageEncoder;
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            image::ExtendedColorType::Rgba8,
        )
        .map_err(|e| MeshError::Encode {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
    Ok(out)
}
