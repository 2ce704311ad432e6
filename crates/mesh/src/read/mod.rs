//! Mesh input: OBJ ([`obj`], tobj), PLY ([`ply`], ply-rs-bw, ASCII and binary) and glTF 2.0
//! ([`gltf`], `.gltf` with external or embedded buffers and `.glb`).
//!
//! [`read_scene`] picks the reader from the extension, converts the file's coordinates into the
//! scene frame (z up, metres; see [`crate::scene`]) and checks the result with the rules of
//! [`crate::report`]: NaN/infinite vertices and out-of-range indices are typed errors naming the
//! file, object, vertex and face; degenerate triangles are dropped and counted; open and
//! non-manifold edges are counted in the [`MeshReport`].

pub mod gltf;
pub mod obj;
pub mod ply;

use crate::MeshError;
use crate::report::{MeshReport, check_objects};
use crate::scene::{Scene, SourceFrame};
use std::path::Path;

/// The mesh file formats read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ (`.obj`): positions, normals, several objects (`o`/`g`).
    Obj,
    /// Stanford PLY (`.ply`), ASCII or binary: one object.
    Ply,
    /// glTF 2.0, JSON (`.gltf`) or binary (`.glb`): one object per node with a mesh.
    Gltf,
}

impl MeshFormat {
    /// The format named by `path`'s extension.
    pub fn from_path(path: &Path) -> Result<Self, MeshError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        match ext.as_str() {
            "obj" => Ok(MeshFormat::Obj),
            "ply" => Ok(MeshFormat::Ply),
            "gltf" | "glb" => Ok(MeshFormat::Gltf),
            _ => Err(MeshError::UnknownFormat {
                path: path.to_path_buf(),
                extension: ext,
            }),
        }
    }
}

/// Reads a mesh file into a scene (z up, metres) and reports what was checked and dropped.
pub fn read_scene(path: &Path, frame: &SourceFrame) -> Result<(Scene, MeshReport), MeshError> {
    let raws = match MeshFormat::from_path(path)? {
        MeshFormat::Obj => obj::read_raw(path)?,
        MeshFormat::Ply => ply::read_raw(path)?,
        MeshFormat::Gltf => gltf::read_raw(path)?,
    };
    check_objects(path, raws, frame)
}

/// The largest mesh file (or glTF buffer) read: 4 GiB.
pub const MAX_MESH_BYTES: u64 = 1 << 32;

/// Reads a whole regular file of at most [`MAX_MESH_BYTES`] (devices and FIFOs are refused
/// before anything is opened, see [`snowscape_io::input`]), naming it in the error.
pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>, MeshError> {
    Ok(snowscape_io::input::read_regular(path, MAX_MESH_BYTES)?)
}
