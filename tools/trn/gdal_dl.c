/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/gdal_dl.c - libgdal loaded at run time (gdal_dl.h). */
#define _GNU_SOURCE /* RTLD_DEFAULT */
#define TRN_GDAL_DL_IMPL
#include "gdal_dl.h"

#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

trn_gdal_fn_t trn_gdal_fn;

#define FN(name) \
    { \
#name, offsetof(trn_gdal_fn_t, name) \
    }
static const struct {
    const char *name;
    size_t off;
} fns[] = {
    FN(GDALAllRegister),
    FN(CPLSetErrorHandler),
    FN(CPLQuietErrorHandler),
    FN(CPLGetLastErrorMsg),
    FN(CPLErrorReset),
    FN(CPLGetLastErrorType),
    FN(VSIFree),
    FN(CSLSetNameValue),
    FN(CSLDestroy),
    FN(GDALOpenEx),
    FN(GDALCreate),
    FN(GDALClose),
    FN(GDALGetDriverByName),
    FN(GDALGetRasterCount),
    FN(GDALGetRasterXSize),
    FN(GDALGetRasterYSize),
    FN(GDALGetGeoTransform),
    FN(GDALSetGeoTransform),
    FN(GDALGetProjectionRef),
    FN(GDALSetProjection),
    FN(GDALGetSpatialRef),
    FN(GDALGetRasterBand),
    FN(GDALRasterIO),
    FN(GDALGetMaskFlags),
    FN(GDALGetMaskBand),
    FN(GDALGetRasterNoDataValue),
    FN(GDALSetRasterNoDataValue),
    FN(GDALGetRasterUnitType),
    FN(GDALGetRasterScale),
    FN(GDALGetRasterOffset),
    FN(OSRNewSpatialReference),
    FN(OSRDestroySpatialReference),
    FN(OSRClone),
    FN(OSRSetFromUserInput),
    FN(OSRExportToWkt),
    FN(OSRIsGeographic),
    FN(OSRIsGeocentric),
    FN(OSRIsProjected),
    FN(OSRIsCompound),
    FN(OSRGetLinearUnits),
    FN(OSRGetTargetLinearUnits),
    FN(OSRSetLinearUnits),
    FN(OSRSetLinearUnitsAndUpdateParameters),
    FN(OSRStripVertical),
};
#undef FN

static pthread_mutex_t load_lock = PTHREAD_MUTEX_INITIALIZER;
static int load_state; /* 0 not tried, 1 ready, -1 unavailable */
static char load_why[1024];
static char load_from[256];

/* Every function from handle h into trn_gdal_fn; 0, or -1 with the first
 * missing name in *missing. A function pointer has the representation of a
 * data pointer on POSIX systems (what dlsym relies on): memcpy, because ISO C
 * has no conversion between the two. */
static int fill(void *h, const char **missing)
{
    size_t i;
    for (i = 0; i < sizeof fns / sizeof fns[0]; ++i) {
        void *sym = dlsym(h, fns[i].name);
        if (sym == NULL) {
            *missing = fns[i].name;
            return -1;
        }
        memcpy((char *)&trn_gdal_fn + fns[i].off, &sym, sizeof sym);
    }
    return 0;
}

/* Try one library name or path; 1 loaded and filled, 0 not. */
static int try_lib(const char *name, char *tried, size_t tried_len)
{
    const char *missing = NULL;
    void *h = dlopen(name, RTLD_NOW | RTLD_LOCAL);
    size_t n = strlen(tried);
    if (h == NULL) {
        snprintf(tried + n, tried_len - n, "%s%s", n > 0 ? ", " : "", name);
        return 0;
    }
    if (fill(h, &missing) != 0) {
        snprintf(tried + n, tried_len - n, "%s%s (no %s: GDAL 3.0 or later is needed)",
                 n > 0 ? ", " : "", name, missing);
        dlclose(h);
        return 0;
    }
    snprintf(load_from, sizeof load_from, "%s", name);
    return 1; /* kept open for the life of the process */
}

/* How to get libgdal, for the reasons below. */
#define INSTALL_HINT \
    "install libgdal (Debian/Ubuntu: apt install libgdal-dev, or the release's libgdalNN; " \
    "Fedora: dnf install gdal-libs; conda: conda install -c conda-forge libgdal)"

static int find_gdal(void)
{
    char tried[400] = "";
    char conda[300];
    const char *env = getenv("TRN_GDAL_LIBRARY");
    const char *missing = NULL;
    int v;

    if (env != NULL && *env != '\0') {
        if (try_lib(env, tried, sizeof tried)) {
            return 0;
        }
        snprintf(
            load_why, sizeof load_why,
            "reading or writing a raster file needs GDAL's C library (libgdal), and "
            "TRN_GDAL_LIBRARY=%.200s does not load (%.300s): point it at a libgdal.so, or unset it "
            "and " INSTALL_HINT "; numpy arrays need no GDAL",
            env, tried);
        return -1;
    }
    if (dlsym(RTLD_DEFAULT, "GDALOpenEx") != NULL && fill(RTLD_DEFAULT, &missing) == 0) {
        snprintf(load_from, sizeof load_from, "(linked)");
        return 0;
    }
#ifdef TRN_GDAL_SONAME
    if (try_lib(TRN_GDAL_SONAME, tried, sizeof tried)) {
        return 0;
    }
#endif
    if (try_lib("libgdal.so", tried, sizeof tried)) {
        return 0;
    }
    for (v = 38; v >= 26; --v) {
        char name[32];
        snprintf(name, sizeof name, "libgdal.so.%d", v);
        if (try_lib(name, tried, sizeof tried)) {
            return 0;
        }
    }
    env = getenv("CONDA_PREFIX");
    if (env != NULL && *env != '\0') {
        snprintf(conda, sizeof conda, "%s/lib/libgdal.so", env);
        if (try_lib(conda, tried, sizeof tried)) {
            return 0;
        }
    }
    snprintf(load_why, sizeof load_why,
             "reading or writing a raster file needs GDAL's C library (libgdal), which is not "
             "installed or not found (tried %.400s): " INSTALL_HINT
             ", or set TRN_GDAL_LIBRARY to its path; numpy arrays need no GDAL",
             tried);
    return -1;
}

int trn_gdal_load(char *err, size_t err_len)
{
    int st;
    pthread_mutex_lock(&load_lock);
    if (load_state == 0) {
        if (find_gdal() == 0) {
            trn_gdal_fn.GDALAllRegister();
            trn_gdal_fn.CPLSetErrorHandler(trn_gdal_fn.CPLQuietErrorHandler);
            load_state = 1;
        } else {
            memset(&trn_gdal_fn, 0, sizeof trn_gdal_fn);
            load_state = -1;
        }
    }
    st = load_state;
    pthread_mutex_unlock(&load_lock);
    if (st != 1 && err != NULL && err_len > 0) {
        snprintf(err, err_len, "%s", load_why);
    }
    return st == 1 ? 0 : -1;
}

const char *trn_gdal_source(void)
{
    const char *s;
    pthread_mutex_lock(&load_lock);
    s = load_state == 1 ? load_from : NULL;
    pthread_mutex_unlock(&load_lock);
    return s;
}
