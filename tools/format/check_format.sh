#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/format/check_format.sh [--fix] [ROOT] - the one formatting rule
# (.clang-format at the top of the tree, clang-format 14).
#
# Checks every C file of the tree (*.c and *.h under src, include, port,
# tools, tests and python; nothing under build/) against `clang-format --style=file`:
# lists each file that differs with the number of its lines that would
# change, and exits 1 when any differs. --fix rewrites those files in place.
# Exits 77 (CTest SKIP_RETURN_CODE) when clang-format 14 is not installed
# (`bash tools/setup.sh format`): another version formats differently.
# CLANG_FORMAT names another binary. CTest `format` runs this.
set -euo pipefail
fix=0
if [ "${1:-}" = "--fix" ]; then
  fix=1
  shift
fi
case ${1:-} in -h|--help) sed -n '3,12p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;; esac
ROOT=${1:-"$(dirname "${BASH_SOURCE[0]}")/../.."}
cd "$ROOT"

CF=${CLANG_FORMAT:-clang-format}
if ! command -v "$CF" >/dev/null 2>&1; then
  echo "format: SKIPPED: $CF not installed (bash tools/setup.sh format installs clang-format 14)"
  exit 77
fi
major=$("$CF" --version | sed -n 's/.*version \([0-9][0-9]*\)\..*/\1/p' | head -n 1)
if [ "$major" != 14 ]; then
  echo "format: SKIPPED: $CF is version ${major:-unknown}; .clang-format is tuned for clang-format 14 (Debian 12)"
  exit 77
fi
[ -f .clang-format ] || { echo "format: no .clang-format in $(pwd)" >&2; exit 2; }

dirs=()
for d in src include port tools tests python; do
  [ -d "$d" ] && dirs+=("$d")
done
mapfile -t files < <(find "${dirs[@]}" -path '*/build' -prune -o -type f \( -name '*.c' -o -name '*.h' \) -print |
                     LC_ALL=C sort)

tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
ndiff=0
nlines=0
for f in "${files[@]}"; do
  "$CF" --style=file "$f" >"$tmp"
  if ! cmp -s "$f" "$tmp"; then
    n=$(diff -U0 "$f" "$tmp" | tail -n +3 | grep -c '^-' || true) # lines removed or changed
    ndiff=$((ndiff + 1))
    nlines=$((nlines + n))
    if [ $fix -eq 1 ]; then
      cat "$tmp" >"$f"
      echo "formatted $f ($n lines)"
    else
      echo "differs: $f ($n lines)"
    fi
  fi
done

if [ $fix -eq 1 ]; then
  echo "format: rewrote $ndiff of ${#files[@]} files ($nlines lines changed)"
  exit 0
fi
if [ $ndiff -ne 0 ]; then
  echo "format: $ndiff of ${#files[@]} files differ from .clang-format ($nlines lines);" \
       "tools/format/check_format.sh --fix rewrites them"
  exit 1
fi
echo "format: all ${#files[@]} files follow .clang-format"
