//! GeoTIFF reading: band 1 of the first image, georeferencing, CRS and nodata.

use super::check;
use super::geokeys::{self, GeoKeys, RASTER_PIXEL_IS_POINT};
use crate::ReadOptions;
use crate::cells::{CellSink, NodataRule, check_cell_size, check_cells};
use crate::crs_sidecar::sidecar_crs;
use crate::error::{
    MAX_ECHO, MAX_FOREIGN_MESSAGE, RasterError, Result, clip, geometry_err, tiff_err,
};
use crate::input::{BoundedReader, open_regular};
use snowscape_terrain::{GeoTransform, Grid, GridGeometry};
use std::fs::File;
use std::io::{BufReader, Read, Seek};
use std::path::Path;
use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

pub(super) type Dec = Decoder<BoundedReader<BufReader<File>>>;

fn tag_err(path: &Path, tag: u16, name: &'static str, reason: String) -> RasterError {
    RasterError::GeoTiffTag {
        path: path.to_path_buf(),
        tag,
        name,
        reason: clip(&reason, MAX_FOREIGN_MESSAGE),
    }
}

/// Reads an optional tag as f64 values; a malformed tag is an error naming it.
fn f64_tag<R: Read + Seek>(
    path: &Path,
    dec: &mut Decoder<R>,
    tag: Tag,
    name: &'static str,
) -> Result<Option<Vec<f64>>> {
    let code = tag.to_u16();
    let value = dec
        .find_tag(tag)
        .map_err(|e| tag_err(path, code, name, e.to_string()))?;
    value
        .map(|v| v.into_f64_vec())
        .transpose()
        .map_err(|e| tag_err(path, code, name, e.to_string()))
}

/// The GeoKeys of the image (empty when it has no key directory).
fn read_geokeys<R: Read + Seek>(path: &Path, dec: &mut Decoder<R>) -> Result<GeoKeys> {
    let name = "GeoKeyDirectoryTag";
    let code = Tag::GeoKeyDirectoryTag.to_u16();
    let Some(dir) = dec
        .find_tag(Tag::GeoKeyDirectoryTag)
        .map_err(|e| tag_err(path, code, name, e.to_string()))?
    else {
        return Ok(GeoKeys::default());
    };
    let dir = dir
        .into_u16_vec()
        .map_err(|e| tag_err(path, code, name, e.to_string()))?;
    let ascii_code = geokeys::TAG_GEO_ASCII_PARAMS;
    let ascii = match dec.find_tag(Tag::GeoAsciiParamsTag) {
        Ok(Some(v)) => v
            .into_string()
            .map_err(|e| tag_err(path, ascii_code, "GeoAsciiParamsTag", e.to_string()))?,
        Ok(None) => String::new(),
        Err(e) => {
            return Err(tag_err(
                path,
                ascii_code,
                "GeoAsciiParamsTag",
                e.to_string(),
            ));
        }
    };
    geokeys::decode(&dir, &ascii).map_err(|reason| tag_err(path, code, name, reason))
}

/// The `GDAL_NODATA` value, if declared.
fn read_gdal_nodata<R: Read + Seek>(path: &Path, dec: &mut Decoder<R>) -> Result<Option<f64>> {
    let (code, name) = (Tag::GdalNodata.to_u16(), "GDAL_NODATA");
    let Some(v) = dec
        .find_tag(Tag::GdalNodata)
        .map_err(|e| tag_err(path, code, name, e.to_string()))?
    else {
        return Ok(None);
    };
    let text = v
        .into_string()
        .map_err(|e| tag_err(path, code, name, e.to_string()))?;
    let t = text.trim_matches(|c: char| c == '\0' || c.is_whitespace());
    t.parse::<f64>().map(Some).map_err(|_| {
        tag_err(
            path,
            code,
            name,
            format!("{:?} is not a number", clip(t, MAX_ECHO)),
        )
    })
}

/// The affine transform from ModelTransformation, or ModelPixelScale + ModelTiepoint, shifted
/// by half a pixel for PixelIsPoint. `None` when the file has no georeferencing.
fn read_transform<R: Read + Seek>(
    path: &Path,
    dec: &mut Decoder<R>,
    keys: &GeoKeys,
) -> Result<Option<GeoTransform>> {
    let t = if let Some(m) = f64_tag(
        path,
        dec,
        Tag::ModelTransformationTag,
        "ModelTransformation",
    )? {
        from_model_transformation(path, &m)?
    } else {
        let scale = f64_tag(path, dec, Tag::ModelPixelScaleTag, "ModelPixelScale")?;
        let tie = f64_tag(path, dec, Tag::ModelTiepointTag, "ModelTiepoint")?;
        match (scale, tie) {
            (Some(s), Some(t)) => from_scale_tiepoint(path, &s, &t)?,
            _ => return Ok(None),
        }
    };
    Ok(Some(if keys.raster_type == Some(RASTER_PIXEL_IS_POINT) {
        GeoTransform {
            origin_x: t.origin_x - 0.5 * t.pixel_width,
            origin_y: t.origin_y + 0.5 * t.pixel_height,
            ..t
        }
    } else {
        t
    }))
}

fn from_model_transformation(path: &Path, m: &[f64]) -> Result<GeoTransform> {
    let err = |reason: String| tag_err(path, 34264, "ModelTransformation", reason);
    let &[a, b, _, d, e, f, _, h, ..] = m else {
        return Err(err(format!("{} values, expected 16", m.len())));
    };
    if b != 0.0 || e != 0.0 {
        return Err(err(format!(
            "rotated or sheared grids are not supported (terms {b}, {e})"
        )));
    }
    let pw = check_cell_size(path, a, "ModelTransformation (tag 34264) x scale")?;
    let ph = check_cell_size(path, -f, "ModelTransformation (tag 34264) negated y scale")?;
    Ok(GeoTransform {
        origin_x: d,
        origin_y: h,
        pixel_width: pw,
        pixel_height: ph,
    })
}

fn from_scale_tiepoint(path: &Path, scale: &[f64], tie: &[f64]) -> Result<GeoTransform> {
    let (&[sx, sy, ..], &[i, j, _, x, y, ..]) = (scale, tie) else {
        return Err(tag_err(
            path,
            33922,
            "ModelTiepoint/ModelPixelScale",
            format!(
                "{} tiepoint and {} scale values, expected at least 6 and 2",
                tie.len(),
                scale.len()
            ),
        ));
    };
    let pw = check_cell_size(path, sx, "ModelPixelScale (tag 33550) x")?;
    let ph = check_cell_size(path, sy, "ModelPixelScale (tag 33550) y")?;
    Ok(GeoTransform {
        origin_x: x - i * pw,
        origin_y: y + j * ph,
        pixel_width: pw,
        pixel_height: ph,
    })
}

/// How band 1 is laid out in `read_image`'s result: the step between its samples.
fn band1_stride(path: &Path, dec: &mut Dec) -> Result<usize> {
    let spp: u16 = dec
        .find_tag_unsigned(Tag::SamplesPerPixel)
        .map_err(tiff_err(path))?
        .unwrap_or(1);
    let planar: u16 = dec
        .find_tag_unsigned(Tag::PlanarConfiguration)
        .map_err(tiff_err(path))?
        .unwrap_or(1);
    // Planar images: read_image decodes plane 0 only, which is band 1.
    Ok(if planar == 2 {
        1
    } else {
        usize::from(spp.max(1))
    })
}

/// Moves band 1 of `samples` into `sink`.
pub(super) fn push_band1(
    path: &Path,
    sink: &mut CellSink,
    samples: DecodingResult,
    n: usize,
    stride: usize,
) -> Result<()> {
    macro_rules! each {
        ($v:expr, $push:ident, $conv:expr) => {{
            let v = $v;
            if v.len() < n.saturating_mul(stride) {
                return Err(RasterError::TiffUnsupported {
                    path: path.to_path_buf(),
                    what: format!(
                        "decoded {} samples, expected {} cells x {} samples",
                        v.len(),
                        n,
                        stride
                    ),
                });
            }
            for s in v.iter().step_by(stride).take(n) {
                sink.$push($conv(*s))?;
            }
        }};
    }
    match samples {
        DecodingResult::U8(v) => each!(v, push_f64, f64::from),
        DecodingResult::U16(v) => each!(v, push_f64, f64::from),
        DecodingResult::U32(v) => each!(v, push_f64, f64::from),
        DecodingResult::U64(v) => each!(v, push_f64, |x: u64| x as f64),
        DecodingResult::I8(v) => each!(v, push_f64, f64::from),
        DecodingResult::I16(v) => each!(v, push_f64, f64::from),
        DecodingResult::I32(v) => each!(v, push_f64, f64::from),
        DecodingResult::I64(v) => each!(v, push_f64, |x: i64| x as f64),
        DecodingResult::F16(v) => {
            let v: Vec<f32> = v.iter().map(|x| x.to_f32()).collect();
            each!(v, push_f32, |x: f32| x)
        }
        DecodingResult::F32(v) => each!(v, push_f32, |x: f32| x),
        DecodingResult::F64(v) => each!(v, push_f64, |x: f64| x),
    }
    Ok(())
}

/// The `tiff` crate's limits for a file whose band-1 strips or tiles decode to at most
/// `chunk` bytes each and store at most `stored` bytes each: one chunk's buffers, and tag
/// values of at most [`TAG_BYTES`] (the precheck has bounded every tag by the file).
fn limits(chunk: u64, stored: u64) -> Limits {
    let mut limits = Limits::default();
    let as_usize = |b: u64| usize::try_from(b).unwrap_or(usize::MAX);
    limits.decoding_buffer_size = as_usize(chunk).max(TAG_BYTES);
    limits.intermediate_buffer_size = as_usize(stored).max(1);
    limits.ifd_value_size = TAG_BYTES;
    limits
}

/// The most bytes the decoder may allocate for the values of one tag (the GeoKey directory,
/// a WKT citation): 16 MiB.
pub const TAG_BYTES: usize = 1 << 24;

/// Opens the decoder after [`check::precheck`] has checked the header, the first directory,
/// the cell count and the size of every strip or tile of band 1 against the file, and sizes
/// the decoder's limits to one strip or tile.
fn open(path: &Path, max_cells: usize) -> Result<(Dec, usize, usize)> {
    let (file, len) = open_regular(path)?;
    let mut reader = BoundedReader::new(BufReader::new(file), len);
    let layout = check::precheck(path, &mut reader, max_cells)?;
    let mut dec = Decoder::new(reader).map_err(tiff_err(path))?;
    let (w, h) = dec.dimensions().map_err(tiff_err(path))?;
    check_cells(path, u64::from(w), u64::from(h), max_cells)?;
    let limits = match layout {
        Some(l) => limits(l.max_chunk_bytes, l.max_stored_bytes),
        // Not a layout the precheck understood: the decoder will refuse the file; nothing
        // beyond the tag budget may be allocated meanwhile.
        None => limits(0, 0),
    };
    Ok((dec.with_limits(limits), w as usize, h as usize))
}

/// An opened (Geo)TIFF, its tags read: the decoder, its size, the grid's geometry, the nodata
/// rule and band 1's sample stride.
pub(super) struct Opened {
    pub dec: Dec,
    pub width: usize,
    pub height: usize,
    pub geometry: GridGeometry,
    pub rule: NodataRule,
    pub stride: usize,
}

/// Opens a (Geo)TIFF and reads its georeferencing, CRS, nodata and layout (no cell yet).
pub(super) fn open_image(path: &Path, opts: &ReadOptions) -> Result<Opened> {
    let (mut dec, w, h) = open(path, opts.max_cells)?;
    let keys = read_geokeys(path, &mut dec)?;
    let transform = read_transform(path, &mut dec, &keys)?;
    let nodata = read_gdal_nodata(path, &mut dec)?;
    let stride = band1_stride(path, &mut dec)?;
    if stride > 16 {
        return Err(RasterError::TiffUnsupported {
            path: path.to_path_buf(),
            what: format!("{stride} interleaved samples per pixel (at most 16)"),
        });
    }
    let crs = match opts.crs.clone().or_else(|| keys.crs()) {
        Some(c) => Some(c),
        None => sidecar_crs(path)?,
    };
    let geometry = match transform {
        Some(t) => GridGeometry::from_transform(w, h, t, crs),
        None => {
            let cell = opts.cell_size.ok_or_else(|| RasterError::MissingOption {
                path: path.to_path_buf(),
                format: "TIFF without georeferencing",
                option: "--cell-size",
                why: "it has no ModelPixelScale or ModelTransformation tag",
            })?;
            let cell = check_cell_size(path, cell, "--cell-size")?;
            GridGeometry::square(w, h, cell).map(|g| g.with_crs(crs))
        }
    }
    .map_err(geometry_err(path))?;
    Ok(Opened {
        dec,
        width: w,
        height: h,
        geometry,
        rule: NodataRule::for_binary(nodata),
        stride,
    })
}

/// Reads band 1 of a (Geo)TIFF as a DEM, one band of strips or tiles at a time (see
/// [`super::TiffRows`]): the memory is the grid's and one band of chunks', never a buffer of
/// the whole image's samples.
pub(crate) fn read(path: &Path, opts: &ReadOptions) -> Result<Grid> {
    super::TiffRows::open(path, opts)?.read_all()
}
