//! The season timeline: snapshots of the season the page can play, step, and scrub through
//! ("any point on the simulation time-line", Cordonnier et al. 2018, Section 3).
//!
//! A snapshot is a fork of the season ([`Winter`] clones continue identically) with the
//! painted maps. Stepping from an earlier snapshot drops the later ones (a new branch). Edits
//! made at a snapshot are written back into it before the timeline moves, so scrubbing away
//! and back keeps them. The number of snapshots is capped by memory: past the cap, the
//! snapshot whose neighbours are closest in time is dropped (never the first, last or current).

use crate::brush::PaintMaps;
use snowscape_season::winter::Winter;

/// Memory the snapshots may take, bytes (a season clone takes about 200 bytes per cell).
pub const SNAPSHOT_BUDGET_BYTES: usize = 2 << 30;
/// Approximate bytes per cell of one snapshot.
const BYTES_PER_CELL: usize = 200;

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
    max: usize,
}

impl Timeline {
    /// A timeline whose first snapshot is `winter`.
    pub fn new(winter: &Winter, paint: &PaintMaps) -> Self {
        let cells = winter.terrain.geometry().len().max(1);
        let max = (SNAPSHOT_BUDGET_BYTES / (cells * BYTES_PER_CELL)).clamp(4, 400);
        Self {
            snaps: vec![Snapshot {
                day: winter.day(),
                winter: winter.clone(),
                paint: paint.clone(),
            }],
            current: 0,
            edited: false,
            max,
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
    /// Most snapshots kept.
    pub fn max(&self) -> usize {
        self.max
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

    /// Appends the state after a step (dropping the snapshots after the current one).
    pub fn push(&mut self, winter: &Winter, paint: &PaintMaps) {
        self.snaps.truncate(self.current + 1);
        self.snaps.push(Snapshot {
            day: winter.day(),
            winter: winter.clone(),
            paint: paint.clone(),
        });
        self.current = self.snaps.len() - 1;
        self.edited = false;
        while self.snaps.len() > self.max {
            let n = self.snaps.len();
            let gap = |k: usize| self.snaps[k + 1].day - self.snaps[k - 1].day;
            let Some(k) = (1..n - 1)
                .filter(|&k| k != self.current)
                .min_by(|&a, &b| gap(a).total_cmp(&gap(b)))
            else {
                break;
            };
            self.snaps.remove(k);
            if self.current > k {
                self.current -= 1;
            }
        }
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
