# SPDX-License-Identifier: Apache-2.0
"""The Python package trn against the `trn` command line on the same inputs,
each bad-input class, the GIL released during C calls, and the field's
progress callback (issue 13 item 3)."""
import math
import threading
import time

import numpy as np
import pytest

import trn
from conftest import read

PRIOR = (1002.9, 2003.3)
ROVER = (1003.25, 2003.25)


def same(py, cli_json, skip=()):
    """Equal key for key (NaN == NaN), keys and nesting included."""
    assert set(py) - set(skip) == set(cli_json) - set(skip)
    for k in cli_json:
        if k not in skip:
            assert py[k] == cli_json[k], k


@pytest.fixture(scope="module")
def gmap(dems):
    a, gt, wkt = read(dems["global"])
    return trn.Map(a, transform=gt, crs=wkt)


# ---- equality with the command line -------------------------------------

def test_version(cli):
    assert trn.__version__ == trn.version()
    assert cli("--version").stdout.strip() == f"trn {trn.__version__}"


def test_localize_equals_cli(cli, dems, gmap):
    want = cli.json("localize", "--dem", dems["global"], "--local", dems["local"], "--prior", "1002.9,2003.3",
                    "--window-m", 0.5)
    a, gt, wkt = read(dems["local"])
    by_array = gmap.localize(a, prior=PRIOR, window_m=0.5, transform=gt, crs=wkt)
    by_path = trn.Map(dems["global"]).localize(dems["local"], prior=PRIOR, window_m=0.5)
    for got in (by_array, by_path):
        same(got, want, skip=("time_ms",))
    assert want["status"] == "ok"
    assert abs(want["x_m"] - dems["truth"][0]) < 0.05 and abs(want["y_m"] - dems["truth"][1]) < 0.05


def refused(gmap, a, gt, wkt, cases):
    """Each (keywords, reason): Map.localize of the array local map a (or of the file that the
    keywords' "local" names) with them raises TrnError matching the reason."""
    for kw, why in cases:
        args = {"local": a, "transform": gt, "crs": wkt, **kw}
        if isinstance(args["local"], str):
            args.pop("transform")
            args.pop("crs")
        with pytest.raises(trn.TrnError, match=why):
            gmap.localize(prior=PRIOR, window_m=0.5, **args)


def test_localize_centroids(cli, dems, gmap, tmp_path):
    """A binned local map's centroids given as arrays (centroids=(cx, cy)) equal the command
    line's --centroid-bands 2 on a 3-band file, key for key, and move the answer; each bad
    centroid input is refused."""
    gdal = pytest.importorskip("osgeo.gdal")
    a, gt, wkt = read(dems["local"])
    rng = np.random.default_rng(4)
    cx = rng.uniform(-0.4, 0.4, a.shape).astype(np.float32)
    cy = rng.uniform(-0.4, 0.4, a.shape).astype(np.float32)
    path = str(tmp_path / "local3.tif")
    ds = gdal.GetDriverByName("GTiff").Create(path, a.shape[1], a.shape[0], 3, gdal.GDT_Float32)
    ds.SetGeoTransform(gt)
    for k, band in enumerate((a, cx, cy)):
        ds.GetRasterBand(k + 1).WriteArray(band)
    ds = None
    want = cli.json("localize", "--dem", dems["global"], "--local", path, "--prior", "1002.9,2003.3",
                    "--window-m", 0.5, "--centroid-bands", 2)
    got = gmap.localize(a, prior=PRIOR, window_m=0.5, transform=gt, crs=wkt, centroids=(cx, cy))
    same(got, want, skip=("time_ms",))
    plain = gmap.localize(a, prior=PRIOR, window_m=0.5, transform=gt, crs=wkt)
    assert got["centroids"] is True and plain["centroids"] is False
    assert abs(got["x_m"] - plain["x_m"]) + abs(got["y_m"] - plain["y_m"]) > 1e-4
    # the local array's no-data value is the heights' alone: a centroid equal to it stays a centroid
    zero = np.zeros_like(cx)
    assert gmap.localize(a, prior=PRIOR, window_m=0.5, transform=gt, crs=wkt, nodata=0.0,
                         centroids=(zero, zero))["status"] == plain["status"]
    bad = cx.copy()
    bad[5, 7] = 0.7
    refused(gmap, a, gt, wkt, (({"local": dems["local"], "centroids": (cx, cy)}, "for an array local map"),
                               ({"centroids": (cx[:, :-1], cy)}, "band 2 is 31 x 32 cells"),
                               ({"centroids": (cx, cy), "centroid_bands": 2}, "give one of them"),
                               ({"centroids": cx}, "a pair of arrays"),
                               ({"centroids": (bad, cy)}, "more than 0.5 cells from its centre"),
                               ({"centroid_bands": 2}, "has 1 band, no band 2")))


def test_localize_counts(cli, dems, gmap, tmp_path):
    """A binned local map's point counts given as an array (counts=n), alone and beside the
    centroids, equal the command line's --count-band on a file of those bands, key for key;
    they change the covariance; each bad count input is refused."""
    gdal = pytest.importorskip("osgeo.gdal")
    a, gt, wkt = read(dems["local"])
    rng = np.random.default_rng(5)
    cx = rng.uniform(-0.4, 0.4, a.shape).astype(np.float32)
    cy = rng.uniform(-0.4, 0.4, a.shape).astype(np.float32)
    n = rng.integers(1, 9, a.shape).astype(np.float32)
    for bands, opts, kw in (((a, n), ("--count-band", 2), {"counts": n}),
                            ((a, cx, cy, n), ("--centroid-bands", 2, "--count-band", 4),
                             {"centroids": (cx, cy), "counts": n})):
        path = str(tmp_path / f"local{len(bands)}.tif")
        ds = gdal.GetDriverByName("GTiff").Create(path, a.shape[1], a.shape[0], len(bands), gdal.GDT_Float32)
        ds.SetGeoTransform(gt)
        for k, band in enumerate(bands):
            ds.GetRasterBand(k + 1).WriteArray(band)
        ds = None
        want = cli.json("localize", "--dem", dems["global"], "--local", path, "--prior", "1002.9,2003.3",
                        "--window-m", 0.5, *opts)
        got = gmap.localize(a, prior=PRIOR, window_m=0.5, transform=gt, crs=wkt, **kw)
        same(got, want, skip=("time_ms",))
        assert got["point_counts"] is True
    plain = gmap.localize(a, prior=PRIOR, window_m=0.5, transform=gt, crs=wkt)
    assert plain["point_counts"] is False and plain["cov_m2"] != got["cov_m2"]
    low = n.copy()
    low[5, 7] = 0.5
    refused(gmap, a, gt, wkt, (({"local": dems["local"], "counts": n}, "for an array local map"),
                               ({"counts": n[:, :-1]}, "band 2 is 31 x 32 cells"),
                               ({"counts": n, "count_band": 2}, "give one of them"),
                               ({"counts": low}, "point count 0.5 is missing or outside"),
                               ({"count_band": 2}, "has 1 band, no band 2")))


class AffineLike:
    """What rasterio's affine.Affine offers: to_gdal()."""

    def __init__(self, gt):
        self.gt = gt

    def to_gdal(self):
        return self.gt


def test_affine_transform(dems, gmap):
    a, gt, wkt = read(dems["global"])
    assert trn.Map(a, transform=AffineLike(gt), crs=wkt).select(rover=ROVER) == gmap.select(rover=ROVER)
    assert trn.Map(a, transform=gt, crs=32611).select(rover=ROVER) == gmap.select(rover=ROVER)


def test_localize_options_equal_cli(cli, dems, gmap):
    """Map options through keywords, and the prepared map re-made when they change; the
    heading search (issue 14) with the auto and the paper configurations."""
    a, gt, _ = read(dems["local"])
    for opts in ({"map_config": "paper"}, {}, {"map_config": "paper", "zbin_m": 0.05},
                 {"heading_window_deg": 6}, {"heading_deg": 2, "heading_window_deg": 4},
                 {"map_config": "paper", "heading_window_deg": 6}):
        args = []
        for k, v in opts.items():
            args += ["--" + k.replace("_", "-"), v]
        want = cli.json("localize", "--dem", dems["global"], "--local", dems["local"], "--prior", "1002.9,2003.3",
                        "--window-m", 0.5, *args)
        same(gmap.localize(a, prior=PRIOR, window_m=0.5, transform=gt, **opts), want, skip=("time_ms",))


def test_select_equals_cli(cli, dems, gmap):
    want = cli.json("select", "--dem", dems["global"], "--rover", "1003.25,2003.25")
    same(gmap.select(rover=ROVER), want)
    # options, and the prepared selection map re-made when they change and kept when they do not
    for opts, args in (({"heading_deg": 30, "pan_deg": (-60, 60), "next_best": 3},
                        ["--heading-deg", 30, "--pan-deg", "-60,60", "--next-best", 3]),
                       # the voxel prediction's eq. 8 sensing positions
                       ({"sensors": [(1000.5, 2000.5), (1006.0, 2006.0)], "max_range_m": 2.5, "map_config": "paper"},
                        ["--sensors", "1000.5,2000.5;1006.0,2006.0", "--max-range-m", 2.5, "--map-config", "paper"]),
                       ({"heading_sigma_deg": 2, "heading_search": 1},
                        ["--heading-sigma-deg", 2, "--heading-search", 1]),
                       # a rover that bins its points: the points it expects a cell
                       ({"points_per_cell": 4}, ["--points-per-cell", 4]),
                       ({}, [])):
        want = cli.json("select", "--dem", dems["global"], "--rover", "1003.25,2003.25", *args)
        same(gmap.select(rover=ROVER, **opts), want)


def test_select_out_map(cli, dems, gmap, tmp_path):
    out = tmp_path / "cand.tif"
    r = gmap.select(rover=ROVER, out_map=out)
    assert r["out_map"] == str(out)
    cand, _, _ = read(out)
    assert np.nanmin(cand) == pytest.approx(r["uncertainty_m"])
    cli_out = tmp_path / "cli_cand.tif"
    want = cli.json("select", "--dem", dems["global"], "--rover", "1003.25,2003.25", "--out-map", cli_out)
    same(r, want, skip=("out_map",))
    mem = gmap.select(rover=ROVER, candidate_map=True)
    same(mem, want, skip=("out_map", "candidate_map"))
    assert "out_map" not in mem
    np.testing.assert_array_equal(mem["candidate_map"], read(cli_out)[0])
    assert np.isposinf(mem["candidate_map"]).sum() == want["candidates"] - want["informative"]


def test_field_equals_cli(cli, dems, gmap, tmp_path):
    f = tmp_path / "f.tif"
    ev = tmp_path / "ev.tif"
    want = cli.json("field", "--dem", dems["global"], "--out", f, "--evaluated-out", ev,
                    "--area-m", "1001,2001,1005.5,2005")
    got = gmap.field(area=(1001, 2001, 1005.5, 2005))
    same(got, want, skip=("seconds", "file", "field", "evaluated"))
    assert got["file"] is None
    fa, _, _ = read(f)
    ea, _, _ = read(ev)
    assert got["field"].dtype == np.float32 and got["field"].shape == (64, 64)
    np.testing.assert_array_equal(got["field"], fa)
    np.testing.assert_array_equal(got["evaluated"], ea)
    assert np.nanmin(got["field"]) == pytest.approx(got["best"]["uncertainty_m"])
    # to a file of the caller's, the reference algorithm
    out = tmp_path / "mine.tif"
    ref = gmap.field(area=(1001, 2001, 1005.5, 2005), out=out, reference=True)
    assert ref["file"] == str(out) and ref["algorithm"] == "trn_field"
    np.testing.assert_array_equal(ref["field"], fa)


# ---- errors ---------------------------------------------------------------

def status_of(fn, *a, **k):
    with pytest.raises(trn.TrnError) as e:
        fn(*a, **k)
    assert e.value.message and "\n" not in e.value.message
    return e.value.status, e.value.message


def test_bad_arrays():
    gt = (0, 0.1, 0, 6.4, 0, -0.1)
    for bad in (np.zeros((4, 4, 2)), np.zeros(16), np.zeros((0, 4)), np.zeros((8, 8), complex),
                np.array([["a"] * 8] * 8)):
        assert status_of(trn.Map, bad, transform=gt)[0] == "bad_input"
    assert status_of(trn.Map, np.zeros((8, 8)), transform=(0, 0.1, 0, math.nan, 0, -0.1))[0] == "bad_input"
    assert status_of(trn.Map, np.zeros((8, 8)), transform=(0, 0.1, 0))[0] == "bad_input"
    assert status_of(trn.Map, np.zeros((8, 8)))[0] == "bad_input"  # no transform
    assert status_of(trn.Map, np.zeros((8, 8)), transform=gt, crs="EPSG:nope")[0] == "bad_input"
    assert status_of(trn.Map, "x.tif", transform=gt)[0] == "bad_input"  # a file has its own


GEO_WKT = ('GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],'
           'PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]]')


def test_geographic_crs(dems):
    """Refused when the DEM is read: EPSG:4326 through GDAL's check; a WKT
    naming a geographic CRS also without GDAL (tests/test_nogdal.py)."""
    a, gt, _ = read(dems["global"])
    for crs in ("EPSG:4326", GEO_WKT):
        m = trn.Map(a, transform=(-110.0, 1e-6, 0, 35.0, 0, -1e-6), crs=crs)
        st, msg = status_of(m.select, rover=(-109.99997, 34.99997))
        assert st == "bad_input" and "geographic" in msg and "map array" in msg


def test_numpy_arrays_equal_cli(cli, tmp_path):
    """Heights made in numpy (no file read): localize from the arrays gives
    `trn localize --json`'s answer on the same heights written to GeoTIFF."""
    rng = np.random.default_rng(7)
    y, x = np.mgrid[0:80, 0:80] * 0.1
    z = np.zeros((80, 80))
    for _ in range(40):  # rocks: Gaussian bumps 0.1-0.4 m high, 0.15-0.5 m wide
        cx, cy, h, s = rng.uniform(0, 8), rng.uniform(0, 8), rng.uniform(0.1, 0.4), rng.uniform(0.15, 0.5)
        z += h * np.exp(-((x - cx) ** 2 + (y - cy) ** 2) / (2 * s * s))
    z = z.astype(np.float32)
    gt = (500.0, 0.1, 0.0, 4008.0, 0.0, -0.1)
    local = np.ascontiguousarray(z[20:56, 30:66])  # rover at column 48, row 38: map (504.8, 4004.2)
    lgt = (-1.8, 0.1, 0.0, 1.8, 0.0, -0.1)
    trn.write_raster(tmp_path / "g.tif", z, gt, "EPSG:32633")
    trn.write_raster(tmp_path / "l.tif", local, lgt)
    want = cli.json("localize", "--dem", tmp_path / "g.tif", "--local", tmp_path / "l.tif",
                    "--prior", "504.95,4004.05", "--window-m", 0.5)
    got = trn.Map(z, transform=gt, crs="EPSG:32633").localize(local, prior=(504.95, 4004.05), window_m=0.5,
                                                              transform=lgt)
    same(got, want, skip=("time_ms",))
    assert want["status"] == "ok"
    assert abs(got["x_m"] - 504.8) < 0.05 and abs(got["y_m"] - 4004.2) < 0.05


def test_array_by_pointer():
    """A float32 C-order array is used in place (no copy), others are converted once."""
    a = np.zeros((8, 8), np.float32)
    m = trn.Map(a, transform=(0, 0.1, 0, 0.8, 0, -0.1))
    assert np.shares_memory(m._keep.array, a)
    m2 = trn.Map(np.zeros((8, 8)), transform=(0, 0.1, 0, 0.8, 0, -0.1))
    assert m2._keep.array.dtype == np.float32


def test_nodata_and_south_up(dems, gmap):
    """nodata means not seen, as a file's; a south-up array (dy > 0) is flipped as a file is."""
    a, gt, wkt = read(dems["global"])
    want = gmap.select(rover=ROVER)
    flipped = (gt[0], gt[1], 0.0, gt[3] + a.shape[0] * gt[5], 0.0, -gt[5])
    assert trn.Map(np.ascontiguousarray(a[::-1]), transform=flipped, crs=wkt).select(rover=ROVER) == want
    holes = a.copy()
    holes[:, :5] = -9999.0
    nan = a.copy()
    nan[:, :5] = np.nan
    assert (trn.Map(holes, transform=gt, crs=wkt, nodata=-9999.0).select(rover=ROVER)
            == trn.Map(nan, transform=gt, crs=wkt).select(rover=ROVER))


def test_read_write_raster(tmp_path):
    a = np.arange(12, dtype=np.float32).reshape(3, 4)
    a[1, 1] = np.inf
    gt = (10.0, 0.5, 0.0, 20.0, 0.0, -0.5)
    trn.write_raster(tmp_path / "r.tif", a, gt, 32611)
    b, gt2, wkt = trn.read_raster(tmp_path / "r.tif", raw=True)
    np.testing.assert_array_equal(a, b)
    assert gt2 == gt and "32611" in wkt
    c, _, _ = trn.read_raster(tmp_path / "r.tif")  # as a DEM: +inf is not seen
    assert np.isnan(c[1, 1]) and c[0, 1] == 1.0
    with pytest.raises(trn.TrnError):
        trn.read_raster(tmp_path / "missing.tif")


def test_missing_file(dems):
    st, msg = status_of(trn.Map("/nonexistent/dem.tif").select, rover=ROVER)
    assert st == "bad_input" and "/nonexistent/dem.tif" in msg
    st, _ = status_of(trn.Map(dems["global"]).localize, "/nonexistent/local.tif", prior=PRIOR)
    assert st == "bad_input"


def test_usage(gmap, dems):
    assert status_of(gmap.select, rover=ROVER, bogus=1) == ("usage", "unknown option '--bogus' (trn select --help)")
    assert status_of(gmap.field, no_such=True)[0] == "usage"
    assert status_of(gmap.localize, dems["local"], prior=PRIOR, help=True)[0] == "usage"
    assert status_of(gmap.select, rover=ROVER, json=True)[0] == "usage"


def test_values_out_of_range(gmap, dems):
    assert status_of(gmap.localize, dems["local"], prior=PRIOR, window_m=-1)[0] == "bad_input"
    st, msg = status_of(gmap.localize, dems["local"], prior=(0.0, 0.0))
    assert st == "bad_input" and "off the map" in msg
    assert status_of(gmap.select, rover=(0.0, 0.0))[0] == "bad_input"
    assert status_of(gmap.select, rover="a,b")[0] == "bad_input"
    assert status_of(gmap.select, rover=ROVER, pan_deg=(10, -10))[0] == "bad_input"
    assert status_of(gmap.select, rover=ROVER, heading_search=2)[0] == "bad_input"
    assert status_of(gmap.field, area=(1005, 2001, 1001, 2005))[0] == "bad_input"  # inverted
    assert status_of(gmap.field, area=(0, 0, 1, 1))[0] == "bad_input"  # off the map
    assert status_of(gmap.field, coarse_step_cells=3)[0] == "bad_input"


def test_no_result():
    flat = trn.Map(np.zeros((48, 48), np.float32), transform=(0, 0.1, 0, 4.8, 0, -0.1))
    assert status_of(flat.select, rover=(2.4, 2.4))[0] == "no_result"
    assert status_of(flat.field)[0] == "no_result"


def test_closed(dems):
    m = trn.Map(dems["global"])
    m.close()
    assert status_of(m.select, rover=ROVER)[0] == "bad_input"


# ---- progress, cancel, GIL ----------------------------------------------------

def test_progress(gmap):
    calls = []
    r = gmap.field(progress=lambda d, t: calls.append((d, t)))
    assert len(calls) >= r["evaluations"]
    done = [d for d, _ in calls]
    assert done == sorted(done) and calls[-1][0] == calls[-1][1]


def test_cancel(gmap):
    calls = []

    def stop(done, total):
        calls.append(done)
        return done >= 20

    st, _ = status_of(gmap.field, progress=stop)
    assert st == "cancelled" and calls[-1] == 20

    def boom(done, total):
        raise KeyError("from the callback")

    with pytest.raises(KeyError):
        gmap.field(progress=boom)
    assert gmap.field()["evaluations"] > 0  # the map still works


def test_gil_released(gmap):
    """A Python thread keeps running while one long field runs in C (no
    progress callback): its longest pause is far shorter than the call
    (holding the GIL, ctypes.PyDLL, it would be the whole call)."""
    stamps = []
    stop = threading.Event()

    def tick():
        while not stop.is_set():
            stamps.append(time.monotonic())
            time.sleep(0.001)

    th = threading.Thread(target=tick)
    th.start()
    time.sleep(0.05)
    t0 = time.monotonic()
    r = gmap.field(coarse_step_cells=2, reference=True)
    t1 = time.monotonic()
    stop.set()
    th.join()
    assert r["evaluations"] > 500
    inside = [s for s in stamps if t0 <= s <= t1]
    gaps = np.diff([t0] + inside + [t1])
    assert t1 - t0 > 0.2, "the field should take a while for this test to mean anything"
    assert len(inside) > 10 and gaps.max() < 0.25 * (t1 - t0)


def test_threads_on_separate_maps(dems):
    """Two maps in two threads give the answers of one thread."""
    want = trn.Map(dems["global"]).select(rover=ROVER)
    out = [None, None]

    def run(i):
        out[i] = trn.Map(dems["global"]).select(rover=ROVER)

    ths = [threading.Thread(target=run, args=(i,)) for i in range(2)]
    for t in ths:
        t.start()
    for t in ths:
        t.join()
    assert out == [want, want]


def test_parse_messages_in_threads(dems):
    """The parsers' messages are caught per call even when threads fail at once."""
    got = {}

    def run(i):
        m = trn.Map(dems["global"])
        msgs = set()
        for _ in range(30):
            try:
                m.select(rover=ROVER, **{f"bogus_{i}": 1})
            except trn.TrnError as e:
                msgs.add((e.status, e.message))
        got[i] = msgs

    ths = [threading.Thread(target=run, args=(i,)) for i in range(4)]
    for t in ths:
        t.start()
    for t in ths:
        t.join()
    for i in range(4):
        assert got[i] == {("usage", f"unknown option '--bogus-{i}' (trn select --help)")}
