#!/usr/bin/env bash
# End-to-end tests of the editor in headless Chromium (Debian's `chromium`) driven by
# playwright-core: builds the page and the binary, starts `snowscape serve` on a free port,
# runs web/tests/browser.mjs against it, and stops the server.
set -euo pipefail
cd "$(dirname "$0")/.."
target="${CARGO_TARGET_DIR:-target}"
(cd web && npm ci --no-audit --no-fund && npm run build)
cargo build --release -p snowscape
scratch=$(mktemp -d)
"$target/release/snowscape" serve --size 256 --port 0 --project "$scratch/project" \
  --web-dir web/dist >"$scratch/serve.log" 2>&1 &
server=$!
trap 'kill "$server" 2>/dev/null || true; wait "$server" 2>/dev/null || true; rm -rf "$scratch"' EXIT
url=""
for _ in $(seq 1 240); do
  url=$(grep -o 'http://[0-9.:]*/' "$scratch/serve.log" | head -n1 || true)
  [ -n "$url" ] && break
  if ! kill -0 "$server" 2>/dev/null; then cat "$scratch/serve.log" >&2; exit 1; fi
  sleep 0.5
done
if [ -z "$url" ]; then echo "error: snowscape serve did not start" >&2; cat "$scratch/serve.log" >&2; exit 1; fi
SNOWSCAPE_URL="$url" SNOWSCAPE_SHOTS="${SNOWSCAPE_SHOTS:-$scratch}" node web/tests/browser.mjs
