//! The season timeline: snapshots of the season the page can play, step, and scrub through
//! ("any point on the simulation time-line", Cordonnier et al. 2018, Section 3).
//!
//! A snapshot is a fork of the season ([`Winter`] clones continue identically) with the
//! painted maps. Stepping from an earlier snapshot drops the later ones (a new branch). Edits
//! made at a snapshot are written back into it before the timeline moves, so scrubbing away
//! and back keeps them.
//!
//! **Memory budget.** A snapshot takes about [`SNAPSHOT_BYTES_PER_CELL`] bytes per grid cell
//! (measured by `tests/snapshot_memory.rs`), so the number kept is the budget
//! ([`DEFAULT_SNAPSHOT_BUDGET_BYTES`] unless `snowscape serve --snapshot-memory` says
//! otherwise) over one snapshot's size, at least 2 and at most [`MAX_SNAPSHOTS`]. Past it the
//! oldest snapshots are dropped, but never the first (a new scenario restarts from it) nor
//! the current one; [`Timeline::push`] says how many went, and the session tells the page.

use crate::brush::PaintMaps;
use snowscape_season::winter::Winter;

/// Memory the snapshots may take by default, bytes (2 GiB: 6 snapshots at 1024², 100 at 256²).
pub const DEFAULT_SNAPSHOT_BUDGET_BYTES: u64 = 2 << 30;
/// Bytes per grid cell of one snapshot: the season's clone (layers, environment maps,
/// scratch buffers, avalanche and skier maps) and the painted maps. Measured at 128² and 256²
/// after three days with skiers (272 and 261 bytes per cell) and rounded up.
pub const SNAPSHOT_BYTES_PER_CELL: u64 = 320;
/// Most snapshots kept, whatever the budget (the state message lists their days).
pub const MAX_SNAPSHOTS: usize = 1000;

struct Snapshot {
    day: f64,
    winter: Winter,
    paint: PaintMaps,
}

/// The snapshots and the one shown.
pub struct Timeline {
    snaps: Vec<Snapshot>,
    current: usize,
    edited: bool,
    /// Estimated bytes of one snapshot.
    snapshot_bytes: u64,
    budget_bytes: u64,
    /// Snapshots dropped for the budget so far.
    dropped: usize,
}

impl Timeline {
    /// A timeline whose first snapshot is `winter`, within the default budget.
    pub fn new(winter: &Winter, paint: &PaintMaps) -> Self {
        let cells = winter.terrain.geometry().len().max(1) as u64;
        Self {
            snaps: vec![Snapshot {
                day: winter.day(),
                winter: winter.clone(),
                paint: paint.clone(),
            }],
            current: 0,
            edited: false,
            snapshot_bytes: cells * SNAPSHOT_BYTES_PER_CELL,
            budget_bytes: DEFAULT_SNAPSHOT_BUDGET_BYTES,
            dropped: 0,
        }
    }

    /// Days of the snapshots.
    pub fn days(&self) -> Vec<f64> {
        self.snaps.iter().map(|s| s.day).collect()
    }
    /// Index of the snapshot shown.
    pub fn current(&self) -> usize {
        self.current
    }
    /// Number of snapshots.
    pub fn len(&self) -> usize {
        self.snaps.len()
    }
    /// Whether there is no snapshot (never: the first one stays).
    pub fn is_empty(&self) -> bool {
        self.snaps.is_empty()
    }
    /// Most snapshots kept: the budget over one snapshot's size, within 2..=[`MAX_SNAPSHOTS`].
    pub fn max(&self) -> usize {
        let n = self.budget_bytes / self.snapshot_bytes.max(1);
        (n.min(MAX_SNAPSHOTS as u64) as usize).max(2)
    }
    /// The memory budget, bytes.
    pub fn budget_bytes(&self) -> u64 {
        self.budget_bytes
    }
    /// Estimated memory of the snapshots kept, bytes.
    pub fn bytes(&self) -> u64 {
        self.snaps.len() as u64 * self.snapshot_bytes
    }
    /// Snapshots dropped for the budget so far.
    pub fn dropped(&self) -> usize {
        self.dropped
    }

    /// Sets the memory budget; returns how many snapshots it dropped.
    pub fn set_budget(&mut self, bytes: u64) -> usize {
        self.budget_bytes = bytes;
        self.enforce_budget()
    }

    /// The working state differs from the current snapshot.
    pub fn mark_edited(&mut self) {
        self.edited = true;
    }

    /// Writes the working state back into the current snapshot if it was edited.
    pub fn store(&mut self, winter: &Winter, paint: &PaintMaps) {
        if self.edited
            && let Some(s) = self.snaps.get_mut(self.current)
        {
            s.winter = winter.clone();
            s.paint = paint.clone();
        }
        self.edited = false;
    }

    /// Appends the state after a step (dropping the snapshots after the current one);
    /// returns how many old snapshots the budget dropped.
    pub fn push(&mut self, winter: &Winter, paint: &PaintMaps) -> usize {
        self.snaps.truncate(self.current + 1);
        self.snaps.push(Snapshot {
            day: winter.day(),
            winter: winter.clone(),
            paint: paint.clone(),
        });
        self.current = self.snaps.len() - 1;
        self.edited = false;
        self.enforce_budget()
    }

    /// Drops the oldest snapshots past [`Timeline::max`], never the first nor the current.
    fn enforce_budget(&mut self) -> usize {
        let mut dropped = 0;
        while self.snaps.len() > self.max() {
            let Some(k) = (1..self.snaps.len()).find(|&k| k != self.current) else {
                break;
            };
            self.snaps.remove(k);
            if self.current > k {
                self.current -= 1;
            }
            dropped += 1;
        }
        self.dropped += dropped;
        dropped
    }

    /// Makes snapshot `index` current; returns a copy of its state.
    pub fn seek(&mut self, index: usize) -> Option<(Winter, PaintMaps)> {
        let s = self.snaps.get(index)?;
        self.current = index;
        self.edited = false;
        Some((s.winter.clone(), s.paint.clone()))
    }

    /// The first snapshot's season and a copy of its painted maps.
    pub fn first(&self) -> (&Winter, PaintMaps) {
        let s = &self.snaps[0];
        (&s.winter, s.paint.clone())
    }
}
