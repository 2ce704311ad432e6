//! Typed errors of mesh input and output. Every variant names the file (where there is one)
//! and the offending value and where it was found (object, vertex, face, line), so a user can
//! fix the input.

use snowscape_io::AtomicWriteError;
use std::path::PathBuf;
use thiserror::Error;

/// Why a mesh could not be read, checked or written.
#[derive(Debug, Error)]
pub enum MeshError {
    /// The file could not be opened or read.
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file is not a regular file (device, FIFO, directory) or too large to read.
    #[error(transparent)]
    Input(snowscape_io::InputError),
    /// A glTF buffer URI that points outside the glTF file's folder (`../x.bin`, an absolute
    /// path, another scheme): a mesh may not read arbitrary files as vertex data.
    #[error(
        "{path}: buffer {buffer} has uri {uri:?}, which is outside the folder of the glTF \
         file ({reason}); buffers must lie in that folder or below it"
    )]
    BufferOutsideFolder {
        path: PathBuf,
        buffer: usize,
        uri: String,
        reason: &'static str,
    },
    /// The format could not be told from the file name.
    #[error(
        "cannot tell the mesh format of {path} from its extension {extension:?}; \
         use .obj, .ply, .glb or .gltf"
    )]
    UnknownFormat { path: PathBuf, extension: String },
    /// The file is not a valid file of its format (truncated, malformed...).
    #[error("{path}: invalid {format} file{}: {message}", line.map(|l| format!(" at line {l}")).unwrap_or_default())]
    Parse {
        path: PathBuf,
        format: &'static str,
        line: Option<usize>,
        message: String,
    },
    /// A feature of the format that this reader does not handle.
    #[error("{path}: {what} is not supported")]
    Unsupported { path: PathBuf, what: String },
    /// A vertex position (or normal) is NaN or infinite.
    #[error(
        "{path}: object {object:?} vertex {vertex} is not finite: {value:?} \
         (NaN or infinite coordinates)"
    )]
    NonFiniteVertex {
        path: PathBuf,
        object: String,
        vertex: usize,
        value: [f32; 3],
    },
    /// The file holds more than a documented limit of [`crate::read`] allows (vertices,
    /// triangles, corners of one face): refused by a linear scan before the data is loaded.
    #[error(
        "{path}{}: {what} {value} exceeds the limit of {limit} (see snowscape_mesh::read's limits)",
        line.map(|l| format!(" line {l}")).unwrap_or_default()
    )]
    TooLarge {
        path: PathBuf,
        /// The line (text formats) where the limit was passed.
        line: Option<usize>,
        what: &'static str,
        value: u64,
        limit: u64,
    },
    /// A vertex coordinate, once scaled into scene metres, lies beyond
    /// [`crate::read::MAX_COORDINATE_M`] (absurd geometry, or a wrong `--scale`).
    #[error(
        "{path}: object {object:?} vertex {vertex}{} is {value:?} in the file, {metres:e} m in \
         the scene: beyond the limit of ±{limit_m:e} m (check the scale)",
        line.map(|l| format!(" (line {l})")).unwrap_or_default()
    )]
    CoordinateTooLarge {
        path: PathBuf,
        object: String,
        vertex: usize,
        line: Option<usize>,
        value: [f32; 3],
        metres: f64,
        limit_m: f64,
    },
    /// The scene's extent is too many times its smallest triangle for the covers' grids and
    /// 32-bit coordinates ([`crate::read::MAX_EXTENT_TO_FEATURE`]).
    #[error(
        "{path}: the scene is {extent_m:e} m across but object {object:?} triangle {triangle} is \
         only {feature_m:e} m long: a ratio of {ratio:e}, beyond the {limit:e} that the covers' \
         grids and 32-bit coordinates can represent"
    )]
    ExtentTooLarge {
        path: PathBuf,
        object: String,
        triangle: usize,
        extent_m: f64,
        feature_m: f64,
        ratio: f64,
        limit: f64,
    },
    /// A face refers to a vertex that does not exist.
    #[error(
        "{path}: object {object:?} face {face} refers to vertex {index}, \
         but the object has {vertex_count} vertices"
    )]
    IndexOutOfRange {
        path: PathBuf,
        object: String,
        face: usize,
        index: i64,
        vertex_count: usize,
    },
    /// The file holds no usable triangle (no faces, or only degenerate ones).
    #[error("{path}: no usable triangle ({reason})")]
    EmptyMesh { path: PathBuf, reason: String },
    /// An option or parameter outside its valid range.
    #[error("invalid {name} {value}: expected {expected}")]
    InvalidOption {
        name: &'static str,
        value: String,
        expected: &'static str,
    },
    /// A mesh handed to a writer is inconsistent (lengths, indices, non-finite values).
    #[error("mesh {mesh:?} cannot be written: {reason}")]
    InvalidMesh { mesh: String, reason: String },
    /// The output could not be written (nothing is left at the target path).
    #[error(transparent)]
    Write(#[from] AtomicWriteError),
    /// A grid that cannot become a mesh (over 2^32 vertices).
    #[error("grid as a mesh: {0}")]
    Grid(#[from] snowscape_terrain::TerrainError),
    /// The output could not be encoded (glTF JSON, PNG...).
    #[error("cannot encode {path}: {message}")]
    Encode { path: PathBuf, message: String },
}

impl From<snowscape_io::InputError> for MeshError {
    /// An I/O failure stays [`MeshError::Io`]; a refused file is [`MeshError::Input`].
    fn from(e: snowscape_io::InputError) -> Self {
        match e {
            snowscape_io::InputError::Io { path, source } => MeshError::Io { path, source },
            other => MeshError::Input(other),
        }
    }
}

impl MeshError {
    /// A [`MeshError::Parse`] without a line number.
    pub(crate) fn parse(
        path: &std::path::Path,
        format: &'static str,
        message: impl ToString,
    ) -> Self {
        MeshError::Parse {
            path: path.to_path_buf(),
            format,
            line: None,
            message: message.to_string(),
        }
    }
}
