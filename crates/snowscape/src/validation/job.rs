//! The validation job (`snowscape validate --run DIR --observed FILE`, the Python package's
//! `snowscape.validate`): reads the run's `depth.tif`, `bedrock.tif` and (for the prevailing
//! wind) `report.json`, compares ([`super::compare`]) and writes `validation.json`
//! ([`ValidationReport`]; its keys are a contract), `validation.png` and `scatter.png` into
//! the output folder (default `DIR/validation`), committed together.
//!
//! The lee/windward wind direction is the job's `wind_from_deg` when given, else the
//! prevailing wind of the run's report.json ([`super::prevailing_wind_from`]), else 270
//! (westerly).

use super::figures::{density_scatter, side_by_side};
use super::{Input, Inputs, Maps, Settings, Validation, ValidationError, ValidationInput, compare};
use crate::control::{Control, Stages, Unattended};
use crate::output_folder::{OutputFolder, REPORT};
use crate::outputs::write_png;
use serde::Serialize;
use snowscape_io::{ReadOptions, read_dem, write_bytes_atomic};
use snowscape_terrain::Grid;
use std::path::{Path, PathBuf};

/// The wind direction used when neither the job nor the run's report gives one, degrees.
pub const DEFAULT_WIND_FROM_DEG: f64 = 270.0;

/// The files a validation writes, in order.
pub const OUTPUTS: [&str; 3] = ["validation.json", "validation.png", "scatter.png"];

/// One validation to run.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidateJob {
    /// Run folder written by `snowscape run` or `snowscape demo`.
    pub run: PathBuf,
    /// Measured snow depth, m (any cell size and extent, matched by map coordinates).
    pub observed: PathBuf,
    /// Compare only cells where this raster is nonzero.
    pub mask: Option<PathBuf>,
    /// Output folder (`None`: `RUN/validation`).
    pub out: Option<PathBuf>,
    /// Depth above which a cell counts as snow-covered, m (>= 0).
    pub snow_threshold_m: f64,
    /// Direction the prevailing wind blows from, degrees clockwise from north (`None`: the
    /// run's report.json, else 270).
    pub wind_from_deg: Option<f64>,
}

/// `validation.json`.
#[derive(Debug, Clone, Serialize)]
pub struct ValidationReport {
    pub snowscape_version: &'static str,
    /// `validate`.
    pub command: &'static str,
    /// The run folder.
    pub run: String,
    /// Its `depth.tif`.
    pub simulated: String,
    /// Its `bedrock.tif`.
    pub bedrock: String,
    pub observed: String,
    pub mask: Option<String>,
    /// Where the lee/windward wind direction came from.
    pub wind_from_source: String,
    #[serde(flatten)]
    pub validation: Validation,
    /// Files written, relative to the output folder.
    pub outputs: Vec<&'static str>,
}

/// A finished validation: its report, the matched maps and the folder written.
#[derive(Debug)]
pub struct ValidationOutcome {
    pub report: ValidationReport,
    pub maps: Maps,
    pub out: PathBuf,
}

fn read(input: ValidationInput, path: &Path) -> Result<Grid, ValidationError> {
    if !path.is_file() {
        return Err(ValidationError::MissingFile {
            input,
            path: path.to_path_buf(),
        });
    }
    read_dem(path, &ReadOptions::default())
        .map_err(|source| ValidationError::Read { input, source })
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
fn wind_from(job: &ValidateJob) -> Result<(f64, String), ValidationError> {
    if let Some(w) = job.wind_from_deg {
        return Ok((w, "--wind-from".into()));
    }
    let path = job.run.join(REPORT);
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
    Ok(match super::prevailing_wind_from(&report) {
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

/// The rasters of a validation, read and checked as files.
struct Rasters {
    depth_path: PathBuf,
    bedrock_path: PathBuf,
    depth: Grid,
    bedrock: Grid,
    observed: Grid,
    mask: Option<Grid>,
}

/// Checks the threshold and the run folder, and reads every raster.
fn read_rasters(job: &ValidateJob) -> Result<Rasters, ValidationError> {
    if !(job.snow_threshold_m.is_finite() && job.snow_threshold_m >= 0.0) {
        return Err(ValidationError::BadParameter {
            input: ValidationInput::SnowThreshold,
            value: job.snow_threshold_m,
            expected: "a depth in metres >= 0",
        });
    }
    if !job.run.is_dir() {
        return Err(ValidationError::MissingFile {
            input: ValidationInput::Run,
            path: job.run.clone(),
        });
    }
    let depth_path = run_file(&job.run, "depth.tif")?;
    let bedrock_path = run_file(&job.run, "bedrock.tif")?;
    Ok(Rasters {
        depth: read(ValidationInput::Run, &depth_path)?,
        bedrock: read(ValidationInput::Run, &bedrock_path)?,
        observed: read(ValidationInput::Observed, &job.observed)?,
        mask: job
            .mask
            .as_deref()
            .map(|p| read(ValidationInput::Mask, p))
            .transpose()?,
        depth_path,
        bedrock_path,
    })
}

/// Runs the validation and writes its files, unattended.
pub fn run(job: &ValidateJob) -> Result<ValidationOutcome, ValidationError> {
    run_with(job, &mut Unattended)
}

/// Runs the validation and writes its files; `control` hears its three stages (reading the
/// rasters, comparing, writing the outputs), and a cancel between them (or before the commit)
/// ends it with [`ValidationError::Cancelled`] and nothing written.
pub fn run_with(
    job: &ValidateJob,
    control: &mut dyn Control,
) -> Result<ValidationOutcome, ValidationError> {
    let mut stages = Stages::new(control, 3);
    stages.begin("reading the rasters")?;
    let r = read_rasters(job)?;
    let (wind_from_deg, wind_from_source) = wind_from(job)?;
    let input = |grid, path, input| Input { grid, path, input };
    let inputs = Inputs {
        depth: input(&r.depth, &r.depth_path, ValidationInput::Run),
        bedrock: input(&r.bedrock, &r.bedrock_path, ValidationInput::Run),
        observed: input(&r.observed, &job.observed, ValidationInput::Observed),
        mask: r
            .mask
            .as_ref()
            .zip(job.mask.as_deref())
            .map(|(grid, path)| input(grid, path, ValidationInput::Mask)),
    };
    let settings = Settings {
        snow_threshold_m: job.snow_threshold_m,
        wind_from_deg,
    };
    stages.begin("comparing")?;
    let (validation, maps) = compare(&inputs, &settings)?;
    stages.begin("writing outputs")?;
    let out = job
        .out
        .clone()
        .unwrap_or_else(|| job.run.join("validation"));
    let folder = OutputFolder::open(&out).map_err(ValidationError::OutputFolder)?;
    let report = ValidationReport {
        snowscape_version: env!("CARGO_PKG_VERSION"),
        command: "validate",
        run: job.run.display().to_string(),
        simulated: r.depth_path.display().to_string(),
        bedrock: r.bedrock_path.display().to_string(),
        observed: job.observed.display().to_string(),
        mask: job.mask.as_ref().map(|p| p.display().to_string()),
        wind_from_source,
        validation,
        outputs: OUTPUTS.to_vec(),
    };
    write(folder, &report, &maps, &mut stages)?;
    Ok(ValidationOutcome { report, maps, out })
}

/// Writes `validation.json`, the side-by-side maps and the density scatter, and commits them.
fn write(
    folder: OutputFolder,
    report: &ValidationReport,
    maps: &Maps,
    stages: &mut Stages,
) -> Result<(), ValidationError> {
    let stage = folder.staging().to_path_buf();
    let json = serde_json::to_vec_pretty(report).map_err(ValidationError::Encode)?;
    write_bytes_atomic(&stage.join("validation.json"), &json)
        .map_err(crate::outputs::OutputError::from)?;
    let maps_img = side_by_side(maps.width, maps.height, &maps.observed, &maps.simulated);
    write_png(&stage.join("validation.png"), &maps_img)?;
    let compared = |v: &[f64]| -> Vec<f64> { v.iter().copied().filter(|x| !x.is_nan()).collect() };
    let scatter = density_scatter(&compared(&maps.observed), &compared(&maps.simulated));
    write_png(&stage.join("scatter.png"), &scatter)?;
    let names: Vec<String> = OUTPUTS.iter().map(|n| n.to_string()).collect();
    stages.finish()?;
    folder.commit(&names, None)?;
    Ok(())
}
