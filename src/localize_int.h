/* SPDX-License-Identifier: Apache-2.0 */
/* localize_int.h - internal to the localization stack (docs/architecture.md,
 * "The localization stack"): the height matcher's localization
 * (src/localize_heights.c), its far basins (src/localize_basins.c) and
 * shared functions (src/localize_common.c), and the parts of src/localize.c
 * that the entries (src/localize_dem.c, src/localize_heading.c) use.
 * Separate files so that their frames do not add to the entries' (no
 * inlining across files; the stack limit of docs/architecture.md) and so
 * that calls go one way. */
#ifndef TRN_LOCALIZE_INT_H
#define TRN_LOCALIZE_INT_H

#include "trn/heading.h"
#include "trn/height_heading.h"
#include "trn/localize.h"
#include "trn/refine.h"

/* Far basins (TRN_REFINE_BASINS): up to that many local maxima of the ln L
 * grid outside the best pose's zone, highest first (their starts and grid
 * ln L); once refined (src/localize_heights.c) each slot holds a refinement that is not
 * the answer: its pose and refined ln L (ok 0: it failed). It lives in the
 * workspace, not on the stack. */
typedef struct {
    int32_t n;
    int32_t x[TRN_REFINE_BASINS], y[TRN_REFINE_BASINS];
    int32_t k[TRN_REFINE_BASINS]; /* heading slice (trn_loc_find_basins3_; 0 in 2-D) */
    double ll[TRN_REFINE_BASINS];
    double px[TRN_REFINE_BASINS], py[TRN_REFINE_BASINS], rll[TRN_REFINE_BASINS];
    int32_t ok[TRN_REFINE_BASINS];
    int32_t moved, mx, my, mk; /* over heading: 1 if the answer moved to start (mx, my, slice mk) */
} trn_loc_basins_t;

/* The signed heading step of the i-th heading searched: 0, -1, 1, -2, 2, ...
 * (the searches over heading, src/heading.c and src/height_heading.c). */
static inline int32_t trn_heading_step_of_(int32_t i)
{
    return (i % 2 == 1) ? -(i + 1) / 2 : i / 2;
}

/* 1 if pose (x, y) lies on the border of window win (the likelihood may
 * rise beyond it: the height matchers' on_window_edge), else 0. */
static inline int32_t trn_loc_on_edge_(const trn_window_t *win, int32_t x, int32_t y)
{
    return (x == win->x0 || x == win->x1 || y == win->y0 || y == win->y1) ? 1 : 0;
}

/* The window is non-empty and inside the map (checked before any work;
 * src/localize.c and src/localize_heading.c). */
static inline int trn_loc_window_ok_(const trn_map_t *map, const trn_window_t *win)
{
    return win->x0 <= win->x1 && win->y0 <= win->y1 && win->x0 >= 0 && win->y0 >= 0 &&
           win->x1 < map->dist.nx && win->y1 < map->dist.ny;
}

/* 1 if the prepared map is consistent: its configuration passes
 * trn_map_cfg_check and its parts have that configuration's shapes
 * (src/localize.c). */
int trn_loc_map_ok_(const trn_map_t *map);

/* Local high-pass against the global low-pass (TRN_LOCAL_HP_MAP) at the
 * reference pose (cx, cy) (src/localize.c; see there). */
trn_status_t trn_loc_highpass_by_map_(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx,
                                      int32_t ry, int32_t cx, int32_t cy, trn_grid_f32_t *out);

/* The height matcher's localization (src/localize_heights.c): the one
 * path of trn_localize_dem (cfg: the heading known, 0) and of
 * trn_localize_dem_heading with a height map. Search (over heading, or the
 * bounded search at heading 0), refinement from the best pose and its
 * neighbours, the noise model's rescale, far basins, shoulders, failure
 * probability, acceptance; statuses as trn_localize_dem_heading's, plus
 * TRN_E_ARG for the bounded search with a heading window or an off-zero
 * centre. cells: what is known of the local cells (trn_local_cells_t), or
 * NULL: nothing. The map, max_points and the cells are checked by the
 * caller. */
trn_status_t trn_loc_heights_(const trn_map_t *map, const trn_grid_f32_t *local,
                              const trn_local_cells_t *cells, int32_t rover_x, int32_t rover_y,
                              const trn_window_t *win, const trn_heading_cfg_t *cfg, void *ws,
                              size_t ws_bytes, trn_heading_result_t *out);
/* Its workspace bytes for a width x height local DEM and half_steps
 * headings either side (trn_height_heading_steps's K); 0 when the map has
 * no heights, the window is not inside it, or the search is refused. */
size_t trn_loc_heights_bytes_(const trn_map_t *map, int32_t width, int32_t height,
                              const trn_window_t *win, int32_t half_steps,
                              const trn_heading_cfg_t *cfg);

/* trn_localize_dem's voxel path after its argument checks
 * (src/localize.c), and its workspace bytes (0 if refused). */
trn_status_t trn_loc_voxel_dem_(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                const trn_local_cells_t *cells, int32_t rover_x, int32_t rover_y,
                                size_t max_points, const trn_window_t *win, void *ws,
                                size_t ws_bytes, trn_loc_result_t *out);
size_t trn_loc_voxel_dem_bytes_(const trn_map_t *map, int32_t width, int32_t height,
                                size_t max_points, const trn_window_t *win);

/* 1 if pose (x, y), ln L v, of the ln L grid g over win is a local maximum:
 * no neighbour in the window higher, and none equal before it in scan order
 * (one pose per plateau). The far basins' rule, here and in the bounded
 * search (src/height_bound.c, whose unscored poses hold -inf). */
int trn_loc_grid_peak_(const double *g, const trn_window_t *win, int32_t x, int32_t y, double v);

/* The refinement in out->refinement becomes the answer: pose, covariance,
 * sigmas and the misfit flag (src/localize_common.c). */
void trn_loc_take_refinement_(const trn_map_t *map, trn_loc_result_t *out);
/* 1 if the residuals at `at` (the local map turned by heading_rad) reject
 * the noise model rc by more than TRN_NOISE_SCALE_Z sds of
 * trn_refine_noise_scale's estimate of its variance factor k2; *scale is
 * then the sd's factor, sqrt(k2). A k2 above 1 is first cut to what the
 * neighbouring residuals' differences support (trn_refine_noise_scale_diff_,
 * at least 1): a smooth misfit (a wrong pose or heading) raises the
 * residuals' level but cancels in their differences; sensor noise does not.
 * 0, *scale untouched, otherwise (src/localize_common.c). */
int trn_loc_noise_rejected_(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx,
                            int32_t ry, const trn_refine_t *at, double heading_rad,
                            const trn_refine_cfg_t *rc, double *scale);
/* The refinement's noise model: the map's, its sd times out->noise_scale,
 * and what is known of the local cells (trn_local_cells_t; NULL, or each
 * pointer NULL: the cells' centres, one measurement a cell)
 * (src/localize_common.c). */
void trn_loc_refine_cfg_(const trn_map_t *map, const trn_loc_result_t *out,
                         const trn_local_cells_t *cells, trn_refine_cfg_t *rc);

/* The refined answer's covariance's mass beyond TRN_FAIL_RADIUS_CELLS
 * (trn_prob_beyond on cov_cells; 1 if it is not a covariance). */
double trn_loc_tail_failure_(const double cov_cells[3]);
/* The far basins (src/localize_heights.c refines them, so that this frame
 * is not under the refinement's on the stack): the local maxima
 * of the ln L grid, (2 half_steps + 1) slices over win (26 neighbours),
 * outside the position zone (radius) of (bx, by) at any heading; k holds
 * the slice. */
void trn_loc_find_basins3_(const double *grid, const trn_window_t *win, int32_t half_steps,
                           int32_t radius, int32_t bx, int32_t by, trn_loc_basins_t *b);

/* The refined far basins' share of the failure probability (see the .c). */
double trn_loc_basins_failure_(const trn_loc_basins_t *b, double infl, const trn_loc_result_t *out);
/* 1 if a far basin refined to (cx, cy), ln L cll, replaces the answer at
 * (ax, ay), ln L all, inflation infl (TRN_REFINE_FAR_NATS). */
int trn_loc_far_wins_(double cx, double cy, double cll, double ax, double ay, double all,
                      double infl);

#endif /* TRN_LOCALIZE_INT_H */
