# SPDX-License-Identifier: Apache-2.0
"""trn: terrain matching and landmark selection (after Olson, ICRA 2000) from Python.

A thin layer over libtrn_run.so (python/trn_py.c), the run layer of the `trn`
command line built as a shared library and loaded with ctypes:

    import trn
    m = trn.Map("global.tif")                        # any raster GDAL reads
    m = trn.Map(heights, transform=gt, crs="EPSG:32611")  # or a 2-D numpy array
    m.localize(local, prior=(x, y))                  # local: array (rover frame) or path
    m.select(rover=(x, y))
    m.field(area=(x0, y0, x1, y1), progress=cb)      # also the raster, as numpy

Results are dicts with the keys and units of `trn <cmd> --json` (they are
written by the same JSON writer, in C). Options are the command's options as
keywords: `--pan-deg -30,30` is `pan_deg=(-30, 30)`, `--map-config paper` is
`map_config="paper"`, a flag is `reference=True`. Errors raise TrnError with
.status: "bad_input", "usage" (an unknown keyword, a missing value),
"no_result" (no informative target) or "cancelled" (the progress callback
stopped a field).

Threads: ctypes releases the GIL for the whole C call (ctypes.CDLL), so other
Python threads run while a localization, selection or field runs; the progress
callback takes the GIL back for each call. One Map serialises its own calls
(a lock); use one Map per thread to run in parallel.

Arrays reach the C side as GDAL in-memory files (/vsimem/) written with
osgeo.gdal (Debian's python3-gdal), which shares libgdal with libtrn_run.so.
"""

import ctypes
import itertools
import json
import math
import os
import threading

import numpy as np

__all__ = ["Map", "TrnError", "version", "__version__"]

_STATUS = {1: "bad_input", 2: "usage", 3: "no_result"}
_ERR_LEN = 1024

_PROGRESS_FN = ctypes.CFUNCTYPE(ctypes.c_int32, ctypes.c_void_p, ctypes.c_uint32, ctypes.c_uint32)


class TrnError(Exception):
    """A failed call: .status is the status name ("bad_input", "usage",
    "no_result", "cancelled"), .message the one-line reason (the text `trn
    <cmd>: <reason>` would print)."""

    def __init__(self, status, message):
        super().__init__(f"{status}: {message}")
        self.status = status
        self.message = message


def _load():
    here = os.path.dirname(os.path.abspath(__file__))
    path = os.environ.get("TRN_RUN_LIBRARY") or os.path.join(here, "libtrn_run.so")
    lib = ctypes.CDLL(path)  # CDLL: the GIL is released during every call
    lib.trn_py_version.restype = ctypes.c_char_p
    lib.trn_py_version.argtypes = []
    lib.trn_py_map_new.restype = ctypes.c_void_p
    lib.trn_py_map_new.argtypes = []
    lib.trn_py_map_free.restype = None
    lib.trn_py_map_free.argtypes = [ctypes.c_void_p]
    lib.trn_py_free.restype = None
    lib.trn_py_free.argtypes = [ctypes.c_void_p]
    common = [ctypes.c_void_p, ctypes.c_int, ctypes.POINTER(ctypes.c_char_p), ctypes.c_char_p]
    out = [ctypes.POINTER(ctypes.c_void_p), ctypes.c_char_p, ctypes.c_size_t]
    for name in ("trn_py_localize", "trn_py_select"):
        fn = getattr(lib, name)
        fn.restype = ctypes.c_int
        fn.argtypes = common + out
    lib.trn_py_field.restype = ctypes.c_int
    lib.trn_py_field.argtypes = common + [_PROGRESS_FN, ctypes.c_void_p] + out
    return lib


_lib = _load()
__version__ = _lib.trn_py_version().decode()


def version():
    """The library's version (the `version` of every result; `trn --version`)."""
    return __version__


# ---- options: keywords -> the command's argv -------------------------------

def _num(v):
    if isinstance(v, bool):
        raise TrnError("bad_input", f"expected a number, got {v!r}")
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return repr(float(v))  # shortest round trip, as the CLI reads it with strtod


def _value(key, v):
    """One keyword's value as the command line's text."""
    if isinstance(v, str):
        return v
    if isinstance(v, os.PathLike):
        return os.fspath(v)
    if isinstance(v, (list, tuple, np.ndarray)):
        items = list(v)
        if items and all(isinstance(i, (list, tuple, np.ndarray)) for i in items):  # sensors: [(x, y), ...]
            return ";".join(",".join(_num(c) for c in i) for i in items)
        return ",".join(_num(i) for i in items)
    return _num(v)


def _argv(cmd, opts):
    """["cmd", "--opt", "value", ...]; True is a flag, False and None are left out."""
    argv = [cmd]
    for key, v in opts.items():
        if v is None or v is False:
            continue
        if not isinstance(key, str) or not key or key.startswith("_") or key in ("help", "json"):
            raise TrnError("usage", f"unknown option {key!r}")
        argv.append("--" + key.replace("_", "-"))
        if v is not True:
            argv.append(_value(key, v))
    return argv


def _key(argv, per_call, defaults=None):
    """What a preparation depends on: every option except the per-call ones,
    with the defaults that differ between commands (select's stride 1,
    field's 2) written out, so select and field share a map only when it is
    the same."""
    out, i = [], 1
    seen = set()
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


# ---- arrays -> GDAL in-memory files ----------------------------------------

_vsi_ids = itertools.count()


def _gdal():
    try:
        from osgeo import gdal, osr
    except ImportError as e:  # pragma: no cover - Debian's python3-gdal is a requirement
        raise TrnError("bad_input", f"arrays need GDAL's Python bindings (Debian python3-gdal): {e}") from e
    return gdal, osr  # the caller's exception settings are left alone: return codes checked


def _geotransform(transform):
    """A GDAL geotransform (6 numbers) or an affine.Affine-like object."""
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
    return gt


def _check_array(a):
    a = np.asarray(a)
    if a.ndim != 2 or a.shape[0] < 1 or a.shape[1] < 1:
        raise TrnError("bad_input", f"heights: want a 2-D array (rows, columns), got shape {a.shape}")
    if a.dtype.kind not in "fiu":
        raise TrnError("bad_input", f"heights: want real numbers (float or int), got dtype {a.dtype}")
    return np.ascontiguousarray(a, dtype=np.float32)


class _VsiFile:
    """A GeoTIFF in GDAL's memory file system, removed when this is collected."""

    def __init__(self, heights, transform, crs, nodata=None):
        gdal, osr = _gdal()
        a = _check_array(heights)
        gt = _geotransform(transform)
        self.path = f"/vsimem/trn_py/{os.getpid()}_{next(_vsi_ids)}.tif"
        wkt = None
        if crs is not None and crs != "":  # "": GDAL's GetProjection() of a file without one
            srs = osr.SpatialReference()
            try:
                bad = srs.SetFromUserInput(str(crs) if not isinstance(crs, int) else f"EPSG:{crs}") != 0
            except RuntimeError:
                bad = True
            if bad:
                raise TrnError("bad_input", f"crs {crs!r}: not a CRS GDAL knows (EPSG:n, WKT, PROJ)")
            wkt = srs.ExportToWkt()
        ds = gdal.GetDriverByName("GTiff").Create(self.path, a.shape[1], a.shape[0], 1, gdal.GDT_Float32)
        if ds is None:
            raise TrnError("bad_input", f"cannot create the in-memory raster {self.path}")
        ds.SetGeoTransform(gt)
        if wkt is not None:
            ds.SetProjection(wkt)
        band = ds.GetRasterBand(1)
        if nodata is not None:
            band.SetNoDataValue(float(nodata))
        band.WriteArray(a)
        ds = None

    def __del__(self):
        try:
            _unlink(self.path)
        except Exception:  # pragma: no cover - interpreter shutdown
            pass


def _raster_source(src, transform, crs, nodata, what):
    """(path, keep-alive) for a path or an array."""
    if isinstance(src, (str, os.PathLike)):
        if transform is not None or crs is not None:
            raise TrnError("bad_input", f"{what}: transform and crs are for arrays; a file carries its own")
        return os.fspath(src), None
    if isinstance(src, Map):
        return src.path, src
    f = _VsiFile(src, transform, crs, nodata)
    return f.path, f


def _unlink(path):
    """Remove a /vsimem/ file if it is there, whatever the caller's GDAL exception setting."""
    gdal, _ = _gdal()
    try:
        if gdal.VSIStatL(path) is not None:
            gdal.Unlink(path)
    except RuntimeError:  # pragma: no cover
        pass


def _read_vsi(path):
    a = _read_file(path)
    _unlink(path)
    return a


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

    Map(path, band=1): any raster GDAL reads.
    Map(heights, transform=gt, crs=None, nodata=None): a 2-D array (row 0
    north), gt a GDAL geotransform (x0, dx, 0, y0, 0, -dy) or an
    affine.Affine, crs anything OSR reads ("EPSG:32611", WKT, an EPSG number)
    or None (metres). NaN heights (and nodata) mean "not seen".

    The DEM is read and prepared at the first call that needs it (so a
    missing file or a geographic CRS is reported by that call, as the command
    line reports it), then kept until close() or collection.
    """

    def __init__(self, source, transform=None, crs=None, nodata=None, band=1):
        self.path, self._keep = _raster_source(source, transform, crs, nodata, "Map")
        self.band = band
        self._lock = threading.Lock()
        self._h = _lib.trn_py_map_new()
        if not self._h:
            raise MemoryError("trn_py_map_new")

    def close(self):
        """Free the prepared maps now (also done when the Map is collected)."""
        h, self._h = getattr(self, "_h", None), None
        if h:
            _lib.trn_py_map_free(h)

    def __del__(self):
        self.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _call(self, fn, argv, per_call, extra=(), defaults=None):
        if not self._h:
            raise TrnError("bad_input", "the Map is closed")
        key = _key(argv, per_call, defaults).encode()
        cargv = (ctypes.c_char_p * len(argv))(*[a.encode() for a in argv])
        out = ctypes.c_void_p()
        err = ctypes.create_string_buffer(_ERR_LEN)
        with self._lock:
            rc = fn(self._h, len(argv), cargv, key, *extra, ctypes.byref(out), err, _ERR_LEN)
        if rc != 0:
            raise TrnError(_STATUS.get(rc, f"status_{rc}"), err.value.decode(errors="replace"))
        try:
            return json.loads(ctypes.string_at(out.value).decode())
        finally:
            _lib.trn_py_free(out)

    def localize(self, local, prior, window_m=2.5, transform=None, crs=None, nodata=None, **options):
        """The rover's position from its local DEM (rover frame: rover at
        0,0, x east, y north; an array with its transform, or a path) around
        prior (x, y map metres) within +-window_m. Options: those of `trn
        localize` (map_config, match, zbin_m, heading_window_deg ...).
        Returns the dict of `trn localize --json`."""
        lpath, keep = _raster_source(local, transform, crs, nodata, "local")
        argv = _argv("localize", {"dem": self.path, "band": self.band, "local": lpath, "prior": prior,
                                  "window_m": window_m, **options})
        r = self._call(_lib.trn_py_localize, argv, _LOCALIZE_PER_CALL)
        del keep
        return r

    def select(self, rover, candidate_map=False, **options):
        """The landmark to sense next from rover (x, y map metres). Options:
        those of `trn select` (heading_deg, pan_deg, min_range_m, max_range_m,
        patch_m, stride_cells, sensors, next_best, out_map ...). Returns the
        dict of `trn select --json`; with candidate_map=True also
        "candidate_map", every candidate's predicted uncertainty on the map's
        grid (metres, float32; +inf: ill-conditioned, NaN: not a candidate;
        what out_map writes)."""
        vsi = None
        if candidate_map and options.get("out_map") is None:
            vsi = f"/vsimem/trn_py/{os.getpid()}_{next(_vsi_ids)}_candidates.tif"
            options["out_map"] = vsi
        argv = _argv("select", {"dem": self.path, "band": self.band, "rover": rover, **options})
        try:
            r = self._call(_lib.trn_py_select, argv, _SELECT_PER_CALL, defaults={"--stride-cells": "1"})
            if candidate_map:
                r["candidate_map"] = _read_file(options["out_map"])
        finally:
            if vsi is not None:
                _unlink(vsi)
        if vsi is not None:
            del r["out_map"]  # as the command line without --out-map
        return r

    def field(self, area=None, progress=None, **options):
        """The sensor uncertainty field over area (x0, y0, x1, y1 map metres;
        None: the whole map). progress(done, total) is called as the field
        runs (from the calling thread); a true return value stops it
        (TrnError "cancelled"). Options: those of `trn field` (out,
        evaluated_out, coarse_step_cells, reference, and the selection
        options). Returns the dict of `trn field --json` with two more keys:
        "field" (the raster on the map's grid, metres; NaN outside the area,
        +inf where nothing is informative) and "evaluated" (1 computed, 0
        interpolated, NaN outside), numpy float32 arrays; "file" is the out
        option, or None."""
        user_out = options.pop("out", None)
        user_ev = options.pop("evaluated_out", None)
        n = next(_vsi_ids)
        out = user_out if user_out is not None else f"/vsimem/trn_py/{os.getpid()}_{n}_field.tif"
        ev = user_ev if user_ev is not None else f"/vsimem/trn_py/{os.getpid()}_{n}_evaluated.tif"
        if area is not None:
            area = _value("area_m", area)
        argv = _argv("field", {"dem": self.path, "band": self.band, "out": os.fspath(out),
                               "area_m": area, "evaluated_out": os.fspath(ev), **options})
        state = {"cancelled": False, "error": None}

        def on_progress(_user, done, total):
            try:
                if progress(int(done), int(total)):
                    state["cancelled"] = True
                    return 1
            except BaseException as e:  # re-raised below, after the C call
                state["error"] = e
                return 1
            return 0

        cb = _PROGRESS_FN(on_progress) if progress is not None else _PROGRESS_FN()
        try:
            r = self._call(_lib.trn_py_field, argv, _FIELD_PER_CALL, (cb, None), defaults={"--stride-cells": "2"})
        except TrnError as e:
            for p in (out, ev):
                if str(p).startswith("/vsimem/"):
                    _unlink(str(p))
            if state["error"] is not None:
                raise state["error"] from None
            if state["cancelled"]:
                raise TrnError("cancelled", "the progress callback stopped the field") from e
            raise
        r["field"] = _read_vsi(out) if user_out is None else _read_file(out)
        r["evaluated"] = _read_vsi(ev) if user_ev is None else _read_file(ev)
        r["file"] = None if user_out is None else os.fspath(user_out)
        return r


def _read_file(path):
    gdal, _ = _gdal()
    ds = gdal.Open(os.fspath(path))
    a = ds.GetRasterBand(1).ReadAsArray()
    ds = None
    return a
