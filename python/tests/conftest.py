# SPDX-License-Identifier: Apache-2.0
"""Fixtures of the Python package's tests: the `trn` command line (for the
CLI-equality checks) and small DEMs it makes. No test needs GDAL's Python
bindings (osgeo): files are read and written by the package's C side
(trn.read_raster, trn.write_raster, through libgdal), so the same tests run in
a plain venv (tools/test.d/47-python-venv.sh).

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
    import trn

    d = tmp_path_factory.mktemp("dems")
    g = str(d / "global.tif")
    loc = str(d / "local.tif")
    cli("terrain", "--out", g, "--size-cells", 64, "--origin", "1000,2000", "--coverage", 0.15, "--seed", 3,
        "--crs", "EPSG:32611")
    # columns 12..43, rows 14..45: map x 1001.2..1004.4, y 2001.8..2005.0; rover frame origin at (1002.8, 2003.4)
    a, _, _ = trn.read_raster(g, raw=True)
    trn.write_raster(loc, a[14:46, 12:44], (-1.6, 0.1, 0.0, 1.6, 0.0, -0.1))
    return {"dir": d, "global": g, "local": loc, "truth": (1002.8, 2003.4)}


def read(path):
    """(heights float32 as stored, geotransform, WKT or "") of a raster."""
    import trn

    a, gt, wkt = trn.read_raster(path, raw=True)
    return a, gt, wkt or ""
