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

/* trn_localize_dem_heading for a TRN_MATCH_HEIGHTS map (src/height_heading.c):
 * the arguments are checked there up to the map (map_ok) and max_points. */
trn_status_t trn_localize_heights_heading_(const trn_map_t *map, const trn_grid_f32_t *local,
                                           int32_t rover_x, int32_t rover_y, size_t max_points,
                                           const trn_window_t *win, const trn_heading_cfg_t *cfg,
                                           void *ws, size_t ws_bytes, trn_heading_result_t *out);

#endif /* TRN_REFINE_INT_H */
