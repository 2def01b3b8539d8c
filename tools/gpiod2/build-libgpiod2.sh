#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/gpiod2/build-libgpiod2.sh [OUT_DIR] - a static libgpiod 2 for testing
# the Linux port's libgpiod 2 code (port/linux/linux_gpio_v2.c) on a machine
# whose distribution ships libgpiod 1.6 only (Debian 12).
#
# Debian 12 has no libgpiod 2 package. The PyPI package `gpiod` (libgpiod's
# own Python bindings, 2.x) ships the C library's sources in its sdist
# (include/gpiod.h, lib/*.c; libgpiod-version.txt names the libgpiod
# release). This script downloads that sdist with the project venv's pip
# (.venv, made on first use like tools/real/dems.py does; nothing is
# installed), compiles lib/*.c into OUT_DIR/lib/libgpiod.a with gpiod.h in
# OUT_DIR/include, and prints OUT_DIR. Kept while the version stays the same
# (OUT_DIR/version). Default OUT_DIR: build/libgpiod2. libgpiod is LGPL-2.1:
# it is only built here, for the tests, never installed or packaged.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
ROOT=$(pwd)
PKG="gpiod==2.5.0"
OUT=${1:-"$ROOT/build/libgpiod2"}
log() { echo "libgpiod2: $*" >&2; }

if [ -f "$OUT/version" ] && [ "$(cat "$OUT/version")" = "$PKG" ] && [ -f "$OUT/lib/libgpiod.a" ]; then
  echo "$OUT"
  exit 0
fi

VENV="$ROOT/.venv"
if [ ! -x "$VENV/bin/python3" ]; then
  log "making the project venv $VENV"
  /usr/bin/python3 -m venv --system-site-packages "$VENV"
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
log "pip download $PKG (sdist)"
"$VENV/bin/python3" -m pip download -q --no-deps --no-binary gpiod -d "$tmp" "$PKG" >&2
sdist=$(ls "$tmp"/gpiod-*.tar.gz)
tar -xzf "$sdist" -C "$tmp"
src=$(ls -d "$tmp"/gpiod-*/)
[ -f "$src/include/gpiod.h" ] && ls "$src"/lib/*.c >/dev/null ||
  { log "$sdist has no libgpiod sources (include/gpiod.h, lib/*.c)"; exit 1; }
ver=$(cat "$src/libgpiod-version.txt")
log "libgpiod $ver from $(basename "$sdist")"

rm -rf "$OUT"
mkdir -p "$OUT/include" "$OUT/lib" "$OUT/obj"
for c in "$src"/lib/*.c; do
  cc -O2 -fPIC -D_GNU_SOURCE -I"$src/include" -I"$src/lib" "-DGPIOD_API_VERSION_STR=\"$ver\"" \
     -c "$c" -o "$OUT/obj/$(basename "$c" .c).o"
done
ar rcs "$OUT/lib/libgpiod.a" "$OUT"/obj/*.o
cp "$src/include/gpiod.h" "$OUT/include/"
echo "$PKG" >"$OUT/version"
echo "$ver" >"$OUT/libgpiod-version"
echo "$OUT"
