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
