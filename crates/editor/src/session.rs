//! The editor's one shared state: a season in progress ([`Winter`]), its timeline of snapshots,
//! the brushes' undo and redo stacks, the painted maps, and the live avalanche or skier.
//!
//! Cordonnier et al. 2018, Section 3: "any point on the simulation time-line" can be edited
//! with brushes, the scenario and the parameters, or by triggering avalanches and skiers. The
//! session is free of I/O: [`Session::handle`] turns a [`ClientMessage`] into [`Out`]puts for
//! every tab or for the sender alone, and [`Session::tick`] advances a live event by one frame;
//! the server ([`crate::server`]) moves them over the network. Long work (a season step, a
//! scenario change, a load, an export) is a [`crate::job::Job`] that [`Session::start`] hands
//! out and [`Session::finish_job`] takes back, so that the server can run it on a worker.

use crate::brush::{self, CellRect, Dab, Edit, PaintMaps};
use crate::history::Action;
use crate::job::{Job, JobOutcome, JobProgress, RunningJob};
use crate::live::{LiveAvalanche, LiveSkiers, skier_progress, tiles_near};
use crate::protocol::{BrushTarget, ClientMessage, ErrorCode, ServerMessage};
use crate::timeline::Timeline;
use crate::wire::{self, Channel, Field, Quant, TILE};
use serde::{Deserialize, Serialize};
use snowscape_season::scenario::WeatherPeriod;
use snowscape_season::winter::Winter;
use snowscape_skiers::{SkiArea, SkiScratch};
use snowscape_terrain::{LayeredTerrain, SnowLayer};
use std::path::Path;
use std::sync::Arc;

mod messages;

/// A message on its way out.
#[derive(Debug, Clone, PartialEq)]
pub enum Outgoing {
    Text(String),
    Binary(Vec<u8>),
}

/// An output and who gets it.
#[derive(Debug, Clone, PartialEq)]
pub enum Out {
    /// Every connected tab (the state changed).
    All(Outgoing),
    /// The tab that sent the message.
    Sender(Outgoing),
}

/// A refused request: the reply's code and message.
pub type Refusal = (ErrorCode, String);

/// What [`Session::start`] made of a message.
pub enum Started {
    /// Handled: the outputs.
    Done(Vec<Out>),
    /// A job for a worker, and the outputs to send now (its `started` message).
    Job(Job, Vec<Out>),
}

/// Writes the outputs of `snowscape run` for a season state into a folder; returns the
/// written file names (the command-line front end supplies it).
pub type Exporter = dyn Fn(&Winter, &Path) -> Result<Vec<String>, String> + Send + Sync;

/// Local solar time of the sun the page lights its view with, hours: mid-morning, low enough
/// in winter to model the relief with shadows.
pub const VIEW_SOLAR_HOUR: f64 = 10.5;

/// The direction towards the sun `[east, north, up]` on the season's current day at
/// [`VIEW_SOLAR_HOUR`].
fn view_sun(winter: &Winter) -> [f64; 3] {
    use snowscape_environment::solar::{DeclinationModel, declination, hour_angle, sun_vector};
    let start = snowscape_season::scenario::day_of_year(&winter.scenario().start_date).unwrap_or(1);
    let doy = ((f64::from(start) - 1.0 + winter.day()).rem_euclid(365.0) + 1.0).floor() as u32;
    let dec = declination(doy.clamp(1, 365), DeclinationModel::Spencer);
    sun_vector(winter.latitude_deg(), dec, hour_angle(VIEW_SOLAR_HOUR))
}

/// Memory the brushes' undo and redo history may take by default, bytes (256 MiB: about 10 M
/// recorded values, a stroke on the total depth over every cell of a 1024² terrain being
/// 4 M). Past it the oldest strokes are dropped first (they can no longer be undone); a stroke
/// that alone exceeds it is not recorded and cannot be undone. Every tab is told.
pub const UNDO_BUDGET_BYTES: u64 = 256 << 20;

/// The state summary every tab shows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StateSummary {
    pub width: usize,
    pub height: usize,
    pub cell_size_m: f64,
    /// Where the terrain came from.
    pub source: String,
    pub day: f64,
    pub season_days: f64,
    /// Days of the timeline's snapshots, and the one shown.
    pub snapshots: Vec<f64>,
    pub current: usize,
    pub undo: usize,
    pub redo: usize,
    /// A live avalanche or skier, or a job, is running (season steps wait).
    pub busy: bool,
    /// The running job (a season step, a scenario change, a load, an export), if any.
    pub job: Option<JobProgress>,
    /// Avalanches of the season so far (not counting live ones).
    pub season_avalanches: usize,
    /// The scenario (weather timeline, Table 2 parameters), as JSON.
    pub scenario: serde_json::Value,
    /// The resolved weather timeline.
    pub weather: Vec<WeatherPeriod>,
    /// Snow volume, m³.
    pub snow_volume_m3: f64,
    /// Latitude the season runs at, degrees north.
    pub latitude_deg: f64,
    /// Unit vector towards the sun `[east, north, up]` the page lights the view with: the
    /// season's date and latitude at [`VIEW_SOLAR_HOUR`] (Spencer's declination, as the
    /// precompute's sun).
    pub sun: [f64; 3],
    /// The snapshots' memory budget and their estimated memory, bytes; snapshots dropped
    /// for the budget so far (the oldest, never the first).
    pub snapshot_budget_bytes: u64,
    pub snapshot_bytes: u64,
    pub snapshots_dropped: usize,
}

/// Values at one cell (reply to `probe`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellValues {
    pub col: usize,
    pub row: usize,
    pub bedrock: f32,
    /// Compacted, stable, unstable, powder, m.
    pub layers: [f32; 4],
    pub depth: f32,
    pub avalanche_probability: f32,
    pub ski_area: f32,
}

/// The session.
pub struct Session {
    pub(crate) winter: Winter,
    pub(crate) paint: PaintMaps,
    pub(crate) timeline: Timeline,
    undo: Vec<Edit>,
    redo: Vec<Edit>,
    /// Memory the undo and redo history may take, bytes.
    undo_budget: u64,
    /// The stroke that went past the undo budget (not recorded).
    unrecorded_stroke: Option<u32>,
    seq: u32,
    bedrock_quant: Quant,
    pub(crate) source: String,
    pub(crate) avalanche: Option<LiveAvalanche>,
    pub(crate) skiers: Option<LiveSkiers>,
    /// Skier descents in progress.
    pub(crate) skiing: bool,
    /// The job running on a worker, and the last job's number.
    pub(crate) job: Option<RunningJob>,
    pub(crate) job_seq: u64,
    /// What the user did, in order (saved with the project).
    pub(crate) history: Vec<crate::history::Action>,
}

fn refuse<T>(code: ErrorCode, message: impl Into<String>) -> Result<T, Refusal> {
    Err((code, message.into()))
}

fn text(m: &ServerMessage) -> Outgoing {
    Outgoing::Text(m.to_json())
}

impl Session {
    /// A session on a season (day 0 is the first snapshot).
    pub fn new(winter: Winter, source: impl Into<String>) -> Self {
        let n = winter.terrain.geometry().len();
        Self::with_paint(winter, PaintMaps::new(n), source)
    }

    pub(crate) fn with_paint(winter: Winter, paint: PaintMaps, source: impl Into<String>) -> Self {
        let bedrock_quant = Quant::spanning(&winter.terrain.bedrock);
        let timeline = Timeline::new(&winter, &paint);
        Self {
            winter,
            paint,
            timeline,
            undo: Vec::new(),
            redo: Vec::new(),
            undo_budget: UNDO_BUDGET_BYTES,
            unrecorded_stroke: None,
            seq: 0,
            bedrock_quant,
            source: source.into(),
            avalanche: None,
            skiers: None,
            skiing: false,
            job: None,
            job_seq: 0,
            history: Vec::new(),
        }
    }

    /// Sets the memory the timeline's snapshots may take, bytes (kept across scenario
    /// changes and loads); the oldest snapshots past it are dropped.
    pub fn set_snapshot_budget(&mut self, bytes: u64) {
        self.timeline.set_budget(bytes);
    }

    /// Sets the memory the undo and redo history may take, bytes; the oldest strokes past it
    /// are dropped.
    pub fn set_undo_budget(&mut self, bytes: u64) {
        self.undo_budget = bytes;
        self.enforce_undo_budget(None);
    }

    /// Estimated memory of the undo and redo history, bytes.
    pub fn undo_bytes(&self) -> u64 {
        self.undo.iter().chain(&self.redo).map(Edit::bytes).sum()
    }

    /// Drops the oldest strokes (redo first, then undo) until the history fits its budget;
    /// the notice for every tab, if any went. When `stroke` (the one in progress) is dropped
    /// too, it goes on unrecorded.
    fn enforce_undo_budget(&mut self, stroke: Option<u32>) -> Option<Out> {
        let mut total = self.undo_bytes();
        if total <= self.undo_budget {
            return None;
        }
        let mut dropped = 0usize;
        while total > self.undo_budget {
            let e = if self.redo.is_empty() {
                if self.undo.is_empty() {
                    break;
                }
                self.undo.remove(0)
            } else {
                self.redo.remove(0)
            };
            total -= e.bytes().min(total);
            dropped += 1;
            if self.undo.is_empty() && self.redo.is_empty() && stroke == Some(e.stroke) {
                // The stroke in progress alone was past the budget: it goes unrecorded.
                self.unrecorded_stroke = stroke;
            }
        }
        let message = format!(
            "the undo history keeps at most {} MiB: {dropped} oldest stroke(s) dropped{}",
            self.undo_budget >> 20,
            if stroke.is_some() && self.unrecorded_stroke == stroke {
                " (this stroke alone is larger: it cannot be undone)"
            } else {
                ""
            }
        );
        tracing::info!("{message}");
        Some(Out::All(text(&ServerMessage::Notice { message })))
    }

    /// Replaces this session by `next` (a new scenario, a loaded project), keeping the
    /// snapshot budget and the job numbers.
    pub(crate) fn replace_with(&mut self, mut next: Session) {
        next.undo_budget = self.undo_budget;
        next.set_snapshot_budget(self.timeline.budget_bytes());
        next.job_seq = self.job_seq;
        *self = next;
    }

    /// The notice (to every tab, and the log) that `dropped` old snapshots went for the
    /// memory budget.
    pub(crate) fn dropped_notice(&self, dropped: usize) -> Option<Out> {
        if dropped == 0 {
            return None;
        }
        let t = &self.timeline;
        let message = format!(
            "{dropped} old snapshot(s) dropped to keep the timeline within its memory budget of {} MiB ({} snapshots of {:.1} MiB kept; the first one stays)",
            t.budget_bytes() >> 20,
            t.len(),
            t.bytes() as f64 / t.len().max(1) as f64 / (1u64 << 20) as f64,
        );
        tracing::info!("{message}");
        Some(Out::All(text(&ServerMessage::Notice { message })))
    }

    /// The timeline of snapshots.
    pub fn timeline(&self) -> &Timeline {
        &self.timeline
    }

    /// The season being edited.
    pub fn winter(&self) -> &Winter {
        &self.winter
    }

    /// The painted maps.
    pub fn paint(&self) -> &PaintMaps {
        &self.paint
    }

    /// Whether a live event is running ([`Session::tick`] advances it).
    pub fn live(&self) -> bool {
        self.avalanche.is_some() || self.skiing
    }

    /// Whether a live event or a job is running (the season waits).
    pub fn busy(&self) -> bool {
        self.live() || self.job.is_some()
    }

    /// The state summary.
    pub fn summary(&self) -> StateSummary {
        let g = self.winter.terrain.geometry();
        StateSummary {
            width: g.width(),
            height: g.height(),
            cell_size_m: g.cell_size_x(),
            source: self.source.clone(),
            day: self.winter.day(),
            season_days: self.winter.scenario().days,
            snapshots: self.timeline.days(),
            current: self.timeline.current(),
            undo: self.undo.len(),
            redo: self.redo.len(),
            busy: self.busy(),
            job: self.job().cloned(),
            season_avalanches: self.winter.avalanches().len(),
            scenario: serde_json::to_value(self.winter.scenario()).unwrap_or_default(),
            weather: self.winter.weather().to_vec(),
            snow_volume_m3: self.winter.terrain.snow_volume(),
            latitude_deg: self.winter.latitude_deg(),
            sun: view_sun(&self.winter),
            snapshot_budget_bytes: self.timeline.budget_bytes(),
            snapshot_bytes: self.timeline.bytes(),
            snapshots_dropped: self.timeline.dropped(),
        }
    }

    /// Values at a cell.
    pub fn probe(&self, col: usize, row: usize) -> Result<CellValues, Refusal> {
        let t = &self.winter.terrain;
        let g = t.geometry();
        if col >= g.width() || row >= g.height() {
            return refuse(
                ErrorCode::InvalidValue,
                format!(
                    "cell ({col}, {row}) is outside the {}x{} grid",
                    g.width(),
                    g.height()
                ),
            );
        }
        let i = g.index(col, row);
        Ok(CellValues {
            col,
            row,
            bedrock: t.bedrock[i],
            layers: SnowLayer::ALL.map(|l| t.layer(l)[i]),
            depth: t.depth_at(i),
            avalanche_probability: self.paint.avalanche_probability[i],
            ski_area: self.paint.ski_area[i],
        })
    }

    fn next_seq(&mut self) -> u32 {
        self.seq = self.seq.wrapping_add(1);
        self.seq
    }

    /// A frame of `tiles` of one channel (`None` for all tiles).
    fn frame(&mut self, channel: Channel, tiles: Option<&[(usize, usize)]>) -> Option<Outgoing> {
        let seq = self.next_seq();
        let t = &self.winter.terrain;
        let g = t.geometry();
        let (w, h) = (g.width(), g.height());
        let env = self.winter.environment();
        let wind: Vec<f32>;
        let masked: Vec<f32>;
        let (values, quant): (&[f32], Quant) = match channel {
            // Nodata cells go out as the wire's nodata code, so the page does not draw them.
            Channel::Bedrock => match t.mask().invalid_cells() {
                Some(invalid) => {
                    masked = t
                        .bedrock
                        .iter()
                        .zip(invalid)
                        .map(|(&z, &bad)| if bad { f32::NAN } else { z })
                        .collect();
                    (&masked, self.bedrock_quant)
                }
                None => (&t.bedrock, self.bedrock_quant),
            },
            Channel::Compacted => (t.layer(SnowLayer::Compacted), Quant::THICKNESS),
            Channel::Stable => (t.layer(SnowLayer::Stable), Quant::THICKNESS),
            Channel::Unstable => (t.layer(SnowLayer::Unstable), Quant::THICKNESS),
            Channel::Powder => (t.layer(SnowLayer::Powder), Quant::THICKNESS),
            Channel::Temperature => (&env.temperature, Quant::spanning(&env.temperature)),
            Channel::Sun => (&env.sun, Quant::spanning(&env.sun)),
            Channel::Wind => {
                wind = env
                    .wind_u
                    .iter()
                    .zip(&env.wind_v)
                    .map(|(u, v)| u.hypot(*v))
                    .collect();
                (&wind, Quant::spanning(&wind))
            }
            Channel::AvalancheProbability => (&self.paint.avalanche_probability, Quant::UNIT),
            Channel::SkiArea => (&self.paint.ski_area, Quant::UNIT),
            Channel::Flow => return None,
        };
        let all;
        let tiles = match tiles {
            Some(t) => t,
            None => {
                all = wire::all_tiles(w, h);
                &all
            }
        };
        let field = Field {
            channel,
            values,
            width: w,
            height: h,
            quant,
        };
        let (tw, th) = wire::tile_counts(w, h);
        wire::encode_tiles(&field, tiles, tiles.len() == tw * th, seq)
            .ok()
            .map(Outgoing::Binary)
    }

    pub(crate) fn layer_frames(&mut self, tiles: &[(usize, usize)]) -> Vec<Out> {
        if tiles.is_empty() {
            return Vec::new();
        }
        Channel::LAYERS
            .iter()
            .filter_map(|&c| self.frame(c, Some(tiles)))
            .map(Out::All)
            .collect()
    }

    pub(crate) fn state_out(&self) -> Out {
        Out::All(text(&ServerMessage::State(Box::new(self.summary()))))
    }

    /// Everything a tab needs: the state and every channel in full.
    pub fn full_state(&mut self) -> Vec<Outgoing> {
        let mut v = vec![text(&ServerMessage::State(Box::new(self.summary())))];
        for c in [
            Channel::Bedrock,
            Channel::Compacted,
            Channel::Stable,
            Channel::Unstable,
            Channel::Powder,
            Channel::Temperature,
            Channel::Sun,
            Channel::Wind,
            Channel::AvalancheProbability,
            Channel::SkiArea,
        ] {
            v.extend(self.frame(c, None));
        }
        v
    }

    pub(crate) fn everything(&mut self) -> Vec<Out> {
        self.full_state().into_iter().map(Out::All).collect()
    }

    fn tiles_of_rect(r: CellRect) -> Vec<(usize, usize)> {
        (r.r0 / TILE..=r.r1 / TILE)
            .flat_map(|ty| (r.c0 / TILE..=r.c1 / TILE).map(move |tx| (tx, ty)))
            .collect()
    }

    fn rect_frames(&mut self, target: BrushTarget, rect: CellRect) -> Vec<Out> {
        let tiles = Self::tiles_of_rect(rect);
        match target {
            BrushTarget::AvalancheProbability => self
                .frame(Channel::AvalancheProbability, Some(&tiles))
                .map(Out::All)
                .into_iter()
                .collect(),
            BrushTarget::SkiArea => self
                .frame(Channel::SkiArea, Some(&tiles))
                .map(Out::All)
                .into_iter()
                .collect(),
            _ => self.layer_frames(&tiles),
        }
    }

    /// What the user did in this session, in order (a saved project's `history.json`).
    pub fn history(&self) -> &[Action] {
        &self.history
    }

    pub(crate) fn log(&mut self, entry: crate::history::Action) {
        self.history.push(entry);
    }

    /// Forgets undo and redo (the season moved on, or a live event changed the snow).
    pub(crate) fn clear_undo(&mut self) {
        self.undo.clear();
        self.redo.clear();
    }

    /// Handles one message at once, running any job it starts on this thread (tests, and
    /// callers without a network); `export` writes outputs, `project` is the project folder.
    pub fn handle(
        &mut self,
        msg: ClientMessage,
        project: Option<&crate::project::ProjectDir>,
        export: Option<&Arc<Exporter>>,
    ) -> Result<Vec<Out>, Refusal> {
        match self.start(msg, project, export)? {
            Started::Done(out) => Ok(out),
            Started::Job(job, mut out) => {
                let id = job.id();
                match job.run(&mut |_| {}) {
                    // A failed job is a refusal, as at once.
                    JobOutcome::Failed(refusal) => {
                        self.finish_job(id, JobOutcome::Failed(refusal.clone()));
                        Err(refusal)
                    }
                    outcome => {
                        out.extend(self.finish_job(id, outcome));
                        Ok(out)
                    }
                }
            }
        }
    }

    /// Why `msg` must wait, if it must: while a job runs only `probe`, `resync` and `cancel`
    /// are answered; while a live event runs, brushes too.
    fn busy_refusal(&self, msg: &ClientMessage) -> Option<Refusal> {
        let reads = matches!(
            msg,
            ClientMessage::Probe { .. } | ClientMessage::Resync {} | ClientMessage::Cancel {}
        );
        if reads {
            return None;
        }
        if let Some(j) = self.job() {
            return Some((
                ErrorCode::Busy,
                format!(
                    "{} is running ({}); send cancel to stop it, or try again when it ends",
                    j.kind.describe(),
                    j.message
                ),
            ));
        }
        (self.live() && !matches!(msg, ClientMessage::Brush { .. })).then(|| {
            (
                ErrorCode::Busy,
                "a live avalanche or skier is running; send cancel to stop it, or try again when it ends"
                    .to_string(),
            )
        })
    }

    /// Handles one message: at once ([`Started::Done`]), or as a [`Job`] for a worker
    /// ([`Started::Job`], with the job's `started` message) whose outcome goes to
    /// [`Session::finish_job`]. `export` writes outputs, `project` is the project folder.
    pub fn start(
        &mut self,
        msg: ClientMessage,
        project: Option<&crate::project::ProjectDir>,
        export: Option<&Arc<Exporter>>,
    ) -> Result<Started, Refusal> {
        msg.validate().map_err(|e| (e.code(), e.to_string()))?;
        if let Some(refusal) = self.busy_refusal(&msg) {
            return Err(refusal);
        }
        let job = |r: Result<(Job, Vec<Out>), Refusal>| r.map(|(j, o)| Started::Job(j, o));
        let done = match msg {
            ClientMessage::Brush {
                stroke,
                op,
                target,
                col,
                row,
                radius_m,
                strength,
                value,
            } => self.brush(
                stroke,
                Dab {
                    op,
                    target,
                    col,
                    row,
                    radius_m,
                    strength,
                    value,
                },
            ),
            ClientMessage::Undo {} => self.undo_or_redo(true),
            ClientMessage::Redo {} => self.undo_or_redo(false),
            ClientMessage::Step { days } => return job(self.step_job(days)),
            ClientMessage::Seek { index } => self.seek(index),
            ClientMessage::TriggerAvalanche { col, row } => self.trigger_avalanche(col, row),
            ClientMessage::LaunchSkier { col, row } => self.launch_skier(col, row),
            ClientMessage::SetScenario { scenario } => {
                return job(self.scenario_job(scenario, project));
            }
            ClientMessage::Save { name } => return job(self.save_job(name, project)),
            ClientMessage::Load { name } => return job(self.load_job(name, project)),
            ClientMessage::Export { name } => return job(self.export_job(name, project, export)),
            ClientMessage::Cancel {} => self.cancel(),
            ClientMessage::Probe { col, row } => Ok(vec![Out::Sender(text(&ServerMessage::Cell(
                self.probe(col, row)?,
            )))]),
            ClientMessage::Resync {} => {
                Ok(self.full_state().into_iter().map(Out::Sender).collect())
            }
        };
        done.map(Started::Done)
    }

    fn launch_skier(&mut self, col: f64, row: f64) -> Result<Vec<Out>, Refusal> {
        let p = self.winter.scenario().skiers.clone();
        let t = &self.winter.terrain;
        let g = t.geometry().clone();
        if col.round() as usize >= g.width() || row.round() as usize >= g.height() {
            return refuse(
                ErrorCode::InvalidValue,
                format!("cell ({col}, {row}) is outside the grid"),
            );
        }
        if self.skiers.is_none() {
            let area = SkiArea::new(&p.ski, t, p.terminus.clone(), self.winter.scenario().seed)
                .map_err(|e| (ErrorCode::InvalidValue, format!("no skiing here: {e}")))?;
            self.skiers = Some(LiveSkiers {
                area,
                scratch: SkiScratch::default(),
                time_s: 0.0,
            });
        }
        let Some(s) = self.skiers.as_mut() else {
            return refuse(ErrorCode::Failed, "no ski area");
        };
        s.area
            .refresh_terminus(&p.ski, &self.winter.terrain)
            .map_err(|e| (ErrorCode::InvalidValue, format!("no skiing here: {e}")))?;
        let (x, y) = g.cell_centre(col.round() as usize, row.round() as usize);
        s.area
            .spawn_at(&p.ski, &self.winter.terrain, x, y)
            .map_err(|e| {
                (
                    ErrorCode::InvalidValue,
                    format!("no skier at ({col}, {row}): {e}"),
                )
            })?;
        s.time_s = 0.0;
        self.skiing = true;
        self.undo.clear();
        self.redo.clear();
        self.timeline.mark_edited();
        let progress = skier_progress(&s.area, &self.winter.terrain, 0.0);
        self.log(Action::Skier {
            col,
            row,
            day: self.winter.day(),
        });
        Ok(vec![
            Out::All(text(&ServerMessage::Skiers(progress))),
            self.state_out(),
        ])
    }

    /// Advances the live avalanche or skiers by one frame.
    pub fn tick(&mut self) -> Result<Vec<Out>, Refusal> {
        if let Some(mut live) = self.avalanche.take() {
            let (flow, tiles) = live
                .advance(&mut self.winter.terrain)
                .map_err(|e| (ErrorCode::Failed, e))?;
            let g = self.winter.terrain.geometry();
            let field = Field {
                channel: Channel::Flow,
                values: &flow,
                width: g.width(),
                height: g.height(),
                quant: Quant::THICKNESS,
            };
            let seq = self.next_seq();
            let mut out = Vec::new();
            if !tiles.is_empty() {
                let bytes = wire::encode_tiles(&field, &tiles, false, seq)
                    .map_err(|e| (ErrorCode::Failed, e.to_string()))?;
                out.push(Out::All(Outgoing::Binary(bytes)));
            }
            if live.finished() {
                let tiles = live
                    .finish(&mut self.winter.terrain)
                    .map_err(|e| (ErrorCode::Failed, e))?;
                out.extend(self.layer_frames(&tiles));
                out.push(Out::All(text(&ServerMessage::Avalanche(
                    live.progress.clone(),
                ))));
                out.push(self.state_out());
            } else {
                if live.progress.records % 5 == 1 {
                    out.push(Out::All(text(&ServerMessage::Avalanche(
                        live.progress.clone(),
                    ))));
                }
                self.avalanche = Some(live);
            }
            return Ok(out);
        }
        if self.skiing {
            return self.tick_skiers();
        }
        Ok(Vec::new())
    }

    fn tick_skiers(&mut self) -> Result<Vec<Out>, Refusal> {
        let p = self.winter.scenario().skiers.clone();
        let Some(s) = self.skiers.as_mut() else {
            self.skiing = false;
            return Ok(Vec::new());
        };
        let before = skier_progress(&s.area, &self.winter.terrain, s.time_s).positions;
        let r = snowscape_skiers::step(
            &p.ski,
            &mut s.area,
            &mut self.winter.terrain,
            &mut s.scratch,
            p.step_s,
        )
        .map_err(|e| (ErrorCode::Failed, e.to_string()))?;
        s.time_s += p.step_s;
        let progress = skier_progress(&s.area, &self.winter.terrain, s.time_s);
        let done = r.active == 0 || s.time_s >= p.max_run_s;
        let g = self.winter.terrain.geometry();
        let mut pts = before;
        pts.extend(progress.positions.iter().copied());
        let tiles = tiles_near(&pts, g.width(), g.height(), 2.0);
        let mut out = self.layer_frames(&tiles);
        out.push(Out::All(text(&ServerMessage::Skiers(progress))));
        if done {
            self.skiing = false;
            out.push(self.state_out());
        }
        Ok(out)
    }

    /// Runs the live event to its end (tests, and callers without a network).
    pub fn run_live_to_end(&mut self) -> Result<Vec<Out>, Refusal> {
        let mut out = Vec::new();
        while self.busy() {
            out.extend(self.tick()?);
        }
        Ok(out)
    }

    /// The terrain being edited.
    pub fn terrain(&self) -> &LayeredTerrain {
        &self.winter.terrain
    }
}
