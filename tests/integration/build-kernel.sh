#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tests/integration/build-kernel.sh - build (once) the small Linux the kernel
# tests boot, and print the path of its bzImage.
#
#   bash tests/integration/build-kernel.sh     # prints .../kernel-<key>/bzImage
#
# Source: Debian's linux-source-6.1 (/usr/src/linux-source-6.1.tar.xz), x86_64
# `make tinyconfig` plus the options of kernel.config. The result is cached
# outside the build tree, in ${TRN_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/trn},
# under a key made of the hash of kernel.config and the linux-source package
# version: fresh clones on the same machine reuse it, and any change of the
# option list rebuilds the whole kernel. Concurrent callers wait on a lock.
# Every wanted option is checked in the final .config (olddefconfig silently
# drops options whose parents are off); a missing one fails the build loudly.
# Build log: <cache>/kernel-<key>.log. Parallelism: TRN_KERNEL_JOBS (default 2).
set -euo pipefail

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
FRAG="$HERE/kernel.config"
TARBALL=/usr/src/linux-source-6.1.tar.xz
CACHE=${TRN_CACHE_DIR:-${XDG_CACHE_HOME:-${HOME:-/tmp}/.cache}/trn}
JOBS=${TRN_KERNEL_JOBS:-2}

die() { echo "build-kernel: $*" >&2; exit 1; }

[ -r "$TARBALL" ] || die "$TARBALL missing (bash tools/setup.sh vm)"
srcver=$(dpkg-query -W -f='${Version}' linux-source-6.1 2>/dev/null || echo unknown)
key=$( { cat "$FRAG"; echo "linux-source-6.1 $srcver"; } | sha256sum | cut -c1-16)
OUT="$CACHE/kernel-$key"
IMAGE="$OUT/bzImage"

mkdir -p "$CACHE"
if [ -s "$IMAGE" ]; then
  echo "$IMAGE"
  exit 0
fi

exec 9>"$CACHE/kernel-$key.lock"
flock 9
if [ -s "$IMAGE" ]; then    # built by another caller while we waited
  echo "$IMAGE"
  exit 0
fi

WORK="$CACHE/kernel-$key.build"
LOG="$CACHE/kernel-$key.log"
rm -rf "$WORK"
mkdir -p "$WORK"
echo "build-kernel: building $IMAGE (log: $LOG; about 5 min with -j$JOBS)" >&2
t0=$SECONDS
{
  tar -C "$WORK" -xf "$TARBALL"
  cd "$WORK/linux-source-6.1"
  make ARCH=x86_64 tinyconfig
  scripts/kconfig/merge_config.sh -m .config "$FRAG"
  make ARCH=x86_64 olddefconfig
} >"$LOG" 2>&1 || die "configuring failed, see $LOG"

cd "$WORK/linux-source-6.1"
missing=()
while IFS= read -r line; do
  case $line in ''|'#'*) continue ;; esac
  grep -qx -- "$line" .config || missing+=("$line")
done <"$FRAG"
if [ ${#missing[@]} -ne 0 ]; then
  die "the final .config lacks: ${missing[*]} (a parent option is off?); see $WORK/linux-source-6.1/.config"
fi

make ARCH=x86_64 -j"$JOBS" bzImage >>"$LOG" 2>&1 || die "make bzImage failed, see $LOG"
mkdir -p "$OUT"
cp .config "$OUT/config"
cp arch/x86/boot/bzImage "$OUT/bzImage.tmp"
mv "$OUT/bzImage.tmp" "$IMAGE"
cd /
rm -rf "$WORK"
echo "build-kernel: built in $((SECONDS - t0)) s" >&2
echo "$IMAGE"
