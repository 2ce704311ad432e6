#!/usr/bin/env bash
# Compares the environment precompute with SAGA GIS on a real DEM:
#   - sky view factor: ours (Häntzschel 2005 formula, 8 directions) vs `saga_cmd ta_lighting 3`
#     (Sky View Factor, 8 sectors, unlimited radius);
#   - direct sun: ours (sun-hours on the winter solstice, 30-minute samples) vs
#     `saga_cmd ta_lighting 2` (Potential Incoming Solar Radiation, direct insolation, same
#     day and step, lumped atmospheric transmittance 100 % so only geometry and shading differ).
# Prints Pearson correlations (all valid cells, and 10 cells in from the edge) and the runtime
# ratio. Needs `saga_cmd` (Debian package `saga`) and python3.
#
# Usage: crates/environment/scripts/compare_saga.sh [DEM.asc] [OUT_DIR] [LATITUDE]
set -euo pipefail
cd "$(dirname "$0")/../../.."
DEM=${1:-/work/shared/data/dem/avaframe_avaMal/avaMal.asc}
OUT=${2:-target/compare_saga}
LAT=${3:-47}
DAY=355            # 21 December
DATE=2025-12-21
mkdir -p "$OUT"
command -v saga_cmd >/dev/null || { echo "saga_cmd not found (apt-get install saga)"; exit 1; }

now() { date +%s.%N; }
cargo build --release -q -p snowscape-environment --example environment_asc
t0=$(now)
./target/release/examples/environment_asc "$DEM" "$OUT" "$LAT" "$DAY" 1 1 2 8 >"$OUT/ours.log"
t1=$(now)

t2=$(now)
saga_cmd ta_lighting 3 -DEM="$DEM" -SVF="$OUT/saga_svf.sdat" -VISIBLE="$OUT/saga_visible.sdat" \
    -NDIRS=8 -RADIUS=1000000 -METHOD=0 >"$OUT/saga_svf.log" 2>&1
t3=$(now)
saga_cmd ta_lighting 2 -GRD_DEM="$DEM" -GRD_DIRECT="$OUT/saga_direct.sdat" \
    -GRD_DIFFUS="$OUT/saga_diffuse.sdat" -LOCATION=0 -LATITUDE="$LAT" -PERIOD=1 -DAY="$DATE" \
    -HOUR_RANGE_MIN=0 -HOUR_RANGE_MAX=24 -HOUR_STEP=0.5 -METHOD=2 -LUMPED=100 -SHADOW=0 \
    -UNITS=0 >"$OUT/saga_sun.log" 2>&1
t4=$(now)

echo "== timings (this machine)"
cat "$OUT/ours.log"
python3 - "$t0" "$t1" "$t2" "$t3" "$t4" "$OUT/ours.log" <<'PY'
import sys
t0, t1, t2, t3, t4 = map(float, sys.argv[1:6])
ours = dict(l.split() for l in open(sys.argv[6]) if l.strip())
sky, sun = float(ours["sky_alone_ms"]) / 1e3, float(ours["sun_alone_ms"]) / 1e3
print(f"ours: whole example run {t1 - t0:.2f} s (sky view {sky:.3f} s, sun {sun:.3f} s)")
print(f"saga: sky view factor {t3 - t2:.2f} s, potential solar radiation {t4 - t3:.2f} s")
print(f"runtime ratio saga/ours: sky view {(t3 - t2) / sky:.0f}x, sun {(t4 - t3) / sun:.0f}x")
PY
echo "== sky view factor (ours svf.asc vs SAGA SVF)"
python3 crates/environment/scripts/compare_grids.py "$OUT/svf.asc" "$OUT/saga_svf.sgrd"
python3 crates/environment/scripts/compare_grids.py "$OUT/svf.asc" "$OUT/saga_svf.sgrd" 10
echo "== direct sun (ours sun-hours vs SAGA direct insolation, kWh/m2)"
python3 crates/environment/scripts/compare_grids.py "$OUT/sun.asc" "$OUT/saga_direct.sgrd"
python3 crates/environment/scripts/compare_grids.py "$OUT/sun.asc" "$OUT/saga_direct.sgrd" 10
