//! Counter-based random numbers: a value is a pure function of (seed, stream, index).
//!
//! A run draws each random number from a key, never from a shared generator's state, so the
//! result does not depend on the order in which threads, tiles or machines visit cells
//! (`docs/src/architecture.md#conventions`, determinism). The mixing function is SplitMix64's finaliser (Steele, Lea &
//! Flood 2014), applied to a combination of the three keys.

/// SplitMix64 finaliser: a bijective 64-bit mix with full avalanche.
#[inline(always)]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A 64-bit random value keyed by (seed, stream, index).
#[inline(always)]
pub fn hash3(seed: u64, stream: u64, index: u64) -> u64 {
    let a = mix64(seed ^ 0x9e37_79b9_7f4a_7c15);
    let b = mix64(a ^ stream.wrapping_mul(0xd1b5_4a32_d192_ed03));
    mix64(b ^ index.wrapping_mul(0x8cb9_2ba7_2f3d_8dd7))
}

/// A uniform f64 in [0, 1) keyed by (seed, stream, index).
#[inline(always)]
pub fn uniform(seed: u64, stream: u64, index: u64) -> f64 {
    (hash3(seed, stream, index) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A standard normal value keyed by (seed, stream, index) (Box-Muller on two keyed uniforms).
pub fn normal(seed: u64, stream: u64, index: u64) -> f64 {
    let u1 = uniform(seed, stream, index.wrapping_mul(2)).max(f64::MIN_POSITIVE);
    let u2 = uniform(seed, stream, index.wrapping_mul(2).wrapping_add(1));
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// A small sequential generator for code that draws many numbers in a fixed order from one key
/// (one event, one agent): the n-th draw is `uniform(seed, stream, n)`.
#[derive(Debug, Clone)]
pub struct KeyedRng {
    seed: u64,
    stream: u64,
    counter: u64,
}

impl KeyedRng {
    /// A generator for one (seed, stream) key.
    pub fn new(seed: u64, stream: u64) -> Self {
        Self {
            seed,
            stream,
            counter: 0,
        }
    }
    /// The next uniform value in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        let v = uniform(self.seed, self.stream, self.counter);
        self.counter += 1;
        v
    }
    /// The next standard normal value.
    pub fn next_normal(&mut self) -> f64 {
        let v = normal(self.seed, self.stream, self.counter);
        self.counter += 1;
        v
    }
    /// A uniform value in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_is_in_range_and_mean_is_half() {
        let n = 100_000;
        let mut s = 0.0;
        for i in 0..n {
            let u = uniform(42, 7, i);
            assert!((0.0..1.0).contains(&u));
            s += u;
        }
        assert!((s / n as f64 - 0.5).abs() < 0.005);
    }

    #[test]
    fn keys_are_independent() {
        assert_ne!(hash3(1, 0, 0), hash3(0, 1, 0));
        assert_ne!(hash3(0, 0, 1), hash3(0, 1, 0));
        assert_eq!(hash3(5, 6, 7), hash3(5, 6, 7));
    }

    #[test]
    fn normal_has_unit_variance() {
        let n = 50_000u64;
        let xs: Vec<f64> = (0..n).map(|i| normal(3, 1, i)).collect();
        let m = xs.iter().sum::<f64>() / n as f64;
        let v = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n as f64;
        assert!(m.abs() < 0.02 && (v - 1.0).abs() < 0.03, "mean {m} var {v}");
    }
}
