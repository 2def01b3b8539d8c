/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/gdal_dl.h - GDAL's C API, loaded at run time (dlopen).
 *
 * dem_io.c is the only user of GDAL. It reaches GDAL through this header
 * instead of GDAL's own: the handful of types, constants and functions it
 * calls are declared here, and each function name is a macro for a pointer in
 * trn_gdal_fn, filled by trn_gdal_load() from libgdal. So nothing that links
 * dem_io.c needs GDAL at build time, and a program that never reads or writes
 * a file never needs libgdal at all: libtrn_run.so (the Python package) loads
 * without it and takes DEMs given as arrays (dem_io.h, in-memory rasters);
 * only a file, a CRS check or a GeoTIFF output loads libgdal, and its absence
 * is a one-line reason that says how to install it. The `trn` command line
 * still links libgdal (so its package depends on it); the loader then finds
 * GDAL's functions already in the process.
 *
 * Where GDAL is looked for, in order: $TRN_GDAL_LIBRARY alone when set (a
 * path or a file name; a name no library has makes GDAL unavailable, as the
 * tests do); else the functions already in the process (a program linked to
 * libgdal); else the soname of the libgdal the build found (TRN_GDAL_SONAME,
 * when CMake found one), libgdal.so, libgdal.so.38 down to .26 (GDAL 3.0 to
 * 3.10 and later), and $CONDA_PREFIX/lib/libgdal.so.
 *
 * The declarations follow GDAL's C API as of GDAL 3.0 (GDALGetSpatialRef),
 * which every libgdal the loader accepts has: handles are opaque pointers,
 * GDAL's enums are passed as int (their C representation), and the numeric
 * constants are GDAL's values (gdal.h, cpl_error.h, ogr_core.h). */
#ifndef TRN_GDAL_DL_H
#define TRN_GDAL_DL_H

#include <stddef.h>

typedef void *GDALDatasetH;
typedef void *GDALRasterBandH;
typedef void *GDALDriverH;
typedef void *OGRSpatialReferenceH;
typedef int CPLErr;       /* enum CPLErr */
typedef int OGRErr;       /* int in GDAL too */
typedef int GDALDataType; /* enum GDALDataType */
typedef int GDALRWFlag;   /* enum GDALRWFlag */
typedef void (*CPLErrorHandler)(CPLErr, int, const char *);

#define CE_None 0
#define CE_Failure 3
#define OGRERR_NONE 0
#define OGRERR_FAILURE 6
#define GDT_Byte 1
#define GDT_Float32 6
#define GF_Read 0
#define GF_Write 1
#define GDAL_OF_READONLY 0x00
#define GDAL_OF_RASTER 0x02
#define GMF_ALL_VALID 0x01
#define GMF_NODATA 0x08
#define SRS_UL_METER "metre"

/* One member per GDAL function dem_io.c calls, named as the function. */
typedef struct {
    void (*GDALAllRegister)(void);
    CPLErrorHandler (*CPLSetErrorHandler)(CPLErrorHandler);
    CPLErrorHandler CPLQuietErrorHandler; /* the function itself, handed to CPLSetErrorHandler */
    const char *(*CPLGetLastErrorMsg)(void);
    void (*CPLErrorReset)(void);
    CPLErr (*CPLGetLastErrorType)(void);
    void (*VSIFree)(void *);
    char **(*CSLSetNameValue)(char **, const char *, const char *);
    void (*CSLDestroy)(char **);
    GDALDatasetH (*GDALOpenEx)(const char *, unsigned int, const char *const *, const char *const *,
                               const char *const *);
    GDALDatasetH (*GDALCreate)(GDALDriverH, const char *, int, int, int, GDALDataType, char **);
    void (*GDALClose)(GDALDatasetH);
    GDALDriverH (*GDALGetDriverByName)(const char *);
    int (*GDALGetRasterCount)(GDALDatasetH);
    int (*GDALGetRasterXSize)(GDALDatasetH);
    int (*GDALGetRasterYSize)(GDALDatasetH);
    CPLErr (*GDALGetGeoTransform)(GDALDatasetH, double *);
    CPLErr (*GDALSetGeoTransform)(GDALDatasetH, double *);
    const char *(*GDALGetProjectionRef)(GDALDatasetH);
    CPLErr (*GDALSetProjection)(GDALDatasetH, const char *);
    OGRSpatialReferenceH (*GDALGetSpatialRef)(GDALDatasetH);
    GDALRasterBandH (*GDALGetRasterBand)(GDALDatasetH, int);
    CPLErr (*GDALRasterIO)(GDALRasterBandH, GDALRWFlag, int, int, int, int, void *, int, int,
                           GDALDataType, int, int);
    int (*GDALGetMaskFlags)(GDALRasterBandH);
    GDALRasterBandH (*GDALGetMaskBand)(GDALRasterBandH);
    double (*GDALGetRasterNoDataValue)(GDALRasterBandH, int *);
    CPLErr (*GDALSetRasterNoDataValue)(GDALRasterBandH, double);
    const char *(*GDALGetRasterUnitType)(GDALRasterBandH);
    double (*GDALGetRasterScale)(GDALRasterBandH, int *);
    double (*GDALGetRasterOffset)(GDALRasterBandH, int *);
    OGRSpatialReferenceH (*OSRNewSpatialReference)(const char *);
    void (*OSRDestroySpatialReference)(OGRSpatialReferenceH);
    OGRSpatialReferenceH (*OSRClone)(OGRSpatialReferenceH);
    OGRErr (*OSRSetFromUserInput)(OGRSpatialReferenceH, const char *);
    OGRErr (*OSRExportToWkt)(OGRSpatialReferenceH, char **);
    int (*OSRIsGeographic)(OGRSpatialReferenceH);
    int (*OSRIsGeocentric)(OGRSpatialReferenceH);
    int (*OSRIsProjected)(OGRSpatialReferenceH);
    int (*OSRIsCompound)(OGRSpatialReferenceH);
    double (*OSRGetLinearUnits)(OGRSpatialReferenceH, char **);
    double (*OSRGetTargetLinearUnits)(OGRSpatialReferenceH, const char *, char **);
    OGRErr (*OSRSetLinearUnits)(OGRSpatialReferenceH, const char *, double);
    OGRErr (*OSRSetLinearUnitsAndUpdateParameters)(OGRSpatialReferenceH, const char *, double);
    OGRErr (*OSRStripVertical)(OGRSpatialReferenceH);
} trn_gdal_fn_t;

extern trn_gdal_fn_t trn_gdal_fn;

/* Load libgdal once per process (thread-safe), register its drivers and make
 * its error messages quiet (they reach the user through the callers'
 * one-line reasons). Returns 0 when GDAL is ready; otherwise -1 and a
 * one-line reason that names the fix (install libgdal, or set
 * TRN_GDAL_LIBRARY) in err; every later call gives the same answer. */
int trn_gdal_load(char *err, size_t err_len);

/* The library GDAL was loaded from ("(linked)" when found in the process),
 * or NULL before a successful trn_gdal_load. */
const char *trn_gdal_source(void);

/* The names as calls through the table (not in gdal_dl.c itself, which names
 * the members). */
#ifndef TRN_GDAL_DL_IMPL
#define GDALAllRegister (trn_gdal_fn.GDALAllRegister)
#define CPLSetErrorHandler (trn_gdal_fn.CPLSetErrorHandler)
#define CPLQuietErrorHandler (trn_gdal_fn.CPLQuietErrorHandler)
#define CPLGetLastErrorMsg (trn_gdal_fn.CPLGetLastErrorMsg)
#define CPLErrorReset (trn_gdal_fn.CPLErrorReset)
#define CPLGetLastErrorType (trn_gdal_fn.CPLGetLastErrorType)
#define CPLFree (trn_gdal_fn.VSIFree) /* CPLFree is GDAL's alias of VSIFree */
#define CSLSetNameValue (trn_gdal_fn.CSLSetNameValue)
#define CSLDestroy (trn_gdal_fn.CSLDestroy)
#define GDALOpenEx (trn_gdal_fn.GDALOpenEx)
#define GDALCreate (trn_gdal_fn.GDALCreate)
#define GDALClose (trn_gdal_fn.GDALClose)
#define GDALGetDriverByName (trn_gdal_fn.GDALGetDriverByName)
#define GDALGetRasterCount (trn_gdal_fn.GDALGetRasterCount)
#define GDALGetRasterXSize (trn_gdal_fn.GDALGetRasterXSize)
#define GDALGetRasterYSize (trn_gdal_fn.GDALGetRasterYSize)
#define GDALGetGeoTransform (trn_gdal_fn.GDALGetGeoTransform)
#define GDALSetGeoTransform (trn_gdal_fn.GDALSetGeoTransform)
#define GDALGetProjectionRef (trn_gdal_fn.GDALGetProjectionRef)
#define GDALSetProjection (trn_gdal_fn.GDALSetProjection)
#define GDALGetSpatialRef (trn_gdal_fn.GDALGetSpatialRef)
#define GDALGetRasterBand (trn_gdal_fn.GDALGetRasterBand)
#define GDALRasterIO (trn_gdal_fn.GDALRasterIO)
#define GDALGetMaskFlags (trn_gdal_fn.GDALGetMaskFlags)
#define GDALGetMaskBand (trn_gdal_fn.GDALGetMaskBand)
#define GDALGetRasterNoDataValue (trn_gdal_fn.GDALGetRasterNoDataValue)
#define GDALSetRasterNoDataValue (trn_gdal_fn.GDALSetRasterNoDataValue)
#define GDALGetRasterUnitType (trn_gdal_fn.GDALGetRasterUnitType)
#define GDALGetRasterScale (trn_gdal_fn.GDALGetRasterScale)
#define GDALGetRasterOffset (trn_gdal_fn.GDALGetRasterOffset)
#define OSRNewSpatialReference (trn_gdal_fn.OSRNewSpatialReference)
#define OSRDestroySpatialReference (trn_gdal_fn.OSRDestroySpatialReference)
#define OSRClone (trn_gdal_fn.OSRClone)
#define OSRSetFromUserInput (trn_gdal_fn.OSRSetFromUserInput)
#define OSRExportToWkt (trn_gdal_fn.OSRExportToWkt)
#define OSRIsGeographic (trn_gdal_fn.OSRIsGeographic)
#define OSRIsGeocentric (trn_gdal_fn.OSRIsGeocentric)
#define OSRIsProjected (trn_gdal_fn.OSRIsProjected)
#define OSRIsCompound (trn_gdal_fn.OSRIsCompound)
#define OSRGetLinearUnits (trn_gdal_fn.OSRGetLinearUnits)
#define OSRGetTargetLinearUnits (trn_gdal_fn.OSRGetTargetLinearUnits)
#define OSRSetLinearUnits (trn_gdal_fn.OSRSetLinearUnits)
#define OSRSetLinearUnitsAndUpdateParameters (trn_gdal_fn.OSRSetLinearUnitsAndUpdateParameters)
#define OSRStripVertical (trn_gdal_fn.OSRStripVertical)
#endif

#endif /* TRN_GDAL_DL_H */
