/* SPDX-License-Identifier: Apache-2.0 */
/* bench_select.h - trn_bench's landmark-selection part (bench_select.c):
 * probability map (eq. 8), all candidates of one rover position, and the
 * sensor uncertainty field, each against the naive version in the same run. */
#ifndef TRN_BENCH_SELECT_H
#define TRN_BENCH_SELECT_H
#include "trn/trn.h"

typedef struct {
    double pmap_ms, pmap_naive_ms, pmap_cv_ms; /* medians; cv_ms < 0 without OpenCV */
    double select_ms, select_naive_ms;
    double field_ms, field_naive_est_ms;
    unsigned field_evals, field_cells;
    double field_fast_ms;             /* trn_field_fast, same field as field_ms */
    double fpaper_ms, fpaper_fast_ms; /* paper defaults: trn_field, trn_field_fast */
    int32_t fpaper_side;              /* over this square area (the whole map up to 256) */
    unsigned fpaper_evals;
    size_t fpaper_ws, fpaper_fast_ws; /* workspace bytes of the two */
    int wrong;                        /* a fast answer differed from the naive one */
} bench_select_result_t;

/* Run and print the rows for one map (size n). Returns 0, or 3 on a setup failure. */
int bench_select_run(const trn_map_t *map, int32_t n, int repeats, bench_select_result_t *r);
#endif
