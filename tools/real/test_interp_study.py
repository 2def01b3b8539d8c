#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/real/test_interp_study.py - self-test of tools/real/interp_study.py.

    /usr/bin/python3 tools/real/test_interp_study.py   # exit 0: all checks passed

* the splines interpolate: at the map's cells each spline equals the heights (the prefilter
  inverts the sampled B-spline; checked on random heights, to 1e-9);
* the cubic spline reproduces a cubic surface 14 cells inside the map (to 1e-7: the mirrored
  edges' effect falls by 3.7 a cell), Keys' kernel only quadratics (its error on the cubic is
  above 1e-4);
* a DEM that is the bilinear surface of a coarse grid, its points as the local map and the
  coarse grid as the map: the bilinear interpolant's pose error is 0 (below 1e-9 cells), Keys'
  is not (above 1e-4): the study finds an interpolant's error where there is one and none where
  there is none;
* Keys' kernel turns every frequency by the same phase as the bilinear one (at sub-cell
  positions 0.05-0.95 and 0.1-3 radians a cell, to 1e-12): the two differ only in how much of
  each frequency they keep;
* a DEM that is the cubic spline's surface of a coarse grid (K = 16, the map its point
  samples): the error that --bias-ref spline3 predicts for Keys' kernel is the error (the
  correlation above 0.95, what is left below a fifth of it);
* bad input: an unknown interpolant, K = 0, a map too small for the radius.
"""
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import interp_study as st  # noqa: E402


def check(cond, what):
    if not cond:
        sys.exit(f"test_interp_study: FAILED: {what}")
    print(f"test_interp_study: ok: {what}")


def main():
    rng = np.random.default_rng(1)
    z = rng.normal(size=(40, 50))
    for name in ("spline3", "spline5"):
        s = st.Surface(z, name)
        rr, cc = np.mgrid[3:37, 3:47]
        err = float(np.max(np.abs(s(rr.astype(float), cc.astype(float)) - z[3:37, 3:47])))
        check(err < 1e-9, f"{name} passes through every height ({err:.1e})")
    rr, cc = np.mgrid[0:48, 0:48].astype(float)
    cubic = lambda r, c: 0.01 * (r - 20) ** 3 - 0.02 * (r - 20) * (c - 24) ** 2 + 0.1 * r * c
    s3, sk = st.Surface(cubic(rr, cc), "spline3"), st.Surface(cubic(rr, cc), "keys")
    pr, pc = rng.uniform(14, 33, 500), rng.uniform(14, 33, 500)
    e3 = float(np.max(np.abs(s3(pr, pc) - cubic(pr, pc))))
    ek = float(np.max(np.abs(sk(pr, pc) - cubic(pr, pc))))
    check(e3 < 1e-7, f"the cubic spline reproduces a cubic inside the map ({e3:.1e})")
    check(ek > 1e-4, f"Keys' kernel does not ({ek:.1e})")
    # a fine DEM that is the bilinear surface of a coarse grid (K = 2, nodes at fine 2 i + 1)
    k, n = 2, 70
    coarse = rng.normal(size=(n, n))
    f = (np.arange(k * n) - k // 2) / k
    f = np.clip(f, 0, n - 1 - 1e-9)
    i0 = np.floor(f).astype(int)
    t = f - i0
    rows = (1 - t)[:, None] * coarse[i0, :] + t[:, None] * coarse[i0 + 1, :]
    fine = (1 - t)[None, :] * rows[:, i0] + t[None, :] * rows[:, i0 + 1]
    res = st.study(fine, k, 10, 12, 3, "point", "point", ["bilinear", "keys"])
    eb = max(res["bilinear"][ax]["err"] for ax in ("row", "col"))
    ek = max(res["keys"][ax]["err"] for ax in ("row", "col"))
    check(eb < 1e-9, f"no interpolant error, none found ({eb:.1e} cells)")
    check(ek > 1e-4, f"Keys' kernel on it has one ({ek:.1e} cells)")
    worst = 0.0
    for phi in np.linspace(0.05, 0.95, 19):
        ks = np.arange(-1, 3)
        w = st.keys_w(phi - ks)
        for th in (0.1, 0.5, 1.0, 2.0, 3.0):
            pk = np.angle(np.sum(w * np.exp(1j * th * ks)))
            pl = np.angle((1 - phi) + phi * np.exp(1j * th))
            worst = max(worst, abs(pk - pl))
    check(worst < 1e-12, f"Keys' phase response is the bilinear one ({worst:.1e} rad)")
    k, n = 16, 48
    cg = rng.normal(size=(n, n))
    pos = np.clip((np.arange(k * n) - k // 2) / k, 2.0, n - 3.0)
    spl = st.Surface(cg, "spline3")
    fr, fcol = np.meshgrid(pos, pos, indexing="ij")
    sfine = spl(fr, fcol)
    res = st.study(sfine, k, 8, 24, 3, "point", "point", ["keys"], ["spline3"])
    for ax in ("row", "col"):
        r = res["keys"][ax]
        p = r["pred_spline3"]
        check(p["corr"] > 0.95 and p["resid"] < 0.2 * r["err"],
              f"{ax}: on the spline's own surface its prediction is Keys' error (corr "
              f"{p['corr']:.3f}, resid {p['resid']:.2e} of err {r['err']:.2e})")
    for args, what in (((fine, 0, 10, 12, 3, "point", "point", ["keys"]), "K = 0"),
                       ((fine, 2, 40, 12, 3, "point", "point", ["keys"]), "a radius beyond the map"),
                       ((fine, 2, 10, 12, 3, "point", "point", ["sinc"]), "an unknown interpolant")):
        try:
            st.study(*args)
        except st.InputError as e:
            check(True, f"{what} refused: {e}")
        else:
            check(False, f"{what} refused")
    return 0


if __name__ == "__main__":
    sys.exit(main())
