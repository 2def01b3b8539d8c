#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/real/test_real.py - quick self-test of the real-terrain benchmark's pieces.

    /usr/bin/python3 tools/real/test_real.py      # exit 0: all checks passed

On small synthetic DEMs with analytic surfaces (no download, ~10 s):
* the local DEM's frame: on a plane (which bilinear and cubic sampling reproduce
  exactly) every local cell equals the plane at truth + ((j-R)c, (R-i)c) + offset;
* the written local GeoTIFF: rover-frame geotransform, no CRS, NaN no-data, the
  rover at map-frame (0, 0) (centre of the centre cell);
* visibility (range annulus, 120 deg wedge) and the noise model's sigma;
* generate(): priors within +-4 cells, window 6 cells, truths inside the margin, the
  batch list file;
* peers: with no noise and full view the SSD peer recovers a sub-cell truth within
  0.1 cell (bilinear and cubic): with its per-axis parabola on terrain of many wave
  directions, with the 2-D quadratic fit on ridged terrain (where the per-axis fit
  is biased, printed for information); an integer-offset case is recovered exactly by both
  peers (integer pose = the truth's cell; the per-axis parabola then moves it by less
  than 0.02 cell: s(-1) and s(+1) differ by the window's edge terms);
* model error (--truth-fine K): the block average's frame (a plane's block means are
  the plane at the coarse cell centres; a sinusoid's are attenuated by the known
  factor sin(pi K c / L) / (K sin(pi c / L)), phase kept, along rows and columns);
  the written coarse GeoTIFF; local maps from the fine DEM at the coarse spacing equal
  the coarse map's bilinear interpolation exactly on a plane; on smooth terrain
  (wavelengths of 10-20 coarse cells) the SSD peer on the coarse map recovers sub-cell
  truths without bias (a half-fine-cell frame slip would be (K-1)/2K coarse cells);
* cases.point_sample (--fine-map point): a sinusoid's point samples every K cells equal it
  at the coarse centres, K odd and even;
* dems.float_nan_tif: no-data to NaN in float32, same grid, the CRS kept or set;
* bench_real.py exits 1 with one line on bad input;
* --fine-local mean: on a plane the cell means equal the centre samples; a pattern
  alternating +-1 along the fine columns averages to exactly 0 in every local cell;
* --fine-local binned: K^2 points a cell on average, their counts varying; on a plane each
  cell equals the plane at its points' centroid, which lies in the cell; the noise is the
  mean of the points' (residuals over sqrt(sum sd_i^2) / n of sd 1); the cases' draws kept;
* --counts: the cells' point counts, whole and >= 1 where seen, NaN where no point fell (those
  cells unseen), the heights as without them, written as the GeoTIFF's band after the heights
  and any centroids; without binned cells bench_real exits 1 with one line;
* --points-draw D: draw 0 gives the binned heights bit for bit; draws 1 and 2 the same next draw
  of the case's generator and the same seen cells but those no point fell in, with heights that differ from draw 0's and
  from each other; with other constructions, or negative, bench_real exits 1 with one line;
* --mast-view: the ray cast (cases.mast_visible) sees every cell on flat and tilted ground;
  behind a wall of height W at distance d a mast of height H loses the cells up to
  d H / (H - W) (similar triangles); in a pit of depth D behind a rim at distance d, the
  floor up to d (H + D) / H; the cases' heights unchanged where seen;
* tools/real/rover_map_error.py on a plane: no interpolation error, the binning error the
  plane's rise to each cell's points' centroid;
* --prior-miss F: round(F n) cases get a prior whose Chebyshev distance from the truth lies in
  [window + 1.5, miss max] cells (so the truth lies 1.5 cells or more outside the window), the
  others within +-4; the margin grows by the miss; the main draws (azimuth, offset) unchanged;
  F = 0 the cases bit for bit; a missing case is never right in the metrics, even 0.5 cells
  off, and its failure counts 1 in the Brier score; bad values exit 1 with one line; end to
  end (when trn is built) the JSON's missing cases have their truth outside their window;
* draw_study.analyse: a covariance free of noise gives CV 0 and the same coverage with each
  draw's own covariance as with the case's mean; the points' and the case's parts of the true
  trace exactly on draws b_i +- d; a covariance doubled and halved by turns gives its CV and,
  divided by that factor as the inflation, the noise-free coverage; one draw is refused;
* variance_by_fifth (does the covariance follow the error from case to case): errors at the
  predicted variance give 1 in every fifth; one error over traces 1..10 gives 2 / (4k + 3) in
  fifth k, in any order of the cases; through the metrics, over the right answers only;
* --dem-file (a user's DEM): a missing or geographic file exits 1 with one line; a
  projected synthetic DEM runs end to end under its file name (when trn is built);
* if build/host-release/trn exists: trn localize recovers the noiseless integer case
  (frame agreement of the local file with trn; reported, not required).
"""
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
import peers  # noqa: E402

gdal.UseExceptions()
FAILS = []


def check(cond, what):
    print(f"{'ok  ' if cond else 'FAIL'} {what}")
    if not cond:
        FAILS.append(what)


def synth_dem(f, n=160, c=10.0, x0=1000.0, y0=4000.0):
    """A Dem whose cell (row, col) centre holds f(x, y)."""
    col = np.arange(n)
    x = x0 + (col + 0.5) * c
    y = y0 - (col + 0.5) * c
    z = f(x[None, :], y[:, None])
    return cm.Dem(z.astype(np.float64), x0, y0, c, "synthetic")


def plane(x, y):
    return 0.3 * x - 0.7 * y + 12.0 + 0 * x * y


def hills(x, y):
    return (40 * np.sin(x / 97.0) * np.cos(y / 131.0) + 25 * np.sin((x + 2 * y) / 71.0)
            + 15 * np.cos((3 * x - y) / 53.0))


def test_frame():
    dem = synth_dem(plane)
    R = 8
    for method in ("bilinear", "cubic"):
        p = cm.CaseParams(radius=R, noise=False, full_view=True, resample=method, min_range_cells=0)
        truth = (1000 + 763.37, 4000 - 671.81)
        local, seen = cm.make_local(dem, truth, p, None, 0.0, 17.5)
        k = np.arange(-R, R + 1)
        want = plane(truth[0] + k[None, :] * dem.c, truth[1] - k[:, None] * dem.c) + 17.5
        err = np.nanmax(np.abs(local - want))
        k2 = np.hypot(k[None, :], k[:, None])
        check(err < 1e-9, f"{method}: local cell (i, j) = G(truth + ((j-R)c, (R-i)c)) + offset "
                          f"on a plane (max err {err:.2e} m)")
        check(np.array_equal(seen, k2 <= R), f"{method}: full view sees every cell within R")


def test_file():
    with tempfile.TemporaryDirectory() as tmp:
        dem = synth_dem(hills)
        p = cm.CaseParams(radius=6)
        cs = cm.generate(dem, 5, 3, p, tmp)
        ds = gdal.Open(cs[0].path)
        gt = ds.GetGeoTransform()
        c, R = dem.c, 6
        check(gt == (-(R + 0.5) * c, c, 0.0, (R + 0.5) * c, 0.0, -c), f"local geotransform {gt}")
        check(ds.GetProjection() == "", "local GeoTIFF has no CRS")
        b = ds.GetRasterBand(1)
        check(b.DataType == gdal.GDT_Float32 and math.isnan(b.GetNoDataValue()), "float32, no-data NaN")
        a = b.ReadAsArray()
        check((ds.RasterXSize, ds.RasterYSize) == (2 * R + 1, 2 * R + 1), "size (2R+1)^2")
        check(np.array_equal(np.isnan(a), ~cs[0].seen), "NaN exactly where unseen")
        cx = gt[0] + (R + 0.5) * gt[1]
        cy = gt[3] + (R + 0.5) * gt[5]
        check(cx == 0.0 and cy == 0.0, "the centre cell's centre is map-frame (0, 0)")
        with open(os.path.join(tmp, "cases.txt")) as f:
            lines = f.read().splitlines()
        ok = len(lines) == 5
        for ln, cs_ in zip(lines, cs):
            w = ln.split()
            ok &= (w[0] == cs_.path and float(w[1]) == cs_.prior[0] and float(w[2]) == cs_.prior[1]
                   and float(w[3]) == 6 * c)
        check(ok, "batch list: LOCAL.tif PRIOR_X PRIOR_Y WINDOW_M per case")


def test_generate():
    dem = synth_dem(hills, n=200)
    p = cm.CaseParams(radius=10)
    cs = cm.generate(dem, 300, 7, p)
    c = dem.c
    d = np.array([[cs_.prior[0] - cs_.truth[0], cs_.prior[1] - cs_.truth[1]] for cs_ in cs]) / c
    check(np.abs(d).max() <= 4.0 and np.abs(d).max() > 3.5, f"prior offsets within +-4 cells (max {np.abs(d).max():.2f})")
    check(all(cs_.window_m == 6 * c for cs_ in cs), "window 6 cells")
    m = p.margin_cells
    rc = np.array([dem.frac_index(*cs_.truth) for cs_ in cs])
    check(rc.min() >= m - 1e-9 and rc.max() <= dem.z.shape[0] - 1 - m + 1e-9,
          f"truths at least {m:g} cells from the edge")
    frac = np.abs(rc - np.round(rc))
    check((frac.max(axis=1) > 1e-6).all(), "truths off the cell centres")
    offs = np.array([cs_.offset_m for cs_ in cs])
    check(np.abs(offs).max() <= 50 and np.abs(offs).max() > 45, "height offsets within +-50 m")
    cs2 = cm.generate(dem, 300, 7, p)
    check(all(np.array_equal(a.local, b.local, equal_nan=True) and a.truth == b.truth for a, b in zip(cs, cs2)),
          "same seed, same cases")
    # visibility: annulus and wedge
    e, n = cm.rover_frame_offsets(10, c)
    r = np.hypot(e, n)
    cs_ = cs[0]
    s = cs_.seen
    check(not s[r < 1.5 * c].any() and not s[r > 10 * c].any(), "unseen: r < 1.5 cells and r > R cells")
    az = np.degrees(np.arctan2(n, e))
    dd = np.abs((az - cs_.azimuth_deg + 180) % 360 - 180)
    check(not s[dd > 60 + 1e-9].any(), "unseen outside the 120 deg wedge")
    ann = (r >= 1.5 * c) & (r <= 10 * c)
    fr = np.mean([x.seen.sum() / ann.sum() for x in cs])
    check(abs(fr - 1 / 3) < 0.03, f"seen fraction of the annulus {fr:.3f} ~ 1/3")


def test_noise():
    dem = synth_dem(plane, n=120)
    R = 10
    p = cm.CaseParams(radius=R, full_view=True)
    rng = np.random.default_rng(5)
    truth = (1000 + 600.3, 4000 - 590.8)
    p0 = cm.CaseParams(radius=R, full_view=True, noise=False)
    clean, _ = cm.make_local(dem, truth, p0, None, 0.0, 0.0)
    res = []
    for _ in range(400):
        loc, _ = cm.make_local(dem, truth, p, rng, 0.0, 0.0)
        res.append(loc - clean)
    res = np.array(res)
    e, n = cm.rover_frame_offsets(R, dem.c)
    sigma = 0.01 + 0.0004 * (e**2 + n**2) / dem.c
    seen = np.isfinite(clean)
    z = np.std(res[:, seen] / sigma[seen][None], axis=0)
    check(abs(np.nanmean(z) - 1) < 0.02, f"noise sigma 0.01 + 0.0004 r^2 / c (ratio {np.nanmean(z):.3f})")


def waves(n, lmin_m, lmax_m, seed):
    """A sum of n plane waves of random direction, wavelength and phase."""
    g = np.random.default_rng(seed)
    th = g.uniform(0, np.pi, n)
    lam = g.uniform(lmin_m, lmax_m, n)
    ph = g.uniform(0, 2 * np.pi, n)
    amp = g.uniform(5, 15, n)

    def f(x, y):
        z = 0 * x * y
        for k in range(n):
            z = z + amp[k] * np.sin(2 * np.pi * (x * np.cos(th[k]) + y * np.sin(th[k])) / lam[k] + ph[k])
        return z
    return f


RICH = waves(16, 60.0, 200.0, 2)  # many directions: a round SSD bowl
RIDGED = waves(8, 150.0, 400.0, 2)  # few long waves: elongated, oblique bowls


def subcell_worst(dem, R, method, fit, rng, n=20):
    p = cm.CaseParams(radius=R, noise=False, full_view=True, resample=method)
    worst = [0.0, 0.0]
    m = p.margin_cells
    last = dem.z.shape[0] - 1 - m
    for _ in range(n):
        truth = dem.xy(rng.uniform(m, last), rng.uniform(m, last))
        local, seen = cm.make_local(dem, truth, p, None, 0.0, 0.0)
        prior = (truth[0] + rng.uniform(-40, 40), truth[1] + rng.uniform(-40, 40))
        for k, fn in enumerate((peers.ssd, peers.ncc)):
            x, y, _ = fn(dem, local, seen, prior, 60.0, fit)
            worst[k] = max(worst[k], math.hypot(x - truth[0], y - truth[1]) / dem.c)
    return worst


def test_peers():
    R = 20
    for name, f, fit in (("rich", RICH, "axis"), ("ridged", RIDGED, "quad2d")):
        dem = synth_dem(f, n=200)
        for method in ("bilinear", "cubic"):
            w = subcell_worst(dem, R, method, fit, np.random.default_rng(11))
            check(w[0] < 0.1, f"{name} terrain, {method}, {fit} fit: SSD peer within 0.1 cell of a sub-cell "
                              f"truth, no noise, full view (worst of 20: {w[0]:.3f}; NCC {w[1]:.3f})")
    dem = synth_dem(RIDGED, n=200)
    w = subcell_worst(dem, R, "bilinear", "axis", np.random.default_rng(11))
    print(f"info ridged terrain, per-axis parabola: worst of 20 SSD {w[0]:.3f}, NCC {w[1]:.3f} cells "
          f"(the per-axis fit's bias on oblique bowls)")
    dem = synth_dem(RICH, n=200)
    # integer offset: truth on a cell centre
    p = cm.CaseParams(radius=R, noise=False, full_view=True)
    row, col = 97, 104
    truth = dem.xy(row, col)
    local, seen = cm.make_local(dem, truth, p, None, 0.0, 0.0)
    check(np.array_equal(local[seen], dem.z[row - R:row + R + 1, col - R:col + R + 1][seen]),
          "integer case: the local map is the global crop")
    prior = (truth[0] + 31.0, truth[1] - 22.0)
    for name, fn in peers.PEERS.items():
        x, y, pose = fn(dem, local, seen, prior, 60.0)
        e = math.hypot(x - truth[0], y - truth[1]) / dem.c
        check(pose == (row, col) and e < 0.02, f"integer case: {name} pose {pose} exact, error after the "
                                               f"sub-cell fit {e:.2e} cells (< 0.02)")
    # ... and with an unseen wedge (masked NCC)
    p = cm.CaseParams(radius=R, noise=False)
    local, seen = cm.make_local(dem, truth, p, None, 40.0, 10.0)
    for name, fn in peers.PEERS.items():
        x, y, pose = fn(dem, local, seen, prior, 60.0)
        check(pose == (row, col), f"integer case, 120 deg wedge, offset 10 m: {name} pose {pose}")
    return dem, local, seen, truth, prior


def test_trn(dem, local, seen, truth, prior):
    trn = os.path.join(os.path.dirname(os.path.dirname(HERE)), "build", "host-release", "trn")
    if not os.path.exists(trn):
        print("skip trn frame check (no build/host-release/trn)")
        return
    with tempfile.TemporaryDirectory() as tmp:
        g = os.path.join(tmp, "g.tif")
        ds = gdal.GetDriverByName("GTiff").Create(g, dem.z.shape[1], dem.z.shape[0], 1, gdal.GDT_Float32)
        ds.SetGeoTransform((dem.x0, dem.c, 0, dem.y0, 0, -dem.c))
        ds.GetRasterBand(1).WriteArray(dem.z.astype(np.float32))
        ds = None
        lp = os.path.join(tmp, "l.tif")
        cm.write_local(lp, local, dem.c)
        r = subprocess.run([trn, "localize", "--dem", g, "--local", lp, "--prior", f"{prior[0]},{prior[1]}",
                            "--window-m", "60", "--json"], capture_output=True, text=True)
        if r.returncode != 0:
            print(f"note: trn localize failed: {r.stderr.strip()}")
            return
        import json
        j = json.loads(r.stdout)
        e = math.hypot(j["x_m"] - truth[0], j["y_m"] - truth[1]) / dem.c
        print(f"{'note' if e > 0.5 else 'ok  '} trn localize on the integer case: error {e:.3f} cells "
              f"(status {j['status']}; reported only)")


def test_truth_fine():
    K, cf = 3, 10.0
    cc = K * cf
    # plane: block means = the plane at the coarse centres; local = coarse bilinear
    fine = synth_dem(plane, n=240, c=cf)
    g = cm.block_average(fine, K)
    rows = np.arange(g.z.shape[0])
    X, Y = g.xy(rows[:, None] + 0.0, rows[None, :] + 0.0)
    X, Y = np.broadcast_arrays(X, Y)
    check(g.c == cc and g.z.shape == (80, 80) and np.abs(g.z - plane(Y * 0 + X, Y)).max() < 1e-9,
          f"block mean of a plane ({K} x {K}) = the plane at the coarse cell centres")
    R = 10
    p = cm.CaseParams(radius=R, noise=False, full_view=True, min_range_cells=0)
    truth = (1000 + 1217.3, 4000 - 1093.9)
    local, seen = cm.make_local(g, truth, p, None, 0.0, 4.5, fine)
    k = np.arange(-R, R + 1)
    fr, fc = g.frac_index(*truth)
    kr, kc = np.broadcast_arrays(k[:, None] + 0.0, k[None, :] + 0.0)
    want = cm.sample(g.z, fr + kr, fc + kc) + 4.5
    exact = plane(truth[0] + kc * cc, truth[1] - kr * cc) + 4.5
    d1 = np.abs(local - want)[seen].max()
    d2 = np.abs(local - exact)[seen].max()
    check(seen.sum() > 300 and d1 < 1e-9 and d2 < 1e-9,
          f"plane: local map from the fine DEM at the coarse spacing = the coarse map's bilinear "
          f"interpolation = the plane at truth + ((j-R)c', (R-i)c') (max diffs {d1:.1e}, {d2:.1e} m)")
    # sinusoids along x and along y: the known attenuation, no phase shift
    L1, L2 = 7.3 * cf, 11.9 * cf

    def sines(x, y):
        return 20 * np.sin(2 * np.pi * x / L1 + 0.4) + 12 * np.cos(2 * np.pi * y / L2 - 1.1)
    fine = synth_dem(sines, n=240, c=cf)
    g = cm.block_average(fine, K)
    a1 = math.sin(math.pi * K * cf / L1) / (K * math.sin(math.pi * cf / L1))
    a2 = math.sin(math.pi * K * cf / L2) / (K * math.sin(math.pi * cf / L2))
    want = 20 * a1 * np.sin(2 * np.pi * X / L1 + 0.4) + 12 * a2 * np.cos(2 * np.pi * Y / L2 - 1.1)
    err = np.abs(g.z - want).max()
    check(err < 1e-9, f"block mean of sinusoids: amplitude x {a1:.4f} (x) and {a2:.4f} (y), phase kept "
                      f"(max err {err:.1e} m)")
    fine.z[5, 7] = np.nan
    check(np.isnan(cm.block_average(fine, K).z[1, 2]) and np.isfinite(cm.block_average(fine, K).z[1, 1]),
          "a block with a missing cell is missing")
    # the written coarse map
    with tempfile.TemporaryDirectory() as tmp:
        src = os.path.join(tmp, "fine.tif")
        ds = gdal.GetDriverByName("GTiff").Create(src, 30, 20, 1, gdal.GDT_Float32)
        ds.SetGeoTransform((500.0, 2.0, 0, 9000.0, 0, -2.0))
        from osgeo import osr
        sr = osr.SpatialReference()
        sr.ImportFromEPSG(32615)
        ds.SetProjection(sr.ExportToWkt())
        ds.GetRasterBand(1).WriteArray(np.arange(600, dtype=np.float32).reshape(20, 30))
        ds = None
        f = cm.read_dem(src)
        out = cm.write_global(os.path.join(tmp, "g.tif"), cm.block_average(f, 4), like=src)
        ds = gdal.Open(out)
        srs = osr.SpatialReference(wkt=ds.GetProjection())
        zz = ds.GetRasterBand(1).ReadAsArray()
        check(ds.GetGeoTransform() == (500.0, 8.0, 0, 9000.0, 0, -8.0) and zz.shape == (5, 7)
              and srs.GetAuthorityCode(None) == "32615" and zz[0, 0] == np.arange(600).reshape(20, 30)[:4, :4].mean(),
              f"coarse GeoTIFF: corner kept, cell 4 c, trailing cells dropped, CRS copied ({zz.shape})")
    # smooth terrain: SSD on the coarse map, local maps from the fine DEM, no noise
    smooth = waves(12, 10 * cc, 20 * cc, 4)
    fine = synth_dem(smooth, n=330, c=cf)
    g = cm.block_average(fine, K)
    rng = np.random.default_rng(3)
    p = cm.CaseParams(radius=20, noise=False, full_view=True)
    m = p.margin_cells
    errs = []
    for _ in range(20):
        tr = g.xy(rng.uniform(m, g.z.shape[0] - 1 - m), rng.uniform(m, g.z.shape[1] - 1 - m))
        loc, seen = cm.make_local(g, tr, p, None, 0.0, 0.0, fine)
        prior = (tr[0] + rng.uniform(-3, 3) * cc, tr[1] + rng.uniform(-3, 3) * cc)
        x, y, _ = peers.ssd(g, loc, seen, prior, 6 * cc, "quad2d")
        errs.append(((x - tr[0]) / cc, (y - tr[1]) / cc))
    errs = np.array(errs)
    worst = np.hypot(errs[:, 0], errs[:, 1]).max()
    bias = np.hypot(*errs.mean(axis=0))
    check(worst < 0.05 and bias < 0.02, f"K = {K}, smooth terrain, no noise: SSD (2-D fit) on the coarse map "
                                        f"within 0.05 coarse cell (worst of 20 {worst:.3f}, mean error "
                                        f"{bias:.3f}; a frame slip would be {(K - 1) / (2 * K):.2f})")


def test_point_sample():
    """cases.point_sample: coarse cell (I, J) is fine cell (K I + K//2, K J + K//2), centred
    on it, so a sinusoid's point samples equal it at the coarse centres, with no
    attenuation (block_average's would be attenuated), for K odd and even."""
    cf = 10.0

    def sines(x, y):
        return 20 * np.sin(2 * np.pi * x / (3.1 * cf) + 0.4) + 12 * np.cos(2 * np.pi * y / (4.7 * cf) - 1.1)
    fine = synth_dem(sines, n=121, c=cf)
    for K in (2, 3):
        g = cm.point_sample(fine, K)
        r = np.arange(g.z.shape[0])[:, None] + 0.0 * np.arange(g.z.shape[1])[None, :]
        c = 0.0 * np.arange(g.z.shape[0])[:, None] + np.arange(g.z.shape[1])[None, :]
        X, Y = g.xy(r, c)
        n_want = (121 - K // 2 + K - 1) // K
        d = np.abs(g.z - sines(X, Y)).max()
        check(g.c == K * cf and g.z.shape == (n_want, n_want) and d < 1e-9,
              f"point samples every {K} cells: {g.z.shape[0]}^2 cells of {g.c:g} m, equal to the "
              f"surface at the coarse centres (max diff {d:.1e} m)")


def test_float_nan_tif():
    """dems.float_nan_tif: an int16 raster with a no-data value becomes float32 with NaN
    there and the other heights unchanged, on the same grid, keeping its CRS or taking
    EPSG:epsg."""
    import dems
    from osgeo import osr
    z = np.arange(12 * 10, dtype=np.int16).reshape(12, 10) - 40
    z[3, 4] = z[7, 1] = -9999
    gt = (500000.0, 2.0, 0.0, 4100000.0, 0.0, -2.0)
    with tempfile.TemporaryDirectory() as tmp:
        src = os.path.join(tmp, "src.tif")
        ds = gdal.GetDriverByName("GTiff").Create(src, 10, 12, 1, gdal.GDT_Int16)
        ds.SetGeoTransform(gt)
        srs = osr.SpatialReference()
        srs.ImportFromEPSG(32611)
        ds.SetProjection(srs.ExportToWkt())
        ds.GetRasterBand(1).SetNoDataValue(-9999)
        ds.GetRasterBand(1).WriteArray(z)
        ds = None
        for epsg, want in ((None, "32611"), (32612, "32612")):
            out = os.path.join(tmp, "sub", f"out_{epsg}.tif")
            dems.float_nan_tif(src, out, -9999, epsg)
            d = gdal.Open(out)
            got = d.GetRasterBand(1).ReadAsArray()
            keep = z != -9999
            code = osr.SpatialReference(wkt=d.GetProjection()).GetAuthorityCode(None)
            check(d.GetRasterBand(1).DataType == gdal.GDT_Float32 and np.isnan(got[~keep]).all()
                  and np.array_equal(got[keep], z[keep].astype(np.float32))
                  and d.GetGeoTransform() == gt and code == want
                  and not os.path.exists(out + ".part.tif"),
                  f"float_nan_tif (epsg {epsg}): float32, the 2 no-data cells NaN, the other 118 "
                  f"unchanged, same grid, CRS EPSG:{code}")


def test_cli():
    b = os.path.join(HERE, "bench_real.py")
    for args, what in ((["--dem", "no_such_dem"], "unknown DEM"), (["--cases", "0"], "--cases 0"),
                       (["--fine-map", "median"], "--fine-map median"),
                       (["--trn", "/nonexistent/trn"], "missing trn"), (["--bogus"], "unknown option"),
                      (["--truth-fine", "1"], "--truth-fine 1"), (["--noise-scale", "-1"], "--noise-scale -1"),
                      (["--noise-scale", "nan"], "--noise-scale nan"), (["--fine-local", "median"], "--fine-local median"),
                      (["--outliers", "1"], "--outliers 1"), (["--outliers", "-0.1"], "--outliers -0.1"),
                      (["--mast-view", "0"], "--mast-view 0"), (["--mast-view", "inf"], "--mast-view inf"),
                      (["--fine-local", "binned"], "--fine-local binned without --truth-fine"),
                      (["--points-draw", "1"], "--points-draw without binned cells"),
                      (["--truth-fine", "2", "--fine-local", "binned", "--points-draw", "-1"], "--points-draw -1"),
                      (["--points-draw", "x"], "--points-draw x"),
                      (["--counts"], "--counts without binned cells")):
        r = subprocess.run([sys.executable, b] + args, capture_output=True, text=True)
        check(r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1 and r.stdout == "",
              f"bench_real {what}: exit 1, one line ({r.stderr.strip()})")


def test_local_mean():
    """--fine-local mean: a local cell is the fine surface's mean over the cell. On a plane it
    equals the centre sample; on a surface alternating +-1 along the fine columns (K = 2) the
    two sub-samples across a cell are one fine cell apart, so bilinear gives v and -v: every
    local cell is exactly 0, wherever the rover is, while the centre samples are not."""
    K, cf = 2, 10.0
    fine = synth_dem(plane, n=240, c=cf)
    g = cm.block_average(fine, K)
    R = 6
    pm = cm.CaseParams(radius=R, noise=False, full_view=True, min_range_cells=0, local="mean")
    pp = cm.CaseParams(radius=R, noise=False, full_view=True, min_range_cells=0)
    truth = (fine.x0 + 120 * cf + 3.7, fine.y0 - 120 * cf - 6.1)
    lm, _ = cm.make_local(g, truth, pm, None, 0.0, 0.0, fine)
    lp, _ = cm.make_local(g, truth, pp, None, 0.0, 0.0, fine)
    check(np.allclose(lm, lp, rtol=0.0, atol=1e-9, equal_nan=True) and np.isfinite(lm).sum() > 100,
          f"local mean on a plane = the centre samples "
          f"(max diff {np.nanmax(np.abs(lm - lp)):.2e})")
    alt = synth_dem(plane, n=240, c=cf)
    alt.z = np.tile(np.where(np.arange(240) % 2 == 0, 1.0, -1.0), (240, 1))
    g = cm.block_average(alt, K)
    worst = 0.0
    spread = 0.0
    for tx, ty in ((3.7, 6.1), (0.0, 0.0), (12.5, 2.2), (7.3, 19.9)):
        truth = (alt.x0 + 120 * cf + tx, alt.y0 - 120 * cf - ty)
        lm, _ = cm.make_local(g, truth, pm, None, 0.0, 0.0, alt)
        lp, _ = cm.make_local(g, truth, pp, None, 0.0, 0.0, alt)
        worst = max(worst, float(np.nanmax(np.abs(lm))))
        spread = max(spread, float(np.nanmax(np.abs(lp))))
    check(worst < 1e-9 and spread > 0.5, f"local mean of a +-1 fine-column pattern (K = 2): every cell 0 "
                                         f"(max {worst:.1e}); the centre samples reach {spread:.2f}")


def test_binned():
    """--fine-local binned: each local cell the mean of the scattered points that fall in it."""
    cf, R = 10.0, 6
    fine = synth_dem(plane, n=240, c=cf)
    pb = cm.CaseParams(radius=R, full_view=True, min_range_cells=0, local="binned")
    truth = (fine.x0 + 120 * cf + 3.7, fine.y0 - 120 * cf - 6.1)
    fr, fc = fine.frac_index(*truth)
    for K, turn in ((2, 0.0), (3, 30.0)):
        g = cm.block_average(fine, K)
        b = cm.binned_points(fine, fr, fc, R, K, turn, pb, g.c, np.random.default_rng(K), False)
        k = np.arange(-R, R + 1)
        e, nn = k[None, :] + b.cx, -(k[:, None] + b.cy)  # the centroid, local cells east / north
        ct, st = math.cos(math.radians(turn)), math.sin(math.radians(turn))
        X, Y = truth[0] + (e * ct - nn * st) * g.c, truth[1] + (e * st + nn * ct) * g.c
        d = np.nanmax(np.abs(b.h - plane(X, Y)))
        inside = np.nanmax(np.abs(np.stack([b.cx, b.cy])))
        check(d < 1e-6 and inside <= 0.5 and b.n.sum() == (2 * R + 1) ** 2 * K * K
              and abs(b.n.mean() - K * K) < 1e-9 and b.n.min() < K * K < b.n.max(),
              f"binned, K = {K}, turned {turn:g} deg, a plane: {b.n.sum()} points, {b.n.min()}-{b.n.max()} "
              f"a cell; each cell the plane at its points' centroid (max diff {d:.1e} m), the centroid "
              f"inside the cell")
    # the noise: that of the mean of the cell's points' noises
    g = cm.block_average(fine, 2)
    pn = cm.CaseParams(radius=10, full_view=True, min_range_cells=0, local="binned")
    e, nn = cm.rover_frame_offsets(10, g.c)
    model = pn.noise0_m + pn.noise_k * (e ** 2 + nn ** 2) / g.c
    z, ratio = [], []
    for s in range(100):
        b = cm.binned_points(fine, fr, fc, 10, 2, 0.0, pn, g.c, np.random.default_rng(s))
        ok = b.n > 0
        z.append(((b.h - b.h0) / b.sd)[ok])
        ratio.append((b.sd * np.sqrt(b.n) / model)[ok])
    z, ratio = np.concatenate(z), float(np.median(np.concatenate(ratio)))
    check(z.size > 30000 and abs(z.std() - 1.0) < 0.02 and 0.9 < ratio < 1.1,
          f"binned noise: residuals over the mean's sd have sd {z.std():.3f} (1); sd x sqrt(n) / the "
          f"model's {ratio:.3f} (about 1)")
    # make_local: the cases stay paired with the other constructions (the same draws follow)
    r1, r2 = np.random.default_rng(8), np.random.default_rng(8)
    cm.make_local(g, truth, pn, r1, 0.0, 0.0, fine)
    cm.make_local(g, truth, cm.CaseParams(radius=10, full_view=True, min_range_cells=0), r2, 0.0, 0.0, fine)
    check(r1.uniform() == r2.uniform(), "binned: the case generator's next draw as with --fine-local point")
    # --points-draw: draw 0 the cases bit for bit; another draw the same truths, priors and
    # seen cells (full view) with other points (other heights), the next draw unchanged
    hills_fine = synth_dem(hills, n=240, c=cf)
    hg = cm.block_average(hills_fine, 2)
    runs = {}
    for d in (0, 1, 2):
        pd = cm.CaseParams(radius=8, full_view=True, min_range_cells=0, local="binned", points_draw=d)
        rng = np.random.default_rng(3)
        h, seen = cm.make_local(hg, truth, pd, rng, 0.0, 0.0, hills_fine)
        runs[d] = (h, seen, rng.uniform())
    ref_h, _ = cm.make_local(hg, truth, cm.CaseParams(radius=8, full_view=True, min_range_cells=0,
                                                               local="binned"), np.random.default_rng(3),
                                       0.0, 0.0, hills_fine)
    check(np.array_equal(runs[0][0], ref_h, equal_nan=True), "--points-draw 0: the binned heights bit for bit")
    # a cell no point fell in is unseen: at K = 2 about e^-4 of them, different ones each draw
    flip = [float(np.mean(runs[d][1] != runs[0][1])) for d in (1, 2)]
    same = all(runs[d][2] == runs[0][2] for d in (1, 2))
    moved = [float(np.nanmax(np.abs(runs[d][0] - runs[0][0]))) for d in (1, 2)]
    check(same and max(flip) < 0.06 and min(moved) > 1e-3
          and not np.array_equal(runs[1][0], runs[2][0], equal_nan=True),
          f"--points-draw 1, 2: the case generator's next draw kept, the seen cells but the empty ones "
          f"({flip} differ), other heights (up to {[round(v, 2) for v in moved]} m apart)")
    # --counts: the cells' point counts (whole, >= 1) where a point fell, NaN elsewhere, the same
    # heights as without them; the local GeoTIFF's band after the heights and any centroids
    with tempfile.TemporaryDirectory() as tmp:
        for cen in (False, True):
            pc = cm.CaseParams(radius=8, full_view=True, min_range_cells=0, local="binned", counts=True,
                               centroids=cen)
            extra = {}
            h, _ = cm.make_local(hg, truth, pc, np.random.default_rng(3), 0.0, 0.0, hills_fine, extra=extra)
            n = extra["n"]
            seen = np.isfinite(h)
            whole = bool(np.all(n[seen] >= 1) and np.all(n[seen] == np.round(n[seen]))
                         and not np.any(seen[np.isnan(n)]))
            path = os.path.join(tmp, f"local{int(cen)}.tif")
            cm.write_local(path, h, hg.c, (extra["cx"], extra["cy"]) if cen else None, n)
            ds = gdal.Open(path)
            band = ds.GetRasterBand(ds.RasterCount).ReadAsArray().astype(np.float64)
            check(whole and np.array_equal(h, ref_h, equal_nan=True) and ds.RasterCount == (4 if cen else 2)
                  and np.array_equal(band, n, equal_nan=True) and 3.0 < float(np.nanmean(n)) < 5.0,
                  f"--counts{' --centroids' if cen else ''}: counts whole and >= 1 where seen (mean "
                  f"{np.nanmean(n):.2f}, K = 2), the same heights, band {ds.RasterCount} of the GeoTIFF")
            ds = None


def test_rover_map_error():
    """tools/real/rover_map_error.py on a plane: the map's interpolants are exact (the block
    mean of a plane is the plane at the coarse centres), so the interpolation error is 0;
    the binning error is the plane's rise from the cell's centre to its points' centroid."""
    import rover_map_error as rme
    fine = synth_dem(plane, n=240, c=10.0)
    g = cm.block_average(fine, 2)
    p = cm.CaseParams(radius=8, local="binned")
    cs = cm.generate(g, 3, 5, p, None, fine)
    x = np.concatenate([rme.case_errors(g, fine, c, 2, p, np.random.default_rng(1)) for c in cs], axis=1)
    b = cm.binned_points(fine, *fine.frac_index(*cs[-1].truth), 8, 2, 0.0, p, g.c, np.random.default_rng(1), False)
    rise = (0.3 * b.cx + 0.7 * b.cy) * g.c  # plane(): 0.3 per metre east, -0.7 per metre north
    want = rise[cs[-1].seen & np.isfinite(b.h0)]
    got = x[2, -want.size:]
    check(np.abs(x[0:2]).max() < 1e-6 and np.abs(got - want).max() < 1e-6 and np.abs(want).max() > 1.0,
          f"rover_map_error on a plane: interpolation error 0 (max {np.abs(x[0:2]).max():.1e} m), the "
          f"binning error the rise to the points' centroid (up to {np.abs(want).max():.1f} m)")


def mast_row(z, r0, c0, cols, H):
    rows = np.full(len(cols), float(r0))
    return cm.mast_visible(z, float(r0), float(c0), rows, np.asarray(cols, dtype=np.float64), H)


def test_mast_view():
    """cases.mast_visible against similar triangles; the grid's cells 1 index unit (the
    ray cast never uses the horizontal metres)."""
    n, r0, c0, H = 80, 40, 10, 2.0
    yy, xx = np.mgrid[0:n, 0:n].astype(np.float64)
    rr, cc = np.broadcast_arrays(yy[25:56, 11:60], xx[25:56, 11:60])
    for name, z in (("flat", np.full((n, n), 7.0)), ("tilted", 0.3 * xx - 0.2 * yy)):
        v = cm.mast_visible(z, r0, c0, rr, cc, H)
        check(v.all(), f"mast view, {name} ground: every one of {v.size} cells seen")
    W, xb = 0.6, 12  # a wall W high, its top from 1 to 2 cells before xb, xb cells from the mast
    z = np.zeros((n, n))
    z[:, c0 + xb - 1:c0 + xb + 1] = W
    end = xb * H / (H - W)  # similar triangles: the shadow reaches d H / (H - W) = 17.14
    dx = np.arange(1, 40)
    v = mast_row(z, r0, c0, c0 + dx, H)
    want = ~((dx > xb) & (dx <= end))
    check(np.array_equal(v, want), f"mast {H:g} m, wall {W:g} m at {xb} cells: along the ray the hidden "
                                   f"cells are {dx[~v].min()}-{dx[~v].max()} (similar triangles: "
                                   f"{xb + 1}-{int(end)}, shadow {end - xb:.2f} cells)")
    v = cm.mast_visible(z, r0, c0, rr, cc, H)
    x = cc - c0
    sure_hidden = (x > xb) & (x <= (xb - 0.5) * H / (H - W))  # a sample within half a cell of the top's edge
    sure_seen = (x <= xb) | (x >= end + 1)
    check(not v[sure_hidden].any() and v[sure_seen].all(),
          f"wall, {v.size} cells off the ray too: hidden behind it, seen before it and beyond "
          f"{end:.2f} + 1 cells")
    D, xa, xf = 0.9, 10, 22  # a pit D deep, its floor from xa + 1 to xf
    z = np.zeros((n, n))
    z[:, c0 + xa + 1:c0 + xf + 1] = -D
    floor = xa * (H + D) / H  # the floor is seen beyond d (H + D) / H = 14.5
    v = mast_row(z, r0, c0, c0 + dx, H)
    want = ~((dx > xa) & (dx < floor))
    check(np.array_equal(v, want), f"pit {D:g} m deep, rim at {xa} cells: hidden floor cells "
                                   f"{dx[~v].min()}-{dx[~v].max()} (similar triangles: to {floor:.2f}), "
                                   f"the far floor, wall and ground seen")
    v = cm.mast_visible(z, r0, c0, rr, cc, H)
    x = cc - c0
    sure_hidden = (x > xa) & (x <= (xa - 0.5) * (H + D) / H)
    sure_seen = (x <= xa) | (x >= floor + 0.5)
    check(not v[sure_hidden].any() and v[sure_seen].all(), f"pit, {v.size} cells off the ray too")
    # through make_local: a wall in a fine DEM; seen cells keep their heights, the paired noise too
    dem = synth_dem(hills, n=200, c=10.0)
    truth = (dem.x0 + 1003.3, dem.y0 - 987.1)
    p0 = cm.CaseParams(radius=15)
    pm = cm.CaseParams(radius=15, mast_m=1.8)
    a0, s0 = cm.make_local(dem, truth, p0, np.random.default_rng(9), 40.0, 3.0)
    a1, s1 = cm.make_local(dem, truth, pm, np.random.default_rng(9), 40.0, 3.0)
    check(s1.sum() < s0.sum() and not (s1 & ~s0).any() and np.array_equal(a0[s1], a1[s1]),
          f"make_local with a 1.8 m mast on hills: {s1.sum()} of {s0.sum()} wedge cells seen, the "
          f"same heights")


def test_outliers():
    """--outliers P: each seen cell is a blunder with probability P, its height uniform over the
    seen heights' range widened by that range on each side; unseen cells stay NaN. At P = 0 the
    cases are the same bit for bit as without the option."""
    dem = synth_dem(plane, n=200, c=1.0)
    truth = (dem.x0 + 100.3, dem.y0 - 100.6)
    p0 = cm.CaseParams(radius=20, noise=False)
    ref, seen = cm.make_local(dem, truth, p0, np.random.default_rng(5), 30.0, 2.0)
    same, _ = cm.make_local(dem, truth, cm.CaseParams(radius=20, noise=False, outlier_frac=0.0),
                            np.random.default_rng(5), 30.0, 2.0)
    check(np.array_equal(ref, same, equal_nan=True), "--outliers 0: the local map bit-identical")
    lo, hi = float(np.nanmin(ref)), float(np.nanmax(ref))
    shares, good = [], True
    for s in range(20):
        bad, seen2 = cm.make_local(dem, truth, cm.CaseParams(radius=20, noise=False, outlier_frac=0.2),
                                   np.random.default_rng(100 + s), 30.0, 2.0)
        moved = seen & (np.abs(bad - ref) > 1e-9)
        inside = np.all((bad[moved] >= lo - (hi - lo) - 1e-9) & (bad[moved] <= hi + (hi - lo) + 1e-9))
        good &= bool(np.array_equal(seen, seen2) and np.all(np.isnan(bad[~seen])) and inside)
        shares.append(moved.sum() / seen.sum())
    check(good, "--outliers 0.2, 20 maps: the same cells seen, unseen ones NaN, blunders within the "
                "widened range")
    m = float(np.mean(shares))
    # 20 maps of ~390 seen cells at p = 0.2: the mean share's sd is about 0.005
    check(abs(m - 0.2) < 0.025, f"--outliers 0.2: {100 * m:.1f} % of the seen cells changed (expected 20 %)")


def test_draw_study():
    import draw_study as ds
    # every draw's covariance its case's: the own and the case-mean coverage agree, CV 0
    rng = np.random.default_rng(11)
    n, m = 40, 25
    var = rng.uniform(0.5, 2.0, n)
    err = rng.standard_normal((n, m, 2)) * np.sqrt(var)[:, None, None]
    cov = np.zeros((n, m, 3))
    cov[:, :, 0] = cov[:, :, 1] = var[:, None]
    r = ds.analyse(err, cov, np.ones((n, m)))
    check(r["cv_median"] == 0.0 and r["coverage_own"] == r["coverage_case_mean"]
          and r["coverage_own"] == r["coverage_own_no_inflation"],
          f"draw_study: a noise-free covariance: CV 0, own coverage = the case mean's ({r['coverage_own']})")
    # the parts of the true trace, exactly: case i's draws are b_i + (+-d, 0) in pairs
    b = rng.uniform(-1.0, 1.0, (n, 2))
    d = 0.3
    sign = np.where(np.arange(m - 1) % 2 == 0, 1.0, -1.0)
    e2 = np.zeros((n, m - 1, 2))
    e2[:, :, 0] = b[:, 0:1] + d * sign
    e2[:, :, 1] = b[:, 1:2]
    c2 = np.ones((n, m - 1, 3)) * np.array([1.0, 1.0, 0.0])
    r = ds.analyse(e2, c2, np.ones((n, m - 1)))
    k = m - 1  # even: the draws' mean is b exactly
    want_pts = d * d * k / (k - 1)
    want_case = float(((b ** 2).sum(axis=1)).mean()) - want_pts / k
    check(abs(r["points_trace"] - want_pts) < 1e-12 and abs(r["case_trace"] - want_case) < 1e-12,
          f"draw_study: the points' part {r['points_trace']:.6f} ({want_pts:.6f}), the case's "
          f"{r['case_trace']:.6f} ({want_case:.6f})")
    # a covariance that doubles and halves from draw to draw: CV 0.6 (sd of (2, 0.5) over their
    # mean 1.25), its own coverage differs from the case mean's; the inflation divides out
    c3 = cov.copy()
    c3[:, 0::2, 0:2] *= 2.0
    c3[:, 1::2, 0:2] *= 0.5
    infl = np.where(np.arange(m) % 2 == 0, 2.0, 0.5)[None, :] * np.ones((n, 1))
    r = ds.analyse(err, c3, infl)
    r0 = ds.analyse(err, cov, np.ones((n, m)))
    cv_want = float(np.std([2.0, 0.5] * 12 + [2.0]) / np.mean([2.0, 0.5] * 12 + [2.0]))
    check(abs(r["cv_median"] - cv_want) < 1e-12 and r["coverage_own"] != r["coverage_case_mean"]
          and r["coverage_own_no_inflation"] == r0["coverage_own"],
          f"draw_study: a covariance x2 and x0.5 by turns: CV {r['cv_median']:.4f} ({cv_want:.4f}); "
          f"without the inflation the noise-free coverage")
    try:
        ds.analyse(err[:, :1], cov[:, :1], np.ones((n, 1)))
        check(False, "draw_study: one draw refused")
    except ds.Fail:
        check(True, "draw_study: one draw refused")
    r = subprocess.run([sys.executable, os.path.join(HERE, "draw_study.py"), "--dem", "aletsch", "--draws", "1"],
                       capture_output=True, text=True)
    check(r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1,
          f"draw_study --draws 1: exit 1, one line ({r.stderr.strip()})")


def test_variance_by_fifth():
    import bench_real as br
    rng = np.random.default_rng(5)
    tr = rng.uniform(1.0, 100.0, 50)
    # errors exactly at the predicted variance: 1 in every fifth
    v = br.variance_by_fifth([((math.sqrt(t), 0.0), (0.25 * t, 0.75 * t, 0.1 * t)) for t in tr])
    check(v is not None and max(abs(x - 1.0) for x in v) < 1e-12,
          f"variance_by_fifth: errors at the prediction give 1 in every fifth ({v})")
    # one error for every case, traces 1..10: fifth k holds traces 2k+1, 2k+2 -> 2 / (4k + 3)
    pairs = [((0.6, -0.8), (0.5 * t, 0.5 * t, 0.0)) for t in range(1, 11)]
    want = [2.0 / (4 * k + 3) for k in range(5)]
    v = br.variance_by_fifth(pairs)
    v2 = br.variance_by_fifth([pairs[k] for k in rng.permutation(10)])
    check(v is not None and max(abs(a - b) for a, b in zip(v, want)) < 1e-12 and v2 == v,
          f"variance_by_fifth: a constant error over traces 1..10 gives 2 / (4k + 3) ({v}), in any order")
    check(br.variance_by_fifth(pairs[:4]) is None, "variance_by_fifth: fewer than 5 right answers give None")
    # through the metrics: a wrong answer (err > 1.5 cells) is not counted
    recs = [{"truth": [100.0, 200.0], "trn": {"err_cells": 0.1, "status": "ok", "failure_probability": 0.0,
                                              "mahalanobis2": 1.0, "x": 100.0 + e[0], "y": 200.0 + e[1],
                                              "cov_m2": list(c), "time_ms": 1.0}} for e, c in pairs]
    recs.append({"truth": [0.0, 0.0], "trn": {"err_cells": 3.0, "status": "ok", "failure_probability": 0.0,
                                              "mahalanobis2": 1.0, "x": 1e3, "y": 0.0, "cov_m2": [1.0, 1.0, 0.0],
                                              "time_ms": 1.0}})
    got = br.metrics(recs, "trn")["calibration"]["variance_by_fifth"]
    check(got is not None and max(abs(a - b) for a, b in zip(got, want)) < 1e-9,
          f"metrics: variance_by_fifth over the right answers only ({got})")


def test_prior_miss():
    dem = synth_dem(hills, n=200)
    c = dem.c
    p0 = cm.CaseParams(radius=10)
    ref = cm.generate(dem, 200, 9, p0)
    same = cm.generate(dem, 200, 9, cm.CaseParams(radius=10, prior_miss=0.0))
    check(all(a.truth == b.truth and a.prior == b.prior and np.array_equal(a.local, b.local, equal_nan=True)
              and not b.prior_miss for a, b in zip(ref, same)), "--prior-miss 0: the cases bit for bit")
    p = cm.CaseParams(radius=10, prior_miss=0.3)
    cs = cm.generate(dem, 200, 9, p)
    miss = [x for x in cs if x.prior_miss]
    hit = [x for x in cs if not x.prior_miss]
    check(len(miss) == 60, f"--prior-miss 0.3 of 200: 60 missing priors ({len(miss)})")
    cheb = np.array([max(abs(x.prior[0] - x.truth[0]), abs(x.prior[1] - x.truth[1])) for x in miss]) / c
    win = np.array([x.window_m for x in miss]) / c
    out = cheb - win
    check(len(miss) > 0 and out.min() >= 1.5 - 1e-9 and cheb.max() <= 12.0 + 1e-9 and cheb.min() < 8.0
          and cheb.max() > 11.5,
          f"missing priors: the truth {out.min():.2f}-{out.max():.2f} cells outside its window (>= 1.5), "
          f"Chebyshev {cheb.min():.2f}-{cheb.max():.2f} cells (in [7.5, 12], spread over it)")
    d = np.array([[x.prior[0] - x.truth[0], x.prior[1] - x.truth[1]] for x in miss]) / c
    big = np.abs(d).argmax(axis=1)
    sides = {(int(k), bool(d[i, k] > 0)) for i, k in enumerate(big)}
    check(len(sides) == 4, f"missing priors on both axes and both sides ({len(sides)} of 4)")
    dh = np.array([[x.prior[0] - x.truth[0], x.prior[1] - x.truth[1]] for x in hit]) / c
    check(np.abs(dh).max() <= 4.0, f"the other priors within +-4 cells (max {np.abs(dh).max():.2f})")
    rc = np.array([dem.frac_index(*x.truth) for x in cs])
    m = p.margin_cells
    check(m == 10 + 6 + 12 + 3 and rc.min() >= m - 1e-9 and rc.max() <= dem.z.shape[0] - 1 - m + 1e-9,
          f"--prior-miss: truths at least {m:g} cells from the edge (R + window + 12 + 3)")
    check(all(a.azimuth_deg == b.azimuth_deg and a.offset_m == b.offset_m for a, b in zip(ref, cs)),
          "--prior-miss: the main generator's azimuths and offsets unchanged")
    cs2 = cm.generate(dem, 200, 9, p)
    check([x.prior for x in cs2] == [x.prior for x in cs], "--prior-miss: same seed, same priors")
    # the metrics: a missing case is never right, its failure is 1
    import bench_real as br
    recs = []
    for k, (err, pm, st, fp) in enumerate(((0.2, False, "ok", 0.01), (3.0, False, "ambiguous", 0.4),
                                           (0.5, True, "ill_conditioned", 0.001), (4.0, True, "ok", 0.01),
                                           (5.0, True, "ambiguous", 0.9))):
        recs.append({"prior_miss": pm, "truth_outside_cells": 2.0 if pm else -3.0,
                     "trn": {"err_cells": err, "status": st, "failure_probability": fp, "mahalanobis2": 1.0,
                             "time_ms": 1.0}})
    mt = br.metrics(recs, "trn")
    mi = mt["prior_miss"]
    want_brier = np.mean([(0.01 - 0) ** 2, (0.4 - 1) ** 2, (0.001 - 1) ** 2, (0.01 - 1) ** 2, (0.9 - 1) ** 2])
    check(mt["success"] == 1 and mt["prior_hit"]["success"] == 1 and mt["prior_hit"]["n"] == 2
          and abs(mt["brier"] - want_brier) < 1e-12,
          f"metrics: the missing case 0.5 cells off is not right (successes {mt['success']}), Brier "
          f"{mt['brier']:.4f} counts it failed ({want_brier:.4f})")
    want_miss = np.mean([(0.001 - 1) ** 2, (0.01 - 1) ** 2, (0.9 - 1) ** 2])
    want_unfl = np.mean([(0.01 - 1) ** 2, (0.9 - 1) ** 2])
    check(mi["n"] == 3 and mi["fixes"] == 1 and mi["confidently_wrong"] == 1 and mi["near_truth"] == 1
          and mi["below_half"] == 2 and abs(mi["brier"] - want_miss) < 1e-12
          and mi["n_unflagged"] == 2 and abs(mi["brier_unflagged"] - want_unfl) < 1e-12,
          f"miss metrics: 3 cases, 1 fix, 1 confidently wrong, 1 near the truth, Brier against 1 {mi['brier']:.4f} "
          f"({want_miss:.4f}), not ill_conditioned {mi['brier_unflagged']:.4f} ({want_unfl:.4f})")
    b = os.path.join(HERE, "bench_real.py")
    for args, what in ((["--prior-miss", "1.5"], "--prior-miss 1.5"), (["--prior-miss", "-0.1"], "--prior-miss -0.1"),
                       (["--prior-miss", "0.5", "--miss-max", "7"], "--miss-max 7"),
                       (["--prior-miss", "0.5", "--miss-max", "inf"], "--miss-max inf"),
                       (["--miss-max", "10"], "--miss-max without --prior-miss")):
        r = subprocess.run([sys.executable, b] + args, capture_output=True, text=True)
        check(r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1 and r.stdout == "",
              f"bench_real {what}: exit 1, one line ({r.stderr.strip()})")


def test_dem_file():
    """--dem-file: a user's own DEM. Missing and geographic files exit 1 with one line;
    a projected one runs end to end (when trn is built) under its file name's id."""
    import json
    from osgeo import osr
    b = os.path.join(HERE, "bench_real.py")
    trn = os.path.join(os.path.dirname(os.path.dirname(HERE)), "build", "host-release", "trn")
    with tempfile.TemporaryDirectory() as tmp:
        rng = np.random.default_rng(3)
        n = 120
        yy, xx = np.mgrid[0:n, 0:n].astype(np.float64)
        z = np.zeros((n, n))
        for _ in range(12):  # rolling terrain of several wave directions, 8-30 cells
            k = 2 * math.pi / rng.uniform(8.0, 30.0)
            t = rng.uniform(0.0, math.pi)
            z += rng.uniform(1.0, 4.0) * np.sin(k * (xx * math.cos(t) + yy * math.sin(t)) + rng.uniform(0, 6.3))
        paths = {}
        for name, epsg, cell in (("geo_dem", 4326, 0.001), ("my_hills", 32633, 10.0)):
            paths[name] = os.path.join(tmp, name + ".tif")
            ds = gdal.GetDriverByName("GTiff").Create(paths[name], n, n, 1, gdal.GDT_Float32)
            ds.SetGeoTransform((500000.0 if epsg != 4326 else 15.0, cell, 0.0,
                                5000000.0 if epsg != 4326 else 45.0, 0.0, -cell))
            sr = osr.SpatialReference()
            sr.ImportFromEPSG(epsg)
            ds.SetProjection(sr.ExportToWkt())
            ds.GetRasterBand(1).WriteArray(z.astype(np.float32))
            ds = None
        out = os.path.join(tmp, "out")
        for args, what, want in ((["--dem-file", os.path.join(tmp, "none.tif")], "missing file", "no such file"),
                                 (["--dem-file", paths["geo_dem"], "--cases", "2", "--out", out],
                                  "geographic file", "geographic CRS")):
            if not os.path.exists(trn) and what == "geographic file":
                continue  # parse_args refuses a missing trn first
            r = subprocess.run([sys.executable, b] + args, capture_output=True, text=True)
            check(r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1 and want in r.stderr,
                  f"bench_real --dem-file, {what}: exit 1, one line naming it ({r.stderr.strip()})")
        if not os.path.exists(trn):
            print("skip bench_real --dem-file run (no build/host-release/trn)")
            return
        r = subprocess.run([sys.executable, b, "--dem-file", paths["my_hills"], "--cases", "20", "--seed", "3",
                            "--radius", "12", "--no-plot", "--out", out], capture_output=True, text=True)
        ok = r.returncode == 0 and os.path.exists(os.path.join(out, "bench.json"))
        j = json.load(open(os.path.join(out, "bench.json"))) if ok else {"dems": {}}
        d = j["dems"].get("my_hills")
        check(ok and list(j["dems"]) == ["my_hills"] and d["meta"]["character"] == "user file"
              and len(d["cases"]) == 20 and all(k in d["metrics"] for k in ("trn", "ssd", "ncc")),
              f"bench_real --dem-file my_hills.tif: only that DEM, 20 cases, trn and both peers "
              f"(exit {r.returncode}{'' if ok else ': ' + r.stderr.strip()[-200:]})")
        if ok:
            rate = d["metrics"]["trn"]["rate"]
            check(rate >= 0.9, f"bench_real --dem-file: trn right in {100 * rate:.0f} % of 20 noisy cases "
                               f"on smooth rolling terrain (>= 90 %)")
        out2 = os.path.join(tmp, "out_miss")
        r = subprocess.run([sys.executable, b, "--dem-file", paths["my_hills"], "--cases", "20", "--seed", "3",
                            "--radius", "12", "--no-plot", "--prior-miss", "0.5", "--out", out2],
                           capture_output=True, text=True)
        ok = r.returncode == 0 and os.path.exists(os.path.join(out2, "bench.json"))
        d = json.load(open(os.path.join(out2, "bench.json")))["dems"]["my_hills"] if ok else None
        if d is None:
            check(False, f"bench_real --prior-miss 0.5 runs (exit {r.returncode}: {r.stderr.strip()[-200:]})")
            return
        c = d["meta"]["cell_m"]
        miss = [x for x in d["cases"] if x["prior_miss"]]
        outside = [max(abs(x["prior"][0] - x["truth"][0]), abs(x["prior"][1] - x["truth"][1])) - x["window_m"]
                   for x in miss]
        t = d["metrics"]["trn"]
        check(len(miss) == 10 and min(outside) >= 1.5 * c - 1e-6 and t["prior_miss"]["n"] == 10
              and t["prior_hit"]["n"] == 10 and t["success"] == t["prior_hit"]["success"]
              and "prior misses" in r.stdout,
              f"bench_real --prior-miss 0.5, 20 cases: 10 missing, each truth {min(outside) / c:.2f} cells "
              f"or more outside its window (>= 1.5), scored apart, none right, printed")


def main():
    test_frame()
    test_file()
    test_generate()
    test_noise()
    test_truth_fine()
    case = test_peers()
    test_trn(*case)
    test_point_sample()
    test_float_nan_tif()
    test_cli()
    test_local_mean()
    test_outliers()
    test_binned()
    test_mast_view()
    test_rover_map_error()
    test_variance_by_fifth()
    test_draw_study()
    test_prior_miss()
    test_dem_file()
    if FAILS:
        print(f"test_real: {len(FAILS)} check(s) failed", file=sys.stderr)
        return 1
    print("test_real: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
