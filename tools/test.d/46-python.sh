#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/test.d/46-python.sh - the Python package `trn` (python/, issue 13
# item 3): installed with pip into the project venv and tested with pytest.
#
# 1. tools/setup.sh python (Debian: python3-venv, numpy, GDAL's bindings,
#    pytest, matplotlib, libgdal-dev, cmake, ninja);
# 2. the project venv .venv (gitignored), made from Debian's /usr/bin/python3
#    with --system-site-packages, so numpy, osgeo, xarray, tqdm and dask are
#    Debian's (the package needs only numpy; osgeo is for the Dask tests'
#    GeoTIFF layout checks); made again when it cannot import them (another
#    tool may have made it without). The clean venv of a pip user is
#    tools/test.d/47-python-venv.sh;
# 3. scikit-build-core from PyPI into .venv when missing (the one package
#    Debian 12 lacks), then `pip install --no-build-isolation --force-reinstall
#    --no-deps ./python`: scikit-build-core builds libtrn_run.so through the
#    top-level CMakeLists.txt (TRN_PYTHON=ON) in build/python/;
# 4. the installed package (imported from outside the source tree) checked,
#    and python/tests run with pytest against build/host-release/trn (the CLI
#    equality tests; the host-release preset is built by then).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
ROOT=$(pwd)
VENV=$ROOT/.venv
PY=$VENV/bin/python
SKBUILD="scikit-build-core==1.1.2"
fail() { echo "46-python: $*" >&2; exit 1; }
# the wheel's CMake build: two jobs at most (cmake --build reads this)
export CMAKE_BUILD_PARALLEL_LEVEL=${CMAKE_BUILD_PARALLEL_LEVEL:-2}

bash tools/setup.sh python
if ! "$PY" -c 'import numpy, pytest; from osgeo import gdal' 2>/dev/null; then
  echo "46-python: making the project venv $VENV (--system-site-packages, /usr/bin/python3)"
  rm -rf "$VENV"
  /usr/bin/python3 -m venv --system-site-packages "$VENV"
fi
if ! "$PY" -c 'import scikit_build_core' 2>/dev/null; then
  "$PY" -m pip install -q "$SKBUILD"
fi
"$PY" -m pip install -q --no-build-isolation --force-reinstall --no-deps ./python ||
  fail "pip install ./python failed"
where=$(cd / && "$PY" -c 'import trn; print(trn.__file__)')
case $where in
  "$VENV"/*) ;;
  *) fail "import trn found $where, not the package installed in $VENV" ;;
esac
[ -x build/host-release/trn ] || fail "build/host-release/trn is missing (cmake --build --preset host-release)"
mkdir -p build/python-tests
cd build/python-tests
TRN_CLI=$ROOT/build/host-release/trn "$PY" -m pytest -q -p no:cacheprovider "$ROOT/python/tests"
