#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# tools/test.d/48-walkthrough.sh - the README's "Your own DEM in ten minutes",
# run as written: the ```sh block after `<!-- readme-example: own-dem -->`,
# from a scratch folder that looks like the repository's root (build/ and
# tools/ linked in, mine/my_dem.tif made by tools/docs/sample_dem.py: the
# Jacksboro sample DEM in degrees). Then checks what the README says it gives:
# a fix (`ok`) within half a cell of the cut's centre, a landmark, a field with
# a best position, and the three figures. Needs the host-release build (made
# by tools/test.sh before this stage) and the packages of core gdal plot real.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
ROOT=$(pwd)
fail() { echo "48-walkthrough: $*" >&2; exit 1; }
bash tools/setup.sh core gdal plot real

W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
ln -s "$ROOT/build" "$W/build"
ln -s "$ROOT/tools" "$W/tools"
mkdir "$W/mine"
/usr/bin/python3 tools/docs/sample_dem.py "$W/mine/my_dem.tif"
/usr/bin/python3 - "$ROOT/README.md" "$W/walkthrough.sh" <<'PY'
import re, sys
text = open(sys.argv[1], encoding="utf-8").read()
at = text.index("<!-- readme-example: own-dem -->")
m = re.compile(r"```sh\n(.*?)\n```", re.S).search(text, at)
open(sys.argv[2], "w").write("set -euo pipefail\n" + m.group(1) + "\n")
PY
t0=$SECONDS
(cd "$W" && bash walkthrough.sh) >"$W/out.txt" 2>&1 || { cat "$W/out.txt" >&2; fail "the README's block failed"; }
echo "48-walkthrough: the README's block ran in $((SECONDS - t0)) s"
/usr/bin/python3 - "$W/mine" <<'PY'
import json, os, sys
d = sys.argv[1]
def fail(msg):
    sys.exit(f"48-walkthrough: {msg}")
fix = json.load(open(os.path.join(d, "fix.json")))
if fix["status"] != "ok":
    fail(f"fix status {fix['status']}, not ok")
err = max(abs(fix["x_m"] - 747520.0), abs(fix["y_m"] - 4054320.0))
if not err <= 40.0:
    fail(f"fix ({fix['x_m']}, {fix['y_m']}) is {err:.1f} m from the cut's centre (747520, 4054320)")
if not (0 < fix["sigma_x_m"] < 80 and 0 < fix["sigma_y_m"] < 80):
    fail(f"fix sigmas {fix['sigma_x_m']}, {fix['sigma_y_m']} m")
lm = json.load(open(os.path.join(d, "landmark.json")))
r = lm["target"]["range_m"]
if not (250 <= r <= 3000 and lm["uncertainty_m"] > 0):
    fail(f"landmark at {r} m, uncertainty {lm['uncertainty_m']}")
fd = json.load(open(os.path.join(d, "field.json")))
b = fd["best"]
if not (745000 <= b["x_m"] <= 750000 and 4052000 <= b["y_m"] <= 4057000 and b["uncertainty_m"] > 0):
    fail(f"field's best {b}")
for png in ("fix.png", "landmark.png", "field.png"):
    if os.path.getsize(os.path.join(d, png)) < 10000:
        fail(f"{png} is too small")
print(f"48-walkthrough: fix {err:.3f} m from the truth, sigma {fix['sigma_x_m']:.4f} x {fix['sigma_y_m']:.4f} m; "
      f"landmark {r:.0f} m away, {lm['uncertainty_m']:.1f} m; field best {b['uncertainty_m']:.1f} m "
      f"({fd['evaluations']} of {fd['cells']} positions)")
PY
