//! Snow-mesh output: [`SnowMesh`] (scene metres, z up) written as binary glTF ([`glb`]) or as
//! OBJ + MTL + PNG texture ([`obj`]), converted back into the input's own axes and units with
//! its [`SourceFrame`](crate::SourceFrame), so the snow lies exactly on the user's scene. Every file goes through
//! [`snowscape_io::write_atomic`]: a temporary file renamed when complete.

pub mod glb;
pub mod obj;

pub use glb::{SNOW_BASE_COLOUR, SNOW_ROUGHNESS, glb_bytes, write_glb};
pub use obj::write_obj;

use crate::MeshError;
use crate::scene::{SceneObject, cross, norm};
use image::RgbaImage;

/// A triangle mesh to write (snow, or any scene object), in scene metres, z up.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SnowMesh {
    pub name: String,
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals, one per position; empty to have them computed (area-weighted).
    pub normals: Vec<[f32; 3]>,
    /// Texture coordinates, one per position, glTF convention: u right, v down from the top
    /// left of the image.
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Counter-clockwise triangles (seen from outside).
    pub triangles: Vec<[u32; 3]>,
    /// RGBA base colour texture; its alpha is a mask (cut at 0.5): snow where alpha is high.
    pub texture: Option<RgbaImage>,
}

impl SnowMesh {
    /// A scene object as a mesh to write (its normals, or computed ones).
    pub fn from_object(object: &SceneObject) -> Self {
        let mut m = SnowMesh {
            name: object.name.clone(),
            positions: object.positions.clone(),
            normals: object.normals.clone().unwrap_or_default(),
            uvs: None,
            triangles: object.triangles.clone(),
            texture: None,
        };
        if m.normals.is_empty() {
            m.normals = vertex_normals(&m.positions, &m.triangles);
        }
        m
    }

    /// Checks lengths, indices and finiteness; fills in missing normals.
    pub(crate) fn checked(&self) -> Result<std::borrow::Cow<'_, SnowMesh>, MeshError> {
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
        if !self.normals.is_empty() && self.normals.len() != n {
            return Err(bad(format!(
                "{} normals for {n} vertices",
                self.normals.len()
            )));
        }
        if let Some(uvs) = &self.uvs
            && uvs.len() != n
        {
            return Err(bad(format!(
                "{} texture coordinates for {n} vertices",
                uvs.len()
            )));
        }
        if self.normals.is_empty() {
            let mut m = self.clone();
            m.normals = vertex_normals(&m.positions, &m.triangles);
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
