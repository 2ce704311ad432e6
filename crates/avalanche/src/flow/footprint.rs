//! The tiles an avalanche touched, and a bed read from the terrain only where the flow goes.
//!
//! A season runs hundreds of avalanches on one grid, each over a few per cent of it. Every
//! per-avalanche cost that scanned, allocated or zeroed the whole grid (building the padded
//! bed, finding the release top, the mass centre, the summary, the deposit, resetting the
//! state) is replaced by work over the *touched tiles*: the 16×16 tiles of the active set
//! ([`super::tiles`]) and their 8 neighbours, marked before every sub-step. A sub-step reads
//! cells within 4 of the content of the occupied tiles (its passes visit the content grown by
//! 3 and read one cell farther), and that lies in the 3×3 tiles around them, so the touched
//! tiles hold every cell a run ever read or wrote.
//!
//! **Lazy bed.** A state built by [`AvalancheState::on_terrain_lazily`] holds no bed: a tile's
//! bed is read from a [`BedSource`] (the terrain: bedrock + compacted + stable snow, the same
//! sums as [`AvalancheState::from_terrain`]) when the tile is first touched after
//! [`AvalancheState::reset_touched`], which also returns the touched tiles to rest (no snow,
//! no motion) for the next avalanche. The result is bit-identical to building a fresh state
//! from the terrain before each avalanche.

use super::{AvalancheError, AvalancheState, tiles::TILE};
use snowscape_terrain::{LayeredTerrain, SnowLayer};

/// Where a lazily built state reads the avalanche bed (m) of a grid cell (row-major index).
pub trait BedSource {
    /// Bed altitude of valid grid cell `i`, m.
    fn bed(&self, i: usize) -> f64;
}

impl BedSource for LayeredTerrain {
    #[inline]
    fn bed(&self, i: usize) -> f64 {
        self.bedrock[i] as f64
            + self.layer(SnowLayer::Compacted)[i] as f64
            + self.layer(SnowLayer::Stable)[i] as f64
    }
}

/// Which tiles the current run touched and, in a lazy state, which tiles' bed is fresh (an
/// epoch per tile, so clearing either is free).
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct Footprint {
    epoch: u32,
    touched_epoch: Vec<u32>,
    bed_epoch: Vec<u32>,
    /// Tiles touched in this epoch, in the order they were touched.
    pub(crate) touched: Vec<u32>,
    /// The bed of a tile not read in this epoch is stale (read from a [`BedSource`]).
    pub(crate) lazy: bool,
}

impl Footprint {
    pub(crate) fn new(tiles: usize, lazy: bool) -> Self {
        Self {
            epoch: 1,
            touched_epoch: vec![0; tiles],
            bed_epoch: if lazy { vec![0; tiles] } else { Vec::new() },
            touched: Vec::new(),
            lazy,
        }
    }
}

impl AvalancheState {
    /// A state on the avalanche bed of `terrain` that reads the bed only where the flow goes
    /// (see the module documentation); step it with a [`BedSource`].
    pub(crate) fn on_terrain_lazily(terrain: &LayeredTerrain) -> Result<Self, AvalancheError> {
        let g = terrain.geometry();
        let mut s = Self::new(g, terrain.mask(), &vec![0.0; g.len()])?;
        s.footprint = Footprint::new(s.footprint.touched_epoch.len(), true);
        Ok(s)
    }

    /// The padded cells of the `o`-th touched tile, an inclusive box `(r0, r1, c0, c1)`.
    fn touched_box(&self, o: usize) -> (usize, usize, usize, usize) {
        let t = self.footprint.touched[o] as usize;
        let ntx = self.tiles.ntx();
        let (r0, c0) = ((t / ntx) * TILE, (t % ntx) * TILE);
        (
            r0,
            (r0 + TILE).min(self.ph) - 1,
            c0,
            (c0 + TILE).min(self.pw) - 1,
        )
    }

    /// The touched tiles' cells as inclusive padded boxes `(r0, r1, c0, c1)`.
    pub(crate) fn touched_boxes(&self) -> impl Iterator<Item = (usize, usize, usize, usize)> + '_ {
        (0..self.footprint.touched.len()).map(|o| self.touched_box(o))
    }

    /// The grid cells of the touched tiles as inclusive boxes `(r0, r1, c0, c1)` of grid rows
    /// and columns.
    pub(crate) fn touched_cells(&self) -> impl Iterator<Item = (usize, usize, usize, usize)> + '_ {
        let (w, hgt) = (self.geometry.width(), self.geometry.height());
        self.touched_boxes().filter_map(move |(r0, r1, c0, c1)| {
            let (r0, r1) = (r0.max(1) - 1, r1.min(hgt).checked_sub(1)?);
            let (c0, c1) = (c0.max(1) - 1, c1.min(w).checked_sub(1)?);
            (r0 <= r1 && c0 <= c1).then_some((r0, r1, c0, c1))
        })
    }

    /// Marks tile `t` touched.
    pub(crate) fn touch_tile(&mut self, t: usize) {
        let f = &mut self.footprint;
        if f.touched_epoch[t] != f.epoch {
            f.touched_epoch[t] = f.epoch;
            f.touched.push(t as u32);
        }
    }

    /// In a lazy state, reads the bed of tile `t` from `source` unless it is fresh.
    fn fresh_bed(
        &mut self,
        t: usize,
        source: Option<&dyn BedSource>,
    ) -> Result<(), AvalancheError> {
        if !self.footprint.lazy || self.footprint.bed_epoch[t] == self.footprint.epoch {
            return Ok(());
        }
        let source = source.ok_or(AvalancheError::BedSourceMissing)?;
        let ntx = self.tiles.ntx();
        let (r0, c0) = ((t / ntx) * TILE, (t % ntx) * TILE);
        for r in r0..(r0 + TILE).min(self.ph) {
            for c in c0..(c0 + TILE).min(self.pw) {
                let k = r * self.pw + c;
                // As `AvalancheState::new`: the ghost ring and nodata cells take the bed of a
                // valid cell (`AvalancheState::bed_source`).
                self.bed[k] = match self.bed_source(k) {
                    None => 0.0,
                    Some(i) => {
                        let b = source.bed(i);
                        if !b.is_finite() {
                            return Err(AvalancheError::BadValue {
                                what: "bed",
                                index: i,
                                value: b,
                            });
                        }
                        b
                    }
                };
            }
        }
        self.footprint.bed_epoch[t] = self.footprint.epoch;
        Ok(())
    }

    /// Marks the tiles around tile `(tr, tc)` (itself and its 8 neighbours) touched, with a
    /// fresh bed.
    fn touch_around_tile(
        &mut self,
        tr: usize,
        tc: usize,
        source: Option<&dyn BedSource>,
    ) -> Result<(), AvalancheError> {
        let ntx = self.tiles.ntx();
        let nty = self.ph.div_ceil(TILE);
        for r in tr.saturating_sub(1)..=(tr + 1).min(nty - 1) {
            for c in tc.saturating_sub(1)..=(tc + 1).min(ntx - 1) {
                self.touch_tile(r * ntx + c);
                self.fresh_bed(r * ntx + c, source)?;
            }
        }
        Ok(())
    }

    /// Marks the tile of padded cell `k` and its 8 neighbours touched, with a fresh bed.
    pub(crate) fn touch_around_cell(
        &mut self,
        k: usize,
        source: Option<&dyn BedSource>,
    ) -> Result<(), AvalancheError> {
        self.touch_around_tile((k / self.pw) / TILE, (k % self.pw) / TILE, source)
    }

    /// Marks every occupied tile and its 8 neighbours touched, with a fresh bed (before a
    /// sub-step).
    pub(crate) fn touch_around_content(
        &mut self,
        source: Option<&dyn BedSource>,
    ) -> Result<(), AvalancheError> {
        let ntx = self.tiles.ntx();
        for o in 0..self.tiles.occupied().len() {
            let t = self.tiles.occupied()[o] as usize;
            self.touch_around_tile(t / ntx, t % ntx, source)?;
        }
        Ok(())
    }

    /// Returns the touched tiles to rest (no flowing or settled snow, no motion) and starts a
    /// new epoch: no tile is touched, and a lazy state's bed is stale everywhere (the terrain
    /// may have changed since). The cost is that of the last run's footprint.
    pub(crate) fn reset_touched(&mut self) {
        for o in 0..self.footprint.touched.len() {
            let (r0, r1, c0, c1) = self.touched_box(o);
            for r in r0..=r1 {
                let row = r * self.pw + c0..=r * self.pw + c1;
                self.h[row.clone()].fill(0.0);
                self.settled[row.clone()].fill(0.0);
                for p in &mut self.pipes {
                    p[row.clone()].fill(0.0);
                }
            }
        }
        self.tiles.clear();
        self.active = None;
        self.maxima = (0.0, 0.0);
        self.footprint.touched.clear();
        self.footprint.epoch = self.footprint.epoch.wrapping_add(1);
        if self.footprint.epoch == 0 {
            self.footprint.touched_epoch.fill(0);
            self.footprint.bed_epoch.fill(0);
            self.footprint.epoch = 1;
        }
    }

    /// Stops all motion after a deposit of every cell: the touched tiles' pipes are zeroed
    /// and nothing is active.
    pub(crate) fn stop_all(&mut self) {
        for o in 0..self.footprint.touched.len() {
            let (r0, r1, c0, c1) = self.touched_box(o);
            for r in r0..=r1 {
                for p in &mut self.pipes {
                    p[r * self.pw + c0..=r * self.pw + c1].fill(0.0);
                }
            }
        }
        self.tiles.clear();
        self.active = None;
        self.maxima = (0.0, 0.0);
    }

    /// [`AvalancheState::refresh_active`] over the touched tiles only (all snow and motion
    /// lie in them).
    pub(crate) fn refresh_active_touched(&mut self) {
        let boxes: Vec<_> = self.touched_boxes().collect();
        self.refresh_active_over(&boxes);
    }
}
