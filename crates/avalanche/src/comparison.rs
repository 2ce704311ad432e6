//! An AIMEC-like comparison of a run with a reference run along an avalanche path (after
//! AvaFrame's ana3AIMEC, Fischer 2013): every cell within a corridor of the path is placed at
//! its distance along the path `s` (its nearest point on the polyline); the runout point of a
//! run is the largest `s` its footprint reaches, and the two runs are compared by the runout
//! difference, the true/false positive and negative areas of their footprints, and the
//! profiles of the peak values along `s`.
//!
//! The path is the line the user gives (AvaFrame's `LINES/path_aimec.shp`) or, without one,
//! the thalweg of the run itself: the peak-thickness-weighted centres of its footprint in
//! bands of equal altitude, from the top down.

use crate::validation::{Overlap, distance_to_polyline, footprint_overlap};
use serde::Serialize;
use snowscape_terrain::{Grid, GridGeometry};

/// One bin of the profiles along the path.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ProfileBin {
    /// Distance along the path of the bin's start, m.
    pub s_m: f64,
    /// Largest peak thickness of the run in the bin, m.
    pub thickness_m: f64,
    /// Largest peak thickness of the reference in the bin, m.
    pub reference_thickness_m: f64,
    /// Largest peak speed of the run in the bin, m/s.
    pub speed_m_s: f64,
}

/// The comparison's figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PathComparison {
    /// Where the path came from: `"given"` or `"thalweg of the run"`.
    pub path_source: &'static str,
    /// Length of the path, m.
    pub path_length_m: f64,
    /// Half-width of the corridor around the path, m.
    pub corridor_m: f64,
    /// Runout point of the run along the path, m.
    pub runout_s_m: f64,
    /// Runout point of the reference along the path, m.
    pub reference_runout_s_m: f64,
    /// `runout_s_m − reference_runout_s_m`, m.
    pub runout_difference_m: f64,
    /// Footprint cells in both, m² (true positive).
    pub true_positive_m2: f64,
    /// Footprint of the run only, m² (false positive).
    pub false_positive_m2: f64,
    /// Footprint of the reference only, m² (false negative).
    pub false_negative_m2: f64,
    /// Jaccard index of the two footprints.
    pub jaccard: f64,
    /// The profiles, in bins of one cell size along the path.
    pub profile: Vec<ProfileBin>,
    /// The path's vertices, map coordinates.
    pub path: Vec<(f64, f64)>,
}

/// The thalweg of a run: peak-weighted centres of its footprint (`peak > threshold_m`) in
/// `bands` altitude bands of the bed, highest first, and a last vertex continuing the last
/// segment by the line's length. Empty when the footprint is.
pub fn thalweg(
    geometry: &GridGeometry,
    bed: &[f64],
    peak: &[f64],
    threshold_m: f64,
    bands: usize,
) -> Vec<(f64, f64)> {
    let cells: Vec<usize> = (0..peak.len()).filter(|&i| peak[i] > threshold_m).collect();
    let (lo, hi) = cells
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &i| {
            (l.min(bed[i]), h.max(bed[i]))
        });
    if cells.is_empty() || hi <= lo {
        return Vec::new();
    }
    let mut sums = vec![(0.0f64, 0.0f64, 0.0f64); bands];
    let w = geometry.width();
    for &i in &cells {
        let band = (((hi - bed[i]) / (hi - lo) * bands as f64) as usize).min(bands - 1);
        let (x, y) = geometry.cell_centre(i % w, i / w);
        let s = &mut sums[band];
        s.0 += peak[i] * x;
        s.1 += peak[i] * y;
        s.2 += peak[i];
    }
    let mut line: Vec<(f64, f64)> = sums
        .iter()
        .filter(|s| s.2 > 0.0)
        .map(|s| (s.0 / s.2, s.1 / s.2))
        .collect();
    // Continued straight past its last centre by its own length, so that a reference that
    // runs out further is not cut off at the end of the line.
    if let [.., a, b] = line[..] {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let seg = dx.hypot(dy);
        let total: f64 = line
            .windows(2)
            .map(|p| (p[1].0 - p[0].0).hypot(p[1].1 - p[0].1))
            .sum();
        if seg > 0.0 {
            line.push((b.0 + dx / seg * total, b.1 + dy / seg * total));
        }
    }
    line
}

/// Compares a run (its `peak_thickness` and `peak_speed` on `geometry`) with a reference
/// peak-thickness raster along `path`, counting the cells within `corridor_m` of it.
pub fn compare_along_path(
    geometry: &GridGeometry,
    peak_thickness: &[f64],
    peak_speed: &[f64],
    reference: &Grid,
    path: (&[(f64, f64)], &'static str),
    threshold_m: f64,
    corridor_m: f64,
) -> PathComparison {
    let (line, path_source) = path;
    let overlap: Overlap = footprint_overlap(geometry, peak_thickness, reference, threshold_m);
    let length: f64 = line
        .windows(2)
        .map(|s| (s[1].0 - s[0].0).hypot(s[1].1 - s[0].1))
        .sum();
    let bin = geometry.cell_size_x().min(geometry.cell_size_y()).max(1e-3);
    let bins = ((length / bin).ceil() as usize + 1).min(1 << 20);
    let mut profile: Vec<ProfileBin> = (0..bins)
        .map(|k| ProfileBin {
            s_m: k as f64 * bin,
            thickness_m: 0.0,
            reference_thickness_m: 0.0,
            speed_m_s: 0.0,
        })
        .collect();
    let (mut runout, mut reference_runout) = (0.0f64, 0.0f64);
    let place = |x: f64, y: f64| -> Option<(f64, usize)> {
        let (d, s) = distance_to_polyline(line, x, y);
        (d <= corridor_m && !line.is_empty())
            .then(|| (s, ((s / bin) as usize).min(bins.saturating_sub(1))))
    };
    let w = geometry.width();
    for (i, &peak) in peak_thickness.iter().enumerate() {
        if peak > threshold_m {
            let (x, y) = geometry.cell_centre(i % w, i / w);
            if let Some((s, k)) = place(x, y) {
                runout = runout.max(s);
                let b = &mut profile[k];
                b.thickness_m = b.thickness_m.max(peak);
                b.speed_m_s = b.speed_m_s.max(peak_speed.get(i).copied().unwrap_or(0.0));
            }
        }
    }
    let rg = reference.geometry();
    for i in 0..rg.len() {
        let v = reference.data()[i] as f64;
        if reference.mask().is_valid(i) && v > threshold_m {
            let (x, y) = rg.cell_centre(i % rg.width(), i / rg.width());
            if let Some((s, k)) = place(x, y) {
                reference_runout = reference_runout.max(s);
                let b = &mut profile[k];
                b.reference_thickness_m = b.reference_thickness_m.max(v);
            }
        }
    }
    PathComparison {
        path_source,
        path_length_m: length,
        corridor_m,
        runout_s_m: runout,
        reference_runout_s_m: reference_runout,
        runout_difference_m: runout - reference_runout,
        true_positive_m2: overlap.both_m2,
        false_positive_m2: overlap.ours_m2 - overlap.both_m2,
        false_negative_m2: overlap.reference_m2 - overlap.both_m2,
        jaccard: overlap.jaccard,
        profile,
        path: line.to_vec(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_terrain::NodataMask;

    #[test]
    fn a_run_one_cell_longer_than_the_reference_runs_out_one_cell_further() {
        // A 40 x 5 strip of 10 m cells; the path runs down its middle row.
        let g = GridGeometry::square(40, 5, 10.0).unwrap();
        let w = 40;
        let ours: Vec<f64> = (0..200)
            .map(|i| if i % w < 21 { 1.0 } else { 0.0 })
            .collect();
        let reference = Grid::new(
            g.clone(),
            (0..200)
                .map(|i| if i % w < 20 { 2.0 } else { 0.0 })
                .collect(),
            NodataMask::all_valid(),
        )
        .unwrap();
        let (x0, y) = g.cell_centre(0, 2);
        let (x1, _) = g.cell_centre(39, 2);
        let line = [(x0, y), (x1, y)];
        let c = compare_along_path(
            &g,
            &ours,
            &vec![5.0; 200],
            &reference,
            (&line, "given"),
            0.01,
            100.0,
        );
        assert!((c.runout_s_m - 200.0).abs() < 1e-9, "{}", c.runout_s_m);
        assert!((c.reference_runout_s_m - 190.0).abs() < 1e-9);
        assert!((c.runout_difference_m - 10.0).abs() < 1e-9);
        assert!((c.true_positive_m2 - 100.0 * 100.0).abs() < 1e-6);
        assert!((c.false_positive_m2 - 5.0 * 100.0).abs() < 1e-6);
        assert_eq!(c.false_negative_m2, 0.0);
        assert_eq!(c.profile[0].thickness_m, 1.0);
        assert_eq!(c.profile[0].reference_thickness_m, 2.0);
        assert_eq!(c.profile[0].speed_m_s, 5.0);
        // The thalweg of a strip sloping down to the east runs west to east.
        let bed: Vec<f64> = (0..200).map(|i| 100.0 - (i % w) as f64).collect();
        let t = thalweg(&g, &bed, &ours, 0.01, 5);
        assert_eq!(t.len(), 6);
        assert!(t.windows(2).all(|p| p[1].0 > p[0].0));
    }
}
