#!/usr/bin/env bash
# Hostile rasters under a memory cap (issue 46): each crafted file (deflate bombs of a few KB
# claiming 1-1.6 GB, offsets past the end, huge tag and header counts; see
# crates/io/examples/reader_limits.rs) is read by `read_dem` in its own process under
# `ulimit -v` (default 1 GiB). Every read must be refused with a typed error (exit 2); a panic
# (101), an allocation abort (134), a kill (137) or a read that succeeds fails the script.
# Usage: scripts/reader-limits.sh [LIMIT_KIB]
set -euo pipefail
cd "$(dirname "$0")/.."
limit_kib="${1:-1048576}"
cargo build --release -q -p snowscape-io --example reader_limits
bin=target/release/examples/reader_limits
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$bin" craft "$dir"
failed=0
# file, then the cell limit (default: ReadOptions's 2^28)
cases=(
  "bomb16k.tif" ""
  "bomb20k.tif" ""
  "bomb20k.tif" "1073741824"
  "bigtiff_far.tif" ""
  "tag.tif" ""
  "bomb.png" ""
  "far.exr" ""
  "big.npy" ""
  "long.asc" ""
)
for ((i = 0; i < ${#cases[@]}; i += 2)); do
  f="${cases[i]}"
  max="${cases[i + 1]}"
  set +e
  out=$( (ulimit -v "$limit_kib"; exec "$bin" read "$dir/$f" $max) 2>&1)
  rc=$?
  set -e
  label="$f${max:+ (max_cells $max)}"
  if [ "$rc" -eq 2 ]; then
    echo "ok   $label: ${out:0:200}"
  else
    echo "FAIL $label: exit $rc under ulimit -v $limit_kib KiB: ${out:0:300}" >&2
    failed=1
  fi
done
if [ "$failed" -ne 0 ]; then
  echo "scripts/reader-limits.sh: a hostile raster was not refused cleanly" >&2
  exit 1
fi
echo "scripts/reader-limits.sh: every crafted raster refused with a typed error under ulimit -v $limit_kib KiB"
