//! Matching an observed raster and a mask to the cells of a run by map coordinates (CRS
//! units), whatever their cell sizes and extents.
//!
//! - An observed raster FINER than the run (pixels smaller along both axes) is block-averaged:
//!   a run cell gets the area-weighted mean of the valid observed cells its footprint overlaps
//!   (weights = overlap areas). It is compared when at least half of its footprint lies inside
//!   the observed raster and at least half of that part is valid data.
//! - An observed raster as coarse as the run or coarser is sampled bilinearly at the run
//!   cell's centre ([`Grid::sample`]: nodata corners left out, weights renormalised); the
//!   observed cell containing the centre must be valid.
//! - The mask is sampled at the centre by nearest cell (a category is not interpolated): a
//!   valid non-zero value keeps the cell; zero, nodata, or outside the mask drops it.
//!
//! Observed values are used as they are (lidar depths may be slightly negative over bare
//! ground; clamping them would bias the comparison).

use serde::Serialize;
use snowscape_terrain::{Grid, GridGeometry};
use std::fmt;

/// The rectangle a raster covers, in CRS units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Extent {
    pub x_min: f64,
    pub x_max: f64,
    pub y_min: f64,
    pub y_max: f64,
}

impl Extent {
    /// The extent of a grid.
    pub fn of(g: &GridGeometry) -> Self {
        let [x_min, y_min, x_max, y_max] = g.map_bounds();
        Self {
            x_min,
            x_max,
            y_min,
            y_max,
        }
    }

    /// Whether the two rectangles share some area.
    pub fn overlaps(&self, other: &Extent) -> bool {
        self.x_min < other.x_max
            && other.x_min < self.x_max
            && self.y_min < other.y_max
            && other.y_min < self.y_max
    }
}

impl fmt::Display for Extent {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "x {}..{}, y {}..{}",
            self.x_min, self.x_max, self.y_min, self.y_max
        )
    }
}

/// How the observed raster was sampled onto the run's cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Sampling {
    BlockAverage,
    Bilinear,
}

impl Sampling {
    /// The method in words.
    pub fn name(self) -> &'static str {
        match self {
            Sampling::BlockAverage => "block-average",
            Sampling::Bilinear => "bilinear",
        }
    }
}

/// What a run cell got from a raster matched onto it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CellSample {
    Value(f64),
    /// The cell lies (mostly) outside the raster.
    Outside,
    /// The raster has no valid data there.
    Nodata,
}

/// Whether `observed` is finer than `run` along both axes (so block averaging applies).
pub fn sampling_for(run: &GridGeometry, observed: &GridGeometry) -> Sampling {
    let (r, o) = (run.transform(), observed.transform());
    if o.pixel_width < r.pixel_width && o.pixel_height < r.pixel_height {
        Sampling::BlockAverage
    } else {
        Sampling::Bilinear
    }
}

/// The observed value of every run cell (flat index order).
pub fn sample_observed(run: &GridGeometry, observed: &Grid) -> (Sampling, Vec<CellSample>) {
    let sampling = sampling_for(run, observed.geometry());
    let mut out = Vec::with_capacity(run.len());
    for row in 0..run.height() {
        for col in 0..run.width() {
            out.push(match sampling {
                Sampling::BlockAverage => block_average(run, col, row, observed),
                Sampling::Bilinear => bilinear(run, col, row, observed),
            });
        }
    }
    (sampling, out)
}

fn bilinear(run: &GridGeometry, col: usize, row: usize, observed: &Grid) -> CellSample {
    let g = observed.geometry();
    let (x, y) = run.cell_centre(col, row);
    let Some((c, r)) = g.map_to_cell(x, y) else {
        return CellSample::Outside;
    };
    let nc = (c.round().max(0.0) as usize).min(g.width() - 1);
    let nr = (r.round().max(0.0) as usize).min(g.height() - 1);
    if !observed.mask().is_valid(g.index(nc, nr)) {
        return CellSample::Nodata;
    }
    match observed.sample(c, r) {
        Some(v) => CellSample::Value(f64::from(v)),
        None => CellSample::Nodata,
    }
}

fn block_average(run: &GridGeometry, col: usize, row: usize, observed: &Grid) -> CellSample {
    let (g, t) = (observed.geometry(), observed.geometry().transform());
    let rt = run.transform();
    let x0 = rt.origin_x + col as f64 * rt.pixel_width;
    let x1 = x0 + rt.pixel_width;
    let y1 = rt.origin_y - row as f64 * rt.pixel_height;
    let y0 = y1 - rt.pixel_height;
    let footprint = rt.pixel_width * rt.pixel_height;
    // Observed columns and rows the footprint may overlap, clamped to the raster.
    let span = |lo: f64, hi: f64, n: usize| -> Option<(usize, usize)> {
        let (a, b) = (lo.floor().max(0.0), (hi.ceil() - 1.0).min(n as f64 - 1.0));
        (a <= b).then_some((a as usize, b as usize))
    };
    let cols = span(
        (x0 - t.origin_x) / t.pixel_width,
        (x1 - t.origin_x) / t.pixel_width,
        g.width(),
    );
    let rows = span(
        (t.origin_y - y1) / t.pixel_height,
        (t.origin_y - y0) / t.pixel_height,
        g.height(),
    );
    let (Some((c0, c1)), Some((r0, r1))) = (cols, rows) else {
        return CellSample::Outside;
    };
    let (mut inside, mut valid, mut sum) = (0.0, 0.0, 0.0);
    for r in r0..=r1 {
        let top = t.origin_y - r as f64 * t.pixel_height;
        let dy = top.min(y1) - (top - t.pixel_height).max(y0);
        if dy <= 0.0 {
            continue;
        }
        for c in c0..=c1 {
            let left = t.origin_x + c as f64 * t.pixel_width;
            let dx = (left + t.pixel_width).min(x1) - left.max(x0);
            if dx <= 0.0 {
                continue;
            }
            let w = dx * dy;
            inside += w;
            let i = g.index(c, r);
            if observed.mask().is_valid(i) {
                valid += w;
                sum += w * f64::from(observed.data()[i]);
            }
        }
    }
    if inside < 0.5 * footprint {
        CellSample::Outside
    } else if valid < 0.5 * inside {
        CellSample::Nodata
    } else {
        CellSample::Value(sum / valid)
    }
}

/// What the mask says of a run cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MaskSample {
    Use,
    /// Zero or nodata in the mask.
    MaskedOut,
    Outside,
}

/// The mask at every run cell's centre, nearest cell (flat index order).
pub fn sample_mask(run: &GridGeometry, mask: &Grid) -> Vec<MaskSample> {
    let g = mask.geometry();
    let mut out = Vec::with_capacity(run.len());
    for row in 0..run.height() {
        for col in 0..run.width() {
            let (x, y) = run.cell_centre(col, row);
            out.push(match g.map_to_cell(x, y) {
                None => MaskSample::Outside,
                Some((c, r)) => {
                    let nc = (c.round().max(0.0) as usize).min(g.width() - 1);
                    let nr = (r.round().max(0.0) as usize).min(g.height() - 1);
                    let i = g.index(nc, nr);
                    if mask.mask().is_valid(i) && mask.data()[i] != 0.0 {
                        MaskSample::Use
                    } else {
                        MaskSample::MaskedOut
                    }
                }
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_terrain::{GeoTransform, NodataMask};

    fn grid(
        w: usize,
        h: usize,
        ox: f64,
        oy: f64,
        px: f64,
        f: impl Fn(usize, usize) -> f32,
    ) -> Grid {
        let t = GeoTransform {
            origin_x: ox,
            origin_y: oy,
            pixel_width: px,
            pixel_height: px,
        };
        Grid::from_fn(GridGeometry::from_transform(w, h, t, None).unwrap(), f)
    }

    #[test]
    fn a_finer_raster_is_block_averaged_by_overlap_area() {
        // Run: 2x1 cells of 10 m from (0, 10). Observed: 5 m cells from (-2.5, 12.5), so run
        // cell 0 (x 0..10, y 0..10) overlaps observed columns 0..=2 and rows 0..=2 by
        // 2.5, 5, 2.5 m along each axis.
        let run = GridGeometry::from_transform(
            2,
            1,
            GeoTransform {
                origin_x: 0.0,
                origin_y: 10.0,
                pixel_width: 10.0,
                pixel_height: 10.0,
            },
            None,
        )
        .unwrap();
        let obs = grid(6, 4, -2.5, 12.5, 5.0, |c, r| (c + 10 * r) as f32);
        let (s, v) = sample_observed(&run, &obs);
        assert_eq!(s, Sampling::BlockAverage);
        // Weights 1/4, 1/2, 1/4 per axis: the mean of c + 10 r is 1 + 10·1 = 11.
        assert_eq!(v[0], CellSample::Value(11.0));
        assert_eq!(v[1], CellSample::Value(13.0));
    }

    #[test]
    fn coarse_rasters_are_bilinear_and_nodata_or_outside_cells_are_flagged() {
        let run = GridGeometry::square(4, 1, 10.0).unwrap(); // x 0..40, y 0..10
        // Observed: 20 m cells from x = 0, value = column; nodata in column 1.
        let t = GeoTransform {
            origin_x: 0.0,
            origin_y: 20.0,
            pixel_width: 20.0,
            pixel_height: 20.0,
        };
        let g = GridGeometry::from_transform(3, 1, t, None).unwrap();
        let obs = Grid::new(
            g,
            vec![0.0, 1.0, 2.0],
            NodataMask::from_invalid(vec![false, false, true]),
        )
        .unwrap();
        let (s, v) = sample_observed(&run, &obs);
        assert_eq!(s, Sampling::Bilinear);
        // Centres x = 5, 15 (col 0 -> 0.25 .. col 1 -> -0.25 of fractional col) ...
        assert_eq!(v[0], CellSample::Value(0.0)); // clamped at the border
        assert_eq!(v[1], CellSample::Value(0.25));
        assert_eq!(v[2], CellSample::Value(0.75));
        assert_eq!(v[3], CellSample::Value(1.0)); // the nodata corner is left out
        let far = grid(2, 2, 100.0, 100.0, 20.0, |_, _| 1.0);
        let (_, v) = sample_observed(&run, &far);
        assert!(v.iter().all(|s| *s == CellSample::Outside));
        assert!(!Extent::of(&run).overlaps(&Extent::of(far.geometry())));
        assert!(Extent::of(&run).overlaps(&Extent::of(obs.geometry())));
    }

    #[test]
    fn the_mask_is_nearest_and_nonzero_means_use() {
        let run = GridGeometry::square(3, 1, 10.0).unwrap();
        let mask = grid(2, 1, 0.0, 10.0, 10.0, |c, _| c as f32);
        let m = sample_mask(&run, &mask);
        assert_eq!(
            m,
            vec![MaskSample::MaskedOut, MaskSample::Use, MaskSample::Outside]
        );
    }
}
