//! Typed errors of the renderer. Each variant carries the offending values.

use thiserror::Error;

/// A rendering, encoding or export failure.
#[derive(Debug, Error)]
pub enum RenderError {
    /// A numeric option outside its valid range.
    #[error("invalid option {name} = {value}: {expected}")]
    InvalidOption {
        name: &'static str,
        value: f64,
        expected: &'static str,
    },
    /// A count option (size, decimation, vertex budget) outside its valid range.
    #[error("invalid option {name} = {value}: {expected}")]
    InvalidCount {
        name: &'static str,
        value: usize,
        expected: &'static str,
    },
    /// A layer or map whose length does not match the terrain's geometry.
    #[error("{what} has {actual} values but the {width}x{height} grid needs {expected}")]
    LengthMismatch {
        what: String,
        width: usize,
        height: usize,
        expected: usize,
        actual: usize,
    },
    /// `ColourMode::Map` names a map the terrain does not have.
    #[error("the terrain has no map named {name:?}; available maps: {}", list_or_none(.available))]
    MissingMap {
        name: String,
        available: Vec<String>,
    },
    /// An output image whose side does not fit the format.
    #[error("a {width}x{height} image is too large: {limit}")]
    ImageTooLarge {
        width: usize,
        height: usize,
        limit: &'static str,
    },
    /// `encode_gif` was given no frames.
    #[error("an animated GIF needs at least one frame")]
    NoFrames,
    /// A time-lapse frame whose size differs from the first frame's.
    #[error("frame {index} is {actual_width}x{actual_height} but frame 0 is {width}x{height}")]
    FrameSizeMismatch {
        index: usize,
        width: u32,
        height: u32,
        actual_width: u32,
        actual_height: u32,
    },
    /// PNG or GIF encoding failed.
    #[error("{format} encoding failed: {source}")]
    Encode {
        format: &'static str,
        source: image::ImageError,
    },
    /// The GIF encoder failed.
    #[error("GIF encoding failed: {0}")]
    GifEncode(#[from] gif::EncodingError),
    /// A NaN or infinite altitude or snow depth in a valid cell (glTF export).
    #[error("non-finite {what} {value} at cell (col {col}, row {row})")]
    NonFinite {
        what: &'static str,
        col: usize,
        row: usize,
        value: f32,
    },
    /// The terrain has no valid triangle to export.
    #[error(
        "nothing to export: the {width}x{height} terrain has no triangle with three valid corners"
    )]
    EmptyMesh { width: usize, height: usize },
    /// A GLB larger than the 4 GiB its 32-bit length fields can describe.
    #[error("the GLB would be {bytes} bytes, beyond the 4 GiB a GLB can hold; decimate more")]
    GlbTooLarge { bytes: u64 },
    /// Serialising the glTF JSON failed.
    #[error("glTF JSON serialisation failed: {0}")]
    Json(#[from] serde_json::Error),
}

fn list_or_none(names: &[String]) -> String {
    if names.is_empty() {
        "none".to_string()
    } else {
        names.join(", ")
    }
}
