/* SPDX-License-Identifier: Apache-2.0 */
/* test_kernels.c - the ten sqrt(2)-spaced kernels (kernels.h).
 *
 * Oracles: the definition (sigma_0 sqrt(2)^j, ceil(3 sigma) radius,
 * normalized Gaussian taps) recomputed in double, and nearest-in-log-sigma
 * computed with log2 and round for the pick. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>

#include "rng.h"
#include "trn/kernels.h"

static void test_table(void **state)
{
    static trn_kernels_t k;
    const float s0s[3] = {0.5f, 0.25f, 0.9f};
    int t, j, i;
    (void)state;
    for (t = 0; t < 3; ++t) {
        assert_int_equal(trn_kernels_build(&k, s0s[t]), TRN_OK);
        for (j = 0; j < TRN_KERNEL_COUNT; ++j) {
            const double s = (double)s0s[t] * pow(2.0, 0.5 * j);
            const int r = (int)ceil(3.0 * s);
            double sum = 0.0;
            assert_true(fabs((double)k.sigma_cells[j] / s - 1.0) < 1e-6);
            if (j > 0) { /* exact powers of sqrt(2) apart (to float rounding) */
                assert_true(fabs((double)k.sigma_cells[j] / (double)k.sigma_cells[j - 1] -
                                 sqrt(2.0)) < 1e-6);
            }
            assert_int_equal(k.radius[j], r);
            for (i = -TRN_KERNEL_MAX_RADIUS; i <= TRN_KERNEL_MAX_RADIUS; ++i) {
                const double v = k.taps[j][TRN_KERNEL_MAX_RADIUS + i];
                if (i < -r || i > r) {
                    assert_true(v == 0.0);
                } else {
                    const double g = exp(-(double)i * i / (2.0 * s * s));
                    const double c = k.taps[j][TRN_KERNEL_MAX_RADIUS];
                    assert_true(v > 0.0);
                    assert_true(v == k.taps[j][TRN_KERNEL_MAX_RADIUS - i]);  /* symmetric */
                    assert_true(fabs(v / c - g) < 1e-6 * (1.0 + g) + 1e-12); /* Gaussian shape */
                }
                sum += v;
            }
            assert_true(fabs(sum - 1.0) < 1e-6);
        }
    }
}

static void test_pick_nearest_in_log(void **state)
{
    static trn_kernels_t k;
    trn_rng_t r;
    int n, checked = 0;
    (void)state;
    assert_int_equal(trn_kernels_build(&k, 0.5f), TRN_OK);
    trn_rng_seed(&r, 42);
    for (n = 0; n < 20000; ++n) {
        /* log-uniform over [sigma_0 / 8, sigma_9 * 8] */
        const double ls = log2(0.5 / 8.0) +
                          trn_rng_unit(&r) * (log2(0.5 * 22.63 * 8.0) - log2(0.5 / 8.0));
        const float s = (float)exp2(ls);
        const double jj = 2.0 * log2((double)s / 0.5); /* position in kernel steps */
        int want = (int)floor(jj + 0.5), j, best = 0;
        double bd = HUGE_VAL;
        if (fabs(jj - floor(jj) - 0.5) < 1e-4) {
            continue; /* too close to a boundary for float */
        }
        want = want < 0 ? 0 : (want > 9 ? 9 : want);
        for (j = 0; j < TRN_KERNEL_COUNT; ++j) { /* nearest by |log sigma difference| */
            const double dl = fabs(log((double)s) - log((double)k.sigma_cells[j]));
            if (dl < bd) {
                bd = dl;
                best = j;
            }
        }
        assert_int_equal(want, best);
        assert_int_equal(trn_kernel_pick(&k, s), want);
        ++checked;
    }
    assert_true(checked > 19000);
    /* exact kernel sigmas pick themselves; clamping at both ends */
    for (n = 0; n < TRN_KERNEL_COUNT; ++n) {
        assert_int_equal(trn_kernel_pick(&k, k.sigma_cells[n]), n);
    }
    assert_int_equal(trn_kernel_pick(&k, 0.0f), 0);
    assert_int_equal(trn_kernel_pick(&k, 1e6f), 9);
    assert_int_equal(trn_kernel_pick(&k, NAN), 0);
}

static void test_bad_inputs(void **state)
{
    static trn_kernels_t k;
    (void)state;
    assert_int_equal(trn_kernels_build(NULL, 0.5f), TRN_E_NULL);
    assert_int_equal(trn_kernels_build(&k, NAN), TRN_E_ARG);
    assert_int_equal(trn_kernels_build(&k, INFINITY), TRN_E_ARG);
    assert_int_equal(trn_kernels_build(&k, 0.0f), TRN_E_ARG);
    assert_int_equal(trn_kernels_build(&k, -1.0f), TRN_E_ARG);
    assert_int_equal(trn_kernels_build(&k, 0.01f), TRN_E_ARG);
    assert_int_equal(trn_kernels_build(&k, 1.0f), TRN_E_ARG); /* R_9 = 68 > 64 */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_table),
        cmocka_unit_test(test_pick_nearest_in_log),
        cmocka_unit_test(test_bad_inputs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
