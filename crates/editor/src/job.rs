//! Long work off the request path: a season step (days of the season, Cordonnier et al. 2018,
//! Section 5), a scenario change (the environment precompute of Section 4), loading and
//! saving a project and exporting the outputs.
//!
//! [`Session::start`] turns such a message into a [`Job`]: owned copies of what the work reads
//! (a fork of the season, the painted maps, the new scenario and the first snapshot's
//! terrain, ...), so that it runs on a worker thread while the session itself stays where it
//! was and keeps answering the tabs' `probe`, `resync`, state and cell requests. Requests
//! that would change the state are answered [`ErrorCode::Busy`] until the job ends. The worker
//! reports [`JobProgress`] (a step: the days done) and ends with a [`JobOutcome`] that
//! [`Session::finish_job`] installs.
//!
//! **A step** runs the season through the library's driver ([`snowscape::simulation`]), as
//! `snowscape run` and the Python package do: in [`STEP_SLICES`] chunks, the progress reported
//! every [`PROGRESS_INTERVAL`] of wall time.
//!
//! **Cancel.** A `cancel` message raises the job's flag: a step stops between two season
//! events (the flag is the driver's interrupt) and is dropped, so the season stays at the day
//! the step started from; a scenario change, a load or an export cannot
//! stop inside the season's precompute or the file writers, so their result is dropped when
//! they end (files an export wrote stay). `cancel` also ends a live avalanche (its flowing
//! snow deposits where it is) or a skier descent. Without a server, [`Session::handle`] runs
//! jobs at once on the calling thread.

use crate::brush::PaintMaps;
use crate::live::skier_progress;
use crate::project::{ProjectContents, ProjectDir, ProjectError};
use crate::protocol::{ErrorCode, ServerMessage};
use crate::session::{Exporter, Out, Outgoing, Refusal, Session};
use serde::{Deserialize, Serialize};
use snowscape::simulation::{Control, Schedule, Simulation, StopReason};
use snowscape_season::scenario::Scenario;
use snowscape_season::winter::Winter;
use snowscape_terrain::LayeredTerrain;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Most cells of a DEM imported from the page (4096², as a 64 MiB f32 grid and its season
/// state stay well within a workstation's memory).
pub const MAX_IMPORT_CELLS: usize = 4096 * 4096;

/// Chunks of a season step (the driver's chunk is the step's length over this).
pub const STEP_SLICES: usize = 100;
/// Shortest wall time between two progress reports of a job.
pub const PROGRESS_INTERVAL: Duration = Duration::from_millis(100);

/// What a job does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JobKind {
    Step,
    SetScenario,
    Load,
    Export,
    Save,
    Import,
}

impl JobKind {
    /// The job in words.
    pub fn describe(self) -> &'static str {
        match self {
            JobKind::Step => "a season step",
            JobKind::SetScenario => "a scenario change (the environment precompute)",
            JobKind::Load => "loading a project",
            JobKind::Export => "an export",
            JobKind::Save => "saving a project",
            JobKind::Import => "importing a DEM",
        }
    }
}

/// Where a job stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JobPhase {
    Started,
    Running,
    /// A cancel was asked; the job stops at its next cancel point.
    Cancelling,
    Ended,
    Cancelled,
    Failed,
}

/// A job's progress (sent as [`ServerMessage::Job`] to every tab; also in the state).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JobProgress {
    pub id: u64,
    pub kind: JobKind,
    pub phase: JobPhase,
    /// Work done and to do: season days for a step, else 0 of 1 until it ends.
    pub done: f64,
    pub total: f64,
    /// Wall seconds since the job started.
    pub elapsed_s: f64,
    /// What it does, in words (or why it failed).
    pub message: String,
}

/// A running job as the session knows it.
pub(crate) struct RunningJob {
    pub(crate) progress: JobProgress,
    cancel: Arc<AtomicBool>,
    started: Instant,
}

enum Work {
    Step {
        winter: Box<Winter>,
        paint: PaintMaps,
        days: f64,
    },
    SetScenario {
        scenario: Box<Scenario>,
        terrain: Box<LayeredTerrain>,
        paint: PaintMaps,
        source: String,
    },
    Load {
        project: ProjectDir,
        name: String,
    },
    Export {
        winter: Box<Winter>,
        dir: PathBuf,
        name: String,
        export: Arc<Exporter>,
    },
    Save {
        project: ProjectDir,
        name: String,
        contents: Box<ProjectContents>,
    },
    /// A DEM uploaded from the page (saved at `path`), read as `snowscape run --dem` reads it,
    /// starts a season of the current scenario on it.
    ImportDem {
        path: PathBuf,
        name: String,
        scenario: Box<Scenario>,
    },
}

/// The file of an imported DEM (the server's temporary upload): kept as `imports/NAME` beside
/// it when the import succeeded, else removed (a refused or failed upload leaves nothing).
fn keep_or_remove_upload(path: &std::path::Path, name: &str, keep: bool) {
    let kept = keep
        && path.parent().is_some_and(|dir| {
            path.file_name() == Some(std::ffi::OsStr::new(name))
                || std::fs::rename(path, dir.join(name)).is_ok()
        });
    if !kept
        && let Err(e) = std::fs::remove_file(path)
        && e.kind() != std::io::ErrorKind::NotFound
    {
        tracing::warn!("cannot remove the upload {}: {e}", path.display());
    }
}

/// A season step as the driver sees it: progress reported to the tabs, the job's cancel flag
/// stopping the season between two events.
struct StepControl<'a> {
    progress: &'a mut JobProgress,
    report: &'a mut dyn FnMut(JobProgress),
    cancel: Arc<AtomicBool>,
    /// The step's first day.
    from: f64,
    started: Instant,
}

impl Control for StepControl<'_> {
    fn progress(&mut self, day: f64, stop_time: f64) {
        self.progress.phase = JobPhase::Running;
        self.progress.done = day.min(stop_time) - self.from;
        self.progress.elapsed_s = self.started.elapsed().as_secs_f64();
        (self.report)(self.progress.clone());
    }

    fn interrupt_flag(&self) -> Option<Arc<AtomicBool>> {
        Some(self.cancel.clone())
    }
}

/// Work handed to a worker: everything it needs, owned.
pub struct Job {
    progress: JobProgress,
    cancel: Arc<AtomicBool>,
    work: Work,
}

/// How a job ended.
pub enum JobOutcome {
    Stepped { winter: Box<Winter>, from: f64 },
    SetScenario(Box<Session>),
    Loaded { session: Box<Session>, name: String },
    Exported { name: String, files: Vec<String> },
    Saved { name: String, files: Vec<String> },
    Cancelled,
    Failed(Refusal),
}

impl Job {
    /// The job's id.
    pub fn id(&self) -> u64 {
        self.progress.id
    }

    /// Runs the job; `report` gets its progress at most every [`PROGRESS_INTERVAL`].
    pub fn run(self, report: &mut dyn FnMut(JobProgress)) -> JobOutcome {
        let started = Instant::now();
        let mut progress = self.progress;
        let cancelled = || self.cancel.load(Ordering::SeqCst);
        let outcome = match self.work {
            Work::Step {
                mut winter,
                paint,
                days,
            } => {
                let from = winter.day();
                let target = (from + days).min(winter.scenario().days);
                // The painted release probability is a hazard source of the season's
                // scheduler: its avalanches start during the step's days.
                if let Err(e) = crate::painted::set_painted_release(&mut winter, &paint) {
                    return JobOutcome::Failed(e);
                }
                let mut control = StepControl {
                    progress: &mut progress,
                    report,
                    cancel: self.cancel.clone(),
                    from,
                    started,
                };
                // The driver's chunks end where a single run_until(target) would pass anyway:
                // the same events in the same order, so the same season.
                let reason = Simulation::new(&mut winter, target)
                    .max_chunk_days((target - from) / STEP_SLICES as f64)
                    .progress(Schedule::WallTimeInterval(PROGRESS_INTERVAL))
                    .run(&mut control);
                match reason {
                    Err(e) => JobOutcome::Failed((ErrorCode::Failed, e.to_string())),
                    Ok(StopReason::Cancelled { .. }) => JobOutcome::Cancelled,
                    Ok(_) => match crate::painted::apply_painted(&mut winter, &paint, from) {
                        Ok(()) => JobOutcome::Stepped { winter, from },
                        Err(e) => JobOutcome::Failed(e),
                    },
                }
            }
            Work::SetScenario {
                scenario,
                terrain,
                paint,
                source,
            } => match Winter::new(*scenario, *terrain) {
                Ok(winter) => {
                    JobOutcome::SetScenario(Box::new(Session::with_paint(winter, paint, source)))
                }
                Err(e) => JobOutcome::Failed((ErrorCode::Failed, e.to_string())),
            },
            Work::Load { project, name } => match project.load(&name) {
                Ok(s) => JobOutcome::Loaded {
                    session: Box::new(s),
                    name,
                },
                Err(e) => {
                    let code = match e {
                        ProjectError::NotFound(_) => ErrorCode::NotFound,
                        ProjectError::ScenarioPath(_) => ErrorCode::BadPath,
                        _ => ErrorCode::Failed,
                    };
                    JobOutcome::Failed((code, e.to_string()))
                }
            },
            Work::Export {
                winter,
                dir,
                name,
                export,
            } => match export(&winter, &dir) {
                Ok(files) => JobOutcome::Exported {
                    files: files
                        .into_iter()
                        .map(|f| format!("exports/{name}/{f}"))
                        .collect(),
                    name,
                },
                Err(e) => JobOutcome::Failed((ErrorCode::Failed, e)),
            },
            Work::ImportDem {
                path,
                name,
                scenario,
            } => {
                let options = snowscape_io::ReadOptions {
                    max_cells: MAX_IMPORT_CELLS,
                    ..Default::default()
                };
                let outcome = match snowscape_io::read_terrain(&path, &options) {
                    Err(e) => JobOutcome::Failed((ErrorCode::InvalidValue, format!("{name}: {e}"))),
                    Ok(bedrock) => match scenario
                        .validate_on(bedrock.geometry(), "the current scenario")
                        .map_err(|e| e.to_string())
                        .and_then(|()| {
                            // A terrain whose season would not fit in memory is refused
                            // before the season is built (the check `snowscape run` makes).
                            snowscape::memory::check_season(bedrock.geometry().len(), None)
                                .map_err(|e| e.to_string())
                        })
                        .and_then(|()| {
                            Winter::new(*scenario, LayeredTerrain::from_bedrock(bedrock))
                                .map_err(|e| e.to_string())
                        }) {
                        Ok(winter) => JobOutcome::Loaded {
                            session: Box::new(Session::new(winter, format!("imported {name}"))),
                            name: name.clone(),
                        },
                        Err(e) => {
                            JobOutcome::Failed((ErrorCode::InvalidValue, format!("{name}: {e}")))
                        }
                    },
                };
                keep_or_remove_upload(
                    &path,
                    &name,
                    matches!(outcome, JobOutcome::Loaded { .. }) && !cancelled(),
                );
                outcome
            }
            Work::Save {
                project,
                name,
                contents,
            } => match project.save(&name, &contents) {
                Ok(files) => JobOutcome::Saved { name, files },
                Err(e) => {
                    let code = match e {
                        ProjectError::BadPath(_) | ProjectError::ScenarioPath(_) => {
                            ErrorCode::BadPath
                        }
                        _ => ErrorCode::Failed,
                    };
                    JobOutcome::Failed((code, e.to_string()))
                }
            },
        };
        // A cancel asked while the uninterruptible part ran drops its result.
        if cancelled() && !matches!(outcome, JobOutcome::Failed(_)) {
            return JobOutcome::Cancelled;
        }
        outcome
    }
}

/// The server's project folder, or the refusal a server without one gives.
fn project_folder(project: Option<&ProjectDir>) -> Result<&ProjectDir, Refusal> {
    project.ok_or((ErrorCode::Failed, "no project folder".to_string()))
}

fn text(m: &ServerMessage) -> Outgoing {
    Outgoing::Text(m.to_json())
}

impl Session {
    /// The running job, if any.
    pub fn job(&self) -> Option<&JobProgress> {
        self.job.as_ref().map(|j| &j.progress)
    }

    /// Registers a job of `kind` and returns it with its `started` message and the (busy)
    /// state.
    fn new_job(
        &mut self,
        kind: JobKind,
        total: f64,
        message: String,
        work: Work,
    ) -> (Job, Vec<Out>) {
        self.job_seq += 1;
        let cancel = Arc::new(AtomicBool::new(false));
        let progress = JobProgress {
            id: self.job_seq,
            kind,
            phase: JobPhase::Started,
            done: 0.0,
            total,
            elapsed_s: 0.0,
            message,
        };
        tracing::info!("job {}: {} started", progress.id, progress.message);
        self.job = Some(RunningJob {
            progress: progress.clone(),
            cancel: cancel.clone(),
            started: Instant::now(),
        });
        let out = vec![
            Out::All(text(&ServerMessage::Job(progress.clone()))),
            self.state_out(),
        ];
        (
            Job {
                progress,
                cancel,
                work,
            },
            out,
        )
    }

    /// A season step of `days` as a job (the current snapshot takes the edits first).
    pub(crate) fn step_job(&mut self, days: f64) -> Result<(Job, Vec<Out>), Refusal> {
        self.timeline.store(&self.winter, &self.paint);
        if self.winter.finished() {
            return Err((
                ErrorCode::InvalidValue,
                format!("the season ends at day {}", self.winter.scenario().days),
            ));
        }
        let from = self.winter.day();
        let to = (from + days).min(self.winter.scenario().days);
        let work = Work::Step {
            winter: Box::new(self.winter.clone()),
            paint: self.paint.clone(),
            days,
        };
        Ok(self.new_job(
            JobKind::Step,
            to - from,
            format!("season step from day {from:.2} to day {to:.2}"),
            work,
        ))
    }

    /// A scenario change as a job: the season restarts from the first snapshot's snow.
    pub(crate) fn scenario_job(
        &mut self,
        value: serde_json::Value,
        project: Option<&ProjectDir>,
    ) -> Result<(Job, Vec<Out>), Refusal> {
        let scenario = crate::page_scenario::read_scenario(value, project)?;
        let (first, paint) = self
            .timeline
            .first(&self.winter)
            .map_err(|e| (ErrorCode::Failed, e))?;
        let work = Work::SetScenario {
            scenario: Box::new(scenario),
            terrain: Box::new(first.terrain),
            paint,
            source: self.source.clone(),
        };
        Ok(self.new_job(
            JobKind::SetScenario,
            1.0,
            "new scenario: the season restarts from the first snapshot".into(),
            work,
        ))
    }

    /// Loading project `name` as a job.
    pub(crate) fn load_job(
        &mut self,
        name: String,
        project: Option<&ProjectDir>,
    ) -> Result<(Job, Vec<Out>), Refusal> {
        let project = project_folder(project)?.clone();
        let message = format!("loading project {name}");
        Ok(self.new_job(JobKind::Load, 1.0, message, Work::Load { project, name }))
    }

    /// Importing the DEM uploaded to `path` (named `name`) as a job: the season of the
    /// current scenario restarts on it.
    pub(crate) fn import_dem_job(
        &mut self,
        path: PathBuf,
        name: String,
    ) -> Result<(Job, Vec<Out>), Refusal> {
        if self.busy() {
            return Err((
                ErrorCode::Busy,
                "busy: wait for the running job or live event, or cancel it".into(),
            ));
        }
        let scenario = Box::new(self.winter.scenario().clone());
        let message = format!("importing the DEM {name}: the season restarts on it");
        let work = Work::ImportDem {
            path,
            name,
            scenario,
        };
        Ok(self.new_job(JobKind::Import, 1.0, message, work))
    }

    /// An export to `exports/<name>` as a job.
    pub(crate) fn export_job(
        &mut self,
        name: String,
        project: Option<&ProjectDir>,
        export: Option<&Arc<Exporter>>,
    ) -> Result<(Job, Vec<Out>), Refusal> {
        let p = project_folder(project)?;
        let export = export
            .ok_or((
                ErrorCode::Failed,
                "this server cannot export outputs".to_string(),
            ))?
            .clone();
        let dir = p
            .create_dir(&format!("exports/{name}"))
            .map_err(|e| (ErrorCode::BadPath, e.to_string()))?;
        let message = format!("exporting the outputs to exports/{name}");
        let work = Work::Export {
            winter: Box::new(self.winter.clone()),
            dir,
            name,
            export,
        };
        Ok(self.new_job(JobKind::Export, 1.0, message, work))
    }

    /// Saving project `name` as a job: the session's contents are copied now, the files
    /// written by the worker.
    pub(crate) fn save_job(
        &mut self,
        name: String,
        project: Option<&ProjectDir>,
    ) -> Result<(Job, Vec<Out>), Refusal> {
        let project = project_folder(project)?.clone();
        crate::protocol::check_name(&name).map_err(|e| (ErrorCode::BadPath, e.to_string()))?;
        let contents = Box::new(ProjectContents::of(self));
        let message = format!("saving project {name}");
        let work = Work::Save {
            project,
            name,
            contents,
        };
        Ok(self.new_job(JobKind::Save, 1.0, message, work))
    }

    /// Takes a worker's progress report; returns the message for the tabs (none when the
    /// job is not the running one).
    pub fn job_progress(&mut self, p: JobProgress) -> Option<Out> {
        let running = self.job.as_mut().filter(|j| j.progress.id == p.id)?;
        if running.progress.phase == JobPhase::Cancelling {
            return None;
        }
        running.progress = p.clone();
        Some(Out::All(text(&ServerMessage::Job(p))))
    }

    /// Installs the outcome of job `id`. Every tab gets the job's last message and the state;
    /// [`Out::Sender`] outputs are for the tab that asked for the job.
    pub fn finish_job(&mut self, id: u64, outcome: JobOutcome) -> Vec<Out> {
        let Some(running) = self.job.take_if(|j| j.progress.id == id) else {
            return Vec::new();
        };
        let mut p = running.progress;
        p.elapsed_s = running.started.elapsed().as_secs_f64();
        p.phase = match &outcome {
            JobOutcome::Cancelled => JobPhase::Cancelled,
            JobOutcome::Failed(_) => JobPhase::Failed,
            _ => JobPhase::Ended,
        };
        if let JobOutcome::Failed((_, message)) = &outcome {
            p.message = message.clone();
        }
        if matches!(outcome, JobOutcome::Stepped { .. }) {
            p.done = p.total;
        }
        tracing::info!(
            "job {}: {:?} after {:.1} s ({})",
            p.id,
            p.phase,
            p.elapsed_s,
            p.message
        );
        let mut out = vec![Out::All(text(&ServerMessage::Job(p)))];
        match outcome {
            JobOutcome::Stepped { winter, from } => {
                self.winter = *winter;
                let dropped = self.timeline.push(&self.winter, &self.paint);
                self.clear_undo();
                self.log(crate::history::Action::Step {
                    from,
                    to: self.winter.day(),
                });
                out.extend(self.everything());
                out.extend(self.dropped_notice(dropped));
            }
            JobOutcome::SetScenario(mut next) => {
                next.history = std::mem::take(&mut self.history);
                self.replace_with(*next);
                self.log(crate::history::Action::SetScenario);
                out.extend(self.everything());
            }
            JobOutcome::Loaded { session, name } => {
                self.replace_with(*session);
                out.extend(self.everything());
                out.push(Out::All(text(&ServerMessage::Done {
                    what: "loaded".into(),
                    name,
                    files: Vec::new(),
                })));
            }
            JobOutcome::Exported { name, files } => {
                out.push(Out::Sender(text(&ServerMessage::Done {
                    what: "exported".into(),
                    name,
                    files,
                })));
                out.push(self.state_out());
            }
            JobOutcome::Saved { name, files } => {
                out.push(Out::All(text(&ServerMessage::Done {
                    what: "saved".into(),
                    name,
                    files,
                })));
                out.push(self.state_out());
            }
            JobOutcome::Cancelled => out.push(self.state_out()),
            JobOutcome::Failed((code, message)) => {
                out.push(Out::Sender(text(&ServerMessage::error(code, message))));
                out.push(self.state_out());
            }
        }
        out
    }

    /// Answers `cancel`: raises the running job's flag, or ends the live avalanche (its
    /// flowing snow deposits where it is) or the skier descent.
    pub(crate) fn cancel(&mut self) -> Result<Vec<Out>, Refusal> {
        if let Some(j) = self.job.as_mut() {
            j.cancel.store(true, Ordering::SeqCst);
            j.progress.phase = JobPhase::Cancelling;
            j.progress.elapsed_s = j.started.elapsed().as_secs_f64();
            tracing::info!("job {}: cancel asked", j.progress.id);
            return Ok(vec![Out::All(text(&ServerMessage::Job(
                j.progress.clone(),
            )))]);
        }
        if let Some(mut live) = self.avalanche.take() {
            let tiles = live
                .finish(&mut self.winter.terrain)
                .map_err(|e| (ErrorCode::Failed, e))?;
            live.progress.stop = Some("cancelled".into());
            // The page clears the flow on the `ended` phase.
            let mut out = self.layer_frames(&tiles);
            out.push(Out::All(text(&ServerMessage::Avalanche(
                live.progress.clone(),
            ))));
            out.push(self.state_out());
            return Ok(out);
        }
        if self.skiing {
            self.skiing = false;
            let mut out = Vec::new();
            if let Some(s) = &self.skiers {
                out.push(Out::All(text(&ServerMessage::Skiers(skier_progress(
                    &s.area,
                    &self.winter.terrain,
                    s.time_s,
                )))));
            }
            out.push(self.state_out());
            return Ok(out);
        }
        Err((
            ErrorCode::InvalidValue,
            "nothing is running to cancel".into(),
        ))
    }
}
