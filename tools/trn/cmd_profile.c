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
 * The default localizer (trn localize's: trn_map_cfg_auto through mapopt,
 * TRN_MATCH_HEIGHTS, the exhaustive search) on the same DEM, local DEM and
 * window, timed by the public functions its localization is made of
 * (src/localize.c, localize_heights) and whole:
 *   height_map_build    mapopt_config (trn_map_cfg_auto) + trn_map_build
 *   height_search       trn_height_search_heading at the one heading 0: every
 *                       pose of the window scored by the pose score
 *                       trn_localize_dem's search runs (src/height_score.c)
 *   height_refine       trn_refine_pose from the search's best pose
 *   height_failure      trn_height_mass (the posterior mass outside the
 *                       exclusion zone) + trn_prob_beyond (the refined
 *                       covariance's tail beyond TRN_FAIL_RADIUS_CELLS)
 *   height_rest         height_localize minus the three parts above: the
 *                       second refinement starts, the noise rescale (the
 *                       refinement again when the residuals at the answer
 *                       reject the noise model), far basins, shoulders, valley and
 *                       the input checks. Not run: time median = whole's
 *                       median - the parts' medians, max = whole's max -
 *                       the parts' medians; instructions = whole's - the
 *                       parts' (exact).
 *   height_localize     trn_localize_dem with that map: one whole localization
 *
 * --dem FILE: a real DEM (any raster GDAL reads in a projected CRS, e.g. one
 * of bench_real's, build/real/ID.tif) instead of the synthetic terrain: the
 * --map-cells square at its centre is the global map, the local DEM is that
 * map sampled bilinearly at the same sub-cell rover position, and everything
 * runs in the DEM's cell: the voxel stages with the paper's configuration
 * scaled to the cell (mapopt "paper"), the selection with the synthetic
 * case's geometry in cells (lengths x cell / 0.1 m).
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
#include "dem_io.h"
#include "mapopt.h"
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
    ST_H_MAP,
    ST_H_SEARCH,
    ST_H_REFINE,
    ST_H_FAILURE,
    ST_H_REST,
    ST_H_LOCALIZE,
    ST_COUNT
} stage_t;

/* The stages height_rest is the whole minus. */
#define IS_H_PART(s) ((s) == ST_H_SEARCH || (s) == ST_H_REFINE || (s) == ST_H_FAILURE)

static const char *const k_names[ST_COUNT] = {
    "highpass_occupancy", "chamfer",       "map_build",      "prob_map",    "select",
    "local_occupancy",    "search",        "peak_fit",       "localize",    "height_map_build",
    "height_search",      "height_refine", "height_failure", "height_rest", "height_localize"};
static const char *const k_what[ST_COUNT] = {
    "trn_highpass + trn_occupancy, global DEM",
    "trn_chamfer3d, global occupancy",
    "trn_map_build (filter, occupancy, chamfer, K, pyramid)",
    "trn_prob_global_map (eq. 8)",
    "trn_select, every candidate target",
    "trn_highpass + trn_occupancy_points + order, local DEM",
    "trn_search_bb, best pose in the window",
    "9 x trn_score_pose + trn_peak_fit (eq. 6)",
    "trn_localize_dem, one localization",
    "trn_map_cfg_auto + trn_map_build, height matcher's map",
    "trn_height_search_heading at heading 0, every pose",
    "trn_refine_pose from the best pose",
    "trn_height_mass + trn_prob_beyond",
    "height_localize minus the three stages above",
    "trn_localize_dem, heights (the default localizer)"};

/* The public functions each stage calls (for the stack figures of
 * tools/profile/add_stack.py). */
static const char *const k_funcs[ST_COUNT] = {"trn_highpass,trn_occupancy",
                                              "trn_chamfer3d",
                                              "trn_map_build",
                                              "trn_prob_global_map",
                                              "trn_select",
                                              "trn_highpass,trn_occupancy_points,trn_points_order",
                                              "trn_search_bb",
                                              "trn_score_pose,trn_peak_fit",
                                              "trn_localize_dem",
                                              "trn_map_cfg_auto,trn_map_build",
                                              "trn_height_search_heading",
                                              "trn_refine_pose",
                                              "trn_height_mass,trn_prob_beyond",
                                              "trn_localize_dem",
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
    /* --dem: the file (NULL: the synthetic terrain) and its cell */
    const char *dem_path;
    double cell_m;
    /* the height matcher (the default localizer) */
    trn_map_cfg_t hcfg;
    void *hmapbuf;
    size_t hmap_bytes, hauto_bytes;
    trn_map_t hmap;
    trn_refine_cfg_t hrc;
    double *ll_grid;
    void *hs_ws; /* the search's workspace (trn_height_heading_workspace_bytes) */
    size_t hs_ws_bytes;
    trn_height_best3_t hbest3;
    trn_height_best_t hbest, hsecond;
    trn_refine_t href;
    double hfail;
    void *hloc_ws;
    size_t hloc_ws_bytes;
    trn_loc_result_t hres;
    trn_status_t hres_st;
} world_t;

static void *alloc16(size_t n)
{
    void *p = NULL;
    if (posix_memalign(&p, 16u, n == 0 ? 16u : n) != 0) {
        return NULL;
    }
    return p;
}

static void world_free(world_t *w)
{
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
    free(w->hmapbuf);
    free(w->ll_grid);
    free(w->hloc_ws);
    free(w->hs_ws);
}

/* The search trn_localize_dem runs: its pose score (src/height_score.c) at
 * the one heading 0 (trn_height_search, without a workspace, is the slower
 * reference). */
static trn_status_t height_search(world_t *w)
{
    const trn_heading_cfg_t one = {0.0, 0.0, 0.0};
    const trn_status_t st = trn_height_search_heading(
        &w->hmap.heights, &w->lg, w->rx, w->ry, &w->win, &one, &w->hrc, w->hcfg.inlier_prob,
        w->hs_ws, w->hs_ws_bytes, w->ll_grid, &w->hbest3);
    w->hbest.x = w->hbest3.x;
    w->hbest.y = w->hbest3.y;
    w->hbest.ll = w->hbest3.ll;
    return st;
}

/* The height matcher's map: the configuration trn localize chooses by
 * default (mapopt: trn_map_cfg_auto with the tools' noise model), built. */
static trn_status_t height_map(world_t *w)
{
    mapopt_t mo;
    char why[256];
    mapopt_init(&mo);
    if (mapopt_config(&mo, w->dem, (int)w->n, (int)w->n, w->cell_m, &w->hcfg, NULL, why,
                      sizeof why) != 0) {
        return TRN_E_ARG;
    }
    return trn_map_build(&w->hmap, &w->hcfg, &w->g, w->hmapbuf, w->hmap_bytes);
}

/* The failure probability's public parts: the posterior mass outside the
 * exclusion zone around the best pose (the stored ln L grid, divided by the
 * refinement's ll_inflation) and the refined covariance's tail beyond
 * TRN_FAIL_RADIUS_CELLS; the larger. */
static trn_status_t height_failure(world_t *w)
{
    trn_exclusion_t ex;
    trn_status_t st;
    double infl = w->href.ll_inflation >= 1.0 ? w->href.ll_inflation : 1.0, tail = 0.0;
    ex.cx = w->hbest.x;
    ex.cy = w->hbest.y;
    ex.radius = w->hcfg.min_exclusion_cells;
    st = trn_height_mass(w->ll_grid, &w->win, &ex, infl, &w->hsecond);
    if (st == TRN_E_NODATA) {
        w->hfail = 0.0; /* no pose outside the zone: no competitor */
        st = TRN_OK;
    } else if (st == TRN_OK) {
        w->hfail = exp(w->hsecond.lse_out - w->hsecond.lse_all);
    }
    if (st == TRN_OK && isfinite(w->href.cov_cells[0]) && isfinite(w->href.cov_cells[1])) {
        st = trn_prob_beyond(w->href.cov_cells, TRN_FAIL_RADIUS_CELLS, &tail);
        w->hfail = fmax(w->hfail, tail);
    }
    return st;
}

/* One run of a stage. Returns its status (TRN_OK or the stage's documented
 * success-with-warning status). */
static trn_status_t run_stage(world_t *w, stage_t s)
{
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
    case ST_CHAMFER: st = trn_chamfer3d(&w->occ, &w->dist, w->cfg.cap); break;
    case ST_MAP_BUILD: st = trn_map_build(&w->map, &w->cfg, &w->g, w->mapbuf, w->map_bytes); break;
    case ST_PROB_MAP: {
        trn_sigma_model_t gm;
        trn_sigma_global_default(&gm);
        if (w->dem_path != NULL) { /* the synthetic case's model in cells */
            gm.sigma_min_m = (float)((double)gm.sigma_min_m * w->cell_m / 0.1);
            gm.k_per_m = (float)((double)gm.k_per_m * 0.1 / w->cell_m);
        }
        st = trn_prob_global_map(&w->k, &gm, &w->sensor, 1u, &w->map, &w->pg, w->pg_ws,
                                 w->pg_ws_bytes);
        break;
    }
    case ST_SELECT:
        st = trn_select(&w->map, &w->k, &w->pg, &w->scfg, &w->rover, w->cands, w->cand_cap,
                        w->ranked, sizeof w->ranked / sizeof w->ranked[0], &w->sel, w->sel_ws,
                        w->sel_ws_bytes);
        if (st == TRN_E_NOTARGET) {
            st = TRN_OK; /* a valid outcome: the work was done */
        }
        break;
    case ST_LOCAL_OCC:
        st = trn_highpass(&w->lg, &w->cfg.terrain, &w->lhp, w->lhp_ws, w->lhp_ws_bytes);
        if (st == TRN_OK) {
            st = trn_occupancy_points(&w->lhp, &w->cfg.terrain, w->rx, w->ry, w->pts, w->max_pts,
                                      &w->n_pts);
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
        st = trn_localize_dem(&w->map, &w->lg, w->rx, w->ry, w->max_pts, &w->win, w->loc_ws,
                              w->loc_ws_bytes, &w->res);
        if (st == TRN_E_ILLCOND || st == TRN_E_AMBIGUOUS) {
            st = TRN_OK; /* an answer, not a fix: the work was done */
        }
        break;
    case ST_H_MAP: st = height_map(w); break;
    case ST_H_SEARCH: st = height_search(w); break;
    case ST_H_REFINE:
        st = trn_refine_pose(&w->hmap.heights, &w->lg, w->rx, w->ry, w->hbest.x, w->hbest.y,
                             &w->hrc, &w->href);
        if (st == TRN_E_ILLCOND) {
            st = TRN_OK; /* the refinement ran; no finite covariance is an answer */
        }
        break;
    case ST_H_FAILURE: st = height_failure(w); break;
    case ST_H_REST: break; /* derived: height_localize minus the parts */
    case ST_H_LOCALIZE:
        st = trn_localize_dem(&w->hmap, &w->lg, w->rx, w->ry, w->max_pts, &w->win, w->hloc_ws,
                              w->hloc_ws_bytes, &w->hres);
        w->hres_st = st;
        if (st == TRN_E_ILLCOND || st == TRN_E_AMBIGUOUS) {
            st = TRN_OK; /* an answer, not a fix: the work was done */
        }
        break;
    default: st = TRN_E_ARG; break;
    }
    return st;
}

/* Memory each stage needs beyond its inputs: the library's sizing function
 * (scratch) plus the outputs the stage writes (from the dimensions). */
static void stage_bytes(const world_t *w, stage_t s, size_t *scratch, size_t *total)
{
    size_t cells = (size_t)w->n * (size_t)w->n;
    size_t vox = cells * (size_t)w->cfg.terrain.nz;
    size_t lcells = (size_t)w->nl * (size_t)w->nl;
    size_t sc = 0, out = 0;
    switch (s) {
    case ST_HIGHPASS_OCC:
        sc = w->hp_ws_bytes;
        out = cells * sizeof(float) + vox;
        break;
    case ST_CHAMFER: out = vox; break;
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
    case ST_SEARCH: sc = w->bb_ws_bytes; break;
    case ST_PEAK_FIT: break;
    case ST_LOCALIZE: sc = w->loc_ws_bytes; break;
    case ST_H_MAP: sc = w->hmap_bytes + w->hauto_bytes; break;
    case ST_H_SEARCH:
        sc = w->hs_ws_bytes;
        out = (size_t)(w->win.x1 - w->win.x0 + 1) * (size_t)(w->win.y1 - w->win.y0 + 1) *
              sizeof(double); /* the ln L grid */
        break;
    case ST_H_LOCALIZE: sc = w->hloc_ws_bytes; break;
    default: break;
    }
    *scratch = sc;
    *total = sc + out;
}

/* Bilinear height of the map at fractional cell (x, y) (cell centres at
 * integers); NaN off the map or where a corner is NaN. */
static float bilinear(const float *z, long n, double x, double y)
{
    long x0 = (long)floor(x), y0 = (long)floor(y);
    double fx = x - (double)x0, fy = y - (double)y0;
    if (x0 < 0 || y0 < 0 || x0 + 1 >= n || y0 + 1 >= n) {
        return NAN;
    }
    return (float)((1.0 - fy) * ((1.0 - fx) * z[y0 * n + x0] + fx * z[y0 * n + x0 + 1]) +
                   fy * ((1.0 - fx) * z[(y0 + 1) * n + x0] + fx * z[(y0 + 1) * n + x0 + 1]));
}

/* --dem: the --map-cells square at the DEM's centre into w->dem, its cell
 * into w->cell_m, the local DEM sampled from it at (truth_x, truth_y). */
static int world_dem(world_t *w, char *err, size_t err_len)
{
    dem_t d;
    long r, c, half = w->nl / 2, r0, c0;
    char why[512];
    memset(&d, 0, sizeof d);
    if (dem_read(w->dem_path, 1, TRN_MAX_DIM, &d, why, sizeof why) != 0) {
        snprintf(err, err_len, "--dem %s: %s", w->dem_path, why);
        return 1;
    }
    if ((long)d.width < w->n || (long)d.height < w->n) {
        snprintf(err, err_len, "--dem %s is %d x %d cells, smaller than --map-cells %ld",
                 w->dem_path, d.width, d.height, w->n);
        dem_free(&d);
        return 1;
    }
    w->cell_m = d.cell_m;
    r0 = ((long)d.height - w->n) / 2;
    c0 = ((long)d.width - w->n) / 2;
    w->dem = malloc(sizeof(float) * (size_t)w->n * (size_t)w->n);
    w->loc = malloc(sizeof(float) * (size_t)w->nl * (size_t)w->nl);
    if (w->dem == NULL || w->loc == NULL) {
        dem_free(&d);
        snprintf(err, err_len, "out of memory for the terrain");
        return 1;
    }
    for (r = 0; r < w->n; ++r) {
        memcpy(w->dem + r * w->n, d.data + (r0 + r) * (long)d.width + c0,
               sizeof(float) * (size_t)w->n);
    }
    dem_free(&d);
    for (r = 0; r < w->nl; ++r) {
        for (c = 0; c < w->nl; ++c) {
            w->loc[r * w->nl + c] = bilinear(w->dem, w->n, w->truth_x + (double)(c - half),
                                             w->truth_y + (double)(r - half));
        }
    }
    return 0;
}

/* The terrain, the rover's local map in its own grid, and the pose window. */
static int world_terrain(world_t *w, char *err, size_t err_len)
{
    const double cell = 0.1;
    synth_terrain_t t;
    synth_rock_t *rocks;
    size_t nrocks, cells = (size_t)w->n * (size_t)w->n;
    int32_t px, py, half, mid;

    /* The rover a fraction of a cell off the map centre; its local map in its own grid. */
    half = (int32_t)(w->nl / 2);
    mid = (int32_t)(w->n / 2); /* the integer centre cell */
    w->truth_x = (double)mid + 0.3;
    w->truth_y = (double)mid - 0.2;
    w->cell_m = cell;
    if (w->dem_path != NULL) {
        if (world_dem(w, err, err_len) != 0) {
            return 1;
        }
    } else {
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
        synth_render(&t, w->loc, (int)w->nl, (int)w->nl, (w->truth_x - half) * cell,
                     (w->truth_y - half) * cell, cell);
        free(rocks);
    }
    if (trn_grid_f32_init(&w->g, w->dem, cells, (int32_t)w->n, (int32_t)w->n) != TRN_OK ||
        trn_grid_f32_init(&w->lg, w->loc, (size_t)w->nl * (size_t)w->nl, (int32_t)w->nl,
                          (int32_t)w->nl) != TRN_OK) {
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
    return 0;
}

/* highpass_occupancy + chamfer buffers, and the map. */
static int world_map(world_t *w, char *err, size_t err_len)
{
    size_t cells = (size_t)w->n * (size_t)w->n;
    trn_status_t st;

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
        trn_vol_u8_init(&w->occ, w->occ_data, cells * (size_t)w->cfg.terrain.nz, (int32_t)w->n,
                        (int32_t)w->n, w->cfg.terrain.nz) != TRN_OK ||
        trn_vol_u8_init(&w->dist, w->dist_data, cells * (size_t)w->cfg.terrain.nz, (int32_t)w->n,
                        (int32_t)w->n, w->cfg.terrain.nz) != TRN_OK) {
        snprintf(err, err_len, "volume sizes rejected by the core");
        return 1;
    }
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
    /* the height matcher's map (the default localizer's configuration) */
    {
        mapopt_t mo;
        char why[256];
        mapopt_init(&mo);
        if (mapopt_config(&mo, w->dem, (int)w->n, (int)w->n, w->cell_m, &w->hcfg, NULL, why,
                          sizeof why) != 0) {
            snprintf(err, err_len, "height matcher's map configuration: %s", why);
            return 1;
        }
    }
    w->hauto_bytes = trn_map_cfg_auto_workspace_bytes((int32_t)w->n, (int32_t)w->n);
    w->hmap_bytes = trn_map_bytes(&w->hcfg, (int32_t)w->n, (int32_t)w->n);
    w->hmapbuf = alloc16(w->hmap_bytes);
    if (w->hmap_bytes == 0 || w->hmapbuf == NULL) {
        snprintf(err, err_len, "cannot allocate %zu bytes for the height matcher's map",
                 w->hmap_bytes);
        return 1;
    }
    if ((st = height_map(w)) != TRN_OK) {
        snprintf(err, err_len, "height matcher's map build failed: %s", trn_strerror(st));
        return 1;
    }
    w->hrc.cell_m = w->hcfg.terrain.cell_m;
    w->hrc.noise_m = w->hcfg.noise_m;
    w->hrc.noise_k_per_m = w->hcfg.noise_k_per_m;
    w->hrc.inlier_prob = w->hcfg.inlier_prob;
    w->hrc.fit_noise = w->hcfg.noise_auto;
    w->hrc.centroid_x = NULL; /* the cells' centres */
    w->hrc.centroid_y = NULL;
    w->hrc.point_count = NULL; /* one measurement a cell */
    return 0;
}

/* The kernels, the probability map's buffers and the selection's. */
static int world_select(world_t *w, char *err, size_t err_len)
{
    size_t cells = (size_t)w->n * (size_t)w->n;
    trn_status_t st;

    if ((st = trn_kernels_build(&w->k, TRN_KERNEL_SIGMA0_DEFAULT_CELLS)) != TRN_OK) {
        snprintf(err, err_len, "kernels: %s", trn_strerror(st));
        return 1;
    }
    w->sensor.x_cells = (float)((double)w->n / 2.0);
    w->sensor.y_cells = (float)((double)w->n / 2.0);
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
    trn_select_cfg_default(&w->scfg);
    w->scfg.max_range_m = (float)w->max_range_m;
    if (w->dem_path != NULL) {
        /* the synthetic case's geometry in cells: every length x cell / 0.1 m */
        const double k = w->cell_m / 0.1;
        w->scfg.max_range_m = (float)(w->max_range_m * k);
        w->scfg.min_range_m = (float)((double)w->scfg.min_range_m * k);
        w->scfg.footprint_radius_m = (float)((double)w->scfg.footprint_radius_m * k);
        w->scfg.patch_m = (float)((double)w->scfg.patch_m * k);
        w->scfg.min_separation_m = (float)((double)w->scfg.min_separation_m * k);
        w->scfg.local_sigma.sigma_min_m = (float)((double)w->scfg.local_sigma.sigma_min_m * k);
        w->scfg.local_sigma.k_per_m = (float)((double)w->scfg.local_sigma.k_per_m / k);
    }
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
        snprintf(err, err_len, "cannot allocate the selection workspace (%zu bytes)",
                 w->sel_ws_bytes);
        return 1;
    }
    return 0;
}

/* The local map's buffers, the search's and the localization's workspaces. */
static int world_local(world_t *w, char *err, size_t err_len)
{
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
    w->loc_ws_bytes = trn_localize_dem_workspace_bytes(&w->map, (int32_t)w->nl, (int32_t)w->nl,
                                                       w->max_pts, &w->win);
    w->loc_ws = alloc16(w->loc_ws_bytes);
    if (w->bb_ws_bytes == 0 || w->bb_ws == NULL || w->loc_ws_bytes == 0 || w->loc_ws == NULL) {
        snprintf(err, err_len, "cannot size or allocate the search workspace");
        return 1;
    }
    w->ll_grid = malloc((size_t)(w->win.x1 - w->win.x0 + 1) * (size_t)(w->win.y1 - w->win.y0 + 1) *
                        sizeof(double));
    w->hloc_ws_bytes = trn_localize_dem_workspace_bytes(&w->hmap, (int32_t)w->nl, (int32_t)w->nl,
                                                        w->max_pts, &w->win);
    w->hloc_ws = alloc16(w->hloc_ws_bytes);
    w->hs_ws_bytes = trn_height_heading_workspace_bytes((int32_t)w->nl, (int32_t)w->nl);
    w->hs_ws = alloc16(w->hs_ws_bytes);
    if (w->ll_grid == NULL || w->hloc_ws_bytes == 0 || w->hloc_ws == NULL || w->hs_ws_bytes == 0 ||
        w->hs_ws == NULL) {
        snprintf(err, err_len, "cannot size or allocate the height matcher's workspace");
        return 1;
    }
    return 0;
}

static int world_init(world_t *w, char *err, size_t err_len)
{
    trn_map_cfg_default(&w->cfg);
    if (world_terrain(w, err, err_len) != 0) {
        return 1;
    }
    if (w->dem_path != NULL) {
        /* the paper's configuration scaled to the DEM's cell, as trn localize
         * --map-config paper */
        mapopt_t mo;
        char why[256];
        mapopt_init(&mo);
        mo.config = "paper";
        if (mapopt_config(&mo, w->dem, (int)w->n, (int)w->n, w->cell_m, &w->cfg, NULL, why,
                          sizeof why) != 0) {
            snprintf(err, err_len, "voxel map configuration: %s", why);
            return 1;
        }
    }
    if (world_map(w, err, err_len) != 0 || world_select(w, err, err_len) != 0 ||
        world_local(w, err, err_len) != 0) {
        return 1;
    }
    return 0;
}

/* Stages need their predecessors' outputs: run each once in order. */
static int world_prime(world_t *w, char *err, size_t err_len)
{
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

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y ? 1 : 0;
}

/* ---- callgrind --------------------------------------------------------- */

/* The child under callgrind: count each stage once, dump, exit. */
static int callgrind_child(world_t *w)
{
#if defined(TRN_HAVE_CALLGRIND)
    int s;
    if (!RUNNING_ON_VALGRIND) {
        fprintf(stderr, "trn profile: %s is set but the program is not running under valgrind\n",
                CG_ENV);
        return 1;
    }
    for (s = 0; s < ST_COUNT; ++s) {
        trn_status_t st;
        if (s == ST_H_REST) {
            continue; /* derived from the others' counts */
        }
        CALLGRIND_ZERO_STATS;
        CALLGRIND_TOGGLE_COLLECT;
        st = run_stage(w, (stage_t)s);
        CALLGRIND_TOGGLE_COLLECT;
        CALLGRIND_DUMP_STATS_AT(k_names[s]);
        if (st != TRN_OK) {
            fprintf(stderr, "trn profile: stage %s failed under callgrind: %s\n", k_names[s],
                    trn_strerror(st));
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
static int read_dump(const char *path, char *name, size_t name_len, unsigned long long *ir)
{
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
        } else if (strncmp(line, "totals: ", 8) == 0 ||
                   (!have_total && strncmp(line, "summary: ", 9) == 0)) {
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

/* Run `valgrind --tool=callgrind ... exe argv` with stdout to /dev/null,
 * stderr to logp and the dumps to out; wait for it. 0, or 1 with the reason. */
static int spawn_callgrind(const char *exe, int argc, char **argv, const char *out,
                           const char *logp, char *err, size_t err_len)
{
    char a0[] = "valgrind", a1[] = "--tool=callgrind", a2[] = "--collect-atstart=no", a3[] = "-q",
         a4[700];
    char exe_copy[4096];
    char **av;
    pid_t pid;
    int wst = 0, i;

    av = calloc((size_t)argc + 8u, sizeof *av);
    if (av == NULL) {
        snprintf(err, err_len, "out of memory");
        return 1;
    }
    snprintf(a4, sizeof a4, "--callgrind-out-file=%s", out);
    snprintf(exe_copy, sizeof exe_copy, "%s", exe);
    av[0] = a0;
    av[1] = a1;
    av[2] = a2;
    av[3] = a3;
    av[4] = a4;
    av[5] = exe_copy;
    for (i = 0; i < argc; ++i) {
        av[6 + i] = argv[i]; /* argv[0] is "profile" */
    }
    av[6 + argc] = NULL;
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
            snprintf(err, err_len,
                     "--instructions needs valgrind (Debian package valgrind: bash tools/setup.sh "
                     "profile)");
        } else {
            snprintf(err, err_len, "--instructions: the callgrind run failed (%s)",
                     first[0] ? first : "no message");
        }
        return 1;
    }
    return 0;
}

/* The dumps out.1, out.2, ... (the final one at exit is `out` itself, empty:
 * nothing collected) into ir[] and have[]; every file removed. Returns the
 * number of stages found. */
static int collect_dumps(const char *out, long long *ir, int *have)
{
    int i, found = 0;
    for (i = 1; i <= ST_COUNT + 4; ++i) {
        char p[700], name[256];
        unsigned long long v = 0;
        int s;
        snprintf(p, sizeof p, "%s.%d", out, i);
        if (read_dump(p, name, sizeof name, &v)) {
            for (s = 0; s < ST_COUNT; ++s) {
                if (strcmp(name, k_names[s]) == 0 && !have[s]) {
                    ir[s] = (long long)v;
                    have[s] = 1;
                    ++found;
                }
            }
        }
        unlink(p);
    }
    unlink(out);
    return found;
}

/* Run ourselves under callgrind and fill ir[] per stage. */
static int count_instructions(int argc, char **argv, long long *ir, int *have, char *err,
                              size_t err_len)
{
    char dir[] = "/tmp/trn-profile-cg.XXXXXX";
    char out[600], logp[600], exe[4096];
    int i, found;
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
        snprintf(err, err_len, "--instructions: cannot make a temporary directory: %s",
                 strerror(errno));
        return 1;
    }
    snprintf(out, sizeof out, "%s/cg.out", dir);
    snprintf(logp, sizeof logp, "%s/valgrind.log", dir);
    if (spawn_callgrind(exe, argc, argv, out, logp, err, err_len) != 0) {
        return 1;
    }
    found = collect_dumps(out, ir, have);
    unlink(logp);
    rmdir(dir);
    if (found != ST_COUNT - 1) {
        snprintf(err, err_len, "--instructions: found %d of %d stage dumps in the callgrind output",
                 found, (int)ST_COUNT - 1);
        return 1;
    }
    /* height_rest: the whole localization's count minus its parts' (exact) */
    ir[ST_H_REST] = ir[ST_H_LOCALIZE];
    for (i = 0; i < ST_COUNT; ++i) {
        if (IS_H_PART(i)) {
            ir[ST_H_REST] -= ir[i];
        }
    }
    have[ST_H_REST] = 1;
    return 0;
}

/* ---- the command --------------------------------------------------------- */

/* ---- parse, run, report ----------------------------------------------------- */
typedef struct {
    long n, nl, win_cells, stride, runs; /* map and local sides, window, lattice step, timed runs */
    double max_range_m;
    uint64_t seed;
    const char *budget_path; /* budget file, or NULL */
    const char *dem_path;    /* --dem: a real DEM instead of the synthetic terrain, or NULL */
    int json, check, instructions;
    int argc; /* --instructions: the command line re-run under callgrind */
    char **argv;
} profile_params_t;

/* The timings of a run (world_t above holds the stages' inputs and outputs). */
typedef struct {
    world_t w;
    pb_budget_t budget;
    double med[ST_COUNT], mx[ST_COUNT];
    long long ir[ST_COUNT]; /* height_rest's may be negative (see the file comment) */
    int have_ir[ST_COUNT];
    int over; /* stages over budget */
} profile_result_t;

static void profile_params_default(profile_params_t *p)
{
    memset(p, 0, sizeof *p);
    p->n = 256;
    p->nl = 64;
    p->win_cells = 25;
    p->stride = 2;
    p->runs = 7;
    p->max_range_m = 10.0;
    p->seed = 1;
}

/* argv -> p. Returns CLI_OK, CLI_HELP (usage printed) or the usage / bad input status (message printed). */
static int profile_parse(int argc, char **argv, profile_params_t *p)
{
    cli_opt_t opts[] = {
        {"--map-cells", CLI_LONG, &p->n, 64, 4096, 0, "N",
         "global map side, cells of 0.1 m (the main job's)", 0},
        {"--local-cells", CLI_LONG, &p->nl, 16, 512, 0, "N", "local map side, cells", 0},
        {"--window-cells", CLI_LONG, &p->win_cells, 1, 1024, 0, "R",
         "pose window +-R cells around the prior", 0},
        {"--max-range-m", CLI_DOUBLE, &p->max_range_m, 0.5, 400.0, 0, "M",
         "farthest candidate target, m", 0},
        {"--stride-cells", CLI_LONG, &p->stride, 1, 64, 0, "S", "candidate lattice step, cells", 0},
        {"--runs", CLI_LONG, &p->runs, 1, MAX_RUNS, 0, "N",
         "timed runs per stage after one warm-up", 0},
        {"--seed", CLI_U64, &p->seed, 0, 0, 0, "S", "terrain seed", 0},
        {"--dem", CLI_STRING, &p->dem_path, 0, 0, 0, "FILE",
         "a real DEM (projected, e.g. bench_real's build/real/ID.tif) instead of the synthetic "
         "terrain: its central --map-cells square, in its own cell (default: none)",
         0},
        {"--budget", CLI_STRING, &p->budget_path, 0, 0, 0, "FILE",
         "target budget per stage and host-to-target scale (docs/benchmarks.md) (default: none)",
         0},
        {"--check", CLI_FLAG, &p->check, 0, 0, 0, NULL,
         "exit 3 if a stage's worst target time is over its budget", 0},
        {"--instructions", CLI_FLAG, &p->instructions, 0, 0, 0, NULL,
         "also count instructions per stage (valgrind --tool=callgrind)", 0},
        {"--json", CLI_FLAG, &p->json, 0, 0, 0, NULL, "print one JSON object instead of the table",
         0},
    };
    cli_cmd_t cmd = {"profile",
                     "Time the onboard pipeline's stages on a synthetic terrain; workspace and "
                     "budget share per stage.",
                     "Stages: highpass_occupancy, chamfer, map_build, prob_map, select, "
                     "local_occupancy, search,\n"
                     "peak_fit, localize (the voxel matcher); height_map_build, height_search, "
                     "height_refine,\n"
                     "height_failure, height_rest, height_localize (the default localizer, "
                     "TRN_MATCH_HEIGHTS;\n"
                     "height_rest = height_localize minus the three before it) "
                     "(docs/modules/cli.md).\n"
                     "Wall time: CLOCK_MONOTONIC, one warm-up, then --runs\n"
                     "timed runs; median and max. workspace_bytes: the library's sizing function "
                     "plus the outputs\n"
                     "the stage writes. With --budget, target_ms = host ms x scale and share = "
                     "worst target ms /\n"
                     "budget; a share above 1 is over budget. Exit status: 0, 1 bad input, 2 "
                     "usage, 3 over budget\n"
                     "with --check.",
                     opts, sizeof opts / sizeof opts[0]};
    int rc = cli_parse(&cmd, argc, argv);
    if (rc != CLI_OK) {
        return rc;
    }
    if (p->check && p->budget_path == NULL) {
        fprintf(stderr, "trn profile: --check needs --budget FILE (try --help)\n");
        return CLI_USAGE;
    }
    p->argc = argc;
    p->argv = argv;
    return CLI_OK;
}

/* The sizes no stage can run with. */
static int profile_check(const profile_params_t *p, char *err, size_t err_len)
{
    if (p->nl / 2 + p->win_cells + 8 > p->n / 2) {
        snprintf(err, err_len,
                 "--map-cells %ld too small for --local-cells %ld and --window-cells %ld "
                 "(need map/2 >= local/2 + window + 8)",
                 p->n, p->nl, p->win_cells);
        return CLI_BAD_INPUT;
    }
    return CLI_OK;
}

/* The stages' inputs and buffers, each stage run once (free w with world_free, also on failure). */
static int profile_world(const profile_params_t *p, world_t *w, char *err, size_t err_len)
{
    memset(w, 0, sizeof *w);
    w->n = p->n;
    w->nl = p->nl;
    w->win_cells = p->win_cells;
    w->max_range_m = p->max_range_m;
    w->stride = p->stride;
    w->seed = p->seed;
    w->dem_path = p->dem_path;
    if (world_init(w, err, err_len) != 0 || world_prime(w, err, err_len) != 0) {
        return CLI_BAD_INPUT;
    }
    return CLI_OK;
}

/* Each stage: one warm-up, then p->runs timed runs; median and max into r. */
static int profile_time(const profile_params_t *p, profile_result_t *r, char *err, size_t err_len)
{
    double *t = malloc(sizeof *t * (size_t)p->runs);
    long runs = p->runs;
    int s;
    if (t == NULL) {
        snprintf(err, err_len, "out of memory");
        return CLI_BAD_INPUT;
    }
    for (s = 0; s < ST_COUNT; ++s) {
        long k;
        trn_status_t st;
        if (s == ST_H_REST) {
            continue; /* derived below */
        }
        st = run_stage(&r->w, (stage_t)s); /* warm-up */
        for (k = 0; k < runs && st == TRN_OK; ++k) {
            double t0 = now_ms();
            st = run_stage(&r->w, (stage_t)s);
            t[k] = now_ms() - t0;
        }
        if (st != TRN_OK) {
            free(t);
            snprintf(err, err_len, "stage %s failed: %s", k_names[s], trn_strerror(st));
            return CLI_BAD_INPUT;
        }
        qsort(t, (size_t)runs, sizeof *t, cmp_double);
        r->med[s] = runs % 2 ? t[runs / 2] : 0.5 * (t[runs / 2 - 1] + t[runs / 2]);
        r->mx[s] = t[runs - 1];
    }
    free(t);
    /* height_rest: the whole localization minus the parts' medians */
    r->med[ST_H_REST] = r->med[ST_H_LOCALIZE];
    r->mx[ST_H_REST] = r->mx[ST_H_LOCALIZE];
    for (s = 0; s < ST_COUNT; ++s) {
        if (IS_H_PART(s)) {
            r->med[ST_H_REST] -= r->med[s];
            r->mx[ST_H_REST] -= r->med[s];
        }
    }
    return CLI_OK;
}

/* Times, instruction counts (--instructions) and budget shares (--budget) of every stage. */
static int profile_run(const profile_params_t *p, profile_result_t *r, char *err, size_t err_len)
{
    int s, rc;

    memset(r, 0, sizeof *r);
    if ((rc = profile_check(p, err, err_len)) != CLI_OK) {
        return rc;
    }
    if (p->budget_path != NULL &&
        pb_load(p->budget_path, k_names, ST_COUNT, &r->budget, err, err_len) != 0) {
        return CLI_BAD_INPUT;
    }
    if ((rc = profile_world(p, &r->w, err, err_len)) != CLI_OK ||
        (rc = profile_time(p, r, err, err_len)) != CLI_OK) {
        return rc;
    }
    if (p->instructions &&
        count_instructions(p->argc, p->argv, r->ir, r->have_ir, err, err_len) != 0) {
        return CLI_BAD_INPUT;
    }
    for (s = 0; s < ST_COUNT && p->budget_path != NULL; ++s) {
        if (r->budget.budget_ms[s] > 0.0 && r->mx[s] * r->budget.scale > r->budget.budget_ms[s]) {
            ++r->over;
        }
    }
    return CLI_OK;
}

/* The child under callgrind (TRN_PROFILE_CALLGRIND_OUT set): the world, then each stage counted once. */
static int profile_child(const profile_params_t *p)
{
    world_t w;
    char err[1024];
    int rc = profile_check(p, err, sizeof err);
    if (rc != CLI_OK) {
        return cli_fail("profile", "%s", err);
    }
    if (profile_world(p, &w, err, sizeof err) != CLI_OK) {
        world_free(&w);
        return cli_fail("profile", "%s", err);
    }
    rc = callgrind_child(&w);
    world_free(&w);
    return rc;
}

static void profile_json_stage(json_t *j, const profile_params_t *p, const profile_result_t *r,
                               int s)
{
    const pb_budget_t *b = &r->budget;
    size_t sc, tot;
    stage_bytes(&r->w, (stage_t)s, &sc, &tot);
    json_obj(j, k_names[s]);
    json_str(j, "what", k_what[s]);
    json_str(j, "functions", k_funcs[s]);
    json_num(j, "wall_ms", r->med[s]);
    json_num(j, "wall_max_ms", r->mx[s]);
    json_int(j, "workspace_bytes", (long long)tot);
    json_int(j, "scratch_bytes", (long long)sc);
    if (r->have_ir[s]) {
        json_int(j, "instructions", (long long)r->ir[s]);
    }
    if (p->budget_path != NULL && b->budget_ms[s] > 0.0) {
        json_num(j, "budget_ms", b->budget_ms[s]);
        json_num(j, "target_ms", r->med[s] * b->scale);
        json_num(j, "target_max_ms", r->mx[s] * b->scale);
        json_num(j, "share", r->mx[s] * b->scale / b->budget_ms[s]);
        json_bool(j, "over", r->mx[s] * b->scale > b->budget_ms[s]);
    }
    json_obj_end(j);
}

static void profile_report_json(const profile_params_t *p, const profile_result_t *r)
{
    json_t j;
    int s;
    json_begin(&j, stdout);
    json_obj(&j, "config");
    json_int(&j, "map_cells", p->n);
    json_int(&j, "local_cells", p->nl);
    json_int(&j, "window_cells", p->win_cells);
    json_int(&j, "poses", (2 * p->win_cells + 1) * (2 * p->win_cells + 1));
    json_num(&j, "max_range_m", p->max_range_m);
    json_int(&j, "stride_cells", p->stride);
    json_int(&j, "candidates", (long long)r->w.sel.n_candidates);
    json_int(&j, "local_points", (long long)r->w.n_pts);
    json_int(&j, "runs", p->runs);
    json_int(&j, "seed", (long long)p->seed);
    json_num(&j, "cell_m", r->w.cell_m);
    if (p->dem_path != NULL) {
        json_str(&j, "dem", p->dem_path);
    }
    json_int(&j, "height_bins", r->w.cfg.terrain.nz);
    json_int(&j, "height_matcher_bins", r->w.hcfg.terrain.nz);
    json_int(&j, "height_matcher_poses_scored", (long long)r->w.hres.stats.poses_scored);
    json_str(&j, "height_matcher_status", trn_strerror(r->w.hres_st));
    json_num(&j, "height_matcher_error_cells",
             hypot(r->w.hres.x - r->w.truth_x, r->w.hres.y - r->w.truth_y));
    json_num(&j, "height_matcher_failure_probability", r->w.hres.failure_probability);
    json_num(&j, "height_matcher_noise_scale", r->w.hres.noise_scale);
    json_num(&j, "height_failure_stage_probability", r->w.hfail);
    json_int(&j, "stack_limit_bytes", TRN_STACK_LIMIT_BYTES);
    json_obj_end(&j);
    if (p->budget_path != NULL) {
        json_obj(&j, "budget");
        json_str(&j, "file", p->budget_path);
        json_num(&j, "scale", r->budget.scale);
        json_int(&j, "over_budget", r->over);
        json_obj_end(&j);
    }
    json_obj(&j, "stages");
    for (s = 0; s < ST_COUNT; ++s) {
        profile_json_stage(&j, p, r, s);
    }
    json_obj_end(&j);
    json_end(&j);
}

static void profile_report_text(const profile_params_t *p, const profile_result_t *r)
{
    const pb_budget_t *b = &r->budget;
    int s;
    printf("profile   map %ld x %ld cells of %g m, %d bins; local %ld x %ld (%zu points); window "
           "+-%ld cells "
           "(%ld poses); %zu candidates (range <= %g m, stride %ld); %s%s%s%llu; %ld runs\n",
           p->n, p->n, r->w.cell_m, (int)r->w.cfg.terrain.nz, p->nl, p->nl, r->w.n_pts,
           p->win_cells, (2 * p->win_cells + 1) * (2 * p->win_cells + 1), r->w.sel.n_candidates,
           p->max_range_m * r->w.cell_m / 0.1, p->stride, p->dem_path != NULL ? "dem " : "",
           p->dem_path != NULL ? p->dem_path : "", p->dem_path != NULL ? ", seed " : "seed ",
           (unsigned long long)p->seed, p->runs);
    printf("heights   the default localizer (trn_map_cfg_auto, %d bins): %s, error %.2f cells, "
           "failure probability %.3g, noise scale %.3g (not 1: refined twice)\n",
           (int)r->w.hcfg.terrain.nz, trn_strerror(r->w.hres_st),
           hypot(r->w.hres.x - r->w.truth_x, r->w.hres.y - r->w.truth_y),
           r->w.hres.failure_probability, r->w.hres.noise_scale);
    if (p->budget_path != NULL) {
        printf(
            "budget    %s, scale %g (target ms = host ms x scale; share = worst target / budget)\n",
            p->budget_path, b->scale);
    }
    printf("\n%-19s %10s %10s %13s %15s", "stage", "median ms", "max ms", "workspace B",
           "instructions");
    if (p->budget_path != NULL) {
        printf(" %11s %11s %7s", "target max", "budget ms", "share");
    }
    printf("\n");
    for (s = 0; s < ST_COUNT; ++s) {
        size_t sc, tot;
        char irs[32] = "-";
        stage_bytes(&r->w, (stage_t)s, &sc, &tot);
        if (r->have_ir[s]) {
            snprintf(irs, sizeof irs, "%lld", r->ir[s]);
        }
        printf("%-19s %10.3f %10.3f %13zu %15s", k_names[s], r->med[s], r->mx[s], tot, irs);
        if (p->budget_path != NULL) {
            if (b->budget_ms[s] > 0.0) {
                double share = r->mx[s] * b->scale / b->budget_ms[s];
                printf(" %11.1f %11.1f %6.0f%%%s", r->mx[s] * b->scale, b->budget_ms[s],
                       100.0 * share, share > 1.0 ? "  OVER BUDGET" : "");
            } else {
                printf(" %11.1f %11s %7s", r->mx[s] * b->scale, "-", "-");
            }
        }
        printf("\n");
    }
    if (p->budget_path != NULL) {
        printf("\n%d stage(s) over budget\n", r->over);
    }
}

int trn_cmd_profile(int argc, char **argv)
{
    profile_params_t p;
    profile_result_t *r;
    char err[1024];
    const char *cg_env = getenv(CG_ENV);
    int rc;

    profile_params_default(&p);
    rc = profile_parse(argc, argv, &p);
    if (rc != CLI_OK) {
        return rc == CLI_HELP ? 0 : rc;
    }
    if (cg_env != NULL && cg_env[0] != '\0') {
        return profile_child(&p);
    }
    r = malloc(sizeof *r);
    if (r == NULL) {
        return cli_fail("profile", "out of memory");
    }
    rc = profile_run(&p, r, err, sizeof err);
    if (rc != CLI_OK) {
        cli_fail("profile", "%s", err);
    } else if (p.json) {
        profile_report_json(&p, r);
    } else {
        profile_report_text(&p, r);
    }
    world_free(&r->w);
    if (rc == CLI_OK && p.check && r->over > 0) {
        rc = EXIT_OVER_BUDGET;
    }
    free(r);
    return rc;
}
