#!/usr/bin/env python3
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
