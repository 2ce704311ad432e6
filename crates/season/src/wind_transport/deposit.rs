//! Pass 2 of wind transport: every cell removes its own erosion, is tamped, and gathers what
//! its four neighbours send it.

use super::{Context, WindScratch, WindTerms, tamping_share};
use crate::phenomenon::{Validity, row_gradient_norm};
use snowscape_terrain::LayeredTerrain;
use snowscape_terrain::parallel::{self, PerRow};

/// Per-thread row buffers.
struct Row {
    gradient: Vec<f32>,
    deposited: Vec<f32>,
    slab: Vec<f32>,
    tamped: Vec<f32>,
}

/// Updates the powder and unstable layers; returns per-row
/// `[deposited, deposited as unstable, tamped]`, m.
pub(super) fn run<V: Validity>(
    ctx: &Context,
    valid: &V,
    terms: &WindTerms,
    terrain: &mut LayeredTerrain,
    scratch: &mut WindScratch,
    fill_surface_after: bool,
) -> Vec<[f64; 3]> {
    let w = ctx.geometry.width();
    let h = ctx.geometry.height();
    let WindScratch {
        surface: a,
        out_x: ox,
        out_y: oy,
        surface_after,
        ..
    } = scratch;
    let (a, ox, oy) = (&*a, &*ox, &*oy);
    // Per row, where to write its surface after the pass (none when not asked for).
    let after_rows: Vec<Option<&mut [f32]>> = if fill_surface_after {
        surface_after.resize(a.len(), 0.0);
        surface_after.chunks_mut(w).map(Some).collect()
    } else {
        (0..h).map(|_| None).collect()
    };
    let a_z = &terms.vertical_change;
    let bedrock = &terrain.bedrock;
    let [compacted, stable, unstable, powder] = &mut terrain.snow;
    let (compacted, stable) = (&*compacted, &*stable);
    parallel::map_rows_with(
        w,
        (unstable, powder, PerRow(after_rows)),
        || Row {
            gradient: vec![0.0; w],
            deposited: vec![0.0; w],
            slab: vec![0.0; w],
            tamped: vec![0.0; w],
        },
        |buf, row, (un, pw, after)| {
            row_gradient_norm(a, ctx.geometry, ctx.mask, valid, row, &mut buf.gradient);
            let base = row * w;
            let general = |col: usize, buf: &mut Row, un: &mut f32, pw: &mut f32| {
                let i = base + col;
                if !valid.at(i) {
                    (buf.deposited[col], buf.slab[col], buf.tamped[col]) = (0.0, 0.0, 0.0);
                    return;
                }
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
                let e = ox[i].abs() + oy[i].abs();
                let (slab, tamped) = cell_update(ctx, e, a_z[i], d, buf.gradient[col], pw, un);
                (buf.deposited[col], buf.slab[col], buf.tamped[col]) = (d, slab, tamped);
            };
            if row > 0 && row + 1 < h && w >= 3 {
                general(0, buf, &mut un[0], &mut pw[0]);
                general(w - 1, buf, &mut un[w - 1], &mut pw[w - 1]);
                let ox_mid = &ox[base..base + w];
                let (oy_up, oy_mid, oy_dn) = (
                    &oy[base - w..base],
                    &oy[base..base + w],
                    &oy[base + w..base + 2 * w],
                );
                let (un, pw) = (&mut un[..w], &mut pw[..w]);
                let a_z_row = &a_z[base..base + w];
                let grad = &buf.gradient[..w];
                let deposited = &mut buf.deposited[..w];
                let slabs = &mut buf.slab[..w];
                let tamps = &mut buf.tamped[..w];
                for col in 1..w - 1 {
                    if !valid.at(base + col) {
                        (deposited[col], slabs[col], tamps[col]) = (0.0, 0.0, 0.0);
                        continue;
                    }
                    // (All four neighbours are in the grid; a nodata one sends nothing.)
                    let d = ox_mid[col - 1].max(0.0)
                        + (-ox_mid[col + 1]).max(0.0)
                        + (-oy_up[col]).max(0.0)
                        + oy_dn[col].max(0.0);
                    let e = ox_mid[col].abs() + oy_mid[col].abs();
                    let (slab, tamped) = cell_update(
                        ctx,
                        e,
                        a_z_row[col],
                        d,
                        grad[col],
                        &mut pw[col],
                        &mut un[col],
                    );
                    (deposited[col], slabs[col], tamps[col]) = (d, slab, tamped);
                }
            } else {
                for col in 0..w {
                    general(col, buf, &mut un[col], &mut pw[col]);
                }
            }
            if let Some(after) = after {
                // The same sum, in the same order, as `fill_surface`.
                let r = row * w..(row + 1) * w;
                let (b, c, s) = (&bedrock[r.clone()], &compacted[r.clone()], &stable[r]);
                for (k, a) in after.iter_mut().enumerate() {
                    *a = b[k] + (c[k] + s[k] + un[k] + pw[k]);
                }
            }
            [
                crate::row_sum(&buf.deposited[..w]),
                crate::row_sum(&buf.slab[..w]),
                crate::row_sum(&buf.tamped[..w]),
            ]
        },
    )
}

/// One cell's update: removes its erosion `e` (powder first, then unstable snow), tamps
/// its powder by `a_z`, and adds the deposit `d` as powder, or as unstable snow where the
/// surface gradient exceeds the slab slope; powder and unstable depths below
/// [`crate::phenomenon::NEGLIGIBLE_DEPTH_M`] are set to 0. Returns `(deposit landed as
/// unstable, tamped)`.
#[inline(always)]
fn cell_update(
    ctx: &Context,
    e: f32,
    a_z: f32,
    d: f32,
    gradient: f32,
    powder: &mut f32,
    unstable: &mut f32,
) -> (f32, f32) {
    let from_powder = e.min(*powder);
    *powder -= from_powder;
    *unstable -= (e - from_powder).min(*unstable);
    let tamped = *powder * tamping_share(a_z, ctx.tamping_dt);
    *powder -= tamped;
    *unstable += tamped;
    let slab = if gradient > ctx.slab_gradient { d } else { 0.0 };
    *unstable = crate::phenomenon::flush_negligible(*unstable + slab);
    *powder = crate::phenomenon::flush_negligible(*powder + (d - slab));
    (slab, tamped)
}
