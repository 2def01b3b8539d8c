#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tests/real/test_real_heading.py BUILD_TRN OUT [--cases N] - the height matcher over
(x, y, heading) on real DEMs (issue 14), asserted.

For each of the three package DEMs of the real_dems test (Jacksboro hills 83 m, Minnesota
lidar 1 m, Rhine basin 900 m; made into build/real/ by tools/real/dems.py on first use), and
the benchmark's synthetic rock field (`trn terrain`, 0.1 m: calibration over heading on rocks
when the local map has no representation error, docs/modules/heading.md),
N seeded cases (default 200, seed 14) built as tools/real/cases.py builds the real
benchmark's (bilinear from the DEM at a sub-cell truth, a height offset, noise of
1 cm + 0.04 % r^2 / c, a 120 deg wedge of 20 cells, prior within +-4 cells, window
+-6 cells) with the local DEM turned by a heading error drawn uniform in +-6 deg, run
through `trn localize --batch LIST --heading-window-deg 8` with the default (auto) map
configuration. Per DEM, over the answers with status ok whose position is within 1.5
cells (right):
  * at least 90 % of the cases are ok and right (rock field: 70 %; a 120 deg wedge of 2 m sees
    few rocks, and many of its answers are near-ties flagged ambiguous; measured 85.5 % of 200
    at the acceptance limit 0.05, 77.5 % at 0.02 with the ellipse's tail, both since 2026-12-05,
    74.0 % since the shoulders widen the ellipse over heading too, 2026-12-06 (1,000 cases:
    75.9 -> 74.1 %): docs/method.md 9);
  * RMS heading error at most 0.5 deg (Rhine: 2 deg, its noise at 20 cells is 144 m; rock
    field: 1.5 deg, measured 1.08);
    measured figures in docs/modules/heading.md;
  * heading errors within 1 / 2 / 3 sigma_heading: 1 sigma in [50, 90] %, 2 and 3 sigma at
    least 83 and 94 % (a normal: 68.3 / 95.4 / 99.7; 200 cases spread ~3 points at 1 sigma);
  * position errors inside the 1 / 2 / 3-sigma ellipses of cov3's position block: 1 sigma in
    [25, 60] %, 2 and 3 sigma at least 72 and 88 % (a 2-D normal: 39.3 / 86.5 / 98.9; measured
    2026-12-02 at worst 37.5 / 78.8 / 92.9 %, the Rhine's, docs/modules/heading.md).
Prints the measured figures.
"""
import json
import math
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tools", "real"))
import cases as cm  # noqa: E402
import dems  # noqa: E402

DEMS = ("jacksboro", "lidar_mn", "rhine", "rockfield")
RIGHT_MIN = {"rockfield": 0.70}  # share of the cases ok and right; default 0.9
RMS_MAX_DEG = {"rhine": 2.0, "rockfield": 1.5}  # default 0.5
TURN_DEG = 6.0
WINDOW_DEG = 8.0


def make_cases(dem, n, seed, folder):
    """n cases as cases.generate, each local DEM turned by its own drawn error; the
    batch list path and the cases with their errors (case.extra['turn_deg'])."""
    p = cm.CaseParams()
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        truth = cm.draw_truth(dem, rng, p)
        az = float(rng.uniform(-180.0, 180.0))
        off = float(rng.uniform(-p.offset_m, p.offset_m))
        turn = float(rng.uniform(-TURN_DEG, TURN_DEG))
        local, seen = cm.make_local(dem, truth, p, rng, az, off, None, turn)
        d = rng.uniform(-p.prior_cells, p.prior_cells, 2) * dem.c
        prior = (truth[0] + float(d[0]), truth[1] + float(d[1]))
        cs = cm.Case(i, truth, prior, p.window_cells * dem.c, local, seen, az, off)
        cs.extra["turn_deg"] = turn
        out.append(cs)
    return cm.write_cases(out, dem.c, folder), out


def run_dem(trn, out, dem_id, n):
    path = dems.get(dem_id)
    dem = cm.read_dem(path)
    lst, cs = make_cases(dem, n, 14, os.path.join(out, dem_id))
    r = subprocess.run([trn, "localize", "--dem", path, "--batch", lst, "--heading-window-deg",
                        str(WINDOW_DEG), "--json"], capture_output=True, text=True)
    if r.returncode != 0:
        print(f"FAIL {dem_id}: trn exited {r.returncode}: {r.stderr.strip()[-300:]}")
        return 1
    res = [json.loads(x) for x in r.stdout.splitlines() if x.strip()]
    if len(res) != len(cs):
        print(f"FAIL {dem_id}: {len(res)} results for {len(cs)} cases")
        return 1
    eh, z, zp, times, statuses = [], [], [], [], {}
    for c, j in zip(cs, res):
        statuses[j["status"]] = statuses.get(j["status"], 0) + 1
        if j["status"] != "ok":
            continue
        times.append(j["time_ms"])
        if math.hypot(j["x_m"] - c.truth[0], j["y_m"] - c.truth[1]) > 1.5 * dem.c:
            continue
        e = j["heading_deg"] - c.extra["turn_deg"]
        eh.append(e)
        z.append(abs(e) / j["sigma_heading_deg"])
        cv = np.array(j["cov3"], dtype=float).reshape(3, 3)[:2, :2]
        dp = np.array([j["x_m"] - c.truth[0], j["y_m"] - c.truth[1]])
        zp.append(float(dp @ np.linalg.solve(cv, dp)))  # squared Mahalanobis distance
    eh, z, zp = np.array(eh), np.array(z), np.array(zp)
    rms_max = RMS_MAX_DEG.get(dem_id, 0.5)
    right_min = RIGHT_MIN.get(dem_id, 0.9)
    right = len(eh)
    rms = float(np.sqrt(np.mean(eh ** 2))) if right else float("inf")
    cov = [100.0 * float(np.mean(z < k)) if right else 0.0 for k in (1, 2, 3)]
    covp = [100.0 * float(np.mean(zp < k * k)) if right else 0.0 for k in (1, 2, 3)]
    print(f"{dem_id}: {n} cases, statuses {statuses}; ok and right {right}; RMS heading error "
          f"{rms:.3f} deg; heading within 1/2/3 sigma {cov[0]:.1f} / {cov[1]:.1f} / {cov[2]:.1f} % "
          f"(68.3 / 95.4 / 99.7); position in the 1/2/3-sigma ellipses {covp[0]:.1f} / {covp[1]:.1f} / "
          f"{covp[2]:.1f} % (39.3 / 86.5 / 98.9); median time {float(np.median(times)) if times else 0:.1f} ms")
    checks = [
        (right >= right_min * n, f"ok and right {right} >= {100 * right_min:.0f} % of {n}"),
        (rms <= rms_max, f"RMS heading error {rms:.3f} <= {rms_max} deg"),
        (50.0 <= cov[0] <= 90.0, f"1 sigma {cov[0]:.1f} % in [50, 90]"),
        (cov[1] >= 83.0 and cov[2] >= 94.0, f"2 / 3 sigma {cov[1]:.1f} / {cov[2]:.1f} >= 83 / 94 %"),
        (25.0 <= covp[0] <= 60.0, f"position 1 sigma {covp[0]:.1f} % in [25, 60]"),
        (covp[1] >= 72.0 and covp[2] >= 88.0,
         f"position 2 / 3 sigma {covp[1]:.1f} / {covp[2]:.1f} >= 72 / 88 %"),
    ]
    bad = 0
    for ok, what in checks:
        print(f"{'ok  ' if ok else 'FAIL'} {dem_id}: {what}")
        bad += 0 if ok else 1
    return bad


def main():
    args = sys.argv[1:]
    n = 200
    if "--cases" in args:
        k = args.index("--cases")
        n = int(args[k + 1])
        del args[k:k + 2]
    if len(args) != 2:
        print("usage: test_real_heading.py TRN OUT [--cases N]", file=sys.stderr)
        return 2
    trn, out = args
    os.environ.setdefault("TRN", trn)  # the synthetic rock field is made by the trn under test
    bad = sum(run_dem(trn, out, d, n) for d in DEMS)
    print(f"{len(DEMS)} DEMs, {bad} checks failed")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
