//! The tracks as file contents: the track texture as a georeferenced grayscale PNG, the tracks
//! as GeoJSON. The files are written by `snowscape::outputs` (`write_track_png`,
//! `write_tracks_geojson`).
//!
//! **PNG.** [`encode_track_png`] encodes the texture as 8- or 16-bit grayscale, code
//! `round(intensity · (2^bits − 1))`, row 0 north, with two sidecars:
//! - `<file>.json` (e.g. `tracks.png.json`, a [`TrackSidecar`]): `{"format":"snowscape-ski-tracks",
//!   "bits", "encoding", "width", "height", "texels_per_cell", "grid_width", "grid_height",
//!   "transform":{origin_x, origin_y, pixel_width, pixel_height}, "crs", "crs_name"}` with the
//!   transform of the texel corners in CRS units (the snowscape heightmap sidecar's layout);
//! - an ESRI world file `<stem>.pgw` (pixel width, 0, 0, −pixel height, map x and y of the
//!   centre of the upper-left texel), which GIS tools read beside a PNG.
//!
//! **GeoJSON.** [`tracks_geojson`] is a `FeatureCollection` with one `LineString` per track
//! (refined-track vertices, map coordinates of the DEM's CRS) and the properties `skier`,
//! `start_time_s`, `end_time_s`, `length_m` (horizontal length of the refined track),
//! `coarse_length_m`, `stop` and `active`. When the grid has an EPSG code the collection
//! carries the legacy (2008 GeoJSON) member `"crs": {"type": "name", "properties": {"name":
//! "EPSG:xxxx"}}`, which GDAL/QGIS read; RFC 7946 readers ignore it.

use crate::area::SkiArea;
use crate::frame::local_to_map;
use crate::texture::TrackTexture;
use crate::{SkiError, Track};
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};
use serde::Serialize;
use serde_json::{Value, json};
use snowscape_terrain::{Crs, GeoTransform, GridGeometry};

/// Bit depth of the track PNG.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, Serialize)]
pub enum PngDepth {
    /// 8-bit grayscale (code = intensity · 255).
    Eight,
    /// 16-bit grayscale (code = intensity · 65535).
    #[default]
    Sixteen,
}

/// The JSON sidecar of a track PNG.
#[derive(Debug, Clone, Serialize)]
pub struct TrackSidecar {
    pub format: &'static str,
    /// Bits per texel.
    pub bits: u32,
    /// How a code maps to an intensity.
    pub encoding: String,
    /// Texels along x and y.
    pub width: usize,
    pub height: usize,
    pub texels_per_cell: usize,
    /// The terrain grid's cells along x and y.
    pub grid_width: usize,
    pub grid_height: usize,
    /// Texel size (x, y), m.
    pub texel_size_m: [f64; 2],
    /// The texel corners in CRS units.
    pub transform: GeoTransform,
    pub crs: Option<Crs>,
    pub crs_name: Option<String>,
}

/// A track PNG and its two sidecars, encoded.
#[derive(Debug, Clone)]
pub struct TrackPng {
    /// The PNG file.
    pub png: Vec<u8>,
    /// `<file>.json`.
    pub sidecar: TrackSidecar,
    /// `<stem>.pgw`, the ESRI world file.
    pub world_file: String,
}

/// The geometry of the texture: the grid's extent with `texels_per_cell` times finer cells.
pub fn texture_geometry(
    texture: &TrackTexture,
    geometry: &GridGeometry,
) -> Result<GridGeometry, SkiError> {
    let (w, h) = texture.size();
    geometry
        .resampled(w, h)
        .map_err(|_| SkiError::TextureTooLarge {
            width: w,
            height: h,
            reason: "no grid geometry can hold it",
        })
}

/// `texture` (over `geometry`, the terrain grid) as a grayscale PNG, with its JSON sidecar and
/// world file.
pub fn encode_track_png(
    texture: &TrackTexture,
    geometry: &GridGeometry,
    depth: PngDepth,
) -> Result<TrackPng, SkiError> {
    let (w, h) = texture.size();
    let tg = texture_geometry(texture, geometry)?;
    let too_big = || SkiError::TextureTooLarge {
        width: w,
        height: h,
        reason: "a PNG side holds at most 2^31 - 1 pixels",
    };
    let (w32, h32) = (
        u32::try_from(w).map_err(|_| too_big())?,
        u32::try_from(h).map_err(|_| too_big())?,
    );
    if w32 > i32::MAX as u32 || h32 > i32::MAX as u32 {
        return Err(too_big());
    }
    let (bits, top) = match depth {
        PngDepth::Eight => (8u32, 255.0f32),
        PngDepth::Sixteen => (16u32, 65535.0f32),
    };
    let bytes_per = (bits / 8) as usize;
    let mut pixels = vec![0u8; w * h * bytes_per];
    let mut row = vec![0.0f32; w];
    for v in 0..h {
        texture.row(v, &mut row);
        let out = &mut pixels[v * w * bytes_per..(v + 1) * w * bytes_per];
        for (u, &x) in row.iter().enumerate() {
            let code = (x.clamp(0.0, 1.0) * top).round();
            match depth {
                PngDepth::Eight => out[u] = code as u8,
                PngDepth::Sixteen => {
                    out[2 * u..2 * u + 2].copy_from_slice(&(code as u16).to_ne_bytes())
                }
            }
        }
    }
    let color = match depth {
        PngDepth::Eight => ExtendedColorType::L8,
        PngDepth::Sixteen => ExtendedColorType::L16,
    };
    let mut png = Vec::new();
    PngEncoder::new(&mut png)
        .write_image(&pixels, w32, h32, color)
        .map_err(|source| SkiError::Png { source })?;
    let t = *tg.transform();
    let sidecar = TrackSidecar {
        format: "snowscape-ski-tracks",
        bits,
        encoding: format!("track intensity in [0, 1] = code / {top}"),
        width: w,
        height: h,
        texels_per_cell: texture.texels_per_cell(),
        grid_width: geometry.width(),
        grid_height: geometry.height(),
        texel_size_m: [texture.texel_size().0, texture.texel_size().1],
        transform: t,
        crs: geometry.crs().cloned(),
        crs_name: geometry.crs().map(|c| match c {
            Crs::Epsg(code) => format!("EPSG:{code}"),
            Crs::Wkt(wkt) => wkt.clone(),
        }),
    };
    let world_file = format!(
        "{}\n0\n0\n{}\n{}\n{}\n",
        t.pixel_width,
        -t.pixel_height,
        t.origin_x + 0.5 * t.pixel_width,
        t.origin_y - 0.5 * t.pixel_height
    );
    Ok(TrackPng {
        png,
        sidecar,
        world_file,
    })
}

fn feature(track: &Track, geometry: &GridGeometry, active: bool) -> Value {
    let coords: Vec<[f64; 2]> = track
        .vertices
        .iter()
        .map(|&[x, y]| {
            let (mx, my) = local_to_map(geometry, x, y);
            [mx, my]
        })
        .collect();
    // A LineString needs two positions; a skier that has not moved repeats its start.
    let coords = if coords.len() == 1 {
        vec![coords[0], coords[0]]
    } else {
        coords
    };
    json!({
        "type": "Feature",
        "geometry": { "type": "LineString", "coordinates": coords },
        "properties": {
            "skier": track.id,
            "start_time_s": track.start_time_s,
            "end_time_s": track.end_time_s,
            "length_m": track.length_m,
            "coarse_length_m": track.coarse_length_m,
            "stop": track.stop,
            "active": active,
        }
    })
}

/// The tracks of `area` (finished and active) as a GeoJSON `FeatureCollection` (see the module
/// docs).
pub fn tracks_geojson(area: &SkiArea) -> Value {
    let g = area.geometry();
    let mut features: Vec<Value> = area
        .finished_tracks()
        .iter()
        .map(|t| feature(t, g, false))
        .collect();
    features.extend(area.skiers().iter().map(|s| feature(s.track(), g, true)));
    let mut fc = json!({ "type": "FeatureCollection", "features": features });
    if let Some(Crs::Epsg(code)) = g.crs() {
        fc["crs"] = json!({ "type": "name", "properties": { "name": format!("EPSG:{code}") } });
    }
    fc
}
