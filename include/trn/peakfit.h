/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file peakfit.h
 * @brief Uncertainty of the maximum-likelihood pose (paper eq. 6, method.md
 * 2.8-2.9).
 *
 * Eq. 6 is a 2-D normal; in the log domain it is the quadratic
 *   f(x, y) = c0 + c1 x + c2 y + c3 x^2 + c4 x y + c5 y^2,
 * fitted by least squares to ln L at the best integer pose and its eight
 * neighbours (x, y in {-1, 0, 1}). The fit gives the subpixel peak
 * -H^-1 (c1, c2) and the covariance Sigma = -H^-1 of the pose, H being the
 * Hessian [[2 c3, c4], [c4, 2 c5]]. If H is not negative definite (a flat or
 * ridge-shaped peak, including a curvature below the rounding noise of the
 * inputs: 64 ulp of the largest |ln L|) no finite covariance exists: TRN_E_ILLCOND, never a
 * small uncertainty.
 */
#ifndef TRN_PEAKFIT_H
#define TRN_PEAKFIT_H

#include "trn/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Result of the eq. 6 fit, in cells (multiply by the cell size for metres). */
typedef struct {
    double dx, dy;           /**< subpixel peak offset from the centre pose */
    double var_x, var_y;     /**< covariance diagonal, cells^2 */
    double cov_xy;           /**< covariance off-diagonal, cells^2 */
    double sigma_x, sigma_y; /**< standard deviations, cells */
    double rho;              /**< correlation coefficient, (-1, 1) */
} trn_peak_t;

/**
 * @brief Fit eq. 6 to a 3x3 patch of log-likelihoods.
 * @param[in]  ll  ln L in nats, row-major: ll[(dy + 1) * 3 + (dx + 1)].
 * @param[out] out the fit. On TRN_E_ILLCOND dx, dy = 0 and the variances and
 *             sigmas are +infinity, rho 0.
 * @retval TRN_OK
 * @retval TRN_E_NULL    ll or out NULL
 * @retval TRN_E_ARG     a value is NaN or infinite
 * @retval TRN_E_ILLCOND Hessian not negative definite, or the fitted peak
 *                       lies outside the 3x3 patch (|dx| or |dy| > 1), or
 *                       an input differs from the centre by more than
 *                       1e300 nats (the fit would overflow)
 */
trn_status_t trn_peak_fit(const double ll[9], trn_peak_t *out);

/** Result of the three-dimensional fit (trn_peak_fit3), in grid units. */
typedef struct {
    double offset[3];     /**< peak offset from the centre sample, per axis */
    double covariance[9]; /**< row-major 3 x 3, units^2 */
    double sigma[3];      /**< standard deviations, sqrt of cov's diagonal */
} trn_peak3_t;

/**
 * @brief Eq. 6 in three dimensions (x, y, heading for
 * trn_localize_points_heading): the 10-term quadratic fitted by least
 * squares to ln L on a 3 x 3 x 3 grid of samples; peak -H^-1 g and
 * covariance -H^-1, as trn_peak_fit.
 * @param[in]  ll  ln L in nats, ll[(d2 + 1) * 9 + (d1 + 1) * 3 + (d0 + 1)],
 *                 d0 fastest.
 * @param[out] out the fit. On TRN_E_ILLCOND d = 0 and the variances and
 *             sigmas are +infinity (off-diagonals 0).
 * @retval TRN_OK
 * @retval TRN_E_NULL    ll or out NULL
 * @retval TRN_E_ARG     a value is NaN or infinite
 * @retval TRN_E_ILLCOND -H not positive definite (a pivot of its Cholesky
 *                       factor at or below the inputs' rounding noise), the
 *                       peak outside the grid (an |offset| above 1), or an
 *                       input more than 1e300 nats from the centre
 */
trn_status_t trn_peak_fit3(const double ll[27], trn_peak3_t *out);

/**
 * @brief Probability that the best peak is the wrong one (method.md 2.9):
 * the two best separated hypotheses weighed by their likelihoods,
 * P = L2 / (L1 + L2) = 1 / (1 + exp(ln L1 - ln L2)).
 * @param[in] ll_best   ln L of the best pose, nats.
 * @param[in] ll_second ln L of the best pose outside the best peak, nats.
 * @param[out] p        probability in [0, 1].
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (not finite, or ll_second > ll_best).
 */
trn_status_t trn_failure_probability(double ll_best, double ll_second, double *p);

#ifdef __cplusplus
}
#endif
#endif /* TRN_PEAKFIT_H */
