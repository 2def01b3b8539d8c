#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/real/rover_map_error.py - what a rover's binned local map differs from the map by.

    /usr/bin/python3 tools/real/rover_map_error.py [--dem ID ...] [--k K ...] [--radius R ...]
        [--cases N] [--seed S] [--json PATH]

No trn run. For bench_real's cases (--truth-fine K --fine-local binned: the map the K x K
block mean of the DEM, the rover's stereo points scattered over the DEM's surface and
binned into its cells), over the seen cells of N cases per DEM, K and R, in metres:

* interp: the map's bicubic (Keys, a = -1/2) and bilinear interpolants at each local
  cell's centre against the true area mean of the cell's footprint (the DEM's bilinear
  surface averaged over (4K)^2 sub-samples): the interpolant's representation error;
* binning: the cell's points' noise-free mean against that area mean (where the points
  fell in the cell);
* total: the points' noise-free mean against the bicubic interpolant (what trn's fit
  sees besides the noise);
* the noise: the model's sd at the cell's range (what trn is told), the sd of the mean of
  the cell's points' noises (what the cell has), the points per cell.

Prints one row per DEM, K and R (RMS in metres and over the model's sd) and writes the
rows as JSON. Exit 0, or 1 with one line on bad input.
"""
import argparse
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import cases as cm  # noqa: E402
import dems  # noqa: E402


def area_mean(fine, fr, fc, R, K, sub):
    """Each local cell's footprint mean of the fine surface: sub x sub bilinear samples."""
    offs = (np.arange(sub) + 0.5) / sub - 0.5
    acc = np.zeros((2 * R + 1, 2 * R + 1))
    for du in offs:
        for dv in offs:
            acc += cm.sample(fine.z, *cm.cell_positions(fr, fc, R, K, 0.0, du, dv))
    return acc / (sub * sub)


def case_errors(dem, fine, cs, K, p, gen):
    """Per seen cell of one case: (interp bicubic, interp bilinear, binning, total) errors,
    the model's sd, the mean's sd and the count."""
    R = p.radius
    fr, fc = fine.frac_index(*cs.truth)
    gr, gc = dem.frac_index(*cs.truth)
    rows, cols = cm.cell_positions(gr, gc, R, 1.0, 0.0)
    cub, lin = cm.sample(dem.z, rows, cols, "cubic"), cm.sample(dem.z, rows, cols)
    am = area_mean(fine, fr, fc, R, K, 4 * K)
    b = cm.binned_points(fine, fr, fc, R, K, 0.0, p, dem.c, gen, False)
    e, n = cm.rover_frame_offsets(R, dem.c)
    model = p.noise0_m + p.noise_k * (e ** 2 + n ** 2) / dem.c
    use = cs.seen & np.isfinite(cub + lin + am + b.h0)
    cols_ = (cub - am, lin - am, b.h0 - am, b.h0 - cub, model, b.sd, b.n)
    return np.stack([c[use].astype(np.float64) for c in cols_])


def rms(v):
    return float(np.sqrt(np.mean(v * v)))


def summarize(x):
    i_cub, i_lin, binn, tot, model, sd, n = x
    return {"cells": int(x.shape[1]),
            "rms_m": {"interp_cubic": rms(i_cub), "interp_bilinear": rms(i_lin), "binning": rms(binn),
                      "total": rms(tot), "model_sd": rms(model), "mean_sd": rms(sd)},
            "rms_over_model_sd": {"interp_cubic": rms(i_cub / model), "binning": rms(binn / model),
                                  "total": rms(tot / model), "mean_sd": rms(sd / model)},
            "points": {"mean": float(n.mean()), "median": float(np.median(n)), "min": int(n.min()),
                       "max": int(n.max()), "share_1": float(np.mean(n == 1))}}


def run(dem_id, K, R, ncases, seed):
    fine = cm.read_dem(dems.get(dem_id))
    dem = cm.block_average(fine, K)
    p = cm.CaseParams(radius=R, local="binned")
    cs = cm.generate(dem, ncases, seed, p, None, fine)
    gen = np.random.default_rng(seed)
    return summarize(np.concatenate([case_errors(dem, fine, c, K, p, gen) for c in cs], axis=1))


def main(argv):
    ap = argparse.ArgumentParser(prog="rover_map_error.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("--dem", action="append", help="DEM id (repeatable; default all of dems.DEFAULT)")
    ap.add_argument("--k", action="append", type=int, help="block size K (repeatable; default 2 and 4)")
    ap.add_argument("--radius", action="append", type=int, help="R (repeatable; default 12 and 20)")
    ap.add_argument("--cases", type=int, default=50)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--json", default=os.path.join(dems.BUILD, "rover_map_error.json"))
    a = ap.parse_args(argv)
    rows = []
    print(f"{'dem':15s} {'K':>2s} {'R':>3s} {'cells':>6s} | RMS m: {'cubic':>8s} {'bilin':>8s} {'binning':>8s} "
          f"{'total':>8s} {'model sd':>8s} {'mean sd':>8s} | over model sd: {'cubic':>6s} {'binning':>7s} "
          f"{'total':>6s} {'mean sd':>7s} | points mean min-max =1")
    for d in a.dem or dems.DEFAULT:
        for K in a.k or (2, 4):
            for R in a.radius or (12, 20):
                try:
                    s = run(d, K, R, a.cases, a.seed)
                except (cm.InputError, ValueError) as e:
                    print(f"{d:15s} {K:2d} {R:3d} skipped: {e}")
                    continue
                rows.append({"dem": d, "k": K, "radius": R, **s})
                m, z, pt = s["rms_m"], s["rms_over_model_sd"], s["points"]
                print(f"{d:15s} {K:2d} {R:3d} {s['cells']:6d} |        {m['interp_cubic']:8.3g} "
                      f"{m['interp_bilinear']:8.3g} {m['binning']:8.3g} {m['total']:8.3g} {m['model_sd']:8.3g} "
                      f"{m['mean_sd']:8.3g} |                {z['interp_cubic']:6.2f} {z['binning']:7.2f} "
                      f"{z['total']:6.2f} {z['mean_sd']:7.2f} | {pt['mean']:5.2f} {pt['min']}-{pt['max']} "
                      f"{100 * pt['share_1']:.1f} %", flush=True)
    os.makedirs(os.path.dirname(os.path.abspath(a.json)), exist_ok=True)
    with open(a.json, "w") as f:
        json.dump(rows, f, indent=1)
    print(f"rows: {a.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
