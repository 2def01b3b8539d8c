#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tests/cli/test_cli.py - the `trn` command line end to end (CTest `cli`).

    python3 tests/cli/test_cli.py PATH/TO/trn WORKDIR

Runs the built `trn` for each subcommand's happy path and each bad-input class,
checking exit codes, the one-line `trn <cmd>: <reason>` messages, the JSON, and
the GeoTIFFs (read back with GDAL's Python bindings). DEMs come from
`trn terrain` itself; other formats (ESRI ASCII grid), rover-frame local maps,
rotated / non-square / south-up / no-data variants are made with GDAL here.
Exit status 0 when every check passes; each failure is printed.
"""
import json
import math
import os
import shutil
import subprocess
import sys

import numpy as np
from osgeo import gdal

gdal.UseExceptions()

import clitest  # noqa: E402  (tests/cli/, the script's own directory)

TRN = os.path.abspath(sys.argv[1])
WORK = os.path.abspath(sys.argv[2])
H = clitest.Harness(TRN, sub=())
check, run, expect_error, run_json = H.check, H.run, H.expect_error, H.run_json
write_raster = clitest.write_raster


def read(path):
    ds = gdal.Open(path)
    arr = ds.GetRasterBand(1).ReadAsArray().astype(np.float64)
    return ds, arr


def p(name):
    return os.path.join(WORK, name)


# --------------------------------------------------------------------------
shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)

# ---- dispatcher -------------------------------------------------------------
rc, out, err = run("--help")
check(rc == 0 and "terrain" in out and "localize" in out, "trn --help lists terrain and localize")
# exit statuses and the version (issue 15): --help lists 0-3, --version and
# `version` print "trn X.Y.Z", the CMake project version in trn/version.h.
check(all(k in out for k in ("0 ok", "1 bad input", "2 usage error", "3 no result")),
      f"trn --help lists every exit status: {out[-300:]!r}")
for cmd, has3 in (("terrain", False), ("select", True), ("field", True), ("profile", True),
                  ("localize", False), ("experiment", False), ("can-decode", False)):
    rc, hout, _ = run(cmd, "--help")
    check(rc == 0 and "exit status: 0 ok, 1 bad input" in hout and ("2 usage error" in hout)
          and ((", 3 " in hout) == has3), f"trn {cmd} --help: exit statuses ({hout[-200:]!r})")
VERSION = H.version()
check(VERSION.count(".") == 2 and all(x.isdigit() for x in VERSION.split(".")),
      f"trn --version prints a version X.Y.Z: {VERSION!r}")
rc, out, err = run("version")
check(rc == 0 and out == f"trn {VERSION}\n" and err == "", f"trn version: {rc} {out!r}")
rc, out, err = run("--version")
check(rc == 0 and out == f"trn {VERSION}\n" and err == "", f"trn --version: {rc} {out!r}")
rc, out, err = run("nosuch")
check(rc == 2 and "unknown command" in err, "trn nosuch: exit 2, unknown command")
for cmd in ("terrain", "localize"):
    rc, out, err = run(cmd, "--help")
    check(rc == 0 and out.startswith(f"usage: trn {cmd}") and err == "", f"trn {cmd} --help")

# Every option with a value states its default (printed from the value the
# command starts with, or said in words), and --help anywhere prints it.
import re  # noqa: E402
for cmd in ("terrain", "select", "field", "localize", "experiment", "profile"):
    rc, out, _ = run(cmd, "--bogus-first", "--help")
    check(rc == 0 and out.startswith(f"usage: trn {cmd}"), f"trn {cmd}: --help after another argument")
    for line in out.splitlines():
        m = re.match(r"  (--[a-z0-9-]+) (\S+)\s+(.*)$", line)
        if m and "default" not in m.group(3) and "required" not in m.group(3):
            check(m.group(1) in ("--dem", "--out", "--rover", "--local", "--batch", "--reference"),
                  f"trn {cmd} --help: {m.group(1)} states no default: {line.strip()}")
rc, out, _ = run("field", "--help")
check(re.search(r"--margin-rel M .*\(default 0\.4\)", out) is not None and
      re.search(r"--change-rel C .*\(default 1\.5\)", out) is not None and
      re.search(r"--coarse-step-cells N .*\(default 16\)", out) is not None,
      "trn field --help: the core's trn_field_cfg_default (0.4, 1.5, 16), printed from the values used")

# ---- terrain: happy path ----------------------------------------------------
ORIGIN = (1000.0, 2000.0)
CELL = 0.1
N = 256
g_tif = p("global.tif")
t = run_json("terrain", "--out", g_tif, "--origin", "1000,2000", "--coverage", "0.15", "--seed", "3", "--json")
for key in ("file", "width", "height", "cell_m", "coverage_k", "rocks", "rock_area_fraction",
            "model_area_fraction", "seed"):
    check(key in t, f"terrain --json has {key}")
check(t.get("width") == N and t.get("height") == N and t.get("cell_m") == CELL, "terrain JSON size and cell")
check(t.get("rocks", 0) > 100, f"terrain draws rocks ({t.get('rocks')})")
# Realised rock area on one small map: within 30 % of the model (the sharp
# statistical test is test_terrain_gen over large maps).
check(abs(t.get("rock_area_fraction", 0) / t.get("model_area_fraction", 1) - 1) < 0.3,
      "terrain rock area fraction near the model")
ds, G = read(g_tif)
gt = ds.GetGeoTransform()
want_gt = (ORIGIN[0], CELL, 0.0, ORIGIN[1] + N * CELL, 0.0, -CELL)
check(all(abs(a - b) < 1e-9 for a, b in zip(gt, want_gt)), f"terrain geotransform {gt} == {want_gt}")
check(ds.RasterXSize == N and ds.RasterYSize == N, "terrain raster size")
check(ds.GetRasterBand(1).DataType == gdal.GDT_Float32, "terrain is float32")
check(math.isnan(ds.GetRasterBand(1).GetNoDataValue() or 0.0), "terrain no-data is NaN")
check(np.isfinite(G).all(), "terrain heights all finite")
check(G.max() - np.median(G) > 0.2, "terrain has rocks standing above the ground")
check(ds.GetProjection() == "", "terrain without --crs has no CRS")
ds = None
rc, out, err = run("terrain", "--out", p("same.tif"), "--origin", "1000,2000", "--coverage", "0.15", "--seed", "3")
check(rc == 0 and out.startswith("wrote ") and err == "", "terrain human summary, quiet stderr off a terminal")
check(np.array_equal(read(p("same.tif"))[1], G), "terrain: same seed, same heights")
run("terrain", "--out", p("other.tif"), "--origin", "1000,2000", "--coverage", "0.15", "--seed", "4")
check(not np.array_equal(read(p("other.tif"))[1], G), "terrain: another seed, other heights")
rc, out, err = run("terrain", "--out", p("crs.tif"), "--size-cells", "32", "--crs", "EPSG:32611")
# Progress bar: drawn on stderr when it is a terminal (a pseudo-terminal here).
import pty  # noqa: E402
master, slave = pty.openpty()
pr = subprocess.Popen([TRN, "terrain", "--out", p("tty.tif"), "--size-cells", "512"], stdout=subprocess.DEVNULL,
                      stderr=slave)
os.close(slave)
tty_err = b""
while True:  # read while it runs: a full pty buffer would block the writer
    try:
        chunk = os.read(master, 65536)
    except OSError:  # EIO: the child closed its end
        break
    if not chunk:
        break
    tty_err += chunk
pr.wait(timeout=300)
os.close(master)
check(pr.returncode == 0 and b"terrain [" in tty_err and b"100.0%" in tty_err,
      f"terrain draws a progress bar on a terminal: {tty_err[-120:]!r}")
ds = gdal.Open(p("crs.tif"))
check(rc == 0 and "UTM zone 11N" in ds.GetProjection(), "terrain --crs tags the GeoTIFF")
ds = None

# ---- terrain: bad input -------------------------------------------------------
x = p("x.tif")
expect_error(1, "--size-cells: 3 is out of range", "terrain", "--out", x, "--size-cells", "3")
expect_error(1, "--size-cells: '12abc' is not an integer", "terrain", "--out", x, "--size-cells", "12abc")
expect_error(1, "--cell-m: 'abc' is not a finite number", "terrain", "--out", x, "--cell-m", "abc")
expect_error(1, "--cell-m: 'nan' is not a finite number", "terrain", "--out", x, "--cell-m", "nan")
expect_error(1, "--coverage: 0 is out of range", "terrain", "--out", x, "--coverage", "0")
expect_error(1, "--seed: '-1' is not an unsigned", "terrain", "--out", x, "--seed", "-1")
expect_error(1, "--origin: '5' is not a pair", "terrain", "--out", x, "--origin", "5")
expect_error(1, "below the smallest", "terrain", "--out", x, "--min-diameter-m", "0.5", "--max-diameter-m", "0.3")
expect_error(1, "cannot create", "terrain", "--out", p("no/such/dir/x.tif"))
expect_error(1, "--crs 'NOT_A_CRS'", "terrain", "--out", x, "--crs", "NOT_A_CRS")
expect_error(2, "unknown option '--bogus'", "terrain", "--out", x, "--bogus", "1")
expect_error(2, "missing required option '--out'", "terrain")
expect_error(2, "missing value for '--out'", "terrain", "--out")
expect_error(2, "unexpected argument 'extra'", "terrain", "--out", x, "extra")
expect_error(2, "takes no value", "terrain", "--out", x, "--json=1")
expect_error(2, "given twice", "terrain", "--out", x, "--seed", "1", "--seed", "2")

# ---- localize: happy paths ---------------------------------------------------
# Truth: the rover stands on the centre of global cell (col 140, row 120).
# The local map is the 64 x 64 crop starting at (108, 88), so the rover is
# at local cell (32.5 - 0.5 ...) = centre of local (32, 32); in the rover
# frame the crop's top-left corner is ((108 - 140.5) c, -(88 - 120.5) c).
C0, R0, L = 108, 88, 64
RC, RR = 140, 120
truth = (ORIGIN[0] + (RC + 0.5) * CELL, ORIGIN[1] + N * CELL - (RR + 0.5) * CELL)
prior = f"{truth[0] + 0.7:.3f},{truth[1] - 0.5:.3f}"
crop = G[R0:R0 + L, C0:C0 + L].astype(np.float32)
rover_gt = ((C0 - (RC + 0.5)) * CELL, CELL, 0.0, -(R0 - (RR + 0.5)) * CELL, 0.0, -CELL)
local_tif = p("local.tif")
write_raster(local_tif, crop, rover_gt)


def expect_fix(label, want, *args, tol=0.03):
    r = run_json("localize", *args, "--json")
    for key in ("x_m", "y_m", "sigma_x_m", "sigma_y_m", "rho", "failure_probability", "status"):
        check(key in r, f"localize {label}: JSON has {key}")
    if "x_m" in r:
        err_m = math.hypot(r["x_m"] - want[0], r["y_m"] - want[1])
        print(f"localize {label}: ({r['x_m']:.4f}, {r['y_m']:.4f}) vs truth ({want[0]:.4f}, {want[1]:.4f}): "
              f"error {err_m:.4f} m, sigma ({r['sigma_x_m']}, {r['sigma_y_m']}), status {r['status']}")
        check(err_m < tol, f"localize {label}: error {err_m:.4f} m >= {tol} m")
        check(r["status"] == "ok", f"localize {label}: status {r['status']}")
        check(r["failure_probability"] < 0.01, f"localize {label}: failure probability {r['failure_probability']}")
        check(0 < r["sigma_x_m"] < 0.05 and 0 < r["sigma_y_m"] < 0.05, f"localize {label}: sigmas")
        if r.get("refined"):
            rf = r.get("refinement", {})
            check(all(k in rf for k in ("model_m", "chi2_dof", "inflation", "ll_inflation", "interp_mix",
                                           "spline_step_cells", "points_used",
                                           "log_likelihood")),
                  f"localize {label}: refinement fields {sorted(rf)}")
            check(rf.get("inflation", 0) >= 1 and rf.get("ll_inflation", 0) >= 1
                  and rf.get("points_used", 0) > 0
                  and -1.5 <= rf.get("interp_mix", 9) <= 2.5
                  and len(rf.get("spline_step_cells", [])) == 2, f"localize {label}: refinement {rf}")
    return r


r_tif = expect_fix("GeoTIFF", truth, "--dem", g_tif, "--local", local_tif, "--prior", prior)
check(r_tif.get("refined") is True and "refinement" in r_tif, "localize GeoTIFF: the auto map refines")
rc, out, err = run("localize", "--dem", g_tif, "--local", local_tif, "--prior", prior)
check(rc == 0 and out.startswith("estimate") and "status: ok" in out, "localize human summary")

# Second GDAL format: both maps as ESRI ASCII grids.
g_asc, l_asc = p("global.asc"), p("local.asc")
gdal.Translate(g_asc, g_tif, format="AAIGrid")
gdal.Translate(l_asc, local_tif, format="AAIGrid")
expect_fix("AAIGrid", truth, "--dem", g_asc, "--local", l_asc, "--prior", prior)

# The rover between cells: the same crop, rover-frame origin moved by half a
# cell east and a quarter north, so the rover stands there in map terms.
sub_gt = (rover_gt[0] - 0.05, CELL, 0.0, rover_gt[3] + 0.025, 0.0, -CELL)
write_raster(p("local_sub.tif"), crop, sub_gt)
expect_fix("sub-cell rover", (truth[0] + 0.05, truth[1] - 0.025),
           "--dem", g_tif, "--local", p("local_sub.tif"), "--prior", prior, tol=0.02)

# South-up storage (rows flipped, positive pixel height): same heights, same answer.
south_gt = (rover_gt[0], CELL, 0.0, rover_gt[3] - L * CELL, 0.0, CELL)
write_raster(p("local_south.tif"), crop[::-1, :].copy(), south_gt)
expect_fix("south-up local", truth, "--dem", g_tif, "--local", p("local_south.tif"), "--prior", prior)

# No-data holes (value -9999) in the local map: still localizes.
holed = crop.copy()
holed[10:30, 5:25] = -9999.0
write_raster(p("local_holes.tif"), holed, rover_gt, nodata=-9999.0)
expect_fix("no-data holes", truth, "--dem", g_tif, "--local", p("local_holes.tif"), "--prior", prior)

# A local map smaller than the window and off-centre rover: crop 40 x 40 to the east of the rover.
crop2 = G[RR - 20:RR + 20, RC + 5:RC + 45].astype(np.float32)
gt2 = ((RC + 5 - (RC + 0.5)) * CELL, CELL, 0.0, -(RR - 20 - (RR + 0.5)) * CELL, 0.0, -CELL)
write_raster(p("local_east.tif"), crop2, gt2)
expect_fix("rover outside its local map", truth, "--dem", g_tif, "--local", p("local_east.tif"),
           "--prior", prior)

# A featureless plain: the peak is flat, so the answer is "ill_conditioned"
# with null sigmas (JSON has no infinity), exit 0.
run("terrain", "--out", p("flat.tif"), "--relief-m", "0", "--min-diameter-m", "20", "--max-diameter-m", "20")
write_raster(p("flat_local.tif"), read(p("flat.tif"))[1][100:164, 100:164].astype(np.float32),
             (-3.2, CELL, 0.0, 3.2, 0.0, -CELL))
r = run_json("localize", "--dem", p("flat.tif"), "--local", p("flat_local.tif"), "--prior", "13,13", "--json")
check(r.get("status") == "ill_conditioned" and r.get("sigma_x_m", 0) is None and r.get("sigma_y_m", 0) is None,
      f"localize on a plain: ill_conditioned with null sigmas: {r}")

# A map that repeats every 3 cells east-west: the match is as good 3 cells either side, the
# failure probability about 2/3, so the default acceptance limit (0.02 with auto) answers
# "ambiguous" (exit 0, everything reported); --max-failure-prob 1 accepts the same answer.
yy, xx = np.mgrid[0:96, 0:96]
per = (0.3 * np.sin(2 * np.pi * xx / 3.0) + 0.4 * np.sin(0.37 * yy) + 0.15 * np.cos(0.61 * yy)).astype(np.float32)
write_raster(p("periodic.tif"), per, (0.0, CELL, 0.0, 9.6, 0.0, -CELL))
write_raster(p("periodic_local.tif"), per[28:69, 28:69].copy(), (-2.05, CELL, 0.0, 2.05, 0.0, -CELL))
pargs = ["--dem", p("periodic.tif"), "--local", p("periodic_local.tif"), "--prior", "4.85,4.75", "--window-m", "0.4"]
ra = run_json("localize", *pargs, "--json")
check(ra.get("status") == "ambiguous" and 0.05 < ra.get("failure_probability", 0) < 0.9,
      f"localize on a periodic map: ambiguous: {ra.get('status')} {ra.get('failure_probability')}")
check(abs(ra.get("map_config", {}).get("max_failure_prob", 0) - 0.02) < 1e-7, "auto's acceptance limit 0.02 in the JSON")
ro = run_json("localize", *pargs, "--max-failure-prob", "1", "--json")
check(ro.get("status") == "ok" and ro.get("x_m") == ra.get("x_m") and
      ro.get("failure_probability") == ra.get("failure_probability"),
      f"--max-failure-prob 1 accepts the same answer: {ro.get('status')}")
rp = run_json("localize", *pargs, "--map-config", "paper", "--json")
check(rp.get("map_config", {}).get("max_failure_prob") == 1, "the paper's configuration never flags (limit 1)")
for bad, why in (("0", "out of range"), ("1.5", "out of range"), ("nan", "not a finite number")):
    expect_error(1, why, "localize", *pargs, "--max-failure-prob", bad)
# The noise model's scale from the data (--noise-auto, 1 with auto): the JSON says which scale was
# used; with the option at 0 it is 1 and the configuration says so; a value other than 0 or 1 is
# refused with one line.
check(r_tif.get("noise_scale", 0) > 0 and ra.get("map_config", {}).get("noise_auto") == 1,
      f"noise_scale {r_tif.get('noise_scale')} reported, auto's noise_auto 1")
rn = run_json("localize", *pargs, "--noise-auto", "0", "--json")
check(rn.get("noise_scale") == 1 and rn.get("map_config", {}).get("noise_auto") == 0,
      f"--noise-auto 0: noise_scale {rn.get('noise_scale')}, noise_auto {rn.get('map_config', {}).get('noise_auto')}")
for bad in ("2", "-1"):
    expect_error(1, "out of range", "localize", *pargs, "--noise-auto", bad)

# ---- localize: bad input ------------------------------------------------------
common = ["--local", local_tif, "--prior", prior]
expect_error(1, "--dem: cannot read", "localize", "--dem", p("missing.tif"), *common)
with open(p("notes.txt"), "w") as f:
    f.write("this is not a raster\n")
expect_error(1, "--dem: cannot read", "localize", "--dem", p("notes.txt"), *common)
expect_error(1, "has 1 band, no band 2", "localize", "--dem", g_tif, "--band", "2", *common)
expect_error(1, "--band: 0 is out of range", "localize", "--dem", g_tif, "--band", "0", *common)
expect_error(1, "is off the map", "localize", "--dem", g_tif, "--local", local_tif, "--prior", "0,0")
expect_error(1, "is off the map", "localize", "--dem", g_tif, "--local", local_tif,
             "--prior", f"{ORIGIN[0] + 25.65},{ORIGIN[1] + 10}")
expect_error(1, "larger than --max-local-cells 32", "localize", "--dem", g_tif, *common,
             "--max-local-cells", "32")
write_raster(p("huge.tif"), np.zeros((8, 4097), np.float32), want_gt)
expect_error(1, "is 4097 x 8 cells; the maximum side is", "localize", "--dem", p("huge.tif"), *common)
write_raster(p("small_global.tif"), G[:48, :48].astype(np.float32), want_gt)
expect_error(1, "is larger than --dem", "localize", "--dem", p("small_global.tif"), *common)
write_raster(p("local_coarse.tif"), crop[::2, ::2].copy(),
             (rover_gt[0], 2 * CELL, 0.0, rover_gt[3], 0.0, -2 * CELL))
expect_error(1, "cell sizes differ", "localize", "--dem", g_tif, "--local", p("local_coarse.tif"),
             "--prior", prior)
write_raster(p("rotated.tif"), crop, (rover_gt[0], CELL, 0.01, rover_gt[3], 0.01, -CELL))
expect_error(1, "rotated geotransform", "localize", "--dem", g_tif, "--local", p("rotated.tif"),
             "--prior", prior)
write_raster(p("nonsquare.tif"), crop, (rover_gt[0], CELL, 0.0, rover_gt[3], 0.0, -2 * CELL))
expect_error(1, "non-square cells", "localize", "--dem", g_tif, "--local", p("nonsquare.tif"),
             "--prior", prior)
write_raster(p("nogt.tif"), crop, None)
expect_error(1, "has no geotransform", "localize", "--dem", g_tif, "--local", p("nogt.tif"), "--prior", prior)
write_raster(p("allnan.tif"), np.full((L, L), np.nan, np.float32), rover_gt)
expect_error(1, "no usable data", "localize", "--dem", g_tif, "--local", p("allnan.tif"), "--prior", prior)
far_gt = (1e6, CELL, 0.0, 1e6, 0.0, -CELL)
write_raster(p("far.tif"), crop, far_gt)
expect_error(1, "is it in the rover frame", "localize", "--dem", g_tif, "--local", p("far.tif"),
             "--prior", prior)
expect_error(1, "--window-m: -1 is out of range", "localize", "--dem", g_tif, *common, "--window-m", "-1")
expect_error(1, "--window-m: 'wide' is not a finite number", "localize", "--dem", g_tif, *common,
             "--window-m", "wide")
expect_error(1, "--window-m 1000 is 10000 cells", "localize", "--dem", g_tif, *common, "--window-m", "1000")
expect_error(1, "--prior: '1,2,3' is not a pair", "localize", "--dem", g_tif, "--local", local_tif,
             "--prior", "1,2,3")
expect_error(1, "--prior: '1014' is not a pair", "localize", "--dem", g_tif, "--local", local_tif,
             "--prior", "1014")
expect_error(2, "give --local FILE and --prior X,Y, or --batch LIST", "localize", "--dem", g_tif, "--prior", prior)
expect_error(2, "unknown option '--rover'", "localize", "--dem", g_tif, *common, "--rover", "1,2")

# ---- localize: the map configuration options and --batch ----------------------
expect_error(2, "--batch replaces --local and --prior", "localize", "--dem", g_tif, *common, "--batch", p("x.txt"))
expect_error(1, "--map-config must be auto or paper", "localize", "--dem", g_tif, *common, "--map-config", "best")
expect_error(1, "--local-highpass must be box or map", "localize", "--dem", g_tif, *common, "--local-highpass", "disc")
expect_error(1, "--nz: 0 is out of range", "localize", "--dem", g_tif, *common, "--nz", "0")
expect_error(1, "--refine: 2 is out of range", "localize", "--dem", g_tif, *common, "--refine", "2")
expect_error(1, "--zbin-m: -0.1 is out of range", "localize", "--dem", g_tif, *common, "--zbin-m", "-0.1")
expect_error(1, "map configuration rejected", "localize", "--dem", g_tif, *common, "--match", "voxel",
             "--highpass-m", "0.01")
# a map option the matcher does not read is refused, not ignored (tests/cli/test_cli_options.py has all)
expect_error(2, "--nz applies to the voxel matcher", "localize", "--dem", g_tif, *common, "--nz", "8")
expect_error(1, "--batch " + p("missing.txt") + ": cannot open", "localize", "--dem", g_tif, "--batch", p("missing.txt"))
# a map that cannot be prepared says why with --batch as without it (it printed nothing before)
expect_error(1, "no_such_map.tif", "localize", "--dem", p("no_such_map.tif"), "--batch", p("missing.txt"))
with open(p("bad_batch.txt"), "w") as f:
    f.write(f"{local_tif} 1014.75\n")
expect_error(1, "line 1: expected 'LOCAL PRIOR_X PRIOR_Y [WINDOW_M]'", "localize", "--dem", g_tif,
             "--batch", p("bad_batch.txt"))
# Batch = the single-case command, line by line; a bad case is reported in its line, the rest go on.
with open(p("batch.txt"), "w") as f:
    f.write(f"# comment\n{local_tif} {prior.replace(',', ' ')}\n\n{p('missing.tif')} {prior.replace(',', ' ')} 1.0\n"
            f"{local_tif} {prior.replace(',', ' ')} 1.5\n")
single = run_json("localize", "--dem", g_tif, *common, "--json")
single15 = run_json("localize", "--dem", g_tif, *common, "--window-m", "1.5", "--json")
out = run("localize", "--dem", g_tif, "--batch", p("batch.txt"))
lines = [json.loads(x) for x in out[1].splitlines() if x.strip()]
for k, obj in enumerate(lines):
    H.check_version(obj, f"localize --batch line {k + 1}")
check(len(lines) == 3, f"batch: three result lines: {len(lines)}")
if len(lines) == 3:
    for got, want in ((lines[0], single), (lines[2], single15)):
        check(all(got[k] == want[k] for k in ("x_m", "y_m", "sigma_x_m", "sigma_y_m", "failure_probability", "status")),
              f"batch line equals the single-case result: {got} vs {want}")
    check(lines[1]["status"] == "error" and "cannot read" in lines[1]["error"], f"batch: bad case reported: {lines[1]}")
for mode in ("auto", "paper"):
    r = run_json("localize", "--dem", g_tif, *common, "--map-config", mode, "--json")
    err = math.hypot(r["x_m"] - truth[0], r["y_m"] - truth[1]) if r.get("x_m") is not None else 1e9
    check(err < 0.5 * CELL and r["status"] == "ok", f"--map-config {mode}: error {err:.4f} m, {r['status']}")
    check(r["map_config"]["refine"] == (1 if mode == "auto" else 0), f"--map-config {mode}: refine {r['map_config']}")

# ---- localize over heading (--heading-deg, --heading-window-deg; issue 14) -------
# The local DEM seen with the heading off by DELTA: its cell offset o (east,
# south, cells) shows the terrain at o turned DELTA counterclockwise about the
# rover, bilinear from G; the search must give the correction DELTA.
DELTA = 4.0
c_, s_ = math.cos(math.radians(DELTA)), math.sin(math.radians(DELTA))
jj, ii = np.meshgrid(np.arange(L) - 32.0, np.arange(L) - 32.0)  # jj: column offset, ii: row offset
gx, gy = RC + jj * c_ + ii * s_, RR - jj * s_ + ii * c_
x0, y0 = np.floor(gx).astype(int), np.floor(gy).astype(int)
fx, fy = gx - x0, gy - y0
rot = (G[y0, x0] * (1 - fx) * (1 - fy) + G[y0, x0 + 1] * fx * (1 - fy) + G[y0 + 1, x0] * (1 - fx) * fy
       + G[y0 + 1, x0 + 1] * fx * fy).astype(np.float32)
rot_gt = (-32.5 * CELL, CELL, 0.0, 32.5 * CELL, 0.0, -CELL)  # rover at the centre of local cell (32, 32)
write_raster(p("local_turned.tif"), rot, rot_gt)
turned = ["--local", p("local_turned.tif"), "--prior", prior, "--map-config", "paper"]
r = run_json("localize", "--dem", g_tif, *turned, "--heading-window-deg", "8", "--json")
if r.get("heading_deg") is not None:
    err = math.hypot(r["x_m"] - truth[0], r["y_m"] - truth[1])
    cov3 = r["cov3"]
    print(f"localize over heading: {r['heading_deg']:+.3f} deg (true {DELTA:+.1f}), sigma {r['sigma_heading_deg']:.3f} "
          f"deg, position error {err:.4f} m, {r['status']}")
    check(abs(r["heading_deg"] - DELTA) < 1.0, f"--heading-window-deg: heading {r['heading_deg']} vs {DELTA}")
    check(err < 1.5 * CELL and r["status"] == "ok", f"--heading-window-deg: position error {err:.4f} m, {r['status']}")
    check(len(cov3) == 9 and all(abs(cov3[3 * a + b] - cov3[3 * b + a]) < 1e-12 for a in range(3) for b in range(3))
          and cov3[8] > 0 and abs(cov3[8] ** 0.5 - r["sigma_heading_deg"]) < 1e-9 and cov3[0] == r["cov_m2"][0],
          f"--heading-window-deg: cov3 symmetric, its heading variance sigma^2: {cov3}")
else:
    check(False, f"--heading-window-deg: no heading in {r}")
r0 = run_json("localize", "--dem", g_tif, *turned, "--json")
err0 = math.hypot(r0["x_m"] - truth[0], r0["y_m"] - truth[1]) if r0.get("x_m") is not None else 1e9
check("heading_deg" not in r0, "no heading fields without the heading options")
print(f"the same case with the heading taken as known: error {err0:.4f} m, {r0.get('status')}")
# --heading-deg alone turns the local DEM by the given correction (window 0): the turned map back in place
rh = run_json("localize", "--dem", g_tif, *turned, "--heading-deg", str(DELTA), "--json")
errh = math.hypot(rh["x_m"] - truth[0], rh["y_m"] - truth[1]) if rh.get("x_m") is not None else 1e9
check(rh.get("heading_deg") == DELTA and rh.get("sigma_heading_deg") == 0 and errh < 1.5 * CELL,
      f"--heading-deg {DELTA} alone: heading {rh.get('heading_deg')}, error {errh:.4f} m")
expect_error(1, "the voxel matcher searches heading without refinement only", "localize", "--dem", g_tif,
             *common, "--match", "voxel", "--heading-window-deg", "5")
# the default (auto) configuration: the height matcher over heading, refined
auto_turned = [a for a in turned if a not in ("--map-config", "paper")]
rha = run_json("localize", "--dem", g_tif, *auto_turned, "--heading-window-deg", "8", "--json")
erra = math.hypot(rha["x_m"] - truth[0], rha["y_m"] - truth[1]) if rha.get("x_m") is not None else 1e9
print(f"localize over heading, auto (height matcher): {rha.get('heading_deg')} deg (true {DELTA:+.1f}), sigma "
      f"{rha.get('sigma_heading_deg')} deg, position error {erra:.4f} m, {rha.get('status')}")
check(rha.get("heading_deg") is not None and abs(rha["heading_deg"] - DELTA) < 0.5 and erra < 0.5 * CELL
      and rha["status"] == "ok" and rha["refined"] and rha["map_config"]["match"] == "heights",
      f"--heading-window-deg with the auto configuration: {rha}")
check(rha.get("sigma_heading_deg", 0) > 0 and abs(rha["cov3"][8] ** 0.5 - rha["sigma_heading_deg"]) < 1e-9
      and rha["cov3"][0] == rha["cov_m2"][0], f"auto: cov3's heading variance sigma^2: {rha.get('cov3')}")
# W = 0 with the auto configuration is the plain localization, field for field
r0a = run_json("localize", "--dem", g_tif, *common, "--heading-window-deg", "0", "--json")
r0b = run_json("localize", "--dem", g_tif, *common, "--json")
check(all(r0a[k] == r0b[k] for k in ("x_m", "y_m", "cov_m2", "failure_probability", "status", "poses_scored"))
      and r0a["heading_deg"] == 0 and r0a["sigma_heading_deg"] == 0,
      f"auto, --heading-window-deg 0: the plain result {r0a} vs {r0b}")
expect_error(1, "--heading-window-deg: 200 is out of range", "localize", "--dem", g_tif, *turned,
             "--heading-window-deg", "200")
expect_error(1, "--heading-deg: 'nan' is not a finite number", "localize", "--dem", g_tif, *turned,
             "--heading-deg", "nan")

# ---- figures (tools/plot/trn_plot.py), when matplotlib is there -----------------
try:
    import matplotlib  # noqa: F401
    have_mpl = True
except ImportError:
    have_mpl = False
    print("note: matplotlib missing, figures not checked")
if have_mpl:
    plot = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "plot", "trn_plot.py")
    loc_json = p("loc.json")
    with open(loc_json, "w") as f:
        f.write(run("localize", "--dem", g_tif, "--local", local_tif, "--prior", prior, "--json")[1])
    for fig, extra in (("dem", ["--rover", f"{truth[0]},{truth[1]}", "--localize-json", loc_json]),
                       ("surface", []), ("raster", ["--label", "height (m)", "--target", "1010,2020"])):
        png = p(f"fig_{fig}.png")
        r = subprocess.run([sys.executable, plot, fig, g_asc if fig == "raster" else g_tif, "--out", png] + extra,
                           capture_output=True, text=True, timeout=300)
        ok = r.returncode == 0 and os.path.exists(png) and os.path.getsize(png) > 20000
        with open(png, "rb") if os.path.exists(png) else open(os.devnull, "rb") as f:
            ok = ok and f.read(8) == b"\x89PNG\r\n\x1a\n"
        check(ok, f"trn_plot.py {fig}: {r.returncode} {r.stderr.strip()[-300:]}")
    r = subprocess.run([sys.executable, plot, "dem", p("missing.tif"), "--out", p("no.png")],
                       capture_output=True, text=True, timeout=60)
    check(r.returncode != 0 and "cannot read" in r.stderr and not os.path.exists(p("no.png")),
          "trn_plot.py dem on a missing file fails with a reason")

sys.exit(H.finish())
