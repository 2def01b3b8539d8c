/* tools/trn/cmd_localize.c - `trn localize`: the maximum-likelihood rover
 * position of a local DEM (rover frame) in a global DEM (map frame).
 *
 * Frames. Map: x east, y north, metres (the global DEM's geotransform).
 * Rover frame: the local DEM's geotransform gives metres relative to the
 * rover, x east, y north, the rover at (0, 0) (heading known, paper section
 * 2). The core works in global cells with y = row (south); the local DEM is
 * handed over with the rover's nearest local cell (rx, ry) as its origin, and
 * the core's pose is where that cell's centre lands in the global grid. The
 * rover's map position is that point minus the cell centre's offset from the
 * rover. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "dem_io.h"
#include "trn/trn.h"

/* 16-byte aligned block; free with free(raw). */
static void *alloc16(size_t n, void **raw) {
  uint8_t *p = malloc(n + 16u);
  *raw = p;
  if (p == NULL) {
    return NULL;
  }
  return p + ((16u - ((uintptr_t)p & 15u)) & 15u);
}

static const char *status_word(trn_status_t st) {
  return st == TRN_OK ? "ok" : st == TRN_E_ILLCOND ? "ill_conditioned" : "error";
}

int trn_cmd_localize(int argc, char **argv) {
  const char *dem_path = NULL, *local_path = NULL;
  double prior[2] = {0.0, 0.0};
  double window_m = 2.5;
  long band = 1, local_band = 1, max_local = 1024;
  int json = 0;
  cli_opt_t opts[] = {
      {"--dem", CLI_STRING, &dem_path, 0, 0, 1, "FILE", "global DEM (any GDAL raster; map frame)", 0},
      {"--local", CLI_STRING, &local_path, 0, 0, 1, "FILE", "local DEM in the rover frame (rover at 0,0; x east, y north)", 0},
      {"--prior", CLI_XY, prior, 0, 0, 1, "X,Y", "where the rover believes it is, map metres", 0},
      {"--window-m", CLI_DOUBLE, &window_m, 0.0, 1e6, 0, "R", "prior uncertainty searched: +-R metres per axis (default 2.5)", 0},
      {"--band", CLI_LONG, &band, 1, 65535, 0, "N", "band of --dem (default 1)", 0},
      {"--local-band", CLI_LONG, &local_band, 1, 65535, 0, "N", "band of --local (default 1)", 0},
      {"--max-local-cells", CLI_LONG, &max_local, 8, TRN_MAX_DIM, 0, "N", "largest local map side accepted, cells (default 1024)", 0},
      {"--json", CLI_FLAG, &json, 0, 0, 0, NULL, "print one JSON object instead of the summary", 0},
  };
  cli_cmd_t cmd = {"localize", "Localize a rover: match its local DEM against the global DEM (paper section 2).",
                   "Both DEMs must have the same square cell size; heights in metres, no-data and NaN\n"
                   "mean \"not seen\". The map configuration scales with the cell size c: high-pass\n"
                   "half-width 10c, height bins c, inlier sigma c (at c = 0.1 m: trn_map_cfg_default).\n"
                   "Output: x_m, y_m (map), sigma_x_m (east), sigma_y_m (north), rho (east-north),\n"
                   "failure_probability, status (ok | ill_conditioned).",
                   opts, sizeof opts / sizeof opts[0]};
  dem_t g, l;
  char err[768];
  double cell, rcol, rrow, dx_m, dy_m, pc, pr, ex, ey, est_x, est_y, rho_en;
  long radius;
  int rx, ry, pcol, prow, rc;
  trn_map_cfg_t cfg;
  trn_map_t map;
  trn_grid_f32_t gg, lg;
  trn_window_t win;
  trn_loc_result_t res;
  trn_status_t st;
  size_t mb, wb, max_pts;
  void *mraw = NULL, *wraw = NULL, *mbuf, *ws;

  rc = cli_parse(&cmd, argc, argv);
  if (rc == CLI_HELP) {
    return 0;
  }
  if (rc != CLI_OK) {
    return rc;
  }
  if (dem_read(dem_path, (int)band, TRN_MAX_DIM, &g, err, sizeof err) != 0) {
    return cli_fail(cmd.name, "--dem: %s", err);
  }
  if (dem_read(local_path, (int)local_band, TRN_MAX_DIM, &l, err, sizeof err) != 0) {
    dem_free(&g);
    return cli_fail(cmd.name, "--local: %s", err);
  }
  rc = CLI_BAD_INPUT;
  cell = g.cell_m;
  if (l.width > max_local || l.height > max_local) {
    cli_fail(cmd.name, "--local is %d x %d cells, larger than --max-local-cells %ld", l.width, l.height,
             max_local);
    goto done;
  }
  if (l.width > g.width || l.height > g.height) {
    cli_fail(cmd.name, "--local (%d x %d cells) is larger than --dem (%d x %d cells)", l.width, l.height,
             g.width, g.height);
    goto done;
  }
  if (fabs(l.cell_m - cell) > 1e-6 * cell) {
    cli_fail(cmd.name, "cell sizes differ: --dem %g m, --local %g m (resample one to the other)", cell,
             l.cell_m);
    goto done;
  }
  if (cell > 1000.0) {
    cli_fail(cmd.name, "cell size %g m is above the 1000 m the core accepts", cell);
    goto done;
  }
  /* The rover (0, 0 in the rover frame) in the local grid. */
  dem_map_to_cell(l.gt, 0.0, 0.0, &rcol, &rrow);
  if (fabs(rcol) > (double)TRN_MAX_DIM || fabs(rrow) > (double)TRN_MAX_DIM) {
    cli_fail(cmd.name, "--local: the rover (0,0 of its geotransform) is %.0f, %.0f cells from the grid; is it "
                       "in the rover frame?", rcol, rrow);
    goto done;
  }
  rx = (int)floor(rcol + 0.5);
  ry = (int)floor(rrow + 0.5);
  /* Offset of that local cell's centre from the rover, map metres. */
  dem_cell_to_map(l.gt, (double)rx, (double)ry, &dx_m, &dy_m);

  if (!dem_cell_of(&g, prior[0], prior[1], &pcol, &prow)) {
    cli_fail(cmd.name, "--prior %.3f,%.3f is off the map (x %.3f..%.3f, y %.3f..%.3f)", prior[0], prior[1], g.gt[0],
             g.gt[0] + g.width * cell, g.gt[3] - g.height * cell, g.gt[3]);
    goto done;
  }
  radius = (long)ceil(window_m / cell - 1e-9);
  if (radius > TRN_MAX_DIM) {
    cli_fail(cmd.name, "--window-m %g is %ld cells, more than the %d the core searches", window_m, radius,
             TRN_MAX_DIM);
    goto done;
  }
  /* Window of poses of the local cell (rx, ry), clipped to the map. */
  dem_map_to_cell(g.gt, prior[0] + dx_m, prior[1] + dy_m, &pc, &pr);
  pcol = (int)floor(pc + 0.5);
  prow = (int)floor(pr + 0.5);
  win.x0 = (int32_t)(pcol - radius < 0 ? 0 : pcol - radius);
  win.y0 = (int32_t)(prow - radius < 0 ? 0 : prow - radius);
  win.x1 = (int32_t)(pcol + radius > g.width - 1 ? g.width - 1 : pcol + radius);
  win.y1 = (int32_t)(prow + radius > g.height - 1 ? g.height - 1 : prow + radius);
  if (win.x0 > win.x1 || win.y0 > win.y1) {
    cli_fail(cmd.name, "the searched window around --prior lies off the map");
    goto done;
  }

  trn_map_cfg_default(&cfg);
  cfg.terrain.cell_m = (float)cell;
  cfg.terrain.zbin_m = (float)cell;
  cfg.terrain.highpass_half_m = (float)(10.0 * cell);
  cfg.sigma_m = (float)cell;
  if ((st = trn_map_cfg_check(&cfg)) != TRN_OK) {
    cli_fail(cmd.name, "map configuration for %g m cells rejected: %s", cell, trn_strerror(st));
    goto done;
  }
  if (trn_grid_f32_init(&gg, g.data, (size_t)g.width * (size_t)g.height, g.width, g.height) != TRN_OK ||
      trn_grid_f32_init(&lg, l.data, (size_t)l.width * (size_t)l.height, l.width, l.height) != TRN_OK) {
    cli_fail(cmd.name, "DEM sizes rejected by the core");
    goto done;
  }
  mb = trn_map_bytes(&cfg, g.width, g.height);
  mbuf = mb > 0 ? alloc16(mb, &mraw) : NULL;
  if (mbuf == NULL) {
    cli_fail(cmd.name, "cannot allocate %zu bytes for the prepared map", mb);
    goto done;
  }
  st = trn_map_build(&map, &cfg, &gg, mbuf, mb);
  if (st != TRN_OK) {
    cli_fail(cmd.name, "--dem: cannot prepare the map: %s", trn_strerror(st));
    goto done;
  }
  max_pts = (size_t)l.width * (size_t)l.height * (size_t)cfg.terrain.nz;
  wb = trn_localize_dem_workspace_bytes(&map, l.width, l.height, max_pts, &win);
  ws = wb > 0 ? alloc16(wb, &wraw) : NULL;
  if (ws == NULL) {
    cli_fail(cmd.name, "cannot allocate %zu bytes of localization workspace", wb);
    goto done;
  }
  st = trn_localize_dem(&map, &lg, rx, ry, max_pts, &win, ws, wb, &res);
  if (st != TRN_OK && st != TRN_E_ILLCOND) {
    cli_fail(cmd.name, "localization failed: %s", trn_strerror(st));
    goto done;
  }

  /* Pose (global cells, y = row = south) -> rover position (map, y north). */
  dem_cell_to_map(g.gt, res.x, res.y, &ex, &ey);
  est_x = ex - dx_m;
  est_y = ey - dy_m;
  /* The core's row axis points south: flip the correlation's sign (no -0). */
  rho_en = isfinite(res.rho) && res.rho != 0.0 ? -res.rho : res.rho == 0.0 ? 0.0 : res.rho;
  if (json) {
    json_t j;
    json_begin(&j, stdout);
    json_num(&j, "x_m", est_x);
    json_num(&j, "y_m", est_y);
    json_num(&j, "sigma_x_m", res.sigma_x_m);
    json_num(&j, "sigma_y_m", res.sigma_y_m);
    json_num(&j, "rho", rho_en);
    json_num(&j, "failure_probability", res.failure_probability);
    json_str(&j, "status", status_word(st));
    json_obj(&j, "prior");
    json_num(&j, "x_m", prior[0]);
    json_num(&j, "y_m", prior[1]);
    json_obj_end(&j);
    json_num(&j, "window_m", window_m);
    json_num(&j, "cell_m", cell);
    json_bool(&j, "on_window_edge", res.on_window_edge != 0);
    json_int(&j, "local_points", (long long)res.n_points);
    json_num(&j, "log_likelihood", res.ll_best);
    json_int(&j, "poses_scored", (long long)res.stats.poses_scored);
    json_end(&j);
  } else {
    printf("estimate     x = %.3f m   y = %.3f m   status: %s\n", est_x, est_y, status_word(st));
    printf("prior        x = %.3f m   y = %.3f m   (window +-%g m = %ld cells)\n", prior[0], prior[1], window_m,
           radius);
    printf("covariance   sigma_x = %.4f m  sigma_y = %.4f m  rho = %.3f\n", res.sigma_x_m, res.sigma_y_m,
           rho_en);
    printf("failure      probability %.3g%s\n", res.failure_probability,
           res.on_window_edge ? "   (best pose on the window edge: widen --window-m)" : "");
    printf("matched      %zu local voxels, %llu poses scored exactly\n", res.n_points,
           (unsigned long long)res.stats.poses_scored);
  }
  rc = 0;

done:
  free(mraw);
  free(wraw);
  dem_free(&g);
  dem_free(&l);
  return rc;
}
