#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# 42-fuzz.sh - every libFuzzer harness in tests/fuzz/ (clang, ASan + UBSan)
# for a bounded number of executions from its seed corpus; fails on any crash,
# sanitizer report, leak or timeout (docs/assurance.md, "Fuzzing").
# TRN_FUZZ_RUNS overrides the count (default 20000 per harness: 50 s with a
# fresh build for the ten harnesses, measured 2026-11-25).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
bash tools/setup.sh assure
bash tests/fuzz/run.sh "${TRN_FUZZ_RUNS:-20000}"
