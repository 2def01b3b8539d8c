#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/real/bench_real.py - seeded real-terrain benchmark: trn against two peers.

    /usr/bin/python3 tools/real/bench_real.py [--dem ID ...] [--dem-file PATH ...] [--cases N] [--seed S]
        [--radius R] [--resample bilinear|cubic] [--truth-fine K] [--fine-map mean|point]
        [--fine-local point|mean|binned] [--centroids] [--counts] [--points-draw D] [--noise-scale F]
        [--outliers P] [--mast-view H]
        [--subcell axis|quad2d] [--prior-miss F] [--miss-max C]
        [--trn PATH] [--trn-mode auto|batch|single]
        [--out DIR] [--keep-cases] [--no-plot] [-- TRN_ARGS...]

For each DEM of tools/real/dems.py (default: all but the fresh ones, dems.DEFAULT; made or
found under build/real/) and each --dem-file (a user's own projected DEM; with only
--dem-file given, only those run), N seeded cases (tools/real/cases.py: a rover at a random
off-centre position, its (2R+1)^2 rover-frame local DEM with a height offset,
range-dependent noise and a 120 deg field of view; a prior within +-4 cells; a +-6 cell
search window) are localized by

* trn: `trn localize --dem G.tif --batch LIST --json [TRN_ARGS]` (one map build,
  one JSON line per case) when this trn has --batch, else one `trn localize --dem G
  --local L --prior X,Y --window-m W --json [TRN_ARGS]` per case (then the time is
  the call's wall time, map build included, unless the JSON carries time_ms);
* ssd: mean-removed SSD over the window + per-axis parabola (tools/real/peers.py);
* ncc: OpenCV matchTemplate TM_CCOEFF_NORMED + per-axis parabola;

each peer timed with time.perf_counter per localization in the same run.

--truth-fine K (model error): the global map given to trn and the peers is the DEM
block-averaged over K x K cells (cell K c, written as OUT/ID_meanK.tif), while each
local DEM is sampled from the ORIGINAL DEM (bilinear on the fine grid at the coarse
cell spacing, centred on the rover): the rover sees the true terrain, the map is a
smoothed coarser product. With --fine-map point the map is the DEM's point samples
every K cells instead (OUT/ID_pointK.tif): a map that samples the terrain at its cell
centres, so that what it cannot resolve is aliased, not smoothed. With --fine-local
mean each local cell is the mean of the original over the cell instead of its value
at the cell's centre (K x K bilinear sub-samples at even spacing about the cell's centre,
each cell the model's noise). With --fine-local binned (issue 36's rover) the rover's stereo
points lie on the original DEM's surface (bilinear) at uniformly random positions, on
average one per fine cell, and are binned into the local cells around the rover at its
sub-cell position; a cell is the mean of its points (K^2 on average, the count varying;
none: unseen), each point with the noise model's sd at its own range, so a cell's noise is
that of the mean of its points' (about 1/K of the model's sd; trn is told the model). Radius, prior, window, noise and errors are then in coarse cells
(tools/real/cases.py).

--mast-view H: the rover sees from a mast H metres above the ground at its position; a
local cell whose ground is hidden behind a rise of the true surface (the original DEM
with --truth-fine) is unseen (NaN): the line from the mast head to the cell centre's
ground must pass above the surface (bilinear) at every sample, samples at most half a
grid cell apart (cases.mast_visible). Default: every cell of the wedge seen.

--prior-miss F (a prior that misses): a share F of each DEM's cases (round(F N), chosen by a
generator of their own) get a prior displaced so that the truth lies OUTSIDE the search
window: its Chebyshev distance from the truth uniform in [window + 1.5, C] cells, C from
--miss-max (default 12 = twice the +-6-cell window's half-width: from just past the edge to
a window's width away), on a random axis and side. The dead reckoning drifted beyond what the
window was sized for; no pose in the window is within 1.5 cells of the truth, and what a
localizer can still do right is say so: not answer `ok` and give a failure probability near 1.
Such a case is never counted right, whatever its error (the answer the window was asked for
does not exist); its failure, for the Brier score, is always 1. The truths keep a margin of
R + window + C + 3 cells from the map's edge, so they differ from those without the option.

Metrics per DEM and method: success (radial error <= 1.5 cells) rate, median error
(cells) over all cases and over the successes, median time per localization (ms);
trn also: confidently wrong (error > 1.5 cells, status ok, failure_probability < 0.5),
calibration over the successful cases with a finite covariance (fraction inside the
1, 2, 3-sigma ellipses of the reported 2x2 covariance; targets 39.3 / 86.5 / 98.9 %),
whether the covariance follows the error from case to case (`variance_by_fifth`: the
successes sorted by the predicted variance's trace and cut into fifths, each fifth's sum of
squared errors over its sum of traces, tightest first; 1 throughout when it does) and
reliability (bins of failure_probability against the observed failure rate).
With --prior-miss, trn's metrics also hold `prior_hit` (the same metrics over the cases whose
prior does not miss) and `prior_miss` (over the missing ones: status counts, fixes = status ok,
confidently wrong = status ok with failure_probability < 0.5 and error > 1.5 cells, the Brier
score of failure_probability against 1 over all of them and over those not ill_conditioned,
its median and the count below 0.5, and the answers within 1.5 cells of the truth all the
same, outside the window: counted, never right); each is printed. The overall `confidently
wrong` counts every status-ok answer under 0.5 that is not a success, missing priors' too.
Prints a table per DEM; writes OUT/bench.json, OUT/reliability.png and
OUT/match_<ID>.png (tools/real/plot_real.py). OUT defaults to build/real/.
Exit status 0 ok, 1 bad input or a failed run (one line on stderr).
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import cases as casemod  # noqa: E402
import dems  # noqa: E402
import peers  # noqa: E402

SUCCESS_CELLS = 1.5
# Mahalanobis^2 of the k-sigma ellipse of a 2-D Gaussian is k^2; the mass inside
# is 1 - exp(-k^2 / 2) = 0.3935, 0.8647, 0.9889 (1, 2, 3 sigma).
CHI2_2D = (1.0, 4.0, 9.0)
CAL_TARGET = (39.3, 86.5, 98.9)
REL_EDGES = (0.0, 0.01, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 0.9, 1.0)
METHODS = ("trn", "ssd", "ncc")


class Fail(Exception):
    """One-line reason; exit 1."""


class Parser(argparse.ArgumentParser):
    def error(self, message):
        raise Fail(message)


def parse_args(argv):
    trn_extra = []
    if "--" in argv:
        k = argv.index("--")
        argv, trn_extra = argv[:k], argv[k + 1:]
    ap = Parser(prog="bench_real.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("--dem", action="append",
                    help="DEM id of tools/real/dems.py (repeatable; default all but the fresh ones)")
    ap.add_argument("--dem-file", action="append", default=[], metavar="PATH",
                    help="a DEM of your own (repeatable): any raster GDAL reads, projected (metres), "
                         "north-up, square cells; its id is the file's name without extension")
    ap.add_argument("--cases", type=int, default=200, help="cases per DEM (default 200)")
    ap.add_argument("--seed", type=int, default=1, help="seed (default 1)")
    ap.add_argument("--radius", type=int, default=20, help="local map radius R, cells (default 20)")
    ap.add_argument("--resample", default="bilinear", choices=("bilinear", "cubic"),
                    help="local DEM sampling (default bilinear)")
    ap.add_argument("--truth-fine", type=int, default=None, metavar="K",
                    help="model error: global map = DEM block-averaged K x K (K >= 2), local maps from the DEM")
    ap.add_argument("--fine-map", default="mean", choices=("mean", "point"),
                    help="with --truth-fine: the map is the K x K block mean (default) or the point "
                         "samples every K cells")
    ap.add_argument("--fine-local", default="point", choices=("point", "mean", "binned"),
                    help="with --truth-fine: each local cell samples the DEM at its centre (default), is "
                         "the mean of K x K bilinear sub-samples over the cell with the model's noise "
                         "(mean), or is the mean of the scattered stereo points of the DEM's surface that "
                         "fall in it, binned at the rover's sub-cell position, each point with the model's "
                         "noise (binned)")
    ap.add_argument("--centroids", action="store_true",
                    help="with --fine-local binned: each local GeoTIFF also holds its cells' points' "
                         "centroids (bands 2 and 3), and trn reads the map there (--centroid-bands 2)")
    ap.add_argument("--counts", action="store_true",
                    help="with --fine-local binned: each local GeoTIFF also holds its cells' point counts "
                         "(the band after the heights and any centroids), and trn reads them "
                         "(--count-band): a cell's noise is that of the mean of its points")
    ap.add_argument("--points-draw", type=int, default=0, metavar="D",
                    help="with --fine-local binned: draw D of the stereo points and their noise (default "
                         "0, the cases' own); the truths, priors, views and offsets stay those of draw 0, so "
                         "draws 0..N-1 show how much of an answer's error and of its covariance comes from "
                         "the points alone (tools/real/draw_study.py)")
    ap.add_argument("--mast-view", type=float, default=None, metavar="H",
                    help="only the local cells whose ground a mast H metres above the rover's ground "
                         "sees past the true surface's rises (default: every cell of the wedge)")
    ap.add_argument("--noise-scale", type=float, default=1.0, metavar="F",
                    help="the local maps' height noise is F times the issue's model (default 1); trn is "
                         "not told (its own --noise-m / --noise-k stay as given after --)")
    ap.add_argument("--outliers", type=float, default=0.0, metavar="P",
                    help="share of the seen local cells that are stereo blunders: a height uniform over "
                         "the seen heights' range widened by that range on each side (default 0); trn is "
                         "not told")
    ap.add_argument("--prior-miss", type=float, default=0.0, metavar="F",
                    help="share of the cases whose prior misses: displaced so that the truth lies 1.5 "
                         "cells or more outside the search window (default 0)")
    ap.add_argument("--miss-max", type=float, default=None, metavar="C",
                    help="with --prior-miss: a missing prior's largest Chebyshev distance from the "
                         "truth, cells (default 12, twice the window's half-width; at least 7.5)")
    ap.add_argument("--subcell", default="axis", choices=("axis", "quad2d"),
                    help="peers' sub-cell fit: a parabola per axis (default) or the 3x3 2-D quadratic")
    ap.add_argument("--trn", default=os.path.join(dems.ROOT, "build", "host-release", "trn"),
                    help="trn binary (default build/host-release/trn)")
    ap.add_argument("--trn-mode", default="auto", choices=("auto", "batch", "single"),
                    help="trn --batch or one call per case (default: batch when supported)")
    ap.add_argument("--out", default=dems.BUILD, help="output folder (default build/real)")
    ap.add_argument("--keep-cases", action="store_true", help="keep the local DEMs under OUT/cases_ID/")
    ap.add_argument("--no-plot", action="store_true", help="no figures")
    ap.add_argument("--trn-arg", action="append", default=[],
                    help="one extra argument for trn localize (repeatable; or put them after --)")
    a = ap.parse_args(argv)
    a.trn_extra = a.trn_arg + trn_extra
    a.dem = a.dem or ([] if a.dem_file else list(dems.DEFAULT))
    for d in a.dem:
        if d not in dems.BY_ID:
            raise Fail(f"unknown DEM '{d}' (known: {', '.join(dems.BY_ID)})")
    a.files = {}
    for f in a.dem_file:
        if not os.path.isfile(f):
            raise Fail(f"--dem-file {f}: no such file")
        d = os.path.splitext(os.path.basename(f))[0]
        if d in dems.BY_ID or d in a.files:
            raise Fail(f"--dem-file {f}: its id '{d}' is taken (rename the file)")
        a.files[d] = os.path.abspath(f)
        a.dem.append(d)
    if a.cases < 1:
        raise Fail(f"--cases {a.cases}: must be >= 1")
    if not (a.noise_scale >= 0.0 and math.isfinite(a.noise_scale)):
        raise Fail(f"--noise-scale {a.noise_scale}: must be a finite number >= 0")
    if not 0.0 <= a.outliers < 1.0:
        raise Fail(f"--outliers {a.outliers}: must be in [0, 1)")
    if not 0.0 <= a.prior_miss <= 1.0:
        raise Fail(f"--prior-miss {a.prior_miss}: must be in [0, 1]")
    miss_min = casemod.CaseParams.window_cells + 1.5
    if a.miss_max is not None and a.prior_miss == 0.0:
        raise Fail(f"--miss-max {a.miss_max}: needs --prior-miss F > 0")
    a.miss_max = 2.0 * casemod.CaseParams.window_cells if a.miss_max is None else a.miss_max
    if not (a.miss_max >= miss_min and math.isfinite(a.miss_max)):
        raise Fail(f"--miss-max {a.miss_max}: must be a finite distance >= {miss_min:g} cells "
                   f"(1.5 cells past the window's edge)")
    if a.mast_view is not None and not (a.mast_view > 0.0 and math.isfinite(a.mast_view)):
        raise Fail(f"--mast-view {a.mast_view}: must be a finite height > 0 metres")
    if a.fine_local != "point" and a.truth_fine is None:
        raise Fail(f"--fine-local {a.fine_local}: needs --truth-fine K")
    if a.centroids and (a.fine_local != "binned" or a.truth_fine is None):
        raise Fail("--centroids: needs --truth-fine K --fine-local binned (only binned cells have "
                   "centroids)")
    if a.counts and (a.fine_local != "binned" or a.truth_fine is None):
        raise Fail("--counts: needs --truth-fine K --fine-local binned (only binned cells have "
                   "point counts)")
    if a.points_draw != 0 and (a.fine_local != "binned" or a.truth_fine is None):
        raise Fail("--points-draw: needs --truth-fine K --fine-local binned (only binned cells have points)")
    if a.points_draw < 0:
        raise Fail(f"--points-draw {a.points_draw}: must be >= 0")
    if a.centroids:
        a.trn_extra = list(a.trn_extra) + ["--centroid-bands", "2"]
    if a.counts:
        a.trn_extra = list(a.trn_extra) + ["--count-band", "4" if a.centroids else "2"]
    a.mast_view = a.mast_view or 0.0
    if a.truth_fine is not None and a.truth_fine < 2:
        raise Fail(f"--truth-fine {a.truth_fine}: must be >= 2")
    if not 2 <= a.radius <= 500:
        raise Fail(f"--radius {a.radius}: must be in 2..500")
    if not (os.path.isfile(a.trn) and os.access(a.trn, os.X_OK)):
        raise Fail(f"trn binary {a.trn} not found or not executable (cmake --build --preset host-release)")
    if peers.cv2 is None:
        raise Fail("OpenCV's python3 module missing (bash tools/setup.sh real)")
    return a


# --- trn ------------------------------------------------------------------------
def trn_has_batch(trn):
    r = subprocess.run([trn, "localize", "--help"], capture_output=True, text=True)
    return "--batch" in (r.stdout + r.stderr)


def trn_result(j, wall_ms=None):
    """A trn JSON object -> the per-case record fields."""
    out = {"x": j.get("x_m"), "y": j.get("y_m"), "status": j.get("status", "error"),
           "failure_probability": j.get("failure_probability")}
    cov = j.get("cov_m2")
    if cov is None and all(j.get(k) is not None for k in ("sigma_x_m", "sigma_y_m", "rho")):
        sx, sy, rho = j["sigma_x_m"], j["sigma_y_m"], j["rho"]
        cov = [sx * sx, sy * sy, rho * sx * sy]
    out["cov_m2"] = cov
    if j.get("refinement") is not None:
        out["refinement"] = j["refinement"]
    if j.get("noise_scale") is not None:
        out["noise_scale"] = j["noise_scale"]
    if j.get("time_ms") is not None:
        out["time_ms"], out["time_includes_map_build"] = float(j["time_ms"]), False
    else:
        out["time_ms"], out["time_includes_map_build"] = wall_ms, True
    if j.get("error"):
        out["error"] = j["error"]
    return out


def run_trn_batch(a, dem_path, lst, cs):
    cmd = [a.trn, "localize", "--dem", dem_path, "--batch", lst, "--json"] + a.trn_extra
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = (time.perf_counter() - t0) * 1e3
    lines = [ln for ln in r.stdout.splitlines() if ln.strip()]
    if r.returncode != 0 and not lines:
        raise Fail(f"trn --batch failed (exit {r.returncode}): {(r.stderr.strip().splitlines() or [''])[0]}")
    res = []
    for k, cs_ in enumerate(cs):
        if k >= len(lines):
            res.append({"status": "error", "error": "no output line", "time_ms": None})
            continue
        try:
            j = json.loads(lines[k])
        except json.JSONDecodeError:
            res.append({"status": "error", "error": "bad JSON line", "time_ms": None})
            continue
        if j.get("local") not in (None, cs_.path):
            raise Fail(f"trn --batch line {k + 1} is for {j.get('local')}, expected {cs_.path}")
        res.append(trn_result(j))
    return res, wall


def run_trn_single(a, dem_path, cs):
    res = []
    t_all = time.perf_counter()
    for cs_ in cs:
        cmd = [a.trn, "localize", "--dem", dem_path, "--local", cs_.path,
               "--prior", f"{cs_.prior[0]!r},{cs_.prior[1]!r}", "--window-m", repr(cs_.window_m),
               "--json"] + a.trn_extra
        t0 = time.perf_counter()
        r = subprocess.run(cmd, capture_output=True, text=True)
        wall = (time.perf_counter() - t0) * 1e3
        if r.returncode == 2:
            raise Fail(f"trn usage error: {(r.stderr.strip().splitlines() or [''])[0]}")
        try:
            j = json.loads(r.stdout) if r.returncode == 0 else None
        except json.JSONDecodeError:
            j = None
        if j is None:
            res.append({"status": "error", "error": (r.stderr.strip().splitlines() or [""])[0],
                        "time_ms": wall, "time_includes_map_build": True})
        else:
            res.append(trn_result(j, wall))
    return res, (time.perf_counter() - t_all) * 1e3


# --- metrics --------------------------------------------------------------------
def radial_cells(rec, truth, c):
    if rec.get("x") is None or rec.get("y") is None:
        return math.inf
    return math.hypot(rec["x"] - truth[0], rec["y"] - truth[1]) / c


def mahalanobis2(rec, truth):
    cov = rec.get("cov_m2")
    if cov is None or any(v is None or not math.isfinite(v) for v in cov):
        return None
    C = np.array([[cov[0], cov[2]], [cov[2], cov[1]]])
    if np.linalg.det(C) <= 0 or C[0, 0] <= 0:
        return None
    e = np.array([rec["x"] - truth[0], rec["y"] - truth[1]])
    return float(e @ np.linalg.solve(C, e))


def variance_by_fifth(pairs):
    """Does the predicted covariance follow the error from case to case? pairs: (error (dx, dy),
    cov_m2 (xx, yy, xy)) of the right answers. Sorted by the predicted variance's trace and cut
    into fifths (tightest first), each fifth's sum of squared errors over its sum of traces. 1 in
    every fifth: the prediction follows the errors. Above 1 in the tightest fifths and below in the
    loosest: the predictions spread wider than the errors do (regression to the mean), which the
    pooled coverage hides. None with fewer than 5 pairs."""
    tr = sorted((c[0] + c[1], e[0] * e[0] + e[1] * e[1]) for e, c in pairs)
    n = len(tr)
    if n < 5:
        return None
    out = []
    for f in range(5):
        part = tr[f * n // 5:(f + 1) * n // 5]
        out.append(sum(e for _, e in part) / sum(t for t, _ in part))
    return out


def med(v):
    v = [x for x in v if x is not None]
    return float(np.median(v)) if v else None


def metrics(records, method, split=True):
    """A method's metrics over the records; a case whose prior misses is never a success.
    For trn with missing priors among the records (and split): also `prior_hit`, the same
    metrics over the others, and `prior_miss` (miss_metrics)."""
    errs = [r[method]["err_cells"] for r in records]
    ok = [e <= SUCCESS_CELLS and not r.get("prior_miss") for e, r in zip(errs, records)]
    n = len(records)
    m = {"n": n, "success": int(sum(ok)), "rate": sum(ok) / n,
         "median_err_cells": med([e if math.isfinite(e) else 1e9 for e in errs]),
         "median_err_success_cells": med([e for e, s in zip(errs, ok) if s]),
         "median_time_ms": med([r[method].get("time_ms") for r in records])}
    if method != "trn":
        return m
    t = [r["trn"] for r in records]
    m["status"] = {s: sum(1 for x in t if x["status"] == s) for s in sorted({x["status"] for x in t})}
    cw = [not s and x["status"] == "ok" and x.get("failure_probability") is not None
          and x["failure_probability"] < 0.5 for x, s in zip(t, ok)]
    m["confidently_wrong"] = int(sum(cw))
    m["confidently_wrong_rate"] = sum(cw) / n
    m["time_includes_map_build"] = any(x.get("time_includes_map_build") for x in t)
    d2 = [x.get("mahalanobis2") for x, s in zip(t, ok) if s]
    d2 = [v for v in d2 if v is not None]
    m["calibration"] = {"n": len(d2), "target_pct": list(CAL_TARGET),
                        "inside_pct": [100.0 * sum(v <= k for v in d2) / len(d2) if d2 else None
                                       for k in CHI2_2D]}
    pairs = [((x["x"] - r["truth"][0], x["y"] - r["truth"][1]), x["cov_m2"])
             for r, x, s in zip(records, t, ok)
             if s and x.get("mahalanobis2") is not None and x.get("cov_m2") is not None]
    m["calibration"]["variance_by_fifth"] = variance_by_fifth(pairs)
    bins = []
    fp = [(x.get("failure_probability"), not s) for x, s in zip(t, ok)]
    fp = [(p, f) for p, f in fp if p is not None and math.isfinite(p)]
    for lo, hi in zip(REL_EDGES[:-1], REL_EDGES[1:]):
        inb = [(p, f) for p, f in fp if lo <= p < hi or (hi == 1.0 and p == 1.0)]
        bins.append({"lo": lo, "hi": hi, "n": len(inb),
                     "mean_predicted": float(np.mean([p for p, _ in inb])) if inb else None,
                     "observed": float(np.mean([f for _, f in inb])) if inb else None})
    m["reliability"] = bins
    m["brier"] = float(np.mean([(p - f) ** 2 for p, f in fp])) if fp else None
    if split and any(r.get("prior_miss") for r in records):
        hit = [r for r in records if not r.get("prior_miss")]
        m["prior_hit"] = metrics(hit, method, split=False) if hit else None
        m["prior_miss"] = miss_metrics([r for r in records if r.get("prior_miss")])
    return m


def miss_metrics(records):
    """trn on the cases whose prior misses (the truth outside the window): every one a failure.
    fixes: status ok; confidently wrong: status ok, failure_probability < 0.5 and the error
    above 1.5 cells; near_truth: answers within 1.5 cells of the truth all the same (outside
    the window; counted, never right); Brier: of failure_probability against 1, over all of
    them and over those not flagged ill_conditioned (status ok or ambiguous: where the failure
    probability is what decides)."""
    t = [r["trn"] for r in records]

    def probs(xs):
        v = [x.get("failure_probability") for x in xs]
        return [p for p in v if p is not None and math.isfinite(p)]
    fp = probs(t)
    fu = probs([x for x in t if x["status"] in ("ok", "ambiguous")])
    return {"n": len(t),
            "status": {s: sum(1 for x in t if x["status"] == s) for s in sorted({x["status"] for x in t})},
            "fixes": sum(1 for x in t if x["status"] == "ok"),
            "confidently_wrong": sum(1 for x in t if x["status"] == "ok" and x["err_cells"] > SUCCESS_CELLS
                                     and x.get("failure_probability") is not None
                                     and x["failure_probability"] < 0.5),
            "near_truth": sum(1 for x in t if x["err_cells"] <= SUCCESS_CELLS),
            "n_failure_probability": len(fp),
            "brier": float(np.mean([(p - 1.0) ** 2 for p in fp])) if fp else None,
            "n_unflagged": len(fu),
            "brier_unflagged": float(np.mean([(p - 1.0) ** 2 for p in fu])) if fu else None,
            "median_failure_probability": med(fp),
            "below_half": sum(1 for p in fp if p < 0.5),
            "truth_outside_cells": [min(r["truth_outside_cells"] for r in records),
                                    max(r["truth_outside_cells"] for r in records)]}


def fmt(v, spec):
    return "-" if v is None else format(v, spec)


def print_table(dem_id, meta, ms):
    how = "point samples (every K-th cell) of" if meta.get("fine_map") == "point" else "block mean of"
    kk = meta.get("truth_fine")
    lhow = {"mean": "each local cell its mean over the cell",
            "binned": "each local cell the mean of the stereo points binned in it"}.get(
        meta.get("fine_local"), "each local cell its value at the cell's centre")
    fine = (f", map = {kk} x {kk} {how} the {meta['fine_cell_m']:g} m "
            f"DEM the local maps are sampled from ({lhow})") if kk else ""
    ns = meta.get("noise_scale", 1.0)
    noise = f", local noise {ns:g} x the issue's (trn not told)" if ns != 1.0 else ""
    if meta.get("outliers"):
        noise += f", {100 * meta['outliers']:g} % of the seen cells blunders (trn not told)"
    if meta.get("mast_view"):
        noise += f", seen from a {meta['mast_view']:g} m mast (hidden cells unseen)"
    if meta.get("prior_miss"):
        noise += (f", {100 * meta['prior_miss']:g} % of the priors miss (truth 1.5-"
                  f"{meta['miss_max'] - meta['window_m'] / meta['cell_m']:g} cells outside the window)")
    print(f"\n{dem_id} ({meta['character']}, held_out={meta['held_out']}): {meta['cols']} x {meta['rows']} "
          f"cells of {meta['cell_m']:g} m, {ms['trn']['n']} cases, R = {meta['radius']} cells, "
          f"{meta['resample']}, trn {meta['trn_mode']}{fine}{noise}")
    print(f"  {'method':6s} {'success':>12s} {'med err':>8s} {'med err ok':>10s} {'med ms':>8s}  (errors in cells)")
    for k in METHODS:
        m = ms[k]
        note = " (incl. map build)" if m.get("time_includes_map_build") else ""
        print(f"  {k:6s} {m['success']:5d} {100 * m['rate']:5.1f} % {fmt(m['median_err_cells'], '8.3f')} "
              f"{fmt(m['median_err_success_cells'], '10.3f')} {fmt(m['median_time_ms'], '8.2f')}{note}")
    t = ms["trn"]
    print(f"  trn status {t['status']}; confidently wrong {t['confidently_wrong']} "
          f"({100 * t['confidently_wrong_rate']:.1f} %); Brier {fmt(t['brier'], '.4f')}")
    cal = t["calibration"]
    ins = " / ".join(fmt(v, ".1f") for v in cal["inside_pct"])
    print(f"  trn calibration (n = {cal['n']} successes): inside 1/2/3 sigma {ins} % "
          f"(target 39.3 / 86.5 / 98.9)")
    if cal.get("variance_by_fifth") is not None:
        print("  trn error^2 over predicted variance by fifth of the prediction (tightest first): "
              + " ".join(f"{v:.2f}" for v in cal["variance_by_fifth"]))
    rel = "  ".join(f"[{b['lo']:g},{b['hi']:g}) {b['n']}: {fmt(b['observed'], '.2f')}"
                    for b in t["reliability"] if b["n"])
    print(f"  trn reliability (bin n: observed failure rate): {rel}")
    h, mi = t.get("prior_hit"), t.get("prior_miss")
    if mi is not None:
        if h is not None:
            print(f"  trn, the {h['n']} cases whose prior hits: right {h['success']} ({100 * h['rate']:.1f} %); "
                  f"confidently wrong {h['confidently_wrong']}; fixes {h['status'].get('ok', 0)}; "
                  f"Brier {fmt(h['brier'], '.4f')}")
        print(f"  trn, the {mi['n']} cases whose prior misses (truth {mi['truth_outside_cells'][0]:.1f}-"
              f"{mi['truth_outside_cells'][1]:.1f} cells outside the window): status {mi['status']}; "
              f"confidently wrong {mi['confidently_wrong']}; failure probability below 0.5 in "
              f"{mi['below_half']}, median {fmt(mi['median_failure_probability'], '.3g')}; "
              f"Brier {fmt(mi['brier'], '.4f')} (over the {mi['n_unflagged']} not ill_conditioned "
              f"{fmt(mi['brier_unflagged'], '.4f')}); within 1.5 cells of the truth all the same {mi['near_truth']}")


# --- one DEM --------------------------------------------------------------------
def bench_dem(a, dem_id, batch):
    os.environ.setdefault("TRN", a.trn)  # the synthetic DEM is made by this trn
    if dem_id in a.files:
        path = a.files[dem_id]
        entry = {"character": "user file", "held_out": True, "description": path}
    else:
        try:
            path = dems.get(dem_id)
        except Exception as e:  # a recipe failed: name it
            raise Fail(f"DEM {dem_id}: {e}")
        d = dems.BY_ID[dem_id]
        entry = {"character": d.character, "held_out": d.held_out, "description": d.description}
    dem = casemod.read_dem(path)
    fine = None
    if a.truth_fine:
        fine = dem
        if a.fine_map == "point":
            dem = casemod.point_sample(fine, a.truth_fine)
        else:
            dem = casemod.block_average(fine, a.truth_fine)
        os.makedirs(a.out, exist_ok=True)
        path = casemod.write_global(os.path.join(a.out, f"{dem_id}_{a.fine_map}{a.truth_fine}.tif"), dem,
                                    like=fine.path)
        dem.path = path
    p = casemod.CaseParams(radius=a.radius, resample=a.resample,
                           noise0_m=casemod.CaseParams.noise0_m * a.noise_scale,
                           noise_k=casemod.CaseParams.noise_k * a.noise_scale,
                           local=a.fine_local if a.truth_fine else "point", mast_m=a.mast_view,
                           centroids=a.centroids, counts=a.counts, points_draw=a.points_draw,
                           outlier_frac=a.outliers, prior_miss=a.prior_miss, miss_max_cells=a.miss_max)
    tmp = tempfile.mkdtemp(prefix=f"bench_real_{dem_id}_")
    try:
        t0 = time.perf_counter()
        cs = casemod.generate(dem, a.cases, a.seed, p, tmp, fine)
        gen_s = time.perf_counter() - t0
        lst = os.path.join(tmp, "cases.txt")
        print(f"bench_real: {dem_id}: {a.cases} cases in {gen_s:.1f} s; trn ({'batch' if batch else 'single'})",
              file=sys.stderr, flush=True)
        if batch:
            trn_res, trn_wall = run_trn_batch(a, path, lst, cs)
        else:
            trn_res, trn_wall = run_trn_single(a, path, cs)
        print(f"bench_real: {dem_id}: trn {trn_wall / 1e3:.1f} s; peers", file=sys.stderr, flush=True)
        records = []
        for cs_, tr in zip(cs, trn_res):
            rec = {"index": cs_.index, "truth": list(cs_.truth), "prior": list(cs_.prior),
                   "window_m": cs_.window_m, "azimuth_deg": cs_.azimuth_deg, "offset_m": cs_.offset_m,
                   "seen_cells": int(cs_.seen.sum()), "prior_miss": cs_.prior_miss,
                   # Chebyshev distance of the truth beyond the window's edge, cells (< 0: inside)
                   "truth_outside_cells": max(abs(cs_.prior[0] - cs_.truth[0]), abs(cs_.prior[1] - cs_.truth[1]))
                   / dem.c - p.window_cells}
            tr["err_cells"] = radial_cells(tr, cs_.truth, dem.c)
            tr["mahalanobis2"] = mahalanobis2(tr, cs_.truth) if math.isfinite(tr["err_cells"]) else None
            rec["trn"] = tr
            for name, fn in peers.PEERS.items():
                t1 = time.perf_counter()
                try:
                    out = fn(dem, cs_.local, cs_.seen, cs_.prior, cs_.window_m, a.subcell)
                except ValueError:
                    out = None
                dt = (time.perf_counter() - t1) * 1e3
                r = {"x": None, "y": None, "time_ms": dt} if out is None else \
                    {"x": out[0], "y": out[1], "pose": list(out[2]), "time_ms": dt}
                r["err_cells"] = radial_cells(r, cs_.truth, dem.c)
                rec[name] = r
            records.append(rec)
        meta = {"path": path, "character": entry["character"],
                "held_out": entry["held_out"], "description": entry["description"],
                "cell_m": dem.c, "rows": dem.z.shape[0], "cols": dem.z.shape[1], "radius": a.radius,
                "window_m": p.window_cells * dem.c, "prior_cells": p.prior_cells, "resample": a.resample,
                "trn_mode": "batch" if batch else "single", "trn_wall_ms": trn_wall,
                "opencv_mask": peers.mask_supported(), "truth_fine": a.truth_fine,
                "fine_map": a.fine_map if a.truth_fine else None,
                "fine_local": a.fine_local if a.truth_fine else None, "centroids": a.centroids,
                "counts": a.counts,
                "points_draw": a.points_draw, "noise_scale": a.noise_scale, "outliers": a.outliers,
                "mast_view": a.mast_view,
                "prior_miss": a.prior_miss, "miss_max": a.miss_max if a.prior_miss else None,
                "fine_cell_m": fine.c if fine is not None else None,
                "fine_path": fine.path if fine is not None else None}
        # the figure's case: the first trn success (else case 0); keep its local DEM
        pick = next((r["index"] for r in records if r["trn"]["err_cells"] <= SUCCESS_CELLS
                     and not r["prior_miss"]), 0)
        os.makedirs(a.out, exist_ok=True)
        keep = os.path.join(a.out, f"match_{dem_id}_local.tif")
        shutil.copyfile(cs[pick].path, keep)
        meta["figure_case"] = pick
        meta["figure_local"] = keep
        if a.keep_cases:
            dst = os.path.join(a.out, f"cases_{dem_id}")
            shutil.rmtree(dst, ignore_errors=True)
            shutil.copytree(tmp, dst)
            meta["cases_dir"] = dst
        ms = {k: metrics(records, k) for k in METHODS}
        return {"meta": meta, "metrics": ms, "cases": records}
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def finite(v):
    """v with non-finite floats as None (strict JSON)."""
    if isinstance(v, dict):
        return {k: finite(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [finite(x) for x in v]
    if isinstance(v, (float, np.floating)):
        return float(v) if math.isfinite(v) else None
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, np.bool_):
        return bool(v)
    return v


def main(argv):
    try:
        a = parse_args(argv)
        mode = a.trn_mode
        batch = trn_has_batch(a.trn) if mode == "auto" else mode == "batch"
        res = {"config": {"cases": a.cases, "seed": a.seed, "radius": a.radius, "resample": a.resample,
                          "subcell": a.subcell, "truth_fine": a.truth_fine, "fine_map": a.fine_map,
                          "fine_local": a.fine_local, "centroids": a.centroids, "counts": a.counts,
                          "points_draw": a.points_draw,
                          "mast_view": a.mast_view, "noise_scale": a.noise_scale,
                          "outliers": a.outliers, "prior_miss": a.prior_miss,
                          "miss_max": a.miss_max if a.prior_miss else None,
                          "trn": a.trn, "trn_args": a.trn_extra, "success_cells": SUCCESS_CELLS},
               "dems": {}}
        for d in a.dem:
            r = bench_dem(a, d, batch)
            res["dems"][d] = r
            print_table(d, r["meta"], r["metrics"])
        os.makedirs(a.out, exist_ok=True)
        out_json = os.path.join(a.out, "bench.json")
        with open(out_json, "w") as f:
            json.dump(finite(res), f, indent=1)
        print(f"\nresults: {out_json}")
        if not a.no_plot:
            import plot_real
            for pth in plot_real.all_figures(res, a.out):
                print(f"figure: {pth}")
        return 0
    except (Fail, casemod.InputError) as e:
        print(f"bench_real: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
