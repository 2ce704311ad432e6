//! Progress display and per-stage timings.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::time::Instant;

/// Runs the named stages of a job behind one progress bar and records how long each took.
pub struct Stages {
    bar: ProgressBar,
    timings: Vec<(String, f64)>,
}

impl Stages {
    /// A bar for `total` stages; hidden when `quiet` (indicatif also hides it off a terminal).
    pub fn new(total: u64, quiet: bool) -> Self {
        let bar = ProgressBar::new(total);
        if quiet {
            bar.set_draw_target(ProgressDrawTarget::hidden());
        }
        if let Ok(style) = ProgressStyle::with_template(
            "{elapsed_precise:.dim} [{bar:30.cyan/blue}] {pos}/{len} {msg}",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        Self {
            bar,
            timings: Vec::new(),
        }
    }

    /// Runs one stage, timing it under `name`.
    pub fn run<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        self.bar.set_message(name.to_string());
        let t0 = Instant::now();
        let out = f();
        self.record(name, t0.elapsed().as_secs_f64());
        self.bar.inc(1);
        out
    }

    /// Counts a stage that ran elsewhere (concurrently with others) in `seconds`.
    pub fn finished(&mut self, name: &str, seconds: f64) {
        self.record(name, seconds);
        self.bar.inc(1);
    }

    /// Adds `seconds` to the timing of `name` (stages may run several times).
    pub fn record(&mut self, name: &str, seconds: f64) {
        match self.timings.iter_mut().find(|(n, _)| n == name) {
            Some((_, s)) => *s += seconds,
            None => self.timings.push((name.to_string(), seconds)),
        }
    }

    /// Closes the bar and returns the timings in the order the stages first ran.
    pub fn finish(self) -> Vec<(String, f64)> {
        self.bar.finish_and_clear();
        self.timings
    }
}

/// A bar counting simulated days (in tenths), hidden when `quiet`.
pub fn day_bar(days: f64, quiet: bool) -> ProgressBar {
    let bar = ProgressBar::new((days * 10.0).ceil() as u64);
    if quiet {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    if let Ok(style) = ProgressStyle::with_template(
        "{elapsed_precise:.dim} season [{bar:30.cyan/blue}] day {msg} ({per_sec}, eta {eta})",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}
