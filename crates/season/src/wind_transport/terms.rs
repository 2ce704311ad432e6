//! The terms of wind transport that depend on the wind field and the grid only, not on the
//! snow: the vertical acceleration of the wind along its path `a_z` of every cell (tamping;
//! see the parent module) and the dominant wind (the direction of the Sx sweep, see
//! [`super::sheltered`]). They stay the same while the wind field does (a season's weather
//! period): [`WindTerms::new`] computes them once and [`WindMaps::terms`] hands them to every
//! step; a step given none computes them itself (the same bits either way).

use super::{Context, WindMaps, WindTransportParams, second_difference, vertical_wind_change};
use crate::phenomenon::{PhenomenonError, Validity, check_map, with_validity};
use snowscape_terrain::{GridGeometry, NodataMask, parallel};

/// The snow-independent terms of one wind field on one grid.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WindTerms {
    /// `a_z = W · ∇(W · ∇Wz)` of every cell, m/s² (0 on nodata).
    pub(super) vertical_change: Vec<f32>,
    /// The unit dominant wind `(east, north)`: the mean of the wind field over valid cells.
    /// `None` in calm air.
    pub(super) dominant: Option<(f64, f64)>,
}

impl WindTerms {
    /// The terms of `wind` (its `terms`, if any, are not read) on a grid of `geometry` with
    /// `mask`: checks the maps' lengths, then one row-parallel pass.
    pub fn new(
        geometry: &GridGeometry,
        mask: &NodataMask,
        wind: &WindMaps,
    ) -> Result<Self, PhenomenonError> {
        wind.check(geometry)?;
        let params = WindTransportParams::default();
        // The terms read the grid and the wind only, not the rates of the context.
        let ctx = Context::new(geometry, mask, wind, &params, 0.0);
        let mut terms = Self::default();
        with_validity!(mask, |valid| terms.compute(&ctx, valid));
        Ok(terms)
    }

    /// Checks that the terms are for a grid of `geometry`.
    pub(super) fn check(&self, geometry: &GridGeometry) -> Result<(), PhenomenonError> {
        check_map(
            "wind terms (vertical_change)",
            &self.vertical_change,
            geometry,
        )
    }

    /// Recomputes the terms for `ctx`'s grid and wind, reusing the allocation.
    pub(super) fn compute<V: Validity>(&mut self, ctx: &Context, valid: &V) {
        let w = ctx.geometry.width();
        self.vertical_change.resize(ctx.geometry.len(), 0.0);
        parallel::for_each_row(w, &mut self.vertical_change, |row, out| {
            vertical_change_row(ctx, valid, row, out)
        });
        self.dominant = dominant(ctx, valid);
    }
}

/// `a_z` of the cells of one row (0 on nodata): the central stencil where the cell and its 8
/// neighbours hold data, the border rules of the parent module elsewhere.
fn vertical_change_row<V: Validity>(ctx: &Context, valid: &V, row: usize, out: &mut [f32]) {
    let (w, h) = (ctx.geometry.width(), ctx.geometry.height());
    let base = row * w;
    let general = |col: usize| {
        if valid.at(base + col) {
            general_vertical_change(ctx, valid, col, row)
        } else {
            0.0
        }
    };
    if !(row > 0 && row + 1 < h && w >= 3) {
        for (col, o) in out.iter_mut().enumerate() {
            *o = general(col);
        }
        return;
    }
    let z = ctx.wind.effect_surface;
    let (z_up, z_mid, z_dn) = (
        &z[base - w..base],
        &z[base..base + w],
        &z[base + w..base + 2 * w],
    );
    let (u_row, v_row) = (&ctx.wind.u[base..base + w], &ctx.wind.v[base..base + w]);
    let out = &mut out[..w];
    out[0] = general(0);
    out[w - 1] = general(w - 1);
    for col in 1..w - 1 {
        let i = base + col;
        let ring = [
            i - w - 1,
            i - w,
            i - w + 1,
            i - 1,
            i + 1,
            i + w - 1,
            i + w,
            i + w + 1,
        ];
        if !valid.at(i) || !ring.iter().all(|&j| valid.at(j)) {
            // Nodata or next to it: the border rules.
            out[col] = general(col);
            continue;
        }
        let z_xx = second_difference(z_mid[col - 1], z_mid[col], z_mid[col + 1]);
        let z_yy = second_difference(z_up[col], z_mid[col], z_dn[col]);
        let z_xy = z_up[col + 1] - z_up[col - 1] - z_dn[col + 1] + z_dn[col - 1];
        out[col] = vertical_wind_change(
            z_xx * ctx.inv_dx2,
            z_xy * ctx.inv_4dxdy,
            z_yy * ctx.inv_dy2,
            u_row[col],
            v_row[col],
        );
    }
}

/// `a_z` at any valid cell, with the border rules of the parent module.
fn general_vertical_change<V: Validity>(ctx: &Context, valid: &V, col: usize, row: usize) -> f32 {
    let i = row * ctx.geometry.width() + col;
    let z = ctx.wind.effect_surface;
    let (z_xx, z_yy) = ctx.second_differences(valid, z, col, row);
    let z_xy = ctx.cross_difference(valid, z, col, row);
    vertical_wind_change(z_xx, z_xy, z_yy, ctx.wind.u[i], ctx.wind.v[i])
}

/// The unit dominant wind `(east, north)`: the mean of the wind field over valid cells (row
/// sums in row order, so it does not depend on the thread count). `None` in calm air.
fn dominant<V: Validity>(ctx: &Context, valid: &V) -> Option<(f64, f64)> {
    let w = ctx.geometry.width();
    let rows: Vec<(f64, f64)> = parallel::map_rows(w, (ctx.wind.u, ctx.wind.v), |row, (u, v)| {
        (0..w)
            .filter(|&c| valid.at(row * w + c))
            .fold((0.0, 0.0), |(a, b), c| (a + u[c] as f64, b + v[c] as f64))
    });
    let (su, sv) = rows.iter().fold((0.0, 0.0), |(a, b), r| (a + r.0, b + r.1));
    let norm = su.hypot(sv);
    (norm > 0.0 && norm.is_finite()).then(|| (su / norm, sv / norm))
}
