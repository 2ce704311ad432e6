//! Validation of a run's snow depth against a measured depth raster (`snowscape validate`, the
//! Python package's `snowscape.validate`; the job and its typed `validation.json` are
//! [`run`] and [`ValidationReport`]).
//!
//! [`compare`] matches the observed raster (and an optional mask) to the run's cells by map
//! coordinates ([`matching`]), keeps the cells valid in every input, and measures on them:
//!
//! - the simulation: Spearman's ρ, Pearson's r, RMSE, bias (simulated − observed) and the
//!   snow-cover agreement above a depth threshold (accuracy, hit rate, false alarm ratio,
//!   CSI, Cohen's κ) ([`stats`]);
//! - two baselines that know only the terrain, to say whether the simulation beats them:
//!   (a) **altitude rank**: ρ is that of the altitude itself; for the other metrics the
//!   altitude ranks are quantile-mapped onto the observed depths (the cell of altitude rank R
//!   gets the observed depth of rank R, [`stats::quantile_map`]), a prediction with the
//!   observed distribution ordered by altitude; (b) **altitude + northness**: the least-squares
//!   plane depth ≈ c₀ + c₁·altitude + c₂·northness fitted on the compared cells themselves
//!   (in-sample, so an optimistic baseline: it has seen the observations);
//! - depth ratios stratified by 200 m elevation bands and pooled over them (the ratio of the
//!   band-weighted class means, not a mean of per-band ratios), simulated and observed:
//!   north/south, steep/moderate, lee/windward, with the per-band table and the cell counts
//!   per class ([`classes`]);
//! - ρ of each depth with altitude (measured snow is far less tied to altitude than a
//!   temperature-driven model: see `docs/src/model.md#sources-and-the-reading-of-table-2`).
//!
//! [`figures`] draws the side-by-side maps and the density scatter; [`summary`] prints the
//! table.

pub mod classes;
mod compare;
pub mod figures;
mod job;
pub mod matching;
pub mod stats;
pub mod summary;

pub use compare::compare;
pub use job::{
    DEFAULT_WIND_FROM_DEG, OUTPUTS, ValidateJob, ValidationOutcome, ValidationReport, run, run_with,
};

use classes::ContrastRatio;
use matching::{Extent, Sampling};
use serde::Serialize;
use snowscape_io::RasterError;
use snowscape_terrain::{Crs, Grid};
use stats::Metrics;
use std::fmt;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Which input of a validation a file or value came from ([`ValidateJob`]'s fields), named as
/// each front end names it: the command line's flag or the Python keyword.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ValidationInput {
    /// The run folder (`--run`, `run=`).
    Run,
    /// The observed depth raster (`--observed`, `observed=`).
    Observed,
    /// The mask raster (`--mask`, `mask=`).
    Mask,
    /// The snow-cover threshold (`--snow-threshold`, `snow_threshold=`).
    SnowThreshold,
    /// The prevailing wind direction (`--wind-from`, `wind_from=`).
    WindFrom,
}

impl ValidationInput {
    /// The command line's flag.
    pub fn flag(self) -> &'static str {
        match self {
            Self::Run => "--run",
            Self::Observed => "--observed",
            Self::Mask => "--mask",
            Self::SnowThreshold => "--snow-threshold",
            Self::WindFrom => "--wind-from",
        }
    }

    /// The Python keyword (and [`ValidateJob`]'s field, less its unit).
    pub fn parameter(self) -> &'static str {
        match self {
            Self::Run => "run",
            Self::Observed => "observed",
            Self::Mask => "mask",
            Self::SnowThreshold => "snow_threshold",
            Self::WindFrom => "wind_from",
        }
    }

    /// The input with its value, as `naming` says it: `--observed FILE` or `observed=FILE`.
    fn with(self, naming: Naming, value: impl fmt::Display) -> String {
        match naming {
            Naming::Flags => format!("{} {value}", self.flag()),
            Naming::Parameters => format!("{}={value}", self.parameter()),
        }
    }

    /// The input alone, as `naming` says it.
    fn name(self, naming: Naming) -> &'static str {
        match naming {
            Naming::Flags => self.flag(),
            Naming::Parameters => self.parameter(),
        }
    }
}

/// How an error names its input: by the command line's flags (its `Display`) or by the Python
/// keywords ([`ValidationError::message`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Naming {
    Flags,
    Parameters,
}

/// Why a validation cannot run. Each names the input ([`ValidationInput`]) and the file or
/// value at fault; `Display` names inputs by their flags, [`ValidationError::message`] either
/// way.
#[derive(Debug, Error)]
pub enum ValidationError {
    MissingRunFile {
        dir: PathBuf,
        file: &'static str,
    },
    MissingFile {
        input: ValidationInput,
        path: PathBuf,
    },
    Read {
        input: ValidationInput,
        #[source]
        source: RasterError,
    },
    GridMismatch {
        dir: PathBuf,
        bedrock: String,
        depth: String,
    },
    CrsMismatch {
        input: ValidationInput,
        path: PathBuf,
        theirs: Crs,
        ours: Crs,
    },
    NoOverlap {
        input: ValidationInput,
        path: PathBuf,
        extent: Box<Extent>,
        run: PathBuf,
        run_extent: Box<Extent>,
    },
    NoValidCells {
        run: PathBuf,
        observed: PathBuf,
        excluded: Exclusions,
    },
    BadParameter {
        input: ValidationInput,
        value: f64,
        expected: &'static str,
    },
    Report {
        path: PathBuf,
        message: String,
    },
    /// The output folder cannot be opened (nothing was written).
    OutputFolder(crate::outputs::OutputError),
    /// An output could not be written.
    Output(#[from] crate::outputs::OutputError),
    Encode(#[source] serde_json::Error),
    /// The front end cancelled the job before `stage` (nothing was written).
    Cancelled {
        stage: &'static str,
    },
}

impl From<crate::control::StageCancelled> for ValidationError {
    fn from(c: crate::control::StageCancelled) -> Self {
        ValidationError::Cancelled { stage: c.0 }
    }
}

impl fmt::Display for ValidationError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message(Naming::Flags))
    }
}

impl ValidationError {
    /// The message, naming the inputs as `naming` says (the CLI's flags, Python's keywords).
    pub fn message(&self, naming: Naming) -> String {
        use ValidationInput::{Observed, Run};
        let path = |p: &PathBuf| p.display().to_string();
        match self {
            Self::MissingRunFile { dir, file } => format!(
                "{}: no {file} in the run folder (`snowscape run` and `snowscape demo` write it)",
                Run.with(naming, dir.display())
            ),
            Self::MissingFile { input, path: p } => {
                format!("{}: no such file", input.with(naming, path(p)))
            }
            Self::Read { input, source } => format!("{}: {source}", input.name(naming)),
            Self::GridMismatch {
                dir,
                bedrock,
                depth,
            } => format!(
                "{}: bedrock.tif ({bedrock}) and depth.tif ({depth}) are not the same grid",
                Run.with(naming, dir.display())
            ),
            Self::CrsMismatch {
                input,
                path: p,
                theirs,
                ours,
            } => format!(
                "{} is in {theirs} but the run is in {ours}: reproject it onto the run's CRS",
                input.with(naming, path(p))
            ),
            Self::NoOverlap {
                input,
                path: p,
                extent,
                run,
                run_extent,
            } => format!(
                "{} does not overlap the run: it covers {extent}, the run {} covers {run_extent} (map coordinates)",
                input.with(naming, path(p)),
                run.display()
            ),
            Self::NoValidCells {
                run,
                observed,
                excluded,
            } => format!(
                "no cell to compare between the run {} and {}: {excluded}",
                run.display(),
                Observed.with(naming, observed.display())
            ),
            Self::BadParameter {
                input,
                value,
                expected,
            } => format!("{}: expected {expected}", input.with(naming, value)),
            Self::Report { path: p, message } => {
                format!("{}: {message}", Run.with(naming, path(p)))
            }
            Self::OutputFolder(e) | Self::Output(e) => e.to_string(),
            Self::Encode(e) => format!("cannot encode validation.json: {e}"),
            Self::Cancelled { stage } => format!("cancelled before {stage}; nothing was written"),
        }
    }

    /// Whether the validation was refused for its input (nothing was written) rather than
    /// failing while it wrote.
    pub fn is_bad_input(&self) -> bool {
        !matches!(
            self,
            Self::Output(_) | Self::Encode(_) | Self::Cancelled { .. }
        )
    }
}

/// A raster of the validation and where it came from.
#[derive(Debug, Clone, Copy)]
pub struct Input<'a> {
    pub grid: &'a Grid,
    pub path: &'a Path,
    /// The input that named it (the run, the observed raster, the mask).
    pub input: ValidationInput,
}

/// What to compare.
#[derive(Debug, Clone, Copy)]
pub struct Inputs<'a> {
    /// The run's `depth.tif` (total snow depth, metres).
    pub depth: Input<'a>,
    /// The run's `bedrock.tif` (same grid): altitude, slope, aspect.
    pub bedrock: Input<'a>,
    pub observed: Input<'a>,
    pub mask: Option<Input<'a>>,
}

/// The options of a validation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Depth above which a cell is snow-covered, metres (>= 0).
    pub snow_threshold_m: f64,
    /// Direction the prevailing wind blows from, degrees clockwise from north.
    pub wind_from_deg: f64,
}

/// Run cells left out of the comparison, by the first reason that applies.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Exclusions {
    /// Nodata (or not finite) in the run's depth or bedrock.
    pub run_nodata: usize,
    /// Outside the observed raster.
    pub outside_observed: usize,
    /// Nodata in the observed raster.
    pub observed_nodata: usize,
    /// Outside the mask.
    pub outside_mask: usize,
    /// Zero or nodata in the mask.
    pub masked_out: usize,
}

impl fmt::Display for Exclusions {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} run cells are nodata, {} lie outside the observed raster, {} are nodata there, {} lie outside the mask, {} are masked out",
            self.run_nodata,
            self.outside_observed,
            self.observed_nodata,
            self.outside_mask,
            self.masked_out
        )
    }
}

/// How the rasters were matched.
#[derive(Debug, Clone, Serialize)]
pub struct MatchingSummary {
    pub sampling: Sampling,
    pub run_extent: Extent,
    pub observed_extent: Extent,
    /// Pixel width and height in CRS units.
    pub run_pixel_size: [f64; 2],
    pub observed_pixel_size: [f64; 2],
    pub mask_extent: Option<Extent>,
}

/// A terrain-only baseline and how it scores.
#[derive(Debug, Clone, Serialize)]
pub struct Baseline {
    pub prediction: &'static str,
    /// The fitted plane (altitude + northness baseline).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit: Option<PlaneFit>,
    pub metrics: Metrics,
}

/// depth ≈ intercept_m + per_m_altitude·altitude + per_northness·northness.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct PlaneFit {
    pub intercept_m: f64,
    pub per_m_altitude: f64,
    pub per_northness: f64,
}

/// Both baselines.
#[derive(Debug, Clone, Serialize)]
pub struct Baselines {
    pub altitude_rank: Baseline,
    pub altitude_northness: Baseline,
}

/// Spearman's ρ of a depth with altitude.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct AltitudeRho {
    pub simulated: Option<f64>,
    pub observed: Option<f64>,
}

/// The depth ratios between terrain classes.
#[derive(Debug, Clone, Serialize)]
pub struct Ratios {
    pub band_m: f64,
    pub wind_from_deg: f64,
    pub north_south: ContrastRatio,
    pub steep_moderate: ContrastRatio,
    pub lee_windward: ContrastRatio,
}

/// Everything a validation measured (the body of `validation.json`).
#[derive(Debug, Clone, Serialize)]
pub struct Validation {
    pub cells_compared: usize,
    pub excluded: Exclusions,
    pub matching: MatchingSummary,
    pub snow_threshold_m: f64,
    pub observed_mean_m: f64,
    pub simulation: Metrics,
    pub baselines: Baselines,
    pub spearman_with_altitude: AltitudeRho,
    pub ratios: Ratios,
}

/// The matched maps, one value per run cell (row-major), NaN where a cell is not compared.
#[derive(Debug, Clone)]
pub struct Maps {
    pub width: usize,
    pub height: usize,
    pub observed: Vec<f64>,
    pub simulated: Vec<f64>,
}

/// The prevailing wind of a run from its `report.json`: the direction of the mean wind
/// vector over the season, each weather period's direction weighted by its speed times its
/// length in days (the last period lasts until `parameters.scenario.days`). `None` when the
/// report has no weather timeline (or its winds cancel out).
pub fn prevailing_wind_from(report: &serde_json::Value) -> Option<f64> {
    let params = report.get("parameters")?;
    let weather = params
        .get("weather")
        .and_then(|w| w.as_array())
        .filter(|w| !w.is_empty())
        .or_else(|| params.pointer("/scenario/weather")?.as_array())?;
    let days = params.pointer("/scenario/days").and_then(|d| d.as_f64());
    let mut periods: Vec<(f64, f64, f64)> = weather
        .iter()
        .filter_map(|w| {
            Some((
                w.get("from_day").and_then(|v| v.as_f64()).unwrap_or(0.0),
                w.get("wind_from_deg")?.as_f64()?,
                w.get("wind_speed_m_s")
                    .and_then(|v| v.as_f64())
                    .unwrap_or(1.0),
            ))
        })
        .collect();
    periods.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut east, mut north) = (0.0, 0.0);
    for (k, &(from, dir, speed)) in periods.iter().enumerate() {
        let until = periods.get(k + 1).map(|p| p.0).or(days);
        let length = until.map_or(1.0, |u| (u - from).max(0.0));
        let r = dir.to_radians();
        east += length * speed * r.sin();
        north += length * speed * r.cos();
    }
    let norm = (east * east + north * north).sqrt();
    (norm > 1e-9).then(|| east.atan2(north).to_degrees().rem_euclid(360.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn prevailing_wind_is_the_weighted_vector_mean() {
        // 10 days from 270 at 10 m/s, 10 days from 0 at 10 m/s: the mean points from 315.
        let r = json!({"parameters": {"weather": [
            {"from_day": 10.0, "wind_from_deg": 0.0, "wind_speed_m_s": 10.0},
            {"from_day": 0.0, "wind_from_deg": 270.0, "wind_speed_m_s": 10.0},
        ], "scenario": {"days": 20.0}}});
        assert!((prevailing_wind_from(&r).unwrap() - 315.0).abs() < 1e-9);
        // A longer westerly period pulls it west.
        let r = json!({"parameters": {"weather": [
            {"from_day": 0.0, "wind_from_deg": 270.0, "wind_speed_m_s": 10.0},
            {"from_day": 15.0, "wind_from_deg": 0.0, "wind_speed_m_s": 10.0},
        ], "scenario": {"days": 20.0}}});
        let w = prevailing_wind_from(&r).unwrap();
        assert!((w - (360.0 - 71.565_051)).abs() < 1e-3, "{w}");
        assert_eq!(prevailing_wind_from(&json!({"parameters": {}})), None);
        assert_eq!(prevailing_wind_from(&json!({})), None);
    }
}
