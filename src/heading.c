/* SPDX-License-Identifier: Apache-2.0 */
/* heading.c - localization over (x, y, heading) (see trn/heading.h). */
#include "trn/heading.h"

#include <math.h>
#include <stdlib.h>

#include "likelihood_int.h"
#include "localize_int.h"
#include "ws.h"

/* Largest |x|, |y| of a point turned: sqrt(2) x 16383 < 32767. */
#define HEADING_MAX_OFFSET 16383

/* Positions kept by the one-pass search (the first of those with a pose
 * within the margin of the best: a few near the peak on terrain that pins
 * the pose down). More than the zone's (2 r + 1)^2, r = 2 by default: a
 * full list always holds a position outside the zone. If the zone holds
 * every one, the competitor is searched again (search_all). 32: fewer
 * falls back more often on few points; more lowers the threshold once
 * full (more work), measured in docs/modules/heading.md. */
#define HEADING_KEEP 32

trn_status_t trn_heading_steps(const trn_point_t *pts, size_t n, const trn_heading_cfg_t *cfg,
                               double *step_rad, int32_t *half_steps)
{
    double step, k;
    if (pts == NULL || cfg == NULL || step_rad == NULL || half_steps == NULL) {
        return TRN_E_NULL;
    }
    if (!(fabs(cfg->center_rad) <= TRN_HEADING_MAX_WINDOW_RAD) ||
        !(cfg->window_rad >= 0.0 && cfg->window_rad <= TRN_HEADING_MAX_WINDOW_RAD) ||
        !(cfg->step_rad >= 0.0 && cfg->step_rad <= TRN_HEADING_MAX_WINDOW_RAD)) {
        return TRN_E_ARG;
    }
    if (n == 0u) {
        return TRN_E_NODATA;
    }
    step = cfg->step_rad;
    if (step == 0.0) {
        double r2 = 0.0;
        size_t i;
        for (i = 0; i < n; ++i) {
            const double x = (double)pts[i].x, y = (double)pts[i].y;
            if (x * x + y * y > r2) {
                r2 = x * x + y * y;
            }
        }
        if (!(r2 > 0.0)) {
            if (cfg->window_rad > 0.0) {
                return TRN_E_NODATA; /* no lever arm: heading unobservable */
            }
            r2 = 1.0;
        }
        step = 1.0 / sqrt(r2);
    }
    /* K = ceil(W / step); a hair of slack so W = K step exactly gives K */
    k = cfg->window_rad > 0.0 ? ceil(cfg->window_rad / step - 1e-9) : 0.0;
    if (!(2.0 * k + 1.0 <= (double)TRN_MAX_HEADING_STEPS)) {
        return TRN_E_SIZE;
    }
    *step_rad = step;
    *half_steps = (int32_t)k;
    return TRN_OK;
}

trn_status_t trn_points_rotate(const trn_point_t *in, size_t n, double angle_rad, trn_point_t *out)
{
    double c, s;
    size_t i;
    if (in == NULL || out == NULL) {
        return TRN_E_NULL;
    }
    if (!isfinite(angle_rad)) {
        return TRN_E_ARG;
    }
    for (i = 0; i < n; ++i) {
        if (in[i].x > HEADING_MAX_OFFSET || in[i].x < -HEADING_MAX_OFFSET ||
            in[i].y > HEADING_MAX_OFFSET || in[i].y < -HEADING_MAX_OFFSET) {
            return TRN_E_ARG;
        }
    }
    c = cos(angle_rad);
    s = sin(angle_rad);
    for (i = 0; i < n; ++i) {
        const double x = (double)in[i].x, y = (double)in[i].y;
        out[i].x = (int16_t)floor(x * c + y * s + 0.5);
        out[i].y = (int16_t)floor(-x * s + y * c + 0.5);
        out[i].z = in[i].z;
    }
    return TRN_OK;
}

/* One heading of a search (see search_all). */
typedef struct {
    int32_t k;
    int64_t proxy; /* score of the seed's best pose at this heading */
} heading_t;

/* The search's context: map, points, window, headings, exclusion. */
typedef struct {
    const trn_map_t *map;
    const trn_point_t *pts;
    size_t n;
    const trn_window_t *win;
    const trn_heading_cfg_t *cfg;
    double step;
    int32_t kk;
    const trn_exclusion_t *ex; /* poses in this zone are skipped at every heading */
    trn_point_t *buf;
    heading_t *hs; /* 2 kk + 1 */
    void *sws;
    size_t swb;
} hsearch_t;

/* The fit's samples and result, in the workspace (kept off the stack). */
typedef struct {
    double ll[27];
    trn_peak3_t pk;
    hsearch_t h;      /* the search's context */
    trn_bb_keep_t kp; /* the one-pass search's best and kept poses */
} fit_t;

/* The workspace: the turned points, the fit, the search's heading list,
 * the kept poses, then trn_search_bb's workspace. */
static size_t heading_carve(const trn_map_t *map, size_t n, const trn_window_t *win, void *base,
                            trn_point_t **buf, fit_t **fit, heading_t **hs, void **search,
                            size_t *search_bytes)
{
    trn_ws_t w;
    size_t sw = trn_localize_workspace_bytes(map, win);
    *buf = NULL;
    *fit = NULL;
    *hs = NULL;
    *search = NULL;
    *search_bytes = 0u;
    if (sw == 0u || n == 0u ||
        n > (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_ZBINS) {
        return 0u;
    }
    trn_ws_begin(&w, base);
    *buf = (trn_point_t *)trn_ws_take(&w, n * sizeof(trn_point_t));
    *fit = (fit_t *)trn_ws_take(&w, sizeof(fit_t));
    *hs = (heading_t *)trn_ws_take(&w, (size_t)TRN_MAX_HEADING_STEPS * sizeof(heading_t));
    {
        trn_kept_pose_t *list = (trn_kept_pose_t *)trn_ws_take(&w, (size_t)HEADING_KEEP *
                                                                       sizeof(trn_kept_pose_t));
        if (*fit != NULL) {
            (*fit)->kp.list = list;
        }
    }
    *search = trn_ws_take(&w, sw);
    *search_bytes = sw;
    return w.total;
}

size_t trn_localize_heading_workspace_bytes(const trn_map_t *map, size_t n, const trn_window_t *win)
{
    trn_point_t *buf;
    fit_t *fit;
    heading_t *hs;
    void *search;
    size_t sb;
    return heading_carve(map, n, win, NULL, &buf, &fit, &hs, &search, &sb);
}

/* The points turned to heading step k, ordered for the search. Neither
 * call can fail: trn_localize_points_heading checked every point's offsets
 * and bins first, and n is below UINT32_MAX. */
static void turn(const trn_point_t *pts, size_t n, const trn_heading_cfg_t *cfg, double step,
                 int32_t k, int32_t nz, trn_point_t *buf)
{
    (void)trn_points_rotate(pts, n, cfg->center_rad + (double)k * step, buf);
    (void)trn_points_order(buf, n, nz);
}

/* Add a search's work to the result's counters. */
static void add_stats(trn_search_stats_t *sum, const trn_search_stats_t *s)
{
    sum->poses_scored += s->poses_scored;
    sum->blocks_bounded += s->blocks_bounded;
}

/* Tie rank of step k in the order 0, -1, +1, -2, +2, ...: the lower wins a tie. */
static int32_t tie_rank(int32_t k) { return k > 0 ? 2 * k : (k < 0 ? -2 * k - 1 : 0); }

/* Larger proxy first, then tie rank: the order headings are searched in. */
static int heading_before(const heading_t *a, const heading_t *b)
{
    if (a->proxy != b->proxy) {
        return a->proxy > b->proxy;
    }
    return tie_rank(a->k) < tie_rank(b->k);
}

/* Sort hs[0..m) by heading_before (insertion sort into place; m is at most
 * TRN_MAX_HEADING_STEPS and nearly sorted by construction). */
static void sort_headings(heading_t *hs, int32_t m)
{
    int32_t i, j;
    for (i = 1; i < m; ++i) {
        const heading_t v = hs[i];
        for (j = i; j > 0 && heading_before(&v, &hs[j - 1]); --j) {
            hs[j] = hs[j - 1];
        }
        hs[j] = v;
    }
}


/* Search heading k for a pose beating (best, best_k) under the tie rule
 * (score, then tie rank of the heading, then trn_search_bb's order), or any
 * pose above floor when nothing is found yet. The searches can only answer
 * TRN_OK or TRN_E_NODATA here: the map, window, points and workspace were
 * checked before (trn_localize_points_heading). */
static void search_one(hsearch_t *h, int32_t k, int64_t floor, int *found, trn_best_t *best,
                       int32_t *best_k, trn_search_stats_t *stats)
{
    trn_search_stats_t s = {0u, 0u};
    trn_best_t b;
    trn_status_t st;
    turn(h->pts, h->n, h->cfg, h->step, k, h->map->dist.nz, h->buf);
    if (*found) { /* a tie counts only when this heading ranks first */
        const int64_t f = tie_rank(k) < tie_rank(*best_k) ? best->score - 1 : best->score;
        st = trn_search_bb_above(&h->map->pyr, &h->map->lnp, h->buf, h->n, h->win, h->ex, f, h->sws,
                                 h->swb, &b, &s);
    } else {
        st = trn_search_bb_above(&h->map->pyr, &h->map->lnp, h->buf, h->n, h->win, h->ex, floor,
                                 h->sws, h->swb, &b, &s);
    }
    add_stats(stats, &s);
    if (st == TRN_OK) {
        *best = b;
        *best_k = k;
        *found = 1;
    }
}

/* The best pose above floor over every heading, outside h->ex (exactly:
 * each heading is searched by branch-and-bound above the best found so
 * far), TRN_OK or TRN_E_NODATA: the competitor when the kept poses cannot
 * tell it (kept_second). The seed heading first; the others in the order
 * of the score the seed's answer has at them, so a good floor comes early
 * and the rest stop after a few blocks. */
static trn_status_t search_all(hsearch_t *h, int32_t seed, int64_t floor, trn_best_t *best,
                               int32_t *best_k, trn_search_stats_t *stats)
{
    int32_t i, m = 0;
    int found = 0;
    search_one(h, seed, floor, &found, best, best_k, stats);
    for (i = 0; i <= 2 * h->kk; ++i) {
        const int32_t k = trn_heading_step_of_(i);
        int64_t p = 0; /* ordering proxy; all equal when the seed found nothing */
        if (k == seed) {
            continue;
        }
        if (found) { /* a pose inside the map's range: cannot fail */
            turn(h->pts, h->n, h->cfg, h->step, k, h->map->dist.nz, h->buf);
            (void)trn_score_pose(&h->map->dist, &h->map->lnp, h->buf, h->n, best->x, best->y, &p);
        }
        h->hs[m].k = k;
        h->hs[m].proxy = p;
        ++m;
    }
    sort_headings(h->hs, m);
    for (i = 0; i < m; ++i) {
        search_one(h, h->hs[i].k, floor, &found, best, best_k, stats);
    }
    return found ? TRN_OK : TRN_E_NODATA;
}

/* Heading k of the one-pass search (trn_search_bb_keep_; it cannot fail:
 * its arguments were checked as search_one's). */
static void keep_one(hsearch_t *h, int32_t k, trn_bb_keep_t *kp, trn_search_stats_t *stats)
{
    trn_search_stats_t s = {0u, 0u};
    turn(h->pts, h->n, h->cfg, h->step, k, h->map->dist.nz, h->buf);
    kp->k = k;
    kp->rank = tie_rank(k);
    (void)trn_search_bb_keep_(&h->map->pyr, &h->map->lnp, h->buf, h->n, h->win, h->sws, h->swb, kp,
                              &s);
    add_stats(stats, &s);
}

/* The best (x, y, heading) and the poses near it, in one pass over the
 * headings: each heading is searched by branch-and-bound above keep's
 * threshold (the best so far minus the margin, or the last kept position's
 * score once HEADING_KEEP positions are kept; carried across headings), the
 * poses at or above it offered to kp's list. Heading 0 first, the others in the
 * order of the score its best pose has at them, so a high bound comes
 * early. n > 0 points and no zone: kp->found is set. */
static void keep_all(hsearch_t *h, trn_bb_keep_t *kp, trn_search_stats_t *stats)
{
    int32_t i, m = 0;
    keep_one(h, 0, kp, stats);
    for (i = 1; i <= 2 * h->kk; ++i) {
        const int32_t k = trn_heading_step_of_(i);
        int64_t p = 0;
        turn(h->pts, h->n, h->cfg, h->step, k, h->map->dist.nz, h->buf);
        (void)trn_score_pose(&h->map->dist, &h->map->lnp, h->buf, h->n, kp->best.x, kp->best.y, &p);
        h->hs[m].k = k;
        h->hs[m].proxy = p;
        ++m;
    }
    sort_headings(h->hs, m);
    for (i = 0; i < m; ++i) {
        keep_one(h, h->hs[i].k, kp, stats);
    }
}

/* The competitor from the kept poses: the first, in the search's order
 * (score, tie rank of the heading, y, x), outside the zone and above floor
 * (the best minus the margin). Returns 1 and sets it if there is one; 0
 * if there is none at all (the list holds every pose above floor: it is
 * not full, or its last kept pose scores at most floor); -1 if the list
 * cannot tell (full, every pose above floor in it inside the zone: a pose
 * not kept may be the competitor). Exact: a pose not kept comes after
 * every pose kept or scores at most floor (trn_bb_keep_t). */
static int kept_second(const trn_bb_keep_t *kp, const trn_exclusion_t *ex, int64_t floor,
                       trn_best_t *second, int32_t *sk)
{
    const trn_kept_pose_t *c = NULL;
    size_t i;
    for (i = 0; i < kp->len; ++i) {
        const trn_kept_pose_t *e = &kp->list[i];
        const int32_t dx = e->x > ex->cx ? e->x - ex->cx : ex->cx - e->x;
        const int32_t dy = e->y > ex->cy ? e->y - ex->cy : ex->cy - e->y;
        if (e->score <= floor || (dx <= ex->radius && dy <= ex->radius)) {
            continue;
        }
        if (c == NULL || e->score > c->score ||
            (e->score == c->score &&
             (e->rank < c->rank ||
              (e->rank == c->rank && (e->y < c->y || (e->y == c->y && e->x < c->x)))))) {
            c = e;
        }
    }
    if (c != NULL) {
        second->x = c->x;
        second->y = c->y;
        second->score = c->score;
        *sk = c->k;
        return 1;
    }
    return (kp->len < kp->cap || kp->list[0].score <= floor) ? 0 : -1;
}

/* ln L, nats, on the 3 x 3 x 3 grid around (x, y, k) (checked points, poses
 * within one cell of the window: the scorer cannot fail). */
static void grid27(const trn_map_t *map, const trn_point_t *pts, size_t n,
                   const trn_heading_cfg_t *cfg, double step, int32_t x, int32_t y, int32_t k,
                   trn_point_t *buf, double ll[27])
{
    int32_t dk, i;
    for (dk = -1; dk <= 1; ++dk) {
        (void)trn_points_rotate(pts, n, cfg->center_rad + (double)(k + dk) * step, buf);
        for (i = 0; i < 9; ++i) {
            int64_t s = 0;
            (void)trn_score_pose(&map->dist, &map->lnp, buf, n, x + i % 3 - 1, y + i / 3 - 1, &s);
            ll[(dk + 1) * 9 + i] = (double)s / (double)TRN_LNP_SCALE;
        }
    }
}

/* W = 0: trn_localize_points on the points turned by the centre (buf, by
 * the caller's check); its status, the result filled in either case. */
static trn_status_t fixed_heading(const trn_map_t *map, size_t n, const trn_window_t *win,
                                  const trn_heading_cfg_t *cfg, const trn_point_t *buf, void *sws,
                                  size_t swb, trn_heading_result_t *out)
{
    const trn_status_t st = trn_localize_points(map, buf, n, win, sws, swb, &out->loc);
    int32_t i;
    out->heading_rad = cfg->center_rad;
    out->sigma_heading_rad = 0.0;
    for (i = 0; i < 9; ++i) {
        out->cov3[i] = 0.0;
    }
    out->cov3[0] = out->loc.cov_m2[0];
    out->cov3[4] = out->loc.cov_m2[1];
    out->cov3[1] = out->cov3[3] = out->loc.cov_m2[2];
    out->best_step = 0;
    return st;
}

trn_status_t trn_localize_points_heading(const trn_map_t *map, const trn_point_t *pts, size_t n,
                                         const trn_window_t *win, const trn_heading_cfg_t *cfg,
                                         void *ws, size_t ws_bytes, trn_heading_result_t *out)
{
    trn_status_t st, fit_st;
    trn_point_t *buf;
    heading_t *hsl;
    hsearch_t *h;
    int64_t margin;
    void *sws;
    size_t swb, need, i;
    double step, cell;
    fit_t *fit;
    int32_t kk, bk = 0, r, sk = 0;
    trn_best_t best, second;
    trn_exclusion_t ex;
    trn_search_stats_t stats = {0u, 0u}, s2 = {0u, 0u};

    if (map == NULL || pts == NULL || win == NULL || cfg == NULL || ws == NULL || out == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_heading_steps(pts, n, cfg, &step, &kk)) != TRN_OK) {
        return st;
    }
    if (win->x0 > win->x1 || win->y0 > win->y1 || win->x0 < 0 || win->y0 < 0 ||
        win->x1 >= map->dist.nx || win->y1 >= map->dist.ny) {
        return TRN_E_RANGE;
    }
    need = heading_carve(map, n, win, NULL, &buf, &fit, &hsl, &sws, &swb);
    if (need == 0u) {
        return TRN_E_ARG;
    }
    if ((st = trn_ws_check(ws, ws_bytes, need)) != TRN_OK) {
        return st;
    }
    (void)heading_carve(map, n, win, ws, &buf, &fit, &hsl, &sws, &swb);
    h = &fit->h;
    /* every point turnable and in the map's bins, so that nothing below can fail */
    if ((st = trn_points_rotate(pts, n, cfg->center_rad, buf)) != TRN_OK) {
        return st;
    }
    for (i = 0; i < n; ++i) {
        if (pts[i].z < 0 || pts[i].z >= map->dist.nz) {
            return TRN_E_ARG;
        }
    }
    out->step_rad = step;
    out->half_steps = kk;
    if (kk == 0) {
        return fixed_heading(map, n, win, cfg, buf, sws, swb, out);
    }

    /* the best (x, y, heading): exact, each heading above the best so far */
    h->map = map;
    h->pts = pts;
    h->n = n;
    h->win = win;
    h->cfg = cfg;
    h->step = step;
    h->kk = kk;
    h->ex = NULL;
    h->buf = buf;
    h->hs = hsl;
    h->sws = sws;
    h->swb = swb;
    /* scores are sums of n int32 table entries, n < 2^31: the differences cannot wrap */
    fit->kp.margin = (int64_t)TRN_HEADING_MARGIN_NATS * (int64_t)TRN_LNP_SCALE;
    fit->kp.found = 0;
    fit->kp.len = 0u;
    fit->kp.cap = HEADING_KEEP;
    keep_all(h, &fit->kp, &stats); /* n > 0 points, no zone: always a best */
    best = fit->kp.best;
    bk = fit->kp.best_k;
    out->loc.refined = 0;
    out->loc.misfit = 0;
    out->loc.relief_z = (double)INFINITY;
    out->loc.ix = best.x;
    out->loc.iy = best.y;
    out->loc.ll_best = (double)best.score / (double)TRN_LNP_SCALE;
    out->loc.n_points = n;
    out->loc.on_window_edge = (best.x == win->x0 || best.x == win->x1 || best.y == win->y0 ||
                               best.y == win->y1 || bk == -kk || bk == kk)
                                  ? 1
                                  : 0;
    out->best_step = bk;

    /* eq. 6 in (x, y, heading) */
    grid27(map, pts, n, cfg, step, best.x, best.y, bk, buf, fit->ll);
    fit_st = trn_peak_fit3(fit->ll, &fit->pk);
    cell = (double)map->cfg.terrain.cell_m;
    {
        const double sc[3] = {cell, cell, step};
        for (i = 0; i < 9u; ++i) {
            out->cov3[i] = fit->pk.covariance[i] * sc[i / 3u] * sc[i % 3u];
        }
    }
    out->loc.x = (double)best.x + fit->pk.offset[0];
    out->loc.y = (double)best.y + fit->pk.offset[1];
    out->heading_rad = cfg->center_rad + ((double)bk + fit->pk.offset[2]) * step;
    out->sigma_heading_rad = fit->pk.sigma[2] * step;
    out->loc.sigma_x_m = fit->pk.sigma[0] * cell;
    out->loc.sigma_y_m = fit->pk.sigma[1] * cell;
    out->loc.rho = (fit_st == TRN_OK)
                       ? fit->pk.covariance[1] / (fit->pk.sigma[0] * fit->pk.sigma[1])
                       : 0.0;
    out->loc.cov_m2[0] = out->cov3[0];
    out->loc.cov_m2[1] = out->cov3[4];
    out->loc.cov_m2[2] = out->cov3[1];

    /* the competitor: the best pose, at any heading, outside ~4 sigma of the
     * peak's position (a position failure is what the probability is of; the
     * same position at another heading is this peak's own tail) */
    r = map->cfg.min_exclusion_cells;
    if (fit_st == TRN_OK) {
        /* finite sigmas (a fitted peak); beyond the map no zone is wider */
        const double r4 = ceil(
            fmin(4.0 * fmax(fit->pk.sigma[0], fit->pk.sigma[1]), (double)TRN_MAX_DIM));
        r = (int32_t)fmax((double)r, r4);
    }
    ex.cx = best.x;
    ex.cy = best.y;
    ex.radius = r;
    out->loc.exclusion_cells = r;
    h->ex = &ex;
    margin = best.score - fit->kp.margin;
    /* the kept poses decide, unless the zone holds every one of them */
    r = kept_second(&fit->kp, &ex, margin, &second, &sk); /* r: the zone is in ex */
    if (r >= 0) {
        st = r ? TRN_OK : TRN_E_NODATA;
    } else {
        st = search_all(h, bk, margin, &second, &sk, &s2);
    }
    out->loc.stats = stats; /* the one pass's work (not the search again) */
    if (st == TRN_OK) {
        out->loc.has_second = 1;
        out->loc.second_x = second.x;
        out->loc.second_y = second.y;
        out->loc.ll_second = (double)second.score / (double)TRN_LNP_SCALE;
        /* finite, and at most the best's (the best is the maximum): cannot fail */
        (void)trn_failure_probability(out->loc.ll_best, out->loc.ll_second,
                                      &out->loc.failure_probability);
    } else { /* TRN_E_NODATA: nothing outside the zone within the margin */
        out->loc.has_second = 0;
        out->loc.second_x = best.x;
        out->loc.second_y = best.y;
        out->loc.ll_second = out->loc.ll_best;
        out->loc.failure_probability = 0.0;
    }
    (void)sk;
    return fit_st == TRN_OK ? TRN_OK : TRN_E_ILLCOND;
}
