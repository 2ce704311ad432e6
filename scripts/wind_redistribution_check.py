#!/usr/bin/env python3
"""Wind redistribution figures of one or more run folders (issue 47, item 3).

For each run folder written by `snowscape run` / `snowscape demo` (its depth.tif and
bedrock.tif, converted to .npy by `snowscape convert`, and report.json for the cell size):

- east/west: within 200 m altitude bands, the mean depth of east-facing slopes (aspect
  45-135°, slope > 15°) over that of west-facing ones (225-315°), averaged over the bands
  weighted by their cells (bands with at least `min_cells` of each class, and both means at
  least `--min-depth`, 0.05 m: a band where one aspect is bare, e.g. below the snow line,
  says nothing of the wind and its ratio is unbounded); the lee of a westerly is east-facing,
  so >1 means the lee holds more snow. The statistic of
  crates/season/tests/sx_redistribution.rs, with the depth floor. Also the pooled ratio
  (sum over the same bands of cells x east mean over the same for west).
- crests: Winstral et al. 2002's maximum upwind slope Sx over a long search (default
  1000 m) and a short one (100 m) of the bedrock for the wind direction, computed here
  independently of the model (bilinear samples every cell size along seven rays, ±15° in 5°
  steps); the mean depth of the most exposed cells (lowest long-range Sx, top `--top` share)
  and of the most sheltered ones (highest long-range Sx), and the mean depth overall.
- rho_depth_altitude: Spearman rank correlation of depth with altitude (context).

Usage:
    python3 scripts/wind_redistribution_check.py RUN [RUN ...] [--wind-from 270]
        [--snowscape target/release/snowscape] [--long-m 1000] [--top 0.05]

Prints one JSON object per run. Needs python3 and numpy only.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np


def load_raster(snowscape, path):
    """The raster at `path` as a float64 array, NaN on nodata (via `snowscape convert`)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "r.npy")
        subprocess.run([snowscape, "convert", "-q", path, out], check=True)
        return np.load(out).astype(np.float64)


def max_upwind_slope(z, cell, wind_from_deg, dmax_m, half_deg=15.0, step_deg=5.0):
    """Sx (degrees) of every cell of `z` (NaN nodata), Winstral et al. 2002."""
    h, w = z.shape
    n_steps = max(1, int(dmax_m / cell + 1e-9))
    pad = n_steps + 2
    zp = np.full((h + 2 * pad, w + 2 * pad), np.nan)
    zp[pad:pad + h, pad:pad + w] = z
    total = np.zeros_like(z)
    count = np.zeros_like(z)
    m = int(half_deg / step_deg + 1e-9)
    for k in range(-m, m + 1):
        a = np.radians(wind_from_deg + k * step_deg)
        best = np.full_like(z, -np.inf)
        for s in range(1, n_steps + 1):
            d = s * cell
            oc, orow = d * np.sin(a) / cell, -d * np.cos(a) / cell
            c0, r0 = int(np.floor(oc)), int(np.floor(orow))
            fc, fr = oc - c0, orow - r0
            acc = np.zeros_like(z)
            for dr, dc, wt in ((0, 0, (1 - fr) * (1 - fc)), (0, 1, (1 - fr) * fc),
                               (1, 0, fr * (1 - fc)), (1, 1, fr * fc)):
                if wt < 1e-9:
                    continue
                r, c = pad + r0 + dr, pad + c0 + dc
                acc += wt * (zp[r:r + h, c:c + w] - z)
            best = np.fmax(best, acc / d)
        ok = np.isfinite(best)
        total[ok] += np.degrees(np.arctan(best[ok]))
        count[ok] += 1
    sx = np.where(count > 0, total / np.maximum(count, 1), 0.0)
    return np.where(np.isnan(z), np.nan, sx)


def east_west_ratio(depth, z, cell, min_cells, min_depth):
    gy, gx = np.gradient(z, cell)  # rows go south: d/drow = -d/dnorth
    gn = -gy
    slope = np.degrees(np.arctan(np.hypot(gx, gn)))
    aspect = np.degrees(np.arctan2(-gx, -gn)) % 360.0
    ok = np.isfinite(depth) & np.isfinite(slope) & (slope > 15.0)
    east = ok & (aspect >= 45) & (aspect <= 135)
    west = ok & (aspect >= 225) & (aspect <= 315)
    lo = np.nanmin(z)
    band = np.floor((z - lo) / 200.0)
    num = den = pooled_e = pooled_w = 0.0
    bands = []
    for b in np.unique(band[ok]):
        e, wmask = east & (band == b), west & (band == b)
        ne, nw = int(e.sum()), int(wmask.sum())
        if ne < min_cells or nw < min_cells:
            continue
        de, dw = float(depth[e].mean()), float(depth[wmask].mean())
        if min(de, dw) < min_depth:
            continue
        bands.append({"band_from_m": float(lo + 200 * b), "east_m": de, "west_m": dw,
                      "east_cells": ne, "west_cells": nw})
        num += de / dw * (ne + nw)
        den += ne + nw
        pooled_e += de * (ne + nw)
        pooled_w += dw * (ne + nw)
    nan = float("nan")
    return (num / den if den else nan), (pooled_e / pooled_w if den else nan), bands


def spearman(a, b):
    ra = np.argsort(np.argsort(a)).astype(float)
    rb = np.argsort(np.argsort(b)).astype(float)
    return float(np.corrcoef(ra, rb)[0, 1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--wind-from", type=float, default=270.0)
    ap.add_argument("--snowscape", default=os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "target", "release", "snowscape"))
    ap.add_argument("--long-m", type=float, default=1000.0)
    ap.add_argument("--short-m", type=float, default=100.0)
    ap.add_argument("--top", type=float, default=0.05)
    ap.add_argument("--min-cells", type=int, default=None,
                    help="cells of each class a band needs (default max(10, 5000 m² / cell area))")
    ap.add_argument("--min-depth", type=float, default=0.05,
                    help="mean depth both classes of a band need, m (default 0.05)")
    ap.add_argument("--bands", action="store_true", help="also print the bands")
    args = ap.parse_args()
    for run in args.runs:
        depth = load_raster(args.snowscape, os.path.join(run, "depth.tif"))
        z = load_raster(args.snowscape, os.path.join(run, "bedrock.tif"))
        report = json.load(open(os.path.join(run, "report.json")))
        cell = float(report["input"]["cell_size_x"])
        min_cells = args.min_cells or max(10, int(round(5000.0 / (cell * cell))))
        ratio, pooled, bands = east_west_ratio(depth, z, cell, min_cells, args.min_depth)
        sx_long = max_upwind_slope(z, cell, args.wind_from, args.long_m)
        sx_short = max_upwind_slope(z, cell, args.wind_from, args.short_m)
        ok = np.isfinite(depth) & np.isfinite(sx_long)
        lo_q, hi_q = np.quantile(sx_long[ok], [args.top, 1.0 - args.top])
        exposed = ok & (sx_long <= lo_q)
        sheltered = ok & (sx_long >= hi_q)
        budget = report.get("mass_budget", {})
        out = {
            "run": run,
            "cell_m": cell,
            "wind_from_deg": args.wind_from,
            "east_west_ratio": ratio,
            "east_west_pooled": pooled,
            "east_west_bands": len(bands),
            "mean_depth_m": float(depth[ok].mean()),
            "exposed_top_depth_m": float(depth[exposed].mean()),
            "exposed_top_sx_long_deg": float(sx_long[exposed].mean()),
            "exposed_top_altitude_m": float(z[exposed].mean()),
            "sheltered_top_depth_m": float(depth[sheltered].mean()),
            "sheltered_top_sx_long_deg": float(sx_long[sheltered].mean()),
            "corr_sx_long_depth_spearman": spearman(sx_long[ok], depth[ok]),
            "corr_sx_short_depth_spearman": spearman(sx_short[ok], depth[ok]),
            "rho_depth_altitude": spearman(depth[ok], z[ok]),
            "wind_sublimation_m3": budget.get("outputs", {}).get("wind_sublimation"),
            "closure_error": budget.get("closure_error"),
            "wind_phase_s": report.get("timings", {}).get("phenomena", {}).get("wind_transport"),
            "sheltering_s": report.get("timings", {}).get("phenomena", {}).get("sheltering"),
        }
        if args.bands:
            out["bands"] = bands
        json.dump(out, sys.stdout)
        sys.stdout.write("\n")


if __name__ == "__main__":
    main()
