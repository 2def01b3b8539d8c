/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/cmd_profile.c - `trn profile`: the onboard pipeline's stages on a
 * stated configuration, timed on the host, optionally counted in
 * instructions under callgrind, with the workspace each needs and its share
 * of a target budget.
 *
 * Input: a deterministic synthetic terrain made in-process (tools/support
 * synth: the main job's rock field, 15 % cover, radii 5-30 cm, 0.1 m cells),
 * a rover near the map centre whose local map is rendered at a sub-cell
 * offset, a prior a few cells off, and the map centre as the global map's
 * sensing position. Same seed, same input, same instruction counts.
 *
 * Stages (names as in the budget file), in pipeline order:
 *   highpass_occupancy  trn_highpass + trn_occupancy of the global DEM
 *   chamfer             trn_chamfer3d of that occupancy
 *   map_build           trn_map_build (the two above + K, ln p table, pyramid)
 *   prob_map            trn_prob_global_map (eq. 8)
 *   select              trn_select: every candidate target of the rover
 *   local_occupancy     trn_highpass + trn_occupancy_points + trn_points_order
 *                       of the local DEM
 *   search              trn_search_bb: the best pose in the prior window
 *   peak_fit            9 x trn_score_pose around it + trn_peak_fit (eq. 6)
 *   localize            trn_localize_dem: one whole localization
 *
 * Instructions: with --instructions the command runs itself once more under
 * `valgrind --tool=callgrind --collect-atstart=no`, with the environment
 * variable TRN_PROFILE_CALLGRIND_OUT naming the output file. That child runs
 * each stage once between CALLGRIND_ZERO_STATS / CALLGRIND_TOGGLE_COLLECT
 * and dumps the counts with CALLGRIND_DUMP_STATS_AT(stage); the parent reads
 * the `totals:` line of each dump. Only the stage's own call is collected, so
 * the count is exact and repeatable. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "commands.h"
#include "profile_budget.h"
#include "synth.h"
#include "trn/trn.h"

#if defined(TRN_HAVE_CALLGRIND)
#include <valgrind/callgrind.h>
#endif

#define PI 3.14159265358979323846
#define MAX_RUNS 1000
#define CG_ENV "TRN_PROFILE_CALLGRIND_OUT"
#define EXIT_OVER_BUDGET CLI_NO_RESULT

typedef enum {
  ST_HIGHPASS_OCC = 0,
  ST_CHAMFER,
  ST_MAP_BUILD,
  ST_PROB_MAP,
  ST_SELECT,
  ST_LOCAL_OCC,
  ST_SEARCH,
  ST_PEAK_FIT,
  ST_LOCALIZE,
  ST_COUNT
} stage_t;

static const char *const k_names[ST_COUNT] = {"highpass_occupancy", "chamfer", "map_build",
                                              "prob_map", "select", "local_occupancy",
                                              "search", "peak_fit", "localize"};
static const char *const k_what[ST_COUNT] = {
    "trn_highpass + trn_occupancy, global DEM",
    "trn_chamfer3d, global occupancy",
    "trn_map_build (filter, occupancy, chamfer, K, pyramid)",
    "trn_prob_global_map (eq. 8)",
    "trn_select, every candidate target",
    "trn_highpass + trn_occupancy_points + order, local DEM",
    "trn_search_bb, best pose in the window",
    "9 x trn_score_pose + trn_peak_fit (eq. 6)",
    "trn_localize_dem, one localization"};

/* The public functions each stage calls (for the stack figures of
 * tools/profile/add_stack.py). */
static const char *const k_funcs[ST_COUNT] = {
    "trn_highpass,trn_occupancy", "trn_chamfer3d", "trn_map_build", "trn_prob_global_map", "trn_select",
    "trn_highpass,trn_occupancy_points,trn_points_order", "trn_search_bb", "trn_score_pose,trn_peak_fit",
    "trn_localize_dem"};

/* Everything the stages work on; heap memory of the tool (the core never allocates). */
typedef struct {
  long n, nl, win_cells;
  double max_range_m;
  long stride;
  uint64_t seed;
  /* terrain */
  float *dem, *loc;
  trn_grid_f32_t g, lg;
  trn_map_cfg_t cfg;
  /* highpass_occupancy + chamfer */
  void *hp_ws;
  size_t hp_ws_bytes;
  float *hp_data;
  trn_grid_f32_t hp;
  uint8_t *occ_data, *dist_data;
  trn_vol_u8_t occ, dist;
  /* map */
  void *mapbuf;
  size_t map_bytes;
  trn_map_t map;
  /* probability map + select */
  trn_kernels_t k;
  trn_xy_t sensor;
  float *pg_data;
  trn_vol_f32_t pg;
  void *pg_ws;
  size_t pg_ws_bytes;
  trn_select_cfg_t scfg;
  trn_rover_t rover;
  trn_candidate_t *cands;
  size_t cand_cap;
  size_t ranked[8];
  void *sel_ws;
  size_t sel_ws_bytes;
  trn_select_result_t sel;
  /* local map, search, peak fit, localize */
  int32_t rx, ry;
  trn_window_t win;
  void *lhp_ws;
  size_t lhp_ws_bytes;
  float *lhp_data;
  trn_grid_f32_t lhp;
  trn_point_t *pts;
  size_t max_pts, n_pts;
  void *bb_ws;
  size_t bb_ws_bytes;
  trn_best_t best;
  trn_search_stats_t bb_stats;
  trn_peak_t peak;
  void *loc_ws;
  size_t loc_ws_bytes;
  trn_loc_result_t res;
  double truth_x, truth_y;
} world_t;

static void *alloc16(size_t n) {
  void *p = NULL;
  if (posix_memalign(&p, 16u, n == 0 ? 16u : n) != 0) {
    return NULL;
  }
  return p;
}

static void world_free(world_t *w) {
  free(w->dem);
  free(w->loc);
  free(w->hp_ws);
  free(w->hp_data);
  free(w->occ_data);
  free(w->dist_data);
  free(w->mapbuf);
  free(w->pg_data);
  free(w->pg_ws);
  free(w->cands);
  free(w->sel_ws);
  free(w->lhp_ws);
  free(w->lhp_data);
  free(w->pts);
  free(w->bb_ws);
  free(w->loc_ws);
}

/* One run of a stage. Returns its status (TRN_OK or the stage's documented
 * success-with-warning status). */
static trn_status_t run_stage(world_t *w, stage_t s) {
  trn_status_t st = TRN_OK;
  switch (s) {
    case ST_HIGHPASS_OCC: {
      uint32_t n_occ = 0;
      st = trn_highpass(&w->g, &w->cfg.terrain, &w->hp, w->hp_ws, w->hp_ws_bytes);
      if (st == TRN_OK) {
        st = trn_occupancy(&w->hp, &w->cfg.terrain, &w->occ, &n_occ);
      }
      break;
    }
    case ST_CHAMFER:
      st = trn_chamfer3d(&w->occ, &w->dist, w->cfg.cap);
      break;
    case ST_MAP_BUILD:
      st = trn_map_build(&w->map, &w->cfg, &w->g, w->mapbuf, w->map_bytes);
      break;
    case ST_PROB_MAP: {
      trn_sigma_model_t gm;
      trn_sigma_global_default(&gm);
      st = trn_prob_global_map(&w->k, &gm, &w->sensor, 1u, &w->map, &w->pg, w->pg_ws, w->pg_ws_bytes);
      break;
    }
    case ST_SELECT:
      st = trn_select(&w->map, &w->k, &w->pg, &w->scfg, &w->rover, w->cands, w->cand_cap, w->ranked,
                      sizeof w->ranked / sizeof w->ranked[0], &w->sel, w->sel_ws, w->sel_ws_bytes);
      if (st == TRN_E_NOTARGET) {
        st = TRN_OK; /* a valid outcome: the work was done */
      }
      break;
    case ST_LOCAL_OCC:
      st = trn_highpass(&w->lg, &w->cfg.terrain, &w->lhp, w->lhp_ws, w->lhp_ws_bytes);
      if (st == TRN_OK) {
        st = trn_occupancy_points(&w->lhp, &w->cfg.terrain, w->rx, w->ry, w->pts, w->max_pts, &w->n_pts);
      }
      if (st == TRN_OK) {
        st = trn_points_order(w->pts, w->n_pts, w->cfg.terrain.nz);
      }
      break;
    case ST_SEARCH:
      st = trn_search_bb(&w->map.pyr, &w->map.lnp, w->pts, w->n_pts, &w->win, NULL, w->bb_ws,
                         w->bb_ws_bytes, &w->best, &w->bb_stats);
      break;
    case ST_PEAK_FIT: {
      double ll[9];
      int i;
      for (i = 0; i < 9 && st == TRN_OK; ++i) {
        int64_t sc = 0;
        st = trn_score_pose(&w->map.dist, &w->map.lnp, w->pts, w->n_pts, w->best.x + i % 3 - 1,
                            w->best.y + i / 3 - 1, &sc);
        ll[i] = (double)sc / (double)TRN_LNP_SCALE;
      }
      if (st == TRN_OK) {
        st = trn_peak_fit(ll, &w->peak);
        if (st == TRN_E_ILLCOND) {
          st = TRN_OK; /* the fit ran; a flat peak is an answer */
        }
      }
      break;
    }
    case ST_LOCALIZE:
      st = trn_localize_dem(&w->map, &w->lg, w->rx, w->ry, w->max_pts, &w->win, w->loc_ws, w->loc_ws_bytes,
                            &w->res);
      if (st == TRN_E_ILLCOND) {
        st = TRN_OK;
      }
      break;
    default:
      st = TRN_E_ARG;
      break;
  }
  return st;
}

/* Memory each stage needs beyond its inputs: the library's sizing function
 * (scratch) plus the outputs the stage writes (from the dimensions). */
static void stage_bytes(const world_t *w, stage_t s, size_t *scratch, size_t *total) {
  size_t cells = (size_t)w->n * (size_t)w->n;
  size_t vox = cells * (size_t)w->cfg.terrain.nz;
  size_t lcells = (size_t)w->nl * (size_t)w->nl;
  size_t sc = 0, out = 0;
  switch (s) {
    case ST_HIGHPASS_OCC:
      sc = w->hp_ws_bytes;
      out = cells * sizeof(float) + vox;
      break;
    case ST_CHAMFER:
      out = vox;
      break;
    case ST_MAP_BUILD:
      sc = w->map_bytes; /* trn_map_bytes: the map and its build scratch */
      out = 0;
      break;
    case ST_PROB_MAP:
      sc = w->pg_ws_bytes;
      out = vox * sizeof(float);
      break;
    case ST_SELECT:
      sc = w->sel_ws_bytes;
      out = w->cand_cap * sizeof(trn_candidate_t) + sizeof w->ranked;
      break;
    case ST_LOCAL_OCC:
      sc = w->lhp_ws_bytes;
      out = lcells * sizeof(float) + w->max_pts * sizeof(trn_point_t);
      break;
    case ST_SEARCH:
      sc = w->bb_ws_bytes;
      break;
    case ST_PEAK_FIT:
      break;
    case ST_LOCALIZE:
      sc = w->loc_ws_bytes;
      break;
    default:
      break;
  }
  *scratch = sc;
  *total = sc + out;
}

static int world_init(world_t *w, char *err, size_t err_len) {
  const double cell = 0.1;
  synth_terrain_t t;
  synth_rock_t *rocks;
  size_t nrocks, cells;
  trn_status_t st;
  double cx, cy;
  int32_t px, py, half;

  trn_map_cfg_default(&w->cfg);
  cells = (size_t)w->n * (size_t)w->n;
  /* The main job's rock field (tools/trn_demo.c): 15 % cover, radii 5-30 cm. */
  nrocks = (size_t)((double)w->n * (double)w->n * cell * cell * 0.15 / (PI * 0.15 * 0.15));
  rocks = malloc(sizeof *rocks * (nrocks + 1));
  w->dem = malloc(sizeof(float) * cells);
  w->loc = malloc(sizeof(float) * (size_t)w->nl * (size_t)w->nl);
  if (rocks == NULL || w->dem == NULL || w->loc == NULL) {
    free(rocks);
    snprintf(err, err_len, "out of memory for the terrain");
    return 1;
  }
  synth_make(&t, rocks, nrocks, (double)w->n * cell, 0.05, 0.3, 0.5, 0.2, w->seed);
  synth_render(&t, w->dem, (int)w->n, (int)w->n, 0.0, 0.0, cell);
  /* The rover a fraction of a cell off the map centre; its local map in its own grid. */
  half = (int32_t)(w->nl / 2);
  w->truth_x = (double)(w->n / 2) + 0.3;
  w->truth_y = (double)(w->n / 2) - 0.2;
  synth_render(&t, w->loc, (int)w->nl, (int)w->nl, (w->truth_x - half) * cell, (w->truth_y - half) * cell,
               cell);
  free(rocks);
  if (trn_grid_f32_init(&w->g, w->dem, cells, (int32_t)w->n, (int32_t)w->n) != TRN_OK ||
      trn_grid_f32_init(&w->lg, w->loc, (size_t)w->nl * (size_t)w->nl, (int32_t)w->nl, (int32_t)w->nl) !=
          TRN_OK) {
    snprintf(err, err_len, "grid sizes rejected by the core");
    return 1;
  }
  w->rx = half;
  w->ry = half;
  px = (int32_t)lround(w->truth_x) + 3;
  py = (int32_t)lround(w->truth_y) - 2;
  w->win.x0 = px - (int32_t)w->win_cells;
  w->win.y0 = py - (int32_t)w->win_cells;
  w->win.x1 = px + (int32_t)w->win_cells;
  w->win.y1 = py + (int32_t)w->win_cells;

  /* highpass_occupancy + chamfer buffers */
  w->hp_ws_bytes = trn_highpass_workspace_bytes((int32_t)w->n, (int32_t)w->n);
  w->hp_ws = alloc16(w->hp_ws_bytes);
  w->hp_data = alloc16(cells * sizeof(float));
  w->occ_data = alloc16(cells * (size_t)w->cfg.terrain.nz);
  w->dist_data = alloc16(cells * (size_t)w->cfg.terrain.nz);
  if (w->hp_ws == NULL || w->hp_data == NULL || w->occ_data == NULL || w->dist_data == NULL) {
    snprintf(err, err_len, "out of memory for the occupancy");
    return 1;
  }
  if (trn_grid_f32_init(&w->hp, w->hp_data, cells, (int32_t)w->n, (int32_t)w->n) != TRN_OK ||
      trn_vol_u8_init(&w->occ, w->occ_data, cells * (size_t)w->cfg.terrain.nz, (int32_t)w->n, (int32_t)w->n,
                      w->cfg.terrain.nz) != TRN_OK ||
      trn_vol_u8_init(&w->dist, w->dist_data, cells * (size_t)w->cfg.terrain.nz, (int32_t)w->n,
                      (int32_t)w->n, w->cfg.terrain.nz) != TRN_OK) {
    snprintf(err, err_len, "volume sizes rejected by the core");
    return 1;
  }
  /* the map */
  w->map_bytes = trn_map_bytes(&w->cfg, (int32_t)w->n, (int32_t)w->n);
  w->mapbuf = alloc16(w->map_bytes);
  if (w->map_bytes == 0 || w->mapbuf == NULL) {
    snprintf(err, err_len, "cannot allocate %zu bytes for the map", w->map_bytes);
    return 1;
  }
  if ((st = trn_map_build(&w->map, &w->cfg, &w->g, w->mapbuf, w->map_bytes)) != TRN_OK) {
    snprintf(err, err_len, "map build failed: %s", trn_strerror(st));
    return 1;
  }
  /* probability map */
  if ((st = trn_kernels_build(&w->k, TRN_KERNEL_SIGMA0_DEFAULT_CELLS)) != TRN_OK) {
    snprintf(err, err_len, "kernels: %s", trn_strerror(st));
    return 1;
  }
  cx = (double)w->n / 2.0;
  cy = (double)w->n / 2.0;
  w->sensor.x_cells = (float)cx;
  w->sensor.y_cells = (float)cy;
  w->pg_data = alloc16(cells * (size_t)w->cfg.terrain.nz * sizeof(float));
  w->pg_ws_bytes = trn_prob_global_workspace_bytes((int32_t)w->n, (int32_t)w->n);
  w->pg_ws = alloc16(w->pg_ws_bytes);
  if (w->pg_data == NULL || w->pg_ws == NULL) {
    snprintf(err, err_len, "out of memory for the probability map");
    return 1;
  }
  w->pg.data = w->pg_data;
  w->pg.nx = (int32_t)w->n;
  w->pg.ny = (int32_t)w->n;
  w->pg.nz = w->cfg.terrain.nz;
  /* select */
  trn_select_cfg_default(&w->scfg);
  w->scfg.max_range_m = (float)w->max_range_m;
  if (w->scfg.min_range_m > w->scfg.max_range_m) {
    w->scfg.min_range_m = w->scfg.max_range_m;
  }
  w->scfg.stride_cells = (int32_t)w->stride;
  if ((st = trn_select_cfg_check(&w->scfg, w->cfg.terrain.cell_m)) != TRN_OK) {
    snprintf(err, err_len, "selection configuration rejected: %s", trn_strerror(st));
    return 1;
  }
  w->rover.pos.x_cells = (float)w->truth_x;
  w->rover.pos.y_cells = (float)w->truth_y;
  w->rover.heading_rad = 0.0f;
  w->cand_cap = trn_select_max_candidates(&w->scfg, w->cfg.terrain.cell_m);
  w->cands = malloc((w->cand_cap == 0 ? 1 : w->cand_cap) * sizeof(trn_candidate_t));
  w->sel_ws_bytes = trn_select_workspace_bytes(&w->scfg, &w->map, &w->k);
  w->sel_ws = alloc16(w->sel_ws_bytes);
  if (w->cands == NULL || w->sel_ws == NULL || w->sel_ws_bytes == 0) {
    snprintf(err, err_len, "cannot allocate the selection workspace (%zu bytes)", w->sel_ws_bytes);
    return 1;
  }
  /* local map, search, localize */
  w->lhp_ws_bytes = trn_highpass_workspace_bytes((int32_t)w->nl, (int32_t)w->nl);
  w->lhp_ws = alloc16(w->lhp_ws_bytes);
  w->lhp_data = alloc16((size_t)w->nl * (size_t)w->nl * sizeof(float));
  w->max_pts = (size_t)w->nl * (size_t)w->nl * (size_t)w->cfg.terrain.nz;
  w->pts = malloc(w->max_pts * sizeof(trn_point_t));
  if (w->lhp_ws == NULL || w->lhp_data == NULL || w->pts == NULL ||
      trn_grid_f32_init(&w->lhp, w->lhp_data, (size_t)w->nl * (size_t)w->nl, (int32_t)w->nl,
                        (int32_t)w->nl) != TRN_OK) {
    snprintf(err, err_len, "out of memory for the local map");
    return 1;
  }
  w->bb_ws_bytes = trn_search_bb_workspace_bytes(&w->map.pyr, &w->win);
  w->bb_ws = alloc16(w->bb_ws_bytes);
  w->loc_ws_bytes = trn_localize_dem_workspace_bytes(&w->map, (int32_t)w->nl, (int32_t)w->nl, w->max_pts,
                                                     &w->win);
  w->loc_ws = alloc16(w->loc_ws_bytes);
  if (w->bb_ws_bytes == 0 || w->bb_ws == NULL || w->loc_ws_bytes == 0 || w->loc_ws == NULL) {
    snprintf(err, err_len, "cannot size or allocate the search workspace");
    return 1;
  }
  return 0;
}

/* Stages need their predecessors' outputs: run each once in order. */
static int world_prime(world_t *w, char *err, size_t err_len) {
  int s;
  for (s = 0; s < ST_COUNT; ++s) {
    trn_status_t st = run_stage(w, (stage_t)s);
    if (st != TRN_OK) {
      snprintf(err, err_len, "stage %s failed: %s", k_names[s], trn_strerror(st));
      return 1;
    }
  }
  return 0;
}

static double now_ms(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return x < y ? -1 : x > y ? 1 : 0;
}

/* ---- callgrind --------------------------------------------------------- */

/* The child under callgrind: count each stage once, dump, exit. */
static int callgrind_child(world_t *w) {
#if defined(TRN_HAVE_CALLGRIND)
  int s;
  if (!RUNNING_ON_VALGRIND) {
    fprintf(stderr, "trn profile: %s is set but the program is not running under valgrind\n", CG_ENV);
    return 1;
  }
  for (s = 0; s < ST_COUNT; ++s) {
    trn_status_t st;
    CALLGRIND_ZERO_STATS;
    CALLGRIND_TOGGLE_COLLECT;
    st = run_stage(w, (stage_t)s);
    CALLGRIND_TOGGLE_COLLECT;
    CALLGRIND_DUMP_STATS_AT(k_names[s]);
    if (st != TRN_OK) {
      fprintf(stderr, "trn profile: stage %s failed under callgrind: %s\n", k_names[s], trn_strerror(st));
      return 1;
    }
  }
  return 0;
#else
  (void)w;
  fprintf(stderr, "trn profile: built without valgrind/callgrind.h\n");
  return 1;
#endif
}

/* Read one callgrind dump: the stage named in its trigger and its totals. */
static int read_dump(const char *path, char *name, size_t name_len, unsigned long long *ir) {
  FILE *fp = fopen(path, "r");
  char line[4096];
  int have_name = 0, have_total = 0;
  const char *tag = "desc: Trigger: Client Request: ";
  if (fp == NULL) {
    return 0;
  }
  while (fgets(line, sizeof line, fp) != NULL) {
    size_t len = strlen(line);
    while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r')) {
      line[--len] = '\0';
    }
    if (strncmp(line, tag, strlen(tag)) == 0) {
      size_t k = strlen(line + strlen(tag));
      if (k < name_len) {
        memcpy(name, line + strlen(tag), k + 1);
        have_name = 1;
      }
    } else if (strncmp(line, "totals: ", 8) == 0 || (!have_total && strncmp(line, "summary: ", 9) == 0)) {
      const char *v = line + (line[0] == 't' ? 8 : 9);
      char *end;
      errno = 0;
      *ir = strtoull(v, &end, 10);
      have_total = errno == 0 && end != v;
    }
  }
  fclose(fp);
  return have_name && have_total;
}

/* Run ourselves under callgrind and fill ir[] per stage. */
static int count_instructions(int argc, char **argv, unsigned long long *ir, int *have, char *err,
                              size_t err_len) {
  char dir[] = "/tmp/trn-profile-cg.XXXXXX";
  char out[600], logp[600], exe[4096];
  char **av;
  pid_t pid;
  int wst = 0, i, found = 0;
  ssize_t n;

  for (i = 0; i < ST_COUNT; ++i) {
    have[i] = 0;
    ir[i] = 0;
  }
  n = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (n <= 0) {
    snprintf(err, err_len, "--instructions: cannot find our own executable (/proc/self/exe)");
    return 1;
  }
  exe[n] = '\0';
  if (mkdtemp(dir) == NULL) {
    snprintf(err, err_len, "--instructions: cannot make a temporary directory: %s", strerror(errno));
    return 1;
  }
  snprintf(out, sizeof out, "%s/cg.out", dir);
  snprintf(logp, sizeof logp, "%s/valgrind.log", dir);
  av = calloc((size_t)argc + 8u, sizeof *av);
  if (av == NULL) {
    snprintf(err, err_len, "out of memory");
    return 1;
  }
  {
    static char a0[] = "valgrind", a1[] = "--tool=callgrind", a2[] = "--collect-atstart=no", a3[] = "-q";
    static char a4[700];
    snprintf(a4, sizeof a4, "--callgrind-out-file=%s", out);
    av[0] = a0;
    av[1] = a1;
    av[2] = a2;
    av[3] = a3;
    av[4] = a4;
    av[5] = exe;
    for (i = 0; i < argc; ++i) {
      av[6 + i] = argv[i]; /* argv[0] is "profile" */
    }
    av[6 + argc] = NULL;
  }
  fflush(stdout);
  fflush(stderr);
  pid = fork();
  if (pid == 0) {
    int fd = open("/dev/null", O_WRONLY);
    int lf = open(logp, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (fd >= 0) {
      dup2(fd, 1);
    }
    if (lf >= 0) {
      dup2(lf, 2);
    }
    setenv(CG_ENV, out, 1);
    execvp("valgrind", av);
    _exit(127);
  }
  free(av);
  if (pid < 0 || waitpid(pid, &wst, 0) != pid) {
    snprintf(err, err_len, "--instructions: cannot start valgrind");
    return 1;
  }
  if (!WIFEXITED(wst) || WEXITSTATUS(wst) != 0) {
    char first[300] = "";
    FILE *lf = fopen(logp, "r");
    if (lf != NULL) {
      if (fgets(first, sizeof first, lf) == NULL) {
        first[0] = '\0';
      }
      fclose(lf);
    }
    first[strcspn(first, "\n")] = '\0';
    if (WIFEXITED(wst) && WEXITSTATUS(wst) == 127) {
      snprintf(err, err_len, "--instructions needs valgrind (Debian package valgrind: bash tools/setup.sh profile)");
    } else {
      snprintf(err, err_len, "--instructions: the callgrind run failed (%s)", first[0] ? first : "no message");
    }
    return 1;
  }
  /* Dumps are out.1, out.2, ...; the final one at exit is `out` itself (empty: nothing collected). */
  for (i = 1; i <= ST_COUNT + 4; ++i) {
    char p[700], name[256];
    unsigned long long v = 0;
    int s;
    snprintf(p, sizeof p, "%s.%d", out, i);
    if (read_dump(p, name, sizeof name, &v)) {
      for (s = 0; s < ST_COUNT; ++s) {
        if (strcmp(name, k_names[s]) == 0 && !have[s]) {
          ir[s] = v;
          have[s] = 1;
          ++found;
        }
      }
    }
    unlink(p);
  }
  unlink(out);
  unlink(logp);
  rmdir(dir);
  if (found != ST_COUNT) {
    snprintf(err, err_len, "--instructions: found %d of %d stage dumps in the callgrind output", found,
             (int)ST_COUNT);
    return 1;
  }
  return 0;
}

/* ---- the command --------------------------------------------------------- */

int trn_cmd_profile(int argc, char **argv) {
  long n = 256, nl = 64, win_cells = 25, stride = 2, runs = 7;
  double max_range_m = 10.0;
  uint64_t seed = 1;
  const char *budget_path = NULL;
  int json = 0, check = 0, instructions = 0;
  cli_opt_t opts[] = {
      {"--map-cells", CLI_LONG, &n, 64, 4096, 0, "N", "global map side, cells of 0.1 m (the main job's)", 0},
      {"--local-cells", CLI_LONG, &nl, 16, 512, 0, "N", "local map side, cells", 0},
      {"--window-cells", CLI_LONG, &win_cells, 1, 1024, 0, "R", "pose window +-R cells around the prior", 0},
      {"--max-range-m", CLI_DOUBLE, &max_range_m, 0.5, 400.0, 0, "M", "farthest candidate target, m", 0},
      {"--stride-cells", CLI_LONG, &stride, 1, 64, 0, "S", "candidate lattice step, cells", 0},
      {"--runs", CLI_LONG, &runs, 1, MAX_RUNS, 0, "N", "timed runs per stage after one warm-up", 0},
      {"--seed", CLI_U64, &seed, 0, 0, 0, "S", "terrain seed", 0},
      {"--budget", CLI_STRING, &budget_path, 0, 0, 0, "FILE", "target budget per stage and host-to-target scale (README) (default: none)", 0},
      {"--check", CLI_FLAG, &check, 0, 0, 0, NULL, "exit 3 if a stage's worst target time is over its budget", 0},
      {"--instructions", CLI_FLAG, &instructions, 0, 0, 0, NULL, "also count instructions per stage (valgrind --tool=callgrind)", 0},
      {"--json", CLI_FLAG, &json, 0, 0, 0, NULL, "print one JSON object instead of the table", 0},
  };
  cli_cmd_t cmd = {
      "profile",
      "Time the onboard pipeline's stages on a synthetic terrain; workspace and budget share per stage.",
      "Stages: highpass_occupancy, chamfer, map_build, prob_map, select, local_occupancy, search,\n"
      "peak_fit, localize (docs/modules/cli.md). Wall time: CLOCK_MONOTONIC, one warm-up, then --runs\n"
      "timed runs; median and max. workspace_bytes: the library's sizing function plus the outputs\n"
      "the stage writes. With --budget, target_ms = host ms x scale and share = worst target ms /\n"
      "budget; a share above 1 is over budget. Exit status: 0, 1 bad input, 2 usage, 3 over budget\n"
      "with --check.",
      opts, sizeof opts / sizeof opts[0]};
  world_t w;
  pb_budget_t budget;
  char err[1024];
  double *t = NULL;
  double med[ST_COUNT], mx[ST_COUNT];
  unsigned long long ir[ST_COUNT];
  int have_ir[ST_COUNT];
  int rc, s, over = 0, child;
  const char *cg_env;

  rc = cli_parse(&cmd, argc, argv);
  if (rc == CLI_HELP) {
    return 0;
  }
  if (rc != CLI_OK) {
    return rc;
  }
  if (check && budget_path == NULL) {
    fprintf(stderr, "trn profile: --check needs --budget FILE (try --help)\n");
    return CLI_USAGE;
  }
  if (nl / 2 + win_cells + 8 > n / 2) {
    return cli_fail(cmd.name, "--map-cells %ld too small for --local-cells %ld and --window-cells %ld "
                              "(need map/2 >= local/2 + window + 8)", n, nl, win_cells);
  }
  cg_env = getenv(CG_ENV);
  child = cg_env != NULL && cg_env[0] != '\0';
  if (budget_path != NULL && !child &&
      pb_load(budget_path, k_names, ST_COUNT, &budget, err, sizeof err) != 0) {
    return cli_fail(cmd.name, "%s", err);
  }
  memset(&w, 0, sizeof w);
  w.n = n;
  w.nl = nl;
  w.win_cells = win_cells;
  w.max_range_m = max_range_m;
  w.stride = stride;
  w.seed = seed;
  if (world_init(&w, err, sizeof err) != 0 || world_prime(&w, err, sizeof err) != 0) {
    world_free(&w);
    return cli_fail(cmd.name, "%s", err);
  }
  if (child) {
    rc = callgrind_child(&w);
    world_free(&w);
    return rc;
  }

  t = malloc(sizeof *t * (size_t)runs);
  if (t == NULL) {
    world_free(&w);
    return cli_fail(cmd.name, "out of memory");
  }
  for (s = 0; s < ST_COUNT; ++s) {
    long r;
    trn_status_t st = run_stage(&w, (stage_t)s); /* warm-up */
    for (r = 0; r < runs && st == TRN_OK; ++r) {
      double t0 = now_ms();
      st = run_stage(&w, (stage_t)s);
      t[r] = now_ms() - t0;
    }
    if (st != TRN_OK) {
      free(t);
      world_free(&w);
      return cli_fail(cmd.name, "stage %s failed: %s", k_names[s], trn_strerror(st));
    }
    qsort(t, (size_t)runs, sizeof *t, cmp_double);
    med[s] = runs % 2 ? t[runs / 2] : 0.5 * (t[runs / 2 - 1] + t[runs / 2]);
    mx[s] = t[runs - 1];
  }
  free(t);
  if (instructions && count_instructions(argc, argv, ir, have_ir, err, sizeof err) != 0) {
    world_free(&w);
    return cli_fail(cmd.name, "%s", err);
  }
  if (!instructions) {
    for (s = 0; s < ST_COUNT; ++s) {
      have_ir[s] = 0;
    }
  }
  for (s = 0; s < ST_COUNT && budget_path != NULL; ++s) {
    if (budget.budget_ms[s] > 0.0 && mx[s] * budget.scale > budget.budget_ms[s]) {
      ++over;
    }
  }

  if (json) {
    json_t j;
    json_begin(&j, stdout);
    json_obj(&j, "config");
    json_int(&j, "map_cells", n);
    json_int(&j, "local_cells", nl);
    json_int(&j, "window_cells", win_cells);
    json_int(&j, "poses", (2 * win_cells + 1) * (2 * win_cells + 1));
    json_num(&j, "max_range_m", max_range_m);
    json_int(&j, "stride_cells", stride);
    json_int(&j, "candidates", (long long)w.sel.n_candidates);
    json_int(&j, "local_points", (long long)w.n_pts);
    json_int(&j, "runs", runs);
    json_int(&j, "seed", (long long)seed);
    json_num(&j, "cell_m", 0.1);
    json_int(&j, "height_bins", w.cfg.terrain.nz);
    json_int(&j, "stack_limit_bytes", TRN_STACK_LIMIT_BYTES);
    json_obj_end(&j);
    if (budget_path != NULL) {
      json_obj(&j, "budget");
      json_str(&j, "file", budget_path);
      json_num(&j, "scale", budget.scale);
      json_int(&j, "over_budget", over);
      json_obj_end(&j);
    }
    json_obj(&j, "stages");
    for (s = 0; s < ST_COUNT; ++s) {
      size_t sc, tot;
      stage_bytes(&w, (stage_t)s, &sc, &tot);
      json_obj(&j, k_names[s]);
      json_str(&j, "what", k_what[s]);
      json_str(&j, "functions", k_funcs[s]);
      json_num(&j, "wall_ms", med[s]);
      json_num(&j, "wall_max_ms", mx[s]);
      json_int(&j, "workspace_bytes", (long long)tot);
      json_int(&j, "scratch_bytes", (long long)sc);
      if (have_ir[s]) {
        json_int(&j, "instructions", (long long)ir[s]);
      }
      if (budget_path != NULL && budget.budget_ms[s] > 0.0) {
        json_num(&j, "budget_ms", budget.budget_ms[s]);
        json_num(&j, "target_ms", med[s] * budget.scale);
        json_num(&j, "target_max_ms", mx[s] * budget.scale);
        json_num(&j, "share", mx[s] * budget.scale / budget.budget_ms[s]);
        json_bool(&j, "over", mx[s] * budget.scale > budget.budget_ms[s]);
      }
      json_obj_end(&j);
    }
    json_obj_end(&j);
    json_end(&j);
  } else {
    printf("profile   map %ld x %ld cells of 0.1 m, %d bins; local %ld x %ld (%zu points); window +-%ld cells "
           "(%ld poses); %zu candidates (range <= %g m, stride %ld); seed %llu; %ld runs\n",
           n, n, (int)w.cfg.terrain.nz, nl, nl, w.n_pts, win_cells, (2 * win_cells + 1) * (2 * win_cells + 1),
           w.sel.n_candidates, max_range_m, stride, (unsigned long long)seed, runs);
    if (budget_path != NULL) {
      printf("budget    %s, scale %g (target ms = host ms x scale; share = worst target / budget)\n",
             budget_path, budget.scale);
    }
    printf("\n%-19s %10s %10s %13s %15s", "stage", "median ms", "max ms", "workspace B", "instructions");
    if (budget_path != NULL) {
      printf(" %11s %11s %7s", "target max", "budget ms", "share");
    }
    printf("\n");
    for (s = 0; s < ST_COUNT; ++s) {
      size_t sc, tot;
      char irs[32] = "-";
      stage_bytes(&w, (stage_t)s, &sc, &tot);
      if (have_ir[s]) {
        snprintf(irs, sizeof irs, "%llu", ir[s]);
      }
      printf("%-19s %10.3f %10.3f %13zu %15s", k_names[s], med[s], mx[s], tot, irs);
      if (budget_path != NULL) {
        if (budget.budget_ms[s] > 0.0) {
          double share = mx[s] * budget.scale / budget.budget_ms[s];
          printf(" %11.1f %11.1f %6.0f%%%s", mx[s] * budget.scale, budget.budget_ms[s], 100.0 * share,
                 share > 1.0 ? "  OVER BUDGET" : "");
        } else {
          printf(" %11.1f %11s %7s", mx[s] * budget.scale, "-", "-");
        }
      }
      printf("\n");
    }
    if (budget_path != NULL) {
      printf("\n%d stage(s) over budget\n", over);
    }
  }
  world_free(&w);
  return check && over > 0 ? EXIT_OVER_BUDGET : 0;
}
