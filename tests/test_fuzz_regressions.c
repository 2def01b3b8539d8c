/* SPDX-License-Identifier: Apache-2.0 */
/* test_fuzz_regressions.c - every input the fuzzers (tests/fuzz/) found that
 * broke a contract, as a unit test written before the fix (docs/assurance.md,
 * "Fuzzing"). Each test names the harness and the artifact it came from and
 * asserts the documented behaviour, so it failed on the code of that day.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>

#include "trn/mast.h"
#include "trn/peakfit.h"
#include "trn/terrain.h"

/* fuzz_peakfit, crash-5289317781f4840a61fb1087d1469cded5b6e886: a peak of
 * curvature ~1e231 nats/cell^2. det(H) overflowed to +inf, so the variances
 * came out 0 and rho NaN with TRN_OK. Contract: TRN_OK only with finite,
 * positive variances and |rho| < 1. The exact answer: -H^-1 is tiny but
 * representable (about 1e-232 cells^2). */
static void test_peakfit_huge_curvature(void **state)
{
    const double ll[9] = {
        4.074231918653e-312, -1.000000000014495,     -2.0, -1.0, 0.0, -1.0, -3.105036184601418e+231,
        9.44e-322,           -3.105036184601418e+231};
    trn_peak_t p;
    trn_status_t st;
    (void)state;
    st = trn_peak_fit(ll, &p);
    if (st == TRN_OK) {
        assert_true(p.var_x > 0.0 && isfinite(p.var_x));
        assert_true(p.var_y > 0.0 && isfinite(p.var_y));
        assert_true(p.sigma_x > 0.0 && p.sigma_y > 0.0);
        assert_true(isfinite(p.rho) && fabs(p.rho) < 1.0);
    } else {
        assert_int_equal(st, TRN_E_ILLCOND);
        assert_true(isinf(p.sigma_x) && isinf(p.sigma_y));
    }
}

/* fuzz_peakfit, crash-93e437fa0d133bff67cf81e6642301d8f3b1e9f8: finite
 * inputs near +-1e308 whose differences overflow the gradient sums; the peak
 * offset came out NaN with TRN_OK. Contract: TRN_OK only with |dx|, |dy| <= 1
 * (NaN is not), otherwise TRN_E_ILLCOND with infinite sigmas. */
static void test_peakfit_gradient_overflow(void **state)
{
    const double ll[9] = {9.999996651535603e+307,  1.38099255942677e-309,  -3.065401726890636e+248,
                          -3.065401728968514e+248, 3.000000007447147,      4.0,
                          1.8986433709307e-310,    2.027487299871762e-304, -9.99999999869373e+307};
    trn_peak_t p;
    trn_status_t st;
    (void)state;
    st = trn_peak_fit(ll, &p);
    if (st == TRN_OK) {
        assert_true(fabs(p.dx) <= 1.0 && fabs(p.dy) <= 1.0);
        assert_true(p.var_x > 0.0 && isfinite(p.var_x) && p.var_y > 0.0 && isfinite(p.var_y));
    } else {
        assert_int_equal(st, TRN_E_ILLCOND);
        assert_true(isinf(p.sigma_x) && isinf(p.sigma_y));
        assert_true(p.dx == 0.0 && p.dy == 0.0);
    }
}

/* The limit both findings led to: a difference of exactly 1e300 nats is
 * fitted, one beyond it is TRN_E_ILLCOND (peakfit.h). */
static void test_peakfit_difference_limit(void **state)
{
    double ll[9] = {-1.0, -1.0, -1.0, -1.0, 0.0, -1.0, -1.0, -1.0, -1.0};
    trn_peak_t p;
    (void)state;
    ll[0] = -1.0e300;
    assert_int_not_equal(trn_peak_fit(ll, &p), TRN_E_ARG);
    ll[0] = -1.0001e300;
    assert_int_equal(trn_peak_fit(ll, &p), TRN_E_ILLCOND);
    assert_true(isinf(p.sigma_x) && p.dx == 0.0);
    ll[0] = -1.0;
    ll[4] = 1.0001e300; /* the centre itself far from the rest */
    assert_int_equal(trn_peak_fit(ll, &p), TRN_E_ILLCOND);
}

/* fuzz_terrain (10^6-execution run), crash-970f0f5a0a099c7eccf041f7d34ce0ea315954e6:
 * finite heights near +-3.4e38 m. The filtered height h - mean is computed
 * in double and exceeded FLT_MAX, so its conversion to float gave inf (C99
 * 6.3.1.5 leaves that undefined; IEC 60559 gives inf): a seen height became
 * "not seen".
 * Contract (terrain.h): only NaN/inf inputs are missing, so every finite
 * height gives a finite filtered height, and missing stays NaN. */
static void test_highpass_extreme_heights_stay_finite(void **state)
{
    /* Two 3x3 blocks side by side, box half-width 1 cell: the left block is
     * +3.3e38 around a -3.3e38 centre (h' about -5.9e38), the right one the
     * mirror image (h' about +5.9e38); one corner is missing. */
    enum { W = 6, H = 3 };
    static float dem_buf[W * H], out_buf[W * H];
    TRN_WORKSPACE_DECLARE(ws, 1024 * sizeof(double));
    const trn_terrain_cfg_t cfg = {0.1f, 0.1f, 0.1f, 9};
    trn_grid_f32_t dem, out;
    int x, y, i;
    (void)state;
    for (y = 0; y < H; ++y) {
        for (x = 0; x < W; ++x) {
            dem_buf[y * W + x] = (x < 3) ? 3.3e38f : -3.3e38f;
        }
    }
    dem_buf[1 * W + 1] = -3.3e38f;
    dem_buf[1 * W + 4] = 3.3e38f;
    dem_buf[0] = NAN;
    assert_int_equal(trn_grid_f32_init(&dem, dem_buf, W * H, W, H), TRN_OK);
    assert_int_equal(trn_grid_f32_init(&out, out_buf, W * H, W, H), TRN_OK);
    assert_true(trn_highpass_workspace_bytes(W, H) <= sizeof ws);
    assert_int_equal(trn_highpass(&dem, &cfg, &out, ws, sizeof ws), TRN_OK);
    for (i = 0; i < W * H; ++i) {
        if (isfinite(dem_buf[i])) {
            assert_true(isfinite(out_buf[i]));
        } else {
            assert_true(isnan(out_buf[i]));
        }
    }
    assert_true(out_buf[1 * W + 1] == -FLT_MAX); /* clamped, not -inf */
    assert_true(out_buf[1 * W + 4] == FLT_MAX);  /* clamped, not +inf */
}

/* fuzz_mast (raw mode), input build/fuzz/artifacts/mast-subnormal-cell
 * (crafted while writing the harness from the reading of mast.c, then run
 * through it): cell_m = 1e-45 m is finite and > 0, so accepted, but
 * 1 / cell_m overflows to +inf; a point exactly at the rover position gives
 * 0 * inf = NaN cells, and the NaN went into an int32_t conversion
 * (undefined behaviour; clang's UBSan: "-nan is outside the range of
 * representable values of type 'int'"; on x86 the point was silently
 * dropped, TRN_E_NODATA). Contract after the fix: a cell size whose
 * reciprocal is not finite is TRN_E_ARG, like a non-finite one. */
static void test_mast_local_dem_subnormal_cell(void **state)
{
    const trn_vec3f_t pt = {0.0f, 0.0f, 1.0f};
    const trn_rover_pose_t pose = {0.0f, 0.0f, 0.0f, 0.0f};
    trn_local_dem_cfg_t cfg = {1.0e-45f, 2, 2, 1};
    float cells[25];
    trn_grid_f32_t dem;
    size_t used = 99u;
    (void)state;
    assert_int_equal(trn_grid_f32_init(&dem, cells, 25u, 5, 5), TRN_OK);
    assert_true(cfg.cell_m > 0.0f && isinf(1.0f / cfg.cell_m));
    assert_int_equal(trn_mast_local_dem(&pt, 1u, &pose, &cfg, &dem, &used), TRN_E_ARG);
    /* the smallest normal float still bins the point into the rover cell */
    cfg.cell_m = FLT_MIN;
    assert_int_equal(trn_mast_local_dem(&pt, 1u, &pose, &cfg, &dem, &used), TRN_OK);
    assert_int_equal((int)used, 1);
    assert_true(TRN_GRID_AT(&dem, 2, 2) == 1.0f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_peakfit_huge_curvature),
        cmocka_unit_test(test_peakfit_gradient_overflow),
        cmocka_unit_test(test_peakfit_difference_limit),
        cmocka_unit_test(test_highpass_extreme_heights_stay_finite),
        cmocka_unit_test(test_mast_local_dem_subnormal_cell),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
