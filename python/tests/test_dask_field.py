# SPDX-License-Identifier: Apache-2.0
"""The tiled field on Dask (python/trn/dask_field.py, issue 13 item 4): equal
bit for bit to the whole map's field (every position evaluated) at 1024 x
1024 on a LocalCluster of two worker processes; a halo below the reach
changes it; the global map's sensing positions are the whole map's, in map
metres; the output is a tiled DEFLATE GeoTIFF on the DTM's grid; bad input.

Fast field settings (ranges 0.5-1 m, 0.3 m patches, 0.2 m footprint) keep the
1024^2 field, evaluated at every one of its 1,048,576 positions, near a minute
on two cores; the tiling, halo and sensors are exercised all the same."""
import math

import numpy as np
import pytest

import trn

pytest.importorskip("distributed")  # trn[dask]; not in the clean venv of 47-python-venv.sh
pytest.importorskip("osgeo")  # read() below checks the GeoTIFF's tiling with GDAL's bindings

from trn import dask_field  # noqa: E402
from trn.dask_field import halo_cells, plan_tiles, tiled_field  # noqa: E402

# Debian's tornado 6.2 under distributed 2022.12 warns at every LocalCluster start
pytestmark = pytest.mark.filterwarnings("ignore:make_current is deprecated:DeprecationWarning")

FAST = dict(min_range_m=0.5, max_range_m=1.0, patch_m=0.3, footprint_m=0.2)


@pytest.fixture(scope="module")
def client():
    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    c = Client(cluster)
    yield c
    c.close()
    cluster.close()


@pytest.fixture(scope="module")
def t256(cli, tmp_path_factory):
    d = tmp_path_factory.mktemp("dask256")
    p = str(d / "t256.tif")
    cli("terrain", "--out", p, "--size-cells", 256, "--origin", "1000,2000", "--seed", 5, "--crs", "EPSG:32611")
    return p


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


def read(path):
    from osgeo import gdal

    ds = gdal.Open(str(path))
    b = ds.GetRasterBand(1)
    return {"a": b.ReadAsArray(), "gt": ds.GetGeoTransform(), "wkt": ds.GetProjection(),
            "nodata": b.GetNoDataValue(), "block": b.GetBlockSize(),
            "compression": ds.GetMetadata("IMAGE_STRUCTURE").get("COMPRESSION")}


def whole(path, **opts):
    # the tiled field takes the paper's configuration (the voxel prediction)
    with trn.Map(path) as m:
        return m.field(coarse_step_cells=1, map_config="paper", **FAST, **opts)


# ---- the plan ------------------------------------------------------------------

def test_halo_and_plan():
    # 0.1 m cells, 1 m range: reach 11, half patch 1, pose 1, eq. 9 and eq. 8 2 x 2 x 34, 1, high-pass 10
    assert halo_cells(0.1, 1.0, 0.3) == 11 + 1 + 1 + 136 + 1 + 10
    assert halo_cells(0.1) == 101 + 10 + 1 + 136 + 1 + 10  # trn field's defaults: 10 m, 2 m patches
    tiles = plan_tiles(100, 70, 32, 5)
    assert len(tiles) == 4 * 3
    cover = np.zeros((70, 100), int)
    for t in tiles:
        c0, r0, c1, r1 = t.core
        cover[r0:r1, c0:c1] += 1
        assert t.read == (max(0, c0 - 5), max(0, r0 - 5), min(100, c1 + 5), min(70, r1 + 5))
    assert (cover == 1).all()  # every cell in exactly one core


# ---- equality ------------------------------------------------------------------

def test_tiled_equals_whole_1024(cli, client, tmp_path):
    dtm = str(tmp_path / "t1024.tif")
    cli("terrain", "--out", dtm, "--size-cells", 1024, "--origin", "1000,2000", "--seed", 5, "--crs", "EPSG:32611")
    out = tmp_path / "tiled.tif"
    r = tiled_field(dtm, out, tile=256, client=client, **FAST)
    w = whole(dtm)
    assert r["tiles"] == 16 and r["cells"] == 1024 * 1024 == r["evaluations"] == w["evaluations"]
    assert r["outlier_density_per_m"] == w["outlier_density_per_m"]
    f = read(out)
    assert np.isfinite(w["field"]).sum() > 100000 and np.isinf(w["field"]).sum() > 1000  # both kinds present
    assert np.array_equal(bits(f["a"]), bits(w["field"]))  # bit for bit, +inf included
    src = read(dtm)
    assert f["gt"] == src["gt"] and f["wkt"] == src["wkt"]
    assert f["compression"] == "DEFLATE" and f["block"] == [256, 256] and math.isnan(f["nodata"])


def test_too_small_halo_differs(client, t256, tmp_path):
    w = whole(t256)["field"]
    reach_only = 11 + 1 + 1  # candidate centres and their patches, without the maps' own reach
    small = tiled_field(t256, tmp_path / "small.tif", tile=64, halo=reach_only, client=client, **FAST)
    assert small["halo"] == reach_only
    a = read(tmp_path / "small.tif")["a"]
    assert not np.array_equal(bits(a), bits(w))
    full = tiled_field(t256, tmp_path / "full.tif", tile=64, client=client, **FAST)
    assert np.array_equal(bits(read(tmp_path / "full.tif")["a"]), bits(w))


def test_area_and_sensors_in_map_metres(client, t256, tmp_path):
    area = (1003.0, 2004.0, 1019.0, 2015.0)
    sensors = [(1001.0, 2001.0), (1024.0, 2024.0)]  # two corners of the map, none at a tile's centre
    w = whole(t256, area=area, sensors=sensors)
    r = tiled_field(t256, tmp_path / "s.tif", tile=48, area=area, sensors=sensors, client=client, **FAST)
    assert r["tiles"] > 4 and r["sensors"] == sensors
    a = read(tmp_path / "s.tif")["a"]
    assert np.array_equal(bits(a), bits(w["field"]))
    assert np.isnan(a).sum() == 256 * 256 - r["cells"]  # NaN outside the area
    # the sensors matter: the default (the whole DTM's centre, given to every tile) is another field,
    # equal to the whole map's default
    d = tiled_field(t256, tmp_path / "d.tif", tile=48, area=area, client=client, **FAST)
    b = read(tmp_path / "d.tif")["a"]
    assert not np.array_equal(bits(a), bits(b))
    assert len(d["sensors"]) == 1 and d["sensors"][0] == pytest.approx((1012.8, 2012.8), abs=1e-9)
    assert np.array_equal(bits(b), bits(whole(t256, area=area)["field"]))


# ---- bad input -------------------------------------------------------------------

@pytest.mark.parametrize("kw, status, text", [
    ({"tile": 8}, "bad_input", "at least 16"),
    ({"tile": 64.0}, "bad_input", "integer"),
    ({"halo": -1}, "bad_input", "halo"),
    ({"tile": 4000, "halo": 100}, "bad_input", "smaller tile"),
    ({"coarse_step_cells": 16}, "usage", "coarse_step_cells"),
    ({"map_config": "auto"}, "bad_input", "paper"),
    ({"area": (0, 0, 1, 1)}, "bad_input", "no cell centre"),
    ({"area": (1010, 2010, 1005, 2015)}, "bad_input", "X0 <= X1"),
    ({"out": "/nonexistent-dir/x.tif"}, "bad_input", "no such folder"),
])
def test_bad_input(t256, tmp_path, kw, status, text):
    kw = dict(kw)
    out = kw.pop("out", tmp_path / "x.tif")
    with pytest.raises(trn.TrnError) as e:
        tiled_field(t256, out, client=object(), **kw)  # refused before any task
    assert e.value.status == status and text in e.value.message


def test_missing_file(tmp_path):
    with pytest.raises(trn.TrnError) as e:
        tiled_field(tmp_path / "missing.tif", tmp_path / "x.tif", client=object())
    assert e.value.status == "bad_input" and "no such file" in e.value.message
    with pytest.raises(trn.TrnError) as e:
        dask_field.whole_map_outlier_density(tmp_path / "missing.tif")
    assert "no such file" in e.value.message


def test_array_equals_file(client, t256):
    """A DTM given as a numpy array (each task handed its window, no file
    read): the same field, returned as an array when out is None."""
    a, gt, wkt = trn.read_raster(t256)
    r = tiled_field(a, None, transform=gt, crs=wkt, tile=64, client=client, **FAST)
    assert r["file"] is None and r["tiles"] == 16
    assert np.array_equal(bits(r["field"]), bits(whole(t256)["field"]))


def test_scheduler_address(client, t256, tmp_path):
    """The same code against a scheduler given by its address (as a multi-machine one would be)."""
    area = (1005.0, 2005.0, 1015.0, 2015.0)
    r = tiled_field(t256, tmp_path / "a.tif", tile=64, area=area, scheduler=client.scheduler.address, **FAST)
    assert r["tiles"] == 4
    assert np.array_equal(bits(read(tmp_path / "a.tif")["a"]), bits(whole(t256, area=area)["field"]))
