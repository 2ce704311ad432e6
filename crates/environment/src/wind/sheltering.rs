//! Wind sheltering: the maximum upwind slope `Sx` of Winstral, Marks & Gurney 2002
//! ("Simulating wind fields and snow redistribution using terrain-based parameters to model
//! snow accumulation and melt over a semi-arid mountain catchment", J. Hydrometeorol. 3,
//! 524-538).
//!
//! **Definition.** For a cell `i` and the direction `A` the wind blows FROM (meteorological,
//! clockwise from north),
//!
//! ```text
//! Sx_A(i) = max over upwind points v at distance d_v ≤ dmax of  atan((z(v) − z(i)) / d_v)
//! ```
//!
//! in degrees: positive where upwind terrain rises above the cell (sheltered, lee slopes and
//! hollows), negative where the terrain falls away upwind (exposed, windward slopes and crests).
//! Winstral et al. average `Sx` over a window of directions around the wind, `A ± 15°` in 5°
//! increments (seven rays); we do the same ([`ShelteringParams::window_half_deg`],
//! [`ShelteringParams::window_step_deg`]). `max` then `atan` equals `atan` then `max`
//! (atan is monotone), so each ray keeps the largest rise over distance and takes one `atan`.
//!
//! **Search distance in metres.** `dmax` is a distance, not a cell count, so the same terrain
//! gives the same `Sx` from 2 m to 100 m cells. Winstral et al. 2002 found `dmax = 100 m` best
//! for delineating drifts and scour in their catchment (Reynolds Mountain East, Idaho); later
//! studies use longer searches (e.g. 300 m) for the larger-scale wind exposure. Default: 100 m.
//! When `dmax` is below one cell the search still takes one cell.
//!
//! **Sampling.** Each ray is sampled every `min(dx, dy)` metres, at distances `s·min(dx, dy)`,
//! `s = 1..=max(1, ⌊dmax / min(dx, dy)⌋)`, by bilinear interpolation of the surface. The sample
//! offsets are the same for every cell, so the taps and weights are computed once per ray and
//! step and the inner loop runs along rows over a NaN-padded copy of the surface. A sample
//! whose bilinear stencil touches a nodata cell or leaves the grid is skipped (NaN, which
//! `f32::max` ignores). A ray with no valid sample does not enter the average; a cell none of
//! whose rays has a sample (e.g. the upwind grid border) gets `Sx = 0`, as if the terrain
//! beyond the grid were level with it. Nodata cells get 0.
//!
//! **Bounded by cells.** A ray never samples beyond the grid's diagonal (samples there all
//! fall outside the grid and are skipped anyway), and never more than [`MAX_SX_STEPS`]
//! samples: the step count is `min(⌊dmax / min(dx, dy)⌋, ⌈diagonal / min(dx, dy)⌉ + 1,
//! MAX_SX_STEPS)`, so the padded copy holds at most `(w + 2·pad)(h + 2·pad)` values with
//! `pad ≤ max(w, h)·max(dx, dy)/min(dx, dy)`-ish and in any case `pad ≤ MAX_SX_STEPS + 2`
//! cells: memory is bounded by the cell count, never by `dmax` divided by the cell size
//! (1 cm cells and the default 100 m once asked for a 20 000-cell pad, 1.5 GB for 32×32 cells).
//! At the cap a ray reaches `MAX_SX_STEPS·min(dx, dy)` (512 m on 1 m cells, 51 m on 10 cm).
//!
//! **Cost and determinism.** `O(cells · rays · min(dmax / min(dx, dy), MAX_SX_STEPS))`, parallel over rows; each
//! cell's value is a pure function of the surface, so the map is bit-identical for any thread
//! count.
//!
//! **Two scales: the sheltering index.** Snow redistribution follows the terrain at more than
//! one scale: the 100 m search delineates drifts and scour at the scale of a slope (Winstral
//! et al. 2002), while basin-scale exposure and shelter (a crest kilometres long, a cirque in
//! the lee of a range) need a search of the order of the range's own scale (Winstral, Marks &
//! Gurney 2013, "Simulating wind-affected snow accumulations at catchment to basin scales",
//! Adv. Water Resour. 55, 64-79, carry Sx-based redistribution from the catchment to the basin
//! scale). [`sheltering_index`] returns
//!
//! ```text
//! Sx = Sx_short + w_long · Sx_long
//! ```
//!
//! with `Sx_short` the search of `dmax_m` on the grid's own cells and `Sx_long` a search of
//! `long_range_dmax_m` ([`long_range`]) on a coarsened grid; where both scales agree (a crest
//! exposed to the whole range, a lee slope below a ridge in a sheltered basin) the index is
//! strongest, and a windward slope deep in a valley in the lee of the upwind range is
//! exposed locally but sheltered at the scale of the range. `w_long` = 1 (both scales count
//! alike) is chosen here; `long_range_dmax_m = 0` or `w_long = 0` gives Winstral et al.
//! 2002's single search.

use crate::EnvironmentError;
use crate::error::check_param;
use crate::field::validate;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use snowscape_terrain::{GridGeometry, NodataMask};

/// The most samples along one ray (module docs, "Bounded by cells").
pub const MAX_SX_STEPS: usize = 512;

/// Parameters of the maximum upwind slope `Sx` (Winstral et al. 2002).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct ShelteringParams {
    /// Search distance upwind, metres (> 0). Default 100 m: Winstral et al. 2002's choice for
    /// drift and scour zones; 300 m is also common for larger-scale exposure. At least one cell
    /// is searched whatever the value.
    pub dmax_m: f64,
    /// Half-width of the window of directions around the wind, degrees, in [0, 90].
    /// Default 15°: Winstral et al. 2002 (a 30° window).
    pub window_half_deg: f64,
    /// Spacing of the directions in the window, degrees (> 0). Default 5°: Winstral et al. 2002
    /// (seven rays for the 30° window). The rays are `A + k·step`, `|k·step| ≤ half`.
    pub window_step_deg: f64,
    /// Search distance of the long-range `Sx` ([`long_range`]), metres, in [0, 5000]; 0
    /// switches it off. Default 1000 m: chosen here, the scale of a range's crests and
    /// valleys (basin-scale exposure, Winstral et al. 2013; the lidar depths of a high-Sierra
    /// basin follow `Sx` over about 1000 m better than over 100 m, issue 47).
    pub long_range_dmax_m: f64,
    /// Cell size of the coarse grid the long-range search runs on, metres (> 0): the grid's
    /// cells are averaged in blocks of `max(1, ⌈long_range_cell_m / min(dx, dy)⌉)` cells a
    /// side. Default 50 m: chosen here, half the short search, so the long search takes at
    /// most `long_range_dmax_m / 50 m` = 20 samples per ray whatever the grid's cells.
    pub long_range_cell_m: f64,
    /// Weight `w_long` of the long-range `Sx` in the sheltering index (module docs), in
    /// [0, 10]. Default 1: chosen here (both scales count alike).
    pub long_range_weight: f64,
}

impl Default for ShelteringParams {
    fn default() -> Self {
        Self {
            dmax_m: 100.0,
            window_half_deg: 15.0,
            window_step_deg: 5.0,
            long_range_dmax_m: 1000.0,
            long_range_cell_m: 50.0,
            long_range_weight: 1.0,
        }
    }
}

impl ShelteringParams {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), EnvironmentError> {
        let d = self.dmax_m;
        check_param(
            "sheltering.dmax_m",
            d,
            d > 0.0 && d <= 2000.0,
            "must be in (0, 2000] m",
        )?;
        let h = self.window_half_deg;
        check_param(
            "sheltering.window_half_deg",
            h,
            (0.0..=90.0).contains(&h),
            "must be in [0, 90]",
        )?;
        let s = self.window_step_deg;
        check_param(
            "sheltering.window_step_deg",
            s,
            (0.5..=90.0).contains(&s),
            "must be in [0.5, 90] °",
        )?;
        let d = self.long_range_dmax_m;
        check_param(
            "sheltering.long_range_dmax_m",
            d,
            (0.0..=5000.0).contains(&d),
            "must be in [0, 5000] m",
        )?;
        let c = self.long_range_cell_m;
        check_param(
            "sheltering.long_range_cell_m",
            c,
            c > 0.0 && c <= 1000.0,
            "must be in (0, 1000] m",
        )?;
        let w = self.long_range_weight;
        check_param(
            "sheltering.long_range_weight",
            w,
            (0.0..=10.0).contains(&w),
            "must be in [0, 10]",
        )
    }

    /// The ray directions (wind FROM, degrees) around `wind_from_deg`, in window order.
    pub fn directions(&self, wind_from_deg: f64) -> Vec<f64> {
        let m = (self.window_half_deg / self.window_step_deg + 1e-9).floor() as i64;
        (-m..=m)
            .map(|k| wind_from_deg + k as f64 * self.window_step_deg)
            .collect()
    }

    /// Number of samples along each ray on cells of `geometry`: at least one, at most to the
    /// grid's diagonal and at most [`MAX_SX_STEPS`] (module docs, "Bounded by cells").
    pub fn steps(&self, geometry: &GridGeometry) -> usize {
        let (dx, dy) = (geometry.cell_size_x(), geometry.cell_size_y());
        let step = dx.min(dy);
        let diagonal = (geometry.width() as f64 * dx).hypot(geometry.height() as f64 * dy);
        let wanted = (self.dmax_m / step + 1e-9).floor();
        let inside = (diagonal / step).ceil() + 1.0;
        // `as usize` saturates (and maps NaN to 0) before the minimum with the cap.
        (wanted.min(inside) as usize).clamp(1, MAX_SX_STEPS)
    }
}

/// One bilinear tap: offset into the padded surface and weight.
#[derive(Debug, Clone, Copy)]
struct Tap {
    offset: isize,
    weight: f32,
}

/// One sample along a ray: its taps (1 to 4) and `1 / distance`.
#[derive(Debug, Clone)]
struct Sample {
    taps: Vec<Tap>,
    inv_d: f32,
}

/// Fractions this close to 0 or 1 snap to the cell (rays along the grid axes would otherwise
/// read a neighbour with a weight of 1e-16 and lose the sample where that neighbour is nodata).
const SNAP: f64 = 1e-4;

/// Splits a cell offset into `(floor, fraction)`, snapping near-integers.
fn split(o: f64) -> (isize, f64) {
    let f = o.floor();
    let frac = o - f;
    if frac < SNAP {
        (f as isize, 0.0)
    } else if frac > 1.0 - SNAP {
        (f as isize + 1, 0.0)
    } else {
        (f as isize, frac)
    }
}

/// The maximum upwind slope `Sx` of every cell, degrees (module documentation), for the wind
/// blowing FROM `wind_from_deg` (meteorological: 270 = westerly) over `surface` (m).
pub fn max_upwind_slope(
    surface: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    wind_from_deg: f64,
    params: &ShelteringParams,
) -> Result<Vec<f32>, EnvironmentError> {
    params.validate()?;
    check_param("wind_from_deg", wind_from_deg, true, "must be finite")?;
    validate(surface, geometry, mask)?;
    let w = geometry.width();
    let (dx, dy) = (geometry.cell_size_x(), geometry.cell_size_y());
    let step = dx.min(dy);
    let n_steps = params.steps(geometry);
    // Ray offsets in cells: east is +col, north is −row.
    let rays: Vec<Vec<(f64, f64, f64)>> = params
        .directions(wind_from_deg)
        .iter()
        .map(|deg| {
            let (s, c) = deg.to_radians().sin_cos();
            (1..=n_steps)
                .map(|k| {
                    let d = k as f64 * step;
                    (d * s / dx, -d * c / dy, d)
                })
                .collect()
        })
        .collect();
    let reach = rays
        .iter()
        .flatten()
        .map(|&(oc, or, _)| oc.abs().max(or.abs()))
        .fold(0.0f64, f64::max);
    let pad = reach.ceil() as usize + 2;
    let pw = w + 2 * pad;
    let padded = pad_surface(surface, geometry, mask, pad);
    let rays: Vec<Vec<Sample>> = rays
        .iter()
        .map(|ray| {
            ray.iter()
                .map(|&(oc, or, d)| {
                    let (c0, fc) = split(oc);
                    let (r0, fr) = split(or);
                    let corners = [
                        (r0, c0, (1.0 - fr) * (1.0 - fc)),
                        (r0, c0 + 1, (1.0 - fr) * fc),
                        (r0 + 1, c0, fr * (1.0 - fc)),
                        (r0 + 1, c0 + 1, fr * fc),
                    ];
                    Sample {
                        taps: corners
                            .iter()
                            .filter(|c| c.2 > 0.0)
                            .map(|&(r, c, wt)| Tap {
                                offset: r * pw as isize + c,
                                weight: wt as f32,
                            })
                            .collect(),
                        inv_d: (1.0 / d) as f32,
                    }
                })
                .collect()
        })
        .collect();
    let mut out = vec![0.0f32; geometry.len()];
    out.par_chunks_mut(w).enumerate().for_each_init(
        || RowBuffers {
            best: vec![0.0; w],
            acc: vec![0.0; w],
            sum: vec![0.0; w],
            count: vec![0; w],
        },
        |buf, (row, line)| {
            sx_row(&padded, pw, pad, row, &rays, buf, line);
        },
    );
    Ok(out)
}

/// Per-thread row accumulators.
struct RowBuffers {
    /// Largest rise over distance along the current ray.
    best: Vec<f32>,
    /// Weighted rise of the current sample.
    acc: Vec<f32>,
    /// Sum over rays of `Sx`, degrees.
    sum: Vec<f32>,
    /// Rays with at least one valid sample.
    count: Vec<u32>,
}

/// `Sx` of one row into `line`. Index loops over parallel row slices (they vectorise).
#[allow(clippy::needless_range_loop)]
fn sx_row(
    padded: &[f32],
    pw: usize,
    pad: usize,
    row: usize,
    rays: &[Vec<Sample>],
    buf: &mut RowBuffers,
    line: &mut [f32],
) {
    let w = line.len();
    let centre = (row + pad) * pw + pad;
    let zc = &padded[centre..centre + w];
    buf.sum.fill(0.0);
    buf.count.fill(0);
    for ray in rays {
        let best = &mut buf.best[..w];
        best.fill(f32::NEG_INFINITY);
        for sample in ray {
            let inv_d = sample.inv_d;
            let tap_row = |t: &Tap| {
                let start = (centre as isize + t.offset) as usize;
                (&padded[start..start + w], t.weight)
            };
            // Rise over distance, as a weighted sum of differences (exactly 0 on level
            // ground). NaN samples (nodata, outside the grid) leave `best` unchanged:
            // f32::max ignores NaN.
            match sample.taps.as_slice() {
                [a] => {
                    let (za, _) = tap_row(a);
                    for k in 0..w {
                        best[k] = best[k].max((za[k] - zc[k]) * inv_d);
                    }
                }
                [a, b] => {
                    let ((za, wa), (zb, wb)) = (tap_row(a), tap_row(b));
                    for k in 0..w {
                        let rise = (za[k] - zc[k]) * wa + (zb[k] - zc[k]) * wb;
                        best[k] = best[k].max(rise * inv_d);
                    }
                }
                taps => {
                    let acc = &mut buf.acc[..w];
                    acc.fill(0.0);
                    for t in taps {
                        let (z, wt) = tap_row(t);
                        for k in 0..w {
                            acc[k] += (z[k] - zc[k]) * wt;
                        }
                    }
                    for k in 0..w {
                        best[k] = best[k].max(acc[k] * inv_d);
                    }
                }
            }
        }
        for k in 0..w {
            if best[k] > f32::NEG_INFINITY {
                buf.sum[k] += best[k].atan().to_degrees();
                buf.count[k] += 1;
            }
        }
    }
    for k in 0..w {
        line[k] = if zc[k].is_nan() || buf.count[k] == 0 {
            0.0
        } else {
            buf.sum[k] / buf.count[k] as f32
        };
    }
}

/// The surface in a frame of `pad` NaN cells, nodata cells NaN too.
fn pad_surface(
    surface: &[f32],
    geometry: &GridGeometry,
    mask: &NodataMask,
    pad: usize,
) -> Vec<f32> {
    let (w, h) = (geometry.width(), geometry.height());
    let pw = w + 2 * pad;
    let mut padded = vec![f32::NAN; pw * (h + 2 * pad)];
    padded[pad * pw..(pad + h) * pw]
        .par_chunks_mut(pw)
        .enumerate()
        .for_each(|(row, line)| {
            for col in 0..w {
                let i = row * w + col;
                if mask.is_valid(i) {
                    line[pad + col] = surface[i];
                }
            }
        });
    padded
}

pub mod long_range;
pub use long_range::{LongRangePlan, long_range_upwind_slope, sheltering_index};

#[cfg(test)]
mod tests;
