/* SPDX-License-Identifier: Apache-2.0 */
/* test_likelihood_errors.c - one assertion per argument check of the
 * likelihood module (likelihood.h), each sub-condition of a compound check on
 * its own, as OSAL's coverage tests do: the rest of the arguments valid, one
 * made invalid, the documented status asserted. The behaviour on valid input
 * is tested in test_likelihood.c; here only the rejections. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "trn/likelihood.h"

#define NX 8
#define NY 8
#define NZ 4
#define CAP 9u

static uint8_t dist_buf[NX * NY * NZ];
TRN_WORKSPACE_DECLARE(pyr_buf, 1 << 16);
TRN_WORKSPACE_DECLARE(ws_buf, 4096 * sizeof(double));

typedef struct {
    trn_vol_u8_t dist;
    trn_lik_cfg_t cfg;
    trn_lnp_table_t t;
    trn_pyramid_t p;
    trn_point_t pts[2];
    trn_window_t win;
} fix_t;

static void fixture(fix_t *f)
{
    double k;
    size_t i;
    for (i = 0; i < sizeof dist_buf; ++i) {
        dist_buf[i] = (uint8_t)(i % (CAP + 1u));
    }
    assert_int_equal(trn_vol_u8_init(&f->dist, dist_buf, sizeof dist_buf, NX, NY, NZ), TRN_OK);
    f->cfg.cell_m = 0.1f;
    f->cfg.sigma_m = 0.1f;
    f->cfg.inlier_prob = 0.95f;
    f->cfg.cap = CAP;
    assert_int_equal(trn_outlier_density(&f->dist, &f->cfg, &k), TRN_OK);
    assert_int_equal(trn_lnp_table_build(&f->t, &f->cfg, k), TRN_OK);
    assert_int_equal(trn_pyramid_build(&f->p, &f->dist, CAP, 2, pyr_buf, sizeof pyr_buf), TRN_OK);
    f->pts[0].x = 0;
    f->pts[0].y = 0;
    f->pts[0].z = 1;
    f->pts[1].x = 1;
    f->pts[1].y = -1;
    f->pts[1].z = 2;
    f->win.x0 = 1;
    f->win.y0 = 1;
    f->win.x1 = 6;
    f->win.y1 = 6;
}

static void test_lik_cfg_each_field(void **state)
{
    trn_lik_cfg_t c, ok = {0.1f, 0.1f, 0.95f, CAP};
    (void)state;
    assert_int_equal(trn_lik_cfg_check(&ok), TRN_OK);
    c = ok;
    c.cell_m = 0.0f;
    assert_int_equal(trn_lik_cfg_check(&c), TRN_E_ARG);
    c = ok;
    c.cell_m = TRN_CELL_MAX_M;
    assert_int_equal(trn_lik_cfg_check(&c), TRN_OK);
    c.cell_m = nextafterf(TRN_CELL_MAX_M, INFINITY);
    assert_int_equal(trn_lik_cfg_check(&c), TRN_E_ARG);
    c = ok;
    c.cell_m = NAN;
    assert_int_equal(trn_lik_cfg_check(&c), TRN_E_ARG);
    c = ok;
    c.sigma_m = -1.0f;
    assert_int_equal(trn_lik_cfg_check(&c), TRN_E_ARG);
    c = ok; /* s: one cell in the map configurations, so the cell's bound */
    c.sigma_m = TRN_CELL_MAX_M;
    assert_int_equal(trn_lik_cfg_check(&c), TRN_OK);
    c.sigma_m = nextafterf(TRN_CELL_MAX_M, INFINITY);
    assert_int_equal(trn_lik_cfg_check(&c), TRN_E_ARG);
    c = ok;
    c.inlier_prob = 0.0f;
    assert_int_equal(trn_lik_cfg_check(&c), TRN_E_ARG);
    c = ok;
    c.inlier_prob = 1.0f;
    assert_int_equal(trn_lik_cfg_check(&c), TRN_E_ARG);
    c = ok;
    c.cap = 2u;
    assert_int_equal(trn_lik_cfg_check(&c), TRN_E_ARG);
    c = ok;
    c.cap = (uint8_t)(TRN_CHAMFER_CAP_MAX + 1);
    assert_int_equal(trn_lik_cfg_check(&c), TRN_E_ARG);
    assert_int_equal(trn_lik_cfg_check(NULL), TRN_E_NULL);
}

static void test_outlier_density_and_table_bad_cfg(void **state)
{
    fix_t f;
    trn_lik_cfg_t bad;
    double k = -1.0;
    (void)state;
    fixture(&f);
    bad = f.cfg;
    bad.sigma_m = 0.0f;
    assert_int_equal(trn_outlier_density(&f.dist, &bad, &k), TRN_E_ARG);
    assert_int_equal(trn_lnp_table_build(&f.t, &bad, 1.0), TRN_E_ARG);
    assert_int_equal(trn_lnp_table_build(&f.t, &f.cfg, INFINITY), TRN_E_ARG);
    assert_int_equal(trn_lnp_table_build(&f.t, &f.cfg, 0.0), TRN_E_ARG);
}

static void test_score_pose_table_cap(void **state)
{
    fix_t f;
    int64_t s;
    (void)state;
    fixture(&f);
    f.t.cap = 2u;
    assert_int_equal(trn_score_pose(&f.dist, &f.t, f.pts, 2, 3, 3, &s), TRN_E_ARG);
    f.t.cap = (uint8_t)(TRN_CHAMFER_CAP_MAX + 1);
    assert_int_equal(trn_score_pose(&f.dist, &f.t, f.pts, 2, 3, 3, &s), TRN_E_ARG);
}

static void test_score_pose_point_z(void **state)
{
    fix_t f;
    int64_t s;
    (void)state;
    fixture(&f);
    f.pts[1].z = -1;
    assert_int_equal(trn_score_pose(&f.dist, &f.t, f.pts, 2, 3, 3, &s), TRN_E_ARG);
    f.pts[1].z = NZ;
    assert_int_equal(trn_score_pose(&f.dist, &f.t, f.pts, 2, 3, 3, &s), TRN_E_ARG);
}

static void test_score_pose_far_pose(void **state)
{
    fix_t f;
    int64_t s;
    const int32_t far = 2 * TRN_MAX_DIM + 1;
    (void)state;
    fixture(&f);
    assert_int_equal(trn_score_pose(&f.dist, &f.t, f.pts, 2, -far, 3, &s), TRN_E_RANGE);
    assert_int_equal(trn_score_pose(&f.dist, &f.t, f.pts, 2, far, 3, &s), TRN_E_RANGE);
    assert_int_equal(trn_score_pose(&f.dist, &f.t, f.pts, 2, 3, -far, &s), TRN_E_RANGE);
    assert_int_equal(trn_score_pose(&f.dist, &f.t, f.pts, 2, 3, far, &s), TRN_E_RANGE);
    /* The farthest accepted pose scores every point as off the map. */
    assert_int_equal(trn_score_pose(&f.dist, &f.t, f.pts, 2, far - 1, 3, &s), TRN_OK);
    assert_true(s == 2 * (int64_t)f.t.lnp[CAP]);
}

/* Each bound of the window on its own, for both searches. */
static void test_window_each_bound(void **state)
{
    fix_t f;
    trn_best_t b;
    trn_window_t w;
    int i;
    (void)state;
    fixture(&f);
    for (i = 0; i < 6; ++i) {
        w = f.win;
        switch (i) {
        case 0: w.x0 = w.x1 + 1; break;
        case 1: w.y0 = w.y1 + 1; break;
        case 2: w.x0 = -1; break;
        case 3: w.y0 = -1; break;
        case 4: w.x1 = NX; break;
        default: w.y1 = NY; break;
        }
        assert_int_equal(trn_search_exhaustive(&f.dist, &f.t, f.pts, 2, &w, NULL, &b, NULL),
                         TRN_E_RANGE);
        assert_int_equal(
            trn_search_bb(&f.p, &f.t, f.pts, 2, &w, NULL, ws_buf, sizeof ws_buf, &b, NULL),
            TRN_E_RANGE);
    }
}

static void test_pyramid_bytes_each_arg(void **state)
{
    (void)state;
    assert_true(trn_pyramid_bytes(NX, NY, NZ, 2) > 0u);
    assert_int_equal(trn_pyramid_bytes(0, NY, NZ, 2), 0);
    assert_int_equal(trn_pyramid_bytes(NX, 0, NZ, 2), 0);
    assert_int_equal(trn_pyramid_bytes(NX, NY, 0, 2), 0);
    assert_int_equal(trn_pyramid_bytes(TRN_MAX_DIM + 1, NY, NZ, 2), 0);
    assert_int_equal(trn_pyramid_bytes(NX, TRN_MAX_DIM + 1, NZ, 2), 0);
    assert_int_equal(trn_pyramid_bytes(NX, NY, TRN_MAX_ZBINS + 1, 2), 0);
    assert_int_equal(trn_pyramid_bytes(NX, NY, NZ, 0), 0);
    assert_int_equal(trn_pyramid_bytes(NX, NY, NZ, TRN_MAX_LEVELS + 1), 0);
}

static void test_pyramid_build_each_arg(void **state)
{
    fix_t f;
    trn_pyramid_t p;
    (void)state;
    fixture(&f);
    assert_int_equal(trn_pyramid_build(&p, &f.dist, CAP, 0, pyr_buf, sizeof pyr_buf), TRN_E_ARG);
    assert_int_equal(
        trn_pyramid_build(&p, &f.dist, CAP, TRN_MAX_LEVELS + 1, pyr_buf, sizeof pyr_buf),
        TRN_E_ARG);
    assert_int_equal(trn_pyramid_build(&p, &f.dist, 2u, 2, pyr_buf, sizeof pyr_buf), TRN_E_ARG);
    assert_int_equal(trn_pyramid_build(&p, &f.dist, (uint8_t)(TRN_CHAMFER_CAP_MAX + 1), 2, pyr_buf,
                                       sizeof pyr_buf),
                     TRN_E_ARG);
}

static void test_bb_workspace_bytes_each_arg(void **state)
{
    fix_t f;
    trn_pyramid_t p;
    trn_window_t w;
    (void)state;
    fixture(&f);
    assert_true(trn_search_bb_workspace_bytes(&f.p, &f.win) > 0u);
    assert_int_equal(trn_search_bb_workspace_bytes(NULL, &f.win), 0);
    assert_int_equal(trn_search_bb_workspace_bytes(&f.p, NULL), 0);
    p = f.p;
    p.nlevels = 0;
    assert_int_equal(trn_search_bb_workspace_bytes(&p, &f.win), 0);
    p = f.p;
    p.nlevels = TRN_MAX_LEVELS + 1;
    assert_int_equal(trn_search_bb_workspace_bytes(&p, &f.win), 0);
    w = f.win;
    w.x1 = w.x0 - 1;
    assert_int_equal(trn_search_bb_workspace_bytes(&f.p, &w), 0);
    w = f.win;
    w.y1 = w.y0 - 1;
    assert_int_equal(trn_search_bb_workspace_bytes(&f.p, &w), 0);
    w = f.win;
    w.x0 = 0;
    w.x1 = TRN_MAX_DIM;
    assert_int_equal(trn_search_bb_workspace_bytes(&f.p, &w), 0);
    w = f.win;
    w.y0 = 0;
    w.y1 = TRN_MAX_DIM;
    assert_int_equal(trn_search_bb_workspace_bytes(&f.p, &w), 0);
}

static void test_search_bb_pyramid_table_mismatch(void **state)
{
    fix_t f;
    trn_pyramid_t p;
    trn_best_t b;
    (void)state;
    fixture(&f);
    assert_int_equal(
        trn_search_bb(&f.p, &f.t, f.pts, 2, &f.win, NULL, ws_buf, sizeof ws_buf, &b, NULL), TRN_OK);
    p = f.p;
    p.nlevels = 0;
    assert_int_equal(
        trn_search_bb(&p, &f.t, f.pts, 2, &f.win, NULL, ws_buf, sizeof ws_buf, &b, NULL),
        TRN_E_ARG);
    p = f.p;
    p.nlevels = TRN_MAX_LEVELS + 1;
    assert_int_equal(
        trn_search_bb(&p, &f.t, f.pts, 2, &f.win, NULL, ws_buf, sizeof ws_buf, &b, NULL),
        TRN_E_ARG);
    p = f.p;
    p.cap = (uint8_t)(CAP - 1u);
    assert_int_equal(
        trn_search_bb(&p, &f.t, f.pts, 2, &f.win, NULL, ws_buf, sizeof ws_buf, &b, NULL),
        TRN_E_ARG);
}

/* A distance volume with a zero dimension: TRN_E_SIZE from both searches. */
static void test_searches_bad_volume_size(void **state)
{
    fix_t f;
    trn_vol_u8_t d;
    trn_pyramid_t p;
    trn_best_t b;
    (void)state;
    fixture(&f);
    d = f.dist;
    d.nx = 0;
    assert_int_equal(trn_search_exhaustive(&d, &f.t, f.pts, 2, &f.win, NULL, &b, NULL), TRN_E_SIZE);
    p = f.p;
    p.base.ny = 0;
    assert_int_equal(
        trn_search_bb(&p, &f.t, f.pts, 2, &f.win, NULL, ws_buf, sizeof ws_buf, &b, NULL),
        TRN_E_SIZE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lik_cfg_each_field),
        cmocka_unit_test(test_outlier_density_and_table_bad_cfg),
        cmocka_unit_test(test_score_pose_table_cap),
        cmocka_unit_test(test_score_pose_point_z),
        cmocka_unit_test(test_score_pose_far_pose),
        cmocka_unit_test(test_window_each_bound),
        cmocka_unit_test(test_pyramid_bytes_each_arg),
        cmocka_unit_test(test_pyramid_build_each_arg),
        cmocka_unit_test(test_bb_workspace_bytes_each_arg),
        cmocka_unit_test(test_search_bb_pyramid_table_mismatch),
        cmocka_unit_test(test_searches_bad_volume_size),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
