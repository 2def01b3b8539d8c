#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# 43-coverage.sh - line and branch coverage of src/ and port/ by the unit
# tests (coverage preset: gcc --coverage -O0), reported per file with gcovr,
# floors enforced per directory (docs/assurance.md, "Coverage"):
#
#   src/          lines >= 95 %, branches >= 95 %   (the core)
#   port/proto/   lines and branches 100 %          (protocol, reassembly)
#   port/         lines >= 80 %, branches >= 76 %   (OS code; rest of port/)
#
# The OS code's floor is what the host can reach: argument checks, the
# framing, error-frame and timeout logic through a Unix socket pair, failing
# system calls on pipes and closed descriptors, send/recv and libgpiod
# failures injected with ld --wrap (tests/test_port_linux*.c).
# Opening a CAN or can-isotp socket and a real GPIO chip need vcan,
# can-isotp or gpio-sim: the kernel tests run that in a VM
# (stage 50-kernel, tests/integration), whose static programs gcov does not
# count (docs/assurance.md, "Coverage").
#
# A floor applies to the directory's total, so new code merged into a
# directory must arrive with its tests to keep the total there. A directory
# without sources is skipped.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
bash tools/setup.sh assure

cmake --preset coverage >/dev/null
cmake --build --preset coverage
# Stale counters of a previous run would inflate the numbers.
find build/coverage -name '*.gcda' -delete
ctest --preset coverage >build/coverage/ctest.log 2>&1 || { tail -n 30 build/coverage/ctest.log; exit 1; }
grep -E 'tests passed' build/coverage/ctest.log

GCOVR=(gcovr -r . --object-directory build/coverage --exclude-unreachable-branches
       --exclude-throw-branches)
# Per file: lines (with the uncovered line numbers), then branches (with the
# lines holding an untaken branch). gcov's complaints about CMake's compiler-id
# objects go to a log.
"${GCOVR[@]}" --filter 'src/' --filter 'port/' 2>build/coverage/gcovr.log
"${GCOVR[@]}" --filter 'src/' --filter 'port/' -b 2>>build/coverage/gcovr.log

fail=0
# floor DIR_REGEX NAME LINES% BRANCHES%
floor() {
  local filt=$1 name=$2 minl=$3 minb=$4 js l b
  js=$("${GCOVR[@]}" --filter "$filt" --json-summary 2>/dev/null)
  if [ "$(python3 -c 'import json,sys; print(len(json.load(sys.stdin)["files"]))' <<<"$js")" = 0 ]; then
    echo "coverage: $name: no sources, skipped"
    return
  fi
  read -r l b < <(python3 -c 'import json,sys; d=json.load(sys.stdin); print(d["line_percent"], d["branch_percent"])' <<<"$js")
  if python3 -c "import sys; sys.exit(0 if $l >= $minl and $b >= $minb else 1)"; then
    echo "coverage: $name: lines $l % (floor $minl), branches $b % (floor $minb): ok"
  else
    echo "coverage: $name: lines $l % (floor $minl), branches $b % (floor $minb): BELOW FLOOR" >&2
    fail=1
  fi
}
floor 'src/' 'core src/' 95 95
floor 'port/proto/' 'port/proto/' 100 100
# 80, not 81: a few of its lines run or not by timing (remaining_ms's
# expired deadline in linux_can.c); measured 80.8-81.1 % on the same code
# (2026-12-02), so a floor of 81 failed one run in three.
floor 'port/(?!proto/)' 'port/ (OS code)' 80 76
exit $fail
