//! `snowscape avalanche --dem FILE --release FILE|X,Y`: one avalanche from release to rest on a
//! terrain, with the maps practitioners compare (peak thickness and velocity, deposit,
//! footprint), playback frames and a report. The job is the library's
//! ([`snowscape::avalanche_job`]); this is its flags, its progress bar, its summary line and its
//! exit codes.

use crate::cli::{AvalancheArgs, FrictionArg, GlobalArgs, SlopeGravityArg, ThicknessArg};
use crate::commands::render::preview_options;
use crate::failure::{BAD_INPUT, ExitCodeExt, Failure, JOB_FAILED};
use crate::progress::{INTERRUPTED, install_interrupt_flag};
use crate::stdout::outln;
use anyhow::{anyhow, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use snowscape::avalanche::validation::ThicknessConvention;
use snowscape::avalanche::{
    AvalancheParams, FrictionLaw, FrictionMaps, RunOptions, SamosAtParams, SlopeGravity, StopReason,
};
use snowscape::avalanche_job::{
    self, AvalancheJob, AvalancheJobError, AvalancheSettings, CompareSpec, FrictionRasterError,
    FrictionRasters, FrictionReport, OutputSpec,
};
use snowscape::avalanche_release::ReleaseSpec;
use snowscape::control::Control;
use snowscape_render::ColourMode;
use snowscape_terrain::Grid;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// The flow parameters the flags set: which flags belong to which friction law.
fn flow_params(args: &AvalancheArgs) -> anyhow::Result<AvalancheParams> {
    let mut p = AvalancheParams::default();
    if let Some(a) = args.friction_angle {
        p.rest_angle_deg = a;
    }
    if let Some(k) = args.viscosity {
        p.k_viscous = k;
    }
    if let Some(a) = args.dry_fraction {
        p.alpha = a;
    }
    p.friction = match args.friction_model {
        FrictionArg::Coulomb => FrictionLaw::Coulomb,
        FrictionArg::Voellmy => FrictionLaw::Voellmy,
        FrictionArg::SamosAt => {
            p.samos_at = SamosAtParams::standard();
            FrictionLaw::SamosAt
        }
        FrictionArg::SamosAtSmall => {
            p.samos_at = SamosAtParams::small();
            FrictionLaw::SamosAt
        }
    };
    p.slope_gravity = match args.slope_gravity {
        SlopeGravityArg::Shallow => SlopeGravity::Shallow,
        SlopeGravityArg::Projected => SlopeGravity::Projected,
    };
    p.curvature = !args.no_curvature;
    if args.no_curvature && p.slope_gravity != SlopeGravity::Projected {
        bail!(
            "--no-curvature acts on --slope-gravity projected only (the shallow form has no curvature term)"
        );
    }
    if p.friction == FrictionLaw::Coulomb && (args.mu.is_some() || args.xi.is_some()) {
        bail!("--mu and --xi are the Voellmy law's: add --friction-model voellmy");
    }
    if p.friction == FrictionLaw::SamosAt && args.xi.is_some() {
        bail!("--xi is the Voellmy law's (samosAT has no ξ): add --friction-model voellmy");
    }
    if p.friction != FrictionLaw::Coulomb {
        for (flag, given) in [
            ("--friction-angle", args.friction_angle.is_some()),
            ("--viscosity", args.viscosity.is_some()),
            ("--dry-fraction", args.dry_fraction.is_some()),
        ] {
            if given {
                bail!(
                    "{flag} is the Coulomb law's (the default law is AvaFrame's samosATSmall): \
                     add --friction-model coulomb"
                );
            }
        }
    }
    if let Some(m) = args.mu {
        p.voellmy_mu = m;
        p.samos_at.mu = m;
    }
    if let Some(x) = args.xi {
        p.voellmy_xi_m_s2 = x;
    }
    p.entrainment.enabled = !args.no_entrainment;
    if let Some(e) = args.erosion_energy {
        p.entrainment.erosion_energy_j_kg = e;
    }
    // The ranges are the job's to check (`AvalancheSettings::check`).
    Ok(p)
}

/// The job's settings from the flags (their ranges are checked by the job).
fn settings(args: &AvalancheArgs) -> anyhow::Result<AvalancheSettings> {
    let flow = flow_params(args)?;
    let release = ReleaseSpec::parse(&args.release).map_err(|e| anyhow!("--release {e}"))?;
    let view = preview_options(&args.view, ColourMode::Layers)?;
    Ok(AvalancheSettings {
        release,
        thickness_m: args.thickness,
        thickness_measured: match args.thickness_measured {
            ThicknessArg::Vertical => ThicknessConvention::Vertical,
            ThicknessArg::SlopeNormal => ThicknessConvention::SlopeNormal,
        },
        snow_cover_m: args.snow_cover,
        dem_options: args.dem_input.read_options()?,
        flow,
        run: RunOptions {
            duration_s: args.duration,
            settle_thickness_m: args.settle_thickness,
            stop_energy_fraction: args.stop_energy,
            ..RunOptions::default()
        },
        friction_rasters: FrictionRasters {
            mu: args.mu_raster.clone(),
            xi: args.xi_raster.clone(),
        },
        compare: args.compare.as_ref().map(|reference| CompareSpec {
            reference: reference.clone(),
            path: args.path.clone(),
            corridor_m: args.corridor,
        }),
        seed: args.seed,
        output: Some(OutputSpec {
            folder: args.out.clone(),
            frame_interval_s: args.frame_interval,
            view,
        }),
    })
}

/// A job's error in the flags' words, with its exit code.
fn failure(e: AvalancheJobError, args: &AvalancheArgs) -> Failure {
    let code = if e.is_bad_input() {
        BAD_INPUT
    } else if matches!(e, AvalancheJobError::Cancelled { .. }) {
        INTERRUPTED
    } else {
        JOB_FAILED
    };
    let error = match e {
        AvalancheJobError::FlowParameters(e) => anyhow!(e).context(
            "--friction-angle / --viscosity / --dry-fraction / --mu / --xi / --erosion-energy",
        ),
        AvalancheJobError::RunOptions(e) => {
            anyhow!(e).context("--duration, --settle-thickness or --stop-energy")
        }
        e @ (AvalancheJobError::Release(_) | AvalancheJobError::NoReleaseFile(_)) => {
            anyhow!(e).context(format!("--release {}", args.release))
        }
        AvalancheJobError::FrictionRasters(e) => {
            friction_error(e, &args.mu_raster, &args.xi_raster)
        }
        AvalancheJobError::CompareReference { path, source } => {
            anyhow!(source).context(format!("--compare {}", path.display()))
        }
        AvalancheJobError::ComparePath { path, source } => {
            anyhow!(source).context(format!("--path {}", path.display()))
        }
        AvalancheJobError::PathTooShort { path, vertices } => anyhow!(
            "--path {}: the line has {vertices} vertices, it needs at least 2",
            path.display()
        ),
        e => anyhow!(e),
    };
    Failure { code, error }
}

/// A friction raster's error naming its flag (`--mu-raster FILE`, `--xi-raster FILE`).
fn friction_error(
    e: FrictionRasterError,
    mu_raster: &Option<PathBuf>,
    xi_raster: &Option<PathBuf>,
) -> anyhow::Error {
    match e {
        FrictionRasterError::Read {
            which,
            path,
            source,
        } => anyhow!(source).context(format!("--{which}-raster {}", path.display())),
        FrictionRasterError::Match(e) => {
            let flags = match (mu_raster, xi_raster) {
                (Some(m), Some(x)) => {
                    format!("--mu-raster {}, --xi-raster {}", m.display(), x.display())
                }
                (Some(m), None) => format!("--mu-raster {}", m.display()),
                (None, Some(x)) => format!("--xi-raster {}", x.display()),
                (None, None) => String::new(),
            };
            anyhow!("{flags}: {e}")
        }
    }
}

/// The μ and ξ rasters of `--mu-raster` and `--xi-raster` matched onto the DEM's cells
/// ([`avalanche_job::friction_maps`]), their errors naming the flags (`snowscape run`'s
/// season avalanches).
pub(crate) fn friction_maps(
    mu_raster: &Option<PathBuf>,
    xi_raster: &Option<PathBuf>,
    dem: &Grid,
    params: &AvalancheParams,
) -> anyhow::Result<(FrictionMaps, Option<FrictionReport>)> {
    let rasters = FrictionRasters {
        mu: mu_raster.clone(),
        xi: xi_raster.clone(),
    };
    avalanche_job::friction_maps(&rasters, dem, params)
        .map_err(|e| friction_error(e, mu_raster, xi_raster))
}

/// The progress bar (simulated seconds, the moving volume and the kinetic energy) and the
/// Ctrl-C flag that cancels the run.
struct Bar(ProgressBar, Arc<AtomicBool>);

impl Control for Bar {
    fn progress(&mut self, time_s: f64, _duration_s: f64) {
        self.0.set_position((time_s * 10.0).round() as u64);
    }
    fn status(&mut self, line: &str) {
        if line == "writing outputs" {
            self.0.finish_and_clear();
        } else {
            self.0.set_message(line.to_string());
        }
    }
    fn interrupt_flag(&self) -> Option<Arc<AtomicBool>> {
        Some(self.1.clone())
    }
}

pub fn run(args: &AvalancheArgs, global: &GlobalArgs) -> Result<(), Failure> {
    let settings = settings(args).bad_input()?;
    settings.check().map_err(|e| failure(e, args))?;
    let dem = args.dem_input.read(&args.dem).bad_input()?;
    let job = AvalancheJob {
        source: args.dem.display().to_string(),
        dem,
        settings,
    };
    let bar = ProgressBar::new((args.duration * 10.0).ceil() as u64);
    if global.quiet {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    if let Ok(style) =
        ProgressStyle::with_template("{elapsed_precise:.dim} avalanche [{bar:30.cyan/blue}] {msg}")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    let mut bar = Bar(bar, install_interrupt_flag());
    let outcome = avalanche_job::run(&job, &mut bar).map_err(|e| {
        bar.0.abandon();
        failure(e, args)
    })?;
    let r = &outcome.report;
    if !global.quiet {
        outln!(
            "avalanche: released {:.0} m³, entrained {:.0} m³, ran {:.1} s ({}), runout {:.0} m, travel angle {:.1}°, footprint {:.0} m², {:.2} s wall -> {}",
            r.summary.released_volume_m3,
            r.summary.entrained_volume_m3,
            r.summary.simulated_s,
            stop_words(r.summary.stop),
            r.summary.runout_length_m,
            r.summary.travel_angle_deg,
            r.summary.footprint_area_m2,
            r.wall_s,
            args.out.display()
        );
    }
    Ok(())
}

/// Why the run ended, in words for the summary line (`report.json` keeps the snake_case name).
fn stop_words(stop: Option<StopReason>) -> &'static str {
    match stop {
        Some(StopReason::AtRest) => "stopped at rest",
        Some(StopReason::EnergyCriterion) => {
            "stopped: kinetic energy below the stop fraction of its peak"
        }
        Some(StopReason::Duration) => "stopped: duration reached",
        Some(StopReason::Empty) => "stopped: all the snow left the grid",
        None => "still moving when it ended",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stop_reasons_are_told_in_words() {
        for stop in [
            None,
            Some(StopReason::AtRest),
            Some(StopReason::EnergyCriterion),
            Some(StopReason::Duration),
            Some(StopReason::Empty),
        ] {
            let words = stop_words(stop);
            assert!(
                !words.contains("Some(") && !words.contains("Criterion"),
                "{words}"
            );
        }
        assert!(stop_words(Some(StopReason::EnergyCriterion)).contains("kinetic energy"));
    }
}
