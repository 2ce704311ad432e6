//! Progress display.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

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
