#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/can/test_can_decode.sh TRN DATA_DIR - CTest `can_decode_logs`.
#
# Runs `TRN can-decode` on the hand-made logs in DATA_DIR (tests/data/can,
# written by tools/can/make_fixture.py) and compares stdout, stderr and the
# exit status with the reviewed golden files NAME.out / NAME.err.
# Regenerate the golden files only after reading the diff:
#   UPDATE=1 tools/can/test_can_decode.sh build/host/trn tests/data/can
set -uo pipefail
trn=${1:?usage: test_can_decode.sh TRN DATA_DIR}
data=${2:?usage: test_can_decode.sh TRN DATA_DIR}
trn=$(cd "$(dirname "$trn")" && pwd)/$(basename "$trn")
cd "$data" || exit 1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0

# name  log  expected-exit  extra-args
check() {
  local name=$1 log=$2 want=$3
  shift 3
  "$trn" can-decode "$@" "$log" >"$tmp/$name.out" 2>"$tmp/$name.err"
  local rc=$?
  if [ "${UPDATE:-0}" = 1 ]; then
    cp "$tmp/$name.out" "$name.out"
    cp "$tmp/$name.err" "$name.err"
  fi
  if [ "$rc" -ne "$want" ]; then
    echo "FAIL $name: exit status $rc, want $want"
    fail=1
  fi
  for s in out err; do
    if ! diff -u "$name.$s" "$tmp/$name.$s" >"$tmp/diff"; then
      echo "FAIL $name: std$s differs from $name.$s:"
      head -40 "$tmp/diff"
      fail=1
    fi
  done
}

check traffic traffic.log 0
check faults faults.log 0
check faults_strict faults.log 1 --strict
check malformed malformed.log 1
# a capture of the simulator (tools/sim) recorded with candump -l in the VM (kt_loop)
check sim_capture sim_capture.log 0 --strict

# reading standard input gives the same decode
"$trn" can-decode - <traffic.log >"$tmp/stdin.out" 2>&1 || { echo "FAIL stdin: exit status $?"; fail=1; }
diff -q traffic.out "$tmp/stdin.out" >/dev/null || { echo "FAIL stdin: output differs from traffic.out"; fail=1; }
# usage errors
"$trn" can-decode >/dev/null 2>&1; [ $? -eq 2 ] || { echo "FAIL: no LOG must exit 2"; fail=1; }
"$trn" can-decode --bogus x.log >/dev/null 2>&1; [ $? -eq 2 ] || { echo "FAIL: unknown option must exit 2"; fail=1; }
"$trn" can-decode --help >/dev/null 2>&1 || { echo "FAIL: --help must exit 0"; fail=1; }
"$trn" can-decode does-not-exist.log >/dev/null 2>&1; [ $? -eq 1 ] || { echo "FAIL: missing file must exit 1"; fail=1; }

# the fixtures are real candump -l syntax: can-utils' own parser (log2asc,
# tools/setup.sh group `can`) reads every line of them as one event
if command -v log2asc >/dev/null 2>&1; then
  for log in traffic.log faults.log sim_capture.log; do
    n_in=$(grep -c . "$log")
    n_out=$(log2asc -I "$log" vcan0 | tail -n +4 | grep -c .)
    if [ "$n_in" -ne "$n_out" ]; then
      echo "FAIL $log: log2asc made $n_out events of $n_in lines"
      fail=1
    fi
  done
else
  echo "note: log2asc (can-utils) not installed, fixture syntax not cross-checked"
fi

[ $fail -eq 0 ] && echo "can-decode: all logs decode as reviewed"
exit $fail
