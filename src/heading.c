/* SPDX-License-Identifier: Apache-2.0 */
/* heading.c - localization over (x, y, heading) (see trn/heading.h). */
#include "trn/heading.h"

#include <math.h>
#include <stdlib.h>

#include "ws.h"

/* Largest |x|, |y| of a point turned: sqrt(2) x 16383 < 32767. */
#define HEADING_MAX_OFFSET 16383

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
        if (in[i].x > HEADING_MAX_OFFSET || in[i].x < -HEADING_MAX_OFFSET || in[i].y > HEADING_MAX_OFFSET ||
            in[i].y < -HEADING_MAX_OFFSET) {
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

/* The workspace: the turned points, the 27 ln L of the fit (kept off the
 * stack), then trn_search_bb's workspace. */
static size_t heading_carve(const trn_map_t *map, size_t n, const trn_window_t *win, void *base,
                            trn_point_t **buf, double **ll, void **search, size_t *search_bytes)
{
    trn_ws_t w;
    size_t sw = trn_localize_workspace_bytes(map, win);
    if (sw == 0u || n == 0u || n > (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_ZBINS) {
        return 0u;
    }
    trn_ws_begin(&w, base);
    *buf = (trn_point_t *)trn_ws_take(&w, n * sizeof(trn_point_t));
    *ll = (double *)trn_ws_take(&w, 27u * sizeof(double));
    *search = trn_ws_take(&w, sw);
    *search_bytes = sw;
    return w.total;
}

size_t trn_localize_heading_workspace_bytes(const trn_map_t *map, size_t n, const trn_window_t *win)
{
    trn_point_t *buf;
    double *ll;
    void *search;
    size_t sb;
    return heading_carve(map, n, win, NULL, &buf, &ll, &search, &sb);
}

/* k of the i-th heading searched: 0, -1, 1, -2, 2, ... */
static int32_t step_of(int32_t i) { return (i % 2 == 1) ? -(i + 1) / 2 : i / 2; }

/* The points turned to heading step k, ordered for the search. */
static trn_status_t turn(const trn_point_t *pts, size_t n, const trn_heading_cfg_t *cfg, double step,
                         int32_t k, int32_t nz, trn_point_t *buf)
{
    trn_status_t st = trn_points_rotate(pts, n, cfg->center_rad + (double)k * step, buf);
    if (st == TRN_OK) {
        st = trn_points_order(buf, n, nz);
    }
    return st;
}

/* Add a search's work to the result's counters. */
static void add_stats(trn_search_stats_t *sum, const trn_search_stats_t *s)
{
    sum->poses_scored += s->poses_scored;
    sum->blocks_bounded += s->blocks_bounded;
}

/* The best pose over every heading, each searched above the best so far;
 * with ex, poses within ex of headings |k - ex_k| <= ex_steps are skipped. */
static trn_status_t search_all(const trn_map_t *map, const trn_point_t *pts, size_t n, const trn_window_t *win,
                               const trn_heading_cfg_t *cfg, double step, int32_t kk, const trn_exclusion_t *ex,
                               int32_t ex_k, int32_t ex_steps, trn_point_t *buf, void *sws, size_t swb,
                               trn_best_t *best, int32_t *best_k, trn_search_stats_t *stats)
{
    int32_t i;
    int found = 0;
    for (i = 0; i <= 2 * kk; ++i) {
        const int32_t k = step_of(i);
        const trn_exclusion_t *e = (ex != NULL && abs(k - ex_k) <= ex_steps) ? ex : NULL;
        trn_search_stats_t s = {0u, 0u};
        trn_best_t b;
        trn_status_t st = turn(pts, n, cfg, step, k, map->dist.nz, buf);
        if (st != TRN_OK) {
            return st;
        }
        if (!found) {
            st = trn_search_bb(&map->pyr, &map->lnp, buf, n, win, e, sws, swb, &b, &s);
        } else {
            st = trn_search_bb_above(&map->pyr, &map->lnp, buf, n, win, e, best->score, sws, swb, &b, &s);
        }
        add_stats(stats, &s);
        if (st == TRN_OK) {
            *best = b;
            *best_k = k;
            found = 1;
        } else if (st != TRN_E_NODATA) {
            return st;
        }
    }
    return found ? TRN_OK : TRN_E_NODATA;
}

/* ln L, nats, on the 3 x 3 x 3 grid around (x, y, k). */
static trn_status_t grid27(const trn_map_t *map, const trn_point_t *pts, size_t n, const trn_heading_cfg_t *cfg,
                           double step, int32_t x, int32_t y, int32_t k, trn_point_t *buf, double ll[27])
{
    int32_t dk, i;
    for (dk = -1; dk <= 1; ++dk) {
        trn_status_t st = trn_points_rotate(pts, n, cfg->center_rad + (double)(k + dk) * step, buf);
        if (st != TRN_OK) {
            return st;
        }
        for (i = 0; i < 9; ++i) {
            int64_t s;
            if ((st = trn_score_pose(&map->dist, &map->lnp, buf, n, x + i % 3 - 1, y + i / 3 - 1, &s)) != TRN_OK) {
                return st;
            }
            ll[(dk + 1) * 9 + i] = (double)s / (double)TRN_LNP_SCALE;
        }
    }
    return TRN_OK;
}

/* W = 0: trn_localize_points on the points turned by the centre. */
static trn_status_t fixed_heading(const trn_map_t *map, const trn_point_t *pts, size_t n, const trn_window_t *win,
                                  const trn_heading_cfg_t *cfg, trn_point_t *buf, void *sws, size_t swb,
                                  trn_heading_result_t *out)
{
    trn_status_t st = trn_points_rotate(pts, n, cfg->center_rad, buf);
    int32_t i;
    if (st != TRN_OK) {
        return st;
    }
    st = trn_localize_points(map, buf, n, win, sws, swb, &out->loc);
    if (st != TRN_OK && st != TRN_E_ILLCOND) {
        return st;
    }
    out->heading_rad = cfg->center_rad;
    out->sigma_heading_rad = 0.0;
    for (i = 0; i < 9; ++i) {
        out->cov3[i] = 0.0;
    }
    out->cov3[0] = out->loc.cov_m2[0];
    out->cov3[4] = out->loc.cov_m2[1];
    out->cov3[1] = out->cov3[3] = out->loc.cov_m2[2];
    out->best_step = 0;
    out->exclusion_steps = 0;
    return st;
}

trn_status_t trn_localize_points_heading(const trn_map_t *map, const trn_point_t *pts, size_t n,
                                         const trn_window_t *win, const trn_heading_cfg_t *cfg,
                                         void *ws, size_t ws_bytes, trn_heading_result_t *out)
{
    trn_status_t st, fit_st;
    trn_point_t *buf;
    void *sws;
    size_t swb, need;
    double step, cell, *ll;
    int32_t kk, bk = 0, rk = 1, r, sk = 0;
    trn_best_t best, second;
    trn_exclusion_t ex;
    trn_peak3_t pk;
    trn_search_stats_t stats = {0u, 0u}, s2 = {0u, 0u};

    if (map == NULL || pts == NULL || win == NULL || cfg == NULL || ws == NULL || out == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_heading_steps(pts, n, cfg, &step, &kk)) != TRN_OK) {
        return st;
    }
    if (win->x0 > win->x1 || win->y0 > win->y1 || win->x0 < 0 || win->y0 < 0 || win->x1 >= map->dist.nx ||
        win->y1 >= map->dist.ny) {
        return TRN_E_RANGE;
    }
    need = heading_carve(map, n, win, NULL, &buf, &ll, &sws, &swb);
    if (need == 0u) {
        return TRN_E_ARG;
    }
    if ((st = trn_ws_check(ws, ws_bytes, need)) != TRN_OK) {
        return st;
    }
    (void)heading_carve(map, n, win, ws, &buf, &ll, &sws, &swb);
    out->step_rad = step;
    out->half_steps = kk;
    if (kk == 0) {
        return fixed_heading(map, pts, n, win, cfg, buf, sws, swb, out);
    }

    /* the best (x, y, heading): exact, each heading above the best so far */
    if ((st = search_all(map, pts, n, win, cfg, step, kk, NULL, 0, 0, buf, sws, swb, &best, &bk, &stats)) != TRN_OK) {
        return st;
    }
    out->loc.refined = 0;
    out->loc.misfit = 0;
    out->loc.ix = best.x;
    out->loc.iy = best.y;
    out->loc.ll_best = (double)best.score / (double)TRN_LNP_SCALE;
    out->loc.n_points = n;
    out->loc.on_window_edge = (best.x == win->x0 || best.x == win->x1 || best.y == win->y0 || best.y == win->y1 ||
                               bk == -kk || bk == kk) ? 1 : 0;
    out->best_step = bk;

    /* eq. 6 in (x, y, heading) */
    if ((st = grid27(map, pts, n, cfg, step, best.x, best.y, bk, buf, ll)) != TRN_OK) {
        return st;
    }
    fit_st = trn_peak_fit3(ll, &pk);
    cell = (double)map->cfg.terrain.cell_m;
    {
        const double sc[3] = {cell, cell, step};
        int32_t i;
        for (i = 0; i < 9; ++i) {
            out->cov3[i] = pk.cov[i] * sc[i / 3] * sc[i % 3];
        }
    }
    out->loc.x = (double)best.x + pk.d[0];
    out->loc.y = (double)best.y + pk.d[1];
    out->heading_rad = cfg->center_rad + ((double)bk + pk.d[2]) * step;
    out->sigma_heading_rad = pk.sigma[2] * step;
    out->loc.sigma_x_m = pk.sigma[0] * cell;
    out->loc.sigma_y_m = pk.sigma[1] * cell;
    out->loc.rho = (fit_st == TRN_OK) ? pk.cov[1] / (pk.sigma[0] * pk.sigma[1]) : 0.0;
    out->loc.cov_m2[0] = out->cov3[0];
    out->loc.cov_m2[1] = out->cov3[4];
    out->loc.cov_m2[2] = out->cov3[1];

    /* the competitor: the best pose outside ~4 sigma of the peak in (x, y, heading) */
    r = map->cfg.min_exclusion_cells;
    if (fit_st == TRN_OK) {
        const double smax = pk.sigma[0] > pk.sigma[1] ? pk.sigma[0] : pk.sigma[1];
        if (4.0 * smax > (double)r) {
            r = 4.0 * smax < (double)TRN_MAX_DIM ? (int32_t)ceil(4.0 * smax) : TRN_MAX_DIM;
        }
        if (4.0 * pk.sigma[2] > (double)rk) {
            rk = 4.0 * pk.sigma[2] < (double)TRN_MAX_HEADING_STEPS ? (int32_t)ceil(4.0 * pk.sigma[2])
                                                                 : TRN_MAX_HEADING_STEPS;
        }
    }
    ex.cx = best.x;
    ex.cy = best.y;
    ex.radius = r;
    out->loc.exclusion_cells = r;
    out->exclusion_steps = rk;
    st = search_all(map, pts, n, win, cfg, step, kk, &ex, bk, rk, buf, sws, swb, &second, &sk, &s2);
    out->loc.stats = stats; /* the first search's work, as trn_localize_points */
    if (st == TRN_OK) {
        out->loc.has_second = 1;
        out->loc.second_x = second.x;
        out->loc.second_y = second.y;
        out->loc.ll_second = (double)second.score / (double)TRN_LNP_SCALE;
        if ((st = trn_failure_probability(out->loc.ll_best, out->loc.ll_second,
                                          &out->loc.failure_probability)) != TRN_OK) {
            return st;
        }
    } else if (st == TRN_E_NODATA) {
        out->loc.has_second = 0;
        out->loc.second_x = best.x;
        out->loc.second_y = best.y;
        out->loc.ll_second = out->loc.ll_best;
        out->loc.failure_probability = 0.0;
    } else {
        return st;
    }
    (void)sk;
    return fit_st == TRN_OK ? TRN_OK : TRN_E_ILLCOND;
}
