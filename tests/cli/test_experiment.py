#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tests/cli/test_experiment.py - `trn experiment` end to end (CTest `cli_experiment`).

    python3 tests/cli/test_experiment.py PATH/TO/trn WORKDIR

A small, fast configuration (128 x 128 cells, a few trials): determinism (same seed ->
identical JSON; another seed -> different trials), the JSON's fields and their
consistency (successes <= localizations, 9 localizations per trial without selection,
rates inside their 95 % intervals, mean error inside its interval and within the
success radius), the human table, every bad-input class (exit 1 or 2, one line
`trn experiment: ...`, nothing on stdout), and the figure (tools/plot/trn_plot.py
experiment) when matplotlib is there. Exit status 0 when every check passes.
"""
import json
import math
import os
import shutil
import subprocess
import sys

import clitest  # noqa: E402  (tests/cli/, the script's own directory)

TRN = os.path.abspath(sys.argv[1])
WORK = os.path.abspath(sys.argv[2])
H = clitest.Harness(TRN, sub=("experiment",))
check, run, expect_error = H.check, H.run, H.expect_error


shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)
SMALL = ["--size-cells", 128, "--trials", 6]

# ---- determinism ------------------------------------------------------------
rc1, out1, err1 = run(*SMALL, "--seed", 5, "--json")
rc2, out2, err2 = run(*SMALL, "--seed", 5, "--json")
check(rc1 == 0 and rc2 == 0, f"small runs exit {rc1}, {rc2}: {err1.strip()} {err2.strip()}")
check(out1 == out2 and out1 != "", "same seed, same options: the JSON differs between runs")
check(err1 == "", f"stderr not empty without a terminal (progress bar must stay off): {err1!r}")
rc3, out3, _ = run(*SMALL, "--seed", 6, "--json")
check(rc3 == 0 and out3 != out1, "another seed gives the same JSON")
rc4, out4, _ = run(*SMALL, "--seed", 6, "--terrain-seed", 5, "--json")
check(rc4 == 0 and out4 not in (out1, out3), "--terrain-seed changes nothing")

# ---- the JSON -----------------------------------------------------------------
try:
    r = json.loads(out1)
except ValueError:
    r = {}
    check(False, f"not one JSON object: {out1!r}")
check(out1.count("\n") == 1, "JSON is not one line")
H.check_version(r, "experiment --json")
check(r.get("localizer") == "voxel", f"the generated terrain's default localizer: {r.get('localizer')}")
check(r.get("trials") == 6 and r.get("seed") == 5, f"trials / seed wrong: {r.get('trials')}, {r.get('seed')}")
check(r.get("terrain", {}).get("seed") == 5 and r["terrain"].get("size_cells") == 128,
      "terrain seed defaults to --seed, size as asked")
par = r.get("parameters", {})
for key in ("patch_cells", "window_m", "prior_error_m", "grid_spacing_m", "success_radius_m", "sensor_model"):
    check(key in par, f"parameters.{key} missing")
check(abs(par.get("success_radius_m", 0) - 0.2) < 1e-12, "default success radius is not 2 cells = 0.2 m")
for arm, per in (("with_selection", 1), ("without_selection", 9)):
    a = r.get(arm)
    check(isinstance(a, dict), f"{arm} missing")
    if not isinstance(a, dict):
        continue
    for key in ("success_rate", "successes", "mean_error_m", "ci95", "localizations", "mean_error_ci95"):
        check(key in a, f"{arm}.{key} missing")
    n, k = a.get("localizations", -1), a.get("successes", -1)
    check(n == per * 6, f"{arm}: {n} localizations for 6 trials, want {per * 6}")
    check(0 <= k <= n, f"{arm}: successes {k} not in [0, {n}]")
    check(abs(a["success_rate"] - k / n) < 1e-12, f"{arm}: success_rate {a['success_rate']} != {k}/{n}")
    lo, hi = a["ci95"]
    check(0 <= lo <= a["success_rate"] <= hi <= 1, f"{arm}: ci95 {a['ci95']} does not hold the rate")
    check(a["success_rate_1_cell"] <= a["success_rate"] <= a["success_rate_5_cells"],
          f"{arm}: rates at 1 / 2 / 5 cells not ordered")
    if k >= 2:
        e = a["mean_error_m"]
        elo, ehi = a["mean_error_ci95"]
        check(0 <= e <= 0.2 + 1e-9, f"{arm}: mean error {e} of successes beyond the success radius")
        check(elo <= e <= ehi, f"{arm}: mean_error_ci95 {a['mean_error_ci95']} does not hold {e}")

# A larger success radius can only add successes (same trials, same seed).
rc, out, _ = run(*SMALL, "--seed", 5, "--json", "--success-cells", 5)
if rc == 0:
    r5 = json.loads(out)
    for arm in ("with_selection", "without_selection"):
        check(r5[arm]["successes"] >= r[arm]["successes"] and
              r5[arm]["successes"] == round(r[arm]["success_rate_5_cells"] * r[arm]["localizations"]),
              f"{arm}: --success-cells 5 disagrees with success_rate_5_cells")
else:
    check(False, "--success-cells 5 run failed")

# The diagnostic DEM sensor runs and says so.
rc, out, err = run(*SMALL, "--sensor", "dem", "--height-noise-m", 0.02, "--json")
check(rc == 0 and json.loads(out)["parameters"]["sensor"] == "dem", f"--sensor dem: {rc} {err.strip()}")

# The largest seed is printed as it was given (unsigned 64 bit).
rc, out, err = run("--size-cells", 128, "--trials", 1, "--seed", 18446744073709551615, "--json")
check(rc == 0 and json.loads(out)["seed"] == 18446744073709551615 and
      json.loads(out)["terrain"]["seed"] == 18446744073709551615, f"seed 2^64-1: {rc} {out[:80]!r} {err.strip()}")

# ---- the human table ----------------------------------------------------------------
rc, out, err = run(*SMALL, "--seed", 5)
check(rc == 0 and "with selection" in out and "without selection" in out and "%" in out,
      f"table output: {rc} {out!r} {err!r}")
rc, out, _ = run("--help")
check(rc == 0 and "--trials" in out and "--coverage" in out and "--seed" in out, "--help lists the options")

# ---- bad input ------------------------------------------------------------------------
expect_error(1, "--trials", "--trials", 0)
expect_error(1, "--trials", "--trials", "ten")
expect_error(1, "--trials", "--trials", 2000000)
expect_error(1, "--seed", "--seed", -1)
expect_error(1, "--coverage", "--coverage", 0.9)
expect_error(1, "--coverage", "--coverage", "nan")
expect_error(1, "--size-cells", "--size-cells", 32)
expect_error(1, "--window-m", "--window-m", 0)
expect_error(1, "below the prior error", "--window-m", 0.5, "--prior-error-m", 1)
expect_error(1, "--success-cells", "--success-cells", -1)
expect_error(1, "smallest rock", "--min-diameter-m", 3, "--trials", 1, "--size-cells", 128)
expect_error(1, "nine fixed targets", "--size-cells", 64, "--trials", 1)
expect_error(1, "--sensor", "--sensor", "lidar")
expect_error(1, "height noise applies only", "--height-noise-m", 0.01)
expect_error(1, "--height-noise-m", "--sensor", "dem", "--height-noise-m", 2)
expect_error(2, "unknown option", "--bogus")
expect_error(2, "--trials", "--trials")


# ---- heading error (issue 14, item 6) ----------------------------------------------------
# 0 is the paper's run bit for bit; S > 0 adds the 3-DOF arms on the same localizations,
# selection counts the lever arm, the window is 3 S by default
rc, out0, _ = run(*SMALL, "--seed", 5, "--heading-error-deg", 0, "--json")
check(rc == 0 and out0 == out1, "--heading-error-deg 0 is the default run bit for bit")
check("heading" not in r, "no heading block without a heading error")
rc, outh, errh = run(*SMALL, "--seed", 5, "--heading-error-deg", 3, "--json")
try:
    rh = json.loads(outh)
except ValueError:
    rh = {}
    check(False, f"heading run: not one JSON object: {outh!r} {errh!r}")
hd = rh.get("heading", {})
check(abs(hd.get("error_deg", 0) - 3) < 1e-12 and abs(hd.get("window_deg", 0) - 9) < 1e-9,
      f"heading block: error 3, window 3 x 3 = 9 deg ({hd})")
check(abs(hd.get("selection_sigma_heading_rad", 0) - math.radians(3)) < 1e-7, "selection's sigma_heading is the error")
for arm, base in (("with_selection_3dof", "with_selection"), ("without_selection_3dof", "without_selection")):
    a3, a2 = hd.get(arm, {}), rh.get(base, {})
    check(a3.get("localizations") == a2.get("localizations") and a3.get("localizations", 0) > 0,
          f"{arm}: the same localizations as {base} ({a3.get('localizations')}, {a2.get('localizations')})")
    check(0 <= a3.get("successes", -1) <= a3.get("localizations", 0), f"{arm}: successes within the localizations")
# the 3-DOF arm with selection ranks its own target for a heading search (default 1); with 0 it
# senses the x-y arm's. Either way the x-y arms and the 3-DOF arm without selection are the same
# (its sensing starts from the trial's random state before the x-y arm's)
check(hd.get("select_heading_search") == 1, "the 3-DOF arm's selection knows the heading is searched")
ntr = rh.get("trials", 0)
check(0 <= hd.get("trials_3dof_other_target", -1) <= ntr, f"trials with another 3-DOF target: {hd}")
rc, outs0, _ = run(*SMALL, "--seed", 5, "--heading-error-deg", 3, "--select-heading-search", 0, "--json")
rs0 = json.loads(outs0) if rc == 0 else {}
hs0 = rs0.get("heading", {})
check(hs0.get("select_heading_search") == 0 and hs0.get("trials_3dof_other_target") == 0,
      "--select-heading-search 0: the 3-DOF arm senses the x-y arm's targets")
for key in ("with_selection", "without_selection"):
    check(rs0.get(key) == rh.get(key), f"{key}: the same with either 3-DOF selection")
check(hs0.get("without_selection_3dof") == hd.get("without_selection_3dof"),
      "without_selection_3dof: the same with either 3-DOF selection")
if hd.get("trials_3dof_other_target") == 0:
    check(hs0.get("with_selection_3dof") == hd.get("with_selection_3dof"),
          "the same targets: the same 3-DOF arm")
expect_error(1, "--select-heading-search", "--heading-error-deg", 3, "--select-heading-search", 2)
rc, outw, _ = run(*SMALL, "--seed", 5, "--heading-error-deg", 3, "--heading-window-deg", 4, "--json")
check(rc == 0 and abs(json.loads(outw).get("heading", {}).get("window_deg", 0) - 4) < 1e-12, "--heading-window-deg 4")
rc, outt, _ = run(*SMALL, "--seed", 5, "--heading-error-deg", 3)
check(rc == 0 and "3-DOF" in outt, "the table shows the 3-DOF arms")
expect_error(1, "--heading-error-deg", "--heading-error-deg", -1)
expect_error(1, "--heading-error-deg", "--heading-error-deg", 31)
expect_error(1, "--heading-error-deg", "--heading-error-deg", "nan")
expect_error(1, "--heading-window-deg", "--heading-window-deg", 181)

# ---- --dem: the experiment on a given DEM (issue 12, item 7) ----------------------------
# The generated terrain written by `trn terrain` and handed back as --dem with the
# paper's configuration gives the same trials and numbers as the generated run.
dem128 = os.path.join(WORK, "t128.tif")
p_ = subprocess.run([TRN, "terrain", "--out", dem128, "--size-cells", "128", "--seed", "5", "--crs", "EPSG:32615"],
                    capture_output=True, text=True, timeout=120)
rc, err = p_.returncode, p_.stderr
check(rc == 0, f"trn terrain for --dem: {err}")
rc, outd, errd = run("--dem", dem128, "--trials", 6, "--seed", 5, "--map-config", "paper", "--json")
check(rc == 0, f"--dem run: {rc} {errd.strip()}")
if rc == 0:
    d = json.loads(outd)
    check(d["terrain"].get("dem") == dem128 and d["terrain"].get("width") == 128 and d["terrain"].get("scale") == 1,
          f"--dem: terrain block {d['terrain']}")
    for arm in ("with_selection", "without_selection"):
        check(d[arm] == r[arm], f"--dem of the generated terrain, paper configuration: {arm} differs from the generated run")
    check(d.get("map_config_name") == "paper" and d["parameters"].get("max_range_m") == 10, "paper config, 10 m reach")
rc, outa, erra = run("--dem", dem128, "--trials", 6, "--seed", 5, "--json")
check(rc == 0 and json.loads(outa).get("map_config_name") == "auto", f"--dem defaults to --map-config auto: {erra.strip()}")
check(rc == 0 and json.loads(outa).get("localizer") == "heights", "--dem's auto configuration localizes with heights")
# 10x the cell: every length scales by 10 (the same experiment in cells)
try:
    from osgeo import gdal
    gdal.UseExceptions()
    ds = gdal.Open(dem128)
    arr = ds.GetRasterBand(1).ReadAsArray()
    srs = ds.GetProjection()
    ds = None
    big = os.path.join(WORK, "t128x10.tif")
    clitest.write_raster(big, arr * 10.0, (0.0, 1.0, 0.0, 128.0, 0.0, -1.0), srs=srs)
    rc, outb, errb = run("--dem", big, "--trials", 6, "--seed", 5, "--map-config", "paper", "--json")
    check(rc == 0, f"--dem at 1 m: {errb.strip()}")
    if rc == 0:
        b = json.loads(outb)
        pb = b["parameters"]
        check(b["terrain"]["scale"] == 10 and pb["window_m"] == 20 and pb["prior_error_m"] == 10 and
              pb["grid_spacing_m"] == 20 and abs(pb["max_range_m"] - 100) < 1e-4 and abs(pb["patch_m"] - 20) < 1e-4 and
              pb["patch_cells"] == 21, f"--dem at 1 m cells: lengths x 10: {pb}")
        for arm in ("with_selection", "without_selection"):
            check(b[arm]["successes"] == r[arm]["successes"] and
                  abs(b[arm]["mean_error_m"] - 10 * r[arm]["mean_error_m"]) <= 1e-4 * b[arm]["mean_error_m"],
                  f"{arm}: the same experiment in cells at 10x the cell")
    # bad DEMs: geographic, too small, too large, all no-data
    geo = os.path.join(WORK, "geo.tif")
    clitest.write_raster(geo, arr, (10.0, 1e-5, 0.0, 50.0, 0.0, -1e-5), srs="EPSG:4326")
    expect_error(1, "--dem:", "--dem", geo, "--trials", 1)
    small = os.path.join(WORK, "small.tif")
    clitest.write_raster(small, arr[:50, :50], (0.0, 0.1, 0.0, 5.0, 0.0, -0.1), srs=srs)
    expect_error(1, "too small for the experiment", "--dem", small, "--trials", 1, "--map-config", "paper")
    wide = os.path.join(WORK, "wide.tif")
    import numpy as np
    clitest.write_raster(wide, np.zeros((20, 1100), dtype=np.float32), (0.0, 0.1, 0.0, 2.0, 0.0, -0.1), srs=srs)
    expect_error(1, "--dem:", "--dem", wide, "--trials", 1)
    nod = os.path.join(WORK, "nodata.tif")
    clitest.write_raster(nod, np.full((128, 128), -9999.0, dtype=np.float32), (0.0, 0.1, 0.0, 12.8, 0.0, -0.1),
                         nodata=-9999.0, srs=srs)
    expect_error(1, "--dem:", "--dem", nod, "--trials", 1)
    errr = os.path.join(WORK, "err_small.tif")
    clitest.write_raster(errr, np.full((64, 64), 0.1, dtype=np.float32), (0.0, 0.1, 0.0, 6.4, 0.0, -0.1), srs=srs)
    expect_error(1, "must be on the DEM's grid", "--dem", dem128, "--trials", 1, "--match", "voxel", "--global-error",
                 errr)
    # with the height matcher (auto, the default with --dem) eq. 8's raster is the voxel prediction's only
    expect_error(2, "applies to the voxel prediction", "--dem", dem128, "--trials", 1, "--global-error", errr)
    errok = os.path.join(WORK, "err_nan.tif")
    clitest.write_raster(errok, np.full((128, 128), np.nan, dtype=np.float32), (0.0, 0.1, 0.0, 12.8, 0.0, -0.1),
                         srs=srs)
    rc, oute, erre = run("--dem", dem128, "--trials", 6, "--seed", 5, "--map-config", "paper", "--global-error", errok,
                         "--json")
    check(rc == 0 and json.loads(oute)["with_selection"] == r["with_selection"],
          f"--global-error all no-data = the model: {erre.strip()}")
    rc, outg, errg = run("--dem", dem128, "--trials", 6, "--seed", 5, "--map-config", "paper", "--global-sigma-m", 0.2,
                         "--global-sigma-k", 0, "--json")
    check(rc == 0 and abs(json.loads(outg)["global_error"]["sigma_m"] - 0.2) < 1e-7, "--global-sigma-m in experiment")
except ImportError:
    print("note: GDAL's Python bindings missing, the scaled and bad --dem cases are not checked")
expect_error(1, "--dem: cannot read", "--dem", os.path.join(WORK, "missing.tif"), "--trials", 1)
expect_error(2, "--coverage shapes the generated terrain", "--dem", dem128, "--coverage", 0.2)
expect_error(2, "--global-error needs --dem", "--global-error", dem128)
expect_error(1, "--map-config must be auto or paper", "--trials", 1, "--size-cells", 128, "--map-config", "x")
# ---- the figure -------------------------------------------------------------------------
try:
    import matplotlib  # noqa: F401
    have_mpl = True
except ImportError:
    have_mpl = False
    print("note: matplotlib missing, the figure is not checked")
if have_mpl:
    plot = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "plot", "trn_plot.py")
    j1, j2 = os.path.join(WORK, "a.json"), os.path.join(WORK, "b.json")
    with open(j1, "w") as f:
        f.write(out1)
    with open(j2, "w") as f:
        f.write(out3)
    png = os.path.join(WORK, "exp.png")
    p = subprocess.run([sys.executable, plot, "experiment", j1, j2, "--labels", "seed 5,seed 6", "--out", png],
                       capture_output=True, text=True, timeout=300)
    ok = p.returncode == 0 and os.path.exists(png) and os.path.getsize(png) > 20000
    if ok:
        with open(png, "rb") as f:
            ok = f.read(8) == b"\x89PNG\r\n\x1a\n"
    check(ok, f"trn_plot.py experiment: {p.returncode} {p.stderr.strip()[-300:]}")
    bad = os.path.join(WORK, "bad.json")
    with open(bad, "w") as f:
        f.write('{"trials": 1}\n')
    p = subprocess.run([sys.executable, plot, "experiment", bad, "--out", os.path.join(WORK, "no.png")],
                       capture_output=True, text=True, timeout=60)
    check(p.returncode != 0 and "not `trn experiment --json` output" in p.stderr
          and not os.path.exists(os.path.join(WORK, "no.png")), "trn_plot.py experiment on a wrong JSON")

sys.exit(H.finish())
