#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# 41-analysis.sh - cppcheck with the MISRA C:2012 addon on the core,
# cppcheck without it on port/, tools/, tests/ and python/, clang-tidy over
# all of them (every C file of the tree); fails on any finding not deviated
# in tools/analysis/deviations.txt (docs/assurance.md, "Static analysis"). gdal: the headers dem_io.c includes.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
bash tools/setup.sh assure gpiod2 gdal
bash tools/analysis/run.sh
