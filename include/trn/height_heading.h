/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file height_heading.h
 * @brief The natural-terrain height matcher (TRN_MATCH_HEIGHTS, refine.h)
 * over (x, y, heading) (issue 14, docs/modules/heading.md).
 *
 * The local DEM's own seen cells are the observations at every heading:
 * only their offsets from the rover cell turn (trn_points_rotate's
 * convention and rounding, a table per call in the workspace), so each
 * heading's likelihood sums the same data and the ln L of different
 * headings compare. The search is exhaustive over every integer pose of the
 * window at every heading step (centre + k step, k = -K..K, the step as
 * trn_heading_steps chooses it from the farthest seen cell); every
 * (pose, heading)'s ln L is kept, so the failure probability is the
 * posterior mass of the whole (x, y, heading) space outside the position
 * zone. The refinement is trn_refine_pose's Gauss-Newton with the heading
 * as a fourth parameter (the map at the pose plus the offset turned
 * continuously; d/d heading = gradient . the turned offset rotated by 90
 * degrees), with the same weights, model variance, clip, interpolants' mix
 * (estimated, folded out of the covariance), block-sandwich inflation,
 * interpolants' shift weighted by the data's misfit and refined mixture
 * ln L, giving the 3 x 3 (x, y, heading) covariance.
 */
#ifndef TRN_HEIGHT_HEADING_H
#define TRN_HEIGHT_HEADING_H

#include <stddef.h>
#include <stdint.h>

#include "trn/heading.h"
#include "trn/refine.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Farthest the refined heading may turn from its start, in heading steps
 *  (the search's grid): as TRN_REFINE_MAX_SHIFT in cells. */
#define TRN_REFINE_MAX_TURN_STEPS 2.0

/** Best (pose, heading) of trn_height_search_heading. */
typedef struct {
    int32_t x, y;       /**< best integer pose (global cell of the rover cell) */
    int32_t k;          /**< its heading step: heading = centre + k step */
    double ll;          /**< its ln L, nats (as trn_height_search) */
    double dz_m;        /**< its vertical offset local - global, metres */
    double model_m;     /**< its model error m, metres */
    double step_rad;    /**< heading step used */
    int32_t half_steps; /**< K */
    uint64_t poses;     /**< (pose, heading) pairs scored */
} trn_height_best3_t;

/** Result of trn_refine_pose_heading. */
typedef struct {
    trn_refine_t pos;               /**< as trn_refine_pose: pose, dz, model error, cov_cells (the
                              position block of cov3), chi2, inflation, spline_step
                              (x, y), interp_mix, ll (at the refined
                              heading), counts */
    double heading_rad;             /**< refined heading (the start when held fixed) */
    double cov3[9];                 /**< covariance of (x cells, y cells, heading rad), row-major;
                              heading row and column 0 when held fixed */
    double spline_step_heading_rad; /**< heading part of the spline step, rad */
} trn_refine3_t;

/**
 * @brief Heading step and K for the seen cells of a local DEM: as
 * trn_heading_steps with the farthest seen cell from the rover as r_max.
 * @retval TRN_OK
 * @retval TRN_E_NULL
 * @retval TRN_E_SIZE bad grid, or more than TRN_MAX_HEADING_STEPS headings
 * @retval TRN_E_ARG  cfg out of range or NaN, or the rover cell farther than
 *         TRN_MAX_DIM from the grid
 * @retval TRN_E_NODATA no seen cell, or only the rover's own with a window
 */
trn_status_t trn_height_heading_steps(const trn_grid_f32_t *local, int32_t rover_x, int32_t rover_y,
                                      const trn_heading_cfg_t *cfg, double *step_rad,
                                      int32_t *half_steps);

/** @brief Workspace bytes of trn_height_search_heading for a width x height
 * local DEM (the seen cells, their turned offsets and one pose's residuals,
 * 52 bytes a cell; 0 if invalid). */
size_t trn_height_heading_workspace_bytes(int32_t width, int32_t height);

/**
 * @brief Exhaustive height search over every integer pose of the window at
 * every heading step (see the file comment). Per (pose, heading): the same
 * score as trn_height_search with the offsets turned (src/height_score.c, the
 * one scorer of the searches with a workspace); at a heading of 0 it is
 * trn_height_search's ln L within rounding (1e-12 relative), and
 * trn_localize_dem's search's bit for bit. Ties: the heading first in the
 * order 0, -1, +1, -2, ..., then the scan order (y, then x).
 * @param[in] ws       trn_height_heading_workspace_bytes(width, height) bytes,
 *                     TRN_WS_ALIGN-aligned
 * @param[out] ll_grid NULL, or (2K + 1) x window poses doubles (K from
 *                     trn_height_heading_steps): ln L of
 *                     heading step k at pose (x, y) at
 *                     [((k + K) (y1 - y0 + 1) + y - y0) (x1 - x0 + 1) + x - x0]
 * @retval TRN_OK
 * @retval TRN_E_NULL
 * @retval TRN_E_SIZE bad grids, or more than TRN_MAX_HEADING_STEPS headings
 * @retval TRN_E_ARG  rcfg, a, hcfg (NaN or out of range) or the rover cell
 * @retval TRN_E_RANGE window empty or not inside the global grid
 * @retval TRN_E_WORKSPACE ws_bytes too small or ws misaligned
 * @retval TRN_E_NODATA fewer than 8 seen local points
 */
trn_status_t trn_height_search_heading(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                                       int32_t rover_x, int32_t rover_y, const trn_window_t *win,
                                       const trn_heading_cfg_t *hcfg, const trn_refine_cfg_t *rcfg,
                                       float inlier_prob, void *ws, size_t ws_bytes,
                                       double *ll_grid, trn_height_best3_t *best);

/**
 * @brief trn_refine_pose over (x, y, heading, dz, mix) from the integer
 * pose (ix, iy) at heading heading_rad (the local DEM's offsets turned by
 * it). With the heading held fixed at 0 the answer is trn_refine_pose's.
 * @param[in] max_turn_rad farthest the heading may move, [0, pi]; 0: the
 *            heading is held fixed (x, y, dz and the mix only).
 * @retval TRN_OK
 * @retval TRN_E_NULL, TRN_E_SIZE (bad grids)
 * @retval TRN_E_ARG cfg (inlier_prob included), heading not finite or over
 *         pi in size, max_turn_rad out of range, or the rover cell farther
 *         than TRN_MAX_DIM
 * @retval TRN_E_RANGE   start pose off the global grid
 * @retval TRN_E_NODATA  fewer than 8 seen points with global heights
 * @retval TRN_E_ILLCOND singular normal matrix, the estimate left the start's
 *         neighbourhood (TRN_REFINE_MAX_SHIFT cells, max_turn_rad), or fewer
 *         than half of the points inliers: out is the start with infinite
 *         variances
 */
trn_status_t trn_refine_pose_heading(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                                     int32_t rover_x, int32_t rover_y, int32_t ix, int32_t iy,
                                     double heading_rad, double max_turn_rad,
                                     const trn_refine_cfg_t *cfg, trn_refine3_t *out);

/**
 * @brief Workspace bytes of trn_localize_dem_heading for this local DEM,
 * rover cell and heading search: with a TRN_MATCH_HEIGHTS map the exact
 * need (the search's tables and every (pose, heading)'s ln L); otherwise
 * trn_localize_dem_heading_workspace_bytes. 0 if invalid.
 */
size_t trn_localize_dem_heading_workspace_bytes_cfg(const trn_map_t *map,
                                                    const trn_grid_f32_t *local_dem,
                                                    int32_t rover_x, int32_t rover_y,
                                                    size_t max_points, const trn_window_t *win,
                                                    const trn_heading_cfg_t *cfg);

#ifdef __cplusplus
}
#endif
#endif /* TRN_HEIGHT_HEADING_H */
