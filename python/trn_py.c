/* SPDX-License-Identifier: Apache-2.0 */
/* python/trn_py.c - the flat C ABI of libtrn_run.so, which the Python package
 * `trn` (python/trn/__init__.py) calls through ctypes.
 *
 * Every call takes the command's own argv (argv[0] the command's name, then
 * `--option value` pairs, exactly what `trn <cmd>` takes), parses it with the
 * command's parser (cmd_<name>_parse, so every option, default, range and
 * message is the command line's), runs the run half of cmd_run.h and writes
 * the command's JSON report (cmd_<name>_report_json, the writer of `trn <cmd>
 * --json`) into a malloc'd string. So a result has the CLI's keys, units and
 * numbers by construction.
 *
 * A trn_py_map_t keeps what the runs prepare from the global DEM between
 * calls: the localization map (cmd_localize_prepare) and the selection map
 * (selmap_prepare), each with the key of the options it was prepared with
 * (the caller's string: the DEM and every option that goes into the
 * preparation); a call with another key prepares again. One map must not be
 * used by two threads at once (the Python class holds a lock); different maps
 * may.
 *
 * Returns: the CLI's exit statuses (0 ok, 1 bad input, 2 usage, 3 no
 * result), and otherwise the one-line reason in err (without the "trn <cmd>: "
 * prefix). The parsers print their messages on cli_message_stream(), set here
 * to a memory stream for the call; that setting is process-wide, so parses are
 * serialised by a mutex (runs are not).
 *
 * Rasters without files (dem_io.h, in-memory rasters): trn_py_raster_put
 * registers a numpy array's buffer (float32, row-major, by pointer: not
 * copied until a run reads it) with its geotransform, no-data value and CRS
 * text under a name "trn-mem:N" that the calls take wherever the command
 * takes a path (--dem, --local); trn_py_raster_name gives a name for an
 * output (--out, --evaluated-out, --out-map), and trn_py_raster_read returns
 * what was written there. None of this needs GDAL: only files do (GDAL is
 * loaded at run time, tools/trn/gdal_dl.c; trn_py_gdal says whether it
 * loads, and why not). */
#define _POSIX_C_SOURCE 200809L /* open_memstream, strdup */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "cmd_run.h"
#include "dem_io.h"
#include "gdal_dl.h"
#include "selmap.h"
#include "trn/version.h"

typedef struct {
    cmd_localize_ctx_t loc;
    char *loc_key; /* NULL: loc not prepared */
    selmap_t sel;
    char *sel_key; /* NULL: sel not prepared */
} trn_py_map_t;

/* Declared here: the ABI is this file (the Python side mirrors it). */
const char *trn_py_version(void);
trn_py_map_t *trn_py_map_new(void);
void trn_py_map_free(trn_py_map_t *m);
void trn_py_free(char *s);
int trn_py_localize(trn_py_map_t *m, int argc, char **argv, const char *key, char **json, char *err,
                    size_t err_len);
int trn_py_select(trn_py_map_t *m, int argc, char **argv, const char *key, char **json, char *err,
                  size_t err_len);
int trn_py_field(trn_py_map_t *m, int argc, char **argv, const char *key,
                 trn_field_progress_fn_t progress, void *progress_user, char **json, char *err,
                 size_t err_len);

int trn_py_options(const char *cmd, char **json, char *err, size_t err_len);
int trn_py_gdal(char *err, size_t err_len);
int trn_py_raster_put(const float *data, int width, int height, int bands, const double *gt,
                      int has_nodata, double nodata, const char *crs, const char *label, char *name,
                      size_t name_len, char *err, size_t err_len);
int trn_py_raster_name(char *name, size_t name_len);
int trn_py_crs_wkt(const char *crs, char **wkt, char *err, size_t err_len);
void trn_py_raster_drop(const char *name);
int trn_py_raster_read(const char *path, int band, int raw, float **data, int *width, int *height,
                       double *gt, char **crs, char *err, size_t err_len);
int trn_py_raster_write(const char *path, const float *data, int width, int height,
                        const double *gt, const char *crs, char *err, size_t err_len);

enum { PY_LOCALIZE, PY_SELECT, PY_FIELD };

static pthread_mutex_t parse_lock = PTHREAD_MUTEX_INITIALIZER;

const char *trn_py_version(void) { return TRN_VERSION_STRING; }

trn_py_map_t *trn_py_map_new(void) { return calloc(1, sizeof(trn_py_map_t)); }

static void drop_loc(trn_py_map_t *m)
{
    if (m->loc_key != NULL) {
        cmd_localize_ctx_free(&m->loc);
        free(m->loc_key);
        m->loc_key = NULL;
    }
}

static void drop_sel(trn_py_map_t *m)
{
    if (m->sel_key != NULL) {
        selmap_free(&m->sel);
        free(m->sel_key);
        m->sel_key = NULL;
    }
}

void trn_py_map_free(trn_py_map_t *m)
{
    if (m != NULL) {
        drop_loc(m);
        drop_sel(m);
        free(m);
    }
}

void trn_py_free(char *s) { free(s); }

/* The message text without "trn <cmd>: " and the trailing newline, into err. */
static void set_message(const char *msg, char *err, size_t err_len)
{
    const char *s = msg;
    size_t n;
    if (strncmp(s, "trn ", 4) == 0 && strstr(s, ": ") != NULL) {
        s = strstr(s, ": ") + 2;
    }
    n = strcspn(s, "\n");
    if (n >= err_len) {
        n = err_len - 1;
    }
    memcpy(err, s, n);
    err[n] = '\0';
}

/* The command's parser into p (defaults first), its messages caught. */
static int parse_cmd(int which, int argc, char **argv, void *p, char *err, size_t err_len)
{
    char *buf = NULL;
    size_t n = 0;
    FILE *f;
    int rc;
    pthread_mutex_lock(&parse_lock);
    f = open_memstream(&buf, &n);
    cli_set_message_stream(f);
    if (which == PY_LOCALIZE) {
        cmd_localize_params_default(p);
        rc = cmd_localize_parse(argc, argv, p);
    } else if (which == PY_SELECT) {
        cmd_select_params_default(p);
        rc = cmd_select_parse(argc, argv, p);
    } else {
        cmd_field_params_default(p);
        rc = cmd_field_parse(argc, argv, p);
    }
    cli_set_message_stream(NULL);
    if (f != NULL) {
        fclose(f);
    }
    pthread_mutex_unlock(&parse_lock);
    if (rc == CLI_HELP) {
        snprintf(err, err_len, "--help is not an option here");
        rc = CLI_USAGE;
    } else if (rc != CLI_OK) {
        set_message(buf != NULL && n > 0 ? buf : "invalid arguments", err, err_len);
    }
    free(buf);
    return rc;
}

/* A memory stream for a JSON report; *json gets the text after close_json. */
static FILE *open_json(char **json, size_t *n, char *err, size_t err_len)
{
    FILE *f;
    *json = NULL;
    f = open_memstream(json, n);
    if (f == NULL) {
        snprintf(err, err_len, "cannot open a memory stream for the result");
    }
    return f;
}

int trn_py_localize(trn_py_map_t *m, int argc, char **argv, const char *key, char **json, char *err,
                    size_t err_len)
{
    cmd_localize_params_t p;
    cmd_localize_out_t o;
    size_t n;
    FILE *f;
    int rc = parse_cmd(PY_LOCALIZE, argc, argv, &p, err, err_len);
    *json = NULL;
    if (rc != CLI_OK) {
        return rc;
    }
    if (p.batch_path != NULL) {
        snprintf(err, err_len, "--batch is for the command line; call localize once per case");
        return CLI_USAGE;
    }
    if (m->loc_key == NULL || strcmp(m->loc_key, key) != 0) {
        drop_loc(m);
        rc = cmd_localize_prepare(&p, &m->loc, err, err_len);
        m->loc_key = rc == CLI_OK ? strdup(key) : NULL;
        if (rc != CLI_OK || m->loc_key == NULL) {
            cmd_localize_ctx_free(&m->loc);
            return rc != CLI_OK ? rc : CLI_BAD_INPUT;
        }
    }
    rc = cmd_localize_run(&m->loc, p.local_path, p.prior, p.window_m, &o, err, err_len);
    if (rc == CLI_OK && (f = open_json(json, &n, err, err_len)) != NULL) {
        cmd_localize_report_json(f, &m->loc, p.local_path, p.prior, p.window_m, &o, 0);
        fclose(f);
    }
    return rc == CLI_OK && *json == NULL ? CLI_BAD_INPUT : rc;
}

/* The selection map for dem_path and so, prepared again when key changed. */
static int ensure_sel(trn_py_map_t *m, const char *dem_path, const selmap_opts_t *so,
                      const char *key, char *err, size_t err_len)
{
    if (m->sel_key != NULL && strcmp(m->sel_key, key) == 0) {
        return CLI_OK;
    }
    drop_sel(m);
    if (selmap_prepare(&m->sel, dem_path, so, err, err_len) != 0) {
        return CLI_BAD_INPUT;
    }
    m->sel_key = strdup(key);
    if (m->sel_key == NULL) {
        selmap_free(&m->sel);
        snprintf(err, err_len, "out of memory");
        return CLI_BAD_INPUT;
    }
    return CLI_OK;
}

int trn_py_select(trn_py_map_t *m, int argc, char **argv, const char *key, char **json, char *err,
                  size_t err_len)
{
    cmd_select_params_t p;
    cmd_select_result_t r;
    size_t n;
    FILE *f;
    int rc = parse_cmd(PY_SELECT, argc, argv, &p, err, err_len);
    *json = NULL;
    if (rc != CLI_OK || (rc = ensure_sel(m, p.dem_path, &p.so, key, err, err_len)) != CLI_OK) {
        return rc;
    }
    rc = cmd_select_run_prepared(&p, &m->sel, &r, err, err_len);
    if (rc == CLI_OK && (f = open_json(json, &n, err, err_len)) != NULL) {
        cmd_select_report_json(f, &p, &r);
        fclose(f);
    }
    cmd_select_result_release(&r);
    return rc == CLI_OK && *json == NULL ? CLI_BAD_INPUT : rc;
}

int trn_py_field(trn_py_map_t *m, int argc, char **argv, const char *key,
                 trn_field_progress_fn_t progress, void *progress_user, char **json, char *err,
                 size_t err_len)
{
    cmd_field_params_t p;
    cmd_field_result_t r;
    size_t n;
    FILE *f;
    int rc = parse_cmd(PY_FIELD, argc, argv, &p, err, err_len);
    *json = NULL;
    if (rc != CLI_OK || (rc = ensure_sel(m, p.dem_path, &p.so, key, err, err_len)) != CLI_OK) {
        return rc;
    }
    p.progress = progress;
    p.progress_user = progress_user;
    rc = cmd_field_run_prepared(&p, &m->sel, &r, err, err_len);
    if (rc == CLI_OK && (f = open_json(json, &n, err, err_len)) != NULL) {
        cmd_field_report_json(f, &p, &r);
        fclose(f);
    }
    return rc == CLI_OK && *json == NULL ? CLI_BAD_INPUT : rc;
}

/* The option table of `trn <cmd> --help` as JSON (cli_help_json): what the
 * Python docstrings list. Returns 0, or CLI_USAGE for an unknown command. */
int trn_py_options(const char *cmd, char **json, char *err, size_t err_len)
{
    union {
        cmd_localize_params_t l;
        cmd_select_params_t s;
        cmd_field_params_t f;
    } p;
    char *argv[2];
    size_t n = 0;
    FILE *f;
    int rc;
    *json = NULL;
    if (cmd == NULL) {
        snprintf(err, err_len, "no command named");
        return CLI_USAGE;
    }
    argv[0] = (char *)(size_t)cmd; /* the parsers take char **; they do not write */
    argv[1] = (char *)(size_t) "--help";
    pthread_mutex_lock(&parse_lock);
    f = open_memstream(json, &n);
    if (f == NULL) {
        pthread_mutex_unlock(&parse_lock);
        snprintf(err, err_len, "cannot open a memory stream");
        return CLI_BAD_INPUT;
    }
    cli_set_help_json_stream(f);
    if (strcmp(cmd, "localize") == 0) {
        cmd_localize_params_default(&p.l);
        rc = cmd_localize_parse(2, argv, &p.l);
    } else if (strcmp(cmd, "select") == 0) {
        cmd_select_params_default(&p.s);
        rc = cmd_select_parse(2, argv, &p.s);
    } else if (strcmp(cmd, "field") == 0) {
        cmd_field_params_default(&p.f);
        rc = cmd_field_parse(2, argv, &p.f);
    } else {
        rc = CLI_USAGE;
    }
    cli_set_help_json_stream(NULL);
    fclose(f);
    pthread_mutex_unlock(&parse_lock);
    if (rc != CLI_HELP || *json == NULL) {
        free(*json);
        *json = NULL;
        snprintf(err, err_len, "no command '%s' (localize, select, field)", cmd);
        return CLI_USAGE;
    }
    return CLI_OK;
}

/* 0 when GDAL's C library loads (files can be read and written), else 1
 * with the reason, which names the fix. */
int trn_py_gdal(char *err, size_t err_len) { return trn_gdal_load(err, err_len) == 0 ? 0 : 1; }

int trn_py_raster_put(const float *data, int width, int height, int bands, const double *gt,
                      int has_nodata, double nodata, const char *crs, const char *label, char *name,
                      size_t name_len, char *err, size_t err_len)
{
    return dem_mem_put(data, width, height, bands, gt, has_nodata, nodata, crs, label, name,
                       name_len, err, err_len) == 0
               ? CLI_OK
               : CLI_BAD_INPUT;
}

int trn_py_raster_name(char *name, size_t name_len)
{
    return dem_mem_name(name, name_len) == 0 ? CLI_OK : CLI_BAD_INPUT;
}

void trn_py_raster_drop(const char *name) { dem_mem_drop(name); }

/* Band `band` of a file or in-memory raster: raw 1 as stored (dem_read_raw:
 * what a command wrote), raw 0 as the commands read a DEM (dem_read: metres,
 * north-up, not seen as NaN). *data (width x height, row-major) and *crs
 * (the CRS as WKT, or NULL) are malloc'd: trn_py_free them. */
int trn_py_raster_read(const char *path, int band, int raw, float **data, int *width, int *height,
                       double *gt, char **crs, char *err, size_t err_len)
{
    dem_t d;
    int rc = raw ? dem_read_raw(path, band, &d, err, err_len)
                 : dem_read(path, band, TRN_MAX_DIM, &d, err, err_len);
    *data = NULL;
    *crs = NULL;
    if (rc != 0) {
        return CLI_BAD_INPUT;
    }
    *data = d.data;
    *crs = d.srs_wkt;
    *width = d.width;
    *height = d.height;
    memcpy(gt, d.gt, 6 * sizeof *gt);
    return CLI_OK;
}

int trn_py_raster_write(const char *path, const float *data, int width, int height,
                        const double *gt, const char *crs, char *err, size_t err_len)
{
    if (path == NULL || data == NULL || gt == NULL || width < 1 || height < 1) {
        snprintf(err, err_len,
                 "write: want a path, data of at least 1 x 1 cells and a geotransform");
        return CLI_BAD_INPUT;
    }
    return dem_write_gtiff(path, data, width, height, gt, crs, err, err_len) == 0 ? CLI_OK
                                                                                  : CLI_BAD_INPUT;
}

/* A CRS text (EPSG:n, WKT, PROJ ...) as WKT, through GDAL (which must load).
 * *wkt is malloc'd: trn_py_free it. */
int trn_py_crs_wkt(const char *crs, char **wkt, char *err, size_t err_len)
{
    *wkt = NULL;
    if (crs == NULL || *crs == '\0') {
        snprintf(err, err_len, "no CRS given");
        return CLI_BAD_INPUT;
    }
    *wkt = dem_srs_to_wkt(crs, err, err_len);
    return *wkt != NULL ? CLI_OK : CLI_BAD_INPUT;
}
