//! Single-instruction forms of `max`, `min` and truncation for the hot loops. The library
//! versions handle NaN and saturation with extra instructions the kernels do not need: here
//! the comparison form decides what a NaN gives, and it is stated on each function.

/// `f32::max(x, lo)` as one `maxss`: the comparison form gives `lo` for a NaN `x` too.
#[inline(always)]
pub(crate) fn at_least(x: f32, lo: f32) -> f32 {
    if x > lo { x } else { lo }
}

/// `f32::min(x, hi)` as one `minss` (`hi` for a NaN `x`, as [`f32::min`]).
#[inline(always)]
pub(crate) fn at_most(x: f32, hi: f32) -> f32 {
    if x < hi { x } else { hi }
}

/// `t` rounded towards zero, for `0 ≤ t < 2³¹`; NaN gives `2³¹`. One instruction on
/// x86-64, where `as` would add the saturation checks it does not need here.
#[inline(always)]
pub(crate) fn truncate(t: f32) -> u32 {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cvttss_si32, _mm_set_ss};
        // SAFETY: SSE is part of the x86-64 baseline, so these instructions always exist.
        unsafe { _mm_cvttss_si32(_mm_set_ss(t)) as u32 }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        if t.is_nan() { 1 << 31 } else { t as u32 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comparison_forms_match_the_library_on_numbers_and_pick_the_bound_for_nan() {
        for (x, b) in [(1.0f32, 2.0), (3.0, 2.0), (-0.5, 0.0), (2.0, 2.0)] {
            assert_eq!(at_least(x, b), x.max(b));
            assert_eq!(at_most(x, b), x.min(b));
        }
        assert_eq!(at_least(f32::NAN, 1.5), 1.5);
        assert_eq!(at_most(f32::NAN, 1.5), 1.5);
        assert_eq!(truncate(0.0), 0);
        assert_eq!(truncate(7.999), 7);
        assert_eq!(truncate(123_456.5), 123_456);
        assert_eq!(truncate(f32::NAN), 1 << 31);
    }
}
