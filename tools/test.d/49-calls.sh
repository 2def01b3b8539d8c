#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# 49-calls.sh - the calls between the core's source files go one way (issue
# 35; docs/architecture.md, "The localization stack"): the checker's own
# tests (small compiled programs with and without a circle), then
# tools/lint/call_cycles.py on GCC's call-graph files (.ci) of the host build
# (Debug -O0: no call folded away) and of the arm-none-eabi build. Fails,
# naming the circle and one call for each step of it, when src/*.c call each
# other round in a circle.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."

python3 -m unittest discover -s tools/lint -p 'test_call_cycles.py' 2>&1 | tail -n 3
python3 tools/lint/call_cycles.py --build build/host --build build/arm-none-eabi
