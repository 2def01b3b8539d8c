/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/dem_io.h - DEMs in and out of GDAL, and map <-> cell coordinates.
 *
 * A DEM in memory (dem_t) is always north-up: row 0 is the northern edge,
 * column 0 the western edge, rows run south, columns run east. The cell is
 * square, cell_m metres. The core's grids take it as is (x = column,
 * y = row), so the core's +y points SOUTH in map terms; every conversion
 * between map coordinates (x east, y north, metres) and cells goes through
 * dem_map_to_cell / dem_cell_to_map.
 *
 * Cell (c, r) is centred at map coordinates
 *     X = gt[0] + (c + 0.5) * gt[1],   Y = gt[3] + (r + 0.5) * gt[5]
 * with gt[1] = cell_m > 0 and gt[5] = -cell_m (GDAL's geotransform, kept
 * after normalisation). A file stored south-up (gt[5] > 0) or east-to-west
 * (gt[1] < 0) is flipped on reading and its geotransform adjusted, so the
 * same map coordinates still name the same heights. Rotated geotransforms
 * and non-square cells are rejected.
 *
 * GDAL is loaded at run time (gdal_dl.h): reading or writing a file, or
 * checking a CRS, loads it; when it cannot be loaded those calls fail with a
 * reason that says how to install it.
 *
 * In-memory rasters: wherever a path is taken (dem_read, dem_read_raw,
 * dem_write_gtiff, and so every command's --dem, --local, --out ...), a name
 * DEM_MEM_PREFIX "N" made by dem_mem_put (an input: the caller's heights,
 * by pointer) or dem_mem_name (an output slot that dem_write_gtiff fills)
 * stands for a file. They need no GDAL. This is how the Python package hands
 * numpy arrays to the command's run layer and gets its rasters back. */
#ifndef TRN_DEM_IO_H
#define TRN_DEM_IO_H

#include <stddef.h>

typedef struct {
    float *data;   /* width*height heights, row-major, NaN = not seen */
    int width;     /* columns */
    int height;    /* rows */
    double gt[6];  /* GDAL geotransform in metres, north-up after normalisation */
    double cell_m; /* gt[1] = -gt[5] */
    char *srs_wkt; /* the file's CRS as WKT (in metres when converted), or NULL when it had none */
} dem_t;

/* Read band `band` (1-based) of anything GDAL opens, in metres. Not seen
 * (NaN): the band's no-data value, its mask (when not all-valid), non-finite
 * values and |value| >= 3.0e38 (+-FLT_MAX, the ISIS special pixels of float
 * cubes, the PDS/ESRI -3.4028226550889e38 filler). A geographic or
 * geocentric CRS is refused (no CRS is accepted: a rover-frame map); a CRS
 * whose linear unit is not the metre (feet, US survey feet) has its
 * geotransform converted to metres and srs_wkt is that CRS in metres.
 * Heights: raw * band scale + band offset, times the band's unit (metres,
 * feet, US survey feet, cm, mm, km; none: a compound CRS's vertical unit,
 * else metres); any other unit is refused. max_dim bounds width and height
 * (the reason names the gdal_translate cut). Returns 0 on success; on
 * failure returns -1 and writes a one-line reason (no trailing newline)
 * into err. */
int dem_read(const char *path, int band, int max_dim, dem_t *dem, char *err, size_t err_len);

/* Read band `band` of a raster as stored, float32, without dem_read's
 * conversions (no unit, no-data or flip; cells its mask marks invalid are
 * NaN; +-inf kept): what a command wrote (dem_write_gtiff) read back. No size
 * bound. dem->srs_wkt is the raster's CRS text or NULL; cell_m is gt[1].
 * Returns 0, or -1 with a reason. */
int dem_read_raw(const char *path, int band, dem_t *dem, char *err, size_t err_len);

/* Write data (width x height, north-up as dem_t) as a one-band float32
 * GeoTIFF with geotransform gt, no-data NaN, and srs_wkt when not NULL/empty.
 * Returns 0 or -1 with a reason in err. */
int dem_write_gtiff(const char *path, const float *data, int width, int height, const double gt[6],
                    const char *srs_wkt, char *err, size_t err_len);

/* Free what dem_read allocated; dem is zeroed. */
void dem_free(dem_t *dem);

/* Map coordinates -> fractional cell coordinates (cell centres at integers). */
void dem_map_to_cell(const double gt[6], double x_m, double y_m, double *col, double *row);

/* Fractional cell coordinates -> map coordinates. */
void dem_cell_to_map(const double gt[6], double col, double row, double *x_m, double *y_m);

/* Nearest cell of a map position; 1 if it lies on the map, 0 if off it. */
int dem_cell_of(const dem_t *dem, double x_m, double y_m, int *col, int *row);

/* Convert a user CRS text (EPSG:xxxx, WKT, PROJ string, IAU_2015:xxxx ...)
 * to WKT. Returns a malloc'd string or NULL with a reason in err. */
char *dem_srs_to_wkt(const char *user, char *err, size_t err_len);

/* ---- in-memory rasters ---------------------------------------------------- */

#define DEM_MEM_PREFIX "trn-mem:"

/* 1 when path is an in-memory raster name (DEM_MEM_PREFIX...), else 0. */
int dem_is_mem(const char *path);

/* Most bands an in-memory input raster holds. */
#define DEM_MEM_MAX_BANDS 8

/* Register `bands` planes of width x height values (each row-major, row 0 at
 * gt[3]; band k, 1-based, at data + (k - 1) width height) as an input raster
 * and write its name into name: band 1 the heights, later bands what an
 * option reads by band (trn localize --centroid-bands). Every band shares
 * the geotransform and the CRS; the no-data value and the CRS's vertical
 * unit apply to band 1 only, later bands are read as stored (NaN and +-inf
 * still "not seen"). data is NOT copied: it must stay
 * valid and unchanged until dem_mem_drop(name); each dem_read copies it. gt
 * is the GDAL geotransform (finite; rotation and non-square cells are
 * refused when read, as a file's); has_nodata/nodata a value that means
 * "not seen" (NaN, +-inf and |v| >= 3e38 always do); crs the CRS as any text
 * GDAL reads (EPSG:n, WKT, PROJ) or NULL/"" for none (metres, a rover-frame
 * map); label what messages call the raster ("map array").
 * The CRS: where GDAL loads, a text it cannot read is refused here, and a
 * geographic or geocentric CRS, or one whose unit has no length in metres,
 * when the raster is read; a foot CRS has its geotransform converted to
 * metres (dem_read). Where GDAL does not load, only a WKT whose first keyword
 * names a geographic or geocentric CRS is refused: the geotransform and the
 * heights are then taken as metres, whatever the text says.
 * Returns 0, or -1 with a reason. */
int dem_mem_put(const float *data, int width, int height, int bands, const double gt[6],
                int has_nodata, double nodata, const char *crs, const char *label, char *name,
                size_t name_len, char *err, size_t err_len);

/* A fresh in-memory name, for a command to write an output to. 0, or -1
 * when name_len is too short. */
int dem_mem_name(char *name, size_t name_len);

/* Forget the raster named name (an input's data is the caller's again; an
 * output's is freed). Unknown names are ignored. */
void dem_mem_drop(const char *name);

#endif /* TRN_DEM_IO_H */
