#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tests/cli/test_cli_dem.py - real DEM files through dem_read (CTest `cli_dem`).

    python3 tests/cli/test_cli_dem.py PATH/TO/trn WORKDIR

Every class of real-world DEM input that dem_read() converts or refuses, seen
through `trn select` and `trn localize`:

- ISIS / PDS special pixels and +-FLT_MAX cells (|v| >= 3e38) are "not seen":
  a DEM holding a block of them gives exactly the answers (JSON and the
  per-candidate map) of its twin with NaN there, and not those of the DEM
  without the hole; a global and a local map holding them still localize.
- A geographic CRS (Earth and Mars) is refused with the gdalwarp hint; a file
  with no CRS is accepted.
- A projected CRS in US survey feet (EPSG:2227, also as a compound CRS with
  heights in ftUS from its vertical CRS) or international feet, heights in
  feet (band unit), and band scale/offset: each gives the answers of its
  metre twin, the per-candidate map comes back on the metre grid in a metre
  CRS that names the same places, and `trn localize` with a feet global map
  and a metre rover-frame local map finds the truth in metres.
- An unknown height unit and a DEM over TRN_MAX_DIM (4096) cells a side are
  refused with one line naming the unit / the size, the limit and the
  gdal_translate hint.
- A binned local map's centroid bands (--centroid-bands): given, the answer
  is the truth where without them it moves with their common offset; zero
  centroids give the one-band file's answer; a seen cell's centroid missing
  or beyond half a cell, a band that is not there and a heading search are
  refused with one line.
- Its point counts (--count-band): counts of 1 beside the centroids give the
  centroids' answer; counts of 16 another covariance, the same answer; a seen
  cell's count below 1 or missing, a band that is not there and a heading
  search are refused with one line.
Maps are small (96 x 96 cells, 40 x 40 local) so the ASan build stays quick.
"""
import math
import os
import shutil
import sys

import numpy as np
from osgeo import gdal, osr

gdal.UseExceptions()

import clitest  # noqa: E402  (tests/cli/, the script's own directory)

TRN = os.path.abspath(sys.argv[1])
WORK = os.path.abspath(sys.argv[2])
H = clitest.Harness(TRN, sub=(), timeout=600)
check, run, expect_error, run_json = H.check, H.run, H.expect_error, H.run_json

FTUS = 1200.0 / 3937.0  # US survey foot, m
FT = 0.3048             # international foot, m


def p(name):
    return os.path.join(WORK, name)


def srs_of(text):
    s = osr.SpatialReference()
    s.SetFromUserInput(text)
    s.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    return s


def write(path, arr, gt, srs=None, unit=None, scale=None, offset=None, nodata=None):
    """A one-band float32 GeoTIFF with optional CRS (an osr object), unit type, scale/offset, no-data."""
    mem = gdal.GetDriverByName("MEM").Create("", arr.shape[1], arr.shape[0], 1, gdal.GDT_Float32)
    mem.SetGeoTransform(gt)
    if srs is not None:
        mem.SetProjection(srs.ExportToWkt())
    b = mem.GetRasterBand(1)
    if unit is not None:
        b.SetUnitType(unit)
    if scale is not None:
        b.SetScale(scale)
    if offset is not None:
        b.SetOffset(offset)
    if nodata is not None:
        b.SetNoDataValue(nodata)
    b.WriteArray(arr)
    gdal.GetDriverByName("GTiff").CreateCopy(path, mem)
    mem = None


def read(path):
    if not os.path.exists(path):  # a failed run (already counted): an empty stand-in
        check(False, f"{os.path.basename(path)} was not written")
        return (0.0,) * 6, np.full((1, 1), np.nan), ""
    ds = gdal.Open(path)
    arr = ds.GetRasterBand(1).ReadAsArray().astype(np.float64)
    out = (ds.GetGeoTransform(), arr, ds.GetProjection())
    ds = None
    return out


def scaled_gt(gt, k):
    """The geotransform in a unit k times the metre (origin and cell divided by k)."""
    return (gt[0] / k, gt[1] / k, 0.0, gt[3] / k, 0.0, gt[5] / k)


shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)

# ---- the base terrain (metres, no CRS) -----------------------------------------
# A site in NAD83 / California zone 3 (EPSG:26943, metres), whose feet twin is EPSG:2227.
N, CELL = 96, 0.1
X0, Y0 = 1839000.0, 640000.0
GT = (X0, CELL, 0.0, Y0 + N * CELL, 0.0, -CELL)
base = p("base.tif")
rc, out, err = run("terrain", "--out", base, "--size-cells", N, "--origin", f"{X0:.1f},{Y0:.1f}",
                   "--coverage", "0.2", "--seed", "5")
check(rc == 0, f"terrain: {err}")
G = read(base)[1].astype(np.float32)
ROVER = (X0 + 4.85, Y0 + 4.75)  # cell (48, 47)
SEL = ["--rover", f"{ROVER[0]},{ROVER[1]}", "--max-range-m", "3", "--patch-m", "1", "--separation-m", "0.5",
       "--next-best", "4", "--json"]
SEL_KEYS = ("sigma_x_m", "sigma_y_m", "rho", "uncertainty_m", "candidates", "informative")


def select(dem, out_map):
    return run_json("select", "--dem", dem, "--out-map", out_map, *SEL)


def same_answer(label, a, b, rel=0.0, pos=0.0):
    """Two select answers agree: exactly (rel = pos = 0) or within rel (sigmas) and pos (m, positions)."""
    ok = all(k in a and k in b for k in SEL_KEYS + ("target", "next_best"))
    check(ok, f"{label}: both answers complete ({sorted(a)}, {sorted(b)})")
    if not ok:
        return
    for k in ("candidates", "informative"):
        check(a[k] == b[k], f"{label}: {k} {a[k]} vs {b[k]}")
    for k in ("sigma_x_m", "sigma_y_m", "uncertainty_m"):
        check(abs(a[k] - b[k]) <= rel * abs(b[k]), f"{label}: {k} {a[k]!r} vs {b[k]!r}")
    check(abs(a["rho"] - b["rho"]) <= rel, f"{label}: rho {a['rho']!r} vs {b['rho']!r}")
    ta = [a["target"]] + a["next_best"]
    tb = [b["target"]] + b["next_best"]
    check(len(ta) == len(tb), f"{label}: {len(ta)} vs {len(tb)} ranked targets")
    for i, (u, v) in enumerate(zip(ta, tb)):
        check(abs(u["x_m"] - v["x_m"]) <= pos and abs(u["y_m"] - v["y_m"]) <= pos,
              f"{label}: target {i} at ({u['x_m']}, {u['y_m']}) vs ({v['x_m']}, {v['y_m']})")


def same_map(label, ma, mb, rel=0.0):
    """Two per-candidate maps: same NaN (not a candidate) and +inf cells, values equal within rel."""
    check(ma.shape == mb.shape, f"{label}: map shapes {ma.shape} vs {mb.shape}")
    if ma.shape != mb.shape:
        return
    check(np.array_equal(np.isnan(ma), np.isnan(mb)), f"{label}: same candidates (NaN pattern)")
    check(np.array_equal(np.isposinf(ma), np.isposinf(mb)), f"{label}: same ill-conditioned candidates")
    fa, fb = np.isfinite(ma), np.isfinite(mb)
    if fa.any() and np.array_equal(fa, fb):
        d = np.abs(ma[fa] - mb[fa]) / np.abs(mb[fa])
        check(float(d.max()) <= rel, f"{label}: per-candidate uncertainties differ by {float(d.max()):.3g} > {rel}")


# ---- 1. ISIS special pixels and +-FLT_MAX: not seen ------------------------------
# The five ISIS 32-bit float special pixels (NULL, LRS, LIS, HIS, HRS) by bit
# pattern, then +FLT_MAX, a value just inside 3e38's side and the boundary.
specials = np.array([0xFF7FFFFB, 0xFF7FFFFC, 0xFF7FFFFD, 0xFF7FFFFE, 0xFF7FFFFF, 0x7F7FFFFF],
                    np.uint32).view(np.float32)
check(abs(float(specials[0]) + 3.4028226550889e38) < 1e25, f"ISIS NULL is -3.4028226550889e38 ({specials[0]})")
check(float(specials[4]) == -float(np.finfo(np.float32).max), "ISIS HIGH_REPR_SAT is -FLT_MAX")
specials = np.concatenate([specials, np.array([-3.1e38, 3.0e38], np.float32)])
# The hole: rows 30..49, columns 50..69, in reach of the rover (1..3 m) and next to it.
hole = (slice(30, 50), slice(50, 70))
isis = G.copy()
for j in range(20):  # column j of the hole: special value j mod 8
    isis[hole[0], 50 + j] = specials[j % len(specials)]
check(bool((np.abs(isis[hole]) >= 3.0e38).all()), "the hole is all special values")
nan_twin = G.copy()
nan_twin[hole] = np.nan
write(p("isis.tif"), isis, GT)
write(p("isis_nd.tif"), isis, GT, nodata=-32768.0)  # a declared no-data value that is not these
write(p("nan.tif"), nan_twin, GT)
r_nan = select(p("nan.tif"), p("nan_map.tif"))
r_isis = select(p("isis.tif"), p("isis_map.tif"))
r_isis_nd = select(p("isis_nd.tif"), p("isis_nd_map.tif"))
r_full = select(base, p("full_map.tif"))
same_answer("ISIS/FLT_MAX hole = NaN hole", r_isis, r_nan)
same_answer("ISIS hole with another no-data value = NaN hole", r_isis_nd, r_nan)
m_nan, m_isis, m_full = read(p("nan_map.tif"))[1], read(p("isis_map.tif"))[1], read(p("full_map.tif"))[1]
same_map("ISIS hole: per-candidate map = NaN hole's", m_isis, m_nan)
same_map("ISIS hole (declared -32768): per-candidate map = NaN hole's", read(p("isis_nd_map.tif"))[1], m_nan)
check(not np.array_equal(np.isnan(m_nan), np.isnan(m_full)) or
      not np.allclose(np.nan_to_num(m_nan, posinf=9), np.nan_to_num(m_full, posinf=9)),
      "the hole matters: the NaN-hole map differs from the whole DEM's")
for path in (p("isis_map.tif"), p("nan_map.tif")):
    m = read(path)[1]
    fin = m[np.isfinite(m)]
    # no special value leaked into a gradient: it would give an absurdly small sigma (or a huge
    # one); the height prediction's flattest patches reach a few metres on this map (the whole
    # DEM's too)
    check(fin.size > 0 and float(fin.min()) > 1e-6 and float(fin.max()) < 100.0,
          f"{os.path.basename(path)}: uncertainties are sane (1e-6 to 100 m): {fin.min():.3g}-{fin.max():.3g}")

# localize: the special values in the global map and in the local map.
TC, TR = 40, 50  # the rover on the centre of global cell (40, 50)
truth = (X0 + (TC + 0.5) * CELL, Y0 + N * CELL - (TR + 0.5) * CELL)
LC0, LR0, L = 20, 30, 40
crop = G[LR0:LR0 + L, LC0:LC0 + L].copy()
rover_gt = ((LC0 - (TC + 0.5)) * CELL, CELL, 0.0, -(LR0 - (TR + 0.5)) * CELL, 0.0, -CELL)
write(p("local.tif"), crop, rover_gt)
crop_isis = crop.copy()
crop_isis[5:15, 25:35] = specials[0]
crop_isis[20:25, 2:8] = specials[4]
crop_nan = crop.copy()
crop_nan[5:15, 25:35] = np.nan
crop_nan[20:25, 2:8] = np.nan
write(p("local_isis.tif"), crop_isis, rover_gt)
write(p("local_nan.tif"), crop_nan, rover_gt)
prior = f"{truth[0] + 0.4:.3f},{truth[1] - 0.3:.3f}"
LOC = ["--prior", prior, "--window-m", "2", "--json"]


def localize(dem, local, label, want=truth, tol=0.03):
    r = run_json("localize", "--dem", dem, "--local", local, *LOC)
    if "x_m" in r:
        e = math.hypot(r["x_m"] - want[0], r["y_m"] - want[1])
        print(f"localize {label}: ({r['x_m']:.4f}, {r['y_m']:.4f}) error {e:.4f} m, status {r['status']}")
        check(e < tol and r["status"] == "ok", f"localize {label}: error {e:.4f} m, status {r['status']}")
    else:
        check(False, f"localize {label}: no position in {r}")
    return r


# The global maps' special values lie in a corner of the search area, away from
# the local map's footprint (a 2 x 2 m hole over the footprint itself moves
# the fix, NaN or ISIS alike: the core's business, not dem_read's).
g_isis, g_nan = G.copy(), G.copy()
for j in range(16):
    g_isis[78:92, 70 + j] = specials[j % len(specials)]
g_nan[78:92, 70:86] = np.nan
write(p("global_isis.tif"), g_isis, GT)
write(p("global_nan.tif"), g_nan, GT)
l_isis = localize(p("global_isis.tif"), p("local_isis.tif"), "ISIS global and local")
l_nan = localize(p("global_nan.tif"), p("local_nan.tif"), "NaN global and local")
untimed = [{k: v for k, v in r.items() if "time" not in k} for r in (l_isis, l_nan)]  # wall times differ
check(untimed[0] == untimed[1], f"localize: ISIS-holed maps give the NaN-holed maps' answer ({l_isis} vs {l_nan})")

# ---- 2. geographic CRS refused, no CRS accepted -------------------------------------
GEO_HINT = "reproject it to metres first, e.g. gdalwarp -t_srs EPSG:326NN"
write(p("wgs84.tif"), G, (-121.5, 1e-6, 0.0, 38.0, 0.0, -1e-6), srs=srs_of("EPSG:4326"))
expect_error(1, "is in a geographic CRS (degrees)", "select", "--dem", p("wgs84.tif"), *SEL)
expect_error(1, GEO_HINT, "select", "--dem", p("wgs84.tif"), *SEL)
expect_error(1, "gdalwarp -t_srs EPSG:326NN", "localize", "--dem", p("wgs84.tif"), "--local", p("local.tif"), *LOC)
# Mars, planetocentric degrees (IAU 2015)
write(p("mars_geo.tif"), G, (137.4, 1e-7, 0.0, -4.6, 0.0, -1e-7), srs=srs_of("IAU_2015:49900"))
expect_error(1, "geographic CRS (degrees)", "select", "--dem", p("mars_geo.tif"), *SEL)
# a rover-frame local map tagged geographic is refused too
write(p("local_wgs84.tif"), crop, rover_gt, srs=srs_of("EPSG:4326"))
expect_error(1, "'" + p("local_wgs84.tif") + "' is in a geographic CRS", "localize", "--dem", base,
             "--local", p("local_wgs84.tif"), *LOC)
# no CRS at all: accepted (base.tif has none), and a metre CRS changes nothing
check(read(base)[2] == "", "base.tif has no CRS")
write(p("metre.tif"), G, GT, srs=srs_of("EPSG:26943"))
r_m = select(p("metre.tif"), p("metre_map.tif"))
same_answer("EPSG:26943 (metres) = no CRS", r_m, r_full)
m_m = read(p("metre_map.tif"))
same_map("EPSG:26943 map = no-CRS map", m_m[1], m_full)
check("26943" in m_m[2], "a metre CRS is handed on unchanged (EPSG:26943 on --out-map)")


# ---- 3. feet and scaled heights: the metre twin's answers ---------------------------------
def check_metre_map(label, path):
    """--out-map of a converted DEM: the metre grid, a metre CRS naming the same places as EPSG:26943."""
    gt, m, wkt = read(path)
    check(all(abs(a - b) < 1e-6 for a, b in zip(gt, GT)), f"{label}: --out-map geotransform {gt} in metres")
    if not wkt:
        check(False, f"{label}: --out-map has no CRS")
        return m
    s = osr.SpatialReference()
    s.ImportFromWkt(wkt)
    s.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
    check(s.IsProjected() and abs(s.GetLinearUnits() - 1.0) < 1e-12 and not s.IsCompound(),
          f"{label}: --out-map CRS is projected in metres ({s.GetLinearUnitsName()})")
    t = osr.CoordinateTransformation(s, srs_of("EPSG:26943"))
    x, y, _ = t.TransformPoint(X0, Y0)
    check(math.hypot(x - X0, y - Y0) < 0.01, f"{label}: the metre CRS names the same places ({x}, {y})")
    return m


TOL = dict(rel=1e-4, pos=1e-6)
ft_us = srs_of("EPSG:2227")
check(abs(ft_us.GetLinearUnits() - FTUS) < 1e-15, "EPSG:2227 is in US survey feet")
# a) EPSG:2227: geotransform and heights in US survey feet (band unit)
write(p("ftus.tif"), (G / FTUS).astype(np.float32), scaled_gt(GT, FTUS), srs=ft_us, unit="US survey foot")
r = select(p("ftus.tif"), p("ftus_map.tif"))
same_answer("EPSG:2227, heights in ftUS = metre twin", r, r_m, **TOL)
same_map("EPSG:2227 map = metre twin's", check_metre_map("EPSG:2227", p("ftus_map.tif")), m_m[1], rel=1e-4)
# b) compound EPSG:2227+6360 (NAVD88 height in ftUS): the heights' unit from the vertical CRS
write(p("ftus_compound.tif"), (G / FTUS).astype(np.float32), scaled_gt(GT, FTUS), srs=srs_of("EPSG:2227+6360"))
ds = gdal.Open(p("ftus_compound.tif"))
check(ds.GetSpatialRef().IsCompound() == 1, "the compound test file keeps its vertical CRS")
# (GDAL's GeoTIFF driver also reports the vertical unit as the band's unit type.)
ds = None
r = select(p("ftus_compound.tif"), p("ftus_compound_map.tif"))
same_answer("EPSG:2227+6360, heights in ftUS from the vertical CRS = metre twin", r, r_m, **TOL)
check_metre_map("EPSG:2227+6360", p("ftus_compound_map.tif"))
# c) international feet (EPSG:26943 with its unit set to the foot), heights in metres (band unit "m")
ft_int = srs_of("EPSG:26943")
ft_int.SetLinearUnitsAndUpdateParameters("foot", FT)
write(p("ft.tif"), G, scaled_gt(GT, FT), srs=ft_int, unit="m")
r = select(p("ft.tif"), p("ft_map.tif"))
same_answer("international feet CRS, heights in m = metre twin", r, r_m, **TOL)
check_metre_map("international feet", p("ft_map.tif"))
# d) metre CRS, heights in international feet ("ft", "feet")
for u in ("ft", "feet", "Foot"):
    write(p("zft.tif"), (G / FT).astype(np.float32), GT, srs=srs_of("EPSG:26943"), unit=u)
    r = select(p("zft.tif"), p("zft_map.tif"))
    same_answer(f"heights in '{u}' = metre twin", r, r_m, **TOL)
# e) band scale and offset (stored = (height - 100) / 0.5)
write(p("scaled.tif"), ((G - 100.0) / 0.5).astype(np.float32), GT, srs=srs_of("EPSG:26943"), scale=0.5,
      offset=100.0)
r = select(p("scaled.tif"), p("scaled_map.tif"))
same_answer("band scale 0.5, offset 100 = metre twin", r, r_m, **TOL)
# f) localize: a global map in US survey feet, the rover-frame local map in metres (no CRS)
l_m = localize(p("metre.tif"), p("local.tif"), "metre global")
l_ft = localize(p("ftus.tif"), p("local.tif"), "ftUS global")
if "x_m" in l_m and "x_m" in l_ft:
    check(math.hypot(l_m["x_m"] - l_ft["x_m"], l_m["y_m"] - l_ft["y_m"]) < 1e-4,
          f"localize: ftUS global = metre global ({l_ft['x_m']}, {l_ft['y_m']})")

# ---- 4. unknown height unit refused ---------------------------------------------------
write(p("furlong.tif"), G, GT, unit="furlong")
expect_error(1, "heights in unit 'furlong'", "select", "--dem", p("furlong.tif"), *SEL)
expect_error(1, "convert the heights to metres", "select", "--dem", p("furlong.tif"), *SEL)
write(p("local_deg.tif"), crop, rover_gt, unit="degC")
expect_error(1, "heights in unit 'degC'", "localize", "--dem", base, "--local", p("local_deg.tif"), *LOC)

# ---- 5. larger than TRN_MAX_DIM (4096) a side: refused with the cut --------------------------
write(p("wide.tif"), np.zeros((8, 4097), np.float32), GT)
write(p("tall.tif"), np.zeros((4097, 8), np.float32), GT)
expect_error(1, "is 4097 x 8 cells; the maximum side is 4096 cells", "select", "--dem", p("wide.tif"), *SEL)
expect_error(1, "gdal_translate -srcwin XOFF YOFF XSIZE YSIZE IN.tif OUT.tif", "select", "--dem", p("wide.tif"),
             *SEL)
expect_error(1, "is 8 x 4097 cells; the maximum side is 4096 cells", "localize", "--dem", base,
             "--local", p("tall.tif"), *LOC)
expect_error(1, "gdalwarp -tr", "localize", "--dem", p("tall.tif"), "--local", p("local.tif"), *LOC)


# ---- 6. a binned local map's centroids (--centroid-bands) -----------------------------
def write_bands(path, bands, gt):
    """A float32 GeoTIFF of several bands, no CRS, no-data NaN."""
    mem = gdal.GetDriverByName("MEM").Create("", bands[0].shape[1], bands[0].shape[0], len(bands),
                                             gdal.GDT_Float32)
    mem.SetGeoTransform(gt)
    for k, v in enumerate(bands):
        mem.GetRasterBand(k + 1).SetNoDataValue(float("nan"))
        mem.GetRasterBand(k + 1).WriteArray(v.astype(np.float32))
    gdal.GetDriverByName("GTiff").CreateCopy(path, mem)
    mem = None


def bilinear(z, rows, cols):
    r0, c0 = np.floor(rows).astype(int), np.floor(cols).astype(int)
    fr, fc = rows - r0, cols - c0
    z = z.astype(np.float64)
    return ((z[r0, c0] * (1 - fc) + z[r0, c0 + 1] * fc) * (1 - fr) +
            (z[r0 + 1, c0] * (1 - fc) + z[r0 + 1, c0 + 1] * fc) * fr)


# Each local cell the ground (the map's bilinear surface) at its points' centroid: a common
# (0.3, -0.2) cells (east, south) plus up to 0.1 more per cell. Given the centroids, the
# refinement reads the map there and finds the truth; without them the answer moves with the
# common offset (0.036 m).
rng = np.random.default_rng(3)
cx = 0.3 + rng.uniform(-0.1, 0.1, crop.shape)
cy = -0.2 + rng.uniform(-0.1, 0.1, crop.shape)
jj, ii = np.meshgrid(np.arange(L), np.arange(L))
binned = bilinear(G, LR0 + ii + cy, LC0 + jj + cx)
write_bands(p("local_binned.tif"), [binned, cx, cy], rover_gt)
write_bands(p("local_zero.tif"), [crop, 0.0 * crop, 0.0 * crop], rover_gt)
r_with = run_json("localize", "--dem", base, "--local", p("local_binned.tif"), "--centroid-bands", "2",
                  *LOC)
r_without = run_json("localize", "--dem", base, "--local", p("local_binned.tif"), *LOC)
if "x_m" in r_with and "x_m" in r_without:
    e_with = math.hypot(r_with["x_m"] - truth[0], r_with["y_m"] - truth[1])
    e_without = math.hypot(r_without["x_m"] - truth[0], r_without["y_m"] - truth[1])
    print(f"localize binned: error {e_with:.4f} m given the centroids, {e_without:.4f} m without")
    check(e_with < 0.005 and r_with["status"] == "ok" and r_with.get("centroids") is True,
          f"localize binned, --centroid-bands 2: error {e_with:.4f} m, {r_with}")
    check(e_without > 0.02 and r_without.get("centroids") is False,
          f"localize binned without its centroids: error {e_without:.4f} m (the common offset, 0.036 m)")
else:
    check(False, f"localize binned: no position in {r_with} / {r_without}")
# zero centroids: the cells' centres, the same answer as the one-band file's
r_zero = run_json("localize", "--dem", base, "--local", p("local_zero.tif"), "--centroid-bands", "2", *LOC)
r_one = run_json("localize", "--dem", base, "--local", p("local.tif"), *LOC)
untimed = [{k: v for k, v in r.items() if "time" not in k and k != "centroids"} for r in (r_zero, r_one)]
check(untimed[0] == untimed[1], f"localize: zero centroids = the cells' centres ({r_zero} vs {r_one})")
# refused: a seen cell's centroid beyond half a cell or missing, a band that is not there,
# and a heading search (the centroids are read at heading 0 only)
far = cx.copy()
far[7, 9] = 0.7
write_bands(p("local_far.tif"), [binned, far, cy], rover_gt)
expect_error(1, "local cell (9, 7) is seen but its centroid (0.7, ", "localize", "--dem", base, "--local",
             p("local_far.tif"), "--centroid-bands", "2", *LOC)
gap = cy.copy()
gap[3, 4] = np.nan
write_bands(p("local_gap.tif"), [binned, cx, gap], rover_gt)
expect_error(1, "missing or more than 0.5 cells from its centre", "localize", "--dem", base, "--local",
             p("local_gap.tif"), "--centroid-bands", "2", *LOC)
expect_error(1, "--centroid-bands: ", "localize", "--dem", base, "--local", p("local_binned.tif"),
             "--centroid-bands", "3", *LOC)
expect_error(2, "--centroid-bands does not apply to a heading search", "localize", "--dem", base, "--local",
             p("local_binned.tif"), "--centroid-bands", "2", "--heading-deg", "1", *LOC)

# ---- 7. its point counts (--count-band) ------------------------------------------------
ones = np.where(np.isfinite(binned), 1.0, np.nan)
write_bands(p("local_counts1.tif"), [binned, cx, cy, ones], rover_gt)
write_bands(p("local_counts16.tif"), [binned, cx, cy, 16.0 * ones], rover_gt)
r_c1 = run_json("localize", "--dem", base, "--local", p("local_counts1.tif"), "--centroid-bands", "2",
                "--count-band", "4", *LOC)
untimed = [{k: v for k, v in r.items() if "time" not in k and k != "point_counts"} for r in (r_c1, r_with)]
check(untimed[0] == untimed[1] and r_c1.get("point_counts") is True,
      f"localize: counts of 1 = one measurement a cell ({r_c1} vs {r_with})")
r_c16 = run_json("localize", "--dem", base, "--local", p("local_counts16.tif"), "--centroid-bands", "2",
                 "--count-band", "4", *LOC)
if "x_m" in r_c16:
    e16 = math.hypot(r_c16["x_m"] - truth[0], r_c16["y_m"] - truth[1])
    print(f"localize binned, 16 points a cell: error {e16:.4f} m, sigma_x {r_c16['sigma_x_m']:.3g} m "
          f"(one a cell: {r_with.get('sigma_x_m')})")
    check(e16 < 0.005 and r_c16["status"] == "ok" and r_c16["cov_m2"] != r_with.get("cov_m2"),
          f"localize binned, --count-band 4 (16 a cell): error {e16:.4f} m, another covariance")
else:
    check(False, f"localize binned, --count-band 4: no position in {r_c16}")
low = ones.copy()
low[7, 9] = 0.5
write_bands(p("local_low.tif"), [binned, low], rover_gt)
expect_error(1, "local cell (9, 7) is seen but its point count 0.5 is missing or outside [1, ", "localize",
             "--dem", base, "--local", p("local_low.tif"), "--count-band", "2", *LOC)
low[7, 9] = np.nan
write_bands(p("local_low.tif"), [binned, low], rover_gt)
expect_error(1, "local cell (9, 7) is seen but its point count nan is missing", "localize", "--dem", base,
             "--local", p("local_low.tif"), "--count-band", "2", *LOC)
expect_error(1, "--count-band: ", "localize", "--dem", base, "--local", p("local_counts1.tif"),
             "--count-band", "5", *LOC)
expect_error(2, "--count-band does not apply to a heading search", "localize", "--dem", base, "--local",
             p("local_counts1.tif"), "--count-band", "4", "--heading-window-deg", "1", *LOC)

sys.exit(H.finish("cli_dem"))
