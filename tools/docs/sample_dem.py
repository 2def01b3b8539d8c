#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""tools/docs/sample_dem.py OUT.tif - a DEM to follow the README's "Your own DEM
in ten minutes" with: matplotlib's sample DEM of the Jacksboro fault,
Tennessee (Debian python-matplotlib-data, `bash tools/setup.sh real`), 403 x
344 cells of 3 arc-seconds, written as a float32 GeoTIFF in geographic
coordinates (WGS 84, degrees), as an SRTM tile arrives. Row 0 is the north
edge. The walkthrough's test (tools/test.d/48-walkthrough.sh) uses it too."""
import glob
import os
import sys

import numpy as np
from osgeo import gdal, osr


def main(argv):
    if len(argv) != 1:
        print("usage: sample_dem.py OUT.tif", file=sys.stderr)
        return 2
    found = glob.glob("/usr/share/matplotlib/**/jacksboro_fault_dem.npz", recursive=True)
    if not found:
        print("sample_dem.py: matplotlib's sample data are not installed (bash tools/setup.sh real)",
              file=sys.stderr)
        return 1
    os.makedirs(os.path.dirname(os.path.abspath(argv[0])), exist_ok=True)
    d = np.load(found[0])
    z = d["elevation"].astype(np.float32)
    north = max(float(d["ymin"]), float(d["ymax"]))
    ds = gdal.GetDriverByName("GTiff").Create(argv[0], z.shape[1], z.shape[0], 1, gdal.GDT_Float32)
    ds.SetGeoTransform((float(d["xmin"]), float(d["dx"]), 0.0, north, 0.0, -float(d["dy"])))
    srs = osr.SpatialReference()
    srs.ImportFromEPSG(4326)
    ds.SetProjection(srs.ExportToWkt())
    ds.GetRasterBand(1).WriteArray(z)
    ds = None
    print(f"sample_dem.py: wrote {argv[0]} ({z.shape[1]} x {z.shape[0]} cells, WGS 84 degrees)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
