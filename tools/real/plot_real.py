#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/real/plot_real.py - figures of the real-terrain benchmark (bench_real.py).

    /usr/bin/python3 tools/real/plot_real.py build/real/bench.json [--out DIR]

* reliability.png: trn's predicted failure probability (bins) against the observed
  failure rate (radial error > 1.5 cells), one line per DEM, the diagonal = perfect;
  beside it the fraction of successes inside trn's 1/2/3-sigma ellipses vs target.
* match_<ID>.png: one case per DEM: a hillshade of the global DEM around the rover,
  the local map's seen cells drawn at trn's estimated pose (coloured by height),
  truth, estimate, the peers' estimates, the prior and its search window.

Matplotlib Agg; needs python3-matplotlib, python3-numpy, python3-gdal.
"""
import argparse
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.patches  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LightSource  # noqa: E402
from osgeo import gdal  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import cases as casemod  # noqa: E402

gdal.UseExceptions()


def fig_reliability(res):
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 4.8))
    bw = 0.8 / max(1, len(res["dems"]))  # one group of bars per sigma level, all DEMs inside it
    ax.plot([0, 1], [0, 1], color="0.6", lw=1, ls="--", label="perfect")
    for k, (dem_id, r) in enumerate(res["dems"].items()):
        bins = [b for b in r["metrics"]["trn"]["reliability"] if b["n"]]
        if not bins:
            continue
        x = [b["mean_predicted"] for b in bins]
        y = [b["observed"] for b in bins]
        n = np.array([b["n"] for b in bins], float)
        line, = ax.plot(x, y, "-", lw=1, label=f"{dem_id} (n = {int(n.sum())})")
        ax.scatter(x, y, s=12 + 150 * n / n.max(), color=line.get_color(), zorder=3)
        for xi, yi, ni in zip(x, y, n):
            ax.annotate(f"{int(ni)}", (xi, yi), textcoords="offset points", xytext=(4, -10), fontsize=7)
        cal = r["metrics"]["trn"]["calibration"]
        if cal["n"]:
            xs = np.arange(3) - 0.4 + bw * (k + 0.5)
            ax2.bar(xs, [v or 0 for v in cal["inside_pct"]], width=bw, color=line.get_color(),
                    label=f"{dem_id} (n = {cal['n']})")
    ax.set_xlim(-0.02, 1.02)
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel("predicted failure probability (bin mean)")
    ax.set_ylabel("observed failure rate (error > 1.5 cells)")
    ax.set_title("trn reliability (marker size: cases in bin)")
    ax.legend(fontsize=8, loc="upper left")
    for i, t in enumerate((39.3, 86.5, 98.9)):
        ax2.hlines(t, i - 0.42, i + 0.42, color="k", lw=2)
    ax2.set_xticks(range(3), ["1 sigma", "2 sigma", "3 sigma"])
    ax2.set_ylabel("successes inside the ellipse (%)")
    ax2.set_title("trn covariance calibration (black: target)")
    ax2.set_ylim(0, 105)
    ax2.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    return fig


def hillshade_crop(dem, cx, cy, half_m):
    fr, fc = dem.frac_index(cx, cy)
    h = int(np.ceil(half_m / dem.c))
    r0, r1 = max(0, int(fr) - h), min(dem.z.shape[0], int(fr) + h + 1)
    c0, c1 = max(0, int(fc) - h), min(dem.z.shape[1], int(fc) + h + 1)
    z = dem.z[r0:r1, c0:c1]
    zf = np.where(np.isfinite(z), z, np.nanmean(z))
    hs = LightSource(azdeg=315, altdeg=45).hillshade(zf, dx=dem.c, dy=dem.c)
    x_lo, y_hi = dem.x0 + c0 * dem.c, dem.y0 - r0 * dem.c
    ext = (x_lo, x_lo + (c1 - c0) * dem.c, y_hi - (r1 - r0) * dem.c, y_hi)
    return hs, ext


def fig_match(dem_id, r):
    meta = r["meta"]
    dem = casemod.read_dem(meta["path"])
    case = r["cases"][meta["figure_case"]]
    loc = casemod.read_dem(meta["figure_local"])
    R = meta["radius"]
    c = dem.c
    tx, ty = case["truth"]
    est = case["trn"]
    ex, ey = (est["x"], est["y"]) if est.get("x") is not None else (tx, ty)
    half = (R + meta["window_m"] / c + meta["prior_cells"] + 4) * c
    hs, ext = hillshade_crop(dem, tx, ty, half)
    fig, ax = plt.subplots(figsize=(7.5, 7))
    ax.imshow(hs, extent=ext, cmap="gray", origin="upper", interpolation="nearest")
    z = loc.z - np.nanmean(loc.z)
    lim = np.nanmax(np.abs(z)) if np.isfinite(z).any() else 1.0
    im = ax.imshow(z, extent=(ex - (R + 0.5) * c, ex + (R + 0.5) * c, ey - (R + 0.5) * c, ey + (R + 0.5) * c),
                   cmap="RdBu_r", vmin=-lim, vmax=lim, alpha=0.75, origin="upper", interpolation="nearest")
    fig.colorbar(im, ax=ax, shrink=0.7, label="local height, mean removed (m)")
    px, py = case["prior"]
    w = case["window_m"]
    ax.add_patch(matplotlib.patches.Rectangle((px - w, py - w), 2 * w, 2 * w, fill=False, ls="--",
                                              ec="orange", lw=1.2, label="prior and search window"))
    ax.plot(px, py, "s", mfc="none", mec="orange", ms=8)
    ax.plot(tx, ty, "o", mfc="none", mec="lime", mew=2, ms=12, label="truth")
    ax.plot(ex, ey, "+", color="red", mew=2, ms=14,
            label=f"trn estimate ({case['trn']['err_cells']:.2f} cells)")
    for name, mk in (("ssd", "x"), ("ncc", "1")):
        p = case.get(name, {})
        if p.get("x") is not None:
            ax.plot(p["x"], p["y"], mk, color="yellow", mew=1.5, ms=9,
                    label=f"{name} estimate ({p['err_cells']:.2f} cells)")
    ax.set_xlim(ext[0], ext[1])
    ax.set_ylim(ext[2], ext[3])
    ax.set_xlabel("x east (m)")
    ax.set_ylabel("y north (m)")
    ax.ticklabel_format(useOffset=False, style="plain")
    ax.set_title(f"{dem_id}: case {case['index']}, local map ({2 * R + 1}^2 cells of {c:g} m, "
                 f"120 deg view) at trn's pose", fontsize=10)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    return fig


def all_figures(res, out):
    os.makedirs(out, exist_ok=True)
    paths = []
    fig = fig_reliability(res)
    p = os.path.join(out, "reliability.png")
    fig.savefig(p, dpi=120)
    plt.close(fig)
    paths.append(p)
    for dem_id, r in res["dems"].items():
        if not os.path.exists(r["meta"].get("figure_local", "")):
            continue
        fig = fig_match(dem_id, r)
        p = os.path.join(out, f"match_{dem_id}.png")
        fig.savefig(p, dpi=120)
        plt.close(fig)
        paths.append(p)
    return paths


def main(argv):
    ap = argparse.ArgumentParser(description="figures of tools/real/bench_real.py")
    ap.add_argument("bench_json")
    ap.add_argument("--out", help="folder (default: the JSON's)")
    a = ap.parse_args(argv)
    try:
        with open(a.bench_json) as f:
            res = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        print(f"plot_real: {a.bench_json}: {e}", file=sys.stderr)
        return 1
    for p in all_figures(res, a.out or os.path.dirname(os.path.abspath(a.bench_json))):
        print(p)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
