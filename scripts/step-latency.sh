#!/usr/bin/env bash
# How long a season step takes to show in the editor's page after the server finishes it, on a
# SIZE² procedural terrain (default 1024) in headless Chromium (web/tests/step_latency.mjs).
# Usage: scripts/step-latency.sh [SIZE] [DAYS]
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib/serve-background.sh
start_server "${1:-1024}" >/dev/null
echo "with shadows:"
SNOWSCAPE_REPEATS=4 SNOWSCAPE_URL="$url" SNOWSCAPE_DAYS="${2:-1}" node web/tests/step_latency.mjs
echo "without shadows (?noshadows):"
SNOWSCAPE_REPEATS=4 SNOWSCAPE_URL="$url" SNOWSCAPE_DAYS="${2:-1}" SNOWSCAPE_NO_SHADOWS=1 node web/tests/step_latency.mjs
