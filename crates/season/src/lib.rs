//! # snowscape-season: snow-cover evolution through a winter
//!
//! The phenomena of Cordonnier et al. 2018, Section 5, each a module with a pure step
//! `step(params, state, scratch, dt) -> budget` over a [`LayeredTerrain`](snowscape_terrain::LayeredTerrain).
//! Every step reports the snow volume it added, removed or moved, so a run's mass budget is
//! tracked rather than hoped for.
//!
//! Beyond the paper, the default season follows sun, wind and slope on real terrain, each model
//! selectable against the paper's by name: [`melt::enhanced`] (enhanced temperature-index
//! melt with albedo, cold content and refreezing), [`climate`] and [`weather`] (climatology,
//! lapse rate, diurnal cycle, orographic precipitation and phase, hour by hour), [`storms`]
//! (storm temperature, psychrometric phase, season precipitation totals),
//! [`snowfall::add_precipitation`], [`slope_shedding`] (SnowSlide), the Sx redistribution of
//! [`wind_transport`], and station forcing ([`forcing`]).

pub mod avalanches;
pub mod bands;
pub mod checkpoint;
pub mod climate;
pub mod forcing;
pub mod melt;
pub mod parameter_catalogue;
pub mod phenomenon;
pub mod powder_diffusion;
pub mod scenario;
pub mod scheduler;
pub mod skiing;
pub mod slope_shedding;
pub mod snowfall;
pub mod snowtran_transport;
pub mod stability;
pub mod storms;
pub mod weather;
pub mod wind_transport;
pub mod winter;

/// Most characters of a value read from an input file (a forcing cell, a scenario string, a
/// checkpoint field) that an error message repeats: a longer one is cut, and the message says
/// how long it was, so a hostile file cannot flood the terminal or a log.
pub const MAX_ECHO_CHARS: usize = 80;

/// `s` for an error message: itself when it has at most [`MAX_ECHO_CHARS`] characters, else
/// its first characters, `...` and its length in bytes.
pub fn clip_for_message(s: &str) -> String {
    if s.chars().nth(MAX_ECHO_CHARS).is_none() {
        return s.to_string();
    }
    let head: String = s.chars().take(MAX_ECHO_CHARS - 3).collect();
    format!("{head}... ({} bytes)", s.len())
}

/// `v` for an error message: as Rust writes it (`0.5`, `-3`, `NaN`), but with an exponent
/// when it is very large or very small (`1e308`, `-1e-300`), whose plain form runs to hundreds
/// of digits and would be cut before its value shows.
pub fn number_for_message(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-5..1e16).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        v.to_string()
    }
}

/// Snow volume a step added to and removed from the terrain, m³ of snow.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VolumeChange {
    /// m³ of snow added (snowfall, deposit from outside).
    pub added: f64,
    /// m³ of snow removed (melt, outflow across the border).
    pub removed: f64,
}

/// Sums per-row partial sums in row order, so totals do not depend on the thread count.
pub(crate) fn ordered_sum(rows: &[f64]) -> f64 {
    rows.iter().sum()
}

/// Lanes of [`row_sum`].
pub(crate) const SUM_LANES: usize = 4;

/// The total of [`SUM_LANES`] partial sums, added in a fixed order.
#[inline(always)]
pub(crate) fn lane_total(acc: [f64; SUM_LANES]) -> f64 {
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// `Σ v` in f64 over one row of a budget term, in [`SUM_LANES`] interleaved partial sums
/// added in a fixed order at the end: the same bits for any thread count (one thread sums a
/// row), and a loop that vectorises, where one running sum waits on the latency of each
/// addition (the melt's six row sums cost ~20 cycles a cell that way).
pub(crate) fn row_sum(v: &[f32]) -> f64 {
    row_sum_by(v, |x| x)
}

/// [`row_sum`] of `f(a[k], b[k])`.
#[inline(always)]
pub(crate) fn row_sum_pairs(a: &[f32], b: &[f32], f: impl Fn(f32, f32) -> f32) -> f64 {
    let n = a.len().min(b.len());
    let mut acc = [0.0f64; SUM_LANES];
    let full = n - n % SUM_LANES;
    for (ca, cb) in a[..full]
        .chunks_exact(SUM_LANES)
        .zip(b[..full].chunks_exact(SUM_LANES))
    {
        for l in 0..SUM_LANES {
            acc[l] += f64::from(f(ca[l], cb[l]));
        }
    }
    for k in full..n {
        acc[0] += f64::from(f(a[k], b[k]));
    }
    lane_total(acc)
}

/// [`row_sum`] of `f(v[k])`.
#[inline(always)]
pub(crate) fn row_sum_by(v: &[f32], f: impl Fn(f32) -> f32) -> f64 {
    let mut acc = [0.0f64; SUM_LANES];
    let chunks = v.chunks_exact(SUM_LANES);
    let rest = chunks.remainder();
    for c in chunks {
        for (a, &x) in acc.iter_mut().zip(c) {
            *a += f64::from(f(x));
        }
    }
    for &x in rest {
        acc[0] += f64::from(f(x));
    }
    lane_total(acc)
}
