#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tests/real/test_real_predict.py - the height matcher's prediction (trn select's default)
against the errors the height matcher achieves, on the three package DEMs of tests/real
(issue 36 item 2; docs/method.md 4, "Predicted against achieved: measured"): a reduced run of
tools/real/predict_study.py (200 cases from 20 rover positions a DEM, seed 36).

Then the rover that bins its stereo points (issue 36 item 4): `--truth-fine 2 --counts` on
Jacksboro and the lidar (300 cases from 30 positions each), the map the DEM's 2 x 2 block mean,
each local map binned points of the DEM with their counts, the prediction told 4 points a cell
(`trn select --points-per-cell 4`). Fails when, on either DEM, the Spearman correlation is more
than 0.12 below that of an exact prediction on the same cases (predict_study.spearman_ideal: one
error is one draw, so even an exact prediction ranks them imperfectly; the full runs of 1,000
cases: -0.007 to 0.035 below; this reduced run over seeds 1-4 and 36: -0.004 to 0.100 below), the
achieved RMS over the predicted sigma, pooled over the cases predicted below half a cell, is
outside [0.8, 1.25] (the prediction without the points a cell: pooled 0.45-0.59, its lowest decile 1.2-1.5 at
the bottom), or one such decile is outside [0.6, 1.6] (30 cases a decile).

Fails when, on any DEM (the first run):
- the Spearman correlation of predicted uncertainty and achieved error is below 0.8 (the goal);
- a decile whose predicted per-axis sigma is below half a cell has an achieved RMS above 1.25
  times the prediction (the goal's upper side: the prediction must not be optimistic), or below
  0.6 times it (pessimism beyond what the representation term explains on these maps, which are
  sampled from the map itself: 0.63 at worst in the full run; the goal's lower side, 0.8, is not
  met there and is not checked);
- the localizer's own failure probabilities, summed over the cases, are outside 0.5-2 times the
  number of wrong answers where there are at least 5 (the full run: 0.85-1.29).

usage: test_real_predict.py TRN OUT_DIR
"""
import json
import os
import subprocess
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
DEMS = ("jacksboro", "lidar_mn", "rhine")
BINNED_DEMS = ("jacksboro", "lidar_mn")


def main(argv):
    if len(argv) != 3:
        sys.exit("usage: test_real_predict.py TRN OUT_DIR")
    trn, out = argv[1], argv[2]
    res, why = study(trn, out, DEMS, "--cases", "200", "--rovers", "20")
    if res is None:
        sys.exit(f"test_real_predict: {why}")
    bad = []
    for d in DEMS:
        dem = res["dems"][d]
        st, c = dem["stats"], dem["meta"]["cell_m"]
        h = st["heights"]
        rho = h["spearman_all"]
        low = [q["ratio"] for q in h["deciles"]
               if q.get("pred_axis_m") is not None and q.get("ratio") is not None and q["pred_axis_m"] < 0.5 * c]
        fp = sum(cs.get("failure_prob") or 0.0 for cs in dem["cases"])
        wrong = st["wrong"]["n"]
        print(f"test_real_predict: {d}: Spearman {rho:.3f}; below half a cell {len(low)} deciles, ratio "
              f"{min(low):.2f}-{max(low):.2f}; failure probabilities sum {fp:.1f} for {wrong} wrong")
        if not rho >= 0.8:
            bad.append(f"{d}: Spearman {rho:.3f} < 0.8")
        if not low:
            bad.append(f"{d}: no decile below half a cell")
        elif max(low) > 1.25 or min(low) < 0.6:
            bad.append(f"{d}: a decile below half a cell at ratio {min(low):.2f}-{max(low):.2f}, not in [0.6, 1.25]")
        if wrong >= 5 and not 0.5 * wrong <= fp <= 2.0 * wrong:
            bad.append(f"{d}: failure probabilities sum {fp:.1f} for {wrong} wrong answers")
    bad += binned(trn, os.path.join(out, "binned"))
    if bad:
        sys.exit("test_real_predict: " + "; ".join(bad))
    print("test_real_predict: ok")


def study(trn, out, dems, *args):
    """predict_study.py on dems (seed 36) with args: (its predict.json, None), or (None, why)."""
    cmd = ["/usr/bin/python3", os.path.join(ROOT, "tools", "real", "predict_study.py"), "--trn", trn,
           "--out", out, "--no-plot", "--seed", "36", *args]
    for d in dems:
        cmd += ["--dem", d]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        return None, f"predict_study.py exited {r.returncode}: {r.stderr.strip()[-400:]}"
    res = json.load(open(os.path.join(out, "predict.json")))
    missing = [d for d in dems if d not in res["dems"]]
    return (None, f"{', '.join(missing)} not run") if missing else (res, None)


def binned(trn, out):
    """The binned rover with its counts; returns the failures."""
    res, why = study(trn, out, BINNED_DEMS, "--cases", "300", "--rovers", "30", "--truth-fine", "2", "--counts")
    if res is None:
        return [f"binned: {why}"]
    bad = []
    for d in BINNED_DEMS:
        dem = res["dems"][d]
        c = dem["meta"]["cell_m"]
        h = dem["stats"]["heights"]
        rho, ideal = h["spearman_all"], h["spearman_ideal"]
        low = [q for q in h["deciles"] if q.get("ratio") is not None and q["pred_axis_m"] < 0.5 * c]
        ratios = [q["ratio"] for q in low]
        pooled = (sum(q["rms_axis_m"] ** 2 * q["right"] for q in low) /
                  sum(q["pred_axis_m"] ** 2 * q["right"] for q in low)) ** 0.5 if low else float("nan")
        print(f"test_real_predict: binned {d}: Spearman {rho:.3f} (an exact prediction {ideal:.3f}); below half "
              f"a cell {len(low)} deciles, ratio {min(ratios):.2f}-{max(ratios):.2f}, pooled {pooled:.2f}")
        if not rho >= ideal - 0.12:
            bad.append(f"binned {d}: Spearman {rho:.3f} more than 0.12 below an exact prediction's {ideal:.3f}")
        if not low:
            bad.append(f"binned {d}: no decile below half a cell")
        elif not (0.8 <= pooled <= 1.25 and min(ratios) >= 0.6 and max(ratios) <= 1.6):
            bad.append(f"binned {d}: below half a cell pooled ratio {pooled:.2f}, deciles "
                       f"{min(ratios):.2f}-{max(ratios):.2f}")
    return bad


if __name__ == "__main__":
    main(sys.argv)
