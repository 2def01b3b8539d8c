#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tests/package/test_deb.sh BUILD_DIR VERSION WORK_DIR [CC [CFLAGS]] - the
# CTest `package_deb`: the Debian package CPack makes of this build.
#
#   1. cpack -G DEB with BUILD_DIR's CPackConfig.cmake, into WORK_DIR;
#   2. the package's control fields (name, version, architecture) and its
#      file list: trn, trn-plot, libtrn.a/.so, libtrn_proto.a, the headers
#      (trn/version.h included), the CMake package, trn.pc, the DBC, LICENSE;
#   3. dpkg -x into a scratch root under WORK_DIR (no change to this
#      machine's dpkg database), then the unpacked usr/bin/trn --version must
#      print "trn VERSION", and trn-plot --help must run where python3 has
#      matplotlib and GDAL;
#   4. with CC: main.c of tests/consumer compiled against the unpacked tree
#      through its trn.pc (PKG_CONFIG_PATH) and run.
# Exits non-zero with a one-line reason on the first failure.
set -euo pipefail
[ $# -ge 3 ] || { echo "usage: $0 BUILD_DIR VERSION WORK_DIR [CC [CFLAGS]]" >&2; exit 2; }
BUILD=$(cd "$1" && pwd)
VERSION=$2
WORK=$3
CC_BIN=${4:-}
CFLAGS_IN=${5:-}
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)

fail() { echo "package_deb: $*" >&2; exit 1; }
for t in cpack dpkg-deb; do
  command -v "$t" >/dev/null || fail "$t not found (bash tools/setup.sh core)"
done

rm -rf "$WORK"
mkdir -p "$WORK"
echo "package_deb: cpack -G DEB ($BUILD)"
cpack -G DEB --config "$BUILD/CPackConfig.cmake" -B "$WORK" >"$WORK/cpack.log" 2>&1 ||
  { tail -n 30 "$WORK/cpack.log" >&2; fail "cpack failed (log: $WORK/cpack.log)"; }
shopt -s nullglob
debs=("$WORK"/trn_*.deb)
[ ${#debs[@]} -eq 1 ] || fail "expected one trn_*.deb in $WORK, found ${#debs[@]}"
deb=${debs[0]}
echo "package_deb: $(basename "$deb") ($(stat -c %s "$deb") bytes)"

field() { dpkg-deb -f "$deb" "$1"; }
[ "$(field Package)" = trn ] || fail "Package: $(field Package), want trn"
[ "$(field Version)" = "$VERSION" ] || fail "Version: $(field Version), want $VERSION"
[ "$(field Architecture)" = "$(dpkg --print-architecture)" ] ||
  fail "Architecture: $(field Architecture), want $(dpkg --print-architecture)"
echo "package_deb: Depends: $(field Depends)"

list=$(dpkg-deb -c "$deb" | awk '{print $6}')
wants=(usr/bin/trn usr/bin/trn-plot 'usr/lib/[^ ]*libtrn\.a' 'usr/lib/[^ ]*libtrn\.so'
       'usr/lib/[^ ]*libtrn_proto\.a' usr/include/trn/trn.h usr/include/trn/version.h
       usr/include/trn_port/can_msg.h 'usr/lib/[^ ]*cmake/trn/trnConfig\.cmake'
       'usr/lib/[^ ]*cmake/trn/trnConfigVersion\.cmake' 'usr/lib/[^ ]*pkgconfig/trn\.pc'
       usr/share/trn/trn_mast.dbc usr/share/doc/trn/LICENSE)
for want in "${wants[@]}"; do
  grep -Eq "^\./$want\$" <<<"$list" || fail "the package lacks $want"
done

root="$WORK/root"
dpkg-deb -x "$deb" "$root"
out=$("$root/usr/bin/trn" --version) || fail "unpacked trn --version exited $?"
[ "$out" = "trn $VERSION" ] || fail "unpacked trn --version printed '$out', want 'trn $VERSION'"
echo "package_deb: unpacked usr/bin/trn --version: $out"
if /usr/bin/python3 -c "import matplotlib, numpy; from osgeo import gdal" 2>/dev/null; then
  /usr/bin/python3 "$root/usr/bin/trn-plot" --help >/dev/null || fail "unpacked trn-plot --help failed"
  echo "package_deb: unpacked usr/bin/trn-plot --help ok"
fi

if [ -n "$CC_BIN" ]; then
  pcdir=$(dirname "$(find "$root/usr" -name trn.pc | head -n 1)")
  libdir=$(dirname "$pcdir")
  # shellcheck disable=SC2046,SC2086  # word splitting of the flags is intended
  "$CC_BIN" $CFLAGS_IN -std=c99 -Wall -Wextra -pedantic -Werror "-DEXPECT_VERSION=\"$VERSION\"" \
    -DCONSUMER_PROTO=1 "$HERE/../consumer/main.c" -o "$WORK/consumer" \
    $(PKG_CONFIG_PATH="$pcdir" pkg-config --cflags --libs trn trn-proto) ||
    fail "consumer against the unpacked package's trn.pc did not build"
  LD_LIBRARY_PATH="$libdir" "$WORK/consumer" >/dev/null || fail "consumer against the package failed"
  echo "package_deb: consumer built through the package's trn.pc and ran"
fi
echo "package_deb: ok"
