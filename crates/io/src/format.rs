//! Raster format names, detection from file extensions, and reader options.

use snowscape_terrain::Crs;
use std::path::Path;
use std::str::FromStr;
use thiserror::Error;

/// The raster formats snowscape reads and writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RasterFormat {
    /// ESRI ASCII grid (`.asc`).
    Asc,
    /// GeoTIFF (`.tif`, `.tiff`).
    GeoTiff,
    /// 16-bit grayscale PNG heightmap (`.png`).
    Png16,
    /// Headerless little-endian u16 heightmap, Unreal/Unity style (`.raw`, `.r16`).
    Raw16,
    /// NumPy array (`.npy`).
    Npy,
    /// OpenEXR (`.exr`).
    Exr,
}

/// A format name that is not one of those [`RasterFormat`] knows.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error(
    "unknown raster format {name:?}; expected one of asc, tif, tiff, geotiff, png, png16, raw, \
     r16, raw16, npy, exr"
)]
pub struct ParseFormatError {
    /// The name that was given.
    pub name: String,
}

impl RasterFormat {
    /// Every format, in documentation order.
    pub const ALL: [RasterFormat; 6] = [
        RasterFormat::Asc,
        RasterFormat::GeoTiff,
        RasterFormat::Png16,
        RasterFormat::Raw16,
        RasterFormat::Npy,
        RasterFormat::Exr,
    ];

    /// The format a file name's extension names (case-insensitive), if any.
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?;
        ext.parse().ok()
    }

    /// The usual file extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            RasterFormat::Asc => "asc",
            RasterFormat::GeoTiff => "tif",
            RasterFormat::Png16 => "png",
            RasterFormat::Raw16 => "raw",
            RasterFormat::Npy => "npy",
            RasterFormat::Exr => "exr",
        }
    }

    /// A human-readable name for messages.
    pub fn name(self) -> &'static str {
        match self {
            RasterFormat::Asc => "ESRI ASCII",
            RasterFormat::GeoTiff => "GeoTIFF",
            RasterFormat::Png16 => "16-bit PNG",
            RasterFormat::Raw16 => "RAW16",
            RasterFormat::Npy => "NPY",
            RasterFormat::Exr => "OpenEXR",
        }
    }
}

impl FromStr for RasterFormat {
    type Err = ParseFormatError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "asc" => Ok(RasterFormat::Asc),
            "tif" | "tiff" | "geotiff" => Ok(RasterFormat::GeoTiff),
            "png" | "png16" => Ok(RasterFormat::Png16),
            "raw" | "r16" | "raw16" => Ok(RasterFormat::Raw16),
            "npy" => Ok(RasterFormat::Npy),
            "exr" => Ok(RasterFormat::Exr),
            _ => Err(ParseFormatError {
                name: s.to_string(),
            }),
        }
    }
}

impl std::fmt::Display for RasterFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.extension())
    }
}

/// The default cell limit of [`ReadOptions::max_cells`]: 2^28 cells (1 GiB per f32 layer).
pub const DEFAULT_MAX_CELLS: usize = 1 << 28;

/// How to read a DEM. Only the fields a format needs are used (see the table in the crate docs).
#[derive(Debug, Clone, PartialEq)]
pub struct ReadOptions {
    /// Force a format instead of guessing it from the extension.
    pub format: Option<RasterFormat>,
    /// Cell size in metres, for formats without georeferencing (PNG16, RAW16, NPY, EXR,
    /// non-georeferenced TIFF). Ignored by georeferenced files.
    pub cell_size: Option<f64>,
    /// Altitudes of the lowest and highest code of a PNG16 / RAW16 file, metres.
    pub height_range: Option<(f64, f64)>,
    /// Columns and rows of a RAW16 file (default: a square from the file length).
    pub raw_size: Option<(usize, usize)>,
    /// The largest grid a reader may allocate; checked before any allocation.
    pub max_cells: usize,
    /// Overrides the CRS the file declares (or lacks).
    pub crs: Option<Crs>,
}

impl ReadOptions {
    /// Checks every option a user set before a file is read, whether or not the file's format
    /// uses it (a georeferenced file ignores the cell size, but a negative one is still a
    /// mistake): the cell size finite and positive, the height range finite and in order, the
    /// raw size at least 1x1. The one check for every front end (command line, Python, editor).
    pub fn validate(&self, path: &Path) -> Result<(), crate::RasterError> {
        if let Some(c) = self.cell_size {
            crate::cells::check_cell_size(path, c, "the cell size option (--cell-size)")?;
        }
        if let Some((min, max)) = self.height_range
            && !(min.is_finite() && max.is_finite() && min <= max)
        {
            return Err(crate::RasterError::InvalidHeightRange {
                path: path.to_path_buf(),
                min,
                max,
            });
        }
        if let Some((width, height)) = self.raw_size
            && (width == 0 || height == 0)
        {
            return Err(crate::RasterError::InvalidRawSize {
                path: path.to_path_buf(),
                width,
                height,
            });
        }
        Ok(())
    }
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self {
            format: None,
            cell_size: None,
            height_range: None,
            raw_size: None,
            max_cells: DEFAULT_MAX_CELLS,
            crs: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_extensions_parse() {
        for (s, f) in [
            ("asc", RasterFormat::Asc),
            ("TIF", RasterFormat::GeoTiff),
            ("tiff", RasterFormat::GeoTiff),
            ("geotiff", RasterFormat::GeoTiff),
            ("png", RasterFormat::Png16),
            ("raw", RasterFormat::Raw16),
            ("r16", RasterFormat::Raw16),
            ("npy", RasterFormat::Npy),
            ("exr", RasterFormat::Exr),
        ] {
            assert_eq!(s.parse::<RasterFormat>(), Ok(f));
        }
        let e = "jpeg".parse::<RasterFormat>().unwrap_err();
        assert!(e.to_string().contains("jpeg"));
        assert_eq!(
            RasterFormat::from_path(Path::new("a/b/dem.TIFF")),
            Some(RasterFormat::GeoTiff)
        );
        assert_eq!(RasterFormat::from_path(Path::new("dem")), None);
        for f in RasterFormat::ALL {
            assert_eq!(f.extension().parse::<RasterFormat>(), Ok(f));
        }
    }

    #[test]
    fn default_limit_is_2_pow_28() {
        assert_eq!(ReadOptions::default().max_cells, 1 << 28);
    }
}
