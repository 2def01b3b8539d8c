/* SPDX-License-Identifier: Apache-2.0 */
/* height_heading.c - the height matcher and its refinement over (x, y,
 * heading) (see trn/height_heading.h). */
#include "trn/height_heading.h"

#include <math.h>
#include <stdlib.h>

#include "height_score.h"
#include "localize_int.h"
#include "refine_int.h"
#include "ws.h"

static int rcfg_ok(const trn_refine_cfg_t *cfg)
{
    return cfg->cell_m > 0.0f && cfg->cell_m <= 1000.0f && cfg->noise_m > 0.0f &&
           cfg->noise_m <= 1000.0f && cfg->noise_k_per_m >= 0.0f && cfg->noise_k_per_m <= 1000.0f;
}

static int rover_ok(const trn_grid_f32_t *l, int32_t rx, int32_t ry)
{
    return rx >= -TRN_MAX_DIM && ry >= -TRN_MAX_DIM && rx <= l->width - 1 + TRN_MAX_DIM &&
           ry <= l->height - 1 + TRN_MAX_DIM;
}

trn_status_t trn_height_heading_steps(const trn_grid_f32_t *local, int32_t rover_x, int32_t rover_y,
                                      const trn_heading_cfg_t *cfg, double *step_rad,
                                      int32_t *half_steps)
{
    trn_status_t st;
    trn_point_t far;
    int64_t r2 = -1;
    int32_t x, y;
    if (local == NULL || cfg == NULL || step_rad == NULL || half_steps == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_grid_f32_check(local)) != TRN_OK) {
        return st;
    }
    if (!rover_ok(local, rover_x, rover_y)) {
        return TRN_E_ARG;
    }
    far.x = 0;
    far.y = 0;
    far.z = 0;
    for (y = 0; y < local->height; ++y) {
        for (x = 0; x < local->width; ++x) {
            const int64_t ox = (int64_t)x - rover_x, oy = (int64_t)y - rover_y;
            if (isfinite(TRN_GRID_AT(local, x, y)) && ox * ox + oy * oy > r2) {
                r2 = ox * ox + oy * oy;
                far.x = (int16_t)ox;
                far.y = (int16_t)oy;
            }
        }
    }
    /* the offsets fit int16_t: |.| <= TRN_MAX_DIM - 1 + TRN_MAX_DIM; with no
     * seen cell, n = 0 gives trn_heading_steps' TRN_E_NODATA after its
     * argument checks */
    return trn_heading_steps(&far, r2 < 0 ? 0u : 1u, cfg, step_rad, half_steps);
}

size_t trn_height_heading_workspace_bytes(int32_t width, int32_t height)
{
    return trn_hs_bytes(width, height);
}

/* Score every pose of the window at heading step k (grid: its slice, may be
 * NULL), keeping a better best (strictly higher ln L). */
static void search_heading(trn_hs_t *s, const trn_window_t *win, int32_t k, double *grid,
                           int *found, trn_height_best3_t *best)
{
    int32_t x, y;
    for (y = win->y0; y <= win->y1; ++y) {
        for (x = win->x0; x <= win->x1; ++x) {
            double dz, m, ll = trn_hs_ll(s, x, y, &dz, &m);
            if (grid != NULL) {
                grid[(size_t)(y - win->y0) * (size_t)(win->x1 - win->x0 + 1) +
                     (size_t)(x - win->x0)] = ll;
            }
            best->poses += 1u;
            if (!*found || ll > best->ll) {
                best->x = x;
                best->y = y;
                best->k = k;
                best->ll = ll;
                best->dz_m = dz;
                best->model_m = m;
                *found = 1;
            }
        }
    }
}

trn_status_t trn_height_search_heading(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                                       int32_t rover_x, int32_t rover_y, const trn_window_t *win,
                                       const trn_heading_cfg_t *hcfg, const trn_refine_cfg_t *rcfg,
                                       float inlier_prob, void *ws, size_t ws_bytes,
                                       double *ll_grid, trn_height_best3_t *best)
{
    trn_status_t st;
    trn_hs_t sc;
    double step;
    int32_t kk, i;
    size_t poses;
    int found = 0;

    if (global == NULL || local == NULL || win == NULL || hcfg == NULL || rcfg == NULL ||
        ws == NULL || best == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_grid_f32_check(global)) != TRN_OK) {
        return st;
    }
    if (!rcfg_ok(rcfg) || !(inlier_prob > 0.0f && inlier_prob < 1.0f)) {
        return TRN_E_ARG;
    }
    if ((st = trn_height_heading_steps(local, rover_x, rover_y, hcfg, &step, &kk)) != TRN_OK) {
        return st;
    }
    if (win->x0 > win->x1 || win->y0 > win->y1 || win->x0 < 0 || win->y0 < 0 ||
        win->x1 >= global->width || win->y1 >= global->height) {
        return TRN_E_RANGE;
    }
    if ((st = trn_ws_check(ws, ws_bytes, trn_hs_bytes(local->width, local->height))) != TRN_OK) {
        return st;
    }
    if (trn_hs_init(&sc, ws, global, local, rover_x, rover_y, rcfg, (double)inlier_prob) < 8u) {
        return TRN_E_NODATA;
    }
    poses = (size_t)(win->x1 - win->x0 + 1) * (size_t)(win->y1 - win->y0 + 1);
    best->poses = 0u;
    best->step_rad = step;
    best->half_steps = kk;
    for (i = 0; i < 2 * kk + 1; ++i) {
        const int32_t k = trn_heading_step_of_(i);
        double c, sn;
        trn_heading_trig_(hcfg->center_rad + (double)k * step, &c, &sn);
        trn_hs_turn(&sc, c, sn);
        search_heading(&sc, win, k, ll_grid != NULL ? ll_grid + (size_t)(k + kk) * poses : NULL,
                       &found, best);
    }
    return TRN_OK;
}

/* ln(exp(a) + exp(b)) without overflow (a, b finite). */
static double log_add(double a, double b)
{
    return fmax(a, b) + log1p(exp(fmin(a, b) - fmax(a, b)));
}

/* Layout of trn_localize_dem_heading's workspace for a TRN_MATCH_HEIGHTS
 * map with a heading window: [search best | refinement | a candidate
 * refinement (the second starts) | ln L of every (pose, heading) | the
 * search's workspace]. */
typedef struct {
    size_t best, ref, cand, basins, grid, search, total;
} hh_layout_t;

static void hh_layout(const trn_grid_f32_t *local, const trn_window_t *win, int32_t kk,
                      hh_layout_t *lay)
{
    trn_ws_t w;
    size_t poses = (size_t)(win->x1 - win->x0 + 1) * (size_t)(win->y1 - win->y0 + 1);
    trn_ws_begin(&w, NULL);
    lay->best = trn_ws_offset(&w, sizeof(trn_height_best3_t));
    lay->ref = trn_ws_offset(&w, sizeof(trn_refine3_t));
    lay->cand = trn_ws_offset(&w, sizeof(trn_refine3_t));
    lay->basins = trn_ws_offset(&w, trn_loc_basins_bytes_()); /* far basins */
    lay->grid = trn_ws_offset(&w, (size_t)(2 * kk + 1) * poses * sizeof(double));
    lay->search = trn_ws_offset(&w,
                                trn_height_heading_workspace_bytes(local->width, local->height));
    lay->total = w.total;
}

/* The window is non-empty and inside the map. */
static int window_in(const trn_map_t *map, const trn_window_t *win)
{
    return win->x0 <= win->x1 && win->y0 <= win->y1 && win->x0 >= 0 && win->y0 >= 0 &&
           win->x1 < map->heights.width && win->y1 < map->heights.height;
}

/* W = 0 at centre 0: trn_localize_dem itself (the heading known). */
static int is_2d(const trn_heading_cfg_t *cfg)
{
    return cfg->window_rad == 0.0 && cfg->center_rad == 0.0;
}

size_t trn_localize_heights3_bytes_(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                    int32_t rover_x, int32_t rover_y, const trn_window_t *win,
                                    const trn_heading_cfg_t *cfg, size_t dem)
{
    hh_layout_t lay;
    double step;
    int32_t kk;
    if (map->heights.data == NULL || !window_in(map, win) ||
        trn_height_heading_steps(local_dem, rover_x, rover_y, cfg, &step, &kk) != TRN_OK) {
        return 0u;
    }
    if (is_2d(cfg)) {
        return dem;
    }
    hh_layout(local_dem, win, kk, &lay);
    return lay.total;
}

/* The search's answer into out, before the refinement. */
static void search_result(const trn_height_best3_t *b, const trn_window_t *win,
                          const trn_heading_cfg_t *cfg, trn_heading_result_t *out)
{
    int32_t p;
    out->loc.ix = b->x;
    out->loc.iy = b->y;
    out->loc.ll_best = b->ll;
    out->loc.n_points = 0u;
    out->loc.stats.poses_scored = b->poses;
    out->loc.stats.blocks_bounded = 0u;
    out->loc.on_window_edge = trn_loc_on_edge_(win, b->x, b->y);
    out->loc.x = (double)b->x;
    out->loc.y = (double)b->y;
    out->loc.sigma_x_m = out->loc.sigma_y_m = (double)INFINITY;
    out->loc.rho = 0.0;
    out->loc.cov_m2[0] = out->loc.cov_m2[1] = (double)INFINITY;
    out->loc.cov_m2[2] = 0.0;
    out->loc.refined = 0;
    out->loc.misfit = 0;
    out->step_rad = b->step_rad;
    out->half_steps = b->half_steps;
    out->best_step = b->k;
    out->heading_rad = cfg->center_rad + (double)b->k * b->step_rad;
    out->sigma_heading_rad = cfg->window_rad > 0.0 ? (double)INFINITY : 0.0;
    for (p = 0; p < 9; ++p) {
        out->cov3[p] = (p % 4 == 0) ? (double)INFINITY : 0.0;
    }
}

/* The refinement's answer into out (metres; refined, misfit). */
static void refine_result(const trn_map_t *map, const trn_refine3_t *r, trn_heading_result_t *out)
{
    const double cell = (double)map->cfg.terrain.cell_m;
    const double lim = map->roughness_m > (double)map->cfg.noise_m ? map->roughness_m
                                                                   : (double)map->cfg.noise_m;
    int32_t p;
    out->loc.refined = 1;
    out->loc.misfit = r->pos.model_m > TRN_MISFIT_ROUGHNESS * lim ? 1 : 0;
    out->loc.x = r->pos.x;
    out->loc.y = r->pos.y;
    for (p = 0; p < 9; ++p) {
        const double sr = (p / 3 < 2) ? cell : 1.0, sc = (p % 3 < 2) ? cell : 1.0;
        out->cov3[p] = r->cov3[p] * sr * sc;
    }
    out->loc.cov_m2[0] = out->cov3[0];
    out->loc.cov_m2[1] = out->cov3[4];
    out->loc.cov_m2[2] = out->cov3[1];
    out->loc.sigma_x_m = sqrt(out->cov3[0]);
    out->loc.sigma_y_m = sqrt(out->cov3[4]);
    out->loc.rho = out->cov3[1] / (out->loc.sigma_x_m * out->loc.sigma_y_m);
    out->heading_rad = r->heading_rad;
    out->sigma_heading_rad = sqrt(out->cov3[8]);
}

/* The failure probability: the posterior mass (uniform prior over the window
 * and the headings) of every (pose, heading) outside the position zone
 * around the answer, ln L divided by the inflation (trn_height_mass per
 * heading, summed); the competitor is the best of them. */
static void masses(const double *grid, const trn_window_t *win, int32_t kk, double infl,
                   trn_loc_result_t *loc)
{
    const size_t poses = (size_t)(win->x1 - win->x0 + 1) * (size_t)(win->y1 - win->y0 + 1);
    trn_exclusion_t ex;
    trn_height_best_t m;
    double lse_all = 0.0, lse_out = 0.0;
    int32_t k;
    int any = 0;
    ex.cx = loc->ix;
    ex.cy = loc->iy;
    ex.radius = loc->exclusion_cells;
    loc->has_second = 0;
    loc->second_x = loc->ix;
    loc->second_y = loc->iy;
    loc->ll_second = loc->ll_best;
    for (k = 0; k < 2 * kk + 1; ++k) {
        /* TRN_OK or TRN_E_NODATA (every pose in the zone): the window, zone
         * and scale were checked; lse_all is filled in either case */
        const int ok = trn_height_mass(grid + (size_t)k * poses, win, &ex, infl, &m) == TRN_OK;
        lse_all = k == 0 ? m.lse_all : log_add(lse_all, m.lse_all);
        if (ok && (!any || m.ll > loc->ll_second)) {
            loc->ll_second = m.ll;
            loc->second_x = m.x;
            loc->second_y = m.y;
        }
        if (ok) {
            lse_out = any ? log_add(lse_out, m.lse_out) : m.lse_out;
            any = 1;
        }
    }
    loc->has_second = any;
    /* no pose outside the zone: no competitor, probability 0 */
    loc->failure_probability = any ? exp(fmin(0.0, lse_out - lse_all)) : 0.0;
}

/* trn_refine_pose_heading from the search's best (pose, heading) and, as
 * trn_localize_dem's refinement, from each of the 8 position neighbours at
 * the best heading step whose ln L is within TRN_REFINE_START_NATS of the
 * best's (inside the window): on terrain a cell or two wide the best integer
 * pose can lie in the basin of a lesser sub-cell peak. Keeps in ref the
 * refinement with the highest refined ln L (ties: the best pose's); 1 if
 * any succeeded. */
static int refine_starts(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx, int32_t ry,
                         const trn_window_t *win, const double *grid, const trn_height_best3_t *b,
                         double heading, double max_turn, const trn_refine_cfg_t *rc,
                         trn_refine3_t *ref, trn_refine3_t *cand, trn_loc_basins_t *far)
{
    /* the window is inside the map, x0 <= x1 and y0 <= y1 (window_in) */
    const size_t wx = (size_t)win->x1 - (size_t)win->x0 + 1u;
    const size_t wy = (size_t)win->y1 - (size_t)win->y0 + 1u;
    const double *slice = grid + (size_t)(b->k + b->half_steps) * wx * wy;
    int found = trn_refine_pose_heading(&map->heights, local, rx, ry, b->x, b->y, heading, max_turn,
                                        rc, ref) == TRN_OK;
    int32_t k;
    for (k = 0; k < 9; ++k) {
        const int32_t sx = b->x + k % 3 - 1, sy = b->y + k / 3 - 1;
        if (k == 4 || sx < win->x0 || sx > win->x1 || sy < win->y0 || sy > win->y1 ||
            !(slice[(size_t)(sy - win->y0) * wx + (size_t)(sx - win->x0)] >
              b->ll - TRN_REFINE_START_NATS)) {
            continue;
        }
        if (trn_refine_pose_heading(&map->heights, local, rx, ry, sx, sy, heading, max_turn, rc,
                                    cand) == TRN_OK &&
            (!found || cand->pos.ll > ref->pos.ll)) {
            *ref = *cand;
            found = 1;
        }
    }
    /* then the far basins (trn_loc_find_basins3_), at their own headings: one
     * replaces the answer if trn_loc_far_wins_ says so (its refined ln L
     * beats it by more than TRN_REFINE_FAR_NATS), the answer taking its slot
     * (far->moved, mx, my, mk: the new start) */
    for (k = 0; found && k < far->n; ++k) {
        int32_t ax, ay;
        far->ok[k] = trn_refine_pose_heading(&map->heights, local, rx, ry, far->x[k], far->y[k],
                                             heading + (double)(far->k[k] - b->half_steps - b->k) *
                                                           b->step_rad,
                                             max_turn, rc, cand) == TRN_OK;
        far->px[k] = cand->pos.x;
        far->py[k] = cand->pos.y;
        far->rll[k] = cand->pos.ll;
        /* the answer's start so far goes into the slot */
        ax = far->moved ? far->mx : b->x;
        ay = far->moved ? far->my : b->y;
        if (far->ok[k] && trn_loc_far_wins_(cand->pos.x, cand->pos.y, cand->pos.ll, ref->pos.x,
                                            ref->pos.y, ref->pos.ll, ref->pos.ll_inflation)) {
            const trn_refine3_t t = *ref;
            const int32_t sx = far->x[k], sy = far->y[k], sk = far->k[k];
            far->x[k] = ax;
            far->y[k] = ay;
            far->k[k] = far->moved ? far->mk : b->k + b->half_steps;
            far->moved = 1;
            far->mx = sx;
            far->my = sy;
            far->mk = sk;
            *ref = *cand;
            far->px[k] = t.pos.x;
            far->py[k] = t.pos.y;
            far->rll[k] = t.pos.ll;
        }
    }
    return found;
}

/* 1 (out->loc.noise_scale set) if the residuals at the answer, the local
 * map turned by its heading, reject the noise model rc
 * (trn_loc_noise_rejected_, trn_localize_dem's rule), else 0. The answer is ref
 * when the refinement succeeded, else the search's best (pose, heading)
 * with its offset and model variance, written into tmp. */
static int rescale_noise3(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx, int32_t ry,
                          const trn_refine_cfg_t *rc, const trn_height_best3_t *b,
                          const trn_refine3_t *ref, trn_refine3_t *tmp, trn_heading_result_t *out)
{
    double heading = out->heading_rad;
    const trn_refine_t *at = &tmp->pos;
    if (ref != NULL) {
        at = &ref->pos;
        heading = ref->heading_rad;
    } else {
        tmp->pos.x = (double)b->x;
        tmp->pos.y = (double)b->y;
        tmp->pos.dz_m = b->dz_m;
        tmp->pos.model_m = b->model_m;
        tmp->pos.interp_mix = TRN_REFINE_MIX_MEAN;
    }
    return trn_loc_noise_rejected_(map, local, rx, ry, at, heading, rc, &out->loc.noise_scale);
}

/* The valley's share of the failure probability at the refined answer's
 * heading, held (trn_refine_valley_fail_ over the window). */
static double valley3(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx, int32_t ry,
                      const trn_window_t *win, const trn_refine_cfg_t *rc, const trn_refine3_t *ref)
{
    const double lo[2] = {(double)win->x0, (double)win->y0};
    const double hi[2] = {(double)win->x1, (double)win->y1};
    return trn_refine_valley_fail_(&map->heights, local, rx, ry, rc, &ref->pos, ref->heading_rad,
                                   ref->pos.ll_inflation, lo, hi);
}

trn_status_t trn_localize_heights3_(const trn_map_t *map, const trn_grid_f32_t *local,
                                    int32_t rover_x, int32_t rover_y, const trn_window_t *win,
                                    const trn_heading_cfg_t *cfg, void *ws, size_t ws_bytes,
                                    trn_heading_result_t *out)
{
    trn_status_t st;
    trn_refine_cfg_t rc;
    hh_layout_t lay;
    uint8_t *b = (uint8_t *)ws;
    trn_height_best3_t *best;
    trn_refine3_t *ref;
    trn_loc_basins_t *far;
    double step, *grid;
    uint64_t cost, work = 0u;
    int32_t kk, pass;
    int found = 0;

    if (!window_in(map, win)) {
        return TRN_E_RANGE;
    }
    if ((st = trn_height_heading_steps(local, rover_x, rover_y, cfg, &step, &kk)) != TRN_OK) {
        return st;
    }
    hh_layout(local, win, kk, &lay);
    if ((st = trn_ws_check(ws, ws_bytes, lay.total)) != TRN_OK) {
        return st;
    }
    best = (trn_height_best3_t *)(void *)(b + lay.best);
    ref = (trn_refine3_t *)(void *)(b + lay.ref);
    grid = (double *)(void *)(b + lay.grid);
    far = (trn_loc_basins_t *)(void *)(b + lay.basins);
    out->loc.noise_scale = 1.0;
    /* one pass scores every (pose, heading) of the window */
    cost = (uint64_t)(win->x1 - win->x0 + 1) * (uint64_t)(win->y1 - win->y0 + 1) *
           (uint64_t)(2 * kk + 1);
    pass = 0;
    do {
        /* the configured noise model; once more, rescaled, if the residuals
         * at the answer reject it (trn_localize_dem's rule) */
        trn_loc_refine_cfg_(map, &out->loc, &rc);
        if (map->cfg.node_budget != 0u && work + cost > (uint64_t)map->cfg.node_budget) {
            return TRN_E_BUDGET; /* before the pass, as trn_localize_dem's */
        }
        work += cost;
        if ((st = trn_height_search_heading(&map->heights, local, rover_x, rover_y, win, cfg, &rc,
                                            map->cfg.inlier_prob, b + lay.search,
                                            ws_bytes - lay.search, grid, best)) != TRN_OK) {
            return st;
        }
        search_result(best, win, cfg, out);
        trn_loc_find_basins3_(grid, win, kk, map->cfg.min_exclusion_cells, best->x, best->y, far);
        found = refine_starts(map, local, rover_x, rover_y, win, grid, best, out->heading_rad,
                              cfg->window_rad > 0.0 ? TRN_REFINE_MAX_TURN_STEPS * step : 0.0, &rc,
                              ref, (trn_refine3_t *)(void *)(b + lay.cand), far);
        pass += 1;
    } while (pass == 1 && map->cfg.noise_auto != 0 &&
             rescale_noise3(map, local, rover_x, rover_y, &rc, best, found ? ref : NULL,
                            (trn_refine3_t *)(void *)(b + lay.cand), out) != 0);
    if (found) {
        if (far->moved) { /* the answer's start moved to a far basin's */
            out->loc.ix = far->mx;
            out->loc.iy = far->my;
            out->best_step = far->mk - kk;
            out->loc.ll_best = grid[(size_t)far->mk * (size_t)(win->x1 - win->x0 + 1) *
                                        (size_t)(win->y1 - win->y0 + 1) +
                                    (size_t)(far->my - win->y0) * (size_t)(win->x1 - win->x0 + 1) +
                                    (size_t)(far->mx - win->x0)];
            out->loc.on_window_edge = trn_loc_on_edge_(win, far->mx, far->my);
        }
        /* the final answer's ellipse: ln L's fall at 2 sds at its heading,
         * cov3's position block stretched alike (trn_localize_dem's
         * shoulders, docs/method.md 9) */
        trn_loc_refine_cfg_(map, &out->loc, &rc);
        trn_refine_shoulders_(&map->heights, local, rover_x, rover_y, &rc, ref->heading_rad,
                              &ref->pos, ref->cov3);
        refine_result(map, ref, out);
    }
    out->loc.refinement = ref->pos;
    out->loc.n_points = (size_t)(ref->pos.n_seen > 0 ? ref->pos.n_seen : 0);
    /* the zone as trn_localize_dem's height matcher: min_exclusion_cells */
    out->loc.exclusion_cells = map->cfg.min_exclusion_cells;
    masses(grid, win, kk, out->loc.refined ? ref->pos.ll_inflation : 1.0, &out->loc);
    if (out->loc.refined) { /* the far basins' share (localize_int.h) */
        out->loc.failure_probability = fmax(
            out->loc.failure_probability,
            trn_loc_basins_failure_(far, ref->pos.ll_inflation, &out->loc));
        /* the position ellipse's tail beyond the failure radius, and the
         * valley's share along its major axis at the answer's heading (as
         * trn_localize_dem's: docs/method.md 9) */
        out->loc.failure_probability = fmax(out->loc.failure_probability,
                                            trn_loc_tail_failure_(ref->pos.cov_cells));
        out->loc.failure_probability = fmax(out->loc.failure_probability,
                                            valley3(map, local, rover_x, rover_y, win, &rc, ref));
    }
    /* the best pose on the window's edge, or the refined heading beyond the
     * heading window: the likelihood may rise beyond what was searched, so
     * no fix (trn_localize_dem's rule, over heading too) */
    if (!out->loc.refined || out->loc.misfit || out->loc.on_window_edge ||
        (cfg->window_rad > 0.0 && fabs(out->heading_rad - cfg->center_rad) > cfg->window_rad)) {
        return TRN_E_ILLCOND;
    }
    return out->loc.failure_probability > (double)map->cfg.max_failure_prob ? TRN_E_AMBIGUOUS
                                                                            : TRN_OK;
}
