/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file refine.h
 * @brief Continuous sub-cell refinement of a matched pose over heights, with
 * its covariance (trn's natural-terrain extension; docs/method.md section 9).
 *
 * Model: a seen local height h_i at rover-relative cell (x_i, y_i) is the
 * global DEM's height at the pose plus one unknown vertical offset plus
 * Gaussian noise: h_i = dz + G(px + x_i, py + y_i) + e_i, with e_i ~ N(0,
 * s_i^2 + m^2), s_i = noise_m + noise_k_per_m * r_i^2 (r_i the cell's range
 * from the rover, metres) and m^2 one model variance common to all points
 * (what the map cannot say of the terrain between and beyond its samples),
 * estimated from the residuals by precision-squared weighted moments at
 * every step. trn_height_search finds the best integer pose exhaustively
 * under that model (G the DEM's own samples, plus a uniform outlier
 * density). trn_refine_pose refines it by Gauss-Newton over (px, py, dz,
 * mix), G between cell centres being the mix B + mix (C - B) of the
 * bilinear B and the bicubic C (Keys' cubic convolution; bilinear where
 * its 4 x 4 support is incomplete), the mix estimated from the data under a
 * weak prior (TRN_REFINE_MIX_MEAN, TRN_REFINE_MIX_SD); residuals beyond
 * TRN_REFINE_CLIP standard deviations are outliers (re-decided every step).
 * Covariance of (px, py), the mix marginalized: (J^T W J)^-1 M (J^T W J)^-1,
 * M the sum of w^2 J J^T times each inlier's variance fitted at the answer
 * (the noise model's, a model variance and the steep cells' sp2 |grad|^2,
 * by leverage-corrected moments; TRN_REFINE_STEEP), x the block-sandwich
 * inflation (TRN_REFINE_BLOCK), only where above 1 by more than
 * TRN_REFINE_SYS_Z of its sampling sds under the noise model (else 1).
 * Beside the estimate, the spline step (trn_refine_t.spline_step): minus
 * the mix (held to [0, 1]) times the pose error the interpolant would make
 * were the ground the map's interpolating cubic B-spline; trn_localize_dem
 * adds it to its answer. docs/modules/refine.md.
 */
#ifndef TRN_REFINE_H
#define TRN_REFINE_H

#include "trn/grid.h"
#include "trn/likelihood.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Residual clip, in robust scales. */
#define TRN_REFINE_CLIP 3.0
/** The height searches' clipped pose fit is repeated from its own estimate
 *  while a pass drops more than 1 % of the pose's points, at most this many
 *  more times (stereo blunders; docs/method.md 9). */
#define TRN_CLIP_AGAIN 4
/** Farthest the refined pose may move from the integer start, cells per
 *  axis: the voxel search can land one cell off on a smooth slope (its
 *  height bins are coarse there); beyond this the start was not this peak. */
#define TRN_REFINE_MAX_SHIFT 2.0
/** Side of the blocks of local cells whose residuals are taken as
 *  correlated by the covariance (cluster-robust sandwich). */
#define TRN_REFINE_BLOCK 4
#ifndef TRN_REFINE_SYS_Z
/** The covariance's block-sandwich ratio (trn_refine_t.inflation; and the
 *  reduced chi-square, built with TRN_REFINE_STEEP 0) count only where above
 *  1 by more than this many of their sampling standard deviations under the
 *  noise model. */
#define TRN_REFINE_SYS_Z 1.0
#endif
#ifndef TRN_REFINE_STEEP
/** 1: the covariance holds the steep cells' variance, sp2 |grad|^2 a cell
 *  beyond the model, sp2 fitted from the residuals (docs/method.md 9.5); 0
 *  leaves it out (the ablation's switch). */
#define TRN_REFINE_STEEP 1
#endif
/** The covariance's shoulders (trn_localize_dem's height matcher, x-y only;
 *  docs/method.md 9, "The shoulders"): along each axis of the refined (x, y)
 *  covariance ln L's fall over t^2 is compared at t = TRN_SHOULDER_NEAR_SD
 *  and TRN_SHOULDER_FAR_SD sds; where it is smaller far out, ln L is not
 *  the quadratic its peak's curvature describes (a bilinear map's kinks at
 *  the cell edges: a sharp peak with broad shoulders), and that axis's
 *  variance takes the ratio, at most TRN_SHOULDER_MAX. Two sds: the middle
 *  of the 1, 2 and 3-sigma ellipses the calibration is judged by. */
#define TRN_SHOULDER_FAR_SD 2.0
/** ... near: half an sd, where the peak's own curvature rules */
#define TRN_SHOULDER_NEAR_SD 0.5
/** ... largest factor (a profile that hardly falls is the failure
 *  probability's to report, not the ellipse's) */
#define TRN_SHOULDER_MAX 16.0
/** Prior of the interpolants' mix (0 bilinear, 1 bicubic): its mean, the
 *  middle of the bracket the two interpolants make, */
#define TRN_REFINE_MIX_MEAN 0.5
/** and its standard deviation: weak, so a data set that pins the mix down
 *  (a local map sampled bilinearly, bicubically, or sharper than either)
 *  is not pulled to the middle. */
#define TRN_REFINE_MIX_SD 1.0
/** Largest Gauss-Newton iterations of each of the refinement's two phases
 *  (the plain clip, then the relief rule: docs/method.md 9, "the clip"). */
#define TRN_REFINE_MAX_ITER 12

/** Largest |centroid| a seen local cell may give (trn_refine_cfg_t.centroid_x,
 *  centroid_y), cells: a point binned into a cell lies within half a cell of
 *  its centre. */
#define TRN_CENTROID_MAX 0.5
/** Largest point count a seen local cell may give (trn_refine_cfg_t.point_count). */
#define TRN_POINT_COUNT_MAX 1000000.0

/** Height-noise model of the local map, s(r) = noise_m + noise_k_per_m r^2,
 *  and where and from how many points the local cells were measured. Zero
 *  the struct (or set the centroid and count pointers NULL) before filling
 *  it in. */
typedef struct {
    float cell_m;             /**< cell of both grids, metres, (0, TRN_CELL_MAX_M] */
    float noise_m;            /**< constant part, metres, (0, 1000] */
    float noise_k_per_m;      /**< range-squared part, 1/m, [0, 1000] */
    float inlier_prob;        /**< a of the mixture ln L (trn_refine_t.ll), (0, 1) */
    int32_t fit_noise;        /**< 1: the searches' pose score fits the noise model's scale per pose
                              (a variance factor in [TRN_NOISE_SCALE2_MIN, TRN_NOISE_SCALE2_MAX]
                              beside the offset and the model variance: docs/method.md 9.2);
                              0: the model as given. The refinements ignore it. 0 or 1. */
    const float *centroid_x;  /**< NULL (both NULL): each local cell's height is the ground at
                                  the cell's centre. Otherwise, per local cell in the local
                                  grid's layout (its stride), where in the cell its height
                                  was measured, cells east of its centre: for a cell that is
                                  the mean of binned stereo points, their centroid. Every
                                  refinement pass reads the model there (the searches at
                                  integer poses do not). Seen cells: finite, within
                                  [-TRN_CENTROID_MAX, TRN_CENTROID_MAX]; unseen cells are not
                                  read (docs/method.md 9.10, "The centroids") */
    const float *centroid_y;  /**< the same, cells south of the centre (the grid's rows) */
    const float *point_count; /**< NULL: each local cell is one measurement, its noise the
                                  model's s(r). Otherwise, per local cell in the local grid's
                                  layout, the number n of stereo points whose mean its height
                                  is: its noise variance is s(r)^2 / n, and without the
                                  centroids their unknown centroid adds |grad|^2 / (12 n)
                                  (cells^2 times the slope's square) to the covariance's
                                  cell variance, and the covariance leaves out the block
                                  sandwich (trn_refine_t.inflation 1). Every refinement pass
                                  reads it (the searches
                                  at integer poses do not). Seen cells: finite, within
                                  [1, TRN_POINT_COUNT_MAX]; unseen cells are not read
                                  (docs/method.md 9.10, "The point counts") */
} trn_refine_cfg_t;

/** Best integer pose of trn_height_search. */
typedef struct {
    int32_t x, y;   /**< global cell of the local rover cell */
    double ll;      /**< its log-likelihood, nats (see trn_height_search) */
    double dz_m;    /**< its vertical offset local - global, metres */
    double model_m; /**< its model error m, metres */
    uint64_t poses; /**< poses evaluated */
    double lse_all; /**< ln sum over every pose of the window of exp(ll / ll_scale) */
    double lse_out; /**< the same over the poses outside the exclusion zone
                             (= lse_all without one) */
} trn_height_best_t;

/** Result of trn_refine_pose. Pose in global cells (x = column, y = row). */
typedef struct {
    double x, y;           /**< refined pose of the local rover cell */
    double dz_m;           /**< vertical offset local - global, metres */
    double model_m;        /**< model error estimated beside the noise, metres */
    double cov_cells[3];   /**< var_x, var_y, cov_xy in cells^2 */
    double chi2_dof;       /**< reduced chi-square of the inliers (built with
                                 TRN_REFINE_STEEP 0 the covariance takes it where beyond
                                 TRN_REFINE_SYS_Z sds, sqrt(2 / dof), of 1) */
    double inflation;      /**< factor (>= 1) the block sandwich put on the model covariance:
                                 its larger position variance ratio where beyond
                                 TRN_REFINE_SYS_Z sampling sds of 1, else 1; 1 where the
                                 configuration gives the point counts (the cells' noise and
                                 jitter known: docs/method.md 9.5) */
    double ll_inflation;   /**< the ratio ungated, against the model times max(1, chi2_dof)
                                 (>= 1; the factor before 2026-12-04): ln L's divisor in the
                                 failure probability (trn_localize_dem) */
    double spline_step[2]; /**< the spline step applied to (x, y), cells: the mix held to
                                 [0, 1] times minus the pose error the model's interpolant
                                 makes where the ground runs as the map's interpolating
                                 cubic B-spline (docs/method.md 9.4); 0 where not taken */
    double shoulders;      /**< factor (>= 1) trn_localize_dem put on the (x, y)
                                 covariance along an axis where ln L's fall at
                                 TRN_SHOULDER_FAR_SD sds is flatter than at
                                 TRN_SHOULDER_NEAR_SD (the larger axis's); 1 from
                                 trn_refine_pose, over heading and where not applied */
    double interp_mix;     /**< the estimated mix of the interpolants: 0 bilinear,
                                 1 bicubic (beyond [0, 1]: sharper or smoother) */
    double ll;             /**< trn_height_search's mixture ln L at the refined pose
                                 (the mixed interpolant; compares refinements) */
    int32_t n_used;        /**< inlier points of the last iteration */
    int32_t n_seen;        /**< seen local points with a global height under them */
    int32_t iterations;    /**< Gauss-Newton steps taken, both phases */
} trn_refine_t;

/**
 * @brief Refine the pose of a local DEM in a global DEM from an integer
 * start (ix, iy) (the voxel search's best pose).
 * @param[in] global  global heights, metres (NaN = unknown)
 * @param[in] local   local heights, metres, same cell size (NaN = not seen)
 * @param[in] rover_x, rover_y the rover's cell in local's grid
 * @retval TRN_OK
 * @retval TRN_E_NULL, TRN_E_SIZE (bad grids), TRN_E_ARG (cfg, or a rover
 *         cell farther than TRN_MAX_DIM from the local grid)
 * @retval TRN_E_RANGE   start pose off the global grid
 * @retval TRN_E_NODATA  fewer than 8 seen points with global heights
 * @retval TRN_E_ILLCOND the normal matrix is singular (flat terrain), the
 *         estimate left the start pose's neighbourhood (|dx| or |dy|
 *         over TRN_REFINE_MAX_SHIFT cells), or fewer than half of the points are inliers: the
 *         out values are then the start pose and infinite variances
 */
trn_status_t trn_refine_pose(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                             int32_t rover_x, int32_t rover_y, int32_t ix, int32_t iy,
                             const trn_refine_cfg_t *cfg, trn_refine_t *out);

/** The data must reject the configured noise model by this many sampling
 *  standard deviations of trn_refine_noise_scale's estimate before
 *  trn_localize_dem rescales it (a two-sided test at about 95 %). */
#define TRN_NOISE_SCALE_Z 2.0
/** Mean square of a unit normal truncated at +-TRN_REFINE_CLIP (3):
 *  1 - 2 x 3 phi(3) / (2 Phi(3) - 1). Residuals kept within the clip have
 *  this fraction of their variance as their mean square. */
#define TRN_CLIP_MEAN_SQUARE 0.973343
/** Smallest noise scale (variance factor) trn_refine_noise_scale reports,
 *  and the least the searches' pose score fits (trn_refine_cfg_t.fit_noise). */
#define TRN_NOISE_SCALE2_MIN 1e-4
/** Largest noise scale (variance factor) the searches' pose score fits. */
#define TRN_NOISE_SCALE2_MAX 1e4

/**
 * @brief The noise scale the residuals at a refined pose ask for: the local
 * heights' residuals r_i at `at` (pose, offset dz_m, interp_mix), regressed
 * as r_i^2 = k2 s_i^2 + m2 (s_i the configured sensor noise, m2 >= 0 a
 * model variance common to all points) by least squares weighted by
 * 1 / v_i^2, v_i = k2 s_i^2 + m2, over the points within TRN_REFINE_CLIP
 * sqrt(v_i) (their mean squares divided by TRN_CLIP_MEAN_SQUARE), from k2 =
 * 1 and m2 = at->model_m^2, four times. The sensor's noise grows with range
 * and the model variance does not, which is what tells them apart; with a
 * narrow range of s_i the estimate's sd is large. docs/method.md 9, "the
 * sensor's noise from the data".
 * @param[in]  at    a refinement of trn_refine_pose (TRN_OK) of this local map, or
 *                   the pos of trn_refine_pose_heading's
 * @param[in]  heading_rad the local map's turn at `at` (trn_refine3_t.heading_rad; 0
 *                   for trn_refine_pose's), |heading_rad| <= TRN_HEADING_MAX_WINDOW_RAD
 * @param[out] k2    the variance factor on the configured noise, >= TRN_NOISE_SCALE2_MIN
 * @param[out] k2_sd its sampling sd were the model right: sqrt(2 (X^T Q X)^-1) of
 *                   the two-parameter fit (Gaussian residuals), also where m2 met its bound
 * @retval TRN_OK
 * @retval TRN_E_NULL, TRN_E_SIZE (bad grids), TRN_E_ARG (cfg, rover cell, `at`
 *         not finite, heading_rad out of range)
 * @retval TRN_E_NODATA fewer than 8 points within the clip
 * @retval TRN_E_ILLCOND the regression is singular (every s_i alike and m2 free)
 */
trn_status_t trn_refine_noise_scale(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                                    int32_t rover_x, int32_t rover_y, const trn_refine_t *at,
                                    double heading_rad, const trn_refine_cfg_t *cfg, double *k2,
                                    double *k2_sd);

/**
 * @brief Exhaustive maximum-likelihood search of integer poses over heights
 * (the natural-terrain matcher, docs/method.md section 9). Every seen local
 * point i contributes ln(a N(r_i - dz; 0, s_i^2 + m^2) + (1 - a) K), with
 * r_i = h_i - G(pose + p_i) at integer cells; a point with no global height
 * under it (off the map, NaN) contributes ln((1 - a) K). Per pose, dz and m^2
 * are estimated (weighted mean; moments), then again without the points
 * beyond TRN_REFINE_CLIP of that fit, repeated while a pass drops more than
 * 1 % of the points (at most TRN_CLIP_AGAIN more times; a profile
 * likelihood). K = 1 / (10 sd of the local
 * heights), one value per call, so scores compare across poses.
 * With an exclusion zone every pose is still scored (it counts in lse_all)
 * but the best is taken outside the zone; exp(lse_out - lse_all) is then the
 * posterior mass outside the zone (uniform prior over the window), the
 * failure probability trn_localize_dem reports.
 * @param[in] inlier_prob a, in (0, 1)
 * @param[in] ex          poses that cannot be the best (NULL: none)
 * @param[in] ll_scale    ln L is divided by it in lse_all and lse_out, [1, 1e6]
 *                        (correlated residuals: trn_refine_t.inflation)
 * @param[out] ll_grid    NULL, or (x1-x0+1)*(y1-y0+1) doubles: every pose's
 *                        ln L, row-major over the window (trn_height_mass)
 * @retval TRN_OK
 * @retval TRN_E_NULL, TRN_E_SIZE (bad grids), TRN_E_ARG (cfg, a, rover cell
 *         farther than TRN_MAX_DIM, negative exclusion radius)
 * @retval TRN_E_RANGE  window empty or not inside the global grid
 * @retval TRN_E_NODATA fewer than 8 seen local points, or every pose excluded
 */
trn_status_t trn_height_search(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                               int32_t rover_x, int32_t rover_y, const trn_window_t *win,
                               const trn_exclusion_t *ex, const trn_refine_cfg_t *cfg,
                               float inlier_prob, double ll_scale, double *ll_grid,
                               trn_height_best_t *best);

/**
 * @brief trn_height_search's best pose outside a zone, lse_all and lse_out,
 * from the ln L grid of an earlier search over the same window (no pose is
 * scored again; dz_m and model_m are NaN).
 * @retval TRN_OK
 * @retval TRN_E_NULL, TRN_E_ARG (negative radius, ll_scale outside [1, 1e6])
 * @retval TRN_E_RANGE  window empty, negative or beyond TRN_MAX_DIM
 * @retval TRN_E_NODATA every pose excluded
 */
trn_status_t trn_height_mass(const double *ll_grid, const trn_window_t *win,
                             const trn_exclusion_t *ex, double ll_scale, trn_height_best_t *best);

#ifdef __cplusplus
}
#endif
#endif /* TRN_REFINE_H */
