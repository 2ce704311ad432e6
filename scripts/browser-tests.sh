#!/usr/bin/env bash
# End-to-end tests of the editor in headless Chromium (Debian's `chromium`) driven by
# playwright-core: builds the page and the binary, starts `snowscape serve` on a free port
# (and a small one bound to 0.0.0.0, which asks for its access token, and one on the real
# avaMal DEM of ../shared/data, 37 % nodata), runs
# web/tests/browser.mjs against them, and stops the servers.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib/serve-background.sh
start_server 128 --bind 0.0.0.0
token_url="$url"
start_server 128 --dem ../shared/data/dem/avaframe_avaMal/avaMal.asc
dem_url="$url"
start_server 256
SNOWSCAPE_URL="$url" SNOWSCAPE_TOKEN_URL="$token_url" SNOWSCAPE_DEM_URL="$dem_url" \
  SNOWSCAPE_SHOTS="${SNOWSCAPE_SHOTS:-$scratch}" node web/tests/browser.mjs
# The live avalanche stream as a bare WebSocket client counts it (scripts/live-rate.sh measures
# it at 1024²), here for 2 s on the 256² server, so that the measuring client keeps working.
SNOWSCAPE_URL="$url" SNOWSCAPE_SECONDS=2 node --experimental-websocket web/tests/live_rate_ws.mjs

# scripts/serve.sh run from another folder: a relative --dem path is the caller's, npm ci is
# skipped while web/node_modules matches the lock file, and the page is served.
root="$(pwd)"
# (a folder inside the git-ignored target/, so that the relative path means nothing from the
# checkout's root)
caller_root="$root/target/serve-sh-check"
caller="$caller_root/caller"
rm -rf "$caller_root"
mkdir -p "$caller"
dem_rel=$(realpath --relative-to="$caller" ../shared/data/dem/avaframe_avaMal/avaMal.asc)
(cd "$caller" && exec bash "$root/scripts/serve.sh" --dem "$dem_rel" --port 0) >"$caller/log" 2>&1 &
serve_sh=$!
serve_url=""
for _ in $(seq 1 600); do
  serve_url=$(grep -o 'http://[0-9.:]*/' "$caller/log" | head -n1 || true)
  serve_token=$(grep -o 'token=[0-9a-f]*' "$caller/log" | head -n1 || true)
  [ -n "$serve_url" ] && break
  kill -0 "$serve_sh" 2>/dev/null || break
  sleep 0.5
done
serve_sh_ok=1
if [ -z "$serve_url" ]; then
  echo "FAIL scripts/serve.sh from another folder did not start:"; cat "$caller/log"; serve_sh_ok=0
else
  # The data needs the printed URL's access token (loopback included); the page does not.
  state=$(curl -sf "${serve_url}api/state?${serve_token}" || true)
  page=$(curl -sf "$serve_url" || true)
  if ! grep -q '"width":[0-9]' <<<"$state" || ! grep -qi '<html' <<<"$page"; then
    echo "FAIL scripts/serve.sh: no state or page at $serve_url"; serve_sh_ok=0
  elif [ "$(grep -o '"width":[0-9]*' <<<"$state")" != "\"width\":$(awk '/^ncols/ {print $2}' ../shared/data/dem/avaframe_avaMal/avaMal.asc)" ]; then
    echo "FAIL scripts/serve.sh: the relative --dem was not read from the caller's folder: $state"; serve_sh_ok=0
  elif grep -q "added [0-9]* packages" "$caller/log"; then
    echo "FAIL scripts/serve.sh ran npm ci although web/node_modules is current"; serve_sh_ok=0
  else
    echo "ok   scripts/serve.sh from another folder: relative --dem read, page served, no npm ci"
  fi
fi
kill "$serve_sh" 2>/dev/null || true
wait "$serve_sh" 2>/dev/null || true
rm -rf "$caller_root"
[ "$serve_sh_ok" = 1 ]
