"""A winter on a real DEM from Python: the depth map written as GeoTIFF, the volume budget
printed, and (when matplotlib is installed) a figure of the depth over the shaded terrain.

    python examples/python/season.py [DEM] [DAYS] [OUT_DIR]

Default DEM: ../shared/data/dem/avaframe_avaWog/avaWog.asc (beside the checkout).
"""

import sys
from pathlib import Path

import numpy as np

import snowscape

root = Path(__file__).resolve().parents[2]
dem_path = Path(sys.argv[1]) if len(sys.argv) > 1 and sys.argv[1] else root.parent / "shared/data/dem/avaframe_avaWog/avaWog.asc"
days = float(sys.argv[2]) if len(sys.argv) > 2 else 30.0
out = Path(sys.argv[3]) if len(sys.argv) > 3 else Path("out/python_season")
out.mkdir(parents=True, exist_ok=True)

dem = snowscape.read_dem(dem_path)
print(f"{dem_path.name}: {dem}")
winter = snowscape.Winter(dem, scenario={"days": days}, seed=1)
winter.run(progress=lambda day: print(f"\rday {day:6.2f} / {days:g}", end="", flush=True))
print()
depth = winter.depth()
snowscape.write(depth, out / "depth.tif")
b = winter.budget()
print(
    f"depth: mean {np.nanmean(depth.values):.2f} m, max {np.nanmax(depth.values):.2f} m; "
    f"snowfall {b['snowfall']:.0f} m³, melt {b['melt']:.0f} m³, shed {b['shedding_moved']:.0f} m³"
)
print(f"wrote {out / 'depth.tif'}")

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("(matplotlib is not installed: no figure)")
else:
    z = dem.values
    gy, gx = np.gradient(np.nan_to_num(z, nan=np.nanmin(z)), dem.cell_size)
    shade = np.clip(0.6 - 0.4 * gx + 0.4 * gy, 0, 1)
    x0, dx, _, y0, _, dy = dem.transform
    h, w = z.shape
    extent = (x0, x0 + w * dx, y0 + h * dy, y0)
    fig, ax = plt.subplots(figsize=(7, 7))
    ax.imshow(np.where(np.isnan(z), np.nan, shade), cmap="gray", extent=extent)
    # The colour scale to the 99th percentile: debris cones at the foot of faces would wash out the rest.
    vmax = float(np.nanpercentile(depth.values, 99))
    im = ax.imshow(np.ma.masked_less(depth.values, 0.01), cmap="Blues", vmin=0, vmax=vmax, alpha=0.85, extent=extent)
    fig.colorbar(im, ax=ax, label="snow depth (m; 99th percentile and above in the darkest blue)")
    ax.set_title(f"{dem_path.stem}: snow depth after {days:g} days")
    fig.savefig(out / "depth.png", dpi=120)
    print(f"wrote {out / 'depth.png'}")
