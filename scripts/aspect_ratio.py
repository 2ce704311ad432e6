#!/usr/bin/env python3
"""North/south snow-depth ratio within altitude bands, from a season's outputs.

Reads `depth.tif` and `bedrock.tif` of a `snowscape run` / `demo` output folder (plain
GeoTIFFs: strips, uncompressed or Deflate, float32; not the `--cog` tiled layout) with numpy
and the standard library only, and prints, per altitude band (200 m by default), the mean
depth on north-facing and south-facing slopes steeper than 15 degrees (aspect within 45
degrees of north or of south, from the bedrock by central differences, raster rows running
north to south) and their ratio, then two summaries over the bands with at least
`--min-cells` cells of each: the sum of the bands' north means over the sum of their south
means (robust where south-facing snow is nearly gone), and the mean of the band ratios
weighted by min(north cells, south cells). `--pair east-west` compares east-facing
with west-facing slopes the same way (the lee of a westerly over its windward side). Issue 47's figure: `python3 scripts/aspect_ratio.py OUT` after
`snowscape run --dem avaMal.asc --latitude 37.6 --out OUT`.

Also prints the Spearman rank correlation of depth with altitude over snow-covered cells.
"""

import argparse
import struct
import sys
import zlib

import numpy as np


def read_geotiff(path):
    """(array float64 with NaN for nodata, cell size x, cell size y) of a strip GeoTIFF."""
    data = open(path, "rb").read()
    endian = "<" if data[:2] == b"II" else ">"
    if struct.unpack(endian + "H", data[2:4])[0] != 42:
        sys.exit(f"{path}: not a classic TIFF")
    offset = struct.unpack(endian + "I", data[4:8])[0]
    count = struct.unpack(endian + "H", data[offset:offset + 2])[0]
    sizes = {1: 1, 2: 1, 3: 2, 4: 4, 5: 8, 11: 4, 12: 8, 16: 8}
    codes = {1: "B", 2: "c", 3: "H", 4: "I", 5: "II", 11: "f", 12: "d", 16: "Q"}
    tags = {}
    for i in range(count):
        entry = data[offset + 2 + 12 * i: offset + 14 + 12 * i]
        tag, kind, n = struct.unpack(endian + "HHI", entry[:8])
        size = sizes.get(kind, 1) * n
        raw = entry[8:12] if size <= 4 else data[
            struct.unpack(endian + "I", entry[8:12])[0]:][:size]
        if kind in (1, 2, 7):
            tags[tag] = raw[:n]
        else:
            fmt = endian + codes[kind] * n
            tags[tag] = struct.unpack(fmt, raw[:struct.calcsize(fmt)])
    width, height = tags[256][0], tags[257][0]
    if 322 in tags:
        sys.exit(f"{path}: tiled (COG) layout is not supported; run without --cog")
    bits, compression = tags[258][0], tags.get(259, (1,))[0]
    predictor = tags.get(317, (1,))[0]
    fmt = tags.get(339, (1,))[0]
    if compression not in (1, 8, 32946) or predictor != 1:
        sys.exit(f"{path}: compression {compression} / predictor {predictor} not supported")
    dtype = {(3, 32): "f4", (3, 64): "f8", (1, 16): "u2", (2, 16): "i2"}[(fmt, bits)]
    chunks = []
    for start, length in zip(tags[273], tags[279]):
        chunk = data[start:start + length]
        chunks.append(zlib.decompress(chunk) if compression != 1 else chunk)
    values = np.frombuffer(b"".join(chunks), dtype=endian + dtype)[:width * height]
    grid = values.reshape(height, width).astype(np.float64)
    if 42113 in tags:
        nodata = float(bytes(tags[42113]).rstrip(b"\0").decode())
        grid[grid == nodata] = np.nan
    scale = tags.get(33550, (1.0, 1.0, 0.0))
    return grid, scale[0], scale[1]


def rank(values):
    order = np.argsort(values, kind="stable")
    ranks = np.empty(len(values))
    ranks[order] = np.arange(len(values))
    return ranks


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", help="output folder with depth.tif and bedrock.tif")
    parser.add_argument("--band", type=float, default=200.0, help="band height, m")
    parser.add_argument("--min-slope", type=float, default=15.0, help="degrees")
    parser.add_argument("--min-cells", type=int, default=50)
    parser.add_argument("--pair", choices=["north-south", "east-west"], default="north-south",
                        help="which two aspects to compare (east-west: the lee of a westerly "
                             "over its windward side)")
    args = parser.parse_args()
    depth, _, _ = read_geotiff(f"{args.out}/depth.tif")
    bedrock, dx, dy = read_geotiff(f"{args.out}/bedrock.tif")
    # Gradient: east along columns, north against rows.
    dz_east = np.full(bedrock.shape, np.nan)
    dz_north = np.full(bedrock.shape, np.nan)
    dz_east[:, 1:-1] = (bedrock[:, 2:] - bedrock[:, :-2]) / (2 * dx)
    dz_north[1:-1, :] = (bedrock[:-2, :] - bedrock[2:, :]) / (2 * dy)
    slope = np.degrees(np.arctan(np.hypot(dz_east, dz_north)))
    # Aspect: the downslope direction, clockwise from north.
    aspect = np.degrees(np.arctan2(-dz_east, -dz_north)) % 360.0
    valid = np.isfinite(slope) & np.isfinite(depth) & (slope > args.min_slope)
    if args.pair == "north-south":
        north = valid & ((aspect >= 315.0) | (aspect < 45.0))
        south = valid & (aspect >= 135.0) & (aspect < 225.0)
    else:
        # The same arithmetic with east in the first place and west in the second.
        north = valid & (aspect >= 45.0) & (aspect < 135.0)
        south = valid & (aspect >= 225.0) & (aspect < 315.0)
    first, second = ("north", "south") if args.pair == "north-south" else ("east", "west")
    band = np.floor(bedrock / args.band)
    print(f"{'band, m':>13} {first + ' cells':>11} {second + ' cells':>11} "
          f"{first + ' m':>8} {second + ' m':>8} {first[0].upper() + '/' + second[0].upper():>6}")
    weights, ratios, sums = [], [], [0.0, 0.0]
    for b in np.unique(band[valid]):
        n = north & (band == b)
        s = south & (band == b)
        if not n.any() or not s.any():
            continue
        dn, ds = depth[n].mean(), depth[s].mean()
        ratio = dn / ds if ds > 0 else float("inf")
        lo = int(b * args.band)
        print(f"{lo:>6}-{lo + int(args.band):<6} {n.sum():>11} {s.sum():>11} "
              f"{dn:>8.3f} {ds:>8.3f} {ratio:>6.2f}")
        if min(n.sum(), s.sum()) >= args.min_cells:
            sums[0] += dn
            sums[1] += ds
            if np.isfinite(ratio):
                weights.append(min(n.sum(), s.sum()))
                ratios.append(ratio)
    if sums[1] > 0:
        print(f"{first}/{second} ratio of the band means, summed over the bands with >= "
              f"{args.min_cells} cells of each: {sums[0] / sums[1]:.3f}")
    if ratios:
        pooled = float(np.average(ratios, weights=weights))
        print(f"band ratios weighted by the smaller count: {pooled:.3f} over {len(ratios)} "
              f"bands (unstable where {second}-facing snow is nearly gone)")
    snowy = np.isfinite(depth) & np.isfinite(bedrock) & (depth > 0)
    if snowy.sum() > 2:
        rho = np.corrcoef(rank(depth[snowy]), rank(bedrock[snowy]))[0, 1]
        print(f"Spearman rho(depth, altitude) over {snowy.sum()} snow-covered cells: {rho:.3f}")
    print(f"mean depth of valid cells: {np.nanmean(depth):.3f} m")


if __name__ == "__main__":
    main()
