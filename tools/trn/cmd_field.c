/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/cmd_field.c - `trn field`: the sensor uncertainty field (paper
 * section 6): for every rover position of an area, the predicted uncertainty
 * of its best landmark, computed coarse to fine by trn_field, as a GeoTIFF on
 * the DEM's grid.
 *
 * By default the ground path trn_field_fast (the same raster as trn_field,
 * bit for bit, about an order of magnitude faster, more memory: field.md);
 * --reference runs trn_field, the onboard algorithm.
 *
 * Progress: trn_field's progress callback (trn_field_cfg_t.progress) counts
 * the evaluations; the count is drawn on stderr only when stderr is a
 * terminal. The coarse lattice's size is known in advance, the refinement's
 * is not, so the line shows the coarse phase as a fraction and then the
 * running count. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "commands.h"
#include "dem_io.h"
#include "selmap.h"
#include "trn/trn.h"

/* ---- progress line (trn_field_cfg_t.progress) --------------------------- */
static struct {
  int active; /* stderr is a terminal */
  long count, coarse;
  long shown;
} g_prog;

static void prog_draw(void) {
  if (g_prog.count <= g_prog.coarse) {
    fprintf(stderr, "\rfield: coarse lattice %ld/%ld (%.0f%%)", g_prog.count, g_prog.coarse,
            100.0 * (double)g_prog.count / (double)g_prog.coarse);
  } else {
    fprintf(stderr, "\rfield: coarse lattice %ld/%ld, refining: %ld positions evaluated", g_prog.coarse,
            g_prog.coarse, g_prog.count);
  }
  fflush(stderr);
  g_prog.shown = g_prog.count;
}

/* Called by the core after every evaluation (done = evaluations so far) and
 * once at the end (done = total); never cancels. */
static int32_t field_progress(void *user, uint32_t done, uint32_t total) {
  (void)user;
  if (g_prog.active && done < total) {
    g_prog.count = (long)done;
    if (g_prog.count - g_prog.shown >= 16 || g_prog.count == g_prog.coarse) {
      prog_draw();
    }
  }
  return 0;
}

/* "X0,Y0,X1,Y1" -> 4 finite numbers; 1 ok. */
static int parse_box(const char *s, double v[4]) {
  char buf[256], *p = buf, *c;
  int i;
  if (strlen(s) >= sizeof buf) {
    return 0;
  }
  strcpy(buf, s);
  for (i = 0; i < 4; ++i) {
    c = strchr(p, ',');
    if ((c == NULL) != (i == 3)) {
      return 0;
    }
    if (c != NULL) {
      *c = '\0';
    }
    if (!cli_parse_double(p, &v[i])) {
      return 0;
    }
    p = c != NULL ? c + 1 : p;
  }
  return 1;
}

static int cmpf(const void *a, const void *b) {
  float x = *(const float *)a, y = *(const float *)b;
  return (x > y) - (x < y);
}

static long lattice_count(long n, long step) { return (n - 1 + step - 1) / step + 1; }

int trn_cmd_field(int argc, char **argv) {
  const char *dem_path = NULL, *out = NULL, *area_text = NULL, *ev_out = NULL;
  long coarse;
  double margin, change;
  int json = 0, reference = 0;
  selmap_opts_t so;
  cli_opt_t opts[7 + SELMAP_N_OPTS + 2];
  cli_cmd_t cmd = {"field",
                   "Sensor uncertainty field: the predicted uncertainty of the best landmark from every rover\n"
                   "position of an area (paper section 6), computed coarse to fine.",
                   "Each evaluated position runs the selection of `trn select` (same options, heading fixed for\n"
                   "the whole area); positions between evaluated ones are interpolated bilinearly (the number\n"
                   "of evaluations is reported). Output: float32 GeoTIFF on the DEM's grid, metres; +inf where\n"
                   "no target is informative, no-data (NaN) outside --area-m. --evaluated-out writes 1 where\n"
                   "the value was computed, 0 where interpolated. Map configuration and the global map's error\n"
                   "as `trn select` (default --map-config " SELMAP_MAP_CONFIG_DEFAULT ").",
                   opts, 0};
  selmap_t w;
  int rc, i;
  double box[4];
  trn_window_t area;
  trn_field_cfg_t fcfg;
  trn_field_stats_t stats;
  trn_grid_f32_t g;
  float *fbuf = NULL, *full = NULL;
  uint8_t *ev = NULL;
  void *wsraw = NULL, *ws;
  size_t wsb, aw, ah, n, x, y;
  trn_status_t st;
  char err[768];
  struct timespec t0, t1;
  double secs, bx = NAN, by = NAN, vmin = INFINITY, vmed = NAN;
  long n_inf = 0;

  /* the defaults are the core's (trn_field_cfg_default), printed by --help from these */
  trn_field_cfg_default(&fcfg);
  coarse = fcfg.coarse_step_cells;
  margin = (double)fcfg.margin_rel;
  change = (double)fcfg.change_rel;
  selmap_opts_default(&so, 2);
  opts[0] = (cli_opt_t){"--dem", CLI_STRING, &dem_path, 0, 0, 1, "FILE", "global DEM (any GDAL raster; map frame)", 0};
  opts[1] = (cli_opt_t){"--out", CLI_STRING, &out, 0, 0, 1, "FILE.tif", "the field, GeoTIFF (metres)", 0};
  opts[2] = (cli_opt_t){"--area-m", CLI_STRING, &area_text, 0, 0, 0, "X0,Y0,X1,Y1",
                        "rover positions covered: a map box in metres (default: the whole DEM)", 0};
  opts[3] = (cli_opt_t){"--coarse-step-cells", CLI_LONG, &coarse, 1, 256, 0, "N",
                        "first lattice step, a power of two", 0};
  opts[4] = (cli_opt_t){"--margin-rel", CLI_DOUBLE, &margin, 0.0, 100.0, 0, "M",
                        "refine squares within M x spread of the best", 0};
  opts[5] = (cli_opt_t){"--change-rel", CLI_DOUBLE, &change, 0.0, 100.0, 0, "C",
                        "refine squares changing by more than C x spread", 0};
  opts[6] = (cli_opt_t){"--evaluated-out", CLI_STRING, &ev_out, 0, 0, 0, "FILE.tif",
                        "also write 1 where computed, 0 where interpolated (default: none)", 0};
  selmap_opts(&so, opts + 7);
  cli_find(opts, 7 + SELMAP_N_OPTS, "--stride-cells")->help = "candidate lattice step, cells, as the core's select configuration";
  opts[7 + SELMAP_N_OPTS] = (cli_opt_t){"--json", CLI_FLAG, &json, 0, 0, 0, NULL,
                                        "print one JSON object instead of the summary", 0};
  opts[7 + SELMAP_N_OPTS + 1] = (cli_opt_t){"--reference", CLI_FLAG, &reference, 0, 0, 0, NULL,
                                            "run the onboard algorithm trn_field (same raster, slower, "
                                            "less memory) instead of trn_field_fast", 0};
  cmd.n_opts = sizeof opts / sizeof opts[0];

  rc = cli_parse(&cmd, argc, argv);
  if (rc == CLI_HELP) {
    return 0;
  }
  if (rc != CLI_OK) {
    return rc;
  }
  if ((coarse & (coarse - 1)) != 0) {
    return cli_fail(cmd.name, "--coarse-step-cells %ld is not a power of two", coarse);
  }
  if (area_text != NULL && !parse_box(area_text, box)) {
    return cli_fail(cmd.name, "--area-m: '%s' is not X0,Y0,X1,Y1 (four finite numbers)", area_text);
  }
  if (area_text != NULL && (box[0] > box[2] || box[1] > box[3])) {
    return cli_fail(cmd.name, "--area-m: want X0 <= X1 and Y0 <= Y1, got %s", area_text);
  }
  if (selmap_prepare(&w, cmd.name, dem_path, &so) != 0) {
    return CLI_BAD_INPUT;
  }
  rc = CLI_BAD_INPUT;
  if (area_text == NULL) {
    area.x0 = 0;
    area.y0 = 0;
    area.x1 = w.dem.width - 1;
    area.y1 = w.dem.height - 1;
  } else {
    /* Cells whose centres lie in the box: west/east -> columns, north/south -> rows. */
    double c0, c1, r0, r1;
    dem_map_to_cell(w.dem.gt, box[0], box[3], &c0, &r0);
    dem_map_to_cell(w.dem.gt, box[2], box[1], &c1, &r1);
    c0 = ceil(c0 - 1e-9);
    r0 = ceil(r0 - 1e-9);
    c1 = floor(c1 + 1e-9);
    r1 = floor(r1 + 1e-9);
    if (c0 < 0) c0 = 0;
    if (r0 < 0) r0 = 0;
    if (c1 > w.dem.width - 1) c1 = w.dem.width - 1;
    if (r1 > w.dem.height - 1) r1 = w.dem.height - 1;
    if (c0 > c1 || r0 > r1) {
      cli_fail(cmd.name, "--area-m %s holds no cell centre of the map (x %.3f..%.3f, y %.3f..%.3f)", area_text,
               w.dem.gt[0], w.dem.gt[0] + w.dem.width * w.dem.cell_m, w.dem.gt[3] - w.dem.height * w.dem.cell_m,
               w.dem.gt[3]);
      goto done;
    }
    area.x0 = (int32_t)c0;
    area.y0 = (int32_t)r0;
    area.x1 = (int32_t)c1;
    area.y1 = (int32_t)r1;
  }
  aw = (size_t)(area.x1 - area.x0 + 1);
  ah = (size_t)(area.y1 - area.y0 + 1);
  n = aw * ah;

  trn_field_cfg_default(&fcfg);
  fcfg.coarse_step_cells = (int32_t)coarse;
  fcfg.margin_rel = (float)margin;
  fcfg.change_rel = (float)change;
  fcfg.progress = field_progress;
  fcfg.progress_user = NULL;
  wsb = reference ? trn_field_workspace_bytes(&w.scfg, &w.map, &w.k)
                  : trn_field_fast_workspace_bytes(&w.scfg, &w.map, &w.k, &w.pg);
  ws = wsb > 0 ? selmap_alloc16(wsb, &wsraw) : NULL;
  fbuf = malloc(n * sizeof *fbuf);
  ev = malloc(n);
  full = malloc((size_t)w.dem.width * (size_t)w.dem.height * sizeof *full);
  if (ws == NULL || fbuf == NULL || ev == NULL || full == NULL) {
    cli_fail(cmd.name, "cannot allocate %zu bytes of workspace and the %zu x %zu field", wsb, aw, ah);
    goto done;
  }
  if (trn_grid_f32_init(&g, fbuf, n, (int32_t)aw, (int32_t)ah) != TRN_OK) {
    cli_fail(cmd.name, "area %zu x %zu rejected by the core", aw, ah);
    goto done;
  }

  g_prog.active = isatty(2);
  g_prog.count = 0;
  g_prog.shown = 0;
  g_prog.coarse = lattice_count((long)aw, coarse) * lattice_count((long)ah, coarse);
  clock_gettime(CLOCK_MONOTONIC, &t0);
  if (reference) {
    st = trn_field(&w.map, &w.k, &w.pg, &w.scfg, &fcfg, w.heading_grid_rad, &area, &g, ev, n, &stats, ws, wsb);
  } else {
    st = trn_field_fast(&w.map, &w.k, &w.pg, &w.scfg, &fcfg, w.heading_grid_rad, &area, &g, ev, n, &stats, ws,
                        wsb);
  }
  clock_gettime(CLOCK_MONOTONIC, &t1);
  if (g_prog.active) {
    prog_draw();
    fputc('\n', stderr);
  }
  g_prog.active = 0;
  secs = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
  if (st != TRN_OK) {
    cli_fail(cmd.name, "field failed: %s", trn_strerror(st));
    goto done;
  }
  if (stats.best_x < 0) {
    cli_fail(cmd.name, "no informative target from any of the %u positions evaluated (featureless terrain?); "
             "nothing written", stats.evaluations);
    rc = CLI_NO_RESULT;
    goto done;
  }

  /* Area -> the DEM's grid. */
  for (i = 0; i < w.dem.width * w.dem.height; ++i) {
    full[i] = NAN;
  }
  for (y = 0; y < ah; ++y) {
    for (x = 0; x < aw; ++x) {
      full[((size_t)area.y0 + y) * (size_t)w.dem.width + (size_t)area.x0 + x] = fbuf[y * aw + x];
    }
  }
  if (dem_write_gtiff(out, full, w.dem.width, w.dem.height, w.dem.gt, w.dem.srs_wkt, err, sizeof err) != 0) {
    cli_fail(cmd.name, "--out: %s", err);
    goto done;
  }
  if (ev_out != NULL) {
    for (y = 0; y < ah; ++y) {
      for (x = 0; x < aw; ++x) {
        full[((size_t)area.y0 + y) * (size_t)w.dem.width + (size_t)area.x0 + x] = ev[y * aw + x] ? 1.0f : 0.0f;
      }
    }
    if (dem_write_gtiff(ev_out, full, w.dem.width, w.dem.height, w.dem.gt, w.dem.srs_wkt, err, sizeof err) != 0) {
      cli_fail(cmd.name, "--evaluated-out: %s", err);
      goto done;
    }
  }

  /* Summary: minimum (the core's), median of the finite values, infinite count. */
  {
    size_t nf = 0;
    for (i = 0; i < (int)n; ++i) {
      if (isfinite(fbuf[i])) {
        fbuf[nf++] = fbuf[i];
      } else {
        ++n_inf;
      }
    }
    if (nf > 0) {
      qsort(fbuf, nf, sizeof *fbuf, cmpf);
      vmed = fbuf[nf / 2];
    }
  }
  if (stats.best_x >= 0) {
    dem_cell_to_map(w.dem.gt, (double)stats.best_x, (double)stats.best_y, &bx, &by);
    vmin = stats.best_m;
  }
  if (json) {
    json_t j;
    json_begin(&j, stdout);
    json_str(&j, "file", out);
    json_int(&j, "width", (long long)aw);
    json_int(&j, "height", (long long)ah);
    json_obj(&j, "area");
    {
      double ax0, ay0, ax1, ay1;
      dem_cell_to_map(w.dem.gt, area.x0 - 0.5, area.y1 + 0.5, &ax0, &ay0);
      dem_cell_to_map(w.dem.gt, area.x1 + 0.5, area.y0 - 0.5, &ax1, &ay1);
      json_num(&j, "x0_m", selmap_um(ax0));
      json_num(&j, "y0_m", selmap_um(ay0));
      json_num(&j, "x1_m", selmap_um(ax1));
      json_num(&j, "y1_m", selmap_um(ay1));
    }
    json_obj_end(&j);
    json_int(&j, "cells", (long long)stats.cells);
    json_int(&j, "evaluations", (long long)stats.evaluations);
    json_obj(&j, "best");
    json_num(&j, "x_m", selmap_um(bx));
    json_num(&j, "y_m", selmap_um(by));
    json_num(&j, "uncertainty_m", vmin);
    json_obj_end(&j);
    json_num(&j, "median_uncertainty_m", vmed);
    json_int(&j, "no_target_cells", n_inf);
    json_num(&j, "heading_deg", so.heading_deg);
    json_int(&j, "coarse_step_cells", coarse);
    json_int(&j, "stride_cells", so.stride_cells);
    json_num(&j, "seconds", secs);
    json_str(&j, "algorithm", reference ? "trn_field" : "trn_field_fast");
    json_int(&j, "workspace_bytes", (long long)wsb);
    selmap_json_config(&j, &so, &w.cfg, w.sigma_h);
    json_end(&j);
  } else {
    printf("wrote %s: field over %zu x %zu rover positions of %g m\n", out, aw, ah, w.dem.cell_m);
    printf("evaluated    %u of %u positions (%.1fx fewer), %.1f s\n", stats.evaluations, stats.cells,
           stats.evaluations > 0 ? (double)stats.cells / stats.evaluations : 0.0, secs);
    if (stats.best_x >= 0) {
      printf("best         x = %.3f m   y = %.3f m   uncertainty %.4f m\n", bx, by, vmin);
      printf("median       %.4f m; %ld positions with no informative target\n", vmed, n_inf);
    } else {
      printf("best         none: no position has an informative target\n");
    }
    selmap_print_config(&so, &w.cfg);
  }
  rc = 0;

done:
  free(fbuf);
  free(full);
  free(ev);
  free(wsraw);
  selmap_free(&w);
  return rc;
}

