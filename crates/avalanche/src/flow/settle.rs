//! Film settling: thin films spread around a flow come to rest.
//!
//! The pipe model spreads mass cell by cell, so a flow leaves behind, and pushes ahead of it
//! on slopes steeper than θc, films a few millimetres thick that keep creeping (a Coulomb
//! sheet thinner than the friction can hold still accelerates at g·(sinθ − cosθ·tanθc)
//! whatever its thickness). They carry no visible snow but keep the active set, and the
//! run, alive. A cell whose flowing thickness and whose 8 neighbours' are all below a
//! threshold settles: its snow leaves the flow for the `settled` field (it is deposit; mass
//! is conserved: [`AvalancheState::total_volume`]). Its pipes keep their velocity, so snow
//! arriving behind the film keeps its momentum (stopping them slowed every front).
//!
//! The rule reads only thicknesses below the threshold and writes zeros, so the cells it
//! settles do not depend on the order of the visit. The threshold is chosen here (5 mm by
//! default in [`crate::RunOptions`], half the 1 cm footprint threshold of AvaFrame's
//! peak-flow-thickness maps, so a settled film never counts in a footprint).

use super::AvalancheState;

impl AvalancheState {
    /// Settles the films thinner than `threshold` m (cell and 8 neighbours), returns the
    /// volume settled, m³. Visits the active tiles only.
    pub fn settle_films(&mut self, threshold: f64) -> f64 {
        if threshold.is_nan() || threshold <= 0.0 || self.active.is_none() {
            return 0.0;
        }
        // Settled in place, in one visit: a cell that settles was below the threshold and
        // stays below it (0), so its neighbours' tests read the same answer either way.
        let mut volume = 0.0;
        // Grid cells only: the ghost ring never holds snow at rest.
        for t in 0..self.occupied_tiles() {
            let Some((r0, r1, c0, c1)) = self.content_cells_of(t) else {
                continue;
            };
            for r in r0..=r1 {
                for c in c0..=c1 {
                    let k = self.pad(c, r);
                    let hk = self.h[k];
                    if hk > 0.0 && hk < threshold && self.neighbours_below(k, threshold) {
                        volume += hk;
                        self.settled[k] += hk;
                        self.h[k] = 0.0;
                    }
                }
            }
        }
        volume * self.geometry.cell_area()
    }

    fn neighbours_below(&self, k: usize, threshold: f64) -> bool {
        let pw = self.pw;
        [
            k - pw - 1,
            k - pw,
            k - pw + 1,
            k - 1,
            k + 1,
            k + pw - 1,
            k + pw,
            k + pw + 1,
        ]
        .into_iter()
        .all(|n| self.h[n] < threshold)
    }

    /// The content boxes of the active tiles in grid cells, inclusive `(r0, r1, c0, c1)`:
    /// every cell with flowing snow or a moving pipe lies in one (or is next to one).
    pub(crate) fn content_cells(&self) -> impl Iterator<Item = (usize, usize, usize, usize)> + '_ {
        (0..self.occupied_tiles()).filter_map(|t| self.content_cells_of(t))
    }

    /// The number of active tiles.
    pub(crate) fn occupied_tiles(&self) -> usize {
        self.tiles.occupied().len()
    }

    /// The content box of the `t`-th active tile in grid cells, inclusive `(r0, r1, c0, c1)`
    /// (`None` where it holds ghost cells only): for a loop over the content that changes the
    /// state as it goes.
    pub(crate) fn content_cells_of(&self, t: usize) -> Option<(usize, usize, usize, usize)> {
        let (w, hgt) = (self.geometry.width(), self.geometry.height());
        self.tiles.content_box(t).and_then(|b| grid_box(b, w, hgt))
    }

    /// Thickness of the films settled so far (row-major), m.
    pub fn settled_thickness(&self) -> Vec<f64> {
        self.grid_values(&self.settled)
    }

    /// Snow of the avalanche per cell, flowing plus settled (row-major), m.
    pub fn snow_thickness(&self) -> Vec<f64> {
        let mut out = self.thickness();
        for (o, s) in out.iter_mut().zip(self.settled_thickness()) {
            *o += s;
        }
        out
    }

    /// Snow of the avalanche at a grid cell, flowing plus settled, m.
    pub fn snow_at(&self, col: usize, row: usize) -> f64 {
        let k = self.pad(col, row);
        self.h[k] + self.settled[k]
    }

    /// Volume of the avalanche on the grid, flowing plus settled, m³ (the settled films lie
    /// in the touched tiles; summed tile by tile).
    pub fn total_volume(&self) -> f64 {
        let settled: f64 = self
            .touched_cells()
            .map(|(r0, r1, c0, c1)| {
                (r0..=r1)
                    .map(|r| {
                        let k = self.pad(c0, r);
                        self.settled[k..=k + c1 - c0].iter().sum::<f64>()
                    })
                    .sum::<f64>()
            })
            .sum();
        self.flowing_volume() + settled * self.geometry.cell_area()
    }

    /// The grid cells of a padded array (row-major).
    fn grid_values(&self, a: &[f64]) -> Vec<f64> {
        let (w, hgt) = (self.geometry.width(), self.geometry.height());
        let mut out = Vec::with_capacity(w * hgt);
        for r in 0..hgt {
            let k = (r + 1) * self.pw + 1;
            out.extend_from_slice(&a[k..k + w]);
        }
        out
    }
}

/// A padded box `(r0, r1, c0, c1)` in grid cells of a `w x hgt` grid (`None`: in the ghost
/// ring only).
fn grid_box(
    (r0, r1, c0, c1): (usize, usize, usize, usize),
    w: usize,
    hgt: usize,
) -> Option<(usize, usize, usize, usize)> {
    let (r0, r1) = (r0.max(1) - 1, r1.min(hgt).checked_sub(1)?);
    let (c0, c1) = (c0.max(1) - 1, c1.min(w).checked_sub(1)?);
    (r0 <= r1 && c0 <= c1).then_some((r0, r1, c0, c1))
}
