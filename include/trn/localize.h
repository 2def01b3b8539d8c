/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file localize.h
 * @brief End-to-end terrain-matching localization (paper section 2):
 * global DEM -> prepared map (high-pass, occupancy, chamfer transform, K,
 * ln p table, search pyramid); local DEM or local occupancy + prior pose
 * window -> maximum-likelihood pose, covariance (eq. 6), failure probability.
 *
 * Frames: poses are global-map cells (x = column, y = row). A local map is
 * given relative to the rover: local point (x, y) sits x columns and y rows
 * from the rover's cell, in the global map's orientation (heading is known
 * from other sensors, paper section 2) and at the global map's cell size.
 */
#ifndef TRN_LOCALIZE_H
#define TRN_LOCALIZE_H

#include "trn/chamfer.h"
#include "trn/likelihood.h"
#include "trn/peakfit.h"
#include "trn/refine.h"
#include "trn/terrain.h"

#ifdef __cplusplus
extern "C" {
#endif

/** How trn_localize_dem high-passes the local DEM. */
typedef enum {
    /** The paper's filter on the local DEM alone: each cell minus the mean of
     *  the seen heights in its box. Biased where the box is cut by the edge
     *  of what was seen, on any slope (docs/method.md section 9). */
    TRN_LOCAL_HP_BOX = 0,
    /** Each local cell minus the GLOBAL map's low-pass (its full, uncut box)
     *  at the window centre's pose, minus one constant (the mean difference):
     *  a slope or an absolute offset cancels exactly; what remains is the
     *  low-pass's curvature times the prior's error. Needs the map's stored
     *  heights (trn_map_bytes grows by 8 bytes per cell). */
    TRN_LOCAL_HP_MAP = 1
} trn_local_hp_t;

/** What trn_localize_dem matches. */
typedef enum {
    /** The paper: the local DEM's 3-D occupancy against the map's chamfer
     *  distances (trn_search_bb), eq. 6 or the height refinement after it. */
    TRN_MATCH_VOXEL = 0,
    /** Natural terrain: the local heights against the map's heights,
     *  exhaustively over the window (trn_height_search), then
     *  trn_refine_pose; the failure probability from the same likelihood.
     *  Needs the map's stored heights. docs/method.md section 9. */
    TRN_MATCH_HEIGHTS = 1
} trn_match_t;

/** How the height matcher searches the window (TRN_MATCH_HEIGHTS). */
typedef enum {
    /** Every pose of the window scored once: a fixed cost of the window's
     *  poses. The default. */
    TRN_SEARCH_EXHAUSTIVE = 0,
    /** Branch and bound over blocks of poses (src/height_bound.c): the
     *  exhaustive search's best pose, far basins and competitor, its failure
     *  probability within trn_loc_result_t.failure_prob_bound. Its cost
     *  depends on the data (docs/method.md 9, "The bounded search": today
     *  it prunes little on the terrain measured, so it is not the default). */
    TRN_SEARCH_BOUNDED = 1
} trn_search_t;

/** Everything that shapes a prepared map. */
typedef struct {
    trn_terrain_cfg_t terrain;   /**< filter and occupancy (cell_m is the map's cell) */
    float sigma_m;               /**< inlier standard deviation s, metres */
    float inlier_prob;           /**< a, (0, 1) */
    uint8_t cap;                 /**< chamfer cap, chamfer units (3 per cell) */
    int32_t levels;              /**< pyramid levels of the fast search, 1..TRN_MAX_LEVELS */
    int32_t min_exclusion_cells; /**< least radius around the best pose excluded when
                                      looking for the competing hypothesis, 1..TRN_MAX_DIM */
    int32_t local_highpass;      /**< trn_local_hp_t */
    int32_t refine;              /**< 1: trn_localize_dem refines the pose over heights
                                      (trn_refine_pose) and reports that covariance;
                                      0: eq. 6 only (the paper). Needs stored heights. */
    float noise_m;               /**< local map height noise, constant part, metres (0, 1000] */
    float noise_k_per_m;         /**< local map height noise, range-squared part, 1/m [0, 1000]:
                                      s(r) = noise_m + noise_k_per_m r^2 */
    int32_t match;               /**< trn_match_t (trn_localize_dem only; trn_localize_points
                                      always matches voxels) */
    float max_failure_prob;      /**< acceptance limit, (0, 1]: trn_localize_dem returns
                                      TRN_E_AMBIGUOUS (result filled in) when an answer's
                                      failure probability is above it; 1 (the default):
                                      never. trn_map_cfg_auto sets
                                      TRN_MAP_MAX_FAILURE_PROB_AUTO */
    int32_t noise_auto;          /**< 1: the height matcher's search fits the noise model's
                                      scale per pose (trn_refine_cfg_t.fit_noise), and the
                                      scale from the residuals at its answer
                                      (trn_refine_noise_scale), where they reject the
                                      model by more than TRN_NOISE_SCALE_Z sds, is the
                                      refinement's, which runs again with it
                                      (trn_loc_result_t.noise_scale);
                                      0: noise_m and noise_k_per_m as given.
                                      trn_map_cfg_auto sets 1, trn_map_cfg_default 0 */
    int32_t search;              /**< trn_search_t: the height matcher's search over (x, y)
                                      (the search over heading is exhaustive) */
    uint32_t node_budget;        /**< the height matcher's searches: most pose scores (over
                                      heading, (pose, heading) scores; bounded, also block
                                      bounds) in one localization; beyond it
                                      trn_localize_dem and trn_localize_dem_heading give
                                      up with TRN_E_BUDGET (a hard bound on their time; an
                                      exhaustive search checks each pass's count before
                                      it starts); 0: none */
} trn_map_cfg_t;

/** A prepared global map. All pointers point into the caller's buffer. */
typedef struct {
    trn_map_cfg_t cfg;
    trn_vol_u8_t dist;      /**< chamfer distances of the global occupancy */
    trn_pyramid_t pyr;      /**< min-filtered distances for branch-and-bound */
    trn_lnp_table_t lnp;    /**< ln p(d), with K of this map */
    uint32_t n_occupied;    /**< occupied voxels of the global map */
    trn_grid_f32_t heights; /**< the DEM (NaN = unknown); data NULL unless the
                                 configuration needs it (TRN_LOCAL_HP_MAP, refine or
                                 TRN_MATCH_HEIGHTS) */
    trn_grid_f32_t lowpass; /**< heights minus their high-pass (same condition) */
    double roughness_m;     /**< RMS over the map of (height - mean of its 4 neighbours),
                                 metres: the scale of the DEM's own interpolation error
                                 (bilinear's is at most half of it); 0 without heights */
} trn_map_t;

/** Result of one localization. Pose values are global cells. */
typedef struct {
    double x, y;                      /**< ML pose, subpixel (ix + dx, iy + dy) */
    int32_t ix, iy;                   /**< best integer pose */
    double sigma_x_m, sigma_y_m, rho; /**< eq. 6 fit; +inf sigmas when ill-conditioned */
    double cov_m2[3];                 /**< var_x, var_y, cov_xy in m^2 */
    double ll_best;                   /**< ln L at (ix, iy), nats */
    double ll_second;                 /**< ln L of the best pose outside the exclusion zone */
    int32_t second_x, second_y;       /**< that pose (valid when has_second) */
    int32_t has_second;               /**< 0 when the window holds no pose outside the zone */
    int32_t exclusion_cells;          /**< radius of the zone around (ix, iy) */
    double failure_probability;       /**< trn_failure_probability; 0 without a second */
    int32_t on_window_edge;           /**< best pose on the window border: truth may lie outside
                                           (the height matcher: status TRN_E_ILLCOND) */
    size_t n_points;                  /**< occupied local voxels matched */
    trn_search_stats_t stats;         /**< work of the first search */
    int32_t refined;                  /**< 1: x, y, sigmas and cov_m2 come from
                                           trn_refine_pose, not from eq. 6 */
    trn_refine_t refinement;          /**< its details (valid when cfg.refine) */
    int32_t misfit;                   /**< 1: the refined model error exceeds
                                           TRN_MISFIT_ROUGHNESS x the map's roughness, or
                                           the relief test fails (relief_z):
                                           the local heights match nowhere in the window
                                           as well as the map can be matched (status
                                           TRN_E_ILLCOND) */
    double noise_scale;               /**< factor the height matcher put on the configured
                                           noise model's sd (noise_m and noise_k_per_m)
                                           because the residuals rejected it by more than
                                           TRN_NOISE_SCALE_Z sds (trn_refine_noise_scale;
                                           the refinement then ran again with it; over
                                           heading the same with the local map turned);
                                           1 otherwise, and on the voxel path */
    double failure_prob_bound;        /**< the bounded search: failure_probability is within
                                           this of the exhaustive search's (the unscored
                                           poses' mass, bounded: at most TRN_BOUND_EPS);
                                           0 when every pose was scored */
    int32_t search;                   /**< trn_search_t that ran (the search over heading:
                                           TRN_SEARCH_EXHAUSTIVE) */
    double relief_z;                  /**< the height matcher's relief test at the refined
                                           answer: (g - 1) / sd(g), g the local heights'
                                           gain on the map's relief there (local = a + plane
                                           + g x map), sd(g) from the noise model and the
                                           answer's model variance; below
                                           -TRN_RELIEF_Z the answer misfits (misfit 1).
                                           +inf where not tested (the voxel path, no
                                           refinement) */
} trn_loc_result_t;

/** Inlier probability a of trn_map_cfg_default (the paper's). */
#define TRN_MAP_INLIER_PROB_DEFAULT 0.95
/** trn_map_cfg_auto's acceptance limit on the failure probability: an
 *  answer is a fix only if the probability that it is more than 1.5 cells
 *  off is at most 2 % (0.05 before 2026-12-05; docs/method.md section 9). */
#define TRN_MAP_MAX_FAILURE_PROB_AUTO 0.02
/** High-pass half-width of the tools' and trn_map_cfg_auto's maps, cells. */
#define TRN_MAP_HIGHPASS_CELLS 10

/** A refined match whose model error m exceeds this many times the map's
 *  roughness (and the constant noise) is flagged: correct matches measured
 *  m / roughness <= 1.8 on three real DEMs; a local map from outside the
 *  window 5-50 (docs/method.md section 9). */
#define TRN_MISFIT_ROUGHNESS 3.0
/** A refined match whose local heights reproduce the map's relief at the
 *  answer with a gain g more than this many of its sds (under the noise
 *  model and the answer's model variance) below 1 is flagged (misfit;
 *  relief_z): at the truth g is 1, and a
 *  map smoother than the ground only raises it; a pose beside the truth
 *  matches the relief in part, and the fit takes a weaker copy of it
 *  (docs/method.md 9.4, "The relief test"). One-sided, about 0.1 % of
 *  right matches under the model. */
#define TRN_RELIEF_Z 3.0
/** The height matcher refines from the best integer pose and from each of
 *  its 8 neighbours whose ln L is within this many nats of the best, and
 *  keeps the refinement with the highest refined ln L (docs/method.md 9). */
#define TRN_REFINE_START_NATS 30.0
/** ... and from the integer poses of this many other basins: the highest
 *  local maxima of the ln L grid outside the best pose's zone. A sub-cell
 *  peak can score far below its refined ln L at its nearest integer pose (a
 *  half-cell shift on terrain a cell wide), so the best integer pose is not
 *  always in the best refined basin (docs/method.md 9). */
#define TRN_REFINE_BASINS 4
/** A far basin whose refinement ends more than TRN_FAIL_RADIUS_CELLS from
 *  the answer's replaces it if its refined ln L, over the inflation (the
 *  failure probability's scale), is higher by more than this many nats: odds
 *  of e^3 = 20 to 1, the 5 % level. Within this margin the answer stays;
 *  the far basins' share of the failure probability carries the tie
 *  (docs/method.md 9, "Which basin is the answer"). */
#define TRN_REFINE_FAR_NATS 3.0
/** A localization fails when its answer is more than this many cells from
 *  the truth: the event of the failure probability (docs/method.md 9). */
#define TRN_FAIL_RADIUS_CELLS 1.5

/** The bounded search's error budget on the failure probability: poses
 *  whose bounded mass could add more than this share (over the window's
 *  poses) of the scored mass are scored (docs/method.md 9, "The bounded
 *  search"). */
#define TRN_BOUND_EPS 1e-4

/**
 * @brief Probability that a 2-D normal error lies beyond a radius:
 * P(|e| > r), e ~ N(0, [[cov[0], cov[2]], [cov[2], cov[1]]]) (r in the unit
 * whose square is cov's: cells with cov_cells, metres with cov_m2). In
 * whitened coordinates the error's direction is uniform and its squared
 * length chi-square with 2 degrees of freedom, so P = (1 / 2 pi) int
 * exp(-r^2 / (2 g(psi))) dpsi, g = (a + b) / 2 + sqrt(((a - b) / 2)^2 +
 * c^2) cos(psi), by the trapezoid rule over 128 angles (periodic and
 * smooth: converged to rounding). The height matcher's failure probability
 * is at least this of its covariance at TRN_FAIL_RADIUS_CELLS
 * (docs/method.md 9, "the covariance's tail").
 * @param[in]  cov var_x, var_y, cov_xy: finite, positive semi-definite
 * @param[in]  r   radius, finite, > 0
 * @param[out] p   the probability, [0, 1]
 * @retval TRN_OK
 * @retval TRN_E_NULL cov or p is NULL
 * @retval TRN_E_ARG  r not finite or not > 0; cov not finite, or not
 *         positive semi-definite (a negative variance or |cov_xy| beyond
 *         sqrt(var_x var_y) by more than rounding)
 */
trn_status_t trn_prob_beyond(const double cov[3], double r, double *p);

/** @brief The paper's configuration on its rock fields: 0.1 m cells and
 * bins, 1 m high-pass half-width, 16 bins, s = 0.1 m, a = 0.95, cap 60
 * (20 cells), 4 levels, exclusion at least 2 cells, the local DEM filtered on
 * its own (TRN_LOCAL_HP_BOX), no refinement; height noise 0.01 m + 0.004/m r^2 (= 0.0004 r^2 / cell). */
void trn_map_cfg_default(trn_map_cfg_t *cfg);

/** @brief Workspace bytes of trn_map_cfg_auto for a width x height DEM (0 if invalid). */
size_t trn_map_cfg_auto_workspace_bytes(int32_t width, int32_t height);

/**
 * @brief The configuration chosen from the data (docs/method.md section 9):
 * high-pass half-width 10 cells; sigma_H = standard deviation of the DEM's
 * high-passed heights; height bin zbin = min(cell, max(sigma_H / 2,
 * 2 s(10 cells))) with s the local map's height noise; nz = 2 ceil(4 sigma_H /
 * zbin) + 1 clamped to [16, min(64, TRN_MAX_ZBINS)];
 * s = one cell; TRN_LOCAL_HP_MAP and refinement on; the rest as
 * trn_map_cfg_default. The noise model is the caller's (cfg->noise_m,
 * cfg->noise_k_per_m on entry are kept).
 * @param[in,out] cfg  noise_m and noise_k_per_m read; everything else written.
 * @param[in] cell_m   the DEM's cell, metres, (0, TRN_CELL_MAX_M].
 * @param[out] sigma_h_m sigma_H (may be NULL).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (cell or noise out of range),
 *         TRN_E_SIZE, TRN_E_WORKSPACE (ws below trn_map_cfg_auto_workspace_bytes
 *         or not TRN_WS_ALIGN-aligned), TRN_E_NODATA (no valid height)
 */
trn_status_t trn_map_cfg_auto(trn_map_cfg_t *cfg, const trn_grid_f32_t *dem, float cell_m, void *ws,
                              size_t ws_bytes, double *sigma_h_m);

/** @brief Check a map configuration. @retval TRN_OK, TRN_E_NULL, TRN_E_ARG, TRN_E_SIZE. */
trn_status_t trn_map_cfg_check(const trn_map_cfg_t *cfg);

/** @brief Buffer bytes trn_map_build needs for a width x height DEM (0 if invalid). */
size_t trn_map_bytes(const trn_map_cfg_t *cfg, int32_t width, int32_t height);

/**
 * @brief Prepare a global map from its DEM (NaN / inf = not seen).
 * @param[out] map  filled; valid while buf lives and is unchanged.
 * @param[in]  buf  trn_map_bytes() bytes, TRN_WS_ALIGN-aligned
 *                  (TRN_WORKSPACE_DECLARE for a static one).
 * @retval TRN_OK
 * @retval TRN_E_NULL, TRN_E_SIZE, TRN_E_ARG
 * @retval TRN_E_WORKSPACE len below trn_map_bytes or buf not TRN_WS_ALIGN-aligned
 * @retval TRN_E_NODATA the DEM has no valid height
 */
trn_status_t trn_map_build(trn_map_t *map, const trn_map_cfg_t *cfg, const trn_grid_f32_t *dem,
                           void *buf, size_t len);

/** @brief Workspace bytes of trn_localize_points for this window (0 if invalid). */
size_t trn_localize_workspace_bytes(const trn_map_t *map, const trn_window_t *win);

/**
 * @brief Localize a local occupancy (point list relative to the rover) in
 * the prior window of rover poses.
 * @retval TRN_OK
 * @retval TRN_E_ILLCOND the best pose is found (ix, iy, ll_best, failure
 *         probability are valid) but the peak has no finite covariance
 * @retval TRN_E_NULL, TRN_E_ARG, TRN_E_SIZE
 * @retval TRN_E_WORKSPACE ws_bytes below trn_localize_workspace_bytes or ws
 *         not TRN_WS_ALIGN-aligned
 * @retval TRN_E_RANGE  window not inside the map
 * @retval TRN_E_NODATA no points
 */
trn_status_t trn_localize_points(const trn_map_t *map, const trn_point_t *pts, size_t n,
                                 const trn_window_t *win, void *ws, size_t ws_bytes,
                                 trn_loc_result_t *out);

/** @brief Workspace bytes of trn_localize_dem (0 if invalid). */
size_t trn_localize_dem_workspace_bytes(const trn_map_t *map, int32_t width, int32_t height,
                                        size_t max_points, const trn_window_t *win);

/**
 * @brief Localize a local DEM: high-pass (cfg.local_highpass; with
 * TRN_LOCAL_HP_MAP against the map's low-pass at the window's centre) and
 * occupancy with the map's terrain configuration, trn_points_order on the
 * points (the result does not depend on it; the searches get cheaper), then
 * trn_localize_points; with cfg.refine, trn_refine_pose from its integer
 * pose: when that succeeds (out->refined = 1) x, y, the sigmas and cov_m2
 * are the refinement's; otherwise eq. 6's are kept (out->refined = 0).
 * @param[in] rover_x, rover_y the rover's cell in local_dem's grid.
 * @param[in] max_points       largest local occupancy accepted.
 * @retval as trn_localize_points, plus TRN_E_CAPACITY (more than max_points
 *         occupied voxels) and TRN_E_NODATA (local DEM all missing).
 * @retval TRN_E_AMBIGUOUS an answer that would be TRN_OK, but its failure
 *         probability is above cfg.max_failure_prob: out is filled in as
 *         for TRN_OK; it is not a fix (the acceptance test,
 *         docs/method.md section 9).
 * @retval TRN_E_ILLCOND also (TRN_MATCH_HEIGHTS) where the refinement
 *         failed or misfits (out->misfit), or the best pose lies on the
 *         window's edge (out->on_window_edge): the likelihood may rise
 *         beyond the window, which neither the search nor the failure
 *         probability sees (a prior that missed the truth; widen the
 *         window). out is filled in.
 */
trn_status_t trn_localize_dem(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                              int32_t rover_x, int32_t rover_y, size_t max_points,
                              const trn_window_t *win, void *ws, size_t ws_bytes,
                              trn_loc_result_t *out);

/**
 * @brief trn_localize_dem for a local map whose cells were not measured at
 * their centres: a rover that bins its stereo points into cells knows, for
 * each cell, the centroid of the points whose mean its height is. Every
 * refinement pass reads the map's model at each cell's centroid instead of
 * its centre (trn_refine_cfg_t.centroid_x, centroid_y); the searches over
 * integer poses and the voxel occupancy are as trn_localize_dem's. Where
 * the points are spread unevenly over a cell (a few points each: a map
 * cell of about 4 of them or fewer), their centroid's offset is a position
 * error of the cell that no residual shows; given, it is no error
 * (docs/method.md 9.10, "The centroids").
 * @param[in] centroid_x, centroid_y per local cell, in local_dem's layout
 *            (its stride): the centroid's offset from the cell's centre,
 *            cells east (x) and south (y, the grid's rows); for every seen
 *            cell finite and within TRN_CENTROID_MAX. Both NULL: the cells'
 *            centres (trn_localize_dem, bit for bit).
 * @retval as trn_localize_dem, plus TRN_E_NULL (one of the two NULL) and
 *         TRN_E_ARG (a seen cell's centroid not finite or beyond
 *         TRN_CENTROID_MAX). Its workspace is trn_localize_dem_workspace_bytes.
 */
trn_status_t trn_localize_dem_centroids(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                        const float *centroid_x, const float *centroid_y,
                                        int32_t rover_x, int32_t rover_y, size_t max_points,
                                        const trn_window_t *win, void *ws, size_t ws_bytes,
                                        trn_loc_result_t *out);

/** What a rover that bins its stereo points knows of each local cell beyond
 *  its height, in the local DEM's layout (its stride); each NULL where not
 *  known. */
typedef struct {
    const float *centroid_x;  /**< the points' centroid, cells east of the centre
                                   (trn_localize_dem_centroids); with centroid_y */
    const float *centroid_y;  /**< the same, cells south (the grid's rows) */
    const float *point_count; /**< how many points the height is the mean of
                                   (trn_refine_cfg_t.point_count) */
} trn_local_cells_t;

/**
 * @brief trn_localize_dem_centroids with the cells' point counts too: a
 * cell that is the mean of n stereo points has the noise variance s(r)^2 /
 * n of the map's noise model, and without its centroid, a position error
 * of variance 1 / (12 n) cells^2 per axis (trn_refine_cfg_t.point_count).
 * Every refinement pass takes them, and with them the covariance is the
 * model's without the block sandwich (refinement.inflation 1); the searches
 * over integer poses are as trn_localize_dem's (docs/method.md 9.4, 9.5,
 * 9.10 "The point counts").
 * @param[in] cells the centroids and the counts, each NULL where not
 *            known (all NULL: trn_localize_dem, bit for bit).
 * @retval as trn_localize_dem_centroids, plus TRN_E_NULL (cells NULL) and
 *         TRN_E_ARG (a seen cell's count not finite or outside [1,
 *         TRN_POINT_COUNT_MAX]). Its workspace is
 *         trn_localize_dem_workspace_bytes.
 */
trn_status_t trn_localize_dem_cells(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                    const trn_local_cells_t *cells, int32_t rover_x,
                                    int32_t rover_y, size_t max_points, const trn_window_t *win,
                                    void *ws, size_t ws_bytes, trn_loc_result_t *out);

#ifdef __cplusplus
}
#endif
#endif /* TRN_LOCALIZE_H */
