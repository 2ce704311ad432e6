//! A (Geo)TIFF read a window of rows at a time ([`TiffRows`]): only the chunks (strips or tiles)
//! that overlap the window are decoded, so the memory is that of the window, not of the file,
//! and a 16384² raster can be resampled in a few megabytes. Each window holds the cells and
//! the nodata of the same rows of [`crate::read_dem`]'s grid, bit for bit (tested).

use super::read::{Opened, open_image, push_band1};
use crate::ReadOptions;
use crate::cells::CellSink;
use crate::error::{RasterError, Result, geometry_err, tiff_err};
use snowscape_terrain::{GeoTransform, Grid, GridGeometry};
use std::ops::Range;
use std::path::{Path, PathBuf};
use tiff::decoder::ChunkType;

/// A (Geo)TIFF opened for reading windows of rows (band 1, as [`crate::read_dem`] reads it).
pub struct TiffRows {
    path: PathBuf,
    opened: Opened,
    /// Chunk width and height, cells (a strip spans the width).
    chunk: (usize, usize),
    /// The last band of chunks decoded (its index and its chunks, left to right): windows
    /// that share a band (a 512-row COG tile read 64 rows at a time) decode it once.
    band: Option<(usize, Vec<Chunk>)>,
}

/// One decoded chunk: its data width and its cells (values, and which are nodata).
struct Chunk {
    width: usize,
    values: Vec<f32>,
    nodata: Vec<bool>,
}

impl TiffRows {
    /// Opens `path` and reads its tags (no cell yet); the options as for [`crate::read_dem`].
    pub fn open(path: &Path, opts: &ReadOptions) -> Result<Self> {
        opts.validate(path)?;
        let opened = open_image(path, opts)?;
        let (cw, ch) = opened.dec.chunk_dimensions();
        let chunk = match opened.dec.get_chunk_type() {
            ChunkType::Strip => (opened.width, ch as usize),
            ChunkType::Tile => (cw as usize, ch as usize),
        };
        if chunk.0 == 0 || chunk.1 == 0 {
            return Err(RasterError::TiffUnsupported {
                path: path.to_path_buf(),
                what: format!("chunks of {}x{} cells", chunk.0, chunk.1),
            });
        }
        Ok(Self {
            path: path.to_path_buf(),
            opened,
            chunk,
            band: None,
        })
    }

    /// The whole raster's geometry.
    pub fn geometry(&self) -> &GridGeometry {
        &self.opened.geometry
    }

    /// The whole raster, as [`crate::read_dem`] reads it.
    pub(crate) fn read_all(mut self) -> Result<Grid> {
        let (w, h) = (self.opened.width, self.opened.height);
        let path = self.path.clone();
        let mut sink = CellSink::new(&path, w, h, self.opened.rule);
        self.push_rows(&path, 0..h, &mut sink)?;
        sink.finish(self.opened.geometry)
    }

    /// Rows `rows` of the raster as a grid of the raster's width: its transform is the file's
    /// moved down by `rows.start` rows (same CRS).
    pub fn read_rows(&mut self, rows: Range<usize>) -> Result<Grid> {
        let (w, h) = (self.opened.width, self.opened.height);
        if rows.start >= rows.end || rows.end > h {
            return Err(RasterError::TiffUnsupported {
                path: self.path.clone(),
                what: format!("rows {}..{} of a {h}-row image", rows.start, rows.end),
            });
        }
        let path = self.path.clone();
        let mut sink =
            CellSink::new(&path, w, rows.len(), self.opened.rule).starting_at(0, rows.start);
        self.push_rows(&path, rows.clone(), &mut sink)?;
        let t = *self.opened.geometry.transform();
        let moved = GeoTransform {
            origin_y: t.origin_y - rows.start as f64 * t.pixel_height,
            ..t
        };
        let geometry =
            GridGeometry::from_transform(w, rows.len(), moved, self.opened.geometry.crs().cloned())
                .map_err(geometry_err(&path))?;
        sink.finish(geometry)
    }

    /// Decodes the chunks over `rows` (a band of chunks at a time, the last band kept) and
    /// pushes those rows into `sink`.
    fn push_rows(&mut self, path: &Path, rows: Range<usize>, sink: &mut CellSink) -> Result<()> {
        let w = self.opened.width;
        let (cw, ch) = self.chunk;
        let across = w.div_ceil(cw);
        for chunk_row in rows.start / ch..=(rows.end - 1) / ch {
            if self.band.as_ref().is_none_or(|(b, _)| *b != chunk_row) {
                // The chunks of this band of rows, decoded to band 1, left to right.
                let mut chunks = Vec::with_capacity(across);
                for tc in 0..across {
                    let index = (chunk_row * across + tc) as u32;
                    let at = (tc * cw, chunk_row * ch);
                    chunks.push(decode_chunk(path, &mut self.opened, index, at)?);
                }
                self.band = Some((chunk_row, chunks));
            }
            let Some((_, chunks)) = &self.band else {
                unreachable!("the band was decoded above");
            };
            let top = chunk_row * ch;
            for r in rows.start.max(top)..rows.end.min(top + ch) {
                for chunk in chunks {
                    let line = (r - top) * chunk.width..(r - top + 1) * chunk.width;
                    for k in line {
                        if chunk.nodata[k] {
                            sink.push_nodata();
                        } else {
                            sink.push_data(chunk.values[k]);
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// Chunk `index`, whose first cell is `at` (column, row) in the file, decoded to band 1 and
/// classified by the file's nodata rule as a whole-image read classifies it.
fn decode_chunk(path: &Path, opened: &mut Opened, index: u32, at: (usize, usize)) -> Result<Chunk> {
    let (dw, dh) = opened.dec.chunk_data_dimensions(index);
    let (dw, dh) = (dw as usize, dh as usize);
    let samples = opened.dec.read_chunk(index).map_err(tiff_err(path))?;
    let mut sink = CellSink::new(path, dw, dh, opened.rule).starting_at(at.0, at.1);
    push_band1(path, &mut sink, samples, dw * dh, opened.stride)?;
    let (values, nodata) = sink.into_parts();
    Ok(Chunk {
        width: dw,
        values,
        nodata,
    })
}
