//! Typed errors of raster input and output. Every variant names the file and the offending
//! value, and where it was found (line, cell, TIFF tag...), so a user can fix the input.

use crate::AtomicWriteError;
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
    #[error("{path}: TIFF error: {source}")]
    Tiff {
        path: PathBuf,
        #[source]
        source: tiff::TiffError,
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
    #[error("{path}: PNG error: {source}")]
    Png {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    /// A PNG that is not single-channel grayscale.
    #[error("{path}: PNG colour type {color} is not a heightmap (need 16- or 8-bit grayscale)")]
    PngColor { path: PathBuf, color: String },
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
    #[error("{path}: EXR error: {source}")]
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
    /// A sidecar file (JSON scale, CRS) that cannot be read or written.
    #[error("{path}: sidecar error: {reason}")]
    Sidecar { path: PathBuf, reason: String },
}

/// Shorthand used by every module.
pub type Result<T> = std::result::Result<T, RasterError>;

/// Closure helpers that attach a path to foreign errors.
pub(crate) fn io_err(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> RasterError + '_ {
    move |source| RasterError::Io {
        path: path.to_path_buf(),
        source,
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

pub(crate) fn tiff_err(path: &std::path::Path) -> impl FnOnce(tiff::TiffError) -> RasterError + '_ {
    move |source| RasterError::Tiff {
        path: path.to_path_buf(),
        source,
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
