//! One row of the downwind drift sweep ([`super::Half::sweep`]): the scour of each cell, the
//! load carried along the row, the share each cell keeps and the share handed to the next row.
//!
//! Along a row the load is a linear recurrence: the carry into the next cell downwind is
//! `c_{p+1} = (c_p + a_p) · g_p`, with `a_p` what reaches cell `p` apart from the carry (the
//! share sent from the row upwind plus the cell's own scour) and `g_p = (1 − |k_p|)(1 − σ_p)
//! f_x` the share of its load it passes on along the row (`σ_p` the share that sublimates,
//! `k_p` the share of the rest it keeps, `f_x` the east/west share of what leaves; 0 where the
//! next cell is nodata or off the grid). Computed
//! cell after cell, each carry waits on the operations of the one before, and a cell's
//! branches on its neighbours and its layer: the sweep took 1.15-1.19 s of a calm 1024² season
//! (193 wind steps, two threads). Here the row is cut into [`SEGMENTS`] segments, each
//! scanned from a carry of 0 while the product of its shares is kept (`c_p = L_p + P_p · S`,
//! `S` the carry into the segment), so the segments' chains run side by side; the carries into
//! the segments follow in [`SEGMENTS`] steps, and every cell's carry from its segment's. The
//! per-cell passes before and after the scan are straight loops over the row, without
//! branches, and vectorise: the sweep takes 0.6 s of that season (0.65 s with eight segments,
//! whose sixteen running values no longer fit the registers). The sums are regrouped,
//! not changed: the layers agree with the cell-by-cell recurrence to a few units in the last
//! place of f32 (tested against it), and each cell keeps what its load does not send on, so
//! what is scoured is deposited or leaves the grid to that round-off. The segments are fixed
//! by the row, not the threads.

use crate::phenomenon::flush_below;

/// Independent segments of a row's carry scan (chains the core runs side by side).
pub(super) const SEGMENTS: usize = 4;

/// Loads below this are 0, m: far below any snow that matters (the layers' own floor,
/// [`crate::phenomenon::NEGLIGIBLE_DEPTH_M`]).
pub(super) const NEGLIGIBLE_LOAD: f32 = crate::phenomenon::NEGLIGIBLE_DEPTH_M;

/// Shares (and products of shares) below this are 0: a load passed on at that share is
/// below [`NEGLIGIBLE_LOAD`] for any depth of snow. With both floors no operand of the sweep
/// and no product of a load and a share (at least `1e-35`) is a subnormal float (see
/// [`crate::phenomenon::NEGLIGIBLE_DEPTH_M`]; the Sx sweep of a calm 1024² season on a 2-core
/// Xeon VM: 1.65 -> 1.38 s of wind transport; carries and products were flushed at 1e-30
/// before, which left the products of two of them to underflow).
pub(super) const NEGLIGIBLE_SHARE: f32 = 1e-15;

/// The per-row buffers of one half of the sweep, in sweep order (the first cell downwind of
/// the row's start first), padded with cells that receive and pass on nothing.
#[derive(Debug, Default)]
pub(super) struct DriftRow {
    /// Cells of the half.
    cells: usize,
    /// What reaches each cell apart from the carry.
    pub(super) arriving: Vec<f32>,
    /// Share of each cell's load carried to the next cell downwind.
    pub(super) passed: Vec<f32>,
    /// Carry into each position from the start of its segment alone, and the product of
    /// `passed` from the start of its segment to it.
    from_segment: Vec<f32>,
    product: Vec<f32>,
    /// The carry into each position; at `cells`, the carry out of the row.
    pub(super) carry: Vec<f32>,
}

/// Per cell of a row: scour, depth kept, of it as unstable snow, border outflow and depth
/// sublimated, summed per row in a fixed order.
#[derive(Debug, Default)]
pub(super) struct RowTotals {
    pub(super) eroded: Vec<f32>,
    pub(super) kept: Vec<f32>,
    pub(super) kept_unstable: Vec<f32>,
    pub(super) border: Vec<f32>,
    pub(super) sublimated: Vec<f32>,
}

impl RowTotals {
    pub(super) fn new(cells: usize) -> Self {
        Self {
            eroded: vec![0.0; cells],
            kept: vec![0.0; cells],
            kept_unstable: vec![0.0; cells],
            border: vec![0.0; cells],
            sublimated: vec![0.0; cells],
        }
    }

    /// Adds the row's totals to `sums` (each in a fixed order).
    pub(super) fn add_to(&self, sums: &mut super::SxSums) {
        sums.eroded += crate::row_sum(&self.eroded);
        sums.deposited += crate::row_sum(&self.kept);
        sums.deposited_unstable += crate::row_sum(&self.kept_unstable);
        sums.border += crate::row_sum(&self.border);
        sums.sublimated += crate::row_sum(&self.sublimated);
    }
}

/// Where the shares of one cell's load that are not carried along the row go.
#[derive(Debug, Clone, Copy)]
pub(super) struct Exits {
    /// The cell is on the grid's last column downwind or its downwind neighbour along the row
    /// is nodata (its east/west share leaves the terrain).
    pub(super) off_along: bool,
    /// The cell in the next row holds data.
    pub(super) across: bool,
    /// The row is the last downwind or the cell in the next row is nodata (its north/south
    /// share leaves the terrain).
    pub(super) off_across: bool,
}

impl DriftRow {
    /// Buffers for a half of `cells` columns.
    pub(super) fn new(cells: usize) -> Self {
        // Room for one position past the last cell (the carry out of the row), in whole
        // segments.
        let padded = (cells + 1).div_ceil(SEGMENTS) * SEGMENTS;
        Self {
            cells,
            arriving: vec![0.0; padded],
            passed: vec![0.0; padded],
            from_segment: vec![0.0; padded],
            product: vec![0.0; padded],
            carry: vec![0.0; padded],
        }
    }

    /// The carry into every position, given the carry `into_row` (at least
    /// [`NEGLIGIBLE_LOAD`], or 0) into the first: the
    /// segments scanned from a carry of 0 (side by side), then the carries into the segments
    /// in order. Returns the carry out of the row.
    pub(super) fn carries(&mut self, into_row: f32) -> f32 {
        let m = self.arriving.len() / SEGMENTS;
        let (mut carry, mut product) = ([0.0f32; SEGMENTS], [1.0f32; SEGMENTS]);
        for t in 0..m {
            for j in 0..SEGMENTS {
                let p = j * m + t;
                self.from_segment[p] = carry[j];
                self.product[p] = product[j];
                let c = (carry[j] + self.arriving[p]) * self.passed[p];
                let q = product[j] * self.passed[p];
                carry[j] = flush_below(c, NEGLIGIBLE_LOAD);
                product[j] = flush_below(q, NEGLIGIBLE_SHARE);
            }
        }
        let mut into = into_row;
        for j in 0..SEGMENTS {
            let r = j * m..(j + 1) * m;
            for ((c, &l), &q) in self.carry[r.clone()]
                .iter_mut()
                .zip(&self.from_segment[r.clone()])
                .zip(&self.product[r])
            {
                *c = l + q * into;
            }
            into = flush_below(carry[j] + product[j] * into, NEGLIGIBLE_LOAD);
        }
        self.carry[self.cells]
    }
}

/// What a cell of load `load`, of which the share `sublimated` sublimates, keeping the share
/// `|keep|` of the rest and sending `carried_on` along the row, does with its load: `(sent to
/// the next row, kept, border outflow, sublimated)`. What leaves is split `f_x` along the row,
/// the rest across; a share aimed off the grid or at nodata is border outflow (`exits`); the
/// cell keeps the rest of what it does not send on.
#[inline(always)]
pub(super) fn share_out(
    load: f32,
    (keep, sublimated, fx): (f32, f32, f32),
    carried_on: f32,
    exits: Exits,
) -> [f32; 4] {
    let lost = load * sublimated;
    let load = load - lost;
    let out = load - load * keep.abs();
    let along = out * fx;
    let across = out - along;
    let sent_across = if exits.across { across } else { 0.0 };
    let border =
        if exits.off_along { along } else { 0.0 } + if exits.off_across { across } else { 0.0 };
    let kept = (load - carried_on - sent_across - border).max(0.0);
    [sent_across, kept, border, lost]
}
