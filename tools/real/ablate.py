#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/real/ablate.py - the height matcher's parts, each removed alone, on bench_real.

    /usr/bin/python3 tools/real/ablate.py [--dem ID ...] [--cases N] [--seed S]
        [--variant NAME ...] [--out DIR] [--jobs J]

Each variant is the tree at HEAD (git archive, under OUT/src) with one part of the height matcher
removed by a textual patch listed in VARIANTS below (each patch must match the source exactly
once, so a patch that no longer fits fails loudly instead of measuring nothing); `--noise-auto 0`
is a run-time option. Each variant's `trn` is built (Release) with its patch in, copied to
OUT/trn-NAME, the patch taken back, and run through tools/real/bench_real.py on the same seeded
cases. The shipped source is not changed.

Prints, per variant over the DEMs: the right rate (within 1.5 cells), the confidently wrong count
(off by more than 1.5 cells, status ok, failure probability below 0.5), the fixes (status ok), the
Brier score of the failure probability, and the range over the DEMs of the 1/2/3-sigma coverage
of the right answers (target 39.3 / 86.5 / 98.9 %); then per variant and DEM with the median
error and time. Writes OUT/ablation.json and OUT/ablation.md. --bench-arg passes a construction
to bench_real (e.g. --bench-arg=--outliers=0.2); --reuse takes results already in OUT.

With --bench-arg=--prior-miss=F (a share F of the cases with a prior that misses: the truth
1.5 cells or more outside the search window, so never right) the first table is over the cases
whose prior hits, and a third table gives per variant, over the cases whose prior misses: the
fixes (status ok), the confidently wrong (status ok, failure probability below 0.5, off by more
than 1.5 cells), the answers flagged ambiguous and ill_conditioned, the count with a failure
probability below 0.5, and the Brier score of the failure probability against 1, over all of
them and over those not flagged ill_conditioned; a fourth the same per variant and DEM. With
--prior-miss=1 only these two.
"""
import argparse
import json
import os
import subprocess
import sys
import tarfile
import io
import shutil

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

# name: (what it removes, [(file, old, new)], extra trn arguments)
VARIANTS = {
    "all": ("nothing: the height matcher as shipped", [], []),
    "no_second_starts": (
        "the refinement from the best pose's neighbours within 30 nats",
        [("src/localize_heights.c", "    for (k = 0; k < 9; ++k) {\n        const int32_t sx = b->x + k % 3 - 1",
          "    for (k = 0; k < 0; ++k) {\n        const int32_t sx = b->x + k % 3 - 1")], []),
    "no_far_basins": (
        "the far basins (refinement from the 4 highest other local maxima, their moves and share)",
        [("src/localize_heights.c", "    trn_loc_find_basins3_(s->grid, win, s->kk, radius, b->x, b->y, far);",
          "    far->n = 0;\n    far->moved = 0;")], []),
    "no_basin_share": (
        "the refined far basins' share of the failure probability",
        [("src/localize_heights.c", "    double pf = fmax(trn_loc_basins_failure_(&s->far, infl, loc),",
          "    double pf = fmax(0.0 * trn_loc_basins_failure_(&s->far, infl, loc),")], []),
    "no_valley": (
        "the valley's share of the failure probability (ln L along the major axis)",
        [("src/localize_heights.c", "    return fmax(pf, trn_refine_valley_fail_(&map->heights",
          "    return fmax(pf, 0.0 * trn_refine_valley_fail_(&map->heights")], []),
    "no_tail": (
        "the ellipse's tail beyond 1.5 cells as a floor of the failure probability",
        [("src/localize_heights.c", "                     trn_loc_tail_failure_(s->ref.pos.cov_cells));",
          "                     0.0 * trn_loc_tail_failure_(s->ref.pos.cov_cells));")], []),
    "no_shoulders": (
        "the ellipse widened where ln L's fall at 2 sds is flatter than at half an sd",
        [("src/localize_heights.c", "        trn_refine_shoulders_(&map->heights, local, rover_x, rover_y, &s->rc,",
          "        if (0) trn_refine_shoulders_(&map->heights, local, rover_x, rover_y, &s->rc,")], []),
    "no_relief_test": (
        "the relief test (an answer whose local heights take a weaker copy of the map's relief misfits)",
        [("src/localize_heights.c", "        if (out->loc.relief_z < -TRN_RELIEF_Z) {",
          "        if (0 && out->loc.relief_z < -TRN_RELIEF_Z) {")], []),
    "no_spline_step": (
        "the spline step (the answer is the refinement's own estimate)",
        [("src/localize_common.c", "    out->x = out->refinement.x + out->refinement.spline_step[0];\n"
          "    out->y = out->refinement.y + out->refinement.spline_step[1];",
          "    out->x = out->refinement.x;\n    out->y = out->refinement.y;"),
         ("src/localize_heights.c", "    out->heading_rad = s->ref.heading_rad + s->ref.spline_step_heading_rad;",
          "    out->heading_rad = s->ref.heading_rad;")], []),
    "no_clip_again": (
        "the search's repeated clip (one clipped pass only)",
        [("src/refine.c", "        for (again = 0; again <= TRN_CLIP_AGAIN; ++again) {\n            n = pose_fit(",
          "        for (again = 0; again <= 0; ++again) {\n            n = pose_fit(")], []),
    "no_noise_rescale": (
        "the noise model rescaled from the residuals (--noise-auto 0)", [], ["--noise-auto", "0"]),
}


def run(cmd, **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        raise SystemExit(f"ablate: {' '.join(cmd[:4])} ... failed: {(r.stderr or r.stdout).strip()[-400:]}")
    return r.stdout


def tree(out):
    """The source at HEAD under OUT/src (made once), configured for Release under OUT/src/build-abl."""
    src = os.path.join(out, "src")
    if not os.path.isdir(src):
        data = subprocess.run(["git", "-C", ROOT, "archive", "HEAD"], capture_output=True, check=True).stdout
        with tarfile.open(fileobj=io.BytesIO(data)) as t:
            t.extractall(src)
        run(["cmake", "-S", src, "-B", os.path.join(src, "build-abl"), "-G", "Ninja",
             "-DCMAKE_BUILD_TYPE=Release"])
    return src


def variant_trn(src, name, patches, out, jobs):
    """trn of one variant: its patches applied, trn rebuilt (one file changes), copied to
    OUT/trn-NAME, the patches taken back."""
    kept = {}
    try:
        for f, old, new in patches:
            p = os.path.join(src, f)
            s = open(p).read()
            if s.count(old) != 1:
                raise SystemExit(f"ablate: variant {name}: the patch of {f} matches {s.count(old)} times, not once")
            kept[p] = s
            with open(p, "w") as fh:
                fh.write(s.replace(old, new))
        run(["cmake", "--build", os.path.join(src, "build-abl"), "--target", "trn", "-j", str(jobs)])
        dst = os.path.join(out, f"trn-{name}")
        shutil.copy2(os.path.join(src, "build-abl", "trn"), dst)
        return dst
    finally:
        for p, s in kept.items():
            with open(p, "w") as fh:
                fh.write(s)


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--dem", action="append", help="DEM id (repeat; default: six of bench_real's)")
    ap.add_argument("--cases", type=int, default=200)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--variant", action="append", choices=sorted(VARIANTS))
    ap.add_argument("--out", default=os.path.join(ROOT, "build", "ablate"))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--bench-arg", action="append", default=[],
                    help="a bench_real option for every variant, as --bench-arg=--outliers=0.2 (repeat)")
    ap.add_argument("--reuse", action="store_true",
                    help="take a variant's OUT/bench-NAME/bench.json when it exists (no rebuild, no rerun)")
    a = ap.parse_args(argv)
    if a.cases < 1:
        print("ablate: --cases must be positive", file=sys.stderr)
        return 1
    dem_ids = a.dem or ["rockfield", "rhine", "kossou", "merewether", "tian_shan", "carrizo"]
    names = a.variant or list(VARIANTS)
    os.makedirs(a.out, exist_ok=True)
    res = {}
    for name in names:
        what, patches, extra = VARIANTS[name]
        bo = os.path.join(a.out, f"bench-{name}")
        if not (a.reuse and os.path.exists(os.path.join(bo, "bench.json"))):
            trn = variant_trn(tree(a.out), name, patches, a.out, a.jobs)
            cmd = ["/usr/bin/python3", os.path.join(HERE, "bench_real.py"), "--cases", str(a.cases),
                   "--seed", str(a.seed), "--trn", trn, "--out", bo, "--no-plot"] + a.bench_arg
            for d in dem_ids:
                cmd += ["--dem", d]
            for x in extra:
                cmd.append(f"--trn-arg={x}")
            run(cmd)
        dems = json.load(open(os.path.join(bo, "bench.json")))["dems"]
        res[name] = {"what": what, "dems": {}}
        for d in dem_ids:
            m = dems[d]["metrics"]["trn"]
            if m.get("prior_miss") is not None:
                res[name].setdefault("miss", {})[d] = m["prior_miss"]
                m = m["prior_hit"]
                if m is None:  # --prior-miss=1: no case whose prior hits
                    continue
            res[name]["dems"][d] = {
                "right_pct": 100.0 * m["rate"], "median_err_cells": m["median_err_cells"],
                "cover_pct": m["calibration"]["inside_pct"], "conf_wrong": m["confidently_wrong"],
                "fixes": m["status"].get("ok", 0), "median_ms": m["median_time_ms"], "n": m["n"],
                "right": m["success"], "brier": m["brier"]}
        print(f"ablate: {name} done", file=sys.stderr, flush=True)
    lines = ["| removed | right % | conf. wrong | fixes | Brier | 1-sigma % | 2-sigma % | 3-sigma % |",
             "|---|---|---|---|---|---|---|---|"]
    for name in names:
        v = list(res[name]["dems"].values())
        n = sum(x["n"] for x in v)
        if n == 0:
            continue
        c = [[x["cover_pct"][k] for x in v] for k in range(3)]
        lines.append(f"| {name}: {res[name]['what']} | {100.0 * sum(x['right'] for x in v) / n:.2f} | "
                     f"{sum(x['conf_wrong'] for x in v)} | {sum(x['fixes'] for x in v)} | "
                     f"{sum(x['brier'] * x['n'] for x in v) / n:.4f} | "
                     + " | ".join(f"{min(ck):.1f}-{max(ck):.1f}" for ck in c) + " |")
    lines += ["", "| variant | DEM | right % | median err (cells) | 1/2/3-sigma % | conf. wrong | fixes | ms |",
              "|---|---|---|---|---|---|---|---|"]
    for name in names:
        for d, v in res[name]["dems"].items():
            c = v["cover_pct"]
            lines.append(f"| {name} | {d} | {v['right_pct']:.1f} | {v['median_err_cells']:.3f} | "
                         f"{c[0]:.1f} / {c[1]:.1f} / {c[2]:.1f} | {v['conf_wrong']} | {v['fixes']} | "
                         f"{v['median_ms']:.1f} |")
    if not any(res[name]["dems"] for name in names):
        lines = []  # --prior-miss=1: no case whose prior hits, only the missing priors' tables
    if any("miss" in res[name] for name in names):
        lines += ["", "Cases whose prior misses (the truth outside the window; never right):", "",
                  "| removed | cases | fixes | conf. wrong | ambiguous | ill-conditioned | p < 0.5 | Brier | "
                  "Brier, not ill-cond. (n) |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for name in names:
            v = list(res[name].get("miss", {}).values())
            n = sum(x["n"] for x in v)
            nb, nu = sum(x["n_failure_probability"] for x in v), sum(x["n_unflagged"] for x in v)
            br = sum(x["brier"] * x["n_failure_probability"] for x in v if x["brier"] is not None)
            bu = sum(x["brier_unflagged"] * x["n_unflagged"] for x in v if x["brier_unflagged"] is not None)
            lines.append(f"| {name} | {n} | {sum(x['fixes'] for x in v)} | "
                         f"{sum(x['confidently_wrong'] for x in v)} | "
                         f"{sum(x['status'].get('ambiguous', 0) for x in v)} | "
                         f"{sum(x['status'].get('ill_conditioned', 0) for x in v)} | "
                         f"{sum(x['below_half'] for x in v)} | {br / nb if nb else float('nan'):.4f} | "
                         f"{bu / nu if nu else float('nan'):.4f} ({nu}) |")
        lines += ["", "| variant | DEM | cases | fixes | conf. wrong | p < 0.5 | Brier |", "|---|---|---|---|---|---|---|"]
        for name in names:
            for d, x in res[name].get("miss", {}).items():
                lines.append(f"| {name} | {d} | {x['n']} | {x['fixes']} | {x['confidently_wrong']} | "
                             f"{x['below_half']} | {x['brier'] if x['brier'] is not None else float('nan'):.4f} |")
    md = "\n".join(lines).lstrip("\n") + "\n"
    with open(os.path.join(a.out, "ablation.md"), "w") as f:
        f.write(md)
    with open(os.path.join(a.out, "ablation.json"), "w") as f:
        json.dump(res, f, indent=1)
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
