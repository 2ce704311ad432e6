# Sourced by the browser scripts: builds the page and the binary, starts `snowscape serve` on
# a free port with a scratch project, waits for its URL, and stops it on exit.
# Usage: start_server SIZE [SERVE OPTIONS...]   (sets $url, with `?token=…` when the options
# bind beyond loopback; every server started is killed and the scratch removed on exit; the
# page and the binary are built on the first call)
servers=()
scratch=""
stop_servers() {
  for s in "${servers[@]}"; do kill "$s" 2>/dev/null || true; wait "$s" 2>/dev/null || true; done
  [ -n "$scratch" ] && rm -rf "$scratch"
}
start_server() {
  local size="$1"
  shift
  local target="${CARGO_TARGET_DIR:-target}"
  if [ -z "$scratch" ]; then
    (cd web && npm ci --no-audit --no-fund && npm run build)
    cargo build --release -p snowscape-cli
    scratch=$(mktemp -d)
    trap stop_servers EXIT
  fi
  local n=${#servers[@]}
  local log="$scratch/serve$n.log"
  "$target/release/snowscape" serve --size "$size" --port 0 --project "$scratch/project$n" \
    --web-dir web/dist "$@" >"$log" 2>&1 &
  local server=$!
  servers+=("$server")
  url=""
  for _ in $(seq 1 600); do
    url=$(grep -o 'http://[0-9.:]*/[?=a-z0-9]*' "$log" | head -n1 || true)
    [ -n "$url" ] && break
    if ! kill -0 "$server" 2>/dev/null; then cat "$log" >&2; exit 1; fi
    sleep 0.5
  done
  if [ -z "$url" ]; then echo "error: snowscape serve did not start" >&2; cat "$log" >&2; exit 1; fi
}
