//! GeoTIFF (`.tif`, `.tiff`), read and write, with the `tiff` crate and a hand-written GeoKey
//! decoder ([`geokeys`]).
//!
//! Specs: TIFF 6.0 (Adobe, 1992) and OGC GeoTIFF 1.1 (2019). Georeferencing tags:
//! `ModelPixelScale` (33550) + `ModelTiepoint` (33922), or `ModelTransformation` (34264,
//! north-up only); the CRS from the GeoKey directory (34735): `ProjectedCSTypeGeoKey` (3072),
//! else `GeographicTypeGeoKey` (2048), else a WKT citation; `GTRasterTypeGeoKey` (1025) = 2
//! (PixelIsPoint) moves the tiepoint from the cell centre to its corner (half a cell up-left).
//! Nodata: the `GDAL_NODATA` ASCII tag (42113).
//!
//! Reading: band 1 of the first image; samples u8/u16/u32/i8/i16/i32/f16/f32/f64 (64-bit
//! integers too); strips or tiles; uncompressed, LZW, Deflate, PackBits (whatever the `tiff`
//! crate decodes); pixel-interleaved or planar bands. The cell count is checked against
//! [`crate::ReadOptions::max_cells`], and every offset and strip or tile size against the
//! file ([`check`]), before the decoder's memory limits are set to one strip or tile.
//! Without georeferencing tags, `--cell-size` is required. The CRS: `ReadOptions::crs`, else
//! the GeoKeys, else a `.prj` / `CRS.txt` sidecar. Truncated or corrupt files give
//! [`crate::RasterError::Tiff`] (or a `GeoTiffTag` error naming the bad tag), never a panic.
//!
//! Writing: see [`write_geotiff_bands`]; Cloud-Optimized: [`write_cog`].

pub mod check;
mod cog;
pub(crate) mod geokeys;
mod read;
mod rows;
mod write;

pub use cog::{COG_TILE, write_cog};
pub(crate) use read::read;
pub use rows::TiffRows;
pub use write::{GEOTIFF_NODATA, write_geotiff, write_geotiff_bands};
