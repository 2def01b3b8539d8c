# SPDX-License-Identifier: Apache-2.0
"""tools/real/cases.py - seeded localization cases cut from a real global DEM.

For a global DEM G (north-up, square cell c metres) a case is:

* truth: a random map position (continuous, so off the cell centres), at least
  `margin_cells` = R + window + prior offset + 3 cells from the map edge, whose local
  footprint is mostly valid (>= min_valid of its (2R+1)^2 global cells finite);
* local DEM: (2R+1) x (2R+1) cells of size c centred on the rover (the rover is at the
  centre of the centre cell), cell (i, j) sampled from G at truth + ((j-R)c, (R-i)c)
  by bilinear interpolation (or `cubic`: Keys' cubic convolution, a = -0.5, to avoid
  the inverse crime of bilinear-on-bilinear); in the ROVER FRAME (geotransform
  (-(R+0.5)c, c, 0, (R+0.5)c, 0, -c), no CRS: the rover at map-frame (0, 0));
  plus one constant height offset drawn in +-offset_m, plus Gaussian noise of sigma
  0.01 m + 0.0004 r^2 / c (r the range in metres); seen only inside a 120 deg wedge
  of random azimuth, at ranges 1.5 c <= r <= R c (unseen: NaN, also no-data);
* prior: truth + a uniform offset in +-prior_cells cells per axis; search window
  +-window_cells cells (half-width, metres in the list file).

A prior that misses (`prior_miss` F > 0, bench_real.py --prior-miss F): round(F n) of the n
cases, chosen by a generator of their own (seeded (seed, 1)), get instead a prior whose
Chebyshev distance from the truth is uniform in [window_cells + 1.5, miss_max_cells] cells
(default 7.5-12 with the +-6-cell window: from just past the window's edge to one window's
width away; the axis, the side and the offset along the other axis, uniform within that
distance, drawn at random): the truth lies at least 1.5 cells outside the search window, so
no pose in the window is within 1.5 cells of it. The dead reckoning drifted past what the
window was sized for. The margin then grows to R + window + miss_max + 3 cells (every
window as far inside the map as without misses), so the truths differ from those of the
construction without misses; the main generator's draws are the same in number and order.

Model error (`fine`, bench_real.py --truth-fine K): the global map G is then the fine
DEM F block-averaged over K x K cells (block_average: cell c = K c_F, the same
corner, so coarse cell (I, J)'s centre is the centroid of F's cells (KI..KI+K-1,
KJ..KJ+K-1)), or, with --fine-map point, F's point samples every K cells
(point_sample: coarse cell (I, J) is F's cell (KI + K//2, KJ + K//2), centred on
it), and the local DEM is sampled from F instead (bilinear on F's grid at
truth + ((j-R)c, (R-i)c), c the COARSE cell): the rover sees the true surface, the
map is a smoothed coarser product. With --fine-local mean each local cell is instead
the mean of F over the cell (K x K sub-samples at F's spacing, bilinear on F): a rover
that grids its dense stereo points into the map's cells by averaging. Truth, prior,
window, radius, visibility and noise are all in coarse cells, as without `fine`.

Map coordinates of global cell (row, col)'s centre: x = x0 + (col + 0.5) c,
y = y0 - (row + 0.5) c, with (x0, c, 0, y0, 0, -c) the DEM's geotransform.
"""
import math
import os
from dataclasses import dataclass, field

import numpy as np
from osgeo import gdal

gdal.UseExceptions()


class InputError(Exception):
    """Bad input: the benchmark exits 1 with this one-line reason."""


@dataclass
class Dem:
    z: np.ndarray  # float64, NaN = missing, row 0 north
    x0: float
    y0: float
    c: float
    path: str = ""

    def frac_index(self, x, y):
        """Fractional (row, col) of map point (x, y): integers at cell centres."""
        return (self.y0 - y) / self.c - 0.5, (x - self.x0) / self.c - 0.5

    def xy(self, row, col):
        """Map point of fractional (row, col)."""
        return self.x0 + (col + 0.5) * self.c, self.y0 - (row + 0.5) * self.c


def read_dem(path):
    """Band 1 of a north-up, square-cell raster as a Dem (no-data -> NaN)."""
    try:
        ds = gdal.Open(path)
    except RuntimeError as e:
        raise InputError(f"cannot open {path}: {str(e).strip()}")
    gt = ds.GetGeoTransform()
    srs = ds.GetSpatialRef()
    if srs is not None and srs.IsGeographic():
        raise InputError(f"{path}: geographic CRS (degrees); reproject it to metres first, e.g. "
                         f"gdalwarp -t_srs EPSG:<UTM zone> -r bilinear {os.path.basename(path)} out.tif")
    if gt[2] != 0 or gt[4] != 0 or gt[5] >= 0:
        raise InputError(f"{path}: not north-up (gdalwarp it to a north-up grid)")
    if abs(gt[1] + gt[5]) > 1e-9 * gt[1]:
        raise InputError(f"{path}: cells not square ({gt[1]:g} x {-gt[5]:g})")
    b = ds.GetRasterBand(1)
    z = b.ReadAsArray().astype(np.float64)
    nd = b.GetNoDataValue()
    if nd is not None and not math.isnan(nd):
        z[z == nd] = np.nan
    mask = b.GetMaskBand().ReadAsArray()
    z[mask == 0] = np.nan
    return Dem(z, gt[0], gt[3], gt[1], path)


def block_average(dem, k):
    """`dem` averaged over k x k blocks of cells: cell k c, the same north-west corner
    (x0, y0); trailing rows / columns that do not fill a block are dropped; a block
    with any missing cell is missing."""
    k = int(k)
    if k < 1:
        raise InputError(f"block size {k}: must be >= 1")
    nr, nc = dem.z.shape[0] // k, dem.z.shape[1] // k
    if nr < 1 or nc < 1:
        raise InputError(f"{dem.path}: smaller than one {k} x {k} block")
    z = dem.z[:nr * k, :nc * k].reshape(nr, k, nc, k).mean(axis=(1, 3))
    return Dem(z, dem.x0, dem.y0, dem.c * k, dem.path)


def point_sample(dem, k):
    """`dem`'s point samples every k cells: coarse cell (I, J) holds fine cell
    (k I + k // 2, k J + k // 2) and is centred on it (cell k c; the north-west corner
    moves by (k // 2 + 1/2 - k / 2) fine cells). A map that samples the terrain at its
    cell centres, as a rendered rock field does, where block_average smooths it."""
    k = int(k)
    if k < 1:
        raise InputError(f"sampling step {k}: must be >= 1")
    h = k // 2
    z = dem.z[h::k, h::k]
    nr, nc = (dem.z.shape[0] - h + k - 1) // k, (dem.z.shape[1] - h + k - 1) // k
    if nr < 1 or nc < 1 or z.shape != (nr, nc):
        raise InputError(f"{dem.path}: smaller than one {k} x {k} block")
    shift = (h + 0.5 - 0.5 * k) * dem.c
    return Dem(z.copy(), dem.x0 + shift, dem.y0 - shift, dem.c * k, dem.path)


def write_global(path, dem, like=None):
    """`dem` as a north-up float32 GeoTIFF (no-data NaN), with the CRS of the raster
    `like` (none without it)."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    tmp = path + ".part.tif"
    ds = gdal.GetDriverByName("GTiff").Create(tmp, dem.z.shape[1], dem.z.shape[0], 1, gdal.GDT_Float32,
                                              options=["COMPRESS=DEFLATE", "TILED=YES"])
    ds.SetGeoTransform((dem.x0, dem.c, 0.0, dem.y0, 0.0, -dem.c))
    if like is not None:
        wkt = gdal.Open(like).GetProjection()
        if wkt:
            ds.SetProjection(wkt)
    b = ds.GetRasterBand(1)
    b.SetNoDataValue(float("nan"))
    b.WriteArray(dem.z.astype(np.float32))
    ds = None
    os.replace(tmp, path)
    return path


def write_local(path, z, c, centroids=None, counts=None):
    """A rover-frame local DEM GeoTIFF: float32, no CRS, no-data NaN. With centroids
    (cx, cy), bands 2 and 3 hold them (trn localize --centroid-bands 2); with counts (the
    cells' point counts), the band after those (trn localize --count-band 2 or 4)."""
    n = z.shape[0]
    r = (n - 1) // 2
    bands = [z] + ([] if centroids is None else list(centroids)) + ([] if counts is None else [counts])
    ds = gdal.GetDriverByName("GTiff").Create(path, z.shape[1], n, len(bands), gdal.GDT_Float32)
    ds.SetGeoTransform((-(r + 0.5) * c, c, 0.0, (r + 0.5) * c, 0.0, -c))
    for k, v in enumerate(bands):
        b = ds.GetRasterBand(k + 1)
        b.SetNoDataValue(float("nan"))
        b.WriteArray(np.asarray(v).astype(np.float32))
    ds = None


# --- interpolation ----------------------------------------------------------------
def _keys(t, a=-0.5):
    """Keys' cubic convolution kernel at |t|."""
    t = np.abs(t)
    return np.where(t <= 1, (a + 2) * t**3 - (a + 3) * t**2 + 1,
                    np.where(t < 2, a * t**3 - 5 * a * t**2 + 8 * a * t - 4 * a, 0.0))


def sample(z, rows, cols, method="bilinear"):
    """z at fractional (rows, cols) (arrays of one shape; all inside the grid with
    a 2-cell margin for cubic). NaN neighbours give NaN."""
    r0 = np.floor(rows).astype(int)
    c0 = np.floor(cols).astype(int)
    lo, hi = (0, 1) if method == "bilinear" else (1, 2)
    if r0.min() < lo or c0.min() < lo or r0.max() + hi >= z.shape[0] or c0.max() + hi >= z.shape[1]:
        raise ValueError("sample: position too close to the grid's edge")
    fr = rows - r0
    fc = cols - c0
    if method == "bilinear":
        return ((1 - fr) * (1 - fc) * z[r0, c0] + (1 - fr) * fc * z[r0, c0 + 1]
                + fr * (1 - fc) * z[r0 + 1, c0] + fr * fc * z[r0 + 1, c0 + 1])
    if method == "cubic":
        out = np.zeros(rows.shape)
        for di in range(-1, 3):
            wr = _keys(fr - di)
            for dj in range(-1, 3):
                out += wr * _keys(fc - dj) * z[r0 + di, c0 + dj]
        return out
    raise InputError(f"unknown resampling '{method}' (bilinear | cubic)")


# --- cases ------------------------------------------------------------------------
@dataclass
class CaseParams:
    radius: int = 20  # R, cells
    window_cells: float = 6.0  # search half-width, cells
    prior_cells: float = 4.0  # prior offset bound per axis, cells
    offset_m: float = 50.0  # constant height offset bound, metres
    fov_deg: float = 120.0  # seen wedge
    min_range_cells: float = 1.5  # the rover's own cells: unseen
    noise0_m: float = 0.01  # sigma = noise0 + noise_k * r^2 / c
    noise_k: float = 0.0004
    noise: bool = True
    full_view: bool = False  # tests: every cell within R seen
    resample: str = "bilinear"
    min_valid: float = 0.95
    local: str = "point"  # with `fine`: "point" | "mean" | "binned" (see make_local)
    centroids: bool = False  # "binned": each case's extra gets the cells' centroids (cx, cy)
    counts: bool = False  # "binned": each case's extra gets the cells' point counts (n)
    points_draw: int = 0  # "binned": which draw of the points (0: the cases' own; k > 0 another
    #                      draw of the points and their noise, the truths, priors and views kept)
    mast_m: float = 0.0  # > 0: a mast that high sees the cells (mast_visible); 0: every cell in the wedge
    outlier_frac: float = 0.0  # share of seen cells that are stereo blunders (see make_local)
    prior_miss: float = 0.0  # share of the cases whose prior misses (the truth outside the window)
    miss_max_cells: float = 12.0  # a missing prior's largest Chebyshev distance from the truth, cells

    @property
    def miss_min_cells(self):
        """A missing prior's least Chebyshev distance from the truth: 1.5 cells past the window."""
        return self.window_cells + 1.5

    @property
    def margin_cells(self):
        far = max(self.prior_cells, self.miss_max_cells) if self.prior_miss > 0.0 else self.prior_cells
        return self.radius + self.window_cells + far + 3


@dataclass
class Case:
    index: int
    truth: tuple  # map metres
    prior: tuple
    window_m: float
    local: np.ndarray  # (2R+1)^2, NaN unseen
    seen: np.ndarray  # bool
    azimuth_deg: float
    offset_m: float
    path: str = ""
    extra: dict = field(default_factory=dict)
    prior_miss: bool = False  # the prior misses: the truth lies outside the window


def rover_frame_offsets(radius, c):
    """(east, north) metres of each local cell centre from the rover (the centre cell)."""
    k = np.arange(-radius, radius + 1)
    e = np.broadcast_to(k[None, :] * c, (k.size, k.size))
    n = np.broadcast_to(-k[:, None] * c, (k.size, k.size))
    return e, n


def visibility(radius, c, azimuth_deg, p):
    """Seen mask: range within [min_range, R] cells and (unless full view) inside
    the fov wedge centred on azimuth_deg (counter-clockwise from east)."""
    e, n = rover_frame_offsets(radius, c)
    r = np.hypot(e, n)
    seen = (r <= radius * c + 1e-9) & (r >= p.min_range_cells * c - 1e-9)
    if not p.full_view:
        az = np.degrees(np.arctan2(n, e))
        d = (az - azimuth_deg + 180.0) % 360.0 - 180.0
        seen &= np.abs(d) <= p.fov_deg / 2
    return seen


def cell_positions(fr, fc, R, scale, turn_deg, du=0.0, dv=0.0):
    """Fractional (rows, cols) in the source grid of each local cell's point offset
    (du east, dv south) local cells from its centre; the rover at source (fr, fc),
    `scale` source cells per local cell, the terrain turned turn_deg counterclockwise."""
    k = np.arange(-R, R + 1, dtype=np.float64)
    x, y = k[None, :] + du + 0 * k[:, None], k[:, None] + dv + 0 * k[None, :]
    if turn_deg == 0.0:
        return fr + y * scale, fc + x * scale
    ct, st = math.cos(math.radians(turn_deg)), math.sin(math.radians(turn_deg))
    # column offset x (east), row offset y (south): (x c + y s, -x s + y c)
    return fr + (-x * st + y * ct) * scale, fc + (x * ct + y * st) * scale


@dataclass
class Bins:
    h: np.ndarray  # per local cell: the mean of its points' heights, noise included (NaN: no point)
    h0: np.ndarray  # the same without the noise
    n: np.ndarray  # points per cell
    sd: np.ndarray  # sd of the mean of the cell's points' noises, sqrt(sum sd_i^2) / n
    cx: np.ndarray  # the points' centroid, local cells east of the cell's centre
    cy: np.ndarray  # and south of it


def binned_points(src, fr, fc, R, scale, turn_deg, p, cell_m, gen, noisy=True, centre=(0, 0)):
    """The issue's rover: stereo points of the true ground (the source surface, bilinear)
    scattered uniformly at random (generator gen) over the local map's square, on
    average one per source cell (scale^2 per local cell, so a cell's count varies), binned
    into the local cells around the rover at its sub-cell position (fr, fc). Each point's
    noise sd is the model's at its own range; a cell is the mean of its points. The square
    is the (2R+1)^2 cells about the local cell `centre` (whole cells east, south of the
    rover's; (0, 0): about the rover)."""
    m = 2 * R + 1
    ox, oy = int(centre[0]), int(centre[1])
    npts = int(round(m * m * scale * scale))
    x = gen.uniform(ox - R - 0.5, ox + R + 0.5, npts)  # local east, local cells from the rover
    y = gen.uniform(oy - R - 0.5, oy + R + 0.5, npts)  # local south
    ct, st = math.cos(math.radians(turn_deg)), math.sin(math.radians(turn_deg))
    z = sample(src.z, fr + (-x * st + y * ct) * scale, fc + (x * ct + y * st) * scale)
    sd = p.noise0_m + p.noise_k * (x * x + y * y) * cell_m
    zn = z + gen.standard_normal(npts) * sd if noisy else z
    use = np.isfinite(z)
    ix = np.clip(np.floor(x + 0.5).astype(int) - ox + R, 0, m - 1)
    iy = np.clip(np.floor(y + 0.5).astype(int) - oy + R, 0, m - 1)
    cell = (iy * m + ix)[use]

    def per_cell(w):
        return np.bincount(cell, w[use], minlength=m * m).reshape(m, m)
    n = np.bincount(cell, minlength=m * m).reshape(m, m)
    with np.errstate(invalid="ignore", divide="ignore"):
        k = np.arange(-R, R + 1, dtype=np.float64)
        return Bins(per_cell(zn) / n, per_cell(z) / n, n, np.sqrt(per_cell(sd * sd)) / n,
                    per_cell(x) / n - (k + ox)[None, :], per_cell(y) / n - (k + oy)[:, None])


def points_generator(rng, p, shape):
    """The points' own generator: seeded from one normal per local cell drawn from the
    case's generator (what the other constructions draw for their noise), so that the
    cases (truth, wedge, offset, prior) stay those of the other constructions. Draw
    p.points_draw > 0 adds the draw to that seed: other points and noise, the same case."""
    if rng is None or not p.noise:
        return np.random.default_rng(0)
    seed = np.frombuffer(rng.standard_normal(shape).tobytes(), dtype=np.uint32)
    if p.points_draw > 0:
        seed = np.append(seed, np.uint32(p.points_draw))
    return np.random.default_rng(seed)


def mast_visible(z, r0, c0, rows, cols, mast_m):
    """Which ground points (rows, cols) (fractional indices into heights z, bilinear) a
    mast head mast_m above the ground at (r0, c0) sees: the straight line from the head
    to the point's ground passes above the surface at every sample along it, samples
    at most half a grid cell apart (the end points excluded). A sample on no-data does
    not block. Vectorized over the points: every ray gets the longest ray's sample
    count, each at its own spacing."""
    rows, cols = np.asarray(rows, dtype=np.float64), np.asarray(cols, dtype=np.float64)
    head = sample(z, np.array([r0]), np.array([c0]))[0] + mast_m
    end = sample(z, rows, cols)
    n = np.maximum(2, np.ceil(2.0 * np.hypot(rows - r0, cols - c0))).ravel()
    k = np.arange(1, int(n.max()))
    t = np.minimum(k[None, :] / n[:, None], 1.0)  # past a ray's own end: its end (never blocks)
    inner = k[None, :] < n[:, None]
    rr = r0 + t * (rows.ravel()[:, None] - r0)
    cc = c0 + t * (cols.ravel()[:, None] - c0)
    line = head + t * (end.ravel()[:, None] - head)
    ground = sample(z, rr, cc)
    blocked = inner & (ground >= line)  # NaN ground compares False: no block
    return ~blocked.any(axis=1).reshape(rows.shape)


def make_local(dem, truth, p, rng=None, azimuth_deg=0.0, offset_m=0.0, fine=None, turn_deg=0.0,
               extra=None):
    """The local DEM (heights + offset + noise, NaN unseen) of a rover at truth: cells
    of dem's cell size, heights sampled from `fine` (the true surface) if given, else
    from dem itself. turn_deg: the rover's believed heading is off by this much, so
    local cell offset (east e, north n) shows the terrain at (e, n) turned turn_deg
    counterclockwise about the rover (trn localize --heading-window-deg then finds
    +turn_deg as the correction). p.local: "point" (each cell the surface at its
    centre), "mean" (with `fine`: the mean of fine-spaced sub-samples over the cell),
    "binned" (with `fine`: binned_points, its own noise). p.mast_m > 0: only cells whose ground a mast
    that high above the rover's ground sees through the true surface (mast_visible). With
    "binned", p.centroids and a dict `extra`: extra["cx"], extra["cy"] are the cells' points'
    centroids (local cells east and south of each cell's centre; NaN where unseen); with
    p.counts, extra["n"] the cells' point counts (NaN where no point fell)."""
    R = p.radius
    src = dem if fine is None else fine
    scale = 1.0 if fine is None else dem.c / fine.c  # source cells per local cell
    fr, fc = src.frac_index(*truth)
    e, n = rover_frame_offsets(R, dem.c)
    sigma = p.noise0_m + p.noise_k * (e**2 + n**2) / dem.c
    binned = p.local == "binned" and fine is not None
    if binned:
        gen = points_generator(rng, p, sigma.shape)
        b = binned_points(src, fr, fc, R, scale, turn_deg, p, dem.c, gen, p.noise and rng is not None)
        h = b.h
        if p.centroids and extra is not None:
            extra["cx"], extra["cy"] = b.cx, b.cy
        if p.counts and extra is not None:
            extra["n"] = np.where(b.n > 0, b.n, np.nan).astype(np.float64)
    else:
        # sub-samples per local cell axis: one (its centre), or with "mean" and `fine`
        # the fine cells' count across it, spread evenly (a rover gridding dense stereo
        # into the map's cells by averaging)
        ns = max(1, int(round(scale))) if (fine is not None and p.local == "mean") else 1
        subs = (np.arange(ns) + 0.5) / ns - 0.5
        h = np.zeros((2 * R + 1, 2 * R + 1))
        for du in subs:  # du along the local columns (east), dv along its rows (south)
            for dv in subs:
                h += sample(src.z, *cell_positions(fr, fc, R, scale, turn_deg, du, dv), p.resample)
        h = h / (ns * ns)
    h = h + offset_m
    seen = visibility(R, dem.c, azimuth_deg, p)
    if p.mast_m > 0.0:
        seen &= mast_visible(src.z, fr, fc, *cell_positions(fr, fc, R, scale, turn_deg), p.mast_m)
    if p.noise and rng is not None and not binned:
        h = h + rng.standard_normal(h.shape) * sigma
    seen &= np.isfinite(h)
    if p.outlier_frac > 0.0 and rng is not None and seen.any():
        # stereo blunders (a wrong disparity): each seen cell, with probability outlier_frac,
        # gets a height uniform over the seen heights' range widened by that range on each
        # side, knowing nothing of the true height there (drawn only when asked, so the
        # default cases stay bit-identical)
        lo, hi = float(np.min(h[seen])), float(np.max(h[seen]))
        span = max(hi - lo, 1e-6)
        bad = seen & (rng.uniform(size=h.shape) < p.outlier_frac)
        h = np.where(bad, rng.uniform(lo - span, hi + span, size=h.shape), h)
    if extra is not None and "cx" in extra:
        extra["cx"] = np.where(seen, extra["cx"], np.nan)
        extra["cy"] = np.where(seen, extra["cy"], np.nan)
    return np.where(seen, h, np.nan), seen


def draw_truth(dem, rng, p, tries=10000):
    m = p.margin_cells
    R = p.radius
    nr, nc = dem.z.shape
    if nr - 1 - 2 * m < 1 or nc - 1 - 2 * m < 1:
        raise InputError(f"{dem.path}: {nc} x {nr} cells is too small for a margin of {m:g} cells")
    valid = np.isfinite(dem.z)
    for _ in range(tries):
        r = rng.uniform(m, nr - 1 - m)
        cc = rng.uniform(m, nc - 1 - m)
        ir, ic = int(round(r)), int(round(cc))
        foot = valid[ir - R - 1:ir + R + 2, ic - R - 1:ic + R + 2]
        if foot.mean() < p.min_valid:
            continue
        return dem.xy(r, cc)
    raise InputError(f"{dem.path}: no position with a mostly valid local map")


def miss_choice(n, seed, p):
    """Which of n cases get a prior that misses (a set of indices, round(prior_miss n) of
    them), and the generator of their offsets: both from a generator of their own, seeded
    (seed, 1), so that the main generator's draws stay those of the construction without."""
    if not 0.0 <= p.prior_miss <= 1.0:
        raise InputError(f"prior_miss {p.prior_miss}: must be in [0, 1]")
    if p.prior_miss > 0.0 and not (p.miss_max_cells >= p.miss_min_cells and math.isfinite(p.miss_max_cells)):
        raise InputError(f"miss_max_cells {p.miss_max_cells}: must be at least window + 1.5 = "
                         f"{p.miss_min_cells:g} cells")
    gm = np.random.default_rng((seed, 1))
    k = int(round(p.prior_miss * n))
    return (set(int(i) for i in gm.permutation(n)[:k]) if k else set()), gm


def miss_offset(gm, p):
    """A missing prior's offset from the truth (east, north), cells: its Chebyshev distance
    uniform in [window + 1.5, miss_max], on a random axis and side, the other axis uniform
    within that distance."""
    dist = gm.uniform(p.miss_min_cells, p.miss_max_cells)
    axis = int(gm.integers(2))
    side = 1.0 if gm.uniform() < 0.5 else -1.0
    d = np.empty(2)
    d[axis] = side * dist
    d[1 - axis] = gm.uniform(-dist, dist)
    return d


def generate(dem, n, seed, p, folder=None, fine=None):
    """n seeded cases; with `folder`, each local DEM is written there as a GeoTIFF
    and a batch list (LOCAL.tif PRIOR_X PRIOR_Y WINDOW_M per line) as cases.txt.
    With `fine` (the surface dem was block-averaged from) the local DEMs are sampled
    from it (model error); everything else is in dem's cells."""
    rng = np.random.default_rng(seed)
    c = dem.c
    misses, gm = miss_choice(n, seed, p)
    cases = []
    for i in range(n):
        truth = draw_truth(dem, rng, p)
        az = float(rng.uniform(-180.0, 180.0))
        off = float(rng.uniform(-p.offset_m, p.offset_m))
        extra = {}
        local, seen = make_local(dem, truth, p, rng, az, off, fine, extra=extra)
        d = rng.uniform(-p.prior_cells, p.prior_cells, 2) * c
        if i in misses:
            d = miss_offset(gm, p) * c
        prior = (truth[0] + float(d[0]), truth[1] + float(d[1]))
        cases.append(Case(i, truth, prior, p.window_cells * c, local, seen, az, off, extra=extra,
                          prior_miss=i in misses))
    if folder is not None:
        write_cases(cases, c, folder)
    return cases


def write_cases(cases, c, folder):
    os.makedirs(folder, exist_ok=True)
    lines = []
    for cs in cases:
        cs.path = os.path.join(folder, f"local_{cs.index:05d}.tif")
        cen = (cs.extra["cx"], cs.extra["cy"]) if "cx" in cs.extra else None
        write_local(cs.path, cs.local, c, cen, cs.extra.get("n"))
        lines.append(f"{cs.path} {cs.prior[0]!r} {cs.prior[1]!r} {cs.window_m!r}\n")
    lst = os.path.join(folder, "cases.txt")
    with open(lst, "w") as f:
        f.writelines(lines)
    return lst
