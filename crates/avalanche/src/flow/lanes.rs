//! Lanes of `f64` for the flow kernels: one kernel source runs on one cell (`f64`) or on
//! four consecutive cells of a row (AVX, `F4`). Every lane operation is the IEEE operation
//! of the scalar code (no fused multiply-add, no reassociation), so the two give bit-identical
//! results and the choice of path (CPU features) never changes a result.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A vector of `N` `f64` lanes with a mask type `M` (one flag per lane).
pub(super) trait Lanes:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    const N: usize;
    type M: Copy;
    fn splat(x: f64) -> Self;
    fn store(self, s: &mut [f64], i: usize);
    /// Lanes `p[0..N]`.
    ///
    /// # Safety
    /// `p` must be valid for reading `N` values.
    unsafe fn load_ptr(p: *const f64) -> Self;
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    /// `f64::signum` (for non-NaN lanes).
    fn signum(self) -> Self;
    /// `f64::max` for lanes where neither is NaN and the two are not zeros of opposite signs.
    fn max(self, o: Self) -> Self;
    fn le(self, o: Self) -> Self::M;
    fn lt(self, o: Self) -> Self::M;
    fn gt(self, o: Self) -> Self::M;
    /// `!=` (true when either is NaN).
    fn ne(self, o: Self) -> Self::M;
    fn and(a: Self::M, b: Self::M) -> Self::M;
    fn or(a: Self::M, b: Self::M) -> Self::M;
    fn all(m: Self::M) -> bool;
    fn any(m: Self::M) -> bool;
    /// Bit `i` set when lane `i` is set.
    fn bits(m: Self::M) -> u32;
    /// Per lane, `a` where `m` is set, else `b`.
    fn select(m: Self::M, a: Self, b: Self) -> Self;
    fn lane(self, i: usize) -> f64;
}

impl Lanes for f64 {
    const N: usize = 1;
    type M = bool;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn store(self, s: &mut [f64], i: usize) {
        s[i] = self;
    }
    #[inline(always)]
    unsafe fn load_ptr(p: *const f64) -> Self {
        // SAFETY: the caller's contract.
        unsafe { *p }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f64::abs(self)
    }
    #[inline(always)]
    fn signum(self) -> Self {
        f64::signum(self)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        f64::max(self, o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> bool {
        self <= o
    }
    #[inline(always)]
    fn lt(self, o: Self) -> bool {
        self < o
    }
    #[inline(always)]
    fn gt(self, o: Self) -> bool {
        self > o
    }
    #[inline(always)]
    fn ne(self, o: Self) -> bool {
        self != o
    }
    #[inline(always)]
    fn and(a: bool, b: bool) -> bool {
        a & b
    }
    #[inline(always)]
    fn or(a: bool, b: bool) -> bool {
        a | b
    }
    #[inline(always)]
    fn all(m: bool) -> bool {
        m
    }
    #[inline(always)]
    fn any(m: bool) -> bool {
        m
    }
    #[inline(always)]
    fn bits(m: bool) -> u32 {
        m as u32
    }
    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m { a } else { b }
    }
    #[inline(always)]
    fn lane(self, _i: usize) -> f64 {
        self
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) use avx::F4;

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::Lanes;
    use std::arch::x86_64::*;
    use std::ops::{Add, Div, Mul, Neg, Sub};

    /// Four `f64` lanes in an AVX register. Only used inside functions compiled with the
    /// `avx` target feature (where these wrappers inline), after checking that the CPU has it.
    #[derive(Clone, Copy)]
    pub(in crate::flow) struct F4(__m256d);

    macro_rules! binop {
        ($tr:ident, $f:ident, $intr:ident) => {
            impl $tr for F4 {
                type Output = F4;
                #[inline(always)]
                fn $f(self, o: F4) -> F4 {
                    // SAFETY: F4 only exists where the CPU supports AVX.
                    F4(unsafe { $intr(self.0, o.0) })
                }
            }
        };
    }
    binop!(Add, add, _mm256_add_pd);
    binop!(Sub, sub, _mm256_sub_pd);
    binop!(Mul, mul, _mm256_mul_pd);
    binop!(Div, div, _mm256_div_pd);

    impl Neg for F4 {
        type Output = F4;
        #[inline(always)]
        fn neg(self) -> F4 {
            // SAFETY: as above.
            F4(unsafe { _mm256_xor_pd(self.0, _mm256_set1_pd(-0.0)) })
        }
    }

    // SAFETY (every block below): F4 only exists where the CPU supports AVX; loads and stores
    // go through bounds-checked slices.
    impl Lanes for F4 {
        const N: usize = 4;
        type M = __m256d;
        #[inline(always)]
        fn splat(x: f64) -> Self {
            F4(unsafe { _mm256_set1_pd(x) })
        }
        #[inline(always)]
        fn store(self, s: &mut [f64], i: usize) {
            let s = &mut s[i..i + 4];
            unsafe { _mm256_storeu_pd(s.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        unsafe fn load_ptr(p: *const f64) -> Self {
            // (And the caller's contract.)
            F4(unsafe { _mm256_loadu_pd(p) })
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            F4(unsafe { _mm256_sqrt_pd(self.0) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            F4(unsafe { _mm256_andnot_pd(_mm256_set1_pd(-0.0), self.0) })
        }
        #[inline(always)]
        fn signum(self) -> Self {
            F4(unsafe {
                _mm256_or_pd(
                    _mm256_and_pd(self.0, _mm256_set1_pd(-0.0)),
                    _mm256_set1_pd(1.0),
                )
            })
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            F4(unsafe { _mm256_max_pd(self.0, o.0) })
        }
        #[inline(always)]
        fn le(self, o: Self) -> __m256d {
            unsafe { _mm256_cmp_pd::<_CMP_LE_OQ>(self.0, o.0) }
        }
        #[inline(always)]
        fn lt(self, o: Self) -> __m256d {
            unsafe { _mm256_cmp_pd::<_CMP_LT_OQ>(self.0, o.0) }
        }
        #[inline(always)]
        fn gt(self, o: Self) -> __m256d {
            unsafe { _mm256_cmp_pd::<_CMP_GT_OQ>(self.0, o.0) }
        }
        #[inline(always)]
        fn ne(self, o: Self) -> __m256d {
            unsafe { _mm256_cmp_pd::<_CMP_NEQ_UQ>(self.0, o.0) }
        }
        #[inline(always)]
        fn and(a: __m256d, b: __m256d) -> __m256d {
            unsafe { _mm256_and_pd(a, b) }
        }
        #[inline(always)]
        fn or(a: __m256d, b: __m256d) -> __m256d {
            unsafe { _mm256_or_pd(a, b) }
        }
        #[inline(always)]
        fn all(m: __m256d) -> bool {
            unsafe { _mm256_movemask_pd(m) == 0xF }
        }
        #[inline(always)]
        fn any(m: __m256d) -> bool {
            unsafe { _mm256_movemask_pd(m) != 0 }
        }
        #[inline(always)]
        fn bits(m: __m256d) -> u32 {
            unsafe { _mm256_movemask_pd(m) as u32 }
        }
        #[inline(always)]
        fn select(m: __m256d, a: Self, b: Self) -> Self {
            F4(unsafe { _mm256_blendv_pd(b.0, a.0, m) })
        }
        #[inline(always)]
        fn lane(self, i: usize) -> f64 {
            let mut out = [0.0; 4];
            unsafe { _mm256_storeu_pd(out.as_mut_ptr(), self.0) };
            out[i]
        }
    }
}

/// Whether the four-lane path can run on this CPU.
pub(super) fn simd_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Lanes `s[i..i + V::N]` without a bounds check.
///
/// # Safety
/// `i + V::N <= s.len()`.
#[inline(always)]
pub(super) unsafe fn ld<V: Lanes>(s: &[f64], i: usize) -> V {
    debug_assert!(i + V::N <= s.len());
    // SAFETY: the caller's contract.
    unsafe { V::load_ptr(s.as_ptr().add(i)) }
}
