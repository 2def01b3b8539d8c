#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/sim/record_capture.sh [OUT] - re-record tests/data/can/sim_capture.log:
# runs kt_loop in the VM (its first run records the bus with `candump -l`
# from just before CAPTURE_CMD to the end of the capture and prints the log
# as KT-CANLOG lines) and keeps those lines. Then review and refresh the
# golden decode: UPDATE=1 tools/can/test_can_decode.sh build/host-release/trn tests/data/can
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
out=${1:-tests/data/can/sim_capture.log}
b=build/host-release/tests/integration
cmake --build --preset host-release --target kt_exit kt_loop >/dev/null
bash tests/integration/run-vm.sh --exit-program "$b/kt_exit" "$b/kt_loop" |
  grep -a '^KT-CANLOG ' | sed 's/^KT-CANLOG //' | tr -d '\r' >"$out"
echo "record_capture: $(wc -l <"$out") frames in $out"
