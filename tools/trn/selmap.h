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
#include "trn/trn.h"

/* Options common to select and field; the option table entries are made by
 * selmap_opts (SELMAP_N_OPTS of them). */
typedef struct {
  long band;
  double heading_deg;  /* map frame, CCW from east */
  double pan_deg[2];   /* min,max relative to the heading, map frame */
  double min_range_m, max_range_m, footprint_m, patch_m, separation_m;
  long stride_cells;
  const char *sensors; /* "X,Y[;X,Y...]" map metres, or NULL: the DEM's centre */
} selmap_opts_t;

#define SELMAP_N_OPTS 10

/* Defaults (trn_select_cfg_default in map terms, heading 0, stride given). */
void selmap_opts_default(selmap_opts_t *o, long stride_cells);

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
  void *mraw, *pgraw;
} selmap_t;

/* Read the DEM, check the options, build the map (configuration scaled to the
 * cell as `trn localize` does), the kernels and P_G (eq. 8) from the sensing
 * positions. On failure prints `trn <cmd>: reason` and returns CLI_BAD_INPUT
 * (w is freed); 0 on success. */
int selmap_prepare(selmap_t *w, const char *cmd, const char *dem_path, const selmap_opts_t *o);

void selmap_free(selmap_t *w);

/* 16-byte aligned block; free with free(raw). */
void *selmap_alloc16(size_t n, void **raw);

/* A map coordinate for printing: rounded to the micrometre, so a cell centre
 * prints as 2019.45, not 2019.4499999999998. */
double selmap_um(double v_m);

/* Core correlation (column, row) -> east-north (sign flipped, no -0). */
double selmap_rho_en(double rho_grid);

#endif
