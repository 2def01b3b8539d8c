#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/real/predict_study.py - the height matcher's predicted uncertainty against its achieved
error on real DEMs (issue 36 item 2, "Predicted against achieved"; docs/method.md 4).

    /usr/bin/python3 tools/real/predict_study.py [--dem ID ...] [--cases N] [--rovers M] [--seed S]
        [--patch-cells P] [--min-range-cells A] [--max-range-cells B] [--footprint-cells F]
        [--prior-cells Q] [--window-cells W] [--map-sigma-m S0] [--truth-fine K [--counts]]
        [--trn PATH] [--out DIR] [--no-plot] [--smoke] [--reanalyse predict.json]

Per DEM (tools/real/dems.py ids; cached GeoTIFFs under build/real/):

1. M rover positions uniform over the DEM (at least the reach plus the patch, the window and
   the prior from its edges, 95 % of the cells within reach finite). At each, `trn select --dem
   D --rover X,Y --patch-m P c --min-range-m A c --max-range-m B c --footprint-m F c
   --stride-cells 1 --out-map cand.tif --json` twice: the default (`--map-config auto`, the height
   matcher's prediction, with `--global-sigma-m S0`: the local maps below are sampled from the map
   itself, so the map's own height error is 0 by default) and `--map-config paper` (the voxel
   prediction, its defaults). Every candidate's scalar prediction u = sqrt(sx^2 + sy^2) (m) is read
   from the two rasters at its centre cell (+inf: uninformative).
2. N targets drawn from the pooled candidates of all M positions, stratified over the height
   prediction: ten bins of equal width in ln u between its 0.1 and 99.9 percentiles of the pool,
   N/10 from each (uniform within a bin, without replacement; a bin with too few takes all it has,
   the rest drawn from the whole pool), so the draw covers the whole range of predictions; only
   candidates whose patch and search window lie on known map cells are drawn.
3. Each target's local map (issue 12's construction, tools/real/cases.py): the P x P patch around
   the target on the rover's lattice (cells at whole-cell offsets from the rover's true sub-cell
   position, the patch's centre the target cell's nearest), each cell the DEM bilinear at the
   rover's true position plus its offset, plus one height offset uniform in +-50 m, plus Gaussian
   noise of sd noise_m + noise_k_per_m r^2 at the cell's range r (the map configuration's stereo
   model, read from the select JSON), written as a rover-frame GeoTIFF (the rover at (0, 0), the
   patch at its offset). A prior uniform in +-Q cells per axis about the truth, a window of +-W
   cells; `trn localize --dem D --batch LIST --json` (the default auto configuration).
   With --truth-fine K (K >= 2) the map is the DEM's K x K block mean (OUT/ID_meanK.tif; the
   rovers, targets and cells are its) and each local map is a rover's binned stereo points
   (bench_real.py's --fine-local binned, cases.binned_points): points of the DEM's surface
   (bilinear) uniform over the patch's cells, K^2 a cell on average, each with the stereo model's
   noise at its own range, each cell their mean. The draw's strata are the unbinned prediction's,
   so the targets, maps and priors are the same with --counts, which writes the cells' counts as
   the patch's band 2, localizes with --count-band 2 and predicts with select --points-per-cell
   K^2 (the unbinned prediction of the same targets kept as heights_unbinned).
4. Achieved error |estimate - truth| (m) and per axis; right: within 1.5 cells (bench_real.py);
   the localizer's own failure_probability and status.

Predictions computed here, for the drawn targets only (documented in docs/method.md 4):

* the height prediction's covariance again (fisher_heights: the profiled Fisher information of
  the patch's central-difference gradients, one variance per patch, as src/select_heights.c), for
  its per-axis sigmas; checked against the raster's scalar (JSON: fisher_check);
* two variants of it, as diagnostics of its parts: without the representation term
  (heights_norep) and with each cell's own variance at its range instead of one at the target's
  (heights_percell, fisher_heights_percell); and, needing the rover's true sub-cell position so not
  a prediction, the information of the local map's own cells (bilinear_percell: the bilinear
  surface's gradient at each local cell's sample point, each cell's own variance);
* a predicted failure probability from the map alone (self_similarity): for every integer shift
  d of the patch within +-W cells and at least 2 cells (Chebyshev) from its true place, the
  expected ln L gap between the truth and d under the height model with the offset profiled out,
  D_d = 1/2 sum_i w_i (dh_i(d) - mean_w dh(d))^2, w_i = 1/s_i^2, s_i^2 the stereo model's variance at
  cell i's range plus the map's and a quarter of the representation term of the height
  prediction; the gap ln L(truth) - ln L(d) is then N(D_d, 2 D_d), so d beats the truth with
  probability Phi(-sqrt(D_d / 2)); P_beat = 1 - prod_d (1 - Phi(-sqrt(D_d / 2))). Also the
  posterior share of the expected likelihoods, P_post = S / (1 + S), S = sum_d exp(-D_d).

Statistics (per DEM; JSON and tables): Spearman's rank correlation of the predicted u against the
achieved error over all cases and over the right ones, for the height and the voxel prediction
(+inf ranked highest); per decile of the prediction: cases, right rate, the right answers' RMS
error per axis over the RMS predicted per-axis sigma (u / sqrt(2) for the scalar; x and y apart from
fisher_heights' sigmas), the localizer's mean failure probability and P_beat against the observed
wrong rate; reliability bins of each failure probability. Writes OUT/predict.json and
OUT/predict_vs_achieved.png (one panel per DEM: log-log scatter, the 1:1 line, decile RMS).

--reanalyse predict.json: those predictions and the statistics again from a run's JSON (its trn
results kept; no trn run).
--smoke: 60 cases from 12 positions on the rock field (a quick end-to-end run; it prints its
numbers and checks only that the run is complete, not the goals).
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
from osgeo import gdal

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import cases as casemod  # noqa: E402
import dems  # noqa: E402

gdal.UseExceptions()

RIGHT_CELLS = 1.5
FAIL_ZONE_CELLS = 2  # competitors at least this far (Chebyshev) from the truth: the localizer's zone
DEFAULT_DEMS = ["jacksboro", "lidar_mn", "merewether", "kennemer_dunes", "san_juan_basin", "rhine"]
REL_EDGES = (0.0, 0.01, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 0.9, 1.0)


class Fail(Exception):
    """One-line reason; exit 1."""


class Parser(argparse.ArgumentParser):
    def error(self, message):
        raise Fail(message)


# --- statistics -------------------------------------------------------------------
def rankdata(v):
    """Ranks 1..n of v, ties given their mean rank (+inf ranks above every finite value)."""
    v = np.asarray(v, dtype=np.float64)
    order = np.argsort(v, kind="mergesort")
    s = v[order]
    ranks = np.empty(v.size)
    i = 0
    while i < v.size:
        j = i
        while j + 1 < v.size and s[j + 1] == s[i]:
            j += 1
        ranks[order[i:j + 1]] = 0.5 * (i + j) + 1.0
        i = j + 1
    return ranks


def spearman(a, b):
    """Spearman's rank correlation of a and b (pairs with a NaN dropped; +inf ranks highest);
    None with fewer than 3 pairs or a constant variable."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    keep = ~(np.isnan(a) | np.isnan(b))
    a, b = a[keep], b[keep]
    if a.size < 3:
        return None
    ra, rb = rankdata(a), rankdata(b)
    ra -= ra.mean()
    rb -= rb.mean()
    den = math.sqrt(float(ra @ ra) * float(rb @ rb))
    return float(ra @ rb) / den if den > 0 else None


def spearman_ideal(u, sx, sy, rho, n_sim=20, seed=0):
    """The Spearman correlation that a prediction exactly right in distribution would reach on these
    cases: u against the lengths of errors drawn from each case's own predicted Gaussian (per-axis
    sigmas sx, sy, correlation rho), the mean over n_sim draws. It is below 1 because one error is
    one draw: how far below depends on how widely the cases' predictions spread. None without
    finite predictions."""
    u, sx, sy = (np.asarray(v, dtype=np.float64) for v in (u, sx, sy))
    rho = np.nan_to_num(np.asarray(rho, dtype=np.float64))
    fin = np.isfinite(u) & np.isfinite(sx) & np.isfinite(sy)
    if fin.sum() < 3:
        return None
    rng = np.random.default_rng(seed)
    vals = []
    for _ in range(n_sim):
        z1, z2 = rng.standard_normal((2, int(fin.sum())))
        ex = sx[fin] * z1
        ey = sy[fin] * (rho[fin] * z1 + np.sqrt(np.maximum(0.0, 1.0 - rho[fin] ** 2)) * z2)
        r = spearman(u[fin], np.hypot(ex, ey))
        if r is not None:
            vals.append(r)
    return float(np.mean(vals)) if vals else None


def decile_edges(pred, n_bins=10):
    """Edges of n_bins equal-count bins of the finite predictions (quantiles)."""
    f = np.asarray(pred, dtype=np.float64)
    f = f[np.isfinite(f)]
    return np.quantile(f, np.linspace(0.0, 1.0, n_bins + 1)) if f.size else None


def decile_stats(pred, ex, ey, right, sx=None, sy=None, fail_probs=None, n_bins=10):
    """Per equal-count bin of the finite predictions `pred` (scalar u, m): cases, right rate, the
    right answers' RMS error per axis sqrt(mean((ex^2 + ey^2) / 2)) over the RMS predicted per-axis
    sigma sqrt(mean(u^2 / 2)) (`ratio`), with sx, sy also per axis (ratio_x, ratio_y), and for each
    named failure probability its mean against the observed wrong rate."""
    pred = np.asarray(pred, dtype=np.float64)
    ex, ey = np.asarray(ex, dtype=np.float64), np.asarray(ey, dtype=np.float64)
    right = np.asarray(right, dtype=bool)
    edges = decile_edges(pred, n_bins)
    out = []
    if edges is None:
        return out
    fin = np.isfinite(pred)
    for k in range(n_bins):
        lo, hi = edges[k], edges[k + 1]
        inb = fin & (pred >= lo) & ((pred < hi) if k < n_bins - 1 else (pred <= hi))
        ok = inb & right
        d = {"lo": float(lo), "hi": float(hi), "n": int(inb.sum()), "right": int(ok.sum()),
             "right_rate": float(ok.sum() / inb.sum()) if inb.any() else None}
        if ok.any():
            rms = math.sqrt(float(np.mean((ex[ok] ** 2 + ey[ok] ** 2) / 2.0)))
            prd = math.sqrt(float(np.mean(pred[ok] ** 2 / 2.0)))
            d.update(rms_axis_m=rms, pred_axis_m=prd, ratio=rms / prd if prd > 0 else None,
                     median_err_m=float(np.median(np.hypot(ex[ok], ey[ok]))),
                     median_pred_m=float(np.median(pred[ok])))
            if sx is not None and sy is not None:
                sxa, sya = np.asarray(sx)[ok], np.asarray(sy)[ok]
                g = np.isfinite(sxa) & np.isfinite(sya)
                if g.any():
                    d["ratio_x"] = math.sqrt(float(np.mean(ex[ok][g] ** 2)) / float(np.mean(sxa[g] ** 2)))
                    d["ratio_y"] = math.sqrt(float(np.mean(ey[ok][g] ** 2)) / float(np.mean(sya[g] ** 2)))
        for name, p in (fail_probs or {}).items():
            p = np.asarray(p, dtype=np.float64)
            g = inb & np.isfinite(p)
            d[f"{name}_mean"] = float(np.mean(p[g])) if g.any() else None
        d["wrong_rate"] = float(np.mean(~right[inb])) if inb.any() else None
        out.append(d)
    return out


def reliability(p, wrong, edges=REL_EDGES):
    """Bins of a predicted failure probability against the observed wrong rate."""
    p = np.asarray(p, dtype=np.float64)
    wrong = np.asarray(wrong, dtype=bool)
    g = np.isfinite(p)
    bins = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        inb = g & (p >= lo) & ((p < hi) if hi < 1.0 else (p <= hi))
        bins.append({"lo": lo, "hi": hi, "n": int(inb.sum()),
                     "mean_predicted": float(np.mean(p[inb])) if inb.any() else None,
                     "observed": float(np.mean(wrong[inb])) if inb.any() else None})
    brier = float(np.mean((p[g] - wrong[g]) ** 2)) if g.any() else None
    return {"bins": bins, "brier": brier, "sum_predicted": float(np.sum(p[g])),
            "observed_wrong": int(np.sum(wrong[g]))}


# --- the local map ------------------------------------------------------------------
def patch_offsets(rover_rc, target_rc, patch_cells):
    """The patch on the rover's lattice: whole-cell offsets (kx east, ky south) from the rover of
    its P x P cells, centred on the lattice point nearest the target cell."""
    h = patch_cells // 2
    ox = int(round(target_rc[1] - rover_rc[1]))
    oy = int(round(target_rc[0] - rover_rc[0]))
    k = np.arange(-h, h + 1)
    return ox + k[None, :] + 0 * k[:, None], oy + k[:, None] + 0 * k[None, :]


def local_patch(dem, rover_xy, target_rc, patch_cells, noise_m=0.0, noise_k_per_m=0.0, offset_m=0.0,
                rng=None):
    """The local map of one target: heights (P x P), the rover-frame geotransform, the cells'
    ranges (m). Cell (i, j) is the DEM (bilinear) at the rover's true position plus (kx c east,
    ky c south), plus offset_m, plus N(0, (noise_m + noise_k_per_m r^2)^2) noise when rng is given."""
    c = dem.c
    fr, fc = dem.frac_index(*rover_xy)
    kx, ky = patch_offsets((fr, fc), target_rc, patch_cells)
    z = casemod.sample(dem.z, fr + ky.astype(np.float64), fc + kx.astype(np.float64)) + offset_m
    r = c * np.hypot(kx, ky)
    if rng is not None:
        z = z + rng.standard_normal(z.shape) * (noise_m + noise_k_per_m * r * r)
    h = patch_cells // 2
    gt = ((kx[0, 0] - 0.5) * c, c, 0.0, -(ky[0, 0] - 0.5) * c, 0.0, -c)
    assert kx[0, 0] == kx[0, h] - h
    return z, gt, r


def binned_patch(fine, dem, rover_xy, target_rc, a, noise_m, noise_k_per_m, offset_m, rng):
    """The local map of one target for a rover that bins its stereo points (bench_real.py's
    --fine-local binned, issue 36 item 4): points of the original DEM `fine` (bilinear) uniform over
    the patch's cells of the map `dem` (K x K fine cells each, K^2 points a cell on average), each
    with the stereo model's noise at its own range, each cell their mean plus offset_m (NaN: no
    point). Returns (heights, the rover-frame geotransform, the cells' point counts)."""
    c, k = dem.c, a.truth_fine
    fr, fc = dem.frac_index(*rover_xy)
    kx, ky = patch_offsets((fr, fc), target_rc, a.patch_cells)
    h = a.patch_cells // 2
    ffr, ffc = fine.frac_index(*rover_xy)
    p = casemod.CaseParams(noise0_m=noise_m, noise_k=noise_k_per_m * c)
    gen = np.random.default_rng(rng.integers(0, 2 ** 63))
    b = casemod.binned_points(fine, ffr, ffc, h, k, 0.0, p, c, gen, noisy=True,
                              centre=(int(kx[h, h]), int(ky[h, h])))
    gt = ((kx[0, 0] - 0.5) * c, c, 0.0, -(ky[0, 0] - 0.5) * c, 0.0, -c)
    return b.h + offset_m, gt, b.n.astype(np.float64)


def write_patch(path, z, gt, counts=None):
    """A rover-frame local patch (float32, no-data NaN); the points' counts as band 2 when given."""
    bands = [z] + ([] if counts is None else [np.where(np.isfinite(z), counts, np.nan)])
    ds = gdal.GetDriverByName("GTiff").Create(path, z.shape[1], z.shape[0], len(bands), gdal.GDT_Float32)
    ds.SetGeoTransform(gt)
    for i, v in enumerate(bands):
        b = ds.GetRasterBand(i + 1)
        b.SetNoDataValue(float("nan"))
        b.WriteArray(np.asarray(v).astype(np.float32))
    ds = None


# --- predictions from the map alone -------------------------------------------------
def patch_slices(target_rc, patch_cells, pad=0):
    h = patch_cells // 2 + pad
    r, c = int(target_rc[0]), int(target_rc[1])
    return slice(r - h, r + h + 1), slice(c - h, c + h + 1)


def representation_term(z, target_rc, patch_cells):
    """mean(e^2) / 4 over the patch, e = h less the mean of its four neighbours (NaN-free cells)."""
    sr, sc = patch_slices(target_rc, patch_cells, 1)
    w = z[sr, sc]
    e = w[1:-1, 1:-1] - 0.25 * (w[:-2, 1:-1] + w[2:, 1:-1] + w[1:-1, :-2] + w[1:-1, 2:])
    e = e[np.isfinite(e)]
    return float(np.mean(e * e)) / 4.0 if e.size else math.nan


def fisher_heights(z, target_rc, patch_cells, rover_rc, noise_m, noise_k_per_m, map_sigma_m, cell_m,
                   representation=True, points_per_cell=0.0):
    """The height prediction's covariance of one candidate (src/select_heights.c's model):
    I = sum w (g - g_w)(g - g_w)^T over the patch's cells with four known neighbours, g the
    central-difference gradient (m per cell), g_w its w-weighted mean, w = 1 / s^2 each cell's own
    s^2 = (noise_m + noise_k r^2)^2 + map_sigma^2 + e^2 / 4 (r the cell's range from the rover at
    fractional (row, col) rover_rc; e the cell's height minus its four neighbours' mean, left out
    with representation=False; with points_per_cell n > 0, a binned local map, the noise term over n
    plus the centroid's jitter |g|^2 / (12 n)); singular where its determinant is below 1e-12 of the squared
    uncentred sum w |g|^2 (a plane, flat ground). Returns (sigma_east_m, sigma_north_m, rho_en,
    u_m); +inf when the information is singular."""
    sr, sc = patch_slices(target_rc, patch_cells, 1)
    w = z[sr, sc]
    c0 = w[1:-1, 1:-1]
    gx = 0.5 * (w[1:-1, 2:] - w[1:-1, :-2])  # along columns (east)
    gy = 0.5 * (w[2:, 1:-1] - w[:-2, 1:-1])  # along rows (south)
    e = c0 - 0.25 * (w[:-2, 1:-1] + w[2:, 1:-1] + w[1:-1, :-2] + w[1:-1, 2:])
    ok = np.isfinite(gx) & np.isfinite(gy) & np.isfinite(e)
    inf = (math.inf, math.inf, math.nan, math.inf)
    if ok.sum() < 3:
        return inf
    rows = np.arange(sr.start + 1, sr.stop - 1)[:, None] + 0 * np.arange(sc.start + 1, sc.stop - 1)[None, :]
    cols = np.arange(sc.start + 1, sc.stop - 1)[None, :] + 0 * rows
    r2 = ((rows - rover_rc[0]) ** 2 + (cols - rover_rc[1]) ** 2) * cell_m ** 2
    s2 = binned_var((noise_m + noise_k_per_m * r2) ** 2, gx, gy, points_per_cell) + map_sigma_m ** 2
    if representation:
        s2 = s2 + e * e / 4.0
    wt = 1.0 / s2[ok]
    gx, gy = gx[ok], gy[ok]
    raw = float((wt * (gx * gx + gy * gy)).sum())  # the uncentred sum: the singularity test's scale
    gx = gx - (wt * gx).sum() / wt.sum()
    gy = gy - (wt * gy).sum() / wt.sum()
    a, b, d = float((wt * gx * gx).sum()), float((wt * gx * gy).sum()), float((wt * gy * gy).sum())
    det = a * d - b * b
    if not det > 1e-12 * raw * raw or raw == 0.0:
        return inf
    vx, vy, cxy = d / det * cell_m ** 2, a / det * cell_m ** 2, -b / det * cell_m ** 2
    sx, sy = math.sqrt(vx), math.sqrt(vy)
    return sx, sy, -cxy / (sx * sy), math.sqrt(vx + vy)  # rows point south: rho flips sign


def binned_var(s2, gx, gy, points_per_cell):
    """A cell's stereo variance s2 for a local map binned from points_per_cell n points a cell
    (src/select_heights.c): s2 / n plus the points' centroid's jitter (gx^2 + gy^2) / (12 n); n = 0:
    one measurement a cell, s2."""
    if not points_per_cell > 0:
        return s2
    return (s2 + (gx * gx + gy * gy) / 12.0) / points_per_cell


def fisher_heights_percell(z, target_rc, patch_cells, s2_cells, cell_m):
    """The height prediction with each cell's own variance s2_cells (P x P; the stereo model at the
    cell's range) instead of one per patch: I = sum w (g - mean_w g)(g - mean_w g)^T, w = 1 / s2,
    the offset profiled with the same weights. Returns u (m), +inf when singular."""
    sr, sc = patch_slices(target_rc, patch_cells, 1)
    w = z[sr, sc]
    gx = 0.5 * (w[1:-1, 2:] - w[1:-1, :-2])
    gy = 0.5 * (w[2:, 1:-1] - w[:-2, 1:-1])
    ok = np.isfinite(gx) & np.isfinite(gy)
    if ok.sum() < 3:
        return math.inf
    wt = 1.0 / s2_cells[ok]
    gx, gy = gx[ok], gy[ok]
    unc = float((wt * gx * gx).sum()) * float((wt * gy * gy).sum())
    gx = gx - (wt * gx).sum() / wt.sum()
    gy = gy - (wt * gy).sum() / wt.sum()
    a, b, d = float((wt * gx * gx).sum()), float((wt * gx * gy).sum()), float((wt * gy * gy).sum())
    det = a * d - b * b
    if not det > 1e-12 * unc or unc == 0.0:
        return math.inf
    return math.sqrt((a + d) / det) * cell_m


def fisher_bilinear_percell(z, rover_rc, kx, ky, s2_cells, cell_m):
    """A diagnostic, not a prediction (it needs the rover's true sub-cell position): the information
    of the local map's own cells, the gradient of the bilinear surface at each local cell's sample
    point (where the local map was sampled) instead of the central difference at the map's node,
    each cell's own variance, the offset profiled with the same weights. Returns u (m)."""
    rr, cc = rover_rc[0] + ky.astype(np.float64), rover_rc[1] + kx.astype(np.float64)
    r0, c0 = np.floor(rr).astype(int), np.floor(cc).astype(int)
    fr, fc = rr - r0, cc - c0
    z00, z01, z10, z11 = z[r0, c0], z[r0, c0 + 1], z[r0 + 1, c0], z[r0 + 1, c0 + 1]
    gx = (1 - fr) * (z01 - z00) + fr * (z11 - z10)
    gy = (1 - fc) * (z10 - z00) + fc * (z11 - z01)
    ok = np.isfinite(gx) & np.isfinite(gy)
    wt = 1.0 / s2_cells[ok]
    gx, gy = gx[ok], gy[ok]
    gx = gx - (wt * gx).sum() / wt.sum()
    gy = gy - (wt * gy).sum() / wt.sum()
    a, b, d = float((wt * gx * gx).sum()), float((wt * gx * gy).sum()), float((wt * gy * gy).sum())
    det = a * d - b * b
    return math.sqrt((a + d) / det) * cell_m if det > 0 else math.inf


def self_similarity(z, target_rc, patch_cells, s2_cells, window_cells, zone=FAIL_ZONE_CELLS):
    """The expected ln L gaps D_d (nats) between the patch at its true place and shifted by every
    whole-cell d within +-window_cells at least `zone` cells (Chebyshev) away, with the offset
    profiled out (weights 1 / s2_cells, the P x P variances); P_beat = 1 - prod(1 - Phi(-sqrt(D/2))),
    P_post = S / (1 + S), S = sum exp(-D). Returns (P_beat, P_post, min D, the d of min D as
    (east, south) cells)."""
    W = int(window_cells)
    sr, sc = patch_slices(target_rc, patch_cells, W)
    big = z[sr, sc]
    P = patch_cells
    h0 = big[W:W + P, W:W + P]
    w = 1.0 / s2_cells
    ws = w.sum()
    logq = 0.0  # ln prod(1 - p_d)
    S = 0.0
    dmin, dbest = math.inf, None
    for dy in range(-W, W + 1):
        for dx in range(-W, W + 1):
            if max(abs(dx), abs(dy)) < zone:
                continue
            dh = big[W + dy:W + dy + P, W + dx:W + dx + P] - h0
            if not np.all(np.isfinite(dh)):
                continue
            m = float((w * dh).sum()) / ws
            D = 0.5 * float((w * (dh - m) ** 2).sum())
            if D < dmin:
                dmin, dbest = D, (dx, dy)
            p = 0.5 * math.erfc(math.sqrt(D / 2.0) / math.sqrt(2.0))
            logq += math.log1p(-min(p, 1.0 - 1e-16))
            S += math.exp(-D) if D < 700 else 0.0
    return -math.expm1(logq), S / (1.0 + S), dmin, dbest


# --- running trn --------------------------------------------------------------------
def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    return r.returncode, r.stdout, r.stderr


def points_per_cell(a):
    """The points a binned local cell holds on average that the prediction is told: K^2 with
    --truth-fine K --counts, else 0 (one measurement a cell)."""
    return float(a.truth_fine * a.truth_fine) if a.counts else 0.0


def select(a, dem_path, rover_xy, c, paper, out_map, ppc=0.0):
    cmd = [a.trn, "select", "--dem", dem_path, "--rover", f"{rover_xy[0]!r},{rover_xy[1]!r}",
           "--patch-m", repr(a.patch_cells * c), "--min-range-m", repr(a.min_range_cells * c),
           "--max-range-m", repr(a.max_range_cells * c), "--footprint-m", repr(a.footprint_cells * c),
           "--stride-cells", "1", "--next-best", "0", "--out-map", out_map, "--json"]
    cmd += ["--map-config", "paper"] if paper else ["--global-sigma-m", repr(a.map_sigma_m)]
    if ppc > 0:
        cmd += ["--points-per-cell", repr(ppc)]
    rc, out, err = run(cmd)
    if rc == 3:
        return None, None
    if rc != 0:
        raise Fail(f"trn select failed (exit {rc}): {(err.strip().splitlines() or [''])[0]}")
    j = json.loads(out)
    ds = gdal.Open(out_map)
    m = ds.GetRasterBand(1).ReadAsArray().astype(np.float64)
    ds = None
    return j, m


def localize_batch(a, dem_path, lst, n):
    cmd = [a.trn, "localize", "--dem", dem_path, "--batch", lst, "--json"]
    if a.counts:
        cmd += ["--count-band", "2"]
    rc, out, err = run(cmd)
    lines = [ln for ln in out.splitlines() if ln.strip()]
    if rc != 0 and not lines:
        raise Fail(f"trn localize --batch failed (exit {rc}): {(err.strip().splitlines() or [''])[0]}")
    res = []
    for k in range(n):
        try:
            res.append(json.loads(lines[k]))
        except (IndexError, json.JSONDecodeError):
            res.append({"status": "error"})
    return res


# --- one DEM --------------------------------------------------------------------------
def draw_rovers(dem, rng, n, margin, reach):
    nr, nc = dem.z.shape
    if nr - 2 * margin < 2 or nc - 2 * margin < 2:
        raise Fail(f"{dem.path}: {nc} x {nr} cells is too small for a margin of {margin} cells")
    valid = np.isfinite(dem.z)
    out = []
    for _ in range(200 * n):
        if len(out) == n:
            break
        r, c = rng.uniform(margin, nr - 1 - margin), rng.uniform(margin, nc - 1 - margin)
        ir, ic = int(round(r)), int(round(c))
        if valid[ir - reach:ir + reach + 1, ic - reach:ic + reach + 1].mean() < 0.95:
            continue
        out.append(dem.xy(r, c))
    if len(out) < n:
        raise Fail(f"{dem.path}: only {len(out)} of {n} rover positions with a mostly valid reach")
    return out


def stratified_draw(rng, logu, n, n_bins=10):
    """Indices of n of the pool's finite ln-predictions, n / n_bins from each of n_bins bins of
    equal width in ln u between the pool's 0.1 and 99.9 percentiles (ends clipped in)."""
    idx = np.flatnonzero(np.isfinite(logu))
    if idx.size < n:
        raise Fail(f"only {idx.size} informative candidates for {n} cases")
    lo, hi = np.quantile(logu[idx], [0.001, 0.999])
    b = np.clip(((logu[idx] - lo) / max(hi - lo, 1e-12) * n_bins).astype(int), 0, n_bins - 1)
    per = [n // n_bins + (1 if k < n % n_bins else 0) for k in range(n_bins)]
    chosen = []
    for k in range(n_bins):
        inb = idx[b == k]
        take = min(per[k], inb.size)
        chosen.extend(rng.choice(inb, take, replace=False).tolist())
    if len(chosen) < n:
        rest = np.setdiff1d(idx, np.array(chosen, dtype=np.int64))
        chosen.extend(rng.choice(rest, n - len(chosen), replace=False).tolist())
    return np.array(chosen, dtype=np.int64), (float(lo), float(hi))


def map_predictions(dem, cases, a, noise_m, noise_k):
    """The predictions from the map alone of every case (fisher_heights, with and without the
    representation term, per cell; self_similarity), written into the case records; returns the
    relative differences of fisher_heights' u from trn select's raster."""
    c = dem.c
    ppc = points_per_cell(a)
    fis_rel = []
    for cs in cases:
        tr, tc = cs["target_rc"]
        fr, fc = dem.frac_index(*cs["rover"])
        sx, sy, rho, u = fisher_heights(dem.z, (tr, tc), a.patch_cells, (fr, fc), noise_m, noise_k,
                                        a.map_sigma_m, c, points_per_cell=ppc)
        cs.update(sigma_x_pred_m=sx, sigma_y_pred_m=sy, rho_pred=rho, u_python_m=u)
        if math.isfinite(u) and math.isfinite(cs["u_heights_m"]):
            fis_rel.append(abs(u - cs["u_heights_m"]) / cs["u_heights_m"])
        cs["u_norep_m"] = fisher_heights(dem.z, (tr, tc), a.patch_cells, (fr, fc), noise_m, noise_k,
                                         a.map_sigma_m, c, representation=False, points_per_cell=ppc)[3]
        kx, ky = patch_offsets((fr, fc), (tr, tc), a.patch_cells)
        rcell = c * np.hypot(kx, ky)
        rep = representation_term(dem.z, (tr, tc), a.patch_cells)
        sr, sc = patch_slices((tr, tc), a.patch_cells, 1)
        zz = dem.z[sr, sc]
        gxc, gyc = 0.5 * (zz[1:-1, 2:] - zz[1:-1, :-2]), 0.5 * (zz[2:, 1:-1] - zz[:-2, 1:-1])
        s2 = binned_var((noise_m + noise_k * rcell ** 2) ** 2, gxc, gyc, ppc) + a.map_sigma_m ** 2 + rep
        cs["u_percell_m"] = fisher_heights_percell(dem.z, (tr, tc), a.patch_cells, s2, c)
        cs["u_bilinear_m"] = fisher_bilinear_percell(dem.z, (fr, fc), kx, ky, s2, c)
        pb, pp, dmin, dbest = self_similarity(dem.z, (tr, tc), a.patch_cells, s2, a.window_cells)
        cs.update(p_beat=pb, p_post=pp, gap_min_nats=dmin, best_competitor_cells=dbest)
    return fis_rel


def study_dem(a, dem_id):
    os.environ.setdefault("TRN", a.trn)
    try:
        path = dems.get(dem_id)
    except Exception as e:  # a recipe failed: name it
        raise Fail(f"DEM {dem_id}: {e}")
    fine = None
    if a.truth_fine > 1:  # the map a K x K block mean of the DEM; the rover bins points of the DEM
        fine = casemod.read_dem(path)
        path = casemod.write_global(os.path.join(a.out, f"{dem_id}_mean{a.truth_fine}.tif"),
                                    casemod.block_average(fine, a.truth_fine), like=path)
    dem = casemod.read_dem(path)
    c = dem.c
    ppc = points_per_cell(a)
    rng = np.random.default_rng([a.seed, sum(map(ord, dem_id))])
    h = a.patch_cells // 2
    pad = a.window_cells + int(math.ceil(a.prior_cells)) + 2
    margin = a.max_range_cells + h + pad + 2
    rovers = draw_rovers(dem, rng, a.rovers, margin, a.max_range_cells + h + 1)
    tmp = tempfile.mkdtemp(prefix=f"predict_study_{dem_id}_")
    t0 = time.perf_counter()
    try:
        pool = []  # (rover index, row, col, u heights, u voxel, range m)
        cfg = None
        n_sel = 0
        for i, rv in enumerate(rovers):
            # the draw's prediction is the unbinned one, so the targets are the same with --counts
            jh, mh = select(a, path, rv, c, False, os.path.join(tmp, "h.tif"))
            jv, mv = select(a, path, rv, c, True, os.path.join(tmp, "v.tif"))
            if jh is None and mh is None:
                continue  # no candidate informative: nothing to draw here
            md = mh
            if ppc > 0:
                jh, mh = select(a, path, rv, c, False, os.path.join(tmp, "b.tif"), ppc)
                if mh is None:
                    raise Fail(f"{dem_id}: --points-per-cell {ppc:g} left no candidate map")
            n_sel += 1
            if jh is not None:
                if jh.get("predicts") != "heights":
                    raise Fail(f"trn select predicts {jh.get('predicts')}, expected heights")
                cfg = jh["map_config"]
            rr, cc = np.nonzero(~np.isnan(mh))
            uh = mh[rr, cc]
            uv = mv[rr, cc] if mv is not None else np.full(uh.shape, math.inf)
            fr, fcc = dem.frac_index(*rv)
            rng_m = c * np.hypot(rr - fr, cc - fcc)
            pool.append(np.column_stack([np.full(rr.size, i), rr, cc, uh, uv, rng_m, md[rr, cc]]))
        if cfg is None:
            raise Fail(f"{dem_id}: no rover position with an informative candidate")
        pool = np.vstack(pool)
        sel_s = time.perf_counter() - t0
        uh_all, ud_all = pool[:, 3], pool[:, 6]
        with np.errstate(divide="ignore"):
            logu = np.where(np.isfinite(ud_all) & (ud_all > 0), np.log(np.maximum(ud_all, 1e-300)), np.nan)
        noise_m, noise_k = float(cfg["noise_m"]), float(cfg["noise_k_per_m"])
        # only targets whose patch and window lie on known map cells (a summed-area table of the
        # missing cells), so the draw's strata hold what can be localized
        bad = np.pad(np.cumsum(np.cumsum(~np.isfinite(dem.z), 0), 1), ((1, 0), (1, 0)))
        hw = a.patch_cells // 2 + pad
        r0 = pool[:, 1].astype(np.int64) - hw
        c0 = pool[:, 2].astype(np.int64) - hw
        r1, c1 = r0 + 2 * hw + 1, c0 + 2 * hw + 1
        inside = (r0 >= 0) & (c0 >= 0) & (r1 <= dem.z.shape[0]) & (c1 <= dem.z.shape[1])
        r0, c0, r1, c1 = (np.clip(v, 0, m) for v, m in ((r0, dem.z.shape[0]), (c0, dem.z.shape[1]),
                                                         (r1, dem.z.shape[0]), (c1, dem.z.shape[1])))
        missing = bad[r1, c1] - bad[r0, c1] - bad[r1, c0] + bad[r0, c0]
        usable = inside & (missing == 0)
        draw, (lo, hi) = stratified_draw(rng, np.where(usable, logu, np.nan), a.cases)
        # the cases
        lines, cases = [], []
        for n, k in enumerate(draw):
            ri, tr, tc = int(pool[k, 0]), int(pool[k, 1]), int(pool[k, 2])
            rv = rovers[ri]
            off = float(rng.uniform(-50.0, 50.0))
            counts = None
            if fine is None:
                z, gt, _ = local_patch(dem, rv, (tr, tc), a.patch_cells, noise_m, noise_k, off, rng)
            else:
                z, gt, counts = binned_patch(fine, dem, rv, (tr, tc), a, noise_m, noise_k, off, rng)
            lp = os.path.join(tmp, f"local_{n:05d}.tif")
            write_patch(lp, z, gt, counts if a.counts else None)
            d = rng.uniform(-a.prior_cells, a.prior_cells, 2) * c
            prior = (rv[0] + float(d[0]), rv[1] + float(d[1]))
            lines.append(f"{lp} {prior[0]!r} {prior[1]!r} {a.window_cells * c!r}\n")
            cases.append({"rover": list(rv), "target_rc": [tr, tc], "range_m": float(pool[k, 5]),
                          "u_heights_m": float(pool[k, 3]), "u_voxel_m": float(pool[k, 4]),
                          "u_unbinned_m": float(pool[k, 6]),
                          "prior": list(prior), "offset_m": off})
        lst = os.path.join(tmp, "cases.txt")
        with open(lst, "w") as f:
            f.writelines(lines)
        gen_s = time.perf_counter() - t0 - sel_s
        t1 = time.perf_counter()
        res = localize_batch(a, path, lst, len(cases))
        loc_s = time.perf_counter() - t1
        # predictions from the map alone, for the drawn targets
        t2 = time.perf_counter()
        for cs, r in zip(cases, res):
            rv = cs["rover"]
            x, y = r.get("x_m"), r.get("y_m")
            if x is None or y is None:
                cs.update(ex_m=math.inf, ey_m=math.inf, err_m=math.inf)
            else:
                cs.update(ex_m=x - rv[0], ey_m=y - rv[1], err_m=math.hypot(x - rv[0], y - rv[1]))
            cs["right"] = cs["err_m"] <= RIGHT_CELLS * c
            cs["status"] = r.get("status", "error")
            fp = r.get("failure_probability")
            cs["failure_prob"] = float(fp) if fp is not None else math.nan
            cs["sigma_x_m"], cs["sigma_y_m"] = r.get("sigma_x_m"), r.get("sigma_y_m")
        fis_rel = map_predictions(dem, cases, a, noise_m, noise_k)
        pred_s = time.perf_counter() - t2
        meta = {"path": path, "cell_m": c, "rows": dem.z.shape[0], "cols": dem.z.shape[1],
                "character": dems.BY_ID[dem_id].character if dem_id in dems.BY_ID else "",
                "rovers": len(rovers), "rovers_with_candidates": n_sel, "candidates": int(len(pool)),
                "candidates_informative_heights": int(np.isfinite(uh_all).sum()),
                "candidates_informative_voxel": int(np.isfinite(pool[:, 4]).sum()),
                "candidates_usable": int(usable.sum()),
                "draw_log_range": [lo, hi], "map_config": cfg,
                "fisher_check_worst_rel": float(max(fis_rel)) if fis_rel else None,
                "fisher_check_median_rel": float(np.median(fis_rel)) if fis_rel else None,
                "time_s": {"select": sel_s, "cases": gen_s, "localize": loc_s, "predict": pred_s}}
        return {"meta": meta, "stats": stats(cases, c), "cases": cases}
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def at_competitor(cs, c):
    """Whether a wrong answer lies within 1 cell (Chebyshev) of the patch's most self-similar shift."""
    d = cs.get("best_competitor_cells")
    if d is None or not math.isfinite(cs["err_m"]):
        return False
    return max(abs(cs["ex_m"] / c - d[0]), abs(-cs["ey_m"] / c - d[1])) <= 1.0


def stats(cases, c):
    col = {k: np.array([cs[k] for cs in cases], dtype=np.float64)
           for k in ("u_heights_m", "u_voxel_m", "u_norep_m", "u_percell_m", "u_bilinear_m", "err_m", "ex_m", "ey_m", "failure_prob", "p_beat", "p_post",
                     "sigma_x_pred_m", "sigma_y_pred_m")}
    # the height prediction without the points a cell (the draw's; a run before it: the same)
    col["u_unbinned_m"] = np.array([cs.get("u_unbinned_m", cs["u_heights_m"]) for cs in cases], dtype=np.float64)
    right = np.array([cs["right"] for cs in cases], dtype=bool)
    wrong = ~right
    err = col["err_m"]
    fps = {"localizer_fp": col["failure_prob"], "p_beat": col["p_beat"], "p_post": col["p_post"]}
    out = {"n": len(cases), "right": int(right.sum()), "right_rate": float(right.mean()) if cases else None,
           "status": {s: sum(1 for cs in cases if cs["status"] == s) for s in sorted({cs["status"] for cs in cases})}}
    for name, key in (("heights", "u_heights_m"), ("voxel", "u_voxel_m"), ("heights_norep", "u_norep_m"),
                      ("heights_percell", "u_percell_m"), ("bilinear_percell", "u_bilinear_m"),
                      ("heights_unbinned", "u_unbinned_m")):
        u = col[key]
        d = {"spearman_all": spearman(u, err), "spearman_right": spearman(u[right], err[right]),
             "finite": int(np.isfinite(u).sum())}
        dec = decile_stats(u, col["ex_m"], col["ey_m"], right,
                           col["sigma_x_pred_m"] if name == "heights" else None,
                           col["sigma_y_pred_m"] if name == "heights" else None, fps)
        d["deciles"] = dec
        if name == "heights":
            rho = np.array([cs.get("rho_pred", 0.0) for cs in cases], dtype=np.float64)
            d["spearman_ideal"] = spearman_ideal(u, col["sigma_x_pred_m"], col["sigma_y_pred_m"], rho)
        rs = [x["ratio"] for x in dec if x.get("ratio") is not None]
        d["ratio_range"] = [min(rs), max(rs)] if rs else None
        d["deciles_in_band"] = int(sum(0.8 <= r <= 1.25 for r in rs))
        out[name] = d
    out["reliability"] = {k: reliability(v, wrong) for k, v in fps.items()}
    # the worst prediction of the wrong answers: how wrong they are
    w = [cs for cs in cases if not cs["right"]]
    out["wrong"] = {"n": len(w),
                    "median_err_cells": float(np.median([cs["err_m"] for cs in w])) / c if w else None,
                    "status": {s: sum(1 for cs in w if cs["status"] == s) for s in sorted({cs["status"] for cs in w})},
                    "median_p_beat": float(np.median([cs["p_beat"] for cs in w])) if w else None,
                    # the wrong answer within 1 cell (Chebyshev) of the map's most similar shift
                    "at_best_competitor": int(sum(1 for cs in w if at_competitor(cs, c))),
                    "median_localizer_fp": float(np.nanmedian([cs["failure_prob"] for cs in w])) if w else None}
    return out


# --- output -----------------------------------------------------------------------------
def fmt(v, spec):
    return "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


def print_dem(dem_id, r):
    m, s = r["meta"], r["stats"]
    print(f"\n{dem_id} ({m['character']}): {m['cols']} x {m['rows']} cells of {m['cell_m']:g} m; "
          f"{m['rovers']} rover positions, {m['candidates']} candidates ({m['candidates_informative_heights']} "
          f"informative heights, {m['candidates_informative_voxel']} voxel); {s['n']} cases; right "
          f"{100 * s['right_rate']:.1f} %; status {s['status']}")
    print(f"  time: select {m['time_s']['select']:.1f} s, cases {m['time_s']['cases']:.1f} s, localize "
          f"{m['time_s']['localize']:.1f} s, map-alone predictions {m['time_s']['predict']:.1f} s; "
          f"python Fisher vs raster: median {fmt(m['fisher_check_median_rel'], '.1e')}, worst "
          f"{fmt(m['fisher_check_worst_rel'], '.1e')}")
    for name in ("heights", "voxel", "heights_norep", "heights_percell", "bilinear_percell", "heights_unbinned"):
        if name not in s:  # a run's JSON from before the name was added
            continue
        d = s[name]
        ideal = f" (exact prediction {fmt(d['spearman_ideal'], '.3f')})" if d.get("spearman_ideal") is not None else ""
        print(f"  {name:15s} Spearman all {fmt(d['spearman_all'], '.3f')}{ideal}, right {fmt(d['spearman_right'], '.3f')}; "
              f"finite {d['finite']}; decile ratio {fmt(d['ratio_range'] and d['ratio_range'][0], '.2f')}-"
              f"{fmt(d['ratio_range'] and d['ratio_range'][1], '.2f')}, {d['deciles_in_band']} of "
              f"{len(d['deciles'])} in [0.8, 1.25]")
    print(f"  {'decile u (m)':>22s} {'n':>4s} {'right':>6s} {'ratio':>6s} {'r_x':>5s} {'r_y':>5s} "
          f"{'wrong':>6s} {'loc fp':>7s} {'P_beat':>7s} {'P_post':>7s}")
    for x in s["heights"]["deciles"]:
        print(f"  {x['lo']:10.4g}-{x['hi']:<10.4g} {x['n']:4d} {fmt(x['right_rate'], '6.3f')} "
              f"{fmt(x.get('ratio'), '6.2f')} {fmt(x.get('ratio_x'), '5.2f')} {fmt(x.get('ratio_y'), '5.2f')} "
              f"{fmt(x['wrong_rate'], '6.3f')} {fmt(x.get('localizer_fp_mean'), '7.3f')} "
              f"{fmt(x.get('p_beat_mean'), '7.3f')} {fmt(x.get('p_post_mean'), '7.3f')}")
    for name in ("heights_norep", "heights_percell", "bilinear_percell"):
        print(f"  {name} ratio per decile: " + " ".join(fmt(x.get("ratio"), ".2f") for x in s[name]["deciles"]))
    w = s["wrong"]
    print(f"  wrong answers: {w['n']}, median {fmt(w['median_err_cells'], '.2f')} cells off, status {w['status']}, "
          f"{w['at_best_competitor']} within 1 cell of the map's most similar shift; median P_beat "
          f"{fmt(w['median_p_beat'], '.3f')}, localizer fp {fmt(w['median_localizer_fp'], '.3f')}")
    for k, rel in s["reliability"].items():
        b = "  ".join(f"[{x['lo']:g},{x['hi']:g}) {x['n']}: {fmt(x['mean_predicted'], '.3f')}/{fmt(x['observed'], '.3f')}"
                      for x in rel["bins"] if x["n"])
        print(f"  reliability {k} (bin n: predicted/observed; Brier {fmt(rel['brier'], '.4f')}, "
              f"sum {rel['sum_predicted']:.1f} vs {rel['observed_wrong']} wrong): {b}")


def figure(res, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ids = list(res["dems"])
    n = len(ids)
    cols = min(3, n)
    rows = (n + cols - 1) // cols
    fig, axs = plt.subplots(rows, cols, figsize=(4.6 * cols, 4.2 * rows), squeeze=False)
    for ax, d in zip(axs.ravel(), ids):
        r = res["dems"][d]
        c = r["meta"]["cell_m"]
        u = np.array([cs["u_heights_m"] for cs in r["cases"]]) / math.sqrt(2.0)
        e = np.array([math.sqrt((cs["ex_m"] ** 2 + cs["ey_m"] ** 2) / 2.0) if math.isfinite(cs["err_m"]) else math.nan
                      for cs in r["cases"]])
        ok = np.array([cs["right"] for cs in r["cases"]])
        ax.loglog(u[ok] / c, e[ok] / c, ".", ms=2.5, color="tab:blue", alpha=0.5, label="right")
        ax.loglog(u[~ok] / c, e[~ok] / c, "x", ms=3.5, color="tab:red", alpha=0.7, label="wrong (> 1.5 cells)")
        dec = r["stats"]["heights"]["deciles"]
        px = [x["pred_axis_m"] / c for x in dec if x.get("ratio")]
        py = [x["rms_axis_m"] / c for x in dec if x.get("ratio")]
        ax.loglog(px, py, "o-", color="k", ms=4, label="decile RMS (right)")
        lo = np.nanmin(np.concatenate([u[ok] / c, e[ok][e[ok] > 0] / c])) if ok.any() else 1e-3
        hi = max(np.nanmax(u / c), 3.0)
        ax.loglog([lo, hi], [lo, hi], "--", color="0.5", lw=1, label="1:1")
        ax.axhline(RIGHT_CELLS / math.sqrt(2), color="tab:red", lw=0.6, ls=":")
        h = r["stats"]["heights"]
        ax.set_title(f"{d} ({c:g} m): Spearman {fmt(h['spearman_all'], '.2f')} "
                     f"(voxel {fmt(r['stats']['voxel']['spearman_all'], '.2f')})", fontsize=9)
        ax.set_xlabel("predicted per-axis sigma u/sqrt(2) (cells)", fontsize=8)
        ax.set_ylabel("achieved per-axis error |e|/sqrt(2) (cells)", fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in axs.ravel()[n:]:
        ax.axis("off")
    axs.ravel()[0].legend(fontsize=7, loc="upper left")
    fig.suptitle("The height matcher's predicted uncertainty against its achieved error", fontsize=10)
    fig.tight_layout()
    path = os.path.join(out, "predict_vs_achieved.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def finite(v):
    if isinstance(v, dict):
        return {k: finite(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [finite(x) for x in v]
    if isinstance(v, (float, np.floating)):
        return float(v) if math.isfinite(v) else None
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, np.bool_):
        return bool(v)
    return v


def parse_args(argv):
    ap = Parser(prog="predict_study.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("--dem", action="append", help=f"DEM id (repeatable; default {' '.join(DEFAULT_DEMS)})")
    ap.add_argument("--cases", type=int, default=1000, help="localizations per DEM (default 1000)")
    ap.add_argument("--rovers", type=int, default=50, help="rover positions per DEM (default 50)")
    ap.add_argument("--seed", type=int, default=36, help="seed (default 36)")
    ap.add_argument("--patch-cells", type=int, default=21, help="patch side, cells, odd (default 21)")
    ap.add_argument("--min-range-cells", type=float, default=12.0, help="nearest target, cells (default 12)")
    ap.add_argument("--max-range-cells", type=int, default=40, help="farthest target, cells (default 40)")
    ap.add_argument("--footprint-cells", type=float, default=1.0, help="rover footprint radius, cells (default 1)")
    ap.add_argument("--prior-cells", type=float, default=2.0, help="prior error bound per axis, cells (default 2)")
    ap.add_argument("--window-cells", type=int, default=5, help="search window half-width, cells (default 5)")
    ap.add_argument("--map-sigma-m", type=float, default=0.0,
                    help="the map's height error told to the height prediction (--global-sigma-m; default 0: "
                         "the local maps are sampled from the map itself)")
    ap.add_argument("--truth-fine", type=int, default=1,
                    help="K >= 2: the map is the DEM's K x K block mean and each local map the rover's "
                         "binned stereo points of the DEM, K^2 a cell on average (default 1: the DEM "
                         "sampled at the cells)")
    ap.add_argument("--counts", action="store_true",
                    help="with --truth-fine K: the rover passes its cells' point counts (localize "
                         "--count-band) and the prediction is told K^2 points a cell (select "
                         "--points-per-cell)")
    ap.add_argument("--trn", default=os.path.join(dems.ROOT, "build", "host-release", "trn"))
    ap.add_argument("--out", default=os.path.join(dems.BUILD, "predict"), help="output folder (default build/real/predict)")
    ap.add_argument("--no-plot", action="store_true")
    ap.add_argument("--smoke", action="store_true", help="60 cases from 12 positions on the rock field")
    ap.add_argument("--reanalyse", metavar="JSON", help="recompute the map-alone predictions and the statistics "
                                                         "of a predict.json (no trn run)")
    a = ap.parse_args(argv)
    if a.smoke:
        a.dem = a.dem or ["rockfield"]
        a.cases, a.rovers = 60, 12
    a.dem = a.dem or list(DEFAULT_DEMS)
    for d in a.dem:
        if d not in dems.BY_ID:
            raise Fail(f"unknown DEM '{d}' (known: {', '.join(dems.BY_ID)})")
    if a.cases < 10 or a.rovers < 1:
        raise Fail("--cases must be >= 10 and --rovers >= 1")
    if a.patch_cells < 3 or a.patch_cells % 2 == 0:
        raise Fail(f"--patch-cells {a.patch_cells}: must be odd and >= 3")
    if not 0 <= a.min_range_cells < a.max_range_cells:
        raise Fail("--min-range-cells must be in [0, --max-range-cells)")
    if a.window_cells < FAIL_ZONE_CELLS or a.prior_cells < 0 or a.prior_cells >= a.window_cells:
        raise Fail("--window-cells must be >= 2 and above --prior-cells >= 0")
    if not (a.map_sigma_m >= 0 and math.isfinite(a.map_sigma_m)):
        raise Fail(f"--map-sigma-m {a.map_sigma_m}: must be finite and >= 0")
    if a.truth_fine < 1 or a.truth_fine > 16:
        raise Fail(f"--truth-fine {a.truth_fine}: must be in 1..16")
    if a.counts and a.truth_fine < 2:
        raise Fail("--counts needs --truth-fine K >= 2 (a binned local map)")
    if a.reanalyse:
        if not os.path.isfile(a.reanalyse):
            raise Fail(f"--reanalyse {a.reanalyse}: no such file")
        return a
    if not (os.path.isfile(a.trn) and os.access(a.trn, os.X_OK)):
        raise Fail(f"trn binary {a.trn} not found or not executable (cmake --build --preset host-release)")
    return a


def write_results(res, out):
    os.makedirs(out, exist_ok=True)
    pj = os.path.join(out, "predict.json")
    with open(pj + ".part", "w") as f:
        json.dump(finite(res), f, indent=1)
    os.replace(pj + ".part", pj)
    return pj


def reanalyse(a):
    """Recompute the predictions from the map alone and the statistics of a predict.json (its
    trn results kept), e.g. after a change of this script's own predictions."""
    with open(a.reanalyse) as f:
        res = json.load(f)
    for k, v in res["config"].items():
        if k not in ("trn",):
            setattr(a, k, v)
    for d, r in res["dems"].items():
        dem = casemod.read_dem(r["meta"]["path"])
        cfg = r["meta"]["map_config"]
        for cs in r["cases"]:
            for k in ("ex_m", "ey_m", "err_m", "failure_prob", "u_heights_m", "u_voxel_m"):
                cs[k] = math.inf if cs.get(k) is None and k != "failure_prob" else (
                    math.nan if cs.get(k) is None else cs[k])
        fis = map_predictions(dem, r["cases"], a, float(cfg["noise_m"]), float(cfg["noise_k_per_m"]))
        r["meta"]["fisher_check_worst_rel"] = float(max(fis)) if fis else None
        r["meta"]["fisher_check_median_rel"] = float(np.median(fis)) if fis else None
        r["stats"] = stats(r["cases"], dem.c)
        print_dem(d, r)
    return res


def main(argv):
    try:
        a = parse_args(argv)
        if a.reanalyse:
            res = reanalyse(a)
        else:
            res = {"config": {k: getattr(a, k) for k in ("cases", "rovers", "seed", "patch_cells",
                                                          "min_range_cells", "max_range_cells", "footprint_cells",
                                                          "prior_cells", "window_cells", "map_sigma_m",
                                                          "truth_fine", "counts", "trn")},
                   "dems": {}}
            for d in a.dem:
                print(f"predict_study: {d} ...", file=sys.stderr, flush=True)
                r = study_dem(a, d)
                res["dems"][d] = r
                print_dem(d, r)
                write_results(res, a.out)  # after each DEM: a long run keeps what it has done
        pj = write_results(res, a.out)
        print(f"\nresults: {pj}")
        if not a.no_plot:
            print(f"figure: {figure(res, a.out)}")
        if a.smoke:
            for d, r in res["dems"].items():
                s = r["stats"]
                if s["n"] < 0.9 * a.cases or s["heights"]["spearman_all"] is None:
                    raise Fail(f"smoke: {d}: {s['n']} of {a.cases} cases localized")
        return 0
    except (Fail, casemod.InputError) as e:
        print(f"predict_study: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
