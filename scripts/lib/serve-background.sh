# Sourced by the browser scripts: builds the page and the binary, starts `snowscape serve` on
# a free port with a scratch project, waits for its URL, and stops it on exit.
# Usage: start_server SIZE   (sets $url; the server is killed and the scratch removed on exit)
start_server() {
  local size="$1"
  local target="${CARGO_TARGET_DIR:-target}"
  (cd web && npm ci --no-audit --no-fund && npm run build)
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
}
