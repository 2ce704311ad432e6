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

#[cfg(test)]
mod tests {
    use super::*;

    struct Flagged(Arc<AtomicBool>);
    impl Control for Flagged {
        fn interrupt_flag(&self) -> Option<Arc<AtomicBool>> {
            Some(self.0.clone())
        }
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
