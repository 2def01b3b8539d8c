# SPDX-License-Identifier: Apache-2.0
"""tools/real/peers.py - the two peer localizers of the real-terrain benchmark.

Both search the integer poses of the global grid whose cell centre lies within
prior +- window (per axis): a pose (row, col) puts the local map's centre cell (the
rover) on global cell (row, col). Both return the rover's map position (metres)
after a sub-cell fit, and the integer pose.

* ssd: sum over the seen cells of squared differences of mean-removed heights
  (local minus global at the pose; global cells that are missing drop out of that
  pose's sum), argmin, then a 1-D parabola through the minimum and its two
  neighbours on each axis (offset clamped to +-0.5 cell; none at the window edge).
* ncc: OpenCV cv2.matchTemplate(TM_CCOEFF_NORMED) with the local DEM as template
  (unseen cells excluded with the mask argument when this OpenCV supports it for
  TM_CCOEFF_NORMED, else filled with the mean of the seen ones) on the global crop
  covering the window (missing cells filled with the crop's mean), both float32;
  argmax, then the same per-axis parabola through the peak.

The per-axis parabola is biased where the score's bowl is elongated obliquely (its
x-y cross term; up to ~0.5 cell on noiseless terrain with a dominant ridge
direction); fit="quad2d" (bench_real.py --subcell quad2d) uses the 3 x 3 quadratic
with the cross term instead.
"""
import math

import numpy as np

try:
    import cv2
except ImportError:  # reported by the benchmark
    cv2 = None


def window_poses(dem, prior, window_m, radius):
    """Integer pose range (r0, r1, c0, c1), inclusive, clipped so the local map fits."""
    fr, fc = dem.frac_index(*prior)
    w = window_m / dem.c
    r0 = max(int(math.ceil(fr - w - 1e-9)), radius)
    r1 = min(int(math.floor(fr + w + 1e-9)), dem.z.shape[0] - 1 - radius)
    c0 = max(int(math.ceil(fc - w - 1e-9)), radius)
    c1 = min(int(math.floor(fc + w + 1e-9)), dem.z.shape[1] - 1 - radius)
    if r1 < r0 or c1 < c0:
        raise ValueError("window off the map")
    return r0, r1, c0, c1


def parabola(sm, s0, sp):
    """Vertex offset of the parabola through (-1, sm), (0, s0), (1, sp), in
    [-0.5, 0.5]; 0 if not a proper extremum. Works for minima and maxima alike."""
    den = sm - 2.0 * s0 + sp
    if not np.isfinite(den) or den == 0.0:
        return 0.0
    d = 0.5 * (sm - sp) / den
    if not np.isfinite(d):
        return 0.0
    return float(min(0.5, max(-0.5, d)))


def subcell(score, i, j, sign, fit="axis"):
    """Sub-cell offset (rows, cols) at (i, j) of a score surface; sign +1 minimum,
    -1 maximum. fit "axis": one parabola per axis (the peers' definition); "quad2d":
    the 2-D quadratic of the 3 x 3 neighbourhood (with its cross term, so unbiased on
    elongated bowls; falls back to "axis" when not a proper extremum)."""
    s = sign * score
    if fit == "quad2d" and 0 < i < s.shape[0] - 1 and 0 < j < s.shape[1] - 1:
        w = s[i - 1:i + 2, j - 1:j + 2]
        g = np.array([w[2, 1] - w[0, 1], w[1, 2] - w[1, 0]]) / 2
        hrr = w[2, 1] - 2 * w[1, 1] + w[0, 1]
        hcc = w[1, 2] - 2 * w[1, 1] + w[1, 0]
        hrc = (w[2, 2] - w[2, 0] - w[0, 2] + w[0, 0]) / 4
        det = hrr * hcc - hrc * hrc
        if np.isfinite(det) and det > 0 and hrr > 0:
            d = -np.linalg.solve(np.array([[hrr, hrc], [hrc, hcc]]), g)
            if np.all(np.abs(d) <= 1.0):
                return float(d[0]), float(d[1])
    di = dj = 0.0
    if 0 < i < s.shape[0] - 1 and s[i - 1, j] >= s[i, j] <= s[i + 1, j]:
        di = parabola(s[i - 1, j], s[i, j], s[i + 1, j])
    if 0 < j < s.shape[1] - 1 and s[i, j - 1] >= s[i, j] <= s[i, j + 1]:
        dj = parabola(s[i, j - 1], s[i, j], s[i, j + 1])
    return di, dj


def _crop(dem, poses, radius):
    r0, r1, c0, c1 = poses
    return dem.z[r0 - radius:r1 + radius + 1, c0 - radius:c1 + radius + 1]


def ssd(dem, local, seen, prior, window_m, fit="axis"):
    """SSD + parabola peer. Returns (x, y, (row, col)) or None."""
    R = (local.shape[0] - 1) // 2
    poses = window_poses(dem, prior, window_m, R)
    crop = _crop(dem, poses, R)
    win = np.lib.stride_tricks.sliding_window_view(crop, local.shape)  # (nr, nc, 2R+1, 2R+1)
    m = seen[None, None] & np.isfinite(win)
    n = m.sum(axis=(2, 3)).astype(np.float64)
    L = np.where(seen, local, 0.0)
    g = np.where(m, win, 0.0)
    # mean-removed over each pose's common cells: sum (l - lbar - g + gbar)^2
    sl = (m * L).sum(axis=(2, 3))
    sg = g.sum(axis=(2, 3))
    sll = (m * L * L).sum(axis=(2, 3))
    sgg = (g * g).sum(axis=(2, 3))
    slg = (g * L).sum(axis=(2, 3))
    with np.errstate(invalid="ignore", divide="ignore"):
        d = sl - sg
        score = (sll - 2 * slg + sgg) - d * d / n
        score = score / n  # per cell, so poses with fewer cells compare fairly
    score[n < 0.5 * seen.sum()] = np.inf
    if not np.isfinite(score).any():
        return None
    i, j = np.unravel_index(np.argmin(score), score.shape)
    di, dj = subcell(np.where(np.isfinite(score), score, np.nanmax(score[np.isfinite(score)])), i, j, 1, fit)
    row, col = poses[0] + i, poses[2] + j
    x, y = dem.xy(row + di, col + dj)
    return x, y, (int(row), int(col))


_MASK_OK = None


def mask_supported():
    """Whether cv2.matchTemplate takes a mask with TM_CCOEFF_NORMED (and gets it right)."""
    global _MASK_OK
    if _MASK_OK is None:
        rng = np.random.default_rng(0)
        img = rng.standard_normal((40, 40)).astype(np.float32)
        tpl = img[10:21, 12:23].copy()
        mask = np.ones_like(tpl)
        mask[:5] = 0
        tpl[:5] = 1e3  # must be ignored
        try:
            res = cv2.matchTemplate(img, tpl, cv2.TM_CCOEFF_NORMED, mask=mask)
            _MASK_OK = bool(np.isfinite(res).all()
                            and np.unravel_index(np.argmax(res), res.shape) == (10, 12)
                            and abs(res[10, 12] - 1) < 1e-3)
        except cv2.error:
            _MASK_OK = False
    return _MASK_OK


def ncc(dem, local, seen, prior, window_m, fit="axis"):
    """OpenCV TM_CCOEFF_NORMED + parabola peer. Returns (x, y, (row, col)) or None."""
    R = (local.shape[0] - 1) // 2
    poses = window_poses(dem, prior, window_m, R)
    crop = _crop(dem, poses, R)
    fin = np.isfinite(crop)
    if not fin.any() or not seen.any():
        return None
    img = np.where(fin, crop, crop[fin].mean()).astype(np.float32)
    mean_seen = float(local[seen].mean())
    tpl = np.where(seen, local, mean_seen).astype(np.float32)
    if mask_supported():
        res = cv2.matchTemplate(img, tpl, cv2.TM_CCOEFF_NORMED, mask=seen.astype(np.float32))
    else:
        res = cv2.matchTemplate(img, tpl, cv2.TM_CCOEFF_NORMED)
    res = np.where(np.isfinite(res), res, -np.inf)
    if not np.isfinite(res).any():
        return None
    i, j = np.unravel_index(np.argmax(res), res.shape)
    fill = res[np.isfinite(res)].min()
    di, dj = subcell(np.where(np.isfinite(res), res, fill).astype(np.float64), i, j, -1, fit)
    row, col = poses[0] + i, poses[2] + j
    x, y = dem.xy(row + di, col + dj)
    return x, y, (int(row), int(col))


PEERS = {"ssd": ssd, "ncc": ncc}
