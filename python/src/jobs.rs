//! The one-shot jobs: an avalanche to rest, a mesh cover, the 3D transport run and a
//! validation, each the library's job that the command line runs.

use crate::{GridIn, GridOut, grid_in, grid_out, py_err, value_err};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use snowscape::avalanche::validation::ThicknessConvention;
use snowscape::avalanche::{AvalancheParams, SamosAtParams};
use snowscape::avalanche_job::{
    AvalancheJob, AvalancheJobError, AvalancheSettings, run as run_avalanche,
};
use snowscape::avalanche_release::ReleaseSpec;
use snowscape::control::Unattended;
use snowscape::cover::{CoverJob, CoverJobError, CoverMethod, CoverParameters};
use snowscape::mesh::{SourceFrame, UpAxis};
use std::path::PathBuf;

/// One avalanche from release to rest on `dem`, the job of `snowscape avalanche`
/// ([`snowscape::avalanche_job`], without an output folder): the peak thickness and speed, the
/// deposit and the entrained depth (grid rasters) and the flat summary (JSON,
/// [`snowscape::avalanche_job::AvalancheSummary`]).
#[pyfunction]
#[pyo3(signature = (dem, release_path, release_mask, release_point, thickness, slope_normal, params_json, duration, snow_cover))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn avalanche<'py>(
    py: Python<'py>,
    dem: GridIn,
    release_path: Option<PathBuf>,
    release_mask: Option<&[u8]>,
    release_point: Option<(f64, f64)>,
    thickness: Option<f64>,
    slope_normal: bool,
    params_json: String,
    duration: f64,
    snow_cover: f64,
) -> PyResult<(Vec<(String, GridOut<'py>)>, String)> {
    let dem = grid_in(dem)?;
    let release = match (release_path, release_mask, release_point) {
        (Some(p), None, None) => ReleaseSpec::File(p),
        (None, Some(m), None) => ReleaseSpec::Mask(m.iter().map(|&b| b != 0).collect()),
        (None, None, Some((x, y))) => ReleaseSpec::Point(x, y),
        _ => {
            return Err(value_err(
                "give exactly one release: a path, a mask or (x, y)",
            ));
        }
    };
    let mut settings = AvalancheSettings::new(release);
    settings.thickness_m = thickness;
    settings.thickness_measured = if slope_normal {
        ThicknessConvention::SlopeNormal
    } else {
        ThicknessConvention::Vertical
    };
    settings.snow_cover_m = snow_cover;
    settings.flow = avalanche_params(&params_json)?;
    settings.run.duration_s = duration;
    let job = AvalancheJob {
        source: "python".into(),
        dem,
        settings,
    };
    let outcome = py
        .detach(|| run_avalanche(&job, &mut Unattended))
        .map_err(|e| match e {
            AvalancheJobError::NoReleaseFile(_) => {
                PyOSError::new_err(snowscape::messages::clip_values(&e.to_string()))
            }
            e => py_err(e),
        })?;
    let g = job.dem.geometry();
    let rasters = outcome
        .maps()
        .into_iter()
        .map(|(name, v)| (name.to_string(), grid_out(py, g, job.dem.mask(), &v)))
        .collect();
    let summary = outcome
        .summary()
        .to_json()
        .map_err(|e| value_err(format!("the avalanche summary: {e}")))?;
    Ok((rasters, summary.to_string()))
}

/// The flow parameters from the keyword arguments' JSON. `friction` takes the command line's
/// names (`coulomb`, `voellmy`, `samosat`, `samosat-small`): `samosat` is the samosAT law with
/// AvaFrame's standard coefficients ([`SamosAtParams::standard`]), `samosat-small` with its
/// samosATSmall ones ([`SamosAtParams::small`], the default), under any `samosat={...}` keys
/// given.
fn avalanche_params(json: &str) -> PyResult<AvalancheParams> {
    let mut v: serde_json::Value =
        serde_json::from_str(json).map_err(|e| value_err(format!("avalanche parameters: {e}")))?;
    if let Some(obj) = v.as_object_mut() {
        let set = match obj.get("friction").and_then(|f| f.as_str()) {
            Some("samosat-small") => Some(SamosAtParams::small()),
            Some("samosat" | "samos_at") => Some(SamosAtParams::standard()),
            _ => None,
        };
        if let Some(set) = set {
            obj.insert("friction".into(), "samosat".into());
            let mut coefficients = match serde_json::to_value(set) {
                Ok(serde_json::Value::Object(m)) => m,
                _ => serde_json::Map::new(),
            };
            let given = obj.remove("samosat").or_else(|| obj.remove("samos_at"));
            match given {
                Some(serde_json::Value::Object(m)) => coefficients.extend(m),
                Some(other) => {
                    return Err(value_err(format!(
                        "avalanche parameters: samosat={other}: expected a dict of the samosAT coefficients"
                    )));
                }
                None => {}
            }
            obj.insert("samosat".into(), serde_json::Value::Object(coefficients));
        }
    }
    serde_json::from_value(v).map_err(|e| {
        let hint = if e.to_string().contains("unknown variant") {
            " (friction is one of coulomb, voellmy, samosat, samosat-small)"
        } else {
            ""
        };
        value_err(format!("avalanche parameters: {e}{hint}"))
    })
}

/// A snow cover of a mesh scene (`method` `diffusion` or `fearing`, `params_json` the method's
/// `[diffusion]` / `[fearing]` keys of a cover parameter file), the job of `snowscape cover`
/// ([`snowscape::cover::run`], without an output folder): the snow mesh's vertices (`f32` x,
/// y, z in the mesh file's axes and units, as `snow.obj`) and triangles (`u32`), and the report
/// (JSON, the keys of `report.json`).
#[pyfunction]
#[pyo3(signature = (mesh, method, up, scale, params_json))]
pub(crate) fn cover<'py>(
    py: Python<'py>,
    mesh: PathBuf,
    method: String,
    up: String,
    scale: f64,
    params_json: String,
) -> PyResult<(Bound<'py, PyBytes>, Bound<'py, PyBytes>, String)> {
    let cover_method = match method.as_str() {
        "diffusion" => CoverMethod::Diffusion,
        "fearing" => CoverMethod::Fearing,
        _ => {
            return Err(value_err(format!(
                "method {method:?}: expected \"diffusion\" or \"fearing\""
            )));
        }
    };
    let axis: UpAxis = up
        .parse()
        .map_err(|e| value_err(format!("up {up:?}: {e}")))?;
    let frame = SourceFrame::new(axis, scale).map_err(py_err)?;
    // The keywords are the method's table of a cover parameter file: the same parser and checks.
    let params: serde_json::Value = serde_json::from_str(&params_json)
        .map_err(|e| value_err(format!("cover parameters: {e}")))?;
    let text = toml::to_string(&serde_json::json!({ method.as_str(): params }))
        .map_err(|e| value_err(format!("cover parameters: {e} (None has no TOML form)")))?;
    let file = CoverParameters::from_toml(&text, "the cover keywords").map_err(py_err)?;
    if !mesh.is_file() {
        return Err(PyOSError::new_err(format!(
            "mesh {}: no such file",
            mesh.display()
        )));
    }
    let job = CoverJob {
        up,
        scale,
        parameters: file,
        ..CoverJob::new(mesh.clone(), cover_method)
    };
    let outcome = py
        .detach(|| snowscape::cover::run(&job, &mut Unattended))
        .map_err(|e| match e {
            CoverJobError::NoDiffusionSnow { .. } | CoverJobError::NoFearingSnow(_) => {
                value_err(format!(
                    "no snow settled on {} (try a finer resolution_m or a larger depth_m)",
                    mesh.display()
                ))
            }
            CoverJobError::NoTriangles => {
                value_err(format!("{}: the mesh has no triangles", mesh.display()))
            }
            e => py_err(e),
        })?;
    let snow = &outcome.snow;
    let mut v = Vec::with_capacity(snow.positions.len() * 12);
    for p in &snow.positions {
        for c in frame.to_file(*p) {
            v.extend_from_slice(&c.to_le_bytes());
        }
    }
    let mut f = Vec::with_capacity(snow.triangles.len() * 12);
    for t in &snow.triangles {
        for i in t {
            f.extend_from_slice(&i.to_le_bytes());
        }
    }
    // Through a JSON value, as report.json is written (its f32 values widened to f64).
    let report = serde_json::to_value(&outcome.report).map_err(|e| value_err(e.to_string()))?;
    Ok((
        PyBytes::new(py, &v),
        PyBytes::new(py, &f),
        report.to_string(),
    ))
}

/// A 3D transport run (Jubert 2018) over a DEM or a scenario's own scene, the job of
/// `snowscape transport` ([`snowscape::transport_job::run`], without an output folder): its
/// rasters (snow depth, density, saltation, suspension and sublimation fluxes, precipitation
/// ratio, wind u and v) and its report (mass budget, wind, flakes; JSON, the keys of
/// `report.json` but for `input`, which says whether a DEM was given and the scenario's name).
#[pyfunction]
#[pyo3(signature = (dem, scenario, hours, seed, flakes, wind_iterations, voxel_size, voxel_layers, uniform_precipitation))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn transport<'py>(
    py: Python<'py>,
    dem: Option<GridIn>,
    scenario: Option<String>,
    hours: Option<f64>,
    seed: Option<u64>,
    flakes: Option<usize>,
    wind_iterations: Option<usize>,
    voxel_size: Option<f64>,
    voxel_layers: Option<usize>,
    uniform_precipitation: bool,
) -> PyResult<(Vec<(String, GridOut<'py>)>, String)> {
    use snowscape::dem_source::DemSource;
    use snowscape::transport_job::{Overrides, TransportJob, TransportJobError};
    let dem = dem.map(grid_in).transpose()?;
    let dem_given = dem.is_some();
    let job = TransportJob {
        scenario,
        dem: dem.map(|grid| DemSource::Grid {
            name: "dem".into(),
            grid,
        }),
        mesh: None,
        overrides: Overrides {
            hours,
            flakes,
            seed,
            wind_iterations,
            voxel_size,
            voxel_layers,
            uniform_precipitation,
        },
        output: None,
    };
    let outcome = py
        .detach(|| snowscape::transport_job::run(&job, &mut Unattended))
        .map_err(|e| match e {
            TransportJobError::NoScene => value_err(
                "no scene: give a dem, or a scenario with a [scene] (e.g. scenario=\"castle\")",
            ),
            e => py_err(e),
        })?;
    let (g, mask) = (&outcome.run.geometry, outcome.mask());
    let rasters = outcome
        .maps()
        .into_iter()
        .map(|(n, v)| (n.to_string(), grid_out(py, g, mask, &v)))
        .collect();
    // The report of report.json, but for where the scene came from.
    let mut report = outcome.report;
    report.input = serde_json::json!({ "dem": dem_given, "scenario": report.scenario.name });
    let report = serde_json::to_string(&report).map_err(|e| value_err(e.to_string()))?;
    Ok((rasters, report))
}

/// A run's snow depth against a measured depth raster, the job of `snowscape validate`
/// ([`snowscape::validation::run`]): writes `validation.json`, `validation.png` and
/// `scatter.png` into `out` (default `RUN/validation`) and returns the report (JSON, the keys
/// of `validation.json`).
#[pyfunction]
#[pyo3(signature = (run, observed, mask, out, snow_threshold, wind_from))]
pub(crate) fn validate(
    py: Python<'_>,
    run: PathBuf,
    observed: PathBuf,
    mask: Option<PathBuf>,
    out: Option<PathBuf>,
    snow_threshold: f64,
    wind_from: Option<f64>,
) -> PyResult<String> {
    use snowscape::validation::{Naming, ValidateJob, ValidationError};
    let job = ValidateJob {
        run,
        observed,
        mask,
        out,
        snow_threshold_m: snow_threshold,
        wind_from_deg: wind_from,
    };
    let outcome = py
        .detach(|| snowscape::validation::run(&job))
        .map_err(|e| {
            // Named by the Python keywords (`observed=...`), not the command line's flags.
            let text = snowscape::messages::clip_values(&e.message(Naming::Parameters));
            let missing = matches!(
                e,
                ValidationError::MissingFile { .. } | ValidationError::MissingRunFile { .. }
            );
            if missing || crate::io_in_chain(&e) {
                PyOSError::new_err(text)
            } else {
                PyValueError::new_err(text)
            }
        })?;
    serde_json::to_string(&outcome.report).map_err(|e| value_err(e.to_string()))
}
