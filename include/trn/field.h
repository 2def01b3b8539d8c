/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file field.h
 * @brief Sensor uncertainty field (paper section 6; method.md 5): for rover
 * positions over an area, the predicted uncertainty of the best landmark
 * (trn_select's best uncertainty_m; +inf where no target is informative),
 * computed coarse to fine.
 *
 * Rule: evaluate the lattice of step coarse_step_cells (the last row and
 * column clamped to the area's edge). Then, level by level, halve the step:
 * a square of the current level whose four corners are known is refined
 * (its four edge midpoints and centre evaluated) when, with S the coarse
 * lattice's spread (mean of its finite values minus its minimum),
 *  - it is low: its smallest finite corner v_min <= best + band, best being
 *    the smallest value found before this level and the band
 *    margin_rel * S * step / coarse_step_cells narrowing as the step halves, or
 *  - it changes fast: v_max - v_min > change_rel * S, or some corners are
 *    finite and some infinite; this reason refines only while the step is
 *    above a quarter of coarse_step_cells (edges placed, noise not chased).
 * Squares whose corners are all infinite are not refined. The loop stops at
 * step 1; no recursion, every loop bounded by the area. Cells never
 * evaluated get the bilinear interpolation of the finest known square that
 * encloses them (+inf if a corner is infinite); evaluated[] tells which
 * cells are exact. Cost: one trn_select per evaluated cell (reported).
 */
#ifndef TRN_FIELD_H
#define TRN_FIELD_H

#include "trn/select.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * Progress and cancel callback: called after every evaluated position with
 * done = positions evaluated so far and total = the area's cells (the most
 * evaluations there can be), and once more after the fill with
 * done = total. A nonzero return during the evaluations stops the field:
 * trn_field / trn_field_fast return TRN_E_CANCELLED (out and evaluated are
 * then partly written); the last call's return is ignored.
 */
typedef int32_t (*trn_field_progress_fn_t)(void *user, uint32_t done, uint32_t total);

/** Stack the progress callback may use (it runs on the core's stack; the
 * stack analysis, tools/stack, counts this budget for the call). */
#define TRN_FIELD_PROGRESS_STACK_BYTES 512

/** Refinement parameters. */
typedef struct {
    int32_t coarse_step_cells;        /**< power of two, 1..256 */
    float margin_rel;                 /**< "low" margin, [0, 100] */
    float change_rel;                 /**< "changes fast" threshold, [0, 100] */
    trn_field_progress_fn_t progress; /**< NULL: none (trn_field_progress_fn_t) */
    void *progress_user;              /**< passed to progress */
} trn_field_cfg_t;

/** Work and answer of one field computation. */
typedef struct {
    uint32_t evaluations;   /**< trn_select calls */
    uint32_t cells;         /**< cells of the area */
    int32_t best_x, best_y; /**< global cell of the lowest evaluated value (-1 if none finite) */
    double best_m;          /**< that value, m (+inf if none finite) */
} trn_field_stats_t;

/** @brief Defaults: coarse step 16 cells (1.6 m), margin 0.4, change 1.5, no progress callback.
 * @param[out] cfg the defaults; NULL is ignored. */
void trn_field_cfg_default(trn_field_cfg_t *cfg);

/** @brief Check. @param[in] cfg the parameters.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (step not a power of two in 1..256,
 *         margin or change NaN or out of [0, 100]). */
trn_status_t trn_field_cfg_check(const trn_field_cfg_t *cfg);

/** @brief Workspace bytes of trn_field (0 if invalid): candidates of one
 * position plus trn_select's workspace.
 * @param[in] scfg, map, k as trn_select_workspace_bytes. */
size_t trn_field_workspace_bytes(const trn_select_cfg_t *scfg, const trn_map_t *map,
                                 const trn_kernels_t *k);

/**
 * @brief Coarse-to-fine sensor uncertainty field over area.
 * @param[in]  map, k, pg, scfg  as trn_select.
 * @param[in]  heading_rad       rover heading for every position (finite).
 * @param[in]  area              inclusive window of rover cells, inside the map.
 * @param[out] out               area-sized grid (width = x1-x0+1, height = y1-y0+1), m.
 * @param[out] evaluated         area cells, row-major: 1 where out is exact.
 * @param[in]  evaluated_len     bytes at evaluated.
 * @param[out] stats             work and minimum.
 * @param[in]  ws                trn_field_workspace_bytes bytes, 16-byte aligned.
 * @retval TRN_OK (also when no position has an informative target: stats->best_m = +inf)
 * @retval TRN_E_NULL, TRN_E_ARG (cfgs, heading), TRN_E_SIZE (out or evaluated
 *         not area-sized, pg mismatch), TRN_E_RANGE (area empty or off the
 *         map), TRN_E_WORKSPACE, or another trn_select error
 * @retval TRN_E_CANCELLED fcfg->progress returned nonzero
 */
trn_status_t trn_field(const trn_map_t *map, const trn_kernels_t *k, const trn_vol_f32_t *pg,
                       const trn_select_cfg_t *scfg, const trn_field_cfg_t *fcfg, float heading_rad,
                       const trn_window_t *area, trn_grid_f32_t *out, uint8_t *evaluated,
                       size_t evaluated_len, trn_field_stats_t *stats, void *ws, size_t ws_bytes);

/**
 * @brief Workspace bytes of trn_field_fast for this map and P_G (0 if
 * invalid): the nonzero P_G voxels (8 bytes each), ln p of every voxel's
 * capped distance (4 bytes per voxel), the kernel index of every rover offset
 * within reach ((2 m + 1)^2 bytes, m = reach + half patch + largest kernel
 * radius, cells) and one position's region: eq. 9 (4 bytes per region voxel)
 * and nine int64 sums over a ring of patch rows. Ground (host) use: it grows
 * with the map (main job, 256 x 256 x 16: 9.2 MB; trn_field 5.5 MB).
 * @param[in] scfg, map, k as trn_select_workspace_bytes.
 * @param[in] pg the eq. 8 map trn_field_fast will read (its nonzeros are counted).
 * On a map that matches heights (the height prediction, select.h) and for the
 * heading-searched prediction trn_field_fast runs trn_field's path, and this
 * is trn_field_workspace_bytes.
 */
size_t trn_field_fast_workspace_bytes(const trn_select_cfg_t *scfg, const trn_map_t *map,
                                      const trn_kernels_t *k, const trn_vol_f32_t *pg);

/**
 * @brief trn_field's field, bit for bit (same out, evaluated and stats), from
 * rover-independent data prepared once in ws (ground path; field.md): the
 * kernel index of eq. 9 by offset from the rover, P_G's nonzero voxels by
 * row and ln p of the capped distances. Each position then computes eq. 9
 * from the nonzero sources only, with trn_prob_local's products in its order,
 * over the candidate patches only, each candidate's nine exact int64 window
 * sums in one pass over the region's rows from the nonzero P voxels, and
 * no eq. 6 fit for a candidate whose trace bound shows it cannot be the best.
 * @param[in]  map, k, pg, scfg, fcfg, heading_rad, area  as trn_field.
 * @param[out] out, evaluated, stats                       as trn_field.
 * @param[in]  evaluated_len                               as trn_field.
 * @param[in]  ws       trn_field_fast_workspace_bytes bytes, 16-byte aligned.
 * @param[in]  ws_bytes bytes at ws.
 * @retval TRN_OK (also when no position has an informative target)
 * @retval TRN_E_NULL a pointer argument NULL (or pg->data, map->dist.data)
 * @retval TRN_E_ARG  a configuration or the heading invalid, or k not a built table
 * @retval TRN_E_SIZE out or evaluated not area-sized, pg not the map's size, the
 *         map's distance cap out of range, or a region too large for exact
 *         int64 sums (as trn_select)
 * @retval TRN_E_RANGE area empty or off the map
 * @retval TRN_E_WORKSPACE ws_bytes below trn_field_fast_workspace_bytes or ws not aligned
 * @retval TRN_E_CANCELLED fcfg->progress returned nonzero
 */
trn_status_t trn_field_fast(const trn_map_t *map, const trn_kernels_t *k, const trn_vol_f32_t *pg,
                            const trn_select_cfg_t *scfg, const trn_field_cfg_t *fcfg,
                            float heading_rad, const trn_window_t *area, trn_grid_f32_t *out,
                            uint8_t *evaluated, size_t evaluated_len, trn_field_stats_t *stats,
                            void *ws, size_t ws_bytes);

#ifdef __cplusplus
}
#endif
#endif /* TRN_FIELD_H */
