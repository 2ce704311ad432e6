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
use crate::write_atomic;
use exr::prelude::*;
use snowscape_terrain::{Crs, GeoTransform, Grid, GridGeometry};
use std::collections::{HashMap, HashSet};
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

/// Reads one channel of the first layer as a DEM.
pub(crate) fn read(path: &Path, opts: &ReadOptions) -> Result<Grid> {
    crate::input::check_regular(path)?;
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(exr_err(path))?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| content_err(path, "the file has no layer".into()))?;
    let size = header.layer_size;
    check_cells(path, size.0 as u64, size.1 as u64, opts.max_cells)?;
    let image = exr::prelude::read_first_flat_layer_from_file(path).map_err(exr_err(path))?;
    let layer = &image.layer_data;
    let (w, h) = (layer.size.0, layer.size.1);
    let list = &layer.channel_data.list;
    let wanted = |c: &&AnyChannel<FlatSamples>| {
        let n = c.name.to_string().to_ascii_lowercase();
        n == "height" || n == "y" || n == "z"
    };
    let channel = list
        .iter()
        .find(wanted)
        .or_else(|| list.first())
        .ok_or_else(|| content_err(path, "the layer has no channel".into()))?;
    let geometry = geometry_of(path, (w, h), &layer.attributes.other, opts)?;
    let mut sink = CellSink::new(path, w, h, NodataRule::nan());
    for v in channel.sample_data.values_as_f32() {
        sink.push_f32(v)?;
    }
    if sink.len() != w * h {
        return Err(content_err(
            path,
            format!("channel has {} samples for {w}x{h} pixels", sink.len()),
        ));
    }
    sink.finish(geometry)
}
