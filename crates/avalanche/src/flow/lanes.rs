//! Lanes of `f64` for the flow kernels: one kernel source runs on one cell (`f64`), on four
//! consecutive cells of a row (AVX, `F4`) or on eight (AVX-512, `F8`, with four-lane and
//! one-lane visits for the rest of a segment). Every lane operation is the IEEE operation of
//! the scalar code (no fused multiply-add, no reassociation), so all give bit-identical results
//! and the choice of path (CPU features) never changes a result.

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
    /// Half as many lanes (`f64` for one and four lanes): the kernel for a segment's end.
    type Half: Lanes;
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
    /// `(m, e)` with `self = m·2^e`, `m` in `[1, 2)` and `e` an integer (as `f64`), exactly,
    /// for positive normal finite lanes (bit operations on the IEEE fields).
    fn split_exponent(self) -> (Self, Self);
}

impl Lanes for f64 {
    const N: usize = 1;
    type M = bool;
    type Half = f64;
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
    #[inline(always)]
    fn split_exponent(self) -> (Self, Self) {
        let b = self.to_bits();
        let e = ((b >> 52) & 0x7ff) as f64 - 1023.0;
        let m = f64::from_bits((b & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
        (m, e)
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
        type Half = f64;
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
        #[inline(always)]
        fn split_exponent(self) -> (Self, Self) {
            unsafe {
                let mantissa = _mm256_castsi256_pd(_mm256_set1_epi64x(0x000f_ffff_ffff_ffff));
                let m = _mm256_or_pd(_mm256_and_pd(self.0, mantissa), _mm256_set1_pd(1.0));
                // The biased exponent of each lane (AVX has no 256-bit integer shift: SSE2 on
                // the two halves), made a double exactly by the 2^52 trick.
                let bits = _mm256_castpd_si256(self.0);
                let magic = _mm_set1_epi64x(0x4330_0000_0000_0000);
                let two52 = _mm_set1_pd(4_503_599_627_370_496.0);
                let field = |half: __m128i| {
                    let biased = _mm_and_si128(_mm_srli_epi64(half, 52), _mm_set1_epi64x(0x7ff));
                    _mm_sub_pd(_mm_castsi128_pd(_mm_or_si128(biased, magic)), two52)
                };
                let lo = field(_mm256_castsi256_si128(bits));
                let hi = field(_mm256_extractf128_si256(bits, 1));
                let e = _mm256_insertf128_pd(_mm256_castpd128_pd256(lo), hi, 1);
                (F4(m), F4(_mm256_sub_pd(e, _mm256_set1_pd(1023.0))))
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) use avx512::F8;

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use super::{F4, Lanes};
    use std::arch::x86_64::*;
    use std::ops::{Add, Div, Mul, Neg, Sub};

    /// Eight `f64` lanes in an AVX-512 register. Only used inside functions compiled with the
    /// `avx512f` and `avx512dq` target features (where these wrappers inline), after checking
    /// that the CPU has them.
    #[derive(Clone, Copy)]
    pub(in crate::flow) struct F8(__m512d);

    macro_rules! binop {
        ($tr:ident, $f:ident, $intr:ident) => {
            impl $tr for F8 {
                type Output = F8;
                #[inline(always)]
                fn $f(self, o: F8) -> F8 {
                    // SAFETY: F8 only exists where the CPU supports AVX-512F.
                    F8(unsafe { $intr(self.0, o.0) })
                }
            }
        };
    }
    binop!(Add, add, _mm512_add_pd);
    binop!(Sub, sub, _mm512_sub_pd);
    binop!(Mul, mul, _mm512_mul_pd);
    binop!(Div, div, _mm512_div_pd);

    impl Neg for F8 {
        type Output = F8;
        #[inline(always)]
        fn neg(self) -> F8 {
            // SAFETY: as above (and AVX-512DQ).
            F8(unsafe { _mm512_xor_pd(self.0, _mm512_set1_pd(-0.0)) })
        }
    }

    // SAFETY (every block below): F8 only exists where the CPU supports AVX-512F and DQ; loads
    // and stores go through bounds-checked slices.
    impl Lanes for F8 {
        const N: usize = 8;
        type M = __mmask8;
        type Half = F4;
        #[inline(always)]
        fn splat(x: f64) -> Self {
            F8(unsafe { _mm512_set1_pd(x) })
        }
        #[inline(always)]
        fn store(self, s: &mut [f64], i: usize) {
            let s = &mut s[i..i + 8];
            unsafe { _mm512_storeu_pd(s.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        unsafe fn load_ptr(p: *const f64) -> Self {
            // (And the caller's contract.)
            F8(unsafe { _mm512_loadu_pd(p) })
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            F8(unsafe { _mm512_sqrt_pd(self.0) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            F8(unsafe { _mm512_andnot_pd(_mm512_set1_pd(-0.0), self.0) })
        }
        #[inline(always)]
        fn signum(self) -> Self {
            F8(unsafe {
                _mm512_or_pd(
                    _mm512_and_pd(self.0, _mm512_set1_pd(-0.0)),
                    _mm512_set1_pd(1.0),
                )
            })
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            F8(unsafe { _mm512_max_pd(self.0, o.0) })
        }
        #[inline(always)]
        fn le(self, o: Self) -> __mmask8 {
            unsafe { _mm512_cmp_pd_mask::<_CMP_LE_OQ>(self.0, o.0) }
        }
        #[inline(always)]
        fn lt(self, o: Self) -> __mmask8 {
            unsafe { _mm512_cmp_pd_mask::<_CMP_LT_OQ>(self.0, o.0) }
        }
        #[inline(always)]
        fn gt(self, o: Self) -> __mmask8 {
            unsafe { _mm512_cmp_pd_mask::<_CMP_GT_OQ>(self.0, o.0) }
        }
        #[inline(always)]
        fn ne(self, o: Self) -> __mmask8 {
            unsafe { _mm512_cmp_pd_mask::<_CMP_NEQ_UQ>(self.0, o.0) }
        }
        #[inline(always)]
        fn and(a: __mmask8, b: __mmask8) -> __mmask8 {
            a & b
        }
        #[inline(always)]
        fn or(a: __mmask8, b: __mmask8) -> __mmask8 {
            a | b
        }
        #[inline(always)]
        fn all(m: __mmask8) -> bool {
            m == 0xFF
        }
        #[inline(always)]
        fn any(m: __mmask8) -> bool {
            m != 0
        }
        #[inline(always)]
        fn bits(m: __mmask8) -> u32 {
            m as u32
        }
        #[inline(always)]
        fn select(m: __mmask8, a: Self, b: Self) -> Self {
            // (`mask_blend` takes its second operand where the mask is set.)
            F8(unsafe { _mm512_mask_blend_pd(m, b.0, a.0) })
        }
        #[inline(always)]
        fn lane(self, i: usize) -> f64 {
            let mut out = [0.0; 8];
            unsafe { _mm512_storeu_pd(out.as_mut_ptr(), self.0) };
            out[i]
        }
        #[inline(always)]
        fn split_exponent(self) -> (Self, Self) {
            unsafe {
                let mantissa = _mm512_castsi512_pd(_mm512_set1_epi64(0x000f_ffff_ffff_ffff));
                let m = _mm512_or_pd(_mm512_and_pd(self.0, mantissa), _mm512_set1_pd(1.0));
                // The biased exponent of each lane, made a double exactly by the 2^52 trick.
                let bits = _mm512_castpd_si512(self.0);
                let biased =
                    _mm512_and_si512(_mm512_srli_epi64::<52>(bits), _mm512_set1_epi64(0x7ff));
                let magic = _mm512_set1_epi64(0x4330_0000_0000_0000);
                let two52 = _mm512_set1_pd(4_503_599_627_370_496.0);
                let e = _mm512_sub_pd(_mm512_castsi512_pd(_mm512_or_si512(biased, magic)), two52);
                (F8(m), F8(_mm512_sub_pd(e, _mm512_set1_pd(1023.0))))
            }
        }
    }
}

/// The widest lanes the flow kernels can run on this CPU (ordered by width).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum Simd {
    /// One cell at a time.
    Scalar,
    /// Four cells (AVX).
    Avx,
    /// Eight cells (AVX-512F and DQ), four and one at a segment's end.
    Avx512,
}

impl Simd {
    /// The widest this CPU has (decided once per process).
    pub(super) fn detect() -> Simd {
        static DETECTED: std::sync::OnceLock<Simd> = std::sync::OnceLock::new();
        *DETECTED.get_or_init(|| {
            #[cfg(target_arch = "x86_64")]
            {
                use std::arch::is_x86_feature_detected as has;
                if has!("avx512f") && has!("avx512dq") && has!("avx") {
                    return Simd::Avx512;
                }
                if has!("avx") {
                    return Simd::Avx;
                }
            }
            Simd::Scalar
        })
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

/// `ln(x)` for finite `x >= 1` (the caller passes `max(h/R, 1)` of a finite depth), lane by
/// lane with the exact operations of [`Lanes`] only, so that the one-lane and four-lane kernels
/// agree to the bit (the library `ln` has no vector form here, and calling it lane by lane cost
/// the samosAT law a quarter of a sub-step).
///
/// `x = m·2^e` ([`Lanes::split_exponent`]) with `m` brought into `[√½, √2]`, then
/// `ln m = 2·atanh(s)`, `s = (m − 1)/(m + 1)`, `|s| ≤ 0.1716`: the series
/// `2s·Σ s^(2k)/(2k + 1)` to `k = 8` (Estrin's scheme, for a short dependency chain); the first
/// term left out is below `1e-15` of the sum (tested against `f64::ln`, relative error < 1e-14).
#[inline(always)]
pub(super) fn ln_at_least_one<V: Lanes>(x: V) -> V {
    let (m, e) = x.split_exponent();
    let big = m.gt(V::splat(std::f64::consts::SQRT_2));
    let m = V::select(big, m * V::splat(0.5), m);
    let e = V::select(big, e + V::splat(1.0), e);
    let one = V::splat(1.0);
    let s = (m - one) / (m + one);
    let z = s * s;
    let (z2, c) = (z * z, |d: f64| V::splat(1.0 / d));
    let z4 = z2 * z2;
    let q0 = (one + z * c(3.0)) + z2 * (c(5.0) + z * c(7.0));
    let q1 = (c(9.0) + z * c(11.0)) + z2 * (c(13.0) + z * c(15.0));
    let p = q0 + z4 * (q1 + z4 * c(17.0));
    e * V::splat(std::f64::consts::LN_2) + V::splat(2.0) * s * p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ln_at_least_one_follows_the_library_ln() {
        let mut worst = 0.0f64;
        let mut x = 1.0f64;
        while x < 1e12 {
            for y in [x, x * 1.000_1, x * std::f64::consts::SQRT_2, x * 1.999_999] {
                let got = ln_at_least_one::<f64>(y);
                let want = y.ln();
                let err = if want == 0.0 {
                    got.abs()
                } else {
                    ((got - want) / want).abs()
                };
                worst = worst.max(err);
            }
            x *= 1.37;
        }
        assert!(worst < 1e-14, "relative error {worst:e}");
        assert_eq!(ln_at_least_one::<f64>(1.0), 0.0);
        #[cfg(target_arch = "x86_64")]
        if Simd::detect() != Simd::Scalar {
            // Four lanes give the one-lane bits.
            let xs = [1.0, 2.5, 77.7, 1.0e6];
            // SAFETY: `xs` holds 4 values; AVX is available.
            let v = unsafe { F4::load_ptr(xs.as_ptr()) };
            let l = ln_at_least_one::<F4>(v);
            for (i, &x) in xs.iter().enumerate() {
                assert_eq!(l.lane(i).to_bits(), ln_at_least_one::<f64>(x).to_bits());
            }
        }
        #[cfg(target_arch = "x86_64")]
        if Simd::detect() == Simd::Avx512 {
            // So do eight.
            let xs = [1.0, 2.5, 77.7, 1.0e6, 1.5, 3.0e-0, 1.0e11, 42.0];
            #[target_feature(enable = "avx512f,avx512dq")]
            fn eight(xs: &[f64; 8]) -> [u64; 8] {
                // SAFETY: `xs` holds 8 values; the caller checked AVX-512.
                let l = ln_at_least_one::<F8>(unsafe { F8::load_ptr(xs.as_ptr()) });
                std::array::from_fn(|i| l.lane(i).to_bits())
            }
            // SAFETY: AVX-512F and DQ are available (checked above).
            let got = unsafe { eight(&xs) };
            for (g, &x) in got.iter().zip(&xs) {
                assert_eq!(*g, ln_at_least_one::<f64>(x).to_bits());
            }
        }
    }
}
