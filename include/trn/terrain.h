/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file terrain.h
 * @brief From a digital elevation map to the 3-D occupancy the matcher uses
 * (paper section 2; method.md 2.1-2.3).
 *
 * 1. High-pass filter: H'(x,y) = H(x,y) - mean of the valid heights in the box
 *    [x-r, x+r] x [y-r, y+r] (r = round(highpass_half_m / cell_m) cells,
 *    clipped at the borders). Removes slope and absolute height so the pose
 *    search is over (x, y) only.
 * 2. Occupancy: height bin k(h') = floor(h' / zbin_m + 1/2) + nz/2, clamped
 *    to [0, nz-1]: bins are centred on multiples of zbin_m, so flat ground
 *    (h' = 0) is mid-bin, never on a bin edge. Cell (x, y) occupies bins lo..k(h'), where lo = k(h') unless a
 *    valid 4-neighbour is lower: then lo = (lowest neighbour's bin) + 1, so the
 *    occupied surface has no vertical holes (rock faces are seen as faces).
 *
 * Missing data: a height that is NaN or infinite is "not seen". It stays NaN
 * through the filter, is never occupied and never matched.
 * A finite height stays seen: a filtered value beyond +-FLT_MAX (heights
 * near the float limits) is clamped to +-FLT_MAX, i.e. to the end bin.
 */
#ifndef TRN_TERRAIN_H
#define TRN_TERRAIN_H

#include "trn/grid.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Terrain-to-occupancy parameters, shared by the global and local maps. */
typedef struct {
    float cell_m; /**< grid cell side, metres, (0, TRN_CELL_MAX_M] */
    float zbin_m; /**< height bin, metres, (0, TRN_CELL_MAX_M]; = cell_m for cubic voxels */
    float
        highpass_half_m; /**< half-width of the smoothing box, metres, [cell_m, 1e6] (ten TRN_CELL_MAX_M cells and more) */
    int32_t nz; /**< height bins, 1..TRN_MAX_ZBINS */
} trn_terrain_cfg_t;

/** One occupied voxel of a local map, relative to the rover's cell. */
typedef struct {
    int16_t x; /**< cells east of the rover cell (column offset) */
    int16_t y; /**< cells along +row from the rover cell */
    int16_t z; /**< height bin, 0..nz-1 (same bins as the global map) */
} trn_point_t;

/**
 * @brief Check a terrain configuration.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (a value NaN or out of range),
 *         TRN_E_SIZE (nz out of range).
 */
trn_status_t trn_terrain_cfg_check(const trn_terrain_cfg_t *cfg);

/** @brief Workspace bytes trn_highpass needs for a width x height grid (0 if out of range). */
size_t trn_highpass_workspace_bytes(int32_t width, int32_t height);

/**
 * @brief High-pass filter a DEM (see file comment, step 1).
 * @param[in]  dem   heights, metres; NaN/inf = missing.
 * @param[in]  cfg   terrain parameters.
 * @param[out] out   filtered heights, same size as dem (must not overlap dem).
 * @param[in]  ws    scratch of trn_highpass_workspace_bytes() bytes, TRN_WS_ALIGN-aligned.
 * @param[in]  ws_bytes its size.
 * @retval TRN_OK
 * @retval TRN_E_NULL, TRN_E_SIZE (bad grids or size mismatch), TRN_E_ARG (cfg),
 *         TRN_E_WORKSPACE (ws too small or not TRN_WS_ALIGN-aligned)
 * @retval TRN_E_NODATA every height is missing (out is then all NaN)
 */
trn_status_t trn_highpass(const trn_grid_f32_t *dem, const trn_terrain_cfg_t *cfg,
                          trn_grid_f32_t *out, void *ws, size_t ws_bytes);

/**
 * @brief Occupancy volume of a filtered DEM (step 2). occ must be
 * width x height x cfg->nz; it is overwritten (1 = occupied, 0 = free).
 * @param[out] n_occupied number of occupied voxels (may be NULL).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_SIZE, TRN_E_ARG
 * @retval TRN_E_NODATA nothing occupied (every height missing).
 */
trn_status_t trn_occupancy(const trn_grid_f32_t *hp, const trn_terrain_cfg_t *cfg,
                           trn_vol_u8_t *occ, uint32_t *n_occupied);

/**
 * @brief Occupied voxels of a filtered local DEM as a point list relative to
 * the rover cell (rover_x, rover_y) of that grid (which may lie outside it).
 * Points come ordered by z, then y, then x.
 * @param[out] pts      caller array of capacity points.
 * @param[out] n_points number written.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_SIZE, TRN_E_ARG (cfg, or rover cell
 *         farther than TRN_MAX_DIM from the grid)
 * @retval TRN_E_CAPACITY more occupied voxels than capacity (nothing usable written)
 * @retval TRN_E_NODATA nothing occupied.
 */
trn_status_t trn_occupancy_points(const trn_grid_f32_t *hp, const trn_terrain_cfg_t *cfg,
                                  int32_t rover_x, int32_t rover_y, trn_point_t *pts,
                                  size_t capacity, size_t *n_points);

#ifdef __cplusplus
}
#endif
#endif /* TRN_TERRAIN_H */
