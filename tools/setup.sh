#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/setup.sh [group...] - install the Debian packages the build needs.
#
# Idempotent and fast when everything is present: each package is checked with
# dpkg-query first, and apt-get runs (update, then install) only for what is
# missing. With no argument it installs the `core` group.
#
#   tools/setup.sh              # = tools/setup.sh core
#   tools/setup.sh core bench   # several groups
#   tools/setup.sh --list       # show the groups
#
# To add a group: add one line to PKG_GROUPS below (and its name to
# GROUP_ORDER). A package written `name:arch` is a Debian multiarch package of
# a foreign architecture; the architecture is enabled automatically.
set -euo pipefail

declare -A PKG_GROUPS=(
  # Build, host tests, aarch64 cross + qemu-user, bare-metal Cortex-R5F;
  # pkg-config, dpkg-dev and file for the install tests (the pkg-config
  # consumer; CPack's DEB generator reads Depends with dpkg-shlibdeps, which
  # needs file).
  [core]="cmake ninja-build make gcc libc6-dev pkg-config libcmocka-dev
          gcc-aarch64-linux-gnu binutils-aarch64-linux-gnu libc6-dev-arm64-cross
          libcmocka-dev:arm64 qemu-user
          libgpiod-dev libgpiod-dev:arm64
          gcc-arm-none-eabi binutils-arm-none-eabi libnewlib-arm-none-eabi
          dpkg-dev file"
  # libgpiod 2 for the Linux port's tests (tools/gpiod2/build-libgpiod2.sh:
  # the C sources from the PyPI sdist of its bindings, fetched with the pip
  # of the project venv .venv; used by tools/test.d/41-analysis.sh and 44-gpiod2.sh).
  [gpiod2]="python3 python3-venv gcc binutils"
  # Benchmarks: the optional OpenCV reference in trn_bench (C++).
  [bench]="g++ libopencv-dev"
  # The `trn` command line: GDAL's C API (any raster DEM in, GeoTIFF out),
  # gdal_translate / gdalinfo and the Python bindings (its tests, the plots).
  [gdal]="libgdal-dev gdal-bin python3-gdal"
  # Figures (tools/plot/trn_plot.py).
  [plot]="python3 python3-matplotlib python3-numpy python3-gdal"
  # Kernel integration tests (tests/integration/): build a small Linux from
  # Debian's source, an initramfs of static programs, boot it under QEMU.
  [vm]="linux-source-6.1 xz-utils make gcc bc bison flex libelf-dev cpio gzip
        busybox-static qemu-system-x86 iproute2 can-utils libgpiod-dev gpiod"
  # CAN bus tools: the cantools cross-check of the DBC runs in the project
  # venv (.venv, cantools from PyPI); can-utils to record and replay logs.
  [can]="python3 python3-venv can-utils"
  # The documentation (tools/test.d/47-docs.sh): Doxygen for the API reference
  # (CMake target `docs`); python3 for the words, link and command-line
  # reference checks (tools/docs/).
  [docs]="doxygen python3 git"
  # The formatting rule (.clang-format, CTest `format`): clang-format 14.
  [format]="clang-format"
  # Assurance stages (docs/assurance.md): static analysis (cppcheck + its
  # MISRA addon, clang-tidy), libFuzzer (clang + compiler-rt), coverage (gcovr),
  # the stack tool (python3).
  [assure]="python3 cppcheck clang-tidy clang libclang-rt-14-dev gcovr"
  # `trn profile --instructions`: callgrind and its client-request header
  # (valgrind/callgrind.h), and the CTest profile_instructions.
  [profile]="valgrind"
  # The Python package (python/, tools/test.d/46-python.sh): the project venv
  # (.venv, --system-site-packages) from Debian's python3 with its numpy, GDAL
  # bindings, pytest and matplotlib (the README's planner example); GDAL's C
  # API and CMake for the package's build by scikit-build-core (from PyPI,
  # pip-installed into .venv: Debian 12 has no package of it); Dask and
  # dask.distributed for the tiled field over large DTMs (python/trn/dask_field.py);
  # tqdm and xarray for field(progress=True) and Map.from_xarray (the clean-venv
  # stage, tools/test.d/47-python-venv.sh, takes its packages from PyPI instead).
  [python]="python3 python3-venv python3-numpy python3-gdal python3-pytest python3-matplotlib
            python3-dask python3-distributed python3-tqdm python3-xarray
            libgdal-dev gdal-bin cmake ninja-build gcc"
  # Real-terrain benchmark (tools/real/): the OpenCV peer (cv2.matchTemplate),
  # numpy, GDAL (gdalwarp to UTM, GeoTIFF I/O) and the figures; python3-venv
  # for the project venv (.venv) used only by DEMs shipped on PyPI alone;
  # the DEM recipes of tools/real/dems.py: python-matplotlib-data (jacksboro).
  [real]="python3 python3-venv python3-opencv python3-numpy python3-gdal gdal-bin
          python3-matplotlib python-matplotlib-data"
)
GROUP_ORDER=(core gpiod2 bench gdal can plot vm assure format docs profile real python)

usage() {
  echo "usage: $0 [group...]   (default: core)"
  echo "groups:"
  local g
  for g in "${GROUP_ORDER[@]}"; do
    echo "  $g: $(echo ${PKG_GROUPS[$g]})"
  done
}

log() { echo "setup: $*"; }

# Root runs apt directly; anyone else goes through sudo.
SUDO=()
if [ "$(id -u)" -ne 0 ]; then
  SUDO=(sudo)
fi

NATIVE_ARCH=$(dpkg --print-architecture)

# is_installed PKG: true if PKG (native or arch:all; or exactly PKG:ARCH when
# qualified) is installed.
is_installed() {
  local pkg=$1 status
  status=$(dpkg-query -W -f='${db:Status-Status} ${Architecture}\n' "$pkg" 2>/dev/null) || return 1
  if [[ $pkg == *:* ]]; then
    grep -q '^installed ' <<<"$status"
  else
    grep -Eq "^installed (${NATIVE_ARCH}|all)\$" <<<"$status"
  fi
}

# --- which packages are wanted --------------------------------------------
groups=("$@")
if [ ${#groups[@]} -eq 0 ]; then
  groups=(core)
fi
wanted=()
for g in "${groups[@]}"; do
  case $g in
    -h|--help|--list) usage; exit 0 ;;
  esac
  if [ -z "${PKG_GROUPS[$g]+set}" ]; then
    echo "setup: unknown group '$g'" >&2
    usage >&2
    exit 2
  fi
  # shellcheck disable=SC2206  # word splitting of the package list is intended
  wanted+=(${PKG_GROUPS[$g]})
done

missing=()
for p in "${wanted[@]}"; do
  if ! is_installed "$p"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  log "all packages of [${groups[*]}] present"
  exit 0
fi
log "missing: ${missing[*]}"

# --- foreign architectures (multiarch) --------------------------------------
for p in "${missing[@]}"; do
  if [[ $p == *:* ]]; then
    arch=${p##*:}
    if [ "$arch" != "$NATIVE_ARCH" ] && ! dpkg --print-foreign-architectures | grep -qx "$arch"; then
      log "dpkg --add-architecture $arch"
      "${SUDO[@]}" dpkg --add-architecture "$arch"
    fi
  fi
done

# --- install ------------------------------------------------------------------
export DEBIAN_FRONTEND=noninteractive
retry() {
  local n
  for n in 1 2 3; do
    if "$@"; then return 0; fi
    log "attempt $n failed: $*"
    sleep $((n * 5))
  done
  return 1
}
log "apt-get update"
retry "${SUDO[@]}" apt-get update -q
log "apt-get install ${missing[*]}"
retry "${SUDO[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"

# Check the result, so a silently skipped package fails here, not in the build.
still=()
for p in "${missing[@]}"; do
  is_installed "$p" || still+=("$p")
done
if [ ${#still[@]} -ne 0 ]; then
  echo "setup: still not installed: ${still[*]}" >&2
  exit 1
fi
log "installed: ${missing[*]}"
