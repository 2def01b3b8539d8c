/* SPDX-License-Identifier: Apache-2.0 */
/* test_localize.c - end-to-end localization on synthetic terrain: integer
 * shifts exact, subpixel shifts within 0.1 cell RMS (per axis at 4 m, radial at 6.4 m), flat and ridge peaks
 * ill-conditioned, periodic terrain ambiguous, every bad-input class. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rng.h"
#include "synth.h"
#include "trn/localize.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define CELL 0.1
#define MAXPTS 20000

typedef struct {
    int n;
    float *dem;
    trn_grid_f32_t g;
    trn_map_cfg_t cfg;
    trn_map_t map;
    void *buf;
} world_t;

static synth_rock_t g_rocks[2000];

static void world_render(world_t *w, int n, const synth_terrain_t *t)
{
    size_t mb;
    w->n = n;
    w->dem = malloc(sizeof(float) * (size_t)n * n);
    assert_non_null(w->dem);
    synth_render(t, w->dem, n, n, 0.0, 0.0, CELL);
    assert_int_equal(trn_grid_f32_init(&w->g, w->dem, (size_t)n * n, n, n), TRN_OK);
    trn_map_cfg_default(&w->cfg);
    mb = trn_map_bytes(&w->cfg, n, n);
    assert_true(mb > 0u);
    w->buf = malloc(mb);
    assert_non_null(w->buf);
    assert_int_equal(trn_map_build(&w->map, &w->cfg, &w->g, w->buf, mb), TRN_OK);
}

static void world_free(world_t *w)
{
    free(w->dem);
    free(w->buf);
}

static trn_status_t run_localize(const world_t *w, const trn_grid_f32_t *local, int rx, int ry,
                                 const trn_window_t *win, trn_loc_result_t *res)
{
    size_t wb = trn_localize_dem_workspace_bytes(&w->map, local->width, local->height, MAXPTS, win);
    void *ws;
    trn_status_t st;
    assert_true(wb > 0u);
    ws = malloc(wb);
    assert_non_null(ws);
    st = trn_localize_dem(&w->map, local, rx, ry, MAXPTS, win, ws, wb, res);
    free(ws);
    return st;
}

static void rocky(synth_terrain_t *t, int n, uint64_t seed)
{
    size_t nr = (size_t)(n * n * CELL * CELL * 0.15 / (M_PI * 0.15 * 0.15));
    if (nr > sizeof g_rocks / sizeof g_rocks[0]) {
        nr = sizeof g_rocks / sizeof g_rocks[0];
    }
    synth_make(t, g_rocks, nr, n * CELL, 0.05, 0.3, 0.5, 0.2, seed);
}

/* The local DEM is an exact crop of the global DEM: the pose is an integer
 * shift and must come back exactly, from a prior that is off by up to 5. */
static void test_integer_shift_exact(void **state)
{
    world_t w;
    synth_terrain_t t;
    trn_rng_t r;
    int k;
    (void)state;
    rocky(&t, 112, 17);
    world_render(&w, 112, &t);
    trn_rng_seed(&r, 99);
    for (k = 0; k < 16; ++k) {
        trn_grid_f32_t local;
        trn_loc_result_t res;
        trn_window_t win;
        int gx = trn_rng_int(&r, 0, 112 - 36), gy = trn_rng_int(&r, 0, 112 - 36);
        int tx = gx + 18, ty = gy + 18;
        int px = tx + trn_rng_int(&r, -5, 5), py = ty + trn_rng_int(&r, -5, 5);
        assert_int_equal(trn_grid_f32_sub(&w.g, gx, gy, 36, 36, &local), TRN_OK);
        win.x0 = px - 8 < 0 ? 0 : px - 8;
        win.y0 = py - 8 < 0 ? 0 : py - 8;
        win.x1 = px + 8 > 111 ? 111 : px + 8;
        win.y1 = py + 8 > 111 ? 111 : py + 8;
        assert_int_equal(run_localize(&w, &local, 18, 18, &win, &res), TRN_OK);
        assert_int_equal(res.ix, tx);
        assert_int_equal(res.iy, ty);
        assert_true(fabs(res.x - tx) < 0.5 && fabs(res.y - ty) < 0.5);
        assert_true(res.sigma_x_m > 0.0 && res.sigma_x_m < 0.5 * CELL);
        assert_true(res.failure_probability < 1e-6);
        assert_int_equal(res.has_second, 1);
    }
    world_free(&w);
}

/* The local DEM is the same analytic terrain sampled at a sub-cell offset:
 * the estimate must follow the offset with RMS error <= 0.1 cell per axis. */
/* One subpixel experiment: a rocky world of n x n cells, `trials` local maps
 * of L x L cells rendered (resampled, not cropped) at random real-valued
 * rover positions, localized from a +-10 cell prior. Returns the RMS error
 * per axis and radial (cells) and the mean (e/sigma)^2 per axis. */
static void subpixel_run(int L, int n, int trials, uint64_t seed, double *rms_axis,
                         double *rms_radial, double *mean_norm)
{
    world_t w;
    synth_terrain_t t;
    trn_rng_t r;
    float *loc = malloc(sizeof(float) * (size_t)L * (size_t)L);
    double se = 0.0, sn = 0.0;
    const int margin = L / 2 + 8;
    int k;
    assert_non_null(loc);
    rocky(&t, n, 7);
    world_render(&w, n, &t);
    trn_rng_seed(&r, seed);
    for (k = 0; k < trials; ++k) {
        trn_grid_f32_t local;
        trn_loc_result_t res;
        double tx = trn_rng_int(&r, margin, n - 1 - margin) + trn_rng_unit(&r) - 0.5;
        double ty = trn_rng_int(&r, margin, n - 1 - margin) + trn_rng_unit(&r) - 0.5;
        trn_window_t win;
        double ex, ey;
        synth_render(&t, loc, L, L, (tx - L / 2) * CELL, (ty - L / 2) * CELL, CELL);
        assert_int_equal(trn_grid_f32_init(&local, loc, (size_t)L * (size_t)L, L, L), TRN_OK);
        win.x0 = (int)tx - 10;
        win.y0 = (int)ty - 10;
        win.x1 = (int)tx + 10;
        win.y1 = (int)ty + 10;
        assert_int_equal(run_localize(&w, &local, L / 2, L / 2, &win, &res), TRN_OK);
        ex = res.x - tx;
        ey = res.y - ty;
        se += ex * ex + ey * ey;
        /* normalised error: how well the eq. 6 sigma predicts the error */
        sn += ex * ex / (res.sigma_x_m * res.sigma_x_m / (CELL * CELL)) +
              ey * ey / (res.sigma_y_m * res.sigma_y_m / (CELL * CELL));
    }
    *rms_axis = sqrt(se / (2.0 * trials));
    *rms_radial = sqrt(se / trials);
    *mean_norm = sn / (2.0 * trials);
    printf("subpixel, %dx%d local map (%.1f m): RMS error per axis %.4f, radial %.4f cells over "
           "%d trials; mean (e/sigma)^2 per axis %.2f\n",
           L, L, L * CELL, *rms_axis, *rms_radial, trials, *mean_norm);
    world_free(&w);
    free(loc);
}

/* Subpixel shifts recovered to <= 0.1 cell RMS. With a 4 m local map the
 * per-axis RMS meets it but the radial one does not (about 0.11: the local
 * map's own voxelization noise, docs/method.md section 1); with a 6.4 m map,
 * a mast stereo view's size, the radial RMS meets it too. Both are asserted,
 * so a regression in either shows. */
static void test_subpixel_rms(void **state)
{
    double axis, radial, norm;
    (void)state;
    subpixel_run(40, 128, 40, 3, &axis, &radial, &norm);
    assert_true(axis <= 0.1);
    assert_true(radial <= 0.15);
    /* eq. 6's sigma must describe the error: neither far too small nor large */
    assert_true(norm > 0.25 && norm < 4.0);

    subpixel_run(64, 192, 80, 5, &axis, &radial, &norm);
    assert_true(axis <= 0.1);
    assert_true(radial <= 0.1);
    assert_true(norm > 0.25 && norm < 4.0);
}

/* Least-squares quadratic c0 + c1 x + c2 y + c3 x^2 + c4 xy + c5 y^2 over
 * the (2R+1)^2 patch p[(y + 2) * 5 + (x + 2)], |x|, |y| <= R; returns its
 * vertex. Plain Gauss-Jordan on the 6 x 6 normal equations. */
static void lsq_vertex(const double p[25], int R, double *dx, double *dy)
{
    double A[6][7] = {{0.0}};
    int x, y, i, j, k;
    for (y = -R; y <= R; ++y) {
        for (x = -R; x <= R; ++x) {
            const double b[6] = {1.0, x, y, (double)(x * x), (double)(x * y), (double)(y * y)};
            for (i = 0; i < 6; ++i) {
                for (j = 0; j < 6; ++j) {
                    A[i][j] += b[i] * b[j];
                }
                A[i][6] += b[i] * p[(y + 2) * 5 + (x + 2)];
            }
        }
    }
    for (i = 0; i < 6; ++i) {
        int piv = i;
        for (k = i + 1; k < 6; ++k) {
            if (fabs(A[k][i]) > fabs(A[piv][i])) {
                piv = k;
            }
        }
        for (j = 0; j < 7; ++j) {
            double tmp = A[i][j];
            A[i][j] = A[piv][j];
            A[piv][j] = tmp;
        }
        assert_true(fabs(A[i][i]) > 1e-9);
        for (k = 0; k < 6; ++k) {
            if (k != i) {
                double f = A[k][i] / A[i][i];
                for (j = 0; j < 7; ++j) {
                    A[k][j] -= f * A[i][j];
                }
            }
        }
    }
    {
        double c1 = A[1][6] / A[1][1], c2 = A[2][6] / A[2][2], c3 = A[3][6] / A[3][3];
        double c4 = A[4][6] / A[4][4], c5 = A[5][6] / A[5][5];
        double hxx = 2.0 * c3, hyy = 2.0 * c5, det = hxx * hyy - c4 * c4;
        *dx = (-hyy * c1 + c4 * c2) / det;
        *dy = (c4 * c1 - hxx * c2) / det;
    }
}

/* Why eq. 6 is fitted on 3 x 3 (docs/method.md, measured accuracy): on the
 * sub-cell trials of test_subpixel_rms, a least-squares quadratic over the
 * 5 x 5 scores is less accurate than trn_peak_fit's 3 x 3 one, and the 3 x 3
 * error is mostly noise, not pixel locking: the least-squares slope of the
 * estimated over the true sub-cell offset is close to 1, and removing it
 * leaves most of the error. */
static void test_subpixel_fit_choice(void **state)
{
    enum { L = 40 };
    world_t w;
    synth_terrain_t t;
    trn_rng_t r;
    static float loc[L * L], hpb[L * L];
    static trn_point_t pts[MAXPTS];
    TRN_WORKSPACE_DECLARE(hws, 1u << 16);
    double se3 = 0.0, se5 = 0.0, stt = 0.0, ste = 0.0, see = 0.0, slope, resid;
    int k, trials = 40;
    (void)state;
    assert_true(trn_highpass_workspace_bytes(L, L) <= sizeof hws);
    rocky(&t, 128, 7);
    world_render(&w, 128, &t);
    trn_rng_seed(&r, 3); /* the trials of test_subpixel_rms */
    for (k = 0; k < trials; ++k) {
        trn_grid_f32_t local, hp;
        trn_loc_result_t res;
        trn_window_t win;
        size_t n = 0;
        double p[25], ll[9], d5x, d5y, fx, fy, ex, ey;
        trn_peak_t pk;
        int x, y;
        double tx = trn_rng_int(&r, 30, 97) + trn_rng_unit(&r) - 0.5;
        double ty = trn_rng_int(&r, 30, 97) + trn_rng_unit(&r) - 0.5;
        synth_render(&t, loc, L, L, (tx - L / 2) * CELL, (ty - L / 2) * CELL, CELL);
        assert_int_equal(trn_grid_f32_init(&local, loc, L * L, L, L), TRN_OK);
        win.x0 = (int)tx - 10;
        win.y0 = (int)ty - 10;
        win.x1 = (int)tx + 10;
        win.y1 = (int)ty + 10;
        assert_int_equal(run_localize(&w, &local, L / 2, L / 2, &win, &res), TRN_OK);
        /* the same points trn_localize_dem matched, scored on 5 x 5 */
        assert_int_equal(trn_grid_f32_init(&hp, hpb, L * L, L, L), TRN_OK);
        assert_int_equal(trn_highpass(&local, &w.cfg.terrain, &hp, hws, sizeof hws), TRN_OK);
        assert_int_equal(trn_occupancy_points(&hp, &w.cfg.terrain, L / 2, L / 2, pts, MAXPTS, &n),
                         TRN_OK);
        assert_true(n == res.n_points);
        for (y = -2; y <= 2; ++y) {
            for (x = -2; x <= 2; ++x) {
                int64_t s;
                assert_int_equal(
                    trn_score_pose(&w.map.dist, &w.map.lnp, pts, n, res.ix + x, res.iy + y, &s),
                    TRN_OK);
                p[(y + 2) * 5 + (x + 2)] = (double)s / (double)TRN_LNP_SCALE - res.ll_best;
            }
        }
        for (y = 0; y < 3; ++y) {
            for (x = 0; x < 3; ++x) {
                ll[y * 3 + x] = p[(y + 1) * 5 + (x + 1)];
            }
        }
        assert_int_equal(trn_peak_fit(ll, &pk), TRN_OK);
        assert_true(fabs(res.ix + pk.dx - res.x) < 1e-9 && fabs(res.iy + pk.dy - res.y) < 1e-9);
        lsq_vertex(p, 2, &d5x, &d5y);
        fx = tx - res.ix;
        fy = ty - res.iy;
        ex = pk.dx - fx;
        ey = pk.dy - fy;
        se3 += ex * ex + ey * ey;
        ex = d5x - fx;
        ey = d5y - fy;
        se5 += ex * ex + ey * ey;
        stt += fx * fx + fy * fy;
        ste += fx * pk.dx + fy * pk.dy;
        see += pk.dx * pk.dx + pk.dy * pk.dy;
    }
    slope = ste / stt;
    resid = sqrt((see - 2.0 * slope * ste + slope * slope * stt) / (2.0 * trials));
    printf("sub-cell fit over %d trials, RMS per axis: 3x3 eq. 6 %.4f, 5x5 least squares %.4f; "
           "3x3 slope estimate/true %.3f, RMS left after the slope %.4f\n",
           trials, sqrt(se3 / (2.0 * trials)), sqrt(se5 / (2.0 * trials)), slope, resid);
    assert_true(se3 < se5);
    assert_true(slope > 0.8 && slope < 1.2);
    assert_true(resid > 0.75 * sqrt(se3 / (2.0 * trials)));
    world_free(&w);
}

/* Flat terrain: every pose explains the local map equally well. */
static void test_flat_is_illcond(void **state)
{
    world_t w;
    synth_terrain_t t;
    trn_loc_result_t res;
    trn_grid_f32_t local;
    trn_window_t win = {30, 30, 50, 50};
    (void)state;
    synth_make(&t, g_rocks, 0, 8.0, 0.1, 0.2, 0.5, 0.0, 1);
    world_render(&w, 80, &t);
    assert_int_equal(trn_grid_f32_sub(&w.g, 20, 20, 30, 30, &local), TRN_OK);
    assert_int_equal(run_localize(&w, &local, 15, 15, &win, &res), TRN_E_ILLCOND);
    assert_true(isinf(res.sigma_x_m) && isinf(res.sigma_y_m));
    assert_true(res.failure_probability >= 0.49);
    world_free(&w);
}

/* A terrain that only varies along x (parallel ridges): y is unobservable. */
static void test_ridge_is_illcond(void **state)
{
    enum { N = 80 };
    static float dem[N * N];
    world_t w;
    trn_loc_result_t res;
    trn_grid_f32_t local;
    trn_window_t win = {30, 30, 50, 50};
    size_t mb;
    int x, y;
    (void)state;
    for (y = 0; y < N; ++y) {
        for (x = 0; x < N; ++x) {
            dem[y * N + x] = (float)(0.3 * sin(x * 0.45) + 0.2 * sin(x * 1.3) + 0.02 * x);
        }
    }
    w.dem = NULL;
    assert_int_equal(trn_grid_f32_init(&w.g, dem, N * N, N, N), TRN_OK);
    trn_map_cfg_default(&w.cfg);
    mb = trn_map_bytes(&w.cfg, N, N);
    w.buf = malloc(mb);
    assert_int_equal(trn_map_build(&w.map, &w.cfg, &w.g, w.buf, mb), TRN_OK);
    assert_int_equal(trn_grid_f32_sub(&w.g, 25, 25, 30, 30, &local), TRN_OK);
    assert_int_equal(run_localize(&w, &local, 15, 15, &win, &res), TRN_E_ILLCOND);
    assert_int_equal(res.ix, 40); /* x is still found */
    assert_true(isinf(res.sigma_y_m));
    free(w.buf);
}

/* Identical rocks on a 2 m lattice: the match is ambiguous, and the failure
 * probability says so; on random rocks it is tiny. */
static void test_failure_probability(void **state)
{
    world_t w;
    synth_terrain_t t;
    synth_rock_t lattice[36];
    trn_loc_result_t res;
    trn_grid_f32_t local;
    trn_window_t win = {25, 25, 75, 75};
    int i, j;
    (void)state;
    for (j = 0; j < 6; ++j) {
        for (i = 0; i < 6; ++i) {
            lattice[j * 6 + i].x_m = 1.0 + 2.0 * i;
            lattice[j * 6 + i].y_m = 1.0 + 2.0 * j;
            lattice[j * 6 + i].r_m = 0.35;
            lattice[j * 6 + i].h_m = 0.35;
        }
    }
    synth_make(&t, lattice, 0, 12.0, 0.1, 0.2, 0.5, 0.0, 1);
    t.rocks = lattice;
    t.n_rocks = 36;
    world_render(&w, 120, &t);
    assert_int_equal(trn_grid_f32_sub(&w.g, 35, 35, 30, 30, &local), TRN_OK);
    (void)run_localize(&w, &local, 15, 15, &win, &res);
    printf("lattice: best (%d,%d) second (%d,%d) P_fail %.3f\n", res.ix, res.iy, res.second_x,
           res.second_y, res.failure_probability);
    assert_int_equal(res.has_second, 1);
    assert_true(res.failure_probability > 0.4);
    assert_true((res.ix - 50) % 20 == 0 && (res.iy - 50) % 20 == 0);
    world_free(&w);
}

/* The pose localize returns is the exhaustive search's best pose. */
static void test_localize_matches_exhaustive(void **state)
{
    world_t w;
    synth_terrain_t t;
    trn_rng_t r;
    static float loc[32 * 32];
    static trn_point_t pts[MAXPTS];
    int k;
    (void)state;
    rocky(&t, 96, 5);
    world_render(&w, 96, &t);
    trn_rng_seed(&r, 77);
    for (k = 0; k < 10; ++k) {
        trn_grid_f32_t local, hp;
        static float hpbuf[32 * 32];
        TRN_WORKSPACE_DECLARE(hws, 32 * 1024);
        trn_loc_result_t res;
        trn_best_t best;
        size_t n, wb;
        void *ws;
        double tx = trn_rng_int(&r, 20, 75) + trn_rng_unit(&r), ty = trn_rng_int(&r, 20, 75);
        trn_window_t win = {(int)tx - 12, (int)ty - 12, (int)tx + 12, (int)ty + 12};
        synth_render(&t, loc, 32, 32, (tx - 16) * CELL, (ty - 16) * CELL, CELL);
        assert_int_equal(trn_grid_f32_init(&local, loc, 32 * 32, 32, 32), TRN_OK);
        assert_int_equal(trn_grid_f32_init(&hp, hpbuf, 32 * 32, 32, 32), TRN_OK);
        assert_int_equal(trn_highpass(&local, &w.cfg.terrain, &hp, hws, sizeof hws), TRN_OK);
        assert_int_equal(trn_occupancy_points(&hp, &w.cfg.terrain, 16, 16, pts, MAXPTS, &n),
                         TRN_OK);
        wb = trn_localize_workspace_bytes(&w.map, &win);
        ws = malloc(wb);
        assert_int_equal(trn_localize_points(&w.map, pts, n, &win, ws, wb, &res), TRN_OK);
        assert_int_equal(
            trn_search_exhaustive(&w.map.dist, &w.map.lnp, pts, n, &win, NULL, &best, NULL),
            TRN_OK);
        assert_int_equal(res.ix, best.x);
        assert_int_equal(res.iy, best.y);
        assert_true(fabs(res.ll_best - (double)best.score / TRN_LNP_SCALE) < 1e-9);
        free(ws);
    }
    world_free(&w);
}

static void test_bad_inputs(void **state)
{
    enum { N = 40 };
    static float dem[N * N], nan_dem[N * N];
    TRN_WORKSPACE_DECLARE(buf, 1 << 20);
    TRN_WORKSPACE_DECLARE(ws, 1 << 16);
    trn_grid_f32_t g, gn, local, big;
    trn_map_cfg_t cfg, bc;
    trn_map_t map, zero;
    trn_loc_result_t res;
    trn_window_t win = {10, 10, 30, 30}, off = {30, 30, N, 35};
    trn_point_t pts[2] = {{0, 0, 8}, {1, 0, 8}};
    size_t mb;
    int i;
    (void)state;
    for (i = 0; i < N * N; ++i) {
        dem[i] = (float)(0.3 * sin(i * 0.37) * cos(i * 0.011));
        nan_dem[i] = NAN;
    }
    assert_int_equal(trn_grid_f32_init(&g, dem, N * N, N, N), TRN_OK);
    assert_int_equal(trn_grid_f32_init(&gn, nan_dem, N * N, N, N), TRN_OK);
    trn_map_cfg_default(&cfg);
    trn_map_cfg_default(NULL); /* no crash */

    /* configuration */
    assert_int_equal(trn_map_cfg_check(NULL), TRN_E_NULL);
    assert_int_equal(trn_map_cfg_check(&cfg), TRN_OK);
    bc = cfg;
    bc.terrain.cell_m = -1.0f;
    assert_int_equal(trn_map_cfg_check(&bc), TRN_E_ARG);
    bc = cfg;
    bc.terrain.nz = 0;
    assert_int_equal(trn_map_cfg_check(&bc), TRN_E_SIZE);
    bc = cfg;
    bc.sigma_m = NAN;
    assert_int_equal(trn_map_cfg_check(&bc), TRN_E_ARG);
    bc = cfg;
    bc.inlier_prob = 1.5f;
    assert_int_equal(trn_map_cfg_check(&bc), TRN_E_ARG);
    bc = cfg;
    bc.cap = 1;
    assert_int_equal(trn_map_cfg_check(&bc), TRN_E_ARG);
    bc = cfg;
    bc.levels = 0;
    assert_int_equal(trn_map_cfg_check(&bc), TRN_E_ARG);
    bc = cfg;
    bc.levels = TRN_MAX_LEVELS + 1;
    assert_int_equal(trn_map_cfg_check(&bc), TRN_E_ARG);
    bc = cfg;
    bc.min_exclusion_cells = 0;
    assert_int_equal(trn_map_cfg_check(&bc), TRN_E_ARG);
    assert_int_equal(trn_map_bytes(NULL, N, N), 0u);
    assert_int_equal(trn_map_bytes(&cfg, 0, N), 0u);
    assert_int_equal(trn_map_bytes(&cfg, N, TRN_MAX_DIM + 1), 0u);

    /* map build */
    mb = trn_map_bytes(&cfg, N, N);
    assert_true(mb <= sizeof buf);
    assert_int_equal(trn_map_build(NULL, &cfg, &g, buf, mb), TRN_E_NULL);
    assert_int_equal(trn_map_build(&map, NULL, &g, buf, mb), TRN_E_NULL);
    assert_int_equal(trn_map_build(&map, &cfg, NULL, buf, mb), TRN_E_NULL);
    assert_int_equal(trn_map_build(&map, &cfg, &g, NULL, mb), TRN_E_NULL);
    assert_int_equal(trn_map_build(&map, &cfg, &g, buf, mb - 1), TRN_E_WORKSPACE);
    assert_true(mb + 8u <= sizeof buf); /* misaligned (8 past a 16-byte boundary), large enough */
    assert_int_equal(trn_map_build(&map, &cfg, &g, buf + 8, sizeof buf - 8u), TRN_E_WORKSPACE);
    bc = cfg;
    bc.sigma_m = 0.0f;
    assert_int_equal(trn_map_build(&map, &bc, &g, buf, mb), TRN_E_ARG);
    big = g;
    big.width = 0;
    assert_int_equal(trn_map_build(&map, &cfg, &big, buf, mb), TRN_E_SIZE);
    assert_int_equal(trn_map_build(&map, &cfg, &gn, buf, mb), TRN_E_NODATA);
    assert_int_equal(trn_map_build(&map, &cfg, &g, buf, mb), TRN_OK);

    /* localize_points */
    assert_int_equal(trn_localize_workspace_bytes(NULL, &win), 0u);
    assert_int_equal(trn_localize_workspace_bytes(&map, NULL), 0u);
    assert_int_equal(trn_localize_points(NULL, pts, 2, &win, ws, sizeof ws, &res), TRN_E_NULL);
    assert_int_equal(trn_localize_points(&map, NULL, 2, &win, ws, sizeof ws, &res), TRN_E_NULL);
    assert_int_equal(trn_localize_points(&map, pts, 2, NULL, ws, sizeof ws, &res), TRN_E_NULL);
    assert_int_equal(trn_localize_points(&map, pts, 2, &win, NULL, sizeof ws, &res), TRN_E_NULL);
    assert_int_equal(trn_localize_points(&map, pts, 2, &win, ws, sizeof ws, NULL), TRN_E_NULL);
    assert_int_equal(trn_localize_points(&map, pts, 0, &win, ws, sizeof ws, &res), TRN_E_NODATA);
    assert_int_equal(trn_localize_points(&map, pts, 2, &off, ws, sizeof ws, &res), TRN_E_RANGE);
    assert_int_equal(trn_localize_points(&map, pts, 2, &win, ws, 1, &res), TRN_E_WORKSPACE);
    assert_true(trn_localize_workspace_bytes(&map, &win) + 8u <= sizeof ws);
    assert_int_equal(trn_localize_points(&map, pts, 2, &win, ws + 8, sizeof ws - 8u, &res),
                     TRN_E_WORKSPACE);
    memset(&zero, 0, sizeof zero);
    assert_int_equal(trn_localize_points(&zero, pts, 2, &win, ws, sizeof ws, &res), TRN_E_ARG);

    /* localize_dem */
    assert_int_equal(trn_grid_f32_sub(&g, 5, 5, 20, 20, &local), TRN_OK);
    assert_int_equal(trn_localize_dem_workspace_bytes(NULL, 20, 20, 100, &win), 0u);
    assert_int_equal(trn_localize_dem_workspace_bytes(&map, 0, 20, 100, &win), 0u);
    assert_int_equal(trn_localize_dem_workspace_bytes(&map, 20, 20, 0, &win), 0u);
    assert_int_equal(trn_localize_dem(NULL, &local, 10, 10, 100, &win, ws, sizeof ws, &res),
                     TRN_E_NULL);
    assert_int_equal(trn_localize_dem(&map, NULL, 10, 10, 100, &win, ws, sizeof ws, &res),
                     TRN_E_NULL);
    assert_int_equal(trn_localize_dem(&map, &local, 10, 10, 100, NULL, ws, sizeof ws, &res),
                     TRN_E_NULL);
    assert_int_equal(trn_localize_dem(&map, &local, 10, 10, 100, &win, NULL, sizeof ws, &res),
                     TRN_E_NULL);
    assert_int_equal(trn_localize_dem(&map, &local, 10, 10, 100, &win, ws, sizeof ws, NULL),
                     TRN_E_NULL);
    big = local;
    big.height = TRN_MAX_DIM + 1;
    assert_int_equal(trn_localize_dem(&map, &big, 10, 10, 100, &win, ws, sizeof ws, &res),
                     TRN_E_SIZE);
    assert_int_equal(trn_localize_dem(&map, &local, 10, 10, 0, &win, ws, sizeof ws, &res),
                     TRN_E_ARG);
    assert_int_equal(trn_localize_dem(&zero, &local, 10, 10, 100, &win, ws, sizeof ws, &res),
                     TRN_E_ARG);
    assert_int_equal(trn_localize_dem(&map, &local, 10, 10, 100, &off, ws, sizeof ws, &res),
                     TRN_E_RANGE);
    assert_int_equal(trn_localize_dem(&map, &local, 10, 10, 100, &win, ws, 16, &res),
                     TRN_E_WORKSPACE);
    assert_true(trn_localize_dem_workspace_bytes(&map, 20, 20, 100, &win) + 8u <= sizeof ws);
    assert_int_equal(
        trn_localize_dem(&map, &local, 10, 10, 100, &win, ws + 8, sizeof ws - 8u, &res),
        TRN_E_WORKSPACE);
    assert_int_equal(trn_localize_dem(&map, &local, 10, 10, 3, &win, ws, sizeof ws, &res),
                     TRN_E_CAPACITY);
    assert_int_equal(trn_grid_f32_sub(&gn, 5, 5, 20, 20, &local), TRN_OK);
    assert_int_equal(trn_localize_dem(&map, &local, 10, 10, 100, &win, ws, sizeof ws, &res),
                     TRN_E_NODATA);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_integer_shift_exact),
        cmocka_unit_test(test_subpixel_rms),
        cmocka_unit_test(test_subpixel_fit_choice),
        cmocka_unit_test(test_flat_is_illcond),
        cmocka_unit_test(test_ridge_is_illcond),
        cmocka_unit_test(test_failure_probability),
        cmocka_unit_test(test_localize_matches_exhaustive),
        cmocka_unit_test(test_bad_inputs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
