//! The comparison itself ([`compare`]): the inputs checked against each other (one grid for
//! the run's depth and bedrock, one CRS, overlapping extents), the observed raster and the
//! mask matched to the run's cells ([`super::matching`]), and the measures of the module docs
//! on the cells valid in every input.

use super::classes::{self, CellTerrain, Contrast, cell_terrain, contrast_ratio};
use super::matching::{CellSample, Extent, MaskSample, sample_mask, sample_observed};
use super::stats::{self, LinearFit, Metrics, quantile_map, spearman};
use super::{
    AltitudeRho, Baseline, Baselines, Exclusions, Input, Inputs, Maps, MatchingSummary, PlaneFit,
    Ratios, Settings, Validation, ValidationError, ValidationInput,
};
use snowscape_terrain::{Crs, Grid};
use std::path::Path;

fn pixel_size(g: &Grid) -> [f64; 2] {
    let t = g.geometry().transform();
    [t.pixel_width, t.pixel_height]
}

fn check_crs(run: &Input, other: &Input) -> Result<(), ValidationError> {
    match (run.grid.geometry().crs(), other.grid.geometry().crs()) {
        (Some(ours @ Crs::Epsg(a)), Some(theirs @ Crs::Epsg(b))) if a != b => {
            Err(ValidationError::CrsMismatch {
                input: other.input,
                path: other.path.to_path_buf(),
                theirs: theirs.clone(),
                ours: ours.clone(),
            })
        }
        (Some(ours), Some(theirs)) if ours != theirs => {
            tracing::warn!(
                "{} {} declares {theirs}, the run {ours}: taken as the same CRS",
                other.input.flag(),
                other.path.display()
            );
            Ok(())
        }
        _ => Ok(()),
    }
}

fn check_overlap(run: &Input, other: &Input) -> Result<(), ValidationError> {
    let (a, b) = (
        Extent::of(run.grid.geometry()),
        Extent::of(other.grid.geometry()),
    );
    if a.overlaps(&b) {
        Ok(())
    } else {
        Err(ValidationError::NoOverlap {
            input: other.input,
            path: other.path.to_path_buf(),
            extent: Box::new(b),
            run: run.path.to_path_buf(),
            run_extent: Box::new(a),
        })
    }
}

/// Checks the settings and that the inputs can be compared: depth and bedrock on one grid,
/// the observed raster and the mask in the run's CRS and overlapping it.
fn check(inputs: &Inputs, settings: &Settings) -> Result<(), ValidationError> {
    let threshold = settings.snow_threshold_m;
    if !(threshold.is_finite() && threshold >= 0.0) {
        return Err(ValidationError::BadParameter {
            input: ValidationInput::SnowThreshold,
            value: threshold,
            expected: "a depth in metres >= 0",
        });
    }
    if !settings.wind_from_deg.is_finite() {
        return Err(ValidationError::BadParameter {
            input: ValidationInput::WindFrom,
            value: settings.wind_from_deg,
            expected: "a direction in degrees clockwise from north",
        });
    }
    let (depth, bedrock) = (inputs.depth.grid, inputs.bedrock.grid);
    if !depth.geometry().same_cells(bedrock.geometry()) {
        return Err(ValidationError::GridMismatch {
            dir: inputs
                .depth
                .path
                .parent()
                .unwrap_or(Path::new("."))
                .to_path_buf(),
            bedrock: snowscape_io::describe(bedrock),
            depth: snowscape_io::describe(depth),
        });
    }
    for other in std::iter::once(&inputs.observed).chain(inputs.mask.as_ref()) {
        check_crs(&inputs.depth, other)?;
        check_overlap(&inputs.depth, other)?;
    }
    Ok(())
}

/// The run cells compared (valid in every input), their observed depths, the cells left out
/// and the matched maps.
struct Matched {
    cells: Vec<usize>,
    observed: Vec<f64>,
    excluded: Exclusions,
    maps: Maps,
    sampling: super::matching::Sampling,
}

/// Matches the observed raster and the mask to the run's cells.
fn match_cells(inputs: &Inputs) -> Matched {
    let (depth, bedrock) = (inputs.depth.grid, inputs.bedrock.grid);
    let run = depth.geometry();
    let (sampling, observed) = sample_observed(run, inputs.observed.grid);
    let mask = inputs.mask.map(|m| sample_mask(run, m.grid));
    let mut m = Matched {
        cells: Vec::new(),
        observed: Vec::new(),
        excluded: Exclusions::default(),
        maps: Maps {
            width: run.width(),
            height: run.height(),
            observed: vec![f64::NAN; run.len()],
            simulated: vec![f64::NAN; run.len()],
        },
        sampling,
    };
    for i in 0..run.len() {
        let valid = |g: &Grid| g.mask().is_valid(i) && g.data()[i].is_finite();
        if !valid(depth) || !valid(bedrock) {
            m.excluded.run_nodata += 1;
            continue;
        }
        let o = match observed[i] {
            CellSample::Outside => {
                m.excluded.outside_observed += 1;
                continue;
            }
            CellSample::Nodata => {
                m.excluded.observed_nodata += 1;
                continue;
            }
            CellSample::Value(v) => v,
        };
        match mask.as_ref().map(|k| k[i]) {
            Some(MaskSample::Outside) => m.excluded.outside_mask += 1,
            Some(MaskSample::MaskedOut) => m.excluded.masked_out += 1,
            Some(MaskSample::Use) | None => {
                m.cells.push(i);
                m.observed.push(o);
                m.maps.observed[i] = o;
                m.maps.simulated[i] = f64::from(depth.data()[i]);
            }
        }
    }
    m
}

/// The two terrain-only baselines on the compared cells.
fn baselines(altitude: &[f64], northness: &[f64], obs: &[f64], threshold: f64) -> Baselines {
    let fit = LinearFit::fit(altitude, northness, obs);
    Baselines {
        altitude_rank: Baseline {
            prediction: "observed depths quantile-mapped onto the altitude ranks; Spearman's rho of the altitude itself",
            fit: None,
            metrics: Metrics::of(&quantile_map(altitude, obs), obs, Some(altitude), threshold),
        },
        altitude_northness: Baseline {
            prediction: "least-squares plane of observed depth on altitude and northness cos(aspect)*sin(slope), fitted on the compared cells",
            fit: Some(PlaneFit {
                intercept_m: fit.intercept,
                per_m_altitude: fit.slope_a,
                per_northness: fit.slope_b,
            }),
            metrics: Metrics::of(&fit.predict(altitude, northness), obs, None, threshold),
        },
    }
}

/// Compares the run's depth with the observed depth (module docs).
pub fn compare(
    inputs: &Inputs,
    settings: &Settings,
) -> Result<(Validation, Maps), ValidationError> {
    check(inputs, settings)?;
    let Settings {
        snow_threshold_m: threshold,
        wind_from_deg,
    } = *settings;
    let Matched {
        cells,
        observed: obs,
        excluded,
        maps,
        sampling,
    } = match_cells(inputs);
    if cells.is_empty() {
        return Err(ValidationError::NoValidCells {
            run: inputs.depth.path.to_path_buf(),
            observed: inputs.observed.path.to_path_buf(),
            excluded,
        });
    }
    let (depth, bedrock) = (inputs.depth.grid, inputs.bedrock.grid);
    let sim: Vec<f64> = cells.iter().map(|&i| f64::from(depth.data()[i])).collect();
    let terrain: Vec<CellTerrain> = cells.iter().map(|&i| cell_terrain(bedrock, i)).collect();
    let altitude: Vec<f64> = terrain.iter().map(|t| t.altitude_m).collect();
    let northness: Vec<f64> = terrain.iter().map(|t| t.northness).collect();
    let ratio = |c| contrast_ratio(c, &terrain, &sim, &obs, wind_from_deg);
    let validation = Validation {
        cells_compared: cells.len(),
        excluded,
        matching: MatchingSummary {
            sampling,
            run_extent: Extent::of(depth.geometry()),
            observed_extent: Extent::of(inputs.observed.grid.geometry()),
            run_pixel_size: pixel_size(depth),
            observed_pixel_size: pixel_size(inputs.observed.grid),
            mask_extent: inputs.mask.map(|m| Extent::of(m.grid.geometry())),
        },
        snow_threshold_m: threshold,
        observed_mean_m: stats::mean(&obs),
        simulation: Metrics::of(&sim, &obs, None, threshold),
        baselines: baselines(&altitude, &northness, &obs, threshold),
        spearman_with_altitude: AltitudeRho {
            simulated: spearman(&sim, &altitude),
            observed: spearman(&obs, &altitude),
        },
        ratios: Ratios {
            band_m: classes::BAND_M,
            wind_from_deg: wind_from_deg.rem_euclid(360.0),
            north_south: ratio(Contrast::NorthSouth),
            steep_moderate: ratio(Contrast::SteepModerate),
            lee_windward: ratio(Contrast::LeeWindward),
        },
    };
    Ok((validation, maps))
}
