/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/dem_io.c - DEM reading and GeoTIFF writing through GDAL's C API
 * (loaded at run time: gdal_dl.h), and the in-memory rasters that stand for
 * files without GDAL (dem_mem_put). */
#include "dem_io.h"

#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gdal_dl.h"

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
 * one-line reasons (CPLGetLastErrorMsg), not on their own (trn_gdal_load).
 * 0, or -1 with the reason (libgdal missing, and how to install it). */
static int gdal_ready(char *err, size_t err_len) { return trn_gdal_load(err, err_len); }

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
static int crs_to_metres(OGRSpatialReferenceH srs, const char *path, double gt[6],
                         OGRSpatialReferenceH *out_srs, double *vert_to_m, char *err,
                         size_t err_len)
{
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

/* Check band, size and geotransform (north-up up to flips, nonzero finite
 * pixel size) of a raster named path with nbands bands of w x h cells; has_gt
 * 0: it has no geotransform. 0, or -1 with the reason. */
static int check_grid(const char *path, int band, int nbands, int w, int h, int max_dim, int has_gt,
                      const double gt[6], char *err, size_t err_len)
{
    if (band < 1 || band > nbands) {
        set_err(err, err_len, "'%s' has %d band%s, no band %d", path, nbands,
                nbands == 1 ? "" : "s", band);
    } else if (w < 1 || h < 1) {
        set_err(err, err_len, "'%s' is %d x %d cells: it has no cells", path, w, h);
    } else if (w > max_dim || h > max_dim) {
        set_err(err, err_len,
                "'%s' is %d x %d cells; the maximum side is %d cells: cut the area you need with "
                "gdal_translate "
                "-srcwin XOFF YOFF XSIZE YSIZE IN.tif OUT.tif, or coarsen it with gdalwarp -tr "
                "CELL CELL "
                "-r bilinear IN.tif OUT.tif",
                path, w, h, max_dim);
    } else if (!has_gt) {
        set_err(err, err_len, "'%s' has no geotransform (cell size and position unknown)", path);
    } else if (gt[2] != 0.0 || gt[4] != 0.0) {
        set_err(err, err_len,
                "'%s' has a rotated geotransform (terms %g, %g); resample it north-up first", path,
                gt[2], gt[4]);
    } else if (!(isfinite(gt[1]) && isfinite(gt[5]) && gt[1] != 0.0 && gt[5] != 0.0)) {
        set_err(err, err_len, "'%s' has a degenerate geotransform (pixel size %g x %g)", path,
                gt[1], gt[5]);
    } else {
        return 0;
    }
    return -1;
}

/* Open path as a raster and check it (check_grid). The dataset, or NULL with
 * the reason. */
static GDALDatasetH open_checked(const char *path, int band, int max_dim, int *w, int *h,
                                 double gt[6], char *err, size_t err_len)
{
    GDALDatasetH ds;
    int has_gt;

    CPLErrorReset();
    ds = GDALOpenEx(path, GDAL_OF_RASTER | GDAL_OF_READONLY, NULL, NULL, NULL);
    if (ds == NULL) {
        set_err(err, err_len, "cannot read '%s' as a raster: %s", path, last_gdal_msg());
        return NULL;
    }
    *w = GDALGetRasterXSize(ds);
    *h = GDALGetRasterYSize(ds);
    has_gt = GDALGetGeoTransform(ds, gt) == CE_None;
    if (check_grid(path, band, GDALGetRasterCount(ds), *w, *h, max_dim, has_gt, gt, err, err_len) ==
        0) {
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
static void heights_to_m(float *data, size_t n, int has_nodata, double nodata, double zscale,
                         double zoffset, double zunit)
{
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
static char *handed_wkt(OGRSpatialReferenceH srs, const char *wkt, OGRSpatialReferenceH msrs,
                        double zunit, double vert_to_m)
{
    char *out = NULL;
    if (msrs == NULL && zunit != 1.0 && vert_to_m > 0.0) {
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
        if (wkt != NULL && *wkt != '\0') {
            out = dup_string(wkt);
        }
    }
    return out;
}

/* ---- in-memory rasters ------------------------------------------------- */

/* One raster held by name: an input (data borrowed from the caller, never
 * written) or an output (owned: what dem_write_gtiff stored). */
typedef struct mem_raster {
    struct mem_raster *next;
    unsigned long id;
    const float *data; /* borrowed (input): `bands` planes of width x height */
    float *owned;      /* owned (output), else NULL */
    int width, height, bands;
    double gt[6];
    int has_nodata;
    double nodata;
    char *crs;   /* the caller's CRS text (input) or WKT (output), or NULL */
    char *label; /* what messages call it */
} mem_raster_t;

static pthread_mutex_t mem_lock = PTHREAD_MUTEX_INITIALIZER;
static mem_raster_t *mem_list;
static unsigned long mem_next_id = 1;

int dem_is_mem(const char *path)
{
    return path != NULL && strncmp(path, DEM_MEM_PREFIX, sizeof DEM_MEM_PREFIX - 1) == 0;
}

/* The id of a name, or 0 when it is not one. */
static unsigned long mem_id(const char *path)
{
    const char *s;
    char *end;
    unsigned long id;
    if (!dem_is_mem(path)) {
        return 0;
    }
    s = path + sizeof DEM_MEM_PREFIX - 1;
    if (*s < '0' || *s > '9') {
        return 0;
    }
    id = strtoul(s, &end, 10);
    return *end == '\0' ? id : 0;
}

/* The entry of id (mem_lock held), or NULL. */
static mem_raster_t *mem_find(unsigned long id)
{
    mem_raster_t *e;
    for (e = mem_list; e != NULL; e = e->next) {
        if (e->id == id) {
            return e;
        }
    }
    return NULL;
}

static void mem_free_entry(mem_raster_t *e)
{
    free(e->owned);
    free(e->crs);
    free(e->label);
    free(e);
}

int dem_mem_name(char *name, size_t name_len)
{
    unsigned long id;
    pthread_mutex_lock(&mem_lock);
    id = mem_next_id++;
    pthread_mutex_unlock(&mem_lock);
    return snprintf(name, name_len, DEM_MEM_PREFIX "%lu", id) < (int)name_len ? 0 : -1;
}

/* A CRS text in WKT that names a geographic or geocentric CRS (its first
 * keyword), the check made without GDAL. */
static const char *wkt_kind(const char *crs)
{
    static const struct {
        const char *kw;
        const char *kind;
    } kws[] = {{"GEOGCS[", "geographic"},
               {"GEOGCRS[", "geographic"},
               {"GEOGRAPHICCRS[", "geographic"},
               {"GEOCCS[", "geocentric"},
               {"GEODCRS[", "geographic or geocentric"},
               {"GEODETICCRS[", "geographic or geocentric"}};
    size_t i;
    while (*crs == ' ' || *crs == '\t' || *crs == '\n' || *crs == '\r') {
        ++crs;
    }
    for (i = 0; i < sizeof kws / sizeof kws[0]; ++i) {
        if (strncmp(crs, kws[i].kw, strlen(kws[i].kw)) == 0) {
            return kws[i].kind;
        }
    }
    return NULL;
}

int dem_mem_put(const float *data, int width, int height, int bands, const double gt[6],
                int has_nodata, double nodata, const char *crs, const char *label, char *name,
                size_t name_len, char *err, size_t err_len)
{
    mem_raster_t *e;
    int i;
    if (label == NULL || *label == '\0') {
        label = "array";
    }
    if (data == NULL || gt == NULL || name == NULL || name_len == 0) {
        set_err(err, err_len, "'%s': no data, geotransform or name buffer", label);
        return -1;
    }
    if (width < 1 || height < 1) {
        set_err(err, err_len, "'%s' is %d x %d cells: it has no cells", label, width, height);
        return -1;
    }
    if (bands < 1 || bands > DEM_MEM_MAX_BANDS) {
        set_err(err, err_len, "'%s' has %d bands; an in-memory raster has 1 to %d", label, bands,
                DEM_MEM_MAX_BANDS);
        return -1;
    }
    for (i = 0; i < 6; ++i) {
        if (!isfinite(gt[i])) {
            set_err(err, err_len, "'%s': geotransform term %d is not finite", label, i);
            return -1;
        }
    }
    if (has_nodata && isnan(nodata)) {
        has_nodata = 0; /* NaN is "not seen" anyway */
    }
    if (crs != NULL && *crs == '\0') {
        crs = NULL;
    }
    /* With GDAL, a CRS it cannot read is refused now; its kind and unit are
     * checked when the raster is read, as a file's are. */
    if (crs != NULL && gdal_ready(NULL, 0) == 0) {
        OGRSpatialReferenceH srs = OSRNewSpatialReference(NULL);
        int bad;
        CPLErrorReset();
        bad = srs == NULL || OSRSetFromUserInput(srs, crs) != OGRERR_NONE;
        if (srs != NULL) {
            OSRDestroySpatialReference(srs);
        }
        if (bad) {
            set_err(err, err_len,
                    "'%s': crs '%s' is not a coordinate reference system GDAL knows: %s", label,
                    crs, last_gdal_msg());
            return -1;
        }
    }
    e = calloc(1, sizeof *e);
    if (e == NULL || (e->label = dup_string(label)) == NULL ||
        (crs != NULL && (e->crs = dup_string(crs)) == NULL)) {
        if (e != NULL) {
            mem_free_entry(e);
        }
        set_err(err, err_len, "out of memory");
        return -1;
    }
    e->data = data;
    e->width = width;
    e->height = height;
    e->bands = bands;
    memcpy(e->gt, gt, sizeof e->gt);
    e->has_nodata = has_nodata;
    e->nodata = nodata;
    pthread_mutex_lock(&mem_lock);
    e->id = mem_next_id++;
    e->next = mem_list;
    mem_list = e;
    pthread_mutex_unlock(&mem_lock);
    if (snprintf(name, name_len, DEM_MEM_PREFIX "%lu", e->id) >= (int)name_len) {
        dem_mem_drop(name);
        set_err(err, err_len, "name buffer too short");
        return -1;
    }
    return 0;
}

void dem_mem_drop(const char *name)
{
    unsigned long id = mem_id(name);
    mem_raster_t **pp, *e = NULL;
    if (id == 0) {
        return;
    }
    pthread_mutex_lock(&mem_lock);
    for (pp = &mem_list; *pp != NULL; pp = &(*pp)->next) {
        if ((*pp)->id == id) {
            e = *pp;
            *pp = e->next;
            break;
        }
    }
    pthread_mutex_unlock(&mem_lock);
    if (e != NULL) {
        mem_free_entry(e);
    }
}

/* A copy of the raster named path: its heights as stored (malloc'd), size,
 * geotransform, no-data, CRS text (malloc'd or NULL) and label (malloc'd). */
typedef struct {
    float *data;
    int width, height, bands;
    double gt[6];
    int has_nodata;
    double nodata;
    char *crs;
    char *label;
} mem_copy_t;

static void mem_copy_free(mem_copy_t *c)
{
    free(c->data);
    free(c->crs);
    free(c->label);
    memset(c, 0, sizeof *c);
}

/* c: a copy of band `band` (1-based) of the raster named path. 0, or -1 with
 * a reason (no such raster or band, out of memory). */
static int mem_copy(const char *path, int band, mem_copy_t *c, char *err, size_t err_len)
{
    mem_raster_t *e;
    size_t n;
    memset(c, 0, sizeof *c);
    pthread_mutex_lock(&mem_lock);
    e = mem_find(mem_id(path));
    if (e == NULL) {
        pthread_mutex_unlock(&mem_lock);
        set_err(err, err_len, "'%s' names no in-memory raster (freed, or never made)", path);
        return -1;
    }
    if (band < 1 || band > e->bands) {
        pthread_mutex_unlock(&mem_lock);
        set_err(err, err_len, "'%s' has %d band%s, no band %d", e->label, e->bands,
                e->bands == 1 ? "" : "s", band);
        return -1;
    }
    n = (size_t)e->width * (size_t)e->height;
    c->data = malloc(n * sizeof *c->data);
    c->label = dup_string(e->label);
    c->crs = e->crs != NULL ? dup_string(e->crs) : NULL;
    if (c->data == NULL || c->label == NULL || (e->crs != NULL && c->crs == NULL)) {
        pthread_mutex_unlock(&mem_lock);
        set_err(err, err_len, "out of memory for a %d x %d raster", e->width, e->height);
        mem_copy_free(c);
        return -1;
    }
    memcpy(c->data, e->owned != NULL ? e->owned : e->data + (size_t)(band - 1) * n,
           n * sizeof *c->data);
    c->width = e->width;
    c->bands = e->bands;
    c->height = e->height;
    memcpy(c->gt, e->gt, sizeof c->gt);
    c->has_nodata = e->has_nodata;
    c->nodata = e->nodata;
    pthread_mutex_unlock(&mem_lock);
    return 0;
}

/* dem_read of an in-memory raster: the checks and conversions of a file's
 * (grid, CRS in metres, no-data, north-up), the heights taken as metres (or
 * the compound CRS's vertical unit, as a file's band without a unit). The CRS
 * is checked with GDAL when GDAL loads; without it only a WKT that names a
 * geographic or geocentric CRS is refused, and the rest is the caller's word
 * that the grid is in metres. */
static int mem_read(const char *path, int band, int max_dim, dem_t *dem, char *err, size_t err_len)
{
    mem_copy_t c;
    OGRSpatialReferenceH srs = NULL, msrs = NULL;
    double vert_to_m = 0.0, zunit = 1.0, cell;
    const char *kind;

    if (mem_copy(path, band, &c, err, err_len) != 0) {
        return -1;
    }
    if (check_grid(c.label, band, c.bands, c.width, c.height, max_dim, 1, c.gt, err, err_len) !=
        0) {
        goto fail;
    }
    if (c.crs != NULL && gdal_ready(NULL, 0) == 0) {
        srs = OSRNewSpatialReference(NULL);
        CPLErrorReset();
        if (srs == NULL || OSRSetFromUserInput(srs, c.crs) != OGRERR_NONE) {
            set_err(err, err_len,
                    "'%s': crs '%s' is not a coordinate reference system GDAL knows: %s", c.label,
                    c.crs, last_gdal_msg());
            goto fail;
        }
        if (crs_to_metres(srs, c.label, c.gt, &msrs, &vert_to_m, err, err_len) != 0) {
            goto fail;
        }
        if (vert_to_m > 0.0) {
            zunit = vert_to_m;
        }
    } else if (c.crs != NULL && (kind = wkt_kind(c.crs)) != NULL) {
        set_err(err, err_len,
                "'%s' is in a %s CRS (its WKT says so); reproject it to metres first, e.g. "
                "gdalwarp -t_srs EPSG:326NN (the UTM zone of the site) -r bilinear IN.tif OUT.tif",
                c.label, kind);
        goto fail;
    }
    cell = fabs(c.gt[1]);
    if (fabs(fabs(c.gt[5]) - cell) / cell > 1e-6) {
        set_err(err, err_len,
                "'%s' has non-square cells (%g x %g m); resample it to square cells first", c.label,
                cell, fabs(c.gt[5]));
        goto fail;
    }
    /* the no-data value and the vertical unit are the heights' (band 1); later
     * bands are taken as stored (NaN and +-inf still "not seen") */
    heights_to_m(c.data, (size_t)c.width * (size_t)c.height, band == 1 ? c.has_nodata : 0, c.nodata,
                 1.0, 0.0, band == 1 ? zunit : 1.0);
    north_up(c.data, c.width, c.height, c.gt);
    if (srs != NULL) {
        char *wkt = NULL;
        if (OSRExportToWkt(srs, &wkt) != OGRERR_NONE) {
            wkt = NULL;
        }
        dem->srs_wkt = handed_wkt(srs, wkt, msrs, zunit, vert_to_m);
        msrs = NULL; /* destroyed by handed_wkt */
        CPLFree(wkt);
        OSRDestroySpatialReference(srs);
        srs = NULL;
    } else if (c.crs != NULL) {
        dem->srs_wkt = c.crs; /* unchecked without GDAL: handed on as given */
        c.crs = NULL;
    }
    dem->data = c.data;
    c.data = NULL;
    dem->width = c.width;
    dem->height = c.height;
    memcpy(dem->gt, c.gt, sizeof dem->gt);
    dem->cell_m = c.gt[1];
    mem_copy_free(&c);
    return 0;
fail:
    if (msrs != NULL) {
        OSRDestroySpatialReference(msrs);
    }
    if (srs != NULL) {
        OSRDestroySpatialReference(srs);
    }
    mem_copy_free(&c);
    return -1;
}

/* dem_write_gtiff to an in-memory name: the raster kept (owned) under it,
 * replacing what it held. */
static int mem_write(const char *path, const float *data, int width, int height, const double gt[6],
                     const char *srs_wkt, char *err, size_t err_len)
{
    unsigned long id = mem_id(path);
    size_t n = (size_t)width * (size_t)height;
    mem_raster_t *e, *old = NULL, **pp;
    if (id == 0) {
        set_err(err, err_len, "'%s' is not an in-memory raster name (" DEM_MEM_PREFIX "N)", path);
        return -1;
    }
    e = calloc(1, sizeof *e);
    if (e == NULL || (e->owned = malloc(n * sizeof *e->owned)) == NULL ||
        (e->label = dup_string(path)) == NULL ||
        (srs_wkt != NULL && *srs_wkt != '\0' && (e->crs = dup_string(srs_wkt)) == NULL)) {
        if (e != NULL) {
            mem_free_entry(e);
        }
        set_err(err, err_len, "out of memory for a %d x %d raster", width, height);
        return -1;
    }
    memcpy(e->owned, data, n * sizeof *e->owned);
    e->id = id;
    e->width = width;
    e->height = height;
    e->bands = 1;
    memcpy(e->gt, gt, sizeof e->gt);
    e->has_nodata = 0;
    pthread_mutex_lock(&mem_lock);
    for (pp = &mem_list; *pp != NULL; pp = &(*pp)->next) {
        if ((*pp)->id == id) {
            old = *pp;
            *pp = old->next;
            break;
        }
    }
    e->next = mem_list;
    mem_list = e;
    pthread_mutex_unlock(&mem_lock);
    if (old != NULL) {
        mem_free_entry(old);
    }
    return 0;
}

/* ---- reading and writing ------------------------------------------------ */

int dem_read(const char *path, int band, int max_dim, dem_t *dem, char *err, size_t err_len)
{
    GDALDatasetH ds;
    GDALRasterBandH b;
    OGRSpatialReferenceH msrs = NULL;
    double gt[6];
    int w, h, has_nodata = 0;
    double vert_to_m, zscale, zoffset, zunit, nodata;
    float *data;
    double cell;

    memset(dem, 0, sizeof *dem);
    if (path == NULL) {
        set_err(err, err_len, "no raster named");
        return -1;
    }
    if (dem_is_mem(path)) {
        return mem_read(path, band, max_dim, dem, err, err_len);
    }
    if (gdal_ready(err, err_len) != 0) {
        return -1;
    }
    ds = open_checked(path, band, max_dim, &w, &h, gt, err, err_len);
    if (ds == NULL) {
        return -1;
    }
    if (crs_to_metres(GDALGetSpatialRef(ds), path, gt, &msrs, &vert_to_m, err, err_len) != 0) {
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
    nodata = GDALGetRasterNoDataValue(b, &has_nodata);
    heights_to_m(data, (size_t)w * (size_t)h, has_nodata, nodata, zscale, zoffset, zunit);
    north_up(data, w, h, gt);
    dem->srs_wkt = handed_wkt(GDALGetSpatialRef(ds), GDALGetProjectionRef(ds), msrs, zunit,
                              vert_to_m);
    GDALClose(ds);

    dem->data = data;
    dem->width = w;
    dem->height = h;
    memcpy(dem->gt, gt, sizeof gt);
    dem->cell_m = gt[1];
    return 0;
}

int dem_read_raw(const char *path, int band, dem_t *dem, char *err, size_t err_len)
{
    GDALDatasetH ds;
    const char *wkt;
    int w, h;
    double gt[6];
    float *data;

    memset(dem, 0, sizeof *dem);
    if (path == NULL) {
        set_err(err, err_len, "no raster named");
        return -1;
    }
    if (dem_is_mem(path)) {
        mem_copy_t c;
        if (mem_copy(path, band, &c, err, err_len) != 0) {
            return -1;
        }
        dem->data = c.data;
        dem->srs_wkt = c.crs;
        dem->width = c.width;
        dem->height = c.height;
        memcpy(dem->gt, c.gt, sizeof dem->gt);
        dem->cell_m = c.gt[1];
        c.data = NULL;
        c.crs = NULL;
        mem_copy_free(&c);
        return 0;
    }
    if (gdal_ready(err, err_len) != 0) {
        return -1;
    }
    ds = open_checked(path, band, INT_MAX, &w, &h, gt, err, err_len);
    if (ds == NULL) {
        return -1;
    }
    data = read_band(GDALGetRasterBand(ds, band), band, path, w, h, err, err_len);
    if (data == NULL) {
        GDALClose(ds);
        return -1;
    }
    wkt = GDALGetProjectionRef(ds);
    dem->srs_wkt = wkt != NULL && *wkt != '\0' ? dup_string(wkt) : NULL;
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

    if (dem_is_mem(path)) {
        return mem_write(path, data, width, height, gt, srs_wkt, err, err_len);
    }
    if (gdal_ready(err, err_len) != 0) {
        return -1;
    }
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
    if (gdal_ready(err, err_len) != 0) {
        return NULL;
    }
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
