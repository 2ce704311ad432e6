//! Cloud-Optimized GeoTIFF (COG) writing, laid out as GDAL's COG driver lays it out, so that
//! `gdalinfo` reports `LAYOUT=COG` and HTTP range readers fetch only the tiles they need:
//!
//! - one f32 band in 256 × 256 tiles, Deflate (zlib) with the floating-point predictor
//!   (`Predictor` 3: each tile row's bytes split into planes, most significant first, then
//!   differenced; TIFF Technical Note 3), partial edge tiles padded with the nodata value;
//! - overviews halving the size until it fits one tile (2 × 2 means of the valid cells; nodata
//!   where all four are nodata), as reduced-resolution images (`NewSubfileType` 1);
//! - after the 8-byte header, GDAL's "ghost" structural metadata (`LAYOUT=IFDS_BEFORE_DATA`,
//!   `BLOCK_ORDER=ROW_MAJOR`, `BLOCK_LEADER=SIZE_AS_UINT4`, `BLOCK_TRAILER=LAST_4_BYTES_REPEATED`),
//!   then every IFD (full resolution first, then the overviews), then the tile data from the
//!   smallest overview to the full resolution, each tile preceded by its size (u32) and
//!   followed by a copy of its last 4 bytes;
//! - the georeferencing of [`super::write_geotiff`]: `ModelPixelScale`, `ModelTiepoint`, the
//!   CRS GeoKeys and `GDAL_NODATA` (nodata cells written as [`GEOTIFF_NODATA`]).
//!
//! Classic TIFF (32-bit offsets): files over 4 GiB are refused.

use super::geokeys;
use super::write::GEOTIFF_NODATA;
use crate::error::{RasterError, Result};
use crate::write_bytes_atomic;
use snowscape_terrain::Grid;
use std::io::Write;
use std::path::Path;

/// Tile side, samples.
pub const COG_TILE: usize = 256;

/// GDAL's structural metadata, written right after the TIFF header.
fn ghost_header() -> Vec<u8> {
    let body = "LAYOUT=IFDS_BEFORE_DATA\nBLOCK_ORDER=ROW_MAJOR\nBLOCK_LEADER=SIZE_AS_UINT4\n\
                BLOCK_TRAILER=LAST_4_BYTES_REPEATED\nKNOWN_INCOMPATIBLE_EDITION=NO\n ";
    format!(
        "GDAL_STRUCTURAL_METADATA_SIZE={:06} bytes\n{body}",
        body.len()
    )
    .into_bytes()
}

/// One resolution level: values (nodata as [`GEOTIFF_NODATA`]), width, height.
struct Level {
    values: Vec<f32>,
    w: usize,
    h: usize,
}

/// The next overview: 2 × 2 means of the valid values.
fn halve(l: &Level) -> Level {
    let (w, h) = (l.w.div_ceil(2), l.h.div_ceil(2));
    let mut values = vec![GEOTIFF_NODATA; w * h];
    for r in 0..h {
        for c in 0..w {
            let (mut sum, mut n) = (0.0f64, 0u32);
            for (dr, dc) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
                let (rr, cc) = (2 * r + dr, 2 * c + dc);
                if rr < l.h && cc < l.w {
                    let v = l.values[rr * l.w + cc];
                    if v != GEOTIFF_NODATA {
                        sum += f64::from(v);
                        n += 1;
                    }
                }
            }
            if n > 0 {
                values[r * w + c] = (sum / f64::from(n)) as f32;
            }
        }
    }
    Level { values, w, h }
}

/// The compressed tiles of a level, row-major.
fn tiles(l: &Level) -> std::io::Result<Vec<Vec<u8>>> {
    let (tx, ty) = (l.w.div_ceil(COG_TILE), l.h.div_ceil(COG_TILE));
    let mut out = Vec::with_capacity(tx * ty);
    let mut raw = Vec::with_capacity(COG_TILE * COG_TILE * 4);
    let mut row = vec![0u8; COG_TILE * 4];
    for j in 0..ty {
        for i in 0..tx {
            raw.clear();
            for r in 0..COG_TILE {
                // The floating-point predictor: byte planes, most significant first, then
                // horizontal differences over the row's bytes.
                for c in 0..COG_TILE {
                    let (rr, cc) = (j * COG_TILE + r, i * COG_TILE + c);
                    let v = if rr < l.h && cc < l.w {
                        l.values[rr * l.w + cc]
                    } else {
                        GEOTIFF_NODATA
                    };
                    let b = v.to_be_bytes();
                    for (plane, byte) in b.iter().enumerate() {
                        row[plane * COG_TILE + c] = *byte;
                    }
                }
                for k in (1..row.len()).rev() {
                    row[k] = row[k].wrapping_sub(row[k - 1]);
                }
                raw.extend_from_slice(&row);
            }
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
            z.write_all(&raw)?;
            out.push(z.finish()?);
        }
    }
    Ok(out)
}

/// A TIFF tag value.
enum Value {
    Short(Vec<u16>),
    Long(Vec<u32>),
    Double(Vec<f64>),
    Ascii(String),
}

impl Value {
    fn kind_count_bytes(&self) -> (u16, u32, Vec<u8>) {
        match self {
            Value::Short(v) => (
                3,
                v.len() as u32,
                v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            ),
            Value::Long(v) => (
                4,
                v.len() as u32,
                v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            ),
            Value::Double(v) => (
                12,
                v.len() as u32,
                v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            ),
            Value::Ascii(s) => {
                let mut b = s.as_bytes().to_vec();
                b.push(0);
                (2, b.len() as u32, b)
            }
        }
    }
}

/// An IFD at `at` (its entries, then the values that do not fit in 4 bytes), linking to
/// `next` (0: the last).
fn ifd_bytes(tags: &[(u16, Value)], at: u32, next: u32) -> Vec<u8> {
    let n = tags.len();
    let table = 2 + 12 * n + 4;
    let mut entries = Vec::with_capacity(table);
    let mut extra: Vec<u8> = Vec::new();
    entries.extend_from_slice(&(n as u16).to_le_bytes());
    for (tag, value) in tags {
        let (kind, count, bytes) = value.kind_count_bytes();
        entries.extend_from_slice(&tag.to_le_bytes());
        entries.extend_from_slice(&kind.to_le_bytes());
        entries.extend_from_slice(&count.to_le_bytes());
        if bytes.len() <= 4 {
            let mut v = bytes.clone();
            v.resize(4, 0);
            entries.extend_from_slice(&v);
        } else {
            let off = at + table as u32 + extra.len() as u32;
            entries.extend_from_slice(&off.to_le_bytes());
            extra.extend_from_slice(&bytes);
            if extra.len() % 2 == 1 {
                extra.push(0);
            }
        }
    }
    entries.extend_from_slice(&next.to_le_bytes());
    entries.extend_from_slice(&extra);
    entries
}

/// The tags of a level's IFD (sorted by tag number), with its tile offsets and byte counts.
fn level_tags(
    grid: &Grid,
    l: &Level,
    overview: bool,
    offsets: Vec<u32>,
    counts: Vec<u32>,
) -> Vec<(u16, Value)> {
    let mut tags = vec![
        (254, Value::Long(vec![u32::from(overview)])),
        (256, Value::Long(vec![l.w as u32])),
        (257, Value::Long(vec![l.h as u32])),
        (258, Value::Short(vec![32])),
        (259, Value::Short(vec![8])),
        (262, Value::Short(vec![1])),
        (277, Value::Short(vec![1])),
        (284, Value::Short(vec![1])),
        (317, Value::Short(vec![3])),
        (322, Value::Short(vec![COG_TILE as u16])),
        (323, Value::Short(vec![COG_TILE as u16])),
        (324, Value::Long(offsets)),
        (325, Value::Long(counts)),
        (339, Value::Short(vec![3])),
    ];
    if !overview {
        let g = grid.geometry();
        let t = g.transform();
        tags.push((
            33550,
            Value::Double(vec![t.pixel_width, t.pixel_height, 0.0]),
        ));
        tags.push((
            33922,
            Value::Double(vec![0.0, 0.0, 0.0, t.origin_x, t.origin_y, 0.0]),
        ));
        let (dir, ascii) = geokeys::encode(g.crs());
        tags.push((34735, Value::Short(dir)));
        if let Some(a) = ascii {
            tags.push((34737, Value::Ascii(a)));
        }
    }
    if grid.mask().has_nodata() {
        tags.push((42113, Value::Ascii(format!("{GEOTIFF_NODATA}"))));
    }
    tags
}

/// Writes `grid` as a single-band f32 Cloud-Optimized GeoTIFF (module documentation),
/// atomically.
pub fn write_cog(path: &Path, grid: &Grid) -> Result<()> {
    let g = grid.geometry();
    let too_big = |what: &'static str| RasterError::UnsupportedOperation {
        path: path.to_path_buf(),
        format: "Cloud-Optimized GeoTIFF",
        what,
    };
    let mask = grid.mask();
    let mut levels = vec![Level {
        values: grid
            .data()
            .iter()
            .enumerate()
            .map(|(i, &v)| if mask.is_valid(i) { v } else { GEOTIFF_NODATA })
            .collect(),
        w: g.width(),
        h: g.height(),
    }];
    while levels.last().is_some_and(|l| l.w.max(l.h) > COG_TILE) {
        let next = halve(levels.last().expect("a level"));
        levels.push(next);
    }
    let io = |e: std::io::Error| RasterError::Io {
        path: path.to_path_buf(),
        source: e,
    };
    let data: Vec<Vec<Vec<u8>>> = levels
        .iter()
        .map(tiles)
        .collect::<std::io::Result<_>>()
        .map_err(io)?;
    // IFD sizes do not depend on the offsets they hold: lay them out with zeros first.
    let ghost = ghost_header();
    let mut at = 8 + ghost.len() as u32;
    let mut ifd_at = Vec::new();
    for (k, l) in levels.iter().enumerate() {
        ifd_at.push(at);
        let n = data[k].len();
        let size = ifd_bytes(&level_tags(grid, l, k > 0, vec![0; n], vec![0; n]), at, 0).len();
        at += size as u32 + (size % 2) as u32;
    }
    // Tile data: smallest overview first; each tile = u32 size, data, last 4 bytes again.
    let mut cursor = u64::from(at);
    let mut offsets: Vec<Vec<u32>> = vec![Vec::new(); levels.len()];
    for k in (0..levels.len()).rev() {
        for t in &data[k] {
            cursor += 4;
            offsets[k]
                .push(u32::try_from(cursor).map_err(|_| too_big("over 4 GiB (classic TIFF)"))?);
            cursor += t.len() as u64 + 4;
        }
    }
    if cursor > u64::from(u32::MAX) {
        return Err(too_big("over 4 GiB (classic TIFF)"));
    }
    let mut out = Vec::with_capacity(cursor as usize);
    out.extend_from_slice(b"II");
    out.extend_from_slice(&42u16.to_le_bytes());
    out.extend_from_slice(&ifd_at[0].to_le_bytes());
    out.extend_from_slice(&ghost);
    for (k, l) in levels.iter().enumerate() {
        let next = ifd_at.get(k + 1).copied().unwrap_or(0);
        let counts = data[k].iter().map(|t| t.len() as u32).collect();
        let bytes = ifd_bytes(
            &level_tags(grid, l, k > 0, offsets[k].clone(), counts),
            ifd_at[k],
            next,
        );
        out.extend_from_slice(&bytes);
        if bytes.len() % 2 == 1 {
            out.push(0);
        }
    }
    for k in (0..levels.len()).rev() {
        for t in &data[k] {
            out.extend_from_slice(&(t.len() as u32).to_le_bytes());
            out.extend_from_slice(t);
            let tail = &t[t.len().saturating_sub(4)..];
            out.extend_from_slice(tail);
            out.extend(std::iter::repeat_n(0u8, 4 - tail.len()));
        }
    }
    write_bytes_atomic(path, &out)?;
    Ok(())
}
