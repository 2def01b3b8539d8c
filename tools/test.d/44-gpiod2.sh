#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/test.d/44-gpiod2.sh - the Linux port against libgpiod 2 (issue 15,
# "builds beyond Debian 12"; Debian 13 and Ubuntu 24.04 ship libgpiod 2).
#
# Builds a static libgpiod 2 from the PyPI sdist of its Python bindings
# (tools/gpiod2/build-libgpiod2.sh), configures build/gpiod2 (Release, unit
# and kernel tests, no tools) with it as the port's libgpiod, checks that
# CMake picked API 2 (port/linux/linux_gpio_v2.c), builds the port and its
# tests with the flight warning set, and runs the port's host unit tests and
# the kernel tests kernel_gpio (power, trigger pulse, deployed edge and
# timeout, active-low lines, lines requested once, bad chip and offsets, on a
# gpio-sim chip in the QEMU VM of tests/integration) and kernel_sim (the
# rover's link against the simulator: power and trigger through libgpiod 2).
# kernel_loop (the whole loop, 38 s more) also passes with it but is left to
# 50-kernel.sh's libgpiod 1.6 run:
#   cmake --build build/gpiod2 --target kt_loop && ctest --test-dir build/gpiod2 -R kernel_loop
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
fail() { echo "44-gpiod2: $*" >&2; exit 1; }

bash tools/setup.sh core vm gpiod2
G=$(bash tools/gpiod2/build-libgpiod2.sh)
B=build/gpiod2
rm -rf "$B"
cmake -S . -B "$B" -G Ninja -DCMAKE_BUILD_TYPE=Release "-DCMAKE_C_FLAGS_RELEASE=-O2 -DNDEBUG" \
  -DTRN_BUILD_TOOLS=OFF -DTRN_BUILD_TESTS=ON -DTRN_BUILD_KERNEL_TESTS=ON \
  "-DTRN_GPIOD_INCLUDE_DIR=$G/include" "-DTRN_GPIOD_LIBRARY=$G/lib/libgpiod.a" \
  "-DTRN_GPIOD_STATIC_LIBRARY=$G/lib/libgpiod.a" >"$B.configure.log" 2>&1 ||
  { tail -n 20 "$B.configure.log" >&2; fail "configure with libgpiod 2 failed"; }
grep -q 'port/linux: on, libgpiod API 2' "$B.configure.log" || fail "CMake did not select libgpiod API 2"
cmake --build "$B" -j2 --target trn_port_linux test_port_linux test_port_linux_errors kt_exit kt_gpio kt_sim \
  >"$B.build.log" 2>&1 || { tail -n 30 "$B.build.log" >&2; fail "build failed"; }
nm "$B"/port/linux/libtrn_port_linux.a | grep -q ' U gpiod_line_request_set_value' ||
  fail "libtrn_port_linux.a does not use libgpiod 2's request API"
ctest --test-dir "$B" -R '^(test_port_linux|test_port_linux_errors|kernel_gpio|kernel_sim)$' --output-on-failure
echo "44-gpiod2: the Linux port builds and passes its GPIO tests with libgpiod $(cat "$G/libgpiod-version")"
