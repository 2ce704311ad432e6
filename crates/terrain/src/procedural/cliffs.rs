//! Cliff bands: terracing applied where the ground is already steep.
//!
//! Strata that resist erosion leave steps on steep mountainsides: a near-vertical rock band, then
//! a ledge. Heights are mapped through a step function of period `band_height` whose risers are
//! about three times steeper than the original ground and whose treads are nearly flat; the
//! result is blended in by a weight that rises from 0 at 28° to 1 at 42° of original slope, so
//! steep ground gets irregular steeper rock bands separated by ledges (blended in at most at
//! `MAX_BLEND`, so they read as rock bands, not contour lines) while gentle ground is left alone.
//! The pass reads one buffer and writes another (Jacobi style), so its result does not depend on
//! the order in which rows are visited.

use crate::operators;
use rayon::prelude::*;

/// Slope (tangent) where terracing starts: tan 28°.
const ONSET_GRADIENT: f32 = 0.531_709_4;
/// Slope (tangent) where terracing is complete: tan 42°.
const FULL_GRADIENT: f32 = 0.900_404;
/// Sharpness of the step function: risers are about `SHARPNESS / 2` times steeper.
const SHARPNESS: f32 = 3.0;
/// Largest share of the terraced height blended in: full terraces read as contour lines
/// under snow, a partial blend as irregular rock bands.
const MAX_BLEND: f32 = 0.6;

/// The step function on one period: `r` in [0, 1) maps to [0, 1], flat near both ends.
#[inline(always)]
fn step_profile(r: f32) -> f32 {
    let half = (0.5 * SHARPNESS).tanh();
    0.5 + 0.5 * (SHARPNESS * (r - 0.5)).tanh() / half
}

/// `h` terraced with period `band_height` (m).
#[inline(always)]
fn terrace(h: f32, band_height: f32) -> f32 {
    let t = h / band_height;
    let floor = t.floor();
    band_height * (floor + step_profile(t - floor))
}

/// Blending weight of the terraces for a slope gradient magnitude (tangent).
#[inline(always)]
fn steepness_weight(gradient: f32) -> f32 {
    let t = ((gradient - ONSET_GRADIENT) / (FULL_GRADIENT - ONSET_GRADIENT)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Gradient magnitude (tangent of the slope) at `(col, row)` of the square field `z`:
/// [`operators::gradient`], one-sided at the borders.
#[inline(always)]
fn gradient_at(z: &[f32], size: usize, col: usize, row: usize, cell_size: f32) -> f32 {
    let at = |dc: isize, dr: isize| {
        let (c, r) = (col as isize + dc, row as isize + dr);
        (c >= 0 && r >= 0 && (c as usize) < size && (r as usize) < size)
            .then(|| z[r as usize * size + c as usize])
    };
    let (gx, gy) = operators::gradient(z[row * size + col], at, cell_size, cell_size);
    operators::slope_tangent(gx, gy)
}

/// Terraces the square height field `z` (`size` cells per side, metres) in bands of
/// `band_height` metres where it is steep. `band_mask(col, row)` in [0, 1] scales the effect
/// (rock bands are regional). A `band_height` of 0 leaves the field unchanged.
pub fn add_cliff_bands(
    z: Vec<f32>,
    size: usize,
    cell_size: f64,
    band_height: f64,
    band_mask: impl Fn(usize, usize) -> f32 + Sync,
) -> Vec<f32> {
    if band_height <= 0.0 || size < 2 {
        return z;
    }
    let (cell, band) = (cell_size as f32, band_height as f32);
    let mut out = vec![0.0f32; z.len()];
    out.par_chunks_mut(size)
        .enumerate()
        .for_each(|(row, line)| {
            for (col, h) in line.iter_mut().enumerate() {
                let old = z[row * size + col];
                let weight = MAX_BLEND
                    * steepness_weight(gradient_at(&z, size, col, row, cell))
                    * band_mask(col, row);
                *h = if weight > 0.0 {
                    old + weight * (terrace(old, band) - old)
                } else {
                    old
                };
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terrace_is_monotonic_and_keeps_band_edges() {
        let band = 50.0;
        assert!((terrace(100.0, band) - 100.0).abs() < 1e-3);
        assert!((terrace(125.0, band) - 125.0).abs() < 1e-3);
        let mut prev = terrace(0.0, band);
        for i in 1..1000 {
            let t = terrace(i as f32 * 0.37, band);
            assert!(t >= prev - 1e-4, "not monotonic at {i}");
            prev = t;
        }
    }

    #[test]
    fn gentle_ground_is_untouched_and_steep_ground_gets_steps() {
        let size = 64;
        let cell = 10.0;
        let ramp = |g: f32| -> Vec<f32> {
            (0..size * size)
                .map(|i| 1000.0 + g * cell as f32 * (i % size) as f32)
                .collect()
        };
        let gentle = ramp(0.2);
        assert_eq!(
            add_cliff_bands(gentle.clone(), size, cell, 50.0, |_, _| 1.0),
            gentle
        );
        let steep = add_cliff_bands(ramp(1.0), size, cell, 50.0, |_, _| 1.0);
        let row = &steep[32 * size..33 * size];
        let rises: Vec<f32> = row.windows(2).map(|w| (w[1] - w[0]) / 10.0).collect();
        let max = rises[2..60].iter().cloned().fold(f32::MIN, f32::max);
        let min = rises[2..60].iter().cloned().fold(f32::MAX, f32::min);
        // On a 45° ramp (gradient 1) the risers reach ≈1.37 and the ledges ≈0.71 (a partial
        // blend of the terraces): untouched ground would stay at 1 everywhere.
        assert!(
            max > 1.3 && min < 0.75 && max > 1.8 * min,
            "gradients {min}..{max}"
        );
    }
}
