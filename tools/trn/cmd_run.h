/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/cmd_run.h - the run half of each `trn` command (issue 15).
 *
 * Every command in tools/trn is three steps: parse (argv -> a params struct,
 * from the option table of cli.h; defaults from the core's *_cfg_default),
 * run (params -> a result struct) and report (result -> the summary or the
 * JSON object on stdout). trn_cmd_<name> only chains them. The run functions
 * declared here print nothing and never exit: each returns an exit status of
 * cli.h (CLI_OK, CLI_BAD_INPUT, CLI_NO_RESULT) and, when it is not CLI_OK,
 * the one-line reason in err (what `trn <cmd>: <reason>` prints). They take
 * plain structs and keep no global state, so a binding calls them (the
 * Python package: python/trn_py.c, libtrn_run.so; docs/modules/python.md);
 * files they are asked to write (--out ...) are
 * written by run. Progress, where a command has any, goes through the
 * optional callback in its params (NULL: none). Results own their memory:
 * free them with the matching *_result_free, also after a failed run.
 * `trn profile` keeps its three steps private to cmd_profile.c: its result is
 * the stages' buffers, and --instructions re-runs the executable itself under
 * callgrind, which only the command line can do. */
#ifndef TRN_TOOLS_CMD_RUN_H
#define TRN_TOOLS_CMD_RUN_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "dem_io.h"
#include "experiment.h"
#include "mapopt.h"
#include "selmap.h"
#include "terrain_gen.h"
#include "trn/trn.h"

/* Room for the one-line reason of a failed run. */
#define CMD_ERR_LEN 1024

/* Progress of a long run: done of total units. */
typedef void (*cmd_progress_fn)(void *ctx, long done, long total);

/* ---- trn terrain ------------------------------------------------------- */
typedef struct {
    const char *out, *crs; /* GeoTIFF to write; CRS to tag it with, or NULL */
    long size;             /* side, cells */
    double cell, k, ratio, relief;
    double dmin, dmax; /* rock diameters, m; <= 0: 2 cells, tg_auto_d_max(k) */
    double origin[2];  /* south-west corner, map metres */
    uint64_t seed;
    int json; /* report as JSON */
    cmd_progress_fn progress;
    void *progress_ctx;
} cmd_terrain_params_t;

typedef struct {
    tg_params_t p; /* the generator's parameters as run */
    size_t n_rocks;
    double area_fraction;  /* realised rock area of the rocks centred on the map */
    double model_fraction; /* F_k(Dmin) - F_k(Dmax) */
} cmd_terrain_result_t;

void cmd_terrain_params_default(cmd_terrain_params_t *p);
int cmd_terrain_run(const cmd_terrain_params_t *p, cmd_terrain_result_t *r, char *err,
                    size_t err_len);

/* ---- trn select ------------------------------------------------------- */
typedef struct {
    const char *dem_path, *out_map; /* out_map: per-candidate GeoTIFF, or NULL */
    double rover_m[2];              /* map metres */
    long next_best;
    int json;
    selmap_opts_t so;
} cmd_select_params_t;

typedef struct {
    selmap_t w; /* the prepared DEM */
    trn_candidate_t *cands;
    size_t *ranked;
    trn_select_result_t res; /* cands[res.best]: the target; ranked[1..n_ranked): next best */
} cmd_select_result_t;

void cmd_select_params_default(cmd_select_params_t *p);
/* CLI_OK, CLI_BAD_INPUT, or CLI_NO_RESULT (no informative target). */
int cmd_select_run(const cmd_select_params_t *p, cmd_select_result_t *r, char *err, size_t err_len);
/* As cmd_select_run on a DEM prepared once (selmap_prepare with p->dem_path
 * and p->so, kept by the caller between runs): r->w is a shallow copy of *w,
 * so release r with cmd_select_result_release (never *_free, which would free
 * the caller's map). */
int cmd_select_run_prepared(const cmd_select_params_t *p, const selmap_t *w, cmd_select_result_t *r,
                            char *err, size_t err_len);
void cmd_select_result_release(cmd_select_result_t *r); /* the candidates, not the map */
void cmd_select_result_free(cmd_select_result_t *r);    /* the candidates and the map */

/* ---- trn field -------------------------------------------------------- */
typedef struct {
    const char *dem_path, *out; /* DEM; the field's GeoTIFF */
    const char *area_text;      /* "X0,Y0,X1,Y1" map metres, or NULL: the whole DEM */
    const char *ev_out;         /* evaluated mask GeoTIFF, or NULL */
    long coarse;                /* trn_field_cfg_t's, defaults from trn_field_cfg_default */
    double margin, change;
    int json, reference; /* reference: trn_field instead of trn_field_fast */
    selmap_opts_t so;
    trn_field_progress_fn_t progress; /* the core's callback (may be NULL) */
    void *progress_user;
} cmd_field_params_t;

typedef struct {
    selmap_t w;        /* the prepared DEM */
    trn_window_t area; /* rover positions covered, cells */
    size_t aw, ah;
    long coarse_positions; /* the coarse lattice's size (set before the core runs; 0 before) */
    trn_field_stats_t stats;
    size_t wsb;                /* workspace bytes */
    double secs;               /* the core's wall time */
    double bx, by, vmin, vmed; /* best position (map metres), its and the median uncertainty */
    long n_inf;                /* positions with no informative target */
} cmd_field_result_t;

void cmd_field_params_default(cmd_field_params_t *p);
/* CLI_OK, CLI_BAD_INPUT, or CLI_NO_RESULT (no informative target anywhere). */
int cmd_field_run(const cmd_field_params_t *p, cmd_field_result_t *r, char *err, size_t err_len);
/* As cmd_field_run on a DEM prepared once (selmap_prepare with p->dem_path and
 * p->so, kept by the caller): r->w is a shallow copy of *w; r owns nothing
 * else, so it needs no freeing (never cmd_field_result_free: the map is the
 * caller's). */
int cmd_field_run_prepared(const cmd_field_params_t *p, const selmap_t *w, cmd_field_result_t *r,
                           char *err, size_t err_len);
void cmd_field_result_free(cmd_field_result_t *r);

/* ---- trn localize ----------------------------------------------------- */
typedef struct {
    const char *dem_path, *local_path, *batch_path; /* --local with --prior, or --batch */
    double prior[2];                                /* map metres */
    double window_m;
    long band, local_band, max_local;
    long centroid_band; /* --centroid-bands N: bands N, N + 1 of --local; 0: none */
    long count_band;    /* --count-band N: band N of --local, the cells' point counts; 0: none */
    int have_prior;     /* --prior given */
    int heading;        /* search heading too (--heading-window-deg or --heading-deg given) */
    double heading_deg, heading_win_deg; /* centre and half-window, degrees counterclockwise */
    const char *search; /* the height matcher's search: NULL (bounded), "bounded", "exhaustive" */
    long node_budget;   /* its node budget; 0 = none */
    int json;
    mapopt_t mo;
} cmd_localize_params_t;

/* What every localization of one run shares: the global map, prepared once. */
typedef struct {
    dem_t g;
    trn_map_cfg_t cfg;
    trn_map_t map;
    void *mraw;
    long local_band, max_local, centroid_band, count_band;
    int heading;
    double heading_deg, heading_win_deg;
} cmd_localize_ctx_t;

/* The result of one case in map terms. */
typedef struct {
    double x_m, y_m, rho_en, cov_en[3], time_ms;
    double heading_deg, sigma_heading_deg,
        cov3[9]; /* heading search: (east m, north m, heading deg) */
    long radius; /* the window, cells */
    trn_loc_result_t res;
    trn_status_t st;
} cmd_localize_out_t;

void cmd_localize_params_default(cmd_localize_params_t *p);
/* Read the global DEM and prepare the map into c (free with cmd_localize_ctx_free). */
int cmd_localize_prepare(const cmd_localize_params_t *p, cmd_localize_ctx_t *c, char *err,
                         size_t err_len);
/* One case: the local DEM at local_path around prior (map metres) within
 * +-window_m. CLI_OK or CLI_BAD_INPUT. */
int cmd_localize_run(const cmd_localize_ctx_t *c, const char *local_path, const double prior[2],
                     double window_m, cmd_localize_out_t *o, char *err, size_t err_len);
void cmd_localize_ctx_free(cmd_localize_ctx_t *c);

/* ---- trn experiment --------------------------------------------------- */
typedef struct {
    long trials, size, band;
    uint64_t seed, tseed;
    double k, dmin, relief, window, prior, spacing, succ, minr, maxr, patch, foot, hnoise;
    double heading_err,
        heading_win;      /* --heading-error-deg, --heading-window-deg (0: none, 3 x the error) */
    long heading_search;  /* --select-heading-search: the 3-DOF arm's selection flag */
    const char *sensor;   /* "prob" or "dem" */
    const char *dem_path; /* a given DEM, or NULL: the generated terrain */
    int json;
    /* given on the command line (else the default, or the length scaled to a --dem's cell) */
    int seen_tseed, seen_dmin, seen_window, seen_prior, seen_spacing;
    selmap_opts_t so;         /* the global map's error options and the map configuration */
    exp_progress_fn progress; /* trials done (may be NULL) */
    void *progress_ctx;
} cmd_experiment_params_t;

typedef struct {
    exp_params_t p; /* the experiment as run */
    exp_result_t r;
    dem_t dem, gerr;    /* --dem and --global-error, when given */
    size_t n_nodata;    /* --dem's no-data cells */
    double f;           /* length scale: --dem's cell / 0.1 m, else 1 */
    double secs;        /* wall time of the trials */
    double gain;        /* 1 - mean error with / without selection */
    const mapopt_t *mo; /* the map configuration's options (map_cfg callback) */
    double sigma_h;     /* the DEM's high-passed height spread (auto), else NaN */
} cmd_experiment_result_t;

void cmd_experiment_params_default(cmd_experiment_params_t *p);
int cmd_experiment_run(const cmd_experiment_params_t *p, cmd_experiment_result_t *r, char *err,
                       size_t err_len);
void cmd_experiment_result_free(cmd_experiment_result_t *r);

/* ---- parse and JSON report, for a binding --------------------------- */
/* argv (argv[0] the command's name) -> p, defaults set first by the caller
 * (*_params_default). Returns CLI_OK, CLI_HELP (usage printed on stdout) or
 * the usage / bad input status with its message on cli_message_stream(). The
 * strings of p point into argv. localize also checks --local/--prior against
 * --batch. */
int cmd_localize_parse(int argc, char **argv, cmd_localize_params_t *p);
int cmd_select_parse(int argc, char **argv, cmd_select_params_t *p);
int cmd_field_parse(int argc, char **argv, cmd_field_params_t *p);
/* The JSON object of `trn <cmd> --json` (one line) on out. localize: batch
 * selects the --batch line's form ("local" instead of the map configuration). */
void cmd_localize_report_json(FILE *out, const cmd_localize_ctx_t *c, const char *local,
                              const double prior[2], double window_m, const cmd_localize_out_t *o,
                              int batch);
void cmd_select_report_json(FILE *out, const cmd_select_params_t *p, const cmd_select_result_t *r);
void cmd_field_report_json(FILE *out, const cmd_field_params_t *p, const cmd_field_result_t *r);

#endif
