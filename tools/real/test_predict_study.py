#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/real/test_predict_study.py - self-test of tools/real/predict_study.py's pieces.

    /usr/bin/python3 tools/real/test_predict_study.py [--smoke]   # exit 0: all checks passed

* the rank correlation: a hand example with ties, +inf ranked highest, +-1 for monotone pairs,
  and scipy.stats.spearmanr on random data with ties when scipy is installed;
* the decile statistics: errors drawn with the predicted per-axis sigma give ratios near 1 in
  every decile (and 2 for twice the error), right rates and failure-probability means per bin;
* the stratified draw: n / 10 from each bin of equal width in ln u;
* the local map on a plane: every cell the plane at the rover's true position plus its whole-cell
  offset plus the height offset; the rover-frame geotransform; the patch centred on the lattice
  point nearest the target; the noise's sd at each cell's range;
* the height prediction's covariance on a paraboloid against its analytic value, a plane
  uninformative; with a variance per cell: equal to it for one variance, against the information
  formed directly with weighted centring for varying ones;
* the self-similarity failure probability: on a plane every shift ties (P_beat near 1), on a
  surface periodic along x the period's shift ties, on a sharp bump nothing competes; the gap
  ln L(truth) - ln L(d) simulated with the noise has mean D_d and variance 2 D_d;
* --smoke (needs build/host-release/trn and the rock field, tools/real/dems.py): the smoke run
  (60 cases on the rock field) completes; its numbers are printed, no goal is checked.
"""
import argparse
import math
import os
import subprocess
import sys
import tempfile

import numpy as np
from osgeo import gdal

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import cases as cm  # noqa: E402
import predict_study as ps  # noqa: E402

gdal.UseExceptions()
FAILS = []


def check(cond, what):
    print(f"{'ok  ' if cond else 'FAIL'} {what}")
    if not cond:
        FAILS.append(what)


def test_spearman():
    r = ps.rankdata([10, 20, 20, 5, math.inf])
    check(list(r) == [2.0, 3.5, 3.5, 1.0, 5.0], f"ranks with a tie and +inf: {list(r)}")
    a = [1, 2, 3, 4, 5]
    check(abs(ps.spearman(a, [2, 4, 8, 16, 1e9]) - 1) < 1e-12, "monotone increasing: +1")
    check(abs(ps.spearman(a, [5, 4, 3, 2, 1]) + 1) < 1e-12, "decreasing: -1")
    # hand example: x = 1 2 3 4, y = 1 3 2 2 -> ranks y 1, 4, 2.5, 2.5; centred ranks x -1.5 -0.5 0.5 1.5,
    # y -1.5 1.5 0 0: Pearson of the ranks = 1.5 / sqrt(5 * 4.5)
    want = 1.5 / math.sqrt(22.5)
    got = ps.spearman([1, 2, 3, 4], [1, 3, 2, 2])
    check(abs(got - want) < 1e-12, f"hand example with a tie: {got:.6f} (want {want:.6f})")
    check(ps.spearman([1, 2], [1, 2]) is None and ps.spearman([1, 1, 1], [1, 2, 3]) is None,
          "fewer than 3 pairs or a constant variable: None")
    check(abs(ps.spearman([1, 2, math.nan, 4, 5], [1, 2, 99, 3, 4]) - 1) < 1e-12, "NaN pairs dropped")
    try:
        from scipy.stats import spearmanr
    except ImportError:
        print("skip scipy comparison (no scipy)")
        return
    rng = np.random.default_rng(3)
    worst = 0.0
    for _ in range(20):
        x = np.round(rng.normal(size=200), 1)  # many ties
        y = np.round(x + rng.normal(size=200), 1)
        worst = max(worst, abs(ps.spearman(x, y) - spearmanr(x, y)[0]))
    check(worst < 1e-12, f"against scipy.stats.spearmanr on 20 tied samples (worst {worst:.1e})")


def test_deciles():
    rng = np.random.default_rng(5)
    n = 20000
    u = np.exp(rng.uniform(math.log(0.01), math.log(1.0), n))
    s = u / math.sqrt(2)
    ex, ey = rng.normal(size=n) * s, rng.normal(size=n) * s
    right = np.ones(n, dtype=bool)
    fp = np.full(n, 0.25)
    d = ps.decile_stats(u, ex, ey, right, s, s, {"fp": fp})
    r = [x["ratio"] for x in d]
    check(len(d) == 10 and all(x["n"] == n // 10 for x in d), "ten bins of equal count")
    check(all(0.95 < v < 1.05 for v in r), f"errors drawn with the predicted sigma: ratios {min(r):.3f}-{max(r):.3f}")
    rx = [x["ratio_x"] for x in d]
    check(all(0.93 < v < 1.07 for v in rx), f"per axis x: {min(rx):.3f}-{max(rx):.3f}")
    d2 = ps.decile_stats(u, 2 * ex, 2 * ey, right)
    r2 = [x["ratio"] for x in d2]
    check(all(1.9 < v < 2.1 for v in r2), f"twice the error: ratios {min(r2):.3f}-{max(r2):.3f}")
    right = u < 0.5
    d3 = ps.decile_stats(u, ex, ey, right, fail_probs={"fp": fp})
    wr = [x["wrong_rate"] for x in d3]
    check(wr[0] == 0.0 and wr[-1] == 1.0 and abs(d3[0]["fp_mean"] - 0.25) < 1e-12,
          f"wrong rates per bin {wr[0]:.2f} .. {wr[-1]:.2f}, failure-probability mean 0.25")
    check("ratio" not in d3[-1], "a bin with no right answer has no ratio")
    rel = ps.reliability(np.array([0.0, 0.0, 0.6, 0.6, 0.95]), np.array([0, 0, 1, 0, 1], dtype=bool))
    b = {x["lo"]: x for x in rel["bins"]}
    check(b[0.0]["observed"] == 0.0 and b[0.5]["observed"] == 0.5 and b[0.9]["observed"] == 1.0
          and abs(rel["sum_predicted"] - 2.15) < 1e-12, "reliability bins and the predicted sum")


def test_draw():
    rng = np.random.default_rng(7)
    logu = rng.normal(size=50000)  # most candidates in the middle
    idx, (lo, hi) = ps.stratified_draw(rng, logu, 1000)
    b = np.clip(((logu[idx] - lo) / (hi - lo) * 10).astype(int), 0, 9)
    cnt = np.bincount(b, minlength=10)
    check(len(set(idx.tolist())) == 1000 and cnt.min() == 100 and cnt.max() == 100,
          f"stratified draw: 100 from each of 10 equal-width ln-u bins ({cnt.tolist()})")


def plane(x, y):
    return 0.3 * x - 0.7 * y + 12.0


def synth_dem(f, n=120, c=2.0, x0=500.0, y0=3000.0):
    k = np.arange(n)
    x = x0 + (k + 0.5) * c
    y = y0 - (k + 0.5) * c
    return cm.Dem(f(x[None, :], y[:, None]).astype(np.float64), x0, y0, c, "synthetic")


def test_local_map():
    dem = synth_dem(plane)
    c = dem.c
    rover = (500.0 + 60.37 * c, 3000.0 - 55.81 * c)  # off the cell centres
    target = (40, 75)  # row, col
    z, gt, r = ps.local_patch(dem, rover, target, 7, offset_m=13.25)
    fr, fc = dem.frac_index(*rover)
    ox, oy = int(round(target[1] - fc)), int(round(target[0] - fr))
    k = np.arange(-3, 4)
    e = (ox + k[None, :]) * c + 0 * k[:, None]
    nn = -(oy + k[:, None]) * c + 0 * k[None, :]
    want = plane(rover[0] + e, rover[1] + nn) + 13.25
    err = float(np.max(np.abs(z - want)))
    check(err < 1e-9, f"plane: each cell the map at the rover's true position + its offset + dz (max {err:.1e} m)")
    # the geotransform: cell (i, j) centred at rover-frame (e, n)
    xc = gt[0] + (np.arange(7) + 0.5) * gt[1]
    yc = gt[3] + (np.arange(7) + 0.5) * gt[5]
    check(np.allclose(xc, e[0]) and np.allclose(yc, nn[:, 0]) and gt[1] == c and gt[5] == -c,
          "rover-frame geotransform: cell centres at whole-cell offsets from the rover (0, 0)")
    # centre cell nearest the target: its map position within half a cell of the target's centre
    tx, ty = dem.xy(*target)
    cx, cy = rover[0] + e[3, 3], rover[1] + nn[3, 3]
    check(abs(cx - tx) <= 0.5 * c and abs(cy - ty) <= 0.5 * c, "the patch centred on the lattice point nearest the target")
    check(np.allclose(r, c * np.hypot(ox + k[None, :], oy + k[:, None])), "cell ranges from the rover")
    # written and read back
    with tempfile.TemporaryDirectory() as tmp:
        p = os.path.join(tmp, "l.tif")
        ps.write_patch(p, z, gt)
        ds = gdal.Open(p)
        check(ds.GetGeoTransform() == gt and np.allclose(ds.ReadAsArray(), z.astype(np.float32)),
              "the written patch: geotransform and heights")
    # the noise: sd noise_m + noise_k r^2 per cell
    rng = np.random.default_rng(11)
    res = []
    for _ in range(400):
        zn, _, _ = ps.local_patch(dem, rover, target, 7, 0.05, 0.002, 13.25, rng)
        res.append((zn - z) / (0.05 + 0.002 * r * r))
    sd = float(np.std(np.array(res)))
    check(abs(sd - 1) < 0.03, f"noise over its model sd: sd {sd:.3f}")


def test_binned_patch():
    """--truth-fine K: the patch binned from the fine DEM's points, on the map's lattice about the
    target, each cell the plane at its points' centroid; the counts as band 2."""
    fine = synth_dem(plane, n=240, c=1.0)
    K, P = 2, 7
    dem = cm.block_average(fine, K)
    c = dem.c
    rover = (fine.x0 + 100.37 * fine.c, fine.y0 - 97.81 * fine.c)
    target = (30, 66)  # the map's row, col
    a = argparse.Namespace(truth_fine=K, patch_cells=P)
    z, gt, n = ps.binned_patch(fine, dem, rover, target, a, 0.0, 0.0, 4.5, np.random.default_rng(3))
    fr, fc = dem.frac_index(*rover)
    kx, ky = ps.patch_offsets((fr, fc), target, P)
    # the cell centres as local_patch places them; every point of a cell lies within half a cell
    _, gt0, _ = ps.local_patch(dem, rover, target, P)
    check(gt == gt0, "binned patch: local_patch's rover-frame geotransform")
    check(n.sum() == P * P * K * K and n.min() >= 0 and abs(n.mean() - K * K) < 1e-9,
          f"binned patch: {int(n.sum())} points, K^2 = {K * K} a cell on average")
    # the plane's value at a cell's centre is within its slope times half a cell of the mean
    xc, yc = rover[0] + kx * c, rover[1] - ky * c
    slope = math.hypot(0.3, 0.7) * 0.5 * c * math.sqrt(2)
    d = np.nanmax(np.abs(z - 4.5 - plane(xc, yc)))
    check(d <= slope + 1e-9 and np.isnan(z[n == 0]).all(),
          f"binned patch: each cell the plane near its centre (max {d:.3f} <= {slope:.3f} m); empty cells NaN")
    with tempfile.TemporaryDirectory() as tmp:
        p = os.path.join(tmp, "b.tif")
        ps.write_patch(p, z, gt, n)
        ds = gdal.Open(p)
        check(ds.RasterCount == 2 and np.array_equal(ds.GetRasterBand(2).ReadAsArray()[n > 0], n[n > 0]),
              "binned patch written: the counts as band 2")
    # the variance the prediction takes: s^2 / n + |g|^2 / (12 n); n = 0 is s^2
    s2, gx, gy = np.array([4.0, 1.0]), np.array([3.0, 0.0]), np.array([4.0, 0.0])
    check(np.array_equal(ps.binned_var(s2, gx, gy, 0.0), s2) and
          np.allclose(ps.binned_var(s2, gx, gy, 4.0), [(4.0 + 25.0 / 12.0) / 4.0, 0.25]),
          "binned_var: s^2 / n plus the jitter |g|^2 / (12 n); unbinned s^2")


def test_spearman_ideal():
    """An exact prediction's Spearman: near 1 when the predictions spread over decades, low when
    they hardly differ (one error is one draw), and the same for errors drawn as it draws them."""
    rng = np.random.default_rng(2)
    wide = np.exp(rng.uniform(0, math.log(1e4), 1000))
    narrow = np.exp(rng.uniform(0, math.log(2.0), 1000))
    r_wide = ps.spearman_ideal(wide * math.sqrt(2), wide, wide, np.zeros(1000))
    r_narrow = ps.spearman_ideal(narrow * math.sqrt(2), narrow, narrow, np.zeros(1000))
    e = np.hypot(wide * rng.standard_normal(1000), wide * rng.standard_normal(1000))
    r_drawn = ps.spearman(wide, e)
    check(r_wide > 0.9 and r_narrow < 0.4 and abs(r_drawn - r_wide) < 0.03,
          f"exact prediction's Spearman: {r_wide:.3f} over four decades, {r_narrow:.3f} over a factor 2; "
          f"errors drawn alike {r_drawn:.3f}")


def test_fisher():
    a, P, c = 0.01, 9, 1.5

    def para(x, y):
        return a * ((x - 500.0) / c - 30.0) ** 2 + a * ((3000.0 - y) / c - 30.0) ** 2
    dem = synth_dem(para, n=60, c=c)
    noise_m = 0.02
    sx, sy, rho, u = ps.fisher_heights(dem.z, (30, 30), P, (30.0, 30.0), noise_m, 0.0, 0.01, c)
    # g = 2 a X per axis (central differences are exact on a quadratic), centred over the patch's
    # cells: sum X^2 over a P x P square = P * 2 * sum_{k=1}^{m} k^2; e = -a everywhere (the mean of
    # the 4 neighbours of a (X^2 + Y^2) is a (X^2 + Y^2) + a)
    m = P // 2
    sumx2 = P * m * (m + 1) * (2 * m + 1) / 3.0
    s2 = noise_m ** 2 + 0.01 ** 2 + (a ** 2) / 4.0
    info = 4 * a * a * sumx2 / s2
    want = math.sqrt(1.0 / info) * c
    check(abs(sx - want) / want < 1e-9 and abs(sy - want) / want < 1e-9 and abs(rho) < 1e-9,
          f"paraboloid: sigma per axis {sx:.6g} m (analytic {want:.6g}), rho 0")
    check(abs(u - math.sqrt(2) * want) / u < 1e-9, "u = sqrt(sx^2 + sy^2)")
    # per cell: with one variance everywhere it is the per-patch prediction; with the variance
    # quadrupled on one half (east of the centre) the information of x falls accordingly
    s2c = np.full((P, P), s2)
    up = ps.fisher_heights_percell(dem.z, (30, 30), P, s2c, c)
    check(abs(up - u) / u < 1e-9, f"per cell, one variance: the per-patch u ({up:.6g} m)")
    rng = np.random.default_rng(1)
    s2r = s2 * np.exp(rng.uniform(-1, 1, (P, P)))
    X = np.arange(P) - m + 0 * np.arange(P)[:, None]
    wt = 1 / s2r
    gxc = 2 * a * (X - (wt * X).sum() / wt.sum())
    Y = X.T
    gyc = 2 * a * (Y - (wt * Y).sum() / wt.sum())
    A = np.array([[(wt * gxc * gxc).sum(), (wt * gxc * gyc).sum()], [(wt * gxc * gyc).sum(), (wt * gyc * gyc).sum()]])
    want_u = math.sqrt(np.trace(np.linalg.inv(A))) * c
    up = ps.fisher_heights_percell(dem.z, (30, 30), P, s2r, c)
    check(abs(up - want_u) / want_u < 1e-9, f"per cell, varying variances: weighted centring ({up:.6g} m, "
                                           f"direct {want_u:.6g})")
    flat = synth_dem(plane, n=60)
    check(math.isinf(ps.fisher_heights_percell(flat.z, (30, 30), P, s2c, 2.0)), "per cell, a plane: uninformative")
    check(math.isinf(ps.fisher_heights(flat.z, (30, 30), P, (25.0, 24.0), 0.01, 0.002, 0.0, 2.0)[3]), "a plane: uninformative")


def test_self_similarity():
    P, W = 7, 4
    s2 = np.full((P, P), 0.01 ** 2)
    flat = synth_dem(plane, n=40)
    pb, pp, dmin, _ = ps.self_similarity(flat.z, (20, 20), P, s2, W)
    check(pb > 0.999 and dmin < 1e-9, f"a plane: every shift ties (P_beat {pb:.4f}, min gap {dmin:.1e})")

    def stripes(x, y):
        return np.sin(2 * math.pi * (x - 500.0) / (3 * 2.0)) + 0.001 * (3000.0 - y) ** 2 / 4.0
    per = synth_dem(stripes, n=40)
    pb, pp, dmin, db = ps.self_similarity(per.z, (20, 20), P, s2, W)
    check(dmin < 1e-9 and db[0] in (-3, 3) and db[1] == 0 and pb >= 0.5,
          f"a surface periodic over 3 cells along x: the shift (+-3, 0) ties (P_beat {pb:.3f})")

    def bump(x, y):
        return 5.0 * np.exp(-(((x - 500.0) / 2.0 - 20.0) ** 2 + ((3000.0 - y) / 2.0 - 20.0) ** 2) / 4.0)
    b = synth_dem(bump, n=40)
    pb, pp, dmin, _ = ps.self_similarity(b.z, (20, 20), P, s2, W)
    check(pb < 1e-12 and pp < 1e-12, f"a sharp bump: nothing competes (P_beat {pb:.1e}, min gap {dmin:.3g} nats)")
    # the gap's distribution under the noise, profiled offset: mean D, variance 2 D
    rng = np.random.default_rng(2)
    sd = 0.3 + 0.4 * rng.uniform(size=(P, P))
    w = 1.0 / sd ** 2
    z = b.z[16:16 + P + 2, 16:16 + P + 2]
    h0 = z[1:1 + P, 1:1 + P]
    h1 = z[1:1 + P, 2:2 + P]  # shift one cell east
    dh = h1 - h0
    D = 0.5 * float((w * (dh - (w * dh).sum() / w.sum()) ** 2).sum())

    def lnl(loc, hm):
        r = loc - hm
        r = r - (w * r).sum() / w.sum()
        return -0.5 * float((w * r * r).sum())
    g = []
    for _ in range(4000):
        loc = h0 + 7.0 + rng.normal(size=(P, P)) * sd
        g.append(lnl(loc, h0) - lnl(loc, h1))
    g = np.array(g)
    check(abs(g.mean() - D) < 4 * math.sqrt(2 * D / len(g)) and abs(g.var() / (2 * D) - 1) < 0.08,
          f"the gap simulated: mean {g.mean():.3f} (D {D:.3f}), variance {g.var():.3f} (2D {2 * D:.3f})")


def test_smoke():
    trn = os.path.join(os.path.dirname(os.path.dirname(HERE)), "build", "host-release", "trn")
    if not os.access(trn, os.X_OK):
        print("skip smoke (no build/host-release/trn)")
        return
    with tempfile.TemporaryDirectory() as tmp:
        r = subprocess.run([sys.executable, os.path.join(HERE, "predict_study.py"), "--smoke", "--no-plot",
                            "--trn", trn, "--out", tmp], capture_output=True, text=True)
        print(r.stdout)
        check(r.returncode == 0 and os.path.isfile(os.path.join(tmp, "predict.json")),
              f"the smoke run completes (exit {r.returncode}: {r.stderr.strip()[-200:]})")


def main(argv):
    test_spearman()
    test_deciles()
    test_draw()
    test_local_map()
    test_binned_patch()
    test_spearman_ideal()
    test_fisher()
    test_self_similarity()
    if "--smoke" in argv:
        test_smoke()
    if FAILS:
        print(f"test_predict_study: {len(FAILS)} check(s) failed", file=sys.stderr)
        return 1
    print("test_predict_study: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
