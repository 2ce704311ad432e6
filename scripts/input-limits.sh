#!/usr/bin/env bash
# Hostile meshes, forcing CSVs, scenarios and checkpoints under a memory cap (issue 46, CI
# item 7; the rasters are scripts/reader-limits.sh): each crafted file (a face of a million
# corners, a PLY header of four billion vertices, a GLB reusing one mesh for 10.1 million
# triangles, an 8 MiB CSV line, 3651 weather periods, a checkpoint announcing a 2^62-byte
# header, forged ones; see crates/cli/examples/hostile_inputs.rs) is given to the `snowscape`
# subcommand that reads it (cover --mesh, run --forcing, run --scenario, run --resume), in its
# own process under `ulimit -v` (default 1 GiB). Every one must be refused with exit 2 and a
# message naming the value; a panic (101), an allocation abort (134), a kill (137), another
# exit or a message without the value fails the script.
# Usage: scripts/input-limits.sh [LIMIT_KIB]
set -euo pipefail
cd "$(dirname "$0")/.."
limit_kib="${1:-1048576}"
cargo build --release -q -p snowscape-cli --bin snowscape --example hostile_inputs
bin=target/release/snowscape
craft=target/release/examples/hostile_inputs
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$craft" craft "$dir"
dem="$dir/dem.asc"
# A genuine checkpoint to forge: a run stopped at day 2 of 4 (not under the cap).
"$bin" --quiet --threads 2 run --dem "$dem" --days 4 --stop-at 2 --out "$dir/run" > /dev/null
"$craft" forge "$dir/run" "$dir"

failed=0
# Runs `snowscape --quiet --threads 2 ARGS...` under the cap (two threads: every worker's
# stack and malloc arena reserve address space, which `ulimit -v` counts, so the cap would
# otherwise depend on the machine's cores); expects exit 2 and NEEDLE in the message.
# Usage: check LABEL NEEDLE ARGS...
check() {
  local label="$1" needle="$2"
  shift 2
  local out rc
  set +e
  out=$( (ulimit -v "$limit_kib"; exec "$bin" --quiet --threads 2 "$@") 2>&1)
  rc=$?
  set -e
  out="${out//$dir\//}"
  if [ "$rc" -eq 2 ] && [[ "$out" == *"$needle"* ]]; then
    echo "ok   $label: ${out:0:200}"
  else
    echo "FAIL $label: exit $rc under ulimit -v $limit_kib KiB (expected 2 and \"$needle\"): ${out:0:300}" >&2
    failed=1
  fi
}
cover() { check "cover --mesh $2" "$1" cover --mesh "$dir/$2" --out "$dir/out_cover"; }
forcing() {
  check "run --forcing $2" "$1" run --dem "$dem" --station-altitude 1800 --out "$dir/out_run" --forcing "$dir/$2"
}
scenario() { check "run --scenario $2" "$1" run --dem "$dem" --out "$dir/out_run" --scenario "$dir/$2"; }
resume() { check "run --resume $2" "$1" run --dem "$dem" --resume "$dir/$2"; }

cover "corners of one face 1000000 exceeds the limit of 1024" huge_face.obj
cover "1e30" far.obj
cover "vertex count 4000000000 exceeds the limit of 10000000" vertices.ply
cover "triangle count 10100000 exceeds the limit of 10000000" reused.glb
cover "accessor 0 of count 1000000" accessor.glb
forcing "8388608 bytes" long_line.csv
forcing "5001 columns" columns.csv
forcing "16777215 bytes" field.csv
forcing "more than 2635200 records" records.csv
forcing "629145600 bytes" big.csv
scenario "5242880 bytes" big.toml
scenario "3651 weather entries" weather.toml
scenario "nested 4999 levels deep" deep.toml
scenario "days = 1e308" days.toml
scenario "snapshot_every_days = 1e-300" snapshots.toml
resume "1099511627776 bytes" ckpt_sparse
resume "4611686018427387904" ckpt_header_len
resume "its header announces 67" ckpt_short
resume "weather_index = 9223372036854775808" ckpt_index
resume "scheduler.time_days = -1e300" ckpt_time
resume "layer 0 cell 5 = NaN" ckpt_nan

for out in out_cover out_run; do
  if [ -e "$dir/$out" ] && [ -n "$(ls -A "$dir/$out")" ]; then
    echo "FAIL: a refused input left files in $out" >&2
    failed=1
  fi
done
if [ "$failed" -ne 0 ]; then
  echo "scripts/input-limits.sh: a hostile input was not refused cleanly" >&2
  exit 1
fi
echo "scripts/input-limits.sh: every crafted mesh, forcing CSV, scenario and checkpoint refused with exit 2 naming the value under ulimit -v $limit_kib KiB"
