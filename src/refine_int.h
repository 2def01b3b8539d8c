/* SPDX-License-Identifier: Apache-2.0 */
/* refine_int.h - refine.c's interpolants and the height matcher over
 * heading's entry for trn_localize_dem_heading, internal to the core. */
#ifndef TRN_REFINE_INT_H
#define TRN_REFINE_INT_H

#include <math.h>

#include "trn/grid.h"
#include "trn/height_heading.h"

/* Height and gradient (per cell) at fractional cell (x, y): bicubic
 * convolution (Keys, a = -1/2), bilinear where the 4 x 4 support is
 * incomplete; 0 when there is no height there. */
int trn_refine_sample_(const trn_grid_f32_t *g, double x, double y, double out[3]);

/* The same by bilinear interpolation only. */
int trn_refine_sample_bilinear_(const trn_grid_f32_t *g, double x, double y, double out[3]);

/* Height and gradient of the mixed interpolant B + lam (C - B) at (x, y)
 * (B bilinear, C bicubic; they agree where the 4 x 4 support is
 * incomplete: there C - B = 0), and C - B, the derivative in lam; 0 when
 * there is no height there. The one copy, inline: every pass of the
 * refinement calls it for every cell, and a frame of its own would sit on
 * the deepest stack. */
static inline int trn_refine_sample_mix_(const trn_grid_f32_t *g, double x, double y, double lam,
                                         double out[3], double *dcb)
{
    double b3[3];
    int k;
    if (!trn_refine_sample_bilinear_(g, x, y, b3)) {
        return 0;
    }
    /* the bicubic sampler has a height exactly where the bilinear one has
     * (it falls back to bilinear where its 4 x 4 support is incomplete) */
    (void)trn_refine_sample_(g, x, y, out);
    *dcb = out[0] - b3[0];
    for (k = 0; k < 3; ++k) {
        out[k] = b3[k] + lam * (out[k] - b3[k]);
    }
    return 1;
}

/* The relief rule's clip (a negative clip in trn_refine_weight_). */
#define TRN_REFINE_CLIP_RELIEF (-TRN_REFINE_CLIP)

/* The refinements' weight factor of residual res (standard deviation sd)
 * at fractional cell (x, y): clip >= 0, 1 within clip sds, else 0; clip < 0
 * (TRN_REFINE_CLIP_RELIEF), 1 within -clip sds, 0 beyond -clip sds plus the
 * relief of the map's four cells around (x, y), Huber's -clip sd / |res|
 * between (refine.c). */
double trn_refine_weight_(const trn_grid_f32_t *g, double x, double y, double res, double sd,
                          double clip);

/* The relief test at `at` (the local map turned by heading_rad; cfg the
 * noise model, checked by the caller): the seen local cells within
 * TRN_REFINE_CLIP sds (noise and model variance) of the answer's model are
 * fitted as local = a + b x + c y + g M, M the map's bilinear height under
 * the cell, x, y the cell's offsets, weights 1 / (s^2 + m^2) (the noise
 * model's variance and the answer's model variance); returns
 * (g - 1) / sd(g), sd(g) from those weights. +inf with fewer than 8 cells
 * or no relief to fit (nothing to test). */
double trn_refine_relief_z_(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                            int32_t ry, const trn_refine_t *at, double heading_rad,
                            const trn_refine_cfg_t *cfg);

/* Standard deviation of the seen local heights about their mean (0 for
 * none), and their count (trn_height_search's K is 1 / (10 x it)). */
double trn_refine_local_spread_(const trn_grid_f32_t *local, int32_t *n_seen);

/* The noise model's variance of local cell (x, y), rover cell (rx, ry): the
 * sd noise_m + noise_k_per_m r^2 at r metres from the rover, squared. The
 * one copy for refine.c, refine_pose.c, height_score.c and
 * height_bound.c (inline: the searches and refinements call it for every
 * cell of every pass). */
static inline double trn_refine_noise_var_(const trn_refine_cfg_t *cfg, int32_t x, int32_t y,
                                           int32_t rx, int32_t ry)
{
    double px = (double)(x - rx), py = (double)(y - ry);
    double r_m = (double)cfg->cell_m * sqrt(px * px + py * py);
    double sd = (double)cfg->noise_m + (double)cfg->noise_k_per_m * r_m * r_m;
    return sd * sd;
}

/* The noise variance of local cell (i, j) of l: the noise model's s^2
 * (trn_refine_noise_var_), over the cell's point count n where the
 * configuration gives the counts (trn_refine_cfg_t.point_count): the mean
 * of n points. The one copy for every refinement pass (the searches at
 * integer poses take the model's s^2 by range alone). */
static inline double trn_refine_cell_var_(const trn_refine_cfg_t *cfg, const trn_grid_f32_t *l,
                                          int32_t i, int32_t j, int32_t rx, int32_t ry)
{
    const double s2 = trn_refine_noise_var_(cfg, i, j, rx, ry);
    if (cfg->point_count != NULL) {
        return s2 / (double)cfg->point_count[(size_t)j * (size_t)l->stride + (size_t)i];
    }
    return s2;
}

/* The variance, cells^2 per axis, of where in local cell (i, j) of l its
 * points' unknown centroid lies: n points spread evenly over the cell,
 * 1 / (12 n); 0 where the configuration gives the centroids or no counts. */
static inline double trn_refine_cell_jitter_(const trn_refine_cfg_t *cfg, const trn_grid_f32_t *l,
                                             int32_t i, int32_t j)
{
    if (cfg->point_count == NULL || cfg->centroid_x != NULL) {
        return 0.0;
    }
    return 1.0 / (12.0 * (double)cfg->point_count[(size_t)j * (size_t)l->stride + (size_t)i]);
}

/* Local cell (i, j)'s offset from the rover's cell (rx, ry), cells, into
 * o[0] (east) and o[1] (south): the cell's centre, plus where the
 * configuration gives them (trn_refine_cfg_t.centroid_x, centroid_y) the
 * centroid of what the cell's height was measured from. The one copy for
 * every refinement pass that reads the model under a local cell (inline:
 * they call it for every cell). */
static inline void trn_refine_offset_(const trn_refine_cfg_t *cfg, const trn_grid_f32_t *l,
                                      int32_t i, int32_t j, int32_t rx, int32_t ry, double o[2])
{
    o[0] = (double)(i - rx);
    o[1] = (double)(j - ry);
    if (cfg->centroid_x != NULL) {
        const size_t k = (size_t)j * (size_t)l->stride + (size_t)i;
        o[0] += (double)cfg->centroid_x[k];
        o[1] += (double)cfg->centroid_y[k];
    }
}

/* 1 if cx and cy are both NULL, or both given and every seen cell of local
 * (a finite height) has a finite centroid within TRN_CENTROID_MAX of its
 * centre in each (the local grid's layout); 0 otherwise. */
int trn_refine_centroids_ok_(const trn_grid_f32_t *local, const float *cx, const float *cy);
/* 1 if n is NULL, or every seen cell of local has a finite count n within
 * [1, TRN_POINT_COUNT_MAX] (the local grid's layout); 0 otherwise. */
int trn_refine_counts_ok_(const trn_grid_f32_t *local, const float *n);

/* trn_refine_pose_heading without its argument checks (out's pos into pos,
 * the rest into full; full NULL holds the heading: trn_refine_pose): for
 * the localizations, whose grids, noise model, centroids and rover cell
 * are checked once at their entry, so that no check scans the local map
 * again at every start and no wrapper's frame sits on the deepest stack
 * (src/refine_pose.c). */
trn_status_t trn_refine_run_(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                             int32_t rover_x, int32_t rover_y, int32_t ix, int32_t iy,
                             double heading_rad, double max_turn_rad, const trn_refine_cfg_t *cfg,
                             trn_refine_t *pos, trn_refine3_t *full);

/* The argument checks of trn_refine_pose and trn_refine_pose_heading (the
 * latter adds its heading's): TRN_E_NULL (global, local, cfg, out, one
 * centroid pointer without the other), the grids' status, TRN_E_ARG (cfg
 * out of range or NaN, a seen cell's centroid not finite or beyond
 * TRN_CENTROID_MAX, the rover cell farther than TRN_MAX_DIM from the local
 * grid); TRN_OK. */
trn_status_t trn_refine_args_(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                              int32_t rover_x, int32_t rover_y, const trn_refine_cfg_t *cfg,
                              const void *out);

/* The variances of a pose fit from its weighted moments: residuals e_i
 * about the offset, noise variances v_i, weights q_i = 1 / (k2 v_i + m2)^2
 * at the previous fit; a0 = sum q e^2, a1 = sum q v e^2, sq = sum q,
 * sqv = sum q v, sqvv = sum q v^2. The model variance m2 >= 0 by the
 * weighted moment equation e^2 = k2 v + m2; with fitk the noise variance
 * factor k2 too (its least squares with m2, or alone where m2 would be
 * negative or the two cannot be told apart, in [TRN_NOISE_SCALE2_MIN,
 * TRN_NOISE_SCALE2_MAX]), else k2 = 1 (docs/method.md 9.2). */
static inline void trn_var_fit_(double a0, double a1, double sq, double sqv, double sqvv, int fitk,
                                double *k2, double *m2)
{
    double k = 1.0, m;
    if (fitk) {
        const double det = sqvv * sq - sqv * sqv;
        k = a1 / sqvv;
        if (det > 1e-9 * sqvv * sq && sqvv * a0 - sqv * a1 >= 0.0) {
            k = (a1 * sq - sqv * a0) / det;
        }
        k = k < TRN_NOISE_SCALE2_MIN   ? TRN_NOISE_SCALE2_MIN
            : k > TRN_NOISE_SCALE2_MAX ? TRN_NOISE_SCALE2_MAX
                                       : k;
    }
    m = (a0 - k * sqv) / sq;
    *k2 = k;
    *m2 = m > 0.0 ? m : 0.0;
}

/* The pose fit's weighted moments (trn_height_search's pose_fit):
 * residuals r taken relative to the first one, weights 1 / (k2 v + m2) for
 * the offset and their squares for the variances. */
typedef struct {
    double sw, swr, sq, sqr, sqrr, sqv, sqvv, sqvr, sqvrr, ref;
    int32_t n;
} trn_pose_mom_t;

/* Adds residual r of noise variance v at the variances (k2, m2) (inline:
 * the reference search scores every point of every pose with it). */
static inline void trn_pose_mom_add_(trn_pose_mom_t *a, double r, double v, double k2, double m2)
{
    const double t = k2 * v + m2, q = 1.0 / (t * t);
    double d;
    if (a->n == 0) {
        a->ref = r;
    }
    d = r - a->ref;
    a->sw += 1.0 / t;
    a->swr += d / t;
    a->sq += q;
    a->sqr += q * d;
    a->sqrr += q * d * d;
    a->sqv += q * v;
    a->sqvv += q * v * v;
    a->sqvr += q * v * d;
    a->sqvrr += q * v * d * d;
    a->n += 1;
}

/* The weighted offset and the variances (trn_var_fit_) into dz, k2 and m2;
 * the number of points (0: all three untouched). */
static inline int32_t trn_pose_mom_end_(const trn_pose_mom_t *a, int fitk, double *dz, double *k2,
                                        double *m2)
{
    double d;
    if (a->n == 0) {
        return 0;
    }
    d = a->swr / a->sw;
    trn_var_fit_(a->sqrr - 2.0 * d * a->sqr + d * d * a->sq,
                 a->sqvrr - 2.0 * d * a->sqvr + d * d * a->sqv, a->sq, a->sqv, a->sqvv, fitk, k2,
                 m2);
    *dz = d + a->ref;
    return a->n;
}

/* The searches' clipped pose fit is repeated from its own estimate while a
 * pass drops more than 1 % of the pose's points (a normal sample loses 0.27 %
 * beyond 3 sd), at most TRN_CLIP_AGAIN (trn/refine.h) more times: one clip
 * at the width that gross errors (stereo blunders) inflated keeps many of
 * them (docs/method.md 9, "stereo blunders"). 1 if n_all points, n_prev in
 * the last pass and n now call for another pass. */
static inline int trn_clip_again_(int32_t n_all, int32_t n_prev, int32_t n)
{
    return n > 0 && 100 * (int64_t)(n_prev - n) > (int64_t)n_all;
}

/* The interpolating cubic B-spline of the map's heights at fractional cell
 * (x, y) into *h (the spline step, docs/method.md 9.4): its cardinal
 * function cut to TRN_SPLINE_TAPS taps per axis and normalised to sum 1,
 * summed over the map's heights; 0 where the taps leave the map or meet a
 * cell without a height. Out of line: the refinement's frame is on the
 * deepest stack. */
int trn_refine_spline_(const trn_grid_f32_t *g, double x, double y, double *h);

/* The refinements' model variance from their precision-squared weighted
 * sums (rr of q r^2, noise2 of q s^2, q), never negative (src/refine.c). */
double trn_refine_model2_(double rr, double noise2, double q);

/* A variance ratio (the reduced chi-square, the block sandwich's) that
 * counts only where beyond TRN_REFINE_SYS_Z of its sampling sds (rel_sd,
 * relative to 1) under the noise model: ratio there, else 1. */
double trn_refine_excess_(double ratio, double rel_sd);

/* cos and sin of a finite angle without libm's exact argument reduction
 * and its stack (src/refine.c; within 1e-14 for |a| <= 4 pi). */
void trn_heading_trig_(double a, double *c, double *s);

/* trn_localize_dem_heading's parts (src/localize_heading.c), each out of
 * line so that no path's stack carries another's frame: the voxel path's
 * preparation, then its search (src/heading.c); the checks, then the voxel
 * path or the height matcher's (src/localize_heights.c). */
trn_status_t trn_localize_dem_heading_prep_(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                            int32_t rover_x, int32_t rover_y, size_t max_points,
                                            const trn_window_t *win, void *ws, size_t ws_bytes,
                                            size_t *n, size_t at[2]);
trn_status_t trn_localize_dem_heading_voxel_(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                             int32_t rover_x, int32_t rover_y, size_t max_points,
                                             const trn_window_t *win, const trn_heading_cfg_t *cfg,
                                             void *ws, size_t ws_bytes, trn_heading_result_t *out);
trn_status_t trn_localize_dem_heading_checked_(const trn_map_t *map,
                                               const trn_grid_f32_t *local_dem, int32_t rover_x,
                                               int32_t rover_y, size_t max_points,
                                               const trn_window_t *win,
                                               const trn_heading_cfg_t *cfg, void *ws,
                                               size_t ws_bytes, trn_heading_result_t *out);

/* The noise model's variance factor that the differences of neighbouring
 * residuals at `at` ask for: the mean of (r_a - r_b)^2 / (s_a^2 + s_b^2)
 * over the pairs of seen local cells next to each other (right and below),
 * each residual within 3 sds of the level fit (k2 s^2 + m2), s the
 * configured noise; *pairs their count (NaN for none). A misfit that is
 * smooth over a cell cancels in the differences; white sensor noise does
 * not. Arguments as trn_refine_noise_scale's, checked by the caller. */
double trn_refine_noise_scale_diff_(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                                    int32_t rx, int32_t ry, const trn_refine_t *at,
                                    double heading_rad, const trn_refine_cfg_t *cfg, double k2,
                                    double m2, int32_t *pairs);
/* The valley's share of the failure probability (docs/method.md 9, "the
 * valley"): ln L, over infl, along the major axis of at's covariance, t
 * every TRN_VALLEY_STEP_CELLS out to TRN_VALLEY_REACH_CELLS each way (or
 * to the window [lo, hi], global cells, or until TRN_VALLEY_NATS below the
 * answer), each point's perpendicular offset and dz at their best; the
 * profile's mass beyond TRN_FAIL_RADIUS_CELLS over its whole, the centre's
 * by the quadratic through its first steps where narrower than a step. The
 * integer grid samples a valley narrower than a cell across poorly, so its
 * mass along the valley can vanish from the grid; this samples it along.
 * At the answer's heading heading_rad, held. */
#define TRN_VALLEY_STEP_CELLS 0.25
#define TRN_VALLEY_REACH_CELLS 4.0
#define TRN_VALLEY_NATS 30.0
#define TRN_VALLEY_ITER 3
double trn_refine_valley_fail_(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                               int32_t rx, int32_t ry, const trn_refine_cfg_t *cfg,
                               const trn_refine_t *at, double heading_rad, double infl,
                               const double lo[2], const double hi[2]);
/* The covariance's shoulders (docs/method.md 9, "The shoulders"): along
 * each axis of at's (x, y) covariance, ln L's fall over t^2 at
 * TRN_SHOULDER_NEAR_SD and at TRN_SHOULDER_FAR_SD sds (both sides
 * averaged; each point's offset across the axis and dz at their best, the
 * mix and model variance held); where the far fall is smaller (ln L's
 * shoulders flatter than its peak: a bilinear map's kinks at the cell
 * edges), that axis's variance is multiplied by the ratio, in [1,
 * TRN_SHOULDER_MAX]; at->shoulders the larger factor. At the answer's heading
 * heading_rad, held; cov3 (NULL: none), the (x, y, heading) covariance in
 * cells and radians, takes the same stretch of its position (T cov T^T, T
 * the square root of the stretch along the axes), the heading's own
 * variance unchanged. */
void trn_refine_shoulders_(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                           int32_t ry, const trn_refine_cfg_t *cfg, double heading_rad,
                           trn_refine_t *at, double cov3[9]);
#endif /* TRN_REFINE_INT_H */
