#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/test.d/45-profile.sh - `trn profile` on the optimised build: its
# command-line test and the instruction counts under callgrind, twice,
# identical (CTest cli_profile and profile_instructions of the host-release
# preset; the host preset's sanitized build cannot run under valgrind).
# Installs the `profile` package group (valgrind).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
bash tools/setup.sh profile
ctest --preset host-release -R '^(cli_profile|profile_instructions)$'
