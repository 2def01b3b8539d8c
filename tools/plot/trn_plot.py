#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/plot/trn_plot.py - figures from the `trn` command line's outputs.

    trn_plot.py dem     DEM.tif --out dem.png [--rover X,Y] [--target X,Y] [--prior X,Y]
                        [--estimate X,Y | --localize-json FILE] [--title T]
    trn_plot.py surface DEM.tif --out surface.png [--zscale Z] [--elev E] [--azim A]
    trn_plot.py raster  MAP.tif --out map.png [--label TEXT] [--cmap NAME] [markers as dem]
    trn_plot.py experiment RUN.json [RUN.json ...] --out exp.png [--labels A,B,...]
    trn_plot.py profile PROFILE.json --out profile.png   (from `trn profile --json [--budget F]`)

Every input is anything GDAL reads (band 1, no-data and NaN shown as missing);
axes are map metres from the raster's geotransform (x east, y north). Needs
Debian's python3-matplotlib, python3-numpy and python3-gdal
(`bash tools/setup.sh plot`); run with /usr/bin/python3.

Selection figures (`trn select --json`, `--out-map`; `trn field`):

    trn_plot.py select      DEM.tif --select-json SEL.json --out select.png
    trn_plot.py uncertainty DEM.tif CANDIDATES.tif [--select-json SEL.json] [--clip PCT] --out fig2b.png
    trn_plot.py field       DEM.tif FIELD.tif [--evaluated EV.tif] [--field-json F.json] --out fig3.png
    trn_plot.py surface     DEM.tif --select-json SEL.json --out fig2c.png

Adding a figure: write `def fig_NAME(args)` that returns a matplotlib Figure,
and `def add_NAME(sub)` that adds its subparser; list it in FIGURES. The
shared pieces are read_raster (heights + extent), add_markers (rover, target,
prior, estimate), and save.
"""
import argparse
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.patches  # noqa: E402
import matplotlib.ticker  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LightSource  # noqa: E402
from osgeo import gdal  # noqa: E402

gdal.UseExceptions()


# ---------------------------------------------------------------------------
# shared pieces
# ---------------------------------------------------------------------------
class Raster:
    """Band 1 of a raster, north-up (row 0 = north edge), NaN = missing."""

    def __init__(self, z, gt, path):
        self.z = z
        self.gt = gt
        self.path = path
        self.cell = gt[1]

    @property
    def extent(self):
        """(left, right, bottom, top) in map metres, for imshow."""
        h, w = self.z.shape
        return (self.gt[0], self.gt[0] + w * self.gt[1], self.gt[3] + h * self.gt[5], self.gt[3])

    def centres(self):
        """Map coordinates of the cell centres, as 1-D x (east) and y (north) arrays."""
        h, w = self.z.shape
        x = self.gt[0] + (np.arange(w) + 0.5) * self.gt[1]
        y = self.gt[3] + (np.arange(h) + 0.5) * self.gt[5]
        return x, y


def read_raster(path, band=1):
    try:
        ds = gdal.Open(path)
    except RuntimeError as e:
        sys.exit(f"trn_plot: cannot read '{path}': {e}")
    if band > ds.RasterCount:
        sys.exit(f"trn_plot: '{path}' has {ds.RasterCount} band(s), no band {band}")
    b = ds.GetRasterBand(band)
    z = b.ReadAsArray().astype(np.float64)
    nd = b.GetNoDataValue()
    if nd is not None and np.isfinite(nd):
        z[z == np.float32(nd)] = np.nan
    z[~np.isfinite(z)] = np.nan
    gt = list(ds.GetGeoTransform())
    if gt[2] != 0 or gt[4] != 0:
        sys.exit(f"trn_plot: '{path}' has a rotated geotransform")
    if gt[5] > 0:  # south-up: flip to north-up
        z = z[::-1, :]
        gt[3] += z.shape[0] * gt[5]
        gt[5] = -gt[5]
    if gt[1] < 0:
        z = z[:, ::-1]
        gt[0] += z.shape[1] * gt[1]
        gt[1] = -gt[1]
    return Raster(z, tuple(gt), path)


def xy(text):
    """argparse type for X,Y."""
    try:
        x, y = text.split(",")
        v = (float(x), float(y))
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a pair X,Y")
    if not all(np.isfinite(v)):
        raise argparse.ArgumentTypeError(f"'{text}' is not finite")
    return v


MARKERS = {
    # name: (matplotlib marker, colour, size, label)
    "prior": ("+", "#ffd000", 140, "prior"),
    "rover": ("o", "#ff2d2d", 70, "rover"),
    "target": ("*", "#00e5ff", 220, "selected target"),
    "estimate": ("x", "#ffffff", 90, "estimate"),
}


def add_marker_options(p):
    p.add_argument("--rover", type=xy, metavar="X,Y", help="rover position, map metres")
    p.add_argument("--target", type=xy, metavar="X,Y", help="selected target, map metres")
    p.add_argument("--prior", type=xy, metavar="X,Y", help="prior position, map metres")
    p.add_argument("--estimate", type=xy, metavar="X,Y", help="localization estimate, map metres")
    p.add_argument("--localize-json", metavar="FILE",
                   help="output of `trn localize --json`: marks its estimate (x_m, y_m) and prior")


def add_markers(ax, args):
    pts = {k: getattr(args, k, None) for k in MARKERS}
    if getattr(args, "localize_json", None):
        with open(args.localize_json) as f:
            r = json.load(f)
        pts["estimate"] = pts["estimate"] or (r["x_m"], r["y_m"])
        if "prior" in r:
            pts["prior"] = pts["prior"] or (r["prior"]["x_m"], r["prior"]["y_m"])
    shown = False
    for k, (m, c, s, label) in MARKERS.items():
        if pts[k] is not None:
            ax.scatter([pts[k][0]], [pts[k][1]], marker=m, c=c, s=s, label=label, zorder=5,
                       edgecolors="black" if m not in "+x" else None, linewidths=1.0 if m not in "+x" else 2.0)
            shown = True
    if shown:
        ax.legend(loc="upper right", fontsize=8, framealpha=0.8)


def map_axes(ax, r):
    ax.set_xlabel("x east (m)")
    ax.set_ylabel("y north (m)")
    ax.set_aspect("equal")
    ax.ticklabel_format(useOffset=False, style="plain")


def save(fig, path, dpi):
    fig.savefig(path, dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    print(f"wrote {path}")


# ---------------------------------------------------------------------------
# figures
# ---------------------------------------------------------------------------
def fig_dem(args):
    """Shaded relief coloured by height (the paper's Fig. 2a), with markers."""
    r = read_raster(args.dem)
    z = r.z
    valid = np.isfinite(z)
    if not valid.any():
        sys.exit(f"trn_plot: '{args.dem}' has no valid height")
    lo, hi = np.nanpercentile(z, [1, 99.5])
    filled = np.where(valid, z, np.nanmin(z))
    ls = LightSource(azdeg=315, altdeg=40)
    rgb = ls.shade(filled, cmap=plt.get_cmap("gist_earth"), vmin=lo, vmax=hi, vert_exag=args.vert_exag,
                   dx=r.cell, dy=r.cell, blend_mode="overlay")
    rgb[~valid] = (0.6, 0.6, 0.6, 1.0)  # not seen: grey
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    ax.imshow(rgb, extent=r.extent, origin="upper", interpolation="nearest")
    sm = plt.cm.ScalarMappable(cmap="gist_earth", norm=plt.Normalize(lo, hi))
    fig.colorbar(sm, ax=ax, shrink=0.8, label="height (m)")
    map_axes(ax, r)
    add_markers(ax, args)
    h, w = z.shape
    ax.set_title(args.title or f"{args.dem.split('/')[-1]}: {w} x {h} cells of {r.cell:g} m")
    return fig


def add_dem(sub):
    p = sub.add_parser("dem", help="shaded DEM with rover / target / estimate markers")
    p.add_argument("dem", help="DEM (any GDAL raster)")
    p.add_argument("--vert-exag", type=float, default=2.0, help="hillshade vertical exaggeration (default 2)")
    add_marker_options(p)
    return p


def fig_surface(args):
    """3-D view of the terrain (the paper's Fig. 2c)."""
    r = read_raster(args.dem)
    z = r.z
    x, y = r.centres()
    step = max(1, int(np.ceil(max(z.shape) / args.max_cells)))
    zs = z[::step, ::step]
    X, Y = np.meshgrid(x[::step], y[::step])
    fig = plt.figure(figsize=(9, 7))
    ax = fig.add_subplot(projection="3d")
    lo, hi = np.nanpercentile(z, [1, 99.5])
    ax.plot_surface(X, Y, zs, cmap="gist_earth", vmin=lo, vmax=hi, rstride=1, cstride=1,
                    linewidth=0, antialiased=False, shade=True)
    ax.set_xlabel("x east (m)")
    ax.set_ylabel("y north (m)")
    ax.set_zlabel("height (m)", labelpad=12)
    ax.tick_params(axis="z", pad=6)
    ax.zaxis.set_major_locator(matplotlib.ticker.MaxNLocator(3))
    xr, yr = x[-1] - x[0], y[0] - y[-1]
    zr = max(np.nanmax(zs) - np.nanmin(zs), 1e-6)
    ax.set_box_aspect((xr, yr, zr * args.zscale))
    ax.view_init(elev=args.elev, azim=args.azim)
    ax.ticklabel_format(useOffset=False, style="plain")
    if getattr(args, "select_json", None):  # rover and selected target, on stalks above the ground
        sel = read_json(args.select_json)
        top = np.nanmax(zs) + 0.6 * zr
        ax.computed_zorder = False  # draw the markers over the surface
        for key, m, c, sz, label in (("rover", "o", "#ff2d2d", 60, "rover"),
                                     ("target", "*", "#00e5ff", 220, "selected target")):
            px, py = sel[key]["x_m"], sel[key]["y_m"]
            col = int(np.clip(np.searchsorted(x, px), 0, x.size - 1))
            row = int(np.clip(np.searchsorted(-y, -py), 0, y.size - 1))
            ground = z[row, col] if np.isfinite(z[row, col]) else np.nanmin(zs)
            ax.plot([px, px], [py, py], [ground, top], color=c, lw=1.5, zorder=10)
            ax.scatter([px], [py], [top], marker=m, c=c, s=sz, edgecolors="black", label=label, zorder=11,
                       depthshade=False)
        ax.legend(loc="upper left", fontsize=8)
    ax.set_title(args.title or f"{args.dem.split('/')[-1]} (heights x{args.zscale:g})")
    return fig


def add_surface(sub):
    p = sub.add_parser("surface", help="3-D view of a DEM (Fig. 2c)")
    p.add_argument("dem", help="DEM (any GDAL raster)")
    p.add_argument("--zscale", type=float, default=2.0, help="vertical exaggeration (default 2)")
    p.add_argument("--elev", type=float, default=35.0, help="view elevation, degrees (default 35)")
    p.add_argument("--azim", type=float, default=-60.0, help="view azimuth, degrees (default -60)")
    p.add_argument("--max-cells", type=int, default=256, help="largest side drawn; coarser grids are subsampled")
    p.add_argument("--select-json", metavar="FILE", help="output of `trn select --json`: marks rover and target")
    return p


def fig_raster(args):
    """Any one-band map (uncertainty per candidate, uncertainty field ...) with a colour bar."""
    r = read_raster(args.raster)
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    z = np.ma.masked_invalid(r.z)
    cmap = plt.get_cmap(args.cmap).copy()
    cmap.set_bad("#999999")
    im = ax.imshow(z, extent=r.extent, origin="upper", cmap=cmap, interpolation="nearest",
                   norm=matplotlib.colors.LogNorm() if args.log else None)
    fig.colorbar(im, ax=ax, shrink=0.8, label=args.label)
    map_axes(ax, r)
    add_markers(ax, args)
    ax.set_title(args.title or args.raster.split("/")[-1])
    return fig


def add_raster(sub):
    p = sub.add_parser("raster", help="any one-band map with a colour bar (grey = no data)")
    p.add_argument("raster", help="map (any GDAL raster)")
    p.add_argument("--label", default="value", help="colour bar label")
    p.add_argument("--cmap", default="viridis", help="matplotlib colour map (default viridis)")
    p.add_argument("--log", action="store_true", help="logarithmic colour scale")
    add_marker_options(p)
    return p


def fig_experiment(args):
    """`trn experiment --json` runs: success rates with and without selection (95 % Wilson
    intervals) and the mean error of the successes (95 % t intervals), one group per run."""
    runs = []
    for path in args.runs:
        try:
            with open(path) as f:
                r = json.load(f)
            for arm in ("with_selection", "without_selection"):
                for key in ("success_rate", "ci95", "mean_error_m", "successes", "localizations"):
                    r[arm][key]
        except (OSError, ValueError, KeyError, TypeError) as e:
            sys.exit(f"trn_plot: '{path}' is not `trn experiment --json` output: {e}")
        runs.append(r)
    if args.labels:
        labels = args.labels.split(",")
        if len(labels) != len(runs):
            sys.exit(f"trn_plot: --labels has {len(labels)} names for {len(runs)} runs")
    else:
        def label(r):
            t = r["terrain"]
            name = (os.path.splitext(os.path.basename(t["dem"]))[0] if "dem" in t
                    else f"k = {t['coverage_k']:g}")
            return name + (", heights" if r.get("localizer") == "heights" else "")
        labels = [label(r) for r in runs]
    arms = (("with_selection", "with selection", "#1f77b4"), ("without_selection", "without selection", "#d62728"))
    x = np.arange(len(runs))
    wbar = 0.38
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.6))

    def nan(v):
        return np.nan if v is None else v

    for i, (key, name, colour) in enumerate(arms):
        off = (i - 0.5) * wbar
        rate = np.array([100 * r[key]["success_rate"] for r in runs])
        lo = np.array([100 * nan(r[key]["ci95"][0]) for r in runs])
        hi = np.array([100 * nan(r[key]["ci95"][1]) for r in runs])
        a1.bar(x + off, rate, wbar, color=colour, label=name,
               yerr=np.vstack([rate - lo, hi - rate]), capsize=4, ecolor="black")
        for xi, v in zip(x + off, rate):
            a1.text(xi, 2, f"{v:.1f}", ha="center", va="bottom", color="white", fontsize=8, fontweight="bold")
        err = np.array([100 * nan(r[key]["mean_error_m"]) for r in runs])  # cm
        elo = np.array([100 * nan((r[key].get("mean_error_ci95") or [None, None])[0]) for r in runs])
        ehi = np.array([100 * nan((r[key].get("mean_error_ci95") or [None, None])[1]) for r in runs])
        yerr = np.vstack([np.nan_to_num(err - elo), np.nan_to_num(ehi - err)])
        a2.bar(x + off, err, wbar, color=colour, label=name, yerr=yerr, capsize=4, ecolor="black")
    a1.axhline(97.8, color="#1f77b4", ls="--", lw=1, label="paper, with: 97.8 %")
    a1.axhline(29.5, color="#d62728", ls="--", lw=1, label="paper, without: 29.5 %")
    a1.set_ylim(0, 105)
    a1.set_ylabel("localizations within the success radius (%)")
    a1.set_title("success rate, 95 % Wilson intervals")
    a2.set_ylabel("mean error of the successes (cm)")
    a2.set_title("accuracy of the successes, 95 % t intervals")
    for a in (a1, a2):
        a.set_xticks(x)
        a.set_xticklabels([f"{lab}\n{r['trials']} trials" for lab, r in zip(labels, runs)])
        a.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False)
    fig.suptitle(args.title or "Landmark selection, the paper's section 5 experiment (trn experiment)")
    fig.tight_layout()
    return fig


def add_experiment(sub):
    p = sub.add_parser("experiment", help="success rates and errors of `trn experiment --json` runs")
    p.add_argument("runs", nargs="+", metavar="RUN.json", help="outputs of `trn experiment --json`")
    p.add_argument("--labels", help="comma-separated names of the runs (default: k = coverage)")
    return p


def fig_profile(args):
    """`trn profile --json` output: time per stage against its budget (a horizontal bar chart).

    With a budget (the JSON holds budget_ms): bars are the target time estimate (median, and the
    worst of the runs as a thin bar on top) as a share of the stage's budget; over-budget stages
    are red, the 100 % line is the budget. Without one: host milliseconds, median and max."""
    try:
        with open(args.profile_json) as f:
            prof = json.load(f)
        stages = prof["stages"]
    except (OSError, ValueError, KeyError) as e:
        sys.exit(f"trn_plot: '{args.profile_json}' is not `trn profile --json` output: {e}")
    names = list(stages)
    budgeted = [n for n in names if "budget_ms" in stages[n]]
    fig, ax = plt.subplots(figsize=(8, 0.45 * len(names) + 1.6))
    y = np.arange(len(names))[::-1]
    if budgeted:
        clip = 300.0  # bars beyond 3x the budget are cut there; the label gives the numbers
        med = [min(clip, 100.0 * stages[n]["target_ms"] / stages[n]["budget_ms"]) if n in budgeted else 0
               for n in names]
        worst = [min(clip, 100.0 * stages[n]["share"]) if n in budgeted else 0 for n in names]
        colours = ["#d62728" if n in budgeted and stages[n]["over"] else "#1f77b4" for n in names]
        ax.barh(y, worst, height=0.25, color="#888888", label="worst of the runs")
        ax.barh(y, med, height=0.6, color=colours, alpha=0.85, label="median")
        ax.axvline(100.0, color="k", lw=1.2, ls="--", label="budget")
        for yi, n in zip(y, names):
            if n in budgeted:
                e = stages[n]
                ax.text(max(worst[names.index(n)], med[names.index(n)]) + 2, yi,
                        f"{e['target_max_ms']:.3g} / {e['budget_ms']:.4g} ms" + ("  OVER" if e["over"] else "")
                        + (f"   stack {e['stack_bytes']} B" if "stack_bytes" in e else ""),
                        va="center", fontsize=8)
            else:
                ax.text(2, yi, "no budget", va="center", fontsize=8, color="#666666")
        ax.set_xlabel(f"target time as % of budget (host ms x scale {prof['budget']['scale']:g})")
        ax.set_xlim(0, max(120.0, 1.25 * max(worst + med)))
        if max(worst) >= clip:
            ax.axvline(clip, color="#d62728", lw=0.8, ls=":")
    else:
        med = [stages[n]["wall_ms"] for n in names]
        worst = [stages[n]["wall_max_ms"] for n in names]
        ax.barh(y, worst, height=0.25, color="#888888", label="max")
        ax.barh(y, med, height=0.6, color="#1f77b4", alpha=0.85, label="median")
        ax.set_xlabel("host wall time (ms)")
    ax.set_yticks(y)
    ax.set_yticklabels(names)
    ax.legend(loc="lower right", fontsize=8)
    c = prof.get("config", {})
    ax.set_title(args.title or f"trn profile: map {c.get('map_cells')} cells, local {c.get('local_cells')}, "
                 f"window +-{c.get('window_cells')}, {c.get('candidates')} candidates, {c.get('runs')} runs",
                 fontsize=10)
    return fig


def add_profile(sub):
    p = sub.add_parser("profile", help="stage time against budget from `trn profile --json`")
    p.add_argument("profile_json", metavar="PROFILE.json", help="output of trn profile --json [--budget FILE]")
    return p


FIGURES = {"dem": (add_dem, fig_dem), "surface": (add_surface, fig_surface), "raster": (add_raster, fig_raster),
           "experiment": (add_experiment, fig_experiment),
           "profile": (add_profile, fig_profile)}


def main(argv=None):
    ap = argparse.ArgumentParser(prog="trn_plot.py", description="Figures from the trn command line's outputs.")
    sub = ap.add_subparsers(dest="figure", required=True, metavar="FIGURE")
    for name, (add, _) in FIGURES.items():
        p = add(sub)
        p.add_argument("--out", required=True, metavar="PNG", help="image to write")
        p.add_argument("--title", help="figure title")
        p.add_argument("--dpi", type=int, default=120, help="resolution (default 120)")
    args = ap.parse_args(argv)
    fig = FIGURES[args.figure][1](args)
    save(fig, args.out, args.dpi)
    return 0


# ---------------------------------------------------------------------------
# landmark selection figures (trn select / trn field)
# ---------------------------------------------------------------------------
def read_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        sys.exit(f"trn_plot: cannot read JSON '{path}': {e}")


def hillshade(ax, r, alpha=1.0):
    """Grey shaded relief of DEM r as a background; missing heights white."""
    z = r.z
    valid = np.isfinite(z)
    filled = np.where(valid, z, np.nanmin(z) if valid.any() else 0.0)
    hs = LightSource(azdeg=315, altdeg=40).hillshade(filled, vert_exag=2.0, dx=r.cell, dy=r.cell)
    hs = np.where(valid, hs, 1.0)
    ax.imshow(hs, extent=r.extent, origin="upper", cmap="gray", vmin=0, vmax=1, alpha=alpha,
              interpolation="bilinear")


def posinf_mask(path):
    """Cells holding +inf (ill-conditioned candidate, no informative target), north-up like read_raster."""
    ds = gdal.Open(path)  # keep the dataset alive while its band is read
    raw = ds.GetRasterBand(1).ReadAsArray()
    gt = ds.GetGeoTransform()
    ds = None
    if gt[5] > 0:
        raw = raw[::-1, :]
    if gt[1] < 0:
        raw = raw[:, ::-1]
    return np.isposinf(raw)


def draw_posinf(ax, mask, extent, label):
    """+inf cells in one flat colour, with a legend entry."""
    if mask.any():
        ax.imshow(np.ma.masked_where(~mask, np.ones(mask.shape)), extent=extent, origin="upper",
                  cmap=matplotlib.colors.ListedColormap(["#ff4fa3"]), interpolation="nearest", alpha=0.9)
        ax.scatter([], [], marker="s", c="#ff4fa3", label=label)


def selection_overlay(ax, sel, patch=True, reach=True, next_best=True):
    """Rover, range ring, selected target (with its patch) and next-best targets from `trn select --json`."""
    rx, ry = sel["rover"]["x_m"], sel["rover"]["y_m"]
    tx, ty = sel["target"]["x_m"], sel["target"]["y_m"]
    half = 0.5 * sel.get("patch_m", 0.0)
    if reach and "max_range_m" in sel:
        ax.add_patch(matplotlib.patches.Circle((rx, ry), sel["max_range_m"], fill=False, ls="--", lw=1.0,
                                               ec="white", alpha=0.8, zorder=4))
    if next_best:
        nb = sel.get("next_best", [])
        for i, t in enumerate(nb):
            if patch:
                ax.add_patch(matplotlib.patches.Rectangle((t["x_m"] - half, t["y_m"] - half), 2 * half, 2 * half,
                                                          fill=False, ec="#ffb000", lw=1.0, zorder=4))
            ax.annotate(str(i + 2), (t["x_m"], t["y_m"]), color="#ffb000", fontsize=9, fontweight="bold",
                        ha="center", va="center", zorder=6)
        if nb:
            ax.scatter([], [], marker="s", facecolors="none", edgecolors="#ffb000", s=80,
                       label=f"next best ({len(nb)}, numbered)")
    if patch:
        ax.add_patch(matplotlib.patches.Rectangle((tx - half, ty - half), 2 * half, 2 * half, fill=False,
                                                  ec="#00e5ff", lw=2.0, zorder=5))
    ax.plot([rx, tx], [ry, ty], color="#00e5ff", lw=1.0, ls=":", zorder=5)
    ax.scatter([rx], [ry], marker="o", c="#ff2d2d", s=70, edgecolors="black", label="rover", zorder=7)
    ax.scatter([tx], [ty], marker="*", c="#00e5ff", s=260, edgecolors="black",
               label=f"selected target ({1000 * sel['uncertainty_m']:.1f} mm)", zorder=7)
    ax.legend(loc="upper right", fontsize=8, framealpha=0.85)


def log_colorbar_ticks(cb):
    """Plain numbers on a log colour bar: decades and their 2x, 3x, 5x multiples."""
    def fmt(x, _):
        m = x / 10 ** np.floor(np.log10(x) + 1e-9)
        return f"{x:.3g}" if min(abs(m - k) for k in (1, 2, 3, 5)) < 1e-6 else ""
    cb.ax.yaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(fmt))
    cb.ax.yaxis.set_minor_formatter(matplotlib.ticker.FuncFormatter(fmt))


def uncertainty_norm(v, clip_pct):
    """Colour scale from the smallest value to the clip_pct percentile (values above saturate):
    logarithmic when that spans a factor 3 or more, linear otherwise. Returns (norm, scale word)."""
    f = v[np.isfinite(v)]
    lo = float(f.min())
    hi = float(np.percentile(f, clip_pct))
    if hi <= lo * 1.01:
        hi = lo * 1.01 + 1e-12
    if hi >= 3 * lo:
        return matplotlib.colors.LogNorm(vmin=lo, vmax=hi), "log"
    return matplotlib.colors.Normalize(vmin=lo, vmax=hi), "linear"


def uncertainty_colorbar(fig, ax, im, norm, label):
    cb = fig.colorbar(im, ax=ax, shrink=0.8, extend="max", label=f"{label} (m, {norm[1]} scale)")
    if norm[1] == "log":
        log_colorbar_ticks(cb)
    return cb


def fig_select(args):
    """The DEM with the rover, the selected target, its patch and the next-best targets."""
    r = read_raster(args.dem)
    sel = read_json(args.select_json)
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    z = r.z
    lo, hi = np.nanpercentile(z, [1, 99.5])
    valid = np.isfinite(z)
    rgb = LightSource(azdeg=315, altdeg=40).shade(np.where(valid, z, np.nanmin(z)), cmap=plt.get_cmap("gist_earth"),
                                                   vmin=lo, vmax=hi, vert_exag=2.0, dx=r.cell, dy=r.cell,
                                                   blend_mode="overlay")
    rgb[~valid] = (0.6, 0.6, 0.6, 1.0)
    ax.imshow(rgb, extent=r.extent, origin="upper", interpolation="nearest")
    fig.colorbar(plt.cm.ScalarMappable(cmap="gist_earth", norm=plt.Normalize(lo, hi)), ax=ax, shrink=0.8,
                 label="height (m)")
    selection_overlay(ax, sel)
    map_axes(ax, r)
    ax.set_title(args.title or
                 f"Landmark selection: target at {sel['target']['range_m']:.1f} m, predicted "
                 f"σx {1000 * sel['sigma_x_m']:.1f} mm, σy {1000 * sel['sigma_y_m']:.1f} mm", fontsize=10)
    return fig


def add_select(sub):
    p = sub.add_parser("select", help="DEM with rover, selected target and next-best targets (trn select --json)")
    p.add_argument("dem", help="DEM (any GDAL raster)")
    p.add_argument("--select-json", required=True, metavar="FILE", help="output of `trn select --json`")
    return p


def fig_uncertainty(args):
    """Predicted uncertainty of every candidate target over the DEM (the paper's Fig. 2b)."""
    r = read_raster(args.dem)
    u = read_raster(args.map)
    inf = posinf_mask(args.map)  # read_raster turns +inf into NaN
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    hillshade(ax, r)
    v = u.z
    if not np.isfinite(v).any():
        sys.exit(f"trn_plot: '{args.map}' has no finite uncertainty")
    norm = uncertainty_norm(v, args.clip)
    cmap = plt.get_cmap("viridis_r").copy()
    cmap.set_over("#3b0f70")
    im = ax.imshow(np.ma.masked_invalid(v), extent=u.extent, origin="upper", cmap=cmap, norm=norm[0],
                   interpolation="nearest", alpha=0.9)
    draw_posinf(ax, inf, u.extent, "no fix (featureless patch)")
    uncertainty_colorbar(fig, ax, im, norm, "predicted uncertainty √(σx²+σy²)")
    if args.select_json:
        selection_overlay(ax, read_json(args.select_json), patch=False, next_best=False)
    elif inf.any():
        ax.legend(loc="upper right", fontsize=8, framealpha=0.85)
    map_axes(ax, r)
    n = int(np.isfinite(v).sum())
    ax.set_title(args.title or f"Predicted uncertainty of each candidate target ({n} informative;\n"
                 f"colours saturate above the {args.clip:g}th percentile)", fontsize=10)
    return fig


def add_uncertainty(sub):
    p = sub.add_parser("uncertainty", help="per-candidate uncertainty (trn select --out-map) over the DEM (Fig. 2b)")
    p.add_argument("dem", help="DEM (any GDAL raster)")
    p.add_argument("map", help="uncertainty map from `trn select --out-map`")
    p.add_argument("--select-json", metavar="FILE", help="output of `trn select --json`: marks rover and target")
    p.add_argument("--clip", type=float, default=95.0, help="colour scale top, percentile (default 95)")
    return p


def fig_field(args):
    """The sensor uncertainty field (the paper's Fig. 3) over the DEM, its minimum marked."""
    r = read_raster(args.dem)
    f = read_raster(args.field)
    v = f.z
    if not np.isfinite(v).any():
        sys.exit(f"trn_plot: '{args.field}' has no finite value")
    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    hillshade(ax, r)
    norm = uncertainty_norm(v, args.clip)
    cmap = plt.get_cmap("magma_r").copy()
    im = ax.imshow(np.ma.masked_invalid(v), extent=f.extent, origin="upper", cmap=cmap, norm=norm[0],
                   interpolation="bilinear", alpha=0.75)
    uncertainty_colorbar(fig, ax, im, norm, "uncertainty of the best landmark")
    draw_posinf(ax, posinf_mask(args.field), f.extent, "no informative target")
    if args.evaluated:
        e = read_raster(args.evaluated)
        x, y = e.centres()
        rows, cols = np.nonzero(e.z > 0.5)
        ax.scatter(x[cols], y[rows], s=1.0, c="#1f5fbf", alpha=0.4, linewidths=0,
                   label=f"evaluated positions ({rows.size})")
    i = np.nanargmin(v)
    row, col = np.unravel_index(i, v.shape)
    x, y = f.centres()
    ax.scatter([x[col]], [y[row]], marker="*", s=260, c="#00e5ff", edgecolors="black", zorder=6,
               label=f"best rover position ({1000 * v[row, col]:.1f} mm)")
    ax.legend(loc="upper right", fontsize=8, framealpha=0.85, markerscale=1.0)
    map_axes(ax, r)
    info = ""
    if args.field_json:
        fj = read_json(args.field_json)
        info = f": {fj['evaluations']} of {fj['cells']} positions evaluated"
    ax.set_title(args.title or f"Sensor uncertainty field{info}", fontsize=10)
    return fig


def add_field(sub):
    p = sub.add_parser("field", help="sensor uncertainty field (trn field) over the DEM (Fig. 3)")
    p.add_argument("dem", help="DEM (any GDAL raster)")
    p.add_argument("field", help="field from `trn field --out`")
    p.add_argument("--evaluated", metavar="FILE", help="`trn field --evaluated-out` map: dots where computed")
    p.add_argument("--field-json", metavar="FILE", help="output of `trn field --json` (evaluations in the title)")
    p.add_argument("--clip", type=float, default=99.0, help="colour scale top, percentile (default 99)")
    return p



FIGURES.update({"select": (add_select, fig_select), "uncertainty": (add_uncertainty, fig_uncertainty),
                "field": (add_field, fig_field)})

if __name__ == "__main__":
    sys.exit(main())
