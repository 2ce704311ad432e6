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
