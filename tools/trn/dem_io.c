/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/dem_io.c - GDAL C API DEM reading and GeoTIFF writing. */
#include "dem_io.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <gdal.h>
#include <ogr_srs_api.h>

static void set_err(char *err, size_t n, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static void set_err(char *err, size_t n, const char *fmt, ...)
{
    va_list ap;
    size_t i;
    if (err == NULL || n == 0) {
        return;
    }
    va_start(ap, fmt);
    vsnprintf(err, n, fmt, ap);
    va_end(ap);
    /* One line: GDAL messages may hold newlines. */
    for (i = 0; err[i] != '\0'; ++i) {
        if (err[i] == '\n' || err[i] == '\r') {
            err[i] = ' ';
        }
    }
}

/* GDAL once per process, quiet: its messages reach the user through our
 * one-line reasons (CPLGetLastErrorMsg), not on their own. */
static void gdal_init(void)
{
    static int done = 0;
    if (!done) {
        GDALAllRegister();
        CPLSetErrorHandler(CPLQuietErrorHandler);
        done = 1;
    }
}

static const char *last_gdal_msg(void)
{
    const char *m = CPLGetLastErrorMsg();
    return (m != NULL && *m != '\0') ? m : "GDAL gave no reason";
}

void dem_free(dem_t *dem)
{
    if (dem == NULL) {
        return;
    }
    free(dem->data);
    free(dem->srs_wkt);
    memset(dem, 0, sizeof *dem);
}

static char *dup_string(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d != NULL) {
        memcpy(d, s, n);
    }
    return d;
}

/* A unit name (a band's unit type) -> metres per unit; 1 if known, 0 if not.
 * Case, surrounding blanks, '_' and '-' are ignored ("US_survey_foot" is
 * "us survey foot"). An empty name is the metre (GDAL's "unknown"). */
static int height_unit_to_m(const char *name, double *to_m)
{
    static const struct {
        const char *name;
        double to_m;
    } units[] = {
        {"", 1.0},
        {"m", 1.0},
        {"metre", 1.0},
        {"metres", 1.0},
        {"meter", 1.0},
        {"meters", 1.0},
        {"ft", 0.3048},
        {"foot", 0.3048},
        {"feet", 0.3048},
        {"international foot", 0.3048},
        {"international feet", 0.3048},
        {"us survey foot", 1200.0 / 3937.0},
        {"us survey feet", 1200.0 / 3937.0},
        {"survey foot", 1200.0 / 3937.0},
        {"survey feet", 1200.0 / 3937.0},
        {"ftus", 1200.0 / 3937.0},
        {"us ft", 1200.0 / 3937.0},
        {"ft us", 1200.0 / 3937.0},
        {"foot us", 1200.0 / 3937.0},
        {"us foot", 1200.0 / 3937.0},
        {"us feet", 1200.0 / 3937.0},
        {"cm", 0.01},
        {"centimetre", 0.01},
        {"centimetres", 0.01},
        {"centimeter", 0.01},
        {"centimeters", 0.01},
        {"mm", 0.001},
        {"millimetre", 0.001},
        {"millimetres", 0.001},
        {"millimeter", 0.001},
        {"millimeters", 0.001},
        {"km", 1000.0},
        {"kilometre", 1000.0},
        {"kilometres", 1000.0},
        {"kilometer", 1000.0},
        {"kilometers", 1000.0},
    };
    char norm[64];
    size_t i, k = 0, len;
    while (*name == ' ' || *name == '\t') {
        ++name;
    }
    len = strlen(name);
    while (len > 0 && (name[len - 1] == ' ' || name[len - 1] == '\t')) {
        --len;
    }
    if (len >= sizeof norm) {
        return 0;
    }
    for (i = 0; i < len; ++i) {
        char ch = name[i];
        if (ch == '_' || ch == '-') {
            ch = ' ';
        } else if (ch >= 'A' && ch <= 'Z') {
            ch = (char)(ch - 'A' + 'a');
        }
        norm[k++] = ch;
    }
    norm[k] = '\0';
    for (i = 0; i < sizeof units / sizeof units[0]; ++i) {
        if (strcmp(norm, units[i].name) == 0) {
            *to_m = units[i].to_m;
            return 1;
        }
    }
    return 0;
}

/* Values at or beyond this magnitude are not heights. The rule covers
 * +-FLT_MAX, the usual float "missing" fillers near it (ESRI's and PDS's
 * -3.4028226550889e38), and the five ISIS special pixels of 32-bit float
 * cubes (NULL, LOW_REPR_SAT, LOW_INSTR_SAT, HIGH_INSTR_SAT, HIGH_REPR_SAT:
 * the bit patterns 0xFF7FFFFB..0xFF7FFFFF, -3.40282266e38 .. -FLT_MAX),
 * whether or not the file declares them as no-data. */
#define DEM_NOT_SEEN_ABS 3.0e38

/* The dataset's CRS, checked and brought to metres. No CRS: nothing to do
 * (a local DEM in the rover frame; its units are taken as metres). A
 * geographic or geocentric CRS is refused. A projected or local CRS whose
 * linear unit is not the metre (US survey feet, feet ...) has its
 * geotransform scaled to metres; *out_srs is then a clone of the CRS with
 * metre units (the caller finishes it), else NULL. *vert_to_m is the
 * vertical CRS's unit in metres when the CRS is compound, else 0. */
static int crs_to_metres(GDALDatasetH ds, const char *path, double gt[6],
                         OGRSpatialReferenceH *out_srs, double *vert_to_m, char *err,
                         size_t err_len)
{
    OGRSpatialReferenceH srs = GDALGetSpatialRef(ds);
    char *unit = NULL;
    double to_m;

    *out_srs = NULL;
    *vert_to_m = 0.0;
    if (srs == NULL) {
        return 0;
    }
    if (OSRIsGeographic(srs) || OSRIsGeocentric(srs)) {
        set_err(err, err_len,
                "'%s' is in a %s CRS (%s); reproject it to metres first, e.g. gdalwarp -t_srs "
                "EPSG:326NN "
                "(the UTM zone of the site) -r bilinear IN.tif OUT.tif",
                path, OSRIsGeographic(srs) ? "geographic" : "geocentric",
                OSRIsGeographic(srs) ? "degrees" : "earth-centred axes");
        return -1;
    }
    if (OSRIsCompound(srs)) {
        char *vunit = NULL;
        double v = OSRGetTargetLinearUnits(srs, "VERT_CS", &vunit);
        if (isfinite(v) && v > 0.0) {
            *vert_to_m = v;
        }
    }
    to_m = OSRGetLinearUnits(srs, &unit);
    if (!(isfinite(to_m) && to_m > 0.0)) {
        set_err(
            err, err_len,
            "'%s': its CRS's linear unit '%s' has no length in metres; reproject it to a metre CRS "
            "first, "
            "e.g. gdalwarp -t_srs EPSG:326NN (the UTM zone of the site) -r bilinear IN.tif OUT.tif",
            path, unit != NULL ? unit : "?");
        return -1;
    }
    if (fabs(to_m - 1.0) > 1e-12) {
        OGRSpatialReferenceH m = OSRClone(srs);
        OGRErr e = OGRERR_FAILURE;
        if (m != NULL) {
            e = OGRERR_NONE;
            if (OSRIsCompound(m)) {
                e = OSRStripVertical(m);
            }
            if (e == OGRERR_NONE) {
                e = OSRIsProjected(m) ? OSRSetLinearUnitsAndUpdateParameters(m, SRS_UL_METER, 1.0)
                                      : OSRSetLinearUnits(m, SRS_UL_METER, 1.0);
            }
        }
        if (e != OGRERR_NONE) {
            set_err(err, err_len,
                    "'%s': cannot express its CRS (linear unit '%s') in metres; reproject it to a "
                    "metre CRS first, "
                    "e.g. gdalwarp -t_srs EPSG:326NN (the UTM zone of the site) -r bilinear IN.tif "
                    "OUT.tif",
                    path, unit != NULL ? unit : "?");
            if (m != NULL) {
                OSRDestroySpatialReference(m);
            }
            return -1;
        }
        gt[0] *= to_m;
        gt[1] *= to_m;
        gt[3] *= to_m;
        gt[5] *= to_m;
        *out_srs = m;
    }
    return 0;
}

/* Heights in metres: raw * scale + offset (the band's own), times the
 * height unit. Returns 0 or -1 with a reason. */
static int band_height_scale(GDALRasterBandH b, int band, const char *path, double vert_to_m,
                             double *scale, double *offset, double *to_m, char *err, size_t err_len)
{
    int ok_s = 0, ok_o = 0;
    const char *unit = GDALGetRasterUnitType(b);
    double s = GDALGetRasterScale(b, &ok_s);
    double o = GDALGetRasterOffset(b, &ok_o);

    *scale = ok_s ? s : 1.0;
    *offset = ok_o ? o : 0.0;
    if (!(isfinite(*scale) && *scale != 0.0 && isfinite(*offset))) {
        set_err(err, err_len, "band %d of '%s' has an unusable scale %g / offset %g", band, path,
                *scale, *offset);
        return -1;
    }
    if (unit == NULL) {
        unit = "";
    }
    if (!height_unit_to_m(unit, to_m)) {
        set_err(err, err_len,
                "band %d of '%s' has heights in unit '%s', which trn does not know (metres, feet, "
                "US survey "
                "feet, cm, mm, km); convert the heights to metres first",
                band, path, unit);
        return -1;
    }
    /* No unit on the band: the compound CRS's vertical unit, when it has one. */
    if (unit[0] == '\0' && vert_to_m > 0.0) {
        *to_m = vert_to_m;
    }
    return 0;
}

/* Open path as a raster and check band, size and geotransform (north-up up
 * to flips, nonzero finite pixel size). The dataset, or NULL with the reason. */
static GDALDatasetH open_checked(const char *path, int band, int max_dim, int *w, int *h,
                                 double gt[6], char *err, size_t err_len)
{
    GDALDatasetH ds;
    int nbands;

    CPLErrorReset();
    ds = GDALOpenEx(path, GDAL_OF_RASTER | GDAL_OF_READONLY, NULL, NULL, NULL);
    if (ds == NULL) {
        set_err(err, err_len, "cannot read '%s' as a raster: %s", path, last_gdal_msg());
        return NULL;
    }
    nbands = GDALGetRasterCount(ds);
    *w = GDALGetRasterXSize(ds);
    *h = GDALGetRasterYSize(ds);
    if (band < 1 || band > nbands) {
        set_err(err, err_len, "'%s' has %d band%s, no band %d", path, nbands,
                nbands == 1 ? "" : "s", band);
    } else if (*w < 1 || *h < 1) {
        set_err(err, err_len, "'%s' is %d x %d cells: it has no cells", path, *w, *h);
    } else if (*w > max_dim || *h > max_dim) {
        set_err(err, err_len,
                "'%s' is %d x %d cells; the maximum side is %d cells: cut the area you need with "
                "gdal_translate "
                "-srcwin XOFF YOFF XSIZE YSIZE IN.tif OUT.tif, or coarsen it with gdalwarp -tr "
                "CELL CELL "
                "-r bilinear IN.tif OUT.tif",
                path, *w, *h, max_dim);
    } else if (GDALGetGeoTransform(ds, gt) != CE_None) {
        set_err(err, err_len, "'%s' has no geotransform (cell size and position unknown)", path);
    } else if (gt[2] != 0.0 || gt[4] != 0.0) {
        set_err(err, err_len,
                "'%s' has a rotated geotransform (terms %g, %g); resample it north-up first", path,
                gt[2], gt[4]);
    } else if (!(isfinite(gt[1]) && isfinite(gt[5]) && gt[1] != 0.0 && gt[5] != 0.0)) {
        set_err(err, err_len, "'%s' has a degenerate geotransform (pixel size %g x %g)", path,
                gt[1], gt[5]);
    } else {
        return ds;
    }
    GDALClose(ds);
    return NULL;
}

/* Band b (w x h) as float32, cells its mask marks invalid as NaN. The
 * heights (free them), or NULL with the reason. */
static float *read_band(GDALRasterBandH b, int band, const char *path, int w, int h, char *err,
                        size_t err_len)
{
    size_t n = (size_t)w * (size_t)h;
    float *data = malloc(n * sizeof *data);
    int mask_flags;
    unsigned char *m;

    if (data == NULL) {
        set_err(err, err_len, "out of memory for a %d x %d DEM", w, h);
        return NULL;
    }
    if (GDALRasterIO(b, GF_Read, 0, 0, w, h, data, w, h, GDT_Float32, 0, 0) != CE_None) {
        set_err(err, err_len, "cannot read band %d of '%s': %s", band, path, last_gdal_msg());
        free(data);
        return NULL;
    }
    mask_flags = GDALGetMaskFlags(b);
    if ((mask_flags & GMF_ALL_VALID) || (mask_flags & GMF_NODATA)) {
        return data;
    }
    m = malloc(n);
    if (m == NULL) {
        set_err(err, err_len, "out of memory for a %d x %d mask", w, h);
        free(data);
        return NULL;
    }
    if (GDALRasterIO(GDALGetMaskBand(b), GF_Read, 0, 0, w, h, m, w, h, GDT_Byte, 0, 0) != CE_None) {
        set_err(err, err_len, "cannot read the mask of band %d of '%s': %s", band, path,
                last_gdal_msg());
        free(m);
        free(data);
        return NULL;
    }
    for (size_t i = 0; i < n; ++i) {
        if (m[i] == 0) {
            data[i] = NAN;
        }
    }
    free(m);
    return data;
}

/* Not seen: no-data value, non-finite, |value| >= DEM_NOT_SEEN_ABS; the
 * others converted to metres. The band is read as float32, so compare with
 * the no-data value as float32 (a double no-data value is rounded the same
 * way the heights are). A NaN no-data value needs no comparison. The tests
 * run on the stored values (a no-data value or an ISIS special pixel is a
 * stored value), then once more on the heights in metres. */
static void heights_to_m(float *data, size_t n, GDALRasterBandH b, double zscale, double zoffset,
                         double zunit)
{
    int has_nodata = 0;
    double nodata = GDALGetRasterNoDataValue(b, &has_nodata);
    int use_nd = has_nodata && isfinite(nodata) && fabs(nodata) <= 3.4e38;
    float nd = use_nd ? (float)nodata : 0.0f;
    int convert = zscale != 1.0 || zoffset != 0.0 || zunit != 1.0;
    for (size_t i = 0; i < n; ++i) {
        float v = data[i];
        if (!isfinite(v) || fabsf(v) >= (float)DEM_NOT_SEEN_ABS || (use_nd && v == nd)) {
            data[i] = NAN;
        } else if (convert) {
            double z = ((double)v * zscale + zoffset) * zunit;
            data[i] = (isfinite(z) && fabs(z) < DEM_NOT_SEEN_ABS) ? (float)z : NAN;
        }
    }
}

/* Normalise to north-up, west-to-east. */
static void north_up(float *data, int w, int h, double gt[6])
{
    int r, c;
    if (gt[5] > 0.0) {
        for (r = 0; r < h / 2; ++r) {
            float *a = data + (size_t)r * (size_t)w;
            float *z = data + (size_t)(h - 1 - r) * (size_t)w;
            for (c = 0; c < w; ++c) {
                float t = a[c];
                a[c] = z[c];
                z[c] = t;
            }
        }
        gt[3] = gt[3] + (double)h * gt[5];
        gt[5] = -gt[5];
    }
    if (gt[1] < 0.0) {
        for (r = 0; r < h; ++r) {
            float *row = data + (size_t)r * (size_t)w;
            for (c = 0; c < w / 2; ++c) {
                float t = row[c];
                row[c] = row[w - 1 - c];
                row[w - 1 - c] = t;
            }
        }
        gt[0] = gt[0] + (double)w * gt[1];
        gt[1] = -gt[1];
    }
}

/* The CRS handed on (WKT to free, or NULL): the file's own, or its metre
 * version msrs after a unit conversion (horizontal only when the heights were
 * converted too, so no vertical CRS claims a unit the heights no longer
 * have). Destroys msrs. */
static char *handed_wkt(GDALDatasetH ds, OGRSpatialReferenceH msrs, double zunit, double vert_to_m)
{
    char *out = NULL;
    const char *wkt;
    if (msrs == NULL && zunit != 1.0 && vert_to_m > 0.0) {
        OGRSpatialReferenceH srs = GDALGetSpatialRef(ds);
        msrs = srs != NULL ? OSRClone(srs) : NULL;
        if (msrs != NULL && OSRStripVertical(msrs) != OGRERR_NONE) {
            OSRDestroySpatialReference(msrs);
            msrs = NULL;
        }
    }
    if (msrs != NULL) {
        char *mwkt = NULL;
        if (OSRExportToWkt(msrs, &mwkt) == OGRERR_NONE && mwkt != NULL && *mwkt != '\0') {
            out = dup_string(mwkt);
        }
        CPLFree(mwkt);
        OSRDestroySpatialReference(msrs);
    } else {
        wkt = GDALGetProjectionRef(ds);
        if (wkt != NULL && *wkt != '\0') {
            out = dup_string(wkt);
        }
    }
    return out;
}

int dem_read(const char *path, int band, int max_dim, dem_t *dem, char *err, size_t err_len)
{
    GDALDatasetH ds;
    GDALRasterBandH b;
    OGRSpatialReferenceH msrs = NULL;
    double gt[6];
    int w, h;
    double vert_to_m, zscale, zoffset, zunit;
    float *data;
    double cell;

    memset(dem, 0, sizeof *dem);
    gdal_init();
    ds = open_checked(path, band, max_dim, &w, &h, gt, err, err_len);
    if (ds == NULL) {
        return -1;
    }
    if (crs_to_metres(ds, path, gt, &msrs, &vert_to_m, err, err_len) != 0) {
        GDALClose(ds);
        return -1;
    }
    cell = fabs(gt[1]);
    b = GDALGetRasterBand(ds, band);
    data = NULL;
    if (fabs(fabs(gt[5]) - cell) / cell > 1e-6) {
        set_err(err, err_len,
                "'%s' has non-square cells (%g x %g m); resample it to square cells first", path,
                cell, fabs(gt[5]));
    } else if (band_height_scale(b, band, path, vert_to_m, &zscale, &zoffset, &zunit, err,
                                 err_len) == 0) {
        data = read_band(b, band, path, w, h, err, err_len);
    }
    if (data == NULL) {
        if (msrs != NULL) {
            OSRDestroySpatialReference(msrs);
        }
        GDALClose(ds);
        return -1;
    }
    heights_to_m(data, (size_t)w * (size_t)h, b, zscale, zoffset, zunit);
    north_up(data, w, h, gt);
    dem->srs_wkt = handed_wkt(ds, msrs, zunit, vert_to_m);
    GDALClose(ds);

    dem->data = data;
    dem->width = w;
    dem->height = h;
    memcpy(dem->gt, gt, sizeof gt);
    dem->cell_m = gt[1];
    return 0;
}

int dem_write_gtiff(const char *path, const float *data, int width, int height, const double gt[6],
                    const char *srs_wkt, char *err, size_t err_len)
{
    GDALDriverH drv;
    GDALDatasetH ds;
    GDALRasterBandH b;
    char **opts = NULL;
    double gtc[6];
    CPLErr e;

    gdal_init();
    CPLErrorReset();
    drv = GDALGetDriverByName("GTiff");
    if (drv == NULL) {
        set_err(err, err_len, "GDAL has no GTiff driver");
        return -1;
    }
    opts = CSLSetNameValue(opts, "COMPRESS", "DEFLATE");
    opts = CSLSetNameValue(opts, "PREDICTOR", "3"); /* floating-point predictor */
    ds = GDALCreate(drv, path, width, height, 1, GDT_Float32, opts);
    CSLDestroy(opts);
    if (ds == NULL) {
        set_err(err, err_len, "cannot create '%s': %s", path, last_gdal_msg());
        return -1;
    }
    memcpy(gtc, gt, sizeof gtc);
    e = GDALSetGeoTransform(ds, gtc);
    if (e == CE_None && srs_wkt != NULL && *srs_wkt != '\0') {
        e = GDALSetProjection(ds, srs_wkt);
    }
    b = GDALGetRasterBand(ds, 1);
    if (e == CE_None) {
        e = GDALSetRasterNoDataValue(b, (double)NAN);
    }
    if (e == CE_None) {
        e = GDALRasterIO(b, GF_Write, 0, 0, width, height, (void *)(size_t)data, width, height,
                         GDT_Float32, 0, 0);
    }
    if (e != CE_None) {
        set_err(err, err_len, "cannot write '%s': %s", path, last_gdal_msg());
        GDALClose(ds);
        return -1;
    }
    GDALClose(ds);
    if (CPLGetLastErrorType() >= CE_Failure) {
        set_err(err, err_len, "cannot finish '%s': %s", path, last_gdal_msg());
        return -1;
    }
    return 0;
}

void dem_map_to_cell(const double gt[6], double x_m, double y_m, double *col, double *row)
{
    *col = (x_m - gt[0]) / gt[1] - 0.5;
    *row = (y_m - gt[3]) / gt[5] - 0.5;
}

void dem_cell_to_map(const double gt[6], double col, double row, double *x_m, double *y_m)
{
    *x_m = gt[0] + (col + 0.5) * gt[1];
    *y_m = gt[3] + (row + 0.5) * gt[5];
}

int dem_cell_of(const dem_t *dem, double x_m, double y_m, int *col, int *row)
{
    double c, r;
    dem_map_to_cell(dem->gt, x_m, y_m, &c, &r);
    c = floor(c + 0.5);
    r = floor(r + 0.5);
    if (!(c >= 0.0 && c <= (double)(dem->width - 1) && r >= 0.0 &&
          r <= (double)(dem->height - 1))) {
        return 0;
    }
    *col = (int)c;
    *row = (int)r;
    return 1;
}

char *dem_srs_to_wkt(const char *user, char *err, size_t err_len)
{
    OGRSpatialReferenceH srs;
    char *wkt = NULL;
    char *out;
    gdal_init();
    CPLErrorReset();
    srs = OSRNewSpatialReference(NULL);
    if (srs == NULL || OSRSetFromUserInput(srs, user) != OGRERR_NONE) {
        set_err(err, err_len, "--crs '%s' is not a coordinate reference system GDAL knows: %s",
                user, last_gdal_msg());
        if (srs != NULL) {
            OSRDestroySpatialReference(srs);
        }
        return NULL;
    }
    if (OSRExportToWkt(srs, &wkt) != OGRERR_NONE || wkt == NULL) {
        set_err(err, err_len, "--crs '%s' cannot be written as WKT", user);
        OSRDestroySpatialReference(srs);
        return NULL;
    }
    out = dup_string(wkt);
    CPLFree(wkt);
    OSRDestroySpatialReference(srs);
    if (out == NULL) {
        set_err(err, err_len, "out of memory");
    }
    return out;
}
