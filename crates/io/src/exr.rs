//! OpenEXR (`.exr`), write (one f32 channel per named layer) and read (one channel as a DEM),
//! with the `exr` crate.
//!
//! Format: OpenEXR 2 (ILM / ASWF), single part, scan lines of the data window, RLE-compressed
//! 64x64 tiles (`Encoding::FAST_LOSSLESS`, in increasing line order so the bytes are deterministic), lossless f32 samples. Channel names are sorted
//! alphabetically in the file, as the format requires. Nodata: EXR has no nodata declaration,
//! so nodata is NaN (written as NaN by [`crate::write_raster`], read as nodata; see
//! [`crate::cells`]). [`write_exr`] writes the values it is given as they are.
//!
//! Georeferencing travels in ONE custom text attribute, `snowscape.georeference`: a first line
//! `origin_x origin_y pixel_width pixel_height` (shortest round-trip decimal f64s), then the
//! CRS (`EPSG:n` or WKT, possibly empty) on the following lines; other tools ignore it. One
//! attribute, because the exr crate keeps custom attributes in a `HashMap` and writes them in
//! its random order: several attributes would make identical runs write different bytes. Reading takes `--cell-size`
//! if given, else these attributes, else fails naming `--cell-size`. The channel read is the
//! one named `height`, `Y` or `Z` (case-insensitive), else the first.

use crate::ReadOptions;
use crate::cells::{CellSink, NodataRule, check_cell_size, check_cells};
use crate::crs_sidecar::parse_crs_text;
use crate::error::{RasterError, Result, geometry_err};
use crate::input::BoundedReader;
use crate::write_atomic;
use exr::prelude::*;
use snowscape_terrain::{Crs, GeoTransform, Grid, GridGeometry};
use std::collections::{HashMap, HashSet};
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

const ATTR_GEOREFERENCE: &str = "snowscape.georeference";

fn exr_err(path: &Path) -> impl FnOnce(exr::error::Error) -> RasterError + '_ {
    move |source| RasterError::Exr {
        path: path.to_path_buf(),
        source,
    }
}

fn content_err(path: &Path, reason: String) -> RasterError {
    RasterError::ExrContent {
        path: path.to_path_buf(),
        reason,
    }
}

/// Checks channel names (non-empty, Latin-1, unique) and lengths.
fn check_channels(path: &Path, geometry: &GridGeometry, channels: &[(&str, &[f32])]) -> Result<()> {
    if channels.is_empty() {
        return Err(content_err(path, "no channels to write".into()));
    }
    let mut seen = HashSet::new();
    for (name, values) in channels {
        if name.is_empty() || Text::new_or_none(name).is_none() {
            return Err(content_err(
                path,
                format!("channel name {name:?} is empty or not Latin-1"),
            ));
        }
        if !seen.insert(*name) {
            return Err(content_err(
                path,
                format!("channel name {name:?} appears twice"),
            ));
        }
        if values.len() != geometry.len() {
            return Err(RasterError::LengthMismatch {
                path: path.to_path_buf(),
                what: format!("channel {name:?}"),
                width: geometry.width(),
                height: geometry.height(),
                expected: geometry.len(),
                found: values.len(),
            });
        }
    }
    Ok(())
}

/// The custom attribute that carries the georeferencing (see the module docs).
fn geo_attributes(geometry: &GridGeometry) -> HashMap<Text, AttributeValue> {
    let t = geometry.transform();
    let crs = geometry.crs().map_or(String::new(), |c| match c {
        Crs::Epsg(code) => format!("EPSG:{code}"),
        Crs::Wkt(w) => w.clone(),
    });
    let text = format!(
        "{} {} {} {}\n{crs}",
        t.origin_x, t.origin_y, t.pixel_width, t.pixel_height
    );
    let mut out = HashMap::new();
    if let (Some(k), Some(v)) = (
        Text::new_or_none(ATTR_GEOREFERENCE),
        Text::new_or_none(text),
    ) {
        out.insert(k, AttributeValue::Text(v));
    }
    out
}

/// The transform and CRS text of a `snowscape.georeference` attribute.
fn parse_georeference(text: &str) -> Option<(GeoTransform, Option<Crs>)> {
    let (numbers, crs) = text.split_once('\n').unwrap_or((text, ""));
    let v: Vec<f64> = numbers
        .split_whitespace()
        .map(str::parse)
        .collect::<std::result::Result<_, _>>()
        .ok()?;
    let &[origin_x, origin_y, pixel_width, pixel_height] = v.as_slice() else {
        return None;
    };
    let transform = GeoTransform {
        origin_x,
        origin_y,
        pixel_width,
        pixel_height,
    };
    Some((transform, parse_crs_text(crs)))
}

/// Writes one f32 channel per `(name, values)` pair, atomically, with the georeferencing in
/// custom attributes (see the module docs). Values are written as given (NaN stays NaN).
pub fn write_exr(path: &Path, geometry: &GridGeometry, channels: &[(&str, &[f32])]) -> Result<()> {
    check_channels(path, geometry, channels)?;
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = channels
        .iter()
        .filter_map(|(name, values)| {
            let name = Text::new_or_none(name)?;
            Some(AnyChannel::new(name, FlatSamples::F32(values.to_vec())))
        })
        .collect();
    let attributes = LayerAttributes {
        other: geo_attributes(geometry),
        ..Default::default()
    };
    let layer = Layer::new(
        (geometry.width(), geometry.height()),
        attributes,
        // Increasing line order makes the parallel compressor write chunks in a fixed order
        // (with `Unspecified` it writes them as threads finish: same image, different bytes).
        Encoding {
            line_order: LineOrder::Increasing,
            ..Encoding::FAST_LOSSLESS
        },
        AnyChannels::sort(list),
    );
    let image = Image::from_layer(layer);
    write_atomic(path, |w| {
        image.write().to_buffered(w).map_err(exr_err(path))
    })
}

/// The geometry: `--cell-size`, else the snowscape attributes.
fn geometry_of(
    path: &Path,
    (w, h): (usize, usize),
    attrs: &HashMap<Text, AttributeValue>,
    opts: &ReadOptions,
) -> Result<GridGeometry> {
    if let Some(c) = opts.cell_size {
        let c = check_cell_size(path, c, "--cell-size")?;
        return GridGeometry::square(w, h, c)
            .map(|g| g.with_crs(opts.crs.clone()))
            .map_err(geometry_err(path));
    }
    let georeference = Text::new_or_none(ATTR_GEOREFERENCE).and_then(|k| match attrs.get(&k) {
        Some(AttributeValue::Text(t)) => parse_georeference(&t.to_string()),
        _ => None,
    });
    let Some((transform, file_crs)) = georeference else {
        return Err(RasterError::MissingOption {
            path: path.to_path_buf(),
            format: "EXR",
            option: "--cell-size",
            why: "it has no snowscape georeferencing attribute",
        });
    };
    let crs = opts.crs.clone().or(file_crs);
    GridGeometry::from_transform(w, h, transform, crs).map_err(geometry_err(path))
}

/// The largest expansion of an EXR compression: how many decoded bytes one stored byte can
/// become (generous for the wavelet and DCT codecs, whose bound is not simple).
fn max_expansion(c: Compression) -> (&'static str, u64) {
    match c {
        Compression::Uncompressed => ("uncompressed", 1),
        Compression::RLE => ("RLE", 64),
        Compression::ZIP1 | Compression::ZIP16 => ("ZIP", 1032),
        Compression::PXR24 => ("PXR24", 1376),
        Compression::B44 | Compression::B44A => ("B44", 32),
        _ => ("PIZ/DWA/HTJ2K", 1 << 16),
    }
}

/// Walks the header attributes of the file behind `r` (from its start) and returns the
/// offset of the first offset table: after the magic number, the version, the header(s) and
/// their terminating null bytes. `parts` is the number of headers.
fn offset_table_start<R: Read + Seek>(
    path: &Path,
    r: &mut BoundedReader<R>,
    multipart: bool,
) -> Result<u64> {
    let len = r.len();
    let byte = |r: &mut BoundedReader<R>| -> Result<u8> {
        let mut b = [0u8; 1];
        r.read_exact(&mut b).map_err(|_| {
            content_err(
                path,
                format!("the header runs past the end of the {len}-byte file"),
            )
        })?;
        Ok(b[0])
    };
    for _ in 0..8 {
        byte(r)?;
    }
    loop {
        // One header: attributes `name\0 type\0 size value` until an empty name.
        let mut attributes = 0usize;
        loop {
            let first = byte(r)?;
            if first == 0 {
                break;
            }
            for _ in 0..2 {
                // The rest of the name, then the type name, each up to its null byte
                // (at most 255 bytes each, as the format allows).
                let mut n = 0;
                while byte(r)? != 0 {
                    n += 1;
                    if n > 256 {
                        return Err(content_err(
                            path,
                            "an attribute name or type longer than 255 bytes".into(),
                        ));
                    }
                }
            }
            let size = i32::from_le_bytes([byte(r)?, byte(r)?, byte(r)?, byte(r)?]);
            let size = u64::try_from(size)
                .map_err(|_| content_err(path, format!("attribute size {size} is negative")))?;
            let at = r.position();
            if at.saturating_add(size) > len {
                return Err(RasterError::RunsPastEnd {
                    path: path.to_path_buf(),
                    what: format!("header attribute {}", attributes + 1),
                    offset: at,
                    count: size,
                    bytes: len,
                });
            }
            r.seek(SeekFrom::Start(at + size))
                .map_err(crate::error::io_err(path))?;
            attributes += 1;
        }
        if !multipart || attributes == 0 {
            return Ok(r.position());
        }
    }
}

/// Checks, before any pixel is read, that the offset tables of every part fit in the file
/// and point inside it, and that the first layer's claimed size can come out of the file's
/// bytes with its compression (see [`max_expansion`]).
fn check_layout(path: &Path, meta: &exr::meta::MetaData, len: u64) -> Result<()> {
    let (file, _) = crate::input::open_regular(path)?;
    let mut r = BoundedReader::new(std::io::BufReader::new(file), len);
    let multipart = meta.requirements.has_multiple_layers;
    let start = offset_table_start(path, &mut r, multipart)?;
    let chunks: u64 = meta.headers.iter().map(|h| h.chunk_count as u64).sum();
    let table_bytes = chunks.saturating_mul(8);
    if start.saturating_add(table_bytes) > len {
        return Err(RasterError::RunsPastEnd {
            path: path.to_path_buf(),
            what: format!("the offset table of {chunks} chunks"),
            offset: start,
            count: table_bytes,
            bytes: len,
        });
    }
    let end = start + table_bytes;
    for i in 0..chunks {
        let mut b = [0u8; 8];
        r.read_exact(&mut b).map_err(crate::error::io_err(path))?;
        let offset = u64::from_le_bytes(b);
        if offset >= len || offset < end {
            return Err(RasterError::PastEnd {
                path: path.to_path_buf(),
                what: if offset >= len {
                    format!("chunk {i}")
                } else {
                    format!("chunk {i} (inside the header or offset table, which end at {end})")
                },
                offset,
                bytes: len,
            });
        }
    }
    let header = &meta.headers[0];
    let sample_bytes: u64 = header
        .channels
        .list
        .iter()
        .map(|c| c.sample_type.bytes_per_sample() as u64)
        .sum();
    let decoded = (header.layer_size.0 as u64)
        .saturating_mul(header.layer_size.1 as u64)
        .saturating_mul(sample_bytes);
    let (compression, ratio) = max_expansion(header.compression);
    if decoded > len.saturating_mul(ratio) {
        return Err(RasterError::DecodedSize {
            path: path.to_path_buf(),
            what: format!(
                "the first layer ({}x{} pixels of {} channels)",
                header.layer_size.0,
                header.layer_size.1,
                header.channels.list.len()
            ),
            decoded,
            stored: len,
            compression,
            ratio,
        });
    }
    Ok(())
}

/// An exr error; a seek past the end of the file is [`RasterError::PastEnd`].
fn read_err(path: &Path) -> impl FnOnce(exr::error::Error) -> RasterError + '_ {
    move |e| match &e {
        exr::error::Error::Io(io) => match crate::input::PastEnd::of(io) {
            Some(p) => crate::error::past_end(path, "a chunk", p),
            None => exr_err(path)(e),
        },
        _ => exr_err(path)(e),
    }
}

/// Reads one channel of the first layer as a DEM: the header, then the checks of
/// [`check_layout`], then that channel alone, sequentially (no decoding threads).
pub(crate) fn read(path: &Path, opts: &ReadOptions) -> Result<Grid> {
    let (file, len) = crate::input::open_regular(path)?;
    let reader = BoundedReader::new(std::io::BufReader::new(file), len);
    let meta = exr::meta::MetaData::read_from_buffered(reader, false).map_err(read_err(path))?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| content_err(path, "the file has no layer".into()))?;
    if header.deep {
        return Err(content_err(path, "deep data is not a height grid".into()));
    }
    let size = header.layer_size;
    check_cells(path, size.0 as u64, size.1 as u64, opts.max_cells)?;
    check_layout(path, &meta, len)?;
    let wanted = |n: &str| {
        let n = n.to_ascii_lowercase();
        n == "height" || n == "y" || n == "z"
    };
    let list = &header.channels.list;
    let name = list
        .iter()
        .find(|c| wanted(&c.name.to_string()))
        .or_else(|| list.first())
        .ok_or_else(|| content_err(path, "the layer has no channel".into()))?
        .name
        .clone();
    let (file, _) = crate::input::open_regular(path)?;
    let reader = BoundedReader::new(std::io::BufReader::new(file), len);
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .specific_channels()
        .required(name)
        .collect_pixels(
            |size, _| (size.0, vec![f32::NAN; size.0 * size.1]),
            |(w, values): &mut (usize, Vec<f32>), at, (v,): (f32,)| {
                values[at.1 * *w + at.0] = v;
            },
        )
        .first_valid_layer()
        .all_attributes()
        .non_parallel()
        .from_buffered(reader)
        .map_err(read_err(path))?;
    let layer = &image.layer_data;
    let (w, h) = (layer.size.0, layer.size.1);
    let values = &layer.channel_data.pixels.1;
    if values.len() != w * h {
        return Err(content_err(
            path,
            format!("channel has {} samples for {w}x{h} pixels", values.len()),
        ));
    }
    let geometry = geometry_of(path, (w, h), &layer.attributes.other, opts)?;
    let mut sink = CellSink::new(path, w, h, NodataRule::nan());
    for &v in values {
        sink.push_f32(v)?;
    }
    sink.finish(geometry)
}
