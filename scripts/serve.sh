#!/usr/bin/env bash
# One command on a fresh machine: installs the page's JavaScript libraries from the npm
# registry (web/package-lock.json), builds the page, then builds and starts the editor.
# Arguments go to `snowscape serve` (e.g. --dem FILE, --size 512, --port 8080, --project DIR).
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v npm >/dev/null; then
  echo "error: npm is missing: install Node.js (e.g. apt-get install nodejs npm)" >&2
  exit 1
fi
(cd web && npm ci --no-audit --no-fund && npm run build)
exec cargo run --release -p snowscape -- serve --web-dir web/dist "$@"
