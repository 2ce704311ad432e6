//! The rasters a preview is drawn from, at the output resolution.
//!
//! A grid whose longest side exceeds the requested `max_size` is reduced by an integer factor
//! `f = ceil(longest / max_size)` with a box average over `f x f` blocks (the last block of a
//! row or column may be partial). Only valid cells enter an average; a block is nodata when
//! fewer than half its cells are valid. The cell size grows by `f`, so slopes and shadows stay
//! metric. Grids already small enough are borrowed, not copied.

use crate::RenderError;
use rayon::prelude::*;
use snowscape_terrain::{GridGeometry, NodataMask};
use std::borrow::Cow;

/// Bedrock, optional snow layers and an optional named map over one geometry.
pub struct Planes<'a> {
    /// The output-resolution geometry (local metric; georeferencing is irrelevant here).
    pub geometry: GridGeometry,
    /// Which output cells hold data.
    pub mask: Cow<'a, NodataMask>,
    /// Bedrock altitude, metres.
    pub bedrock: Cow<'a, [f32]>,
    /// Compacted, stable, unstable and powder thickness, metres (absent for a bare DEM).
    pub snow: Option<[Cow<'a, [f32]>; 4]>,
    /// The map drawn in `ColourMode::Map`.
    pub map: Option<Cow<'a, [f32]>>,
}

/// The source rasters at full resolution.
pub struct Source<'a> {
    /// Full-resolution geometry.
    pub geometry: &'a GridGeometry,
    /// Full-resolution nodata mask.
    pub mask: &'a NodataMask,
    /// Bedrock altitude, metres.
    pub bedrock: &'a [f32],
    /// Snow layers, metres.
    pub snow: Option<[&'a [f32]; 4]>,
    /// The map to draw.
    pub map: Option<&'a [f32]>,
}

/// The integer reduction factor that brings the longest side to at most `max_size`.
pub fn reduction_factor(width: usize, height: usize, max_size: Option<usize>) -> usize {
    match max_size {
        Some(m) if m > 0 => width.max(height).div_ceil(m).max(1),
        _ => 1,
    }
}

/// Checks that `values` has one value per cell of `geometry`.
pub fn check_length(
    what: &str,
    values: &[f32],
    geometry: &GridGeometry,
) -> Result<(), RenderError> {
    if values.len() == geometry.len() {
        Ok(())
    } else {
        Err(RenderError::LengthMismatch {
            what: what.to_string(),
            width: geometry.width(),
            height: geometry.height(),
            expected: geometry.len(),
            actual: values.len(),
        })
    }
}

impl<'a> Planes<'a> {
    /// The planes of `source` reduced so the longest side is at most `max_size` pixels.
    pub fn build(source: Source<'a>, max_size: Option<usize>) -> Result<Self, RenderError> {
        let g = source.geometry;
        if max_size == Some(0) {
            return Err(RenderError::InvalidCount {
                name: "max_size",
                value: 0,
                expected: "at least 1 pixel",
            });
        }
        let f = reduction_factor(g.width(), g.height(), max_size);
        if f == 1 {
            return Ok(Self {
                geometry: g.clone(),
                mask: Cow::Borrowed(source.mask),
                bedrock: Cow::Borrowed(source.bedrock),
                snow: source.snow.map(|s| s.map(Cow::Borrowed)),
                map: source.map.map(Cow::Borrowed),
            });
        }
        let blocks = Blocks {
            width: g.width(),
            height: g.height(),
            factor: f,
            mask: source.mask,
        };
        let (out_w, out_h) = blocks.output_size();
        let geometry = GridGeometry::new(
            out_w,
            out_h,
            g.cell_size_x() * f as f64,
            g.cell_size_y() * f as f64,
        )
        .map_err(|_| RenderError::ImageTooLarge {
            width: out_w,
            height: out_h,
            limit: "not a valid grid geometry",
        })?;
        let average = |v: &[f32]| Cow::Owned(blocks.average(v));
        Ok(Self {
            geometry,
            mask: Cow::Owned(blocks.validity()),
            bedrock: average(source.bedrock),
            snow: source.snow.map(|s| s.map(average)),
            map: source.map.map(average),
        })
    }
}

/// Box-averaging over `factor x factor` blocks of a `width x height` grid.
struct Blocks<'a> {
    width: usize,
    height: usize,
    factor: usize,
    mask: &'a NodataMask,
}

impl Blocks<'_> {
    fn output_size(&self) -> (usize, usize) {
        (
            self.width.div_ceil(self.factor),
            self.height.div_ceil(self.factor),
        )
    }

    /// Column range and row range of the source cells in output cell `(oc, or)`.
    fn extent(&self, oc: usize, or: usize) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
        let f = self.factor;
        (
            oc * f..((oc + 1) * f).min(self.width),
            or * f..((or + 1) * f).min(self.height),
        )
    }

    /// Output mask: a block is valid when at least half its cells are.
    fn validity(&self) -> NodataMask {
        if !self.mask.has_nodata() {
            return NodataMask::all_valid();
        }
        let (ow, oh) = self.output_size();
        let mut invalid = vec![false; ow * oh];
        invalid
            .par_chunks_mut(ow)
            .enumerate()
            .for_each(|(or, line)| {
                for (oc, bad) in line.iter_mut().enumerate() {
                    let (cols, rows) = self.extent(oc, or);
                    let total = cols.len() * rows.len();
                    let valid = rows
                        .flat_map(|r| cols.clone().map(move |c| r * self.width + c))
                        .filter(|&i| self.mask.is_valid(i))
                        .count();
                    *bad = 2 * valid < total;
                }
            });
        NodataMask::from_invalid(invalid)
    }

    /// Mean of the valid cells of each block (0 where none is valid).
    fn average(&self, values: &[f32]) -> Vec<f32> {
        let (ow, oh) = self.output_size();
        let f = self.factor;
        let mut out = vec![0.0f32; ow * oh];
        out.par_chunks_mut(ow).enumerate().for_each(|(or, line)| {
            let mut sums = vec![0.0f64; ow];
            let mut counts = vec![0u32; ow];
            let (_, rows) = self.extent(0, or);
            for r in rows {
                let src = &values[r * self.width..(r + 1) * self.width];
                let invalid = self
                    .mask
                    .invalid_cells()
                    .map(|m| &m[r * self.width..(r + 1) * self.width]);
                for (oc, block) in src.chunks(f).enumerate() {
                    let (sum, n) = match invalid {
                        None => (block.iter().sum::<f32>(), block.len() as u32),
                        Some(m) => block
                            .iter()
                            .zip(&m[oc * f..])
                            .filter(|&(_, &bad)| !bad)
                            .fold((0.0f32, 0u32), |(s, n), (&v, _)| (s + v, n + 1)),
                    };
                    sums[oc] += sum as f64;
                    counts[oc] += n;
                }
            }
            for ((o, s), n) in line.iter_mut().zip(sums).zip(counts) {
                *o = if n > 0 { (s / n as f64) as f32 } else { 0.0 };
            }
        });
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factor_keeps_the_longest_side_within_max_size() {
        assert_eq!(reduction_factor(8192, 4096, Some(1024)), 8);
        assert_eq!(reduction_factor(1500, 10, Some(1024)), 2);
        assert_eq!(reduction_factor(1024, 1024, Some(1024)), 1);
        assert_eq!(reduction_factor(5000, 5000, None), 1);
    }

    #[test]
    fn block_average_skips_nodata_and_flags_mostly_empty_blocks() {
        // 3x2 grid, factor 2: blocks {0,1,3,4} and the partial {2,5}.
        let geometry = GridGeometry::square(3, 2, 1.0).unwrap();
        let mask = NodataMask::from_invalid(vec![false, true, true, false, false, false]);
        let values = [1.0, 99.0, 99.0, 3.0, 5.0, 7.0];
        let planes = Planes::build(
            Source {
                geometry: &geometry,
                mask: &mask,
                bedrock: &values,
                snow: None,
                map: None,
            },
            Some(2),
        )
        .unwrap();
        assert_eq!((planes.geometry.width(), planes.geometry.height()), (2, 1));
        assert_eq!(planes.geometry.cell_size_x(), 2.0);
        assert_eq!(&planes.bedrock[..], &[3.0, 7.0]);
        // Block 0 has 3 valid cells of 4; block 1 has 1 of 2: both valid.
        assert!(planes.mask.is_valid(0) && planes.mask.is_valid(1));
    }
}
