//! The season pipeline shared by `snowscape run` (a DEM file) and `snowscape demo` (the
//! procedural terrain) is the library's ([`snowscape::season_run`]); this module puts the
//! command line around it: the progress bar, Ctrl-C, the exit codes and the summary line.

use crate::failure::Failure;
use crate::progress::{INTERRUPTED, install_interrupt_flag};
use crate::stdout::outln;
use anyhow::anyhow;
use snowscape::control::Control;
use snowscape::season_run::{SeasonOutcome, run_season as run_job};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

pub use snowscape::season_run::SeasonJob;

/// The day bar, advanced by the season, and the Ctrl-C flag that stops it.
struct Bar(indicatif::ProgressBar, Arc<AtomicBool>);

impl Control for Bar {
    fn progress(&mut self, day: f64, _stop_time: f64) {
        self.0.set_position((day * 10.0) as u64);
    }
    fn interrupt_flag(&self) -> Option<Arc<AtomicBool>> {
        Some(self.1.clone())
    }
}

/// Runs the season and writes every output.
pub fn run_season(job: SeasonJob, quiet: bool) -> Result<(), Failure> {
    let interrupted = install_interrupt_flag();
    let out = job.out.clone();
    let days = job.scenario.days;
    let mut bar = Bar(crate::progress::day_bar(days, quiet), interrupted);
    let outcome = run_job(job, &mut bar).map_err(|e| {
        bar.0.abandon();
        let code = if e.is_bad_input() {
            crate::failure::BAD_INPUT
        } else {
            crate::failure::JOB_FAILED
        };
        Failure {
            code,
            error: e.into(),
        }
    });
    match outcome? {
        SeasonOutcome::Interrupted {
            day,
            outputs_pending,
        } => {
            bar.0.abandon();
            let error = if outputs_pending {
                anyhow!(
                    "interrupted while writing the outputs; the season is complete: write them with --resume {}",
                    out.display()
                )
            } else {
                anyhow!(
                    "interrupted at day {day:.2}; checkpoint written; continue with --resume {}",
                    out.display()
                )
            };
            Err(Failure {
                code: INTERRUPTED,
                error,
            })
        }
        SeasonOutcome::Stopped { day } => {
            bar.0.finish_and_clear();
            if !quiet {
                outln!(
                    "stopped at day {day:.2} as asked; continue with --resume {}",
                    out.display()
                );
            }
            Ok(())
        }
        SeasonOutcome::Finished(report) => {
            bar.0.finish_and_clear();
            if !quiet {
                let b = &report.mass_budget;
                outln!(
                    "{}: {:.0} days on {}x{} cells; snowfall {:.3e} m³, final store {:.3e} m³ (closure error {:.1e}); {} files in {}",
                    report.command,
                    days,
                    report.input.width,
                    report.input.height,
                    b.inputs.get("snowfall").copied().unwrap_or(0.0),
                    b.final_store,
                    b.closure_error,
                    report.outputs.len(),
                    out.display()
                );
                if let Some(bands) = report.bands.as_deref() {
                    outln!("{}", band_table(bands));
                }
            }
            Ok(())
        }
    }
}

/// The season by altitude band, one line a band (empty bands left out).
fn band_table(bands: &[snowscape_season::bands::BandSummary]) -> String {
    let mut t = String::from(
        "altitude band    cells  precipitation  rain  peak SWE\n             m             mm w.e.     %   mm w.e.",
    );
    for b in bands.iter().filter(|b| b.cells > 0) {
        t.push_str(&format!(
            "\n{:>6.0}-{:<6.0} {:>8} {:>14.0} {:>5.0} {:>9.0}",
            b.from_m,
            b.to_m,
            b.cells,
            b.precipitation_mm,
            100.0 * b.rain_share,
            b.peak_swe_mm
        ));
    }
    t
}
