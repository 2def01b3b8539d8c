/* SPDX-License-Identifier: Apache-2.0 */
/* select_heights.h - the height matcher's prediction for trn_select
 * (trn/select.h, docs/method.md 4, "The height matcher's prediction"),
 * internal to the core.
 *
 * Per map cell of the region with its four neighbours known: the central
 * differences g = (gx, gy), metres per cell (the bicubic interpolant's
 * gradient at a node), the representation residual e = h - the mean of the
 * four neighbours, metres, and the weight w = 1 / s^2, s^2 the noise model
 * at the cell's range from the rover (over n and plus the centroid's jitter
 * |g|^2 / (12 n) for a binned map of n points a cell) plus the map's error
 * plus e^2 / 4.
 * Exact int64 summed-area tables of the count, w, w gx, w gy, w gx^2,
 * w gx gy and w gy^2 give each candidate's sums in four reads per table;
 * each table's terms are quantized to the finest power of two (at most
 * 2^-40 of its unit) with which no sum over the region can overflow, chosen
 * from the region's largest term (TRN_E_SIZE when even a quantum of 1 cannot).
 * With the heading searched, double tables of w gt, w gt gx, w gt gy and
 * w gt^2 too, gt = g . J u the heading's column (u the cell's offset from
 * the rover, cells). */
#ifndef TRN_SELECT_HEIGHTS_H
#define TRN_SELECT_HEIGHTS_H

#include <stddef.h>
#include <stdint.h>

#include "trn/grid.h"
#include "trn/likelihood.h"
#include "trn/status.h"

/* The noise of the prediction: the rover (cells), the cell (m), the
 * matcher's noise model sd = noise_m + noise_k r^2 (r in m), the map's
 * error variance (m^2), the share of sd^2 a cell keeps (1 / n for the mean
 * of n points, else 1) and the centroid's jitter per |g|^2 (cells^2: 1 /
 * (12 n), else 0). */
typedef struct {
    double rxf, ryf, cell, noise_m, noise_k, map_var, inv_n, jitter;
} trn_selh_noise_t;

/* One patch's sums (the tables' units undone): the count of cells with
 * terms, the profiled information (the offset dz's share removed:
 * sum w g g^T - (sum w g)(sum w g)^T / sum w), per cell^2, its uncentred
 * trace raw = sum w |g|^2; with the heading: bx, by, cc the profiled
 * (x, y) x heading and heading x heading sums (u in cells). */
typedef struct {
    double n;
    double axx, axy, ayy;
    double raw;
    double bx, by, cc;
} trn_selh_sums_t;

/* Bytes of the tables for a region of w x h cells (heading: the heading's
 * four double tables too). */
size_t trn_selh_bytes_(int32_t w, int32_t h, int heading);

/* Builds the tables over roi of heights into base (trn_selh_bytes_ bytes,
 * TRN_WS_ALIGN-aligned) with the noise nm. TRN_E_SIZE when the region's
 * int64 sums could overflow. */
trn_status_t trn_selh_build_(const trn_grid_f32_t *heights, const trn_window_t *roi, int heading,
                             const trn_selh_noise_t *nm, void *base);

/* The sums of patch pw (inside roi) from the tables. */
void trn_selh_sums_(const void *base, const trn_window_t *roi, const trn_window_t *pw, int heading,
                    trn_selh_sums_t *s);

#endif /* TRN_SELECT_HEIGHTS_H */
