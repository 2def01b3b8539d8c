#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# 40-stack.sh - worst-case stack of every public function, from the build
# (docs/assurance.md, "Stack"): the tool's own tests (hand count, cycle,
# indirect call, unknown callee, limit), then the arm-none-eabi and
# host-release graphs against TRN_STACK_LIMIT_BYTES, then the per-module size
# of libtrn.a on arm-none-eabi. Needs both presets built with TRN_STACK_USAGE
# (the default with GCC).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
bash tools/setup.sh assure

python3 -m unittest discover -s tools/stack -p 'test_*.py' 2>&1 | tail -n 3

for b in build/arm-none-eabi build/host-release; do
  echo "--- $b"
  python3 tools/stack/trn_stack.py --build "$b"
done

echo "--- arm-none-eabi-size per module (bytes)"
# Every static library of the bare-metal build (libtrn.a, and libtrn_proto.a
# once port/proto exists), found rather than named.
while IFS= read -r lib; do
  echo "$lib:"
  arm-none-eabi-size -t "$lib" | sed "s#(ex .*/#(ex #"
done < <(find build/arm-none-eabi -name '*.a' -not -path '*/CMakeFiles/*' | sort)
