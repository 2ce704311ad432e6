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
//! Rows are independent along x (each is swept right after its shear pass); along y, bands
//! of columns are swept independently (rayon over bands), each writing its share of every
//! row in place. Every value depends only on its upwind chain, so the result is the same for
//! any thread count.

use super::Shear;
use crate::physics::saltation::fetch_limited_flux;
use rayon::prelude::*;

/// Widest column band of the y sweep: a band row is read as one run of memory, and wide
/// runs are what the hardware prefetcher follows from row to row.
const MAX_BAND: usize = 256;
/// Narrowest column band, for many threads on a narrow grid.
const MIN_BAND: usize = 64;

/// The fixed settings of a sweep along one axis.
#[derive(Debug, Clone, Copy)]
pub(super) struct Sweep {
    /// `μ Δ / f` capped at 1, `Δ` the cell size along the axis.
    pub relax: f32,
    pub saturated_inflow: bool,
}

/// The flux leaving an upwind cell and its `u*`.
type Upwind = Option<(f32, f32)>;

impl Sweep {
    /// One step of the recurrence: the flux (magnitude) leaving a cell of wind component
    /// `comp` along the axis, given its upwind cell (`None` at the border or across a
    /// change of wind direction).
    #[inline]
    fn relax_cell(&self, cell: &Shear, up: Upwind, comp: f32) -> f32 {
        // The capacity component along the axis: Qs_max |comp| / W.
        let q_max = cell.q_max_per_speed * comp.abs();
        let (q_up, u_star_up) = match up {
            Some(upwind) => upwind,
            None if self.saturated_inflow => (q_max, cell.u_star),
            None => (0.0, cell.u_star),
        };
        fetch_limited_flux(q_up, q_max, cell.u_star >= u_star_up, self.relax)
    }
}

/// Signed saltation flux along a line of cells (positive towards increasing index) whose
/// wind component along the line is `comp`, into `q`. The cells blowing towards increasing
/// index are swept from the start and the others from the far end in the same loop: the
/// two recurrences touch different cells, and interleaving them lets the processor run
/// both dependency chains at once.
pub(super) fn sweep_line(sweep: &Sweep, shear: &[Shear], comp: &[f32], q: &mut [f32]) {
    let n = q.len();
    let (shear, comp) = (&shear[..n], &comp[..n]);
    let (mut forward, mut backward): (Upwind, Upwind) = (None, None);
    for i in 0..n {
        let (cell, c) = (&shear[i], comp[i]);
        forward = if c > 0.0 {
            let flux = sweep.relax_cell(cell, forward, c);
            q[i] = flux;
            Some((flux, cell.u_star))
        } else {
            None
        };
        let j = n - 1 - i;
        let (cell, c) = (&shear[j], comp[j]);
        backward = if c < 0.0 {
            let flux = sweep.relax_cell(cell, backward, c);
            q[j] = -flux;
            Some((flux, cell.u_star))
        } else {
            if c == 0.0 {
                q[j] = 0.0;
            }
            None
        };
    }
}

/// Signed saltation flux along y (north positive), kg m⁻¹ s⁻¹, into `q_y`, on a grid
/// `width` cells wide. Row 0 is north.
pub(super) fn sweep_y(
    sweep: &Sweep,
    width: usize,
    shear: &[Shear],
    wind_v: &[f32],
    q_y: &mut [f32],
) {
    let w = width;
    let h = shear.len() / w;
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
            let band_row = |r: usize| {
                let cells = r * w + c0..r * w + c0 + bw;
                shear[cells.clone()].iter().zip(&wind_v[cells])
            };
            // Southward cells (v < 0), north to south: upwind is row − 1 (stored negative);
            // the others get 0 until the northward pass.
            let mut up: [Upwind; MAX_BAND] = [None; MAX_BAND];
            for (r, q_row) in q_rows.iter_mut().enumerate() {
                for ((up, (cell, &v)), q) in up.iter_mut().zip(band_row(r)).zip(q_row.iter_mut()) {
                    *up = if v < 0.0 {
                        let flux = sweep.relax_cell(cell, *up, v);
                        *q = -flux;
                        Some((flux, cell.u_star))
                    } else {
                        *q = 0.0;
                        None
                    };
                }
            }
            // Northward cells (v > 0), south to north: upwind is row + 1.
            let mut up: [Upwind; MAX_BAND] = [None; MAX_BAND];
            for (r, q_row) in q_rows.iter_mut().enumerate().rev() {
                for ((up, (cell, &v)), q) in up.iter_mut().zip(band_row(r)).zip(q_row.iter_mut()) {
                    *up = if v > 0.0 {
                        let flux = sweep.relax_cell(cell, *up, v);
                        *q = flux;
                        Some((flux, cell.u_star))
                    } else {
                        None
                    };
                }
            }
        });
}
