/* SPDX-License-Identifier: Apache-2.0 */
/* test_peakfit.c - eq. 6 peak fit and failure probability (peakfit.h).
 *
 * Oracles: analytic 2-D Gaussian log-surfaces (exactly quadratic, so the
 * least-squares fit must recover mean and covariance to rounding error),
 * hand-made degenerate surfaces, and the closed form of the failure
 * probability. Every documented @retval has its own assertion.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>
#include <stdio.h>

#include "trn/peakfit.h"
#include "rng.h"

/* Bound asserted on the recovery of random Gaussians (see
 * test_gaussian_recovery). The issue asks for 1e-3; the fit is exact for a
 * quadratic, and the measured worst case over the 2000 seeded surfaces is
 * about 2.5e-11 (printed when the test runs), so 1e-9 leaves a factor 40 of
 * margin for other compilers and FMA contraction while still catching any
 * real error in the normal equations. (Fitting without the centre
 * subtraction measures ~3e-10 here, still inside the bound:
 * test_centre_subtraction is the test that catches that.) */
#define RECOVERY_TOL 1e-9

static double uniform(trn_rng_t *r, double lo, double hi)
{
    return lo + (hi - lo) * trn_rng_unit(r);
}

/* ln L(x, y) = c - 0.5 [x - mu]^T Sigma^-1 [x - mu] on the 3x3 grid. */
static void gaussian_patch(double c, double mx, double my, double sx, double sy, double rho,
                           double ll[9])
{
    const double vxx = sx * sx, vyy = sy * sy, vxy = rho * sx * sy;
    const double det = vxx * vyy - vxy * vxy;
    const double pxx = vyy / det, pyy = vxx / det, pxy = -vxy / det; /* Sigma^-1 */
    int x, y;
    for (y = -1; y <= 1; ++y) {
        for (x = -1; x <= 1; ++x) {
            const double ex = (double)x - mx, ey = (double)y - my;
            ll[(y + 1) * 3 + (x + 1)] = c -
                                        0.5 * (pxx * ex * ex + 2.0 * pxy * ex * ey + pyy * ey * ey);
        }
    }
}

/* General quadratic c0 + c1 x + c2 y + c3 x^2 + c4 x y + c5 y^2 on the grid. */
static void quad_patch(double c0, double c1, double c2, double c3, double c4, double c5,
                       double ll[9])
{
    int x, y;
    for (y = -1; y <= 1; ++y) {
        for (x = -1; x <= 1; ++x) {
            const double fx = (double)x, fy = (double)y;
            ll[(y + 1) * 3 + (x + 1)] = c0 + c1 * fx + c2 * fy + c3 * fx * fx + c4 * fx * fy +
                                        c5 * fy * fy;
        }
    }
}

static void assert_illcond_outputs(const trn_peak_t *p)
{
    assert_true(p->dx == 0.0);
    assert_true(p->dy == 0.0);
    assert_true(isinf(p->var_x) && p->var_x > 0.0);
    assert_true(isinf(p->var_y) && p->var_y > 0.0);
    assert_true(isinf(p->sigma_x) && p->sigma_x > 0.0);
    assert_true(isinf(p->sigma_y) && p->sigma_y > 0.0);
    assert_true(p->rho == 0.0);
    assert_true(p->cov_xy == 0.0);
}

static void expect_illcond(const double ll[9])
{
    trn_peak_t p;
    p.dx = p.dy = 0.25; /* garbage the function must overwrite */
    p.var_x = p.var_y = p.cov_xy = p.sigma_x = p.sigma_y = p.rho = 0.5;
    assert_int_equal(trn_peak_fit(ll, &p), TRN_E_ILLCOND);
    assert_illcond_outputs(&p);
}

/* ------------------------------------------------------------------------ */

static void test_gaussian_centred(void **state)
{
    double ll[9];
    trn_peak_t p;
    (void)state;
    /* unit isotropic Gaussian at the centre: exact answers */
    gaussian_patch(0.0, 0.0, 0.0, 1.0, 1.0, 0.0, ll);
    assert_int_equal(trn_peak_fit(ll, &p), TRN_OK);
    assert_true(fabs(p.dx) < 1e-15);
    assert_true(fabs(p.dy) < 1e-15);
    assert_true(fabs(p.sigma_x - 1.0) < 1e-15);
    assert_true(fabs(p.sigma_y - 1.0) < 1e-15);
    assert_true(fabs(p.rho) < 1e-15);
    /* known shift, known sigmas: ln L = -(x-0.25)^2/(2*0.25) - (y+0.5)^2/(2*4) */
    gaussian_patch(-3.0, 0.25, -0.5, 0.5, 2.0, 0.0, ll);
    assert_int_equal(trn_peak_fit(ll, &p), TRN_OK);
    assert_true(fabs(p.dx - 0.25) < 1e-12);
    assert_true(fabs(p.dy + 0.5) < 1e-12);
    assert_true(fabs(p.sigma_x - 0.5) < 1e-12);
    assert_true(fabs(p.sigma_y - 2.0) < 1e-12);
    assert_true(fabs(p.var_x - 0.25) < 1e-12);
    assert_true(fabs(p.var_y - 4.0) < 1e-12);
    assert_true(fabs(p.rho) < 1e-12);
    /* the sign of rho follows the tilt of the ellipse */
    gaussian_patch(0.0, 0.0, 0.0, 1.0, 1.0, 0.6, ll);
    assert_int_equal(trn_peak_fit(ll, &p), TRN_OK);
    assert_true(fabs(p.rho - 0.6) < 1e-12);
    gaussian_patch(0.0, 0.0, 0.0, 1.0, 1.0, -0.6, ll);
    assert_int_equal(trn_peak_fit(ll, &p), TRN_OK);
    assert_true(fabs(p.rho + 0.6) < 1e-12);
}

/* ln L = c - 0.5 [x-mu]^T P [x-mu] with a dyadic precision matrix P, mean and
 * offset c = -2^40: every sample is exact in double (ulp 2^-12 at 2^40), so
 * a fit that works relative to the centre sample recovers the Gaussian to
 * rounding error, while one that sums the raw values (|ll| ~ 1e12) loses
 * everything to cancellation. */
static void test_centre_subtraction(void **state)
{
    static const double offsets[] = {0.0, -1099511627776.0, 1099511627776.0, -3.0e15};
    const double pxx = 2.0, pxy = 0.5, pyy = 1.0, mx = 0.25, my = -0.5;
    /* Sigma = P^-1 = [[4/7, -2/7], [-2/7, 8/7]] */
    const double sx = sqrt(4.0 / 7.0), sy = sqrt(8.0 / 7.0), rho = -2.0 / sqrt(32.0);
    size_t i;
    (void)state;
    for (i = 0; i < sizeof offsets / sizeof offsets[0]; ++i) {
        /* 3e15 has ulp 0.5: the samples are no longer exact there, so it only
         * has to stay a finite, well-formed answer or an honest ILLCOND. */
        const double tol = fabs(offsets[i]) > 1e13 ? -1.0 : 1e-12;
        double ll[9];
        trn_peak_t p;
        trn_status_t st;
        int x, y;
        for (y = -1; y <= 1; ++y) {
            for (x = -1; x <= 1; ++x) {
                const double ex = (double)x - mx, ey = (double)y - my;
                ll[(y + 1) * 3 + (x + 1)] = offsets[i] -
                                            0.5 * (pxx * ex * ex + 2.0 * pxy * ex * ey +
                                                   pyy * ey * ey);
            }
        }
        st = trn_peak_fit(ll, &p);
        if (tol < 0.0) {
            assert_true(st == TRN_OK || st == TRN_E_ILLCOND);
            if (st == TRN_OK) {
                assert_true(isfinite(p.sigma_x) && isfinite(p.sigma_y) && fabs(p.rho) < 1.0);
            }
            continue;
        }
        assert_int_equal(st, TRN_OK);
        if (!(fabs(p.dx - mx) <= tol && fabs(p.dy - my) <= tol && fabs(p.sigma_x - sx) <= tol &&
              fabs(p.sigma_y - sy) <= tol && fabs(p.rho - rho) <= tol)) {
            fail_msg("offset %.17g: (%.17g, %.17g) sigma (%.17g, %.17g) rho %.17g", offsets[i],
                     p.dx, p.dy, p.sigma_x, p.sigma_y, p.rho);
        }
    }
}

static void test_gaussian_recovery(void **state)
{
    trn_rng_t rng;
    double e_mu = 0.0, e_sig = 0.0, e_rho = 0.0, e_var = 0.0;
    int i;
    (void)state;
    trn_rng_seed(&rng, 0x7065616b666974ull);
    for (i = 0; i < 2000; ++i) {
        const double mx = uniform(&rng, -0.5, 0.5), my = uniform(&rng, -0.5, 0.5);
        const double sx = uniform(&rng, 0.2, 5.0), sy = uniform(&rng, 0.2, 5.0);
        const double rho = uniform(&rng, -0.9, 0.9);
        const double c = uniform(&rng, -1.2e4, -0.8e4);
        double ll[9], e;
        trn_peak_t p;
        gaussian_patch(c, mx, my, sx, sy, rho, ll);
        assert_int_equal(trn_peak_fit(ll, &p), TRN_OK);
        e = fmax(fabs(p.dx - mx), fabs(p.dy - my));
        e_mu = fmax(e_mu, e);
        e = fmax(fabs(p.sigma_x - sx) / sx, fabs(p.sigma_y - sy) / sy);
        e_sig = fmax(e_sig, e);
        e = fabs(p.rho - rho);
        e_rho = fmax(e_rho, e);
        /* internal consistency of the reported covariance */
        e = fmax(fabs(p.var_x - p.sigma_x * p.sigma_x) / p.var_x,
                 fmax(fabs(p.var_y - p.sigma_y * p.sigma_y) / p.var_y,
                      fabs(p.cov_xy - p.rho * p.sigma_x * p.sigma_y) / (p.sigma_x * p.sigma_y)));
        e_var = fmax(e_var, e);
        if (!(fabs(p.dx - mx) <= RECOVERY_TOL && fabs(p.dy - my) <= RECOVERY_TOL &&
              fabs(p.sigma_x - sx) <= RECOVERY_TOL * sx &&
              fabs(p.sigma_y - sy) <= RECOVERY_TOL * sy && fabs(p.rho - rho) <= RECOVERY_TOL)) {
            fail_msg("trial %d: mu (%.17g, %.17g) sigma (%.17g, %.17g) rho %.17g c %.17g -> "
                     "(%.17g, %.17g) (%.17g, %.17g) %.17g",
                     i, mx, my, sx, sy, rho, c, p.dx, p.dy, p.sigma_x, p.sigma_y, p.rho);
        }
    }
    assert_true(e_var <= 1e-14);
    printf("    peak_fit recovery over 2000 Gaussians, c ~ -1e4: max |dmu| = %.3g cells, "
           "max rel. sigma err = %.3g, max |drho| = %.3g (asserted <= %g)\n",
           e_mu, e_sig, e_rho, RECOVERY_TOL);
}

static void test_peak_on_patch_edge(void **state)
{
    double ll[9];
    trn_peak_t p;
    (void)state;
    /* fitted maximum inside the patch, near its edge: fine */
    gaussian_patch(-1e4, 0.99, -0.99, 1.0, 1.5, 0.3, ll);
    assert_int_equal(trn_peak_fit(ll, &p), TRN_OK);
    assert_true(fabs(p.dx - 0.99) < 1e-9);
    assert_true(fabs(p.dy + 0.99) < 1e-9);
}

static void test_illcond_shapes(void **state)
{
    double ll[9];
    (void)state;
    /* flat patch, at zero and at a large offset */
    quad_patch(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, ll);
    expect_illcond(ll);
    quad_patch(-1e4, 0.0, 0.0, 0.0, 0.0, 0.0, ll);
    expect_illcond(ll);
    /* ridge constant along y (curved in x only), and along x */
    quad_patch(-5.0, 0.0, 0.0, -1.0, 0.0, 0.0, ll);
    expect_illcond(ll);
    quad_patch(-5.0, 0.0, 0.0, 0.0, 0.0, -2.0, ll);
    expect_illcond(ll);
    /* ridge along the diagonal: -(x - y)^2 */
    quad_patch(0.0, 0.0, 0.0, -1.0, 2.0, -1.0, ll);
    expect_illcond(ll);
    /* a sloping ridge (linear along its axis) */
    quad_patch(0.0, 0.0, 0.5, -1.0, 0.0, 0.0, ll);
    expect_illcond(ll);
    /* saddle: down in x, up in y; and the rotated saddle x*y */
    quad_patch(0.0, 0.0, 0.0, -1.0, 0.0, 1.0, ll);
    expect_illcond(ll);
    quad_patch(0.0, 0.0, 0.0, 0.0, 1.0, 0.0, ll);
    expect_illcond(ll);
    /* a saddle whose x curvature is negative (only the determinant tells) */
    quad_patch(0.0, 0.0, 0.0, -1.0, 3.0, -1.0, ll);
    expect_illcond(ll);
    /* upward bowl (a likelihood minimum) */
    quad_patch(-1e4, 0.0, 0.0, 1.0, 0.0, 1.0, ll);
    expect_illcond(ll);
    /* a pure slope */
    quad_patch(0.0, 1.0, -1.0, 0.0, 0.0, 0.0, ll);
    expect_illcond(ll);
}

/* The documented noise floor: a curvature below 64 ulp of the largest |ln L|
 * is no curvature (TRN_E_ILLCOND); one well above it is a (very wide) peak. */
static void test_curvature_noise_floor(void **state)
{
    static const struct {
        double c, lambda;
        trn_status_t st;
    } cases[] = {
        {0.0, 1e-12, TRN_OK},         {0.0, 1e-16, TRN_E_ILLCOND}, {-1e4, 1e-8, TRN_OK},
        {-1e4, 1e-12, TRN_E_ILLCOND}, {-1e9, 1e-3, TRN_OK},        {-1e9, 1e-7, TRN_E_ILLCOND},
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        double ll[9];
        trn_peak_t p;
        quad_patch(cases[i].c, 0.0, 0.0, -0.5 * cases[i].lambda, 0.0, -0.5 * cases[i].lambda, ll);
        if (cases[i].st == TRN_OK) {
            assert_int_equal(trn_peak_fit(ll, &p), TRN_OK);
            /* sigma = 1/sqrt(lambda), to the precision the samples carry */
            assert_true(fabs(p.sigma_x * sqrt(cases[i].lambda) - 1.0) < 1e-3);
            assert_true(fabs(p.sigma_y * sqrt(cases[i].lambda) - 1.0) < 1e-3);
            assert_true(fabs(p.dx) < 1e-3 && fabs(p.dy) < 1e-3);
        } else {
            expect_illcond(ll);
        }
    }
}

static void test_illcond_peak_outside(void **state)
{
    static const double mu[][2] = {{1.5, 0.0},   {0.0, -2.0}, {1.2, 1.2},
                                   {-1.01, 0.0}, {0.0, 1.01}, {-3.0, 4.0}};
    double ll[9];
    size_t i;
    (void)state;
    for (i = 0; i < sizeof mu / sizeof mu[0]; ++i) {
        gaussian_patch(-1e4, mu[i][0], mu[i][1], 1.0, 0.8, 0.2, ll);
        expect_illcond(ll);
    }
}

/* Ridges constant along one axis with random curvature, offset and centre.
 * The Hessian is exactly singular, so the header promises TRN_E_ILLCOND;
 * rounding in the normal equations must not turn a ridge into a finite
 * (if huge) covariance. */
static void test_illcond_random_ridges(void **state)
{
    trn_rng_t rng;
    int i, n_ok = 0, first_bad = -1, bad_axis = 0;
    double worst_sigma = 0.0, bad_a = 0.0, bad_b = 0.0, bad_c = 0.0;
    (void)state;
    trn_rng_seed(&rng, 0x7269646765ull);
    for (i = 0; i < 20000; ++i) {
        const double a = uniform(&rng, 0.01, 10.0);
        const double b = uniform(&rng, -1.0, 1.0);
        const double c = uniform(&rng, -1.2e4, 0.0);
        const int along_x = (int)(trn_rng_u64(&rng) & 1u);
        double ll[9];
        trn_peak_t p;
        int x, y;
        for (y = -1; y <= 1; ++y) {
            for (x = -1; x <= 1; ++x) {
                const double u = along_x ? (double)y : (double)x;
                ll[(y + 1) * 3 + (x + 1)] = c - a * (u - b) * (u - b);
            }
        }
        if (trn_peak_fit(ll, &p) != TRN_E_ILLCOND) {
            if (first_bad < 0) {
                first_bad = i;
                bad_a = a;
                bad_b = b;
                bad_c = c;
                bad_axis = along_x;
            }
            ++n_ok;
            worst_sigma = fmax(worst_sigma, fmax(p.sigma_x, p.sigma_y));
        }
    }
    if (n_ok != 0) {
        fail_msg("%d of 20000 exact ridges were fitted as TRN_OK with a finite sigma up to "
                 "%.3g cells instead of TRN_E_ILLCOND; first: trial %d, "
                 "ln L = %.17g - %.17g * (%s - %.17g)^2",
                 n_ok, worst_sigma, first_bad, bad_c, bad_a, bad_axis ? "y" : "x", bad_b);
    }
}

static void test_peak_fit_args(void **state)
{
    double ll[9];
    trn_peak_t p;
    const double bad[] = {NAN, INFINITY, -INFINITY};
    size_t i, k;
    (void)state;
    gaussian_patch(-10.0, 0.1, 0.2, 1.0, 1.0, 0.0, ll);
    /* TRN_E_NULL */
    assert_int_equal(trn_peak_fit(NULL, &p), TRN_E_NULL);
    assert_int_equal(trn_peak_fit(ll, NULL), TRN_E_NULL);
    assert_int_equal(trn_peak_fit(NULL, NULL), TRN_E_NULL);
    /* TRN_E_ARG: NaN or +-inf at each of the nine positions */
    for (k = 0; k < 3; ++k) {
        for (i = 0; i < 9; ++i) {
            double v[9];
            size_t j;
            for (j = 0; j < 9; ++j) {
                v[j] = ll[j];
            }
            v[i] = bad[k];
            assert_int_equal(trn_peak_fit(v, &p), TRN_E_ARG);
        }
    }
    /* the valid patch still fits */
    assert_int_equal(trn_peak_fit(ll, &p), TRN_OK);
}

/* ------------------------------------------------------------------------ */

static void test_failure_probability_values(void **state)
{
    double p = -1.0;
    trn_rng_t rng;
    int i;
    (void)state;
    assert_int_equal(trn_failure_probability(-123.0, -123.0, &p), TRN_OK);
    assert_true(p == 0.5);
    assert_int_equal(trn_failure_probability(0.0, 0.0, &p), TRN_OK);
    assert_true(p == 0.5);
    /* L1 = 3 L2: P = 1 / (1 + 3) */
    assert_int_equal(trn_failure_probability(log(3.0), 0.0, &p), TRN_OK);
    assert_true(fabs(p - 0.25) < 1e-15);
    assert_int_equal(trn_failure_probability(-1e4 + log(3.0), -1e4, &p), TRN_OK);
    assert_true(fabs(p - 0.25) < 1e-12);
    /* huge differences: 0, finite, never NaN */
    assert_int_equal(trn_failure_probability(1e6, -1e6, &p), TRN_OK);
    assert_true(isfinite(p) && p >= 0.0 && p < 1e-300);
    assert_int_equal(trn_failure_probability(DBL_MAX, -DBL_MAX, &p), TRN_OK);
    assert_true(isfinite(p) && p >= 0.0 && p < 1e-300);
    assert_int_equal(trn_failure_probability(800.0, 0.0, &p), TRN_OK);
    assert_true(isfinite(p) && p >= 0.0 && p < 1e-300);
    /* random pairs against the two-hypothesis formula L2 / (L1 + L2) */
    trn_rng_seed(&rng, 0x6661696cull);
    for (i = 0; i < 1000; ++i) {
        const double d = 30.0 * trn_rng_unit(&rng);
        const double l2 = -1e3 * trn_rng_unit(&rng);
        const double expect = exp(-d) / (1.0 + exp(-d));
        assert_int_equal(trn_failure_probability(l2 + d, l2, &p), TRN_OK);
        assert_true(p >= 0.0 && p <= 0.5);
        /* 1e-13 relative: the difference (l2 + d) - l2 is rounded at |l2| ~ 1e3 */
        assert_true(fabs(p - expect) <= 1e-12 * expect);
    }
}

static void test_failure_probability_args(void **state)
{
    double p = 0.0;
    (void)state;
    /* TRN_E_NULL */
    assert_int_equal(trn_failure_probability(1.0, 0.0, NULL), TRN_E_NULL);
    /* TRN_E_ARG: second better than best */
    assert_int_equal(trn_failure_probability(0.0, 1.0, &p), TRN_E_ARG);
    assert_int_equal(trn_failure_probability(-1e4, -1e4 + 1e-9, &p), TRN_E_ARG);
    /* TRN_E_ARG: not finite, in either argument */
    assert_int_equal(trn_failure_probability(NAN, 0.0, &p), TRN_E_ARG);
    assert_int_equal(trn_failure_probability(0.0, NAN, &p), TRN_E_ARG);
    assert_int_equal(trn_failure_probability(INFINITY, 0.0, &p), TRN_E_ARG);
    assert_int_equal(trn_failure_probability(0.0, -INFINITY, &p), TRN_E_ARG);
    assert_int_equal(trn_failure_probability(-INFINITY, -INFINITY, &p), TRN_E_ARG);
    assert_int_equal(trn_failure_probability(INFINITY, INFINITY, &p), TRN_E_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gaussian_centred),
        cmocka_unit_test(test_centre_subtraction),
        cmocka_unit_test(test_gaussian_recovery),
        cmocka_unit_test(test_peak_on_patch_edge),
        cmocka_unit_test(test_illcond_shapes),
        cmocka_unit_test(test_curvature_noise_floor),
        cmocka_unit_test(test_illcond_peak_outside),
        cmocka_unit_test(test_illcond_random_ridges),
        cmocka_unit_test(test_peak_fit_args),
        cmocka_unit_test(test_failure_probability_values),
        cmocka_unit_test(test_failure_probability_args),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
