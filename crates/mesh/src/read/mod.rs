//! Mesh input: OBJ ([`obj`], tobj), PLY ([`ply`], ply-rs-bw, ASCII and binary) and glTF 2.0
//! ([`gltf`], `.gltf` with external or embedded buffers and `.glb`).
//!
//! [`read_scene`] picks the reader from the extension, converts the file's coordinates into the
//! scene frame (z up, metres; see [`crate::scene`]) and checks the result with the rules of
//! [`crate::report`]: NaN/infinite vertices and out-of-range indices are typed errors naming the
//! file, object, vertex and face; degenerate triangles are dropped and counted; open and
//! non-manifold edges are counted in the [`MeshReport`].
//!
//! # Limits
//!
//! Every reader refuses, with a typed error naming the file, the line (text formats) and the
//! value, data beyond these documented limits, *before* loading it (a linear scan of the OBJ
//! text, the PLY header, the glTF accessor counts), so memory stays bounded by the limits:
//! - [`MAX_MESH_BYTES`] (4 GiB) per file or glTF buffer;
//! - [`MAX_VERTICES`] (10 million) vertices and [`MAX_TRIANGLES`] (10 million) triangles per
//!   file (polygons counted as the triangles of their fan; glTF nodes that reuse a mesh count it
//!   each time): about 1.5 GiB of memory while reading at the limits;
//! - [`MAX_FACE_CORNERS`] (1024) corners per polygon: a polygon is split into a fan of
//!   triangles around its first corner (linear time), and a fan of a million triangles around one
//!   vertex would make the covers' neighbour searches quadratic;
//! - every vertex coordinate, in scene metres (after the scale), within ±[`MAX_COORDINATE_M`]
//!   (10,000 km): [`MeshError::CoordinateTooLarge`] (NaN and infinity are
//!   [`MeshError::NonFiniteVertex`]);
//! - the scene's extent (diagonal of its box) at most [`MAX_EXTENT_TO_FEATURE`] (10^6) times its
//!   smallest kept triangle (longest edge): beyond that, 32-bit coordinates quantise the smallest
//!   triangles and the covers' grids cannot resolve them ([`MeshError::ExtentTooLarge`]).
//!
//! Triangles repeated with the same corners in the same order (an OBJ line pasted a million
//! times) are dropped and counted like degenerate ones ([`crate::ObjectReport::duplicates_dropped`]).

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
        MeshFormat::Obj => obj::read_raw(path, frame)?,
        MeshFormat::Ply => ply::read_raw(path)?,
        MeshFormat::Gltf => gltf::read_raw(path)?,
    };
    check_objects(path, raws, frame)
}

/// Most vertices in one file (see the module's limits).
pub const MAX_VERTICES: u64 = 10_000_000;
/// Most triangles in one file, polygons counted as their fans (see the module's limits).
pub const MAX_TRIANGLES: u64 = 10_000_000;
/// Most corners of one polygon (see the module's limits).
pub const MAX_FACE_CORNERS: u64 = 1024;
/// Largest magnitude of a vertex coordinate in scene metres, after the scale: 10,000 km.
pub const MAX_COORDINATE_M: f64 = 1e7;
/// Largest ratio of the scene's extent to its smallest kept triangle's longest edge.
pub const MAX_EXTENT_TO_FEATURE: f64 = 1e6;

/// A running count of what a reader has accepted, refusing the first step past a limit.
#[derive(Debug, Default)]
pub(crate) struct Tally {
    pub vertices: u64,
    pub triangles: u64,
}

impl Tally {
    /// Adds `vertices` vertices and a face of `corners` corners (0 for none) found at `line`.
    pub fn add(
        &mut self,
        path: &Path,
        line: Option<usize>,
        vertices: u64,
        corners: u64,
    ) -> Result<(), MeshError> {
        let too_large = |what, value, limit| MeshError::TooLarge {
            path: path.to_path_buf(),
            line,
            what,
            value,
            limit,
        };
        if corners > MAX_FACE_CORNERS {
            return Err(too_large("corners of one face", corners, MAX_FACE_CORNERS));
        }
        self.vertices = self.vertices.saturating_add(vertices);
        if self.vertices > MAX_VERTICES {
            return Err(too_large("vertex count", self.vertices, MAX_VERTICES));
        }
        self.triangles = self.triangles.saturating_add(corners.saturating_sub(2));
        if self.triangles > MAX_TRIANGLES {
            return Err(too_large("triangle count", self.triangles, MAX_TRIANGLES));
        }
        Ok(())
    }

    /// Adds `triangles` triangles (of a glTF primitive), refusing a total past the limit.
    pub fn add_triangles(&mut self, path: &Path, triangles: u64) -> Result<(), MeshError> {
        self.triangles = self.triangles.saturating_add(triangles);
        if self.triangles > MAX_TRIANGLES {
            return Err(MeshError::TooLarge {
                path: path.to_path_buf(),
                line: None,
                what: "triangle count",
                value: self.triangles,
                limit: MAX_TRIANGLES,
            });
        }
        Ok(())
    }
}

/// Text from a file (a line, a token, an object name) as an error quotes it: at most
/// [`snowscape_io::error::MAX_ECHO`] characters, so a corrupt file cannot put megabytes into
/// a message.
pub(crate) fn echo(text: &str) -> String {
    snowscape_io::error::clip(text, snowscape_io::error::MAX_ECHO)
}

/// The largest mesh file (or glTF buffer) read: 4 GiB.
pub const MAX_MESH_BYTES: u64 = 1 << 32;

/// Reads a whole regular file of at most [`MAX_MESH_BYTES`] (devices and FIFOs are refused
/// before anything is opened, see [`snowscape_io::input`]), naming it in the error.
pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>, MeshError> {
    Ok(snowscape_io::input::read_regular(path, MAX_MESH_BYTES)?)
}
