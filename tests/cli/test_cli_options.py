#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tests/cli/test_cli_options.py - no option of `trn` is silently ignored (CTest `cli_options`).

    python3 tests/cli/test_cli_options.py PATH/TO/trn WORKDIR [--list]

The commands are the ones `trn --help` lists (commands.def) and, for each, the
options and arguments its `--help` lists: that text is printed from the very
option table cli_parse reads (tools/trn/cli.c, cli_usage), so an option added
to a table shows up here without anyone touching this file, and the test fails
until CASES says how to see what it does.

Each option of each command is one case of CASES[command]:

  effect(ARGS)   the run with ARGS added to the command's base run must differ
                 from the base run in what the command does: its JSON output
                 with the keys that merely repeat an option removed (ECHO), or
                 its stdout without --json, or the files it writes (SHA-256).
                 ctx= adds arguments to both runs (an option that works in
                 combination), base= replaces the base run of the variant (a
                 required option given another value, --batch for --local).
  refused(ARGS)  the run must fail with the given exit status (1 bad input, 2
                 usage; tools/trn/cli.h), one stderr line `trn CMD: reason`
                 holding the given phrase, and nothing on stdout.
  unseen(ARGS)   an option whose effect the small case cannot show (the reason
                 is the comment beside it); ARGS is a bad value, which must be
                 refused as above.

The base run of every command is run twice and must give the same signature,
so that a changing output (a time, a temporary name) cannot pass an option as
effective. Terrains are small (96 x 96 and 128 x 128 cells), windows a few
cells: the whole test takes seconds under the sanitizers.

--list prints every command's options and the case kind, for a reader.
"""
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys

import numpy as np

import clitest  # noqa: E402  (tests/cli/, the script's own directory)

TRN = os.path.abspath(sys.argv[1])
WORK = os.path.abspath(sys.argv[2])
LIST = "--list" in sys.argv[3:]
H = clitest.Harness(TRN, sub=(), timeout=300)
check = H.check
SRC = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(SRC))

shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)


def p(name):
    return os.path.join(WORK, name)


# ---- the cases ----------------------------------------------------------------
class Case:
    def __init__(self, kind, args, ctx=(), base=None, drop=(), rc=None, needle=None, why=None):
        self.kind, self.args, self.ctx = kind, [str(a) for a in args], [str(a) for a in ctx]
        self.base, self.drop = base, list(drop)
        self.rc, self.needle, self.why = rc, needle, why


def effect(*args, ctx=(), base=None, drop=(), rc=0):
    return Case("effect", args, ctx=ctx, base=base, drop=drop, rc=rc)


def refused(*args, rc, needle, ctx=(), base=None, drop=()):
    return Case("refused", args, ctx=ctx, base=base, drop=drop, rc=rc, needle=needle)


def unseen(*args, rc, needle, why, ctx=(), base=None, drop=()):
    return Case("unseen", args, ctx=ctx, base=base, drop=drop, rc=rc, needle=needle, why=why)


FLAGS = {"--json", "--reference", "--strict", "--check", "--instructions"}


def split(args):
    """args -> [(option, value or None)] (a positional argument: (None, value))."""
    out, i = [], 0
    while i < len(args):
        a = args[i]
        if a.startswith("--") and "=" not in a and a not in FLAGS:
            out.append((a, args[i + 1]))
            i += 2
        else:
            out.append((a, None) if a.startswith("--") else (None, a))
            i += 1
    return out


def join(pairs):
    return [w for o, v in pairs for w in (o, v) if w is not None]


def merge(base, extra):
    """base with extra's options added, an option base already has taking extra's value."""
    pairs = split(base)
    for o, v in split(extra):
        at = [k for k, (bo, _) in enumerate(pairs) if o is not None and bo == o]
        if at:
            pairs[at[0]] = (o, v)
        else:
            pairs.append((o, v))
    return join(pairs)


def drop(base, names):
    """base without the options names (and their values)."""
    return join([(o, v) for o, v in split(base) if o not in names])


# ---- inputs: a small terrain, a local DEM cut from it, a CAN log -------------
G, G2, LOCAL, LOCAL2B = p("g.tif"), p("g128.tif"), p("local.tif"), p("local_2band.tif")
H.run("terrain", "--out", G, "--size-cells", "96", "--seed", "3")
H.run("terrain", "--out", G2, "--size-cells", "128", "--seed", "5")
from osgeo import gdal  # noqa: E402

gdal.UseExceptions()
ds = gdal.Open(G)
g = ds.GetRasterBand(1).ReadAsArray().astype(np.float32)
ds = None
# rover on global cell (48, 48): map (4.85, 4.75); the local DEM is the 32 x 32
# crop from (32, 32) in the rover frame, with 1 cm of seeded height noise
C0, L, RC, CELL = 32, 32, 48, 0.1
crop = g[C0:C0 + L, C0:C0 + L] + np.random.default_rng(7).normal(0.0, 0.01, (L, L)).astype(np.float32)
rover_gt = ((C0 - (RC + 0.5)) * CELL, CELL, 0.0, -(C0 - (RC + 0.5)) * CELL, 0.0, -CELL)
clitest.write_raster(LOCAL, crop, rover_gt)
PRIOR = "4.9,4.65"
with open(p("batch.txt"), "w") as f:  # two cases: the second a window that misses the truth
    f.write(f"{LOCAL} 4.9 4.65\n{LOCAL} 5.3 4.3 0.1\n")
with open(p("tight_budget.txt"), "w") as f:  # every stage over budget
    f.write("scale 1000\nsearch 0.000001\n")
# a map that repeats every 3 cells east-west (as in test_cli.py): a failure probability near 2/3
yy, xx = np.mgrid[0:96, 0:96]
per = (0.3 * np.sin(2 * np.pi * xx / 3.0) + 0.4 * np.sin(0.37 * yy) + 0.15 * np.cos(0.61 * yy)).astype(np.float32)
clitest.write_raster(p("periodic.tif"), per, (0.0, CELL, 0.0, 9.6, 0.0, -CELL))
clitest.write_raster(p("periodic_local.tif"), per[28:69, 28:69].copy(), (-2.05, CELL, 0.0, 2.05, 0.0, -CELL))
PERIODIC = ["--dem", p("periodic.tif"), "--local", p("periodic_local.tif"), "--prior", "4.85,4.75",
            "--window-m", "0.4"]
CAN_LOG = os.path.join(ROOT, "tests", "data", "can", "sim_capture.log")

SEL_SMALL = ["--max-range-m", "2", "--min-range-m", "0.5", "--patch-m", "1", "--separation-m", "0.3"]

# JSON keys (dotted paths) that only repeat an option's value, removed before
# comparing, and keys that change from run to run (times).
ECHO_SELMAP = ["rover", "min_range_m", "max_range_m", "stride_cells", "heading_sigma_deg",
               "heading_search", "sensors", "out_map", "global_error", "map_config_name", "predicts", "sigma_h_m",
               "map_config", "patch_m", "cell_m"]
ECHO = {
    "terrain": ["file", "origin", "cell_m", "coverage_k", "height_ratio", "d_min_m", "d_max_m",
                "relief_m", "seed", "width", "height", "q_per_m", "model_area_fraction"],
    "localize": ["prior", "window_m", "cell_m", "map_config", "local", "time_ms", "heading_window_deg",
                 "heading_center_deg"],
    "select": ECHO_SELMAP,
    "field": ECHO_SELMAP + ["file", "heading_deg", "coarse_step_cells", "seconds", "algorithm",
                            "outlier_density_per_m"],
    "experiment": ["trials", "seed", "terrain", "parameters", "global_error", "map_config_name",
                   "sigma_h_m", "map_config", "heading.error_deg", "heading.window_deg",
                   "heading.selection_sigma_heading_rad", "heading.select_heading_search"],
    "profile": ["config.map_cells", "config.local_cells", "config.window_cells", "config.max_range_m",
                "config.stride_cells", "config.runs", "config.seed", "config.dem", "budget.file"],
    "can-decode": [],
}
# keys removed wherever they are (wall times)
VOLATILE = re.compile(r"(^|_)(ms|wall_ms|wall_max_ms|seconds|time_ms|target_ms|share)$")

BASE = {
    "terrain": ["--out", "t.tif", "--size-cells", "32", "--json"],
    "localize": ["--dem", G, "--local", LOCAL, "--prior", PRIOR, "--window-m", "0.3", "--json"],
    "select": ["--dem", G, "--rover", "4.8,4.8", *SEL_SMALL, "--stride-cells", "2", "--json"],
    "field": ["--dem", G, "--out", "f.tif", "--area-m", "4,4,5.5,5.5", *SEL_SMALL[:6], "--stride-cells", "2",
              "--coarse-step-cells", "8", "--json"],
    "experiment": ["--trials", "2", "--size-cells", "128", "--json"],
    "profile": ["--map-cells", "64", "--local-cells", "16", "--window-cells", "2", "--runs", "1",
                "--max-range-m", "2", "--stride-cells", "4", "--json"],
    "can-decode": ["--json", CAN_LOG],
}

# The map configuration's options (tools/trn/mapopt.c). `trn localize`:
# the height matcher (the auto configuration, the base run) reads the DEM's
# heights, so the voxel map's options are seen with --match voxel and refused
# with the height matcher (mapopt_check_use).
VOXEL = ["--map-config", "paper"]
MAP_LOCALIZE = {
    "--map-config": effect("--map-config", "paper"),
    "--zbin-m": [effect("--zbin-m", "0.05", ctx=VOXEL),
                 refused("--zbin-m", "0.05", rc=2, needle="--match voxel")],
    "--nz": [effect("--nz", "8", ctx=VOXEL), refused("--nz", "8", rc=2, needle="--match voxel")],
    "--highpass-m": [effect("--highpass-m", "0.5", ctx=VOXEL),
                     refused("--highpass-m", "0.5", rc=2, needle="--match voxel")],
    "--sigma-m": [effect("--sigma-m", "0.3", ctx=VOXEL),
                  refused("--sigma-m", "0.3", rc=2, needle="--match voxel")],
    "--inlier-prob": [effect("--inlier-prob", "0.5"), effect("--inlier-prob", "0.5", ctx=VOXEL)],
    "--noise-m": [effect("--noise-m", "0.05"), effect("--noise-m", "0.05", ctx=VOXEL + ["--refine", "1"]),
                  refused("--noise-m", "0.05", ctx=VOXEL, rc=2, needle="--refine 1")],
    "--noise-k": [effect("--noise-k", "0.5"), effect("--noise-k", "0.5", ctx=VOXEL + ["--refine", "1"]),
                  refused("--noise-k", "0.5", ctx=VOXEL, rc=2, needle="--refine 1")],
    "--local-highpass": [effect("--local-highpass", "map", ctx=VOXEL),
                         refused("--local-highpass", "box", rc=2, needle="--match voxel")],
    "--refine": [effect("--refine", "1", ctx=VOXEL),
                 refused("--refine", "0", rc=2, needle="--match voxel")],
    "--noise-auto": [effect("--noise-auto", "0"),
                     refused("--noise-auto", "1", ctx=VOXEL + ["--refine", "1"], rc=2, needle="--match heights")],
    "--match": effect("--match", "voxel"),
    # the acceptance limit: on a map that repeats every 3 cells the answer is
    # 'ambiguous' under the auto configuration's limit, a fix under 1
    "--max-failure-prob": effect("--max-failure-prob", "1", ctx=PERIODIC),
}
# `trn experiment`: the voxel map alone
MAP_VOXEL = {
    "--map-config": effect("--map-config", "auto"),
    "--zbin-m": effect("--zbin-m", "0.05"),
    "--nz": effect("--nz", "8"),
    "--highpass-m": effect("--highpass-m", "0.5"),
    "--sigma-m": effect("--sigma-m", "0.3"),
    "--inlier-prob": effect("--inlier-prob", "0.5"),
    # the local noise model sets the automatic configuration's height bin, and nothing else here
    "--noise-m": [effect("--noise-m", "0.05", ctx=["--map-config", "auto"]),
                  refused("--noise-m", "0.05", rc=2, needle="--map-config auto")],
    "--noise-k": [effect("--noise-k", "0.5", ctx=["--map-config", "auto"]),
                  refused("--noise-k", "0.5", rc=2, needle="--map-config auto")],
}
# `trn select`, `trn field`: the prediction of the configuration's matcher,
# the height matcher by default (auto), the voxel matcher with paper
VOXEL_SEL = ["--map-config", "paper"]


def voxel_pred(opt, val, needle="--match voxel"):
    """An option of the voxel prediction: seen with paper, refused with the height prediction."""
    return [effect(opt, val, ctx=VOXEL_SEL), refused(opt, val, rc=2, needle=needle)]


MAP_PREDICT = {
    "--map-config": effect("--map-config", "paper"),
    "--match": effect("--match", "voxel"),
    "--zbin-m": voxel_pred("--zbin-m", "0.05"),
    "--nz": voxel_pred("--nz", "8"),
    "--highpass-m": voxel_pred("--highpass-m", "0.5"),
    "--sigma-m": voxel_pred("--sigma-m", "0.3"),
    "--inlier-prob": voxel_pred("--inlier-prob", "0.5", needle="voxel prediction"),
    # the height prediction's noise model; with paper the voxel prediction does not read it
    "--noise-m": [effect("--noise-m", "0.05"),
                  refused("--noise-m", "0.05", rc=2, needle="--map-config auto", ctx=VOXEL_SEL)],
    "--noise-k": [effect("--noise-k", "0.5"),
                  refused("--noise-k", "0.5", rc=2, needle="--map-config auto", ctx=VOXEL_SEL)],
}
SELMAP = {
    "--band": unseen("--band", "2", rc=1, needle="--dem", why="the DEM has one band"),
    # the mast's reach (--pan-deg) turns with it; with every bearing in reach
    # only the bearings `trn select` reports turn (the field reports none)
    "--heading-deg": effect("--heading-deg", "90", ctx=["--pan-deg", "-45,45"]),
    "--heading-sigma-deg": effect("--heading-sigma-deg", "3"),
    "--heading-search": [effect("--heading-search", "1", ctx=["--heading-sigma-deg", "3"]),
                         refused("--heading-search", "1", rc=2, needle="--heading-sigma-deg")],
    "--pan-deg": effect("--pan-deg", "-45,45"),
    "--min-range-m": effect("--min-range-m", "1.2"),
    "--max-range-m": effect("--max-range-m", "1.6"),
    "--footprint-m": effect("--footprint-m", "1.0"),
    "--patch-m": effect("--patch-m", "0.6"),
    "--stride-cells": effect("--stride-cells", "3"),
    "--separation-m": effect("--separation-m", "1.0"),
    "--sensors": voxel_pred("--sensors", "1,1", needle="voxel prediction"),
    "--outlier-density": voxel_pred("--outlier-density", "5", needle="voxel prediction"),
    "--global-sigma-m": [effect("--global-sigma-m", "0.2"), effect("--global-sigma-m", "0.2", ctx=VOXEL_SEL)],
    "--global-sigma-k": voxel_pred("--global-sigma-k", "0.05", needle="voxel prediction"),
    "--global-error": voxel_pred("--global-error", p("gerr.tif"), needle="voxel prediction"),
    # a binned local map's counts: the height prediction's; the voxel prediction refuses it
    "--points-per-cell": [effect("--points-per-cell", "4"),
                          refused("--points-per-cell", "4", rc=2, needle="height prediction", ctx=VOXEL_SEL)],
    **MAP_PREDICT,
    "--json": effect(drop=["--json"]),
}
EXP_DEM = ["--dem", G2]  # with drop=["--size-cells"]: the experiment on a given DEM
# `trn experiment`: the voxel map for the selection (the base run: the paper's
# configuration, the voxel matcher) and, with --match heights, the height
# matcher on height grids, which reads the noise model, the noise rescale and
# the acceptance limit; the voxel matcher reads neither of the last two
HEIGHTS = ["--match", "heights"]
MAP_EXPERIMENT = {
    **MAP_VOXEL,
    # the noise model: the auto configuration's height bin; the height matcher's local maps
    "--noise-m": [effect("--noise-m", "0.05", ctx=["--map-config", "auto", "--match", "voxel"]),
                  effect("--noise-m", "0.05", ctx=HEIGHTS),
                  refused("--noise-m", "0.05", rc=2, needle="--map-config auto")],
    "--noise-k": [effect("--noise-k", "0.5", ctx=["--map-config", "auto", "--match", "voxel"]),
                  effect("--noise-k", "0.5", ctx=HEIGHTS),
                  refused("--noise-k", "0.5", rc=2, needle="--map-config auto")],
    # the voxel map shapes the voxel matcher's selection; with heights the selection predicts
    # the height matcher, which reads the DEM's heights
    "--zbin-m": [effect("--zbin-m", "0.05"),
                 refused("--zbin-m", "0.3", rc=2, needle="--match voxel", ctx=HEIGHTS)],
    "--inlier-prob": [effect("--inlier-prob", "0.5"), effect("--inlier-prob", "0.5", ctx=HEIGHTS)],
    # the residuals of the wrong answers reject the noise model (noise_rescaled)
    "--noise-auto": [effect("--noise-auto", "1", ctx=HEIGHTS),
                     refused("--noise-auto", "1", rc=2, needle="--match heights")],
    # the status: answers above the limit are 'ambiguous', not fixes
    "--max-failure-prob": [effect("--max-failure-prob", "0.01", ctx=HEIGHTS),
                           refused("--max-failure-prob", "0.01", rc=2, needle="--match heights")],
    "--match": effect("--match", "heights"),
}

CASES = {
    "terrain": {
        "--out": effect("--out", "other.tif"),
        "--size-cells": effect("--size-cells", "24"),
        "--cell-m": effect("--cell-m", "0.2"),
        "--coverage": effect("--coverage", "0.2"),
        "--seed": effect("--seed", "2"),
        "--height-ratio": effect("--height-ratio", "1.0"),
        "--min-diameter-m": effect("--min-diameter-m", "0.5"),
        "--max-diameter-m": effect("--max-diameter-m", "0.6"),
        "--relief-m": effect("--relief-m", "0.5"),
        "--origin": effect("--origin", "100,200"),
        "--crs": effect("--crs", "EPSG:32633"),
        "--json": effect(drop=["--json"]),
    },
    "localize": {
        "--dem": effect("--dem", G2),
        "--local": effect("--local", p("local_shift.tif")),
        # a prior whose window misses the truth
        "--prior": effect("--prior", "5.3,4.3"),
        "--batch": effect("--batch", p("batch.txt"), drop=["--local", "--prior"]),
        "--window-m": effect("--window-m", "0.1"),
        # one-band files: a second band does not exist, and must be refused
        "--band": unseen("--band", "2", rc=1, needle="--dem", why="the DEM has one band"),
        "--local-band": unseen("--local-band", "2", rc=1, needle="band", why="the local DEM has one band"),
        "--centroid-bands": unseen("--centroid-bands", "2", rc=1, needle="--centroid-bands",
                                   why="the local DEM has one band (test_cli_dem.py: its effect)"),
        "--count-band": unseen("--count-band", "2", rc=1, needle="--count-band",
                               why="the local DEM has one band (test_cli_dem.py: its effect)"),
        # its effect is the refusal of a larger local DEM
        "--max-local-cells": refused("--max-local-cells", "16", rc=1, needle="16"),
        "--heading-deg": effect("--heading-deg", "3"),
        "--heading-window-deg": effect("--heading-window-deg", "2"),
        # the same answer by design (tests/test_height_bound.c); the work
        # fields (blocks_bounded, failure_prob_bound) show the other search
        "--search": [effect("--search", "bounded"),
                     refused("--search", "fast", rc=1, needle="--search")],
        # a budget below one pass's poses: the named status, exit 1
        "--node-budget": effect("--node-budget", "1", rc=1),
        **MAP_LOCALIZE,
        "--json": effect(drop=["--json"]),
    },
    "select": {
        "--dem": effect("--dem", G2),
        "--rover": effect("--rover", "5.5,4.0"),
        "--out-map": effect("--out-map", "m.tif"),
        "--next-best": effect("--next-best", "1"),
        **SELMAP,
    },
    "field": {
        "--dem": effect("--dem", G2),
        "--out": effect("--out", "other.tif"),
        "--area-m": effect("--area-m", "3,3,5,5"),
        "--coarse-step-cells": effect("--coarse-step-cells", "4"),
        "--margin-rel": effect("--margin-rel", "0"),
        "--change-rel": effect("--change-rel", "0"),
        "--evaluated-out": effect("--evaluated-out", "ev.tif"),
        # trn_field instead of trn_field_fast: the same raster bit for bit by
        # design (docs/modules/field.md), the voxel prediction's smaller
        # workspace is what changes; the height prediction has one path
        "--reference": effect("--reference", ctx=VOXEL_SEL),
        **{k: v for k, v in SELMAP.items() if k != "--separation-m"},  # field ranks no next-best targets
    },
    "experiment": {
        "--trials": effect("--trials", "3"),
        "--seed": effect("--seed", "2"),
        "--dem": effect(*EXP_DEM, drop=["--size-cells"]),
        "--band": [unseen("--band", "2", ctx=EXP_DEM, drop=["--size-cells"], rc=1, needle="--dem",
                          why="the DEM has one band"),
                   refused("--band", "1", rc=2, needle="--dem")],
        "--coverage": effect("--coverage", "0.2"),
        "--terrain-seed": effect("--terrain-seed", "9"),
        "--min-diameter-m": effect("--min-diameter-m", "0.4"),
        "--relief-m": effect("--relief-m", "0.5"),
        "--size-cells": effect("--size-cells", "160"),
        "--window-m": effect("--window-m", "1.5"),
        "--prior-error-m": effect("--prior-error-m", "0.2"),
        "--grid-spacing-m": effect("--grid-spacing-m", "1"),
        "--min-range-m": effect("--min-range-m", "3"),
        "--max-range-m": effect("--max-range-m", "6"),
        "--patch-m": effect("--patch-m", "1.5"),
        "--footprint-m": effect("--footprint-m", "2"),
        "--success-cells": effect("--success-cells", "0.5"),
        "--sensor": [effect("--sensor", "dem"),
                     refused("--sensor", "dem", ctx=HEIGHTS, rc=2, needle="--match voxel")],
        "--height-noise-m": [effect("--height-noise-m", "0.05", ctx=["--sensor", "dem"]),
                             refused("--height-noise-m", "0.05", rc=1, needle="dem sensor"),
                             refused("--height-noise-m", "0.05", ctx=HEIGHTS, rc=2, needle="--match voxel")],
        "--heading-error-deg": [effect("--heading-error-deg", "2"),
                                refused("--heading-error-deg", "2", ctx=HEIGHTS, rc=2, needle="--match voxel")],
        "--heading-window-deg": [effect("--heading-window-deg", "2", ctx=["--heading-error-deg", "2"]),
                                 refused("--heading-window-deg", "2", rc=2, needle="--heading-error-deg")],
        "--select-heading-search": [effect("--select-heading-search", "0", ctx=["--heading-error-deg", "2"]),
                                    refused("--select-heading-search", "0", rc=2,
                                            needle="--heading-error-deg")],
        # the voxel prediction's eq. 8; with heights --global-sigma-m is the DEM's error
        "--global-sigma-m": [effect("--global-sigma-m", "0.2"), effect("--global-sigma-m", "0.2", ctx=HEIGHTS)],
        "--global-sigma-k": [effect("--global-sigma-k", "0.05"),
                             refused("--global-sigma-k", "0.05", rc=2, needle="voxel prediction", ctx=HEIGHTS)],
        "--global-error": [effect("--global-error", p("gerr128.tif"), ctx=[*EXP_DEM, "--match", "voxel"],
                                  drop=["--size-cells"]),
                           refused("--global-error", p("gerr128.tif"), rc=2, needle="voxel prediction",
                                   ctx=EXP_DEM, drop=["--size-cells"]),
                           refused("--global-error", p("gerr128.tif"), rc=2, needle="--dem")],
        **MAP_EXPERIMENT,
        "--json": effect(drop=["--json"]),
    },
    "profile": {
        "--map-cells": effect("--map-cells", "80"),
        "--local-cells": effect("--local-cells", "24"),
        "--window-cells": effect("--window-cells", "3"),
        "--max-range-m": effect("--max-range-m", "3"),
        "--stride-cells": effect("--stride-cells", "2"),
        # only the number of timed runs: wall times, which the comparison drops
        "--runs": unseen("--runs", "0", rc=1, needle="--runs", why="timing only"),
        "--seed": effect("--seed", "2"),
        # a DEM file instead of the synthetic terrain (96 x 96 cells of 0.1 m)
        "--dem": effect("--dem", G),
        "--budget": effect("--budget", os.path.join(ROOT, "tools", "profile", "budget-example.txt")),
        # exit 3 only when a stage is over budget; without --budget it has nothing to check
        "--check": [refused("--check", rc=2, needle="--budget"),
                    effect("--check", ctx=["--budget", p("tight_budget.txt")], rc=3)],
        # needs valgrind and minutes: the CTest profile_instructions runs it
        "--instructions": unseen("--instructions=1", rc=2, needle="takes no value",
                                 why="valgrind, minutes; profile_instructions"),
        "--json": effect(drop=["--json"]),
    },
    "can-decode": {
        "LOG": effect(base=["--json", os.path.join(ROOT, "tests", "data", "can", "faults.log")]),
        # exit status 1 on the log's faults
        "--strict": effect("--strict", base=["--json", os.path.join(ROOT, "tests", "data", "can", "faults.log")],
                           rc=1),
        "--n-cr-ms": effect("--n-cr-ms", "1"),
        "--json": effect(drop=["--json"]),
    },
}


# ---- running and comparing ----------------------------------------------------
def strip(obj, paths):
    """obj without the dotted paths and the VOLATILE keys (recursively)."""
    if isinstance(obj, dict):
        out = {}
        for k, v in obj.items():
            if k in paths or VOLATILE.search(k):
                continue
            sub = [q[len(k) + 1:] for q in paths if q.startswith(k + ".")]
            out[k] = strip(v, sub)
        return out
    if isinstance(obj, list):
        return [strip(v, paths) for v in obj]
    return obj


def run_in(cmd, args, tag):
    """Run trn CMD ARGS in a fresh directory; (rc, stdout, stderr, signature)."""
    d = p(f"run/{cmd}/{tag}")
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    t0 = time.monotonic()
    proc = subprocess.run([TRN, cmd] + args, capture_output=True, text=True, timeout=300, cwd=d)
    n, secs = RUNS.get(cmd, (0, 0.0))
    RUNS[cmd] = (n + 1, secs + time.monotonic() - t0)
    try:
        out = json.dumps(strip(json.loads(proc.stdout), ECHO[cmd]), sort_keys=True)
    except ValueError:
        out = "".join(ln for ln in proc.stdout.splitlines(True)
                      if not re.search(r"\d+(\.\d+)? (ms|s)\b", ln))  # text: lines with a time dropped
    files = {}
    for name in sorted(os.listdir(d)):
        with open(os.path.join(d, name), "rb") as f:
            files[name] = hashlib.sha256(f.read()).hexdigest()
    return proc.returncode, proc.stdout, proc.stderr, (proc.returncode, out, tuple(files.items()))


def help_options(cmd):
    """The options and arguments `trn CMD --help` lists (its table), --help itself aside."""
    rc, out, _ = H.run(cmd, "--help")
    check(rc == 0, f"trn {cmd} --help: exit {rc}")
    names, section = [], None
    for line in out.splitlines():
        if line in ("options:", "arguments:"):
            section = line
        elif section and line.startswith("  ") and not line.startswith("   "):
            name = line.split()[0]
            if name != "--help":
                names.append(name)
        elif not line.strip():
            section = None
    return names


def commands():
    """The commands `trn --help` lists (commands.def), without `version`."""
    rc, out, _ = H.run("--help")
    check(rc == 0, "trn --help: exit 0")
    body = out.split("commands:\n", 1)[1].split("\n\n", 1)[0]
    return [ln.split()[0] for ln in body.splitlines() if ln.strip() and ln.split()[0] != "version"]


def listify(c):
    return [] if c is None else c if isinstance(c, list) else [c]


def check_refusal(cmd, args, case, label):
    rc, out, err, _ = run_in(cmd, args, "refused")
    lines = err.splitlines()
    check(rc == case.rc, f"{label}: exit {rc}, want {case.rc} (stderr {err.strip()!r})")
    check(len(lines) == 1 and err.startswith(f"trn {cmd}: ") and case.needle in err,
          f"{label}: want one line 'trn {cmd}: ...{case.needle}...', got {err!r}")
    check(out == "", f"{label}: stdout not empty: {out[:200]!r}")


# inputs the cases name
clitest.write_raster(p("local_shift.tif"), np.roll(crop, 2, axis=1), rover_gt)
ds = gdal.Open(G)
clitest.write_raster(p("gerr.tif"), np.full((96, 96), 0.3, np.float32), ds.GetGeoTransform())
ds = gdal.Open(G2)
clitest.write_raster(p("gerr128.tif"), np.full((128, 128), 0.3, np.float32), ds.GetGeoTransform())
ds = None

import time  # noqa: E402
RUNS = {}
cmds = commands()
check(set(cmds) == set(CASES), f"commands {sorted(cmds)} against the cases' {sorted(CASES)}")
for cmd in cmds:
    names = help_options(cmd)
    cases = CASES.get(cmd, {})
    missing = [n for n in names if n not in cases]
    stale = [n for n in cases if n not in names]
    check(not missing, f"trn {cmd}: options without a case in {os.path.basename(__file__)}: {missing} "
                       "(say what each does: effect(), refused() or unseen())")
    check(not stale, f"trn {cmd}: cases for options its --help does not list: {stale}")
    if LIST:
        for n in names:
            for c in listify(cases.get(n)) or [None]:
                print(f"{cmd:11s} {n:22s} {c.kind if c else '?':8s} {' '.join(c.ctx + c.args) if c else ''}"
                      f"{'   # ' + c.why if c and c.why else ''}")
    base = BASE[cmd]
    _, _, err0, sig0 = run_in(cmd, base, "base")
    _, _, _, sig0b = run_in(cmd, base, "base_again")
    check(sig0[0] == 0, f"trn {cmd} {' '.join(base)}: exit {sig0[0]}: {err0.strip()}")
    check(sig0 == sig0b, f"trn {cmd}: two base runs differ (a time or a name not dropped?):\n"
                         f"  {sig0}\n  {sig0b}")
    refs = {tuple(base): sig0}
    for name in names:
        for case in listify(cases.get(name)):
            label = f"trn {cmd} {name} ({' '.join(case.args) or 'without ' + ' '.join(case.drop)})"
            # the reference: the base run (or the case's), less case.drop, plus case.ctx;
            # the variant: the reference plus the option
            ref = merge(drop(case.base if case.base is not None else base, case.drop), case.ctx)
            vargs = merge(ref, case.args)
            if case.kind in ("refused", "unseen"):
                check_refusal(cmd, vargs, case, label)
                continue
            # an option shown in a context (ctx, another base) is compared with that
            # context alone; one that needs only some base option dropped (or is that
            # drop) with the base run
            if case.args and (case.ctx or case.base is not None):
                against = ref
            else:
                against = base
            if tuple(against) not in refs:
                rc, _, err, refs[tuple(against)] = run_in(cmd, against, "reference")
                check(rc == 0, f"{label}: the reference run trn {cmd} {' '.join(against)} failed: {err.strip()}")
            rc, out, err, sig = run_in(cmd, vargs, "variant")
            check(rc == case.rc, f"{label}: trn {cmd} {' '.join(vargs)}: exit {rc}, want {case.rc}: {err.strip()}")
            check(sig != refs[tuple(against)],
                  f"{label}: changes nothing: trn {cmd} {' '.join(vargs)} gives what trn {cmd} "
                  f"{' '.join(against)} gives (JSON without its echo, stdout, files)")
for cmd, (n, secs) in RUNS.items():
    print(f"trn {cmd}: {n} runs, {secs:.1f} s")
sys.exit(H.finish("cli_options"))
