# SPDX-License-Identifier: Apache-2.0
"""The package without libgdal: arrays work, files fail with a reason that
names the fix. Each check runs in a child Python whose TRN_GDAL_LIBRARY names
no library, so the C side cannot load GDAL, as on a machine without it (the
loader takes that variable alone when it is set: tools/trn/gdal_dl.c)."""
import json
import os
import subprocess
import sys
import textwrap

import pytest

import trn

NO_GDAL = dict(os.environ, TRN_GDAL_LIBRARY="/nonexistent/libgdal.so.99")


def child(code, env=NO_GDAL):
    p = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout.strip().splitlines()[-1])


ARRAYS = """
    import json, numpy as np, trn
    rng = np.random.default_rng(3)
    y, x = np.mgrid[0:64, 0:64] * 0.1
    z = np.zeros((64, 64))
    for _ in range(30):
        cx, cy, h, s = rng.uniform(0, 6.4), rng.uniform(0, 6.4), rng.uniform(0.1, 0.4), rng.uniform(0.15, 0.5)
        z += h * np.exp(-((x - cx) ** 2 + (y - cy) ** 2) / (2 * s * s))
    z = z.astype(np.float32)
    gt = (1000.0, 0.1, 0.0, 2006.4, 0.0, -0.1)
    m = trn.Map(z, transform=gt, crs="EPSG:32611")
    loc = m.localize(np.ascontiguousarray(z[16:48, 16:48]), prior=(1003.3, 2003.1), window_m=0.5,
                     transform=(-1.6, 0.1, 0.0, 1.6, 0.0, -0.1))
    sel = m.select(rover=(1003.25, 2003.25), candidate_map=True)
    f = m.field(area=(1001, 2001, 1005, 2005))
    out = {"gdal": trn.gdal_available()[0], "loc": loc, "sel": {k: v for k, v in sel.items() if k != "candidate_map"},
           "cand_finite": int(np.isfinite(sel["candidate_map"]).sum()),
           "field": {k: v for k, v in f.items() if k not in ("field", "evaluated", "seconds")},
           "field_min": float(np.nanmin(f["field"]))}
    loc.pop("time_ms")
    print(json.dumps(out))
"""


def test_arrays_without_gdal():
    """localize, select (with its candidate map) and field from arrays with
    GDAL unavailable give the answers they give with it."""
    without = child(ARRAYS)
    with_gdal = child(ARRAYS, env=dict(os.environ, TRN_GDAL_LIBRARY=""))
    assert without["gdal"] is False
    assert without["loc"]["status"] == "ok"
    assert abs(without["loc"]["x_m"] - 1003.2) < 0.05 and abs(without["loc"]["y_m"] - 2003.2) < 0.05
    assert without["cand_finite"] > 100
    if with_gdal["gdal"]:
        for k in ("loc", "sel", "field", "field_min", "cand_finite"):
            assert without[k] == with_gdal[k], k


def test_files_need_gdal():
    r = child("""
        import json, numpy as np, trn
        out = {}
        for what, call in (("map", lambda: trn.Map("dem.tif")),
                           ("read", lambda: trn.read_raster("dem.tif")),
                           ("write", lambda: trn.write_raster("x.tif", np.zeros((2, 2)), (0, 1, 0, 0, 0, -1))),
                           ("local", lambda: trn.Map(np.zeros((8, 8), np.float32), transform=(0, .1, 0, .8, 0, -.1))
                                              .localize("local.tif", prior=(0.4, 0.4)))):
            try:
                call()
                out[what] = None
            except trn.TrnError as e:
                out[what] = [e.status, e.message]
        print(json.dumps(out))
    """)
    for what in ("map", "read", "write", "local"):
        assert r[what] is not None, what
        status, msg = r[what]
        assert status == "bad_input" and "libgdal" in msg and "install" in msg and "TRN_GDAL_LIBRARY" in msg
        assert "\n" not in msg


def test_crs_rule_without_gdal():
    """Without GDAL a CRS text is not parsed (the grid is taken as metres),
    except that a WKT naming a geographic CRS is refused, and EPSG: wants a
    number."""
    r = child("""
        import json, numpy as np, trn
        geo = 'GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],UNIT["degree",0.01745]]'
        out = {}
        z = np.zeros((48, 48), np.float32)
        z[20:28, 20:28] = 0.5
        for name, crs in (("geo", geo), ("epsg_text", "EPSG:nope"), ("unknown", "EPSG:999999")):
            try:
                trn.Map(z, transform=(0, .1, 0, 4.8, 0, -.1), crs=crs).select(rover=(2.0, 2.0), min_range_m=0.3,
                                                                           max_range_m=1.5, patch_m=0.5)
                out[name] = "ok"
            except trn.TrnError as e:
                out[name] = e.message
        print(json.dumps(out))
    """)
    assert "geographic" in r["geo"]
    assert "code number" in r["epsg_text"]
    assert r["unknown"] == "ok"  # not checked without GDAL: the rule for metres applies


def test_main_gdal_flag():
    p = subprocess.run([sys.executable, "-m", "trn", "--gdal"], capture_output=True, text=True, env=NO_GDAL)
    assert p.returncode == 1 and p.stdout.startswith("gdal: no: ") and "install" in p.stdout
    p = subprocess.run([sys.executable, "-m", "trn", "--version"], capture_output=True, text=True)
    assert p.returncode == 0 and p.stdout.strip() == f"trn {trn.__version__}"


@pytest.mark.skipif(not trn.gdal_available()[0], reason="libgdal not installed")
def test_unknown_crs_with_gdal():
    import numpy as np

    with pytest.raises(trn.TrnError) as e:
        trn.Map(np.zeros((8, 8), np.float32), transform=(0, .1, 0, .8, 0, -.1), crs="EPSG:999999")
    assert e.value.status == "bad_input" and "EPSG:999999" in e.value.message
