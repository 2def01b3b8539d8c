/* SPDX-License-Identifier: Apache-2.0 */
/* test_grid.c - status codes (status.h) and grid/volume views (grid.h).
 *
 * Every documented @retval of trn_strerror, trn_grid_f32_init/check/sub and
 * trn_vol_u8_init/check has its own assertion; sub-view addressing is checked
 * against the parent's cells, and capacities exactly enough against one less.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "trn/grid.h"
#include "trn/status.h"
#include "rng.h"

/* ------------------------------------------------------------------------ */
/* status                                                                    */
/* ------------------------------------------------------------------------ */

static const trn_status_t k_all_status[] = {
    TRN_OK,        TRN_E_NULL,      TRN_E_ARG,       TRN_E_SIZE,     TRN_E_WORKSPACE,
    TRN_E_NODATA,  TRN_E_RANGE,     TRN_E_ILLCOND,   TRN_E_CAPACITY, TRN_E_NOTARGET,
    TRN_E_TIMEOUT, TRN_E_CRC,       TRN_E_SEQ,       TRN_E_BUS,      TRN_E_IO,
    TRN_E_FORMAT,  TRN_E_CANCELLED, TRN_E_AMBIGUOUS, TRN_E_BUDGET};
#define N_STATUS (sizeof k_all_status / sizeof k_all_status[0])

static void test_status_values_fixed(void **state)
{
    (void)state;
    /* The header promises values never change meaning. */
    assert_int_equal(TRN_OK, 0);
    assert_int_equal(TRN_E_NULL, -1);
    assert_int_equal(TRN_E_ARG, -2);
    assert_int_equal(TRN_E_SIZE, -3);
    assert_int_equal(TRN_E_WORKSPACE, -4);
    assert_int_equal(TRN_E_NODATA, -5);
    assert_int_equal(TRN_E_RANGE, -6);
    assert_int_equal(TRN_E_ILLCOND, -7);
    assert_int_equal(TRN_E_CAPACITY, -8);
    assert_int_equal(TRN_E_NOTARGET, -9);
    assert_int_equal(TRN_E_TIMEOUT, -10);
    assert_int_equal(TRN_E_CRC, -11);
    assert_int_equal(TRN_E_SEQ, -12);
    assert_int_equal(TRN_E_BUS, -13);
    assert_int_equal(TRN_E_IO, -14);
    assert_int_equal(TRN_E_FORMAT, -15);
    assert_int_equal(TRN_E_CANCELLED, -16);
    assert_int_equal(TRN_E_AMBIGUOUS, -17);
    assert_int_equal(TRN_E_BUDGET, -18);
}

static void test_strerror_distinct(void **state)
{
    size_t i, j;
    (void)state;
    for (i = 0; i < N_STATUS; ++i) {
        const char *s = trn_strerror(k_all_status[i]);
        assert_non_null(s);
        assert_true(strlen(s) > 0u);
        /* a known code never falls through to the default text */
        assert_string_not_equal(s, "unknown status");
        for (j = 0; j < i; ++j) {
            assert_string_not_equal(s, trn_strerror(k_all_status[j]));
        }
    }
}

static void test_strerror_unknown(void **state)
{
    static const int unknown[] = {1, 2, -19, -20, -100, 100, 0x7fffffff, -0x7fffffff};
    size_t i;
    (void)state;
    for (i = 0; i < sizeof unknown / sizeof unknown[0]; ++i) {
        const char *s = trn_strerror((trn_status_t)unknown[i]);
        assert_non_null(s);
        assert_string_equal(s, "unknown status");
    }
}

/* ------------------------------------------------------------------------ */
/* 2-D grids                                                                 */
/* ------------------------------------------------------------------------ */

static void test_grid_init_ok(void **state)
{
    static float buf[12];
    trn_grid_f32_t g;
    (void)state;
    memset(&g, 0, sizeof g);
    assert_int_equal(trn_grid_f32_init(&g, buf, 12u, 4, 3), TRN_OK);
    assert_ptr_equal(g.data, buf);
    assert_int_equal(g.width, 4);
    assert_int_equal(g.height, 3);
    assert_int_equal(g.stride, 4);
    assert_int_equal(trn_grid_f32_check(&g), TRN_OK);
    /* a 1x1 grid is the smallest */
    assert_int_equal(trn_grid_f32_init(&g, buf, 1u, 1, 1), TRN_OK);
    assert_int_equal(g.stride, 1);
}

static void test_grid_init_errors(void **state)
{
    static float buf[16];
    trn_grid_f32_t g;
    (void)state;
    /* TRN_E_NULL */
    assert_int_equal(trn_grid_f32_init(NULL, buf, 16u, 4, 4), TRN_E_NULL);
    assert_int_equal(trn_grid_f32_init(&g, NULL, 16u, 4, 4), TRN_E_NULL);
    /* TRN_E_SIZE: zero, negative, oversize, each dimension */
    assert_int_equal(trn_grid_f32_init(&g, buf, 16u, 0, 4), TRN_E_SIZE);
    assert_int_equal(trn_grid_f32_init(&g, buf, 16u, 4, 0), TRN_E_SIZE);
    assert_int_equal(trn_grid_f32_init(&g, buf, 16u, -1, 4), TRN_E_SIZE);
    assert_int_equal(trn_grid_f32_init(&g, buf, 16u, 4, -1), TRN_E_SIZE);
    assert_int_equal(trn_grid_f32_init(&g, buf, (size_t)-1, TRN_MAX_DIM + 1, 1), TRN_E_SIZE);
    assert_int_equal(trn_grid_f32_init(&g, buf, (size_t)-1, 1, TRN_MAX_DIM + 1), TRN_E_SIZE);
    assert_int_equal(trn_grid_f32_init(&g, buf, (size_t)-1, INT32_MIN, 1), TRN_E_SIZE);
    assert_int_equal(trn_grid_f32_init(&g, buf, (size_t)-1, 1, INT32_MAX), TRN_E_SIZE);
    /* TRN_MAX_DIM itself is allowed (the capacity claims enough: nothing is touched) */
    assert_int_equal(trn_grid_f32_init(&g, buf, (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM,
                                       TRN_MAX_DIM, TRN_MAX_DIM),
                     TRN_OK);
    /* TRN_E_WORKSPACE: capacity exactly enough vs one less */
    assert_int_equal(trn_grid_f32_init(&g, buf, 15u, 5, 3), TRN_OK);
    assert_int_equal(trn_grid_f32_init(&g, buf, 14u, 5, 3), TRN_E_WORKSPACE);
    assert_int_equal(trn_grid_f32_init(&g, buf, 0u, 1, 1), TRN_E_WORKSPACE);
    assert_int_equal(trn_grid_f32_init(&g, buf, (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM - 1u,
                                       TRN_MAX_DIM, TRN_MAX_DIM),
                     TRN_E_WORKSPACE);
}

static void test_grid_check_errors(void **state)
{
    static float buf[64];
    trn_grid_f32_t g;
    (void)state;
    assert_int_equal(trn_grid_f32_check(NULL), TRN_E_NULL);
    g.data = NULL;
    g.width = 4;
    g.height = 4;
    g.stride = 4;
    assert_int_equal(trn_grid_f32_check(&g), TRN_E_NULL);
    g.data = buf;
    assert_int_equal(trn_grid_f32_check(&g), TRN_OK);
    g.stride = 9; /* stride > width: a sub-view, fine */
    assert_int_equal(trn_grid_f32_check(&g), TRN_OK);
    g.stride = 3; /* stride < width */
    assert_int_equal(trn_grid_f32_check(&g), TRN_E_SIZE);
    g.stride = 0;
    assert_int_equal(trn_grid_f32_check(&g), TRN_E_SIZE);
    g.stride = -4;
    assert_int_equal(trn_grid_f32_check(&g), TRN_E_SIZE);
    g.stride = 4;
    g.width = 0;
    assert_int_equal(trn_grid_f32_check(&g), TRN_E_SIZE);
    g.width = -3;
    assert_int_equal(trn_grid_f32_check(&g), TRN_E_SIZE);
    g.width = 4;
    g.height = 0;
    assert_int_equal(trn_grid_f32_check(&g), TRN_E_SIZE);
    g.height = -3;
    assert_int_equal(trn_grid_f32_check(&g), TRN_E_SIZE);
    g.height = TRN_MAX_DIM + 1;
    assert_int_equal(trn_grid_f32_check(&g), TRN_E_SIZE);
    g.height = TRN_MAX_DIM;
    assert_int_equal(trn_grid_f32_check(&g), TRN_OK);
    g.height = 4;
    g.width = TRN_MAX_DIM + 1;
    g.stride = TRN_MAX_DIM + 1;
    assert_int_equal(trn_grid_f32_check(&g), TRN_E_SIZE);
    g.width = TRN_MAX_DIM;
    g.stride = TRN_MAX_DIM;
    assert_int_equal(trn_grid_f32_check(&g), TRN_OK);
}

static void test_grid_sub_errors(void **state)
{
    static float buf[10 * 8];
    trn_grid_f32_t g, s, bad;
    (void)state;
    assert_int_equal(trn_grid_f32_init(&g, buf, 80u, 10, 8), TRN_OK);
    /* TRN_E_NULL: g, g->data, sub */
    assert_int_equal(trn_grid_f32_sub(NULL, 0, 0, 1, 1, &s), TRN_E_NULL);
    assert_int_equal(trn_grid_f32_sub(&g, 0, 0, 1, 1, NULL), TRN_E_NULL);
    bad = g;
    bad.data = NULL;
    assert_int_equal(trn_grid_f32_sub(&bad, 0, 0, 1, 1, &s), TRN_E_NULL);
    /* TRN_E_SIZE: bad parent, zero or negative size */
    bad = g;
    bad.stride = 9;
    assert_int_equal(trn_grid_f32_sub(&bad, 0, 0, 1, 1, &s), TRN_E_SIZE);
    bad = g;
    bad.height = 0;
    assert_int_equal(trn_grid_f32_sub(&bad, 0, 0, 1, 1, &s), TRN_E_SIZE);
    assert_int_equal(trn_grid_f32_sub(&g, 0, 0, 0, 1, &s), TRN_E_SIZE);
    assert_int_equal(trn_grid_f32_sub(&g, 0, 0, 1, 0, &s), TRN_E_SIZE);
    assert_int_equal(trn_grid_f32_sub(&g, 0, 0, -1, 1, &s), TRN_E_SIZE);
    assert_int_equal(trn_grid_f32_sub(&g, 0, 0, 1, -1, &s), TRN_E_SIZE);
    /* TRN_E_RANGE: each edge, one past */
    assert_int_equal(trn_grid_f32_sub(&g, -1, 0, 1, 1, &s), TRN_E_RANGE);
    assert_int_equal(trn_grid_f32_sub(&g, 0, -1, 1, 1, &s), TRN_E_RANGE);
    assert_int_equal(trn_grid_f32_sub(&g, 10, 0, 1, 1, &s), TRN_E_RANGE);
    assert_int_equal(trn_grid_f32_sub(&g, 0, 8, 1, 1, &s), TRN_E_RANGE);
    assert_int_equal(trn_grid_f32_sub(&g, 3, 0, 8, 1, &s), TRN_E_RANGE);
    assert_int_equal(trn_grid_f32_sub(&g, 0, 2, 1, 7, &s), TRN_E_RANGE);
    assert_int_equal(trn_grid_f32_sub(&g, 0, 0, 11, 1, &s), TRN_E_RANGE);
    assert_int_equal(trn_grid_f32_sub(&g, 0, 0, 1, 9, &s), TRN_E_RANGE);
    assert_int_equal(trn_grid_f32_sub(&g, 0, 0, INT32_MAX, 1, &s), TRN_E_RANGE);
    assert_int_equal(trn_grid_f32_sub(&g, INT32_MAX, 0, 1, 1, &s), TRN_E_RANGE);
    assert_int_equal(trn_grid_f32_sub(&g, INT32_MIN, 0, 1, 1, &s), TRN_E_RANGE);
    /* exactly fitting rectangles are fine */
    assert_int_equal(trn_grid_f32_sub(&g, 0, 0, 10, 8, &s), TRN_OK);
    assert_int_equal(trn_grid_f32_sub(&g, 2, 0, 8, 1, &s), TRN_OK);
    assert_int_equal(trn_grid_f32_sub(&g, 0, 1, 1, 7, &s), TRN_OK);
    assert_int_equal(trn_grid_f32_sub(&g, 9, 7, 1, 1, &s), TRN_OK);
}

static void test_grid_sub_addressing(void **state)
{
    enum { W = 13, H = 11 };
    static float buf[W * H];
    trn_grid_f32_t g, s, ss;
    trn_rng_t rng;
    int32_t i, x, y;
    (void)state;
    for (i = 0; i < W * H; ++i) {
        buf[i] = (float)i; /* each cell holds its own linear index */
    }
    assert_int_equal(trn_grid_f32_init(&g, buf, (size_t)(W * H), W, H), TRN_OK);
    for (y = 0; y < H; ++y) {
        for (x = 0; x < W; ++x) {
            assert_true(TRN_GRID_AT(&g, x, y) == (float)(y * W + x));
        }
    }
    trn_rng_seed(&rng, 0x6772696475ull);
    for (i = 0; i < 500; ++i) {
        int32_t x0 = trn_rng_int(&rng, 0, W - 1), y0 = trn_rng_int(&rng, 0, H - 1);
        int32_t sw = trn_rng_int(&rng, 1, W - x0), sh = trn_rng_int(&rng, 1, H - y0);
        int32_t x1, y1, sw2, sh2;
        assert_int_equal(trn_grid_f32_sub(&g, x0, y0, sw, sh, &s), TRN_OK);
        assert_int_equal(s.width, sw);
        assert_int_equal(s.height, sh);
        assert_int_equal(s.stride, W);
        assert_int_equal(trn_grid_f32_check(&s), TRN_OK);
        for (y = 0; y < sh; ++y) {
            for (x = 0; x < sw; ++x) {
                assert_ptr_equal(&TRN_GRID_AT(&s, x, y), &TRN_GRID_AT(&g, x0 + x, y0 + y));
                assert_true(TRN_GRID_AT(&s, x, y) == (float)((y0 + y) * W + x0 + x));
            }
        }
        /* a sub-view of a sub-view addresses the grandparent */
        x1 = trn_rng_int(&rng, 0, sw - 1);
        y1 = trn_rng_int(&rng, 0, sh - 1);
        sw2 = trn_rng_int(&rng, 1, sw - x1);
        sh2 = trn_rng_int(&rng, 1, sh - y1);
        assert_int_equal(trn_grid_f32_sub(&s, x1, y1, sw2, sh2, &ss), TRN_OK);
        assert_int_equal(ss.stride, W);
        for (y = 0; y < sh2; ++y) {
            for (x = 0; x < sw2; ++x) {
                assert_ptr_equal(&TRN_GRID_AT(&ss, x, y),
                                 &TRN_GRID_AT(&g, x0 + x1 + x, y0 + y1 + y));
            }
        }
        /* ...and its range is that of the sub-view, not of the grandparent */
        assert_int_equal(trn_grid_f32_sub(&s, x1, y1, sw - x1 + 1, 1, &ss), TRN_E_RANGE);
        assert_int_equal(trn_grid_f32_sub(&s, x1, y1, 1, sh - y1 + 1, &ss), TRN_E_RANGE);
    }
    /* writes through a sub-view land in the parent */
    assert_int_equal(trn_grid_f32_sub(&g, 3, 4, 2, 2, &s), TRN_OK);
    TRN_GRID_AT(&s, 1, 1) = -7.5f;
    assert_true(buf[5 * W + 4] == -7.5f);
}

/* ------------------------------------------------------------------------ */
/* 3-D volumes                                                               */
/* ------------------------------------------------------------------------ */

static void test_vol_init_ok(void **state)
{
    static uint8_t buf[5 * 4 * 3];
    trn_vol_u8_t v;
    (void)state;
    memset(&v, 0, sizeof v);
    assert_int_equal(trn_vol_u8_init(&v, buf, sizeof buf, 5, 4, 3), TRN_OK);
    assert_ptr_equal(v.data, buf);
    assert_int_equal(v.nx, 5);
    assert_int_equal(v.ny, 4);
    assert_int_equal(v.nz, 3);
    assert_int_equal(trn_vol_u8_check(&v), TRN_OK);
}

static void test_vol_init_errors(void **state)
{
    static uint8_t buf[64];
    const size_t big = (size_t)-1;
    trn_vol_u8_t v;
    (void)state;
    /* TRN_E_NULL */
    assert_int_equal(trn_vol_u8_init(NULL, buf, 64u, 2, 2, 2), TRN_E_NULL);
    assert_int_equal(trn_vol_u8_init(&v, NULL, 64u, 2, 2, 2), TRN_E_NULL);
    /* TRN_E_SIZE: each dimension zero, negative, one over its maximum */
    assert_int_equal(trn_vol_u8_init(&v, buf, 64u, 0, 2, 2), TRN_E_SIZE);
    assert_int_equal(trn_vol_u8_init(&v, buf, 64u, 2, 0, 2), TRN_E_SIZE);
    assert_int_equal(trn_vol_u8_init(&v, buf, 64u, 2, 2, 0), TRN_E_SIZE);
    assert_int_equal(trn_vol_u8_init(&v, buf, 64u, -2, 2, 2), TRN_E_SIZE);
    assert_int_equal(trn_vol_u8_init(&v, buf, 64u, 2, -2, 2), TRN_E_SIZE);
    assert_int_equal(trn_vol_u8_init(&v, buf, 64u, 2, 2, -2), TRN_E_SIZE);
    assert_int_equal(trn_vol_u8_init(&v, buf, big, TRN_MAX_DIM + 1, 1, 1), TRN_E_SIZE);
    assert_int_equal(trn_vol_u8_init(&v, buf, big, 1, TRN_MAX_DIM + 1, 1), TRN_E_SIZE);
    assert_int_equal(trn_vol_u8_init(&v, buf, big, 1, 1, TRN_MAX_ZBINS + 1), TRN_E_SIZE);
    /* the maxima themselves are allowed */
    assert_int_equal(trn_vol_u8_init(&v, buf, big, TRN_MAX_DIM, TRN_MAX_DIM, TRN_MAX_ZBINS),
                     TRN_OK);
    /* TRN_E_WORKSPACE: exactly enough vs one less */
    assert_int_equal(trn_vol_u8_init(&v, buf, 60u, 5, 4, 3), TRN_OK);
    assert_int_equal(trn_vol_u8_init(&v, buf, 59u, 5, 4, 3), TRN_E_WORKSPACE);
    assert_int_equal(trn_vol_u8_init(&v, buf, 0u, 1, 1, 1), TRN_E_WORKSPACE);
    assert_int_equal(
        trn_vol_u8_init(&v, buf,
                        (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_ZBINS - 1u,
                        TRN_MAX_DIM, TRN_MAX_DIM, TRN_MAX_ZBINS),
        TRN_E_WORKSPACE);
}

static void test_vol_check_errors(void **state)
{
    static uint8_t buf[8];
    trn_vol_u8_t v;
    (void)state;
    assert_int_equal(trn_vol_u8_check(NULL), TRN_E_NULL);
    v.data = NULL;
    v.nx = 2;
    v.ny = 2;
    v.nz = 2;
    assert_int_equal(trn_vol_u8_check(&v), TRN_E_NULL);
    v.data = buf;
    assert_int_equal(trn_vol_u8_check(&v), TRN_OK);
    v.nx = 0;
    assert_int_equal(trn_vol_u8_check(&v), TRN_E_SIZE);
    v.nx = TRN_MAX_DIM + 1;
    assert_int_equal(trn_vol_u8_check(&v), TRN_E_SIZE);
    v.nx = 2;
    v.ny = -1;
    assert_int_equal(trn_vol_u8_check(&v), TRN_E_SIZE);
    v.ny = TRN_MAX_DIM + 1;
    assert_int_equal(trn_vol_u8_check(&v), TRN_E_SIZE);
    v.ny = 2;
    v.nz = 0;
    assert_int_equal(trn_vol_u8_check(&v), TRN_E_SIZE);
    v.nz = TRN_MAX_ZBINS + 1;
    assert_int_equal(trn_vol_u8_check(&v), TRN_E_SIZE);
    v.nz = TRN_MAX_ZBINS;
    assert_int_equal(trn_vol_u8_check(&v), TRN_OK);
}

static void test_vol_index(void **state)
{
    enum { NX = 5, NY = 4, NZ = 3 };
    static uint8_t buf[NX * NY * NZ];
    trn_vol_u8_t v;
    int32_t x, y, z;
    size_t expect = 0;
    (void)state;
    assert_int_equal(trn_vol_u8_init(&v, buf, sizeof buf, NX, NY, NZ), TRN_OK);
    /* dense, x fastest, then y, then z: visiting in that order counts 0, 1, 2, ... */
    for (z = 0; z < NZ; ++z) {
        for (y = 0; y < NY; ++y) {
            for (x = 0; x < NX; ++x) {
                assert_int_equal(TRN_VOL_IDX(&v, x, y, z), expect);
                ++expect;
            }
        }
    }
    assert_int_equal(expect, sizeof buf);
}

static void test_align_up(void **state)
{
    size_t n;
    (void)state;
    assert_int_equal(TRN_ALIGN_UP(0u), 0u);
    for (n = 1u; n <= 100u; ++n) {
        size_t a = TRN_ALIGN_UP(n);
        assert_int_equal(a % 16u, 0u);
        assert_true(a >= n && a < n + 16u);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_status_values_fixed),
        cmocka_unit_test(test_strerror_distinct),
        cmocka_unit_test(test_strerror_unknown),
        cmocka_unit_test(test_grid_init_ok),
        cmocka_unit_test(test_grid_init_errors),
        cmocka_unit_test(test_grid_check_errors),
        cmocka_unit_test(test_grid_sub_errors),
        cmocka_unit_test(test_grid_sub_addressing),
        cmocka_unit_test(test_vol_init_ok),
        cmocka_unit_test(test_vol_init_errors),
        cmocka_unit_test(test_vol_check_errors),
        cmocka_unit_test(test_vol_index),
        cmocka_unit_test(test_align_up),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
