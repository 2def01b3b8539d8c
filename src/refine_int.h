/* SPDX-License-Identifier: Apache-2.0 */
/* refine_int.h - refine.c's interpolants and the height matcher over
 * heading's entry for trn_localize_dem_heading, internal to the core. */
#ifndef TRN_REFINE_INT_H
#define TRN_REFINE_INT_H

#include "trn/grid.h"
#include "trn/height_heading.h"

/* Height and gradient (per cell) at fractional cell (x, y): bicubic
 * convolution (Keys, a = -1/2), bilinear where the 4 x 4 support is
 * incomplete; 0 when there is no height there. */
int trn_refine_sample_(const trn_grid_f32_t *g, double x, double y, double out[3]);

/* The same by bilinear interpolation only. */
int trn_refine_sample_bilinear_(const trn_grid_f32_t *g, double x, double y, double out[3]);

/* Standard deviation of the seen local heights about their mean (0 for
 * none), and their count (trn_height_search's K is 1 / (10 x it)). */
double trn_refine_local_spread_(const trn_grid_f32_t *local, int32_t *n_seen);

/* The argument checks of trn_refine_pose and trn_refine_pose_heading (the
 * latter adds its heading's): TRN_E_NULL (global, local, cfg, out), the
 * grids' status, TRN_E_ARG (cfg out of range or NaN, the rover cell
 * farther than TRN_MAX_DIM from the local grid); TRN_OK. */
trn_status_t trn_refine_args_(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                              int32_t rover_x, int32_t rover_y, const trn_refine_cfg_t *cfg,
                              const void *out);

/* cos and sin of a finite angle without libm's exact argument reduction
 * and its stack (src/refine_heading.c; within 1e-14 for |a| <= 4 pi). */
void trn_heading_trig_(double a, double *c, double *s);

/* trn_localize_dem_heading's parts, after its argument checks (up to the
 * map and max_points), each out of line so that no path's stack carries
 * another's frame: the voxel path (src/localize.c: its preparation, then
 * the search); the height matcher
 * over heading with a window or an off-zero centre (src/height_heading.c);
 * the rest of the checks (src/localize.c); W = 0 at centre 0 with a height
 * map, trn_localize_dem (src/height_heading.c). */
trn_status_t trn_localize_dem_heading_prep_(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                            int32_t rover_x, int32_t rover_y, size_t max_points,
                                            const trn_window_t *win, void *ws, size_t ws_bytes,
                                            size_t *n, size_t at[2]);
trn_status_t trn_localize_dem_heading_voxel_(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                             int32_t rover_x, int32_t rover_y, size_t max_points,
                                             const trn_window_t *win, const trn_heading_cfg_t *cfg,
                                             void *ws, size_t ws_bytes, trn_heading_result_t *out);
trn_status_t trn_localize_heights3_(const trn_map_t *map, const trn_grid_f32_t *local,
                                    int32_t rover_x, int32_t rover_y, const trn_window_t *win,
                                    const trn_heading_cfg_t *cfg, void *ws, size_t ws_bytes,
                                    trn_heading_result_t *out);
trn_status_t trn_localize_dem_heading_checked_(const trn_map_t *map,
                                               const trn_grid_f32_t *local_dem, int32_t rover_x,
                                               int32_t rover_y, size_t max_points,
                                               const trn_window_t *win,
                                               const trn_heading_cfg_t *cfg, void *ws,
                                               size_t ws_bytes, trn_heading_result_t *out);
trn_status_t trn_localize_heights2d_(const trn_map_t *map, const trn_grid_f32_t *local,
                                     int32_t rover_x, int32_t rover_y, size_t max_points,
                                     const trn_window_t *win, const trn_heading_cfg_t *cfg,
                                     void *ws, size_t ws_bytes, trn_heading_result_t *out);

#endif /* TRN_REFINE_INT_H */
