# SPDX-License-Identifier: Apache-2.0
"""The sensor uncertainty field of a DTM larger than one core wants, on Dask.

    from trn.dask_field import tiled_field
    r = tiled_field("dtm.tif", "field.tif", tile=512, workers=2,
                    min_range_m=0.5, max_range_m=1.0, patch_m=0.3)
    r = tiled_field(heights, None, transform=gt, crs="EPSG:32611")  # an array: r["field"]

or `python -m trn.dask_field DTM OUT --tile 512 --workers 2` (a LocalCluster)
or `... --scheduler tcp://host:8786` (any dask.distributed scheduler whose
workers import trn and read DTM: a shared file system or a /vsicurl/ URL).

Design (docs/scale.md):

* Tiles: the DTM's rover cells cut into tile x tile cores; each task reads its
  core plus a halo (halo_cells) from the DTM itself (a window read with GDAL's
  Python bindings, osgeo, so no worker holds the whole map), prepares the
  selection map of that window and evaluates the field at every rover cell of
  its core. A DTM given as a numpy array (with transform, crs, nodata) needs
  no GDAL: each task is handed its window of the array. A file without osgeo
  is read whole once by the C side (libgdal; at most 4096 cells a side) and
  then tiled as an array.
* Full evaluation: the tiled field is the field at every position
  (coarse_step_cells 1, the trn_field rule with nothing interpolated); the
  coarse-to-fine refinement takes its decisions from the area's own minimum
  and spread, so a tile would refine otherwise than the whole map. The result
  equals `trn field --coarse-step-cells 1` on the whole DTM bit for bit
  (python/tests/test_dask_field.py, 1024 x 1024).
* What the whole map gives every tile: the global map's sensing positions in
  map metres (default: the whole DTM's centre, as `trn field`; never the
  tile's), and the map's outlier density K of ln p (a mean over the whole
  map's distance volume; `--outlier-density`), from one preparation of the
  whole DTM (a task; DTMs up to TRN_MAX_DIM = 4096 cells a side) or given.
* Output: a tiled (256 x 256), DEFLATE-compressed float32 GeoTIFF with the
  DTM's geotransform and CRS, NaN (no-data) outside the area, written by the
  client as tiles arrive (with osgeo; without it the field is assembled in
  memory and written by trn.write_raster); out=None: no file, the field is
  the result's "field" (a numpy float32 array on the DTM's grid).
"""
from __future__ import annotations


import argparse
import json
import math
import os
import sys
import time
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np
import numpy.typing as npt

import trn

__all__ = ["halo_cells", "plan_tiles", "tiled_field", "whole_map_outlier_density", "Tile"]

# trn_config.h / kernels.h / localize.c / mapopt.c constants the halo is made of
KERNEL_SIGMA0_CELLS = 0.5      # TRN_KERNEL_SIGMA0_DEFAULT_CELLS
KERNEL_COUNT = 10              # sigma_j = sigma_0 sqrt(2)^j, j = 0..9
CHAMFER_CAP_UNITS = 60         # trn_map_cfg_default cap, 3 units a cell
HIGHPASS_CELLS = 10            # TRN_MAP_HIGHPASS_CELLS (paper configuration)
MAX_DIM = 4096                 # TRN_MAX_DIM: the largest DTM side one preparation reads

_DEFAULTS = {"max_range_m": 10.0, "patch_m": 2.0}   # trn select's defaults


class Tile:
    """One task: core (rover cells c0..c1-1, r0..r1-1 of the whole DTM) and
    the read window (core plus halo, clipped to the DTM)."""

    def __init__(self, core: Sequence[int], read: Sequence[int]) -> None:
        self.core: Tuple[int, ...] = tuple(int(v) for v in core)
        self.read: Tuple[int, ...] = tuple(int(v) for v in read)

    def __repr__(self) -> str:
        return f"Tile(core={self.core}, read={self.read})"


def _kernel_radius_max() -> int:
    return int(math.ceil(3.0 * KERNEL_SIGMA0_CELLS * math.sqrt(2.0) ** (KERNEL_COUNT - 1)))


def halo_cells(cell_m: float, max_range_m: Optional[float] = None, patch_m: Optional[float] = None,
               highpass_m: Optional[float] = None) -> int:
    """Cells of DTM a tile must read around its core so that every rover cell
    of the core sees the map it would see in the whole DTM:

    reach      ceil(max_range / cell) + 1 (select.c reach_cells: candidate centres)
    + half     patch_cells // 2 (the candidate's patch) + 1 (the fit's pose offsets, -1..1)
    + eq. 9    2 R9 (P spread from P_G with kernels up to R9 = ceil(3 sigma_0 sqrt2^9) cells;
               twice: a source's truncated kernel could touch cells a radius further)
    + eq. 8    2 R9 (P_G spread from the occupancy, the same kernels)
    + 1        (a column's occupancy reads its four neighbours)
    + high-pass half-width (cells; paper: 10).
    The chamfer distances (cap 60 units = 20 cells) need less than eq. 8's
    reach. A halo below this can change values near the tile edges
    (test_too_small_halo_differs)."""
    if not (cell_m and cell_m > 0 and math.isfinite(cell_m)):
        raise trn.TrnError("bad_input", f"cell size {cell_m!r}: want a positive number of metres")
    max_range_m = _DEFAULTS["max_range_m"] if max_range_m is None else float(max_range_m)
    patch_m = _DEFAULTS["patch_m"] if patch_m is None else float(patch_m)
    hp_cells = HIGHPASS_CELLS if highpass_m is None else int(round(float(highpass_m) / cell_m))
    reach = int(math.ceil(max_range_m / cell_m)) + 1
    n = int(math.floor(patch_m / cell_m + 0.5))
    patch_cells = n + 1 if n % 2 == 0 else n
    r9 = _kernel_radius_max()
    return reach + patch_cells // 2 + 1 + 2 * r9 + 2 * r9 + 1 + hp_cells


def plan_tiles(width: int, height: int, tile: int, halo: int,
               area: Optional[Tuple[int, int, int, int]] = None) -> List[Tile]:
    """Tiles over area (c0, r0, c1, r1 inclusive cells; None: the whole
    DTM): cores tile x tile (the last ones shorter), read windows the core
    plus halo clipped to the DTM."""
    if not isinstance(tile, (int, np.integer)) or isinstance(tile, bool) or tile < 16:
        raise trn.TrnError("bad_input", f"tile {tile!r}: want an integer of at least 16 cells")
    if not isinstance(halo, (int, np.integer)) or isinstance(halo, bool) or halo < 0:
        raise trn.TrnError("bad_input", f"halo {halo!r}: want an integer >= 0 cells")
    if tile + 2 * halo > MAX_DIM:
        raise trn.TrnError("bad_input", f"tile {tile} + 2 x halo {halo} = {tile + 2 * halo} cells is above "
                                        f"the {MAX_DIM} a preparation reads (TRN_MAX_DIM): use a smaller tile")
    a0, b0, a1, b1 = (0, 0, width - 1, height - 1) if area is None else area
    tiles = []
    for r0 in range(b0, b1 + 1, tile):
        for c0 in range(a0, a1 + 1, tile):
            c1, r1 = min(c0 + tile, a1 + 1), min(r0 + tile, b1 + 1)
            read = (max(0, c0 - halo), max(0, r0 - halo), min(width, c1 + halo), min(height, r1 + halo))
            tiles.append(Tile((c0, r0, c1, r1), read))
    return tiles


def _distributed() -> Any:
    """dask.distributed (`pip install trn[dask]`)."""
    import importlib
    try:
        return importlib.import_module("distributed")
    except ImportError as e:
        raise trn.TrnError("bad_input", "the tiled field runs on dask.distributed: pip install dask distributed "
                                        "(or pip install trn[dask])") from e


def _osgeo() -> Any:
    """osgeo.gdal, or None when GDAL's Python bindings are not installed."""
    try:
        import importlib
        return importlib.import_module("osgeo.gdal")
    except ImportError:
        return None


def _dtm_info(path: Any, band: int, transform: Any = None, crs: Any = None,
              nodata: Optional[float] = None) -> Dict[str, Any]:
    """The DTM's grid: from a path (osgeo, or the C side's whole read) or an array."""
    if not isinstance(path, (str, os.PathLike)):
        if path is None:
            raise trn.TrnError("bad_input", "dtm: want a path, a GDAL URL or a 2-D array")
        a = np.asarray(path)
        if a.ndim != 2:
            raise trn.TrnError("bad_input", f"dtm: want a 2-D array, got shape {a.shape}")
        gt = trn._geotransform(transform)
        if gt[2] != 0 or gt[4] != 0 or gt[1] <= 0 or gt[5] >= 0 or abs(abs(gt[5]) - gt[1]) > 1e-9 * gt[1]:
            raise trn.TrnError("bad_input", f"dtm: want a north-up grid of square cells, geotransform {gt}")
        return {"path": None, "array": a, "width": a.shape[1], "height": a.shape[0], "gt": gt,
                "crs": trn._crs_text(crs) or "", "nodata": nodata}
    if transform is not None or crs is not None:
        raise trn.TrnError("bad_input", "dtm: transform and crs are for arrays; a file carries its own")
    path = os.fspath(path)
    if not path.startswith("/vsi") and not os.path.exists(path):
        raise trn.TrnError("bad_input", f"dtm {path}: no such file")
    gdal = _osgeo()
    if gdal is None:  # no window reads: the whole DTM through the C side, then tiled as an array
        a, gt, wkt = trn.read_raster(path, band)
        return _dtm_info(a, 1, gt, wkt, None)
    ds = gdal.Open(path)
    if ds is None:
        raise trn.TrnError("bad_input", f"dtm {path}: GDAL cannot open it")
    if band < 1 or band > ds.RasterCount:
        raise trn.TrnError("bad_input", f"dtm {path}: no band {band} (it has {ds.RasterCount})")
    gt = ds.GetGeoTransform()
    if gt[2] != 0 or gt[4] != 0 or gt[1] <= 0 or gt[5] >= 0 or abs(abs(gt[5]) - gt[1]) > 1e-9 * gt[1]:
        raise trn.TrnError("bad_input", f"dtm {path}: want a north-up grid of square cells, geotransform {gt}")
    info = {"path": path, "array": None, "width": ds.RasterXSize, "height": ds.RasterYSize, "gt": tuple(gt),
            "crs": ds.GetProjection(), "nodata": ds.GetRasterBand(band).GetNoDataValue()}
    ds = None
    return info


def _cell_to_map(gt: Sequence[float], col: float, row: float) -> Tuple[float, float]:
    """dem_io.c dem_cell_to_map, the same double operations."""
    return gt[0] + (col + 0.5) * gt[1], gt[3] + (row + 0.5) * gt[5]


def _area_cells(info: Dict[str, Any], area_m: Optional[Sequence[float]]) -> Tuple[int, int, int, int]:
    """cmd_field.c field_area: the cells whose centres lie in the box."""
    w, h, gt = info["width"], info["height"], info["gt"]
    if area_m is None:
        return (0, 0, w - 1, h - 1)
    x0, y0, x1, y1 = (float(v) for v in area_m)
    if not (x0 <= x1 and y0 <= y1):
        raise trn.TrnError("bad_input", f"area {area_m}: want X0 <= X1 and Y0 <= Y1")
    c0 = math.ceil((x0 - gt[0]) / gt[1] - 0.5 - 1e-9)
    r0 = math.ceil((y1 - gt[3]) / gt[5] - 0.5 - 1e-9)
    c1 = math.floor((x1 - gt[0]) / gt[1] - 0.5 + 1e-9)
    r1 = math.floor((y0 - gt[3]) / gt[5] - 0.5 + 1e-9)
    c0, r0, c1, r1 = max(c0, 0), max(r0, 0), min(c1, w - 1), min(r1, h - 1)
    if c0 > c1 or r0 > r1:
        raise trn.TrnError("bad_input", f"area {area_m} holds no cell centre of the DTM")
    return (c0, r0, c1, r1)


def _default_sensors(info: Dict[str, Any]) -> List[Tuple[float, float]]:
    """`trn field`'s default: the whole DTM's centre (selmap.c sensor_cells)."""
    return [_cell_to_map(info["gt"], 0.5 * (info["width"] - 1), 0.5 * (info["height"] - 1))]


def whole_map_outlier_density(dtm: Any, band: int = 1, transform: Any = None, crs: Any = None,
                              nodata: Optional[float] = None, **options: Any) -> float:
    """K of ln p over the whole DTM's distance volume (what `trn field`
    reports as outlier_density_per_m): one preparation of the whole map, so
    the DTM (a path, or an array with transform, crs, nodata) must fit one
    (at most 4096 cells a side)."""
    info = _dtm_info(dtm, band, transform, crs, nodata)
    if max(info["width"], info["height"]) > MAX_DIM:
        raise trn.TrnError("bad_input", f"dtm {info['path']} is {info['width']} x {info['height']} cells: "
                                        f"its outlier density needs one preparation of at most {MAX_DIM} a "
                                        "side; pass outlier_density= (docs/scale.md)")
    opts = {k: v for k, v in options.items() if k not in ("sensors", "area", "coarse_step_cells")}
    with _info_map(info, band) as m:  # the coarsest lattice: K is all it is for
        try:
            r = m.field(coarse_step_cells=256, margin_rel=0, change_rel=100, **opts)
        except trn.TrnError as e:
            if e.status != "no_result":
                raise
            raise trn.TrnError("no_result", "no informative position on the coarsest lattice, so no outlier "
                                            "density reported: pass outlier_density=") from e
    return float(r["outlier_density_per_m"])


def _info_map(info: Dict[str, Any], band: int) -> trn.Map:
    if info["array"] is not None:
        return trn.Map(info["array"], transform=info["gt"], crs=info["crs"] or None, nodata=info["nodata"])
    return trn.Map(info["path"], band=band)


def _run_tile(info: Dict[str, Any], band: int, tile: Tile, sensors: List[Tuple[float, float]], k: float,
              options: Dict[str, Any], window: Optional[npt.NDArray[Any]] = None) -> Dict[str, Any]:
    """One task (on a worker): read the window (or take the array's), prepare
    it, evaluate the core."""
    t0 = time.perf_counter()
    c0, r0, w, h = tile.read[0], tile.read[1], tile.read[2] - tile.read[0], tile.read[3] - tile.read[1]
    if window is not None:
        a = window
    else:
        gdal = _osgeo()
        ds = gdal.Open(info["path"])
        a = ds.GetRasterBand(band).ReadAsArray(c0, r0, w, h)
        ds = None
    if a is None:
        raise trn.TrnError("bad_input", f"dtm {info['path']}: cannot read window {tile.read}")
    gt = info["gt"]
    tgt = (gt[0] + c0 * gt[1], gt[1], 0.0, gt[3] + r0 * gt[5], 0.0, gt[5])
    k0, l0, k1, l1 = tile.core
    xa, ya = _cell_to_map(tgt, k0 - c0, l1 - 1 - r0)
    xb, yb = _cell_to_map(tgt, k1 - 1 - c0, l0 - r0)
    r: Dict[str, Any]
    with trn.Map(a, transform=tgt, crs=info["crs"] or None, nodata=info["nodata"]) as m:
        try:
            r = dict(m.field(area=(xa, ya, xb, yb), coarse_step_cells=1, sensors=sensors, outlier_density=k,
                             **options))
        except trn.TrnError as e:
            if e.status != "no_result":
                raise
            # no position of the core has an informative target: +inf everywhere, as the whole
            # map's field holds there
            n = (k1 - k0) * (l1 - l0)
            r = {"field": None, "evaluations": n, "seconds": float("nan"), "workspace_bytes": 0}
    if r["field"] is None:
        core = np.full((l1 - l0, k1 - k0), np.inf, dtype=np.float32)
    else:
        core = np.ascontiguousarray(r["field"][l0 - r0:l1 - r0, k0 - c0:k1 - c0])
    return {"core": tile.core, "field": core, "evaluations": r["evaluations"],
            "seconds": time.perf_counter() - t0, "field_seconds": r["seconds"],
            "workspace_bytes": r["workspace_bytes"], "maxrss_kib": _maxrss_kib()}


def _maxrss_kib() -> int:
    import resource
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def _create_out(path: str, info: Dict[str, Any], block: int = 256) -> Any:
    gdal = _osgeo()
    drv = gdal.GetDriverByName("GTiff")
    opts = ["TILED=YES", f"BLOCKXSIZE={block}", f"BLOCKYSIZE={block}", "COMPRESS=DEFLATE", "PREDICTOR=3",
            "BIGTIFF=IF_SAFER"]
    ds = drv.Create(os.fspath(path), info["width"], info["height"], 1, gdal.GDT_Float32, opts)
    if ds is None:
        raise trn.TrnError("bad_input", f"out {path}: GDAL cannot create it")
    ds.SetGeoTransform(info["gt"])
    if info["crs"]:
        ds.SetProjection(info["crs"])
    b = ds.GetRasterBand(1)
    b.SetNoDataValue(float("nan"))
    b.Fill(float("nan"))
    return ds


_FORBIDDEN = {"coarse_step_cells", "margin_rel", "change_rel", "reference", "out", "evaluated_out",
              "area", "area_m", "outlier_density", "sensors", "map_config"}


def tiled_field(dtm: Any, out: Any, tile: int = 512, workers: int = 2, scheduler: Optional[str] = None,
                client: Any = None, area: Optional[Sequence[float]] = None,
                sensors: Optional[Sequence[Tuple[float, float]]] = None, halo: Optional[int] = None,
                outlier_density: Optional[float] = None, band: int = 1, map_config: str = "paper",
                threads_per_worker: int = 1, memory_limit: Any = "auto",
                progress: Optional[Callable[[int, int], Any]] = None, transform: Any = None, crs: Any = None,
                nodata: Optional[float] = None, **options: Any) -> Dict[str, Any]:
    """The field at every rover cell of area (x0, y0, x1, y1 map metres; None:
    the whole DTM) of the DTM dtm (a path, or a 2-D numpy array with
    transform, crs and nodata as trn.Map takes them), computed tile by tile on
    Dask and written to out (tiled DEFLATE GeoTIFF, the DTM's grid, NaN
    outside area), or returned as the result's "field" when out is None.

    client: a dask.distributed Client to use; else scheduler (an address)
    to connect to; else a LocalCluster of `workers` processes. sensors: the
    global map's sensing positions in map metres (default the whole DTM's
    centre). halo: cells read around each tile (default halo_cells(...));
    outlier_density: the whole map's K (default: computed on a worker).
    Options: those of `trn field` that shape the selection (max_range_m,
    patch_m, stride_cells, heading_deg, ...). Returns a dict: cells,
    evaluations, tiles, seconds (end to end), seconds_k (K's preparation),
    cells_per_second, tile timings, the largest worker RSS."""
    bad = sorted(set(options) & _FORBIDDEN)
    if bad:
        raise trn.TrnError("usage", f"tiled_field: {', '.join(bad)} is not an option of the tiled field "
                                    "(it evaluates every position; the area, sensors and density are arguments)")
    if map_config != "paper":
        raise trn.TrnError("bad_input", "tiled_field: map_config 'auto' is made from the whole DTM's statistics; "
                                        "the tiled field takes 'paper' (with explicit zbin_m, nz, ...)")
    t_start = time.perf_counter()
    info = _dtm_info(dtm, band, transform, crs, nodata)
    if out is not None:
        out = os.fspath(out)
    if out is not None and not os.path.isdir(os.path.dirname(os.path.abspath(out))):
        raise trn.TrnError("bad_input", f"out {out}: no such folder")
    area_c = _area_cells(info, area)
    if halo is None:
        halo = halo_cells(info["gt"][1], options.get("max_range_m"), options.get("patch_m"),
                          options.get("highpass_m"))
    tiles = plan_tiles(info["width"], info["height"], tile, halo, area_c)
    sensors = [(float(s[0]), float(s[1])) for s in (sensors if sensors is not None else _default_sensors(info))]
    options = dict(options, map_config=map_config)

    own = None
    if client is None:
        dist: Any = _distributed()
        Client, LocalCluster = dist.Client, dist.LocalCluster
        if scheduler is not None:
            client = own = Client(scheduler)
        else:
            if not isinstance(workers, int) or workers < 1:
                raise trn.TrnError("bad_input", f"workers {workers!r}: want an integer >= 1")
            cluster = LocalCluster(n_workers=workers, threads_per_worker=threads_per_worker, processes=True,
                                   memory_limit=memory_limit, dashboard_address=None)
            client = own = Client(cluster)
    try:
        t_k = time.perf_counter()
        arr = info["array"]
        if outlier_density is None:
            if arr is not None:
                outlier_density = client.submit(whole_map_outlier_density, arr, 1, info["gt"], info["crs"] or None,
                                                info["nodata"], pure=False, **options).result()
            else:
                outlier_density = client.submit(whole_map_outlier_density, info["path"], band, pure=False,
                                                **options).result()
        t_k = time.perf_counter() - t_k
        # an array's tasks get their windows (copies: what a file's tasks would read)
        lean = dict(info, array=None)
        futs = [client.submit(_run_tile, lean, band, t, sensors, outlier_density, options,
                              None if arr is None else np.array(arr[t.read[1]:t.read[3], t.read[0]:t.read[2]]),
                              pure=False)
                for t in tiles]
        gdal_out = out is not None and _osgeo() is not None
        ds = _create_out(out, info) if gdal_out else None
        whole = None if gdal_out else np.full((info["height"], info["width"]), np.nan, dtype=np.float32)
        as_completed = _distributed().as_completed
        done, evals, stats = 0, 0, []
        for fut in as_completed(futs):
            r = fut.result()
            c0, r0, _, _ = r["core"]
            if ds is not None:
                ds.GetRasterBand(1).WriteArray(r["field"], c0, r0)
            else:
                assert whole is not None
                whole[r0:r0 + r["field"].shape[0], c0:c0 + r["field"].shape[1]] = r["field"]
            evals += r["evaluations"]
            stats.append({k: r[k] for k in ("core", "evaluations", "seconds", "field_seconds",
                                            "workspace_bytes", "maxrss_kib")})
            done += 1
            fut.release()
            if progress is not None:
                progress(done, len(tiles))
        if ds is not None:
            ds.FlushCache()
            ds = None
        elif out is not None:
            assert whole is not None
            trn.write_raster(out, whole, info["gt"], info["crs"] or None)
    finally:
        if own is not None:
            cluster = getattr(own, "cluster", None)
            own.close()
            if cluster is not None:
                cluster.close()
    secs = time.perf_counter() - t_start
    cells = (area_c[2] - area_c[0] + 1) * (area_c[3] - area_c[1] + 1)
    res = {"file": out, "cells": cells, "evaluations": evals, "tiles": len(tiles), "tile": tile, "halo": halo,
            "sensors": sensors, "outlier_density_per_m": outlier_density, "seconds": secs, "seconds_k": t_k,
            "cells_per_second": cells / secs if secs > 0 else float("nan"), "area_cells": area_c,
            "tile_stats": sorted(stats, key=lambda s: (s["core"][1], s["core"][0])),
            "max_worker_rss_mib": max((s["maxrss_kib"] for s in stats), default=0) / 1024.0}
    if out is None:
        res["field"] = whole
    return res


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="python -m trn.dask_field",
                                description="The sensor uncertainty field of a large DTM, tile by tile on Dask "
                                            "(every position evaluated; docs/scale.md).")
    p.add_argument("dtm")
    p.add_argument("out", help="tiled DEFLATE GeoTIFF")
    p.add_argument("--tile", type=int, default=512, help="core tile side, cells (default 512)")
    p.add_argument("--halo", type=int, default=None, help="cells read around a tile (default: computed)")
    p.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes (default 2)")
    p.add_argument("--scheduler", default=None, help="a dask.distributed scheduler address instead")
    p.add_argument("--area-m", default=None, help="X0,Y0,X1,Y1 map metres (default: the whole DTM)")
    p.add_argument("--sensors", default=None, help="X,Y[;X,Y..] map metres (default: the DTM's centre)")
    p.add_argument("--outlier-density", type=float, default=None)
    p.add_argument("--report", default=None, help="also write the full report (each tile's timing) as JSON here")
    p.add_argument("--option", action="append", default=[], metavar="KEY=VALUE",
                   help="a `trn field` option, e.g. max_range_m=1.5 (repeatable)")
    a = p.parse_args(argv)
    opts: Dict[str, Any] = {}
    for kv in a.option:
        key, _, val = kv.partition("=")
        opts[key.replace("-", "_")] = val
    area = tuple(float(v) for v in a.area_m.split(",")) if a.area_m else None
    sensors = None
    if a.sensors:
        pairs = [s.split(",") for s in a.sensors.split(";")]
        sensors = [(float(xy[0]), float(xy[1])) for xy in pairs]
    try:
        r = tiled_field(a.dtm, a.out, tile=a.tile, workers=a.workers, scheduler=a.scheduler, area=area,
                        sensors=sensors, halo=a.halo, outlier_density=a.outlier_density, **opts)
    except trn.TrnError as e:
        print(f"trn.dask_field: {e.message}", file=sys.stderr)
        return 1
    if a.report:
        with open(a.report, "w") as f:
            json.dump(r, f)
    r.pop("tile_stats")
    print(json.dumps(r))
    return 0


if __name__ == "__main__":
    sys.exit(main())
