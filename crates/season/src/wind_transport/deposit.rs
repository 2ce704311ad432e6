//! Pass 2 of wind transport: every cell removes its own erosion, is tamped, and gathers what
//! its four neighbours send it.

use super::{Context, WindScratch, second_difference, tamping_share, vertical_wind_change};
use crate::phenomenon::{Validity, row_gradient_norm};
use rayon::prelude::*;
use snowscape_terrain::LayeredTerrain;

/// Updates the powder and unstable layers; returns per-row
/// `[deposited, deposited as unstable, tamped]`, m.
pub(super) fn run<V: Validity>(
    ctx: &Context,
    valid: &V,
    terrain: &mut LayeredTerrain,
    scratch: &WindScratch,
) -> Vec<[f64; 3]> {
    let w = ctx.geometry.width();
    let h = ctx.geometry.height();
    let (a, ox, oy) = (&scratch.surface, &scratch.out_x, &scratch.out_y);
    let [_, _, unstable, powder] = &mut terrain.snow;
    unstable
        .par_chunks_mut(w)
        .zip(powder.par_chunks_mut(w))
        .enumerate()
        .map_init(
            || vec![0.0f32; w],
            |grad, (row, (un, pw))| {
                row_gradient_norm(a, ctx.geometry, ctx.mask, valid, row, grad);
                let mut sums = [0.0f64; 3];
                for col in 0..w {
                    let i = row * w + col;
                    if !valid.at(i) {
                        continue;
                    }
                    // Own erosion: powder first, then unstable snow.
                    let e = ox[i].abs() + oy[i].abs();
                    let from_powder = e.min(pw[col]);
                    pw[col] -= from_powder;
                    un[col] -= (e - from_powder).min(un[col]);
                    // Tamping.
                    let tamped = pw[col]
                        * tamping_share(vertical_change(ctx, valid, col, row), ctx.tamping_dt);
                    pw[col] -= tamped;
                    un[col] += tamped;
                    // Gather from the four neighbours.
                    let mut d = 0.0f32;
                    if col > 0 {
                        d += ox[i - 1].max(0.0);
                    }
                    if col + 1 < w {
                        d += (-ox[i + 1]).max(0.0);
                    }
                    if row > 0 {
                        d += (-oy[i - w]).max(0.0);
                    }
                    if row + 1 < h {
                        d += oy[i + w].max(0.0);
                    }
                    if grad[col] > ctx.slab_gradient {
                        un[col] += d;
                        sums[1] += d as f64;
                    } else {
                        pw[col] += d;
                    }
                    sums[0] += d as f64;
                    sums[2] += tamped as f64;
                }
                sums
            },
        )
        .collect()
}

/// `a_z` at a valid cell from the wind-effect surface (see [`vertical_wind_change`]).
#[inline(always)]
fn vertical_change<V: Validity>(ctx: &Context, valid: &V, col: usize, row: usize) -> f32 {
    let w = ctx.geometry.width();
    let i = row * w + col;
    let z = ctx.wind.effect_surface;
    let (u, v) = (ctx.wind.u[i], ctx.wind.v[i]);
    let fast = row > 0
        && row + 1 < ctx.geometry.height()
        && col > 0
        && col + 1 < w
        && [
            i - w - 1,
            i - w,
            i - w + 1,
            i - 1,
            i + 1,
            i + w - 1,
            i + w,
            i + w + 1,
        ]
        .iter()
        .all(|&j| valid.at(j));
    let (z_xx, z_xy, z_yy) = if fast {
        (
            second_difference(z[i - 1], z[i], z[i + 1]) * ctx.inv_dx2,
            (z[i - w + 1] - z[i - w - 1] - z[i + w + 1] + z[i + w - 1]) * ctx.inv_4dxdy,
            second_difference(z[i - w], z[i], z[i + w]) * ctx.inv_dy2,
        )
    } else {
        let (xx, yy) = ctx.second_differences(valid, z, col, row);
        (xx, ctx.cross_difference(valid, z, col, row), yy)
    };
    vertical_wind_change(z_xx, z_xy, z_yy, u, v)
}
