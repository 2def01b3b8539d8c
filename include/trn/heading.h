/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file heading.h
 * @brief Localization over (x, y, heading) when the rover's heading is
 * uncertain (beyond the paper; issue 14, docs/modules/heading.md).
 *
 * The local points (rover frame, already turned by the believed heading)
 * are turned about the rover's cell by each heading step of a window
 * +-W around a centre, rounded to the voxel grid, and matched as in
 * trn_localize_points. Every heading is searched by branch-and-bound above
 * the best score found so far minus TRN_HEADING_MARGIN_NATS, in one pass
 * that keeps the poses above that threshold (up to a fixed number of
 * positions), so the result is exactly the best (x, y, heading) of the
 * exhaustive search over all of them (ties: the heading first in the order
 * 0, -1, +1, -2, ... steps, then trn_search_bb's order). The order
 * searched: heading 0, then the others by the score its answer has at them,
 * so a high bound comes early. Eq. 6 in three dimensions
 * (trn_peak_fit3) gives the sub-step pose and the 3 x 3 covariance; the
 * failure probability weighs the best pose against the best one, at any
 * heading, outside the position zone around it (max(min_exclusion_cells,
 * 4 sigma) cells: a position failure is what it is the probability of),
 * among the poses above the best's ln L minus TRN_HEADING_MARGIN_NATS: taken
 * from the kept poses, or searched again (trn_search_bb_above at every
 * heading, outside the zone) when the kept ones all lie inside the zone.
 *
 * Angles: radians, counterclockwise in the (east, north) plane; a point at
 * (x cells east, y cells along +row, i.e. south) turned by a goes to
 * (x cos a + y sin a, -x sin a + y cos a).
 */
#ifndef TRN_HEADING_H
#define TRN_HEADING_H

#include <stddef.h>
#include <stdint.h>

#include "trn/localize.h"
#include "trn/peakfit.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Largest half-window in radians (a half turn). */
#define TRN_HEADING_MAX_WINDOW_RAD 3.14159265358979323846

/** The competitor is searched only above the best's ln L minus this many
 *  nats: one further below gives a failure probability under e^-40
 *  (4e-18), reported as 0 with has_second = 0. */
#define TRN_HEADING_MARGIN_NATS 40

/** Heading search. */
typedef struct {
    double center_rad; /**< turn applied to every heading (the believed correction), |.| <= pi */
    double window_rad; /**< W: headings centre +- W are searched, [0, TRN_HEADING_MAX_WINDOW_RAD] */
    double step_rad;   /**< step; 0 = automatic: 1 / r_max, r_max the farthest point in cells
                            (the arc there is one cell) */
} trn_heading_cfg_t;

/** Result of trn_localize_points_heading. */
typedef struct {
    trn_loc_result_t loc;     /**< at the best heading: x, y (sub-step fit), ix, iy, ll_best,
                                 the competitor, the failure probability; sigma_x_m,
                                 sigma_y_m, rho and cov_m2 are the position marginal of cov3;
                                 stats: the one pass's work summed over the headings
                                 (the best pose and every pose within the margin;
                                 a second search for the competitor, when needed,
                                 not counted) */
    double heading_rad;       /**< centre + (k + dk) step */
    double sigma_heading_rad; /**< sqrt(cov3[8]); 0 with W = 0 (heading taken as known) */
    double cov3[9];           /**< covariance of (x m, y m, heading rad), row-major */
    double step_rad;          /**< step used */
    int32_t half_steps;       /**< K: headings centre + k step, k = -K..K */
    int32_t best_step;        /**< k of the best integer pose */
} trn_heading_result_t;

/** @brief Heading step and K for cfg and these points (step 0: automatic).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_NODATA (n = 0, or every point at the
 *         rover's cell with automatic step), TRN_E_ARG (a value NaN or out
 *         of range), TRN_E_SIZE (more than TRN_MAX_HEADING_STEPS headings). */
trn_status_t trn_heading_steps(const trn_point_t *pts, size_t n, const trn_heading_cfg_t *cfg,
                               double *step_rad, int32_t *half_steps);

/** @brief Turn points by angle_rad about the rover's cell (see the file
 * comment), rounded to the nearest cell; z kept. in and out may be the same.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (angle not finite, or a point beyond
 *         +-16383 cells, which could leave int16_t once turned). */
trn_status_t trn_points_rotate(const trn_point_t *in, size_t n, double angle_rad, trn_point_t *out);

/** @brief Workspace bytes of trn_localize_points_heading (0 if invalid). */
size_t trn_localize_heading_workspace_bytes(const trn_map_t *map, size_t n,
                                            const trn_window_t *win);

/**
 * @brief Localize over (x, y, heading) (see the file comment). With W = 0
 * it is trn_localize_points on the points turned by the centre: the same
 * result and cost, heading = centre, sigma_heading 0.
 * @param[in] ws  trn_localize_heading_workspace_bytes bytes, TRN_WS_ALIGN-aligned.
 * @retval TRN_OK
 * @retval TRN_E_ILLCOND the best pose is found (ix, iy, best_step, ll_best,
 *         failure probability valid) but the 3-D peak has no finite covariance
 * @retval TRN_E_NULL, TRN_E_ARG (map, cfg or a point out of range)
 * @retval TRN_E_SIZE more than TRN_MAX_HEADING_STEPS headings
 * @retval TRN_E_WORKSPACE ws_bytes too small or ws misaligned
 * @retval TRN_E_RANGE  window not inside the map
 * @retval TRN_E_NODATA no points
 */
trn_status_t trn_localize_points_heading(const trn_map_t *map, const trn_point_t *pts, size_t n,
                                         const trn_window_t *win, const trn_heading_cfg_t *cfg,
                                         void *ws, size_t ws_bytes, trn_heading_result_t *out);

/** @brief Workspace bytes of trn_localize_dem_heading with a voxel map (0 if
 * invalid, or for a TRN_MATCH_HEIGHTS map, whose need depends on the local
 * DEM and the heading window: trn_localize_dem_heading_workspace_bytes_cfg,
 * trn/height_heading.h). */
size_t trn_localize_dem_heading_workspace_bytes(const trn_map_t *map, int32_t width, int32_t height,
                                                size_t max_points, const trn_window_t *win);

/**
 * @brief trn_localize_points_heading on a local DEM: its high-pass
 * (cfg.local_highpass; with TRN_LOCAL_HP_MAP one pass, against the map's
 * low-pass at the window's centre) and occupancy with the map's terrain
 * configuration, then the search over (x, y, heading). The local DEM is in
 * the map's orientation as the rover believes it (the heading then found is
 * the correction to that belief). With a TRN_MATCH_HEIGHTS map (the auto
 * configuration) it is the height matcher over heading instead
 * (trn_height_search_heading, trn_refine_pose_heading, the failure
 * probability over every (pose, heading), the acceptance test; no local
 * high-pass: heights are matched with their offset); with W = 0 at centre
 * 0 that is trn_localize_dem itself (heading 0, sigma_heading 0, cov3 its
 * position covariance). The voxel matcher with refinement is refused.
 * @retval as trn_localize_points_heading, plus TRN_E_ARG (a voxel map that
 *         refines, or a height map whose search is TRN_SEARCH_BOUNDED with
 *         a heading window or an off-zero centre: the bounded search is
 *         over (x, y) at heading 0), TRN_E_CAPACITY (more than max_points occupied voxels),
 *         TRN_E_NODATA (local DEM all missing) and, with a height map,
 *         TRN_E_AMBIGUOUS and TRN_E_ILLCOND as trn_localize_dem's (the
 *         window's edge including a refined heading beyond centre +- W),
 *         and TRN_E_BUDGET, the map's node_budget below a pass's (pose,
 *         heading) scores;
 *         TRN_E_RANGE also when the
 *         window is not inside the map or the local DEM's size is out of
 *         range.
 */
trn_status_t trn_localize_dem_heading(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                      int32_t rover_x, int32_t rover_y, size_t max_points,
                                      const trn_window_t *win, const trn_heading_cfg_t *cfg,
                                      void *ws, size_t ws_bytes, trn_heading_result_t *out);

#ifdef __cplusplus
}
#endif
#endif /* TRN_HEADING_H */
