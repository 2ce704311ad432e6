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
//! Rows are independent along x (rayon over rows); along y, bands of columns are swept
//! independently (rayon over bands), each in its own buffer, then copied back. Every value
//! depends only on its upwind chain, so the result is the same for any thread count.

use super::Fields;
use crate::physics::saltation::fetch_limited_flux;
use rayon::prelude::*;

/// Width of the column bands of the y sweep.
const BAND: usize = 64;

/// The fixed inputs of a sweep.
pub(super) struct SweepInputs<'a> {
    pub width: usize,
    pub height: usize,
    pub fields: &'a Fields,
    pub wind_u: &'a [f32],
    pub wind_v: &'a [f32],
    /// `μ Δx / f` capped at 1, along x and along y.
    pub relax_x: f32,
    pub relax_y: f32,
    pub saturated_inflow: bool,
}

/// Capacity component of cell `i` along an axis whose wind component is `comp`.
#[inline]
fn capacity_component(fields: &Fields, i: usize, comp: f32, speed: f32) -> f32 {
    if speed > 0.0 {
        fields.q_max[i] * comp.abs() / speed
    } else {
        0.0
    }
}

/// One step of the recurrence: the flux leaving cell `i` given its upwind cell `up`
/// (`None` at the border or across a change of wind direction).
#[inline]
fn relax_cell(inp: &SweepInputs, i: usize, up: Option<(usize, f32)>, comp: f32, relax: f32) -> f32 {
    let f = inp.fields;
    let q_max = capacity_component(f, i, comp, f.speed[i]);
    let (q_up, u_star_up) = match up {
        Some((j, qj)) => (qj, f.u_star[j]),
        None if inp.saturated_inflow => (q_max, f.u_star[i]),
        None => (0.0, f.u_star[i]),
    };
    fetch_limited_flux(q_up, q_max, f.u_star[i] >= u_star_up, relax)
}

/// Signed saltation flux along x (east positive), kg m⁻¹ s⁻¹, into `q_x`.
pub(super) fn sweep_x(inp: &SweepInputs, q_x: &mut [f32]) {
    let w = inp.width;
    q_x.par_chunks_mut(w).enumerate().for_each(|(r, row)| {
        let base = r * w;
        let u = &inp.wind_u[base..base + w];
        // Eastward cells, west to east.
        for c in 0..w {
            if u[c] > 0.0 {
                let up = (c > 0 && u[c - 1] > 0.0).then(|| (base + c - 1, row[c - 1]));
                row[c] = relax_cell(inp, base + c, up, u[c], inp.relax_x);
            }
        }
        // Westward cells, east to west (stored negative).
        for c in (0..w).rev() {
            if u[c] < 0.0 {
                let up = (c + 1 < w && u[c + 1] < 0.0).then(|| (base + c + 1, -row[c + 1]));
                row[c] = -relax_cell(inp, base + c, up, u[c], inp.relax_x);
            } else if u[c] == 0.0 {
                row[c] = 0.0;
            }
        }
    });
}

/// Signed saltation flux along y (north positive), kg m⁻¹ s⁻¹, into `q_y`. Row 0 is north.
pub(super) fn sweep_y(inp: &SweepInputs, q_y: &mut [f32]) {
    let (w, h) = (inp.width, inp.height);
    let bands: Vec<Vec<f32>> = (0..w.div_ceil(BAND))
        .into_par_iter()
        .map(|b| {
            let c0 = b * BAND;
            let bw = BAND.min(w - c0);
            let mut buf = vec![0.0f32; bw * h];
            let v = |r: usize, k: usize| inp.wind_v[r * w + c0 + k];
            // Southward cells (v < 0), north to south: upwind is row − 1.
            for r in 0..h {
                for k in 0..bw {
                    if v(r, k) < 0.0 {
                        let up = (r > 0 && v(r - 1, k) < 0.0)
                            .then(|| ((r - 1) * w + c0 + k, -buf[(r - 1) * bw + k]));
                        buf[r * bw + k] =
                            -relax_cell(inp, r * w + c0 + k, up, v(r, k), inp.relax_y);
                    }
                }
            }
            // Northward cells (v > 0), south to north: upwind is row + 1.
            for r in (0..h).rev() {
                for k in 0..bw {
                    if v(r, k) > 0.0 {
                        let up = (r + 1 < h && v(r + 1, k) > 0.0)
                            .then(|| ((r + 1) * w + c0 + k, buf[(r + 1) * bw + k]));
                        buf[r * bw + k] = relax_cell(inp, r * w + c0 + k, up, v(r, k), inp.relax_y);
                    }
                }
            }
            buf
        })
        .collect();
    q_y.par_chunks_mut(w).enumerate().for_each(|(r, row)| {
        for (b, buf) in bands.iter().enumerate() {
            let c0 = b * BAND;
            let bw = BAND.min(w - c0);
            row[c0..c0 + bw].copy_from_slice(&buf[r * bw..(r + 1) * bw]);
        }
    });
}
