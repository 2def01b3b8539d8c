#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tests/fuzz/run.sh [RUNS] [target...] - build and run the libFuzzer harnesses
# (docs/assurance.md, "Fuzzing").
#
# The core (src/**/*.c) and the pure protocol code (port/proto/**/*.c) are
# compiled once with Debian's clang (-fsanitize=fuzzer-no-link,address,
# undefined, no recovery) into build/fuzz/libtrn_fuzz.a; every
# tests/fuzz/fuzz_<target>.c (plus the files it names in a
# "/* fuzz-extra: path.c */" line) is linked against it into
# build/fuzz/fuzz_<target>, then run for RUNS executions (default 20000,
# fixed seed) over its seed corpus tests/fuzz/corpus/<target>/. New inputs
# libFuzzer finds go to build/fuzz/corpus/<target>/, not into the tree.
# A crash, leak, sanitizer report or timeout fails the script; the input is in
# build/fuzz/artifacts/. Add a harness by adding the .c file and its corpus
# directory: nothing here names a target.
#
# Long runs: FUZZ_JOBS=2 tests/fuzz/run.sh 10000000 localize
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
RUNS=${1:-20000}
shift || true
OUT=${FUZZ_OUT:-build/fuzz}   # another directory for a second run alongside
mkdir -p "$OUT/artifacts"
CC=${FUZZ_CC:-clang}
FLAGS=(-std=c99 -g -O1 -fno-omit-frame-pointer
       -fsanitize=address,undefined -fno-sanitize-recover=all
       -I include -I src)
[ -d port/include ] && FLAGS+=(-I port/include)
shopt -s nullglob globstar
core=(src/**/*.c port/proto/**/*.c)

# The core and port/proto once, instrumented (fuzzer-no-link), into one
# archive every harness links: rebuilt only when a source or header changed.
LIB=$OUT/libtrn_fuzz.a
if [ ! -f "$LIB" ] || [ -n "$(find "${core[@]}" include port/include -newer "$LIB" 2>/dev/null | head -n 1)" ]; then
  echo "--- build $LIB (${#core[@]} sources)"
  rm -rf "$OUT/obj" && mkdir -p "$OUT/obj"
  objs=()
  pids=()
  for c in "${core[@]}"; do
    o=$OUT/obj/$(echo "$c" | tr '/' '_').o
    "$CC" "${FLAGS[@]}" -fsanitize=fuzzer-no-link -c "$c" -o "$o" &
    pids+=($!)
    objs+=("$o")
    # two compilers at a time (the build machine has 2 cores); a failed
    # compile fails the script through set -e
    if [ ${#pids[@]} -eq 2 ]; then
      for p in "${pids[@]}"; do wait "$p"; done
      pids=()
    fi
  done
  for p in "${pids[@]}"; do wait "$p"; done
  rm -f "$LIB"
  ar rcs "$LIB" "${objs[@]}"
fi

targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  for h in tests/fuzz/fuzz_*.c; do
    t=$(basename "$h" .c)
    targets+=("${t#fuzz_}")
  done
fi

for t in "${targets[@]}"; do
  src=tests/fuzz/fuzz_$t.c
  bin=$OUT/fuzz_$t
  [ -f "$src" ] || { echo "fuzz: no harness $src" >&2; exit 2; }
  [ -d "tests/fuzz/corpus/$t" ] || { echo "fuzz: no seed corpus tests/fuzz/corpus/$t/" >&2; exit 2; }
  # Extra sources outside the core, named in the harness by a line
  #   /* fuzz-extra: path/to/file.c */   (its directory goes on the include path)
  extra=()
  while IFS= read -r x; do
    extra+=("$x" -I "$(dirname "$x")")
  done < <(sed -n 's#^/\* fuzz-extra: \([^ ]*\) \*/$#\1#p' "$src")
  if [ ! -x "$bin" ] || [ -n "$(find "$src" tests/fuzz/*.h "$LIB" "${extra[@]}" -newer "$bin" 2>/dev/null | head -n 1)" ]; then
    echo "--- build $bin"
    "$CC" "${FLAGS[@]}" -fsanitize=fuzzer "$src" "${extra[@]}" "$LIB" -o "$bin" -lm
  fi
  mkdir -p "$OUT/corpus/$t"
  echo "--- run fuzz_$t: $RUNS executions"
  t0=$SECONDS
  log=$OUT/fuzz_$t.log
  if ! UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
       "$bin" -runs="$RUNS" -seed=1 -max_len=4096 -timeout=10 -rss_limit_mb=2048 \
       -print_final_stats=1 -artifact_prefix="$OUT/artifacts/$t-" \
       "$OUT/corpus/$t" "tests/fuzz/corpus/$t" >"$log" 2>&1; then
    tail -n 40 "$log"
    echo "fuzz: fuzz_$t FAILED (input in $OUT/artifacts/; make it a unit test first, then fix)" >&2
    exit 1
  fi
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  cov=$(grep -Eo 'cov: [0-9]+' "$log" | tail -n 1)
  echo "    ok: ${execs:-?} executions in $((SECONDS - t0)) s, ${cov:-cov: ?} edges"
done
