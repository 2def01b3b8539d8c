#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/run.sh [--out DIR] [--seed S] [--trials N] - the main job: the paper's whole story on a
# generated Mars-like terrain, every file in one folder (default build/run/, gitignored):
#
#   1. trn terrain     256 x 256 cells of 0.1 m, Golombek & Rapp rocks     terrain.tif
#   2. trn select      rover at the map's centre: the landmark to sense     select.json, candidates.tif
#   3. trn field       the sensor uncertainty field over the whole map      field.json, field.tif, evaluated.tif
#   4. trn experiment  selection vs no selection, same terrain (if `trn experiment` exists)  experiment.json
#   5. figures         tools/plot/trn_plot.py                               *.png
#
# then prints where the files are and a short summary. tools/setup.sh installs the packages
# (core gdal plot) and the host-release preset is built first; setup and build messages go to
# stderr, the summary to stdout. Works from any directory (a relative --out is taken from the
# caller's directory).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
OUT="$ROOT/build/run"
SEED=1
TRIALS=100
usage() {
  sed -n '2,4p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
  echo "  --out DIR     output folder (default build/run/ in the source tree)"
  echo "  --seed S      terrain seed (default 1)"
  echo "  --trials N    experiment trials (default 100)"
}
while [ $# -gt 0 ]; do
  case "$1" in
    --out) [ $# -ge 2 ] || { echo "run.sh: --out needs a folder" >&2; exit 2; }; OUT=$2; shift 2 ;;
    --seed) [ $# -ge 2 ] || { echo "run.sh: --seed needs a value" >&2; exit 2; }; SEED=$2; shift 2 ;;
    --trials) [ $# -ge 2 ] || { echo "run.sh: --trials needs a value" >&2; exit 2; }; TRIALS=$2; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "run.sh: unknown argument '$1' (--help lists them)" >&2; exit 2 ;;
  esac
done
case "$OUT" in /*) ;; *) OUT="$PWD/$OUT" ;; esac

{
  bash "$ROOT/tools/setup.sh" core gdal plot
  (cd "$ROOT" && cmake --preset host-release && cmake --build --preset host-release -j2)
} >&2

T="$ROOT/build/host-release/trn"
PY=/usr/bin/python3
PLOT="$ROOT/tools/plot/trn_plot.py"
if [ ! -x "$T" ]; then
  echo "run.sh: $T was not built (is GDAL installed? bash tools/setup.sh gdal)" >&2
  exit 1
fi
mkdir -p "$OUT"
cd "$OUT"
step() { echo "run.sh: $*" >&2; }

step "1/5 terrain"
"$T" terrain --out terrain.tif --seed "$SEED" --json > terrain.json

# The rover stands at the map's centre (12.85, 12.85 m: a cell centre), heading east, full pan.
ROVER=12.85,12.85
step "2/5 select (rover at $ROVER m)"
rc=0
"$T" select --dem terrain.tif --rover "$ROVER" --out-map candidates.tif --json > select.json || rc=$?
if [ "$rc" -ne 0 ]; then
  echo "run.sh: trn select exited $rc (3: no informative target on this terrain)" >&2
  exit "$rc"
fi

# The whole 256 x 256 field with the library's defaults: 4,887 selections (13.4x fewer than
# cells) by trn_field_fast (the same raster as trn_field), 2.5 s wall on the shared 2-core
# development machine (2026-12-04; trn_field, `--reference`, 39 s).
step "3/5 field (every rover position of the map, coarse to fine; a few seconds)"
"$T" field --dem terrain.tif --out field.tif --evaluated-out evaluated.tif --json > field.json

step "4/5 experiment"
EXPERIMENT=no
if "$T" experiment --help > /dev/null 2>&1; then
  "$T" experiment --trials "$TRIALS" --seed "$SEED" --json > experiment.json
  EXPERIMENT=yes
else
  rm -f experiment.json
  step "    skipped: this trn has no 'experiment' subcommand yet"
fi

step "5/5 figures"
{
  "$PY" "$PLOT" dem terrain.tif --out terrain.png --title "Synthetic Mars terrain (seed $SEED)"
  "$PY" "$PLOT" select terrain.tif --select-json select.json --out select.png
  "$PY" "$PLOT" uncertainty terrain.tif candidates.tif --select-json select.json --out uncertainty.png
  "$PY" "$PLOT" surface terrain.tif --select-json select.json --zscale 4 --out surface.png \
    --title "3-D view (heights x4): rover and selected target"
  "$PY" "$PLOT" field terrain.tif field.tif --evaluated evaluated.tif --field-json field.json --out field.png
} >&2
if [ "$EXPERIMENT" = yes ]; then
  if "$PY" "$PLOT" experiment --help > /dev/null 2>&1; then
    "$PY" "$PLOT" experiment experiment.json --out experiment.png >&2 ||
      step "    the experiment figure failed (see above)"
  else
    step "    no experiment figure: trn_plot.py has no 'experiment' figure yet"
  fi
fi

"$PY" - "$OUT" <<'EOF'
import json, os, sys
out = sys.argv[1]
j = lambda n: json.load(open(os.path.join(out, n)))
t, s, f = j("terrain.json"), j("select.json"), j("field.json")
print(f"trn main job: every output is in {out}/")
print(f"terrain      {t['width']} x {t['height']} cells of {t['cell_m']:g} m, {t['rocks']} rocks "
      f"({100 * t['rock_area_fraction']:.1f} % of the area), seed {t['seed']}        terrain.tif")
tg, rv = s["target"], s["rover"]
print(f"select       rover ({rv['x_m']:.2f}, {rv['y_m']:.2f}) m -> target ({tg['x_m']:.2f}, {tg['y_m']:.2f}) m, "
      f"{tg['range_m']:.1f} m away, bearing {tg['bearing_deg']:.0f} deg")
print(f"             predicted sigma_x {1000 * s['sigma_x_m']:.1f} mm, sigma_y {1000 * s['sigma_y_m']:.1f} mm, "
      f"rho {s['rho']:+.2f}; {s['candidates']} candidates, {s['informative']} informative   select.json")
nb = ", ".join(f"{1000 * q['uncertainty_m']:.1f}" for q in s["next_best"])
print(f"             next best targets: {nb} mm                  candidates.tif")
b = f["best"]
print(f"field        best rover position ({b['x_m']:.2f}, {b['y_m']:.2f}) m: {1000 * b['uncertainty_m']:.1f} mm; "
      f"median {1000 * f['median_uncertainty_m']:.1f} mm")
print(f"             {f['evaluations']} of {f['cells']} positions evaluated ({f['cells'] / f['evaluations']:.1f}x "
      f"fewer), {f['seconds']:.0f} s                 field.tif")
if os.path.exists(os.path.join(out, "experiment.json")):
    e = j("experiment.json")
    w, wo = e.get("with_selection", {}), e.get("without_selection", {})
    def rate(r):
        ci = r.get("ci95")
        ci = f" (95 % CI {100 * ci[0]:.0f}-{100 * ci[1]:.0f} %)" if isinstance(ci, list) and len(ci) == 2 else ""
        return f"{100 * r.get('success_rate', float('nan')):.0f} %{ci}"
    print(f"experiment   {e.get('trials')} trials (seed {e.get('seed')}): localized with selection {rate(w)}, "
          f"without {rate(wo)}")
    cm = lambda r: f"{100 * r['mean_error_m']:.1f} cm" if isinstance(r.get("mean_error_m"), (int, float)) else "-"
    print(f"             mean error of the successes: {cm(w)} with selection, {cm(wo)} without   experiment.json")
else:
    print("experiment   skipped (no `trn experiment` in this build)")
pngs = sorted(n for n in os.listdir(out) if n.endswith(".png"))
print(f"figures      {' '.join(pngs)}")
EOF
