/* SPDX-License-Identifier: Apache-2.0 */
/* test_height_bound.c - the height matcher's bounded search (src/height_bound.c,
 * trn_map_cfg_t.search; docs/method.md 9, "The bounded search").
 *
 * Oracles:
 * - the bound itself: after trn_hb_resolve(t), every pose left unscored has an
 *   exact ln L (the exhaustive search's, scored here one by one) below t, on
 *   rough, smooth, flat and periodic maps, at thresholds from the best down;
 * - its masses: trn_hb_mass's ln sums against the exhaustive grid's, within
 *   the error it states;
 * - the whole localization: trn_localize_dem with TRN_SEARCH_BOUNDED against
 *   TRN_SEARCH_EXHAUSTIVE on the same case, every field: status, integer and
 *   refined pose, ln L, competitor, edge flag and noise scale identical, the
 *   covariance within 1e-9 relative, the failure probability within the
 *   stated failure_prob_bound (at most 1e-3); over 48 seeded cases of six
 *   kinds (rough bumps with noise, a decoy, a flat map, a periodic map, a
 *   local map of 9 cells, holes and a window at the map's edge);
 * - the node budget: a budget below the search's work gives TRN_E_BUDGET,
 *   one above it the same answer as none;
 * - bad input: a search other than the two is refused by trn_map_cfg_check,
 *   and a workspace sized for the exhaustive search is too small.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "height_bound.h"
#include "refine_int.h"
#include "rng.h"
#include "trn/localize.h"
#include "trn/refine.h"

#define GW 64
#define LR 6
#define LW (2 * LR + 1)
#define MAXPTS 4096

enum { K_ROUGH, K_DECOY, K_FLAT, K_PERIODIC, K_TINY, K_HOLES, K_KINDS };

static float g_data[GW * GW];
static float l_data[LW * LW];

static void make_map(int kind, uint64_t seed)
{
    trn_rng_t r;
    int k, x, y;
    trn_rng_seed(&r, seed);
    for (y = 0; y < GW; ++y) {
        for (x = 0; x < GW; ++x) {
            double v = 0.01 * x - 0.02 * y;
            if (kind == K_FLAT) {
                v = 0.001 * trn_rng_gauss(&r);
            } else if (kind == K_PERIODIC) {
                v = 0.3 * sin(6.283185307179586 * x / 4.0) * cos(6.283185307179586 * y / 4.0);
            }
            g_data[y * GW + x] = (float)v;
        }
    }
    if (kind == K_FLAT || kind == K_PERIODIC) {
        return;
    }
    for (k = 0; k < 400; ++k) {
        double cx = trn_rng_unit(&r) * GW, cy = trn_rng_unit(&r) * GW;
        double s = 0.8 + 1.5 * trn_rng_unit(&r), h = 0.2 + 0.8 * trn_rng_unit(&r);
        for (y = 0; y < GW; ++y) {
            for (x = 0; x < GW; ++x) {
                double d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
                if (d2 < 25.0 * s * s) {
                    g_data[y * GW + x] += (float)(h * exp(-0.5 * d2 / (s * s)));
                }
            }
        }
    }
    if (kind == K_HOLES) {
        for (k = 0; k < 60; ++k) {
            g_data[(int)(trn_rng_unit(&r) * GW) * GW + (int)(trn_rng_unit(&r) * GW)] = NAN;
        }
    }
}

static double bilin(double x, double y)
{
    int x0 = (int)floor(x), y0 = (int)floor(y);
    double fx = x - x0, fy = y - y0;
    const float *p;
    if (x0 < 0 || y0 < 0 || x0 + 1 >= GW || y0 + 1 >= GW) {
        return NAN;
    }
    p = &g_data[y0 * GW + x0];
    return (1.0 - fy) * ((1.0 - fx) * p[0] + fx * p[1]) +
           fy * ((1.0 - fx) * p[GW] + fx * p[GW + 1]);
}

/* The local map seen from (tx, ty), with noise sd and an offset of 2 m;
 * tiny: a 3 x 3 patch only. */
static void make_local(double tx, double ty, double sd, int tiny, trn_rng_t *r, trn_grid_f32_t *l)
{
    int i, j;
    for (j = 0; j < LW; ++j) {
        for (i = 0; i < LW; ++i) {
            const int dx = i - LR, dy = j - LR;
            double v = bilin(tx + dx, ty + dy);
            if ((dx == 0 && dy == 0) || dx * dx + dy * dy > LR * LR ||
                (tiny && (abs(dx - 2) > 1 || abs(dy - 1) > 1))) {
                v = NAN;
            }
            l_data[j * LW + i] = isfinite(v) ? (float)(v + 2.0 + sd * trn_rng_gauss(r)) : NAN;
        }
    }
    assert_int_equal(trn_grid_f32_init(l, l_data, LW * LW, LW, LW), TRN_OK);
}

typedef struct {
    trn_map_t map;
    void *buf;
} world_t;

static void build(world_t *w, trn_grid_f32_t *g, int noise_auto)
{
    trn_map_cfg_t cfg;
    size_t ab, mb;
    void *aws;
    double sh;
    assert_int_equal(trn_grid_f32_init(g, g_data, GW * GW, GW, GW), TRN_OK);
    ab = trn_map_cfg_auto_workspace_bytes(GW, GW);
    aws = malloc(ab);
    assert_non_null(aws);
    trn_map_cfg_default(&cfg);
    cfg.noise_m = 0.01f;
    cfg.noise_k_per_m = 0.0004f;
    assert_int_equal(trn_map_cfg_auto(&cfg, g, 1.0f, aws, ab, &sh), TRN_OK);
    free(aws);
    cfg.noise_auto = noise_auto;
    assert_int_equal(cfg.search, TRN_SEARCH_EXHAUSTIVE); /* the default */
    mb = trn_map_bytes(&cfg, GW, GW);
    w->buf = malloc(mb);
    assert_non_null(w->buf);
    assert_int_equal(trn_map_build(&w->map, &cfg, g, w->buf, mb), TRN_OK);
}

static trn_status_t run(world_t *w, int32_t search, uint32_t budget, const trn_grid_f32_t *l,
                        int32_t rx, int32_t ry, const trn_window_t *win, trn_loc_result_t *res)
{
    size_t wb;
    void *ws;
    trn_status_t st;
    w->map.cfg.search = search;
    w->map.cfg.node_budget = budget;
    wb = trn_localize_dem_workspace_bytes(&w->map, l->width, l->height, MAXPTS, win);
    assert_true(wb > 0u);
    ws = malloc(wb);
    assert_non_null(ws);
    memset(res, 0, sizeof *res);
    st = trn_localize_dem(&w->map, l, rx, ry, MAXPTS, win, ws, wb, res);
    free(ws);
    return st;
}

static void near_rel(double a, double b, double rel)
{
    if (isinf(a) || isinf(b) || isnan(a) || isnan(b)) {
        assert_true(a == b || (isnan(a) && isnan(b)));
        return;
    }
    assert_true(fabs(a - b) <= rel * fmax(fabs(a), fabs(b)) + 1e-300);
}

/* Bounded against exhaustive on one case: every field. Returns the
 * exhaustive status. */
static trn_status_t compare(world_t *w, const trn_grid_f32_t *l, int32_t rx, int32_t ry,
                            const trn_window_t *win, uint64_t *evals)
{
    trn_loc_result_t e, b;
    const trn_status_t se = run(w, TRN_SEARCH_EXHAUSTIVE, 0u, l, rx, ry, win, &e);
    const trn_status_t sb = run(w, TRN_SEARCH_BOUNDED, 0u, l, rx, ry, win, &b);
    int i;
    assert_int_equal(sb, se);
    if (se != TRN_OK && se != TRN_E_ILLCOND && se != TRN_E_AMBIGUOUS) {
        return se;
    }
    assert_int_equal(e.search, TRN_SEARCH_EXHAUSTIVE);
    assert_int_equal(b.search, TRN_SEARCH_BOUNDED);
    assert_int_equal(b.ix, e.ix);
    assert_int_equal(b.iy, e.iy);
    assert_true(b.x == e.x && b.y == e.y);
    assert_true(b.ll_best == e.ll_best);
    assert_int_equal(b.has_second, e.has_second);
    if (e.has_second) {
        assert_int_equal(b.second_x, e.second_x);
        assert_int_equal(b.second_y, e.second_y);
        assert_true(b.ll_second == e.ll_second);
    }
    assert_int_equal(b.on_window_edge, e.on_window_edge);
    assert_int_equal(b.refined, e.refined);
    assert_int_equal(b.misfit, e.misfit);
    assert_true(b.noise_scale == e.noise_scale);
    assert_int_equal(b.exclusion_cells, e.exclusion_cells);
    assert_true(b.n_points == e.n_points);
    for (i = 0; i < 3; ++i) {
        near_rel(b.cov_m2[i], e.cov_m2[i], 1e-9);
    }
    near_rel(b.sigma_x_m, e.sigma_x_m, 1e-9);
    near_rel(b.sigma_y_m, e.sigma_y_m, 1e-9);
    assert_true(b.refinement.ll == e.refinement.ll || !e.refined);
    assert_true(e.failure_prob_bound == 0.0);
    assert_true(b.failure_prob_bound >= 0.0 && b.failure_prob_bound <= 1e-3);
    assert_true(fabs(b.failure_probability - e.failure_probability) <= b.failure_prob_bound);
    assert_true(b.stats.poses_scored <= e.stats.poses_scored);
    *evals += b.stats.poses_scored;
    return se;
}

static void test_bounded_equals_exhaustive(void **state)
{
    uint64_t evals = 0u, poses = 0u;
    int kind, s, ok = 0, cases = 0;
    (void)state;
    for (kind = 0; kind < K_KINDS; ++kind) {
        for (s = 0; s < 8; ++s) {
            trn_rng_t r;
            trn_grid_f32_t g, l;
            world_t w;
            /* the truth off the prior by up to 3 cells, sub-cell */
            const double tx = 32.0 + 6.0 * ((s * 37 % 11) / 11.0 - 0.5) + 0.3;
            const double ty = 30.0 + 6.0 * ((s * 53 % 13) / 13.0 - 0.5) + 0.6;
            trn_window_t win = {24, 22, 40, 38};
            trn_rng_seed(&r, 1000u * (uint64_t)kind + (uint64_t)s + 1u);
            make_map(kind, 77u * (uint64_t)kind + (uint64_t)s + 5u);
            make_local(tx, ty, kind == K_FLAT ? 0.001 : 0.01, kind == K_TINY, &r, &l);
            if (kind == K_DECOY) { /* the local heights written into the map elsewhere */
                int i, j;
                for (j = 0; j < LW; ++j) {
                    for (i = 0; i < LW; ++i) {
                        if (isfinite(l_data[j * LW + i])) {
                            g_data[(26 + j - LR) * GW + 36 + i - LR] = l_data[j * LW + i] - 2.0f +
                                                                       ((i + j) % 2 ? 0.02f
                                                                                    : -0.02f);
                        }
                    }
                }
            }
            if (kind == K_HOLES) { /* the window at the map's edge too */
                win.x0 = 6;
                win.y0 = 6;
                win.x1 = 22;
                win.y1 = 20;
            }
            build(&w, &g, s % 2);
            if (compare(&w, &l, LR, LR, &win, &evals) == TRN_OK) {
                ++ok;
            }
            poses += (uint64_t)(win.x1 - win.x0 + 1) * (uint64_t)(win.y1 - win.y0 + 1);
            ++cases;
            free(w.buf);
        }
    }
    printf("bounded = exhaustive on %d cases (%d ok); scored %llu of %llu poses\n", cases, ok,
           (unsigned long long)evals, (unsigned long long)poses);
    assert_true(ok >= 8); /* the comparison is not of failures only */
}

/* Every pose the bound leaves out at t scores below t, exactly, with the
 * noise scale fitted (fit 1: the bound takes every scale the fit allows)
 * and without. */
static void test_bound_holds(void **state)
{
    static const double k_drops[5] = {10.0, 50.0, 210.0, 850.0, 3410.0};
    double worst = 0.0;
    int t, k;
    (void)state;
    for (t = 0; t < 2 * K_KINDS; ++t) {
        const int fit = t / K_KINDS, kind = t % K_KINDS;
        trn_rng_t r;
        trn_grid_f32_t g, l;
        trn_refine_cfg_t rc;
        const trn_window_t win = {20, 20, 44, 42};
        const size_t poses = 25u * 23u;
        const size_t hbb = trn_hb_bytes(&win, LW, LW);
        double *grid = malloc(poses * sizeof(double)), best = -INFINITY;
        void *ws = malloc(hbb);
        uint64_t work = 0u;
        trn_hb_t *hb = NULL;
        trn_height_best_t hbest;
        size_t i, left = 0u;
        assert_non_null(grid);
        assert_non_null(ws);
        trn_rng_seed(&r, (uint64_t)kind + 40u);
        make_map(kind, (uint64_t)kind + 90u);
        make_local(31.4, 30.7, 0.01, kind == K_TINY, &r, &l);
        assert_int_equal(trn_grid_f32_init(&g, g_data, GW * GW, GW, GW), TRN_OK);
        rc.cell_m = 1.0f;
        rc.noise_m = 0.01f;
        rc.noise_k_per_m = 0.0004f;
        rc.inlier_prob = 0.95f;
        rc.fit_noise = fit;
        rc.centroid_x = NULL; /* the cells' centres */
        rc.centroid_y = NULL;
        rc.point_count = NULL; /* one measurement a cell */
        assert_int_equal(
            trn_height_search(&g, &l, LR, LR, &win, NULL, &rc, 0.95f, 1.0, grid, &hbest), TRN_OK);
        for (i = 0; i < poses; ++i) {
            best = fmax(best, grid[i]);
        }
        for (k = 0; k < 5; ++k) { /* 10, 50, 210, 850 and 3410 nats below the best */
            const double drop = k_drops[k];
            double *lazy = malloc(poses * sizeof(double));
            assert_non_null(lazy);
            assert_int_equal(
                trn_hb_init(&hb, ws, &g, &l, LR, LR, &win, &rc, 0.95f, lazy, &work, 0u), TRN_OK);
            assert_int_equal(trn_hb_resolve(hb, best - drop, NULL), TRN_OK);
            for (i = 0; i < poses; ++i) {
                if (hb->done[i]) {
                    /* the scorer (height_score.c) against the reference */
                    worst = fmax(worst, fabs(lazy[i] - grid[i]) / fabs(grid[i]));
                    assert_true(fabs(lazy[i] - grid[i]) <= 1e-12 * fabs(grid[i]));
                } else {
                    assert_true(grid[i] < best - drop);
                    ++left;
                }
            }
            free(lazy);
        }
        /* the bound prunes somewhere except where nothing can (with the
         * noise scale fitted the least scale leaves it little: a pose whose
         * residuals all sit at the offset may score that sharp) */
        if (fit == 0 && (kind == K_ROUGH || kind == K_DECOY)) {
            assert_true(left > 0u);
        }
        free(grid);
        free(ws);
    }
    printf("scorer against the reference: worst ln L difference %.1e (relative)\n", worst);
}

/* trn_hb_mass: the window's masses within the stated error. */
static void test_mass_within_bound(void **state)
{
    trn_rng_t r;
    trn_grid_f32_t g, l;
    trn_refine_cfg_t rc;
    const trn_window_t win = {22, 20, 42, 40};
    const trn_exclusion_t ex = {31, 30, 1};
    const size_t poses = 21u * 21u;
    const size_t hbb = trn_hb_bytes(&win, LW, LW);
    double *grid = malloc(poses * sizeof(double)), *lazy = malloc(poses * sizeof(double));
    void *ws = malloc(hbb);
    trn_height_best_t m;
    trn_hb_t *hb = NULL;
    uint64_t work = 0u;
    static const double k_infl[3] = {1.0, 8.0, 64.0};
    double la, lo, err;
    int k;
    (void)state;
    assert_non_null(grid);
    assert_non_null(lazy);
    assert_non_null(ws);
    trn_rng_seed(&r, 3u);
    make_map(K_ROUGH, 11u);
    make_local(31.2, 30.1, 0.01, 0, &r, &l);
    assert_int_equal(trn_grid_f32_init(&g, g_data, GW * GW, GW, GW), TRN_OK);
    rc.cell_m = 1.0f;
    rc.noise_m = 0.01f;
    rc.noise_k_per_m = 0.0004f;
    rc.inlier_prob = 0.95f;
    rc.fit_noise = 1;
    rc.centroid_x = NULL; /* the cells' centres */
    rc.centroid_y = NULL;
    rc.point_count = NULL; /* one measurement a cell */
    assert_int_equal(trn_height_search(&g, &l, LR, LR, &win, NULL, &rc, 0.95f, 1.0, grid, &m),
                     TRN_OK);
    for (k = 0; k < 3; ++k) { /* ln L over 1, 8 and 64 */
        const double infl = k_infl[k];
        trn_height_best_t e;
        assert_int_equal(trn_height_mass(grid, &win, &ex, infl, &e), TRN_OK);
        assert_int_equal(trn_hb_init(&hb, ws, &g, &l, LR, LR, &win, &rc, 0.95f, lazy, &work, 0u),
                         TRN_OK);
        assert_int_equal(trn_hb_eval_zone(hb, ex.cx, ex.cy, ex.radius), TRN_OK);
        assert_int_equal(trn_hb_mass(hb, &ex, infl, 1e-4, &la, &lo, &err), TRN_OK);
        assert_true(err >= 0.0 && err <= 1e-4);
        assert_true(fabs(exp(lo - la) - exp(e.lse_out - e.lse_all)) <= err + 1e-12);
        assert_true(la >= e.lse_all - 1e-9); /* the unscored mass is bounded from above */
    }
    free(grid);
    free(lazy);
    free(ws);
}

/* The internal entry points' edges: bad sizes, too few seen cells, a local
 * map off the map at every pose, the budget, an empty mass, the basins'
 * slot count clamped. */
static void test_hb_edges(void **state)
{
    static const trn_window_t bad[] = {
        {5, 0, 4, 3}, {0, 5, 3, 4}, {0, 0, TRN_MAX_DIM, 3}, {0, 0, 3, TRN_MAX_DIM}};
    const trn_window_t win = {26, 26, 36, 34};
    const size_t poses = 11u * 9u;
    trn_rng_t r;
    trn_grid_f32_t g, l, few;
    trn_refine_cfg_t rc;
    trn_height_best_t hb_best, ex_best;
    trn_hb_t *hb = NULL;
    float few_data[LW * LW];
    double *grid = malloc(poses * sizeof(double)), *lazy = malloc(poses * sizeof(double));
    double la, lo, err;
    const size_t hbb = trn_hb_bytes(&win, LW, LW);
    void *ws = malloc(hbb);
    uint64_t work = 0u;
    size_t i;
    (void)state;
    assert_non_null(grid);
    assert_non_null(lazy);
    assert_non_null(ws);
    /* sizes refused */
    assert_true(trn_hb_bytes(NULL, LW, LW) == 0u);
    for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        assert_true(trn_hb_bytes(&bad[i], LW, LW) == 0u);
    }
    assert_true(trn_hb_bytes(&win, 0, LW) == 0u);
    assert_true(trn_hb_bytes(&win, LW, 0) == 0u);
    assert_true(trn_hb_bytes(&win, TRN_MAX_DIM + 1, LW) == 0u);
    assert_true(trn_hb_bytes(&win, LW, TRN_MAX_DIM + 1) == 0u);
    trn_rng_seed(&r, 77u);
    make_map(K_ROUGH, 31u);
    make_local(31.3, 30.2, 0.01, 0, &r, &l);
    assert_int_equal(trn_grid_f32_init(&g, g_data, GW * GW, GW, GW), TRN_OK);
    rc.cell_m = 1.0f;
    rc.noise_m = 0.01f;
    rc.noise_k_per_m = 0.0004f;
    rc.inlier_prob = 0.95f;
    rc.fit_noise = 1;
    rc.centroid_x = NULL; /* the cells' centres */
    rc.centroid_y = NULL;
    rc.point_count = NULL; /* one measurement a cell */
    assert_int_equal(trn_hb_init(&hb, ws, &g, &l, LR, LR, &bad[0], &rc, 0.95f, lazy, &work, 0u),
                     TRN_E_RANGE);
    /* fewer than 8 seen cells: the exhaustive search's NODATA */
    for (i = 0; i < (size_t)LW * (size_t)LW; ++i) {
        few_data[i] = i < 5u ? 1.0f : NAN;
    }
    assert_int_equal(trn_grid_f32_init(&few, few_data, LW * LW, LW, LW), TRN_OK);
    assert_int_equal(trn_hb_init(&hb, ws, &g, &few, LR, LR, &win, &rc, 0.95f, lazy, &work, 0u),
                     TRN_E_NODATA);
    /* nothing scored yet: no mass */
    assert_int_equal(trn_hb_init(&hb, ws, &g, &l, LR, LR, &win, &rc, 0.95f, lazy, &work, 0u),
                     TRN_OK);
    assert_int_equal(trn_hb_mass(hb, NULL, 1.0, 1e-4, &la, &lo, &err), TRN_E_NODATA);
    /* the basins with their slot count clamped, both ways */
    assert_int_equal(trn_hb_best(hb, NULL, &hb_best), TRN_OK);
    assert_int_equal(trn_hb_basins(hb, -INFINITY, hb_best.x, hb_best.y, 1, -1), TRN_OK);
    assert_int_equal(trn_hb_basins(hb, -INFINITY, hb_best.x, hb_best.y, 1, 99), TRN_OK);
    /* a budget of 2: the third score is refused, by name */
    work = 0u;
    assert_int_equal(trn_hb_init(&hb, ws, &g, &l, LR, LR, &win, &rc, 0.95f, lazy, &work, 2u),
                     TRN_OK);
    assert_int_equal(trn_hb_eval(hb, 30, 30), TRN_OK);
    assert_int_equal(trn_hb_eval(hb, 31, 30), TRN_OK);
    assert_int_equal(trn_hb_eval(hb, 30, 30), TRN_OK); /* scored already: no work */
    assert_int_equal(trn_hb_eval(hb, 32, 30), TRN_E_BUDGET);
    assert_int_equal(trn_hb_best(hb, NULL, &hb_best), TRN_E_BUDGET);
    /* the local map off the map at every pose (the rover cell far east of
     * it): the same best as the exhaustive search, every cell an outlier */
    work = 0u;
    assert_int_equal(
        trn_height_search(&g, &l, 1000, LR, &win, NULL, &rc, 0.95f, 1.0, grid, &ex_best), TRN_OK);
    assert_int_equal(trn_hb_init(&hb, ws, &g, &l, 1000, LR, &win, &rc, 0.95f, lazy, &work, 0u),
                     TRN_OK);
    assert_int_equal(trn_hb_best(hb, NULL, &hb_best), TRN_OK);
    assert_int_equal(hb_best.x, ex_best.x);
    assert_int_equal(hb_best.y, ex_best.y);
    assert_true(hb_best.ll == ex_best.ll);
    free(grid);
    free(lazy);
    free(ws);
}

/* The node budget is a hard bound wherever the work runs out: the least
 * budget that is enough (the status is monotone in the budget) gives the
 * unbudgeted answer, and every budget below it, spread over the stages
 * that count (the search, the best pose's neighbours, the far basins and
 * their zones, the answer's zone and the masses), TRN_E_BUDGET. */
static void budget_sweep(int kind, uint32_t seed)
{
    trn_rng_t r;
    trn_grid_f32_t g, l;
    world_t w;
    trn_loc_result_t a, b;
    const trn_window_t win = {24, 22, 40, 38};
    trn_status_t st;
    uint32_t lo = 1u, hi, k;
    trn_rng_seed(&r, seed);
    make_map(kind, 21u);
    make_local(31.3, 29.8, 0.01, 0, &r, &l);
    build(&w, &g, 1);
    st = run(&w, TRN_SEARCH_BOUNDED, 0u, &l, LR, LR, &win, &a);
    hi = (uint32_t)(4u * (a.stats.poses_scored + a.stats.blocks_bounded) + 100u);
    assert_int_equal(run(&w, TRN_SEARCH_BOUNDED, hi, &l, LR, LR, &win, &b), st);
    assert_int_equal(run(&w, TRN_SEARCH_BOUNDED, lo, &l, LR, LR, &win, &b), TRN_E_BUDGET);
    while (hi - lo > 1u) {
        const uint32_t mid = lo + (hi - lo) / 2u;
        if (run(&w, TRN_SEARCH_BOUNDED, mid, &l, LR, LR, &win, &b) == TRN_E_BUDGET) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    assert_int_equal(run(&w, TRN_SEARCH_BOUNDED, hi, &l, LR, LR, &win, &b), st);
    assert_true(b.x == a.x && b.y == a.y && b.failure_probability == a.failure_probability &&
                b.sigma_x_m == a.sigma_x_m && b.stats.poses_scored == a.stats.poses_scored &&
                b.stats.blocks_bounded == a.stats.blocks_bounded);
    for (k = 0u; k <= 64u; ++k) {
        assert_int_equal(
            run(&w, TRN_SEARCH_BOUNDED, 1u + (hi - 2u) * k / 64u, &l, LR, LR, &win, &b),
            TRN_E_BUDGET);
    }
    free(w.buf);
}

static void test_node_budget(void **state)
{
    trn_rng_t r;
    trn_grid_f32_t g, l;
    world_t w;
    trn_loc_result_t a, b;
    const trn_window_t win = {24, 22, 40, 38};
    uint64_t work;
    (void)state;
    trn_rng_seed(&r, 9u);
    make_map(K_ROUGH, 21u);
    make_local(31.3, 29.8, 0.01, 0, &r, &l);
    build(&w, &g, 1);
    assert_int_equal(run(&w, TRN_SEARCH_BOUNDED, 0u, &l, LR, LR, &win, &a), TRN_OK);
    work = a.stats.poses_scored + a.stats.blocks_bounded;
    assert_true(work > 20u);
    /* too small a budget: the named status */
    assert_int_equal(run(&w, TRN_SEARCH_BOUNDED, 10u, &l, LR, LR, &win, &b), TRN_E_BUDGET);
    /* enough: the same answer (the budget counts both passes of the noise
     * rescale, so give it room) */
    assert_int_equal(
        run(&w, TRN_SEARCH_BOUNDED, (uint32_t)(4u * work + 100u), &l, LR, LR, &win, &b), TRN_OK);
    assert_true(b.x == a.x && b.y == a.y && b.failure_probability == a.failure_probability);
    free(w.buf);
    budget_sweep(K_ROUGH, 21u);
    budget_sweep(K_PERIODIC, 21u);
    budget_sweep(K_DECOY, 5u);
    assert_string_equal(trn_strerror(TRN_E_BUDGET), "search node budget exhausted");
}

static void test_bad_search(void **state)
{
    trn_rng_t r;
    trn_grid_f32_t g, l;
    world_t w;
    trn_map_cfg_t c;
    trn_loc_result_t res;
    const trn_window_t win = {24, 22, 40, 38};
    size_t small;
    void *ws;
    (void)state;
    trn_map_cfg_default(&c);
    assert_int_equal(trn_map_cfg_check(&c), TRN_OK);
    c.search = 2;
    assert_int_equal(trn_map_cfg_check(&c), TRN_E_ARG);
    c.search = -1;
    assert_int_equal(trn_map_cfg_check(&c), TRN_E_ARG);
    /* the bounded search's workspace is larger: one sized for the
     * exhaustive search is refused, nothing written */
    trn_rng_seed(&r, 5u);
    make_map(K_ROUGH, 8u);
    make_local(31.0, 30.0, 0.01, 0, &r, &l);
    build(&w, &g, 0);
    w.map.cfg.search = TRN_SEARCH_EXHAUSTIVE;
    small = trn_localize_dem_workspace_bytes(&w.map, LW, LW, MAXPTS, &win);
    w.map.cfg.search = TRN_SEARCH_BOUNDED;
    assert_true(trn_localize_dem_workspace_bytes(&w.map, LW, LW, MAXPTS, &win) > small);
    ws = malloc(small);
    assert_non_null(ws);
    memset(&res, 0x5a, sizeof res);
    assert_int_equal(trn_localize_dem(&w.map, &l, LR, LR, MAXPTS, &win, ws, small, &res),
                     TRN_E_WORKSPACE);
    assert_true(((const unsigned char *)&res)[0] == 0x5a);
    free(ws);
    free(w.buf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bound_holds),
        cmocka_unit_test(test_mass_within_bound),
        cmocka_unit_test(test_bounded_equals_exhaustive),
        cmocka_unit_test(test_hb_edges),
        cmocka_unit_test(test_node_budget),
        cmocka_unit_test(test_bad_search),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
