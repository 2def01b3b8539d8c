# SPDX-License-Identifier: Apache-2.0
"""The result dicts of trn.Map's calls as TypedDicts: the keys of `trn <cmd>
--json` (written by the same C JSON writer), with their units in the names
(_m metres, _deg degrees, _m2 square metres). Keys a result has only in some
cases (a heading search, a refinement, a raster the caller asked for) are in
the total=False part. python/tests/test_types.py checks that every key the
command line writes is declared here, so a key added to a report in C is
added here too."""
from __future__ import annotations

from typing import List, Optional, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

__all__ = [
    "XY", "XYHeading", "Area", "Best", "MapConfig", "Refinement", "GlobalError", "Target", "NextBest",
    "LocalizeResult", "SelectResult", "FieldResult", "Raster", "Transform", "RasterRead", "CrsLike",
]

#: A GDAL geotransform: (x0, dx, 0, y0, 0, -dy), metres.
Transform = Tuple[float, float, float, float, float, float]


class XY(TypedDict):
    """A position, map metres (x east, y north)."""
    x_m: float
    y_m: float


class XYHeading(XY):
    """The rover: position (map metres) and heading (degrees)."""
    heading_deg: float


class Area(TypedDict):
    """The field's area, map metres (the cell centres it holds)."""
    x0_m: float
    y0_m: float
    x1_m: float
    y1_m: float


class Best(XY):
    """The field's best position and its uncertainty (metres)."""
    uncertainty_m: float


class MapConfig(TypedDict):
    """The map configuration a preparation used (mapopt.c)."""
    zbin_m: float
    nz: int
    highpass_m: float
    sigma_m: float
    inlier_prob: float
    noise_m: float
    noise_k_per_m: float
    local_highpass: str
    refine: int
    noise_auto: int
    match: str
    max_failure_prob: float


class _RefinementRequired(TypedDict):
    """The refinement's own figures (docs/method.md 9), grid frame."""
    model_m: float
    chi2_dof: float
    inflation: float
    ll_inflation: float
    interp_mix: float
    shoulders: float
    spline_step_cells: List[float]
    points_used: int
    iterations: int
    log_likelihood: float


class Refinement(_RefinementRequired, total=False):
    """The refinement's own figures (docs/method.md 9), grid frame; with the
    height matcher also its relief test (docs/method.md 9.4): relief_z (None
    where not tested) and misfit, the answer's misfit flag."""
    relief_z: Optional[float]
    misfit: bool


class GlobalError(TypedDict):
    """Eq. 8's global map error: S0 + K r^2, or a raster."""
    sigma_m: float
    k_per_m: float
    raster: Optional[str]


class Target(XY):
    """The landmark to sense: position, range (m) and bearing (deg)."""
    range_m: float
    bearing_deg: float


class NextBest(Target):
    """One of the next best targets, with its predicted uncertainty."""
    sigma_x_m: float
    sigma_y_m: float
    rho: float
    uncertainty_m: float
    heading_m: float


class _LocalizeRequired(TypedDict):
    version: str
    x_m: float
    y_m: float
    sigma_x_m: float
    sigma_y_m: float
    rho: float
    cov_m2: List[float]
    failure_probability: float
    status: str
    refined: bool
    centroids: bool  # --centroid-bands: the refinement read the map at each cell's centroid
    point_counts: bool  # --count-band: each cell's noise that of the mean of its points
    noise_scale: float
    prior: XY
    window_m: float
    cell_m: float
    on_window_edge: bool
    local_points: int
    log_likelihood: float
    poses_scored: int
    time_ms: float
    map_config: MapConfig


class LocalizeResult(_LocalizeRequired, total=False):
    """`trn localize --json`: the rover's position (map metres), its
    covariance and status. heading_deg, sigma_heading_deg and cov3 come with
    a heading search; refinement when the answer was refined; search,
    failure_prob_bound and blocks_bounded with the height matcher."""
    heading_deg: float
    sigma_heading_deg: float
    cov3: List[float]
    refinement: Refinement
    # the height matcher's search (not with the voxel matcher): which ran,
    # the failure probability's error bound, and the block bounds computed
    search: str
    failure_prob_bound: float
    blocks_bounded: int


class _SelectRequired(TypedDict):
    version: str
    target: Target
    sigma_x_m: float
    sigma_y_m: float
    rho: float
    uncertainty_m: float
    heading_m: float
    rover: XYHeading
    next_best: List[NextBest]
    candidates: int
    informative: int
    min_range_m: float
    max_range_m: float
    stride_cells: int
    patch_cells: int
    patch_m: float
    cell_m: float
    sensors: List[XY]
    heading_sigma_deg: float
    heading_search: int
    global_error: GlobalError
    map_config_name: str
    predicts: str
    points_per_cell: float
    sigma_h_m: Optional[float]
    map_config: MapConfig


#: A raster on the map's grid (float32, row 0 north).
Raster = npt.NDArray[np.float32]


class SelectResult(_SelectRequired, total=False):
    """`trn select --json`: the target to sense next and its predicted
    uncertainty (metres). out_map when a file was asked for; candidate_map
    (numpy, the map's grid, metres) with candidate_map=True."""
    out_map: str
    candidate_map: Raster


class _FieldRequired(TypedDict):
    version: str
    file: Optional[str]
    width: int
    height: int
    area: Area
    cells: int
    evaluations: int
    best: Best
    median_uncertainty_m: float
    no_target_cells: int
    heading_deg: float
    coarse_step_cells: int
    stride_cells: int
    seconds: float
    algorithm: str
    workspace_bytes: int
    heading_sigma_deg: float
    heading_search: int
    outlier_density_per_m: float
    global_error: GlobalError
    map_config_name: str
    predicts: str
    points_per_cell: float
    sigma_h_m: Optional[float]
    map_config: MapConfig
    field: Raster
    evaluated: Raster


class FieldResult(_FieldRequired, total=False):
    """`trn field --json` plus the rasters: field (metres on the map's grid;
    NaN outside the area, +inf where nothing is informative) and evaluated
    (1 computed, 0 interpolated, NaN outside). file is the out option or
    None."""


#: What trn.read_raster returns: (heights, geotransform, CRS WKT or None).
RasterRead = Tuple[Raster, Transform, Optional[str]]

#: A CRS as the calls take it: "EPSG:n", WKT, PROJ text, an EPSG number, or
#: any object with to_wkt() (pyproj.CRS, rasterio.crs.CRS).
CrsLike = Union[str, int, None, object]
