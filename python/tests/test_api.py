# SPDX-License-Identifier: Apache-2.0
"""The typed API: the TypedDicts declare every key the command line writes
(and the results carry the required ones), the docstrings list every option
of the --help tables with its default, progress=True draws a tqdm bar, and
xarray in and out (skipped where tqdm or xarray are not installed)."""
import typing

import numpy as np
import pytest

import trn
from trn import types as tt
from conftest import read

ROVER = (1003.25, 2003.25)
PRIOR = (1002.9, 2003.3)


def keys(td):
    """(required, optional) keys of a TypedDict."""
    return set(td.__required_keys__), set(td.__optional_keys__)


def check(td, d, path="", added=()):
    """d has td's required keys (but those the package adds to the command's
    JSON) and no key td does not declare; nested dicts likewise."""
    req, opt = keys(td)
    assert req - set(added) <= set(d), (path, req - set(added) - set(d))
    assert set(d) <= req | opt, (path, set(d) - req - opt)
    hints = typing.get_type_hints(td)
    for k, v in d.items():
        h = hints.get(k)
        if isinstance(h, type) and hasattr(h, "__required_keys__") and isinstance(v, dict):
            check(h, v, f"{path}.{k}")
        elif typing.get_origin(h) is list and typing.get_args(h) and hasattr(typing.get_args(h)[0], "__required_keys__"):
            for item in v:
                check(typing.get_args(h)[0], item, f"{path}.{k}[]")


def test_typeddicts_cover_cli_json(cli, dems):
    """Every key of `trn <cmd> --json` is declared (a key added in C must be
    added in python/trn/_types.py too) and every required one is there."""
    check(tt.LocalizeResult, cli.json("localize", "--dem", dems["global"], "--local", dems["local"],
                                      "--prior", "1002.9,2003.3", "--window-m", 0.5))
    check(tt.LocalizeResult, cli.json("localize", "--dem", dems["global"], "--local", dems["local"],
                                      "--prior", "1002.9,2003.3", "--window-m", 0.5, "--heading-window-deg", 4))
    check(tt.SelectResult, cli.json("select", "--dem", dems["global"], "--rover", "1003.25,2003.25"))
    check(tt.FieldResult, cli.json("field", "--dem", dems["global"], "--out", dems["dir"] / "f_api.tif",
                                   "--area-m", "1001,2001,1005.5,2005"), added=("field", "evaluated"))


def test_results_match_typeddicts(dems):
    m = trn.Map(dems["global"])
    a, gt, _ = read(dems["local"])
    check(tt.LocalizeResult, m.localize(a, prior=PRIOR, window_m=0.5, transform=gt))
    check(tt.SelectResult, m.select(rover=ROVER, candidate_map=True))
    check(tt.FieldResult, m.field(area=(1001, 2001, 1005.5, 2005)))


@pytest.mark.parametrize("cmd, method", [("localize", trn.Map.localize), ("select", trn.Map.select),
                                         ("field", trn.Map.field)])
def test_docstrings_list_options(cmd, method):
    doc = method.__doc__
    table = trn.options(cmd)
    assert len(table) > 10
    taken = {"dem", "band", "local", "prior", "rover", "area_m", "json"}
    for o in table:
        kw = o["name"].lstrip("-").replace("-", "_")
        if kw in taken:
            continue
        line = next((ln for ln in doc.splitlines() if ln.strip().startswith(kw + "=")), None)
        assert line is not None, kw
        assert o["help"] in line
        if o["default"]:
            assert f"default {o['default']}" in line
    with pytest.raises(trn.TrnError):
        trn.options("nope")


def test_window_default_from_table():
    w = next(o for o in trn.options("localize") if o["name"] == "--window-m")
    assert w["default"] == "2.5" and "metres" in w["help"] and w["range"] == "0..1e+06"


def test_progress_tqdm(dems, capsys):
    pytest.importorskip("tqdm")
    m = trn.Map(dems["global"])
    r = m.field(area=(1001, 2001, 1005.5, 2005), progress=True)
    err = capsys.readouterr().err
    n = r["cells"]  # the progress counts the area's cells (computed or interpolated)
    assert "trn field" in err and f"{n}/{n}" in err


def test_progress_bad():
    m = trn.Map(np.zeros((48, 48), np.float32), transform=(0, 0.1, 0, 4.8, 0, -0.1))
    with pytest.raises(trn.TrnError) as e:
        m.field(progress="yes")
    assert e.value.status == "bad_input"


def dataarray(dems, south_up=False):
    xr = pytest.importorskip("xarray")
    a, gt, wkt = read(dems["global"])
    x = gt[0] + (np.arange(a.shape[1]) + 0.5) * gt[1]
    y = gt[3] + (np.arange(a.shape[0]) + 0.5) * gt[5]
    if south_up:
        a, y = a[::-1], y[::-1]
        gt = (gt[0], gt[1], 0.0, gt[3] + a.shape[0] * gt[5], 0.0, -gt[5])
    da = xr.DataArray(a, dims=("y", "x"), coords={"y": y, "x": x})
    try:
        import rioxarray  # noqa: F401
        from affine import Affine

        da = da.rio.write_crs(wkt).rio.write_transform(Affine.from_gdal(*gt))
    except ImportError:  # the CF coordinate rioxarray would write
        da = da.assign_coords(spatial_ref=xr.DataArray(0, attrs={"crs_wkt": wkt,
                                                                 "GeoTransform": " ".join(map(repr, gt))}))
    return da


def test_transform_from_coords():
    """Without a GeoTransform, from the cell centres (to rounding)."""
    x = 1000.0 + (np.arange(64) + 0.5) * 0.1
    y = 2006.4 - (np.arange(48) + 0.5) * 0.1
    gt = trn._transform_from_coords(x, y)
    assert gt == pytest.approx((1000.0, 0.1, 0.0, 2006.4, 0.0, -0.1), abs=1e-9)
    with pytest.raises(trn.TrnError):
        trn._transform_from_coords(np.array([0.0, 1.0, 3.0]), y)


@pytest.mark.parametrize("south_up", [False, True])
def test_from_xarray(dems, south_up):
    da = dataarray(dems, south_up)
    a, gt, wkt = read(dems["global"])
    m = trn.Map.from_xarray(da)
    assert m.select(rover=ROVER) == trn.Map(a, transform=gt, crs=wkt).select(rover=ROVER)
    f = m.field_dataarray(area=(1001, 2001, 1005.5, 2005))
    assert f.dims == da.dims and np.array_equal(f["x"], da["x"]) and np.array_equal(f["y"], da["y"])
    want = trn.Map(a, transform=gt, crs=wkt).field(area=(1001, 2001, 1005.5, 2005))["field"]
    np.testing.assert_array_equal(f.values[::-1] if south_up else f.values, want)
    assert f.attrs["units"] == "m" and "best" in f.attrs["trn"]


def test_field_dataarray_from_array(dems):
    pytest.importorskip("xarray")
    a, gt, wkt = read(dems["global"])
    f = trn.Map(a, transform=gt, crs=wkt).field_dataarray(area=(1001, 2001, 1005.5, 2005))
    assert f.shape == a.shape and f["x"][0] == pytest.approx(gt[0] + 0.5 * gt[1])
    assert f["y"][0] == pytest.approx(gt[3] + 0.5 * gt[5]) and "evaluated" in f.coords
