//! Helpers shared by the integration tests.
#![allow(dead_code)]

use snowscape_terrain::{Crs, GeoTransform, Grid, GridGeometry, NodataMask};
use std::path::{Path, PathBuf};

/// A georeferenced grid with distinct non-integer values; with `nodata`, a border ring of
/// nodata cells like the AvaFrame DEMs.
pub fn sample_grid(w: usize, h: usize, crs: Option<Crs>, nodata: bool) -> Grid {
    let t = GeoTransform {
        origin_x: 176_973.25,
        origin_y: 378_821.5,
        pixel_width: 5.0,
        pixel_height: 4.0,
    };
    let geo = GridGeometry::from_transform(w, h, t, crs).unwrap();
    let data: Vec<f32> = (0..w * h)
        .map(|i| 1000.0 + (i % w) as f32 * 1.25 + (i / w) as f32 * 0.37 + (i as f32).sin())
        .collect();
    let invalid: Vec<bool> = (0..w * h)
        .map(|i| nodata && ((i % w) == 0 || (i / w) == h - 1))
        .collect();
    Grid::new(geo, data, NodataMask::from_invalid(invalid)).unwrap()
}

/// A small grid in degrees (WGS84), 3 arc-seconds, at 40 N.
pub fn degree_grid(w: usize, h: usize) -> Grid {
    let t = GeoTransform {
        origin_x: -105.9,
        origin_y: 40.5,
        pixel_width: 1.0 / 1200.0,
        pixel_height: 1.0 / 1200.0,
    };
    let geo = GridGeometry::from_transform(w, h, t, Some(Crs::Epsg(4326))).unwrap();
    Grid::from_fn(geo, |c, r| 2500.0 + c as f32 - r as f32 * 0.5)
}

/// Asserts two grids hold the same cells, mask and values (within `tol`).
pub fn assert_same_cells(a: &Grid, b: &Grid, tol: f32) {
    assert_eq!(a.geometry().width(), b.geometry().width());
    assert_eq!(a.geometry().height(), b.geometry().height());
    assert_eq!(a.mask(), b.mask());
    for (i, (x, y)) in a.data().iter().zip(b.data()).enumerate() {
        assert!((x - y).abs() <= tol, "cell {i}: {x} vs {y}");
    }
}

/// Asserts a file or folder entry does not exist and that `dir` holds only `expected` entries.
pub fn assert_dir_entries(dir: &Path, expected: usize) {
    let names: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(names.len(), expected, "{names:?}");
}

/// One extra IFD entry of a hand-made TIFF: tag, field type, count, little-endian value bytes.
pub type Entry = (u16, u16, u32, Vec<u8>);

pub fn f64_entry(tag: u16, v: &[f64]) -> Entry {
    (
        tag,
        12,
        v.len() as u32,
        v.iter().flat_map(|x| x.to_le_bytes()).collect(),
    )
}
pub fn u16_entry(tag: u16, v: &[u16]) -> Entry {
    (
        tag,
        3,
        v.len() as u32,
        v.iter().flat_map(|x| x.to_le_bytes()).collect(),
    )
}
pub fn ascii_entry(tag: u16, s: &str) -> Entry {
    let mut b = s.as_bytes().to_vec();
    b.push(0);
    (tag, 2, b.len() as u32, b)
}
fn u32_entry(tag: u16, v: &[u32]) -> Entry {
    (
        tag,
        4,
        v.len() as u32,
        v.iter().flat_map(|x| x.to_le_bytes()).collect(),
    )
}

/// A hand-made little-endian uncompressed u16 TIFF (the `tiff` encoder writes neither tiles
/// nor planar bands): `bands` planes of `w x h`; tiled with square `tile` size or stripped
/// with `rows_per_strip`; planar (PlanarConfiguration 2) or pixel-interleaved.
pub struct HandTiff {
    pub w: u32,
    pub h: u32,
    pub bands: Vec<Vec<u16>>,
    pub tile: Option<u32>,
    pub rows_per_strip: u32,
    pub planar: bool,
    pub extra: Vec<Entry>,
}

impl HandTiff {
    fn sample(&self, band: usize, c: u32, r: u32) -> u16 {
        if c < self.w && r < self.h {
            self.bands[band][(r * self.w + c) as usize]
        } else {
            0
        }
    }

    /// The chunks (tiles or strips) in file order, as u16 samples.
    fn chunks(&self) -> Vec<Vec<u16>> {
        let spp = self.bands.len();
        let planes: Vec<Option<usize>> = if self.planar {
            (0..spp).map(Some).collect()
        } else {
            vec![None]
        };
        let mut out = Vec::new();
        for plane in planes {
            let bands: Vec<usize> = plane.map_or((0..spp).collect(), |p| vec![p]);
            let (cw, ch) = match self.tile {
                Some(t) => (t, t),
                None => (self.w, self.rows_per_strip),
            };
            for y0 in (0..self.h).step_by(ch as usize) {
                for x0 in (0..self.w).step_by(cw as usize) {
                    let rows = if self.tile.is_some() {
                        ch
                    } else {
                        ch.min(self.h - y0)
                    };
                    let mut chunk = Vec::new();
                    for r in y0..y0 + rows {
                        for c in x0..x0 + cw {
                            for &b in &bands {
                                chunk.push(self.sample(b, c, r));
                            }
                        }
                    }
                    out.push(chunk);
                }
            }
        }
        out
    }

    pub fn bytes(&self) -> Vec<u8> {
        let spp = self.bands.len() as u16;
        let chunks = self.chunks();
        let mut entries: Vec<Entry> = vec![
            u32_entry(256, &[self.w]),
            u32_entry(257, &[self.h]),
            u16_entry(258, &vec![16; spp as usize]),
            u16_entry(259, &[1]),
            u16_entry(262, &[1]),
            u16_entry(277, &[spp]),
            u16_entry(284, &[if self.planar { 2 } else { 1 }]),
            u16_entry(339, &vec![1; spp as usize]),
        ];
        let counts: Vec<u32> = chunks.iter().map(|c| 2 * c.len() as u32).collect();
        let (off_tag, count_tag) = match self.tile {
            Some(t) => {
                entries.push(u32_entry(322, &[t]));
                entries.push(u32_entry(323, &[t]));
                (324, 325)
            }
            None => {
                entries.push(u32_entry(278, &[self.rows_per_strip]));
                (273, 279)
            }
        };
        entries.push(u32_entry(count_tag, &counts));
        entries.extend(self.extra.iter().cloned());
        // Offsets are filled in once the layout is known: reserve the entry now.
        entries.push(u32_entry(off_tag, &vec![0; chunks.len()]));
        entries.sort_by_key(|e| e.0);
        let ifd_len = 2 + 12 * entries.len() + 4;
        let mut data_at = 8 + ifd_len;
        let mut value_offsets = Vec::new();
        for e in &entries {
            if e.3.len() > 4 {
                value_offsets.push(Some(data_at as u32));
                data_at += e.3.len() + (e.3.len() & 1);
            } else {
                value_offsets.push(None);
            }
        }
        let mut chunk_offsets = Vec::new();
        for c in &chunks {
            chunk_offsets.push(data_at as u32);
            data_at += 2 * c.len();
        }
        let off_bytes: Vec<u8> = chunk_offsets.iter().flat_map(|x| x.to_le_bytes()).collect();
        for e in entries.iter_mut() {
            if e.0 == off_tag {
                e.3 = off_bytes.clone();
            }
        }
        let mut out = b"II*\0".to_vec();
        out.extend(8u32.to_le_bytes());
        out.extend((entries.len() as u16).to_le_bytes());
        for (e, off) in entries.iter().zip(&value_offsets) {
            out.extend(e.0.to_le_bytes());
            out.extend(e.1.to_le_bytes());
            out.extend(e.2.to_le_bytes());
            match off {
                Some(o) => out.extend(o.to_le_bytes()),
                None => {
                    let mut v = e.3.clone();
                    v.resize(4, 0);
                    out.extend(v);
                }
            }
        }
        out.extend(0u32.to_le_bytes());
        for e in &entries {
            if e.3.len() > 4 {
                out.extend(&e.3);
                if e.3.len() & 1 == 1 {
                    out.push(0);
                }
            }
        }
        for c in &chunks {
            out.extend(c.iter().flat_map(|x| x.to_le_bytes()));
        }
        out
    }
}
pub mod craft;
