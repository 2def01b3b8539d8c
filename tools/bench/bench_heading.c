/* SPDX-License-Identifier: Apache-2.0 */
/* bench_heading.c - see bench_heading.h.
 *
 *   3-DOF   trn_localize_points_heading over +-6 deg (automatic step): the
 *           best (x, y, heading), its 3-D fit and the competitor.
 *   2-DOF   trn_localize_points (best pose, eq. 6 fit, competitor) on the
 *           points turned to one heading, timed at every step; their sum is
 *           what searching each heading on its own costs. Its best answer
 *           must be the 3-DOF one (same pose, step and ln L).
 * The ratio 3-DOF / sum is the goal (at most 0.2): the bound carried across
 * headings lets most of them stop after a few top-level blocks, and one pass
 * finds the best pose and the competitor. Each timing is the median of
 * `repeats` calls after one warm-up (CLOCK_MONOTONIC). The work line: the
 * 3-DOF call's one pass (best pose and every pose within the margin)
 * against the 2-DOF calls' best-pose searches only (trn_localize_points
 * does not count its competitor's search). */
#define _POSIX_C_SOURCE 200112L

#include "bench_heading.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define BH_MAX_REPS 64
#define BH_DEG (3.14159265358979323846 / 180.0)

static double bh_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static int bh_cmp(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double bh_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof v[0], bh_cmp);
    return (n % 2) ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int bench_heading_run(const trn_map_t *map, const trn_point_t *pts, size_t n_pts, int32_t px,
                      int32_t py, int32_t w, int32_t n, int repeats, bench_heading_result_t *r)
{
    const trn_window_t win = {px - w, py - w, px + w, py + w};
    trn_heading_cfg_t hc = {0.0, 6.0 * BH_DEG, 0.0};
    trn_heading_result_t hr;
    trn_point_t *turned = malloc(n_pts * sizeof *turned), *rot = malloc(n_pts * sizeof *rot);
    size_t hb = trn_localize_heading_workspace_bytes(map, n_pts, &win);
    size_t lb = trn_localize_workspace_bytes(map, &win);
    void *hws = NULL, *lws = NULL;
    double t3[BH_MAX_REPS], t2[BH_MAX_REPS], best_ll = -HUGE_VAL, sum_med = 0.0;
    unsigned long long work2 = 0u, work3;
    int32_t k, kk, best_k = 0, bx = 0, by = 0;
    int reps = repeats < 1 ? 1 : (repeats > BH_MAX_REPS ? BH_MAX_REPS : repeats), i, rc = 3;
    trn_status_t st;

    memset(r, 0, sizeof *r);
    if (turned == NULL || rot == NULL || hb == 0u || lb == 0u ||
        posix_memalign(&hws, 16u, hb) != 0 || posix_memalign(&lws, 16u, lb) != 0 ||
        trn_points_rotate(pts, n_pts, -3.0 * BH_DEG, turned) != TRN_OK) {
        fprintf(stderr, "trn_bench: heading setup failed\n");
        goto done;
    }
    for (i = -1; i < reps; ++i) { /* i = -1: warm-up */
        const double t0 = bh_ms();
        st = trn_localize_points_heading(map, turned, n_pts, &win, &hc, hws, hb, &hr);
        if (st != TRN_OK && st != TRN_E_ILLCOND) {
            fprintf(stderr, "trn_bench: trn_localize_points_heading: %s\n", trn_strerror(st));
            goto done;
        }
        if (i >= 0) {
            t3[i] = bh_ms() - t0;
        }
    }
    r->heading_ms = bh_median(t3, reps);
    kk = hr.half_steps;
    r->steps = 2 * kk + 1;
    for (k = -kk; k <= kk; ++k) {
        trn_loc_result_t lr;
        if (trn_points_rotate(turned, n_pts, hc.center_rad + (double)k * hr.step_rad, rot) !=
                TRN_OK ||
            trn_points_order(rot, n_pts, map->dist.nz) != TRN_OK) {
            goto done;
        }
        for (i = -1; i < reps; ++i) {
            const double t0 = bh_ms();
            st = trn_localize_points(map, rot, n_pts, &win, lws, lb, &lr);
            if (st != TRN_OK && st != TRN_E_ILLCOND) {
                fprintf(stderr, "trn_bench: trn_localize_points: %s\n", trn_strerror(st));
                goto done;
            }
            if (i >= 0) {
                t2[i] = bh_ms() - t0;
            }
        }
        sum_med += bh_median(t2, reps);
        work2 += (unsigned long long)(lr.stats.poses_scored + lr.stats.blocks_bounded);
        /* strictly better replaces: ties go to the earlier step in the
         * 3-DOF order (0, -1, +1, ...), checked below by value */
        if (lr.ll_best > best_ll || (lr.ll_best == best_ll && abs(k) < abs(best_k))) {
            best_ll = lr.ll_best;
            best_k = k;
            bx = lr.ix;
            by = lr.iy;
        }
    }
    r->per_step_ms = sum_med / (double)r->steps;
    work3 = (unsigned long long)hr.loc.stats.poses_scored +
            (unsigned long long)hr.loc.stats.blocks_bounded;
    r->ratio = r->heading_ms / sum_med;
    r->wrong = !(hr.loc.ll_best == best_ll && hr.best_step == best_k && hr.loc.ix == bx &&
                 hr.loc.iy == by);
    {
        char note[200];
        snprintf(note, sizeof note,
                 "%d headings of %.2f deg, found %+.2f deg (true +3.00), sigma %.2f deg",
                 (int)r->steps, hr.step_rad / BH_DEG, hr.heading_rad / BH_DEG,
                 hr.sigma_heading_rad / BH_DEG);
        printf("%-5d %-50s %4d %11.3f %11s  %s\n", (int)n,
               "heading +-6 deg: trn_localize_points_heading", reps, r->heading_ms, "", note);
        snprintf(note, sizeof note, "%.3f ms a heading; best = 3-DOF answer: %s", r->per_step_ms,
                 r->wrong ? "NO" : "yes");
        printf("%-5d %-50s %4d %11.3f %11s  %s\n", (int)n,
               "heading: trn_localize_points x every step", reps, sum_med, "", note);
        printf("      ratio %-56s %8.3f  (goal <= 0.2)\n", "3-DOF / (2-DOF x steps)", r->ratio);
        printf("      search work (poses scored + blocks bounded): 3-DOF one pass %llu, 2-DOF x "
               "steps best-pose searches %llu (%.3f)\n",
               work3, work2, (double)work3 / (double)work2);
        fflush(stdout);
    }
    rc = 0;
done:
    free(turned);
    free(rot);
    free(hws);
    free(lws);
    return rc;
}
