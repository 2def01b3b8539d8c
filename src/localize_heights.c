/* SPDX-License-Identifier: Apache-2.0 */
/* localize_heights.c - the height matcher's localization (TRN_MATCH_HEIGHTS;
 * docs/method.md 9): one path over (x, y, heading), of which trn_localize_dem
 * is the case of one heading, 0, and no heading searched. In order: the
 * search (src/height_heading.c's over heading, or at heading 0 the bounded
 * search of src/height_bound.c), the refinement from the best pose and its
 * neighbours (src/refine_pose.c), once more with the noise model rescaled
 * when the residuals reject it, the far basins (src/localize_basins.c), the
 * shoulders, the failure probability, the acceptance test. Below the two
 * entries (src/localize.c, src/localize_heading.c), above the stages
 * (docs/architecture.md, "The localization stack"). */
#include <math.h>
#include <string.h>

#include "height_bound.h"
#include "localize_int.h"
#include "refine_int.h"
#include "ws.h"

/* One localization's state, in the workspace (not on the stack: the limit
 * of docs/architecture.md). */
typedef struct {
    trn_refine_cfg_t rc;     /* the noise model: the configured one, then the rescaled */
    trn_height_best3_t best; /* the search's best (pose, heading) */
    trn_refine3_t ref;       /* the refinement taken as the answer */
    trn_refine3_t cand;      /* a candidate refinement (second starts, far basins) */
    trn_loc_basins_t far;    /* the far basins */
    trn_hb_t *hb;            /* the bounded search's state, or NULL */
    double *grid;            /* ln L of every (pose, heading) searched */
    void *search;            /* the search's workspace */
    size_t search_bytes;
    uint64_t work; /* the node budget's count */
    double err;    /* the bounded masses' error */
    int32_t kk;    /* K: headings centre + k step, k = -K..K */
    int found;     /* the refinement succeeded */
} lh_t;

/* Layout: [state | ln L grid, (2K + 1) x the window's poses | the search's
 * workspace: the pose score's, or the bounded search's]. */
typedef struct {
    size_t st, grid, search, total;
} lh_layout_t;

/* The bounded search: asked for, over (x, y) at heading 0 only. */
static int bounded(const trn_map_t *map, const trn_heading_cfg_t *cfg)
{
    return map->cfg.search == TRN_SEARCH_BOUNDED && cfg->window_rad == 0.0 &&
           cfg->center_rad == 0.0;
}

/* 0 if refused: the bounded search with a heading (searched or turned), or
 * a size out of range. */
static int lh_layout(const trn_map_t *map, int32_t w, int32_t h, const trn_window_t *win,
                     int32_t kk, const trn_heading_cfg_t *cfg, lh_layout_t *lay)
{
    trn_ws_t ws;
    const size_t poses = (size_t)(win->x1 - win->x0 + 1) * (size_t)(win->y1 - win->y0 + 1);
    size_t sb = trn_hs_bytes(w, h);
    if (map->cfg.search == TRN_SEARCH_BOUNDED) {
        if (!bounded(map, cfg)) {
            return 0;
        }
        sb = trn_hb_bytes(win, w, h);
    }
    if (sb == 0u) {
        return 0;
    }
    trn_ws_begin(&ws, NULL);
    lay->st = trn_ws_offset(&ws, sizeof(lh_t));
    lay->grid = trn_ws_offset(&ws, (size_t)(2 * kk + 1) * poses * sizeof(double));
    lay->search = trn_ws_offset(&ws, sb);
    lay->total = ws.total;
    return 1;
}

/* The window is non-empty and inside the map's heights. */
static int window_in(const trn_map_t *map, const trn_window_t *win)
{
    return win->x0 <= win->x1 && win->y0 <= win->y1 && win->x0 >= 0 && win->y0 >= 0 &&
           win->x1 < map->heights.width && win->y1 < map->heights.height;
}

size_t trn_loc_heights_bytes_(const trn_map_t *map, int32_t width, int32_t height,
                              const trn_window_t *win, int32_t half_steps,
                              const trn_heading_cfg_t *cfg)
{
    lh_layout_t lay;
    if (map->heights.data == NULL || !window_in(map, win) || half_steps < 0 ||
        !lh_layout(map, width, height, win, half_steps, cfg, &lay)) {
        return 0u;
    }
    return lay.total;
}

/* ln(exp(a) + exp(b)) without overflow (a, b finite). */
static double log_add(double a, double b)
{
    return fmax(a, b) + log1p(exp(fmin(a, b) - fmax(a, b)));
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
    out->loc.relief_z = (double)INFINITY;
    /* W = 0: no heading searched, the heading taken as known */
    out->step_rad = cfg->window_rad > 0.0 ? b->step_rad : 0.0;
    out->half_steps = b->half_steps;
    out->best_step = b->k;
    out->heading_rad = cfg->center_rad + (double)b->k * b->step_rad;
    out->sigma_heading_rad = cfg->window_rad > 0.0 ? (double)INFINITY : 0.0;
    for (p = 0; p < 9; ++p) {
        out->cov3[p] = (p % 4 == 0) ? (double)INFINITY : 0.0;
    }
    if (cfg->window_rad == 0.0) { /* the heading's row and column: known */
        out->cov3[8] = 0.0;
    }
}

/* The search with the noise model s->rc: every (pose, heading)
 * scored, within the node budget; or the bounded search, the best pose's
 * neighbours scored too (the second starts read them). */
static trn_status_t search(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx,
                           int32_t ry, const trn_window_t *win, const trn_heading_cfg_t *cfg,
                           lh_t *s)
{
    trn_status_t st;
    trn_height_best_t b2;
    int32_t k;
    if (!bounded(map, cfg)) {
        const uint64_t cost = (uint64_t)(win->x1 - win->x0 + 1) *
                              (uint64_t)(win->y1 - win->y0 + 1) * (uint64_t)(2 * s->kk + 1);
        if (map->cfg.node_budget != 0u && s->work + cost > (uint64_t)map->cfg.node_budget) {
            return TRN_E_BUDGET; /* before the pass: its cost is its scores */
        }
        s->work += cost;
        return trn_height_search_heading(&map->heights, local, rx, ry, win, cfg, &s->rc,
                                         map->cfg.inlier_prob, s->search, s->search_bytes, s->grid,
                                         &s->best);
    }
    if ((st = trn_hb_init(&s->hb, s->search, &map->heights, local, rx, ry, win, &s->rc,
                          map->cfg.inlier_prob, s->grid, &s->work,
                          (uint64_t)map->cfg.node_budget)) != TRN_OK ||
        (st = trn_hb_best(s->hb, NULL, &b2)) != TRN_OK) {
        return st;
    }
    for (k = 0; k < 9; ++k) {
        const int32_t sx = b2.x + k % 3 - 1, sy = b2.y + k / 3 - 1;
        if (sx >= win->x0 && sx <= win->x1 && sy >= win->y0 && sy <= win->y1 &&
            (st = trn_hb_eval(s->hb, sx, sy)) != TRN_OK) {
            return st;
        }
    }
    s->best.x = b2.x;
    s->best.y = b2.y;
    s->best.k = 0;
    s->best.ll = b2.ll;
    s->best.dz_m = b2.dz_m;
    s->best.model_m = b2.model_m;
    s->best.step_rad = 0.0;
    s->best.half_steps = 0;
    s->best.poses = s->hb->evals;
    return TRN_OK;
}

/* trn_refine_pose_heading from the search's best (pose, heading) and from
 * each of its 8 position neighbours at that heading step whose ln L is
 * within TRN_REFINE_START_NATS of the best's (inside the window): on
 * terrain a cell or two wide the best integer pose can lie in the basin of
 * a lesser sub-cell peak. Keeps in s->ref the refinement with the highest
 * refined ln L (ties: the best pose's); s->found 1 if any succeeded. */
static void refine_starts(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx, int32_t ry,
                          const trn_window_t *win, double heading, double max_turn, lh_t *s)
{
    /* the window is inside the map, x0 <= x1 and y0 <= y1 (window_in) */
    const size_t wx = (size_t)win->x1 - (size_t)win->x0 + 1u;
    const size_t wy = (size_t)win->y1 - (size_t)win->y0 + 1u;
    const trn_height_best3_t *b = &s->best;
    const double *slice = s->grid + (size_t)(b->k + b->half_steps) * wx * wy;
    int32_t k;
    s->found = trn_refine_run_(&map->heights, local, rx, ry, b->x, b->y, heading, max_turn, &s->rc,
                               &s->ref.pos, &s->ref) == TRN_OK;
    for (k = 0; k < 9; ++k) {
        const int32_t sx = b->x + k % 3 - 1, sy = b->y + k / 3 - 1;
        if (k == 4 || sx < win->x0 || sx > win->x1 || sy < win->y0 || sy > win->y1 ||
            !(slice[(size_t)(sy - win->y0) * wx + (size_t)(sx - win->x0)] >
              b->ll - TRN_REFINE_START_NATS)) {
            continue;
        }
        if (trn_refine_run_(&map->heights, local, rx, ry, sx, sy, heading, max_turn, &s->rc,
                            &s->cand.pos, &s->cand) == TRN_OK &&
            (!s->found || s->cand.pos.ll > s->ref.pos.ll)) {
            s->ref = s->cand;
            s->found = 1;
        }
    }
}

/* 1 (out->loc.noise_scale set) if the residuals at the answer, the local
 * map turned by its heading, reject the noise model s->rc
 * (trn_loc_noise_rejected_), else 0. The answer is the refinement when it
 * succeeded, else the search's best (pose, heading) with its offset and
 * model variance (at an integer pose the mix does not enter), written into
 * s->cand. */
static int rescale_noise(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx, int32_t ry,
                         lh_t *s, trn_heading_result_t *out)
{
    double heading = out->heading_rad;
    const trn_refine_t *at = &s->cand.pos;
    if (s->found) {
        at = &s->ref.pos;
        heading = s->ref.heading_rad;
    } else {
        s->cand.pos = s->ref.pos;
        s->cand.pos.x = (double)s->best.x;
        s->cand.pos.y = (double)s->best.y;
        s->cand.pos.dz_m = s->best.dz_m;
        s->cand.pos.model_m = s->best.model_m;
        s->cand.pos.interp_mix = TRN_REFINE_MIX_MEAN;
    }
    return trn_loc_noise_rejected_(map, local, rx, ry, at, heading, &s->rc, &out->loc.noise_scale);
}

/* The far basins (trn_loc_find_basins3_ on the grid; the bounded search
 * scores first every pose that could be one, and their zones): each refined
 * at its own heading; one replaces the answer if trn_loc_far_wins_ says so
 * (its refined ln L beats it by more than TRN_REFINE_FAR_NATS), the answer
 * taking its slot; then the answer's start, grid ln L and edge flag follow. */
static trn_status_t far_basins(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx,
                               int32_t ry, const trn_window_t *win, double heading, double max_turn,
                               lh_t *s, trn_heading_result_t *out)
{
    trn_loc_basins_t *far = &s->far;
    const trn_height_best3_t *b = &s->best;
    const int32_t radius = map->cfg.min_exclusion_cells;
    trn_status_t st;
    int32_t k;
    if (s->hb != NULL && ((st = trn_hb_eval_zone(s->hb, b->x, b->y, radius)) != TRN_OK ||
                          (st = trn_hb_basins(s->hb, -(double)INFINITY, b->x, b->y, radius,
                                              TRN_REFINE_BASINS)) != TRN_OK)) {
        return st;
    }
    trn_loc_find_basins3_(s->grid, win, s->kk, radius, b->x, b->y, far);
    for (k = 0; s->hb != NULL && k < far->n; ++k) {
        if ((st = trn_hb_eval_zone(s->hb, far->x[k], far->y[k], radius)) != TRN_OK) {
            return st;
        }
    }
    for (k = 0; k < far->n; ++k) {
        int32_t ax, ay;
        far->ok[k] = trn_refine_run_(&map->heights, local, rx, ry, far->x[k], far->y[k],
                                     heading +
                                         (double)(far->k[k] - b->half_steps - b->k) * b->step_rad,
                                     max_turn, &s->rc, &s->cand.pos, &s->cand) == TRN_OK;
        far->px[k] = s->cand.pos.x;
        far->py[k] = s->cand.pos.y;
        far->rll[k] = s->cand.pos.ll;
        /* the answer's start so far goes into the slot */
        ax = far->moved ? far->mx : b->x;
        ay = far->moved ? far->my : b->y;
        if (far->ok[k] &&
            trn_loc_far_wins_(s->cand.pos.x, s->cand.pos.y, s->cand.pos.ll, s->ref.pos.x,
                              s->ref.pos.y, s->ref.pos.ll, s->ref.pos.ll_inflation)) {
            const int32_t sx = far->x[k], sy = far->y[k], sk = far->k[k];
            far->x[k] = ax;
            far->y[k] = ay;
            far->k[k] = far->moved ? far->mk : b->k + b->half_steps;
            far->moved = 1;
            far->mx = sx;
            far->my = sy;
            far->mk = sk;
            far->px[k] = s->ref.pos.x;
            far->py[k] = s->ref.pos.y;
            far->rll[k] = s->ref.pos.ll;
            s->ref = s->cand;
        }
    }
    if (far->moved) { /* the answer's start moved to a far basin's */
        /* the window is inside the map, x0 <= x1 and y0 <= y1 (window_in) */
        const size_t wx = (size_t)win->x1 - (size_t)win->x0 + 1u;
        const size_t wy = (size_t)win->y1 - (size_t)win->y0 + 1u;
        out->loc.ix = far->mx;
        out->loc.iy = far->my;
        out->best_step = far->mk - s->kk;
        out->loc.ll_best = s->grid[(size_t)far->mk * wx * wy + (size_t)(far->my - win->y0) * wx +
                                   (size_t)(far->mx - win->x0)];
        out->loc.on_window_edge = trn_loc_on_edge_(win, far->mx, far->my);
    }
    return TRN_OK;
}

/* The refinement s->ref into out: the position as trn_localize_dem's
 * (trn_loc_take_refinement_: metres, misfit flag), cov3 in metres and
 * radians with its position block that covariance. */
static void refine_result(const trn_map_t *map, const lh_t *s, const trn_heading_cfg_t *cfg,
                          trn_heading_result_t *out)
{
    const double cell = (double)map->cfg.terrain.cell_m;
    int32_t p;
    out->loc.refinement = s->ref.pos;
    trn_loc_take_refinement_(map, &out->loc);
    for (p = 0; p < 9; ++p) {
        const double sr = (p / 3 < 2) ? cell : 1.0, sc = (p % 3 < 2) ? cell : 1.0;
        out->cov3[p] = s->ref.cov3[p] * sr * sc;
    }
    out->cov3[0] = out->loc.cov_m2[0];
    out->cov3[4] = out->loc.cov_m2[1];
    out->cov3[1] = out->cov3[3] = out->loc.cov_m2[2];
    out->heading_rad = s->ref.heading_rad + s->ref.spline_step_heading_rad;
    out->sigma_heading_rad = cfg->window_rad > 0.0 ? sqrt(out->cov3[8]) : 0.0;
}

/* The grid's share of the failure probability: the posterior mass (uniform
 * prior over the window and the headings) of every (pose, heading) outside
 * the position zone around the answer, ln L divided by infl (trn_height_mass
 * per heading, summed); the competitor is the best of them. With the
 * bounded search, the competitor exactly and the masses within s->err
 * (trn_hb_mass). TRN_OK, or the bounded search's TRN_E_BUDGET. */
static trn_status_t masses(lh_t *s, const trn_window_t *win, double infl, trn_loc_result_t *loc)
{
    const size_t poses = (size_t)(win->x1 - win->x0 + 1) * (size_t)(win->y1 - win->y0 + 1);
    trn_exclusion_t ex;
    trn_height_best_t m;
    double lse_all = 0.0, lse_out = 0.0;
    trn_status_t st;
    int32_t k;
    int any = 0;
    ex.cx = loc->ix;
    ex.cy = loc->iy;
    ex.radius = loc->exclusion_cells;
    loc->second_x = loc->ix;
    loc->second_y = loc->iy;
    loc->ll_second = loc->ll_best;
    for (k = 0; k < 2 * s->kk + 1; ++k) {
        /* TRN_OK or TRN_E_NODATA (every pose in the zone): the window, zone
         * and scale were checked; lse_all is filled in either case */
        if (s->hb != NULL) { /* one slice: the bounded search is at heading 0 only */
            trn_status_t sb;
            if ((st = trn_hb_eval_zone(s->hb, ex.cx, ex.cy, ex.radius)) != TRN_OK) {
                return st;
            }
            sb = trn_hb_best(s->hb, &ex, &m);
            if ((sb != TRN_OK && sb != TRN_E_NODATA) ||
                (st = trn_hb_mass(s->hb, &ex, infl, TRN_BOUND_EPS, &m.lse_all, &m.lse_out,
                                  &s->err)) != TRN_OK) {
                return sb != TRN_OK && sb != TRN_E_NODATA ? sb : st;
            }
            st = sb;
        } else {
            st = trn_height_mass(s->grid + (size_t)k * poses, win, &ex, infl, &m);
        }
        lse_all = k == 0 ? m.lse_all : log_add(lse_all, m.lse_all);
        if (st == TRN_OK && (!any || m.ll > loc->ll_second)) {
            loc->ll_second = m.ll;
            loc->second_x = m.x;
            loc->second_y = m.y;
        }
        if (st == TRN_OK) {
            lse_out = any ? log_add(lse_out, m.lse_out) : m.lse_out;
            any = 1;
        }
    }
    loc->has_second = any;
    /* no pose outside the zone: no competitor, probability 0 */
    loc->failure_probability = any ? exp(fmin(0.0, lse_out - lse_all)) : 0.0;
    return TRN_OK;
}

/* The failure probability beyond the grid's: the far basins' share
 * (trn_loc_basins_failure_), the position ellipse's tail beyond the
 * failure radius and the valley's share along its major axis at the
 * answer's heading (docs/method.md 9.5). */
static double peak_failure(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx,
                           int32_t ry, const trn_window_t *win, const lh_t *s,
                           const trn_loc_result_t *loc)
{
    const double lo[2] = {(double)win->x0, (double)win->y0};
    const double hi[2] = {(double)win->x1, (double)win->y1};
    const double infl = s->ref.pos.ll_inflation;
    double pf = fmax(trn_loc_basins_failure_(&s->far, infl, loc),
                     trn_loc_tail_failure_(s->ref.pos.cov_cells));
    return fmax(pf, trn_refine_valley_fail_(&map->heights, local, rx, ry, &s->rc, &s->ref.pos,
                                            s->ref.heading_rad, infl, lo, hi));
}

trn_status_t trn_loc_heights_(const trn_map_t *map, const trn_grid_f32_t *local,
                              const trn_local_cells_t *cells, int32_t rover_x, int32_t rover_y,
                              const trn_window_t *win, const trn_heading_cfg_t *cfg, void *ws,
                              size_t ws_bytes, trn_heading_result_t *out)
{
    trn_status_t st;
    lh_layout_t lay;
    uint8_t *b = (uint8_t *)ws;
    lh_t *s;
    double step, max_turn;
    int32_t kk;

    if (!window_in(map, win)) {
        return TRN_E_RANGE;
    }
    if ((st = trn_height_heading_steps(local, rover_x, rover_y, cfg, &step, &kk)) != TRN_OK) {
        return st;
    }
    if (!lh_layout(map, local->width, local->height, win, kk, cfg, &lay)) {
        return map->cfg.search == TRN_SEARCH_BOUNDED && !bounded(map, cfg) ? TRN_E_ARG
                                                                           : TRN_E_RANGE;
    }
    if ((st = trn_ws_check(ws, ws_bytes, lay.total)) != TRN_OK) {
        return st;
    }
    s = (lh_t *)(void *)(b + lay.st);
    (void)memset(s, 0, sizeof(*s)); /* every byte set: results equal bit for bit */
    s->grid = (double *)(void *)(b + lay.grid);
    s->search = b + lay.search;
    s->search_bytes = lay.total - lay.search;
    s->hb = NULL;
    s->kk = kk;
    max_turn = cfg->window_rad > 0.0 ? TRN_REFINE_MAX_TURN_STEPS * step : 0.0;
    out->loc.noise_scale = 1.0;
    out->loc.failure_prob_bound = 0.0;
    out->loc.search = bounded(map, cfg) ? TRN_SEARCH_BOUNDED : TRN_SEARCH_EXHAUSTIVE;
    /* the search, its pose score fitting the noise model's scale per pose
     * (noise_auto); the refinement under the configured model, and once more
     * under the model rescaled if the residuals at the answer reject it
     * (docs/method.md 9.2) */
    trn_loc_refine_cfg_(map, &out->loc, cells, &s->rc);
    if ((st = search(map, local, rover_x, rover_y, win, cfg, s)) != TRN_OK) {
        return st;
    }
    search_result(&s->best, win, cfg, out);
    refine_starts(map, local, rover_x, rover_y, win, out->heading_rad, max_turn, s);
    if (map->cfg.noise_auto != 0 && rescale_noise(map, local, rover_x, rover_y, s, out) != 0) {
        trn_loc_refine_cfg_(map, &out->loc, cells, &s->rc);
        refine_starts(map, local, rover_x, rover_y, win, out->heading_rad, max_turn, s);
    }
    s->far.n = 0;
    s->far.moved = 0;
    if (s->found) {
        if ((st = far_basins(map, local, rover_x, rover_y, win, out->heading_rad, max_turn, s,
                             out)) != TRN_OK) {
            return st;
        }
        /* the final answer's ellipse: ln L's fall at 2 sds at its heading,
         * cov3's position block stretched alike (docs/method.md 9.5, the
         * shoulders) */
        trn_refine_shoulders_(&map->heights, local, rover_x, rover_y, &s->rc, s->ref.heading_rad,
                              &s->ref.pos, s->ref.cov3);
        refine_result(map, s, cfg, out);
        /* the relief test: a pose beside the truth (a prior that missed it)
         * takes a weaker copy of the map's relief (docs/method.md 9.4) */
        out->loc.relief_z = trn_refine_relief_z_(&map->heights, local, rover_x, rover_y,
                                                 &s->ref.pos, s->ref.heading_rad, &s->rc);
        if (out->loc.relief_z < -TRN_RELIEF_Z) {
            out->loc.misfit = 1;
        }
    } else {
        out->loc.refinement = s->ref.pos;
    }
    out->loc.n_points = (size_t)(s->ref.pos.n_seen > 0 ? s->ref.pos.n_seen : 0);
    /* The zone is min_exclusion_cells, not 4 sigma as for eq. 6: the failure
     * probability is the posterior mass of poses that far from the answer,
     * so a broad peak (large sigma) shows as a large probability instead of
     * hiding its competitors inside a wide zone. */
    out->loc.exclusion_cells = map->cfg.min_exclusion_cells;
    if ((st = masses(s, win, out->loc.refined ? s->ref.pos.ll_inflation : 1.0, &out->loc)) !=
        TRN_OK) {
        return st;
    }
    if (s->hb != NULL) {
        out->loc.stats.poses_scored = s->hb->evals;
        out->loc.stats.blocks_bounded = s->hb->bounds;
        /* ... and the sums' rounding (another order than the grid's, of ln L
         * values up to 1e4 and more: a few ulps of those) */
        out->loc.failure_prob_bound = s->err + 1e-9;
    }
    if (out->loc.refined) {
        out->loc.failure_probability = fmax(
            out->loc.failure_probability,
            peak_failure(map, local, rover_x, rover_y, win, s, &out->loc));
    }
    /* the best pose on the window's edge, or the refined heading beyond the
     * heading window: the likelihood may rise beyond what was searched (a
     * prior that missed the truth), so no fix (docs/method.md 9.6) */
    if (!out->loc.refined || out->loc.misfit || out->loc.on_window_edge ||
        (cfg->window_rad > 0.0 && fabs(out->heading_rad - cfg->center_rad) > cfg->window_rad)) {
        return TRN_E_ILLCOND;
    }
    return out->loc.failure_probability > (double)map->cfg.max_failure_prob ? TRN_E_AMBIGUOUS
                                                                            : TRN_OK;
}
