#!/usr/bin/env python3
"""Compare two rasters cell by cell: Pearson correlation, least-squares slope, RMSE.

Usage: compare_grids.py OURS.asc SAGA.sgrd [MARGIN_CELLS]

OURS is an ESRI ASCII grid (as written by the environment_asc example); SAGA is a SAGA grid
(.sgrd header + .sdat float32 data). Only cells valid in both, at least MARGIN_CELLS (default
0) away from the grid edge, are compared. Standard library only.
"""
import math
import struct
import sys


def read_asc(path):
    with open(path) as f:
        header = {}
        for _ in range(6):
            key, value = f.readline().split()
            header[key.lower()] = float(value)
        values = [float(v) for v in f.read().split()]
    ncols, nrows = int(header["ncols"]), int(header["nrows"])
    nodata = header.get("nodata_value", -9999.0)
    assert len(values) == ncols * nrows, f"{path}: {len(values)} values"
    return ncols, nrows, [None if v == nodata else v for v in values]


def read_sgrd(path):
    header = {}
    with open(path) as f:
        for line in f:
            if "=" in line:
                key, value = line.split("=", 1)
                header[key.strip()] = value.strip()
    ncols, nrows = int(header["CELLCOUNT_X"]), int(header["CELLCOUNT_Y"])
    assert header["DATAFORMAT"] == "FLOAT", header["DATAFORMAT"]
    order = ">" if header.get("BYTEORDER_BIG", "FALSE") == "TRUE" else "<"
    nodata = [float(v) for v in header["NODATA_VALUE"].split(";")]
    data_path = path[: -len(".sgrd")] + ".sdat"
    with open(data_path, "rb") as f:
        f.seek(int(header.get("DATAFILE_OFFSET", "0")))
        raw = struct.unpack(f"{order}{ncols * nrows}f", f.read(4 * ncols * nrows))
    rows = [raw[r * ncols:(r + 1) * ncols] for r in range(nrows)]
    if header.get("TOPTOBOTTOM", "FALSE") != "TRUE":
        rows.reverse()
    lo, hi = nodata[0], nodata[-1]
    values = [None if (lo <= v <= hi or math.isnan(v)) else v for row in rows for v in row]
    return ncols, nrows, values


def main():
    ours_path, saga_path = sys.argv[1], sys.argv[2]
    margin = int(sys.argv[3]) if len(sys.argv) > 3 else 0
    w, h, a = read_asc(ours_path)
    w2, h2, b = read_sgrd(saga_path)
    assert (w, h) == (w2, h2), f"sizes differ: {w}x{h} vs {w2}x{h2}"
    pairs = [
        (a[i], b[i])
        for i in range(w * h)
        if a[i] is not None and b[i] is not None
        and margin <= i % w < w - margin and margin <= i // w < h - margin
    ]
    n = len(pairs)
    mx = sum(p[0] for p in pairs) / n
    my = sum(p[1] for p in pairs) / n
    sxx = sum((p[0] - mx) ** 2 for p in pairs)
    syy = sum((p[1] - my) ** 2 for p in pairs)
    sxy = sum((p[0] - mx) * (p[1] - my) for p in pairs)
    r = sxy / math.sqrt(sxx * syy) if sxx > 0 and syy > 0 else float("nan")
    slope = sxy / sxx if sxx > 0 else float("nan")
    rmse = math.sqrt(sum((p[0] - p[1]) ** 2 for p in pairs) / n)
    print(f"cells {n} ours_mean {mx:.4f} saga_mean {my:.4f} pearson_r {r:.4f} "
          f"saga_per_ours_slope {slope:.4f} rmse {rmse:.4f}")


if __name__ == "__main__":
    main()
