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
//! Cost and determinism: the kernel is local and the sites stand in a regular grid of columns,
//! so each row of the disk is one run of the map's columns (`KernelTable::spans`, clipped to
//! the map): O(sites × kernel columns), never O(sites²) (the paper's O(n²) of Fig. 15 was an
//! implementation accident). The columns of at most two sites, whose member choice is a
//! couple of comparisons, are read from contiguous per-column arrays (bases and flags) and
//! summed eight at a time with AVX2 where the CPU has it, a scalar loop elsewhere; the columns
//! of three sites or more go member by member through [`SiteField::member`]
//! ([`evaluate_reference`] takes that path for every column). Weights and terms are summed as
//! 64-bit fixed-point integers (weights in units of 2^-32, `λ / h0` in units of 2^-24, exact
//! 32 × 32 → 64-bit products), so the sums are exact and do not depend on the order of the
//! members or on the path: results are bit-identical for every thread count and with or
//! without AVX2 (tested against [`evaluate_reference`] and lane against
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
    /// Horizontal distance of each table column, in column spacings; [`PAD`] more at the end
    /// (for the lanes).
    distance: Vec<f32>,
    /// Weight times the unit vector towards the column, east (x) and north (y), in 2^-24
    /// units; [`PAD`] more at the end.
    towards_x: Vec<i64>,
    towards_y: Vec<i64>,
    /// Quantised weights as i32 when every one fits and every row's weights sum to less
    /// than 2^32 (always but for a kernel of a few columns), for the dense path's 32 × 32 →
    /// 64-bit products and 32-bit sums over a run; 0 outside the cylinder, [`PAD`] zeros at
    /// the end.
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
        let fits = weight.iter().all(|&w| w < i64::from(i32::MAX))
            && weight
                .chunks(side)
                .all(|row| row.iter().map(|&w| w.max(0)).sum::<i64>() <= i64::from(u32::MAX));
        let weight32 = fits.then(|| {
            let mut w32: Vec<i32> = weight.iter().map(|&w| w.max(0) as i32).collect();
            w32.extend([0; PAD]);
            w32
        });
        let pad = |v: Vec<i64>| {
            let mut v = v;
            v.extend([0; PAD]);
            v
        };
        distance.extend([0.0; PAD]);
        Self {
            reach,
            side,
            towards_x: pad(towards.iter().map(|t| t[0]).collect()),
            towards_y: pad(towards.iter().map(|t| t[1]).collect()),
            weight,
            distance,
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

/// Evaluates the kernel of radius `radius_m` at every site of `field`.
pub fn evaluate(field: &SiteField, radius_m: f64) -> KernelField {
    evaluate_with(field, KernelTable::new(radius_m, field.cell_size), radius_m)
}

/// [`evaluate`] member by member through [`SiteField::member`], without the fast path for
/// the columns of one site or none: the direct reading of the paper the fast path is tested
/// against (the same bits, slower).
pub fn evaluate_reference(field: &SiteField, radius_m: f64) -> KernelField {
    let mut table = KernelTable::new(radius_m, field.cell_size);
    table.weight32 = None;
    evaluate_with(field, table, radius_m)
}

fn evaluate_with(field: &SiteField, table: KernelTable, radius_m: f64) -> KernelField {
    let dense = DenseColumns::new(field);
    let n = field.len();
    let per_site: Vec<(f32, f32, [f32; 2], f32, f32, u64)> = (0..n)
        .into_par_iter()
        .with_min_len(256)
        .map(|i| site_kernel(field, &dense, &table, radius_m, i))
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
    /// For each map row, for each column `x`, the first column at or after `x` that is
    /// neither empty nor one visible site (`width` if none), and one more than the last such
    /// column at or before `x` (0 if none): the stretches of a row around them are plain.
    next_complex: Vec<u32>,
    complex_upto: Vec<u32>,
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
        let (mut next_complex, mut complex_upto) = (vec![w as u32; h * w], vec![0u32; h * w]);
        let plain = |f: i32| f == DENSE || f == DENSE | MEMBER | SEEN;
        for row in 0..h {
            let (f, o) = (&flags[row * w..(row + 1) * w], row * w);
            let mut next = w as u32;
            for x in (0..w).rev() {
                if !plain(f[x]) {
                    next = x as u32;
                }
                next_complex[o + x] = next;
            }
            let mut upto = 0;
            for x in 0..w {
                if !plain(f[x]) {
                    upto = x as u32 + 1;
                }
                complex_upto[o + x] = upto;
            }
        }
        Self {
            base,
            upper,
            flags,
            next_multi,
            next_complex,
            complex_upto,
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
    let mut lanes = LaneSums::default();
    let mut sums = Sums {
        edge: f32::INFINITY,
        ..Default::default()
    };
    let centre = Centre {
        base: s,
        h0,
        inv_h0,
        roomy,
    };
    let general = |sums: &mut Sums, t: usize, column: usize| {
        member_term(field, table, sums, t, column, &centre);
    };
    for y in y0..=y1 {
        // The disk's run of columns in this row, within the map.
        let trow = (y - cy + reach) as usize;
        let (lo, hi) = table.spans[trow];
        let (sa, sb) = (x0.max(cx + i64::from(lo)), x1.min(cx + i64::from(hi)));
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
        // The row's columns of at most two sites take the fast path (the others' lanes
        // masked off), then the columns of three or more the general one. Plain stretches
        // (empty and one-visible-site columns only) at either end of the row, the stretch
        // between its first and last other columns in full.
        let o = y as usize * w as usize;
        let (first, after_last) = (
            dense.next_complex[o + sa as usize] as usize,
            dense.complex_upto[o + sb as usize] as usize,
        );
        let parts = if first > sb as usize {
            [(0, len, true), (len, len, false), (len, len, true)]
        } else {
            let (k0, k1) = (first - sa as usize, after_last - sa as usize);
            [(0, k0, true), (k0, k1, false), (k1, len, true)]
        };
        for (k0, k1, plain) in parts {
            if k1 > k0 {
                let run = DenseRun {
                    base: &dense.base[c0 + k0..],
                    upper: &dense.upper[c0 + k0..],
                    flags: &dense.flags[c0 + k0..],
                    roomy,
                    plain,
                    weight: &weight32[t0 + k0..],
                    len: k1 - k0,
                    table,
                    t0: t0 + k0,
                };
                dense_run(&mut sums, &mut lanes, &run, s, h0, inv_h0);
            }
        }
        let next = &dense.next_multi[y as usize * (w as usize + 1)..];
        let mut x = next[sa as usize] as usize;
        while x <= sb as usize {
            let k = x - sa as usize;
            general(&mut sums, t0 + k, c0 + k);
            x = next[x + 1] as usize;
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

/// A boundary member at table column `t`: the nearest edge and the direction towards it.
#[inline]
fn boundary_term(sums: &mut Sums, table: &KernelTable, t: usize) {
    sums.edge = sums.edge.min(table.distance[t]);
    sums.towards[0] += table.towards_x[t];
    sums.towards[1] += table.towards_y[t];
}

/// `λ / h0` of a height difference `dz`, clipped to [-1, 1] (Eq. 6) and truncated to units of
/// 2^-24 (one instruction, the same on every machine); a NaN counts as -1 (`max` drops it).
#[inline(always)]
#[allow(clippy::manual_clamp)] // `clamp` keeps a NaN, which the lanes' `max` drops.
fn lambda_units(dz: f32, inv_h0: f32) -> i32 {
    ((dz * inv_h0).max(-1.0).min(1.0) * LAMBDA_ONE) as i32
}

/// The site a kernel is centred on, as its member terms read it.
struct Centre {
    /// Base of the site's snow column `s`, m.
    base: f32,
    /// The kernel's depth scale `h0`, m, and its inverse.
    h0: f32,
    inv_h0: f32,
    /// Whether the site is roomy (`SiteField::roomy`).
    roomy: bool,
}

/// The general (scalar) term of the column at table column `t`, grid column `column`.
#[inline(always)]
fn member_term(
    field: &SiteField,
    table: &KernelTable,
    sums: &mut Sums,
    t: usize,
    column: usize,
    centre: &Centre,
) {
    let &Centre {
        base: s,
        h0,
        inv_h0,
        roomy,
    } = centre;
    let wq = table.weight[t];
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

mod lanes;
use lanes::{DenseRun, LaneSums, dense_run};
