//! `snowscape transport --dem FILE | --mesh FILE [--scenario FILE] [--out DIR]`: the
//! physical snow transport of Jubert 2018 (3D wind, precipitation map, SnowTran-3D
//! saltation, suspension, sublimation and melt) over a DEM, a mesh scene, or a mesh
//! standing on a DEM, through a scenario's weather timeline. The job is the library's
//! ([`snowscape::transport_job`]: the scene, the scenario, the run, the files and
//! `report.json`); this is its flags, its two lines on stderr and its exit codes.

use crate::cli::{GlobalArgs, TransportArgs};
use crate::failure::{BAD_INPUT, ExitCodeExt, Failure, JOB_FAILED};
use crate::pairs::parse_xy;
use crate::progress::INTERRUPTED;
use anyhow::anyhow;
use snowscape::control::Unattended;
use snowscape::dem_source::DemSource;
use snowscape::transport_job::{
    Overrides, TransportJob, TransportJobError, TransportMesh, prepare,
};
use std::time::Instant;

/// The job the flags describe (the values' ranges are the job's to check).
fn job(args: &TransportArgs) -> anyhow::Result<TransportJob> {
    let dem = match &args.dem {
        Some(path) => Some(DemSource::File {
            path: path.clone(),
            options: args.dem_input.read_options()?,
        }),
        None => None,
    };
    let mesh = match &args.mesh {
        Some(path) => Some(TransportMesh {
            path: path.clone(),
            up: args.up.clone(),
            scale: args.scale,
            resolution_m: args.resolution,
            margin_m: args.margin,
            // Where the mesh stands is read only when it stands on a DEM.
            at: match (&args.at, &args.dem) {
                (Some(text), Some(_)) => {
                    let (x, y) = parse_xy("--at", text)?;
                    Some([x, y])
                }
                _ => None,
            },
        }),
        None => None,
    };
    Ok(TransportJob {
        scenario: args.scenario.clone(),
        dem,
        mesh,
        overrides: Overrides {
            hours: args.hours,
            flakes: args.flakes,
            seed: args.seed,
            wind_iterations: args.wind_iterations,
            voxel_size: args.voxel_size,
            voxel_layers: args.voxel_layers,
            uniform_precipitation: args.uniform_precipitation,
        },
        output: Some(args.out.clone()),
    })
}

/// A job's error in the flags' words, with its exit code.
fn failure(e: TransportJobError, args: &TransportArgs) -> Failure {
    let code = if e.is_bad_input() {
        BAD_INPUT
    } else if matches!(e, TransportJobError::Cancelled { .. }) {
        INTERRUPTED
    } else {
        JOB_FAILED
    };
    let error = match e {
        TransportJobError::NoScene => anyhow!(
            "no scene: give --dem FILE, --mesh FILE, or a scenario with a [scene] (e.g. --scenario castle)"
        ),
        TransportJobError::Up { up, source } => anyhow!("--up {up:?}: {source}"),
        TransportJobError::Scale(e) => anyhow!("--scale: {e}"),
        TransportJobError::MeshGridOnDem => anyhow!(
            "--resolution and --margin apply to a mesh alone: on a DEM the DEM's grid is used"
        ),
        TransportJobError::AtOutsideDem { .. } => anyhow!(
            "--at {:?} lies outside the DEM",
            args.at.as_deref().unwrap_or_default()
        ),
        e @ TransportJobError::Overridden { .. } => {
            anyhow!(e).context("the scenario after the command-line overrides")
        }
        e => anyhow!(e),
    };
    Failure { code, error }
}

pub fn run_command(args: &TransportArgs, global: &GlobalArgs) -> Result<(), Failure> {
    let started = Instant::now();
    let job = job(args).bad_input()?;
    let prepared = prepare(&job).map_err(|e| failure(e, args))?;
    if !global.quiet {
        let (g, s) = (prepared.geometry(), prepared.scenario());
        eprintln!(
            "transport: {}x{} cells of {:.2} m, wind on {:.2} m voxels x {} layers, {} h",
            g.width(),
            g.height(),
            g.cell_size_x(),
            s.voxel_size_m,
            s.voxel_layers,
            s.duration_h
        );
    }
    // One long stage (the pipeline has no step callback): Ctrl-C ends the process, as it always
    // has; the next job into the folder removes what was staged.
    let outcome = prepared
        .run(&mut Unattended)
        .map_err(|e| failure(e, args))?;
    if !global.quiet {
        let out = &outcome.run;
        let b = &out.budget;
        eprintln!(
            "wrote {} files to {} in {:.1} s: {} steps, residual divergence {:.2e} /s, mass budget closure {:.2e} kg of {:.3e} kg",
            outcome.files.len(),
            args.out.display(),
            started.elapsed().as_secs_f64(),
            out.steps,
            out.wind_report.mean.max_divergence,
            b.closure_error,
            b.final_mass
        );
    }
    Ok(())
}
