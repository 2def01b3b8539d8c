/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file sim_render.h
 * @brief The stereo head of the simulator (tools/sim): range points of a
 * terrain DEM seen from a camera pose, in the camera (optical) frame, with
 * range noise of standard deviation k r^2. Pure C99: no OS, no allocation,
 * caller-owned state and seeded noise, so it runs in cmocka on the host
 * (tests/test_sim_render.c) as well as in the simulator in the VM.
 *
 * Model: a pinhole camera with cols x rows rays spread evenly over the
 * field of view (ray (i, j) has tan(x angle) = tan(hfov/2) (2 (i + 0.5) /
 * cols - 1), the same for y with vfov; x right, y down, z forward, as
 * mast.h's camera frame). Each ray is marched through the DEM (bilinear
 * heights) in steps of half a cell from min_range_m to max_range_m, and the
 * first crossing below the surface is refined by 30 bisections. A ray that
 * leaves the DEM, never crosses it or crosses beyond max_range_m gives no
 * point. The true range r along the ray gets Gaussian noise of sigma
 * noise_k_per_m * r^2 along the ray (the stereo depth error grows with
 * range squared), from the caller's generator (splitmix64 + Box-Muller).
 */
#ifndef TRN_SIM_RENDER_H
#define TRN_SIM_RENDER_H

#include <stddef.h>
#include <stdint.h>
#include "trn/mast.h"
#include "trn/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Most rays per side. */
#define SIM_MAX_RAYS_SIDE 1024
/** Most march steps per ray. */
#define SIM_MAX_STEPS 100000

/** A terrain DEM in the map frame: cell (i, j) = heights[j * width + i] is
 * the height at (x0_m + i cell_m, y0_m + j cell_m) (row index grows north). */
typedef struct {
    const float *heights;  /**< width * height finite values */
    int32_t width, height; /**< cells, >= 2 each */
    float cell_m;          /**< > 0 */
    float x0_m, y0_m;      /**< map position of cell (0, 0) */
} sim_dem_t;

/** The stereo camera. */
typedef struct {
    float hfov_rad, vfov_rad; /**< full fields of view, (0, 3) */
    int32_t cols, rows;       /**< rays per side, 1..SIM_MAX_RAYS_SIDE */
    float min_range_m;        /**< nearest range, >= 0 */
    float max_range_m;        /**< farthest range, > min_range_m */
    float noise_k_per_m;      /**< range sigma = k r^2, >= 0 (0: exact ranges) */
} sim_camera_t;

/** Seeded noise generator (splitmix64). */
typedef struct {
    uint64_t s;
} sim_rng_t;

/** @brief The simulated stereo head: 60 x 45 deg, 64 x 48 rays, 0.5-12 m,
 * range noise 0.002/m r^2 (sim_cfg_default's camera). */
void sim_camera_default(sim_camera_t *cam);

/** @brief The simulated mast's geometry and limits (sim_cfg_default's). */
void sim_geom_default(trn_mast_geom_t *geom);

/**
 * @brief Height of the DEM at a map position (bilinear).
 * @param[in]  dem the DEM.
 * @param[in]  x_m, y_m map position.
 * @param[out] h_m the height.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_RANGE (outside the DEM's cell centres)
 */
trn_status_t sim_dem_height(const sim_dem_t *dem, float x_m, float y_m, float *h_m);

/**
 * @brief Range points of the DEM seen by the camera (see the file comment).
 * @param[in]     dem        terrain.
 * @param[in]     cam        camera.
 * @param[in]     cam_to_map camera-to-map transform (trn_mast_camera_to_map).
 * @param[in,out] rng        noise generator (advanced by two draws per point
 *                           when noise_k_per_m > 0).
 * @param[out]    out        capacity points, camera frame, metres.
 * @param[in]     capacity   entries at out.
 * @param[out]    n          points written.
 * @retval TRN_OK
 * @retval TRN_E_NULL an argument NULL
 * @retval TRN_E_ARG  bad DEM or camera values (ranges, fields of view,
 *         steps above SIM_MAX_STEPS)
 * @retval TRN_E_CAPACITY more points than capacity (the first capacity are written)
 */
trn_status_t sim_render(const sim_dem_t *dem, const sim_camera_t *cam,
                        const trn_rigid_t *cam_to_map, sim_rng_t *rng, trn_vec3f_t *out,
                        size_t capacity, size_t *n);

/**
 * @brief sim_render for the ray rows [row0, row1) only, appending to out
 * from index *n (so a caller can spread one image over several calls, e.g.
 * to keep answering the bus while rendering; rows rendered in order give
 * exactly sim_render's points and noise).
 * @param[in]     row0, row1 0 <= row0 <= row1 <= cam->rows.
 * @param[in,out] n  points already in out; points added on return.
 * @retval as sim_render, plus TRN_E_RANGE (rows out of order or range, or *n > capacity)
 */
trn_status_t sim_render_rows(const sim_dem_t *dem, const sim_camera_t *cam,
                             const trn_rigid_t *cam_to_map, sim_rng_t *rng, int32_t row0,
                             int32_t row1, trn_vec3f_t *out, size_t capacity, size_t *n);

/** @brief Standard normal draw (Box-Muller on two splitmix64 draws).
 * @param[in,out] rng the generator. */
double sim_rng_normal(sim_rng_t *rng);

#ifdef __cplusplus
}
#endif
#endif /* TRN_SIM_RENDER_H */
