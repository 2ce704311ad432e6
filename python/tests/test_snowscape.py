"""The Python package against the command line and hand-computed values, on the shared real
DEMs (../shared/data beside the checkout; the tests fail when it is missing)."""

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import snowscape

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT.parent / "shared" / "data"
WOG = DATA / "dem" / "avaframe_avaWog"
BIN = Path(os.environ.get("SNOWSCAPE_BIN", ROOT / "target" / "release" / "snowscape"))


def wog_dem() -> Path:
    dem = WOG / "avaWog.asc"
    assert dem.is_file(), f"the shared avaWog DEM is missing: expected {dem}"
    return dem


def snowscape_cli(*args: str) -> None:
    assert BIN.is_file(), f"the snowscape binary is missing: build it (cargo build --release) or set SNOWSCAPE_BIN; expected {BIN}"
    subprocess.run([str(BIN), "--quiet", *args], check=True)


def same_bytes(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def test_depth_bytes_equal_snowscape_run(tmp_path):
    dem = wog_dem()
    out = tmp_path / "run"
    snowscape_cli("run", "--dem", str(dem), "--days", "6", "--seed", "3", "--out", str(out))
    cli_depth = snowscape.read_dem(out / "depth.tif").values
    w = snowscape.Winter(snowscape.read_dem(dem), scenario={"days": 6}, seed=3)
    w.run()
    py_depth = w.depth().values
    assert np.nanmax(py_depth) > 0.1, "it snowed"
    assert same_bytes(py_depth, cli_depth)
    # The CLI's folder resumes in Python (the same layout): at its end already.
    resumed = snowscape.Winter.resume(out, dem)
    assert resumed.day == w.day
    assert same_bytes(resumed.depth().values, py_depth)


def test_checkpoint_resume_and_threads_are_bit_identical(tmp_path):
    dem = snowscape.read_dem(wog_dem())
    straight = snowscape.Winter(dem, scenario={"days": 4}, seed=9, threads=1).run()
    half = snowscape.Winter(dem, scenario={"days": 4}, seed=9, threads=2)
    days = []
    half.run(2.0, progress=days.append)
    assert days and days[-1] >= 2.0 and all(b > a for a, b in zip(days, days[1:]))
    half.save_checkpoint(tmp_path / "ck")
    assert (tmp_path / "ck" / "checkpoint.bin").is_file()
    assert (tmp_path / "ck" / "scenario.toml").is_file()
    resumed = snowscape.Winter.resume(tmp_path / "ck", dem)
    assert resumed.day == half.day
    resumed.run()
    assert same_bytes(resumed.depth().values, straight.depth().values)
    for name, r in straight.layers().items():
        assert same_bytes(resumed.layers()[name].values, r.values), name
    b = straight.budget()
    assert b["snowfall"] > 0
    store = float(np.nansum(straight.depth().values)) * dem.cell_size**2
    assert store > 0


def test_an_exception_in_progress_stops_the_season_where_it_stands():
    # The callback runs between two chunks of the library's season driver: its exception
    # stops the run there, and the season runs on from that day to the same bytes.
    dem = snowscape.read_dem(wog_dem())
    straight = snowscape.Winter(dem, scenario={"days": 3}, seed=5).run()
    w = snowscape.Winter(dem, scenario={"days": 3}, seed=5)
    seen = []

    def progress(day):
        seen.append(day)
        if len(seen) == 3:
            raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough"):
        w.run(progress=progress)
    assert len(seen) == 3 and w.day == seen[-1] and 0 < w.day < 3
    w.run()
    assert same_bytes(w.depth().values, straight.depth().values)


def test_transform_matches_the_asc_header():
    dem = snowscape.read_dem(wog_dem())
    # avaWog.asc: ncols 490, nrows 555, xllcenter 167455.348391387, yllcenter 361955.626633194,
    # cellsize 4.997678230579: the upper-left corner is half a cell west and north of the
    # centres' extent.
    cs = 4.997678230579
    x0 = 167455.348391387 - cs / 2
    y0 = 361955.626633194 - cs / 2 + 555 * cs
    assert dem.shape == (555, 490)
    t = dem.transform
    assert t[1] == pytest.approx(cs) and t[5] == pytest.approx(-cs)
    assert t[2] == 0.0 and t[4] == 0.0
    assert t[0] == pytest.approx(x0, abs=1e-6)
    assert t[3] == pytest.approx(y0, abs=1e-6)
    assert dem.cell_size == pytest.approx(cs)
    # Nodata is NaN; the first row's cells at columns 211-214 hold altitudes.
    assert np.isnan(dem.values[0, 0])
    assert dem.values[0, 211] == pytest.approx(1341.815185546875)
    assert dem.xy(0, 0) == pytest.approx((x0 + cs / 2, y0 - cs / 2))


@pytest.mark.parametrize("ext", ["tif", "asc", "npy", "exr", "png"])
def test_numpy_round_trip(tmp_path, ext):
    v = np.linspace(1000.0, 1500.0, 35 * 24, dtype=np.float32).reshape(35, 24)
    v[3, 4] = np.nan
    r = snowscape.Raster(v, 2.5, origin=(600000.0, 5100000.0), crs="EPSG:32632")
    assert r.transform == (600000.0, 2.5, 0.0, 5100000.0, 0.0, -2.5)
    path = tmp_path / f"r.{ext}"
    snowscape.write(r, path)
    back = snowscape.read_dem(path, cell_size=2.5) if ext in ("npy", "exr", "png") else snowscape.read_dem(path)
    assert back.shape == (35, 24)
    if ext == "png":
        # 16-bit codes over the raster's range: within one step.
        step = 500.0 / 65535
        ok = ~np.isnan(back.values)
        assert np.nanmax(np.abs(back.values[ok] - v[ok])) <= step * 1.01
    else:
        assert np.isnan(back.values[3, 4])
        assert same_bytes(np.nan_to_num(back.values, nan=-1), np.nan_to_num(v, nan=-1))
    if ext in ("tif", "asc"):
        assert back.transform == pytest.approx(r.transform)
    if ext == "tif":
        assert back.crs == "EPSG:32632"


def test_avalanche_on_avawog_and_its_release_forms():
    dem = snowscape.read_dem(wog_dem())
    shp = WOG / "REL" / "relWog.shp"
    assert shp.is_file(), f"missing {shp}"
    a = snowscape.avalanche(dem, shp, thickness=1.0, duration=20)
    s = a["summary"]
    released = s["released_volume_m3"]
    assert released > 1e5
    assert abs(released - s["deposited_volume_m3"] - s["border_outflow_m3"]) < 1e-6 * released
    assert s["runout_length_m"] > 200
    assert "summary" not in s  # one flat dict (issue 46: it sat at out["summary"]["summary"])
    peak = a["peak_thickness"].values
    assert np.nanmax(peak) > 0.5 and a["peak_thickness"].transform == dem.transform
    # A point release: a uniform 0.5 m cover breaks at a cell of the release.
    rows, cols = np.nonzero(np.nan_to_num(peak) > 1.0)
    x, y = dem.xy(rows[0], cols[0])
    p = snowscape.avalanche(dem, (x, y), thickness=0.5, duration=10)
    assert p["summary"]["released_volume_m3"] > 0
    # A boolean mask of 20 x 20 cells on the slope.
    m = np.zeros(dem.shape, dtype=bool)
    m[rows[0] : rows[0] + 20, cols[0] : cols[0] + 20] = True
    m &= ~np.isnan(dem.values)
    # (Vertical thickness: the released volume is the mask's cells times 1 m; the default,
    # slope-normal as AvaFrame's, releases d/cosθ.)
    q = snowscape.avalanche(
        dem, m, thickness=1.0, slope_normal=False, duration=10, friction="voellmy", voellmy_mu=0.2
    )
    cell_area = dem.cell_size**2
    assert q["summary"]["released_volume_m3"] == pytest.approx(m.sum() * cell_area, rel=1e-5)
    assert q["summary"]["parameters"]["friction"] == "voellmy"


def test_bad_input_raises_naming_the_value(tmp_path):
    dem = snowscape.read_dem(wog_dem())
    with pytest.raises(OSError, match="no/such.tif"):
        snowscape.read_dem("no/such.tif")
    with pytest.raises(ValueError, match="-2"):
        snowscape.read_dem(wog_dem(), cell_size=-2.0)
    with pytest.raises(ValueError, match="-1"):
        snowscape.Winter(dem, scenario={"days": -1})
    with pytest.raises(ValueError, match="no_such_key"):
        snowscape.Winter(dem, scenario={"days": 2, "no_such_key": 1})
    with pytest.raises(ValueError, match="threads"):
        snowscape.Winter(dem, scenario={"days": 2}, threads=0)
    with pytest.raises(ValueError, match="inf"):
        snowscape.Raster(np.array([[1.0, np.inf]]), 1.0)
    with pytest.raises(ValueError, match="-3"):
        snowscape.Raster(np.zeros((2, 2)), -3.0)
    with pytest.raises(ValueError, match="unknown raster extension"):
        snowscape.write(dem, tmp_path / "x.jpeg")
    assert not (tmp_path / "x.jpeg").exists()
    w = snowscape.Winter(dem, scenario={"days": 2})
    with pytest.raises(ValueError, match="past the season's end"):
        w.run(5)
    with pytest.raises(ValueError, match="outside"):
        w.trigger_avalanche(0.0, 0.0)
    with pytest.raises(ValueError, match="voellmy_mu"):
        snowscape.avalanche(dem, (0.0, 0.0), friction="voellmy", voellmy_mu=1e9)
    with pytest.raises(ValueError, match="1000000000"):
        snowscape.avalanche(dem, (0.0, 0.0), thickness=1e9)
    with pytest.raises(ValueError, match="snow cover -1"):
        snowscape.avalanche(dem, (0.0, 0.0), snow_cover=-1.0)
    with pytest.raises(ValueError, match="no_such_param"):
        snowscape.avalanche(dem, (0.0, 0.0), no_such_param=1)
    with pytest.raises(OSError, match="nothing.shp"):
        snowscape.avalanche(dem, tmp_path / "nothing.shp")
    nan_dem = snowscape.Raster(np.full((4, 4), np.nan, dtype=np.float32), 10.0)
    with pytest.raises(ValueError):
        snowscape.Winter(nan_dem, scenario={"days": 1})


def test_to_xarray():
    xr = pytest.importorskip("xarray")
    r = snowscape.Raster(np.arange(6, dtype=np.float32).reshape(2, 3), 10.0, origin=(100.0, 50.0))
    a = r.to_xarray()
    assert isinstance(a, xr.DataArray)
    assert list(a.x.values) == [105.0, 115.0, 125.0] and list(a.y.values) == [45.0, 35.0]


def test_cover_matches_snowscape_cover(tmp_path):
    mesh = DATA / "meshes" / "spider.obj"
    assert mesh.is_file(), f"the shared spider mesh is missing: expected {mesh}"
    out = tmp_path / "cover"
    snowscape_cli("cover", "--mesh", str(mesh), "--method", "diffusion", "--depth", "0.5", "--out", str(out))
    import json

    cli = json.loads((out / "report.json").read_text())
    c = snowscape.cover(mesh, "diffusion", depth_m=0.5)
    assert c["vertices"].dtype == np.float32 and c["vertices"].shape[1] == 3
    assert c["faces"].dtype == np.uint32 and c["faces"].max() < len(c["vertices"])
    # The same report as report.json, but for the files written and the timings.
    r = c["report"]
    assert r["snow"] == cli["snow"] and r["sites"] == cli["sites"] and r["parameters"] == cli["parameters"]
    assert r["input"]["triangles"] == cli["input"]["triangles"] and r["input"]["dem"] is None
    assert r["outputs"] == [] and r["method"] == "diffusion"
    # The vertices in the file's axes: the OBJ the command line wrote lists the same points.
    first = next(l for l in (out / "snow.obj").read_text().splitlines() if l.startswith("v "))
    assert np.allclose([float(t) for t in first.split()[1:4]], c["vertices"][0], atol=1e-4)
    # budget_s is a wall-clock safety net (the work is set by the passes and sites).
    f = snowscape.cover(mesh, "fearing", passes=1, budget_s=600.0)
    assert len(f["faces"]) > 100 and f["report"]["method"] == "fearing"
    assert f["report"]["input"]["objects"] == cli["input"]["objects"]
    with pytest.raises(ValueError, match=r"kernel radius \(R\) -1"):
        snowscape.cover(mesh, "diffusion", radius_m=-1.0)
    with pytest.raises(ValueError, match="no_such"):
        snowscape.cover(mesh, "diffusion", no_such=1)
    with pytest.raises(ValueError, match="method"):
        snowscape.cover(mesh, "paint")
    with pytest.raises(OSError, match="nothing.obj"):
        snowscape.cover(tmp_path / "nothing.obj")


def test_transport_bytes_equal_snowscape_transport(tmp_path):
    dem = DATA / "dem" / "rme_idaho_50m" / "dem.asc"
    assert dem.is_file(), f"the shared RME DEM is missing: expected {dem}"
    out = tmp_path / "tr"
    snowscape_cli("transport", "--dem", str(dem), "--hours", "2", "--out", str(out))
    r = snowscape.transport(dem, hours=2)
    for name in ("depth", "q_salt", "precipitation"):
        cli = snowscape.read_dem(out / f"{name}.tif").values
        assert same_bytes(r[name].values, cli), name
    import json

    # The report of snowscape transport's report.json (but for where the scene came from).
    cli_report = json.loads((out / "report.json").read_text())
    b = r["report"]["mass_budget"]
    assert b == cli_report["mass_budget"] and b["unit"] == "kg"
    assert b["precipitation_in"] > 0 and abs(b["closure_error"]) < 1e-6 * b["precipitation_in"]
    assert r["report"]["scenario"] == cli_report["scenario"] and r["report"]["steps"] == cli_report["steps"]
    with pytest.raises(ValueError, match="no scene"):
        snowscape.transport()
    with pytest.raises(ValueError, match="hours|duration_h"):
        snowscape.transport(dem, hours=-1.0)
    with pytest.raises(ValueError, match="neither a file nor a shipped scenario"):
        snowscape.transport(dem, scenario="no-such-scenario")


def test_ctrl_c_stops_a_season_between_two_events():
    import signal
    import threading

    dem = snowscape.read_dem(wog_dem())
    w = snowscape.Winter(dem, scenario={"days": 400})
    # A shell without job control starts background commands with SIGINT ignored, and Python
    # then leaves it ignored: Ctrl-C's handler is set here, whatever launched the tests.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    # Ctrl-C from another thread after 0.5 s, again every 0.5 s until the run has stopped.
    stopped = threading.Event()

    def press_ctrl_c():
        while not stopped.wait(0.5):
            os.kill(os.getpid(), signal.SIGINT)

    presser = threading.Thread(target=press_ctrl_c, daemon=True)
    presser.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            w.run()
    finally:
        stopped.set()
        presser.join()
        signal.signal(signal.SIGINT, previous)
    # Stopped part-way, in a consistent state that runs on.
    assert 0 < w.day < 400
    day = w.day
    w.step(1.0)
    assert w.day >= day + 1.0
    d = w.depth().values
    assert np.all(np.isnan(d) | (d >= 0))


def test_friction_names_are_the_command_lines():
    # Issue 46: Python said samos_at where the command line says samosat / samosat-small.
    dem = snowscape.read_dem(wog_dem())
    # A point release where the shapefile's release flows (as the test above finds one).
    a = snowscape.avalanche(dem, WOG / "REL" / "relWog.shp", thickness=1.0, duration=20)
    rows, cols = np.nonzero(np.nan_to_num(a["peak_thickness"].values) > 1.0)
    x, y = dem.xy(rows[0], cols[0])
    used = {}
    for kwargs in [
        {"friction": "samosat"},
        {"friction": "samosat-small"},
        {"friction": "samosat-small", "samosat": {"mu": 0.3}},
        {"friction": "samos_at", "samos_at": {"mu": 0.2}},  # the old spelling still reads
    ]:
        p = snowscape.avalanche(dem, (x, y), thickness=0.5, duration=1, **kwargs)["summary"]["parameters"]
        assert p["friction"] == "samosat", (kwargs, p)
        used[len(used)] = p["samosat"]["mu"]
    assert used == {0: 0.155, 1: 0.22, 2: 0.3, 3: 0.2}
    # Issue 47: the defaults are the command line's (AvaFrame's samosATSmall, the projected
    # gravity with the bed's curvature).
    p = snowscape.avalanche(dem, (x, y), thickness=0.5, duration=1)["summary"]["parameters"]
    assert (p["friction"], p["samosat"]["mu"], p["slope_gravity"], p["curvature"]) == (
        "samosat",
        0.22,
        "projected",
        True,
    ), p
    with pytest.raises(ValueError, match="samosat-small"):
        snowscape.avalanche(dem, (x, y), friction="samosat_tiny")


def test_threads_values_and_messages_are_bounded(tmp_path):
    dem = snowscape.read_dem(wog_dem())
    # threads=-1 was an OverflowError from the conversion.
    for bad in (-1, 0, 1025, 10**30, True, 2.5):
        with pytest.raises(ValueError, match=r"threads=.*1\.\.=1024"):
            snowscape.Winter(dem, scenario={"days": 2}, threads=bad)
    # A 3 MB value (under the 4 MiB a scenario may hold) is named, not echoed whole.
    huge = "x" * 3_000_000
    for call in (
        lambda: snowscape.avalanche(dem, (0.0, 0.0), friction=huge),
        lambda: snowscape.Winter(dem, scenario={"days": 2, "start_date": huge}),
        lambda: snowscape.Winter(dem, scenario={"days": 2, huge: 1}),
    ):
        with pytest.raises(ValueError) as e:
            call()
        text = str(e.value)
        # Clipped by the binding ("more chars") or by the scenario reader ("(N bytes)").
        assert len(text) < 2000 and ("more chars" in text or "bytes)" in text), text[:300]
    # Deep nesting: refused with the place, not "recursion limit" alone.
    deep: dict = {"x": 1}
    for _ in range(100):
        deep = {"a": deep}
    with pytest.raises(ValueError, match="nested 33 levels deep"):
        snowscape.Winter(dem, scenario={"days": 2, "parameters": deep})
    f = tmp_path / "deep.toml"
    f.write_text("days = 2\n" + ".".join(["a"] * 5000) + " = 1\n")
    with pytest.raises(ValueError, match="deep.toml.*line 2"):
        snowscape.Winter(dem, scenario=f)


def test_station_forcing_drives_the_season_as_the_command_line(tmp_path):
    # Issue 48: Python takes the station forcing through the command line's path (the record's
    # calendar, the station altitude required) and resumes a forced season.
    rme = DATA / "reference" / "pysnobal_rme_point" / "gold.snobal.data.input.short.csv"
    dem_path = DATA / "dem" / "rme_idaho_50m" / "dem.asc"
    assert rme.is_file() and dem_path.is_file(), f"the shared RME data are missing: {rme}, {dem_path}"
    out = tmp_path / "run"
    snowscape_cli(
        "run", "--dem", str(dem_path), "--forcing", str(rme), "--station-altitude", "2061",
        "--days", "4", "--out", str(out),
    )
    cli_depth = snowscape.read_dem(out / "depth.tif").values
    dem = snowscape.read_dem(dem_path)
    with pytest.raises(ValueError, match="station altitude is unknown"):
        snowscape.Winter(dem, forcing=rme)
    whole = snowscape.Winter(dem, forcing=rme, station_altitude=2061)
    assert whole.days > 300, "the record's length"
    w = snowscape.Winter(dem, scenario={"days": 4}, forcing=rme, station_altitude=2061).run()
    assert same_bytes(w.depth().values, cli_depth)
    # The command line's forced folder resumes in Python (the record read again).
    resumed = snowscape.Winter.resume(out, dem)
    assert resumed.day == w.day
    assert same_bytes(resumed.depth().values, cli_depth)


def test_validate_matches_the_command_line(tmp_path):
    # A short run on avaWog, its own depth as the observation: the same validation.json as
    # `snowscape validate` (but the paths), rho = 1, and bad input named.
    run = tmp_path / "run"
    snowscape_cli("run", "--dem", str(wog_dem()), "--days", "3", "--out", str(run))
    observed = run / "depth.tif"
    v = snowscape.validate(run, observed, out=tmp_path / "py")
    assert v["command"] == "validate"
    assert v["cells_compared"] > 0
    assert v["outputs"] == ["validation.json", "validation.png", "scatter.png"]
    for name in v["outputs"]:
        assert (tmp_path / "py" / name).is_file(), name
    snowscape_cli("validate", "--run", str(run), "--observed", str(observed), "--out", str(tmp_path / "cli"))
    cli = json.loads((tmp_path / "cli" / "validation.json").read_text())
    assert cli == json.loads((tmp_path / "py" / "validation.json").read_text()) == v
    with pytest.raises(OSError, match="no/such.tif"):
        snowscape.validate(run, "no/such.tif")
    # Named by the Python keyword, not the command line's flag.
    with pytest.raises(ValueError, match="snow_threshold=-1") as e:
        snowscape.validate(run, observed, snow_threshold=-1.0)
    assert "--" not in str(e.value)
    with pytest.raises(OSError, match="observed=no/such.tif") as e:
        snowscape.validate(run, "no/such.tif")
