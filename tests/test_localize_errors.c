/* SPDX-License-Identifier: Apache-2.0 */
/* test_localize_errors.c - the argument checks of localize.h one
 * sub-condition at a time (test_localize.c's test_bad_inputs covers one case
 * per status; here every clause of each compound check gets its own
 * assertion, as OSAL's coverage tests do), plus the single-pose window whose
 * second search has no pose left (has_second = 0). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "trn/localize.h"

enum { N = 24 };
static float dem[N * N];
TRN_WORKSPACE_DECLARE(map_buf, 1 << 20);
TRN_WORKSPACE_DECLARE(ws, 1 << 16);

static void build(trn_map_t *map, trn_map_cfg_t *cfg, trn_grid_f32_t *g)
{
    size_t mb;
    int i;
    for (i = 0; i < N * N; ++i) {
        dem[i] = (float)(0.3 * sin(i * 0.37) * cos(i * 0.011));
    }
    assert_int_equal(trn_grid_f32_init(g, dem, N * N, N, N), TRN_OK);
    trn_map_cfg_default(cfg);
    cfg->levels = 2;
    mb = trn_map_bytes(cfg, N, N);
    assert_true(mb > 0u && mb <= sizeof map_buf);
    assert_int_equal(trn_map_build(map, cfg, g, map_buf, mb), TRN_OK);
}

static void test_map_cfg_exclusion_upper(void **state)
{
    trn_map_cfg_t cfg, bc;
    (void)state;
    trn_map_cfg_default(&cfg);
    bc = cfg;
    bc.min_exclusion_cells = TRN_MAX_DIM;
    assert_int_equal(trn_map_cfg_check(&bc), TRN_OK);
    bc = cfg;
    bc.min_exclusion_cells = TRN_MAX_DIM + 1;
    assert_int_equal(trn_map_cfg_check(&bc), TRN_E_ARG);
}

static void test_map_bytes_each_dim(void **state)
{
    trn_map_cfg_t cfg, bc;
    (void)state;
    trn_map_cfg_default(&cfg);
    assert_true(trn_map_bytes(&cfg, 1, 1) > 0u);
    assert_int_equal(trn_map_bytes(&cfg, 0, 1), 0u);
    assert_int_equal(trn_map_bytes(&cfg, 1, 0), 0u);
    assert_int_equal(trn_map_bytes(&cfg, TRN_MAX_DIM + 1, 1), 0u);
    assert_int_equal(trn_map_bytes(&cfg, 1, TRN_MAX_DIM + 1), 0u);
    bc = cfg;
    bc.levels = 0;
    assert_int_equal(trn_map_bytes(&bc, 1, 1), 0u);
}

/* A map whose fields disagree is rejected before any work, field by field. */
static void test_corrupt_map_each_field(void **state)
{
    trn_map_t map, bad;
    trn_map_cfg_t cfg;
    trn_grid_f32_t g;
    trn_window_t win = {4, 4, 18, 18};
    trn_point_t pts[2] = {{0, 0, 8}, {1, 0, 8}};
    trn_loc_result_t res;
    (void)state;
    build(&map, &cfg, &g);
    assert_true(trn_localize_workspace_bytes(&map, &win) > 0u);
    bad = map;
    bad.cfg.sigma_m = 0.0f;
    assert_int_equal(trn_localize_points(&bad, pts, 2, &win, ws, sizeof ws, &res), TRN_E_ARG);
    assert_int_equal(trn_localize_workspace_bytes(&bad, &win), 0u);
    bad = map;
    bad.dist.nz = 0;
    assert_int_equal(trn_localize_points(&bad, pts, 2, &win, ws, sizeof ws, &res), TRN_E_ARG);
    bad = map;
    bad.pyr.nlevels = map.cfg.levels + 1;
    assert_int_equal(trn_localize_points(&bad, pts, 2, &win, ws, sizeof ws, &res), TRN_E_ARG);
    bad = map;
    bad.lnp.cap = (uint8_t)(map.cfg.cap - 1u);
    assert_int_equal(trn_localize_points(&bad, pts, 2, &win, ws, sizeof ws, &res), TRN_E_ARG);
    assert_int_equal(trn_localize_dem(&bad, &g, 10, 10, 100, &win, ws, sizeof ws, &res), TRN_E_ARG);
}

static void test_window_each_bound(void **state)
{
    trn_map_t map;
    trn_map_cfg_t cfg;
    trn_grid_f32_t g, local;
    trn_window_t ok = {4, 4, 18, 18}, w;
    trn_point_t pts[2] = {{0, 0, 8}, {1, 0, 8}};
    trn_loc_result_t res;
    int i;
    (void)state;
    build(&map, &cfg, &g);
    assert_int_equal(trn_grid_f32_sub(&g, 2, 2, 12, 12, &local), TRN_OK);
    for (i = 0; i < 6; ++i) {
        w = ok;
        switch (i) {
        case 0: w.x0 = w.x1 + 1; break;
        case 1: w.y0 = w.y1 + 1; break;
        case 2: w.x0 = -1; break;
        case 3: w.y0 = -1; break;
        case 4: w.x1 = N; break;
        default: w.y1 = N; break;
        }
        assert_int_equal(trn_localize_points(&map, pts, 2, &w, ws, sizeof ws, &res), TRN_E_RANGE);
        assert_int_equal(trn_localize_dem(&map, &local, 6, 6, 500, &w, ws, sizeof ws, &res),
                         TRN_E_RANGE);
    }
}

static void test_dem_workspace_bytes_each_arg(void **state)
{
    trn_map_t map;
    trn_map_cfg_t cfg;
    trn_grid_f32_t g;
    trn_window_t win = {4, 4, 18, 18}, bad = {4, 4, 3, 18};
    const size_t too_many = (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM + 1u;
    (void)state;
    build(&map, &cfg, &g);
    assert_true(trn_localize_dem_workspace_bytes(&map, 12, 12, 100, &win) > 0u);
    assert_int_equal(trn_localize_dem_workspace_bytes(&map, 12, 12, 100, NULL), 0u);
    assert_int_equal(trn_localize_dem_workspace_bytes(&map, 12, 12, 100, &bad), 0u);
    assert_int_equal(trn_localize_dem_workspace_bytes(&map, 12, 12, too_many, &win), 0u);
}

static void test_localize_dem_too_many_points(void **state)
{
    trn_map_t map;
    trn_map_cfg_t cfg;
    trn_grid_f32_t g, local;
    trn_window_t win = {4, 4, 18, 18};
    trn_loc_result_t res;
    const size_t too_many = (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM + 1u;
    (void)state;
    build(&map, &cfg, &g);
    assert_int_equal(trn_grid_f32_sub(&g, 2, 2, 12, 12, &local), TRN_OK);
    assert_int_equal(trn_localize_dem(&map, &local, 6, 6, too_many, &win, ws, sizeof ws, &res),
                     TRN_E_ARG);
}

/* A one-pose window: the competing-hypothesis search has nothing left, so
 * there is no second pose and the failure probability is 0. */
static void test_single_pose_window_has_no_second(void **state)
{
    trn_map_t map;
    trn_map_cfg_t cfg;
    trn_grid_f32_t g, local;
    trn_window_t win = {10, 10, 10, 10};
    trn_loc_result_t res;
    trn_status_t st;
    (void)state;
    build(&map, &cfg, &g);
    assert_int_equal(trn_grid_f32_sub(&g, 4, 4, 12, 12, &local), TRN_OK);
    st = trn_localize_dem(&map, &local, 6, 6, 2000, &win, ws, sizeof ws, &res);
    assert_true(st == TRN_OK || st == TRN_E_ILLCOND);
    assert_int_equal(res.ix, 10);
    assert_int_equal(res.iy, 10);
    assert_int_equal(res.has_second, 0);
    assert_true(res.failure_probability == 0.0);
    assert_true(res.ll_second == res.ll_best);
    assert_int_equal(res.on_window_edge, 1);
}

/* The local map is the global one cut at (4, 4), rover at local (6, 6): the
 * true pose is (10, 10). Windows that put the truth on each of the four
 * edges in turn, and one with the truth inside: on_window_edge must say
 * which. */
static void test_window_edge_flag_each_side(void **state)
{
    trn_map_t map;
    trn_map_cfg_t cfg;
    trn_grid_f32_t g, local;
    const trn_window_t wins[5] = {
        {10, 8, 14, 12}, /* truth on x0 */
        {6, 8, 10, 12},  /* on x1 */
        {8, 10, 12, 14}, /* on y0 */
        {8, 6, 12, 10},  /* on y1 */
        {8, 8, 12, 12},  /* inside */
    };
    trn_loc_result_t res;
    trn_status_t st;
    int i;
    (void)state;
    build(&map, &cfg, &g);
    assert_int_equal(trn_grid_f32_sub(&g, 4, 4, 12, 12, &local), TRN_OK);
    for (i = 0; i < 5; ++i) {
        st = trn_localize_dem(&map, &local, 6, 6, 4000, &wins[i], ws, sizeof ws, &res);
        assert_true(st == TRN_OK || st == TRN_E_ILLCOND);
        assert_int_equal(res.ix, 10);
        assert_int_equal(res.iy, 10);
        assert_int_equal(res.on_window_edge, i < 4 ? 1 : 0);
    }
}

/* A smooth global map (one Gaussian hill, 2 cells wide) and s = 4 cells:
 * the peak is wide (sigma about 0.6 cells), so the exclusion zone grows from min_exclusion_cells to
 * ceil(4 max(sigma)) cells, as localize.h documents. */
static void test_broad_peak_widens_exclusion(void **state)
{
    trn_map_t map;
    trn_map_cfg_t cfg;
    trn_grid_f32_t g, local;
    trn_window_t win = {6, 6, 18, 18};
    trn_loc_result_t res;
    trn_status_t st;
    double smax_cells;
    size_t mb;
    int x, y;
    (void)state;
    for (y = 0; y < N; ++y) {
        for (x = 0; x < N; ++x) {
            const double dx = x - 12.0, dy = y - 12.0;
            dem[y * N + x] = (float)(1.5 * exp(-(dx * dx + dy * dy) / (2.0 * 2.0 * 2.0)));
        }
    }
    assert_int_equal(trn_grid_f32_init(&g, dem, N * N, N, N), TRN_OK);
    trn_map_cfg_default(&cfg);
    cfg.levels = 2;
    cfg.terrain.highpass_half_m = 2.0f;
    cfg.sigma_m = 0.4f; /* s = 4 cells: ln p changes slowly with distance */
    mb = trn_map_bytes(&cfg, N, N);
    assert_int_equal(trn_map_build(&map, &cfg, &g, map_buf, mb), TRN_OK);
    assert_int_equal(trn_grid_f32_sub(&g, 6, 6, 12, 12, &local), TRN_OK);
    st = trn_localize_dem(&map, &local, 6, 6, 4000, &win, ws, sizeof ws, &res);
    assert_int_equal(st, TRN_OK);
    assert_int_equal(res.ix, 12); /* the truth: cut at (6, 6), rover at local (6, 6) */
    assert_int_equal(res.iy, 12);
    smax_cells = (res.sigma_x_m > res.sigma_y_m ? res.sigma_x_m : res.sigma_y_m) / 0.1;
    print_message("broad peak: sigma %.3f cells, exclusion %d cells\n", smax_cells,
                  (int)res.exclusion_cells);
    assert_true(4.0 * smax_cells > (double)cfg.min_exclusion_cells);
    assert_int_equal(res.exclusion_cells, (int32_t)ceil(4.0 * smax_cells - 1e-9));
}

/* localize_points' remaining documented statuses: TRN_E_SIZE from a map
 * whose search pyramid has lost its base volume, and TRN_E_ILLCOND from a
 * flat map matched with a flat patch (every pose scores the same). */
/* trn_prob_beyond: one assertion per documented @retval and per check. */
static void test_prob_beyond_args(void **state)
{
    const double ok[3] = {1.0, 0.5, 0.2};
    double cov[3], p = -1.0;
    int i;
    (void)state;
    assert_int_equal(trn_prob_beyond(NULL, 1.0, &p), TRN_E_NULL);
    assert_int_equal(trn_prob_beyond(ok, 1.0, NULL), TRN_E_NULL);
    assert_int_equal(trn_prob_beyond(ok, 0.0, &p), TRN_E_ARG);
    assert_int_equal(trn_prob_beyond(ok, -1.0, &p), TRN_E_ARG);
    assert_int_equal(trn_prob_beyond(ok, (double)NAN, &p), TRN_E_ARG);
    assert_int_equal(trn_prob_beyond(ok, (double)INFINITY, &p), TRN_E_ARG);
    for (i = 0; i < 3; ++i) {
        memcpy(cov, ok, sizeof cov);
        cov[i] = (double)NAN;
        assert_int_equal(trn_prob_beyond(cov, 1.0, &p), TRN_E_ARG);
        cov[i] = (double)INFINITY;
        assert_int_equal(trn_prob_beyond(cov, 1.0, &p), TRN_E_ARG);
    }
    cov[0] = -1e-9; /* a negative variance */
    cov[1] = 1.0;
    cov[2] = 0.0;
    assert_int_equal(trn_prob_beyond(cov, 1.0, &p), TRN_E_ARG);
    cov[0] = 1.0;
    cov[1] = -1e-9;
    assert_int_equal(trn_prob_beyond(cov, 1.0, &p), TRN_E_ARG);
    cov[1] = 1.0;
    cov[2] = 1.0 + 1e-9; /* |cov_xy| beyond sqrt(var_x var_y) */
    assert_int_equal(trn_prob_beyond(cov, 1.0, &p), TRN_E_ARG);
    cov[2] = -1.0 - 1e-9;
    assert_int_equal(trn_prob_beyond(cov, 1.0, &p), TRN_E_ARG);
    assert_true(p == -1.0); /* untouched on every error */
    cov[2] = -1.0;          /* semi-definite: allowed */
    assert_int_equal(trn_prob_beyond(cov, 1.0, &p), TRN_OK);
    assert_true(p > 0.0 && p < 1.0);
}

static void test_localize_points_size_and_illcond(void **state)
{
    trn_map_t map, bad;
    trn_map_cfg_t cfg;
    trn_grid_f32_t g;
    trn_window_t win = {6, 6, 16, 16};
    trn_point_t plane[25];
    trn_loc_result_t res;
    size_t mb;
    int i;
    (void)state;
    build(&map, &cfg, &g);
    for (i = 0; i < 25; ++i) {
        plane[i].x = (int16_t)(i % 5 - 2);
        plane[i].y = (int16_t)(i / 5 - 2);
        plane[i].z = (int16_t)(cfg.terrain.nz / 2);
    }
    bad = map;
    bad.pyr.base.nx = 0;
    assert_int_equal(trn_localize_points(&bad, plane, 25, &win, ws, sizeof ws, &res), TRN_E_SIZE);

    for (i = 0; i < N * N; ++i) {
        dem[i] = 0.0f;
    }
    mb = trn_map_bytes(&cfg, N, N);
    assert_int_equal(trn_map_build(&map, &cfg, &g, map_buf, mb), TRN_OK);
    assert_int_equal(trn_localize_points(&map, plane, 25, &win, ws, sizeof ws, &res),
                     TRN_E_ILLCOND);
    assert_true(isinf(res.sigma_x_m) && isinf(res.sigma_y_m));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_map_cfg_exclusion_upper),
        cmocka_unit_test(test_map_bytes_each_dim),
        cmocka_unit_test(test_corrupt_map_each_field),
        cmocka_unit_test(test_window_each_bound),
        cmocka_unit_test(test_dem_workspace_bytes_each_arg),
        cmocka_unit_test(test_localize_dem_too_many_points),
        cmocka_unit_test(test_single_pose_window_has_no_second),
        cmocka_unit_test(test_window_edge_flag_each_side),
        cmocka_unit_test(test_broad_peak_widens_exclusion),
        cmocka_unit_test(test_localize_points_size_and_illcond),
        cmocka_unit_test(test_prob_beyond_args),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
