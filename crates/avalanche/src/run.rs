//! One avalanche from release to rest: stepping, peak fields, stop criterion and the runout
//! figures practitioners compare.
//!
//! [`AvalancheRun`] advances an [`AvalancheState`] by record intervals (the paper's temporal
//! zoom: Section 3.1 steps an avalanche every ~0.1 s of simulated time) and, after each, updates
//! per cell the **peak flow thickness** and **peak speed** (only over the active box, so the
//! cost follows the footprint). By default ([`RecordTiming::AtSubsteps`]) the flow takes the
//! longest sub-steps its CFL condition allows and a record follows the first sub-step ending at
//! least an interval after the last record; [`RecordTiming::Exact`] cuts the sub-steps at every
//! interval instead. The run stops when
//! - the snow is at rest (no moving pipe), or
//! - its kinetic energy `E = Σ ½·h·|v|²·dx·dy` (per unit density, m⁵/s²) has fallen below
//!   `stop_energy_fraction` of its peak (AvaFrame com1DFA's `stopCrit`, default 1 %: the tail of a
//!   Coulomb flow creeps for a long time while nothing visible changes), or
//! - the simulated time reaches `duration_s`.
//!
//! **Figures** ([`RunSummary`]): the *footprint* is where the peak thickness exceeded
//! `footprint_threshold_m` (1 cm, AvaFrame's convention for peak-flow-thickness maps); the
//! *travel angle* is `atan(Δz / L)` of the mass centre between release and stop (`z` the bed
//! altitude under the snow, volume-weighted; for a Coulomb slider it tends to θc); the *runout
//! length* is the horizontal distance from the release's highest cell to the footprint cell
//! farthest from it, and the *α angle* the angle from that release top down to that runout
//! point (the practitioners' "alpha angle").

use crate::entrainment::{EntrainedMaps, entrain};
use crate::flow::{
    AvalancheError, AvalancheParams, AvalancheReport, AvalancheScratch, AvalancheState, BedSource,
    step_at_least, step_on,
};
use serde::{Deserialize, Serialize};
use snowscape_terrain::LayeredTerrain;

/// When an avalanche run records and stops.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct RunOptions {
    /// Longest simulated time, s. Default 600 (chosen here: large avalanche paths run out in
    /// 1–3 minutes; AvaFrame's reference avaKot run takes 118 s).
    pub duration_s: f64,
    /// Simulated time between records (peak fields, frames, stop test), s. Default 0.1 (the
    /// paper's avalanche step, Section 3.1).
    pub record_interval_s: f64,
    /// Stop once the kinetic energy falls below this fraction of its peak. Default 0.01
    /// (AvaFrame com1DFA `stopCrit`); 0 runs until the snow is at rest or `duration_s`.
    pub stop_energy_fraction: f64,
    /// Peak thickness above which a cell belongs to the footprint, m. Default 0.01 (AvaFrame's
    /// peak-flow-thickness convention).
    pub footprint_threshold_m: f64,
    /// Films thinner than this (the cell and its 8 neighbours) come to rest after each record
    /// interval, m (see `AvalancheState::settle_films`). Default 0.005 (chosen here: half the
    /// footprint threshold); 0 keeps every film flowing.
    pub settle_thickness_m: f64,
    /// How records and flow sub-steps meet. Default: records at sub-steps.
    pub records: RecordTiming,
}

/// How records and flow sub-steps meet.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum RecordTiming {
    /// Sub-steps as long as the CFL condition allows; a record follows the first sub-step
    /// that ends at least `record_interval_s` after the last record (records are at least
    /// that far apart, and farther where the CFL step is longer: slow flows on coarse cells).
    #[default]
    AtSubsteps,
    /// Sub-steps cut to end exactly every `record_interval_s` (the paper's fixed 0.1 s
    /// avalanche step; more sub-steps where the CFL step is longer than the interval).
    Exact,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            duration_s: 600.0,
            record_interval_s: 0.1,
            stop_energy_fraction: 0.01,
            footprint_threshold_m: 0.01,
            settle_thickness_m: 0.005,
            records: RecordTiming::AtSubsteps,
        }
    }
}

/// Longest run, s.
pub const MAX_DURATION_S: f64 = 86_400.0;
/// Most records one run may take (`duration_s / record_interval_s`).
pub const MAX_RECORDS: f64 = 1e6;

impl RunOptions {
    /// Checks every field, naming the offending one.
    pub fn validate(&self) -> Result<(), AvalancheError> {
        let positive = |name: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(AvalancheError::InvalidParameter {
                    name,
                    value: v,
                    expected: "finite and > 0",
                })
            }
        };
        positive("duration_s", self.duration_s)?;
        positive("record_interval_s", self.record_interval_s)?;
        if self.duration_s > MAX_DURATION_S {
            return Err(AvalancheError::InvalidParameter {
                name: "duration_s",
                value: self.duration_s,
                expected: "at most 86400 s (a day)",
            });
        }
        if self.duration_s / self.record_interval_s > MAX_RECORDS {
            return Err(AvalancheError::InvalidParameter {
                name: "record_interval_s",
                value: self.record_interval_s,
                expected: "at least duration_s / 1000000 (at most a million records)",
            });
        }
        if !(self.stop_energy_fraction.is_finite()
            && (0.0..1.0).contains(&self.stop_energy_fraction))
        {
            return Err(AvalancheError::InvalidParameter {
                name: "stop_energy_fraction",
                value: self.stop_energy_fraction,
                expected: "in [0, 1)",
            });
        }
        for (name, value) in [
            ("footprint_threshold_m", self.footprint_threshold_m),
            ("settle_thickness_m", self.settle_thickness_m),
        ] {
            if !(value.is_finite() && (0.0..=100.0).contains(&value)) {
                return Err(AvalancheError::InvalidParameter {
                    name,
                    value,
                    expected: "in [0, 100] m",
                });
            }
        }
        Ok(())
    }
}

/// Why a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// No pipe moves.
    AtRest,
    /// Kinetic energy below `stop_energy_fraction` of its peak.
    EnergyCriterion,
    /// `duration_s` reached.
    Duration,
    /// No snow left on the grid (all of it flowed across an open border or into nodata).
    Empty,
}

/// The figures of a finished (or interrupted) run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    /// Released volume, m³.
    pub released_volume_m3: f64,
    /// Volume on the grid at the end (in motion plus deposit), m³.
    pub final_volume_m3: f64,
    /// Volume that left the terrain across an open border (the grid's border or the nodata
    /// outline), m³.
    pub border_outflow_m3: f64,
    /// Volume the flow entrained from the snowpack on its way, m³ ([`crate::entrainment`]).
    #[serde(default)]
    pub entrained_volume_m3: f64,
    /// `|released + entrained − final − outflow| / (released + entrained)`.
    pub volume_closure_rel: f64,
    /// Simulated time, s.
    pub simulated_s: f64,
    /// Flow sub-steps taken.
    pub substeps: usize,
    /// Why the run ended (`None` while it goes on).
    pub stop: Option<StopReason>,
    /// Largest speed reached anywhere, m/s.
    pub max_speed_m_s: f64,
    /// Largest flow thickness reached anywhere, m.
    pub max_thickness_m: f64,
    /// Footprint area (peak thickness above the threshold), m².
    pub footprint_area_m2: f64,
    /// Horizontal distance from the release top to the farthest footprint cell, m.
    pub runout_length_m: f64,
    /// Drop from the release top to that runout point, m.
    pub runout_drop_m: f64,
    /// `atan(runout_drop / runout_length)`, degrees.
    pub alpha_angle_deg: f64,
    /// Horizontal travel of the mass centre, m.
    pub centre_travel_m: f64,
    /// Drop of the mass centre, m.
    pub centre_drop_m: f64,
    /// `atan(centre_drop / centre_travel)`, degrees (90 when the centre did not move).
    pub travel_angle_deg: f64,
    /// Release top and runout point, map coordinates (x, y, z), m.
    pub release_top: [f64; 3],
    /// The footprint cell farthest from the release top, map coordinates (x, y, z), m.
    pub runout_point: [f64; 3],
}

/// An avalanche in progress, with its peak fields.
#[derive(Debug, Clone)]
pub struct AvalancheRun {
    /// The flowing snow.
    pub state: AvalancheState,
    scratch: AvalancheScratch,
    peak_thickness: Vec<f64>,
    peak_speed: Vec<f64>,
    /// Depth entrained per cell in all and of stable snow (grid-sized), m.
    entrained: Vec<f64>,
    entrained_stable: Vec<f64>,
    released_volume: f64,
    entrained_volume: f64,
    border_outflow: f64,
    time: f64,
    substeps: usize,
    energy: f64,
    peak_energy: f64,
    moving: bool,
    stop: Option<StopReason>,
    start_centre: [f64; 3],
    release_top: Option<(usize, usize)>,
}

/// The work buffers of a run, handed from one run to the next ([`AvalancheRun::with_buffers`],
/// [`AvalancheRun::into_parts`]): a season runs hundreds of avalanches on one grid.
#[derive(Debug, Clone, Default)]
pub struct RunBuffers {
    /// The flow's work buffers.
    pub scratch: AvalancheScratch,
    /// Peak fields and entrained depths, all zero between runs (grid-sized; empty until
    /// first used).
    peak_thickness: Vec<f64>,
    peak_speed: Vec<f64>,
    entrained: Vec<f64>,
    entrained_stable: Vec<f64>,
}

impl AvalancheRun {
    /// Starts a run from released snow (the state's flowing thickness).
    pub fn new(state: AvalancheState) -> Self {
        Self::with_scratch(state, AvalancheScratch::default())
    }

    /// [`AvalancheRun::new`] reusing the flow's work buffers of an earlier run
    /// ([`AvalancheRun::take_scratch`] hands them back).
    pub fn with_scratch(state: AvalancheState, scratch: AvalancheScratch) -> Self {
        Self::with_buffers(
            state,
            RunBuffers {
                scratch,
                ..RunBuffers::default()
            },
        )
    }

    /// [`AvalancheRun::new`] reusing every buffer of an earlier run: apart from them, the cost
    /// of starting, recording and summing up a run follows the tiles the flow touches, not
    /// the grid.
    pub fn with_buffers(state: AvalancheState, buffers: RunBuffers) -> Self {
        let n = state.geometry.width() * state.geometry.height();
        let RunBuffers {
            scratch,
            mut peak_thickness,
            mut peak_speed,
            mut entrained,
            mut entrained_stable,
        } = buffers;
        for p in [
            &mut peak_thickness,
            &mut peak_speed,
            &mut entrained,
            &mut entrained_stable,
        ] {
            if p.len() != n {
                *p = vec![0.0; n];
            }
        }
        let released_volume = state.flowing_volume();
        let start_centre = mass_centre(&state);
        // The highest snow-covered cell (the first in row-major order among equals).
        let w = state.geometry.width();
        let mut top: Option<(usize, f64)> = None;
        for (r0, r1, c0, c1) in state.content_cells() {
            for r in r0..=r1 {
                for c in c0..=c1 {
                    if state.thickness_at(c, r) > 0.0 {
                        let (i, z) = (r * w + c, state.bed_at(c, r));
                        if top.is_none_or(|t| z > t.1 || (z == t.1 && i < t.0)) {
                            top = Some((i, z));
                        }
                    }
                }
            }
        }
        let mut run = Self {
            scratch,
            peak_thickness,
            peak_speed,
            entrained,
            entrained_stable,
            released_volume,
            entrained_volume: 0.0,
            border_outflow: 0.0,
            time: 0.0,
            substeps: 0,
            energy: 0.0,
            peak_energy: 0.0,
            moving: true,
            stop: None,
            start_centre,
            release_top: top.map(|t| (t.0 % w, t.0 / w)),
            state,
        };
        run.record();
        if released_volume == 0.0 {
            run.stop = Some(StopReason::Empty);
        }
        run
    }

    /// The flow's work buffers.
    pub(crate) fn scratch_mut(&mut self) -> &mut AvalancheScratch {
        &mut self.scratch
    }

    /// The work buffers, for the next run (this one can no longer advance cheaply: it
    /// reallocates them).
    pub fn take_scratch(&mut self) -> AvalancheScratch {
        std::mem::take(&mut self.scratch)
    }

    /// The state and every buffer, for the next run: the peak fields are zeroed over the
    /// touched tiles (the only cells they can be non-zero in).
    pub fn into_parts(mut self) -> (AvalancheState, RunBuffers) {
        let w = self.state.geometry.width();
        for (r0, r1, c0, c1) in self.state.touched_cells() {
            for r in r0..=r1 {
                self.peak_thickness[r * w + c0..=r * w + c1].fill(0.0);
                self.peak_speed[r * w + c0..=r * w + c1].fill(0.0);
                self.entrained[r * w + c0..=r * w + c1].fill(0.0);
                self.entrained_stable[r * w + c0..=r * w + c1].fill(0.0);
            }
        }
        let buffers = RunBuffers {
            scratch: self.scratch,
            peak_thickness: self.peak_thickness,
            peak_speed: self.peak_speed,
            entrained: self.entrained,
            entrained_stable: self.entrained_stable,
        };
        (self.state, buffers)
    }

    /// The grid cells the run touched, inclusive boxes `(r0, r1, c0, c1)` of rows and
    /// columns: every cell with a non-zero peak or any snow of the avalanche lies in one.
    pub fn touched_cells(&self) -> impl Iterator<Item = (usize, usize, usize, usize)> + '_ {
        self.state.touched_cells()
    }

    /// Simulated time since the release, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Why the run ended, or `None` while it goes on.
    pub fn stop_reason(&self) -> Option<StopReason> {
        self.stop
    }

    /// Peak flow thickness per grid cell (row-major), m.
    pub fn peak_thickness(&self) -> &[f64] {
        &self.peak_thickness
    }

    /// Peak speed per grid cell (row-major), m/s.
    pub fn peak_speed(&self) -> &[f64] {
        &self.peak_speed
    }

    /// Depth the flow entrained per grid cell (row-major), m: its scour of the snowpack.
    pub fn entrained(&self) -> &[f64] {
        &self.entrained
    }

    /// Volume entrained so far, m³.
    pub fn entrained_volume(&self) -> f64 {
        self.entrained_volume
    }

    /// Kinetic energy per unit density at the last record, m⁵/s².
    pub fn kinetic_energy(&self) -> f64 {
        self.energy
    }

    /// Footprint: peak thickness above `threshold` m (row-major).
    pub fn footprint(&self, threshold: f64) -> Vec<bool> {
        self.peak_thickness.iter().map(|&h| h > threshold).collect()
    }

    /// Advances by one record interval (or less, to end exactly at `duration_s`), updates the
    /// peak fields and the stop test. Does nothing once the run has stopped.
    pub fn advance(
        &mut self,
        params: &AvalancheParams,
        options: &RunOptions,
    ) -> Result<AvalancheReport, AvalancheError> {
        self.advance_on(params, options, None)
    }

    /// [`AvalancheRun::advance`] for a state that reads its bed from `bed` where the flow
    /// goes.
    pub fn advance_on(
        &mut self,
        params: &AvalancheParams,
        options: &RunOptions,
        bed: Option<&dyn BedSource>,
    ) -> Result<AvalancheReport, AvalancheError> {
        options.validate()?;
        if self.stop.is_some() {
            return Ok(AvalancheReport::default());
        }
        let remaining = options.duration_s - self.time;
        let dt = options.record_interval_s.min(remaining);
        let (state, scratch) = (&mut self.state, &mut self.scratch);
        let report = match options.records {
            RecordTiming::Exact => step_on(params, state, scratch, dt, bed)?,
            RecordTiming::AtSubsteps => step_at_least(params, state, scratch, dt, remaining, bed)?,
        };
        // (A flow that came to rest within the interval ends it.)
        self.time += report.simulated_s.max(dt);
        self.substeps += report.substeps;
        self.border_outflow += report.border_outflow;
        self.state.settle_films(options.settle_thickness_m);
        self.record();
        self.stop = if self.state.active.is_none() {
            Some(StopReason::Empty)
        } else if !self.moving {
            Some(StopReason::AtRest)
        } else if options.stop_energy_fraction > 0.0
            && self.energy <= options.stop_energy_fraction * self.peak_energy
        {
            Some(StopReason::EnergyCriterion)
        } else if self.time >= options.duration_s * (1.0 - 1e-12) {
            Some(StopReason::Duration)
        } else {
            None
        };
        Ok(report)
    }

    /// [`AvalancheRun::advance_on`] over a layered terrain whose snowpack the flow entrains
    /// ([`crate::entrainment`], when `params.entrainment.enabled`): the run's one way forward
    /// on a terrain (the season, the editor, the command line).
    pub fn advance_over(
        &mut self,
        params: &AvalancheParams,
        options: &RunOptions,
        terrain: &mut LayeredTerrain,
    ) -> Result<AvalancheReport, AvalancheError> {
        let report = self.advance_on(params, options, Some(&*terrain))?;
        if params.entrainment.enabled && report.simulated_s > 0.0 {
            let n = self.state.geometry.width() * self.state.geometry.height();
            if terrain.geometry().len() != n {
                return Err(AvalancheError::LengthMismatch {
                    what: "terrain cells",
                    got: terrain.geometry().len(),
                    expected: n,
                });
            }
            self.entrained_volume += entrain(
                params,
                &mut self.state,
                terrain,
                EntrainedMaps {
                    total: &mut self.entrained,
                    stable: &mut self.entrained_stable,
                },
                report.simulated_s,
            );
        }
        Ok(report)
    }

    /// [`AvalancheRun::run_on`] over a layered terrain whose snowpack the flow entrains
    /// ([`AvalancheRun::advance_over`]).
    pub fn run_over<E: From<AvalancheError>>(
        &mut self,
        params: &AvalancheParams,
        options: &RunOptions,
        terrain: &mut LayeredTerrain,
        mut on_record: impl FnMut(&AvalancheRun) -> Result<(), E>,
    ) -> Result<RunSummary, E> {
        options.validate()?;
        while self.stop.is_none() {
            self.advance_over(params, options, terrain)?;
            on_record(self)?;
        }
        Ok(self.summary(options))
    }

    /// Advances until the run stops, calling `on_record` after every record interval (frames,
    /// progress, cancellation: an error from it ends the run and is returned).
    pub fn run<E: From<AvalancheError>>(
        &mut self,
        params: &AvalancheParams,
        options: &RunOptions,
        on_record: impl FnMut(&AvalancheRun) -> Result<(), E>,
    ) -> Result<RunSummary, E> {
        self.run_on(params, options, None, on_record)
    }

    /// [`AvalancheRun::run`] for a state that reads its bed from `bed` where the flow goes.
    pub fn run_on<E: From<AvalancheError>>(
        &mut self,
        params: &AvalancheParams,
        options: &RunOptions,
        bed: Option<&dyn BedSource>,
        mut on_record: impl FnMut(&AvalancheRun) -> Result<(), E>,
    ) -> Result<RunSummary, E> {
        options.validate()?;
        while self.stop.is_none() {
            self.advance_on(params, options, bed)?;
            on_record(self)?;
        }
        Ok(self.summary(options))
    }

    /// Updates peaks, energy and the moving flag over the active tiles.
    fn record(&mut self) {
        let r = self.state.record_peaks(
            crate::flow::Peaks {
                thickness: &mut self.peak_thickness,
                speed: &mut self.peak_speed,
            },
            &self.scratch,
        );
        self.energy = r.energy;
        self.peak_energy = self.peak_energy.max(r.energy);
        self.moving = r.moving;
    }

    /// The run's figures so far.
    pub fn summary(&self, options: &RunOptions) -> RunSummary {
        let g = &self.state.geometry;
        let w = g.width();
        let final_volume = self.state.total_volume();
        let input = self.released_volume + self.entrained_volume;
        let closure = if input > 0.0 {
            (input - final_volume - self.border_outflow).abs() / input
        } else {
            0.0
        };
        // Distances in local metres (the grid may be in degrees); reported points in map units.
        let point = |c: usize, r: usize| {
            let (x, y) = g.local_metres(c, r);
            [x, y, self.state.bed_at(c, r)]
        };
        let top_cell = self.release_top;
        let top = top_cell.map(|(c, r)| point(c, r));
        let mut runout = top;
        let mut runout_cell = top_cell;
        let mut footprint_cells = 0usize;
        let (mut best, mut best_i) = (-1.0, usize::MAX);
        let (mut max_speed, mut max_thickness) = (0.0f64, 0.0f64);
        // Over the touched tiles (the peaks are 0 elsewhere); the farthest cell, the first in
        // row-major order among equals.
        for (r0, r1, c0, c1) in self.state.touched_cells() {
            for r in r0..=r1 {
                for c in c0..=c1 {
                    let i = r * w + c;
                    let p = self.peak_thickness[i];
                    max_thickness = max_thickness.max(p);
                    max_speed = max_speed.max(self.peak_speed[i]);
                    if p > options.footprint_threshold_m {
                        footprint_cells += 1;
                        if let Some(t) = top {
                            let q = point(c, r);
                            let d = (q[0] - t[0]).hypot(q[1] - t[1]);
                            if d > best || (d == best && i < best_i) {
                                (best, best_i) = (d, i);
                                runout = Some(q);
                                runout_cell = Some((c, r));
                            }
                        }
                    }
                }
            }
        }
        let (top, runout) = (top.unwrap_or([0.0; 3]), runout.unwrap_or([0.0; 3]));
        let map_point = |cell: Option<(usize, usize)>, z: f64| match cell {
            Some((c, r)) => {
                let (x, y) = g.cell_centre(c, r);
                [x, y, z]
            }
            None => [0.0; 3],
        };
        let runout_length = (runout[0] - top[0]).hypot(runout[1] - top[1]);
        let runout_drop = top[2] - runout[2];
        let end = mass_centre(&self.state);
        let start = self.start_centre;
        let travel = (end[0] - start[0]).hypot(end[1] - start[1]);
        let drop = start[2] - end[2];
        let angle = |dz: f64, l: f64| {
            if l > 0.0 {
                dz.atan2(l).to_degrees()
            } else {
                90.0
            }
        };
        RunSummary {
            released_volume_m3: self.released_volume,
            final_volume_m3: final_volume,
            border_outflow_m3: self.border_outflow,
            entrained_volume_m3: self.entrained_volume,
            volume_closure_rel: closure,
            simulated_s: self.time,
            substeps: self.substeps,
            stop: self.stop,
            max_speed_m_s: max_speed,
            max_thickness_m: max_thickness,
            footprint_area_m2: footprint_cells as f64 * g.cell_area(),
            runout_length_m: runout_length,
            runout_drop_m: runout_drop,
            alpha_angle_deg: angle(runout_drop, runout_length),
            centre_travel_m: travel,
            centre_drop_m: drop,
            travel_angle_deg: angle(drop, travel),
            release_top: map_point(top_cell, top[2]),
            runout_point: map_point(runout_cell, runout[2]),
        }
    }
}

/// Volume-weighted centre of the avalanche's snow (flowing and settled): local metres east
/// and south of the grid's north-west corner and the bed altitude under it, m. Sums over the
/// touched tiles (all of the avalanche's snow lies in them), tile by tile.
fn mass_centre(state: &AvalancheState) -> [f64; 3] {
    let g = &state.geometry;
    let (mut sx, mut sy, mut sz, mut sv) = (0.0, 0.0, 0.0, 0.0);
    for (r0, r1, c0, c1) in state.touched_cells() {
        for r in r0..=r1 {
            for c in c0..=c1 {
                let h = state.snow_at(c, r);
                if h > 0.0 {
                    let (x, y) = g.local_metres(c, r);
                    sx += h * x;
                    sy += h * y;
                    sz += h * state.bed_at(c, r);
                    sv += h;
                }
            }
        }
    }
    if sv > 0.0 {
        [sx / sv, sy / sv, sz / sv]
    } else {
        [0.0; 3]
    }
}
