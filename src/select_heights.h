/* SPDX-License-Identifier: Apache-2.0 */
/* select_heights.h - the height matcher's prediction for trn_select
 * (trn/select.h, docs/method.md 4, "The height matcher's prediction"),
 * internal to the core.
 *
 * Per map cell of the region with its four neighbours known: the central
 * differences g = (gx, gy), metres per cell (the bicubic interpolant's
 * gradient at a node), and the representation residual e = h - the mean of
 * the four neighbours, metres. Exact int64 summed-area tables of the count,
 * gx, gy, gx^2, gx gy, gy^2 and e^2 give each candidate's sums in four reads
 * per table. g and e^2 are quantized to the finest powers of two (at most
 * 2^-40) with which no sum over the region can overflow, chosen from the
 * region's largest terms (TRN_E_SIZE when even 1 m per cell cannot); with
 * the heading searched, double tables of the heading's column
 * gt = g . J u (u the cell's offset from the rover, cells), gt gx, gt gy
 * and gt^2 too. */
#ifndef TRN_SELECT_HEIGHTS_H
#define TRN_SELECT_HEIGHTS_H

#include <stddef.h>
#include <stdint.h>

#include "trn/grid.h"
#include "trn/likelihood.h"
#include "trn/status.h"

/* One patch's sums (the tables' units undone): count, the gradient's sum
 * and its profiled outer product (the offset dz's share removed: sum of
 * (g - mean g)(g - mean g)^T), per cell^2 in m^2; e2 the mean of e^2, m^2;
 * with the heading: bx, by, cc the profiled (x, y) x heading and heading x
 * heading sums (u in cells). */
typedef struct {
    double n;
    double axx, axy, ayy;
    double raw;
    double e2;
    double bx, by, cc;
} trn_selh_sums_t;

/* Bytes of the tables for a region of w x h cells (heading: the heading's
 * four double tables too). */
size_t trn_selh_bytes_(int32_t w, int32_t h, int heading);

/* Builds the tables over roi of heights into base (trn_selh_bytes_ bytes,
 * TRN_WS_ALIGN-aligned); rover (rxf, ryf) in cells for the heading's
 * tables. TRN_E_SIZE when the region's int64 sums could overflow (a
 * gradient beyond what the quantum allows over this many cells). */
trn_status_t trn_selh_build_(const trn_grid_f32_t *heights, const trn_window_t *roi, int heading,
                             double rxf, double ryf, void *base);

/* The sums of patch pw (inside roi) from the tables. */
void trn_selh_sums_(const void *base, const trn_window_t *roi, const trn_window_t *pw, int heading,
                    trn_selh_sums_t *s);

#endif /* TRN_SELECT_HEIGHTS_H */
