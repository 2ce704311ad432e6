"""snowscape: snow-covered landscapes from real terrain, from Python.

numpy in, georeferenced rasters out, the same bytes as the command line::

    import snowscape
    dem = snowscape.read_dem("avaMal.asc")
    winter = snowscape.Winter(dem, scenario={"days": 60}, seed=1)
    winter.run(60)
    snowscape.write(winter.depth(), "depth.tif")

Every job runs the library's own path (the one `snowscape run` and `snowscape avalanche`
take). Bad input raises ``ValueError`` (``OSError`` for files) with the command line's message.
"""

from __future__ import annotations

import json
import os
from typing import Any, Callable, Dict, Iterable, Optional, Tuple, Union

import numpy as np

from . import _snowscape

__all__ = ["Raster", "read_dem", "write", "Winter", "avalanche", "cover", "transport", "validate"]

PathLike = Union[str, "os.PathLike[str]"]

#: The longest user value an error message shows whole (as the command line's messages).
_MAX_VALUE_CHARS = 80
#: The deepest nesting a scenario dict may have (a scenario file's deepest table is 4 levels).
_MAX_SCENARIO_DEPTH = 32
#: ``threads=`` range: at least one worker, at most this many.
_MAX_THREADS = 1024


def _clip(value: Any) -> str:
    """``repr(value)`` cut to about 80 characters (its start and end around the count left
    out): error messages name the value without echoing megabytes of it."""
    text = value if isinstance(value, str) else repr(value)
    if len(text) <= _MAX_VALUE_CHARS:
        return text
    return f"{text[:50]}…({len(text) - 70} more chars)…{text[-20:]}"


def _check_threads(threads: Any) -> Optional[int]:
    """``threads`` as an int in 1..=1024, or None; else a ValueError naming it."""
    if threads is None:
        return None
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or not (
        1 <= threads <= _MAX_THREADS
    ):
        raise ValueError(f"threads={_clip(threads)}: must be a whole number in 1..={_MAX_THREADS}")
    return int(threads)


def _check_depth(value: Any, where: str) -> None:
    """Refuses dicts and lists nested deeper than ``_MAX_SCENARIO_DEPTH``, naming the key path
    where the limit is passed (the parsers behind would say "recursion limit" and no place)."""
    stack = [(value, where, 1)]
    while stack:
        v, path, depth = stack.pop()
        if isinstance(v, dict):
            children = [(c, f"{path}[{_clip(k)!s}]") for k, c in v.items()]
        elif isinstance(v, (list, tuple)):
            children = [(c, f"{path}[{i}]") for i, c in enumerate(v)]
        else:
            continue
        if depth > _MAX_SCENARIO_DEPTH:
            shown = path if len(path) <= 200 else path[:120] + " ... " + path[-60:]
            raise ValueError(
                f"the scenario dict: {shown} is nested {depth} levels deep; at most "
                f"{_MAX_SCENARIO_DEPTH} are accepted"
            )
        stack.extend((c, p, depth + 1) for c, p in children)


class Raster:
    """A georeferenced raster: ``values`` (2-D float32, row 0 north, NaN = nodata), the cell
    size in metres, the map position of the upper-left corner (``origin``) and the CRS.

    ``Raster(values, cell_size, origin=None, crs=None)``: ``cell_size`` is one number or
    ``(x, y)``; ``origin`` is the map ``(x, y)`` of the upper-left corner (default: a local
    grid whose lower-left corner is at (0, 0)); ``crs`` an ``"EPSG:n"`` string or WKT.
    """

    def __init__(
        self,
        values: Any,
        cell_size: Union[float, Tuple[float, float]],
        origin: Optional[Tuple[float, float]] = None,
        crs: Optional[str] = None,
    ) -> None:
        a = np.array(values, dtype=np.float32, copy=True)
        if a.ndim != 2 or a.shape[0] < 1 or a.shape[1] < 1:
            raise ValueError(f"values must be a non-empty 2-D array, got shape {a.shape}")
        if np.isinf(a).any():
            r, c = np.argwhere(np.isinf(a))[0]
            raise ValueError(
                f"values at row {r}, column {c} is {a[r, c]}: values must be finite (NaN marks nodata)"
            )
        if np.isscalar(cell_size) or np.ndim(cell_size) == 0:
            dx = dy = float(cell_size)  # type: ignore[arg-type]
        else:
            dx, dy = (float(v) for v in cell_size)  # type: ignore[union-attr]
        for name, v in (("cell_size x", dx), ("cell_size y", dy)):
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a positive number of metres, got {_clip(v)}")
        h, w = a.shape
        if origin is None:
            ox, oy = 0.0, h * dy
        else:
            ox, oy = (float(v) for v in origin)
            if not (np.isfinite(ox) and np.isfinite(oy)):
                raise ValueError(f"origin ({ox}, {oy}) must be finite")
        self._values = a
        self._geo = (ox, oy, dx, dy)
        self._crs = crs
        # The metric cell size (differs from the pixel size only for a geographic CRS).
        self._cell = (dx, dy)

    @classmethod
    def _from_native(cls, parts: Tuple[Any, ...]) -> "Raster":
        data, w, h, geo, crs, cell = parts
        r = cls.__new__(cls)
        r._values = np.frombuffer(data, dtype="<f4").reshape(h, w).astype(np.float32)
        r._geo = tuple(float(v) for v in geo)
        r._crs = crs
        r._cell = tuple(float(v) for v in cell)
        return r

    def _native(self) -> Tuple[bytes, int, int, Tuple[float, float, float, float], Optional[str]]:
        a = np.ascontiguousarray(self._values, dtype="<f4")
        h, w = a.shape
        return (a.tobytes(), w, h, self._geo, self._crs)

    @property
    def values(self) -> np.ndarray:
        """The values, a 2-D float32 array (row 0 north; NaN = nodata)."""
        return self._values

    @property
    def shape(self) -> Tuple[int, int]:
        return self._values.shape  # type: ignore[return-value]

    @property
    def cell_size(self) -> Union[float, Tuple[float, float]]:
        """Cell size in metres: one number for square cells, else ``(x, y)``."""
        dx, dy = self._cell
        return dx if dx == dy else (dx, dy)

    @property
    def origin(self) -> Tuple[float, float]:
        """Map ``(x, y)`` of the upper-left corner."""
        return (self._geo[0], self._geo[1])

    @property
    def transform(self) -> Tuple[float, float, float, float, float, float]:
        """The GDAL geotransform ``(x0, dx, 0, y0, 0, -dy)`` (as rasterio's ``Affine.to_gdal()``)."""
        ox, oy, pw, ph = self._geo
        return (ox, pw, 0.0, oy, 0.0, -ph)

    @property
    def crs(self) -> Optional[str]:
        """The CRS: ``"EPSG:n"`` or WKT; ``None`` when unknown."""
        return self._crs

    def xy(self, row: float, col: float) -> Tuple[float, float]:
        """Map coordinates of the centre of cell ``(row, col)``."""
        ox, oy, pw, ph = self._geo
        return (ox + (col + 0.5) * pw, oy - (row + 0.5) * ph)

    def to_xarray(self) -> Any:
        """An ``xarray.DataArray`` with ``y`` and ``x`` coordinates of the cell centres (needs
        xarray)."""
        try:
            import xarray as xr
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Raster.to_xarray needs xarray: pip install xarray") from e
        ox, oy, pw, ph = self._geo
        h, w = self._values.shape
        x = ox + (np.arange(w) + 0.5) * pw
        y = oy - (np.arange(h) + 0.5) * ph
        attrs = {"transform": self.transform}
        if self._crs is not None:
            attrs["crs"] = self._crs
        return xr.DataArray(self._values, coords={"y": y, "x": x}, dims=("y", "x"), attrs=attrs)

    def __repr__(self) -> str:
        h, w = self._values.shape
        return f"Raster({w} x {h} cells of {self.cell_size} m, origin {self.origin}, crs {self._crs!r})"


def read_dem(
    path: PathLike,
    format: Optional[str] = None,
    cell_size: Optional[float] = None,
    height_range: Optional[Tuple[float, float]] = None,
    raw_size: Optional[Tuple[int, int]] = None,
    crs: Optional[str] = None,
) -> Raster:
    """Reads a raster in any format the command line reads (GeoTIFF, ESRI ASCII, PNG16,
    RAW16, NPY, EXR), with the command line's input options (``--format``, ``--cell-size``,
    ``--height-range``, ``--raw-size``, ``--crs``)."""
    return Raster._from_native(
        _snowscape.read_raster(os.fspath(path), format, cell_size, height_range, raw_size, crs)
    )


def write(raster: Raster, path: PathLike) -> None:
    """Writes ``raster`` in the format its extension names (``.tif``, ``.asc``, ``.png``
    (16-bit), ``.raw``/``.r16``, ``.npy``, ``.exr``), atomically."""
    if not isinstance(raster, Raster):
        raise ValueError(f"write needs a snowscape.Raster, got {type(raster).__name__}")
    _snowscape.write(raster._native(), os.fspath(path))


def _scenario_text(scenario: Union[None, PathLike, Dict[str, Any]]) -> Tuple[Optional[str], bool, str]:
    """The scenario's text, whether it is JSON (a dict) rather than TOML (a file), and the name
    its errors use."""
    if scenario is None:
        return None, False, "the default scenario"
    if isinstance(scenario, dict):
        _check_depth(scenario, "scenario")
        try:
            return json.dumps(scenario, allow_nan=False), True, "the scenario dict"
        except (TypeError, ValueError) as e:
            raise ValueError(f"the scenario dict: {_clip(str(e))}") from None
    path = os.fspath(scenario)
    with open(path, encoding="utf-8") as f:
        return f.read(), False, path


def _sets_days(scenario: Any, text: Optional[str]) -> bool:
    """Whether the scenario sets the season's length (a dict's ``days`` key, a top-level
    ``days =`` line of a file before its first table)."""
    if isinstance(scenario, dict):
        return "days" in scenario
    for line in (text or "").splitlines():
        line = line.strip()
        if line.startswith("["):
            return False
        if line.split("=", 1)[0].strip() == "days" and "=" in line:
            return True
    return False


class Winter:
    """A winter on a terrain: snowfall, melt, sun and wind, shedding, avalanches, day by day.

    ``Winter(dem, scenario=None, seed=0, threads=None, forcing=None, station_altitude=None)``:
    ``dem`` a :class:`Raster` (or a path); ``scenario`` a scenario file's path, a dict of its
    keys (``{"days": 60, "parameters": {...}}``) or ``None`` for the default winter; ``seed``
    the random seed (same seed, same bytes, for any ``threads``); ``forcing`` a station record
    (as ``snowscape run --forcing``: CSV or a snobal input file) that the season follows from
    its first hour, for the record's length or the scenario's ``days`` when it sets them, at
    ``station_altitude`` metres unless the file states it.
    """

    def __init__(
        self,
        dem: Union[Raster, PathLike],
        scenario: Union[None, PathLike, Dict[str, Any]] = None,
        seed: Optional[int] = 0,
        threads: Optional[int] = None,
        forcing: Optional[PathLike] = None,
        station_altitude: Optional[float] = None,
        _native: Any = None,
    ) -> None:
        if _native is not None:
            self._w = _native
            return
        dem = _as_raster(dem)
        text, is_json, name = _scenario_text(scenario)
        if seed is not None and (not isinstance(seed, (int, np.integer)) or seed < 0):
            raise ValueError(f"seed must be a whole number >= 0, got {_clip(seed)}")
        threads = _check_threads(threads)
        self._w = _snowscape._Winter(
            dem._native(),
            text,
            is_json,
            name,
            None if seed is None else int(seed),
            threads,
            None if forcing is None else os.fspath(forcing),
            None if station_altitude is None else float(station_altitude),
            _sets_days(scenario, text),
        )

    @classmethod
    def resume(cls, path: PathLike, dem: Union[Raster, PathLike], threads: Optional[int] = None) -> "Winter":
        """Resumes a season saved by :meth:`save_checkpoint` (or written by ``snowscape run``)
        in the folder ``path``, on its terrain ``dem``: it continues bit-identically."""
        dem = _as_raster(dem)
        threads = _check_threads(threads)
        return cls(dem, _native=_snowscape._Winter.resume(os.fspath(path), dem._native(), threads))

    @property
    def day(self) -> float:
        """The season's day."""
        return self._w.day

    @property
    def days(self) -> float:
        """The season's length, days."""
        return self._w.days

    def run(self, days: Optional[float] = None, progress: Optional[Callable[[float], Any]] = None) -> "Winter":
        """Runs the season to day ``days`` (default: its end). ``progress(day)`` is called every
        quarter day; Ctrl-C stops it between two events (the state stays consistent)."""
        self._w.run_until(self.days if days is None else float(days), progress)
        return self

    def step(self, days: float) -> "Winter":
        """Advances the season by ``days``."""
        d = float(days)
        if not (np.isfinite(d) and d >= 0):
            raise ValueError(f"days {_clip(days)} must be finite and >= 0")
        self._w.run_until(self.day + d, None)
        return self

    def depth(self) -> Raster:
        """Total snow depth, m."""
        return Raster._from_native(self._w.depth())

    def layers(self) -> Dict[str, Raster]:
        """The snow layers (``compacted``, ``stable``, ``unstable``, ``powder``) and the
        ``bedrock``, m."""
        return {
            n: Raster._from_native(self._w.layer(n))
            for n in ("compacted", "stable", "unstable", "powder", "bedrock")
        }

    def budget(self) -> Dict[str, Any]:
        """The season's volume budget (m³ per term, as report.json's ``mass_budget``)."""
        return json.loads(self._w.budget_json())

    def trigger_avalanche(self, x: float, y: float) -> Dict[str, Any]:
        """Triggers an avalanche at map position ``(x, y)``; its record."""
        return json.loads(self._w.trigger_avalanche(float(x), float(y)))

    def save_checkpoint(self, path: PathLike) -> None:
        """Writes the state into the folder ``path`` (``checkpoint.bin`` and ``scenario.toml``,
        the layout ``snowscape run --resume DIR`` reads)."""
        self._w.save_checkpoint(os.fspath(path))

    def scenario_toml(self) -> str:
        """The resolved scenario, as TOML."""
        return self._w.scenario_toml()


def _as_raster(dem: Union[Raster, PathLike]) -> Raster:
    if isinstance(dem, Raster):
        return dem
    if isinstance(dem, (str, os.PathLike)):
        return read_dem(dem)
    raise ValueError(f"dem must be a snowscape.Raster or a path, got {type(dem).__name__}")


def avalanche(
    dem: Union[Raster, PathLike],
    release: Union[PathLike, np.ndarray, Tuple[float, float]],
    thickness: Optional[float] = 1.0,
    *,
    slope_normal: bool = True,
    duration: float = 600.0,
    snow_cover: float = 0.0,
    **params: Any,
) -> Dict[str, Any]:
    """One avalanche from release to rest, as ``snowscape avalanche`` runs it.

    ``release``: a shapefile or raster mask path, a boolean mask array of the DEM's shape, or a
    map point ``(x, y)`` (a uniform cover of ``thickness`` breaks there). ``thickness`` in m
    (``None``: a shapefile's own thickness field); ``slope_normal`` (the default, as the
    command line's) reads it normal to the slope (AvaFrame's convention), ``False`` vertical;
    ``snow_cover`` lays loose snow outside the release for the flow to entrain. ``**params``
    are the flow parameters (``[parameters.avalanche.flow]`` keys: ``friction="voellmy"``,
    ``voellmy_mu=0.2``, ``samosat={"mu": 0.22}``, ``slope_gravity="shallow"``...), by default
    those of ``snowscape avalanche``: AvaFrame's samosATSmall law with the slope-projected
    gravity and the bed's curvature. ``friction`` takes the command line's names:
    ``"coulomb"``, ``"voellmy"``, ``"samosat"`` (AvaFrame's standard μ = 0.155) and
    ``"samosat-small"`` (samosATSmall, μ = 0.22), whose μ ``samosat={...}`` keys override.
    The paper's model: ``friction="coulomb", slope_gravity="shallow", slope_normal=False``.

    Returns ``{"peak_thickness", "peak_velocity", "deposit", "entrained"}`` rasters and
    ``"summary"``, one flat dict: the volumes (``released_volume_m3``,
    ``entrained_volume_m3``, ``deposited_volume_m3``, ``border_outflow_m3``), ``runout_length_m``,
    ``travel_angle_deg``, ``footprint_area_m2``, ``stop``..., ``release_cells``,
    ``release_area_m2`` and the ``parameters`` used.
    """
    dem = _as_raster(dem)
    path = mask = point = None
    if isinstance(release, (str, os.PathLike)):
        path = os.fspath(release)
    elif isinstance(release, tuple) and len(release) == 2 and not isinstance(release[0], (list, np.ndarray)):
        point = (float(release[0]), float(release[1]))
    else:
        m = np.asarray(release)
        if m.shape != dem.shape:
            raise ValueError(f"release mask has shape {m.shape}, the DEM {dem.shape}")
        mask = np.ascontiguousarray(m != 0, dtype=np.uint8).tobytes()
    rasters, summary = _snowscape.avalanche(
        dem._native(),
        path,
        mask,
        point,
        None if thickness is None else float(thickness),
        bool(slope_normal),
        json.dumps(params),
        float(duration),
        float(snow_cover),
    )
    out: Dict[str, Any] = {name: Raster._from_native(parts) for name, parts in rasters}
    out["summary"] = json.loads(summary)
    return out


def cover(
    mesh_path: PathLike,
    method: str = "diffusion",
    *,
    up: str = "y",
    scale: float = 1.0,
    **params: Any,
) -> Dict[str, Any]:
    """Snow on a triangle mesh (OBJ, PLY, glTF/GLB), as ``snowscape cover`` computes it:
    ``method="diffusion"`` (von Festenberg & Gumhold 2011) or ``"fearing"`` (Fearing 2000).

    ``up`` is the file's up axis (``"y"`` or ``"z"``), ``scale`` its metres per unit;
    ``**params`` are the method's keys of a cover parameter file (``depth_m``, ``radius_m``,
    ``overhang``... for diffusion; ``depth_m``, ``passes``, ``material={"aor_deg": 45}``...
    for Fearing). Returns ``{"vertices": (N, 3) float32 in the mesh file's axes and units (as
    snow.obj), "faces": (M, 3) uint32 counter-clockwise triangles, "report": dict}``, the report
    with the keys of ``snowscape cover``'s report.json (no files are written: ``outputs`` is empty).
    """
    v, f, report = _snowscape.cover(
        os.fspath(mesh_path), str(method), str(up), float(scale), json.dumps(params)
    )
    return {
        "vertices": np.frombuffer(v, dtype="<f4").reshape(-1, 3).astype(np.float32),
        "faces": np.frombuffer(f, dtype="<u4").reshape(-1, 3).astype(np.uint32),
        "report": json.loads(report),
    }


def transport(
    dem: Union[None, Raster, PathLike] = None,
    scenario: Optional[str] = None,
    *,
    hours: Optional[float] = None,
    seed: Optional[int] = None,
    flakes: Optional[int] = None,
    wind_iterations: Optional[int] = None,
    voxel_size: Optional[float] = None,
    voxel_layers: Optional[int] = None,
    uniform_precipitation: bool = False,
) -> Dict[str, Any]:
    """Physical snow transport (Jubert 2018: 3D wind, saltation, suspension, sublimation, melt)
    as ``snowscape transport`` runs it, over ``dem`` or the scene of ``scenario`` (a scenario
    file's path or a shipped name, ``"castle"`` or ``"valley"``; default: the weather of Table
    7.I on the DEM, with a wind grid fitted to it).

    Returns the rasters ``depth``, ``density``, ``q_salt``, ``q_susp``, ``q_subl``,
    ``precipitation``, ``wind_u``, ``wind_v`` and ``"report"`` (the keys of ``snowscape
    transport``'s report.json: scenario, grids, wind, flakes, depth, ``mass_budget`` in kg, timings).
    """
    native = None if dem is None else _as_raster(dem)._native()
    rasters, report = _snowscape.transport(
        native,
        None if scenario is None else os.fspath(scenario),
        hours,
        seed,
        flakes,
        wind_iterations,
        voxel_size,
        voxel_layers,
        bool(uniform_precipitation),
    )
    out: Dict[str, Any] = {name: Raster._from_native(parts) for name, parts in rasters}
    out["report"] = json.loads(report)
    return out


def validate(
    run: PathLike,
    observed: PathLike,
    *,
    mask: Optional[PathLike] = None,
    out: Optional[PathLike] = None,
    snow_threshold: float = 0.05,
    wind_from: Optional[float] = None,
) -> Dict[str, Any]:
    """A run's snow depth against a measured depth raster, as ``snowscape validate`` computes
    it: ``run`` is a folder written by ``snowscape run`` or ``demo`` (its ``depth.tif``,
    ``bedrock.tif`` and ``report.json`` are read), ``observed`` a depth raster in metres (any
    cell size and extent, matched by map coordinates), ``mask`` a raster whose nonzero cells are
    compared; ``snow_threshold`` (m) the depth above which a cell is snow-covered,
    ``wind_from`` (degrees clockwise from north) the prevailing wind of the lee/windward ratio
    (default: the run's report.json, else 270).

    Writes ``validation.json``, ``validation.png`` and ``scatter.png`` into ``out`` (default
    ``run/validation``) and returns the report: the keys of ``validation.json`` (correlations,
    errors, snow-cover agreement, terrain-only baselines, class ratios).
    """
    report = _snowscape.validate(
        os.fspath(run),
        os.fspath(observed),
        None if mask is None else os.fspath(mask),
        None if out is None else os.fspath(out),
        float(snow_threshold),
        None if wind_from is None else float(wind_from),
    )
    return json.loads(report)
