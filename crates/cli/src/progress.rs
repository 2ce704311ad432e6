//! Progress display and Ctrl-C.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Exit code of a job stopped by Ctrl-C (128 + SIGINT).
pub const INTERRUPTED: u8 = 130;

/// A flag Ctrl-C raises (a job's [`snowscape::control::Control::interrupt_flag`]).
pub fn install_interrupt_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    // A second install (tests running several jobs in one process) keeps the first handler.
    let _ = ctrlc::set_handler(move || f.store(true, Ordering::SeqCst));
    flag
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
