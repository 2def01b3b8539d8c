#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/real/draw_study.py - how much of the height matcher's reported covariance is the noise
of its own estimate (issue 36 item 4; docs/method.md 9.10, "The covariance's own noise").

    /usr/bin/python3 tools/real/draw_study.py --dem ID [--radius R] [--truth-fine K]
        [--cases N] [--draws M] [--seed S] [--counts] [--trn PATH] [--out DIR] [-- TRN_ARGS...]

The rover's binned local maps of bench_real.py (--truth-fine K --fine-local binned), N cases,
each localized M times: draw d (bench_real --points-draw d) scatters other stereo points with
other noise over the same case (truth, prior, view, offset). A case's answers then share what
the case itself puts into the error (the common error of the map's interpolant: their mean),
and differ by what the points put into it. Per case, over its draws:

* the true covariance's trace: the draws' scatter about their mean (the points' part) plus the
  square of that mean, less its own sampling share (the case's part, `bias2`);
* the reported covariance's trace, its mean over the draws and its coefficient of variation
  (`cv`): how much the estimate moves when only the points move;
* the coverage (inside the 1, 2, 3-sigma ellipses) of the draws' errors with each draw's own
  reported covariance, and with the case's mean reported covariance: what the coverage would
  be were the estimate free of its own noise; both also without the block sandwich's
  inflation and the shoulders (the reported covariance divided by their product);
* the true over the mean reported trace by fifth of the mean reported trace: whether the
  prediction follows the cases.

With --counts trn is given each cell's point count (bench_real --counts). Cases whose answer
is wrong (error above 1.5 cells) in any draw are left out. Prints one
summary and writes OUT/draw_study.json. Errors and covariances in cells."""
import argparse
import io
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_real  # noqa: E402
import dems  # noqa: E402

CHI2 = (1.0, 4.0, 9.0)


Fail = bench_real.Fail  # one refusal type for the study and the benchmark it runs


def mahalanobis2(e, c):
    """e (..., 2) errors, c (..., 3) covariances (xx, yy, xy): e^T C^-1 e."""
    det = c[..., 0] * c[..., 1] - c[..., 2] ** 2
    return (c[..., 1] * e[..., 0] ** 2 - 2.0 * c[..., 2] * e[..., 0] * e[..., 1]
            + c[..., 0] * e[..., 1] ** 2) / det


def coverage(m2):
    return [100.0 * float(np.mean(m2 <= k)) for k in CHI2]


def analyse(err, cov, infl):
    """err (cases, draws, 2), cov (cases, draws, 3), infl (cases, draws): the inflation times the
    shoulders of each answer. Every case has at least 2 draws; the arrays are finite."""
    n, m = err.shape[0], err.shape[1]
    if m < 2 or n < 5:
        raise Fail(f"{n} cases x {m} draws: needs at least 5 cases and 2 draws")
    mean = err.mean(axis=1)
    dev = err - mean[:, None, :]
    rand = (dev ** 2).sum(axis=2).sum(axis=1) / (m - 1)  # trace of the points' part
    bias2 = (mean ** 2).sum(axis=1) - rand / m  # the case's part, less its sampling share
    true_tr = rand + bias2
    tr = cov[:, :, 0] + cov[:, :, 1]
    mtr = tr.mean(axis=1)
    cv = tr.std(axis=1) / mtr
    base = cov / infl[:, :, None]
    own, own_b = mahalanobis2(err, cov), mahalanobis2(err, base)
    mc = np.repeat(cov.mean(axis=1)[:, None, :], m, axis=1)
    mb = np.repeat(base.mean(axis=1)[:, None, :], m, axis=1)
    case_mean, case_mean_b = mahalanobis2(err, mc), mahalanobis2(err, mb)
    order = np.argsort(mtr, kind="stable")
    fifths = [order[f * n // 5:(f + 1) * n // 5] for f in range(5)]
    return {"cases": int(n), "draws": int(m),
            "true_trace": float(true_tr.mean()), "points_trace": float(rand.mean()),
            "case_trace": float(bias2.mean()), "reported_trace": float(mtr.mean()),
            "cv_median": float(np.median(cv)),
            "coverage_own": coverage(own), "coverage_case_mean": coverage(case_mean),
            "coverage_own_no_inflation": coverage(own_b),
            "coverage_case_mean_no_inflation": coverage(case_mean_b),
            "mean_m2_own": float(own.mean()), "mean_m2_case_mean": float(case_mean.mean()),
            "true_over_reported_by_fifth": [float(true_tr[f].sum() / mtr[f].sum()) for f in fifths]}


def parse_args(argv):
    extra = []
    if "--" in argv:
        k = argv.index("--")
        argv, extra = argv[:k], argv[k + 1:]
    ap = argparse.ArgumentParser(prog="draw_study.py", description=__doc__.split("\n")[0])
    ap.add_argument("--dem", required=True, help="a tools/real/dems.py id")
    ap.add_argument("--radius", type=int, default=12, help="local map radius, cells (default 12)")
    ap.add_argument("--truth-fine", type=int, default=2, metavar="K", help="K (default 2)")
    ap.add_argument("--cases", type=int, default=100, help="cases (default 100)")
    ap.add_argument("--draws", type=int, default=40, help="draws of the points a case (default 40)")
    ap.add_argument("--seed", type=int, default=13, help="seed (default 13)")
    ap.add_argument("--counts", action="store_true",
                    help="trn is given each cell's point count (bench_real --counts)")
    ap.add_argument("--trn", default=os.path.join(dems.ROOT, "build", "host-release", "trn"))
    ap.add_argument("--out", default=os.path.join(dems.BUILD, "draw_study"))
    a = ap.parse_args(argv)
    if a.draws < 2 or a.cases < 5:
        raise Fail(f"--cases {a.cases} --draws {a.draws}: needs at least 5 cases and 2 draws")
    a.trn_extra = extra
    return a


def read_draw(path):
    """One draw's bench.json: per case (error x, y, covariance xx, yy, xy, inflation times
    shoulders) in cells, NaN where the answer is wrong or has no covariance."""
    with open(path) as f:
        dem = next(iter(json.load(f)["dems"].values()))
    cell, cs = dem["meta"]["cell_m"], dem["cases"]
    rows = []
    for c in cs:
        t = c["trn"]
        r = t.get("refinement") or {}
        ok = (t.get("err_cells") is not None and t["err_cells"] <= bench_real.SUCCESS_CELLS
              and t.get("cov_m2") is not None and t.get("x") is not None)
        rows.append(((t["x"] - c["truth"][0]) / cell, (t["y"] - c["truth"][1]) / cell,
                     *(v / cell ** 2 for v in t["cov_m2"]),
                     r.get("inflation", 1.0) * r.get("shoulders", 1.0)) if ok else (math.nan,) * 6)
    return np.array(rows, dtype=np.float64)


def main(argv):
    try:
        a = parse_args(argv)
        runs = []
        for d in range(a.draws):
            out = os.path.join(a.out, f"draw{d}")
            args = ["--dem", a.dem, "--cases", str(a.cases), "--seed", str(a.seed), "--radius",
                    str(a.radius), "--truth-fine", str(a.truth_fine), "--fine-local", "binned",
                    "--points-draw", str(d), "--trn", a.trn, "--out", out, "--no-plot"]
            args += ["--counts"] if a.counts else []
            if a.trn_extra:
                args += ["--"] + a.trn_extra
            log = io.StringIO()
            keep = sys.stdout, sys.stderr
            sys.stdout = sys.stderr = log
            try:
                rc = bench_real.main(args)
            finally:
                sys.stdout, sys.stderr = keep
            if rc != 0:
                last = (log.getvalue().strip().splitlines() or [""])[-1]
                raise Fail(f"draw {d}: {last}")
            runs.append(read_draw(os.path.join(out, "bench.json")))
        x = np.stack(runs, axis=1)  # cases, draws, 6
        keep = np.isfinite(x).all(axis=(1, 2))
        x = x[keep]
        r = analyse(x[:, :, 0:2], x[:, :, 2:5], x[:, :, 5])
        r.update({"dem": a.dem, "radius": a.radius, "truth_fine": a.truth_fine, "seed": a.seed,
                  "counts": a.counts,
                  "cases_asked": a.cases, "cases_wrong_in_a_draw": int((~keep).sum())})
        os.makedirs(a.out, exist_ok=True)
        with open(os.path.join(a.out, "draw_study.json"), "w") as f:
            json.dump(r, f, indent=1)
        cov = {k: " / ".join(f"{v:.1f}" for v in r[k]) for k in r if k.startswith("coverage")}
        print(f"{a.dem} K = {a.truth_fine} R = {a.radius}: {r['cases']} cases x {r['draws']} draws "
              f"({r['cases_wrong_in_a_draw']} left out: wrong in a draw)")
        print(f"  true trace {r['true_trace']:.4g} cells^2 (points {r['points_trace']:.4g}, the case "
              f"{r['case_trace']:.4g}); reported {r['reported_trace']:.4g}; its CV over a case's draws "
              f"{r['cv_median']:.2f} (median)")
        print(f"  inside 1/2/3 sigma: own {cov['coverage_own']} %; the case's mean "
              f"{cov['coverage_case_mean']} % (without inflation and shoulders: "
              f"{cov['coverage_own_no_inflation']} and {cov['coverage_case_mean_no_inflation']} %)")
        print("  true over reported trace by fifth of the reported (tightest first): "
              + " ".join(f"{v:.2f}" for v in r["true_over_reported_by_fifth"]))
        return 0
    except (Fail, OSError, ValueError) as e:
        print(f"draw_study: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
