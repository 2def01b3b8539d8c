#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/real/interp_study.py - the pose error the map's interpolant alone causes.

    /usr/bin/python3 tools/real/interp_study.py [--dem ID ...] [--k K] [--radius R]
        [--cases N] [--seed S] [--local mean|point] [--map mean|point]
        [--interp NAME ...] [--bias-ref NAME ...] [--json PATH]

No trn run, no noise. The map is the K x K block mean (--map mean) or the point samples every
K cells (--map point) of a DEM; the rover's local cells, at a random sub-cell position within
the map's cells and a 120-degree wedge of radius R, are the true surface's area mean over each
cell (--local mean: (2K)^2 bilinear sub-samples of the DEM; a rover that bins its points) or its
value at the cell's centre (--local point). At the truth the local cells differ from the map's
interpolant I by e = local - I. The pose error that e alone makes is the Gauss-Newton step of
(x, y, dz) from the truth, dp = (J^T J)^-1 J^T e, J the interpolant's gradients and a column of
ones; "with the mix" adds the column I - bilinear (the refinement's mix, docs/method.md 9.2).

Per DEM and interpolant it prints, per axis, in map cells:

* err: the RMS of dp over the cases (with the mix fitted: err+mix);
* indep, block4: what a covariance of independent errors, or of errors correlated within
  4 x 4-cell blocks, predicts from the true e (the sandwiches (J^T J)^-1 (sum J e e J^T)
  (J^T J)^-1): short of err when e is common to the cells, a bias of the pose;
* shift and corr: the RMS of the interpolants' shift (the step that I - bilinear makes, the
  refinement's interp_shift) and its correlation with dp;
* lock: the amplitude A of the fit dp = A sin(2 pi f) + B cos(2 pi f), f the truth's sub-cell
  position along the axis: the part of the error that only the sub-cell position decides;
* with --bias-ref REF (repeatable): the error predicted from the map alone, the step
  (J^T J)^-1 J^T (REF - I) that the reference interpolant's heights make at the local cells
  (what dp would be were REF the truth): its RMS (pred), its correlation with dp, the slope
  of dp on it through 0, and the RMS of dp less the prediction (resid; below err where the
  prediction could remove the error).

Interpolants (--interp, repeatable; default keys spline3): bilinear, keys (cubic
convolution, a = -1/2: the refinement's), spline3 and spline5 (the interpolating cubic and
quintic B-splines: coefficients by the inverse filter of the sampled B-spline along each row,
then each column, the map mirrored at its edges; numpy only).

Exit 0, or 1 with one line on bad input.
"""
import argparse
import json
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

INTERPS = ("bilinear", "keys", "spline3", "spline5")


class InputError(Exception):
    """Bad input: exit 1 with this one-line reason."""


def keys_w(t):
    """Keys' cubic convolution kernel, a = -1/2."""
    u = np.abs(t)
    return np.where(u < 1.0, 1.5 * u ** 3 - 2.5 * u ** 2 + 1.0,
                    np.where(u < 2.0, -0.5 * u ** 3 + 2.5 * u ** 2 - 4.0 * u + 2.0, 0.0))


# The poles of the sampled cubic and quintic B-splines' inverse filters.
POLES = {3: (math.sqrt(3.0) - 2.0,), 5: (-0.4305753470999738, -0.04309628820326465)}


def prefilter(z, order):
    """B-spline coefficients of z (rows, cols): the gain and one causal and one anti-causal
    recursion per pole along each axis, whole-sample mirror at the ends (the causal start
    summed over 60 terms of the mirrored line, |z|^60 < 1e-21)."""
    c = np.array(z, float)
    for axis in (1, 0):
        c = np.moveaxis(c, axis, 0)  # filter along the first axis, every line at once
        n = c.shape[0]
        for zp in POLES[order]:
            c *= (1.0 - zp) * (1.0 - 1.0 / zp)
            idx = np.arange(60)
            per = 2 * n - 2
            mir = idx % per
            mir = np.where(mir < n, mir, per - mir)
            c0 = np.tensordot(zp ** idx, c[mir], axes=(0, 0))
            c[0] = c0
            for i in range(1, n):
                c[i] = c[i] + zp * c[i - 1]
            c[n - 1] = (zp / (zp * zp - 1.0)) * (c[n - 1] + zp * c[n - 2])
            for i in range(n - 2, -1, -1):
                c[i] = zp * (c[i + 1] - c[i])
        c = np.moveaxis(c, 0, axis)
    return c


def bspline(t, order):
    """The centred cubic or quintic B-spline at t."""
    u = np.abs(t)
    if order == 3:
        return np.where(u < 1.0, 2.0 / 3.0 - u ** 2 + u ** 3 / 2.0,
                        np.where(u < 2.0, (2.0 - u) ** 3 / 6.0, 0.0))
    return np.where(u < 1.0, 11.0 / 20.0 - u ** 2 / 2.0 + u ** 4 / 4.0 - u ** 5 / 12.0,
                    np.where(u < 2.0, 17.0 / 40.0 + 5.0 * u / 8.0 - 7.0 * u ** 2 / 4.0 +
                             5.0 * u ** 3 / 4.0 - 3.0 * u ** 4 / 8.0 + u ** 5 / 24.0,
                             np.where(u < 3.0, (3.0 - u) ** 5 / 120.0, 0.0)))


class Surface:
    """A grid z (rows, cols) read between its cells by one interpolant; values at (r, c)
    arrays (fractional row, column); the caller keeps them 3 cells inside the grid."""

    def __init__(self, z, name):
        if name not in INTERPS:
            raise InputError(f"unknown interpolant {name!r} (one of {', '.join(INTERPS)})")
        self.z, self.name = np.asarray(z, float), name
        self.order = int(name[-1]) if name.startswith("spline") else 0
        self.coef = prefilter(self.z, self.order) if self.order else None

    def _conv(self, r, c, w, grid, lo, hi):
        r0, c0 = np.floor(r).astype(int), np.floor(c).astype(int)
        out = np.zeros(r.shape)
        for j in range(lo, hi + 1):
            wy = w(r - (r0 + j))
            for i in range(lo, hi + 1):
                out += wy * w(c - (c0 + i)) * grid[r0 + j, c0 + i]
        return out

    def __call__(self, r, c):
        r, c = np.asarray(r, float), np.asarray(c, float)
        if self.name == "bilinear":
            r0, c0 = np.floor(r).astype(int), np.floor(c).astype(int)
            fr, fc = r - r0, c - c0
            z = self.z
            return ((1 - fr) * ((1 - fc) * z[r0, c0] + fc * z[r0, c0 + 1]) +
                    fr * ((1 - fc) * z[r0 + 1, c0] + fc * z[r0 + 1, c0 + 1]))
        if self.name == "keys":
            return self._conv(r, c, keys_w, self.z, -1, 2)
        half = (self.order + 1) // 2
        return self._conv(r, c, lambda t: bspline(t, self.order), self.coef, 1 - half, half)

    def grad(self, r, c, h=1e-4):
        """Central differences of the interpolant (its gradient where it is smooth)."""
        return ((self(r + h, c) - self(r - h, c)) / (2 * h),
                (self(r, c + h) - self(r, c - h)) / (2 * h))


def coarse(fine, k, kind):
    """The map: the K x K block mean of fine (kind mean) or its samples every K cells at the
    blocks' centre cells (point); and the fine coordinate of coarse cell 0's centre."""
    rows, cols = fine.shape[0] // k, fine.shape[1] // k
    f = fine[:rows * k, :cols * k]
    if kind == "mean":
        return f.reshape(rows, k, cols, k).mean(axis=(1, 3)), (k - 1) / 2.0
    return f[k // 2::k, k // 2::k][:rows, :cols], float(k // 2)


def bilinear_fine(fine, r, c):
    r0, c0 = np.floor(r).astype(int), np.floor(c).astype(int)
    fr, fc = r - r0, c - c0
    return ((1 - fr) * ((1 - fc) * fine[r0, c0] + fc * fine[r0, c0 + 1]) +
            fr * ((1 - fc) * fine[r0 + 1, c0] + fc * fine[r0 + 1, c0 + 1]))


def study(fine, k, radius, cases, seed, local, maptype, interps, refs=()):
    """The statistics above for one fine DEM (2-D array, NaN unknown); a dict per interpolant.
    refs: the reference interpolants of the predicted error (--bias-ref)."""
    if k < 1 or radius < 2 or cases < 4:
        raise InputError("need K >= 1, R >= 2 and at least 4 cases")
    known = np.isfinite(fine)
    if not known.any():
        raise InputError("the DEM has no known cell")
    m, off = coarse(fine, k, maptype)
    ok = np.isfinite(m)
    margin = radius + 6
    if min(m.shape) < 2 * margin + 2:
        raise InputError(f"the map ({m.shape[0]} x {m.shape[1]} cells at K = {k}) is too small "
                         f"for R = {radius}")
    # unknown cells filled with the mean for the splines' prefilter; truths are drawn where
    # the map is known 12 cells beyond the local map (a spline's coefficients feel a filled
    # cell d cells away by 0.27^d, the quintic's by 0.43^d)
    fill = float(np.mean(m[ok]))
    m = np.where(ok, m, fill)
    fine = np.where(known, fine, float(np.mean(fine[known])))
    surf = {n: Surface(m, n) for n in list(interps) + [r for r in refs if r not in interps]}
    bil = Surface(m, "bilinear")
    a, b = np.mgrid[-radius:radius + 1, -radius:radius + 1]
    rng = np.random.default_rng(seed)
    sub = (np.arange(2 * k) + 0.5) / (2 * k) - 0.5
    rows = {n: [] for n in interps}
    pad = radius + 12
    for _ in range(cases):
        for _try in range(1000):
            tr = rng.uniform(margin, m.shape[0] - margin - 1)
            tc = rng.uniform(margin, m.shape[1] - margin - 1)
            r0, c0 = int(tr), int(tc)
            if ok[max(0, r0 - pad):r0 + pad + 2, max(0, c0 - pad):c0 + pad + 2].all():
                break
        else:
            raise InputError("no place on the map where it is known around a local map")
        az = rng.uniform(0.0, 2.0 * math.pi)
        ang = (np.arctan2(a, b) - az + math.pi) % (2.0 * math.pi) - math.pi
        seen = (np.hypot(a, b) <= radius) & (np.hypot(a, b) >= 1.5) & (np.abs(ang) <= math.pi / 3)
        rr, cc = tr + a[seen], tc + b[seen]
        if local == "mean":
            loc = np.zeros(rr.size)
            for du in sub:
                for dv in sub:
                    loc += bilinear_fine(fine, k * (rr + du) + off, k * (cc + dv) + off)
            loc /= sub.size ** 2
        else:
            loc = bilinear_fine(fine, k * rr + off, k * cc + off)
        blk = ((a[seen] + radius) // 4) * 1000 + (b[seen] + radius) // 4
        for n in interps:
            s = surf[n]
            val = s(rr, cc)
            gr, gc = s.grad(rr, cc)
            e = loc - val
            J = np.c_[gr, gc, np.ones_like(gr)]
            H = np.linalg.inv(J.T @ J)
            dp = H @ (J.T @ e)
            indep = H @ ((J * (e ** 2)[:, None]).T @ J) @ H
            meat = np.zeros((3, 3))
            for key in np.unique(blk):
                g = J[blk == key].T @ e[blk == key]
                meat += np.outer(g, g)
            block = H @ meat @ H
            mixcol = val - bil(rr, cc)
            J4 = np.c_[J, mixcol]
            dp4 = np.linalg.lstsq(J4, e, rcond=None)[0]
            shift = -(H @ (J.T @ mixcol))  # the step from this interpolant to the bilinear one
            pred = []
            for ref in refs:  # the step were the reference the truth
                bp = H @ (J.T @ (surf[ref](rr, cc) - val))
                pred += [bp[0], bp[1]]
            rows[n].append((tr % 1.0, tc % 1.0, dp[0], dp[1], dp4[0], dp4[1], indep[0, 0],
                            indep[1, 1], block[0, 0], block[1, 1], shift[0], shift[1], *pred))
    out = {}
    for n in interps:
        x = np.array(rows[n])
        res = {}
        for ax, name in ((0, "row"), (1, "col")):
            dp, frac, sh = x[:, 2 + ax], x[:, ax], x[:, 10 + ax]
            fit = np.linalg.lstsq(np.c_[np.sin(2 * math.pi * frac), np.cos(2 * math.pi * frac)], dp,
                                  rcond=None)[0]
            res[name] = {
                "err": float(np.sqrt(np.mean(dp ** 2))),
                "err_mix": float(np.sqrt(np.mean(x[:, 4 + ax] ** 2))),
                "indep": float(np.sqrt(np.mean(x[:, 6 + ax]))),
                "block4": float(np.sqrt(np.mean(x[:, 8 + ax]))),
                "shift": float(np.sqrt(np.mean(sh ** 2))),
                "corr": float(np.corrcoef(dp, sh)[0, 1]) if np.std(sh) > 0 and np.std(dp) > 0 else 0.0,
                "lock": float(fit[0]),
            }
            for i, ref in enumerate(refs):
                p = x[:, 12 + 2 * i + ax]
                res[name]["pred_" + ref] = {
                    "pred": float(np.sqrt(np.mean(p ** 2))),
                    "corr": float(np.corrcoef(dp, p)[0, 1]) if np.std(p) > 0 and np.std(dp) > 0
                    else 0.0,
                    "slope": float(np.sum(p * dp) / np.sum(p * p)) if np.any(p != 0) else 0.0,
                    "resid": float(np.sqrt(np.mean((dp - p) ** 2))),
                }
        out[n] = res
    return out


def parse_args(argv):
    ap = argparse.ArgumentParser(description="tools/real/interp_study.py - the pose error the "
                                 "map's interpolant alone causes (no trn run, no noise).")
    ap.add_argument("--dem", action="append", help="DEM id of tools/real/dems.py (repeatable; "
                    "default rockfield jacksboro kossou)")
    ap.add_argument("--k", type=int, default=2, help="map cell in DEM cells (default 2)")
    ap.add_argument("--radius", type=int, default=20, help="local radius, map cells (default 20)")
    ap.add_argument("--cases", type=int, default=60, help="cases per DEM (default 60)")
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--local", choices=("mean", "point"), default="mean")
    ap.add_argument("--map", choices=("mean", "point"), default="mean")
    ap.add_argument("--interp", action="append", help=f"one of {', '.join(INTERPS)} (repeatable; "
                    "default keys spline3)")
    ap.add_argument("--bias-ref", action="append", default=[], help="a reference interpolant "
                    "whose heights predict the error (repeatable; none by default)")
    ap.add_argument("--json", help="write the statistics here")
    return ap.parse_args(argv)


def main(argv):
    a = parse_args(argv)
    interps = a.interp or ["keys", "spline3"]
    try:
        for n in interps + a.bias_ref:
            if n not in INTERPS:
                raise InputError(f"unknown interpolant {n!r} (one of {', '.join(INTERPS)})")
        import cases as cm
        import dems
        allres = {}
        for d in a.dem or ["rockfield", "jacksboro", "kossou"]:
            try:
                path = dems.get(d)
            except Exception as e:  # a recipe failed or an unknown id: name it
                raise InputError(f"DEM {d}: {e}")
            fine = cm.read_dem(path).z.astype(float)
            res = study(fine, a.k, a.radius, a.cases, a.seed, a.local, a.map, interps, a.bias_ref)
            allres[d] = res
            for n in interps:
                for ax in ("row", "col"):
                    r = res[n][ax]
                    print(f"{d} {a.local}/{a.map} K={a.k} R={a.radius} {n:8s} {ax}: err {r['err']:.4f} "
                          f"err+mix {r['err_mix']:.4f} indep {r['indep']:.4f} block4 {r['block4']:.4f} "
                          f"shift {r['shift']:.4f} corr {r['corr']:+.2f} lock {r['lock']:+.4f}" +
                          "".join(f" | {ref}: pred {r['pred_' + ref]['pred']:.4f} corr "
                                  f"{r['pred_' + ref]['corr']:+.2f} slope "
                                  f"{r['pred_' + ref]['slope']:.2f} resid "
                                  f"{r['pred_' + ref]['resid']:.4f}" for ref in a.bias_ref))
        if a.json:
            with open(a.json, "w") as f:
                json.dump({"args": vars(a), "results": allres}, f, indent=1)
    except InputError as e:
        print(f"interp_study: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
