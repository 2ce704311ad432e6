#!/usr/bin/env bash
# The project's test command (docs/src/getting-started.md, "Run the tests"; .ci/run calls
# exactly this). Builds everything, runs every unit, integration, property and real-data test,
# runs each criterion benchmark once in test mode (so none rots), then the `bench` subcommand
# and the demo at a reduced size, the Python package's and the editor's tests, and last checks
# and builds the book (docs/).
set -euo pipefail
shopt -s inherit_errexit 2>/dev/null || true
cd "$(dirname "$0")/.."

if [ ! -d ../shared/data/dem ]; then
  echo "error: ../shared/data/dem is missing: the real-data tests need the shared data folder beside the checkout" >&2
  exit 1
fi

export SNOWSCAPE_BENCH_SIZE="${SNOWSCAPE_BENCH_SIZE:-128}"
log=$(mktemp)
scratch=$(mktemp -d)
trap 'rm -rf "$scratch" "$log"' EXIT
cargo build --release --workspace --all-targets
cargo test --release --workspace --all-targets 2>&1 | tee -a "$log"
cargo test --release --workspace --doc 2>&1 | tee -a "$log"

bin=target/release/snowscape
"$bin" --quiet bench --size 256 --repeats 2 --out "$scratch/bench.json"
"$bin" --quiet demo --size 128 --days 5 --frames 3 --out "$scratch/demo"
test -s "$scratch/demo/report.json"
# The library's examples (a winter from code, an avalanche, a mesh cover, a transport run), so
# none rots.
target/release/examples/winter procedural 5 "$scratch/ex_winter" > /dev/null
test -s "$scratch/ex_winter/depth.tif"
target/release/examples/avalanche ../shared/data "$scratch/ex_avalanche" > /dev/null
test -s "$scratch/ex_avalanche/peak_thickness.tif"
target/release/examples/mesh_cover ../shared/data/meshes/spider.obj "$scratch/ex_cover" > /dev/null
test -s "$scratch/ex_cover/diffusion_snow.glb"
target/release/examples/transport 1 "$scratch/ex_transport" > /dev/null
test -s "$scratch/ex_transport/depth.tif"
# The season's phase timings and the shedding timing at a reduced size (so the example never rots).
target/release/examples/season_phases 128 > /dev/null
target/release/examples/season_phases 128 shed > /dev/null
# The large-export memory check at a reduced size (16384² by hand: scripts/export-memory.sh).
bash scripts/export-memory.sh "$scratch/large_run" 600 > /dev/null
# Crafted rasters (decompression bombs, offsets past the end) read under `ulimit -v`: each is
# refused with exit 2, none killed for memory.
bash scripts/reader-limits.sh > /dev/null
# Crafted meshes, forcing CSVs, scenarios and checkpoints (a face of a million corners, a GLB
# reusing one mesh for 10 million triangles, an 8 MiB CSV line, forged checkpoints) given to
# `snowscape` under `ulimit -v`: each refused with exit 2 naming the value.
bash scripts/input-limits.sh > /dev/null
# A rerun into a full disk (a 5 MB tmpfs) fails and leaves the first run's outputs intact.
bash scripts/full-disk.sh "$bin"
# The Python package: built by pip (maturin) into a fresh virtual environment, from the same
# target folder as the rest, then its tests (the same bytes as `snowscape run`) and example.
python3 -m venv "$scratch/venv"
CARGO_TARGET_DIR="$PWD/target" "$scratch/venv/bin/pip" install --quiet "./python[test]"
"$scratch/venv/bin/python" -m pytest -q python/tests 2>&1 | tee -a "$log"
"$scratch/venv/bin/python" examples/python/season.py "" 3 "$scratch/py_season" > /dev/null
test -s "$scratch/py_season/depth.tif"
bash scripts/browser-tests.sh 2>&1 | tee -a "$log"
# The book (docs/, mdBook): its generated pages (the parameter catalogue, every command's
# --help, the crate dependencies from cargo metadata) must match what this build and the
# Cargo.toml files say, it must build, and no relative link or #anchor in it or in README.md may
# be broken.
python3 scripts/gen-docs.py --check --bin "$bin"
mdbook build docs
python3 scripts/check-doc-links.py
passed=$(grep -Eo '^test result: ok\. [0-9]+ passed' "$log" | awk '{s += $4} END {print s + 0}')
failed=$(grep -Eo '[0-9]+ failed' "$log" | awk '{s += $1} END {print s + 0}')
echo "scripts/test.sh: all checks passed (unit, integration, property, real-data, doc tests; benchmarks in test mode; bench and demo at reduced size; Python package tests; editor browser tests; the book and its links)"
echo "$passed passed, $failed failed"
