#!/usr/bin/env bash
# The project's test command (README "Run the tests"; .ci/run calls exactly this).
# Builds everything, runs every unit, integration, property and real-data test, runs each
# criterion benchmark once in test mode (so none rots), then the `bench` subcommand and the
# demo at a reduced size.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ ! -d ../shared/data/dem ]; then
  echo "error: ../shared/data/dem is missing: the real-data tests need the shared data folder beside the checkout" >&2
  exit 1
fi

export SNOWSCAPE_BENCH_SIZE="${SNOWSCAPE_BENCH_SIZE:-128}"
cargo build --release --workspace --all-targets
cargo test --release --workspace --all-targets
cargo test --release --workspace --doc

bin=target/release/snowscape
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
"$bin" --quiet bench --size 256 --repeats 2 --out "$scratch/bench.json"
"$bin" --quiet demo --size 128 --days 5 --frames 3 --out "$scratch/demo"
test -s "$scratch/demo/report.json"
echo "scripts/test.sh: all checks passed"
