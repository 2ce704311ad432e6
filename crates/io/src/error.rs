//! Typed errors of raster input and output. Every variant names the file and the offending
//! value, and where it was found (line, cell, TIFF tag...), so a user can fix the input.

use crate::AtomicWriteError;
use crate::input::InputError;
use snowscape_terrain::TerrainError;
use std::path::PathBuf;
use thiserror::Error;

/// Why a raster could not be read or written.
#[derive(Debug, Error)]
pub enum RasterError {
    /// The file could not be opened or read.
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The input is not a regular file, or too large to read whole.
    #[error(transparent)]
    Input(InputError),
    /// The output could not be written (nothing is left at the target path).
    #[error(transparent)]
    Write(#[from] AtomicWriteError),
    /// The format could not be told from the file name and was not given.
    #[error(
        "cannot tell the raster format of {path} from its extension {extension:?}; \
         use .asc, .tif, .png, .raw/.r16, .npy or .exr, or name the format"
    )]
    UnknownFormat { path: PathBuf, extension: String },
    /// A format that cannot hold what was asked of it.
    #[error("{path}: the {format} format cannot be {what}")]
    UnsupportedOperation {
        path: PathBuf,
        format: &'static str,
        what: &'static str,
    },
    /// The grid is larger than the reader may allocate.
    #[error(
        "{path}: {width}x{height} cells is more than the {max} cells allowed \
         (raise the cell limit if this is intended)"
    )]
    TooManyCells {
        path: PathBuf,
        width: u64,
        height: u64,
        max: usize,
    },
    /// A format without georeferencing or value scaling needs an option the user did not give.
    #[error("{path}: a {format} file needs {option} ({why})")]
    MissingOption {
        path: PathBuf,
        format: &'static str,
        option: &'static str,
        why: &'static str,
    },
    /// A cell size that is zero, negative or not a number.
    #[error(
        "{path}: invalid cell size {value} from {source_of}: it must be a finite positive number"
    )]
    InvalidCellSize {
        path: PathBuf,
        value: f64,
        source_of: String,
    },
    /// A height range whose bounds are not finite or in order.
    #[error("{path}: invalid height range {min}..{max}: both must be finite and min <= max")]
    InvalidHeightRange { path: PathBuf, min: f64, max: f64 },
    /// A NaN or infinite value in a cell that the file does not mark as nodata.
    #[error(
        "{path}: value {value} at cell (col {col}, row {row}) is not a finite height and not \
         nodata (NaN counts as nodata only in NPY, EXR and float GeoTIFF files without a \
         declared nodata value; infinity is always an error)"
    )]
    NonFinite {
        path: PathBuf,
        col: usize,
        row: usize,
        value: f64,
    },
    /// An ESRI ASCII header line that cannot be understood.
    #[error("{path}:{line}: bad header entry {key:?} = {value:?}: {reason}")]
    AscHeader {
        path: PathBuf,
        line: usize,
        key: String,
        value: String,
        reason: &'static str,
    },
    /// An ESRI ASCII header that lacks a required key.
    #[error("{path}: the ESRI ASCII header has no {key} (header ends at line {line})")]
    AscMissingKey {
        path: PathBuf,
        key: &'static str,
        line: usize,
    },
    /// A data token that is not a number.
    #[error("{path}:{line}: {token:?} is not a number")]
    AscToken {
        path: PathBuf,
        line: usize,
        token: String,
    },
    /// A data value that is not a finite f32 height and not nodata (`1e999`, `inf`, `1e39`),
    /// quoted as written in the file.
    #[error(
        "{path}:{line}: value {token:?} at cell (col {col}, row {row}) is not a finite height \
         and not the NODATA_value"
    )]
    AscValue {
        path: PathBuf,
        line: usize,
        col: usize,
        row: usize,
        token: String,
    },
    /// The number of values does not match ncols x nrows.
    #[error(
        "{path}: the header promises {ncols}x{nrows} = {expected} values but the file holds \
         {found} (last value on line {line})"
    )]
    AscValueCount {
        path: PathBuf,
        ncols: usize,
        nrows: usize,
        expected: usize,
        found: usize,
        line: usize,
    },
    /// The TIFF decoder or encoder failed (truncated or corrupt file, unsupported layout).
    #[error("{path}: TIFF error: {}", clip(&source.to_string(), MAX_FOREIGN_MESSAGE))]
    Tiff {
        path: PathBuf,
        #[source]
        source: tiff::TiffError,
    },
    /// The TIFF ends before the data its directory points to (a cut download or copy).
    #[error(
        "{path}: truncated TIFF: the file ends after {bytes} bytes, before the data its \
         image directory points to"
    )]
    TiffTruncated { path: PathBuf, bytes: u64 },
    /// An offset in the file's directory (a TIFF strip or tile, an image directory or tag
    /// value, an EXR chunk) that points past the end of the file.
    #[error(
        "{path}: {what} offset {offset} is past the end of the {bytes}-byte file (the file is \
         truncated or corrupt)"
    )]
    PastEnd {
        path: PathBuf,
        /// What the offset locates ("strip 3", "the image directory", "chunk 12").
        what: String,
        offset: u64,
        bytes: u64,
    },
    /// A block of the file (a TIFF strip or tile, a tag's values) that starts inside the file
    /// but runs past its end.
    #[error(
        "{path}: {what} ({count} bytes at offset {offset}) runs past the end of the \
         {bytes}-byte file (the file is truncated or corrupt)"
    )]
    RunsPastEnd {
        path: PathBuf,
        what: String,
        offset: u64,
        count: u64,
        bytes: u64,
    },
    /// Data whose decoded size, implied by the file's own tags or header, is more than its
    /// stored bytes can expand to with its compression (a decompression bomb, or a corrupt
    /// size): refused before anything is allocated or inflated.
    #[error(
        "{path}: {what} would decode to {decoded} bytes, but its {stored} stored bytes of \
         {compression} data expand to at most {ratio}x that: refusing it before allocating"
    )]
    DecodedSize {
        path: PathBuf,
        /// What is decoded ("the image", "strip 3", "tile 7").
        what: String,
        decoded: u64,
        stored: u64,
        compression: &'static str,
        /// The largest expansion the compression allows (1 for uncompressed data).
        ratio: u64,
    },
    /// An ESRI ASCII line longer than any line the header's width allows.
    #[error(
        "{path}:{line}: the line is longer than {max} bytes (at most {per_value} bytes per \
         value of the {ncols} columns): not an ESRI ASCII grid"
    )]
    AscLineTooLong {
        path: PathBuf,
        line: usize,
        max: usize,
        per_value: usize,
        ncols: usize,
    },
    /// A TIFF sample layout this reader does not handle.
    #[error("{path}: unsupported TIFF layout: {what}")]
    TiffUnsupported { path: PathBuf, what: String },
    /// A GeoTIFF tag whose value makes no sense.
    #[error("{path}: bad GeoTIFF tag {tag} ({name}): {reason}")]
    GeoTiffTag {
        path: PathBuf,
        tag: u16,
        name: &'static str,
        reason: String,
    },
    /// The PNG decoder or encoder failed.
    #[error("{path}: PNG error: {}", clip(&source.to_string(), MAX_FOREIGN_MESSAGE))]
    Png {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    /// A PNG that is not single-channel grayscale.
    #[error("{path}: PNG colour type {color} is not a heightmap (need 16- or 8-bit grayscale)")]
    PngColor { path: PathBuf, color: String },
    /// A RAW16 grid size option with no columns or no rows.
    #[error("{path}: invalid raw size {width}x{height}: both must be at least 1")]
    InvalidRawSize {
        path: PathBuf,
        width: usize,
        height: usize,
    },
    /// A RAW16 file whose length does not fit the grid size.
    #[error("{path}: {bytes} bytes is not {expected}")]
    RawSize {
        path: PathBuf,
        bytes: u64,
        expected: String,
    },
    /// A NumPy file that cannot be read.
    #[error("{path}: NPY error: {reason}")]
    Npy { path: PathBuf, reason: String },
    /// An OpenEXR file that cannot be read or written.
    #[error("{path}: EXR error: {}", clip(&source.to_string(), MAX_FOREIGN_MESSAGE))]
    Exr {
        path: PathBuf,
        #[source]
        source: exr::error::Error,
    },
    /// An OpenEXR file or channel list that does not fit a height grid.
    #[error("{path}: EXR content: {reason}")]
    ExrContent { path: PathBuf, reason: String },
    /// A band or channel whose length does not match the geometry.
    #[error("{path}: {what} has {found} values but the {width}x{height} grid needs {expected}")]
    LengthMismatch {
        path: PathBuf,
        what: String,
        width: usize,
        height: usize,
        expected: usize,
        found: usize,
    },
    /// The georeferencing or grid built from the file is invalid.
    #[error("{path}: {source}")]
    Geometry {
        path: PathBuf,
        #[source]
        source: TerrainError,
    },
    /// A raster without a CRS whose cells and extent look like degrees of longitude and
    /// latitude (a geographic DEM that lost its CRS): taken as metres its cells would be a
    /// fraction of a millimetre.
    #[error(
        "{path}: cells of {cell_x} x {cell_y} with no CRS over x {x0:.4}..{x1:.4}, y {y0:.4}..{y1:.4} look like degrees of longitude and latitude; pass --crs EPSG:4326 (or the file's geographic CRS) if they are degrees, or its projected CRS with --crs if they are metres"
    )]
    LooksLikeDegrees {
        path: PathBuf,
        cell_x: f64,
        cell_y: f64,
        x0: f64,
        x1: f64,
        y0: f64,
        y1: f64,
    },
    /// The raster was read but cannot be a terrain (too small, no surface, altitude spike).
    #[error("{path}: not a usable terrain: {source}")]
    Terrain {
        path: PathBuf,
        #[source]
        source: TerrainError,
    },
    /// A sidecar file (JSON scale, CRS) that cannot be read or written.
    #[error("{path}: sidecar error: {reason}")]
    Sidecar { path: PathBuf, reason: String },
}

impl From<InputError> for RasterError {
    /// An I/O failure stays [`RasterError::Io`]; a refused file is [`RasterError::Input`].
    fn from(e: InputError) -> Self {
        match e {
            InputError::Io { path, source } => RasterError::Io { path, source },
            other => RasterError::Input(other),
        }
    }
}

/// The most characters of a foreign decoder's message quoted in an error.
pub const MAX_FOREIGN_MESSAGE: usize = 160;

/// The most characters of text taken from a file (a token, a tag, a header) quoted in an
/// error: a corrupt file must not put megabytes into a message.
pub const MAX_ECHO: usize = 80;

/// `text` cut to at most `max` characters, with `...` and the full length when it was cut.
pub fn clip(text: &str, max: usize) -> String {
    let mut chars = text.char_indices();
    match chars.nth(max) {
        None => text.to_string(),
        Some((at, _)) => format!("{}... ({} bytes in all)", &text[..at], text.len()),
    }
}

/// Shorthand used by every module.
pub type Result<T> = std::result::Result<T, RasterError>;

/// Closure helpers that attach a path to foreign errors.
pub(crate) fn io_err(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> RasterError + '_ {
    move |source| match crate::input::PastEnd::of(&source) {
        Some(p) => past_end(path, "a read", p),
        None => RasterError::Io {
            path: path.to_path_buf(),
            source,
        },
    }
}

pub(crate) fn geometry_err(
    path: &std::path::Path,
) -> impl FnOnce(TerrainError) -> RasterError + '_ {
    move |source| RasterError::Geometry {
        path: path.to_path_buf(),
        source,
    }
}

/// A TIFF decoder error; an unexpected end of file becomes [`RasterError::TiffTruncated`]
/// (said once, instead of the decoder's "failed to fill whole buffer").
pub(crate) fn tiff_err(path: &std::path::Path) -> impl FnOnce(tiff::TiffError) -> RasterError + '_ {
    move |source| {
        if let tiff::TiffError::IoError(e) = &source {
            if let Some(p) = crate::input::PastEnd::of(e) {
                return past_end(path, "an image directory or tag value", p);
            }
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                return RasterError::TiffTruncated {
                    path: path.to_path_buf(),
                    bytes: std::fs::metadata(path).map_or(0, |m| m.len()),
                };
            }
        }
        RasterError::Tiff {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// [`RasterError::PastEnd`] for an offset a decoder sought (see [`crate::input::BoundedReader`]).
pub(crate) fn past_end(
    path: &std::path::Path,
    what: &str,
    p: crate::input::PastEnd,
) -> RasterError {
    RasterError::PastEnd {
        path: path.to_path_buf(),
        what: what.to_string(),
        offset: p.offset,
        bytes: p.len,
    }
}

/// An I/O error while filling an output file.
pub(crate) fn write_err(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> RasterError + '_ {
    move |source| {
        RasterError::Write(AtomicWriteError::Write {
            path: path.to_path_buf(),
            source,
        })
    }
}
