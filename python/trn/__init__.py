# SPDX-License-Identifier: Apache-2.0
"""trn: terrain matching and landmark selection (after Olson, ICRA 2000) from Python.

A thin layer over libtrn_run.so (python/trn_py.c), the run layer of the `trn`
command line built as a shared library and loaded with ctypes:

    import numpy as np, trn
    m = trn.Map(heights, transform=gt, crs="EPSG:32611")  # a 2-D numpy array
    m = trn.Map("global.tif")                        # or any raster GDAL reads
    m = trn.Map.from_xarray(da)                      # or a rioxarray DataArray
    m.localize(local, prior=(x, y), transform=lgt)   # local: array (rover frame) or path
    m.select(rover=(x, y))
    m.field(area=(x0, y0, x1, y1), progress=True)    # a tqdm bar, or a callback

Results are dicts (TypedDicts in trn.types) with the keys and units of
`trn <cmd> --json` (they are written by the same JSON writer, in C).
Options are the command's options as keywords: `--pan-deg -30,30` is
`pan_deg=(-30, 30)`, `--map-config paper` is `map_config="paper"`, a flag is
`reference=True`; each method's docstring lists them with units and defaults,
from the same tables as `trn <cmd> --help`. Errors raise TrnError with
.status: "bad_input", "usage" (an unknown keyword, a missing value),
"no_result" (no informative target) or "cancelled" (the progress callback
stopped a field).

Arrays need no GDAL: a numpy array reaches the C run layer by pointer (as an
in-memory raster, with its geotransform, no-data value and CRS text), so the
package works in a plain venv without GDAL's Python bindings and without
libgdal. Files (and GeoTIFF outputs, and the CRS check) go through libgdal on
the C side, loaded when first needed; without it they fail with a TrnError
that says how to install it (gdal_available() tells beforehand). Without
libgdal the CRS text of an array is not parsed: its geotransform and heights
must be in metres (a projected CRS in metres, e.g. UTM, or none for a
rover-frame map); only a WKT naming a geographic or geocentric CRS is refused.

Threads: ctypes releases the GIL for the whole C call, so other Python threads
run while a localization, selection or field runs; the progress callback
takes the GIL back for each call. One Map serialises its own calls (a lock);
use one Map per thread to run in parallel.
"""
from __future__ import annotations

import ctypes
import importlib
import json
import math
import os
import threading
import weakref
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union, cast

import numpy as np
import numpy.typing as npt

from . import _lib as _L
from ._types import (CrsLike, FieldResult, LocalizeResult, Raster, RasterRead, SelectResult, Transform)

__all__ = ["Map", "TrnError", "version", "__version__", "gdal_available", "read_raster", "write_raster",
           "options", "LocalizeResult", "SelectResult", "FieldResult"]

_lib = _L.lib
_STATUS = {1: "bad_input", 2: "usage", 3: "no_result"}

#: What a progress= argument may be: True (a tqdm bar), or a callable
#: progress(done, total) whose true return value stops the field.
Progress = Union[bool, Callable[[int, int], Any], None]
#: A raster source: a path (str or os.PathLike) or a 2-D array of heights.
Source = Union[str, "os.PathLike[str]", npt.ArrayLike]


class TrnError(Exception):
    """A failed call: .status is the status name ("bad_input", "usage",
    "no_result", "cancelled"), .message the one-line reason (the text `trn
    <cmd>: <reason>` would print)."""

    def __init__(self, status: str, message: str) -> None:
        super().__init__(f"{status}: {message}")
        self.status = status
        self.message = message


__version__: str = _lib.trn_py_version().decode()


def version() -> str:
    """The library's version (the `version` of every result; `trn --version`)."""
    return __version__


def gdal_available() -> Tuple[bool, str]:
    """(True, "") when GDAL's C library (libgdal) loads, so files can be read
    and written; else (False, the reason, which says how to install it).
    Arrays never need it."""
    err = ctypes.create_string_buffer(_L.ERR_LEN)
    ok = _lib.trn_py_gdal(err, _L.ERR_LEN) == 0
    return ok, "" if ok else err.value.decode(errors="replace")


def _need_gdal(what: str) -> None:
    ok, why = gdal_available()
    if not ok:
        raise TrnError("bad_input", f"{what}: {why}")


# ---- options: keywords -> the command's argv -------------------------------

def _num(v: Any) -> str:
    if isinstance(v, bool):
        raise TrnError("bad_input", f"expected a number, got {v!r}")
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    try:
        return repr(float(v))  # shortest round trip, as the CLI reads it with strtod
    except (TypeError, ValueError) as e:
        raise TrnError("bad_input", f"expected a number, got {v!r}") from e


def _value(v: Any) -> str:
    """One keyword's value as the command line's text."""
    if isinstance(v, str):
        return v
    if isinstance(v, os.PathLike):
        return str(os.fspath(v))
    if isinstance(v, (list, tuple, np.ndarray)):
        items = list(v)
        if items and all(isinstance(i, (list, tuple, np.ndarray)) for i in items):  # sensors: [(x, y), ...]
            return ";".join(",".join(_num(c) for c in i) for i in items)
        return ",".join(_num(i) for i in items)
    return _num(v)


def _argv(cmd: str, opts: Dict[str, Any]) -> List[str]:
    """["cmd", "--opt", "value", ...]; True is a flag, False and None are left out."""
    argv = [cmd]
    for key, v in opts.items():
        if v is None or v is False:
            continue
        if not isinstance(key, str) or not key or key.startswith("_") or key in ("help", "json"):
            raise TrnError("usage", f"unknown option {key!r}")
        argv.append("--" + key.replace("_", "-"))
        if v is not True:
            argv.append(_value(v))
    return argv


def _key(argv: List[str], per_call: set[str], defaults: Optional[Dict[str, str]] = None) -> str:
    """What a preparation depends on: every option except the per-call ones,
    with the defaults that differ between commands (select's stride 1,
    field's 2) written out, so select and field share a map only when it is
    the same."""
    out: List[str] = []
    seen = set()
    i = 1
    while i < len(argv):
        name = argv[i]
        has_value = i + 1 < len(argv) and not argv[i + 1].startswith("--")
        val = argv[i + 1] if has_value else ""
        if name not in per_call:
            out.append(name + "\x1f" + val)
            seen.add(name)
        i += 2 if has_value else 1
    out += [name + "\x1f" + val for name, val in (defaults or {}).items() if name not in seen]
    return "\x1e".join(sorted(out))


# ---- arrays -> in-memory rasters (by pointer, no GDAL) ---------------------

def _geotransform(transform: Any) -> Transform:
    """A GDAL geotransform (6 numbers) or an affine.Affine-like object (to_gdal())."""
    if transform is None:
        raise TrnError("bad_input", "an array needs transform= (a GDAL geotransform or an affine transform)")
    if hasattr(transform, "to_gdal"):
        transform = transform.to_gdal()
    try:
        gt = [float(v) for v in transform]
    except (TypeError, ValueError) as e:
        raise TrnError("bad_input", f"transform: not 6 numbers ({e})") from e
    if len(gt) != 6 or not all(math.isfinite(v) for v in gt):
        raise TrnError("bad_input", f"transform: want 6 finite numbers (GDAL order x0, dx, 0, y0, 0, -dy), got {gt}")
    return (gt[0], gt[1], gt[2], gt[3], gt[4], gt[5])


def _crs_text(crs: CrsLike) -> Optional[str]:
    """The CRS as text for the C side: None/"" none; an int is EPSG:n; an
    object with to_wkt() (pyproj, rasterio) its WKT; a string as given
    ("EPSG:n", WKT, PROJ). An "EPSG:" text must end in a number."""
    if crs is None:
        return None
    if isinstance(crs, bool):
        raise TrnError("bad_input", f"crs {crs!r}: want EPSG:n, WKT, an EPSG number or a CRS object")
    if isinstance(crs, (int, np.integer)):
        return f"EPSG:{int(crs)}"
    if not isinstance(crs, str):
        to_wkt = getattr(crs, "to_wkt", None)
        if to_wkt is None:
            raise TrnError("bad_input", f"crs {crs!r}: want EPSG:n, WKT, an EPSG number or a CRS object")
        crs = str(to_wkt())
    text = crs.strip()
    if text.upper().startswith("EPSG:") and not text[5:].strip().isdigit():
        raise TrnError("bad_input", f"crs {crs!r}: EPSG: wants a code number (EPSG:32611)")
    return text or None


def _check_array(a: Any) -> npt.NDArray[np.float32]:
    arr = np.asarray(a)
    if arr.ndim != 2 or arr.shape[0] < 1 or arr.shape[1] < 1:
        raise TrnError("bad_input", f"heights: want a 2-D array (rows, columns), got shape {arr.shape}")
    if arr.dtype.kind not in "fiub":
        raise TrnError("bad_input", f"heights: want real numbers (float or int), got dtype {arr.dtype}")
    # float32 and C order: no copy when it already is
    return np.ascontiguousarray(arr, dtype=np.float32)


def _cbuf(s: Optional[str]) -> Optional[bytes]:
    return None if s is None else s.encode()


def _drop(name: bytes, keep: Any) -> None:
    """Forget an in-memory raster; keep (its array) lives until then."""
    _lib.trn_py_raster_drop(name)


class _MemRaster:
    """A 2-D array registered with the C side (trn_py_raster_put) under a
    name "trn-mem:N" the commands take in place of a path. The heights are
    handed by pointer (float32, C order: copied only when the array is not),
    and kept alive here until the name is dropped (close, or collection).
    extra: more bands of the same shape after the heights (bands 2, 3, ...;
    the no-data value is the heights' alone); the bands are then copied into
    one (bands, rows, columns) array."""

    def __init__(self, heights: Any, transform: Any, crs: CrsLike, nodata: Optional[float], label: str,
                 extra: Sequence[Any] = ()) -> None:
        a = _check_array(heights)
        bands = 1 + len(extra)
        if extra:
            more = [_check_array(b) for b in extra]
            for k, b in enumerate(more):
                if b.shape != a.shape:
                    raise TrnError("bad_input", f"{label}: band {k + 2} is {b.shape[1]} x {b.shape[0]} cells, "
                                                f"the heights {a.shape[1]} x {a.shape[0]}")
            a = np.ascontiguousarray(np.stack([a] + more), dtype=np.float32)
        gt = _geotransform(transform)
        text = _crs_text(crs)
        if nodata is not None:
            try:
                nd = float(nodata)
            except (TypeError, ValueError) as e:
                raise TrnError("bad_input", f"nodata {nodata!r}: want a number") from e
        else:
            nd = 0.0
        gtc = (ctypes.c_double * 6)(*gt)
        name = ctypes.create_string_buffer(_L.NAME_LEN)
        err = ctypes.create_string_buffer(_L.ERR_LEN)
        rc = _lib.trn_py_raster_put(a.ctypes.data_as(_L.F32P), a.shape[-1], a.shape[-2], bands, gtc,
                                    1 if nodata is not None else 0, nd, _cbuf(text), label.encode(), name,
                                    _L.NAME_LEN, err, _L.ERR_LEN)
        if rc != 0:
            raise TrnError(_STATUS.get(rc, "bad_input"), err.value.decode(errors="replace"))
        self.path = name.value.decode()
        self.array = a
        self.transform = gt
        self.crs = text
        self._done = weakref.finalize(self, _drop, name.value, a)

    def close(self) -> None:
        self._done()


def _raster_source(src: Any, transform: Any, crs: CrsLike, nodata: Optional[float], what: str,
                   label: str, extra: Sequence[Any] = ()) -> Tuple[str, Optional[_MemRaster]]:
    """(path or in-memory name, the registration to keep alive); extra: more
    bands for an array (_MemRaster)."""
    if isinstance(src, (str, os.PathLike)):
        if transform is not None or crs is not None:
            raise TrnError("bad_input", f"{what}: transform and crs are for arrays; a file carries its own")
        _need_gdal(f"{what} {os.fspath(src)!s}")
        return str(os.fspath(src)), None
    r = _MemRaster(src, transform, crs, nodata, label, extra)
    return r.path, r


def _new_name() -> str:
    name = ctypes.create_string_buffer(_L.NAME_LEN)
    _lib.trn_py_raster_name(name, _L.NAME_LEN)
    return name.value.decode()


def _read(path: str, band: int, raw: bool) -> RasterRead:
    data = ctypes.c_void_p()
    crs = ctypes.c_void_p()
    w, h = ctypes.c_int(), ctypes.c_int()
    gt = (ctypes.c_double * 6)()
    err = ctypes.create_string_buffer(_L.ERR_LEN)
    rc = _lib.trn_py_raster_read(path.encode(), int(band), 1 if raw else 0, ctypes.byref(data), ctypes.byref(w),
                                 ctypes.byref(h), gt, ctypes.byref(crs), err, _L.ERR_LEN)
    if rc != 0:
        raise TrnError(_STATUS.get(rc, "bad_input"), err.value.decode(errors="replace"))
    try:
        n = w.value * h.value
        buf = ctypes.string_at(cast(int, data.value), n * 4)  # the C side's float32 buffer, copied
        a = np.frombuffer(buf, dtype=np.float32, count=n).reshape(h.value, w.value).copy()
        wkt = ctypes.string_at(crs.value).decode() if crs.value is not None else None
    finally:
        _lib.trn_py_free(data)
        _lib.trn_py_free(crs)
    return a, (gt[0], gt[1], gt[2], gt[3], gt[4], gt[5]), wkt


def _take(name: str) -> Raster:
    """An output the run wrote to the in-memory name, then forgotten."""
    try:
        return _read(name, 1, True)[0]
    finally:
        _lib.trn_py_raster_drop(name.encode())


def read_raster(path: Union[str, "os.PathLike[str]"], band: int = 1, raw: bool = False) -> RasterRead:
    """(heights, geotransform, CRS WKT or None) of band `band` of a raster
    file, read by the C side with libgdal. raw=False: as the commands read a
    DEM (metres, north-up, no-data and fillers as NaN; at most 4096 cells a
    side); raw=True: the values as stored (what field and select write, +inf
    kept). Raises TrnError (bad_input) when GDAL is missing, with the fix."""
    p = str(os.fspath(path))
    _need_gdal(f"read {p}")
    return _read(p, band, raw)


def write_raster(path: Union[str, "os.PathLike[str]"], heights: npt.ArrayLike, transform: Any,
                 crs: CrsLike = None) -> None:
    """Write a 2-D array as a one-band float32 GeoTIFF (DEFLATE, no-data NaN)
    with the C side's writer (the one `trn field --out` uses), through
    libgdal. transform: a GDAL geotransform or an affine.Affine; crs: EPSG:n,
    WKT, an EPSG number, a CRS object, or None."""
    p = str(os.fspath(path))
    _need_gdal(f"write {p}")
    a = _check_array(heights)
    gt = (ctypes.c_double * 6)(*_geotransform(transform))
    text = _crs_text(crs)
    err = ctypes.create_string_buffer(_L.ERR_LEN)
    if text is not None:  # as WKT, through GDAL
        w = ctypes.c_void_p()
        if _lib.trn_py_crs_wkt(text.encode(), ctypes.byref(w), err, _L.ERR_LEN) != 0:
            raise TrnError("bad_input", err.value.decode(errors="replace"))
        try:
            text = ctypes.string_at(cast(int, w.value)).decode()
        finally:
            _lib.trn_py_free(w)
    rc = _lib.trn_py_raster_write(p.encode(), a.ctypes.data_as(_L.F32P), a.shape[1], a.shape[0], gt,
                                  _cbuf(text), err, _L.ERR_LEN)
    if rc != 0:
        raise TrnError(_STATUS.get(rc, "bad_input"), err.value.decode(errors="replace"))


# ---- option tables (the --help of each command) ---------------------------

def options(cmd: str) -> List[Dict[str, Any]]:
    """The option table of `trn <cmd> --help` (cmd: localize, select or
    field): one dict per option with name ("--window-m"), kind, metavar,
    help, default and range (the texts --help shows; "" when none) and
    required."""
    out = ctypes.c_void_p()
    err = ctypes.create_string_buffer(_L.ERR_LEN)
    rc = _lib.trn_py_options(cmd.encode(), ctypes.byref(out), err, _L.ERR_LEN)
    if rc != 0:
        raise TrnError(_STATUS.get(rc, "usage"), err.value.decode(errors="replace"))
    try:
        table = json.loads(ctypes.string_at(cast(int, out.value)).decode())
    finally:
        _lib.trn_py_free(out)
    return cast(List[Dict[str, Any]], table["options"])


def _options_doc(cmd: str, taken: Sequence[str]) -> str:
    """The options of `trn <cmd>` as docstring lines: keyword, value, help
    (with its unit), default and range, from the command's own table."""
    lines = [f"\n\nOptions (keywords; those of `trn {cmd}`, from its --help table):"]
    for o in options(cmd):
        kw = o["name"].lstrip("-").replace("-", "_")
        if kw in taken or kw == "json":
            continue
        val = "True" if o["kind"] == "flag" else (o["metavar"] or "VALUE")
        tail = ""
        if o["default"]:
            tail += f"; default {o['default']}"
        if o["range"]:
            tail += f"; range {o['range']}"
        lines.append(f"    {kw}={val}: {o['help']}{tail}")
    return "\n".join(lines) + "\n"


# ---- progress ---------------------------------------------------------------

def _progress_fn(progress: Progress) -> Tuple[Optional[Callable[[int, int], Any]], Any]:
    """(callback or None, a tqdm bar to close or None) for progress=."""
    if progress is None or progress is False:
        return None, None
    if progress is True:
        try:
            tqdm_mod: Any = importlib.import_module("tqdm")
        except ImportError as e:
            raise TrnError("bad_input", "progress=True draws a tqdm bar: pip install tqdm "
                                        "(or pip install trn[progress])") from e
        bar = tqdm_mod.tqdm(total=0, unit="eval", desc="trn field")

        def tick(done: int, total: int) -> None:
            if bar.total != total:
                bar.total = total
            bar.update(done - bar.n)

        return tick, bar
    if not callable(progress):
        raise TrnError("bad_input", f"progress {progress!r}: want True (a tqdm bar) or a callable(done, total)")
    return progress, None


# ---- the prepared map --------------------------------------------------------

_LOCALIZE_PER_CALL = {"--local", "--prior", "--window-m", "--json"}
_SELECT_PER_CALL = {"--rover", "--out-map", "--next-best", "--json"}
_FIELD_PER_CALL = {"--out", "--area-m", "--coarse-step-cells", "--margin-rel", "--change-rel",
                   "--evaluated-out", "--reference", "--json"}


class Map:
    """A global DEM (map frame: x east, y north, metres) prepared once and
    kept between calls: the localization map for localize, the selection map
    (map, kernels, eq. 8) for select and field; each is prepared on first use
    and again only when the options that shape it change.

    Map(path, band=1): any raster GDAL reads (needs libgdal).
    Map(heights, transform=gt, crs=None, nodata=None): a 2-D array (row 0
    north; float32 C-order arrays are used in place, others converted once),
    gt a GDAL geotransform (x0, dx, 0, y0, 0, -dy) or an affine.Affine, crs
    "EPSG:n", WKT, an EPSG number, a pyproj/rasterio CRS, or None (a
    rover-frame map, metres). NaN heights (and nodata) mean "not seen". The
    array must not be changed while the Map lives (it is read by pointer).
    Map.from_xarray(da): a DataArray with rioxarray's transform and CRS.

    The DEM is read and prepared at the first call that needs it (so a
    geographic CRS or a file that cannot be read is reported by that call, as
    the command line reports it), then kept until close() or collection.
    """

    path: str
    band: int
    coords: Optional[Dict[str, Any]]

    def __init__(self, source: Source, transform: Any = None, crs: CrsLike = None,
                 nodata: Optional[float] = None, band: int = 1) -> None:
        self._h: Optional[int] = None
        self.path, self._keep = _raster_source(source, transform, crs, nodata, "Map", "map array")
        self.band = int(band)
        self.coords = None
        self._lock = threading.Lock()
        h = _lib.trn_py_map_new()
        if not h:
            raise MemoryError("trn_py_map_new")
        self._h = h

    @classmethod
    def from_xarray(cls, da: Any, nodata: Optional[float] = None) -> "Map":
        """A Map from a 2-D xarray.DataArray (dims y, x; row 0 north or
        south, either is normalised): its transform and CRS from rioxarray
        (da.rio.transform(), da.rio.crs; `pip install trn[xarray]`) when it is
        installed, else from the CF "spatial_ref" coordinate rioxarray writes
        (GeoTransform, crs_wkt) or, without one, the regular x/y cell-centre
        coordinates (the cell size then to rounding of the coordinates); nodata
        from da.rio.nodata (or the _FillValue attribute) unless given. The
        coordinates are kept, so field_dataarray() returns the field on
        them."""
        if getattr(da, "ndim", None) != 2:
            raise TrnError("bad_input", f"from_xarray: want a 2-D DataArray, got {type(da).__name__} "
                                        f"with ndim {getattr(da, 'ndim', None)}")
        rio = None
        try:
            importlib.import_module("rioxarray")
            rio = da.rio
        except (ImportError, AttributeError):
            rio = None
        ydim, xdim = da.dims
        if rio is not None:
            gt: Any = rio.transform()
            crs: CrsLike = rio.crs
            if nodata is None and rio.nodata is not None:
                nodata = float(rio.nodata)
        else:
            attrs = da.coords["spatial_ref"].attrs if "spatial_ref" in da.coords else {}
            if "GeoTransform" in attrs:  # rioxarray's own record of the transform, exact
                gt = [float(v) for v in str(attrs["GeoTransform"]).split()]
            else:
                gt = _transform_from_coords(np.asarray(da[xdim].values, dtype=float),
                                            np.asarray(da[ydim].values, dtype=float))
            crs = attrs.get("crs_wkt") or attrs.get("spatial_ref")
            if nodata is None and "_FillValue" in da.attrs:
                nodata = float(da.attrs["_FillValue"])
        m = cls(np.asarray(da.values), transform=gt, crs=crs, nodata=nodata)
        m.coords = {"dims": (ydim, xdim), "y": da[ydim], "x": da[xdim], "crs": crs}
        return m

    def close(self) -> None:
        """Free the prepared maps now (also done when the Map is collected)."""
        h, self._h = getattr(self, "_h", None), None
        if h:
            _lib.trn_py_map_free(h)

    def __del__(self) -> None:
        self.close()

    def __enter__(self) -> "Map":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _call(self, fn: Any, argv: List[str], per_call: set[str], extra: Tuple[Any, ...] = (),
              defaults: Optional[Dict[str, str]] = None) -> Dict[str, Any]:
        if not self._h:
            raise TrnError("bad_input", "the Map is closed")
        key = _key(argv, per_call, defaults).encode()
        cargv = (ctypes.c_char_p * len(argv))(*[a.encode() for a in argv])
        out = ctypes.c_void_p()
        err = ctypes.create_string_buffer(_L.ERR_LEN)
        with self._lock:
            rc = fn(self._h, len(argv), cargv, key, *extra, ctypes.byref(out), err, _L.ERR_LEN)
        if rc != 0:
            raise TrnError(_STATUS.get(rc, f"status_{rc}"), err.value.decode(errors="replace"))
        try:
            return cast(Dict[str, Any], json.loads(ctypes.string_at(cast(int, out.value)).decode()))
        finally:
            _lib.trn_py_free(out)

    def localize(self, local: Source, prior: Tuple[float, float], window_m: Optional[float] = None,
                 transform: Any = None, crs: CrsLike = None, nodata: Optional[float] = None,
                 centroids: Optional[Tuple[Any, Any]] = None, counts: Any = None,
                 **options: Any) -> LocalizeResult:
        """The rover's position from its local DEM around prior (x, y map
        metres) within +-window_m metres (None: the command's default).
        local: a 2-D array in the rover frame (rover at 0,0; x east, y north)
        with its transform (and crs, nodata), or a path. centroids: with an
        array, (cx, cy), two arrays of its shape: where in each seen cell its
        height was measured, cells east and south of the cell's centre
        (binned stereo points: their centroid; within 0.5; NaN where unseen),
        what `trn localize --centroid-bands` reads from a file's bands (for a
        file, pass centroid_bands=N). counts: with an array, an array of its
        shape: how many stereo points each seen cell's height is the mean of
        (at least 1; NaN where unseen), what `trn localize --count-band`
        reads (for a file, pass count_band=N). Returns the dict of `trn
        localize --json` (LocalizeResult)."""
        extra: List[Any] = []
        for name, given, band in (("centroids", centroids, "centroid_bands"), ("counts", counts, "count_band")):
            if given is None:
                continue
            if isinstance(local, (str, os.PathLike)):
                raise TrnError("bad_input", f"{name}: for an array local map; a file gives its {name} "
                                            f"as bands ({band}=N)")
            if options.get(band) is not None:
                raise TrnError("bad_input", f"{name} and {band}: give one of them")
        if centroids is not None:
            try:
                cx, cy = centroids
            except (TypeError, ValueError) as e:
                raise TrnError("bad_input", "centroids: want a pair of arrays (cx, cy)") from e
            extra += [cx, cy]
            options["centroid_bands"] = 2
        if counts is not None:
            extra.append(counts)
            options["count_band"] = 1 + len(extra)
        lpath, keep = _raster_source(local, transform, crs, nodata, "local", "local array", extra)
        try:
            argv = _argv("localize", {"dem": self.path, "band": self.band, "local": lpath, "prior": prior,
                                      "window_m": window_m, **options})
            r = self._call(_lib.trn_py_localize, argv, _LOCALIZE_PER_CALL)
        finally:
            if keep is not None:
                keep.close()
        return cast(LocalizeResult, r)

    def select(self, rover: Tuple[float, float], candidate_map: bool = False, **options: Any) -> SelectResult:
        """The landmark to sense next from rover (x, y map metres). Returns
        the dict of `trn select --json` (SelectResult); with
        candidate_map=True also "candidate_map", every candidate's predicted
        uncertainty on the map's grid (metres, float32; +inf: ill-conditioned,
        NaN: not a candidate; what out_map writes)."""
        mem = None
        if candidate_map and options.get("out_map") is None:
            mem = _new_name()
            options["out_map"] = mem
        argv = _argv("select", {"dem": self.path, "band": self.band, "rover": rover, **options})
        try:
            r = self._call(_lib.trn_py_select, argv, _SELECT_PER_CALL, defaults={"--stride-cells": "1"})
            if mem is not None:
                r["candidate_map"] = _take(mem)
                del r["out_map"]  # as the command line without --out-map
            elif candidate_map:
                r["candidate_map"] = read_raster(options["out_map"], raw=True)[0]
        finally:
            if mem is not None:
                _lib.trn_py_raster_drop(mem.encode())
        return cast(SelectResult, r)

    def field(self, area: Optional[Sequence[float]] = None, progress: Progress = None,
              **options: Any) -> FieldResult:
        """The sensor uncertainty field over area (x0, y0, x1, y1 map metres;
        None: the whole map). progress: True draws a tqdm bar (`pip install
        tqdm`); a callable progress(done, total) is called as the field runs
        (from the calling thread) and stops it with a true return value
        (TrnError "cancelled"). Returns the dict of `trn field --json`
        (FieldResult) with two more keys: "field" (the raster on the map's
        grid, metres; NaN outside the area, +inf where nothing is
        informative) and "evaluated" (1 computed, 0 interpolated, NaN
        outside), numpy float32 arrays; "file" is the out option, or None."""
        user_out = options.pop("out", None)
        user_ev = options.pop("evaluated_out", None)
        out = _new_name() if user_out is None else str(os.fspath(user_out))
        ev = _new_name() if user_ev is None else str(os.fspath(user_ev))
        argv = _argv("field", {"dem": self.path, "band": self.band, "out": out,
                               "area_m": None if area is None else _value(area), "evaluated_out": ev,
                               **options})
        fn, bar = _progress_fn(progress)
        state: Dict[str, Any] = {"cancelled": False, "error": None}

        def on_progress(_user: Any, done: int, total: int) -> int:
            try:
                if fn is not None and fn(int(done), int(total)):
                    state["cancelled"] = True
                    return 1
            except BaseException as e:  # re-raised below, after the C call
                state["error"] = e
                return 1
            return 0

        cb = _L.PROGRESS_FN(on_progress) if fn is not None else _L.PROGRESS_FN()
        try:
            r = self._call(_lib.trn_py_field, argv, _FIELD_PER_CALL, (cb, None), defaults={"--stride-cells": "2"})
            r["field"] = _take(out) if user_out is None else read_raster(out, raw=True)[0]
            r["evaluated"] = _take(ev) if user_ev is None else read_raster(ev, raw=True)[0]
        except TrnError as e:
            if state["error"] is not None:
                raise state["error"] from None
            if state["cancelled"]:
                raise TrnError("cancelled", "the progress callback stopped the field") from e
            raise
        finally:
            for p, mine in ((out, user_out is None), (ev, user_ev is None)):
                if mine:
                    _lib.trn_py_raster_drop(p.encode())
            if bar is not None:
                bar.close()
        r["file"] = None if user_out is None else str(os.fspath(user_out))
        return cast(FieldResult, r)

    def field_dataarray(self, area: Optional[Sequence[float]] = None, progress: Progress = None,
                        **options: Any) -> Any:
        """field() as an xarray.DataArray (needs xarray; `pip install
        trn[xarray]`): the field raster (metres) on the map's coordinates (the
        DataArray's own when the Map came from from_xarray, else the cell
        centres of its geotransform, dims y and x), the JSON summary in .attrs
        (without the rasters), the evaluated mask as the "evaluated"
        coordinate, and the CRS written with rioxarray when it is installed.
        So `m.field_dataarray().plot()` draws it."""
        try:
            xr: Any = importlib.import_module("xarray")
        except ImportError as e:
            raise TrnError("bad_input", "field_dataarray needs xarray: pip install xarray "
                                        "(or pip install trn[xarray])") from e
        r = self.field(area=area, progress=progress, **options)
        if self.coords is not None:
            ydim, xdim = self.coords["dims"]
            coords = {ydim: self.coords["y"], xdim: self.coords["x"]}
            crs = self.coords["crs"]
        else:
            ydim, xdim = "y", "x"
            gt = self._grid()
            h, w = r["field"].shape
            coords = {"y": gt[3] + (np.arange(h) + 0.5) * gt[5], "x": gt[0] + (np.arange(w) + 0.5) * gt[1]}
            crs = self._crs()
        attrs = {k: v for k, v in r.items() if k not in ("field", "evaluated")}
        attrs = {"units": "m", "long_name": "sensor uncertainty", "trn": json.dumps(attrs)}
        field = r["field"]
        if self.coords is not None and np.asarray(self.coords["y"].values)[0] < np.asarray(self.coords["y"].values)[-1]:
            field = field[::-1]  # the DataArray's rows run south to north
            ev = r["evaluated"][::-1]
        else:
            ev = r["evaluated"]
        da = xr.DataArray(field, dims=(ydim, xdim), coords=coords, name="uncertainty_m", attrs=attrs)
        da = da.assign_coords(evaluated=((ydim, xdim), ev))
        if crs is not None:
            try:
                importlib.import_module("rioxarray")
                da = da.rio.write_crs(crs)
            except ImportError:
                pass
        return da

    def _grid(self) -> Transform:
        """The map's geotransform (north-up, metres) as the commands read it."""
        if self._keep is not None:
            return _read(self.path, 1, False)[1]
        return read_raster(self.path, self.band)[1]

    def _crs(self) -> Optional[str]:
        return self._keep.crs if self._keep is not None else read_raster(self.path, self.band)[2]


def _transform_from_coords(x: npt.NDArray[np.float64], y: npt.NDArray[np.float64]) -> Transform:
    """The geotransform of a grid whose cell centres are x (columns) and y
    (rows), each regular; rows may run north to south or south to north."""
    if x.size < 2 or y.size < 2:
        raise TrnError("bad_input", "from_xarray: want at least 2 x 2 cells to find the cell size "
                                    "(or install rioxarray)")
    dx = (x[-1] - x[0]) / (x.size - 1)
    dy = (y[-1] - y[0]) / (y.size - 1)
    for c, d, name in ((x, dx, "x"), (y, dy, "y")):
        if not np.allclose(np.diff(c), d, rtol=1e-6, atol=0):
            raise TrnError("bad_input", f"from_xarray: the {name} coordinates are not regular")
    return (float(x[0] - dx / 2), float(dx), 0.0, float(y[0] - dy / 2), 0.0, float(dy))


Map.localize.__doc__ = (Map.localize.__doc__ or "") + _options_doc(
    "localize", ("dem", "band", "local", "prior"))
Map.select.__doc__ = (Map.select.__doc__ or "") + _options_doc("select", ("dem", "band", "rover"))
Map.field.__doc__ = (Map.field.__doc__ or "") + _options_doc("field", ("dem", "band", "area_m"))
Map.field_dataarray.__doc__ = (Map.field_dataarray.__doc__ or "") + "\n\nOptions: those of field()."
