/* SPDX-License-Identifier: Apache-2.0 */
/* test_heading.c - localization over (x, y, heading) (trn/heading.h) and its
 * parts: point rotation against the formula, the automatic step, eq. 6 in
 * three dimensions against analytic quadratics, trn_search_bb_above against
 * trn_search_bb, the heading search against the exhaustive search over
 * every (x, y, heading) on seeded rock fields (the best pose and the
 * competitor, also with few points, where many poses are within the
 * margin and the kept poses may not tell the competitor), headings recovered from local
 * maps rendered turned by known angles, W = 0 equal to trn_localize_points,
 * and every bad-input class. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cal3.h"
#include "rng.h"
#include "synth.h"
#include "trn/heading.h"
#include "trn/terrain.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define CELL 0.1
#define N 128 /* global map side, cells */
#define LR 20 /* local map radius, cells */
#define LW (2 * LR + 1)
#define MAXPTS 20000
#define DEG (M_PI / 180.0)

typedef struct {
    float dem[N * N];
    trn_grid_f32_t g;
    trn_map_cfg_t cfg;
    trn_map_t map;
    synth_terrain_t t;
} world_t;

static world_t g_w;
static synth_rock_t g_rocks[2000];
TRN_WORKSPACE_DECLARE(g_mapbuf, 8u << 20);
TRN_WORKSPACE_DECLARE(g_ws, 4u << 20);
TRN_WORKSPACE_DECLARE(g_mapbuf2, 8u << 20);
static trn_point_t g_pts[MAXPTS], g_rot[MAXPTS];

/* A 0.1 m rock field (the paper's terrain, as tests/test_localize.c). */
static void world_build(uint64_t seed, int flat)
{
    size_t nr = (size_t)(N * N * CELL * CELL * 0.15 / (M_PI * 0.15 * 0.15)), mb;
    int i;
    if (nr > sizeof g_rocks / sizeof g_rocks[0]) {
        nr = sizeof g_rocks / sizeof g_rocks[0];
    }
    synth_make(&g_w.t, g_rocks, nr, N * CELL, 0.05, 0.3, 0.5, 0.2, seed);
    synth_render(&g_w.t, g_w.dem, N, N, 0.0, 0.0, CELL);
    if (flat) {
        for (i = 0; i < N * N; ++i) {
            g_w.dem[i] = 1.0f;
        }
    }
    assert_int_equal(trn_grid_f32_init(&g_w.g, g_w.dem, (size_t)N * N, N, N), TRN_OK);
    trn_map_cfg_default(&g_w.cfg);
    mb = trn_map_bytes(&g_w.cfg, N, N);
    assert_true(mb > 0u && mb <= sizeof g_mapbuf);
    assert_int_equal(trn_map_build(&g_w.map, &g_w.cfg, &g_w.g, g_mapbuf, mb), TRN_OK);
}

/* Local points of a full circle of radius LR around the rover at (rx, ry)
 * (map cells, sub-cell), seen with the heading off by delta: local offset o
 * sees the terrain at the map offset turned by delta (trn_points_rotate's
 * convention), so turning the points by delta puts them back. */
static float g_loc[LW * LW];
static double g_noise_m; /* height noise of the local DEM (test_calibration) */
static trn_rng_t g_noise_rng = {12345u};

/* A standard normal draw (Box-Muller). */
static double gauss(void)
{
    const double u = trn_rng_unit(&g_noise_rng) + 1e-12, v = trn_rng_unit(&g_noise_rng);
    return sqrt(-2.0 * log(u)) * cos(2.0 * M_PI * v);
}

static size_t local_points(double rx, double ry, double delta)
{
    static float hp[LW * LW];
    float *loc = g_loc;
    TRN_WORKSPACE_DECLARE(hws, 64u << 10);
    trn_grid_f32_t lg, hg;
    const double c = cos(delta), s = sin(delta);
    size_t np = 0;
    int i, j;
    for (j = -LR; j <= LR; ++j) {
        for (i = -LR; i <= LR; ++i) {
            const double mx = (double)i * c + (double)j * s, my = -(double)i * s + (double)j * c;
            loc[(j + LR) * LW + (i + LR)] = (i * i + j * j <= LR * LR)
                                                ? (float)(synth_height(&g_w.t, (rx + mx) * CELL,
                                                                       (ry + my) * CELL) +
                                                          g_noise_m * gauss())
                                                : NAN;
        }
    }
    assert_int_equal(trn_grid_f32_init(&lg, loc, LW * LW, LW, LW), TRN_OK);
    assert_int_equal(trn_grid_f32_init(&hg, hp, LW * LW, LW, LW), TRN_OK);
    assert_true(trn_highpass_workspace_bytes(LW, LW) <= sizeof hws);
    assert_int_equal(trn_highpass(&lg, &g_w.cfg.terrain, &hg, hws, sizeof hws), TRN_OK);
    assert_int_equal(trn_occupancy_points(&hg, &g_w.cfg.terrain, LR, LR, g_pts, MAXPTS, &np),
                     TRN_OK);
    return np;
}

static void test_rotate_formula(void **state)
{
    trn_point_t in[64], out[64], same[64];
    trn_rng_t r;
    int i, k;
    (void)state;
    trn_rng_seed(&r, 5);
    for (i = 0; i < 64; ++i) {
        in[i].x = (int16_t)trn_rng_int(&r, -300, 300);
        in[i].y = (int16_t)trn_rng_int(&r, -300, 300);
        in[i].z = (int16_t)trn_rng_int(&r, 0, 20);
    }
    for (k = 0; k < 20; ++k) {
        const double a = (trn_rng_unit(&r) - 0.5) * 2.0 * M_PI;
        assert_int_equal(trn_points_rotate(in, 64, a, out), TRN_OK);
        for (i = 0; i < 64; ++i) {
            const double x = in[i].x * cos(a) + in[i].y * sin(a),
                         y = -in[i].x * sin(a) + in[i].y * cos(a);
            assert_true(fabs(out[i].x - x) <= 0.5 + 1e-9 && fabs(out[i].y - y) <= 0.5 + 1e-9);
            assert_int_equal(out[i].z, in[i].z);
        }
        memcpy(same, in, sizeof same); /* in place */
        assert_int_equal(trn_points_rotate(same, 64, a, same), TRN_OK);
        assert_memory_equal(same, out, sizeof out);
    }
    /* a quarter turn counterclockwise: east goes north (-row), south goes east */
    in[0].x = 10;
    in[0].y = 0;
    in[1].x = 0;
    in[1].y = 10;
    assert_int_equal(trn_points_rotate(in, 2, M_PI / 2, out), TRN_OK);
    assert_int_equal(out[0].x, 0);
    assert_int_equal(out[0].y, -10);
    assert_int_equal(out[1].x, 10);
    assert_int_equal(out[1].y, 0);
    /* bad input */
    assert_int_equal(trn_points_rotate(NULL, 1, 0.1, out), TRN_E_NULL);
    assert_int_equal(trn_points_rotate(in, 1, 0.1, NULL), TRN_E_NULL);
    assert_int_equal(trn_points_rotate(in, 1, NAN, out), TRN_E_ARG);
    assert_int_equal(trn_points_rotate(in, 1, INFINITY, out), TRN_E_ARG);
    in[0].x = 16384;
    assert_int_equal(trn_points_rotate(in, 1, 0.1, out), TRN_E_ARG);
    in[0].x = 0;
    in[0].y = -16384;
    assert_int_equal(trn_points_rotate(in, 1, 0.1, out), TRN_E_ARG);
    in[0].y = 16384;
    assert_int_equal(trn_points_rotate(in, 1, 0.1, out), TRN_E_ARG);
    in[0].x = -16384;
    in[0].y = 0;
    assert_int_equal(trn_points_rotate(in, 1, 0.1, out), TRN_E_ARG);
    in[0].x = 16383;
    in[0].y = -16383; /* the largest offsets turn within int16_t */
    assert_int_equal(trn_points_rotate(in, 1, 0.7, out), TRN_OK);
}

static void test_steps(void **state)
{
    trn_point_t p[3] = {{3, 4, 0}, {-1, 0, 0}, {0, 2, 1}};
    trn_heading_cfg_t c = {0.0, 0.2, 0.0};
    double step = 0.0;
    int32_t k = -1;
    (void)state;
    assert_int_equal(trn_heading_steps(p, 3, &c, &step, &k), TRN_OK);
    assert_true(fabs(step - 0.2) < 1e-15); /* 1 / r_max, r_max = 5 cells */
    assert_int_equal(k, 1);                /* W = step exactly: one step each side */
    c.window_rad = 0.21;
    assert_int_equal(trn_heading_steps(p, 3, &c, &step, &k), TRN_OK);
    assert_int_equal(k, 2);
    c.window_rad = 0.0;
    assert_int_equal(trn_heading_steps(p, 3, &c, &step, &k), TRN_OK);
    assert_int_equal(k, 0);
    c.window_rad = 0.5;
    c.step_rad = 0.01;
    assert_int_equal(trn_heading_steps(p, 3, &c, &step, &k), TRN_OK);
    assert_true(step == 0.01);
    assert_int_equal(k, 50);
    /* bad input, one class each */
    assert_int_equal(trn_heading_steps(NULL, 3, &c, &step, &k), TRN_E_NULL);
    assert_int_equal(trn_heading_steps(p, 3, NULL, &step, &k), TRN_E_NULL);
    assert_int_equal(trn_heading_steps(p, 3, &c, NULL, &k), TRN_E_NULL);
    assert_int_equal(trn_heading_steps(p, 3, &c, &step, NULL), TRN_E_NULL);
    assert_int_equal(trn_heading_steps(p, 0, &c, &step, &k), TRN_E_NODATA);
    c.center_rad = NAN;
    assert_int_equal(trn_heading_steps(p, 3, &c, &step, &k), TRN_E_ARG);
    c.center_rad = 4.0;
    assert_int_equal(trn_heading_steps(p, 3, &c, &step, &k), TRN_E_ARG);
    c.center_rad = 0.0;
    c.window_rad = -0.1;
    assert_int_equal(trn_heading_steps(p, 3, &c, &step, &k), TRN_E_ARG);
    c.window_rad = 3.2;
    assert_int_equal(trn_heading_steps(p, 3, &c, &step, &k), TRN_E_ARG);
    c.window_rad = 0.5;
    c.step_rad = NAN;
    assert_int_equal(trn_heading_steps(p, 3, &c, &step, &k), TRN_E_ARG);
    c.step_rad = 3.5; /* over a half turn */
    assert_int_equal(trn_heading_steps(p, 3, &c, &step, &k), TRN_E_ARG);
    c.step_rad = 1e-4; /* 10001 headings: too fine */
    assert_int_equal(trn_heading_steps(p, 3, &c, &step, &k), TRN_E_SIZE);
    c.step_rad = 0.0; /* automatic, but no lever arm */
    p[0].x = p[0].y = p[1].x = p[1].y = p[2].x = p[2].y = 0;
    assert_int_equal(trn_heading_steps(p, 3, &c, &step, &k), TRN_E_NODATA);
    c.window_rad = 0.0; /* no lever arm, but no heading searched either */
    assert_int_equal(trn_heading_steps(p, 3, &c, &step, &k), TRN_OK);
    assert_int_equal(k, 0);
}

/* ln L of an analytic quadratic c + g.d - d^T A d / 2 on the 3x3x3 grid. */
static void quad27(const double g[3], const double a[9], double c, double ll[27])
{
    int i, p, q;
    for (i = 0; i < 27; ++i) {
        const double d[3] = {(double)(i % 3 - 1), (double)((i / 3) % 3 - 1), (double)(i / 9 - 1)};
        double v = c;
        for (p = 0; p < 3; ++p) {
            v += g[p] * d[p];
            for (q = 0; q < 3; ++q) {
                v -= 0.5 * d[p] * a[p * 3 + q] * d[q];
            }
        }
        ll[i] = v;
    }
}

static void test_fit3_analytic(void **state)
{
    /* A = precision; the fit must return d = A^-1 g and cov = A^-1 exactly */
    const double a[9] = {4.0, 1.0, 0.5, 1.0, 3.0, -0.4, 0.5, -0.4, 2.0};
    const double truth_d[3] = {0.3, -0.2, 0.45};
    double g[3], ll[27], prod[9];
    trn_peak3_t pk;
    int i, j, k;
    (void)state;
    for (i = 0; i < 3; ++i) {
        g[i] = 0.0;
        for (j = 0; j < 3; ++j) {
            g[i] += a[i * 3 + j] * truth_d[j];
        }
    }
    quad27(g, a, -1234.5, ll);
    assert_int_equal(trn_peak_fit3(ll, &pk), TRN_OK);
    for (i = 0; i < 3; ++i) {
        assert_true(fabs(pk.offset[i] - truth_d[i]) < 1e-9);
        assert_true(fabs(pk.sigma[i] - sqrt(pk.covariance[i * 4])) < 1e-15);
    }
    for (i = 0; i < 3; ++i) { /* cov x A = identity */
        for (j = 0; j < 3; ++j) {
            prod[i * 3 + j] = 0.0;
            for (k = 0; k < 3; ++k) {
                prod[i * 3 + j] += pk.covariance[i * 3 + k] * a[k * 3 + j];
            }
            assert_true(fabs(prod[i * 3 + j] - (i == j ? 1.0 : 0.0)) < 1e-9);
        }
    }
    /* a ridge along the heading axis: no finite covariance */
    {
        const double ridge[9] = {4.0, 1.0, 0.0, 1.0, 3.0, 0.0, 0.0, 0.0, 0.0};
        const double g0[3] = {0.0, 0.0, 0.0};
        quad27(g0, ridge, 10.0, ll);
        assert_int_equal(trn_peak_fit3(ll, &pk), TRN_E_ILLCOND);
        assert_true(isinf(pk.sigma[2]) && pk.offset[0] == 0.0);
    }
    /* a peak outside the grid (offset 1.5 along x) */
    {
        const double id[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
        const double g1[3] = {1.5, 0.0, 0.0};
        quad27(g1, id, 0.0, ll);
        assert_int_equal(trn_peak_fit3(ll, &pk), TRN_E_ILLCOND);
    }
    /* a bowl (minimum, not maximum) */
    {
        const double neg[9] = {-1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0};
        const double g0[3] = {0.0, 0.0, 0.0};
        quad27(g0, neg, 0.0, ll);
        assert_int_equal(trn_peak_fit3(ll, &pk), TRN_E_ILLCOND);
        quad27(g0, a, 0.0, ll);
        ll[0] = 2e300; /* overflow guard */
        assert_int_equal(trn_peak_fit3(ll, &pk), TRN_E_ILLCOND);
    }
    quad27(g, a, 0.0, ll);
    ll[5] = NAN;
    assert_int_equal(trn_peak_fit3(ll, &pk), TRN_E_ARG);
    ll[5] = -INFINITY;
    assert_int_equal(trn_peak_fit3(ll, &pk), TRN_E_ARG);
    assert_int_equal(trn_peak_fit3(NULL, &pk), TRN_E_NULL);
    assert_int_equal(trn_peak_fit3(ll, NULL), TRN_E_NULL);
}

static void test_search_bb_above(void **state)
{
    trn_window_t win = {40, 40, 80, 80};
    trn_best_t b, ba;
    trn_search_stats_t s;
    size_t np, wb;
    (void)state;
    world_build(3, 0);
    np = local_points(60.3, 61.6, 0.0);
    wb = trn_search_bb_workspace_bytes(&g_w.map.pyr, &win);
    assert_true(wb > 0u && wb <= sizeof g_ws);
    assert_int_equal(
        trn_search_bb(&g_w.map.pyr, &g_w.map.lnp, g_pts, np, &win, NULL, g_ws, wb, &b, NULL),
        TRN_OK);
    /* just below the best: the same pose; at or above it: none */
    assert_int_equal(trn_search_bb_above(&g_w.map.pyr, &g_w.map.lnp, g_pts, np, &win, NULL,
                                         b.score - 1, g_ws, wb, &ba, &s),
                     TRN_OK);
    assert_int_equal(ba.x, b.x);
    assert_int_equal(ba.y, b.y);
    assert_true(ba.score == b.score);
    ba.x = -7;
    assert_int_equal(trn_search_bb_above(&g_w.map.pyr, &g_w.map.lnp, g_pts, np, &win, NULL, b.score,
                                         g_ws, wb, &ba, NULL),
                     TRN_E_NODATA);
    assert_int_equal(ba.x, -7); /* untouched */
    assert_int_equal(trn_search_bb_above(&g_w.map.pyr, &g_w.map.lnp, g_pts, np, &win, NULL,
                                         INT64_MIN, g_ws, wb, &ba, NULL),
                     TRN_OK);
    assert_int_equal(ba.x, b.x);
    assert_int_equal(trn_search_bb_above(&g_w.map.pyr, &g_w.map.lnp, g_pts, np, &win, NULL, 0, g_ws,
                                         wb, NULL, NULL),
                     TRN_E_NULL);
    assert_int_equal(trn_search_bb_above(&g_w.map.pyr, &g_w.map.lnp, g_pts, np, &win, NULL, 0, g_ws,
                                         1, &ba, NULL),
                     TRN_E_WORKSPACE);
    { /* the rest as trn_search_bb: a bad exclusion, a window off the map, a volume of no size */
        trn_exclusion_t neg = {60, 60, -1};
        trn_window_t off = {120, 40, 140, 80};
        trn_pyramid_t p = g_w.map.pyr;
        assert_int_equal(trn_search_bb_above(&g_w.map.pyr, &g_w.map.lnp, g_pts, np, &win, &neg, 0,
                                             g_ws, wb, &ba, NULL),
                         TRN_E_ARG);
        assert_int_equal(trn_search_bb_above(&g_w.map.pyr, &g_w.map.lnp, g_pts, np, &off, NULL, 0,
                                             g_ws, wb, &ba, NULL),
                         TRN_E_RANGE);
        p.base.ny = 0;
        assert_int_equal(
            trn_search_bb_above(&p, &g_w.map.lnp, g_pts, np, &win, NULL, 0, g_ws, wb, &ba, NULL),
            TRN_E_SIZE);
    }
}

/* The exhaustive reference: every heading in the search's order, every
 * pose (trn_search_exhaustive), strictly better replaces. */
static void exhaustive3(size_t np, const trn_window_t *win, const trn_heading_cfg_t *c, double step,
                        int32_t kk, trn_best_t *best, int32_t *bk)
{
    int32_t i;
    for (i = 0; i <= 2 * kk; ++i) {
        const int32_t k = (i % 2 == 1) ? -(i + 1) / 2 : i / 2;
        trn_best_t b;
        assert_int_equal(trn_points_rotate(g_pts, np, c->center_rad + k * step, g_rot), TRN_OK);
        assert_int_equal(
            trn_search_exhaustive(&g_w.map.dist, &g_w.map.lnp, g_rot, np, win, NULL, &b, NULL),
            TRN_OK);
        if (i == 0 || b.score > best->score) {
            *best = b;
            *bk = k;
        }
    }
}

/* Tie rank of step k (0, -1, +1, -2, ...: the lower wins a tie). */
static int32_t rank_of(int32_t k) { return k > 0 ? 2 * k : (k < 0 ? -2 * k - 1 : 0); }

/* The competitor by brute force: every pose of every heading outside the
 * zone of res scoring above the best minus the margin, the first in the
 * order (score, tie rank, y, x); checked against res (has_second, pose,
 * ln L, failure probability). */
static void check_second(size_t np, const trn_window_t *win, const trn_heading_cfg_t *c,
                         const trn_heading_result_t *res, int *has)
{
    const int64_t best = (int64_t)llround(res->loc.ll_best * TRN_LNP_SCALE);
    const int64_t floor = best - (int64_t)TRN_HEADING_MARGIN_NATS * TRN_LNP_SCALE;
    const int32_t r = res->loc.exclusion_cells;
    int32_t k, x, y, srank = 0;
    int found = 0;
    trn_best_t sec = {0, 0, 0};
    for (k = -res->half_steps; k <= res->half_steps; ++k) {
        assert_int_equal(
            trn_points_rotate(g_pts, np, c->center_rad + (double)k * res->step_rad, g_rot), TRN_OK);
        for (y = win->y0; y <= win->y1; ++y) {
            for (x = win->x0; x <= win->x1; ++x) {
                int64_t s = 0;
                if (abs(x - res->loc.ix) <= r && abs(y - res->loc.iy) <= r) {
                    continue;
                }
                assert_int_equal(trn_score_pose(&g_w.map.dist, &g_w.map.lnp, g_rot, np, x, y, &s),
                                 TRN_OK);
                if (s <= floor) {
                    continue;
                }
                if (!found || s > sec.score ||
                    (s == sec.score &&
                     (rank_of(k) < srank ||
                      (rank_of(k) == srank && (y < sec.y || (y == sec.y && x < sec.x)))))) {
                    sec.x = x;
                    sec.y = y;
                    sec.score = s;
                    srank = rank_of(k);
                    found = 1;
                }
            }
        }
    }
    assert_int_equal(res->loc.has_second, found);
    *has = found;
    if (found) {
        double pf = -1.0;
        assert_int_equal(res->loc.second_x, sec.x);
        assert_int_equal(res->loc.second_y, sec.y);
        assert_true(res->loc.ll_second == (double)sec.score / (double)TRN_LNP_SCALE);
        assert_int_equal(trn_failure_probability(res->loc.ll_best, res->loc.ll_second, &pf),
                         TRN_OK);
        assert_true(res->loc.failure_probability == pf);
    } else {
        assert_true(res->loc.failure_probability == 0.0);
        assert_true(res->loc.ll_second == res->loc.ll_best);
    }
}

/* The heading search on the first np points against exhaustive3: the same
 * best (x, y, heading step), its ln L (to tol nats; 0: the same double) and
 * the competitor (check_second). */
static void search_vs_exhaustive(size_t np, const trn_window_t *win, const trn_heading_cfg_t *c,
                                 double tol, trn_heading_result_t *res, int *has)
{
    trn_best_t ref = {0, 0, 0};
    int32_t rk = 0;
    size_t wb = trn_localize_heading_workspace_bytes(&g_w.map, np, win);
    trn_status_t st;
    assert_true(wb > 0u && wb <= sizeof g_ws);
    st = trn_localize_points_heading(&g_w.map, g_pts, np, win, c, g_ws, wb, res);
    assert_true(st == TRN_OK || st == TRN_E_ILLCOND);
    exhaustive3(np, win, c, res->step_rad, res->half_steps, &ref, &rk);
    assert_int_equal(res->loc.ix, ref.x);
    assert_int_equal(res->loc.iy, ref.y);
    assert_int_equal(res->best_step, rk);
    assert_true(fabs(res->loc.ll_best - (double)ref.score / TRN_LNP_SCALE) <= tol);
    check_second(np, win, c, res, has);
}

static void test_equals_exhaustive(void **state)
{
    trn_rng_t r;
    int cases, seed, has = 0, n_second = 0;
    uint64_t bb_scored = 0, ex_scored = 0;
    (void)state;
    trn_rng_seed(&r, 77);
    for (seed = 0; seed < 3; ++seed) {
        world_build(11u + (uint64_t)seed, 0);
        for (cases = 0; cases < 8; ++cases) {
            const double rx = 40.0 + 48.0 * trn_rng_unit(&r), ry = 40.0 + 48.0 * trn_rng_unit(&r);
            const double delta = (trn_rng_unit(&r) - 0.5) * 16.0 * DEG;
            const int32_t cx = (int32_t)floor(rx + 0.5) + trn_rng_int(&r, -2, 2);
            const int32_t cy = (int32_t)floor(ry + 0.5) + trn_rng_int(&r, -2, 2);
            trn_window_t win = {cx - 6, cy - 6, cx + 6, cy + 6};
            trn_heading_cfg_t c = {0.0, 10.0 * DEG, 0.0};
            trn_heading_result_t res;
            size_t np = local_points(rx, ry, delta);
            if (cases % 4 == 3) {
                c.center_rad = 3.0 * DEG; /* an off-zero centre */
            }
            search_vs_exhaustive(np, &win, &c, 1e-9, &res, &has);
            n_second += has;
            bb_scored += res.loc.stats.poses_scored;
            ex_scored += (uint64_t)(2 * res.half_steps + 1) * 13u * 13u;
        }
    }
    printf("heading search: %llu exact pose scores against %llu exhaustive (%.3f); %d of 24 with "
           "a competitor within the margin\n",
           (unsigned long long)bb_scored, (unsigned long long)ex_scored,
           (double)bb_scored / (double)ex_scored, n_second);
    assert_true(bb_scored < ex_scored); /* the bound across headings prunes */
}

/* The same with fewer points (every j-th of the local map's, 2 to 600 of
 * them), wider windows and some zones wider than the minimum: many poses
 * within the margin of the best, competitors at other headings, the kept
 * poses full (and then at times all inside the zone: the competitor is
 * searched again). Best pose and competitor against brute force. */
static void test_few_points_exhaustive(void **state)
{
    trn_rng_t r;
    int cases, has = 0, n_second = 0;
    (void)state;
    trn_rng_seed(&r, 1414);
    world_build(21u, 0);
    for (cases = 0; cases < 80; ++cases) {
        const double rx = 40.0 + 48.0 * trn_rng_unit(&r), ry = 40.0 + 48.0 * trn_rng_unit(&r);
        const double delta = (trn_rng_unit(&r) - 0.5) * 12.0 * DEG;
        const int32_t cx = (int32_t)floor(rx + 0.5), cy = (int32_t)floor(ry + 0.5);
        const int32_t lo[4] = {2, 9, 60, 200}, hi[4] = {8, 60, 200, 600};
        const int32_t keep = trn_rng_int(&r, lo[cases % 4], hi[cases % 4]);
        const int32_t w = cases % 4 == 3 ? trn_rng_int(&r, 8, 15) : trn_rng_int(&r, 3, 9);
        trn_window_t win = {cx - w, cy - w, cx + w, cy + w};
        trn_heading_cfg_t c = {0.0, (double)trn_rng_int(&r, 2, 8) * DEG, 0.0};
        trn_heading_result_t res;
        size_t np = local_points(rx, ry, delta), i, m = 0, stride;
        stride = np / (size_t)keep > 0u ? np / (size_t)keep : 1u;
        for (i = (size_t)cases % stride; i < np; i += stride) {
            g_pts[m++] = g_pts[i];
        }
        np = m;
        search_vs_exhaustive(np, &win, &c, 0.0, &res, &has);
        n_second += has;
    }
    printf("fewer points: %d of 80 with a competitor within the margin\n", n_second);
    assert_true(n_second >= 30);
}

static void test_recovers_heading(void **state)
{
    trn_rng_t r;
    int k, n = 0, right = 0;
    double se_h = 0.0, se_xy = 0.0, z2 = 0.0;
    (void)state;
    world_build(21, 0);
    trn_rng_seed(&r, 4242);
    for (k = 0; k < 40; ++k) {
        const double rx = 36.0 + 56.0 * trn_rng_unit(&r), ry = 36.0 + 56.0 * trn_rng_unit(&r);
        const double delta = (trn_rng_unit(&r) - 0.5) * 12.0 * DEG;
        const int32_t cx = (int32_t)floor(rx + 0.5) + trn_rng_int(&r, -3, 3);
        const int32_t cy = (int32_t)floor(ry + 0.5) + trn_rng_int(&r, -3, 3);
        trn_window_t win = {cx - 5, cy - 5, cx + 5, cy + 5};
        trn_heading_cfg_t c = {0.0, 8.0 * DEG, 0.0};
        trn_heading_result_t res;
        size_t np = local_points(rx, ry, delta);
        size_t wb = trn_localize_heading_workspace_bytes(&g_w.map, np, &win);
        assert_true(wb > 0u && wb <= sizeof g_ws);
        if (trn_localize_points_heading(&g_w.map, g_pts, np, &win, &c, g_ws, wb, &res) == TRN_OK) {
            const double eh = res.heading_rad - delta, ex = res.loc.x - rx, ey = res.loc.y - ry;
            ++n;
            se_h += eh * eh;
            se_xy += ex * ex + ey * ey;
            z2 += eh * eh / (res.sigma_heading_rad * res.sigma_heading_rad);
            right += (fabs(eh) < 2.0 * DEG && ex * ex + ey * ey < 1.5 * 1.5);
        }
    }
    printf("heading recovered: %d of 40 fitted, %d right; RMS heading error %.3f deg, RMS position "
           "error %.3f "
           "cells, mean (error / sigma)^2 in heading %.2f\n",
           n, right, sqrt(se_h / n) / DEG, sqrt(se_xy / n), z2 / n);
    assert_true(n >= 36);
    assert_true(right >= n - 1);
    assert_true(sqrt(se_h / n) < 0.6 * DEG);
    assert_true(sqrt(se_xy / n) < 0.5);
}

/* Calibration over many cases: heading errors against sigma_heading (a
 * normal's 68.3 / 95.4 / 99.7 % within 1 / 2 / 3 sigma) and position errors
 * against the 2 x 2 marginal (39.3 / 86.5 / 98.9 % inside the ellipses).
 * 40 cases on each of 5 rock fields (TRN_HEADING_CAL_CASES=N in the
 * environment: N cases, 40 a field), 1 cm height noise, true error uniform
 * in +-6 deg, window +-8 deg. The 1000-case figures: docs/modules/heading.md. */
static void test_calibration(void **state)
{
    trn_rng_t r;
    int t, k, n = 0, wrong = 0, ch[3] = {0, 0, 0}, cp[3] = {0, 0, 0}, fields = 5;
    const char *env = getenv("TRN_HEADING_CAL_CASES");
    (void)state;
    if (env != NULL && strtol(env, NULL, 10) >= 40) {
        fields = (int)(strtol(env, NULL, 10) / 40);
    }
    trn_rng_seed(&r, 2026);
    g_noise_m = 0.01;
    for (t = 0; t < fields; ++t) {
        world_build(300u + (uint64_t)t, 0);
        for (k = 0; k < 40; ++k) {
            const double rx = 36.0 + 56.0 * trn_rng_unit(&r), ry = 36.0 + 56.0 * trn_rng_unit(&r);
            const double delta = (trn_rng_unit(&r) - 0.5) * 12.0 * DEG;
            const int32_t cx = (int32_t)floor(rx + 0.5) + trn_rng_int(&r, -3, 3);
            const int32_t cy = (int32_t)floor(ry + 0.5) + trn_rng_int(&r, -3, 3);
            trn_window_t win = {cx - 5, cy - 5, cx + 5, cy + 5};
            trn_heading_cfg_t c = {0.0, 8.0 * DEG, 0.0};
            trn_heading_result_t res;
            size_t np = local_points(rx, ry, delta);
            size_t wb = trn_localize_heading_workspace_bytes(&g_w.map, np, &win);
            if (trn_localize_points_heading(&g_w.map, g_pts, np, &win, &c, g_ws, wb, &res) !=
                TRN_OK) {
                continue;
            }
            if (cal3_tally(&res, rx, ry, delta, CELL, ch, cp)) {
                ++n;
            } else {
                ++wrong;
            }
        }
    }
    g_noise_m = 0.0;
    printf("calibration: %d fitted, %d wrong; heading within 1/2/3 sigma %.1f / %.1f / %.1f %% "
           "(68.3 / 95.4 / "
           "99.7); position inside the 1/2/3-sigma ellipses %.1f / %.1f / %.1f %% (39.3 / 86.5 / "
           "98.9)\n",
           n, wrong, 100.0 * ch[0] / n, 100.0 * ch[1] / n, 100.0 * ch[2] / n, 100.0 * cp[0] / n,
           100.0 * cp[1] / n, 100.0 * cp[2] / n);
    assert_true(n >= 38 * fields && wrong <= fields / 5 + 1);
    assert_true(ch[0] >= 0.60 * n &&
                ch[0] <= 0.80 * n); /* within ~8 points of 68.3 % on 200 cases */
    assert_true(ch[1] >= 0.90 * n && ch[2] >= 0.98 * n);
    assert_true(cp[1] >= 0.80 * n &&
                cp[2] >= 0.97 * n); /* position: never optimistic by more than ~6 points */
}

static void test_w0_is_2d(void **state)
{
    trn_window_t win = {50, 52, 66, 68};
    trn_heading_cfg_t c = {2.0 * DEG, 0.0, 0.0};
    trn_heading_result_t res;
    trn_loc_result_t ref;
    size_t np, wb;
    trn_status_t s1, s2;
    (void)state;
    world_build(8, 0);
    np = local_points(58.4, 60.2, -2.0 * DEG);
    wb = trn_localize_heading_workspace_bytes(&g_w.map, np, &win);
    s1 = trn_localize_points_heading(&g_w.map, g_pts, np, &win, &c, g_ws, wb, &res);
    assert_int_equal(res.half_steps, 0);
    assert_int_equal(trn_points_rotate(g_pts, np, c.center_rad, g_rot), TRN_OK);
    s2 = trn_localize_points(&g_w.map, g_rot, np, &win, g_ws,
                             trn_localize_workspace_bytes(&g_w.map, &win), &ref);
    assert_int_equal(s1, s2);
    assert_true(res.loc.x == ref.x && res.loc.y == ref.y && res.loc.ll_best == ref.ll_best);
    assert_true(res.loc.failure_probability == ref.failure_probability);
    assert_true(res.loc.stats.poses_scored == ref.stats.poses_scored);
    assert_true(res.heading_rad == c.center_rad && res.sigma_heading_rad == 0.0);
    assert_true(res.cov3[0] == ref.cov_m2[0] && res.cov3[4] == ref.cov_m2[1] && res.cov3[8] == 0.0);
}

static void test_bad_inputs(void **state)
{
    trn_window_t win = {50, 50, 70, 70}, off = {120, 50, 130, 70}, inv = {60, 50, 55, 70};
    trn_heading_cfg_t c = {0.0, 5.0 * DEG, 0.0}, bc;
    trn_heading_result_t res;
    trn_map_t zero;
    size_t np, wb;
    (void)state;
    world_build(9, 0);
    np = local_points(60.0, 60.0, 0.0);
    wb = trn_localize_heading_workspace_bytes(&g_w.map, np, &win);
    assert_true(wb > 0u && wb + 16u <= sizeof g_ws);
    assert_int_equal(trn_localize_heading_workspace_bytes(NULL, np, &win), 0u);
    assert_int_equal(trn_localize_heading_workspace_bytes(&g_w.map, 0, &win), 0u);
    assert_int_equal(trn_localize_heading_workspace_bytes(&g_w.map, np, NULL), 0u);
    assert_int_equal(trn_localize_points_heading(NULL, g_pts, np, &win, &c, g_ws, wb, &res),
                     TRN_E_NULL);
    assert_int_equal(trn_localize_points_heading(&g_w.map, NULL, np, &win, &c, g_ws, wb, &res),
                     TRN_E_NULL);
    assert_int_equal(trn_localize_points_heading(&g_w.map, g_pts, np, NULL, &c, g_ws, wb, &res),
                     TRN_E_NULL);
    assert_int_equal(trn_localize_points_heading(&g_w.map, g_pts, np, &win, NULL, g_ws, wb, &res),
                     TRN_E_NULL);
    assert_int_equal(trn_localize_points_heading(&g_w.map, g_pts, np, &win, &c, NULL, wb, &res),
                     TRN_E_NULL);
    assert_int_equal(trn_localize_points_heading(&g_w.map, g_pts, np, &win, &c, g_ws, wb, NULL),
                     TRN_E_NULL);
    /* window out of range, inverted */
    assert_int_equal(trn_localize_points_heading(&g_w.map, g_pts, np, &off, &c, g_ws, wb, &res),
                     TRN_E_RANGE);
    assert_int_equal(trn_localize_points_heading(&g_w.map, g_pts, np, &inv, &c, g_ws, wb, &res),
                     TRN_E_RANGE);
    {
        const trn_window_t offs[4] = {
            {-1, 50, 70, 70}, {50, -1, 70, 70}, {50, 50, 70, N}, {50, 60, 70, 50}};
        int i;
        for (i = 0; i < 4; ++i) {
            assert_int_equal(
                trn_localize_points_heading(&g_w.map, g_pts, np, &offs[i], &c, g_ws, wb, &res),
                TRN_E_RANGE);
        }
    }
    { /* the truth at the window's edge: found there, and flagged */
        trn_window_t edge = {60, 55, 70, 65};
        assert_int_equal(
            trn_localize_points_heading(&g_w.map, g_pts, np, &edge, &c, g_ws, wb, &res), TRN_OK);
        assert_int_equal(res.loc.ix, 60);
        assert_int_equal(res.loc.on_window_edge, 1);
    }
    /* heading window out of range, NaN heading, step too fine */
    bc = c;
    bc.window_rad = 4.0;
    assert_int_equal(trn_localize_points_heading(&g_w.map, g_pts, np, &win, &bc, g_ws, wb, &res),
                     TRN_E_ARG);
    bc = c;
    bc.center_rad = NAN;
    assert_int_equal(trn_localize_points_heading(&g_w.map, g_pts, np, &win, &bc, g_ws, wb, &res),
                     TRN_E_ARG);
    bc = c;
    bc.window_rad = M_PI;
    bc.step_rad = 1e-3;
    assert_int_equal(trn_localize_points_heading(&g_w.map, g_pts, np, &win, &bc, g_ws, wb, &res),
                     TRN_E_SIZE);
    /* workspace short, misaligned */
    assert_int_equal(
        trn_localize_points_heading(&g_w.map, g_pts, np, &win, &c, g_ws, wb - 1u, &res),
        TRN_E_WORKSPACE);
    assert_int_equal(
        trn_localize_points_heading(&g_w.map, g_pts, np, &win, &c, g_ws + 8, wb + 8u, &res),
        TRN_E_WORKSPACE);
    /* no points; an unbuilt map; a point out of the volume's bins */
    assert_int_equal(trn_localize_points_heading(&g_w.map, g_pts, 0, &win, &c, g_ws, wb, &res),
                     TRN_E_NODATA);
    memset(&zero, 0, sizeof zero);
    assert_int_equal(trn_localize_points_heading(&zero, g_pts, np, &win, &c, g_ws, wb, &res),
                     TRN_E_RANGE);
    zero = g_w.map;
    zero.pyr.nlevels = 0;
    assert_int_equal(trn_localize_points_heading(&zero, g_pts, np, &win, &c, g_ws, wb, &res),
                     TRN_E_ARG);
    g_rot[0] = g_pts[0];
    g_rot[0].z = 500;
    assert_int_equal(trn_localize_points_heading(&g_w.map, g_rot, 1, &win, &c, g_ws, wb, &res),
                     TRN_E_ARG);
    /* flat terrain: every pose and heading alike, no finite covariance */
    world_build(9, 1);
    {
        static trn_point_t flat[9];
        int i;
        for (i = 0; i < 9; ++i) {
            flat[i].x = (int16_t)(i % 3 * 5 - 5);
            flat[i].y = (int16_t)(i / 3 * 5 - 5);
            flat[i].z = g_pts[0].z;
        }
        assert_int_equal(trn_localize_points_heading(&g_w.map, flat, 9, &win, &c, g_ws, wb, &res),
                         TRN_E_ILLCOND);
        assert_true(isinf(res.sigma_heading_rad));
    }
}

/* The DEM entry: the same answer as the points entry on the points it
 * makes (box high-pass and occupancy of the map's configuration), and its
 * own bad inputs. */
static void test_dem_entry(void **state)
{
    trn_window_t win = {52, 50, 66, 64};
    trn_heading_cfg_t c = {0.0, 6.0 * DEG, 0.0};
    trn_heading_result_t a, b;
    trn_grid_f32_t lg;
    trn_map_t m2;
    size_t np, wb, wp;
    trn_status_t sa, sb;
    (void)state;
    world_build(14, 0);
    np = local_points(59.3, 57.8, 4.0 * DEG); /* g_loc: the local DEM */
    assert_int_equal(trn_grid_f32_init(&lg, g_loc, LW * LW, LW, LW), TRN_OK);
    wb = trn_localize_dem_heading_workspace_bytes(&g_w.map, LW, LW, MAXPTS, &win);
    wp = trn_localize_heading_workspace_bytes(&g_w.map, np, &win);
    assert_true(wb > 0u && wb + 16u <= sizeof g_ws && wp > 0u);
    a.loc.noise_scale = NAN; /* the voxel path reports the configured model: 1 */
    sa = trn_localize_dem_heading(&g_w.map, &lg, LR, LR, MAXPTS, &win, &c, g_ws, wb, &a);
    assert_int_equal(sa, TRN_OK);
    assert_true(a.loc.noise_scale == 1.0);
    sb = trn_localize_points_heading(&g_w.map, g_pts, np, &win, &c, g_ws, wp, &b);
    assert_int_equal(sa, sb);
    assert_true(a.loc.x == b.loc.x && a.loc.y == b.loc.y && a.heading_rad == b.heading_rad);
    assert_true(a.loc.ll_best == b.loc.ll_best &&
                a.loc.failure_probability == b.loc.failure_probability);
    assert_true(fabs(a.heading_rad - 4.0 * DEG) < 1.0 * DEG && fabs(a.loc.x - 59.3) < 1.0 &&
                fabs(a.loc.y - 57.8) < 1.0);
    { /* the local filter against the map's low-pass (TRN_LOCAL_HP_MAP) finds it too */
        trn_map_cfg_t mc;
        trn_map_t mm;
        size_t mb, wb2;
        trn_map_cfg_default(&mc);
        mc.local_highpass = TRN_LOCAL_HP_MAP;
        mb = trn_map_bytes(&mc, N, N);
        assert_true(mb > 0u && mb <= sizeof g_mapbuf2);
        assert_int_equal(trn_map_build(&mm, &mc, &g_w.g, g_mapbuf2, mb), TRN_OK);
        wb2 = trn_localize_dem_heading_workspace_bytes(&mm, LW, LW, MAXPTS, &win);
        assert_true(wb2 > 0u && wb2 <= sizeof g_ws);
        assert_int_equal(
            trn_localize_dem_heading(&mm, &lg, LR, LR, MAXPTS, &win, &c, g_ws, wb2, &b), TRN_OK);
        assert_true(fabs(b.heading_rad - 4.0 * DEG) < 1.0 * DEG && fabs(b.loc.x - 59.3) < 1.0 &&
                    fabs(b.loc.y - 57.8) < 1.0);
    }
    /* sizing refusals */
    assert_int_equal(trn_localize_dem_heading_workspace_bytes(NULL, LW, LW, MAXPTS, &win), 0u);
    assert_int_equal(trn_localize_dem_heading_workspace_bytes(&g_w.map, LW, LW, 0, &win), 0u);
    assert_int_equal(trn_localize_dem_heading_workspace_bytes(&g_w.map, 0, LW, MAXPTS, &win), 0u);
    /* bad inputs, one class each */
    assert_int_equal(trn_localize_dem_heading(NULL, &lg, LR, LR, MAXPTS, &win, &c, g_ws, wb, &a),
                     TRN_E_NULL);
    assert_int_equal(
        trn_localize_dem_heading(&g_w.map, NULL, LR, LR, MAXPTS, &win, &c, g_ws, wb, &a),
        TRN_E_NULL);
    assert_int_equal(
        trn_localize_dem_heading(&g_w.map, &lg, LR, LR, MAXPTS, NULL, &c, g_ws, wb, &a),
        TRN_E_NULL);
    assert_int_equal(
        trn_localize_dem_heading(&g_w.map, &lg, LR, LR, MAXPTS, &win, NULL, g_ws, wb, &a),
        TRN_E_NULL);
    assert_int_equal(
        trn_localize_dem_heading(&g_w.map, &lg, LR, LR, MAXPTS, &win, &c, NULL, wb, &a),
        TRN_E_NULL);
    assert_int_equal(
        trn_localize_dem_heading(&g_w.map, &lg, LR, LR, MAXPTS, &win, &c, g_ws, wb, NULL),
        TRN_E_NULL);
    {
        trn_grid_f32_t bad = lg;
        bad.width = 0;
        assert_int_equal(
            trn_localize_dem_heading(&g_w.map, &bad, LR, LR, MAXPTS, &win, &c, g_ws, wb, &a),
            TRN_E_SIZE);
    }
    m2 = g_w.map;
    m2.cfg.refine = 1; /* the voxel matcher searches heading without refinement only */
    assert_int_equal(trn_localize_dem_heading(&m2, &lg, LR, LR, MAXPTS, &win, &c, g_ws, wb, &a),
                     TRN_E_ARG);
    m2 = g_w.map;
    m2.cfg.match = TRN_MATCH_HEIGHTS; /* a height map without its heights */
    assert_int_equal(trn_localize_dem_heading(&m2, &lg, LR, LR, MAXPTS, &win, &c, g_ws, wb, &a),
                     TRN_E_ARG);
    assert_int_equal(trn_localize_dem_heading(&g_w.map, &lg, LR, LR,
                                              (size_t)TRN_MAX_DIM * TRN_MAX_DIM + 1u, &win, &c,
                                              g_ws, wb, &a),
                     TRN_E_ARG);
    assert_int_equal(trn_localize_dem_heading_workspace_bytes(&g_w.map, LW, LW, MAXPTS, NULL), 0u);
    assert_int_equal(trn_localize_dem_heading_workspace_bytes(
                         &g_w.map, LW, LW, (size_t)TRN_MAX_DIM * TRN_MAX_DIM + 1u, &win),
                     0u);
    {
        trn_window_t off = {200, 50, 210, 60};
        assert_int_equal(trn_localize_dem_heading_workspace_bytes(&g_w.map, LW, LW, MAXPTS, &off),
                         0u);
        m2 = g_w.map;
        m2.pyr.nlevels = 0;
        assert_int_equal(trn_localize_dem_heading_workspace_bytes(&m2, LW, LW, MAXPTS, &win), 0u);
    }
    assert_int_equal(trn_localize_dem_heading(&g_w.map, &lg, LR, LR, 0, &win, &c, g_ws, wb, &a),
                     TRN_E_ARG);
    {
        trn_window_t off = {200, 50, 210, 60};
        trn_heading_cfg_t fine = {0.0, M_PI, 1e-4}, nan_c = {NAN, 0.1, 0.0};
        assert_int_equal(
            trn_localize_dem_heading(&g_w.map, &lg, LR, LR, MAXPTS, &off, &c, g_ws, wb, &a),
            TRN_E_RANGE);
        assert_int_equal(
            trn_localize_dem_heading(&g_w.map, &lg, LR, LR, MAXPTS, &win, &fine, g_ws, wb, &a),
            TRN_E_SIZE);
        assert_int_equal(
            trn_localize_dem_heading(&g_w.map, &lg, LR, LR, MAXPTS, &win, &nan_c, g_ws, wb, &a),
            TRN_E_ARG);
    }
    assert_int_equal(
        trn_localize_dem_heading(&g_w.map, &lg, LR, LR, MAXPTS, &win, &c, g_ws, wb - 1u, &a),
        TRN_E_WORKSPACE);
    assert_int_equal(
        trn_localize_dem_heading(&g_w.map, &lg, LR, LR, MAXPTS, &win, &c, g_ws + 8, wb, &a),
        TRN_E_WORKSPACE);
    assert_int_equal(trn_localize_dem_heading(&g_w.map, &lg, LR, LR, 3, &win, &c, g_ws, wb, &a),
                     TRN_E_CAPACITY);
    {
        int i;
        for (i = 0; i < LW * LW; ++i) {
            g_loc[i] = NAN;
        }
        assert_int_equal(
            trn_localize_dem_heading(&g_w.map, &lg, LR, LR, MAXPTS, &win, &c, g_ws, wb, &a),
            TRN_E_NODATA);
    }
    /* flat map, flat local DEM: every pose and heading alike */
    world_build(14, 1);
    {
        int i;
        for (i = 0; i < LW * LW; ++i) {
            g_loc[i] = (i % LW - LR) * (i % LW - LR) + (i / LW - LR) * (i / LW - LR) <= LR * LR
                           ? 1.0f
                           : NAN;
        }
        wb = trn_localize_dem_heading_workspace_bytes(&g_w.map, LW, LW, MAXPTS, &win);
        assert_int_equal(
            trn_localize_dem_heading(&g_w.map, &lg, LR, LR, MAXPTS, &win, &c, g_ws, wb, &a),
            TRN_E_ILLCOND);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rotate_formula),
        cmocka_unit_test(test_steps),
        cmocka_unit_test(test_fit3_analytic),
        cmocka_unit_test(test_search_bb_above),
        cmocka_unit_test(test_equals_exhaustive),
        cmocka_unit_test(test_recovers_heading),
        cmocka_unit_test(test_w0_is_2d),
        cmocka_unit_test(test_bad_inputs),
        cmocka_unit_test(test_dem_entry),
        cmocka_unit_test(test_calibration),
        cmocka_unit_test(test_few_points_exhaustive),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
