/* SPDX-License-Identifier: Apache-2.0 */
/* bench_heading.h - trn_bench's heading part (bench_heading.c): the search
 * over (x, y, heading) against the 2-DOF localization repeated at every
 * heading step, in the same run (issue 14's benchmark). */
#ifndef TRN_BENCH_HEADING_H
#define TRN_BENCH_HEADING_H
#include "trn/trn.h"

typedef struct {
    double heading_ms;  /* trn_localize_points_heading, median */
    double per_step_ms; /* trn_localize_points at one heading, median */
    int32_t steps;      /* headings searched, 2 K + 1 */
    double ratio;       /* heading_ms / (per_step_ms x steps); goal <= 0.2 */
    int wrong;          /* the 3-DOF answer differed from the best of the per-heading ones */
} bench_heading_result_t;

/* Rows for one map (size n): the local points pts (the bench's local map, true
 * heading 0) are turned by -3 deg and searched over +-6 deg around 0 in the
 * window +-w around (px, py). Returns 0, or 3 on a setup failure. */
int bench_heading_run(const trn_map_t *map, const trn_point_t *pts, size_t n_pts, int32_t px,
                      int32_t py, int32_t w, int32_t n, int repeats, bench_heading_result_t *r);
#endif
