/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file likelihood.h
 * @brief Maximum-likelihood pose search (paper section 2.1, eqs. 1-5;
 * method.md 2.4-2.7).
 *
 *   ln L(X) = sum_i ln p(D_i^X)                          (eq. 1)
 *   p(d)    = a p1(d) + (1 - a) K                         (eq. 2)
 *   p1(d)   = exp(-d^2 / (2 s^2)) / (s sqrt(2 pi))        (eq. 3)
 *   K       = mean over all voxels v of p1(D(v))          (eq. 5, method.md 2.6)
 *
 * D is the capped chamfer distance (trn/chamfer.h) in chamfer units; d in
 * metres is D / 3 * cell_m. Because D is a small integer, ln p is a lookup
 * table. Table entries are fixed point (TRN_LNP_SCALE units per nat) and
 * scores are exact int64 sums, so every search order gives bit-identical
 * scores on every processor, and a bound that is term-wise larger is larger.
 *
 * A pose (px, py) is the global cell of the rover; local point (x, y, z)
 * then falls on global voxel (px + x, py + y, z). A point off the global map
 * counts as distance `cap` (no information).
 *
 * Two searches return the same best pose (ties: highest score, then smallest
 * y, then smallest x): the exhaustive one, and branch-and-bound over a
 * pyramid of min-filtered distance volumes (level l holds the minimum of D
 * over 2^l x 2^l pose blocks, so sum ln p(D_l) bounds every pose of a block,
 * ln p being non-increasing in d).
 */
#ifndef TRN_LIKELIHOOD_H
#define TRN_LIKELIHOOD_H

#include "trn/grid.h"
#include "trn/terrain.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Sensor-model parameters of the likelihood. */
typedef struct {
    float cell_m;      /**< voxel side, metres, (0, TRN_CELL_MAX_M] */
    float sigma_m;     /**< s: standard deviation of inlier distances, metres,
                            (0, TRN_CELL_MAX_M] (the map configurations set one cell) */
    float inlier_prob; /**< a: probability a local voxel is an inlier, (0, 1) (paper: 0.95) */
    uint8_t cap;       /**< distance cap of the transform, chamfer units, 3..TRN_CHAMFER_CAP_MAX */
} trn_lik_cfg_t;

/** ln p(d) as a fixed-point table indexed by chamfer distance 0..cap. */
typedef struct {
    int32_t lnp[TRN_CHAMFER_CAP_MAX + 1]; /**< round(TRN_LNP_SCALE * ln p(d)), d = i/3*cell_m */
    double k_per_m;                       /**< K, 1/m */
    uint8_t cap;                          /**< entries 0..cap are valid */
} trn_lnp_table_t;

/** Inclusive rectangle of poses, in global cells. */
typedef struct {
    int32_t x0, y0, x1, y1;
} trn_window_t;

/** Poses with max(|x - cx|, |y - cy|) <= radius are skipped by a search. */
typedef struct {
    int32_t cx, cy, radius;
} trn_exclusion_t;

/** Best pose of a search. */
typedef struct {
    int32_t x, y;  /**< global cell */
    int64_t score; /**< ln L in table units (TRN_LNP_SCALE per nat) */
} trn_best_t;

/** Work counters of a search (for benchmarks and tests). */
typedef struct {
    uint64_t poses_scored;   /**< exact pose scores computed */
    uint64_t blocks_bounded; /**< block bounds computed (branch-and-bound only) */
} trn_search_stats_t;

/** Min-filtered distance volumes for branch-and-bound; memory owned by caller. */
typedef struct {
    trn_vol_u8_t base;              /**< level 0: the distance volume (not owned) */
    uint8_t *level[TRN_MAX_LEVELS]; /**< level l (1..nlevels) at level[l-1] */
    int32_t nlevels;                /**< 1..TRN_MAX_LEVELS */
    int32_t pad;                    /**< 2^nlevels - 1 cells of low-side padding in x and y */
    int32_t pnx, pny;               /**< padded sizes nx + pad, ny + pad */
    uint8_t cap;
} trn_pyramid_t;

/** @brief Check a likelihood configuration. @retval TRN_OK, TRN_E_NULL, TRN_E_ARG. */
trn_status_t trn_lik_cfg_check(const trn_lik_cfg_t *cfg);

/**
 * @brief K of eq. 5 from the histogram of a distance volume (double sums).
 * @param[out] k_per_m K in 1/m.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_SIZE, TRN_E_ARG (cfg, or a voxel > cap).
 */
trn_status_t trn_outlier_density(const trn_vol_u8_t *dist, const trn_lik_cfg_t *cfg,
                                 double *k_per_m);

/**
 * @brief Build the ln p(d) table for distances 0..cfg->cap.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (cfg, or K not finite and > 0).
 */
trn_status_t trn_lnp_table_build(trn_lnp_table_t *t, const trn_lik_cfg_t *cfg, double k_per_m);

/**
 * @brief ln L of one pose (eq. 1), any pose (points off the map count as cap).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_SIZE, TRN_E_NODATA (n == 0), TRN_E_ARG
 *         (a point's z outside the volume, or table cap out of range).
 * @retval TRN_E_RANGE px or py outside [-2 TRN_MAX_DIM, 2 TRN_MAX_DIM].
 */
trn_status_t trn_score_pose(const trn_vol_u8_t *dist, const trn_lnp_table_t *t,
                            const trn_point_t *pts, size_t n, int32_t px, int32_t py,
                            int64_t *score);

/**
 * @brief Exhaustive search: every pose of the window not excluded.
 * @param[in] ex    exclusion zone, or NULL.
 * @param[out] stats may be NULL.
 * @retval TRN_OK
 * @retval TRN_E_NULL, TRN_E_SIZE, TRN_E_ARG (point z outside the volume,
 *         negative exclusion radius)
 * @retval TRN_E_RANGE  window empty or not inside the map
 * @retval TRN_E_NODATA no points, or every pose excluded
 */
trn_status_t trn_search_exhaustive(const trn_vol_u8_t *dist, const trn_lnp_table_t *t,
                                   const trn_point_t *pts, size_t n, const trn_window_t *win,
                                   const trn_exclusion_t *ex, trn_best_t *best,
                                   trn_search_stats_t *stats);

/** @brief Bytes trn_pyramid_build needs (0 if arguments out of range). */
size_t trn_pyramid_bytes(int32_t nx, int32_t ny, int32_t nz, int32_t nlevels);

/**
 * @brief Build the min-filter pyramid of a distance volume into buf.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_SIZE, TRN_E_ARG (nlevels or cap out of
 *         range), TRN_E_WORKSPACE (len below trn_pyramid_bytes or buf not
 *         TRN_WS_ALIGN-aligned).
 */
trn_status_t trn_pyramid_build(trn_pyramid_t *p, const trn_vol_u8_t *dist, uint8_t cap,
                               int32_t nlevels, void *buf, size_t len);

/** @brief Workspace bytes of trn_search_bb for this window (0 if invalid). */
size_t trn_search_bb_workspace_bytes(const trn_pyramid_t *p, const trn_window_t *win);

/**
 * @brief Branch-and-bound search; returns exactly what trn_search_exhaustive
 * returns for the same arguments.
 * @retval as trn_search_exhaustive, plus TRN_E_WORKSPACE (ws_bytes below
 *         trn_search_bb_workspace_bytes or ws not TRN_WS_ALIGN-aligned).
 */
trn_status_t trn_search_bb(const trn_pyramid_t *p, const trn_lnp_table_t *t, const trn_point_t *pts,
                           size_t n, const trn_window_t *win, const trn_exclusion_t *ex, void *ws,
                           size_t ws_bytes, trn_best_t *best, trn_search_stats_t *stats);

/**
 * @brief trn_search_bb over the poses scoring strictly above floor (table
 * units): blocks whose bound cannot beat floor are never opened. Chained
 * over several point sets (e.g. the headings of trn_localize_points_heading)
 * with floor = the best score so far, it finds their overall best exactly.
 * best is written only on TRN_OK.
 * @retval as trn_search_bb; TRN_E_NODATA also when no pose scores above floor.
 */
trn_status_t trn_search_bb_above(const trn_pyramid_t *p, const trn_lnp_table_t *t,
                                 const trn_point_t *pts, size_t n, const trn_window_t *win,
                                 const trn_exclusion_t *ex, int64_t floor, void *ws,
                                 size_t ws_bytes, trn_best_t *best, trn_search_stats_t *stats);

/**
 * @brief Reorder local points so that those in the least populated height
 * bins (of these points) come first. Scores are exact sums, so every score
 * and search result is unchanged; the order only makes trn_search_bb's
 * early exit (a bound or score abandoned once its partial sum cannot reach
 * the best score) happen sooner, because points in rare bins (rock tops,
 * deep hollows) are the ones that miss at wrong poses. trn_localize_dem
 * does this to its own points; callers of trn_localize_points may do it
 * first. O(n + nz^2) time, in place, about 3 KiB of stack.
 * @param[in,out] pts points, reordered (a permutation; not stable).
 * @param[in] n       number of points (0 allowed).
 * @param[in] nz      height bins of the volume, 1..TRN_MAX_ZBINS.
 * @retval TRN_OK
 * @retval TRN_E_NULL pts NULL
 * @retval TRN_E_ARG  nz out of range, or a point's z outside 0..nz-1
 * @retval TRN_E_SIZE n above UINT32_MAX (possible only where size_t is wider)
 *                    (pts is then unchanged)
 */
trn_status_t trn_points_order(trn_point_t *pts, size_t n, int32_t nz);

#ifdef __cplusplus
}
#endif
#endif /* TRN_LIKELIHOOD_H */
