//! Pass 1 of wind transport: how much each cell sends to each downwind neighbour.

use super::second_difference;
use super::{Context, WindScratch, downwind_split, eroded_depth, erosion_curvature};
use crate::phenomenon::Validity;
use snowscape_terrain::{LayeredTerrain, SnowLayer, parallel};

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
    parallel::map_rows(
        w,
        (&mut scratch.out_x, &mut scratch.out_y),
        |row, (ox, oy)| {
            let base = row * w;
            let cell = Cell {
                ctx,
                powder: &powder[base..base + w],
                unstable: &unstable[base..base + w],
                u: &ctx.wind.u[base..base + w],
                v: &ctx.wind.v[base..base + w],
                shadow: &ctx.wind.shadow[base..base + w],
                base,
            };
            let mut border = 0.0f64;
            let mut general = |col: usize, ox: &mut f32, oy: &mut f32| {
                border += cell.general(valid, a, row, col, ox, oy) as f64;
            };
            if row > 0 && row + 1 < h && w >= 3 {
                general(0, &mut ox[0], &mut oy[0]);
                general(w - 1, &mut ox[w - 1], &mut oy[w - 1]);
                let up = &a[base - w..base];
                let mid = &a[base..base + w];
                let dn = &a[base + w..base + 2 * w];
                let (ox, oy) = (&mut ox[..w], &mut oy[..w]);
                let (u_row, v_row) = (&cell.u[..w], &cell.v[..w]);
                let shadow = &cell.shadow[..w];
                let (powder, unstable) = (&cell.powder[..w], &cell.unstable[..w]);
                let mut masked_cells = Vec::new();
                for col in 1..w - 1 {
                    let i = base + col;
                    let inner = [i - 1, i + 1, i - w, i + w].iter().all(|&j| valid.at(j));
                    if !valid.at(i) || !inner {
                        // Nodata or next to it: done by the general path below.
                        masked_cells.push(col);
                        continue;
                    }
                    let a_xx = second_difference(mid[col - 1], mid[col], mid[col + 1]);
                    let a_yy = second_difference(up[col], mid[col], dn[col]);
                    let (ex, ey) = amounts(
                        ctx,
                        a_xx * ctx.inv_dx2,
                        a_yy * ctx.inv_dy2,
                        [u_row[col], v_row[col], shadow[col]],
                        [powder[col], unstable[col]],
                    );
                    ox[col] = ex.copysign(u_row[col]);
                    oy[col] = ey.copysign(v_row[col]);
                }
                for col in masked_cells {
                    general(col, &mut ox[col], &mut oy[col]);
                }
            } else {
                for col in 0..w {
                    general(col, &mut ox[col], &mut oy[col]);
                }
            }
            let eroded = crate::row_sum_pairs(ox, oy, |x, y| x.abs() + y.abs());
            [eroded, border]
        },
    )
}

/// One row's view of the layers, for the per-cell erosion.
struct Cell<'a> {
    ctx: &'a Context<'a>,
    powder: &'a [f32],
    unstable: &'a [f32],
    u: &'a [f32],
    v: &'a [f32],
    shadow: &'a [f32],
    base: usize,
}

impl Cell<'_> {
    /// Any cell (border, next to nodata, or nodata): writes its signed outgoing depths and
    /// returns the depth that leaves the grid.
    fn general<V: Validity>(
        &self,
        valid: &V,
        a: &[f32],
        row: usize,
        col: usize,
        ox: &mut f32,
        oy: &mut f32,
    ) -> f32 {
        (*ox, *oy) = (0.0, 0.0);
        if !valid.at(self.base + col) {
            return 0.0;
        }
        let (a_xx, a_yy) = self.ctx.second_differences(valid, a, col, row);
        let (ex, ey) = amounts(
            self.ctx,
            a_xx,
            a_yy,
            [self.u[col], self.v[col], self.shadow[col]],
            [self.powder[col], self.unstable[col]],
        );
        let i = self.base + col;
        let (u, v) = (self.ctx.wind.u[i], self.ctx.wind.v[i]);
        let (sx, bx) = route(
            self.ctx,
            valid,
            col,
            row,
            if u > 0.0 { 1 } else { -1 },
            0,
            ex,
        );
        let (sy, by) = route(
            self.ctx,
            valid,
            col,
            row,
            0,
            if v > 0.0 { -1 } else { 1 },
            ey,
        );
        *ox = sx.copysign(u);
        *oy = sy.copysign(v);
        bx + by
    }
}

/// Unsigned depths `(east/west, north/south)` a cell sends downwind, m, from its
/// curvatures (1/m), its wind `[u, v, shadow]` and its `[powder, unstable]` depths.
#[inline(always)]
fn amounts(
    ctx: &Context,
    a_xx: f32,
    a_yy: f32,
    [u, v, shadow]: [f32; 3],
    [p, un]: [f32; 2],
) -> (f32, f32) {
    let available = p + if ctx.erode_unstable { un } else { 0.0 };
    let curv = erosion_curvature(a_xx, a_yy, u, v);
    let e = eroded_depth(curv, shadow > 0.5, available, ctx.erosion_dt);
    let ex = e * downwind_split(u, v);
    (ex, e - ex)
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
