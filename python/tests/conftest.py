# SPDX-License-Identifier: Apache-2.0
"""Fixtures of the Python package's tests: the `trn` command line (for the
CLI-equality checks) and small DEMs it makes.

The command line: $TRN_CLI, else build/host-release/trn, else build/host/trn
of the repository (tools/test.d/46-python.sh runs after the presets are built).
"""
import json
import os
import subprocess

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def _find_cli():
    cands = [os.environ.get("TRN_CLI")] + [os.path.join(ROOT, "build", p, "trn") for p in ("host-release", "host")]
    for c in cands:
        if c and os.access(c, os.X_OK):
            return c
    pytest.fail("no `trn` command line: build the host-release preset or set TRN_CLI")


@pytest.fixture(scope="session")
def cli():
    path = _find_cli()

    def run(*args, check=True):
        p = subprocess.run([path, *map(str, args)], capture_output=True, text=True)
        if check and p.returncode != 0:
            raise AssertionError(f"trn {' '.join(map(str, args))}: exit {p.returncode}: {p.stderr}")
        return p

    def run_json(*args):
        return json.loads(run(*args, "--json").stdout)

    run.json = run_json
    run.path = path
    return run


@pytest.fixture(scope="session")
def dems(cli, tmp_path_factory):
    """global.tif: 64 x 64 cells of 0.1 m at (1000, 2000), EPSG:32611 (UTM
    11N, metres); local.tif: a 32 x 32 cut of it in the rover frame, the
    rover at map (1002.75, 2003.35) (the README's recipe, smaller)."""
    from osgeo import gdal

    gdal.UseExceptions()
    d = tmp_path_factory.mktemp("dems")
    g = str(d / "global.tif")
    loc = str(d / "local.tif")
    cli("terrain", "--out", g, "--size-cells", 64, "--origin", "1000,2000", "--coverage", 0.15, "--seed", 3,
        "--crs", "EPSG:32611")
    # columns 12..43, rows 14..45: map x 1001.2..1004.4, y 2001.8..2005.0; rover frame origin at (1002.8, 2003.4)
    gdal.Translate(loc, g, srcWin=[12, 14, 32, 32], outputBounds=[-1.6, 1.6, 1.6, -1.6])
    return {"dir": d, "global": g, "local": loc, "truth": (1002.8, 2003.4)}


def read(path):
    """(heights float32, geotransform, WKT) of a raster."""
    from osgeo import gdal

    ds = gdal.Open(str(path))
    a = ds.GetRasterBand(1).ReadAsArray()
    return a, ds.GetGeoTransform(), ds.GetProjection()
