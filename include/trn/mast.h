/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file mast.h
 * @brief Mast kinematics: point the pan-tilt mast at a map target, carry
 * stereo range points from the camera frame to the map frame, and bin them
 * into a local DEM ready for trn_localize_dem (paper section 2: the local
 * map comes from stereo range data taken from the rover's mast).
 *
 * Frames (all right-handed, metres, radians):
 * - map: x east, y north, z up.
 * - body (rover): origin at the rover's reference point, x forward, y left,
 *   z up. Rover pose = map position of the origin + heading, the angle from
 *   map +x (east) to body +x, counterclockwise (north = +pi/2). Roll and
 *   pitch are taken as zero (heading-only pose, as the paper's 2-D search).
 * - panned: the body frame turned by pan about the vertical pan axis, which
 *   passes through body (pan_x_m, pan_y_m); origin at the pan joint height
 *   pan_z_m. Pan 0 looks along body +x, + turns left (counterclockwise from
 *   above).
 * - head (tilted): the panned frame turned by tilt about a horizontal axis
 *   parallel to panned y, located at (tilt_fwd_m, 0, tilt_up_m) in the
 *   panned frame. Tilt 0 is level, + looks up. Head axes: forward
 *   (boresight), left, up.
 * - camera (optical): origin at the optical centre, which sits at
 *   (cam_fwd_m, cam_left_m, cam_up_m) in the head frame; x right, y down,
 *   z forward along the boresight (parallel to head forward).
 */
#ifndef TRN_MAST_H
#define TRN_MAST_H

#include <stddef.h>
#include <stdint.h>
#include "trn/grid.h"
#include "trn/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** A 3-vector, metres. */
typedef struct {
    float x, y, z;
} trn_vec3f_t;

/** Rover pose in the map frame. */
typedef struct {
    float x_m;         /**< east */
    float y_m;         /**< north */
    float z_m;         /**< up (height of the body origin) */
    float heading_rad; /**< from east, counterclockwise */
} trn_rover_pose_t;

/** Mast geometry and joint limits (see the frames above). */
typedef struct {
    float pan_x_m, pan_y_m;           /**< pan axis position in the body frame */
    float pan_z_m;                    /**< pan joint height above the body origin */
    float tilt_fwd_m;                 /**< tilt axis ahead of the pan axis (panned frame) */
    float tilt_up_m;                  /**< tilt axis above the pan joint */
    float cam_fwd_m;                  /**< optical centre ahead of the tilt axis (head frame) */
    float cam_left_m;                 /**< optical centre left of the tilt-axis midpoint */
    float cam_up_m;                   /**< optical centre above the tilt axis */
    float pan_min_rad, pan_max_rad;   /**< pan limits, within [-pi, pi] */
    float tilt_min_rad, tilt_max_rad; /**< tilt limits, within [-pi/2, pi/2] */
} trn_mast_geom_t;

/** Rigid transform p_to = R p_from + t (row-major R). */
typedef struct {
    float r[9];
    trn_vec3f_t t;
} trn_rigid_t;

/** How a local DEM grid sits on the map (rover-centred, map-aligned). */
typedef struct {
    float cell_m;      /**< cell size, the global map's; > 0 */
    int32_t rover_col; /**< the grid column holding the rover's position */
    int32_t rover_row; /**< the grid row holding the rover's position */
    int32_t row_north; /**< +1: row index grows northward; -1: southward (north-up images) */
} trn_local_dem_cfg_t;

/**
 * @brief Check a mast geometry.
 * @param[in] g the geometry.
 * @retval TRN_OK, TRN_E_NULL
 * @retval TRN_E_ARG a value is not finite, a limit lies outside its range
 *         (pan [-pi, pi], tilt [-pi/2, pi/2]) or min > max
 */
trn_status_t trn_mast_geom_check(const trn_mast_geom_t *g);

/**
 * @brief Pan and tilt that put a map target on the camera boresight
 * (the boresight ray from the optical centre passes through the target).
 * Closed form: with the target at horizontal distance r from the pan axis,
 * pan = atan2(py, px) - asin(cam_left / r); in the panned vertical plane,
 * with the target at (a, b) from the tilt axis, tilt = atan2(b, a) -
 * asin(cam_up / hypot(a, b)).
 * @param[in]  g      geometry (checked).
 * @param[in]  pose   rover pose (finite).
 * @param[in]  target map point.
 * @param[out] pan_rad, tilt_rad  angles, pan wrapped to [-pi, pi]; tilt
 *             not wrapped, in [-3pi/2, 3pi/2] (beyond +-pi only for a target
 *             behind the tilt axis, always outside the tilt limits, so
 *             TRN_E_RANGE); written also when TRN_E_RANGE is returned.
 * @retval TRN_OK     reachable within the limits
 * @retval TRN_E_RANGE the angles lie outside the joint limits
 * @retval TRN_E_NULL an argument NULL
 * @retval TRN_E_ARG  bad geometry, non-finite pose or target, or a target
 *            no boresight can reach (within |cam_left| of the pan axis,
 *            within |cam_up| of the tilt axis, or not ahead of the camera)
 */
trn_status_t trn_mast_point_at(const trn_mast_geom_t *g, const trn_rover_pose_t *pose,
                               const trn_vec3f_t *target, float *pan_rad, float *tilt_rad);

/**
 * @brief The camera-to-map transform at the given joint angles:
 * p_map = R p_cam + t, t = the optical centre in the map frame.
 * @param[in]  g          geometry (checked).
 * @param[in]  pose       rover pose.
 * @param[in]  pan_rad    measured pan.
 * @param[in]  tilt_rad   measured tilt.
 * @param[out] cam_to_map the transform.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (bad geometry, non-finite pose or
 *         angles; angles are not checked against the limits: they are
 *         measured values)
 */
trn_status_t trn_mast_camera_to_map(const trn_mast_geom_t *g, const trn_rover_pose_t *pose,
                                    float pan_rad, float tilt_rad, trn_rigid_t *cam_to_map);

/**
 * @brief Apply a rigid transform to n points (in and out may be the same array).
 * @param[in]  T   the transform.
 * @param[in]  in  n points.
 * @param[in]  n   number of points.
 * @param[out] out n points.
 * @retval TRN_OK, TRN_E_NULL (T, or in/out NULL with n > 0)
 */
trn_status_t trn_rigid_apply(const trn_rigid_t *T, const trn_vec3f_t *in, size_t n,
                             trn_vec3f_t *out);

/**
 * @brief Bin map-frame points into a rover-centred, map-aligned local DEM:
 * each cell holds the highest z (map frame) of the points in it, cells
 * without points are NaN. Point p falls in column rover_col +
 * round((p.x - rover.x) / cell_m) and row rover_row + row_north *
 * round((p.y - rover.y) / cell_m) (round half up), so the rover's position
 * is the centre of cell (rover_col, rover_row). Points off the grid or not
 * finite are skipped. The grid is the local DEM of trn_localize_dem with
 * rover cell (rover_col, rover_row).
 * @param[in]  pts   n map-frame points (may be NULL when n == 0).
 * @param[in]  pose  rover pose (only x_m, y_m are used).
 * @param[in]  cfg   placement.
 * @param[out] dem   overwritten entirely.
 * @param[out] n_used points that landed in a cell (may be NULL).
 * @retval TRN_OK
 * @retval TRN_E_NULL  dem, pose or cfg NULL, or pts NULL with n > 0
 * @retval TRN_E_SIZE  dem is not a valid grid
 * @retval TRN_E_ARG   cell_m not finite and > 0 (or so small that
 *                     1 / cell_m overflows), row_north not +-1,
 *                     rover cell farther than TRN_MAX_DIM from the grid,
 *                     pose not finite
 * @retval TRN_E_NODATA no point landed in the grid (dem is all NaN)
 */
trn_status_t trn_mast_local_dem(const trn_vec3f_t *pts, size_t n, const trn_rover_pose_t *pose,
                                const trn_local_dem_cfg_t *cfg, trn_grid_f32_t *dem,
                                size_t *n_used);

/**
 * @brief trn_mast_local_dem with each cell holding the MEAN z of its points
 * (a running mean) instead of the highest. The highest point of a cell lies
 * toward its far side on every slope that faces the camera, and those are
 * the slopes it sees: the local map then sits up to half a cell nearer the
 * rover than the terrain. Measured in the host loop (tests/test_sim_loop.c,
 * 0.1 m cells, targets 2-4.5 m away): the highest point gave a constant
 * 0.03-0.04 m error along the view; the mean removes it. docs/method.md
 * section 2.
 * @param[out] counts     caller scratch of counts_len >= width * height
 *                        entries, overwritten (points per cell).
 * @retval as trn_mast_local_dem, plus TRN_E_NULL (counts NULL) and
 *         TRN_E_WORKSPACE (counts_len too small)
 */
trn_status_t trn_mast_local_dem_mean(const trn_vec3f_t *pts, size_t n, const trn_rover_pose_t *pose,
                                     const trn_local_dem_cfg_t *cfg, trn_grid_f32_t *dem,
                                     uint32_t *counts, size_t counts_len, size_t *n_used);

#ifdef __cplusplus
}
#endif
#endif /* TRN_MAST_H */
