#!/usr/bin/env bash
# Regenerates the book's editor screenshots (docs/src/images/editor_default.png: the bundled terrain
# after 30 days; docs/src/images/editor_avamal_day60.png: the real avaMal DEM at day 60) in headless
# Chromium.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib/serve-background.sh
start_server 256
SNOWSCAPE_URL="$url" SNOWSCAPE_DAYS=30 SNOWSCAPE_OUT=docs/src/images/editor_default.png node web/tests/readme_shots.mjs
start_server 128 --dem ../shared/data/dem/avaframe_avaMal/avaMal.asc
SNOWSCAPE_URL="$url" SNOWSCAPE_DAYS=60 SNOWSCAPE_OUT=docs/src/images/editor_avamal_day60.png node web/tests/readme_shots.mjs
