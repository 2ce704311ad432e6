//! Skiers in the season (Cordonnier et al. 2018, §3.2 and §6.2).
//!
//! **When.** Ski-Track-Start is a Poisson event of rate `per_day` (the paper: "once an hour",
//! 24/day; off by default, turned on by the scenario's `[skiers]` table or `snowscape run
//! --skiers`). Each start spawns one skier, at the next of the scenario's start points or with
//! probability weighted by the distance-to-terminus map ([`snowscape_skiers`]).
//!
//! **Temporal zoom.** The skier then runs to its terminus inside its start event, in steps of
//! `step_s` (the season clock advances by its run time), as avalanches do: "an entire
//! [interactive event] may take place between two lower frequency events" (§3.1, Fig. 4).
//!
//! **Interactions.** A skier compacts the snow it crosses (unstable → stable → compacted); the
//! recent-skier map raises the avalanche hazard ([`crate::avalanches`]); a trigger drawn on
//! unstable snow starts an avalanche there at once (§3.2: "ski-tracks triggering immediate
//! avalanches when they cross unstable snow layers"); snowfall and wind deposits fade the
//! tracks (§6.2). The distance-to-terminus map is refreshed at the next start after snowfall
//! or melt changed the snow.
//!
//! **Checkpoints** hold the snow (compaction included) and the ski area: its clock and next
//! skier id, the skiers on the slopes, the finished tracks, the track texture's tiles, the
//! recent-skier map, the distance-to-terminus map (the spawn weights are rebuilt from it) and
//! whether it is due a refresh ([`snowscape_skiers::snapshot`]), so a resumed season with
//! skiers ends bit-identical to an uninterrupted one (`tests/resume_skiers.rs`).

use serde::{Deserialize, Serialize};
use snowscape_skiers::{SkiParams, Terminus};

/// How many skiers come and where they start.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SkierParameters {
    /// Skier runs per day. Default 0 (no skiers); the paper's "once an hour" is 24.
    pub per_day: f64,
    /// Start points (map x, y), used in turn; empty: spawn weighted by distance to terminus.
    pub starts: Vec<[f64; 2]>,
    /// Where runs end. Default: local minima of the snow surface and the terrain's edges.
    pub terminus: Terminus,
    /// Skier step, s. Default 0.2 (chosen here: 2-3 m per step at skiing speeds, below a
    /// cell of the finest DEMs).
    pub step_s: f64,
    /// Longest run, s. Default 1800.
    pub max_run_s: f64,
    /// Steering, tracks, compaction and trigger parameters.
    pub ski: SkiParams,
}

impl Default for SkierParameters {
    fn default() -> Self {
        Self {
            per_day: 0.0,
            starts: Vec::new(),
            terminus: Terminus::LocalMinima,
            step_s: 0.2,
            max_run_s: 1800.0,
            ski: SkiParams::default(),
        }
    }
}

/// Most skier runs per day (a busy resort's lift capacity): each run costs a descent.
pub const MAX_SKIERS_PER_DAY: f64 = 10_000.0;

impl SkierParameters {
    /// Checks every field; the message names the offending one.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.per_day.is_finite() && (0.0..=MAX_SKIERS_PER_DAY).contains(&self.per_day)) {
            return Err(format!(
                "per_day = {} must be within [0, {MAX_SKIERS_PER_DAY}] runs per day",
                self.per_day
            ));
        }
        if !(self.step_s.is_finite() && self.step_s >= 0.01 && self.step_s <= 60.0) {
            return Err(format!(
                "step_s = {} must be within [0.01, 60] s",
                self.step_s
            ));
        }
        if !(self.max_run_s.is_finite() && self.max_run_s > 0.0 && self.max_run_s <= 86_400.0) {
            return Err(format!(
                "max_run_s = {} must be within (0, 86400] s",
                self.max_run_s
            ));
        }
        for (k, p) in self.starts.iter().enumerate() {
            if !(p[0].is_finite() && p[1].is_finite()) {
                return Err(format!(
                    "starts[{k}] = {p:?} must be finite map coordinates"
                ));
            }
        }
        self.ski.validate().map_err(|e| format!("ski: {e}"))
    }
}

/// What the season's skiers did.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SkiStats {
    /// Skier runs started.
    pub runs: u64,
    /// Runs that reached a terminus.
    pub finished: u64,
    /// Horizontal length skied, m.
    pub distance_m: f64,
    /// Avalanches skiers triggered.
    pub avalanches_triggered: u64,
    /// Skier steps taken.
    pub steps: u64,
}
