//! The season timeline: snapshots of the season the page can play, step, and scrub through
//! ("any point on the simulation time-line", Cordonnier et al. 2018, Section 3).
//!
//! A snapshot is a fork of the season ([`Winter`] clones continue identically) with the
//! painted maps. Stepping from an earlier snapshot drops the later ones (a new branch). Edits
//! made at a snapshot are written back into it before the timeline moves, so scrubbing away
//! and back keeps them.
//!
//! **Compact snapshots.** A snapshot keeps only what restores the season exactly: its
//! checkpoint (the four snow layers, the snowpack's and the avalanches' per-cell maps, the
//! clock, scheduler and budget: what `snowscape run --resume` reads) and the painted maps,
//! both packed ([`pack`]: the bytes split into their four byte planes, so that the floats'
//! signs, exponents and high mantissas sit together, then deflated). The bedrock, the
//! environment maps and the scratch buffers are not stored: a snapshot is restored into a
//! fork of the session's season, which has the same scenario on the same terrain, with
//! [`Winter::restore_checkpoint`] (the weather period's maps recomputed when the snapshot's
//! period is another). Restoring gives back the very bytes that were stored, and the restored
//! season continues exactly as `snowscape run --resume` of them would (the season's ski area
//! and painted release rates included: both are in the checkpoint), at
//! [`SNAPSHOT_BYTES_PER_CELL`] bytes per cell or less on realistic terrains
//! (`tests/snapshot_memory.rs`: 16.8 at 256² after 3 days, 13.7 on the avaMal DEM after 2;
//! a whole copy of the season took 285 and 268).
//!
//! **Memory budget.** The snapshots kept take at most the budget
//! ([`DEFAULT_SNAPSHOT_BUDGET_BYTES`] unless `snowscape serve --snapshot-memory` says
//! otherwise), counted in their packed bytes, and at most [`MAX_SNAPSHOTS`] are kept (at
//! least 2). Past it the oldest snapshots are dropped, but never the first (a new scenario
//! restarts from it) nor the current one; [`Timeline::push`] says how many went, and the
//! session tells the page.

use crate::brush::PaintMaps;
use snowscape_season::winter::Winter;
use std::io::{Read, Write};

/// Memory the snapshots may take by default, bytes (2 GiB).
pub const DEFAULT_SNAPSHOT_BUDGET_BYTES: u64 = 2 << 30;
/// Bytes per grid cell a packed snapshot takes at most on average (its checkpoint and painted
/// maps; measured by `tests/snapshot_memory.rs` on the avaMal DEM and at 256² after a few
/// days): the number of snapshots the budget keeps is at least the budget over this.
pub const SNAPSHOT_BYTES_PER_CELL: u64 = 20;
/// Most snapshots kept, whatever the budget (the state message lists their days).
pub const MAX_SNAPSHOTS: usize = 1000;

/// `bytes` packed: split into four byte planes (byte k of every 4-byte word together), then
/// deflated.
pub fn pack(bytes: &[u8]) -> Vec<u8> {
    let n = bytes.len();
    let mut planes = Vec::with_capacity(n);
    for k in 0..4 {
        planes.extend(bytes.iter().skip(k).step_by(4));
    }
    let mut z =
        flate2::write::DeflateEncoder::new(Vec::with_capacity(n / 4), flate2::Compression::fast());
    // Writing into a Vec cannot fail.
    let _ = z.write_all(&(n as u64).to_le_bytes());
    let _ = z.write_all(&planes);
    let mut out = z.finish().unwrap_or_default();
    out.shrink_to_fit();
    out
}

/// The bytes [`pack`] packed.
pub fn unpack(packed: &[u8]) -> Result<Vec<u8>, String> {
    let mut z = flate2::read::DeflateDecoder::new(packed);
    let mut len = [0u8; 8];
    z.read_exact(&mut len)
        .map_err(|e| format!("a snapshot cannot be unpacked: {e}"))?;
    let n = usize::try_from(u64::from_le_bytes(len))
        .map_err(|_| "a snapshot's length does not fit".to_string())?;
    let mut planes = Vec::with_capacity(n);
    z.read_to_end(&mut planes)
        .map_err(|e| format!("a snapshot cannot be unpacked: {e}"))?;
    if planes.len() != n {
        return Err(format!(
            "a snapshot unpacks to {} bytes, it held {n}",
            planes.len()
        ));
    }
    let mut bytes = vec![0u8; n];
    let mut src = planes.iter();
    for k in 0..4 {
        for b in bytes.iter_mut().skip(k).step_by(4) {
            *b = src.next().copied().unwrap_or(0);
        }
    }
    Ok(bytes)
}

/// A season and its painted maps, packed.
struct Snapshot {
    day: f64,
    /// The season's checkpoint, packed.
    state: Vec<u8>,
    /// The avalanche probability then the skier area, as little-endian f32, packed.
    paint: Vec<u8>,
}

impl Snapshot {
    fn of(winter: &Winter, paint: &PaintMaps) -> Self {
        let mut checkpoint = Vec::new();
        // Writing a checkpoint into memory fails only on a header serde cannot write, which
        // the season's types never hold; the restore would then say so.
        if let Err(e) = winter.write_checkpoint(&mut checkpoint) {
            tracing::error!(
                "a snapshot of day {} could not be written: {e}",
                winter.day()
            );
        }
        let maps: Vec<u8> = paint
            .avalanche_probability
            .iter()
            .chain(&paint.ski_area)
            .flat_map(|v| v.to_le_bytes())
            .collect();
        Self {
            day: winter.day(),
            state: pack(&checkpoint),
            paint: pack(&maps),
        }
    }

    fn bytes(&self) -> u64 {
        (self.state.len() + self.paint.len() + std::mem::size_of::<Self>()) as u64
    }

    /// The season and maps, restored into a fork of `base` (the same scenario and terrain).
    fn restore(&self, base: &Winter) -> Result<(Winter, PaintMaps), String> {
        let checkpoint = unpack(&self.state)?;
        let mut winter = base.clone();
        winter
            .restore_checkpoint(&mut checkpoint.as_slice())
            .map_err(|e| format!("the snapshot of day {} cannot be restored: {e}", self.day))?;
        let maps = unpack(&self.paint)?;
        let n = winter.terrain.geometry().len();
        if maps.len() != 8 * n {
            return Err(format!(
                "the snapshot of day {} holds painted maps of {} bytes, the terrain has {n} cells",
                self.day,
                maps.len()
            ));
        }
        let values: Vec<f32> = maps
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        let (a, s) = values.split_at(n);
        Ok((
            winter,
            PaintMaps {
                avalanche_probability: a.to_vec(),
                ski_area: s.to_vec(),
            },
        ))
    }
}

/// The snapshots and the one shown.
pub struct Timeline {
    snaps: Vec<Snapshot>,
    current: usize,
    edited: bool,
    /// Grid cells (for the estimate of how many snapshots the budget keeps).
    cells: u64,
    budget_bytes: u64,
    /// Snapshots dropped for the budget so far.
    dropped: usize,
}

impl Timeline {
    /// A timeline whose first snapshot is `winter`, within the default budget.
    pub fn new(winter: &Winter, paint: &PaintMaps) -> Self {
        Self {
            snaps: vec![Snapshot::of(winter, paint)],
            current: 0,
            edited: false,
            cells: winter.terrain.geometry().len().max(1) as u64,
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
    /// Most snapshots the budget keeps at least: the budget over [`SNAPSHOT_BYTES_PER_CELL`]
    /// bytes a cell, within 2..=[`MAX_SNAPSHOTS`] (the packed sizes decide: smaller ones,
    /// more are kept).
    pub fn max(&self) -> usize {
        let n = self.budget_bytes / (self.cells * SNAPSHOT_BYTES_PER_CELL).max(1);
        (n.min(MAX_SNAPSHOTS as u64) as usize).max(2)
    }
    /// The memory budget, bytes.
    pub fn budget_bytes(&self) -> u64 {
        self.budget_bytes
    }
    /// Memory of the snapshots kept (their packed bytes), bytes.
    pub fn bytes(&self) -> u64 {
        self.snaps.iter().map(Snapshot::bytes).sum()
    }
    /// Packed bytes of snapshot `index`.
    pub fn snapshot_bytes(&self, index: usize) -> Option<u64> {
        self.snaps.get(index).map(Snapshot::bytes)
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
            *s = Snapshot::of(winter, paint);
        }
        self.edited = false;
    }

    /// Appends the state after a step (dropping the snapshots after the current one);
    /// returns how many old snapshots the budget dropped.
    pub fn push(&mut self, winter: &Winter, paint: &PaintMaps) -> usize {
        self.snaps.truncate(self.current + 1);
        self.snaps.push(Snapshot::of(winter, paint));
        self.current = self.snaps.len() - 1;
        self.edited = false;
        self.enforce_budget()
    }

    /// Drops the oldest snapshots while they take more than the budget or number more than
    /// [`MAX_SNAPSHOTS`], never the first nor the current, and keeping at least 2.
    fn enforce_budget(&mut self) -> usize {
        let mut dropped = 0;
        let mut total = self.bytes();
        while self.snaps.len() > 2
            && (total > self.budget_bytes || self.snaps.len() > MAX_SNAPSHOTS)
        {
            let Some(k) = (1..self.snaps.len()).find(|&k| k != self.current) else {
                break;
            };
            total -= self.snaps.remove(k).bytes().min(total);
            if self.current > k {
                self.current -= 1;
            }
            dropped += 1;
        }
        self.dropped += dropped;
        dropped
    }

    /// Makes snapshot `index` current; returns its state, restored into a fork of `base`
    /// (the session's season: the same scenario on the same terrain). `None` when there is
    /// no such snapshot; an error when it cannot be restored (the timeline is unchanged).
    pub fn seek(
        &mut self,
        index: usize,
        base: &Winter,
    ) -> Option<Result<(Winter, PaintMaps), String>> {
        let restored = self.snaps.get(index)?.restore(base);
        if restored.is_ok() {
            self.current = index;
            self.edited = false;
        }
        Some(restored)
    }

    /// The first snapshot's season and painted maps, restored into a fork of `base`.
    pub fn first(&self, base: &Winter) -> Result<(Winter, PaintMaps), String> {
        self.snaps[0].restore(base)
    }
}
