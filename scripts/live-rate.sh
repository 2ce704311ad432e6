#!/usr/bin/env bash
# Measures the editor's live avalanche update rate over loopback in headless Chromium on a
# SIZE² procedural terrain (default 1024): starts `snowscape serve`, runs
# web/tests/live_rate_ws.mjs (a bare WebSocket client: the server's stream) and
# web/tests/live_rate.mjs (the page in Chromium: stream plus rendering) against it, stops the server. Needs Node.js (npm) and chromium.
set -euo pipefail
cd "$(dirname "$0")/.."
size="${1:-1024}"
target="${CARGO_TARGET_DIR:-target}"
(cd web && npm ci --no-audit --no-fund && npm run build) >/dev/null
cargo build --release -p snowscape
scratch=$(mktemp -d)
"$target/release/snowscape" serve --size "$size" --port 0 --project "$scratch/project" \
  --web-dir web/dist >"$scratch/serve.log" 2>&1 &
server=$!
trap 'kill "$server" 2>/dev/null || true; wait "$server" 2>/dev/null || true; rm -rf "$scratch"' EXIT
url=""
for _ in $(seq 1 600); do
  url=$(grep -o 'http://[0-9.:]*/' "$scratch/serve.log" | head -n1 || true)
  [ -n "$url" ] && break
  if ! kill -0 "$server" 2>/dev/null; then cat "$scratch/serve.log" >&2; exit 1; fi
  sleep 0.5
done
if [ -z "$url" ]; then echo "error: snowscape serve did not start" >&2; cat "$scratch/serve.log" >&2; exit 1; fi
SNOWSCAPE_URL="$url" node --experimental-websocket web/tests/live_rate_ws.mjs
SNOWSCAPE_URL="$url" node web/tests/live_rate.mjs
