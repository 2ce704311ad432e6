//! The one-shot jobs: an avalanche to rest, a mesh cover (and the 3D transport run), each on
//! the library's path that the command line takes.

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
use snowscape::cover::{CoverParameters, DiffusionCoverReport, MeshInputSummary};
use snowscape::mesh::{SourceFrame, UpAxis, read_scene};
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
/// `[diffusion]` / `[fearing]` keys of a cover parameter file): the snow mesh's vertices
/// (`f32` x, y, z in the mesh file's axes and units, as `snow.obj`) and triangles (`u32`), and
/// the report (JSON).
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
    if method != "diffusion" && method != "fearing" {
        return Err(value_err(format!(
            "method {method:?}: expected \"diffusion\" or \"fearing\""
        )));
    }
    let up_name = up.as_str();
    let up: UpAxis = up
        .parse()
        .map_err(|e| value_err(format!("up {up:?}: {e}")))?;
    let frame = SourceFrame::new(up, scale).map_err(py_err)?;
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
    let (snow, report) = py.detach(|| -> PyResult<_> {
        let t0 = std::time::Instant::now();
        let (scene, mesh_report) = read_scene(&mesh, &frame).map_err(py_err)?;
        // The report the command line writes as report.json (without files or a DEM).
        let input = MeshInputSummary::new(&mesh, up_name, scale, &mesh_report, &scene);
        if method == "diffusion" {
            let c = snowscape::festenberg::cover(&scene, &file.diffusion).map_err(py_err)?;
            let report = DiffusionCoverReport::new(
                input,
                &c,
                None,
                &c.stats.timings,
                t0.elapsed().as_secs_f64(),
                Vec::new(),
            );
            let report = serde_json::to_value(&report).map_err(|e| value_err(e.to_string()))?;
            Ok((c.mesh, report))
        } else {
            let params = file.fearing_for(&scene).ok_or_else(|| {
                value_err(format!("{}: the mesh has no triangles", mesh.display()))
            })?;
            let c = snowscape::fearing::cover(&scene, &params).map_err(py_err)?;
            let input = serde_json::to_value(&input).map_err(|e| value_err(e.to_string()))?;
            let report = snowscape::cover::fearing_report(&c, Some(input))
                .map_err(|e| value_err(e.to_string()))?;
            Ok((c.surface.to_mesh("snow"), report))
        }
    })?;
    if snow.triangles.is_empty() {
        return Err(value_err(format!(
            "no snow settled on {} (try a finer resolution_m or a larger depth_m)",
            mesh.display()
        )));
    }
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
    Ok((
        PyBytes::new(py, &v),
        PyBytes::new(py, &f),
        report.to_string(),
    ))
}

/// A 3D transport run (Jubert 2018) over a DEM or a scenario's own scene: its rasters (snow
/// depth, density, saltation, suspension and sublimation fluxes, precipitation ratio, wind u
/// and v) and its report (mass budget, wind, flakes; JSON).
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
    use snowscape::terrain::NodataMask;
    use snowscape::transport::scenario::{SceneSpec, run};
    use snowscape::transport_job::{
        Overrides, TransportReport, dem_heights, fit_to_scene, load_scenario,
    };
    let t0 = std::time::Instant::now();
    let (mut scenario, from_file) = load_scenario(scenario.as_deref()).map_err(py_err)?;
    let dem_given = dem.is_some();
    let (geometry, heights, mask) = match dem {
        Some(d) => {
            let grid = grid_in(d)?;
            let (heights, _) = dem_heights(&grid, "dem").map_err(py_err)?;
            scenario.scene = SceneSpec::Input;
            (grid.geometry().clone(), heights, grid.mask().clone())
        }
        None => match scenario.build_scene().map_err(py_err)? {
            Some((g, h)) => (g, h, NodataMask::all_valid()),
            None => {
                return Err(value_err(
                    "no scene: give a dem, or a scenario with a [scene] (e.g. scenario=\"castle\")",
                ));
            }
        },
    };
    let overrides = Overrides {
        hours,
        flakes,
        seed,
        wind_iterations,
        voxel_size,
        voxel_layers,
        uniform_precipitation,
    };
    if !from_file && !overrides.sets_voxels() {
        fit_to_scene(&mut scenario, &geometry, &heights);
    }
    overrides.apply(&mut scenario).map_err(py_err)?;
    let out = py
        .detach(|| run(&scenario, &geometry, &heights))
        .map_err(py_err)?;
    let maps: Vec<(&str, Vec<f32>)> = vec![
        ("depth", out.state.depth()),
        ("density", out.state.density.clone()),
        ("q_salt", out.q_salt.clone()),
        ("q_susp", out.q_susp.clone()),
        ("q_subl", out.q_subl.clone()),
        ("precipitation", out.precipitation_ratio.clone()),
        ("wind_u", out.wind_u.clone()),
        ("wind_v", out.wind_v.clone()),
    ];
    let rasters = maps
        .into_iter()
        .map(|(n, v)| (n.to_string(), grid_out(py, &out.geometry, &mask, &v)))
        .collect();
    // The report the command line writes as report.json.
    let input = serde_json::json!({ "dem": dem_given, "scenario": scenario.name });
    let report = TransportReport::new(&scenario, &out, input, t0.elapsed().as_secs_f64());
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
