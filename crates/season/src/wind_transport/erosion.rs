//! Pass 1 of wind transport: how much each cell sends to each downwind neighbour.

use super::second_difference;
use super::{Context, WindScratch, downwind_split, eroded_depth, erosion_curvature};
use crate::phenomenon::Validity;
use rayon::prelude::*;
use snowscape_terrain::{LayeredTerrain, SnowLayer};

/// Fills `scratch.out_x` / `out_y` with the signed depths sent east (+) / west (−) and
/// north (+) / south (−); returns per-row `[eroded, border outflow]`, m.
pub(super) fn run<V: Validity>(
    ctx: &Context,
    valid: &V,
    terrain: &LayeredTerrain,
    scratch: &mut WindScratch,
) -> Vec<[f64; 2]> {
    let w = ctx.geometry.width();
    let h = ctx.geometry.height();
    let a = &scratch.surface;
    let powder = terrain.layer(SnowLayer::Powder);
    let unstable = terrain.layer(SnowLayer::Unstable);
    let wind = ctx.wind;
    scratch
        .out_x
        .par_chunks_mut(w)
        .zip(scratch.out_y.par_chunks_mut(w))
        .enumerate()
        .map(|(row, (ox, oy))| {
            let mut sums = [0.0f64; 2];
            let inner_row = row > 0 && row + 1 < h;
            for col in 0..w {
                let i = row * w + col;
                ox[col] = 0.0;
                oy[col] = 0.0;
                if !valid.at(i) {
                    continue;
                }
                let (u, v) = (wind.u[i], wind.v[i]);
                let fast = inner_row
                    && col > 0
                    && col + 1 < w
                    && valid.at(i - 1)
                    && valid.at(i + 1)
                    && valid.at(i - w)
                    && valid.at(i + w);
                let (a_xx, a_yy) = if fast {
                    (
                        second_difference(a[i - 1], a[i], a[i + 1]) * ctx.inv_dx2,
                        second_difference(a[i - w], a[i], a[i + w]) * ctx.inv_dy2,
                    )
                } else {
                    ctx.second_differences(valid, a, col, row)
                };
                let available = powder[i] + if ctx.erode_unstable { unstable[i] } else { 0.0 };
                let curv = erosion_curvature(a_xx, a_yy, u, v);
                let e = eroded_depth(curv, wind.shadow[i] > 0.5, available, ctx.erosion_dt);
                if e <= 0.0 {
                    continue;
                }
                let ex = e * downwind_split(u, v);
                let ey = e - ex;
                let dc = if u > 0.0 { 1 } else { -1 };
                let dr = if v > 0.0 { -1 } else { 1 };
                let (sx, bx) = route(ctx, valid, col, row, dc, 0, ex);
                let (sy, by) = route(ctx, valid, col, row, 0, dr, ey);
                ox[col] = sx.copysign(dc as f32);
                oy[col] = sy.copysign(-dr as f32);
                sums[0] += (sx + sy) as f64;
                sums[1] += (bx + by) as f64;
            }
            sums
        })
        .collect()
}

/// Where `amount` sent from `(col, row)` towards `(dc, dr)` goes: `(sent, of which out of the
/// grid)`. A share aimed at a nodata cell is not sent.
#[inline]
fn route<V: Validity>(
    ctx: &Context,
    valid: &V,
    col: usize,
    row: usize,
    dc: isize,
    dr: isize,
    amount: f32,
) -> (f32, f32) {
    if amount <= 0.0 {
        return (0.0, 0.0);
    }
    match ctx.geometry.neighbour(col, row, dc, dr) {
        None => (amount, amount),
        Some(j) if valid.at(j) => (amount, 0.0),
        Some(_) => (0.0, 0.0),
    }
}
