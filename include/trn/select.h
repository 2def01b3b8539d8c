/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file select.h
 * @brief Landmark selection (paper section 4; method.md 4): predicted
 * localization uncertainty of every candidate target seen from one rover
 * position, the best target and the next best distinct ones.
 *
 * Candidates: patch centres on a lattice of stride_cells around the rover's
 * cell whose patch, grown by one cell for the pose offsets, lies inside the
 * map (a patch cut by the map's edge would look informative because of the
 * edge alone: off the map every voxel scores the cap), at range [min_range_m, max_range_m] from the rover, at a
 * bearing (grid frame: atan2(dy, dx), x = column, y = row) minus the rover's
 * heading within [pan_min_rad, pan_max_rad], and whose square patch (side
 * patch_cells = patch_m / cell_m rounded to the nearest integer, plus one if
 * even, so 2 m at 0.1 m cells is 21 cells) keeps
 * out of the rover's footprint disc (radius footprint_radius_m).
 *
 * Prediction: P = eq. 9 applied to P_G over the union of the candidate
 * patches (trn_prob_local). The patch is a probabilistic local map, so the
 * expected log-likelihood at pose offset d (dx, dy in -1..1) is
 *   E[ln L(d)] = sum_{v in patch} P(v) ln p(D(v + d)),
 * D the global map's chamfer distances (off the map: the cap) and ln p the
 * map's table. Dynamic programming: for each d, C_d(x, y) = sum_z q(P) lnp(D)
 * over the region, with q(P) = round(P * TRN_SELECT_PROB_SCALE) (P clamped
 * to [0, 4]), is accumulated into an exact int64 summed-area table, so every
 * candidate's window sum costs four reads and is exact (a flat map gives
 * exactly equal sums: no rounding can fake a curvature). Eq. 6 on the nine
 * values (trn_peak_fit) gives sigma_x, sigma_y, rho; the scalar to minimise is
 * sqrt(sigma_x^2 + sigma_y^2) in metres. A candidate whose fit is
 * ill-conditioned is uninformative: infinite uncertainty, informative = 0.
 *
 * Uncertain heading (beyond the paper; method.md 4, "The heading's lever
 * arm"): with sigma_heading_rad = s_h > 0 the matcher, which searches x and y
 * with the heading taken as known, places a target at range r off by
 * r * dtheta along the tangent t (perpendicular to the line of sight) when
 * the heading is off by dtheta. That error is common to every point of the
 * patch (a rigid turn, not noise that averages), independent of the
 * matching error, so it adds to the fit's covariance:
 *   cov = cov_fit + s_h^2 r^2 t t^T = cov_fit + s_h^2 c^2 [dy^2, -dx dy; -dx dy, dx^2],
 * (dx, dy) the rover-to-target offset in cells of c metres, and the scalar
 * becomes sqrt(sigma_x^2 + sigma_y^2 + s_h^2 r^2). Targets are compared on
 * it, so with an uncertain heading nearer targets are preferred. With
 * s_h = 0 every value is the paper's prediction bit for bit.
 *
 * Heading searched (heading_search = 1, s_h > 0; method.md 4, "Patches that
 * pin the heading down"): a voxel v at rover-relative u_v (cells) moves by
 * d + theta J u_v under a pose change (d, theta), J the quarter turn. Eq. 6's
 * Hessian is linear in the nine sums, so each voxel has its share A_v of the
 * precision A = -H, and the information of (d, theta) is
 *   [A, b; b^T, c + s_h^-2],  b = sum A_v J u_v,  c = sum (J u_v)^T A_v J u_v;
 * the position's covariance is its marginal
 *   cov = A^-1 + g g^T / (s_h^-2 + I),  g = A^-1 b,  I = max(0, c - b^T g),
 * (times c^2 in m^2), g the lever arm to the patch's information-weighted
 * centroid and I the heading information beyond it (the spread of the
 * structure about that centroid). b and c need the nine sums' first and
 * second moments over each patch (x, y, xx, xy, yy), taken from per-row
 * prefix sums in double beside the exact int64 tables. heading_m is then
 * |g| c / sqrt(s_h^-2 + I). Structure concentrated at the patch centre gives
 * g = J (dx, dy) and I = 0: the lever arm above exactly.
 *
 * The height matcher's prediction (method.md 4, "The height matcher's
 * prediction"): when the map matches heights (map->cfg.match ==
 * TRN_MATCH_HEIGHTS, its heights stored), the prediction is that matcher's
 * own model instead, and k and pg are not read (they may be NULL). The
 * local heights l = h(p + u) + dz + noise of a patch's cells give the
 * information of the pose p (per cell^2)
 *   I = sum w (g - gw)(g - gw)^T,   gw = sum w g / sum w,
 * over the patch's cells whose four neighbours are known, g the map's
 * central-difference gradient (m per cell; the offset dz profiled out,
 * hence the weighted centring), w = 1 / s^2 each cell's own variance
 *   s^2 = (noise_m + noise_k_per_m r^2)^2 + map_sigma_m^2 + e^2 / 4,
 * r the cell's range from the rover, the first term the matcher's own
 * noise model (map->cfg; with points_per_cell n > 0, a binned local map,
 * divided by n and |g|^2 / (12 n) added, its points' centroid's jitter),
 * e = h - the mean of its four neighbours (the
 * map's representation error: a bilinear interpolant's is at most half of
 * it). The covariance is I^-1 (cells^2, times cell_m^2), ll[d] the expected
 * -d^T I d / 2; a patch with fewer than 3 such cells, or whose I is singular
 * to 1e-12 of its uncentred sum w |g|^2 (flat ground, a plane: a shift
 * along a plane is a height offset) is uninformative. Exact int64
 * summed-area tables give every candidate's sums in O(1). The heading's
 * lever arm applies as above; heading searched, the marginal above with
 * the heights' b = sum w (g - gw)(t - tw), c = sum w (t - tw)^2, t = g . J u
 * the heading's column (u the cell's offset from the rover, cells).
 */
#ifndef TRN_SELECT_H
#define TRN_SELECT_H

#include <stddef.h>
#include <stdint.h>
#include "trn/localize.h"
#include "trn/spread.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Fixed-point scale of P in the expected log-likelihood sums. */
#define TRN_SELECT_PROB_SCALE 65536

/** Candidate rules (see the file comment). */
typedef struct {
    float min_range_m;             /**< nearest target, m, [0, max_range_m] */
    float max_range_m;             /**< farthest target, m, (0, 1e6], at most TRN_MAX_DIM cells */
    float pan_min_rad;             /**< bearing limits relative to the heading, */
    float pan_max_rad;             /**< [-pi, pi], min <= max */
    float footprint_radius_m;      /**< rover disc no patch may touch, m, [0, 1e5] */
    float patch_m;                 /**< patch side, m; >= 3 cells after rounding (file comment) */
    int32_t stride_cells;          /**< candidate lattice step, 1..64 */
    float min_separation_m;        /**< least distance between ranked targets, m, [0, 1e6] */
    trn_sigma_model_t local_sigma; /**< eq. 9 error model of the new local map */
    float sigma_heading_rad;       /**< standard deviation of the rover's heading, rad,
                                   [0, TRN_SELECT_MAX_SIGMA_HEADING_RAD]; 0 (the default):
                                   the heading is known, the paper's prediction exactly */
    int32_t heading_search;        /**< 0 (the default): the target will be matched in x and y
                                   with the believed heading (the lever arm above); 1: by a
                                   search over heading too (trn_localize_dem_heading), so with
                                   sigma_heading_rad > 0 the prediction is the position's
                                   marginal of the (x, y, heading) fit with that prior: patches
                                   whose structure spreads across them pin the heading and lose
                                   less (method.md 4); with sigma_heading_rad = 0 no effect */
    float map_sigma_m;             /**< the height prediction only (a map that matches heights):
                                   the global DEM's height error, standard deviation, metres,
                                   [0, 1000] (default 0.02, eq. 8's S0 of
                                   trn_sigma_global_default); the voxel prediction takes the
                                   map's error from P_G (eq. 8) instead */
    float points_per_cell;         /**< the height prediction only: the stereo points the rover
                                   expects to bin into each seen cell of its local map, when it
                                   passes their counts (trn_localize_dem_cells) but not their
                                   centroids: each cell's noise is then the model's s^2 / n and
                                   the jitter of its points' centroid, |g|^2 / (12 n), is added
                                   (method.md 4); 0 (the default): each cell one measurement at
                                   its centre, s^2; else [1, TRN_POINT_COUNT_MAX] */
} trn_select_cfg_t;

/** Largest sigma_heading_rad (0.5 rad, 28.6 deg): the heading's term is the
 * first-order (small-angle) lever arm r * dtheta; at this sigma a 2-sigma
 * turn already moves a target by a chord 4 % shorter than that and points a
 * 10 m target's patch about 10 m off (method.md 4). */
#define TRN_SELECT_MAX_SIGMA_HEADING_RAD 0.5f

/** The rover: position (global cells) and heading (rad, grid frame). */
typedef struct {
    trn_xy_t pos;
    float heading_rad;
} trn_rover_t;

/** One candidate target and its prediction (Fig. 2b is the set of these). */
typedef struct {
    int32_t x, y;                     /**< patch centre, global cells */
    float range_m;                    /**< distance from the rover, m */
    float bearing_rad;                /**< relative to the heading, (-pi, pi] */
    double ll[9];                     /**< E[ln L(d)], nats, ll[(dy + 1) * 3 + (dx + 1)] */
    double sigma_x_m, sigma_y_m, rho; /**< eq. 6 fit (with the heading's term);
                                           +inf sigmas when uninformative */
    double cov_m2[3];                 /**< var_x, var_y, cov_xy, m^2 (with the heading's term) */
    double uncertainty_m; /**< sqrt(sigma_x^2 + sigma_y^2), m; +inf when uninformative */
    double heading_m;     /**< the heading's part, sigma_heading_rad * range, m
                                (heading_search: |g| c / sqrt(s_h^-2 + I), file comment)
                                (0 with a known heading); the fit's own sigmas are
                                sqrt(var - its term) (file comment) */
    int32_t informative;  /**< 1 finite fit, 0 ill-conditioned */
} trn_candidate_t;

/** Summary of one selection. */
typedef struct {
    trn_window_t roi;     /**< region where P (eq. 9) was computed */
    size_t n_candidates;  /**< entries written to the candidate array */
    size_t n_informative; /**< of them with a finite fit */
    size_t n_ranked;      /**< entries written to the ranked array */
    size_t best;          /**< index of the best candidate (= ranked[0]) */
    int32_t patch_cells;  /**< patch side used */
} trn_select_result_t;

/** @brief Defaults (method.md 4): range 1-10 m, full pan (+-pi), footprint
 * 0.5 m, 2 m patch (21 cells at 0.1 m), stride 2 cells, separation 1 m (half
 * a patch), local error trn_sigma_local_default, heading known (sigma 0),
 * the DEM's height error 0.02 m (the height prediction).
 * @param[out] cfg the defaults; NULL is ignored. */
void trn_select_cfg_default(trn_select_cfg_t *cfg);

/** @brief Check a configuration for cells of cell_m (patch >= 3 cells, reach
 * <= TRN_MAX_DIM cells). @param[in] cfg, cell_m the rules and the map's cell (m).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (a value NaN or out of range, also
 *         sigma_heading_rad NaN, negative or above TRN_SELECT_MAX_SIGMA_HEADING_RAD). */
trn_status_t trn_select_cfg_check(const trn_select_cfg_t *cfg, float cell_m);

/** @brief Largest number of candidates of one rover position (array size); 0 if invalid.
 * @param[in] cfg, cell_m the rules and the map's cell (m). */
size_t trn_select_max_candidates(const trn_select_cfg_t *cfg, float cell_m);

/** @brief Workspace bytes of trn_select for this map and kernels (0 if invalid).
 * @param[in] cfg, map, k the rules, the prepared map, the built kernels. */
size_t trn_select_workspace_bytes(const trn_select_cfg_t *cfg, const trn_map_t *map,
                                  const trn_kernels_t *k);

/**
 * @brief Score every candidate target of one rover position and rank them.
 * @param[in]  map      prepared global map (distances, ln p table, cell size;
 *                      a map matching heights: its heights, the height prediction).
 * @param[in]  k        kernel table (not read by the height prediction; may be NULL).
 * @param[in]  pg       eq. 8 probability map of this map (same nx, ny, nz; not
 *                      read by the height prediction; may be NULL).
 * @param[in]  cfg      candidate rules.
 * @param[in]  rover    rover position (on the map) and heading (finite).
 * @param[out] cands    capacity entries; n_candidates written (row-major lattice order).
 * @param[out] ranked   ranked_cap indices into cands: best first, then the
 *                      next best informative targets, each at least
 *                      min_separation_m from every earlier one.
 * @param[out] res      summary.
 * @param[in]  ws       trn_select_workspace_bytes bytes, 16-byte aligned.
 * @retval TRN_OK
 * @retval TRN_E_NOTARGET candidates exist but none is informative (cands,
 *         res filled; n_ranked = 0) or no candidate lies within reach
 * @retval TRN_E_NULL, TRN_E_ARG (cfg, rover not finite), TRN_E_SIZE (pg does
 *         not match the map, or the region is too large for exact int64 sums,
 *         with heights: for its gradients),
 *         TRN_E_RANGE (rover off the map), TRN_E_CAPACITY (more candidates
 *         than capacity, ranked_cap 0), TRN_E_WORKSPACE
 */
trn_status_t trn_select(const trn_map_t *map, const trn_kernels_t *k, const trn_vol_f32_t *pg,
                        const trn_select_cfg_t *cfg, const trn_rover_t *rover,
                        trn_candidate_t *cands, size_t capacity, size_t *ranked, size_t ranked_cap,
                        trn_select_result_t *res, void *ws, size_t ws_bytes);

#ifdef __cplusplus
}
#endif
#endif /* TRN_SELECT_H */
