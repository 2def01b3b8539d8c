#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/license/check_spdx.sh [ROOT] - every tracked source file names its
# licence: the first comment line (the line after a shebang when there is one)
# must be the SPDX identifier of LICENSE:
#
#   /* SPDX-License-Identifier: Apache-2.0 */     C, C++, headers, .def
#   # SPDX-License-Identifier: Apache-2.0         CMake, shell, Python
#
# Source files: *.c *.h *.cpp *.def *.py *.sh *.cmake *.in (templates),
# CMakeLists.txt, and any other file whose first line is a shebang. The list
# comes from `git ls-files` (every file under ROOT outside build/ and .git/
# when ROOT is not a git work tree). Prints each offending file and exits 1;
# exits 0 with a count when all have the line. CTest `spdx` runs this.
set -euo pipefail
ROOT=${1:-"$(dirname "${BASH_SOURCE[0]}")/../.."}
cd "$ROOT"

ID='SPDX-License-Identifier: Apache-2.0'
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files)
else
  mapfile -t files < <(find . -path ./build -prune -o -path ./.git -prune -o -type f -print | sed 's|^\./||')
fi

is_source() {
  case $1 in
    *.c|*.h|*.cpp|*.def|*.py|*.sh|*.cmake|*.in|CMakeLists.txt|*/CMakeLists.txt) return 0 ;;
  esac
  [ -f "$1" ] && [ "$(head -c 2 "$1" | tr -d '\000')" = '#!' ]
}

checked=0
bad=0
for f in "${files[@]}"; do
  [ -f "$f" ] || continue   # deleted in the work tree, not yet committed
  is_source "$f" || continue
  checked=$((checked + 1))
  line=$(head -n 1 "$f")
  if [[ $line == '#!'* ]]; then
    line=$(sed -n 2p "$f")
  fi
  case $line in
    "/* $ID */"|"// $ID"|"# $ID") ;;
    *) echo "spdx: $f: first comment line is not '$ID'"; bad=$((bad + 1)) ;;
  esac
done
if [ "$bad" -ne 0 ]; then
  echo "spdx: $bad of $checked source files lack the SPDX line"
  exit 1
fi
echo "spdx: all $checked source files carry '$ID'"
