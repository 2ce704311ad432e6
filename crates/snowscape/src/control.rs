//! What a front end does while a job runs, one trait for every job: [`Control`] hears the
//! progress (days of a season, simulated seconds of an avalanche, steps of a transport, stages
//! of a cover), shows a status line, asks for a cancel and may run the work where it must (a
//! thread pool, the GIL released). The CLI's progress bars, the editor's job controls and the
//! Python package's callbacks implement it; [`Unattended`] hears nothing and never cancels.
//!
//! A job asks for a cancel where its state is consistent (between a season's chunks or events,
//! between an avalanche's records, between a transport's steps) and then ends with its own
//! typed "cancelled" outcome or error, having written nothing half-way.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// What a front end does while a job runs: hear its progress, cancel it, run its chunks
/// where it must (all optional).
pub trait Control {
    /// The job has reached `done` of `total`, in its own unit (a season: days of a run to its
    /// stop time; an avalanche: simulated seconds of its duration; a transport: steps; a cover:
    /// stages).
    fn progress(&mut self, _done: f64, _total: f64) {}
    /// A short line on what the job is doing (an avalanche's moving volume and energy, the
    /// stage a cover is in, "writing outputs").
    fn status(&mut self, _line: &str) {}
    /// Whether to stop the job now (asked where its state is consistent).
    fn cancelled(&mut self) -> bool {
        false
    }
    /// A flag another thread raises to stop the job (Ctrl-C, an editor's cancel).
    fn interrupt_flag(&self) -> Option<Arc<AtomicBool>> {
        None
    }
    /// Runs one chunk of the job (`chunk` advances it): a front end that must release a lock
    /// or pick a thread pool for the work wraps it here.
    fn run_chunk(&mut self, chunk: &mut (dyn FnMut() + Send)) {
        chunk()
    }
}

/// Hears nothing and never cancels.
pub struct Unattended;

impl Control for Unattended {}

/// Whether `control` asks to stop now: its interrupt flag is raised, or it says so.
pub fn cancel_requested(control: &mut dyn Control) -> bool {
    control
        .interrupt_flag()
        .is_some_and(|f| f.load(Ordering::SeqCst))
        || control.cancelled()
}

/// The stages of a job whose progress counts stages (a cover, the outer steps of a transport):
/// each [`Stages::begin`] asks for a cancel (between two stages), then reports the stages done
/// of all and the new stage's name as the status line.
pub struct Stages<'a> {
    control: &'a mut dyn Control,
    done: usize,
    total: usize,
}

/// A cancel asked between two stages: the stage that would have begun next (`"commit"` before
/// a job's files are moved into place).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StageCancelled(pub &'static str);

impl<'a> Stages<'a> {
    /// `total` stages, none done yet.
    pub fn new(control: &'a mut dyn Control, total: usize) -> Self {
        Self {
            control,
            done: 0,
            total,
        }
    }

    /// Stages done, and stages in all.
    pub fn counts(&self) -> (usize, usize) {
        (self.done, self.total)
    }

    /// Begins stage `name`: a cancel asked since the last stage ends the job here (the first
    /// stage is not asked), else the front end hears `progress(done, total)` and `name`.
    pub fn begin(&mut self, name: &'static str) -> Result<(), StageCancelled> {
        if self.done > 0 && cancel_requested(self.control) {
            return Err(StageCancelled(name));
        }
        self.control.progress(self.done as f64, self.total as f64);
        self.control.status(name);
        self.done = (self.done + 1).min(self.total);
        Ok(())
    }

    /// The last question before the job's files are moved into place: a cancel asked now still
    /// ends the job with nothing written; otherwise every stage is reported done.
    pub fn finish(&mut self) -> Result<(), StageCancelled> {
        if cancel_requested(self.control) {
            return Err(StageCancelled("commit"));
        }
        self.done = self.total;
        self.control.progress(self.total as f64, self.total as f64);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Flagged(Arc<AtomicBool>);
    impl Control for Flagged {
        fn interrupt_flag(&self) -> Option<Arc<AtomicBool>> {
            Some(self.0.clone())
        }
    }

    /// Hears every call and cancels once `stop_at` progress calls were heard.
    #[derive(Default)]
    struct Heard {
        progress: Vec<(f64, f64)>,
        status: Vec<String>,
        stop_at: Option<usize>,
    }
    impl Control for Heard {
        fn progress(&mut self, done: f64, total: f64) {
            self.progress.push((done, total));
        }
        fn status(&mut self, line: &str) {
            self.status.push(line.to_string());
        }
        fn cancelled(&mut self) -> bool {
            self.stop_at.is_some_and(|n| self.progress.len() >= n)
        }
    }

    #[test]
    fn stages_count_up_and_a_cancel_ends_them_between_two() {
        let mut heard = Heard::default();
        let mut s = Stages::new(&mut heard, 2);
        s.begin("read").unwrap();
        s.begin("write").unwrap();
        s.finish().unwrap();
        assert_eq!(heard.progress, [(0.0, 2.0), (1.0, 2.0), (2.0, 2.0)]);
        assert_eq!(heard.status, ["read", "write"]);
        let mut heard = Heard {
            stop_at: Some(1),
            ..Heard::default()
        };
        let mut s = Stages::new(&mut heard, 3);
        s.begin("read").unwrap();
        assert_eq!(s.begin("cover"), Err(StageCancelled("cover")));
        assert_eq!(s.finish(), Err(StageCancelled("commit")));
    }

    #[test]
    fn a_raised_flag_or_a_cancel_stops_and_unattended_never_does() {
        assert!(!cancel_requested(&mut Unattended));
        let flag = Arc::new(AtomicBool::new(false));
        let mut c = Flagged(flag.clone());
        assert!(!cancel_requested(&mut c));
        flag.store(true, Ordering::SeqCst);
        assert!(cancel_requested(&mut c));
    }
}
