//! GeoTIFF writing: f32 bands, Deflate, georeferencing, CRS GeoKeys and `GDAL_NODATA`.

use super::geokeys;
use crate::error::{RasterError, Result, tiff_err};
use crate::write_atomic;
use snowscape_terrain::{Grid, GridGeometry, NodataMask};
use std::borrow::Cow;
use std::io::{Seek, Write};
use std::path::Path;
use tiff::encoder::compression::DeflateLevel;
use tiff::encoder::{Compression, TiffEncoder, TiffKind, colortype::Gray32Float};
use tiff::tags::{ExtraSamples, Tag};

/// The value nodata cells are written as, declared in the `GDAL_NODATA` tag.
pub const GEOTIFF_NODATA: f32 = -9999.0;

/// Above this many bytes of raw samples the file is written as BigTIFF (classic TIFF offsets
/// are 32-bit; compressed data is usually smaller, but not for noisy floats).
const BIGTIFF_THRESHOLD: u64 = 3 << 30;

/// Checks the band lengths against the geometry.
fn check_bands(path: &Path, geometry: &GridGeometry, bands: &[&[f32]]) -> Result<()> {
    if bands.is_empty() {
        return Err(RasterError::UnsupportedOperation {
            path: path.to_path_buf(),
            format: "GeoTIFF",
            what: "written with zero bands",
        });
    }
    for (i, b) in bands.iter().enumerate() {
        if b.len() != geometry.len() {
            return Err(RasterError::LengthMismatch {
                path: path.to_path_buf(),
                what: format!("band {}", i + 1),
                width: geometry.width(),
                height: geometry.height(),
                expected: geometry.len(),
                found: b.len(),
            });
        }
    }
    Ok(())
}

/// The pixel-interleaved samples, nodata cells replaced by [`GEOTIFF_NODATA`]. A single band
/// without nodata is borrowed as is.
fn interleave<'a>(mask: &NodataMask, bands: &[&'a [f32]]) -> Cow<'a, [f32]> {
    if let ([only], false) = (bands, mask.has_nodata()) {
        return Cow::Borrowed(only);
    }
    let n = bands.first().map_or(0, |b| b.len());
    let mut out = Vec::with_capacity(n * bands.len());
    for i in 0..n {
        let valid = mask.is_valid(i);
        out.extend(
            bands
                .iter()
                .map(|b| if valid { b[i] } else { GEOTIFF_NODATA }),
        );
    }
    Cow::Owned(out)
}

/// Encodes one image with its GeoTIFF tags.
fn encode<W: Write + Seek, K: TiffKind>(
    enc: &mut TiffEncoder<W, K>,
    geometry: &GridGeometry,
    has_nodata: bool,
    nbands: usize,
    samples: &[f32],
) -> tiff::TiffResult<()> {
    let (w, h) = (geometry.width() as u32, geometry.height() as u32);
    let mut image = enc.new_image::<Gray32Float>(w, h)?;
    if nbands > 1 {
        image.extra_samples(&vec![ExtraSamples::Unspecified; nbands - 1])?;
    }
    let t = geometry.transform();
    let e = image.encoder();
    e.write_tag(
        Tag::ModelPixelScaleTag,
        &[t.pixel_width, t.pixel_height, 0.0][..],
    )?;
    e.write_tag(
        Tag::ModelTiepointTag,
        &[0.0, 0.0, 0.0, t.origin_x, t.origin_y, 0.0][..],
    )?;
    let (dir, ascii) = geokeys::encode(geometry.crs());
    e.write_tag(Tag::GeoKeyDirectoryTag, &dir[..])?;
    if let Some(a) = &ascii {
        e.write_tag(Tag::GeoAsciiParamsTag, a.as_str())?;
    }
    if has_nodata {
        e.write_tag(Tag::GdalNodata, format!("{GEOTIFF_NODATA}").as_str())?;
    }
    image.write_data(samples)
}

/// Writes a single-band f32 GeoTIFF of `grid` (see [`write_geotiff_bands`]).
pub fn write_geotiff(path: &Path, grid: &Grid) -> Result<()> {
    write_geotiff_bands(path, grid.geometry(), grid.mask(), &[grid.data()])
}

/// Writes an f32 GeoTIFF with one band per slice, atomically: Deflate-compressed strips,
/// pixel-interleaved bands (`PlanarConfiguration` 1, extra samples "unspecified", as GDAL
/// writes multi-band rasters), `ModelPixelScale` + `ModelTiepoint`, a GeoKey directory with
/// the CRS (EPSG as `ProjectedCSTypeGeoKey` or `GeographicTypeGeoKey`, WKT as
/// `GTCitationGeoKey`) and PixelIsArea; nodata cells of `mask` are written as -9999 in every
/// band and declared in `GDAL_NODATA` (the tag is written only when the mask has nodata).
/// Grids above 3 GiB of samples are written as BigTIFF.
pub fn write_geotiff_bands(
    path: &Path,
    geometry: &GridGeometry,
    mask: &NodataMask,
    bands: &[&[f32]],
) -> Result<()> {
    check_bands(path, geometry, bands)?;
    if u32::try_from(geometry.width()).is_err() || u32::try_from(geometry.height()).is_err() {
        return Err(RasterError::UnsupportedOperation {
            path: path.to_path_buf(),
            format: "GeoTIFF",
            what: "wider or taller than 2^32 cells",
        });
    }
    let samples = interleave(mask, bands);
    let compression = Compression::Deflate(DeflateLevel::Fast);
    let big = (samples.len() as u64).saturating_mul(4) > BIGTIFF_THRESHOLD;
    write_atomic(path, |w| {
        let r = if big {
            TiffEncoder::new_big(w).and_then(|e| {
                let mut e = e.with_compression(compression);
                encode(&mut e, geometry, mask.has_nodata(), bands.len(), &samples)
            })
        } else {
            TiffEncoder::new(w).and_then(|e| {
                let mut e = e.with_compression(compression);
                encode(&mut e, geometry, mask.has_nodata(), bands.len(), &samples)
            })
        };
        r.map_err(tiff_err(path))
    })
}
