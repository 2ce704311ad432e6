#!/usr/bin/env bash
# Measures the editor's live avalanche update rate over loopback on a SIZE² procedural terrain
# (default 1024): starts `snowscape serve`, runs web/tests/live_rate_ws.mjs (a bare WebSocket
# client: the server's stream) and web/tests/live_rate.mjs (the page in headless Chromium:
# stream plus rendering) against it, stops the server. Needs Node.js (npm) and chromium.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib/serve-background.sh
start_server "${1:-1024}" >/dev/null
SNOWSCAPE_URL="$url" node --experimental-websocket web/tests/live_rate_ws.mjs
SNOWSCAPE_URL="$url" node web/tests/live_rate.mjs
