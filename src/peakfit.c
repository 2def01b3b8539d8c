/* SPDX-License-Identifier: Apache-2.0 */
/* peakfit.c - eq. 6 fit and failure probability (see trn/peakfit.h). */
#include "trn/peakfit.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

/* Largest |ln L(i) - ln L(centre)| fitted, nats: with it every sum and
 * coefficient below stays under 1e302, far from overflow. Real scores are
 * below 1e12 nats (TRN_LNP_SCALE-unit int64 sums). */
#define FIT_MAX_DIFF 1.0e300

static void set_illcond(trn_peak_t *out)
{
    out->dx = 0.0;
    out->dy = 0.0;
    out->var_x = HUGE_VAL;
    out->var_y = HUGE_VAL;
    out->cov_xy = 0.0;
    out->sigma_x = HUGE_VAL;
    out->sigma_y = HUGE_VAL;
    out->rho = 0.0;
}

trn_status_t trn_peak_fit(const double ll[9], trn_peak_t *out)
{
    double f[9];
    double s0 = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
    double c1, c2, c3, c4, c5, hxx, hyy, hxy, det, ivxx, ivyy, ivxy;
    double mag = 0.0, mean_c, half_d, lam_min, noise, scale;
    int i, x, y;

    if (ll == NULL || out == NULL) {
        return TRN_E_NULL;
    }
    for (i = 0; i < 9; ++i) {
        if (!isfinite(ll[i])) {
            set_illcond(out);
            return TRN_E_ARG;
        }
        if (fabs(ll[i]) > mag) {
            mag = fabs(ll[i]);
        }
    }
    for (i = 0; i < 9; ++i) {
        f[i] = ll[i] - ll[4]; /* relative to the centre: no cancellation */
        /* Differences beyond FIT_MAX_DIFF would overflow the sums below. */
        if (!(fabs(f[i]) <= FIT_MAX_DIFF)) {
            set_illcond(out);
            return TRN_E_ILLCOND;
        }
    }
    for (y = -1; y <= 1; ++y) {
        for (x = -1; x <= 1; ++x) {
            double v = f[(y + 1) * 3 + (x + 1)];
            s0 += v;
            sx += (double)x * v;
            sy += (double)y * v;
            sxx += (double)(x * x) * v;
            syy += (double)(y * y) * v;
            sxy += (double)(x * y) * v;
        }
    }
    /* Normal equations of the 6-term quadratic on the 3x3 grid, solved in
     * closed form (sum x^2 = 6, sum x^2 y^2 = 4, sum (xy)^2 = 4). */
    c1 = sx / 6.0;
    c2 = sy / 6.0;
    c4 = sxy / 4.0;
    c3 = sxx / 2.0 - s0 / 3.0;
    c5 = syy / 2.0 - s0 / 3.0;
    hxx = 2.0 * c3;
    hyy = 2.0 * c5;
    hxy = c4;
    if (!(hxx < 0.0)) {
        set_illcond(out);
        return TRN_E_ILLCOND;
    }
    /* Work on H / scale (entries in [-1, 1]), so the determinant and the
     * eigenvalue cannot overflow or underflow for any finite curvature. */
    scale = fabs(hxx);
    if (fabs(hyy) > scale) {
        scale = fabs(hyy);
    }
    if (fabs(hxy) > scale) {
        scale = fabs(hxy);
    }
    hxx /= scale;
    hyy /= scale;
    hxy /= scale;
    det = hxx * hyy - hxy * hxy;
    /* Smaller eigenvalue of -H: a curvature below the rounding noise of the
     * inputs (64 ulp of the largest |ln L|) is no curvature at all, so an
     * exact ridge whose fit is off by rounding is still a ridge. */
    mean_c = -(hxx + hyy) / 2.0;
    half_d = sqrt((hxx - hyy) * (hxx - hyy) / 4.0 + hxy * hxy);
    lam_min = mean_c - half_d;
    noise = 64.0 * DBL_EPSILON * (mag > 1.0 ? mag : 1.0);
    if (!(det > 0.0) || !(lam_min > noise / scale)) {
        set_illcond(out);
        return TRN_E_ILLCOND;
    }
    /* Sigma = -H^-1 */
    ivxx = -hyy / det / scale;
    ivyy = -hxx / det / scale;
    ivxy = hxy / det / scale;
    out->var_x = ivxx;
    out->var_y = ivyy;
    out->cov_xy = ivxy;
    /* peak = -H^-1 g = Sigma g */
    out->dx = ivxx * c1 + ivxy * c2;
    out->dy = ivxy * c1 + ivyy * c2;
    out->sigma_x = sqrt(ivxx);
    out->sigma_y = sqrt(ivyy);
    /* cov / (sigma_x sigma_y) = hxy / sqrt(hxx hyy): free of the scale, so
     * it stays finite when the variances are tiny. The checks below cannot
     * fail after det > 0 (docs/assurance.md lists them): they guard the
     * contract against rounding. */
    out->rho = hxy / sqrt(hxx * hyy);
    if (!(fabs(out->dx) <= 1.0) || !(fabs(out->dy) <= 1.0) || !(ivxx > 0.0) || !(ivyy > 0.0) ||
        !isfinite(out->sigma_x) || !isfinite(out->sigma_y) || !(fabs(out->rho) < 1.0)) {
        set_illcond(out);
        return TRN_E_ILLCOND;
    }
    return TRN_OK;
}

trn_status_t trn_failure_probability(double ll_best, double ll_second, double *p)
{
    if (p == NULL) {
        return TRN_E_NULL;
    }
    if (!isfinite(ll_best) || !isfinite(ll_second) || ll_second > ll_best) {
        return TRN_E_ARG;
    }
    *p = 1.0 / (1.0 + exp(ll_best - ll_second));
    return TRN_OK;
}

static void set_illcond3(trn_peak3_t *out)
{
    int i;
    for (i = 0; i < 3; ++i) {
        out->offset[i] = 0.0;
        out->sigma[i] = HUGE_VAL;
    }
    for (i = 0; i < 9; ++i) {
        out->covariance[i] = (i % 4 == 0) ? HUGE_VAL : 0.0;
    }
}

/* Cholesky factor of the symmetric 3 x 3 matrix a (row-major): lower l with
 * l l^T = a. Returns 0 unless a is positive definite with every pivot above
 * floor. */
static int chol3(const double a[9], double floor_v, double l[9])
{
    int i, j, k;
    for (i = 0; i < 9; ++i) {
        l[i] = 0.0;
    }
    for (j = 0; j < 3; ++j) {
        double d = a[j * 3 + j];
        for (k = 0; k < j; ++k) {
            d -= l[j * 3 + k] * l[j * 3 + k];
        }
        if (!(d > floor_v)) {
            return 0;
        }
        l[j * 3 + j] = sqrt(d);
        for (i = j + 1; i < 3; ++i) {
            double v = a[i * 3 + j];
            for (k = 0; k < j; ++k) {
                v -= l[i * 3 + k] * l[j * 3 + k];
            }
            l[i * 3 + j] = v / l[j * 3 + j];
        }
    }
    return 1;
}

/* Solve (l l^T) x = b for x, l from chol3. */
static void chol3_solve(const double l[9], const double b[3], double x[3])
{
    double y[3] = {0.0, 0.0, 0.0}, xs[3] = {0.0, 0.0, 0.0};
    int i, k;
    for (i = 0; i < 3; ++i) {
        double v = b[i];
        for (k = 0; k < i; ++k) {
            v -= l[i * 3 + k] * y[k];
        }
        y[i] = v / l[i * 3 + i];
    }
    for (i = 3; i-- > 0;) {
        double v = y[i];
        for (k = i + 1; k < 3; ++k) {
            v -= l[k * 3 + i] * xs[k];
        }
        xs[i] = v / l[i * 3 + i];
    }
    for (i = 0; i < 3; ++i) {
        x[i] = xs[i];
    }
}

trn_status_t trn_peak_fit3(const double ll[27], trn_peak3_t *out)
{
    double f[27], g[3] = {0.0, 0.0, 0.0}, sq[3] = {0.0, 0.0, 0.0}, cr[3] = {0.0, 0.0, 0.0};
    double negh[9], l[9], s0 = 0.0, a_sum, c0, mag = 0.0, scale = 0.0, noise;
    int i, j;

    if (ll == NULL || out == NULL) {
        return TRN_E_NULL;
    }
    for (i = 0; i < 27; ++i) {
        if (!isfinite(ll[i])) {
            set_illcond3(out);
            return TRN_E_ARG;
        }
        if (fabs(ll[i]) > mag) {
            mag = fabs(ll[i]);
        }
    }
    for (i = 0; i < 27; ++i) {
        f[i] = ll[i] - ll[13];
        if (!(fabs(f[i]) <= FIT_MAX_DIFF)) {
            set_illcond3(out);
            return TRN_E_ILLCOND;
        }
    }
    /* Sums over the 3 x 3 x 3 grid, offsets d = (i % 3, i / 3 % 3, i / 9) - 1;
     * cr: d0 d1, d0 d2, d1 d2 */
    for (i = 0; i < 27; ++i) {
        const int i0 = i % 3 - 1, i1 = (i / 3) % 3 - 1, i2 = i / 9 - 1;
        const double d0 = (double)i0, d1 = (double)i1, d2 = (double)i2;
        s0 += f[i];
        g[0] += d0 * f[i];
        g[1] += d1 * f[i];
        g[2] += d2 * f[i];
        sq[0] += d0 * d0 * f[i];
        sq[1] += d1 * d1 * f[i];
        sq[2] += d2 * d2 * f[i];
        cr[0] += d0 * d1 * f[i];
        cr[1] += d0 * d2 * f[i];
        cr[2] += d1 * d2 * f[i];
    }
    /* Least squares of f = c0 + g.d + sum a_i d_i^2 + sum q_ij d_i d_j on the
     * grid, in closed form (sum d_i^2 = 18, sum d_i^2 d_j^2 = 12 (i != j),
     * sum (d_i d_j)^2 = 12): linear and cross terms decouple; the constant
     * and the squares solve a 4 x 4 system: A = sum a_i = (sum sq - 2 s0) / 6,
     * c0 = (s0 - 18 A) / 27, a_i = (sq_i - 18 c0 - 12 A) / 6. */
    a_sum = (sq[0] + sq[1] + sq[2] - 2.0 * s0) / 6.0;
    c0 = (s0 - 18.0 * a_sum) / 27.0;
    for (i = 0; i < 3; ++i) {
        g[i] /= 18.0;
        negh[i * 3 + i] = -2.0 * (sq[i] - 18.0 * c0 - 12.0 * a_sum) / 6.0;
    }
    negh[1] = negh[3] = -cr[0] / 12.0;
    negh[2] = negh[6] = -cr[1] / 12.0;
    negh[5] = negh[7] = -cr[2] / 12.0;
    /* -H scaled to entries in [-1, 1]; a curvature below the inputs'
     * rounding noise (64 ulp of the largest |ln L|) is none. */
    for (i = 0; i < 9; ++i) {
        if (fabs(negh[i]) > scale) {
            scale = fabs(negh[i]);
        }
    }
    if (!(scale > 0.0)) {
        set_illcond3(out);
        return TRN_E_ILLCOND;
    }
    for (i = 0; i < 9; ++i) {
        negh[i] /= scale;
    }
    noise = 64.0 * DBL_EPSILON * (mag > 1.0 ? mag : 1.0);
    if (!chol3(negh, noise / scale, l)) {
        set_illcond3(out);
        return TRN_E_ILLCOND;
    }
    {
        double gs[3], col[3], e[3];
        for (i = 0; i < 3; ++i) {
            gs[i] = g[i] / scale;
        }
        chol3_solve(l, gs, out->offset); /* peak: (-H)^-1 g */
        for (j = 0; j < 3; ++j) {
            e[0] = e[1] = e[2] = 0.0;
            e[j] = 1.0;
            chol3_solve(l, e, col);
            for (i = 0; i < 3; ++i) {
                out->covariance[i * 3 + j] = col[i] / scale;
            }
        }
    }
    for (i = 0; i < 3; ++i) {
        if (!(fabs(out->offset[i]) <= 1.0)) {
            set_illcond3(out);
            return TRN_E_ILLCOND;
        }
        out->sigma[i] = sqrt(out->covariance[(size_t)i * 4u]);
    }
    return TRN_OK;
}
