//! Snow bridges (von Festenberg & Gumhold 2011, Section 5.1): a pre-processing step that
//! "fills gaps in the depth texture layers up to a choosable limit bmax".
//!
//! Every row and every column of the top-most layer (the highest site of each column, or
//! nothing) is scanned for gaps: runs of columns that are empty or lower than both ends by
//! more than `h0` ("step-like local minima in the z-coordinates"), between two supports. A gap
//! of `n` columns of spacing `dx` with `n·dx <= bmax` gets one bridge site per column, on top
//! of the column. Their bases follow a parabola through the supports ("interpolated parabolas
//! to make the bridges' base look more real"): the chord between the support heights, sagging
//! by `BRIDGE_SAG · h0 · (n·dx / bmax)` in the middle. Each bridge site carries its distance
//! coefficient `d = 1 - |2t - 1|` in [0, 1] (t: position along the gap, 0 and 1 at the
//! supports) with which [`crate::sites`] lowers its initial height.
//!
//! A column bridged both along its row and along its column keeps the higher base and the
//! smaller coefficient. The sag is at most `h0 / 2`, below the lower support; a gap column is
//! more than `h0` below it, so a bridge always lies above the surface it spans.

use rayon::prelude::*;
use snowscape_mesh::HeightSpanMap;

/// Sag of a bridge of length `bmax` in the middle, share of `h0` (our choice).
pub const BRIDGE_SAG: f32 = 0.5;

/// A site created on top of a gap column.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BridgeSite {
    /// Column index (row-major, row 0 north).
    pub column: u32,
    /// Height of the bridge's base, metres.
    pub z: f32,
    /// Distance coefficient to the supports: 0 at a support, 1 in the middle.
    pub support: f32,
}

/// The bridge sites of `map` for initial height `h0` and maximum bridge length `bmax`
/// (metres), sorted by column.
pub fn find_bridges(map: &HeightSpanMap, h0: f32, bmax: f64) -> Vec<BridgeSite> {
    let (w, h) = (map.width, map.height);
    let max_gap = (bmax / map.cell_size).floor() as usize;
    if max_gap == 0 || w * h == 0 {
        return Vec::new();
    }
    let per_column = (map.cell_size / bmax) as f32;
    let top: Vec<f32> = (0..w * h)
        .map(|c| {
            map.column(c % w, c / w)
                .last()
                .map_or(f32::NEG_INFINITY, |s| s.z)
        })
        .collect();
    let rows: Vec<Vec<(usize, f32, f32)>> = (0..h)
        .into_par_iter()
        .map(|r| scan_line(&top, r * w, 1, w, h0, max_gap, per_column))
        .collect();
    let cols: Vec<Vec<(usize, f32, f32)>> = (0..w)
        .into_par_iter()
        .map(|c| scan_line(&top, c, w, h, h0, max_gap, per_column))
        .collect();
    let mut best: Vec<Option<(f32, f32)>> = vec![None; w * h];
    for (c, z, d) in rows.into_iter().chain(cols).flatten() {
        best[c] = Some(match best[c] {
            Some((z0, d0)) => (z0.max(z), d0.min(d)),
            None => (z, d),
        });
    }
    best.into_iter()
        .enumerate()
        .filter_map(|(c, b)| {
            b.map(|(z, support)| BridgeSite {
                column: c as u32,
                z,
                support,
            })
        })
        .collect()
}

/// Bridges along one line of `n` columns starting at `start` with stride `step`: (column,
/// base height, distance coefficient). `per_column` is `dx / bmax`.
fn scan_line(
    top: &[f32],
    start: usize,
    step: usize,
    n: usize,
    h0: f32,
    max_gap: usize,
    per_column: f32,
) -> Vec<(usize, f32, f32)> {
    let at = |i: usize| top[start + i * step];
    let mut out = Vec::new();
    let mut a = 0;
    while a + 1 < n {
        let ta = at(a);
        // A support is a surface, and the next column must drop below it by more than h0.
        if ta == f32::NEG_INFINITY || at(a + 1) >= ta - h0 {
            a += 1;
            continue;
        }
        // The gap runs while the columns stay more than h0 below the near support.
        let mut b = a + 1;
        while b < n && at(b) < ta - h0 {
            b += 1;
        }
        let gap = b - a - 1;
        if b == n || gap > max_gap {
            a = b;
            continue;
        }
        // The far support: the gap must also be more than h0 below it.
        let tb = at(b);
        if (a + 1..b).any(|k| at(k) >= tb - h0) {
            a = b;
            continue;
        }
        let span = (b - a) as f32;
        let sag = BRIDGE_SAG * h0 * (gap as f32 * per_column).min(1.0);
        for k in a + 1..b {
            let t = (k - a) as f32 / span;
            let z = ta + t * (tb - ta) - 4.0 * t * (1.0 - t) * sag;
            let d = 1.0 - (2.0 * t - 1.0).abs();
            out.push((start + k * step, z, d));
        }
        a = b;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(v: &[f32]) -> Vec<f32> {
        v.iter()
            .map(|&x| if x.is_nan() { f32::NEG_INFINITY } else { x })
            .collect()
    }

    #[test]
    fn the_papers_example_gap_gets_three_bridge_sites() {
        // {1, 0, 0, 0, 1}: three bridge sites on top of the zeros, parabolic base.
        let top = line(&[1.0, 0.0, 0.0, 0.0, 1.0]);
        let b = scan_line(&top, 0, 1, 5, 0.2, 10, 0.1);
        assert_eq!(b.iter().map(|x| x.0).collect::<Vec<_>>(), vec![1, 2, 3]);
        assert!(b[1].1 < b[0].1 && (b[0].1 - b[2].1).abs() < 1e-6, "{b:?}");
        assert!(b.iter().all(|x| x.1 > 0.5 && x.1 <= 1.0));
        assert_eq!(b[1].2, 1.0);
        assert!((b[0].2 - 0.5).abs() < 1e-6);
        // Too long, a shallow dip, an open end: no bridge.
        assert!(scan_line(&top, 0, 1, 5, 0.2, 2, 0.5).is_empty());
        assert!(scan_line(&top, 0, 1, 5, 2.0, 10, 0.1).is_empty());
        let open = line(&[1.0, 0.0, 0.0, f32::NAN, f32::NAN]);
        assert!(scan_line(&open, 0, 1, 5, 0.2, 10, 0.1).is_empty());
        // An empty gap (nothing below) between two supports is bridged too.
        let hole = line(&[1.0, f32::NAN, f32::NAN, 1.2]);
        assert_eq!(scan_line(&hole, 0, 1, 4, 0.2, 10, 0.1).len(), 2);
    }
}
