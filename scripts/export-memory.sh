#!/usr/bin/env bash
# Peak memory of `snowscape export` on a 16384² run folder (issue: large exports stream tile by
# tile and stay under 2 GB). Writes ~0.9 GB of GeoTIFFs under $1 (default /tmp/snowscape-16k).
# Usage: scripts/export-memory.sh [DIR] [SIZE]
set -euo pipefail
dir="${1:-/tmp/snowscape-16k}"
size="${2:-16384}"
cargo build --release -q -p snowscape-cli -p snowscape --example large_run_folder
[ -f "$dir/layers_powder.tif" ] || target/release/examples/large_run_folder "$size" "$dir"
for args in "--engine unreal --with-snow --tile 2017" "--engine unreal --with-snow" \
    "--engine unity --with-snow" "--engine godot --with-snow"; do
    out="$(mktemp -d)"
    if [ -x /usr/bin/time ]; then
        # shellcheck disable=SC2086
        /usr/bin/time -f "%M KiB peak, %e s" target/release/snowscape export --run "$dir" $args \
            --out "$out" -q 2> "$out.time"
    else
        # shellcheck disable=SC2086
        target/release/snowscape export --run "$dir" $args --out "$out" -q
        echo "(no /usr/bin/time: install Debian's 'time' to measure the peak)" > "$out.time"
    fi
    echo "export $args: $(tail -1 "$out.time") ($(ls "$out" | wc -l) files)"
    rm -rf "$out" "$out.time"
done
