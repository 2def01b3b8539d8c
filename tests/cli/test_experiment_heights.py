#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tests/cli/test_experiment_heights.py - `trn experiment --match heights` (CTest `cli_experiment_heights`).

    python3 tests/cli/test_experiment_heights.py PATH/TO/trn WORKDIR

The experiment with the height matcher (docs/method.md 8, "With the height matcher") on a
small configuration (128 x 128 cells, 20 trials, a 13-cell patch, a +-6-cell window): the
JSON names the localizer; the local maps are height grids (every cell of a fixed target's
patch sensed, where the voxel run samples voxels); the per-arm status counts of
trn_localize_dem add up; the errors are not the voxel run's; a noisier sensor (--noise-m)
localizes worse; selection succeeds in most trials and at least as often as the fixed
targets; the acceptance limit (--max-failure-prob) turns wrong fixes into ambiguous answers.
Exit status 0 when every check passes.
"""
import json
import os
import shutil
import sys

import clitest  # noqa: E402  (tests/cli/, the script's own directory)

TRN = os.path.abspath(sys.argv[1])
WORK = os.path.abspath(sys.argv[2])
H = clitest.Harness(TRN, sub=("experiment",), timeout=900)
check, run = H.check, H.run

shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)
SMALL = ["--size-cells", 128, "--trials", 20, "--seed", 1, "--window-m", 0.6, "--prior-error-m", 0.3,
         "--patch-m", 1.2, "--max-range-m", 6, "--json"]
ARMS = ("with_selection", "without_selection")
STATUS = ("fixes", "wrong_fixes", "ambiguous", "noise_rescaled")


def experiment(*extra):
    rc, out, err = run(*SMALL, *extra)
    check(rc == 0, f"trn experiment {' '.join(map(str, extra))}: exit {rc}: {err.strip()}")
    try:
        return json.loads(out)
    except ValueError:
        check(False, f"not one JSON object: {out[:200]!r}")
        return {}


h = experiment("--match", "heights")
v = experiment("--match", "voxel")
if not h or not v:
    sys.exit(H.finish())

# ---- the localizer and its local maps ------------------------------------------------
check(h.get("localizer") == "heights" and v.get("localizer") == "voxel",
      f"localizer: {h.get('localizer')} with --match heights, {v.get('localizer')} with --match voxel")
check(h["map_config"]["match"] == "heights" and h["map_config"]["refine"] == 1, f"map_config: {h['map_config']}")
check(h["parameters"]["sensor"] == "heights" and "noise_k_per_m" in h["parameters"]["sensor_model"],
      f"parameters.sensor: {h['parameters']['sensor']!r}")
cells = h["parameters"]["patch_cells"] ** 2
check(h["parameters"]["patch_cells"] == 13, f"patch of {h['parameters']['patch_cells']} cells, want 13")
# a fixed target's patch lies inside the map: every one of its cells is a height of the local map
check(h["without_selection"]["mean_local_points"] == cells,
      f"height grids: {h['without_selection']['mean_local_points']} seen cells a patch, want {cells}")
check(0 < h["with_selection"]["mean_local_points"] <= cells, "with selection: at most the patch's cells seen")
check(v["without_selection"]["mean_local_points"] != cells, "the voxel run samples voxels, not cells")
for arm in ARMS:
    a, b = h[arm], v[arm]
    check(all(k in a for k in STATUS) and not any(k in b for k in STATUS),
          f"{arm}: the height matcher's status counts only with heights")
    # every localization has one outcome: a fix, ambiguous, ill-conditioned, no local map or no target
    total = a["fixes"] + a["ambiguous"] + a["ill_conditioned"] + a["empty_local_maps"] + a["no_target"]
    check(total == a["localizations"], f"{arm}: status counts add to {total}, not {a['localizations']}")
    check(0 <= a["wrong_fixes"] <= a["fixes"], f"{arm}: wrong fixes {a['wrong_fixes']} of {a['fixes']}")
    check(a["localizations"] == b["localizations"], f"{arm}: the same trials as the voxel run")
    check(a["mean_error_m"] != b["mean_error_m"] or a["successes"] != b["successes"],
          f"{arm}: the same errors as the voxel run: the height matcher did not run")
# the same trials and targets: the mean target range is the voxel run's
check(h["draws"] == v["draws"] and h["without_selection"]["mean_target_range_m"] ==
      v["without_selection"]["mean_target_range_m"], "the trials' draws differ from the voxel run's")

# ---- the rates ----------------------------------------------------------------------------
w, o = h["with_selection"], h["without_selection"]
check(w["success_rate"] >= 0.8, f"with selection: success rate {w['success_rate']} below 0.8")
check(w["success_rate"] >= o["success_rate"], f"selection: {w['success_rate']} below the fixed targets' {o['success_rate']}")
check(0.2 <= o["success_rate"] <= 0.95, f"without selection: {o['success_rate']} outside [0.2, 0.95] on this terrain")
check(w["mean_error_m"] <= 0.2 and o["mean_error_m"] <= 0.2, "mean errors of the successes within the radius")

# ---- the noise model feeds the local maps; the acceptance limit acts -----------------
n = experiment("--match", "heights", "--noise-m", 0.3)
if n:
    check(n["without_selection"]["success_rate"] < o["success_rate"] - 0.1,
          f"--noise-m 0.3: without selection {n['without_selection']['success_rate']}, not below {o['success_rate']}")
    check(n["map_config"]["noise_m"] > 0.29, "--noise-m in map_config")
f = experiment("--match", "heights", "--max-failure-prob", 0.01)
if f:
    fo = f["without_selection"]
    check(fo["successes"] == o["successes"], "the limit changes the status, not the answers")
    check(fo["ambiguous"] > 0 and fo["wrong_fixes"] < o["wrong_fixes"],
          f"--max-failure-prob 0.01: ambiguous {fo['ambiguous']}, wrong fixes {fo['wrong_fixes']} "
          f"(limit 1: {o['wrong_fixes']})")

# ---- the refusals ---------------------------------------------------------------------
H.expect_error(2, "--match voxel", "--match", "heights", "--sensor", "dem")
H.expect_error(2, "--match voxel", "--match", "heights", "--heading-error-deg", 2)
H.expect_error(2, "--match heights", "--match", "voxel", "--noise-auto", 1)
H.expect_error(2, "--match heights", "--max-failure-prob", 0.1)
H.expect_error(2, "unknown option", "--match", "heights", "--refine", 1)

sys.exit(H.finish())
