#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/test.d/44-port-off.sh - the build without the Linux port (issue 15,
# "builds beyond Debian 12"): a machine without a libgpiod this port supports
# must still build the core, the protocol library and the `trn` command line.
#
# Configures build/port-off (Release, tests and tools) with libgpiod hidden
# (TRN_GPIOD_INCLUDE_DIR / TRN_GPIOD_LIBRARY pointed at nothing) and no
# TRN_PORT_LINUX given, then checks that the option defaulted to OFF, that
# libtrn.a, libtrn_proto.a and trn were built and libtrn_port_linux.a was not,
# that trn does not link libgpiod and prints its version, and runs the unit
# tests and the install / package tests of that build (CTest labels unit and
# check). Then an explicit -DTRN_PORT_LINUX=ON against the hidden libgpiod
# must fail at configure time with a message naming the option.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
B=build/port-off
hide=(-DTRN_GPIOD_INCLUDE_DIR=/nonexistent -DTRN_GPIOD_LIBRARY=/nonexistent/libgpiod.so)
fail() { echo "44-port-off: $*" >&2; exit 1; }

rm -rf "$B"
cmake -S . -B "$B" -G Ninja -DCMAKE_BUILD_TYPE=Release "-DCMAKE_C_FLAGS_RELEASE=-O2 -DNDEBUG" \
  -DTRN_BUILD_TESTS=ON -DTRN_BUILD_TOOLS=ON "${hide[@]}" >"$B.configure.log" 2>&1 ||
  { tail -n 20 "$B.configure.log" >&2; fail "configure without libgpiod failed"; }
grep -q '^TRN_PORT_LINUX:BOOL=OFF$' "$B/CMakeCache.txt" || fail "TRN_PORT_LINUX did not default to OFF"
grep -q 'port/linux: off' "$B.configure.log" || fail "configure did not report the port off"
cmake --build "$B" -j2 >"$B.build.log" 2>&1 || { tail -n 30 "$B.build.log" >&2; fail "build failed"; }
for f in libtrn.a libtrn_proto.a trn; do
  [ -e "$B/$f" ] || fail "$f was not built"
done
if find "$B" -name 'libtrn_port_linux*.a' | grep -q .; then
  fail "libtrn_port_linux was built with TRN_PORT_LINUX=OFF"
fi
if ldd "$B/trn" | grep -q gpiod; then
  fail "trn links libgpiod"
fi
[ "$("$B/trn" --version)" = "trn $(sed -n 's/^CMAKE_PROJECT_VERSION:STATIC=//p' "$B/CMakeCache.txt")" ] ||
  fail "trn --version: $("$B/trn" --version)"
ctest --test-dir "$B" -L 'unit|check' -j2 --output-on-failure

# ON without a usable libgpiod: a configure error that names the way out.
rm -rf "$B-on"
if cmake -S . -B "$B-on" -G Ninja -DTRN_BUILD_TESTS=OFF -DTRN_BUILD_TOOLS=OFF -DTRN_PORT_LINUX=ON \
     "${hide[@]}" >"$B-on.configure.log" 2>&1; then
  fail "-DTRN_PORT_LINUX=ON configured without libgpiod"
fi
grep -q 'TRN_PORT_LINUX=OFF' "$B-on.configure.log" || fail "the ON-without-libgpiod error does not name the option"
rm -rf "$B-on"
echo "44-port-off: core, trn_proto and trn build and pass their tests without the Linux port"
