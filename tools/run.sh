#!/usr/bin/env bash
# tools/run.sh [args...] - build the Release tools and run the demo:
#
#   tools/setup.sh core gdal plot, then configure + build the host-release preset, then
#   exec build/host-release/trn_demo "$@".
#
# Setup and build messages go to stderr, so trn_demo's stdout stays clean for
# pipes. Works from any directory; arguments are passed to trn_demo unchanged
# (relative paths are taken from the caller's directory).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

{
  bash "$ROOT/tools/setup.sh" core gdal plot
  (cd "$ROOT" && cmake --preset host-release && cmake --build --preset host-release)
} >&2

DEMO="$ROOT/build/host-release/trn_demo"
if [ ! -x "$DEMO" ]; then
  echo "run.sh: $DEMO was not built (is tools/trn_demo.c there?)" >&2
  exit 1
fi
exec "$DEMO" "$@"
