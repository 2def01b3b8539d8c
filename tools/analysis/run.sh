#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/analysis/run.sh - static analysis of the C code (docs/assurance.md,
# "Static analysis"); exits non-zero on any finding.
#
#   1. cppcheck (Debian) with the MISRA C:2012 addon over the core: src/,
#      include/trn/ and port/proto/ (pure C99 flight code).
#   2. cppcheck without MISRA over the rest of port/ (OS code).
#   3. clang-tidy (Debian, LLVM 14) over src/ and port/ with the checks in
#      CHECKS below.
#   3b. host code, every other C file of the tree: the host tools (tools/:
#      trn, support, bench, sim, can, stack's test fixture), the tests
#      (tests/**: unit, support, cli, fuzz, integration, consumer, abi, doc)
#      and the Python extension (python/trn_py.c): cppcheck without MISRA
#      (host programs, not flight code) and clang-tidy with the same CHECKS
#      less the deviations scoped to a path under tools/, tests/ or python/
#      (deviations.txt), one process per file.
#   4. no assert()/NDEBUG in the core: argument checks are plain code,
#      compiled in every build type.
#   5. tools/analysis/retval_audit.py: every status a public header documents
#      for a function is asserted by some test.
# Files are found with globs, so new modules are checked without edits here.
# Every suppression comes from tools/analysis/deviations.txt (one reason per
# line); nothing is suppressed inline.
#
# The MISRA addon reports rule numbers only ("misra violation (use
# --rule-texts=<file> ...)"): the rule texts are MISRA's copyrighted document,
# which we do not have; the rule number is enough to look the rule up.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
ROOT=$(pwd)
OUT=build/analysis
# cppcheck's build directories start empty: a cached dump of a header whose
# lines have since moved makes the MISRA addon's whole-program rules (8.5)
# see every declaration after the change twice (measured 2026-12-05)
rm -rf "$OUT"/cppcheck-*
mkdir -p "$OUT/cppcheck-core" "$OUT/cppcheck-port" "$OUT/include/trn"

DEV=tools/analysis/deviations.txt
# clang-tidy: bug finders and CERT C in full; from readability only the checks
# that catch mistakes rather than taste.
CHECKS='-*,bugprone-*,cert-*,clang-analyzer-*'
CHECKS+=',readability-misleading-indentation,readability-braces-around-statements'
CHECKS+=',readability-non-const-parameter,readability-redundant-declaration'
CHECKS+=',readability-duplicate-include,readability-inconsistent-declaration-parameter-name'
CHECKS+=',readability-named-parameter,readability-implicit-bool-conversion'
# The feature-test macros the tools define before their includes are not
# reserved identifiers taken by the program (bugprone-reserved-identifier and
# its CERT aliases).
feature='_POSIX_C_SOURCE;_DEFAULT_SOURCE;_GNU_SOURCE'
TIDY_CONFIG="{CheckOptions: [{key: bugprone-reserved-identifier.AllowedIdentifiers, value: '$feature'},"
TIDY_CONFIG+=" {key: cert-dcl37-c.AllowedIdentifiers, value: '$feature'},"
TIDY_CONFIG+=" {key: cert-dcl51-cpp.AllowedIdentifiers, value: '$feature'}]}"
# clang-tidy deviations scoped to a path under tools/, tests/ or python/:
# "path check" pairs, applied to the host files under that path only.
HOST_OFF=()

# --- suppressions from the one deviations file ------------------------------
supp="$OUT/cppcheck-suppressions.txt"
: >"$supp"
while read -r tool id scope _reason; do
  case $tool in
    cppcheck)
      if [ "$scope" = "*" ]; then echo "$id" >>"$supp"; else echo "$id:$scope" >>"$supp"; fi ;;
    clang-tidy)
      if [ "$scope" = "*" ]; then
        CHECKS+=",-$id"
      elif [[ $scope == tools/* || $scope == tests/* || $scope == python/* ]] && [ -e "$scope" ]; then
        HOST_OFF+=("$scope $id")
      else
        echo "analysis: a clang-tidy deviation has scope * or an existing path under tools/, tests/ or python/: $id $scope" >&2
        exit 2
      fi ;;
    retval) ;; # read by retval_audit.py
    ''|'#'*) ;;
    *) echo "analysis: $DEV: unknown tool '$tool'" >&2; exit 2 ;;
  esac
done < <(grep -v '^[[:space:]]*#' "$DEV" | grep -v '^[[:space:]]*$')

shopt -s nullglob globstar
core=(src/**/*.c port/proto/**/*.c)
port_os=()
# port/linux/linux_gpio_v2.c is the libgpiod 2 variant of linux_gpio.c: it
# needs libgpiod 2's gpiod.h (Debian 12 has 1.6), so it is checked on its own
# below against the one tools/gpiod2/build-libgpiod2.sh builds.
gpio_v2=port/linux/linux_gpio_v2.c
for f in port/**/*.c; do
  case $f in port/proto/*|"$gpio_v2") ;; *) port_os+=("$f") ;; esac
done
incs=(-I include -I src)
[ -d port/include ] && incs+=(-I port/include)

fail=0
TEMPLATE='{file}:{line}: {severity}: {id}: {message}'
common=(--std=c99 --enable=warning,style,performance,portability --inline-suppr
        --suppressions-list="$supp" --error-exitcode=1 -q --template="$TEMPLATE"
        -D__STDC_VERSION__=199901L "${incs[@]}")

echo "--- cppcheck $(cppcheck --version | awk '{print $2}') + MISRA C:2012 addon: ${#core[@]} core files"
if ! cppcheck "${common[@]}" --addon=misra --cppcheck-build-dir="$OUT/cppcheck-core" "${core[@]}"; then
  fail=1
fi
if [ ${#port_os[@]} -gt 0 ]; then
  echo "--- cppcheck (no MISRA): ${#port_os[@]} port files"
  cppcheck "${common[@]}" --cppcheck-build-dir="$OUT/cppcheck-port" "${port_os[@]}" || fail=1
fi

all=("${core[@]}" "${port_os[@]}")
echo "--- clang-tidy $(clang-tidy --version | sed -n 's/.*version \([0-9.]*\).*/\1/p' | head -1): ${#all[@]} files"
echo "    checks: $CHECKS"
log="$OUT/clang-tidy.log"
# -D_DEFAULT_SOURCE for the OS code of port/linux (POSIX + Linux headers).
if ! clang-tidy --quiet --checks="$CHECKS" --warnings-as-errors='*' "${all[@]}" \
     -- -std=c99 "${incs[@]}" -D_DEFAULT_SOURCE >"$log" 2>&1; then
  grep -E 'warning:|error:' "$log" || cat "$log"
  fail=1
fi

if [ -f "$gpio_v2" ]; then
  g2=$(bash tools/gpiod2/build-libgpiod2.sh)
  echo "--- cppcheck (no MISRA) and clang-tidy: $gpio_v2 against libgpiod $(cat "$g2/libgpiod-version")"
  cppcheck "${common[@]}" -I "$g2/include" -DTRN_GPIOD_API=2 --cppcheck-build-dir="$OUT/cppcheck-port" \
    "$gpio_v2" || fail=1
  if ! clang-tidy --quiet --checks="$CHECKS" --warnings-as-errors='*' "$gpio_v2" \
       -- -std=c99 "${incs[@]}" -isystem "$g2/include" -DTRN_GPIOD_API=2 -D_DEFAULT_SOURCE \
       >"$OUT/clang-tidy-gpio-v2.log" 2>&1; then
    grep -E 'warning:|error:' "$OUT/clang-tidy-gpio-v2.log" || cat "$OUT/clang-tidy-gpio-v2.log"
    fail=1
  fi
fi

# --- host code: the tools, the tests, the Python extension -------------------
# trn/version.h is generated by CMake from cmake/version.h.in; the same here,
# so the stage needs no build tree.
version=$(sed -n '/^project(trn/,/)/s/.*VERSION \([0-9][0-9.]*\).*/\1/p' CMakeLists.txt | head -1)
IFS=. read -r v_major v_minor v_patch <<<"$version"
sed -e "s/@PROJECT_VERSION_MAJOR@/$v_major/" -e "s/@PROJECT_VERSION_MINOR@/$v_minor/" \
    -e "s/@PROJECT_VERSION_PATCH@/$v_patch/" -e "s/@PROJECT_VERSION@/$version/" \
    cmake/version.h.in >"$OUT/include/trn/version.h.new"
cmp -s "$OUT/include/trn/version.h.new" "$OUT/include/trn/version.h" ||
  mv "$OUT/include/trn/version.h.new" "$OUT/include/trn/version.h"
rm -f "$OUT/include/trn/version.h.new"
gdal_inc=()
for fl in $(gdal-config --cflags 2>/dev/null); do
  case $fl in -I*) gdal_inc+=(-isystem "${fl#-I}") ;; esac
done

# host_pass NAME FILES... (after HOST_INCS is set): cppcheck without MISRA
# (host programs and tests, not flight code) and clang-tidy with CHECKS less
# the deviations scoped to a path the file is under, one process per file,
# two at a time.
host_pass() {
  local name=$1
  shift
  local files=("$@")
  [ ${#files[@]} -gt 0 ] || return 0
  mkdir -p "$OUT/cppcheck-$name"
  echo "--- cppcheck (no MISRA: host code): ${#files[@]} $name files"
  cppcheck "${common[@]}" "${HOST_INCS[@]}" -j 2 --cppcheck-build-dir="$OUT/cppcheck-$name" "${files[@]}" || fail=1

  echo "--- clang-tidy: ${#files[@]} $name files (GDAL: $(gdal-config --version 2>/dev/null || echo none))"
  rm -rf "$OUT/clang-tidy-$name"
  mkdir -p "$OUT/clang-tidy-$name"
  local running=0 f checks pair flog
  for f in "${files[@]}"; do
    checks=$CHECKS
    for pair in "${HOST_OFF[@]}"; do
      case $f in "${pair%% *}"*) checks+=",-${pair#* }" ;; esac
    done
    flog="$OUT/clang-tidy-$name/$(echo "$f" | tr / _).log"
    ( clang-tidy --quiet --checks="$checks" --config="$TIDY_CONFIG" --warnings-as-errors='*' "$f" \
        -- -std=c99 "${incs[@]}" "${HOST_INCS[@]}" "${gdal_inc[@]}" -D_DEFAULT_SOURCE >"$flog" 2>&1 ||
        touch "$flog.fail" ) &
    running=$((running + 1))
    if [ $running -ge 2 ]; then
      wait -n || true
      running=$((running - 1))
    fi
  done
  wait
  for flog in "$OUT/clang-tidy-$name"/*.log; do
    if [ -e "$flog.fail" ]; then
      grep -E 'warning:|error:' "$flog" || cat "$flog"
      fail=1
    fi
  done
}

# The host tools. C only: tools/bench/opencv/*.cpp is the optional OpenCV peer
# (C++).
HOST_INCS=(-I tools/support -I "$OUT/include")
host_pass tools tools/**/*.c

# The tests (cmocka unit tests, their support, the CLI and fuzz harnesses, the
# kernel tests, the consumer, ABI and README programs) and the Python
# extension python/trn_py.c: the headers the tools export to them, and the
# README's selection example extracted as CMake does for test_readme_select.
mkdir -p "$OUT/doc"
cmake -DREADME=README.md -DMARKER=select -DOUT="$OUT/doc/readme_select_snippet.c" \
  -P cmake/extract_readme_example.cmake
HOST_INCS=(-I tests/support -I tools/support -I tools/trn -I tools/sim -I "$OUT/include" -I "$OUT/doc")
host_pass tests tests/**/*.c
host_pass python python/**/*.c

echo "--- argument checks always compiled in (no assert, no NDEBUG in the core)"
if [ ${#core[@]} -gt 0 ] && grep -nE '\bassert[[:space:]]*\(|NDEBUG|<assert\.h>' "${core[@]}" include/trn/*.h; then
  echo "analysis: the core must check arguments with if + status, not assert()" >&2
  fail=1
fi
echo "--- documented statuses vs tests"
python3 tools/analysis/retval_audit.py || fail=1

if [ $fail -ne 0 ]; then
  echo "analysis: FINDINGS (fix, or add a reasoned line to $DEV)" >&2
  exit 1
fi
echo "analysis: no findings (cppcheck + MISRA, clang-tidy); $(grep -c '^cppcheck\|^clang-tidy' "$DEV") deviations in $DEV"
