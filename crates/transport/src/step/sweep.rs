//! The fetch-limited saltation flux along the wind (Jubert 2018, Eqs. 5.38-5.39), swept
//! separately along x and y as in Section 5.5.3 ("itérer dans chaque direction du vent ...
//! et interpoler linéairement en fonction de la vitesse du vent dans cette direction"): the
//! capacity of a cell is split into `Qs_max |u|/W` along x and `Qs_max |v|/W` along y, and
//! each component relaxes along its own axis.
//!
//! A cell's upwind neighbour along x is the west one where `u > 0`, the east one where
//! `u < 0`; it feeds the cell only if its own wind blows the same way (otherwise the
//! upwind flux is 0: a divergence line starts a new fetch). At the domain border the
//! inflow is 0, or the cell's own capacity with `saturated_inflow`.
//!
//! Each recurrence is a chain along its axis, so the sweeps run many chains side by side:
//! along x the rows of a block of [`X_ROWS`] (interleaved, for the processor to overlap),
//! along y the columns of a band (as vector lanes: the cell loops are branch-free). Rayon
//! works on row blocks along x and on column bands along y. Every value depends only on
//! its upwind chain, so the result is the same for any thread count.

use super::ShearCells;
use crate::physics::saltation::fetch_limited_flux;
use multiversion::multiversion;
use rayon::prelude::*;

/// Rows swept along x together.
pub(super) const X_ROWS: usize = 8;
/// Widest column band of the y sweep: a band row is read as one run of memory, and wide
/// runs are what the hardware prefetcher follows from row to row.
const MAX_BAND: usize = 256;
/// Narrowest column band, for many threads on a narrow grid.
const MIN_BAND: usize = 64;
/// The upwind `u*` of a cell that no upwind cell feeds (at the border or across a change
/// of wind direction): every `u*` grows from it.
const NO_UPWIND: f32 = f32::NEG_INFINITY;

/// The fixed settings of a sweep along one axis.
#[derive(Debug, Clone, Copy)]
pub(super) struct Sweep {
    /// `μ Δ / f` capped at 1, `Δ` the cell size along the axis.
    pub relax: f32,
    pub saturated_inflow: bool,
}

/// What the upwind cells of a set of chains send on: the flux leaving them and their `u*`
/// ([`NO_UPWIND`] where none feeds on, with a flux of 0).
struct Upwind<const N: usize> {
    q: [f32; N],
    u_star: [f32; N],
}

impl<const N: usize> Upwind<N> {
    fn none() -> Self {
        Self {
            q: [0.0; N],
            u_star: [NO_UPWIND; N],
        }
    }
}

impl Sweep {
    /// One step of the recurrence: the flux (magnitude) leaving a cell of capacity per unit
    /// speed `q_max_per_speed`, friction velocity `u_star` and wind component `comp` along
    /// the axis, fed by an upwind cell sending `q_up` at a friction velocity `u_up`
    /// ([`NO_UPWIND`] where none feeds it).
    #[inline(always)]
    fn relax_cell(
        &self,
        q_max_per_speed: f32,
        u_star: f32,
        comp: f32,
        q_up: f32,
        u_up: f32,
    ) -> f32 {
        // The capacity component along the axis: Qs_max |comp| / W.
        let q_max = q_max_per_speed * comp.abs();
        let q_up = if self.saturated_inflow && u_up == NO_UPWIND {
            q_max
        } else {
            q_up
        };
        fetch_limited_flux(q_up, q_max, u_star >= u_up, self.relax)
    }

    /// One cell of a chain running towards the cells where `active`: its flux, or `idle`
    /// where the chain does not run through it (then it feeds no one).
    #[inline(always)]
    fn chain_cell(
        &self,
        cell: (f32, f32, f32),
        up: (&mut f32, &mut f32),
        active: bool,
        sign: f32,
        idle: f32,
    ) -> f32 {
        let (q_max_per_speed, u_star, comp) = cell;
        let flux = self.relax_cell(q_max_per_speed, u_star, comp, *up.0, *up.1);
        *up.0 = if active { flux } else { 0.0 };
        *up.1 = if active { u_star } else { NO_UPWIND };
        if active { sign * flux } else { idle }
    }
}

/// Signed saltation flux along x (east positive) of a block of at most [`X_ROWS`] rows,
/// `width` cells each, whose wind along x is `comp`, into `q`. Eastward cells are swept
/// from the west end, then westward ones from the east end; each pass advances all the
/// block's rows a cell at a time, so their chains overlap.
#[multiversion(targets("x86_64+avx2"))]
pub(super) fn sweep_rows(
    sweep: &Sweep,
    width: usize,
    shear: ShearCells,
    comp: &[f32],
    q: &mut [f32],
) {
    let n = q.len();
    let rows = n / width;
    assert!(rows <= X_ROWS && rows * width == n, "a block of whole rows");
    let (q_max, u_star, comp) = (&shear.q_max_per_speed[..n], &shear.u_star[..n], &comp[..n]);
    // A pass meets no cell blowing its way in most blocks of a steady wind: skip it then
    // (the eastward pass would write 0 everywhere, the westward one keep every value).
    let (eastward, westward) = comp
        .iter()
        .fold((false, false), |(e, w), &c| (e | (c > 0.0), w | (c < 0.0)));
    if eastward {
        sweep_rows_pass::<true>(sweep, width, (q_max, u_star, comp), q);
    } else {
        q.fill(0.0);
    }
    if westward {
        sweep_rows_pass::<false>(sweep, width, (q_max, u_star, comp), q);
    }
}

/// One direction of [`sweep_rows`]: the eastward cells from the west end (the others get
/// 0), or the westward ones from the east end (the others keep their value).
#[inline(always)]
fn sweep_rows_pass<const EASTWARD: bool>(
    sweep: &Sweep,
    width: usize,
    (q_max, u_star, comp): (&[f32], &[f32], &[f32]),
    q: &mut [f32],
) {
    let rows = q.len() / width;
    let mut up = Upwind::<X_ROWS>::none();
    for step in 0..width {
        let i = if EASTWARD { step } else { width - 1 - step };
        for k in 0..rows {
            let a = k * width + i;
            let cell = (q_max[a], u_star[a], comp[a]);
            let lane = (&mut up.q[k], &mut up.u_star[k]);
            q[a] = if EASTWARD {
                sweep.chain_cell(cell, lane, comp[a] > 0.0, 1.0, 0.0)
            } else {
                sweep.chain_cell(cell, lane, comp[a] < 0.0, -1.0, q[a])
            };
        }
    }
}

/// One row of a column band in a y pass: each column is a lane of the chain.
#[inline(always)]
fn sweep_band_row<const SOUTHWARD: bool>(
    sweep: &Sweep,
    shear: ShearCells,
    comp: &[f32],
    q: &mut [f32],
    up: &mut Upwind<MAX_BAND>,
) {
    let n = q.len();
    let (q_max, u_star, comp) = (&shear.q_max_per_speed[..n], &shear.u_star[..n], &comp[..n]);
    let (up_q, up_u) = (&mut up.q[..n], &mut up.u_star[..n]);
    for c in 0..n {
        let cell = (q_max[c], u_star[c], comp[c]);
        let lane = (&mut up_q[c], &mut up_u[c]);
        q[c] = if SOUTHWARD {
            sweep.chain_cell(cell, lane, comp[c] < 0.0, -1.0, 0.0)
        } else {
            sweep.chain_cell(cell, lane, comp[c] > 0.0, 1.0, q[c])
        };
    }
}

/// The y sweep of the columns `band` of a grid `width` cells wide: `q_rows` are the band's
/// share of each row of the flux.
#[multiversion(targets("x86_64+avx2"))]
fn sweep_band(
    sweep: &Sweep,
    width: usize,
    band: std::ops::Range<usize>,
    shear: ShearCells,
    wind_v: &[f32],
    q_rows: &mut [&mut [f32]],
) {
    let band_row = |r: usize| r * width + band.start..r * width + band.end;
    // Southward cells (v < 0), north to south: upwind is row − 1 (stored negative); the
    // others get 0 until the northward pass.
    let mut up = Upwind::none();
    for (r, q_row) in q_rows.iter_mut().enumerate() {
        let cells = band_row(r);
        let v = &wind_v[cells.clone()];
        sweep_band_row::<true>(sweep, shear.cells(cells), v, q_row, &mut up);
    }
    // Northward cells (v > 0), south to north: upwind is row + 1.
    let mut up = Upwind::none();
    for (r, q_row) in q_rows.iter_mut().enumerate().rev() {
        let cells = band_row(r);
        let v = &wind_v[cells.clone()];
        sweep_band_row::<false>(sweep, shear.cells(cells), v, q_row, &mut up);
    }
}

/// Signed saltation flux along y (north positive), kg m⁻¹ s⁻¹, into `q_y`, on a grid
/// `width` cells wide. Row 0 is north.
pub(super) fn sweep_y(
    sweep: &Sweep,
    width: usize,
    shear: ShearCells,
    wind_v: &[f32],
    q_y: &mut [f32],
) {
    let w = width;
    let h = shear.u_star.len() / w;
    // About two bands per thread; the width does not change the result.
    let band = w
        .div_ceil(2 * rayon::current_num_threads())
        .clamp(MIN_BAND, MAX_BAND);
    // Each band's share of every row of `q_y`, so the bands write their cells in place.
    let n_bands = w.div_ceil(band);
    let mut bands: Vec<Vec<&mut [f32]>> = (0..n_bands).map(|_| Vec::with_capacity(h)).collect();
    for row in q_y.chunks_mut(w) {
        for (cells, rows) in row.chunks_mut(band).zip(&mut bands) {
            rows.push(cells);
        }
    }
    bands
        .into_par_iter()
        .enumerate()
        .for_each(|(b, mut q_rows)| {
            let (c0, bw) = (b * band, band.min(w - b * band));
            sweep_band(sweep, w, c0..c0 + bw, shear, wind_v, &mut q_rows);
        });
}
