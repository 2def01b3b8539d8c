/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file spread.h
 * @brief Probability mapping (paper section 3, eqs. 8 and 9; method.md 3):
 * the occupancy of the global map spread by the error of the global map
 * (eq. 8) and again by the expected error of the new local map (eq. 9).
 *
 * The probability map is 3-D like the occupancy it spreads: P(x, y, z) is the
 * probability that voxel (x, y, z) is seen occupied; the spreading acts in x
 * and y only, slice by slice. The normal N of eqs. 8-9 has a width set by the
 * source cell: stereo range error grows with the squared distance r (metres)
 * to the sensing position, sigma(r) = sigma_min_m + k_per_m * r^2
 * (trn_sigma_model_t), converted to cells and mapped to the nearest of the ten
 * kernels (trn_kernel_pick, clamped to the table's range).
 *
 * Separable scatter: each source cell spreads its mass along x with its own
 * kernel (x pass); each intermediate cell then spreads along y with the
 * kernel of the intermediate cell's sigma (y pass). Every kernel sums to 1,
 * so mass is preserved exactly (to float rounding) except what falls off the
 * destination window. Borders: cells outside the map hold nothing (zero
 * padding: unseen terrain predicts no occupancy) and mass scattered past the
 * map's edge is dropped, so P is too low within one kernel radius of a map
 * border. Because widths vary from cell to cell, P is a mass-preserving
 * scatter, not a partition of unity: where sigma changes P can exceed 1 by a
 * little; it is not clamped. Zero sources are skipped (occupancy is sparse).
 */
#ifndef TRN_SPREAD_H
#define TRN_SPREAD_H

#include <stddef.h>
#include <stdint.h>
#include "trn/grid.h"
#include "trn/kernels.h"
#include "trn/likelihood.h"
#include "trn/localize.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Largest number of sensing positions of one global map. */
#ifndef TRN_SPREAD_MAX_SENSORS
#define TRN_SPREAD_MAX_SENSORS 64
#endif
#if TRN_SPREAD_MAX_SENSORS < 1 || TRN_SPREAD_MAX_SENSORS > 4096
#error "TRN_SPREAD_MAX_SENSORS must be in [1, 4096]"
#endif

/** Dense 3-D volume of float: voxel (x, y, z) is data[((size_t)z * ny + y) * nx + x]. */
typedef struct {
    float *data;
    int32_t nx, ny, nz;
} trn_vol_f32_t;

/** A position in global-map cells (x = column, y = row), sub-cell allowed. */
typedef struct {
    float x_cells, y_cells;
} trn_xy_t;

/** Range-error model: sigma_m(r) = sigma_min_m + k_per_m * r_m^2. */
typedef struct {
    float sigma_min_m; /**< error at the sensor, metres, [0, 1e5] (km-cell maps scale it) */
    float k_per_m;     /**< growth with squared range, 1/m, [0, 100] */
} trn_sigma_model_t;

/** @brief Default error of the global map (eq. 8): 0.02 m + 0.001/m r^2
 * (0.12 m at 10 m, 0.65 m at 25 m).
 * @param[out] m the model; NULL is ignored. */
void trn_sigma_global_default(trn_sigma_model_t *m);

/** @brief Default expected error of the new local map (eq. 9), rover mast
 * stereo: 0.02 m + 0.002/m r^2 (0.07 m at 5 m, 0.22 m at 10 m).
 * @param[out] m the model; NULL is ignored. */
void trn_sigma_local_default(trn_sigma_model_t *m);

/** @brief Check a sigma model.
 * @param[in] m the model.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (NaN or out of range). */
trn_status_t trn_sigma_model_check(const trn_sigma_model_t *m);

/**
 * @brief Kernel index of every cell of a window: sigma from the distance of
 * the cell centre to the nearest sensing position, nearest kernel in log-sigma.
 * @param[in]  k, m, cell_m  kernels (built), model, cell side (m, (0, TRN_CELL_MAX_M]).
 * @param[in]  sensors       n_sensors positions (1..TRN_SPREAD_MAX_SENSORS), global cells, finite.
 * @param[in]  win           inclusive window of global cells (any, may lie off a map).
 * @param[out] idx           row-major kernel indices, window width per row.
 * @param[in]  idx_len       bytes at idx, >= window cells.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (model, cell_m, sensor not finite),
 *         TRN_E_SIZE (n_sensors 0 or too many, empty window or a side > TRN_MAX_DIM),
 *         TRN_E_WORKSPACE (idx_len too small)
 */
trn_status_t trn_spread_kernel_map(const trn_kernels_t *k, const trn_sigma_model_t *m, float cell_m,
                                   const trn_xy_t *sensors, size_t n_sensors,
                                   const trn_window_t *win, uint8_t *idx, size_t idx_len);

/** @brief Workspace bytes of trn_prob_global for an nx x ny map (0 if out of range).
 * @param[in] nx, ny map size, cells. */
size_t trn_prob_global_workspace_bytes(int32_t nx, int32_t ny);

/**
 * @brief Eq. 8: P_G = occupancy M spread by the global map's error, sigma
 * from the distance to the nearest of the global map's sensing positions.
 * @param[in]  k, m, cell_m        kernels (built), global error model, cell side (m).
 * @param[in]  sensors, n_sensors  sensing positions of the global map, global cells.
 * @param[in]  occ     occupancy (nonzero = occupied), nx x ny x nz.
 * @param[out] pg      same dimensions as occ, overwritten.
 * @param[in]  ws      trn_prob_global_workspace_bytes bytes, 16-byte aligned.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (model, cell_m, sensors),
 *         TRN_E_SIZE (bad volumes, dimensions differ, sensor count),
 *         TRN_E_WORKSPACE
 */
trn_status_t trn_prob_global(const trn_kernels_t *k, const trn_sigma_model_t *m, float cell_m,
                             const trn_xy_t *sensors, size_t n_sensors, const trn_vol_u8_t *occ,
                             trn_vol_f32_t *pg, void *ws, size_t ws_bytes);

/**
 * @brief Eq. 8 for a prepared global map: as trn_prob_global with the map's
 * occupancy, read from its distance volume (occupied <=> chamfer distance 0),
 * and the map's cell size.
 * @param[in]  k, m, sensors, n_sensors, ws, ws_bytes  as trn_prob_global.
 * @param[in]  map  prepared global map.
 * @param[out] pg   map->dist sized.
 * @retval as trn_prob_global (pg must be map->dist sized).
 */
trn_status_t trn_prob_global_map(const trn_kernels_t *k, const trn_sigma_model_t *m,
                                 const trn_xy_t *sensors, size_t n_sensors, const trn_map_t *map,
                                 trn_vol_f32_t *pg, void *ws, size_t ws_bytes);

/**
 * @brief Eq. 8 for a prepared global map with a per-cell error raster (a DTM's
 * error map, e.g. HiRISE's): as trn_prob_global_map, but each source cell
 * whose sigma_m value is not NaN spreads with that error (metres, converted to
 * cells and mapped to the nearest kernel in log-sigma exactly as the model's
 * sigma is); NaN cells take the model's sigma from the nearest sensing
 * position. The x pass uses the source cell's kernel, the y pass the
 * intermediate cell's, as for the model.
 * @param[in]  k, m, sensors, n_sensors, ws, ws_bytes  as trn_prob_global.
 * @param[in]  sigma_m  error raster, metres, map->dist.nx x map->dist.ny
 *                      (any stride); each cell NaN or finite >= 0.
 * @param[in]  map      prepared global map.
 * @param[out] pg       map->dist sized.
 * @retval TRN_OK
 * @retval TRN_E_NULL  k, m, sensors, sigma_m (or its data), map, pg, pg->data or ws NULL
 * @retval TRN_E_ARG   model, cell or sensor as trn_prob_global; a raster cell
 *                     negative or infinite
 * @retval TRN_E_SIZE  raster not the map's size or a bad view (stride < width);
 *                     pg not map->dist sized; sensor count 0 or above
 *                     TRN_SPREAD_MAX_SENSORS
 * @retval TRN_E_WORKSPACE ws_bytes below trn_prob_global_workspace_bytes or ws
 *                     not 16-byte aligned
 */
trn_status_t trn_prob_global_raster(const trn_kernels_t *k, const trn_sigma_model_t *m,
                                    const trn_xy_t *sensors, size_t n_sensors,
                                    const trn_grid_f32_t *sigma_m, const trn_map_t *map,
                                    trn_vol_f32_t *pg, void *ws, size_t ws_bytes);

/** @brief Workspace bytes of trn_prob_local for roi (0 if invalid): kernel
 * map and one intermediate slice over roi plus the largest kernel radius.
 * @param[in] k built kernels; @param[in] roi the region (any position). */
size_t trn_prob_local_workspace_bytes(const trn_kernels_t *k, const trn_window_t *roi);

/**
 * @brief Eq. 9 on demand for a region: P = P_G spread by the expected error
 * of a local map sensed from the rover's position, for the cells of roi only
 * (sources within the largest kernel radius of roi contribute).
 * @param[in]  k, m, cell_m  kernels (built), local error model, cell side (m).
 * @param[in]  rover   the rover's position, global cells (finite; may be anywhere).
 * @param[in]  pg      eq. 8 result (nx x ny x nz).
 * @param[in]  roi     inclusive window of global cells, inside pg.
 * @param[out] p       roi-sized volume (width x height x pg->nz); voxel
 *                     (x - roi.x0, y - roi.y0, z) is P(x, y, z).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (model, cell_m, rover not finite),
 *         TRN_E_SIZE (bad volumes, p not roi-sized or nz differs),
 *         TRN_E_RANGE (roi empty or not inside pg), TRN_E_WORKSPACE
 */
trn_status_t trn_prob_local(const trn_kernels_t *k, const trn_sigma_model_t *m, float cell_m,
                            trn_xy_t rover, const trn_vol_f32_t *pg, const trn_window_t *roi,
                            trn_vol_f32_t *p, void *ws, size_t ws_bytes);

#ifdef __cplusplus
}
#endif
#endif /* TRN_SPREAD_H */
