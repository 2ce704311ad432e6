//! Refined tracks: sine-wave turns around the coarse path (Cordonnier et al. 2018, Section 6.2,
//! "Refined tracks").
//!
//! On a straight stretch of the coarse path the fine track is `p(t) = a·sin(2π f t)` across the
//! path, `t` the distance along it. Turning slows a skier down: between two extrema (half a
//! wavelength `1/(2f)` along the path, `2a` across) the track has length
//! `l = sqrt(1/(4f²) + 4a²)` and drops `sin(s)/(2f)` on a slope `s`, so its effective slope is
//!
//! ```text
//! se = arcsin( sin(s) / (2 f l) ) = arcsin( sin(s) / sqrt(1 + 16 a² f²) )
//! ```
//!
//! and the frequency that brings it to the target slope `st` is
//!
//! ```text
//! f = sqrt(sin²(s) − sin²(st)) / (4 a sin(st))
//! ```
//!
//! (0 when `s ≤ st`: no turn is needed). The phase `φ` is integrated along the path,
//! `dφ = 2π f dt`, so a change of frequency keeps the track continuous (the paper's "starting
//! phase value" chosen for continuity); the offset is taken across the skier's heading.

use std::f64::consts::TAU;

/// The paper's turn frequency `f = sqrt(sin²s − sin²st)/(4a·sin st)`, 1/m, for a coarse
/// segment of slope `slope_rad` and a target slope `target_rad`; 0 when `slope ≤ target` or
/// when there is no amplitude (`a = 0` cannot slow the skier down).
pub fn turn_frequency(slope_rad: f64, target_rad: f64, amplitude_m: f64) -> f64 {
    let (ss, st) = (slope_rad.sin(), target_rad.sin());
    let excess = ss * ss - st * st;
    if excess <= 0.0 || amplitude_m <= 0.0 || st <= 0.0 {
        return 0.0;
    }
    excess.sqrt() / (4.0 * amplitude_m * st)
}

/// The effective slope `se = arcsin(sin(s)/(2 f l))`, `l = sqrt(1/(4f²) + 4a²)`, of a sine
/// track of frequency `f` (1/m) and amplitude `a` (m) on a slope `s` (rad); `s` itself when
/// `f = 0` (a straight run).
pub fn effective_slope(slope_rad: f64, frequency: f64, amplitude_m: f64) -> f64 {
    if frequency <= 0.0 {
        return slope_rad;
    }
    let l = (1.0 / (4.0 * frequency * frequency) + 4.0 * amplitude_m * amplitude_m).sqrt();
    (slope_rad.sin() / (2.0 * frequency * l))
        .clamp(-1.0, 1.0)
        .asin()
}

/// The sine-wave state of one skier's refined track.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SineTrack {
    /// Amplitude `a`, m.
    pub amplitude_m: f64,
    /// Current frequency `f`, 1/m.
    pub frequency: f64,
    /// Phase `φ`, radians.
    pub phase: f64,
}

impl SineTrack {
    /// Advances the phase by a coarse distance `ds` (m) and returns the new across-track
    /// offset `a·sin φ`, m.
    #[inline]
    pub fn advance(&mut self, ds: f64) -> f64 {
        self.phase = (self.phase + TAU * self.frequency * ds) % TAU;
        self.offset()
    }
    /// The across-track offset `a·sin φ`, m.
    #[inline]
    pub fn offset(&self) -> f64 {
        self.amplitude_m * self.phase.sin()
    }
    /// The fine-track point at coarse position `(x, y)` with unit heading `(hx, hy)`: the
    /// offset is taken along the heading's left normal `(hy, −hx)` in the local frame
    /// (x east, y south).
    #[inline]
    pub fn point(&self, x: f64, y: f64, hx: f64, hy: f64) -> (f64, f64) {
        let o = self.offset();
        (x + o * hy, y - o * hx)
    }
}
