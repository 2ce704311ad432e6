//! `snowscape._snowscape`: the native half of the Python package. Rasters cross the boundary
//! as little-endian `f32` bytes (NaN = nodata) with their width, height, GDAL-style geometry
//! and CRS; `snowscape/__init__.py` turns them into numpy arrays. Every job calls the library's
//! own path (the one `snowscape run` and `snowscape avalanche` take), so that the same inputs
//! give the same bytes from Python as from the command line.

use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use snowscape::io::{RasterFormat, ReadOptions, read_dem, write_raster};
use snowscape::season::scenario::Scenario;
use snowscape::season::winter::Winter;
use snowscape::season_run::{CHECKPOINT, RESOLVED_SCENARIO, write_checkpoint};
use snowscape::simulation::{CHUNK_DAYS, Control, Simulation};
use snowscape::terrain::{
    Crs, GeoTransform, Grid, GridGeometry, LayeredTerrain, NodataMask, SnowLayer,
};
use std::path::{Path, PathBuf};

/// A raster coming in: `f32` bytes, width, height, `(origin_x, origin_y, pixel_width,
/// pixel_height)` and the CRS (EPSG code as `EPSG:n`, or WKT).
pub(crate) type GridIn<'a> = (&'a [u8], usize, usize, (f64, f64, f64, f64), Option<String>);

/// A raster going out: as [`GridIn`], plus the metric cell size `(x, y)`.
pub(crate) type GridOut<'py> = (
    Bound<'py, PyBytes>,
    usize,
    usize,
    (f64, f64, f64, f64),
    Option<String>,
    (f64, f64),
);

/// The message of an error and of its sources, as the command line prints it.
pub(crate) fn message(e: &(dyn std::error::Error + 'static)) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        let part = s.to_string();
        if !text.contains(&part) {
            text.push_str(": ");
            text.push_str(&part);
        }
        source = s.source();
    }
    text
}

/// Whether an I/O error is among `e` and its sources (it is raised as `OSError`).
pub(crate) fn io_in_chain(e: &(dyn std::error::Error + 'static)) -> bool {
    let mut cur = Some(e);
    while let Some(s) = cur {
        if s.downcast_ref::<std::io::Error>().is_some() {
            return true;
        }
        cur = s.source();
    }
    false
}

/// `OSError` when an I/O error lies under `e` (a file missing, unreadable, unwritable), else
/// `ValueError`, with the command line's message.
pub(crate) fn py_err(e: impl std::error::Error + 'static) -> PyErr {
    let text = snowscape::messages::clip_values(&message(&e));
    if io_in_chain(&e) {
        PyOSError::new_err(text)
    } else {
        PyValueError::new_err(text)
    }
}

/// `ValueError` with `text`, every over-long value in it clipped
/// ([`snowscape::messages::clip_values`]: a 10 MB string is not echoed whole).
pub(crate) fn value_err(text: impl Into<String>) -> PyErr {
    PyValueError::new_err(snowscape::messages::clip_values(&text.into()))
}

/// A [`Grid`] from a raster coming in (NaN cells are nodata).
pub(crate) fn grid_in(g: GridIn) -> PyResult<Grid> {
    let (bytes, w, h, (ox, oy, pw, ph), crs) = g;
    let n = w
        .checked_mul(h)
        .filter(|n| n.checked_mul(4) == Some(bytes.len()))
        .ok_or_else(|| {
            value_err(format!(
                "raster values: {} bytes for {w} x {h} cells of float32",
                bytes.len()
            ))
        })?;
    let crs = match crs.as_deref().map(str::trim) {
        None | Some("") => None,
        Some(text) => Some(Crs::parse(text).ok_or_else(|| value_err(format!("crs {text:?}")))?),
    };
    let transform = GeoTransform {
        origin_x: ox,
        origin_y: oy,
        pixel_width: pw,
        pixel_height: ph,
    };
    let geometry = GridGeometry::from_transform(w, h, transform, crs).map_err(py_err)?;
    let mut data = Vec::with_capacity(n);
    let mut invalid = vec![false; n];
    for (i, c) in bytes.chunks_exact(4).enumerate() {
        let v = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
        if v.is_nan() {
            invalid[i] = true;
            data.push(0.0);
        } else if !v.is_finite() {
            return Err(value_err(format!(
                "raster value at row {}, column {} is {v}: values must be finite (NaN marks nodata)",
                i / w,
                i % w
            )));
        } else {
            data.push(v);
        }
    }
    let mask = if invalid.iter().any(|&b| b) {
        NodataMask::from_invalid(invalid)
    } else {
        NodataMask::all_valid()
    };
    Grid::new(geometry, data, mask).map_err(py_err)
}

/// A raster going out: `values` on `geometry`, NaN where `mask` says nodata.
pub(crate) fn grid_out<'py>(
    py: Python<'py>,
    geometry: &GridGeometry,
    mask: &NodataMask,
    values: &[f32],
) -> GridOut<'py> {
    let mut bytes = Vec::with_capacity(values.len() * 4);
    for (i, v) in values.iter().enumerate() {
        let v = if mask.is_valid(i) { *v } else { f32::NAN };
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    let t = geometry.transform();
    (
        PyBytes::new(py, &bytes),
        geometry.width(),
        geometry.height(),
        (t.origin_x, t.origin_y, t.pixel_width, t.pixel_height),
        geometry.crs().map(|c| c.to_string()),
        (geometry.cell_size_x(), geometry.cell_size_y()),
    )
}

pub(crate) fn grid_parts<'py>(py: Python<'py>, g: &Grid) -> GridOut<'py> {
    grid_out(py, g.geometry(), g.mask(), g.data())
}

/// Reads a raster (every format the command line reads), with the command line's input options.
#[pyfunction]
#[pyo3(signature = (path, format=None, cell_size=None, height_range=None, raw_size=None, crs=None))]
fn read_raster<'py>(
    py: Python<'py>,
    path: PathBuf,
    format: Option<String>,
    cell_size: Option<f64>,
    height_range: Option<(f64, f64)>,
    raw_size: Option<(usize, usize)>,
    crs: Option<String>,
) -> PyResult<GridOut<'py>> {
    let mut o = ReadOptions::default();
    if let Some(f) = format {
        o.format = Some(
            f.parse::<RasterFormat>()
                .map_err(|e| value_err(format!("format {f:?}: {e}")))?,
        );
    }
    // The values' ranges are checked by the reader (`ReadOptions::validate`), as for the
    // command line.
    o.cell_size = cell_size;
    o.height_range = height_range;
    o.raw_size = raw_size;
    if let Some(c) = crs {
        o.crs = Some(Crs::parse(&c).ok_or_else(|| value_err(format!("crs {c:?}: empty")))?);
    }
    let grid = py.detach(|| read_dem(&path, &o)).map_err(py_err)?;
    Ok(grid_parts(py, &grid))
}

/// Writes a raster in the format its extension names (atomically, as the command line does).
#[pyfunction]
fn write(py: Python<'_>, raster: GridIn, path: PathBuf) -> PyResult<()> {
    let grid = grid_in(raster)?;
    let format = RasterFormat::from_path(&path).ok_or_else(|| {
        value_err(format!(
            "{}: unknown raster extension; expected .tif, .tiff, .asc, .png, .raw, .r16, .npy or .exr",
            path.display()
        ))
    })?;
    py.detach(|| write_raster(&path, &grid, format))
        .map_err(py_err)
}

/// Runs `f` on the pool when one was asked for.
fn on_pool<T: Send>(pool: &Option<rayon::ThreadPool>, f: impl FnOnce() -> T + Send) -> T {
    match pool {
        Some(p) => p.install(f),
        None => f(),
    }
}

/// A season run from Python: the chunks run without the GIL on the season's thread pool; the
/// progress callback and Ctrl-C are heard between them.
struct PyControl<'py, 'a> {
    py: Python<'py>,
    pool: &'a Option<rayon::ThreadPool>,
    progress: Option<&'a Py<PyAny>>,
    /// The exception that stopped the run (the callback's, or Ctrl-C's KeyboardInterrupt).
    raised: Option<PyErr>,
}

impl Control for PyControl<'_, '_> {
    fn progress(&mut self, day: f64, _stop_time: f64) {
        if self.raised.is_none()
            && let Some(callback) = self.progress
            && let Err(e) = callback.call1(self.py, (day,))
        {
            self.raised = Some(e);
        }
    }

    fn cancelled(&mut self) -> bool {
        if self.raised.is_none()
            && let Err(e) = self.py.check_signals()
        {
            self.raised = Some(e);
        }
        self.raised.is_some()
    }

    fn run_chunk(&mut self, chunk: &mut (dyn FnMut() + Send)) {
        let pool = self.pool;
        self.py.detach(|| on_pool(pool, chunk));
    }
}

/// The most worker threads `threads=` takes.
const MAX_THREADS: i64 = 1024;

/// A pool of `threads` workers (`None`: the global pool). Taken as a signed integer so that
/// `threads=-1` is a `ValueError` naming it, not an `OverflowError` of the conversion.
fn thread_pool(threads: Option<i64>) -> PyResult<Option<rayon::ThreadPool>> {
    threads
        .map(|n| {
            if !(1..=MAX_THREADS).contains(&n) {
                return Err(value_err(format!(
                    "threads={n}: must be a whole number in 1..={MAX_THREADS}"
                )));
            }
            let n = n as usize;
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| value_err(format!("threads {n}: {e}")))
        })
        .transpose()
}

/// A scenario from TOML text (a file's or a dict's), or the default; `seed` overrides its seed.
fn scenario_of(text: Option<&str>, name: &str, seed: Option<u64>) -> PyResult<Scenario> {
    let mut s = match text {
        Some(t) => Scenario::from_toml(t, name).map_err(py_err)?,
        None => Scenario::default(),
    };
    if let Some(seed) = seed {
        s.seed = seed;
    }
    s.validate(name).map_err(py_err)?;
    Ok(s)
}

/// Refuses a season on `cells` cells that would not fit in the memory available
/// (`MemoryError`, before any work: the check `snowscape run` makes).
fn check_memory(cells: usize) -> PyResult<()> {
    snowscape::memory::check_season(cells, None)
        .map_err(|e| pyo3::exceptions::PyMemoryError::new_err(e.to_string()))
}

/// A winter on a terrain (the `Winter` of the Python package).
#[pyclass(name = "_Winter", module = "snowscape._snowscape")]
struct PyWinter {
    winter: Winter,
    pool: Option<rayon::ThreadPool>,
}

#[pymethods]
impl PyWinter {
    /// `scenario`: TOML text (a file's), JSON text (a dict's, when `is_json`) or `None` (the
    /// default scenario).
    ///
    /// `forcing`: a station forcing file (as `snowscape run --forcing`; else the scenario's
    /// `forcing`, relative to the scenario file), at `station_altitude` m unless the file
    /// states it: the season follows the record from its first hour, for the record's length
    /// or the scenario's `days` when it sets them (`days_given`) within the record.
    #[new]
    #[pyo3(signature = (dem, scenario, is_json, scenario_name, seed, threads, forcing=None, station_altitude=None, days_given=false))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        dem: GridIn,
        scenario: Option<String>,
        is_json: bool,
        scenario_name: String,
        seed: Option<u64>,
        threads: Option<i64>,
        forcing: Option<PathBuf>,
        station_altitude: Option<f64>,
        days_given: bool,
    ) -> PyResult<Self> {
        let bedrock = grid_in(dem)?;
        bedrock.check_terrain().map_err(py_err)?;
        let text = match (scenario, is_json) {
            (Some(json), true) => {
                // A dict's keys are a scenario file's: through TOML, the same parser and checks.
                let v: serde_json::Value = serde_json::from_str(&json)
                    .map_err(|e| value_err(format!("{scenario_name}: {e}")))?;
                Some(toml::to_string(&v).map_err(|e| {
                    value_err(format!("{scenario_name}: {e} (None has no TOML form)"))
                })?)
            }
            (text, _) => text,
        };
        let mut scenario = scenario_of(text.as_deref(), &scenario_name, seed)?;
        if station_altitude.is_some() {
            scenario.station_altitude_m = station_altitude;
        }
        let scenario_file = (!is_json && text.is_some()).then(|| Path::new(&scenario_name));
        let days = days_given.then_some(scenario.days);
        let forcing =
            snowscape::station::forcing_path(forcing.as_deref(), &scenario, scenario_file)
                .map(|p| snowscape::station::adopt_station_forcing(&mut scenario, &p, days))
                .transpose()
                .map_err(|e| value_err(e.to_string()))?;
        scenario
            .validate_on(bedrock.geometry(), &scenario_name)
            .map_err(py_err)?;
        check_memory(bedrock.geometry().len())?;
        let pool = thread_pool(threads)?;
        let winter = py
            .detach(|| {
                on_pool(&pool, || {
                    Winter::with_forcing(scenario, LayeredTerrain::from_bedrock(bedrock), forcing)
                })
            })
            .map_err(py_err)?;
        Ok(Self { winter, pool })
    }

    /// Resumes the season saved in `dir` (`checkpoint.bin` and `scenario.toml`, as
    /// `save_checkpoint` and `snowscape run` write them) on its terrain.
    #[staticmethod]
    #[pyo3(signature = (dir, dem, threads=None))]
    fn resume(py: Python<'_>, dir: PathBuf, dem: GridIn, threads: Option<i64>) -> PyResult<Self> {
        let bedrock = grid_in(dem)?;
        bedrock.check_terrain().map_err(py_err)?;
        let scenario_path = dir.join(RESOLVED_SCENARIO);
        // Both read as regular files of bounded size (a link to /dev/zero or a FIFO is refused
        // before any read), as `snowscape run --resume` reads them.
        let text = snowscape::io::input::read_regular_text(&scenario_path)
            .map_err(|e| PyOSError::new_err(e.to_string()))?;
        let scenario =
            Scenario::from_toml(&text, &scenario_path.display().to_string()).map_err(py_err)?;
        check_memory(bedrock.geometry().len())?;
        // A season driven by a station record reads the record again (the resolved scenario
        // names it).
        let forcing = snowscape::station::resumed_station_forcing(&scenario)
            .map_err(|e| value_err(e.to_string()))?;
        let path = dir.join(CHECKPOINT);
        let pool = thread_pool(threads)?;
        let winter = py
            .detach(|| {
                on_pool(&pool, || {
                    Winter::resume_from_file(
                        scenario,
                        LayeredTerrain::from_bedrock(bedrock),
                        forcing,
                        &path,
                    )
                })
            })
            .map_err(|e| {
                value_err(format!(
                    "cannot resume from {}: {}",
                    path.display(),
                    message(&e)
                ))
            })?;
        Ok(Self { winter, pool })
    }

    /// The season's day.
    #[getter]
    fn day(&self) -> f64 {
        self.winter.day()
    }

    /// The season's length, days.
    #[getter]
    fn days(&self) -> f64 {
        self.winter.scenario().days
    }

    /// The scenario as TOML (what `save_checkpoint` writes beside the state).
    fn scenario_toml(&self) -> PyResult<String> {
        toml::to_string(self.winter.scenario()).map_err(|e| value_err(e.to_string()))
    }

    /// Runs the season to `day` through the library's driver (`snowscape::simulation`), in
    /// chunks of at most `CHUNK_DAYS` without the GIL; between chunks calls `progress(day)`
    /// and honours Ctrl-C (the state stays consistent and runs on).
    #[pyo3(signature = (day, progress=None))]
    fn run_until(&mut self, py: Python<'_>, day: f64, progress: Option<Py<PyAny>>) -> PyResult<()> {
        let days = self.winter.scenario().days;
        if !(day.is_finite() && day >= 0.0) {
            return Err(value_err(format!("day {day} must be finite and >= 0")));
        }
        if day > days + 1e-9 {
            return Err(value_err(format!(
                "day {day} lies past the season's end ({days} days): give the scenario more days, e.g. scenario={{\"days\": {day}}}"
            )));
        }
        let Self { winter, pool } = self;
        let mut control = PyControl {
            py,
            pool,
            progress: progress.as_ref(),
            raised: None,
        };
        Simulation::new(winter, day)
            .run(&mut control)
            .map_err(|e| py_err(*e))?;
        // The callback's exception, or Ctrl-C's KeyboardInterrupt, that stopped the run.
        control.raised.map_or(Ok(()), Err)
    }

    /// Total snow depth of every cell, m.
    fn depth<'py>(&self, py: Python<'py>) -> GridOut<'py> {
        let t = &self.winter.terrain;
        grid_out(py, t.geometry(), t.mask(), &t.total_depth())
    }

    /// One snow layer (`compacted`, `stable`, `unstable`, `powder`) or `bedrock`, m.
    fn layer<'py>(&self, py: Python<'py>, name: &str) -> PyResult<GridOut<'py>> {
        let t = &self.winter.terrain;
        if name == "bedrock" {
            return Ok(grid_out(py, t.geometry(), t.mask(), &t.bedrock));
        }
        let layer = SnowLayer::ALL
            .into_iter()
            .find(|l| l.name() == name)
            .ok_or_else(|| {
                value_err(format!(
                    "unknown layer {name:?}; expected compacted, stable, unstable, powder or bedrock"
                ))
            })?;
        Ok(grid_out(py, t.geometry(), t.mask(), t.layer(layer)))
    }

    /// The season's volume budget as JSON.
    fn budget_json(&self) -> PyResult<String> {
        serde_json::to_string(self.winter.budget()).map_err(|e| value_err(e.to_string()))
    }

    /// Triggers an avalanche at map position `(x, y)`; its record as JSON.
    fn trigger_avalanche(&mut self, py: Python<'_>, x: f64, y: f64) -> PyResult<String> {
        let Self { winter, pool } = self;
        let rec = py
            .detach(|| on_pool(pool, || winter.trigger_avalanche(x, y)))
            .map_err(py_err)?;
        serde_json::to_string(&rec).map_err(|e| value_err(e.to_string()))
    }

    /// Writes `dir/checkpoint.bin` and `dir/scenario.toml` (the layout `snowscape run --resume
    /// DIR` reads).
    fn save_checkpoint(&self, py: Python<'_>, dir: PathBuf) -> PyResult<()> {
        std::fs::create_dir_all(&dir)
            .map_err(|e| PyOSError::new_err(format!("cannot create {}: {e}", dir.display())))?;
        let text = self.scenario_toml()?;
        py.detach(|| write_checkpoint(&dir, &self.winter))
            .map_err(py_err)?;
        snowscape::io::write_bytes_atomic(&dir.join(RESOLVED_SCENARIO), text.as_bytes())
            .map_err(py_err)
    }
}

mod jobs;

#[pymodule]
fn _snowscape(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // A CPU without what the build assumes would die on an illegal instruction.
    let missing = snowscape::cpu::missing_features();
    if !missing.is_empty() {
        return Err(pyo3::exceptions::PyImportError::new_err(
            snowscape::cpu::requirement_message(&missing),
        ));
    }
    m.add_function(wrap_pyfunction!(read_raster, m)?)?;
    m.add_function(wrap_pyfunction!(write, m)?)?;
    m.add_function(wrap_pyfunction!(jobs::avalanche, m)?)?;
    m.add_function(wrap_pyfunction!(jobs::cover, m)?)?;
    m.add_function(wrap_pyfunction!(jobs::transport, m)?)?;
    m.add_function(wrap_pyfunction!(jobs::validate, m)?)?;
    m.add_class::<PyWinter>()?;
    m.add("CHUNK_DAYS", CHUNK_DAYS)?;
    Ok(())
}
