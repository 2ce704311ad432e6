//! The kernel's fast path (see the parent module): runs of columns of at most two sites,
//! eight at a time with AVX2 where the CPU has it, one at a time elsewhere, giving the same
//! integers as the member-by-member `member_term`.

use super::{
    DENSE, KernelTable, LAMBDA_ONE, MEMBER, PAD, ROOMY_LOWER, ROOMY_UPPER, SEEN, SEEN_UPPER, Sums,
    TWO, boundary_term, lambda_units,
};

/// A run of `len` contiguous columns of a disk row: their bases and flags and the table's
/// weights for them (`t0` the table index of the first); each slice holds at least
/// `len + PAD` values.
pub(super) struct DenseRun<'a> {
    pub(super) base: &'a [f32],
    pub(super) upper: &'a [f32],
    pub(super) flags: &'a [i32],
    /// Whether the kernel's site has room for 2 h0.
    pub(super) roomy: bool,
    /// Whether every column of the run is empty or holds one visible site (no flags needed:
    /// a column has a member, visible, unless its base is `-∞`).
    pub(super) plain: bool,
    pub(super) weight: &'a [i32],
    pub(super) len: usize,
    pub(super) table: &'a KernelTable,
    pub(super) t0: usize,
}

/// The terms of a [`DenseRun`]'s columns of at most two sites (the others are left to the
/// general path): the integers of [`member_term`], eight
/// columns at a time with AVX2 where the CPU has it (the same IEEE operations as the scalar
/// code, and exact integer sums, so the same bits either way).
pub(super) fn dense_run(
    sums: &mut Sums,
    lanes: &mut LaneSums,
    run: &DenseRun,
    s: f32,
    h0: f32,
    inv_h0: f32,
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 is present.
        unsafe {
            if run.plain {
                dense_lanes_avx2::<true>(lanes, run, s, h0, inv_h0)
            } else {
                dense_lanes_avx2::<false>(lanes, run, s, h0, inv_h0)
            }
        };
        return;
    }
    let _ = lanes;
    dense_scalar(sums, run, s, h0, inv_h0);
}

/// The lanes' sums over a site's runs, kept apart until the site is done (a reduction per row
/// would cost as much as the row).
#[derive(Clone, Copy)]
pub(super) struct LaneSums {
    lambda_even: [i64; 4],
    lambda_odd: [i64; 4],
    member: [i64; 4],
    visible: [i64; 4],
    weight: [i64; 4],
    towards_x: [i64; 4],
    towards_y: [i64; 4],
    edge: [f32; 8],
    visited: u64,
}

impl Default for LaneSums {
    fn default() -> Self {
        Self {
            lambda_even: [0; 4],
            lambda_odd: [0; 4],
            member: [0; 4],
            visible: [0; 4],
            weight: [0; 4],
            towards_x: [0; 4],
            towards_y: [0; 4],
            edge: [f32::INFINITY; 8],
            visited: 0,
        }
    }
}

impl LaneSums {
    /// Adds the lanes into the site's sums (exact integers; the nearest edge by `min`).
    pub(super) fn add_to(&self, sums: &mut Sums) {
        let total = |v: &[i64; 4]| v.iter().sum::<i64>();
        sums.lambda += total(&self.lambda_even) + total(&self.lambda_odd);
        sums.member_weight += total(&self.member);
        sums.visible += total(&self.visible);
        sums.weight += total(&self.weight);
        sums.visited += self.visited;
        sums.towards[0] += total(&self.towards_x);
        sums.towards[1] += total(&self.towards_y);
        sums.edge = self.edge.iter().fold(sums.edge, |e, &d| e.min(d));
    }
}

/// [`dense_run`] one column at a time.
fn dense_scalar(sums: &mut Sums, run: &DenseRun, s: f32, h0: f32, inv_h0: f32) {
    for k in 0..run.len {
        let f = run.flags[k];
        if f & DENSE == 0 {
            continue;
        }
        let mut dz = run.base[k] - s;
        let mut seen = f & SEEN != 0;
        if f & TWO != 0 {
            // `SiteField::member`: the nearer base (ties to the lower site); a roomy site
            // moves up from a lower site without room to an upper one with it.
            let dz_upper = run.upper[k] - s;
            let up = dz_upper.abs() < dz.abs()
                || (run.roomy && f & ROOMY_LOWER == 0 && f & ROOMY_UPPER != 0);
            if up {
                dz = dz_upper;
                seen = f & SEEN_UPPER != 0;
            }
        }
        let w = i64::from(run.weight[k]);
        sums.weight += w;
        sums.visited += 1;
        sums.lambda += w * i64::from(lambda_units(dz, inv_h0));
        if f & MEMBER != 0 {
            sums.member_weight += w;
        }
        if seen {
            sums.visible += w;
        }
        if dz < -h0 {
            boundary_term(sums, run.table, run.t0 + k);
        }
    }
}

/// [`dense_run`] with AVX2: groups of eight columns, the last one's extra lanes masked off.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn dense_lanes_avx2<const PLAIN: bool>(
    acc: &mut LaneSums,
    run: &DenseRun,
    s: f32,
    h0: f32,
    inv_h0: f32,
) {
    use std::arch::x86_64::*;
    let n = run.len;
    assert!(
        run.base.len() >= n + PAD
            && run.upper.len() >= n + PAD
            && run.flags.len() >= n + PAD
            && run.weight.len() >= n + PAD
    );
    let (vs, vdrop, vinv) = (
        _mm256_set1_ps(s),
        _mm256_set1_ps(-h0),
        _mm256_set1_ps(inv_h0),
    );
    let (vlo, vhi, vunit) = (
        _mm256_set1_ps(-1.0),
        _mm256_set1_ps(1.0),
        _mm256_set1_ps(LAMBDA_ONE),
    );
    let bit = |b: i32| _mm256_set1_epi32(b);
    let (dense_bit, member_bit, seen_bit) = (bit(DENSE), bit(MEMBER), bit(SEEN));
    let (two_bit, seen_upper_bit) = (bit(TWO), bit(SEEN_UPPER));
    let (roomy_lower_bit, roomy_upper_bit) = (bit(ROOMY_LOWER), bit(ROOMY_UPPER));
    let roomy = if run.roomy { bit(-1) } else { bit(0) };
    let magnitude = _mm256_castsi256_ps(bit(i32::MAX));
    let has = |f: __m256i, b: __m256i| _mm256_cmpeq_epi32(_mm256_and_si256(f, b), b);
    let lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    let low = _mm256_set1_epi64x(0xffff_ffff);
    let widen = |v: __m256i| _mm256_add_epi64(_mm256_and_si256(v, low), _mm256_srli_epi64::<32>(v));
    let table = run.table;
    assert!(
        table.towards_x.len() >= run.t0 + n + PAD
            && table.towards_y.len() >= run.t0 + n + PAD
            && table.distance.len() >= run.t0 + n + PAD
    );
    let (tx_ptr, ty_ptr, d_ptr) = (
        table.towards_x.as_ptr().wrapping_add(run.t0),
        table.towards_y.as_ptr().wrapping_add(run.t0),
        table.distance.as_ptr().wrapping_add(run.t0),
    );
    let infinity = _mm256_set1_ps(f32::INFINITY);
    let minus_infinity = _mm256_set1_ps(f32::NEG_INFINITY);
    let load = |v: &[i64; 4]| {
        // SAFETY: `v` holds four i64.
        unsafe { _mm256_loadu_si256(v.as_ptr().cast()) }
    };
    // SAFETY: `acc.edge` holds eight f32.
    let mut edge = unsafe { _mm256_loadu_ps(acc.edge.as_ptr()) };
    let (mut towards_x, mut towards_y) = (load(&acc.towards_x), load(&acc.towards_y));
    let (mut even, mut odd) = (load(&acc.lambda_even), load(&acc.lambda_odd));
    // The run's weights, of members and of visible members as 32-bit lane sums (a lane holds
    // part of one disk row, whose weights sum to less than 2^32: `KernelTable::weight32`),
    // widened once at the end; the fast-path columns counted the same way.
    let zero = _mm256_setzero_si256();
    let (mut weight, mut member, mut visible, mut counted) = (zero, zero, zero, zero);
    let (eight, mut remaining) = (_mm256_set1_epi32(8), _mm256_set1_epi32(n as i32));
    let mut k = 0;
    while k < n {
        // The lanes still in the run.
        let tail = _mm256_cmpgt_epi32(remaining, lane);
        remaining = _mm256_sub_epi32(remaining, eight);
        // SAFETY: k < n and every slice holds n + PAD >= k + 8 values.
        let (b, table_w) = unsafe {
            (
                _mm256_loadu_ps(run.base.as_ptr().add(k)),
                _mm256_loadu_si256(run.weight.as_ptr().add(k).cast()),
            )
        };
        let (live, dz, w);
        if PLAIN {
            // Every column is empty (base -∞) or one visible site: visible members are the
            // members, added at the end.
            live = tail;
            dz = _mm256_sub_ps(b, vs);
            w = _mm256_and_si256(table_w, live);
            let is_member = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_NEQ_UQ>(b, minus_infinity));
            member = _mm256_add_epi32(member, _mm256_and_si256(w, is_member));
        } else {
            // SAFETY: as above.
            let (b_upper, f) = unsafe {
                (
                    _mm256_loadu_ps(run.upper.as_ptr().add(k)),
                    _mm256_loadu_si256(run.flags.as_ptr().add(k).cast()),
                )
            };
            live = _mm256_and_si256(tail, has(f, dense_bit));
            let dz_lower = _mm256_sub_ps(b, vs);
            let dz_upper = _mm256_sub_ps(b_upper, vs);
            // The member of a two-site column, as in the scalar loop.
            let nearer = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(
                _mm256_and_ps(dz_upper, magnitude),
                _mm256_and_ps(dz_lower, magnitude),
            ));
            let moves = _mm256_and_si256(
                _mm256_and_si256(roomy, has(f, roomy_upper_bit)),
                _mm256_andnot_si256(has(f, roomy_lower_bit), bit(-1)),
            );
            let up = _mm256_and_si256(has(f, two_bit), _mm256_or_si256(nearer, moves));
            dz = _mm256_blendv_ps(dz_lower, dz_upper, _mm256_castsi256_ps(up));
            w = _mm256_and_si256(table_w, live);
            let seen = _mm256_blendv_epi8(has(f, seen_bit), has(f, seen_upper_bit), up);
            member = _mm256_add_epi32(member, _mm256_and_si256(w, has(f, member_bit)));
            visible = _mm256_add_epi32(visible, _mm256_and_si256(w, seen));
            counted = _mm256_sub_epi32(counted, live);
        }
        weight = _mm256_add_epi32(weight, w);
        // `max` returns its second operand for a NaN, as `f32::max(x, -1)` returns -1 (and
        // an empty column's -∞ gives -1).
        let x = _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(dz, vinv), vlo), vhi);
        let q = _mm256_cvttps_epi32(_mm256_mul_ps(x, vunit));
        // Signed 32 × 32 → 64-bit products of the even lanes, then of the odd ones.
        even = _mm256_add_epi64(even, _mm256_mul_epi32(w, q));
        odd = _mm256_add_epi64(
            odd,
            _mm256_mul_epi32(_mm256_srli_epi64::<32>(w), _mm256_srli_epi64::<32>(q)),
        );
        // Boundary members (drops by more than h0, empty columns): the nearest one's
        // distance and the weighted directions, with the 64-bit sums as two halves.
        let drops = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(dz, vdrop));
        if _mm256_testz_si256(drops, live) == 0 {
            let drops = _mm256_and_si256(drops, live);
            // SAFETY: t0 + k + 8 <= t0 + n + PAD, within the padded tables (asserted).
            let (d, x0, x1, y0, y1) = unsafe {
                (
                    _mm256_loadu_ps(d_ptr.add(k)),
                    _mm256_loadu_si256(tx_ptr.add(k).cast()),
                    _mm256_loadu_si256(tx_ptr.add(k + 4).cast()),
                    _mm256_loadu_si256(ty_ptr.add(k).cast()),
                    _mm256_loadu_si256(ty_ptr.add(k + 4).cast()),
                )
            };
            edge = _mm256_min_ps(
                edge,
                _mm256_blendv_ps(infinity, d, _mm256_castsi256_ps(drops)),
            );
            let m0 = _mm256_cvtepi32_epi64(_mm256_castsi256_si128(drops));
            let m1 = _mm256_cvtepi32_epi64(_mm256_extracti128_si256::<1>(drops));
            towards_x = _mm256_add_epi64(
                towards_x,
                _mm256_add_epi64(_mm256_and_si256(x0, m0), _mm256_and_si256(x1, m1)),
            );
            towards_y = _mm256_add_epi64(
                towards_y,
                _mm256_add_epi64(_mm256_and_si256(y0, m0), _mm256_and_si256(y1, m1)),
            );
        }
        k += 8;
    }
    if PLAIN {
        visible = member;
    }
    let add = |v: &mut [i64; 4], lanes: __m256i| {
        // SAFETY: `v` holds four i64.
        unsafe {
            let sum = _mm256_add_epi64(_mm256_loadu_si256(v.as_ptr().cast()), widen(lanes));
            _mm256_storeu_si256(v.as_mut_ptr().cast(), sum)
        }
    };
    add(&mut acc.weight, weight);
    add(&mut acc.member, member);
    add(&mut acc.visible, visible);
    let store = |v: __m256i, to: &mut [i64; 4]| {
        // SAFETY: `to` holds four i64.
        unsafe { _mm256_storeu_si256(to.as_mut_ptr().cast(), v) }
    };
    store(even, &mut acc.lambda_even);
    store(odd, &mut acc.lambda_odd);
    store(towards_x, &mut acc.towards_x);
    store(towards_y, &mut acc.towards_y);
    // SAFETY: `acc.edge` holds eight f32.
    unsafe { _mm256_storeu_ps(acc.edge.as_mut_ptr(), edge) };
    acc.visited += if PLAIN {
        n as u64
    } else {
        let mut c = [0u32; 8];
        // SAFETY: `c` holds eight u32.
        unsafe { _mm256_storeu_si256(c.as_mut_ptr().cast(), counted) };
        c.iter().map(|&v| u64::from(v)).sum()
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sums_of(f: impl FnOnce(&mut Sums)) -> (i64, i64, i64, i64, [i64; 2], u32, u64) {
        let mut s = Sums {
            edge: f32::INFINITY,
            ..Default::default()
        };
        f(&mut s);
        (
            s.weight,
            s.member_weight,
            s.lambda,
            s.visible,
            s.towards,
            s.edge.to_bits(),
            s.visited,
        )
    }

    /// The AVX2 lanes give the scalar loop's integers on runs of every length, with empty,
    /// covered, visible, two-site and several-site columns, drops and NaN.
    #[test]
    fn the_lanes_match_the_scalar_loop() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 on this CPU: the scalar loop is the only path");
            return;
        }
        let table = KernelTable::new(3.0, 0.1);
        let weight32 = table.weight32.clone().unwrap();
        let n = 200;
        let mut base = Vec::new();
        let mut upper = Vec::new();
        let mut flags = Vec::new();
        for k in 0..n + PAD {
            let r = scramble(k as u64);
            let (b, f) = match r % 9 {
                0 => (f32::NEG_INFINITY, DENSE),
                1 => (0.0, 0),
                2 => ((r % 1000) as f32 * 1e-3, DENSE | MEMBER),
                3 => (f32::NAN, DENSE | MEMBER | SEEN),
                4 | 5 => (
                    (r % 1000) as f32 * 1e-3 - 0.5,
                    DENSE
                        | MEMBER
                        | TWO
                        | ((r >> 20) as i32 & (SEEN | SEEN_UPPER | ROOMY_LOWER | ROOMY_UPPER)),
                ),
                _ => ((r % 2000) as f32 * 1e-3 - 1.0, DENSE | MEMBER | SEEN),
            };
            base.push(b);
            upper.push(b + ((r >> 40) % 800) as f32 * 1e-3);
            flags.push(f);
        }
        // A plain run: empty columns and one-site visible ones only.
        let plain_flags: Vec<i32> = base
            .iter()
            .map(|&b| {
                if b == f32::NEG_INFINITY {
                    DENSE
                } else {
                    DENSE | MEMBER | SEEN
                }
            })
            .collect();
        for (len, roomy) in [0, 1, 7, 8, 9, 16, 61, 200]
            .into_iter()
            .flat_map(|l| [(l, false), (l, true)])
        {
            for (t0, plain) in [0, 13, table.side * 5 + 2]
                .into_iter()
                .flat_map(|t| [(t, false), (t, true)])
            {
                let run = DenseRun {
                    base: &base,
                    upper: &upper,
                    flags: if plain { &plain_flags } else { &flags },
                    roomy,
                    plain,
                    weight: &weight32[t0..],
                    len,
                    table: &table,
                    t0,
                };
                let (s, h0) = (0.1f32, 0.3f32);
                let scalar = sums_of(|x| dense_scalar(x, &run, s, h0, 1.0 / h0));
                // SAFETY: AVX2 is present (checked above).
                let lanes = sums_of(|x| {
                    let mut acc = LaneSums::default();
                    // SAFETY: AVX2 is present (checked above).
                    unsafe {
                        if plain {
                            dense_lanes_avx2::<true>(&mut acc, &run, s, h0, 1.0 / h0)
                        } else {
                            dense_lanes_avx2::<false>(&mut acc, &run, s, h0, 1.0 / h0)
                        }
                    };
                    acc.add_to(x);
                });
                assert_eq!(
                    lanes, scalar,
                    "run of {len} from table column {t0}, roomy {roomy}, plain {plain}"
                );
            }
        }
    }

    /// A fixed scramble of `k` (SplitMix64's finaliser).
    fn scramble(k: u64) -> u64 {
        let mut z = k.wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
}
