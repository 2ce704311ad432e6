#!/usr/bin/env bash
# A run into a full disk (issue 46): a small tmpfs holds a complete 128² demo; a 256² rerun
# into it runs out of space while writing. The rerun must fail with a message naming the
# file and "No space left", and leave the first run's outputs byte for byte, nothing else.
# Needs root with mount rights (CI runs as root); elsewhere it says SKIPPED and exits 0. Usage: scripts/full-disk.sh [BINARY]
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${1:-target/release/snowscape}"
mnt=$(mktemp -d)
if ! mount -t tmpfs -o size=5m tmpfs "$mnt" 2>/dev/null; then
  rmdir "$mnt"
  echo "scripts/full-disk.sh: SKIPPED: cannot mount a tmpfs here (needs root with mount rights)" >&2
  exit 0
fi
trap 'umount "$mnt"; rmdir "$mnt"' EXIT
"$bin" --quiet demo --size 128 --days 3 --frames 2 --out "$mnt/run"
before=$(cd "$mnt/run" && find . -type f -print0 | sort -z | xargs -0 sha256sum)
set +e
err=$("$bin" --quiet demo --size 256 --days 3 --frames 2 --out "$mnt/run" 2>&1)
code=$?
set -e
if [ "$code" = 0 ]; then
  echo "full-disk: the 256² rerun fitted in the tmpfs; make it smaller" >&2
  exit 1
fi
case "$err" in
  *"No space left"*) ;;
  *) echo "full-disk: unexpected error: $err" >&2; exit 1 ;;
esac
after=$(cd "$mnt/run" && find . -type f -print0 | sort -z | xargs -0 sha256sum)
if [ "$before" != "$after" ]; then
  echo "full-disk: the failed rerun changed the first run's outputs" >&2
  diff <(echo "$before") <(echo "$after") >&2 || true
  exit 1
fi
echo "full-disk: the rerun failed (exit $code: ${err:0:160}) and left the first run's $(echo "$before" | wc -l) files intact"
