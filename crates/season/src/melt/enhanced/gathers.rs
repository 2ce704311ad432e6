//! The per-cell table lookups of a melt window ([`Coefficients::lookups`]) eight cells at a
//! time with AVX2 gathers. Written as plain loops the lookups compiled to scalar loads (the
//! compiler's cost model does not gather), six per cell; here each of the six is one gather
//! per eight cells, and every other operation is the IEEE operation of the scalar code in its
//! order (no fused multiply-add), so both paths give the same bits (tested).

use super::{ALBEDO_ENTRIES, ALBEDO_STEP_DAYS, Coefficients, DegreeHours};
use std::arch::x86_64::*;

impl Coefficients {
    /// [`Coefficients::lookups`] of the first cells of a row, in groups of eight; returns how
    /// many it did (the rest, fewer than eight, are the caller's).
    pub(super) fn lookups_avx2(
        &self,
        off: &[f32],
        (age, melting): (&[f32], &[f32]),
        (absorbed, cooling, warm): (&mut [f32], &mut [f32], &mut [f32]),
    ) -> usize {
        let w = off
            .len()
            .min(age.len())
            .min(melting.len())
            .min(absorbed.len())
            .min(cooling.len())
            .min(warm.len());
        let full = w - w % 8;
        let dh = &self.degree_hours;
        // Gathers read the tables at `k` and `k + 1` with `k` clamped to `len − 2` (as the
        // scalar code): in bounds.
        assert!(self.albedo.len() >= 2 * ALBEDO_ENTRIES && dh.cooling.len() >= 2);
        assert!(dh.warm.len() >= dh.cooling.len() && dh.cooling.len() <= 1 << 24);
        // SAFETY: AVX2 is on (the cfg of this module); every load and store is within the
        // first `full` cells of slices at least `w` long; the gathers' indices are in bounds
        // (above).
        unsafe {
            let (t, n) = (self.albedo.as_ptr(), ALBEDO_ENTRIES as i32);
            let zero = _mm256_setzero_ps();
            let one = _mm256_set1_ps(1.0);
            let half = _mm256_set1_ps(0.5);
            let age_scale = _mm256_set1_ps(1.0 / ALBEDO_STEP_DAYS);
            let age_top = _mm256_set1_ps((ALBEDO_ENTRIES - 1) as f32);
            let age_k_top = _mm256_set1_epi32(n - 2);
            let melting_curve = _mm256_set1_epi32(n);
            let (c, wm) = (dh.cooling.as_ptr(), dh.warm.as_ptr());
            let offset_min = _mm256_set1_ps(dh.offset_min);
            let offset_scale = _mm256_set1_ps(1.0 / DegreeHours::STEP_C);
            let offset_k_top = _mm256_set1_epi32(dh.cooling.len() as i32 - 2);
            for col in (0..full).step_by(8) {
                // The albedo (`albedo_at`).
                let a = _mm256_loadu_ps(age.as_ptr().add(col));
                let x = _mm256_min_ps(_mm256_mul_ps(_mm256_max_ps(a, zero), age_scale), age_top);
                let k = _mm256_min_epu32(_mm256_cvttps_epi32(x), age_k_top);
                let f = _mm256_sub_ps(x, _mm256_cvtepi32_ps(k));
                let m =
                    _mm256_cmp_ps::<_CMP_GT_OQ>(_mm256_loadu_ps(melting.as_ptr().add(col)), half);
                let k =
                    _mm256_add_epi32(k, _mm256_and_si256(_mm256_castps_si256(m), melting_curve));
                let t0 = _mm256_i32gather_ps::<4>(t, k);
                let t1 = _mm256_i32gather_ps::<4>(t.add(1), k);
                let albedo = _mm256_add_ps(t0, _mm256_mul_ps(f, _mm256_sub_ps(t1, t0)));
                _mm256_storeu_ps(absorbed.as_mut_ptr().add(col), _mm256_sub_ps(one, albedo));
                // The degree-hours (`DegreeHours::at`).
                let o = _mm256_loadu_ps(off.as_ptr().add(col));
                let x = _mm256_max_ps(
                    _mm256_mul_ps(_mm256_sub_ps(o, offset_min), offset_scale),
                    zero,
                );
                // (`x as u32` saturates; the truncation gives 2^31 from 2^31 up, which the
                // clamp to `len − 2` takes alike.)
                let k = _mm256_min_epu32(_mm256_cvttps_epi32(x), offset_k_top);
                let f = _mm256_min_ps(_mm256_sub_ps(x, _mm256_cvtepi32_ps(k)), one);
                let c0 = _mm256_i32gather_ps::<4>(c, k);
                let c1 = _mm256_i32gather_ps::<4>(c.add(1), k);
                let w0 = _mm256_i32gather_ps::<4>(wm, k);
                let w1 = _mm256_i32gather_ps::<4>(wm.add(1), k);
                let cool = _mm256_add_ps(c0, _mm256_mul_ps(f, _mm256_sub_ps(c1, c0)));
                let warm_h = _mm256_add_ps(w0, _mm256_mul_ps(f, _mm256_sub_ps(w1, w0)));
                _mm256_storeu_ps(cooling.as_mut_ptr().add(col), cool);
                _mm256_storeu_ps(warm.as_mut_ptr().add(col), warm_h);
            }
        }
        full
    }
}
