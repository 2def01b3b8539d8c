#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/can/check_dbc.sh VECTORS_PROGRAM [DBC] - the cantools cross-check.
#
# Makes sure the project venv (.venv, gitignored) exists and has cantools
# (PyPI; Debian has no package), runs VECTORS_PROGRAM (trn_can_vectors) and
# hands its JSON to check_dbc.py with the DBC (default port/proto/trn_mast.dbc).
# Registered as the CTest `can_dbc_cantools` (label check, host presets).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
vectors_prog=${1:?usage: check_dbc.sh VECTORS_PROGRAM [DBC]}
dbc=${2:-$root/port/proto/trn_mast.dbc}
venv=$root/.venv

if ! "$venv/bin/python" -c 'import cantools' 2>/dev/null; then
  if [ ! -x "$venv/bin/python" ]; then
    # the one project venv, as every tool makes it: Debian's python3 with its
    # site packages (numpy, GDAL), so the Python stage does not remake it.
    # A fresh machine may lack python3's venv module (Debian's python3-venv):
    # tools/setup.sh group `can` installs it
    if ! /usr/bin/python3 -m venv --system-site-packages "$venv" >/dev/null 2>&1; then
      rm -rf "$venv"
      bash "$root/tools/setup.sh" can
      /usr/bin/python3 -m venv --system-site-packages "$venv"
    fi
  fi
  "$venv/bin/python" -m pip install --quiet cantools
fi

tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
"$vectors_prog" > "$tmp"
"$venv/bin/python" "$here/check_dbc.py" "$dbc" "$tmp"
