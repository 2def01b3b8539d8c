#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/test.sh - the project's full check (also what CI runs, via .ci/run).
#
#   1. tools/setup.sh core gdal plot profile real format   (install what is missing)
#   2. host:          configure, build, ctest (Debug, ASan + UBSan)
#   3. aarch64:       configure, build, ctest (cross, tests under qemu-aarch64)
#   4. arm-none-eabi: configure, build (bare-metal Cortex-R5F; prints libtrn.a size)
#   5. host-release:  configure, build (Release -O2; the tools)
#   6. tools/test.d/*.sh, in name order: further checks, one script each
#      (each exits non-zero on failure; run with the repository as cwd)
#
# Stops at the first failure. Works from any directory.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
ROOT=$(pwd)
LOGDIR="$ROOT/build/logs"
mkdir -p "$LOGDIR"

steps_done=()
current=""
tests_passed=0
tests_failed=0

summary() {
  local rc=$?
  echo
  echo "==================== summary ===================="
  local s
  for s in "${steps_done[@]}"; do
    echo "  ok      $s"
  done
  if [ "$rc" -ne 0 ] && [ -n "$current" ]; then
    echo "  FAILED  $current (exit $rc)"
  fi
  echo "================================================="
  if [ "$rc" -ne 0 ]; then
    echo "tools/test.sh: FAILED"
  else
    echo "tools/test.sh: all steps passed"
    echo "total: ${tests_passed} passed, ${tests_failed} failed"
  fi
}
trap summary EXIT

# step NAME CMD...: run one step, timed; the EXIT trap reports a failure.
step() {
  current=$1
  shift
  echo
  echo "=== $current: $*"
  local t0=$SECONDS
  "$@"
  steps_done+=("$current ($((SECONDS - t0)) s)")
  current=""
}

# ctest_step PRESET: run the preset's tests, keep the log, count the results
# from ctest's own "N% tests passed, F tests failed out of T" line.
ctest_step() {
  local preset=$1 log="$LOGDIR/ctest-$1.log" line total failed
  ctest --preset "$preset" 2>&1 | tee "$log"
  line=$(grep -E 'tests passed, [0-9]+ tests? failed out of [0-9]+' "$log" | tail -n 1)
  failed=$(sed -E 's/.* ([0-9]+) tests? failed out of ([0-9]+).*/\1/' <<<"$line")
  total=$(sed -E 's/.* failed out of ([0-9]+).*/\1/' <<<"$line")
  tests_passed=$((tests_passed + total - failed))
  tests_failed=$((tests_failed + failed))
}

step "setup" bash tools/setup.sh core gdal plot profile real format

for preset in host aarch64; do
  step "$preset configure" cmake --preset "$preset"
  step "$preset build" cmake --build --preset "$preset"
  step "$preset test" ctest_step "$preset"
done

step "arm-none-eabi configure" cmake --preset arm-none-eabi
step "arm-none-eabi build (size)" cmake --build --preset arm-none-eabi

step "host-release configure" cmake --preset host-release
step "host-release build (tools)" cmake --build --preset host-release

shopt -s nullglob
for stage in tools/test.d/*.sh; do
  step "$(basename "$stage" .sh)" bash "$stage"
done
