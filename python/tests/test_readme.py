# SPDX-License-Identifier: Apache-2.0
"""The README's planner example (the ```python block after
`<!-- readme-example: python-planner -->`), run as written on the README's
global.tif, its answers checked against the command line."""
import os
import re
import subprocess
import sys

import pytest

from conftest import ROOT


def readme_block(marker):
    text = open(os.path.join(ROOT, "README.md"), encoding="utf-8").read()
    at = text.index(f"<!-- readme-example: {marker} -->")
    m = re.compile(r"```python\n(.*?)\n```", re.S).search(text, at)
    assert m, f"no ```python block after the {marker} marker"
    return m.group(1)


def run_planner(cli, tmp_path, code):
    cli("terrain", "--out", tmp_path / "global.tif", "--origin", "1000,2000", "--coverage", 0.15, "--seed", 3)
    (tmp_path / "planner.py").write_text(code)
    p = subprocess.run([sys.executable, "planner.py"], cwd=tmp_path, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "planner.png").stat().st_size > 10000
    field = cli.json("field", "--dem", tmp_path / "global.tif", "--out", tmp_path / "f.tif",
                     "--area-m", "1008,2008,1018,2018")
    b = field["best"]
    assert f"best waypoint {b['x_m']:.2f}, {b['y_m']:.2f} m: {1000 * b['uncertainty_m']:.1f} mm" in p.stdout
    sel = cli.json("select", "--dem", tmp_path / "global.tif", "--rover", f"{b['x_m']!r},{b['y_m']!r}",
                   "--heading-deg", 90, "--pan-deg", "-90,90")
    t = sel["target"]
    assert f"sense the target at {t['x_m']:.2f}, {t['y_m']:.2f} m" in p.stdout


def test_readme_planner(cli, tmp_path):
    code = readme_block("python-planner")
    if "osgeo" in code:  # the README's version before it read the DTM with trn.read_raster
        pytest.importorskip("osgeo")
    run_planner(cli, tmp_path, code)


def test_package_readme_planner(cli, tmp_path):
    """python/README.md's planner: the README's example without osgeo."""
    code = package_readme_block("planner")
    assert "osgeo" not in code
    run_planner(cli, tmp_path, code)


def package_readme_block(marker):
    text = open(os.path.join(ROOT, "python", "README.md"), encoding="utf-8").read()
    at = text.index(f"<!-- python-example: {marker} -->")
    m = re.compile(r"```python\n(.*?)\n```", re.S).search(text, at)
    assert m, f"no ```python block after the {marker} marker"
    return m.group(1)


def test_package_readme_arrays(cli, tmp_path):
    """python/README.md's numpy example, run as written with GDAL made
    unavailable (it needs none); its target equals `trn select` on the same
    heights written to a GeoTIFF."""
    code = package_readme_block("arrays")
    (tmp_path / "example.py").write_text(code)
    env = dict(os.environ, TRN_GDAL_LIBRARY="/nonexistent/libgdal.so.99")
    p = subprocess.run([sys.executable, "example.py"], cwd=tmp_path, capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr
    assert "rover at 1004.80, 2004.80 m (ok)" in p.stdout
    ns = {}
    exec(compile(code, "example.py", "exec"), ns)  # the same heights, here (libgdal loads: the files below)
    import trn

    trn.write_raster(tmp_path / "g.tif", ns["heights"].astype("float32"), ns["gt"], "EPSG:32611")
    fix = ns["fix"]
    sel = cli.json("select", "--dem", tmp_path / "g.tif", "--rover", f"{fix['x_m']!r},{fix['y_m']!r}",
                   "--max-range-m", 3.0)
    t = sel["target"]
    assert f"sense the target at {t['x_m']:.2f}, {t['y_m']:.2f} m" in p.stdout
