/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/cmd_select.c - `trn select`: the landmark a rover should sense
 * next (paper section 4): every candidate target's predicted localization
 * uncertainty from one rover position, the best one, the next best distinct
 * ones, and optionally the per-candidate uncertainty as a GeoTIFF (Fig. 2b).
 *
 * Frames as selmap.h: the rover and every reported position in map metres
 * (x east, y north), bearings in degrees counter-clockwise from the heading,
 * rho in the east-north frame (the core's column-row correlation with its
 * sign flipped). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "dem_io.h"
#include "selmap.h"
#include "trn/trn.h"

#define PI 3.14159265358979323846
#define EXIT_NO_TARGET CLI_NO_RESULT

static void target_json(json_t *j, const selmap_t *w, const trn_candidate_t *c) {
  double x, y;
  dem_cell_to_map(w->dem.gt, (double)c->x, (double)c->y, &x, &y);
  json_num(j, "x_m", selmap_um(x));
  json_num(j, "y_m", selmap_um(y));
  json_num(j, "range_m", (double)c->range_m);
  json_num(j, "bearing_deg", -(double)c->bearing_rad * 180.0 / PI + 0.0);
  json_num(j, "sigma_x_m", c->sigma_x_m);
  json_num(j, "sigma_y_m", c->sigma_y_m);
  json_num(j, "rho", selmap_rho_en(c->rho));
  json_num(j, "uncertainty_m", c->uncertainty_m);
}

int trn_cmd_select(int argc, char **argv) {
  const char *dem_path = NULL, *out_map = NULL;
  double rover_m[2] = {0.0, 0.0};
  long next_best = 5;
  int json = 0;
  selmap_opts_t so;
  cli_opt_t opts[4 + SELMAP_N_OPTS + 1];
  cli_cmd_t cmd = {"select",
                   "Select the landmark to sense next: predicted localization uncertainty of every candidate\n"
                   "target seen from the rover (paper section 4, eqs. 8-9, 6).",
                   "Candidates are patch centres on a lattice of --stride-cells around the rover, within\n"
                   "--min-range-m..--max-range-m and --pan-deg, patch inside the map. The global map's error\n"
                   "grows with the distance to its sensing positions (eq. 8), the new local map's with the\n"
                   "range from the rover (eq. 9). Output: the target (map x_m, y_m), its predicted sigma_x_m\n"
                   "(east), sigma_y_m (north), rho (east-north), uncertainty_m = sqrt(sx^2 + sy^2), and the next\n"
                   "best targets. --out-map: float32 GeoTIFF on the DEM's grid, each candidate's uncertainty (m)\n"
                   "at its centre cell, +inf where its fit is ill-conditioned, no-data (NaN) elsewhere.\n"
                   "Exit 3 (\"no informative target\") when no candidate is informative or none is in reach.\n"
                   "The map configuration defaults to --map-config " SELMAP_MAP_CONFIG_DEFAULT "; the global map's\n"
                   "error is eq. 8's S0 + K r^2 (--global-sigma-m, --global-sigma-k) or a per-cell raster\n"
                   "(--global-error, the model where it has no data).",
                   opts, 0};
  selmap_t w;
  int rc, rcol, rrow;
  double rc_f, rr_f;
  size_t cap, wsb, i, *ranked = NULL, nrank;
  trn_candidate_t *cands = NULL;
  trn_select_result_t res;
  trn_rover_t rover;
  trn_status_t st;
  void *wsraw = NULL, *ws;
  float *map = NULL;

  selmap_opts_default(&so, 1);
  opts[0] = (cli_opt_t){"--dem", CLI_STRING, &dem_path, 0, 0, 1, "FILE", "global DEM (any GDAL raster; map frame)", 0};
  opts[1] = (cli_opt_t){"--rover", CLI_XY, rover_m, 0, 0, 1, "X,Y", "rover position, map metres", 0};
  opts[2] = (cli_opt_t){"--out-map", CLI_STRING, &out_map, 0, 0, 0, "FILE.tif",
                        "write every candidate's predicted uncertainty (m) as a GeoTIFF (default: none)", 0};
  opts[3] = (cli_opt_t){"--next-best", CLI_LONG, &next_best, 0, 64, 0, "N",
                        "distinct next best targets listed", 0};
  selmap_opts(&so, opts + 4);
  cli_find(opts, 4 + SELMAP_N_OPTS, "--stride-cells")->help = "candidate lattice step, cells (1: every cell, the full Fig. 2b map)";
  opts[4 + SELMAP_N_OPTS] = (cli_opt_t){"--json", CLI_FLAG, &json, 0, 0, 0, NULL,
                                        "print one JSON object instead of the summary", 0};
  cmd.n_opts = sizeof opts / sizeof opts[0];

  rc = cli_parse(&cmd, argc, argv);
  if (rc == CLI_HELP) {
    return 0;
  }
  if (rc != CLI_OK) {
    return rc;
  }
  if (selmap_prepare(&w, cmd.name, dem_path, &so) != 0) {
    return CLI_BAD_INPUT;
  }
  rc = CLI_BAD_INPUT;
  if (!dem_cell_of(&w.dem, rover_m[0], rover_m[1], &rcol, &rrow)) {
    cli_fail(cmd.name, "--rover %.3f,%.3f is off the map (x %.3f..%.3f, y %.3f..%.3f)", rover_m[0], rover_m[1],
             w.dem.gt[0], w.dem.gt[0] + w.dem.width * w.dem.cell_m, w.dem.gt[3] - w.dem.height * w.dem.cell_m,
             w.dem.gt[3]);
    goto done;
  }
  dem_map_to_cell(w.dem.gt, rover_m[0], rover_m[1], &rc_f, &rr_f);
  rover.pos.x_cells = (float)rc_f;
  rover.pos.y_cells = (float)rr_f;
  rover.heading_rad = w.heading_grid_rad;

  cap = trn_select_max_candidates(&w.scfg, (float)w.dem.cell_m);
  wsb = trn_select_workspace_bytes(&w.scfg, &w.map, &w.k);
  nrank = (size_t)next_best + 1u;
  cands = cap > 0 ? malloc(cap * sizeof *cands) : NULL;
  ranked = malloc(nrank * sizeof *ranked);
  ws = wsb > 0 ? selmap_alloc16(wsb, &wsraw) : NULL;
  if (cands == NULL || ranked == NULL || ws == NULL) {
    cli_fail(cmd.name, "cannot allocate %zu candidates and %zu bytes of workspace", cap, wsb);
    goto done;
  }
  st = trn_select(&w.map, &w.k, &w.pg, &w.scfg, &rover, cands, cap, ranked, nrank, &res, ws, wsb);
  if (st == TRN_E_NOTARGET) {
    if (res.n_candidates == 0) {
      cli_fail(cmd.name, "no informative target: no candidate lies within reach (range %g..%g m, pan %g..%g deg, "
               "patch inside the map)", so.min_range_m, so.max_range_m, so.pan_deg[0], so.pan_deg[1]);
    } else {
      cli_fail(cmd.name, "no informative target: all %zu candidates are featureless (their predicted fit is "
               "ill-conditioned)", res.n_candidates);
    }
    rc = EXIT_NO_TARGET;
    goto done;
  }
  if (st != TRN_OK) {
    cli_fail(cmd.name, "selection failed: %s", trn_strerror(st));
    goto done;
  }

  if (out_map != NULL) {
    char err[768];
    size_t n = (size_t)w.dem.width * (size_t)w.dem.height;
    map = malloc(n * sizeof *map);
    if (map == NULL) {
      cli_fail(cmd.name, "cannot allocate the output map");
      goto done;
    }
    for (i = 0; i < n; ++i) {
      map[i] = NAN;
    }
    for (i = 0; i < res.n_candidates; ++i) {
      const trn_candidate_t *c = &cands[i];
      map[(size_t)c->y * (size_t)w.dem.width + (size_t)c->x] =
          c->informative ? (float)c->uncertainty_m : (float)INFINITY;
    }
    if (dem_write_gtiff(out_map, map, w.dem.width, w.dem.height, w.dem.gt, w.dem.srs_wkt, err, sizeof err) != 0) {
      cli_fail(cmd.name, "--out-map: %s", err);
      goto done;
    }
  }

  {
    const trn_candidate_t *b = &cands[res.best];
    double tx, ty;
    dem_cell_to_map(w.dem.gt, (double)b->x, (double)b->y, &tx, &ty);
    if (json) {
      json_t j;
      json_begin(&j, stdout);
      json_obj(&j, "target");
      json_num(&j, "x_m", selmap_um(tx));
      json_num(&j, "y_m", selmap_um(ty));
      json_num(&j, "range_m", (double)b->range_m);
      json_num(&j, "bearing_deg", -(double)b->bearing_rad * 180.0 / PI + 0.0);
      json_obj_end(&j);
      json_num(&j, "sigma_x_m", b->sigma_x_m);
      json_num(&j, "sigma_y_m", b->sigma_y_m);
      json_num(&j, "rho", selmap_rho_en(b->rho));
      json_num(&j, "uncertainty_m", b->uncertainty_m);
      json_obj(&j, "rover");
      json_num(&j, "x_m", rover_m[0]);
      json_num(&j, "y_m", rover_m[1]);
      json_num(&j, "heading_deg", so.heading_deg);
      json_obj_end(&j);
      json_arr(&j, "next_best");
      for (i = 1; i < res.n_ranked; ++i) {
        json_obj(&j, NULL);
        target_json(&j, &w, &cands[ranked[i]]);
        json_obj_end(&j);
      }
      json_arr_end(&j);
      json_int(&j, "candidates", (long long)res.n_candidates);
      json_int(&j, "informative", (long long)res.n_informative);
      json_num(&j, "min_range_m", so.min_range_m);
      json_num(&j, "max_range_m", so.max_range_m);
      json_int(&j, "stride_cells", so.stride_cells);
      json_int(&j, "patch_cells", (long long)res.patch_cells);
      json_num(&j, "patch_m", res.patch_cells * w.dem.cell_m);
      json_num(&j, "cell_m", w.dem.cell_m);
      json_arr(&j, "sensors");
      for (i = 0; i < w.n_sensors; ++i) {
        json_obj(&j, NULL);
        json_num(&j, "x_m", selmap_um(w.sensors_m[i][0]));
        json_num(&j, "y_m", selmap_um(w.sensors_m[i][1]));
        json_obj_end(&j);
      }
      json_arr_end(&j);
      if (out_map != NULL) {
        json_str(&j, "out_map", out_map);
      }
      selmap_json_config(&j, &so, &w.cfg, w.sigma_h);
      json_end(&j);
    } else {
      printf("rover        x = %.3f m   y = %.3f m   heading %g deg\n", rover_m[0], rover_m[1], so.heading_deg);
      printf("target       x = %.3f m   y = %.3f m   range %.2f m   bearing %.0f deg\n", tx, ty,
             (double)b->range_m, -(double)b->bearing_rad * 180.0 / PI + 0.0);
      printf("predicted    sigma_x = %.4f m  sigma_y = %.4f m  rho = %.3f   uncertainty %.4f m\n", b->sigma_x_m,
             b->sigma_y_m, selmap_rho_en(b->rho), b->uncertainty_m);
      for (i = 1; i < res.n_ranked; ++i) {
        const trn_candidate_t *c = &cands[ranked[i]];
        double x, y;
        dem_cell_to_map(w.dem.gt, (double)c->x, (double)c->y, &x, &y);
        printf("next best %zu  x = %.3f m   y = %.3f m   range %.2f m   uncertainty %.4f m\n", i, x, y,
               (double)c->range_m, c->uncertainty_m);
      }
      printf("candidates   %zu, %zu informative, patch %d x %d cells (%.2f m)\n", res.n_candidates,
             res.n_informative, res.patch_cells, res.patch_cells, res.patch_cells * w.dem.cell_m);
      selmap_print_config(&so, &w.cfg);
      if (out_map != NULL) {
        printf("wrote %s\n", out_map);
      }
    }
  }
  rc = 0;

done:
  free(map);
  free(cands);
  free(ranked);
  free(wsraw);
  selmap_free(&w);
  return rc;
}
