/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/selmap.h - what `trn select` and `trn field` share: a global DEM
 * prepared for landmark selection (map, kernels, eq. 8 probability map), the
 * selection options in map terms and their conversion to the core's grid
 * frame.
 *
 * Frames. Map: x east, y north, metres (the DEM's geotransform); headings and
 * pan limits in degrees counter-clockwise from east (map x). Core: cells,
 * x = column, y = row (south), angles atan2(row, column), i.e. clockwise in
 * map terms, so a map angle a is the grid angle -a and the pan interval
 * [lo, hi] becomes [-hi, -lo]. Covariances: the sigmas are the same, the
 * correlation's sign flips (docs/method.md section 7). */
#ifndef TRN_TOOLS_SELMAP_H
#define TRN_TOOLS_SELMAP_H

#include <stddef.h>

#include "cli.h"
#include "dem_io.h"
#include "mapopt.h"
#include "trn/trn.h"

/* The map configuration (--map-config) of `trn select` and `trn field`: the
 * default of `trn localize` too (trn_map_cfg_auto), so every command
 * predicts and localizes with the same matcher on the same DEM. */
#define SELMAP_MAP_CONFIG_DEFAULT "auto"

/* `trn experiment`'s on its generated terrain: the paper's experiment
 * (docs/method.md 8); with --dem it takes "auto". */
#define SELMAP_EXPERIMENT_MAP_CONFIG "paper"

/* A sensed patch narrower than this many cells draws a warning on stderr. */
#define SELMAP_PATCH_FEW_CELLS 7

/* Options common to select and field; the option table entries are made by
 * selmap_opts (SELMAP_N_OPTS of them). */
typedef struct {
    long band;
    double heading_deg; /* map frame, CCW from east */
    double
        heading_sigma_deg; /* the heading's 1-sigma uncertainty, degrees (trn_select_cfg_t.sigma_heading_rad) */
    long heading_search; /* 1: the target is matched with the heading searched (trn_select_cfg_t) */
    double pan_deg[2];   /* min,max relative to the heading, map frame */
    double min_range_m, max_range_m, footprint_m, patch_m, separation_m;
    long stride_cells;
    const char *sensors; /* "X,Y[;X,Y...]" map metres, or NULL: the DEM's centre */
    double outlier_k;    /* the map's outlier density K (1/m) for ln p; 0: from the DEM (a tiled
                            field passes the whole map's, python/trn/dask_field.py) */
    mapopt_t mo;         /* the map configuration (mapopt.h) */
    double gsig_m;       /* global map's error at its sensor, m; < 0: trn_sigma_global_default */
    double gsig_k;       /* its growth with squared range, 1/m; < 0: trn_sigma_global_default */
    const char *gerr;    /* per-cell error raster (m, the DEM's grid), or NULL */
    /* the height prediction: the points the rover bins into a cell
     * (trn_select_cfg_t.points_per_cell); 0: one measurement a cell */
    double points_per_cell;
} selmap_opts_t;

/* The selection options (14), the global map's error model (3), the map
 * configuration (MAPOPT_N), in that order. */
#define SELMAP_N_SEL_OPTS 14
#define SELMAP_N_GERR_OPTS 3
#define SELMAP_N_OPTS (SELMAP_N_SEL_OPTS + SELMAP_N_GERR_OPTS + MAPOPT_N)

/* The global map's error options alone (SELMAP_N_GERR_OPTS entries pointing
 * into o: --global-sigma-m, --global-sigma-k, --global-error); used by
 * `trn experiment`. */
void selmap_gerr_opts(selmap_opts_t *o, cli_opt_t *dst);

/* The global map's error model from the options: the library default with
 * what was given replaced. */
void selmap_gerr_model(const selmap_opts_t *o, trn_sigma_model_t *m);

/* Read the error raster at path into e and check it lies on dem's grid (same
 * size and geotransform) and holds NaN or 0..1e6 m. Returns 0 (free e with
 * dem_free), or -1 with a one-line reason in err. */
int selmap_read_error(const char *path, const dem_t *dem, dem_t *e, char *err, size_t err_len);

/* Eq. 8 into w->pg (allocated here, freed by the caller with free(*pgraw)):
 * the model from o, or the raster o->gerr (read and checked against dem's
 * grid) with the model where it is NaN. Returns 0, or -1 with a one-line
 * reason in err. */
int selmap_prob_global(const selmap_opts_t *o, const dem_t *dem, const trn_kernels_t *k,
                       const trn_xy_t *sensors, size_t n_sensors, const trn_map_t *map,
                       trn_vol_f32_t *pg, void **pgraw, char *err, size_t err_len);

/* One summary line "map ..." and one "global error ..." line on stdout. */
void selmap_print_config(const selmap_opts_t *o, const trn_map_cfg_t *cfg);

/* Write "global_error" (model and raster) and the map configuration as JSON. */
void selmap_json_config(json_t *j, const selmap_opts_t *o, const trn_map_cfg_t *cfg,
                        double sigma_h);

/* Defaults (trn_select_cfg_default in map terms, heading 0, stride given). */
void selmap_opts_default(selmap_opts_t *o, long stride_cells);

/* After cli_parse of `trn cmd` (select, field): the usage rules between the
 * options (mapopt_check_use for the voxel map; --heading-search 1 only with
 * --heading-sigma-deg above 0, the only case it changes a prediction).
 * CLI_OK, or CLI_USAGE with the one-line message printed. */
int selmap_check_use(const char *cmd, const selmap_opts_t *o);

/* Fill SELMAP_N_OPTS option table entries pointing into o. */
void selmap_opts(selmap_opts_t *o, cli_opt_t *dst);

/* A prepared global DEM. */
typedef struct {
    dem_t dem;
    trn_map_cfg_t cfg;
    trn_map_t map;
    trn_kernels_t k;
    trn_vol_f32_t pg;
    trn_select_cfg_t scfg;
    trn_xy_t sensors[TRN_SPREAD_MAX_SENSORS]; /* global cells */
    size_t n_sensors;
    double sensors_m[TRN_SPREAD_MAX_SENSORS][2]; /* map metres */
    float heading_grid_rad;
    double sigma_h; /* the DEM's high-passed height spread (auto), else NaN */
    void *mraw, *pgraw;
} selmap_t;

/* Read the DEM, check the options, build the map (configuration from
 * o->mo, mapopt_config), the kernels and P_G (eq. 8) from the sensing
 * positions and the global error model or raster. Prints nothing: on failure
 * returns CLI_BAD_INPUT with the one-line reason in err (w is freed); 0 on
 * success. */
int selmap_prepare(selmap_t *w, const char *dem_path, const selmap_opts_t *o, char *err,
                   size_t err_len);

void selmap_free(selmap_t *w);

/* 16-byte aligned block; free with free(raw). */
void *selmap_alloc16(size_t n, void **raw);

/* A map coordinate for printing: rounded to the micrometre, so a cell centre
 * prints as 2019.45, not 2019.4499999999998. */
double selmap_um(double v_m);

/* Core correlation (column, row) -> east-north (sign flipped, no -0). */
double selmap_rho_en(double rho_grid);

#endif
