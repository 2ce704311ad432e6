#!/usr/bin/env bash
# End-to-end tests of the editor in headless Chromium (Debian's `chromium`) driven by
# playwright-core: builds the page and the binary, starts `snowscape serve` on a free port,
# runs web/tests/browser.mjs against it, and stops the server.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib/serve-background.sh
start_server 256
SNOWSCAPE_URL="$url" SNOWSCAPE_SHOTS="${SNOWSCAPE_SHOTS:-$scratch}" node web/tests/browser.mjs
