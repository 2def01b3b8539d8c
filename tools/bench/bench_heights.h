/* SPDX-License-Identifier: Apache-2.0 */
/* bench_heights.h - trn_bench's rows for the height matcher (bench_heights.c):
 * the default localizer (trn_map_cfg_auto, TRN_MATCH_HEIGHTS) beside the
 * voxel matcher on the same case in the same run, its exhaustive and bounded
 * searches, and the worst cases of a bound (flat, periodic, a few cells). */
#ifndef TRN_BENCH_HEIGHTS_H
#define TRN_BENCH_HEIGHTS_H
#include <stdint.h>

typedef struct {
    int32_t win[2];     /* half-widths of the README case's windows, cells */
    double voxel_ms[2]; /* trn_localize_dem, the paper's voxel map, median */
    double exh_ms[2];   /* the height matcher, TRN_SEARCH_EXHAUSTIVE, median */
    double bnd_ms[2];   /* the height matcher, TRN_SEARCH_BOUNDED, median */
    double worst_ratio; /* largest bounded / exhaustive over the worst cases */
    int wrong;          /* bounded and exhaustive differ in pose or status */
} bench_heights_result_t;

/* The README localize example (trn terrain --coverage 0.15 --seed 3, 256 x
 * 256 cells of 0.1 m; the 64 x 64 local map cut at rows 88.., columns 108..
 * plus 1 cm noise; prior (147, 125)) at windows +-25 and +-50 cells (quick:
 * +-10 only), then the worst cases at +-25 (quick: +-10). Returns 0, or 3
 * on a setup failure. */
int bench_heights_run(int repeats, int quick, bench_heights_result_t *r);
#endif
