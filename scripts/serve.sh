#!/usr/bin/env bash
# One command on a fresh machine: installs the page's JavaScript libraries from the npm
# registry (web/package-lock.json) when web/node_modules is missing or older than the lock
# file, builds the page when a source is newer than the built page, builds the binary, and
# starts the editor serving that page (so a page built after the binary is served too).
# Arguments go to `snowscape serve` (e.g. --dem FILE, --size 512, --port 8080, --project DIR)
# and their paths are the caller's: they are read from the folder this is run from, where the
# default project folder (snowscape-project, git-ignored inside the checkout) is made too.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
web="$root/web"
if ! command -v npm >/dev/null; then
  echo "error: npm is missing: install Node.js (e.g. apt-get install nodejs npm)" >&2
  exit 1
fi
if [ ! -f "$web/node_modules/.package-lock.json" ] ||
  [ "$web/package-lock.json" -nt "$web/node_modules/.package-lock.json" ]; then
  (cd "$web" && npm ci --no-audit --no-fund)
fi
if [ ! -f "$web/dist/index.html" ] ||
  [ -n "$(find "$web/src" "$web/build.mjs" "$web/package.json" "$web/package-lock.json" \
    -newer "$web/dist/index.html" -print 2>/dev/null | head -n1)" ]; then
  (cd "$web" && npm run build)
fi
cargo build --release --quiet --manifest-path "$root/Cargo.toml" -p snowscape-cli
exec "${CARGO_TARGET_DIR:-$root/target}/release/snowscape" serve --web-dir "$web/dist" "$@"
