//! One driver of a season, for every front end: [`Simulation`] advances a
//! [`Winter`] to a stop time in chunks, fires scheduled outputs, reports progress and honours a
//! cancel, so that `snowscape run`/`demo` ([`crate::season_run`]), the editor's season steps and
//! the Python package's `Winter.run_until` stop, write and resume the same way.
//!
//! Modelled on Oceananigans' `Simulation`: outputs hang on [`Schedule`]s
//! ([`Schedule::TimeInterval`], [`Schedule::IterationInterval`], [`Schedule::SpecificTimes`],
//! [`Schedule::WallTimeInterval`]), the run ends at its `stop_time` (a season day) or its
//! wall-time limit, and a front end's [`Control`] hears the progress and may cancel.
//!
//! **Chunks and milestones.** The season runs in chunks of at most [`Simulation::max_chunk_days`]
//! ([`CHUNK_DAYS`] unless set), and every chunk ends exactly at the next scheduled day of a time
//! schedule (a milestone) or at the stop time. `Winter::run_until(day)` runs the events whose
//! start lies before `day`, so a season run in chunks is the season of one `run_until` to the
//! end, bit for bit, wherever the chunks end; a milestone only decides the state an output sees
//! (the state at the first event past its day, as a single run would pass it). An output of a
//! time schedule fires once for each of its days that the chunk reached (a chunk may pass
//! several when events are sparse), in order of day, then of registration; an iteration or
//! wall-time schedule fires at most once a chunk.
//!
//! **Cancel.** [`Control::interrupt_flag`] (set from another thread: Ctrl-C, an editor's
//! cancel) stops a chunk between two events, where the state is consistent;
//! [`Control::cancelled`] is asked between chunks (on the cancel-check schedule, every chunk
//! unless set). Either ends the run with [`StopReason::Cancelled`], after the outputs of the
//! chunk: the state can be checkpointed and runs on bit-identically.

use snowscape_season::winter::{SeasonError, Winter};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Longest stretch of simulated days between two checks of a cancel, unless set.
pub const CHUNK_DAYS: f64 = 0.25;

/// When an output, the progress report or the cancel check fires.
#[derive(Debug, Clone, PartialEq)]
pub enum Schedule {
    /// Every so many days of the season, counted from its day 0: at `k · interval` for
    /// `k = 1, 2, ...` (a non-positive or non-finite interval never fires).
    TimeInterval(f64),
    /// Every so many chunks of the run (0 never fires).
    IterationInterval(u64),
    /// At these season days (sorted and deduplicated; non-finite days dropped).
    SpecificTimes(Vec<f64>),
    /// At the end of the first chunk after so much wall time since the run started or the
    /// schedule last fired.
    WallTimeInterval(Duration),
}

/// One firing of a schedule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Actuation {
    /// Which firing: for a time schedule the position of its day among the schedule's days
    /// (`k - 1` for day `k · interval`, the index in the sorted [`Schedule::SpecificTimes`]),
    /// else the number of earlier firings in this run.
    pub index: usize,
    /// The scheduled day (time schedules), else the season's day when it fired.
    pub day: f64,
}

/// Why a run ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StopReason {
    /// The season reached its last day.
    SeasonEnded { day: f64 },
    /// The run reached its stop time before the season's end.
    StopTime { day: f64 },
    /// The run used its wall-time limit before reaching its stop time.
    WallTimeLimit { day: f64, elapsed: Duration },
    /// The front end cancelled it (between two events or two chunks).
    Cancelled { day: f64 },
    /// No event can happen any more (every event kind's rate is zero): the clock stands at
    /// `day`, before the stop time.
    Stalled { day: f64 },
}

impl StopReason {
    /// The season's day when the run ended.
    pub fn day(&self) -> f64 {
        match *self {
            Self::SeasonEnded { day }
            | Self::StopTime { day }
            | Self::WallTimeLimit { day, .. }
            | Self::Cancelled { day }
            | Self::Stalled { day } => day,
        }
    }
}

pub use crate::control::{Control, Unattended, cancel_requested};

/// Why a run failed: the season's own error, or an output's.
#[derive(Debug, thiserror::Error)]
pub enum SimulationError<E> {
    #[error(transparent)]
    Season(Box<SeasonError>),
    #[error(transparent)]
    Output(E),
}

/// A season run to a stop time with outputs on schedules (module docs). `K` names the outputs
/// for the writer [`Simulation::run_with`] takes.
pub struct Simulation<'w, K = ()> {
    winter: &'w mut Winter,
    stop_time: f64,
    wall_time_limit: Option<Duration>,
    max_chunk_days: f64,
    outputs: Vec<(K, Schedule)>,
    progress: Schedule,
    cancel_check: Schedule,
}

impl<'w, K: Copy> Simulation<'w, K> {
    /// A run of `winter` to `stop_time` (a season day; past the season's end, or NaN, it ends
    /// with the season), in chunks of at most [`CHUNK_DAYS`], reporting progress and asking
    /// for a cancel after every chunk.
    pub fn new(winter: &'w mut Winter, stop_time: f64) -> Self {
        Self {
            winter,
            stop_time,
            wall_time_limit: None,
            max_chunk_days: CHUNK_DAYS,
            outputs: Vec::new(),
            progress: Schedule::IterationInterval(1),
            cancel_check: Schedule::IterationInterval(1),
        }
    }

    /// Ends the run once it has run this long (checked between chunks).
    pub fn wall_time_limit(mut self, limit: Duration) -> Self {
        self.wall_time_limit = Some(limit);
        self
    }

    /// The longest chunk, days (non-positive or non-finite: a chunk runs to the next
    /// milestone).
    pub fn max_chunk_days(mut self, days: f64) -> Self {
        self.max_chunk_days = days;
        self
    }

    /// Fires the output `key` on `schedule` (several outputs may share a key).
    pub fn output(mut self, key: K, schedule: Schedule) -> Self {
        self.outputs.push((key, schedule));
        self
    }

    /// When [`Control::progress`] is told (every chunk unless set).
    pub fn progress(mut self, schedule: Schedule) -> Self {
        self.progress = schedule;
        self
    }

    /// When [`Control::cancelled`] is asked (every chunk unless set; the interrupt flag is
    /// read between every two events regardless).
    pub fn cancel_check(mut self, schedule: Schedule) -> Self {
        self.cancel_check = schedule;
        self
    }

    /// The day the run ends at: its stop time, or the season's end if that comes first.
    fn stop_day(&self) -> f64 {
        self.stop_time.min(self.winter.scenario().days)
    }

    /// Runs to the stop time (or a cancel, the wall-time limit), calling `write` for every
    /// output that fires, with the season as it stands at that chunk's end.
    pub fn run_with<E>(
        &mut self,
        control: &mut dyn Control,
        mut write: impl FnMut(K, Actuation, &Winter) -> Result<(), E>,
    ) -> Result<StopReason, SimulationError<E>> {
        let started = Instant::now();
        let start_day = self.winter.day();
        let stop_time = self.stop_day();
        let mut outputs: Vec<(K, Timer)> = self
            .outputs
            .iter()
            .map(|(k, s)| (*k, Timer::new(s, start_day, started)))
            .collect();
        let mut progress = Timer::new(&self.progress, start_day, started);
        let mut cancel_check = Timer::new(&self.cancel_check, start_day, started);
        let flag = control.interrupt_flag();
        let never = AtomicBool::new(false);
        let interrupt: &AtomicBool = flag.as_deref().unwrap_or(&never);
        let mut iteration = 0_u64;
        let mut due: Vec<(usize, Actuation)> = Vec::new();
        loop {
            let day = self.winter.day();
            if self.winter.finished() {
                return Ok(StopReason::SeasonEnded { day });
            }
            if day >= stop_time {
                return Ok(StopReason::StopTime { day });
            }
            let elapsed = started.elapsed();
            if self.wall_time_limit.is_some_and(|limit| elapsed >= limit) {
                return Ok(StopReason::WallTimeLimit { day, elapsed });
            }
            let milestone = outputs
                .iter()
                .map(|(_, t)| t)
                .chain([&progress, &cancel_check])
                .filter_map(Timer::next_day)
                .fold(stop_time, f64::min);
            let until = if self.max_chunk_days > 0.0 && self.max_chunk_days.is_finite() {
                (day + self.max_chunk_days).min(milestone)
            } else {
                milestone
            };
            let mut result = Ok(());
            let winter = &mut *self.winter;
            control.run_chunk(&mut || result = winter.run_until_unless(until, interrupt));
            result.map_err(|e| SimulationError::Season(Box::new(e)))?;
            iteration += 1;
            let (now_day, now) = (self.winter.day(), Instant::now());
            due.clear();
            for (i, (_, timer)) in outputs.iter_mut().enumerate() {
                timer.fire(now_day, stop_time, iteration, now, |a| due.push((i, a)));
            }
            due.sort_by(|a, b| a.1.day.total_cmp(&b.1.day).then(a.0.cmp(&b.0)));
            for &(i, at) in &due {
                write(outputs[i].0, at, self.winter).map_err(SimulationError::Output)?;
            }
            if progress.fires(now_day, stop_time, iteration, now) {
                control.progress(now_day, stop_time);
            }
            if interrupt.load(Ordering::SeqCst)
                || (cancel_check.fires(now_day, stop_time, iteration, now) && control.cancelled())
            {
                return Ok(StopReason::Cancelled { day: now_day });
            }
            if now_day <= day && !self.winter.finished() && now_day < stop_time {
                return Ok(StopReason::Stalled { day: now_day });
            }
        }
    }
}

impl<'w> Simulation<'w, ()> {
    /// Runs to the stop time (or a cancel, the wall-time limit), without outputs.
    pub fn run(&mut self, control: &mut dyn Control) -> Result<StopReason, Box<SeasonError>> {
        self.run_with(control, |(), _, _| Ok::<(), std::convert::Infallible>(()))
            .map_err(|e| match e {
                SimulationError::Season(e) => e,
                SimulationError::Output(never) => match never {},
            })
    }
}

/// A schedule as a run follows it.
struct Timer {
    schedule: Schedule,
    /// Time schedules: the index of the next day to fire; others: firings so far.
    next: usize,
    /// Wall time of the last firing (or the run's start).
    last: Instant,
}

impl Timer {
    /// Follows `schedule` in a run that starts at `start_day` (days up to it have passed).
    fn new(schedule: &Schedule, start_day: f64, started: Instant) -> Self {
        let schedule = match schedule {
            Schedule::SpecificTimes(days) => {
                let mut days: Vec<f64> = days.iter().copied().filter(|d| d.is_finite()).collect();
                days.sort_by(f64::total_cmp);
                days.dedup();
                Schedule::SpecificTimes(days)
            }
            other => other.clone(),
        };
        let mut timer = Self {
            schedule,
            next: 0,
            last: started,
        };
        if let Schedule::TimeInterval(interval) = timer.schedule
            && interval > 0.0
            && interval.is_finite()
        {
            timer.next = (start_day / interval).floor().max(0.0) as usize;
            while timer.next > 0 && timer.day(timer.next - 1).is_some_and(|d| d > start_day) {
                timer.next -= 1;
            }
        }
        while timer.day(timer.next).is_some_and(|d| d <= start_day) {
            timer.next += 1;
        }
        timer
    }

    /// The `k`-th scheduled day of a time schedule.
    fn day(&self, k: usize) -> Option<f64> {
        match &self.schedule {
            Schedule::TimeInterval(interval) if *interval > 0.0 && interval.is_finite() => {
                Some((k + 1) as f64 * interval)
            }
            Schedule::SpecificTimes(days) => days.get(k).copied(),
            _ => None,
        }
    }

    /// The next scheduled day (time schedules).
    fn next_day(&self) -> Option<f64> {
        self.day(self.next)
    }

    /// Fires (calls `fire` for) every actuation due at the end of chunk `iteration`, the
    /// season at `day`: each scheduled day up to `day` and `stop_time`, or the iteration or
    /// wall-time firing.
    fn fire(
        &mut self,
        day: f64,
        stop_time: f64,
        iteration: u64,
        now: Instant,
        mut fire: impl FnMut(Actuation),
    ) {
        match self.schedule {
            Schedule::TimeInterval(_) | Schedule::SpecificTimes(_) => {
                while let Some(d) = self.next_day().filter(|&d| d <= day && d <= stop_time) {
                    fire(Actuation {
                        index: self.next,
                        day: d,
                    });
                    self.next += 1;
                }
            }
            Schedule::IterationInterval(n) => {
                if n > 0 && iteration.is_multiple_of(n) {
                    fire(Actuation {
                        index: self.next,
                        day,
                    });
                    self.next += 1;
                }
            }
            Schedule::WallTimeInterval(interval) => {
                if now.duration_since(self.last) >= interval {
                    self.last = now;
                    fire(Actuation {
                        index: self.next,
                        day,
                    });
                    self.next += 1;
                }
            }
        }
    }

    /// Whether the schedule fires at the end of this chunk (once, however many of its days
    /// the chunk passed).
    fn fires(&mut self, day: f64, stop_time: f64, iteration: u64, now: Instant) -> bool {
        let mut fired = false;
        self.fire(day, stop_time, iteration, now, |_| fired = true);
        fired
    }
}
