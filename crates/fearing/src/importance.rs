//! Importance ordering (Fearing 2000, Section 3.2): which launch site shoots the next batch.
//!
//! The paper defers the actual weighting to the thesis; ours multiplies the factors it lists:
//!
//! - **Completeness**: a site that has not shot in this pass comes before every site that has
//!   (larger first), so a crude global estimate exists before any refinement.
//! - **Area**: `sqrt(A / mean A)`, clamped to [1/4, 4].
//! - **Neighbourhoods**: the largest difference of sky-hit share with a neighbour, plus the
//!   binomial standard error of the site's own share, plus a floor of 0.05 so every site keeps
//!   improving.
//! - **Effort**: `1 / sqrt(batches)`, so sites aim for equal confidence.
//! - **Steepness**: sites steeper than the AOR (their snow slides away anyway) count a quarter.
//! - **Camera**: `1 / (1 + 3 distance / scene diagonal)` when a camera is given.
//! - **User**: objects tagged "boring" count a tenth.
//!
//! Refinement and merging use the same neighbour disagreement (Section 3.1).

use crate::edge_groups::Topology;
use crate::launch_sites::{Cell, LaunchSites};
use rayon::prelude::*;

/// Per-object and global weights that do not change during a pass.
pub struct Weights {
    pub mean_area: f64,
    /// tan of the AOR: sites whose base slope exceeds it are "steep".
    pub tan_aor: f64,
    pub camera: Option<([f64; 3], f64)>,
    /// User weight of each object.
    pub object_weight: Vec<f64>,
}

/// Largest sky-share difference between site `i` and its neighbours.
pub fn disagreement(cells: &[Cell], topo: &Topology, i: usize) -> f64 {
    let p = cells[topo.leaves[i] as usize].sky_fraction();
    topo.neighbours[i]
        .iter()
        .map(|n| (cells[topo.leaves[n.site as usize] as usize].sky_fraction() - p).abs())
        .fold(0.0, f64::max)
}

/// Slope of a cell's base, as tan.
pub fn base_slope(c: &Cell) -> f64 {
    let nz = crate::launch_sites::normal_z(&c.corners).clamp(1e-6, 1.0);
    (1.0 - nz * nz).sqrt() / nz
}

/// Importance of every site for the current `pass`.
pub fn importance(sites: &LaunchSites, topo: &Topology, w: &Weights, pass: u32) -> Vec<f64> {
    (0..topo.leaves.len())
        .into_par_iter()
        .with_min_len(256)
        .map(|i| {
            let c = &sites.cells[topo.leaves[i] as usize];
            let area = (c.area_xy() / w.mean_area.max(1e-300))
                .sqrt()
                .clamp(0.25, 4.0);
            if c.pass != pass || c.batches == 0 {
                return 1e9 + area;
            }
            let p = c.sky_fraction();
            let se = (p * (1.0 - p) / c.shots.max(1.0)).sqrt();
            let mut v = area * (0.05 + disagreement(&sites.cells, topo, i) + se)
                / (c.batches as f64).sqrt();
            if base_slope(c) > w.tan_aor {
                v *= 0.25;
            }
            if let Some((cam, size)) = w.camera {
                let p = c.centroid();
                let d =
                    ((p[0] - cam[0]).powi(2) + (p[1] - cam[1]).powi(2) + (p[2] - cam[2]).powi(2))
                        .sqrt();
                v /= 1.0 + 3.0 * d / size;
            }
            v * w
                .object_weight
                .get(c.object as usize)
                .copied()
                .unwrap_or(1.0)
        })
        .collect()
}

/// Indices of the `k` most important sites, most important first (ties by index).
pub fn top(importance: &[f64], k: usize) -> Vec<u32> {
    let mut idx: Vec<u32> = (0..importance.len() as u32).collect();
    let cmp = |a: &u32, b: &u32| {
        importance[*b as usize]
            .total_cmp(&importance[*a as usize])
            .then(a.cmp(b))
    };
    if k < idx.len() {
        idx.select_nth_unstable_by(k, cmp);
        idx.truncate(k);
    }
    idx.sort_by(cmp);
    idx
}
