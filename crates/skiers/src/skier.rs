//! One skier: an agent with a position and a heading that follows the coarse path cell by
//! cell and draws its refined track (Cordonnier et al. 2018, Sections 6.2 and 7.3).
//!
//! **Motion.** A step of `dt` seconds moves the skier `speed·dt` metres along its heading, in
//! sub-steps of at most half a cell. Each sub-step first turns the heading towards the centre of
//! the target cell by the share `1 − exp(−δ/turn_distance)` of the angle between them (the
//! paper's "smooth transition to the new steering direction"), then moves. Entering a new cell
//! re-evaluates the steering ([`crate::steering`]), so the coarse path is re-planned once per
//! cell, as the paper's GPU version moves skiers cell by cell.
//!
//! **Staying on snow.** A sub-step that would enter a cell that is neither skiable nor a
//! terminus (or leave the grid) is not taken: the skier re-aims at one of its 4 edge
//! neighbours and heads straight for its centre; from anywhere in a cell, the straight line to
//! an edge neighbour's centre crosses only those two cells, so every accepted position lies on
//! a skiable cell (or a terminus).
//!
//! **Stopping.** A skier stops on entering a terminus, when no candidate has a positive weight
//! (stuck), when it travelled three cell diagonals without leaving a cell (circling), or after
//! [`crate::SkiParams::max_run_length_m`].

use crate::frame::SnowView;
use crate::refine::{SineTrack, turn_frequency};
use crate::steering::{Aim, Pose, SteeringRule, choose};
use crate::terminus::TerminusMap;
use serde::{Deserialize, Serialize};
use snowscape_terrain::random::uniform;

/// Why a skier stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// It reached a terminus.
    Terminus,
    /// No look-ahead cell was acceptable, or it circled inside one cell.
    Stuck,
    /// It travelled `max_run_length_m`.
    MaxLength,
}

/// One steering decision along a track.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SteeringChoice {
    /// The cell the skier was in (row-major index).
    pub cell: usize,
    /// The cell it aimed at.
    pub target: usize,
    /// Slope `s_n` towards the target, radians (downhill positive).
    pub slope_rad: f32,
    /// Turn frequency of the refined track on that segment, 1/m.
    pub frequency: f32,
}

/// The record of one skier's run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Track {
    /// Skier id.
    pub id: u64,
    /// Simulation time at the start, s.
    pub start_time_s: f64,
    /// Simulation time at the stop, s (`None` while skiing).
    pub end_time_s: Option<f64>,
    /// Why it stopped (`None` while skiing).
    pub stop: Option<StopReason>,
    /// Refined-track vertices, local metres (x east, y south of the north-west corner), at
    /// about `vertex_spacing_m` apart, first and last point included.
    pub vertices: Vec<[f64; 2]>,
    /// Horizontal length of the refined track, m.
    pub length_m: f64,
    /// Horizontal length of the coarse path, m.
    pub coarse_length_m: f64,
    /// Cells entered, in order (the coarse path), start cell first.
    pub cells: Vec<usize>,
    /// Steering decisions, in order.
    pub choices: Vec<SteeringChoice>,
}

/// What a skier did during a step, applied to the terrain afterwards in skier order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Event {
    /// A refined-track segment to draw, local metres.
    Segment((f64, f64), (f64, f64)),
    /// The skier left (or stopped in) `cell` after `length_m` of refined track there; `pass`
    /// numbers the skier's passes (the key of its trigger draw).
    Pass {
        cell: usize,
        length_m: f64,
        time_s: f64,
        pass: u64,
    },
}

/// Per-step constants shared by all skiers.
pub(crate) struct StepContext<'a> {
    pub view: SnowView<'a>,
    pub map: &'a TerminusMap,
    pub rule: SteeringRule,
    pub seed: u64,
    pub speed: f64,
    pub turn_distance: f64,
    pub target_slope: f64,
    pub amplitude: f64,
    pub min_frequency: f64,
    pub vertex_spacing: f64,
    pub max_run: f64,
    pub time0: f64,
}

/// Key purpose of steering draws.
pub(crate) const STEER: u64 = 0x5354_4545_5231;

/// A skier on the slope (serialized whole into a season's checkpoint: every field steers
/// the rest of its run).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Skier {
    pub(crate) pos: (f64, f64),
    pub(crate) heading: (f64, f64),
    pub(crate) cell: (usize, usize),
    pub(crate) target: (usize, usize),
    pub(crate) direct: bool,
    pub(crate) sine: SineTrack,
    pub(crate) fine: (f64, f64),
    pub(crate) last_vertex: (f64, f64),
    pub(crate) in_cell_length: f64,
    pub(crate) in_cell_travel: f64,
    pub(crate) decisions: u64,
    pub(crate) passes: u64,
    pub(crate) track: Track,
}

impl Skier {
    /// A skier at local position `pos` in `cell` with unit heading `heading`.
    pub(crate) fn new(
        id: u64,
        time_s: f64,
        pos: (f64, f64),
        cell: (usize, usize),
        heading: (f64, f64),
        amplitude: f64,
        width: usize,
    ) -> Self {
        Self {
            pos,
            heading,
            cell,
            target: cell,
            direct: false,
            sine: SineTrack {
                amplitude_m: amplitude,
                frequency: 0.0,
                phase: 0.0,
            },
            fine: pos,
            last_vertex: pos,
            in_cell_length: 0.0,
            in_cell_travel: 0.0,
            decisions: 0,
            passes: 0,
            track: Track {
                id,
                start_time_s: time_s,
                end_time_s: None,
                stop: None,
                vertices: vec![[pos.0, pos.1]],
                length_m: 0.0,
                coarse_length_m: 0.0,
                cells: vec![cell.1 * width + cell.0],
                choices: Vec::new(),
            },
        }
    }

    /// Skier id.
    pub fn id(&self) -> u64 {
        self.track.id
    }
    /// Position, local metres (x east, y south of the north-west corner).
    pub fn position(&self) -> (f64, f64) {
        self.pos
    }
    /// Unit heading in the local frame.
    pub fn heading(&self) -> (f64, f64) {
        self.heading
    }
    /// Current cell `(col, row)`.
    pub fn cell(&self) -> (usize, usize) {
        self.cell
    }
    /// The run so far.
    pub fn track(&self) -> &Track {
        &self.track
    }
    /// Whether the skier has stopped.
    pub fn stopped(&self) -> bool {
        self.track.stop.is_some()
    }

    /// Re-plans from the current cell; false when stuck.
    pub(crate) fn steer(&mut self, ctx: &StepContext, orthogonal_only: bool) -> bool {
        let u = uniform(ctx.seed ^ STEER, self.track.id, self.decisions);
        self.decisions += 1;
        let pose = Pose {
            cell: self.cell,
            pos: self.pos,
            heading: self.heading,
        };
        let aim = choose(&ctx.rule, &ctx.view, ctx.map, &pose, u, orthogonal_only);
        let Some(Aim { cell, slope }) = aim else {
            return false;
        };
        self.target = cell;
        let f = turn_frequency(slope, ctx.target_slope, ctx.amplitude).max(ctx.min_frequency);
        self.sine.frequency = f;
        let w = ctx.view.width;
        self.track.choices.push(SteeringChoice {
            cell: self.cell.1 * w + self.cell.0,
            target: cell.1 * w + cell.0,
            slope_rad: slope as f32,
            frequency: f as f32,
        });
        true
    }

    fn finish(&mut self, reason: StopReason, time_s: f64, events: &mut Vec<Event>) {
        self.close_pass(time_s, events);
        if self.last_vertex != self.fine {
            self.track.vertices.push([self.fine.0, self.fine.1]);
            self.last_vertex = self.fine;
        }
        self.track.stop = Some(reason);
        self.track.end_time_s = Some(time_s);
    }

    fn close_pass(&mut self, time_s: f64, events: &mut Vec<Event>) {
        events.push(Event::Pass {
            cell: self.track.cells.last().copied().unwrap_or(0),
            length_m: self.in_cell_length,
            time_s,
            pass: self.passes,
        });
        self.passes += 1;
        self.in_cell_length = 0.0;
        self.in_cell_travel = 0.0;
    }

    /// Stops a skier that starts on a terminus (or cannot steer) before its first move.
    pub(crate) fn stop_now(&mut self, reason: StopReason, time_s: f64) {
        self.track.stop = Some(reason);
        self.track.end_time_s = Some(time_s);
    }

    /// Moves the skier for `dt` seconds, pushing its segments and passes into `events`.
    pub(crate) fn advance(&mut self, ctx: &StepContext, dt: f64, events: &mut Vec<Event>) {
        if self.stopped() {
            return;
        }
        let view = &ctx.view;
        let max_sub = 0.5 * view.dx.min(view.dy);
        let stuck_travel = 3.0 * view.dx.hypot(view.dy);
        let mut remaining = ctx.speed * dt;
        let mut time = ctx.time0;
        while remaining > 0.0 {
            let delta = remaining.min(max_sub);
            let (tx, ty) = view.centre(self.target.0, self.target.1);
            let (vx, vy) = (tx - self.pos.0, ty - self.pos.1);
            let len = (vx * vx + vy * vy).sqrt();
            let mut h = self.heading;
            if len > 1e-9 {
                let (dx, dy) = (vx / len, vy / len);
                if self.direct {
                    h = (dx, dy);
                } else {
                    let angle = (h.0 * dy - h.1 * dx).atan2(h.0 * dx + h.1 * dy);
                    let turn = angle * (1.0 - (-delta / ctx.turn_distance).exp());
                    let (s, c) = turn.sin_cos();
                    h = (h.0 * c - h.1 * s, h.0 * s + h.1 * c);
                }
            }
            let next = (self.pos.0 + delta * h.0, self.pos.1 + delta * h.1);
            let next_cell = view.cell_of(next.0, next.1);
            let ok = next_cell.is_some_and(|(c, r)| {
                (c, r) == self.cell || {
                    let j = r * view.width + c;
                    view.skiable(j) || ctx.map.is_terminus(j)
                }
            });
            if !ok {
                if self.direct || !self.steer(ctx, true) {
                    self.finish(StopReason::Stuck, time, events);
                    return;
                }
                self.direct = true;
                continue;
            }
            let next_cell = next_cell.expect("checked above");
            self.heading = h;
            self.pos = next;
            let fine_old = self.fine;
            self.sine.advance(delta);
            self.fine = self.sine.point(next.0, next.1, h.0, h.1);
            let (sx, sy) = (self.fine.0 - fine_old.0, self.fine.1 - fine_old.1);
            let seg = (sx * sx + sy * sy).sqrt();
            events.push(Event::Segment(fine_old, self.fine));
            self.track.length_m += seg;
            self.track.coarse_length_m += delta;
            self.in_cell_length += seg;
            self.in_cell_travel += delta;
            let (lx, ly) = self.last_vertex;
            let (ex, ey) = (self.fine.0 - lx, self.fine.1 - ly);
            if ex * ex + ey * ey >= ctx.vertex_spacing * ctx.vertex_spacing {
                self.track.vertices.push([self.fine.0, self.fine.1]);
                self.last_vertex = self.fine;
            }
            remaining -= delta;
            time += delta / ctx.speed;
            if next_cell != self.cell {
                self.close_pass(time, events);
                self.cell = next_cell;
                self.direct = false;
                let j = next_cell.1 * view.width + next_cell.0;
                self.track.cells.push(j);
                if ctx.map.is_terminus(j) {
                    self.finish(StopReason::Terminus, time, events);
                    return;
                }
                if !self.steer(ctx, false) {
                    self.finish(StopReason::Stuck, time, events);
                    return;
                }
            } else if self.in_cell_travel > stuck_travel {
                self.finish(StopReason::Stuck, time, events);
                return;
            }
            if self.track.coarse_length_m >= ctx.max_run {
                self.finish(StopReason::MaxLength, time, events);
                return;
            }
        }
    }
}
