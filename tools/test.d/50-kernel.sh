#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/test.d/50-kernel.sh - the kernel tests: the Linux port against a real
# kernel (vcan, can-isotp, gpio-sim) in a small VM under QEMU.
#
# Installs the `vm` package group, builds the VM kernel once (cached outside
# the tree by tests/integration/build-kernel.sh, ~3-5 min on 2 cores; later
# runs reuse it), then runs the CTest label `kernel` of the host-release
# preset, where the static test programs are built (docs/architecture.md,
# "Kernel tests in a VM").
set -euo pipefail

bash tools/setup.sh vm
t0=$SECONDS
kernel=$(bash tests/integration/build-kernel.sh)
echo "50-kernel: kernel $kernel ($((SECONDS - t0)) s)"
t1=$SECONDS
ctest --preset host-release -L kernel
echo "50-kernel: VM tests $((SECONDS - t1)) s"
