//! Keyed 2D gradient noise and the fractal sums built on it.
//!
//! Gradient (Perlin) noise on the integer lattice: each lattice point carries one of 16 unit
//! gradients, chosen by hashing (layer key, lattice point) with [`crate::random::mix64`]; the
//! layer key is [`crate::random::hash3`]`(seed, NOISE_STREAM, layer)`. A value is therefore a
//! pure function of (seed, layer, position): no tables, no state, the same bytes on any thread.
//! Values lie in about [-1, 1] (scaled by √2 from the raw ±√½ range); the analytic gradient is
//! returned alongside for distance estimates.

use crate::random::{hash3, mix64};

/// The random stream reserved for noise layer keys.
const NOISE_STREAM: u64 = 0x6e6f_6973_655f_6c79;
/// Odd multipliers that spread lattice coordinates over 64 bits before mixing.
const LATTICE_X: u64 = 0x9e37_79b9_7f4a_7c15;
const LATTICE_Y: u64 = 0xc2b2_ae3d_27d4_eb4f;
/// Scale that maps 2D Perlin noise's ±√½ range to about ±1.
const AMPLITUDE: f64 = std::f64::consts::SQRT_2;

/// cos 45° = sin 45°.
const H: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// 16 unit gradient directions, evenly spaced (k·22.5°).
const GRADIENTS: [(f64, f64); 16] = [
    (1.0, 0.0),
    (0.923_879_532_511_286_7, 0.382_683_432_365_089_8),
    (H, H),
    (0.382_683_432_365_089_8, 0.923_879_532_511_286_7),
    (0.0, 1.0),
    (-0.382_683_432_365_089_8, 0.923_879_532_511_286_7),
    (-H, H),
    (-0.923_879_532_511_286_7, 0.382_683_432_365_089_8),
    (-1.0, 0.0),
    (-0.923_879_532_511_286_7, -0.382_683_432_365_089_8),
    (-H, -H),
    (-0.382_683_432_365_089_8, -0.923_879_532_511_286_7),
    (0.0, -1.0),
    (0.382_683_432_365_089_8, -0.923_879_532_511_286_7),
    (H, -H),
    (0.923_879_532_511_286_7, -0.382_683_432_365_089_8),
];

/// A noise value and its gradient with respect to the (lattice-unit) position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseSample {
    /// Noise value, about [-1, 1].
    pub value: f64,
    /// ∂value/∂x in lattice units.
    pub dx: f64,
    /// ∂value/∂y in lattice units.
    pub dy: f64,
}

/// One independent layer of gradient noise, keyed by (seed, layer).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GradientNoise {
    key: u64,
}

/// Quintic fade `6t⁵ - 15t⁴ + 10t³` and its derivative.
#[inline(always)]
fn fade(t: f64) -> (f64, f64) {
    let t2 = t * t;
    let f = t2 * t * (t * (t * 6.0 - 15.0) + 10.0);
    let df = 30.0 * t2 * (t * (t - 2.0) + 1.0);
    (f, df)
}

impl GradientNoise {
    /// The noise layer `layer` of `seed`.
    pub fn new(seed: u64, layer: u64) -> Self {
        Self {
            key: hash3(seed, NOISE_STREAM, layer),
        }
    }

    /// The unit gradient at lattice point `(ix, iy)`.
    #[inline(always)]
    fn lattice_gradient(&self, ix: i64, iy: i64) -> (f64, f64) {
        let h = mix64(
            self.key
                ^ (ix as u64)
                    .wrapping_mul(LATTICE_X)
                    .wrapping_add((iy as u64).wrapping_mul(LATTICE_Y)),
        );
        GRADIENTS[(h >> 60) as usize]
    }

    /// The noise value at `(x, y)` in lattice units.
    #[inline]
    pub fn value(&self, x: f64, y: f64) -> f64 {
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (ix, iy) = (x0 as i64, y0 as i64);
        let g00 = self.lattice_gradient(ix, iy);
        let g10 = self.lattice_gradient(ix + 1, iy);
        let g01 = self.lattice_gradient(ix, iy + 1);
        let g11 = self.lattice_gradient(ix + 1, iy + 1);
        let a = g00.0 * fx + g00.1 * fy;
        let b = g10.0 * (fx - 1.0) + g10.1 * fy;
        let c = g01.0 * fx + g01.1 * (fy - 1.0);
        let d = g11.0 * (fx - 1.0) + g11.1 * (fy - 1.0);
        let (u, _) = fade(fx);
        let (v, _) = fade(fy);
        let ab = a + u * (b - a);
        let cd = c + u * (d - c);
        AMPLITUDE * (ab + v * (cd - ab))
    }

    /// The noise value and its analytic gradient at `(x, y)` in lattice units.
    #[inline]
    pub fn sample(&self, x: f64, y: f64) -> NoiseSample {
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (ix, iy) = (x0 as i64, y0 as i64);
        let g00 = self.lattice_gradient(ix, iy);
        let g10 = self.lattice_gradient(ix + 1, iy);
        let g01 = self.lattice_gradient(ix, iy + 1);
        let g11 = self.lattice_gradient(ix + 1, iy + 1);
        let a = g00.0 * fx + g00.1 * fy;
        let b = g10.0 * (fx - 1.0) + g10.1 * fy;
        let c = g01.0 * fx + g01.1 * (fy - 1.0);
        let d = g11.0 * (fx - 1.0) + g11.1 * (fy - 1.0);
        let (u, du) = fade(fx);
        let (v, dv) = fade(fy);
        let k = a - b - c + d;
        let value = a + u * (b - a) + v * (c - a) + u * v * k;
        let gx = g00.0
            + u * (g10.0 - g00.0)
            + v * (g01.0 - g00.0)
            + u * v * (g00.0 - g10.0 - g01.0 + g11.0)
            + du * (b - a + v * k);
        let gy = g00.1
            + u * (g10.1 - g00.1)
            + v * (g01.1 - g00.1)
            + u * v * (g00.1 - g10.1 - g01.1 + g11.1)
            + dv * (c - a + u * k);
        NoiseSample {
            value: AMPLITUDE * value,
            dx: AMPLITUDE * gx,
            dy: AMPLITUDE * gy,
        }
    }
}

/// Fractal Brownian motion: `octaves` layers of noise, each at twice the frequency and half the
/// amplitude of the previous one, normalised so the result stays in about [-1, 1].
#[derive(Debug, Clone)]
pub struct Fbm {
    layers: Vec<GradientNoise>,
}

impl Fbm {
    /// An fBm of `octaves` layers keyed by (seed, first_layer + octave).
    pub fn new(seed: u64, first_layer: u64, octaves: usize) -> Self {
        let layers = (0..octaves as u64)
            .map(|o| GradientNoise::new(seed, first_layer + o))
            .collect();
        Self { layers }
    }

    /// The fBm value at `(x, y)` in units of the first octave's lattice.
    #[inline]
    pub fn value(&self, x: f64, y: f64) -> f64 {
        let (mut sum, mut norm, mut amp, mut freq) = (0.0, 0.0, 1.0, 1.0);
        for layer in &self.layers {
            sum += amp * layer.value(x * freq, y * freq);
            norm += amp;
            amp *= 0.5;
            freq *= 2.0;
        }
        if norm > 0.0 { sum / norm } else { 0.0 }
    }
}

/// De Carpentier's "Swiss turbulence" (Scape, 2009): a ridged sum `Σ amp·(1 - |n|)` in which
/// each octave's position is warped by the accumulated noise gradient and each amplitude is
/// scaled by the height summed so far. Warping by the gradient bends the fine ridges down the
/// slopes like eroded gullies; the amplitude feedback keeps valleys smooth and summits rugged.
/// Each octave is also rotated by an irrational angle so no lattice direction is favoured.
#[derive(Debug, Clone)]
pub struct SwissTurbulence {
    layers: Vec<GradientNoise>,
    /// Amplitude ratio between octaves.
    gain: f64,
    /// Strength of the gradient warp, lattice units per unit gradient.
    warp: f64,
}

/// Rotation between octaves: about 37.5°, so lattices of successive octaves never align.
const OCTAVE_COS: f64 = 0.793_353_340_291_235;
const OCTAVE_SIN: f64 = 0.608_761_429_008_720_6;

impl SwissTurbulence {
    /// A Swiss turbulence of `octaves` layers keyed by (seed, first_layer + octave).
    pub fn new(seed: u64, first_layer: u64, octaves: usize) -> Self {
        let layers = (0..octaves as u64)
            .map(|o| GradientNoise::new(seed, first_layer + o))
            .collect();
        Self {
            layers,
            gain: 0.45,
            warp: 0.15,
        }
    }

    /// The largest value [`Self::value`] can return (every octave at full amplitude).
    pub fn max_value(&self) -> f64 {
        let (mut amp, mut total) = (1.0, 0.0);
        for _ in &self.layers {
            total += amp;
            amp *= self.gain;
        }
        total
    }

    /// The turbulence at `(x, y)` in units of the first octave's lattice, in
    /// `[0, max_value()]`.
    #[inline]
    pub fn value(&self, x: f64, y: f64) -> f64 {
        let (mut sum, mut amp, mut freq) = (0.0, 1.0, 1.0);
        let (mut dsum_x, mut dsum_y) = (0.0, 0.0);
        let (mut px, mut py) = (x, y);
        for layer in &self.layers {
            let s = layer.sample(
                (px + self.warp * dsum_x) * freq,
                (py + self.warp * dsum_y) * freq,
            );
            sum += amp * (1.0 - s.value.abs());
            dsum_x -= amp * s.dx * s.value;
            dsum_y -= amp * s.dy * s.value;
            freq *= 2.0;
            amp *= self.gain * sum.clamp(0.0, 1.0);
            (px, py) = (
                OCTAVE_COS * px - OCTAVE_SIN * py,
                OCTAVE_SIN * px + OCTAVE_COS * py,
            );
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_vanishes_on_the_lattice_and_stays_bounded() {
        let n = GradientNoise::new(7, 0);
        assert_eq!(n.value(3.0, -2.0), 0.0);
        let mut max = 0.0f64;
        for i in 0..20_000u64 {
            let x = (i % 200) as f64 * 0.173 - 17.0;
            let y = (i / 200) as f64 * 0.291 - 9.0;
            max = max.max(n.value(x, y).abs());
        }
        assert!(max <= 1.0 + 1e-9 && max > 0.5, "max |noise| {max}");
    }

    #[test]
    fn analytic_gradient_matches_finite_differences() {
        let n = GradientNoise::new(3, 5);
        let h = 1e-6;
        for (x, y) in [(0.3, 0.7), (-4.2, 1.9), (10.55, -3.01)] {
            let s = n.sample(x, y);
            assert!((s.value - n.value(x, y)).abs() < 1e-12);
            let fx = (n.value(x + h, y) - n.value(x - h, y)) / (2.0 * h);
            let fy = (n.value(x, y + h) - n.value(x, y - h)) / (2.0 * h);
            assert!((s.dx - fx).abs() < 1e-5, "{} vs {fx}", s.dx);
            assert!((s.dy - fy).abs() < 1e-5, "{} vs {fy}", s.dy);
        }
    }

    #[test]
    fn layers_and_seeds_are_independent() {
        let a = GradientNoise::new(1, 0).value(0.5, 0.5);
        let b = GradientNoise::new(1, 1).value(0.5, 0.5);
        let c = GradientNoise::new(2, 0).value(0.5, 0.5);
        assert!(a != b && a != c && b != c);
    }

    #[test]
    fn swiss_turbulence_stays_within_its_maximum() {
        let t = SwissTurbulence::new(9, 100, 6);
        let max = t.max_value();
        let mut seen = (f64::MAX, f64::MIN);
        for i in 0..5_000u64 {
            let v = t.value(i as f64 * 0.0371, i as f64 * 0.0213 + 1.0);
            assert!((0.0..=max).contains(&v), "{v} outside [0, {max}]");
            seen = (seen.0.min(v), seen.1.max(v));
        }
        assert!(seen.1 - seen.0 > 0.3 * max, "range {seen:?}");
    }
}
