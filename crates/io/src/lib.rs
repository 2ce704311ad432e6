//! # snowscape-io: raster input and output
//!
//! [`read_dem`] reads a raster into a [`Grid`] (format from the extension, or
//! [`ReadOptions::format`]); [`read_terrain`] reads one that is to be a terrain and checks it
//! ([`Grid::check_terrain`]); [`write_raster`] writes a grid in any format (for
//! `snowscape convert`); [`write_geotiff`], [`write_geotiff_bands`], [`write_exr`],
//! [`write_png16`] and [`write_splat`] write simulation outputs.
//!
//! | format | ext | read | write | georeferencing | nodata | options needed to read |
//! |---|---|---|---|---|---|---|
//! | ESRI ASCII | `.asc` | yes | yes | header; CRS from `.prj` / `CRS.txt` | `NODATA_value` (written -9999) | none |
//! | GeoTIFF | `.tif` `.tiff` | band 1; u8..i32, f16/f32/f64; strips/tiles; none/LZW/Deflate/PackBits | f32, Deflate, 1..n bands | ModelPixelScale+Tiepoint or ModelTransformation; EPSG/WKT GeoKeys | `GDAL_NODATA` (written -9999); NaN if undeclared | `--cell-size` only without georef tags |
//! | PNG16 | `.png` | 16-bit (or 8-bit) grayscale | 16-bit + `<file>.json` sidecar | sidecar | code 0 when the sidecar says so | `--height-range`, `--cell-size` (unless sidecar) |
//! | RAW16 | `.raw` `.r16` | LE u16, square or `--raw-size` | LE u16 + sidecar | sidecar | as PNG16 | `--height-range`, `--cell-size` (unless sidecar) |
//! | NumPy | `.npy` | 2-D f4/f8/i1/i2/i4/u1/u2/u4, C or Fortran order | f32, C order | none | NaN | `--cell-size` |
//! | OpenEXR | `.exr` | channel `height`/`Y`/`Z` or first | one f32 channel per layer | custom attribute `snowscape.georeference` | NaN | `--cell-size` unless written by snowscape |
//! | splat | `.png` | no | RGBA8: R compacted, G stable, B unstable, A powder, share of depth | none | all 0 | — |
//!
//! Rules shared by every reader:
//! - the cell count is checked against [`ReadOptions::max_cells`] (default 2^28) before any
//!   grid-sized allocation;
//! - the size the file's own tags or header claim is checked against the file before
//!   anything is allocated or inflated, in time linear in the header, and every decompression
//!   is bounded by the size the tags say the data decodes to (a decompression bomb is refused
//!   with [`RasterError::DecodedSize`] naming the claimed and stored bytes); the limits:
//!
//! | format | checked before allocating | limit |
//! |---|---|---|
//! | GeoTIFF (classic, BigTIFF, COG) | [`geotiff::check`]: every offset of the first directory, its tags and band 1's strips or tiles inside the file; each strip or tile's stored bytes x its compression's largest expansion >= its decoded size (else an error naming the strip or tile and both sizes); all of band 1 likewise against the file's length | Deflate 1032:1, LZW 4096:1, PackBits 64:1, none 1:1; other compressions refused; a tag holds at most 2^24 values; the decoder's `Limits` sized to one strip or tile (`decoding_buffer_size`, `intermediate_buffer_size`) and 16 MiB of tag values (`ifd_value_size`); decoded a band of strips or tiles at a time |
//! | PNG16 | IHDR: cells, and `rows x (1 + row bytes)` against the file's length | zlib 1032:1; decoder `max_alloc` twice the image + 1 MiB |
//! | OpenEXR | cells; the offset tables fit in the file and every chunk offset lies after them and inside the file; the layer's `cells x channel bytes` against the file's length | RLE 64:1, ZIP 1032:1, PXR24 1376:1, B44 32:1, others 65536:1; one channel read, no decoding threads |
//! | NPY | header length and shape product before parsing, data bytes = shape x item size | none beyond the file |
//! | ESRI ASCII | capacity bounded by the file's length (2 bytes a value); each line at most 64 KiB + 48 bytes x `ncols` | [`asc::MAX_LINE_BYTES_PER_VALUE`] |
//! | RAW16 | file length = 2 x cells | streamed 64 KiB at a time |
//!
//! - an offset past the end of the file is [`RasterError::PastEnd`] naming what it locates and
//!   the value (`strip 3 offset 18446744073709551000 is past the end of the 4096-byte file`),
//!   never the operating system's "Invalid argument"; the TIFF and EXR decoders read through
//!   [`input::BoundedReader`], whose seeks cannot leave the file;
//! - text taken from a file (a token, a tag, a header) is quoted to at most
//!   [`error::MAX_ECHO`] (80) characters, a foreign decoder's message to
//!   [`error::MAX_FOREIGN_MESSAGE`] (160);
//! - nodata follows one rule ([`cells`]): a declared nodata value is nodata; NaN is nodata only
//!   in binary float files without a nodata declaration (NPY, EXR, float GeoTIFF without
//!   `GDAL_NODATA`), an error elsewhere; infinity is always an error naming the cell;
//! - every input is opened through [`input::open_regular`]: devices, FIFOs and directories are
//!   refused before anything is opened or read, and the file length bounds what is allocated;
//! - [`ReadOptions::crs`] overrides whatever CRS the file declares; only a geographic CRS
//!   makes coordinates degrees (metric cell sizes from [`GridGeometry::from_transform`]); a
//!   grid without a CRS is metres whatever its cell size (a warning names cells <= 1 mm); a geographic CRS on a grid whose extent is not in
//!   degrees (a mislabelled file) is dropped with a warning naming both, and the coordinates
//!   are taken as metres (`--crs` sets the right CRS);
//! - every error is a [`RasterError`] naming the file and the offending value.
//!
//! Every output is written through [`atomic::write_atomic`]: to a temporary file in the target
//! folder, flushed and synced, then renamed over the target, so a crash or an error never leaves
//! a half-written file behind. Sidecars (`.json`, `.prj`) are written the same way, after the
//! main file.

pub mod asc;
pub mod atomic;
pub mod cells;
mod crs_sidecar;
pub mod error;
pub mod exr;
pub mod format;
pub mod geotiff;
pub mod glb;
pub mod heightmap16;
pub mod input;
pub mod npy;
pub mod png16;
pub mod raw16;
pub mod splat;

pub mod vector;

pub use atomic::{AtomicWriteError, write_atomic, write_bytes_atomic};
pub use error::RasterError;
pub use exr::write_exr;
pub use format::{DEFAULT_MAX_CELLS, ParseFormatError, RasterFormat, ReadOptions};
pub use geotiff::{
    COG_TILE, GEOTIFF_NODATA, TiffRows, write_cog, write_geotiff, write_geotiff_bands,
};
pub use heightmap16::Png16Scale;
pub use input::{InputError, open_regular};
pub use png16::write_png16;
pub use splat::write_splat;

use snowscape_terrain::{Grid, GridGeometry};
use std::path::Path;

/// The format to read `path` as: the forced one, else the one its extension names.
fn format_of(path: &Path, forced: Option<RasterFormat>) -> Result<RasterFormat, RasterError> {
    forced
        .or_else(|| RasterFormat::from_path(path))
        .ok_or_else(|| RasterError::UnknownFormat {
            path: path.to_path_buf(),
            extension: path
                .extension()
                .map(|e| e.to_string_lossy().into_owned())
                .unwrap_or_default(),
        })
}

/// Whether the grid's CRS is in degrees while its extent cannot be longitudes and latitudes
/// (a mislabelled file, such as a metric DEM tagged EPSG:4326).
fn impossible_geographic_extent(g: &GridGeometry) -> bool {
    if !g.crs().is_some_and(|c| c.is_geographic()) {
        return false;
    }
    let t = g.transform();
    let (x0, x1) = (t.origin_x, t.origin_x + g.width() as f64 * t.pixel_width);
    let (y0, y1) = (t.origin_y - g.height() as f64 * t.pixel_height, t.origin_y);
    !(x0 >= -180.0 && x1 <= 360.0 && y0 >= -90.0 && y1 <= 90.0)
}

/// Reads a DEM (see the crate docs for formats, options and rules).
///
/// A file whose CRS is in degrees but whose extent cannot be longitudes and latitudes (a
/// metric DEM mislabelled EPSG:4326) loads with its coordinates taken as metres and its CRS
/// dropped, with a warning naming the file, the CRS and the extent; `--crs` sets the right one.
pub fn read_dem(path: &Path, opts: &ReadOptions) -> Result<Grid, RasterError> {
    let grid = read_any(path, opts)?;
    warn_tiny_cells_without_crs(path, grid.geometry());
    if !impossible_geographic_extent(grid.geometry()) {
        return Ok(grid);
    }
    let g = grid.geometry();
    let t = *g.transform();
    tracing::warn!(
        "{}: declares {} (degrees) but spans x {:.1}..{:.1}, y {:.1}..{:.1}: taking the coordinates as metres with no CRS; pass --crs to set the right one",
        path.display(),
        g.crs()
            .map(|c| error::clip(&c.to_string(), error::MAX_ECHO))
            .unwrap_or_default(),
        t.origin_x,
        t.origin_x + g.width() as f64 * t.pixel_width,
        t.origin_y - g.height() as f64 * t.pixel_height,
        t.origin_y
    );
    let metric = GridGeometry::from_transform(g.width(), g.height(), t, None).map_err(|e| {
        RasterError::Geometry {
            path: path.to_path_buf(),
            source: e,
        }
    })?;
    let mask = grid.mask().clone();
    Grid::new(metric, grid.into_data(), mask).map_err(|e| RasterError::Geometry {
        path: path.to_path_buf(),
        source: e,
    })
}

/// Reads a DEM that is to be a terrain: [`read_dem`], then [`Grid::check_terrain`] (at least
/// 2x2 cells, a 2x2 block with three valid cells, altitudes finite and within +-1e5 m). Every
/// front end (`snowscape run`, `avalanche`, `transport`, `cover`, `render`, `serve`, the
/// editor's projects) loads its terrain here, so a bad DEM is refused before any work or
/// output.
pub fn read_terrain(path: &Path, opts: &ReadOptions) -> Result<Grid, RasterError> {
    let grid = read_dem(path, opts)?;
    refuse_degrees_without_crs(path, grid.geometry())?;
    grid.check_terrain()
        .map_err(|source| RasterError::Terrain {
            path: path.to_path_buf(),
            source,
        })?;
    Ok(grid)
}

/// Refuses a terrain without a CRS whose cells are below 0.05 (metres or degrees) and whose
/// extent lies inside the longitude and latitude ranges away from the origin: a geographic DEM
/// that lost its CRS (3″ SRTM cells are 0.000833). Taken as metres, its sub-millimetre cells
/// would make every distance-based neighbourhood thousands of cells wide. A metric grid has
/// projected coordinates (far outside ±180) or, voxelised from a mesh, starts at the origin.
fn refuse_degrees_without_crs(path: &Path, g: &GridGeometry) -> Result<(), RasterError> {
    let t = g.transform();
    let (x0, x1) = (t.origin_x, t.origin_x + g.width() as f64 * t.pixel_width);
    let (y0, y1) = (t.origin_y - g.height() as f64 * t.pixel_height, t.origin_y);
    let in_degrees = (-180.0..=360.0).contains(&x0)
        && (-180.0..=360.0).contains(&x1)
        && (-90.0..=90.0).contains(&y0)
        && (-90.0..=90.0).contains(&y1);
    let away_from_origin = x0.abs().max(y1.abs()) >= 0.5;
    if g.crs().is_none()
        && t.pixel_width.max(t.pixel_height) < 0.05
        && in_degrees
        && away_from_origin
    {
        return Err(RasterError::LooksLikeDegrees {
            path: path.to_path_buf(),
            cell_x: t.pixel_width,
            cell_y: t.pixel_height,
            x0,
            x1,
            y0,
            y1,
        });
    }
    Ok(())
}

/// Warns when a grid without a CRS has cells of at most 1 mm inside the range of degrees: it
/// is read as metres (only a geographic CRS makes degrees), which is right for a finely
/// voxelised mesh and wrong for a DEM in degrees that lost its CRS.
fn warn_tiny_cells_without_crs(path: &Path, g: &GridGeometry) {
    let t = g.transform();
    if g.crs().is_none() && t.pixel_width.min(t.pixel_height) <= 1e-3 {
        tracing::warn!(
            "{}: cells of {} x {} with no CRS are taken as metres; if they are degrees, pass --crs EPSG:4326",
            path.display(),
            t.pixel_width,
            t.pixel_height
        );
    }
}

fn read_any(path: &Path, opts: &ReadOptions) -> Result<Grid, RasterError> {
    opts.validate(path)?;
    match format_of(path, opts.format)? {
        RasterFormat::Asc => asc::read(path, opts),
        RasterFormat::GeoTiff => geotiff::read(path, opts),
        RasterFormat::Png16 => png16::read(path, opts),
        RasterFormat::Raw16 => raw16::read(path, opts),
        RasterFormat::Npy => npy::read(path, opts),
        RasterFormat::Exr => exr::read(path, opts),
    }
}

/// The values of `grid` with nodata cells set to NaN (the nodata of NPY and EXR).
fn nan_for_nodata(grid: &Grid) -> Vec<f32> {
    let mask = grid.mask();
    grid.data()
        .iter()
        .enumerate()
        .map(|(i, &v)| if mask.is_valid(i) { v } else { f32::NAN })
        .collect()
}

/// Writes `grid` in `format`, atomically: GeoTIFF (f32, georeferenced), ESRI ASCII, PNG16 or
/// RAW16 (plus their JSON sidecar), NPY (f32, nodata NaN) or EXR (channel `height`, nodata
/// NaN).
pub fn write_raster(path: &Path, grid: &Grid, format: RasterFormat) -> Result<(), RasterError> {
    match format {
        RasterFormat::Asc => asc::write(path, grid),
        RasterFormat::GeoTiff => write_geotiff(path, grid),
        RasterFormat::Png16 => write_png16(path, grid).map(|_| ()),
        RasterFormat::Raw16 => raw16::write(path, grid).map(|_| ()),
        RasterFormat::Npy => npy::write(path, grid),
        RasterFormat::Exr => {
            let values = nan_for_nodata(grid);
            write_exr(path, grid.geometry(), &[("height", &values)])
        }
    }
}

/// A short description of a grid, for `snowscape info` and logs.
pub fn describe(grid: &Grid) -> String {
    let g: &GridGeometry = grid.geometry();
    let crs = g
        .crs()
        .map_or_else(|| "none".to_string(), |c| c.to_string());
    let range = grid
        .value_range()
        .map_or_else(|| "no data".to_string(), |(a, b)| format!("{a}..{b}"));
    format!(
        "{}x{} cells of {:.3}x{:.3} m, CRS {crs}, values {range}, {} nodata cells",
        g.width(),
        g.height(),
        g.cell_size_x(),
        g.cell_size_y(),
        grid.mask().count_nodata()
    )
}
