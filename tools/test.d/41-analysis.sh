#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# 41-analysis.sh - cppcheck with the MISRA C:2012 addon on the core and
# clang-tidy over src/ and port/; fails on any finding not deviated in
# tools/analysis/deviations.txt (docs/assurance.md, "Static analysis").
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
bash tools/setup.sh assure gpiod2
bash tools/analysis/run.sh
