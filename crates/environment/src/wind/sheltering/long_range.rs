//! The long-range maximum upwind slope `Sx_long` and the two-scale sheltering index
//! (parent module, "Two scales").
//!
//! **Coarse grid.** A search of `long_range_dmax_m` (1000 m) sampled every cell would take
//! 200 samples per ray on 5 m cells and 100 000 on 1 cm cells. The long search therefore runs
//! on a coarse grid: the surface averaged over blocks of `k × k` cells,
//! `k = max(1, ⌈long_range_cell_m / min(dx, dy)⌉)` (a block holding at least one valid cell
//! is valid and takes the mean of its valid cells; partial blocks at the east and south edges
//! are kept), searched by [`max_upwind_slope`] with `dmax = long_range_dmax_m` on cells of
//! `k·dx × k·dy`, and interpolated back to the grid's cells bilinearly between the centres of
//! the four nearest blocks (the valid ones, their weights renormalised; a cell's own block is
//! always among them). Nodata cells get 0. At `k = 1` (cells of `long_range_cell_m` or
//! coarser) the search runs on the grid itself.
//!
//! The value at a cell is thus the long search from its block's mean altitude: a crest cell
//! is seen at the altitude of the terrain around it, which is the scale this search is for;
//! the crest's own relief is the short search's.
//!
//! **Bounded by cells.** The coarse cells are at least `long_range_cell_m` a side (or the
//! grid's own cells where those are larger), so a ray takes at most
//! `⌊long_range_dmax_m / long_range_cell_m⌋` samples (20 for the defaults), and never more
//! than [`MAX_SX_STEPS`](super::MAX_SX_STEPS); there are `⌈w/k⌉·⌈h/k⌉ ≤ cells` coarse cells.
//! The work is `O(cells)` for the averaging and the interpolation plus
//! `O(cells / k² · rays · steps)` for the search: 0.2 samples per cell and ray on 5 m cells
//! (20 for the 100 m short search), 1.8 on 20 m cells (5) ([`LongRangePlan`], tested).
//!
//! **Determinism.** Block sums run in a fixed order within each block, rows in parallel; every
//! value is a pure function of the surface, so the maps are bit-identical for any thread count.

use super::{ShelteringParams, max_upwind_slope};
use crate::EnvironmentError;
use crate::error::check_param;
use crate::field::validate;
use rayon::prelude::*;
use snowscape_terrain::{GridGeometry, NodataMask};

/// How the long-range search runs on a grid: the coarse grid and the samples per ray.
#[derive(Debug, Clone, PartialEq)]
pub struct LongRangePlan {
    /// Cells a side of a coarse block.
    pub factor: usize,
    /// The coarse grid (local metric, cells of `factor · dx × factor · dy`).
    pub coarse: GridGeometry,
    /// Samples along each ray on the coarse grid (at most [`MAX_SX_STEPS`](super::MAX_SX_STEPS)).
    pub steps: usize,
}

impl LongRangePlan {
    /// The plan for `params` on a grid of `geometry`; `None` when the long range is off
    /// (`long_range_dmax_m` or `long_range_weight` is 0).
    pub fn new(params: &ShelteringParams, geometry: &GridGeometry) -> Option<Self> {
        if params.long_range_dmax_m <= 0.0 || params.long_range_weight <= 0.0 {
            return None;
        }
        let (dx, dy) = (geometry.cell_size_x(), geometry.cell_size_y());
        // `as usize` saturates, then the factor is bounded by the grid's size.
        let wanted = (params.long_range_cell_m / dx.min(dy) - 1e-9).ceil() as usize;
        let factor = wanted.clamp(1, geometry.width().max(geometry.height()));
        let coarse = GridGeometry::new(
            geometry.width().div_ceil(factor),
            geometry.height().div_ceil(factor),
            dx * factor as f64,
            dy * factor as f64,
        )
        .ok()?;
        let search = ShelteringParams {
            dmax_m: params.long_range_dmax_m,
            ..params.clone()
        };
        let steps = search.steps(&coarse);
        Some(Self {
            factor,
            coarse,
            steps,
        })
    }

    /// Samples of the search per cell of the grid and per ray: `coarse cells · steps / cells`.
    pub fn samples_per_cell(&self, geometry: &GridGeometry) -> f64 {
        (self.coarse.len() * self.steps) as f64 / geometry.len() as f64
    }
}

/// The long-range maximum upwind slope `Sx_long` of every cell, degrees (module docs), for
/// the wind blowing FROM `wind_from_deg`; all zeros when the long range is off.
pub fn long_range_upwind_slope(
    surface: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    wind_from_deg: f64,
    params: &ShelteringParams,
) -> Result<Vec<f32>, EnvironmentError> {
    params.validate()?;
    check_param("wind_from_deg", wind_from_deg, true, "must be finite")?;
    validate(surface, geometry, mask)?;
    let Some(plan) = LongRangePlan::new(params, geometry) else {
        return Ok(vec![0.0; geometry.len()]);
    };
    let search = ShelteringParams {
        dmax_m: params.long_range_dmax_m,
        ..params.clone()
    };
    if plan.factor == 1 {
        return max_upwind_slope(surface, geometry, mask, wind_from_deg, &search);
    }
    let (coarse_z, coarse_valid) = block_average(surface, geometry, mask, plan.factor);
    let coarse_mask = NodataMask::from_invalid(coarse_valid.iter().map(|v| !v).collect());
    let coarse_sx = max_upwind_slope(
        &coarse_z,
        &plan.coarse,
        &coarse_mask,
        wind_from_deg,
        &search,
    )?;
    Ok(interpolate_back(
        &coarse_sx,
        &coarse_valid,
        &plan,
        geometry,
        mask,
    ))
}

/// The sheltering index `Sx_short + w_long · Sx_long`, degrees (parent module, "Two scales").
pub fn sheltering_index(
    surface: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    wind_from_deg: f64,
    params: &ShelteringParams,
) -> Result<Vec<f32>, EnvironmentError> {
    let mut sx = max_upwind_slope(surface, geometry, mask, wind_from_deg, params)?;
    if LongRangePlan::new(params, geometry).is_some() {
        let long = long_range_upwind_slope(surface, geometry, mask, wind_from_deg, params)?;
        let w = params.long_range_weight as f32;
        sx.par_iter_mut()
            .zip(long.par_iter())
            .for_each(|(s, &l)| *s += w * l);
    }
    Ok(sx)
}

/// The surface averaged over `k × k` blocks (mean of the valid cells; a block without any is
/// nodata, its value 0), and which blocks hold data.
fn block_average(
    surface: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    k: usize,
) -> (Vec<f32>, Vec<bool>) {
    let (w, h) = (geometry.width(), geometry.height());
    let (cw, ch) = (w.div_ceil(k), h.div_ceil(k));
    let mut z = vec![0.0f32; cw * ch];
    let mut valid = vec![false; cw * ch];
    z.par_chunks_mut(cw)
        .zip(valid.par_chunks_mut(cw))
        .enumerate()
        .for_each(|(br, (zrow, vrow))| {
            let rows = br * k..((br + 1) * k).min(h);
            for (bc, (zc, vc)) in zrow.iter_mut().zip(vrow.iter_mut()).enumerate() {
                let cols = bc * k..((bc + 1) * k).min(w);
                let (mut sum, mut n) = (0.0f64, 0u32);
                for r in rows.clone() {
                    for c in cols.clone() {
                        let i = r * w + c;
                        if mask.is_valid(i) {
                            sum += f64::from(surface[i]);
                            n += 1;
                        }
                    }
                }
                if n > 0 {
                    *zc = (sum / f64::from(n)) as f32;
                    *vc = true;
                }
            }
        });
    (z, valid)
}

/// The coarse map `coarse` back on the grid's cells: bilinear between the centres of the four
/// nearest blocks, over the valid ones (module docs); 0 on nodata.
fn interpolate_back(
    coarse: &[f32],
    coarse_valid: &[bool],
    plan: &LongRangePlan,
    geometry: &GridGeometry,
    mask: &NodataMask,
) -> Vec<f32> {
    let (w, k) = (geometry.width(), plan.factor as f64);
    let (cw, ch) = (plan.coarse.width(), plan.coarse.height());
    // A cell's position in block units, split into the block before it and the fraction.
    let axis = |i: usize, n: usize| {
        let x = ((i as f64 + 0.5) / k - 0.5).clamp(0.0, (n - 1) as f64);
        let i0 = (x.floor() as usize).min(n - 1);
        let i1 = (i0 + 1).min(n - 1);
        (i0, i1, (x - i0 as f64) as f32)
    };
    let cols: Vec<(usize, usize, f32)> = (0..w).map(|c| axis(c, cw)).collect();
    let mut out = vec![0.0f32; geometry.len()];
    out.par_chunks_mut(w).enumerate().for_each(|(row, line)| {
        let (r0, r1, fr) = axis(row, ch);
        for (col, o) in line.iter_mut().enumerate() {
            if !mask.is_valid(row * w + col) {
                continue;
            }
            let (c0, c1, fc) = cols[col];
            let corners = [
                (r0 * cw + c0, (1.0 - fr) * (1.0 - fc)),
                (r0 * cw + c1, (1.0 - fr) * fc),
                (r1 * cw + c0, fr * (1.0 - fc)),
                (r1 * cw + c1, fr * fc),
            ];
            let (mut sum, mut weight) = (0.0f32, 0.0f32);
            for (j, wt) in corners {
                if coarse_valid[j] && wt > 0.0 {
                    sum += wt * coarse[j];
                    weight += wt;
                }
            }
            *o = if weight > 0.0 { sum / weight } else { 0.0 };
        }
    });
    out
}

#[cfg(test)]
mod tests;
