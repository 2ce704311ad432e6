//! What the facade's job tests share: a front end that hears every call of a job.

use snowscape::control::Control;

/// Hears every progress and status call of a job, and cancels once `cancel_after` status
/// lines (one a stage) were heard.
#[derive(Default)]
pub struct Heard {
    pub progress: Vec<(f64, f64)>,
    pub status: Vec<String>,
    /// Cancel once this many stages were heard.
    pub cancel_after: Option<usize>,
}

impl Control for Heard {
    fn progress(&mut self, done: f64, total: f64) {
        self.progress.push((done, total));
    }
    fn status(&mut self, line: &str) {
        self.status.push(line.to_string());
    }
    fn cancelled(&mut self) -> bool {
        self.cancel_after.is_some_and(|n| self.status.len() >= n)
    }
}
