//! `snowscape validate --run DIR --observed FILE`: a run's snow depth against a measured
//! depth raster. Reads `DIR/depth.tif`, `DIR/bedrock.tif` and (for the prevailing wind)
//! `DIR/report.json`; writes `validation.json`, `validation.png` and `scatter.png` into
//! `--out` (default `DIR/validation`), each atomically, and prints a summary table. The
//! measures are those of [`crate::validation`].
//!
//! The lee/windward wind direction is `--wind-from` when given, else the prevailing wind of
//! the run's report.json ([`prevailing_wind_from`]), else 270 (westerly).

use crate::cli::{GlobalArgs, ValidateArgs};
use crate::failure::{ExitCodeExt, Failure};
use crate::outputs::write_png;
use crate::stdout::{out, outln};
use crate::validation::figures::{density_scatter, side_by_side};
use crate::validation::{
    Input, Inputs, Settings, Validation, ValidationError, compare, prevailing_wind_from, summary,
};
use anyhow::Context;
use serde::Serialize;
use snowscape::output_folder::OutputFolder;
use snowscape_io::{ReadOptions, read_dem, write_bytes_atomic};
use snowscape_terrain::Grid;
use std::path::{Path, PathBuf};

/// The wind direction used when neither the flag nor the report gives one.
const DEFAULT_WIND_FROM_DEG: f64 = 270.0;

/// `validation.json`.
#[derive(Serialize)]
struct Report<'a> {
    snowscape_version: &'static str,
    command: &'static str,
    run: String,
    simulated: String,
    bedrock: String,
    observed: String,
    mask: Option<String>,
    /// Where the lee/windward wind direction came from.
    wind_from_source: String,
    #[serde(flatten)]
    validation: &'a Validation,
    outputs: Vec<&'static str>,
}

fn read(flag: &'static str, path: &Path) -> Result<Grid, ValidationError> {
    if !path.is_file() {
        return Err(ValidationError::MissingFile {
            flag,
            path: path.to_path_buf(),
        });
    }
    read_dem(path, &ReadOptions::default()).map_err(|source| ValidationError::Read { flag, source })
}

fn run_file(dir: &Path, file: &'static str) -> Result<PathBuf, ValidationError> {
    let p = dir.join(file);
    if p.is_file() {
        Ok(p)
    } else {
        Err(ValidationError::MissingRunFile {
            dir: dir.to_path_buf(),
            file,
        })
    }
}

/// The wind direction and where it came from.
fn wind_from(args: &ValidateArgs) -> Result<(f64, String), ValidationError> {
    if let Some(w) = args.wind_from {
        return Ok((w, "--wind-from".into()));
    }
    let path = args.run.join(snowscape::output_folder::REPORT);
    if !path.is_file() {
        return Ok((
            DEFAULT_WIND_FROM_DEG,
            "default 270 (the run folder has no report.json)".into(),
        ));
    }
    let report: serde_json::Value = std::fs::read(&path)
        .map_err(|e| e.to_string())
        .and_then(|bytes| serde_json::from_slice(&bytes).map_err(|e| e.to_string()))
        .map_err(|message| ValidationError::Report {
            path: path.clone(),
            message: format!("cannot read the run's report: {message}"),
        })?;
    Ok(match prevailing_wind_from(&report) {
        Some(w) => (
            w,
            format!(
                "{} (prevailing wind of the weather timeline)",
                path.display()
            ),
        ),
        None => (
            DEFAULT_WIND_FROM_DEG,
            format!("default 270 ({} has no weather timeline)", path.display()),
        ),
    })
}

pub fn run(args: &ValidateArgs, global: &GlobalArgs) -> Result<(), Failure> {
    if !(args.snow_threshold.is_finite() && args.snow_threshold >= 0.0) {
        return Err(ValidationError::BadParameter {
            flag: "--snow-threshold",
            value: args.snow_threshold,
            expected: "a depth in metres >= 0",
        })
        .bad_input();
    }
    if !args.run.is_dir() {
        return Err(ValidationError::MissingFile {
            flag: "--run",
            path: args.run.clone(),
        })
        .bad_input();
    }
    let depth_path = run_file(&args.run, "depth.tif").bad_input()?;
    let bedrock_path = run_file(&args.run, "bedrock.tif").bad_input()?;
    let depth = read("--run", &depth_path).bad_input()?;
    let bedrock = read("--run", &bedrock_path).bad_input()?;
    let observed = read("--observed", &args.observed).bad_input()?;
    let mask = match &args.mask {
        Some(p) => Some(read("--mask", p).bad_input()?),
        None => None,
    };
    let (wind_from_deg, wind_from_source) = wind_from(args).bad_input()?;
    let inputs = Inputs {
        depth: Input {
            grid: &depth,
            path: &depth_path,
            flag: "--run",
        },
        bedrock: Input {
            grid: &bedrock,
            path: &bedrock_path,
            flag: "--run",
        },
        observed: Input {
            grid: &observed,
            path: &args.observed,
            flag: "--observed",
        },
        mask: mask
            .as_ref()
            .zip(args.mask.as_deref())
            .map(|(grid, path)| Input {
                grid,
                path,
                flag: "--mask",
            }),
    };
    let settings = Settings {
        snow_threshold_m: args.snow_threshold,
        wind_from_deg,
    };
    let (validation, maps) = compare(&inputs, &settings).bad_input()?;

    let out = args
        .out
        .clone()
        .unwrap_or_else(|| args.run.join("validation"));
    let folder = OutputFolder::open(&out).bad_input()?;
    let stage = folder.staging().to_path_buf();
    let outputs = vec!["validation.json", "validation.png", "scatter.png"];
    let report = Report {
        snowscape_version: env!("CARGO_PKG_VERSION"),
        command: "validate",
        run: args.run.display().to_string(),
        simulated: depth_path.display().to_string(),
        bedrock: bedrock_path.display().to_string(),
        observed: args.observed.display().to_string(),
        mask: args.mask.as_ref().map(|p| p.display().to_string()),
        wind_from_source,
        validation: &validation,
        outputs: outputs.clone(),
    };
    let json = serde_json::to_vec_pretty(&report)
        .context("cannot encode validation.json")
        .job_failed()?;
    write_bytes_atomic(&stage.join("validation.json"), &json).job_failed()?;
    let maps_img = side_by_side(maps.width, maps.height, &maps.observed, &maps.simulated);
    write_png(&stage.join("validation.png"), &maps_img).job_failed()?;
    let compared = |v: &[f64]| -> Vec<f64> { v.iter().copied().filter(|x| !x.is_nan()).collect() };
    let scatter = density_scatter(&compared(&maps.observed), &compared(&maps.simulated));
    write_png(&stage.join("scatter.png"), &scatter).job_failed()?;
    let names: Vec<String> = outputs.iter().map(|n| n.to_string()).collect();
    folder.commit(&names, None).job_failed()?;
    if !global.quiet {
        out!("{}", summary::table(&validation));
        outln!("wrote {} in {}", outputs.join(", "), out.display());
    }
    Ok(())
}
