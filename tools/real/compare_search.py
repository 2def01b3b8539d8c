#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/real/compare_search.py - the height matcher's bounded search against its oracle.

    /usr/bin/python3 tools/real/compare_search.py [--dem ID ...] [--cases N] [--seed S]
        [--radius R] [--window-cells W] [--trn PATH] [--out FILE] [-- TRN_ARGS...]

For each DEM (tools/real/dems.py; default: every one of dems.DEFAULT) it draws bench_real's
seeded cases (tools/real/cases.py: a rover's (2R+1)^2 local DEM with range-dependent
noise, a prior within +-4 cells; --window-cells W widens the search window from bench_real's
+-6 cells) and localizes each twice in one `trn localize --batch` run per search:
`--search exhaustive` (every pose scored: the oracle) and `--search bounded`. Every field of
each JSON line is compared: statuses, strings and flags equal; numbers equal to the bit
except the failure probability (within the bounded line's failure_prob_bound), the
covariance's entries and sigmas (1e-9 relative), and the work and time fields (poses_scored,
blocks_bounded, time_ms, search, failure_prob_bound), which are reported, not compared.

Prints per DEM: cases, mismatches, median time per localization of each search and their
ratio, the median share of poses scored; writes --out (JSON). Exit status 0 when every
field of every case agrees, 1 otherwise (the first mismatches are printed).
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cases as casemod  # noqa: E402
import dems  # noqa: E402

SKIP = {"time_ms", "poses_scored", "blocks_bounded", "search", "failure_prob_bound"}
REL = {"cov_m2", "sigma_x_m", "sigma_y_m", "rho"}


def run(trn, dem, lst, search, extra):
    cmd = [trn, "localize", "--dem", dem, "--batch", lst, "--json", "--search", search] + extra
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise SystemExit(f"compare_search: {' '.join(cmd)} failed: {r.stderr.strip()[:200]}")
    return [json.loads(x) for x in r.stdout.splitlines() if x.strip()]


def same(a, b, key, bound):
    """None if values a (oracle) and b (bounded) agree under the rule of key."""
    if isinstance(a, dict):
        for k in a:
            if k in SKIP:
                continue
            m = same(a[k], b.get(k), k, bound)
            if m:
                return f"{k}.{m}"
        return None
    if isinstance(a, list):
        if not isinstance(b, list) or len(a) != len(b):
            return f"{key}: {a} != {b}"
        for x, y in zip(a, b):
            m = same(x, y, key, bound)
            if m:
                return m
        return None
    if isinstance(a, float) and isinstance(b, (int, float)):
        if key == "failure_probability":
            return None if abs(a - b) <= bound else f"{key}: {a} vs {b} (bound {bound})"
        if key in REL and math.isfinite(a) and math.isfinite(b):
            return None if abs(a - b) <= 1e-9 * max(abs(a), abs(b)) + 1e-300 else f"{key}: {a} vs {b}"
        return None if (a == b or (math.isnan(a) and math.isnan(b))) else f"{key}: {a!r} vs {b!r}"
    return None if a == b else f"{key}: {a!r} vs {b!r}"


def med(v):
    v = sorted(v)
    return v[len(v) // 2] if v else float("nan")


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dem", action="append", help="DEM id of tools/real/dems.py (repeat; default: all)")
    ap.add_argument("--cases", type=int, default=200)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--radius", type=int, default=20)
    ap.add_argument("--window-cells", type=int, default=6)
    ap.add_argument("--trn", default=os.path.join(dems.ROOT, "build", "host-release", "trn"))
    ap.add_argument("--out", default=None)
    ap.add_argument("rest", nargs="*", help="-- then extra trn localize arguments")
    a = ap.parse_args(argv)
    if a.cases < 1 or a.radius < 2 or a.window_cells < 1:
        print("compare_search: --cases, --radius and --window-cells must be positive", file=sys.stderr)
        return 1
    os.environ.setdefault("TRN", a.trn)
    ids = a.dem or dems.DEFAULT
    report, bad = {}, 0
    print(f"{'dem':16s} {'cases':>5s} {'mism':>5s} {'exh ms':>8s} {'bnd ms':>8s} {'ratio':>6s} {'scored':>7s}")
    for dem_id in ids:
        path = dems.get(dem_id)
        dem = casemod.read_dem(path)
        p = casemod.CaseParams(radius=a.radius, window_cells=float(a.window_cells))
        tmp = tempfile.mkdtemp(prefix=f"compare_search_{dem_id}_")
        casemod.generate(dem, a.cases, a.seed, p, tmp)
        lst = os.path.join(tmp, "cases.txt")
        ex = run(a.trn, path, lst, "exhaustive", a.rest)
        bd = run(a.trn, path, lst, "bounded", a.rest)
        mism = []
        for i, (x, y) in enumerate(zip(ex, bd)):
            m = same(x, y, "", float(y.get("failure_prob_bound", 0.0)))
            if m:
                mism.append((i, m))
        te = [x.get("time_ms", float("nan")) for x in ex]
        tb = [y.get("time_ms", float("nan")) for y in bd]
        share = [y["poses_scored"] / max(1, x["poses_scored"]) for x, y in zip(ex, bd)
                 if "poses_scored" in y and "poses_scored" in x]
        report[dem_id] = {"cases": len(ex), "mismatches": len(mism), "first": mism[:5],
                          "exhaustive_ms": med(te), "bounded_ms": med(tb),
                          "ratio": med(tb) / med(te) if med(te) > 0 else None,
                          "scored_share": med(share), "window_cells": a.window_cells,
                          "radius": a.radius}
        bad += len(mism)
        print(f"{dem_id:16s} {len(ex):5d} {len(mism):5d} {med(te):8.2f} {med(tb):8.2f} "
              f"{med(tb) / med(te):6.2f} {med(share):7.3f}", flush=True)
        for i, m in mism[:3]:
            print(f"  case {i}: {m}")
    if a.out:
        with open(a.out, "w") as f:
            json.dump(report, f, indent=1)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
