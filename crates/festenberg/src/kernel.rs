//! The snow diffusion kernel (von Festenberg & Gumhold 2011, Section 5.2, Eqs. 3-7).
//!
//! For every site `p`, the kernel members `N_p` are one site per column within the cylinder
//! of radius `R` around `p` (chosen by [`SiteField::member`]). With
//! `Δz = (z(p') + h0(p')) - (z(p) + h0(p))`:
//! - Eq. 5, Gaussian weights `K(ρ) = exp(-ρ² / 2R²) / (√(2π) R)` of the horizontal distance
//!   `ρ`, "clamped and normalized at R": the weights of the columns inside the cylinder sum to
//!   one (columns outside the height-span map are left out and the rest renormalised, so the
//!   map's border is no snow edge);
//! - Eq. 6, clipped height differences `λ(Δz) = Δz` if `|Δz| < h0`, else `sgn(Δz)·h0`; an
//!   empty column (nothing below: a drop) counts as `λ = -h0`;
//! - Eq. 4, `Δh = Σ K(p, p') λ(Δz(p, p'))`, in `[-h0, h0]`;
//! - Eq. 7, the edge correction `g1(r) = r (2 - r)`: "boundaries in the snow cover are ...
//!   defined where Δz < -h0" (and at empty columns); `r` is the horizontal distance to the
//!   nearest such member less one column spacing (the boundary lies between the last site and
//!   the member beyond it, so the outermost site gets `r = 0` and no snow: "g1 guarantees
//!   exactly vanishing snow heights at edges"), over `R`, clamped to [0, 1];
//! - the visibility `v`: "summing up the visibility (either 0 or 1) of each p' ... weighted
//!   with the kernel K", normalised by the members' weights; a site is visible when nothing is
//!   above it;
//! - Eq. 3, the final height `h = g1(r) · v · (h0(p) + Δh)`, capped at the capacity `c(p)`
//!   so snow never pierces the geometry above. Sign: the paper prints `h0 - Δh`, but with its
//!   own `Δz` (neighbour minus site) that would pile snow up at drops and thin it in hollows,
//!   the reverse of diffusion (Eq. 2) and of its Fig. 3; `+` is the reading that matches both.
//!
//! The boundary direction (for the overhangs of Section 5.3) is the kernel-weighted mean of the
//! unit vectors from `p` towards its boundary members: "the smoothed direction of r".
//!
//! Cost and determinism: the kernel is local, so members are found through a spatial grid of
//! square buckets of columns (`bucket_columns` on a side) and only the buckets that meet the
//! cylinder's square are visited: O(sites × kernel columns), never O(sites²) (the paper's
//! O(n²) of Fig. 15 was an implementation accident). Each row of the disk is one run of
//! columns (`KernelTable::spans`). The columns of at most two sites, whose member choice is a
//! couple of comparisons, are read from contiguous per-column arrays (bases and flags) and
//! summed eight at a time with AVX2 where the CPU has it, a scalar loop elsewhere; the columns
//! of three sites or more go member by member through [`SiteField::member`]
//! ([`evaluate_reference`] takes that path for every column). Weights and terms are summed as
//! 64-bit fixed-point integers (weights in units of 2^-32, `λ / h0` in units of 2^-24, exact
//! 32 × 32 → 64-bit products), so the sums are exact and do not depend on the order of the
//! members or on the path: results are bit-identical for every bucket size, every thread
//! count and with or without AVX2 (tested against [`evaluate_reference`] and lane against
//! scalar).

use crate::sites::SiteField;
use rayon::prelude::*;

const WEIGHT_ONE: f64 = 4_294_967_296.0; // 2^32
const LAMBDA_ONE: f32 = 16_777_216.0; // 2^24

/// The cylinder of radius `R` as a square table of columns with quantised weights.
#[derive(Debug, Clone)]
pub struct KernelTable {
    /// Half side of the table, columns.
    pub reach: i32,
    /// Side of the table (2·reach + 1).
    side: usize,
    /// Quantised normalised weight of each table column; -1 outside the cylinder.
    weight: Vec<i64>,
    /// Horizontal distance of each table column, in column spacings.
    distance: Vec<f32>,
    /// Weight times the unit vector towards the column (x east, y north), in 2^-24 units.
    towards: Vec<[i64; 2]>,
    /// The same, east and north apart, and the distances, for the lanes; [`PAD`] more at the
    /// end.
    towards_x: Vec<i64>,
    towards_y: Vec<i64>,
    distance_padded: Vec<f32>,
    /// Quantised weights as i32 when every one fits (always but for a kernel of a few
    /// columns), for the dense path's 32 × 32 → 64-bit products; 0 outside the cylinder,
    /// [`PAD`] zeros at the end.
    weight32: Option<Vec<i32>>,
    /// For each table row, the offsets `dx` in `lo..=hi` of the columns inside the cylinder
    /// (a disk's row is one run of columns).
    spans: Vec<(i32, i32)>,
    /// Columns inside the cylinder.
    pub columns: usize,
}

impl KernelTable {
    /// The cylinder of radius `radius_m` over columns of `cell_m` metres (Eq. 5).
    pub fn new(radius_m: f64, cell_m: f64) -> Self {
        let reach = (radius_m / cell_m).floor() as i32;
        let side = (2 * reach + 1) as usize;
        let mut raw = vec![-1.0f64; side * side];
        let mut distance = vec![0.0f32; side * side];
        let mut total = 0.0;
        for dy in -reach..=reach {
            for dx in -reach..=reach {
                let rho = cell_m * ((dx * dx + dy * dy) as f64).sqrt();
                let t = ((dy + reach) as usize) * side + (dx + reach) as usize;
                distance[t] = ((dx * dx + dy * dy) as f64).sqrt() as f32;
                if rho <= radius_m * (1.0 + 1e-12) {
                    let k = (-rho * rho / (2.0 * radius_m * radius_m)).exp()
                        / ((2.0 * std::f64::consts::PI).sqrt() * radius_m);
                    raw[t] = k;
                    total += k;
                }
            }
        }
        let mut weight = vec![-1i64; side * side];
        let mut towards = vec![[0i64; 2]; side * side];
        let mut columns = 0;
        for dy in -reach..=reach {
            for dx in -reach..=reach {
                let t = ((dy + reach) as usize) * side + (dx + reach) as usize;
                if raw[t] < 0.0 {
                    continue;
                }
                let w = (raw[t] / total * WEIGHT_ONE).round() as i64;
                weight[t] = w;
                columns += 1;
                let l = ((dx * dx + dy * dy) as f64).sqrt();
                if l > 0.0 {
                    // Row index grows southwards: north is -dy.
                    let ux = (dx as f64 / l * LAMBDA_ONE as f64).round() as i64;
                    let uy = (-dy as f64 / l * LAMBDA_ONE as f64).round() as i64;
                    towards[t] = [w * ux, w * uy];
                }
            }
        }
        let spans = (0..side)
            .map(|row| {
                let cells = &weight[row * side..(row + 1) * side];
                let lo = cells.iter().position(|&w| w >= 0).unwrap_or(side);
                let hi = cells.iter().rposition(|&w| w >= 0).unwrap_or(0);
                (lo as i32 - reach, hi as i32 - reach)
            })
            .collect();
        let weight32 = weight.iter().all(|&w| w < i64::from(i32::MAX)).then(|| {
            let mut w32: Vec<i32> = weight.iter().map(|&w| w.max(0) as i32).collect();
            w32.extend([0; PAD]);
            w32
        });
        let pad = |v: Vec<i64>| {
            let mut v = v;
            v.extend([0; PAD]);
            v
        };
        let mut distance_padded = distance.clone();
        distance_padded.extend([0.0; PAD]);
        Self {
            reach,
            side,
            towards_x: pad(towards.iter().map(|t| t[0]).collect()),
            towards_y: pad(towards.iter().map(|t| t[1]).collect()),
            distance_padded,
            weight,
            distance,
            towards,
            weight32,
            spans,
            columns,
        }
    }
}

/// What the kernel gives each site.
#[derive(Debug, Clone, PartialEq)]
pub struct KernelField {
    /// Final snow height `h` (Eq. 3), metres.
    pub height: Vec<f32>,
    /// Normalised edge distance `r` in [0, 1] (1: no boundary within `R`).
    pub edge: Vec<f32>,
    /// Smoothed unit direction towards the nearest boundary (x east, y north); zero if none.
    pub towards_edge: Vec<[f32; 2]>,
    /// Visibility `v` in [0, 1].
    pub visibility: Vec<f32>,
    /// Height change `Δh` (Eq. 4), metres.
    pub change: Vec<f32>,
    /// Kernel columns visited in all (inside the map and the cylinder).
    pub members_visited: u64,
}

/// The edge correction of Eq. 7, a quarter circle: 0 at an edge, 1 from `R` on.
#[inline]
pub fn g1(r: f32) -> f32 {
    let r = r.clamp(0.0, 1.0);
    r * (2.0 - r)
}

/// The clipped height difference of Eq. 6.
#[inline]
pub fn clipped(dz: f32, h0: f32) -> f32 {
    if dz.abs() < h0 { dz } else { h0.copysign(dz) }
}

/// Evaluates the kernel of radius `radius_m` at every site of `field`, visiting the columns
/// bucket by bucket (`bucket_columns` >= 1 on a side; results do not depend on it).
pub fn evaluate(field: &SiteField, radius_m: f64, bucket_columns: usize) -> KernelField {
    evaluate_with(
        field,
        KernelTable::new(radius_m, field.cell_size),
        radius_m,
        bucket_columns,
    )
}

/// [`evaluate`] member by member through [`SiteField::member`], without the fast path for
/// the columns of one site or none: the direct reading of the paper the fast path is tested
/// against (the same bits, slower).
pub fn evaluate_reference(field: &SiteField, radius_m: f64) -> KernelField {
    let mut table = KernelTable::new(radius_m, field.cell_size);
    table.weight32 = None;
    evaluate_with(field, table, radius_m, 1)
}

fn evaluate_with(
    field: &SiteField,
    table: KernelTable,
    radius_m: f64,
    bucket_columns: usize,
) -> KernelField {
    let dense = DenseColumns::new(field);
    let n = field.len();
    let per_site: Vec<(f32, f32, [f32; 2], f32, f32, u64)> = (0..n)
        .into_par_iter()
        .with_min_len(256)
        .map(|i| site_kernel(field, &dense, &table, radius_m, bucket_columns.max(1), i))
        .collect();
    let mut out = KernelField {
        height: Vec::with_capacity(n),
        edge: Vec::with_capacity(n),
        towards_edge: Vec::with_capacity(n),
        visibility: Vec::with_capacity(n),
        change: Vec::with_capacity(n),
        members_visited: 0,
    };
    for (h, r, d, v, dh, m) in per_site {
        out.height.push(h);
        out.edge.push(r);
        out.towards_edge.push(d);
        out.visibility.push(v);
        out.change.push(dh);
        out.members_visited += m;
    }
    out
}

/// Lanes past the end of the fast path's arrays, so that a run's last group of eight can be
/// read whole (its extra lanes are masked off).
const PAD: usize = 8;

/// A column of the fast path (bit 0: at most two sites), with a member (bit 1: a site), whose
/// lower (or only) site is visible (bit 2); of two sites (bit 3), whose upper one is visible
/// (bit 4), and whose lower and upper sites have room for 2 h0 (bits 5 and 6).
const DENSE: i32 = 1;
const MEMBER: i32 = 2;
const SEEN: i32 = 4;
const TWO: i32 = 8;
const SEEN_UPPER: i32 = 16;
const ROOMY_LOWER: i32 = 32;
const ROOMY_UPPER: i32 = 64;

/// The columns as the fast path reads them, contiguous by column: the base surfaces and flags
/// of the columns of at most two sites, from which [`SiteField::member`]'s choice is a few
/// comparisons (the nearer base, then the upper site if the lower has no room for a roomy
/// site); the columns of three or more sites take the general path.
struct DenseColumns {
    /// Base surface `s(p')` of a column's lower (or only) site; `-∞` for an empty column (a
    /// drop: `λ = -h0` and a boundary); 0 for a column of three sites or more. [`PAD`] more
    /// at the end.
    base: Vec<f32>,
    /// Base surface of a two-site column's upper site (0 otherwise). [`PAD`] more at the end.
    upper: Vec<f32>,
    /// [`DENSE`], [`MEMBER`], [`SEEN`], [`TWO`], [`SEEN_UPPER`], [`ROOMY_LOWER`],
    /// [`ROOMY_UPPER`]; 0 for a column of three sites or more. [`PAD`] more at the end.
    flags: Vec<i32>,
    /// For each map row, for each column `x`, the first column at or after `x` with three
    /// sites or more (`width` if none): `width + 1` entries a row.
    next_multi: Vec<u32>,
}

impl DenseColumns {
    fn new(field: &SiteField) -> Self {
        let (w, h) = (field.width, field.height);
        let mut base = vec![0.0f32; w * h + PAD];
        let mut upper = vec![0.0f32; w * h + PAD];
        let mut flags = vec![0i32; w * h + PAD];
        let mut next_multi = vec![w as u32; h * (w + 1)];
        for row in 0..h {
            for col in (0..w).rev() {
                let c = row * w + col;
                let sites = field.column_sites(c);
                let at = row * (w + 1) + col;
                next_multi[at] = next_multi[at + 1];
                match sites.len() {
                    0 => {
                        base[c] = f32::NEG_INFINITY;
                        flags[c] = DENSE;
                    }
                    1 => {
                        base[c] = field.base(sites.start);
                        flags[c] = if field.visible(sites.start) {
                            DENSE | MEMBER | SEEN
                        } else {
                            DENSE | MEMBER
                        };
                    }
                    2 => {
                        let (lo, hi) = (sites.start, sites.start + 1);
                        base[c] = field.base(lo);
                        upper[c] = field.base(hi);
                        let bit = |on: bool, b: i32| if on { b } else { 0 };
                        flags[c] = DENSE
                            | MEMBER
                            | TWO
                            | bit(field.visible(lo), SEEN)
                            | bit(field.visible(hi), SEEN_UPPER)
                            | bit(field.roomy(lo), ROOMY_LOWER)
                            | bit(field.roomy(hi), ROOMY_UPPER);
                    }
                    _ => next_multi[at] = col as u32,
                }
            }
        }
        Self {
            base,
            upper,
            flags,
            next_multi,
        }
    }
}

/// Sums of one site's kernel.
#[derive(Default)]
struct Sums {
    /// Weights of the columns inside the map.
    weight: i64,
    /// Weights of the columns with a member.
    member_weight: i64,
    /// Σ K·λ/h0.
    lambda: i64,
    /// Σ K·visible.
    visible: i64,
    /// Σ K·(unit vector to a boundary member).
    towards: [i64; 2],
    /// Distance to the nearest boundary member, column spacings.
    edge: f32,
    visited: u64,
}

fn site_kernel(
    field: &SiteField,
    dense: &DenseColumns,
    table: &KernelTable,
    radius_m: f64,
    bucket: usize,
    i: usize,
) -> (f32, f32, [f32; 2], f32, f32, u64) {
    let (w, h) = (field.width as i64, field.height as i64);
    let c = field.column[i] as i64;
    let (cx, cy) = (c % w, c / w);
    let reach = table.reach as i64;
    let (x0, x1) = ((cx - reach).max(0), (cx + reach).min(w - 1));
    let (y0, y1) = ((cy - reach).max(0), (cy + reach).min(h - 1));
    let s = field.base(i);
    let h0 = field.depth;
    let inv_h0 = 1.0 / h0;
    let roomy = field.roomy(i);
    let b = bucket as i64;
    let mut lanes = LaneSums::default();
    let mut sums = Sums {
        edge: f32::INFINITY,
        ..Default::default()
    };
    let general = |sums: &mut Sums, t: usize, column: usize| {
        member_term(
            field,
            table,
            sums,
            t,
            table.weight[t],
            column,
            s,
            h0,
            inv_h0,
            roomy,
        );
    };
    for by in y0 / b..=y1 / b {
        let (ya, yb) = ((by * b).max(y0), (by * b + b - 1).min(y1));
        for bx in x0 / b..=x1 / b {
            let (xa, xb) = ((bx * b).max(x0), (bx * b + b - 1).min(x1));
            for y in ya..=yb {
                // The disk's run of columns in this row, within the bucket.
                let trow = (y - cy + reach) as usize;
                let (lo, hi) = table.spans[trow];
                let (sa, sb) = (xa.max(cx + i64::from(lo)), xb.min(cx + i64::from(hi)));
                if sa > sb {
                    continue;
                }
                let t0 = trow * table.side + (sa - cx + reach) as usize;
                let c0 = (y * w + sa) as usize;
                let len = (sb - sa + 1) as usize;
                let Some(weight32) = &table.weight32 else {
                    for k in 0..len {
                        general(&mut sums, t0 + k, c0 + k);
                    }
                    continue;
                };
                // The row's columns of at most two sites take the fast path (the others'
                // lanes masked off), then the columns of three or more the general one.
                let run = DenseRun {
                    base: &dense.base[c0..],
                    upper: &dense.upper[c0..],
                    flags: &dense.flags[c0..],
                    roomy,
                    weight: &weight32[t0..],
                    len,
                    table,
                    t0,
                };
                dense_run(&mut sums, &mut lanes, &run, s, h0, inv_h0);
                let next = &dense.next_multi[y as usize * (w as usize + 1)..];
                let mut x = next[sa as usize] as usize;
                while x <= sb as usize {
                    let k = x - sa as usize;
                    general(&mut sums, t0 + k, c0 + k);
                    x = next[x + 1] as usize;
                }
            }
        }
    }
    lanes.add_to(&mut sums);
    let dh = (sums.lambda as f64 / (sums.weight as f64 * LAMBDA_ONE as f64)) as f32 * h0;
    let v = if sums.member_weight > 0 {
        (sums.visible as f64 / sums.member_weight as f64) as f32
    } else {
        0.0
    };
    let r = if sums.edge.is_finite() {
        ((sums.edge as f64 - 1.0) * field.cell_size / radius_m).clamp(0.0, 1.0) as f32
    } else {
        1.0
    };
    let l = ((sums.towards[0] as f64).powi(2) + (sums.towards[1] as f64).powi(2)).sqrt();
    let dir = if l > 0.0 {
        [
            (sums.towards[0] as f64 / l) as f32,
            (sums.towards[1] as f64 / l) as f32,
        ]
    } else {
        [0.0; 2]
    };
    let height = (g1(r) * v * (field.h0[i] + dh)).clamp(0.0, field.capacity[i]);
    (height, r, dir, v, dh, sums.visited)
}

/// A run of `len` contiguous columns of a disk row: their bases and flags and the table's
/// weights for them (`t0` the table index of the first); each slice holds at least
/// `len + PAD` values.
struct DenseRun<'a> {
    base: &'a [f32],
    upper: &'a [f32],
    flags: &'a [i32],
    /// Whether the kernel's site has room for 2 h0.
    roomy: bool,
    weight: &'a [i32],
    len: usize,
    table: &'a KernelTable,
    t0: usize,
}

/// The terms of a [`DenseRun`]'s columns of at most two sites (the others are left to the
/// general path): the integers of [`member_term`], eight
/// columns at a time with AVX2 where the CPU has it (the same IEEE operations as the scalar
/// code, and exact integer sums, so the same bits either way).
fn dense_run(sums: &mut Sums, lanes: &mut LaneSums, run: &DenseRun, s: f32, h0: f32, inv_h0: f32) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 is present.
        unsafe { dense_lanes_avx2(lanes, run, s, h0, inv_h0) };
        return;
    }
    let _ = lanes;
    dense_scalar(sums, run, s, h0, inv_h0);
}

/// The lanes' sums over a site's runs, kept apart until the site is done (a reduction per row
/// would cost as much as the row).
#[derive(Clone, Copy)]
struct LaneSums {
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
    fn add_to(&self, sums: &mut Sums) {
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
unsafe fn dense_lanes_avx2(acc: &mut LaneSums, run: &DenseRun, s: f32, h0: f32, inv_h0: f32) {
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
            && table.distance_padded.len() >= run.t0 + n + PAD
    );
    let (tx_ptr, ty_ptr, d_ptr) = (
        table.towards_x.as_ptr().wrapping_add(run.t0),
        table.towards_y.as_ptr().wrapping_add(run.t0),
        table.distance_padded.as_ptr().wrapping_add(run.t0),
    );
    let infinity = _mm256_set1_ps(f32::INFINITY);
    let load = |v: &[i64; 4]| {
        // SAFETY: `v` holds four i64.
        unsafe { _mm256_loadu_si256(v.as_ptr().cast()) }
    };
    // SAFETY: `acc.edge` holds eight f32.
    let mut edge = unsafe { _mm256_loadu_ps(acc.edge.as_ptr()) };
    let (mut towards_x, mut towards_y) = (load(&acc.towards_x), load(&acc.towards_y));
    let (mut even, mut odd) = (load(&acc.lambda_even), load(&acc.lambda_odd));
    let (mut member, mut visible) = (load(&acc.member), load(&acc.visible));
    let mut weight = load(&acc.weight);
    let mut visited = 0u32;
    let mut k = 0;
    while k < n {
        // The lanes still in the run.
        let live = _mm256_cmpgt_epi32(_mm256_set1_epi32((n - k) as i32), lane);
        // SAFETY: k < n and every slice holds n + PAD >= k + 8 values.
        let (b, b_upper, w, f) = unsafe {
            (
                _mm256_loadu_ps(run.base.as_ptr().add(k)),
                _mm256_loadu_ps(run.upper.as_ptr().add(k)),
                _mm256_loadu_si256(run.weight.as_ptr().add(k).cast()),
                _mm256_loadu_si256(run.flags.as_ptr().add(k).cast()),
            )
        };
        let live = _mm256_and_si256(live, has(f, dense_bit));
        visited += _mm256_movemask_ps(_mm256_castsi256_ps(live)).count_ones();
        let w = _mm256_and_si256(w, live);
        weight = _mm256_add_epi64(weight, widen(w));
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
        let dz = _mm256_blendv_ps(dz_lower, dz_upper, _mm256_castsi256_ps(up));
        let seen = _mm256_blendv_epi8(has(f, seen_bit), has(f, seen_upper_bit), up);
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
        // Weights (>= 0) of members and of visible members, widened to 64 bits.
        member = _mm256_add_epi64(member, widen(_mm256_and_si256(w, has(f, member_bit))));
        visible = _mm256_add_epi64(visible, widen(_mm256_and_si256(w, seen)));
        // Boundary members (drops by more than h0, empty columns): the nearest one's
        // distance and the weighted directions, with the 64-bit sums as two halves.
        let drops = _mm256_and_si256(
            _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(dz, vdrop)),
            live,
        );
        if _mm256_testz_si256(drops, drops) == 0 {
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
    let store = |v: __m256i, to: &mut [i64; 4]| {
        // SAFETY: `to` holds four i64.
        unsafe { _mm256_storeu_si256(to.as_mut_ptr().cast(), v) }
    };
    store(even, &mut acc.lambda_even);
    store(odd, &mut acc.lambda_odd);
    store(member, &mut acc.member);
    store(visible, &mut acc.visible);
    store(weight, &mut acc.weight);
    store(towards_x, &mut acc.towards_x);
    store(towards_y, &mut acc.towards_y);
    // SAFETY: `acc.edge` holds eight f32.
    unsafe { _mm256_storeu_ps(acc.edge.as_mut_ptr(), edge) };
    acc.visited += u64::from(visited);
}

/// A boundary member at table column `t`: the nearest edge and the direction towards it.
#[inline]
fn boundary_term(sums: &mut Sums, table: &KernelTable, t: usize) {
    sums.edge = sums.edge.min(table.distance[t]);
    sums.towards[0] += table.towards[t][0];
    sums.towards[1] += table.towards[t][1];
}

/// `λ / h0` of a height difference `dz`, clipped to [-1, 1] (Eq. 6) and truncated to units of
/// 2^-24 (one instruction, the same on every machine); a NaN counts as -1 (`max` drops it).
#[inline(always)]
#[allow(clippy::manual_clamp)] // `clamp` keeps a NaN, which the lanes' `max` drops.
fn lambda_units(dz: f32, inv_h0: f32) -> i32 {
    ((dz * inv_h0).max(-1.0).min(1.0) * LAMBDA_ONE) as i32
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn member_term(
    field: &SiteField,
    table: &KernelTable,
    sums: &mut Sums,
    t: usize,
    wq: i64,
    column: usize,
    s: f32,
    h0: f32,
    inv_h0: f32,
    roomy: bool,
) {
    sums.visited += 1;
    sums.weight += wq;
    let boundary = match field.member(column, s, roomy) {
        None => {
            sums.lambda -= wq * LAMBDA_ONE as i64;
            true
        }
        Some((m, dz)) => {
            sums.lambda += wq * i64::from(lambda_units(dz, inv_h0));
            sums.member_weight += wq;
            if field.visible(m) {
                sums.visible += wq;
            }
            dz < -h0
        }
    };
    if boundary {
        boundary_term(sums, table, t);
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
        for (len, roomy) in [0, 1, 7, 8, 9, 16, 61, 200]
            .into_iter()
            .flat_map(|l| [(l, false), (l, true)])
        {
            for t0 in [0, 13, table.side * 5 + 2] {
                let run = DenseRun {
                    base: &base,
                    upper: &upper,
                    flags: &flags,
                    roomy,
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
                    unsafe { dense_lanes_avx2(&mut acc, &run, s, h0, 1.0 / h0) };
                    acc.add_to(x);
                });
                assert_eq!(
                    lanes, scalar,
                    "run of {len} from table column {t0}, roomy {roomy}"
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
