//! The kernel's fast path (see the parent module): runs of columns of at most two sites,
//! eight at a time with AVX2 where the CPU has it, one at a time elsewhere, giving the same
//! integers as the member-by-member `member_term`.

use super::{
    DENSE, KernelTable, LAMBDA_ONE, MEMBER, PAD, ROOMY_LOWER, ROOMY_UPPER, SEEN, SEEN_UPPER, Sums,
    TWO, boundary_term, lambda_units,
};
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

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
    let n = run.len;
    assert!(
        run.base.len() >= n + PAD
            && run.upper.len() >= n + PAD
            && run.flags.len() >= n + PAD
            && run.weight.len() >= n + PAD
    );
    let table = run.table;
    assert!(
        table.towards_x.len() >= run.t0 + n + PAD
            && table.towards_y.len() >= run.t0 + n + PAD
            && table.distance.len() >= run.t0 + n + PAD
    );
    let lanes = RunLanes::new(run, s, h0, inv_h0);
    let mut sums = LaneRegisters::load(acc);
    let (eight, mut remaining) = (_mm256_set1_epi32(8), _mm256_set1_epi32(n as i32));
    let mut k = 0;
    while k < n {
        // The lanes still in the run.
        let tail = _mm256_cmpgt_epi32(remaining, lanes.lane);
        remaining = _mm256_sub_epi32(remaining, eight);
        // SAFETY: k < n and every slice holds n + PAD >= k + 8 values.
        let (b, table_w) = unsafe {
            (
                _mm256_loadu_ps(run.base.as_ptr().add(k)),
                _mm256_loadu_si256(run.weight.as_ptr().add(k).cast()),
            )
        };
        let group = Group {
            k,
            tail,
            b,
            table_w,
        };
        let (live, dz, w) = if PLAIN {
            sums.plain_columns(&lanes, group)
        } else {
            // SAFETY: as above.
            unsafe { sums.flagged_columns(&lanes, run, group) }
        };
        sums.weight = _mm256_add_epi32(sums.weight, w);
        sums.add_lambda(&lanes, dz, w);
        // SAFETY: t0 + k + 8 <= t0 + n + PAD, within the padded tables (asserted).
        unsafe { sums.add_boundary(&lanes, k, dz, live) };
        k += 8;
    }
    sums.store::<PLAIN>(acc, n);
}

/// What the AVX2 lanes of a [`DenseRun`] share, in every lane: the base `s` of the site's
/// snow column, the boundary drop `-h0`, `1/h0`, the clamp of a λ to [-1, 1] and its integer
/// unit (`lambda_units`), the flag bits, whether the site is roomy (all ones or zero), the
/// lane indices; and the run's first column in the table's directions and distances.
#[cfg(target_arch = "x86_64")]
struct RunLanes {
    s: __m256,
    drop: __m256,
    inv_h0: __m256,
    lo: __m256,
    hi: __m256,
    unit: __m256,
    dense: __m256i,
    member: __m256i,
    seen: __m256i,
    two: __m256i,
    seen_upper: __m256i,
    roomy_lower: __m256i,
    roomy_upper: __m256i,
    roomy: __m256i,
    /// All bits but the sign (`abs` as an `and`).
    magnitude: __m256,
    lane: __m256i,
    infinity: __m256,
    minus_infinity: __m256,
    towards_x: *const i64,
    towards_y: *const i64,
    distance: *const f32,
}

#[cfg(target_arch = "x86_64")]
impl RunLanes {
    #[target_feature(enable = "avx2")]
    #[inline]
    fn new(run: &DenseRun, s: f32, h0: f32, inv_h0: f32) -> Self {
        let table = run.table;
        Self {
            s: _mm256_set1_ps(s),
            drop: _mm256_set1_ps(-h0),
            inv_h0: _mm256_set1_ps(inv_h0),
            lo: _mm256_set1_ps(-1.0),
            hi: _mm256_set1_ps(1.0),
            unit: _mm256_set1_ps(LAMBDA_ONE),
            dense: bit(DENSE),
            member: bit(MEMBER),
            seen: bit(SEEN),
            two: bit(TWO),
            seen_upper: bit(SEEN_UPPER),
            roomy_lower: bit(ROOMY_LOWER),
            roomy_upper: bit(ROOMY_UPPER),
            roomy: if run.roomy { bit(-1) } else { bit(0) },
            magnitude: _mm256_castsi256_ps(bit(i32::MAX)),
            lane: _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
            infinity: _mm256_set1_ps(f32::INFINITY),
            minus_infinity: _mm256_set1_ps(f32::NEG_INFINITY),
            towards_x: table.towards_x.as_ptr().wrapping_add(run.t0),
            towards_y: table.towards_y.as_ptr().wrapping_add(run.t0),
            distance: table.distance.as_ptr().wrapping_add(run.t0),
        }
    }
}

/// `b` in every lane.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn bit(b: i32) -> __m256i {
    _mm256_set1_epi32(b)
}

/// The lanes of flags `f` that have all the bits of `b`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn has(f: __m256i, b: __m256i) -> __m256i {
    _mm256_cmpeq_epi32(_mm256_and_si256(f, b), b)
}

/// Eight 32-bit lane sums as four 64-bit ones (each the sum of two neighbours).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn widen(v: __m256i) -> __m256i {
    let low = _mm256_set1_epi64x(0xffff_ffff);
    _mm256_add_epi64(_mm256_and_si256(v, low), _mm256_srli_epi64::<32>(v))
}

/// Eight columns of a run from column `k`: the lanes still in the run (`tail`), their bases
/// and the table's weights.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct Group {
    k: usize,
    tail: __m256i,
    b: __m256,
    table_w: __m256i,
}

/// The [`LaneSums`] of a site while a run goes through the lanes. The run's weights, of
/// members and of visible members are 32-bit lane sums (a lane holds part of one disk row,
/// whose weights sum to less than 2^32: `KernelTable::weight32`), widened once at the end;
/// the fast-path columns counted the same way.
#[cfg(target_arch = "x86_64")]
struct LaneRegisters {
    edge: __m256,
    towards_x: __m256i,
    towards_y: __m256i,
    even: __m256i,
    odd: __m256i,
    weight: __m256i,
    member: __m256i,
    visible: __m256i,
    counted: __m256i,
}

#[cfg(target_arch = "x86_64")]
impl LaneRegisters {
    /// The site's sums so far (the run's own from zero).
    #[target_feature(enable = "avx2")]
    #[inline]
    fn load(acc: &LaneSums) -> Self {
        let load = |v: &[i64; 4]| {
            // SAFETY: `v` holds four i64.
            unsafe { _mm256_loadu_si256(v.as_ptr().cast()) }
        };
        let zero = _mm256_setzero_si256();
        Self {
            // SAFETY: `acc.edge` holds eight f32.
            edge: unsafe { _mm256_loadu_ps(acc.edge.as_ptr()) },
            towards_x: load(&acc.towards_x),
            towards_y: load(&acc.towards_y),
            even: load(&acc.lambda_even),
            odd: load(&acc.lambda_odd),
            weight: zero,
            member: zero,
            visible: zero,
            counted: zero,
        }
    }

    /// The member of each column of a plain run (empty, base -∞, or one visible site: the
    /// visible members are the members, added at the end): the live lanes, the member's drop
    /// `dz` and weight `w`.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn plain_columns(&mut self, lanes: &RunLanes, g: Group) -> (__m256i, __m256, __m256i) {
        let live = g.tail;
        let dz = _mm256_sub_ps(g.b, lanes.s);
        let w = _mm256_and_si256(g.table_w, live);
        let is_member =
            _mm256_castps_si256(_mm256_cmp_ps::<_CMP_NEQ_UQ>(g.b, lanes.minus_infinity));
        self.member = _mm256_add_epi32(self.member, _mm256_and_si256(w, is_member));
        (live, dz, w)
    }

    /// The member of each column of a run with flags (the dense columns live; of a two-site
    /// column, as in the scalar loop, the nearer base, ties to the lower site, or the upper
    /// one where a roomy site moves up): the live lanes, the member's drop `dz` and weight `w`.
    ///
    /// # Safety
    /// `run.upper` and `run.flags` hold at least `g.k + 8` values.
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn flagged_columns(
        &mut self,
        lanes: &RunLanes,
        run: &DenseRun,
        g: Group,
    ) -> (__m256i, __m256, __m256i) {
        // SAFETY: the caller guarantees the values are there (see `# Safety`).
        let (b_upper, f) = unsafe {
            (
                _mm256_loadu_ps(run.upper.as_ptr().add(g.k)),
                _mm256_loadu_si256(run.flags.as_ptr().add(g.k).cast()),
            )
        };
        let live = _mm256_and_si256(g.tail, has(f, lanes.dense));
        let dz_lower = _mm256_sub_ps(g.b, lanes.s);
        let dz_upper = _mm256_sub_ps(b_upper, lanes.s);
        let nearer = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(
            _mm256_and_ps(dz_upper, lanes.magnitude),
            _mm256_and_ps(dz_lower, lanes.magnitude),
        ));
        let moves = _mm256_and_si256(
            _mm256_and_si256(lanes.roomy, has(f, lanes.roomy_upper)),
            _mm256_andnot_si256(has(f, lanes.roomy_lower), bit(-1)),
        );
        let up = _mm256_and_si256(has(f, lanes.two), _mm256_or_si256(nearer, moves));
        let dz = _mm256_blendv_ps(dz_lower, dz_upper, _mm256_castsi256_ps(up));
        let w = _mm256_and_si256(g.table_w, live);
        let seen = _mm256_blendv_epi8(has(f, lanes.seen), has(f, lanes.seen_upper), up);
        self.member = _mm256_add_epi32(self.member, _mm256_and_si256(w, has(f, lanes.member)));
        self.visible = _mm256_add_epi32(self.visible, _mm256_and_si256(w, seen));
        self.counted = _mm256_sub_epi32(self.counted, live);
        (live, dz, w)
    }

    /// The weighted λ of the members (drops `dz`, weights `w`) into the 64-bit sums.
    #[target_feature(enable = "avx2")]
    #[inline]
    fn add_lambda(&mut self, lanes: &RunLanes, dz: __m256, w: __m256i) {
        // `max` returns its second operand for a NaN, as `f32::max(x, -1)` returns -1 (and
        // an empty column's -∞ gives -1).
        let x = _mm256_min_ps(
            _mm256_max_ps(_mm256_mul_ps(dz, lanes.inv_h0), lanes.lo),
            lanes.hi,
        );
        let q = _mm256_cvttps_epi32(_mm256_mul_ps(x, lanes.unit));
        // Signed 32 × 32 → 64-bit products of the even lanes, then of the odd ones.
        self.even = _mm256_add_epi64(self.even, _mm256_mul_epi32(w, q));
        self.odd = _mm256_add_epi64(
            self.odd,
            _mm256_mul_epi32(_mm256_srli_epi64::<32>(w), _mm256_srli_epi64::<32>(q)),
        );
    }

    /// Boundary members among the live lanes of the eight columns from `k` (drops `dz` by
    /// more than h0, empty columns): the nearest one's distance and the weighted directions,
    /// with the 64-bit sums as two halves.
    ///
    /// # Safety
    /// The table's directions and distances hold the run's columns `k..k + 8`.
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn add_boundary(&mut self, lanes: &RunLanes, k: usize, dz: __m256, live: __m256i) {
        let drops = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(dz, lanes.drop));
        if _mm256_testz_si256(drops, live) == 0 {
            let drops = _mm256_and_si256(drops, live);
            // SAFETY: the caller guarantees the columns are there (see `# Safety`).
            let (d, x0, x1, y0, y1) = unsafe {
                (
                    _mm256_loadu_ps(lanes.distance.add(k)),
                    _mm256_loadu_si256(lanes.towards_x.add(k).cast()),
                    _mm256_loadu_si256(lanes.towards_x.add(k + 4).cast()),
                    _mm256_loadu_si256(lanes.towards_y.add(k).cast()),
                    _mm256_loadu_si256(lanes.towards_y.add(k + 4).cast()),
                )
            };
            self.edge = _mm256_min_ps(
                self.edge,
                _mm256_blendv_ps(lanes.infinity, d, _mm256_castsi256_ps(drops)),
            );
            let m0 = _mm256_cvtepi32_epi64(_mm256_castsi256_si128(drops));
            let m1 = _mm256_cvtepi32_epi64(_mm256_extracti128_si256::<1>(drops));
            self.towards_x = _mm256_add_epi64(
                self.towards_x,
                _mm256_add_epi64(_mm256_and_si256(x0, m0), _mm256_and_si256(x1, m1)),
            );
            self.towards_y = _mm256_add_epi64(
                self.towards_y,
                _mm256_add_epi64(_mm256_and_si256(y0, m0), _mm256_and_si256(y1, m1)),
            );
        }
    }

    /// The site's sums after a run of `n` columns back into `acc` (the 32-bit sums widened
    /// and added).
    #[target_feature(enable = "avx2")]
    #[inline]
    fn store<const PLAIN: bool>(mut self, acc: &mut LaneSums, n: usize) {
        if PLAIN {
            self.visible = self.member;
        }
        let add = |v: &mut [i64; 4], lanes: __m256i| {
            // SAFETY: `v` holds four i64.
            unsafe {
                let sum = _mm256_add_epi64(_mm256_loadu_si256(v.as_ptr().cast()), widen(lanes));
                _mm256_storeu_si256(v.as_mut_ptr().cast(), sum)
            }
        };
        add(&mut acc.weight, self.weight);
        add(&mut acc.member, self.member);
        add(&mut acc.visible, self.visible);
        let store = |v: __m256i, to: &mut [i64; 4]| {
            // SAFETY: `to` holds four i64.
            unsafe { _mm256_storeu_si256(to.as_mut_ptr().cast(), v) }
        };
        store(self.even, &mut acc.lambda_even);
        store(self.odd, &mut acc.lambda_odd);
        store(self.towards_x, &mut acc.towards_x);
        store(self.towards_y, &mut acc.towards_y);
        // SAFETY: `acc.edge` holds eight f32.
        unsafe { _mm256_storeu_ps(acc.edge.as_mut_ptr(), self.edge) };
        acc.visited += if PLAIN {
            n as u64
        } else {
            let mut c = [0u32; 8];
            // SAFETY: `c` holds eight u32.
            unsafe { _mm256_storeu_si256(c.as_mut_ptr().cast(), self.counted) };
            c.iter().map(|&v| u64::from(v)).sum()
        };
    }
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
