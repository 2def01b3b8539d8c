#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tests/cli/test_cli_select.py - `trn select` and `trn field` end to end (CTest `cli_select`).

    python3 tests/cli/test_cli_select.py PATH/TO/trn WORKDIR

Oracles: an elongated rock at a known map position and orientation (the
selected target must cover it; a ridge running north-east must give a positive
east-north correlation, north-west a negative one, east-west a larger sigma_x,
north-south a larger sigma_y: the frame conversion checked absolutely); the
pan limits relative to a heading (targets in the right half-plane); the
per-candidate GeoTIFF against the JSON; the field at evaluated positions equal
to `trn select` at the same position; the same answers from a second GDAL
format; each bad-input class with its exit status and one-line message.
Maps are small (96 x 96 cells) with a short reach so the ASan build stays fast.
"""
import json
import math
import os
import pty
import shutil
import subprocess
import sys

import numpy as np
from osgeo import gdal

gdal.UseExceptions()

import clitest  # noqa: E402  (tests/cli/, the script's own directory)

TRN = os.path.abspath(sys.argv[1])
WORK = os.path.abspath(sys.argv[2])
H = clitest.Harness(TRN, sub=(), timeout=600)
check, run, expect_error, run_json = H.check, H.run, H.expect_error, H.run_json
write_raster = clitest.write_raster


def read(path):
    ds = gdal.Open(path)
    arr = ds.GetRasterBand(1).ReadAsArray().astype(np.float64)
    gt = ds.GetGeoTransform()
    ds = None
    return gt, arr


def p(name):
    return os.path.join(WORK, name)


shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)

N, CELL = 96, 0.1
X0, Y0 = 1000.0, 2000.0  # south-west corner: a georeferenced map not at 0,0
GT = (X0, CELL, 0.0, Y0 + N * CELL, 0.0, -CELL)
# short reach: quick under ASan; the default configuration predicts the height matcher (SMALL_H), most
# checks below are of the voxel prediction (--map-config paper)
SMALL_H = ["--max-range-m", "3", "--patch-m", "1", "--separation-m", "0.5"]
SMALL = [*SMALL_H, "--map-config", "paper"]
FSMALL = [*SMALL_H[:4], "--map-config", "paper"]  # field ranks no next-best targets: it takes no --separation-m

for cmd in ("select", "field"):
    rc, out, err = run(cmd, "--help")
    check(rc == 0 and out.startswith(f"usage: trn {cmd}") and err == "", f"trn {cmd} --help")
rc, out, err = run("--help")
check(rc == 0 and "select" in out and "field" in out, "trn --help lists select and field")

# ---- frames: an elongated rock of known orientation ------------------------
# A 1.2 m x 0.24 m block, 0.3 m high, centred at map (1004.8, 2006.0), on
# flat ground; the rover 3 m south looks north (heading 90) through a narrow
# pan, so the candidates are the patches over the rock.
ROCK = (1004.8, 2006.0)
ROVER = (1004.8, 2003.0)


def block_dem(angle_deg):
    row, col = np.mgrid[0:N, 0:N]
    x = X0 + (col + 0.5) * CELL
    y = Y0 + (N - (row + 0.5)) * CELL
    a = math.radians(angle_deg)
    u = (x - ROCK[0]) * math.cos(a) + (y - ROCK[1]) * math.sin(a)
    v = -(x - ROCK[0]) * math.sin(a) + (y - ROCK[1]) * math.cos(a)
    return np.where((np.abs(u) < 0.6) & (np.abs(v) < 0.12), 0.3, 0.0) + 0.05


aim = ["--rover", f"{ROVER[0]},{ROVER[1]}", "--heading-deg", "90", "--pan-deg", "-5,5",
       "--min-range-m", "2.8", "--max-range-m", "3.2", "--patch-m", "1.5", "--json"]
res = {}
for ang in (0, 90, 45, -45):
    write_raster(p(f"block{ang}.tif"), block_dem(ang), GT)
    r = run_json("select", "--dem", p(f"block{ang}.tif"), *aim)
    res[ang] = r
    if "target" in r:
        d = math.hypot(r["target"]["x_m"] - ROCK[0], r["target"]["y_m"] - ROCK[1])
        check(d < 0.5, f"block {ang} deg: target {r['target']} within 0.5 m of the rock ({d:.2f} m)")
        check(abs(r["target"]["bearing_deg"]) <= 5.0 + 1e-6, f"block {ang}: bearing within the pan")
        print(f"block {ang:4d} deg: sigma_x {r['sigma_x_m']:.4f} sigma_y {r['sigma_y_m']:.4f} rho {r['rho']:+.3f}")
if all("rho" in res[a] for a in res):
    check(res[0]["sigma_x_m"] > 1.5 * res[0]["sigma_y_m"], "east-west rock: sigma_x (along it) > sigma_y")
    check(res[90]["sigma_y_m"] > 1.5 * res[90]["sigma_x_m"], "north-south rock: sigma_y (along it) > sigma_x")
    check(res[45]["rho"] > 0.3, f"north-east rock: rho > 0 in the east-north frame ({res[45]['rho']})")
    check(res[-45]["rho"] < -0.3, f"north-west rock: rho < 0 ({res[-45]['rho']})")
    check(abs(res[45]["rho"] + res[-45]["rho"]) < 1e-9, "mirror images: opposite rho")

# ---- select on a rocky terrain ------------------------------------------------
g_tif = p("global.tif")
rc, out, err = run("terrain", "--out", g_tif, "--size-cells", N, "--origin", f"{X0:g},{Y0:g}", "--coverage", "0.2",
                   "--seed", "5")
check(rc == 0, f"terrain for select: {err}")
rover = (1004.85, 2004.75)
sel = run_json("select", "--dem", g_tif, "--rover", f"{rover[0]},{rover[1]}", "--out-map", p("cand.tif"), *SMALL,
               "--next-best", "4", "--json")
for key in ("target", "sigma_x_m", "sigma_y_m", "rho", "uncertainty_m", "next_best", "candidates", "informative",
            "rover", "patch_cells"):
    check(key in sel, f"select --json has {key}")
if "target" in sel:
    t = sel["target"]
    rng = math.hypot(t["x_m"] - rover[0], t["y_m"] - rover[1])
    check(1.0 - 1e-6 <= rng <= 3.0 + 1e-6, f"target range {rng:.3f} m within 1..3 m")
    check(abs(rng - t["range_m"]) < 1e-4, f"target range_m {t['range_m']} is the distance {rng}")
    # the target is a cell centre of the map
    fc, fr = (t["x_m"] - X0) / CELL - 0.5, (Y0 + N * CELL - t["y_m"]) / CELL - 0.5
    check(abs(fc - round(fc)) < 1e-4 and abs(fr - round(fr)) < 1e-4, "target on a cell centre (to the micrometre)")
    check(abs(sel["uncertainty_m"] - math.hypot(sel["sigma_x_m"], sel["sigma_y_m"])) < 1e-9,
          "uncertainty_m = hypot(sigma_x, sigma_y)")
    check(-1 < sel["rho"] < 1, "rho in (-1, 1)")
    check(0 < sel["informative"] <= sel["candidates"], "informative <= candidates")
    nb = sel["next_best"]
    check(1 <= len(nb) <= 4, f"next_best has 1..4 entries ({len(nb)})")
    us = [sel["uncertainty_m"]] + [q["uncertainty_m"] for q in nb]
    check(all(a <= b for a, b in zip(us, us[1:])), f"ranked by uncertainty: {us}")
    pts = [(t["x_m"], t["y_m"])] + [(q["x_m"], q["y_m"]) for q in nb]
    check(all(math.hypot(a[0] - b[0], a[1] - b[1]) >= 0.5 - 1e-9 for i, a in enumerate(pts) for b in pts[:i]),
          "ranked targets at least --separation-m apart")
    # the per-candidate map: same grid, NaN = not a candidate, its minimum at the target
    gt, m = read(p("cand.tif"))
    check(all(abs(a - b) < 1e-9 for a, b in zip(gt, GT)), f"--out-map geotransform {gt}")
    check(int((~np.isnan(m)).sum()) == sel["candidates"], "--out-map: one value per candidate")
    check(int(np.isfinite(m).sum()) == sel["informative"], "--out-map: finite where informative, +inf otherwise")
    col, row = int(round(fc)), int(round(fr))
    check(abs(m[row, col] - sel["uncertainty_m"]) < 1e-6 * sel["uncertainty_m"], "--out-map at the target")
    check(np.nanmin(np.where(np.isfinite(m), m, np.nan)) >= np.float32(sel["uncertainty_m"]) - 1e-9,
          "--out-map: no candidate better than the target")
rc, out, err = run("select", "--dem", g_tif, "--rover", f"{rover[0]},{rover[1]}", *SMALL)
check(rc == 0 and out.startswith("rover") and "target" in out and "candidates" in out and err == "",
      "select human summary")

# heading and pan: looking east with +-60 deg, every ranked target lies east of the rover
east = run_json("select", "--dem", g_tif, "--rover", f"{rover[0]},{rover[1]}", *SMALL, "--heading-deg", "0",
                "--pan-deg", "-60,60", "--json")
west = run_json("select", "--dem", g_tif, "--rover", f"{rover[0]},{rover[1]}", *SMALL, "--heading-deg", "180",
                "--pan-deg", "-60,60", "--json")
north = run_json("select", "--dem", g_tif, "--rover", f"{rover[0]},{rover[1]}", *SMALL, "--heading-deg", "90",
                 "--pan-deg", "0,60", "--json")
for name, r, ok in (("east", east, lambda x, y: x - rover[0] >= 0.5 * math.hypot(x - rover[0], y - rover[1])),
                    ("west", west, lambda x, y: rover[0] - x >= 0.5 * math.hypot(x - rover[0], y - rover[1])),
                    ("north, pan 0..60 (CCW: north-west)",
                     north, lambda x, y: y > rover[1] and x <= rover[0] + 1e-9)):
    if "target" in r:
        pts = [(r["target"]["x_m"], r["target"]["y_m"])] + [(q["x_m"], q["y_m"]) for q in r["next_best"]]
        check(all(ok(x, y) for x, y in pts), f"heading {name}: targets {pts}")
check(east.get("candidates", 0) + west.get("candidates", 0) < 2 * sel.get("candidates", 0),
      "pan limits reduce the candidates")

# the heading's lever arm (--heading-sigma-deg, docs/method.md 4): 0 is the
# default bit for bit; with D degrees each target's heading_m is D rad x its
# range, inside its uncertainty; the chosen target is no farther than with 0
h0 = run_json("select", "--dem", g_tif, "--rover", f"{rover[0]},{rover[1]}", *SMALL, "--heading-sigma-deg", "0",
              "--json")
check(all(h0.get(k) == sel.get(k) for k in ("target", "sigma_x_m", "sigma_y_m", "rho", "uncertainty_m")),
      "--heading-sigma-deg 0 gives the default's target and covariance")
check(h0.get("heading_sigma_deg") == 0 and h0.get("heading_m") == 0, "heading_sigma_deg 0, heading_m 0 in the JSON")
h3 = run_json("select", "--dem", g_tif, "--rover", f"{rover[0]},{rover[1]}", *SMALL, "--heading-sigma-deg", "3",
              "--next-best", "4", "--json")
if "target" in h3 and "target" in sel:
    s3 = math.radians(3.0)
    check(abs(h3["heading_m"] - s3 * h3["target"]["range_m"]) < 1e-6,
          f"heading_m {h3['heading_m']} = 3 deg x range {h3['target']['range_m']}")
    check(all(abs(q["heading_m"] - s3 * q["range_m"]) < 1e-6 for q in h3["next_best"]), "next_best heading_m")
    check(h3["uncertainty_m"] >= h3["heading_m"] - 1e-12, "the heading's part is inside the total")
    check(h3["uncertainty_m"] > sel["uncertainty_m"], "an uncertain heading predicts a larger uncertainty")
    check(h3["target"]["range_m"] <= sel["target"]["range_m"] + 1e-9,
          f"an uncertain heading picks a target no farther ({h3['target']['range_m']:.2f} against "
          f"{sel['target']['range_m']:.2f} m)")
for bad, why in (("-1", "out of range"), ("29", "out of range"), ("nan", "not a finite number")):
    expect_error(1, why, "select", "--dem", g_tif, "--rover", f"{rover[0]},{rover[1]}", "--heading-sigma-deg", bad)

# --heading-search 1 (the target matched with the heading searched, docs/method.md 4): with a
# known heading there is nothing to search, so it is refused (it would change nothing); with
# 3 deg the heading's part is the (x, y, heading) marginal's, never above the lever arm to the
# information-weighted centroid, reported in the JSON
for cmd, extra in (("select", ["--rover", f"{rover[0]},{rover[1]}"]), ("field", ["--out", p("hs.tif")])):
    expect_error(2, "--heading-search 1 needs --heading-sigma-deg above 0", cmd, "--dem", g_tif, *extra,
                 *FSMALL, "--heading-search", "1")
hs3 = run_json("select", "--dem", g_tif, "--rover", f"{rover[0]},{rover[1]}", *SMALL, "--heading-sigma-deg", "3",
               "--heading-search", "1", "--next-best", "4", "--json")
check(hs3.get("heading_search") == 1 and hs3.get("heading_sigma_deg") == 3, "heading_search in the JSON")
if "heading_m" in hs3 and "uncertainty_m" in h3:
    check(0 < hs3["heading_m"] <= hs3["uncertainty_m"], "the searched heading's part is inside the total")
    check(hs3["uncertainty_m"] <= h3["uncertainty_m"] * 1.5,
          f"the searched heading's best ({hs3['uncertainty_m']:.4f} m) is near or below the lever arm's "
          f"({h3['uncertainty_m']:.4f} m)")
for bad, why in (("2", "out of range"), ("-1", "out of range"), ("x", "not an integer")):
    expect_error(1, why, "select", "--dem", g_tif, "--rover", f"{rover[0]},{rover[1]}", "--heading-search", bad)

# second GDAL format (ESRI ASCII grid), same answer
g_asc = p("global.asc")
gdal.Translate(g_asc, g_tif, format="AAIGrid")
sel_asc = run_json("select", "--dem", g_asc, "--rover", f"{rover[0]},{rover[1]}", *SMALL, "--next-best", "4",
                   "--json")
check(sel_asc.get("target") == sel.get("target") and sel_asc.get("uncertainty_m") == sel.get("uncertainty_m"),
      "select: AAIGrid gives the GeoTIFF's answer")

# a CRS on the input is kept on the outputs
g_crs = p("global_utm.tif")
gdal.Translate(g_crs, g_tif, outputSRS="EPSG:32611")
rc, out, err = run("select", "--dem", g_crs, "--rover", f"{rover[0]},{rover[1]}", *SMALL, "--out-map", p("cand_utm.tif"))
rc2, out2, err2 = run("field", "--dem", g_crs, "--out", p("field_utm.tif"), *FSMALL, "--area-m",
                      "1004,2004,1005,2005", "--coarse-step-cells", "4")
for path, ok in ((p("cand_utm.tif"), rc == 0), (p("field_utm.tif"), rc2 == 0)):
    ds = gdal.Open(path) if ok else None
    check(ds is not None and "UTM zone 11N" in ds.GetProjection(), f"{path} keeps the input's CRS ({err}{err2})")
    ds = None

# more sensing positions change the prediction (eq. 8)
sel2 = run_json("select", "--dem", g_tif, "--rover", f"{rover[0]},{rover[1]}", *SMALL, "--json",
                "--sensors", "1000,2000;1009.6,2009.6")
check(len(sel2.get("sensors", [])) == 2, "--sensors: two sensing positions reported")

# ---- select: featureless terrain and no candidate: exit 3 -----------------------
write_raster(p("flat.tif"), np.zeros((N, N)), GT)
expect_error(3, "no informative target", "select", "--dem", p("flat.tif"), "--rover", "1004.8,2004.8", *SMALL)
expect_error(3, "no candidate lies within reach", "select", "--dem", g_tif, "--rover", "1004.8,2004.8",
             "--min-range-m", "20", "--max-range-m", "30")

# ---- select: bad input ----------------------------------------------------------
R = ["--rover", f"{rover[0]},{rover[1]}", "--map-config", "paper"]
expect_error(1, "--dem: cannot read", "select", "--dem", p("missing.tif"), *R)
with open(p("notes.txt"), "w") as f:
    f.write("not a raster\n")
expect_error(1, "--dem: cannot read", "select", "--dem", p("notes.txt"), *R)
expect_error(1, "has 1 band, no band 2", "select", "--dem", g_tif, "--band", "2", *R)
expect_error(1, "is off the map", "select", "--dem", g_tif, "--rover", "0,0")
expect_error(1, "is off the map", "select", "--dem", g_tif, "--rover", f"{X0 + N * CELL + 0.01},{Y0 + 1}")
expect_error(1, "--rover: '1004' is not a pair", "select", "--dem", g_tif, "--rover", "1004")
expect_error(1, "--max-range-m: -1 is out of range", "select", "--dem", g_tif, *R, "--max-range-m", "-1")
expect_error(1, "--min-range-m 5 is above --max-range-m 3", "select", "--dem", g_tif, *R, "--min-range-m", "5",
             "--max-range-m", "3")
expect_error(1, "--pan-deg 50,10", "select", "--dem", g_tif, *R, "--pan-deg", "50,10")
expect_error(1, "--pan-deg -200,10", "select", "--dem", g_tif, *R, "--pan-deg", "-200,10")
expect_error(1, "at least 3 cells", "select", "--dem", g_tif, *R, "--patch-m", "0.1")
expect_error(1, "--stride-cells: 0 is out of range", "select", "--dem", g_tif, *R, "--stride-cells", "0")
expect_error(1, "--heading-deg: 'north' is not a finite number", "select", "--dem", g_tif, *R,
             "--heading-deg", "north")
expect_error(1, "--sensors: '1,2,3' is not a pair", "select", "--dem", g_tif, *R, "--sensors", "1,2,3")
expect_error(1, "--next-best: 65 is out of range", "select", "--dem", g_tif, *R, "--next-best", "65")
expect_error(1, "--out-map: cannot create", "select", "--dem", g_tif, *R, *SMALL_H, "--out-map", p("no/dir/x.tif"))
expect_error(2, "missing required option '--rover'", "select", "--dem", g_tif)
expect_error(2, "unknown option '--prior'", "select", "--dem", g_tif, *R, "--prior", "1,2")

# ---- field ------------------------------------------------------------------------
AREA = "1002.4,2002.4,1007.2,2007.2"  # 48 x 48 rover positions inside the map
FCFG = [*FSMALL, "--coarse-step-cells", "8", "--area-m", AREA]
fj = run_json("field", "--dem", g_tif, "--out", p("field.tif"), "--evaluated-out", p("ev.tif"), *FCFG, "--json")
for key in ("file", "width", "height", "cells", "evaluations", "best", "seconds"):
    check(key in fj, f"field --json has {key}")
if "evaluations" in fj:
    check(fj["width"] == 48 and fj["height"] == 48 and fj["cells"] == 48 * 48, f"field area 48 x 48: {fj}")
    check(0 < fj["evaluations"] < fj["cells"], f"field evaluates fewer positions than cells ({fj['evaluations']})")
    gt, F = read(p("field.tif"))
    _, E = read(p("ev.tif"))
    check(all(abs(a - b) < 1e-9 for a, b in zip(gt, GT)), f"field geotransform {gt}")
    inside = ~np.isnan(F)
    check(int(inside.sum()) == 48 * 48, "field: NaN outside --area-m, values inside")
    rows, cols = np.nonzero(inside)
    check(rows.min() == 24 and rows.max() == 71 and cols.min() == 24 and cols.max() == 71, "field area cells")
    check(int((E == 1).sum()) == fj["evaluations"], "--evaluated-out marks every evaluation")
    fin = F[np.isfinite(F)]
    check(abs(fin.min() - fj["best"]["uncertainty_m"]) < 1e-6, "field minimum = best.uncertainty_m")
    bc = int(round((fj["best"]["x_m"] - X0) / CELL - 0.5))
    br = int(round((Y0 + N * CELL - fj["best"]["y_m"]) / CELL - 0.5))
    check(E[br, bc] == 1 and abs(F[br, bc] - fj["best"]["uncertainty_m"]) < 1e-6, "best is an evaluated cell")
    # evaluated cells equal `trn select` (stride 2, as the field) at that rover position
    er, ec = np.nonzero(E == 1)
    rng = np.random.default_rng(7)
    for i in list(rng.choice(er.size, 4, replace=False)) + [int(np.argmin(np.where(E == 1, F, np.inf)[er, ec]))]:
        x = X0 + (ec[i] + 0.5) * CELL
        y = Y0 + N * CELL - (er[i] + 0.5) * CELL
        r = run_json("select", "--dem", g_tif, "--rover", f"{x:.6f},{y:.6f}", *SMALL, "--stride-cells", "2", "--json")
        if "uncertainty_m" in r:
            check(abs(r["uncertainty_m"] - F[er[i], ec[i]]) <= 1e-6 * r["uncertainty_m"],
                  f"field at ({x:.2f}, {y:.2f}) = select there: {F[er[i], ec[i]]} vs {r['uncertainty_m']}")
    # second format, same field
    fa = run_json("field", "--dem", g_asc, "--out", p("field_asc.tif"), *FCFG, "--json")
    check(fa.get("evaluations") == fj["evaluations"] and fa.get("best") == fj["best"], "field: AAIGrid = GeoTIFF")
    check(np.array_equal(read(p("field_asc.tif"))[1], F, equal_nan=True), "field: AAIGrid map = GeoTIFF map")
    # the onboard algorithm (--reference: trn_field) gives the same raster, bit for bit
    check(fj.get("algorithm") == "trn_field_fast" and fj.get("workspace_bytes", 0) > 0,
          f"field --json names the ground path and its workspace: {fj.get('algorithm')}")
    fr = run_json("field", "--dem", g_tif, "--out", p("field_ref.tif"), "--evaluated-out", p("ev_ref.tif"),
                  *FCFG, "--reference", "--json")
    check(fr.get("algorithm") == "trn_field" and fr.get("evaluations") == fj["evaluations"] and
          fr.get("best") == fj["best"], f"field --reference: same evaluations and best ({fr.get('best')})")
    Fr = read(p("field_ref.tif"))[1]
    check(Fr.tobytes() == F.tobytes(), "field --reference: the same raster, bit for bit")
    check(read(p("ev_ref.tif"))[1].tobytes() == read(p("ev.tif"))[1].tobytes(), "field --reference: same evaluated mask")
    # --outlier-density (a tile of a larger map takes that map's K): its own K gives the same raster bit for
    # bit; another K another ln p table, so another field; K must be positive
    k = fj.get("outlier_density_per_m", 0.0)
    check(k > 0 and math.isfinite(k), f"field --json reports the map's outlier density: {k}")
    fk = run_json("field", "--dem", g_tif, "--out", p("field_k.tif"), *FCFG, "--outlier-density", repr(k), "--json")
    check(fk.get("outlier_density_per_m") == k and read(p("field_k.tif"))[1].tobytes() == F.tobytes(),
          "field --outlier-density <its own K>: the same raster, bit for bit")
    run_json("field", "--dem", g_tif, "--out", p("field_k2.tif"), *FCFG, "--outlier-density", repr(20 * k), "--json")
    check(read(p("field_k2.tif"))[1].tobytes() != F.tobytes(), "field --outlier-density 20 K: another field")
    for bad in ("0", "-1", "nan"):
        rc, _, err = run("field", "--dem", g_tif, "--out", p("field_k3.tif"), *FCFG, "--outlier-density", bad)
        check(rc == 1 and "--outlier-density" in err, f"field --outlier-density {bad}: refused ({rc}, {err!r})")
rc, out, err = run("field", "--dem", g_tif, "--out", p("field2.tif"), *FCFG)
check(rc == 0 and out.startswith("wrote ") and "evaluated" in out and err == "",
      f"field human summary, quiet stderr off a terminal: {err!r}")

# progress on a terminal (pseudo-terminal)
master, slave = pty.openpty()
pr = subprocess.Popen([TRN, "field", "--dem", g_tif, "--out", p("tty.tif"), *FCFG], stdout=subprocess.DEVNULL,
                      stderr=slave)
os.close(slave)
tty = b""
while True:
    try:
        chunk = os.read(master, 65536)
    except OSError:
        break
    if not chunk:
        break
    tty += chunk
pr.wait(timeout=600)
os.close(master)
check(pr.returncode == 0 and b"field: coarse lattice 49/49" in tty and b"positions evaluated" in tty,
      f"field draws its progress on a terminal: {tty[-160:]!r}")

# featureless: exit 3, nothing written
expect_error(3, "no informative target", "field", "--dem", p("flat.tif"), "--out", p("flat_field.tif"), *FCFG)
check(not os.path.exists(p("flat_field.tif")), "featureless field: nothing written")

# ---- field: bad input -----------------------------------------------------------------
O = ["--out", p("x.tif")]
expect_error(1, "--dem: cannot read", "field", "--dem", p("missing.tif"), *O)
expect_error(1, "--dem: cannot read", "field", "--dem", p("notes.txt"), *O)
expect_error(1, "has 1 band, no band 3", "field", "--dem", g_tif, *O, "--band", "3")
expect_error(1, "--coarse-step-cells 12 is not a power of two", "field", "--dem", g_tif, *O,
             "--coarse-step-cells", "12")
expect_error(1, "--coarse-step-cells: 512 is out of range", "field", "--dem", g_tif, *O, "--coarse-step-cells", "512")
expect_error(1, "--area-m: '1,2,3' is not X0,Y0,X1,Y1", "field", "--dem", g_tif, *O, "--area-m", "1,2,3")
expect_error(1, "--area-m: want X0 <= X1", "field", "--dem", g_tif, *O, "--area-m", "1005,2000,1001,2005")
expect_error(1, "holds no cell centre of the map", "field", "--dem", g_tif, *O, "--area-m", "0,0,10,10")
expect_error(1, "--margin-rel: -1 is out of range", "field", "--dem", g_tif, *O, "--margin-rel", "-1")
expect_error(1, "--change-rel: 'x' is not a finite number", "field", "--dem", g_tif, *O, "--change-rel", "x")
expect_error(1, "at least 3 cells", "field", "--dem", g_tif, *O, "--patch-m", "0.1")
expect_error(1, "--out: cannot create", "field", "--dem", g_tif, "--out", p("no/dir/f.tif"), *FCFG)
expect_error(2, "missing required option '--out'", "field", "--dem", g_tif)


# ---- the map configuration and the global map's error (issue 12, items 2 and 6) --------
R2 = ["--rover", f"{rover[0]},{rover[1]}", *SMALL_H, "--json"]
dflt = run_json("select", "--dem", g_tif, *R2)
check(dflt.get("map_config_name") == "auto" and dflt.get("predicts") == "heights" and dflt.get("uncertainty_m", 0) > 0,
      f"select defaults to --map-config auto, as localize, and predicts the height matcher: {dflt.get('predicts')}")
# the height prediction reads the DEM's error as one sd: --global-sigma-m changes it, eq. 8's other inputs are refused
hs = run_json("select", "--dem", g_tif, *R2, "--global-sigma-m", "0.3")
check(hs.get("uncertainty_m", 0) > dflt.get("uncertainty_m", 1),
      f"heights: --global-sigma-m 0.3 raises the prediction ({hs.get('uncertainty_m')} > {dflt.get('uncertainty_m')})")
for opt, val in (("--global-sigma-k", "0.01"), ("--sensors", f"{rover[0]},{rover[1]}"), ("--outlier-density", "2"),
                 ("--inlier-prob", "0.9"), ("--zbin-m", "0.05")):
    expect_error(2, f"{opt} applies to the voxel", "select", "--dem", g_tif, *R2, opt, val)
# --match voxel on the auto configuration predicts the voxel matcher
mv = run_json("select", "--dem", g_tif, *R2, "--match", "voxel")
check(mv.get("predicts") == "voxel" and mv.get("uncertainty_m") != dflt.get("uncertainty_m"),
      f"--match voxel predicts the voxel matcher: {mv.get('predicts')}")
# a rover that bins its points (--points-per-cell N, docs/method.md 4): the JSON says N; the mean
# of 16 points a cell predicts a smaller uncertainty than one measurement a cell, even with its
# centroid's jitter; one point a cell (the jitter alone) a larger one; the field takes it too
check(dflt.get("points_per_cell") == 0, f"select: points_per_cell 0 by default ({dflt.get('points_per_cell')})")
b16 = run_json("select", "--dem", g_tif, *R2, "--points-per-cell", "16")
b1 = run_json("select", "--dem", g_tif, *R2, "--points-per-cell", "1")
check(b16.get("points_per_cell") == 16 and 0 < b16.get("uncertainty_m", 0) < dflt.get("uncertainty_m", 0)
      < b1.get("uncertainty_m", 0),
      f"--points-per-cell 16 < unbinned < 1: {b16.get('uncertainty_m')}, {dflt.get('uncertainty_m')}, "
      f"{b1.get('uncertainty_m')}")
for bad, why in (("0.5", "a binned cell holds at least one point"), ("-1", "--points-per-cell: -1 is out of range"),
                 ("2e6", "--points-per-cell: 2e+06 is out of range"), ("x", "--points-per-cell: 'x' is not a finite")):
    expect_error(2 if bad == "0.5" else 1, why, "select", "--dem", g_tif, *R2, "--points-per-cell", bad)
expect_error(2, "--points-per-cell applies to the height prediction", "select", "--dem", g_tif, *R2,
             "--match", "voxel", "--points-per-cell", "4")
expect_error(2, "--points-per-cell applies to the height prediction", "field", "--dem", g_tif, "--out",
             p("ppc.tif"), "--map-config", "paper", "--points-per-cell", "4")
# a patch of few cells is warned about on stderr
rc, out, err = run("select", "--dem", g_tif, "--rover", f"{rover[0]},{rover[1]}", "--max-range-m", "3",
                   "--patch-m", f"{5 * CELL}")
check(rc == 0 and "warning: the" in err and "--patch-m" in err, f"a 5-cell patch draws a warning: {err!r}")
R2 = [*R2, "--map-config", "paper"]
base = run_json("select", "--dem", g_tif, *R2)
check(base.get("map_config_name") == "paper" and base.get("predicts") == "voxel" and
      abs(base.get("map_config", {}).get("zbin_m", 0) - CELL) < 1e-6
      and base["map_config"].get("nz") == 16, f"--map-config paper: the paper's map configuration: {base.get('map_config')}")
ge = base.get("global_error", {})
check(abs(ge.get("sigma_m", 0) - 0.02) < 1e-7 and abs(ge.get("k_per_m", 0) - 0.001) < 1e-7 and ge.get("raster", 1) is None,
      f"select: the default global error model 0.02 m + 0.001/m r^2, no raster: {ge}")
au = run_json("select", "--dem", g_tif, *R2[:-2], "--match", "voxel")
check(au.get("map_config_name") == "auto" and au.get("map_config", {}).get("zbin_m", 1) < CELL and
      au.get("sigma_h_m") is not None and au.get("uncertainty_m", 0) > 0, f"--map-config auto: {au.get('map_config')}")
zb = run_json("select", "--dem", g_tif, *R2, "--zbin-m", "0.05", "--nz", "24")
check(abs(zb.get("map_config", {}).get("zbin_m", 0) - 0.05) < 1e-7 and zb["map_config"].get("nz") == 24,
      "--zbin-m / --nz override the configuration")
# the error model: a larger global error predicts a larger uncertainty
big = run_json("select", "--dem", g_tif, *R2, "--global-sigma-m", "0.3", "--global-sigma-k", "0")
check(big.get("uncertainty_m", 0) > base.get("uncertainty_m", 1) and
      abs(big["global_error"]["sigma_m"] - 0.3) < 1e-7 and big["global_error"]["k_per_m"] == 0,
      f"--global-sigma-m 0.3: uncertainty {big.get('uncertainty_m')} > {base.get('uncertainty_m')}")
# the raster: all no-data = the model; a constant 0.3 m = the constant model; on the DEM's grid only
write_raster(p("err_nan.tif"), np.full((N, N), np.nan), GT)
write_raster(p("err_nodata.tif"), np.full((N, N), -9999.0), GT, nodata=-9999.0)
write_raster(p("err_03.tif"), np.full((N, N), 0.3), GT)
for f in ("err_nan.tif", "err_nodata.tif"):
    r = run_json("select", "--dem", g_tif, *R2, "--global-error", p(f))
    check(r.get("uncertainty_m") == base.get("uncertainty_m") and r.get("target") == base.get("target") and
          r.get("global_error", {}).get("raster") == p(f), f"--global-error {f} (no data anywhere) = the model")
r = run_json("select", "--dem", g_tif, *R2, "--global-error", p("err_03.tif"))
check(r.get("uncertainty_m") == big.get("uncertainty_m") and r.get("target") == big.get("target"),
      f"--global-error 0.3 m everywhere = --global-sigma-m 0.3 --global-sigma-k 0 ({r.get('uncertainty_m')}, "
      f"{big.get('uncertainty_m')})")
half = np.full((N, N), np.nan)
half[:, : N // 2] = 0.3
write_raster(p("err_half.tif"), half, GT)
r = run_json("select", "--dem", g_tif, *R2, "--global-error", p("err_half.tif"))
check(r.get("uncertainty_m") is not None, "--global-error partly no-data runs")
rc, out, err = run("select", "--dem", g_tif, "--rover", f"{rover[0]},{rover[1]}", *SMALL_H, "--map-config", "auto",
                   "--match", "voxel", "--global-sigma-m", "0.05")
check(rc == 0 and "map          auto: bin" in out and "global error 0.05 m + 0.001/m r^2" in out,
      f"the summary names the map configuration and the global error: {out!r}")
write_raster(p("err_small.tif"), np.full((N - 1, N), 0.1), GT)
write_raster(p("err_shift.tif"), np.full((N, N), 0.1), (X0 + 1.0, CELL, 0.0, Y0 + N * CELL, 0.0, -CELL))
neg = np.full((N, N), 0.1)
neg[3, 7] = -0.5
write_raster(p("err_neg.tif"), neg, GT)
huge = np.full((N, N), 0.1)
huge[4, 2] = 2e6  # (non-finite cells are no-data to dem_read: the model)
write_raster(p("err_huge.tif"), huge, GT)
R = ["--rover", f"{rover[0]},{rover[1]}", "--map-config", "paper"]
expect_error(1, "--global-error: cannot read", "select", "--dem", g_tif, *R, "--global-error", p("missing.tif"))
expect_error(1, "must be on the DEM's grid", "select", "--dem", g_tif, *R, "--global-error", p("err_small.tif"))
expect_error(1, "geotransform differs", "select", "--dem", g_tif, *R, "--global-error", p("err_shift.tif"))
expect_error(1, "cell (column 7, row 3) is -0.5 m", "select", "--dem", g_tif, *R, "--global-error", p("err_neg.tif"))
expect_error(1, "cell (column 2, row 4) is 2e+06 m", "select", "--dem", g_tif, *R, "--global-error", p("err_huge.tif"))
expect_error(1, "--global-sigma-m: -1 is out of range", "select", "--dem", g_tif, *R, "--global-sigma-m", "-1")
expect_error(1, "--global-sigma-k: 'x' is not a finite number", "select", "--dem", g_tif, *R, "--global-sigma-k", "x")
expect_error(1, "--map-config must be auto or paper, not 'best'", "select", "--dem", g_tif, *R[:2], "--map-config",
             "best")
expect_error(1, "--nz: 0 is out of range", "select", "--dem", g_tif, *R, "--nz", "0")
expect_error(1, "--map-config must be auto or paper", "field", "--dem", g_tif, "--out", p("x.tif"), "--map-config", "x")
expect_error(1, "must be on the DEM's grid", "field", "--dem", g_tif, "--out", p("x.tif"), "--map-config", "paper",
             "--global-error", p("err_small.tif"))
FA = ["--area-m", f"{X0 + 4.0},{Y0 + 4.0},{X0 + 5.0},{Y0 + 5.0}", *SMALL_H[:4], "--coarse-step-cells", "4", "--json"]
f1 = run_json("field", "--dem", g_tif, "--out", p("fa.tif"), *FA, "--map-config", "paper")
f2 = run_json("field", "--dem", g_tif, "--out", p("fb.tif"), *FA, "--map-config", "paper", "--global-error",
              p("err_nan.tif"))
f3 = run_json("field", "--dem", g_tif, "--out", p("fc.tif"), *FA, "--global-sigma-m", "0.1")
check(f1.get("map_config_name") == "paper" and f1.get("best") == f2.get("best") and f1.get("predicts") == "voxel" and
      f3.get("map_config_name") == "auto" and f3.get("predicts") == "heights" and
      abs(f3.get("global_error", {}).get("sigma_m", 0) - 0.1) < 1e-7,
      f"field: map configuration and global error options ({f1.get('best')}, {f2.get('best')}, {f3.get('map_config')})")

# ---- figures (tools/plot/trn_plot.py) ----------------------------------------------------
try:
    import matplotlib  # noqa: F401
    have_mpl = True
except ImportError:
    have_mpl = False
    print("note: matplotlib missing, figures not checked")
if have_mpl and "target" in sel and "evaluations" in fj:
    plot = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "plot", "trn_plot.py")
    with open(p("sel.json"), "w") as f:
        json.dump(sel, f)
    with open(p("field.json"), "w") as f:
        json.dump(fj, f)
    for fig, args in (("select", [g_tif, "--select-json", p("sel.json")]),
                      ("uncertainty", [g_tif, p("cand.tif"), "--select-json", p("sel.json")]),
                      ("field", [g_asc, p("field.tif"), "--evaluated", p("ev.tif"), "--field-json", p("field.json")]),
                      ("surface", [g_tif, "--select-json", p("sel.json")])):
        png = p(f"fig_{fig}.png")
        r = subprocess.run([sys.executable, plot, fig, *args, "--out", png], capture_output=True, text=True,
                           timeout=300)
        ok = r.returncode == 0 and os.path.exists(png) and os.path.getsize(png) > 20000
        if ok:
            with open(png, "rb") as f:
                ok = f.read(8) == b"\x89PNG\r\n\x1a\n"
        check(ok, f"trn_plot.py {fig}: {r.returncode} {r.stderr.strip()[-300:]}")
    r = subprocess.run([sys.executable, plot, "field", g_tif, p("flat_field.tif"), "--out", p("no.png")],
                       capture_output=True, text=True, timeout=60)
    check(r.returncode != 0 and "cannot read" in r.stderr, "trn_plot.py field on a missing file fails with a reason")

sys.exit(H.finish())
