/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/cmd_terrain.c - `trn terrain`: a synthetic Mars terrain
 * (Golombek & Rapp rocks on smooth relief) as a georeferenced GeoTIFF. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "cli.h"
#include "commands.h"
#include "dem_io.h"
#include "terrain_gen.h"
#include "trn/trn_config.h"

static void on_progress(void *ctx, long done, long total) {
  ((progress_t *)ctx)->total = total;
  progress_update((progress_t *)ctx, done);
}

int trn_cmd_terrain(int argc, char **argv) {
  const char *out = NULL, *crs = NULL;
  long size = 256;
  double cell = 0.1, k = 0.1, ratio = 0.5, dmin = 0.0, dmax = 0.0, relief = 0.05;
  double origin[2] = {0.0, 0.0};
  uint64_t seed = 1;
  int json = 0;
  cli_opt_t opts[] = {
      {"--out", CLI_STRING, &out, 0, 0, 1, "FILE.tif", "GeoTIFF to write", 0},
      {"--size-cells", CLI_LONG, &size, 8, TRN_MAX_DIM, 0, "N", "map side, cells", 0},
      {"--cell-m", CLI_DOUBLE, &cell, 0.001, 100.0, 0, "C", "cell size, metres", 0},
      {"--coverage", CLI_DOUBLE, &k, 0.01, 0.5, 0, "K", "rock coverage k of F_k(D) = k exp(-q(k) D)", 0},
      {"--seed", CLI_U64, &seed, 0, 0, 0, "S", "random seed", 0},
      {"--height-ratio", CLI_DOUBLE, &ratio, 0.05, 2.0, 0, "R", "rock height / diameter (0.5: hemispheres)", 0},
      {"--min-diameter-m", CLI_DOUBLE, &dmin, 0.001, 100.0, 0, "D", "smallest rock drawn (default 2 cells)", 0},
      {"--max-diameter-m", CLI_DOUBLE, &dmax, 0.001, 100.0, 0, "D", "largest rock drawn (default ln(1e4)/q(k))", 0},
      {"--relief-m", CLI_DOUBLE, &relief, 0.0, 100.0, 0, "A", "RMS of the smooth background relief", 0},
      {"--origin", CLI_XY, origin, 0, 0, 0, "X,Y", "map coordinates of the south-west corner", 0},
      {"--crs", CLI_STRING, &crs, 0, 0, 0, "SRS", "CRS to tag the file with (EPSG:n, IAU_2015:n, WKT, PROJ; default none)", 0},
      {"--json", CLI_FLAG, &json, 0, 0, 0, NULL, "print one JSON object instead of the summary", 0},
  };
  cli_cmd_t cmd = {"terrain", "Write a synthetic Mars terrain: Golombek & Rapp (1997) rocks on smooth relief.",
                   "Rocks are half-ellipsoids of diameter D and height R*D drawn from the cumulative\n"
                   "fractional area F_k(D) = k exp(-(1.79 + 0.152/k) D), D in metres (docs/method.md).\n"
                   "The GeoTIFF is north-up, float32 metres, no-data NaN.",
                   opts, sizeof opts / sizeof opts[0]};
  tg_params_t p;
  const char *why;
  tg_rock_t *rocks;
  size_t n, n2, i;
  float *dem;
  double gt[6], area_in = 0.0, map_area, fmodel;
  char *wkt = NULL;
  char err[512];
  progress_t prog;
  int rc = cli_parse(&cmd, argc, argv);

  if (rc == CLI_HELP) {
    return 0;
  }
  if (rc != CLI_OK) {
    return rc;
  }
  tg_default(&p, (int)size, (int)size, cell);
  p.coverage_k = k;
  p.height_ratio = ratio;
  p.d_min_m = cli_find(opts, sizeof opts / sizeof opts[0], "--min-diameter-m")->seen ? dmin : 2.0 * cell;
  p.d_max_m = cli_find(opts, sizeof opts / sizeof opts[0], "--max-diameter-m")->seen ? dmax : tg_auto_d_max(k);
  p.relief_m = relief;
  p.seed = seed;
  if (p.d_max_m < p.d_min_m) {
    return cli_fail(cmd.name, "largest rock diameter %g m is below the smallest %g m (see --min-diameter-m, "
                              "--max-diameter-m)", p.d_max_m, p.d_min_m);
  }
  if ((why = tg_check(&p)) != NULL) {
    return cli_fail(cmd.name, "%s", why);
  }
  if (crs != NULL && (wkt = dem_srs_to_wkt(crs, err, sizeof err)) == NULL) {
    return cli_fail(cmd.name, "%s", err);
  }

  n = tg_draw_rocks(&p, NULL, 0);
  rocks = malloc((n + 1) * sizeof *rocks);
  dem = malloc((size_t)size * (size_t)size * sizeof *dem);
  if (rocks == NULL || dem == NULL) {
    free(rocks);
    free(dem);
    free(wkt);
    return cli_fail(cmd.name, "out of memory for %zu rocks on %ld x %ld cells", n, size, size);
  }
  n2 = tg_draw_rocks(&p, rocks, n);
  if (n2 != n) {
    free(rocks);
    free(dem);
    free(wkt);
    return cli_fail(cmd.name, "internal error: rock draw not repeatable (%zu vs %zu)", n, n2);
  }
  progress_begin(&prog, "terrain", (long)n + size);
  tg_render(&p, rocks, n, dem, on_progress, &prog);
  progress_end(&prog);

  /* Realised rock area: rocks centred on the map, against the model. */
  map_area = (double)size * cell * (double)size * cell;
  for (i = 0; i < n; ++i) {
    double ext = (double)size * cell;
    if (rocks[i].x_m >= 0.0 && rocks[i].x_m < ext && rocks[i].y_m >= 0.0 && rocks[i].y_m < ext) {
      area_in += 0.25 * 3.14159265358979323846 * rocks[i].d_m * rocks[i].d_m;
    }
  }
  fmodel = tg_cum_area(k, p.d_min_m) - tg_cum_area(k, p.d_max_m);

  /* North-up: the top-left corner is (origin x, origin y + side). */
  gt[0] = origin[0];
  gt[1] = cell;
  gt[2] = 0.0;
  gt[3] = origin[1] + (double)size * cell;
  gt[4] = 0.0;
  gt[5] = -cell;
  rc = dem_write_gtiff(out, dem, (int)size, (int)size, gt, wkt, err, sizeof err);
  free(dem);
  free(rocks);
  free(wkt);
  if (rc != 0) {
    return cli_fail(cmd.name, "%s", err);
  }

  if (json) {
    json_t j;
    json_begin(&j, stdout);
    json_str(&j, "file", out);
    json_int(&j, "width", size);
    json_int(&j, "height", size);
    json_num(&j, "cell_m", cell);
    json_obj(&j, "origin");
    json_num(&j, "x_m", origin[0]);
    json_num(&j, "y_m", origin[1]);
    json_obj_end(&j);
    json_num(&j, "coverage_k", k);
    json_num(&j, "q_per_m", tg_q(k));
    json_num(&j, "height_ratio", ratio);
    json_num(&j, "d_min_m", p.d_min_m);
    json_num(&j, "d_max_m", p.d_max_m);
    json_num(&j, "relief_m", relief);
    json_int(&j, "seed", (long long)seed);
    json_int(&j, "rocks", (long long)n);
    json_num(&j, "rock_area_fraction", area_in / map_area);
    json_num(&j, "model_area_fraction", fmodel);
    json_end(&j);
  } else {
    printf("wrote %s: %ld x %ld cells of %g m, origin (%g, %g) m, seed %llu\n", out, size, size, cell,
           origin[0], origin[1], (unsigned long long)seed);
    printf("rocks: %zu with D in [%.3f, %.3f] m, height %.2f D; area fraction %.4f (model F_k(Dmin)-F_k(Dmax) "
           "= %.4f, k = %g)\n",
           n, p.d_min_m, p.d_max_m, ratio, area_in / map_area, fmodel, k);
  }
  return 0;
}
