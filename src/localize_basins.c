/* SPDX-License-Identifier: Apache-2.0 */
/* localize_basins.c - the height matcher's far basins (localize_int.h;
 * docs/modules/refine.md, docs/method.md 9). */
#include "localize_int.h"

#include <math.h>
#include <stdlib.h>

#include "refine_int.h"

static double grid_at(const double *g, const trn_window_t *win, int32_t x, int32_t y)
{
    return g[(size_t)(y - win->y0) * (size_t)(win->x1 - win->x0 + 1) + (size_t)(x - win->x0)];
}

int trn_loc_grid_peak_(const double *g, const trn_window_t *win, int32_t x, int32_t y, double v)
{
    int32_t k;
    for (k = 0; k < 9; ++k) {
        int32_t nx = x + k % 3 - 1, ny = y + k / 3 - 1;
        double w;
        if (k == 4 || nx < win->x0 || nx > win->x1 || ny < win->y0 || ny > win->y1) {
            continue;
        }
        w = grid_at(g, win, nx, ny);
        if (w > v || (w == v && k < 4)) {
            return 0;
        }
    }
    return 1;
}

/* 1 if (cx, cy) is more than TRN_FAIL_RADIUS_CELLS from (ax, ay). */
static int beyond_radius(double cx, double cy, double ax, double ay)
{
    const double dx = cx - ax, dy = cy - ay;
    return dx * dx + dy * dy > TRN_FAIL_RADIUS_CELLS * TRN_FAIL_RADIUS_CELLS;
}

/* 1 if a far basin's refinement c (pose cx, cy; ln L cll) replaces the
 * answer's (ax, ay; all, its inflation infl): it ends more than
 * TRN_FAIL_RADIUS_CELLS away (one that came back to the answer's own basin
 * is not a move, whatever its ln L) and beats the answer's ln L, over the
 * inflation, by more than TRN_REFINE_FAR_NATS. */
int trn_loc_far_wins_(double cx, double cy, double cll, double ax, double ay, double all,
                      double infl)
{
    return beyond_radius(cx, cy, ax, ay) && cll - all > TRN_REFINE_FAR_NATS * fmax(1.0, infl);
}

/* The refined far basins' share of the failure probability: each one
 * whose refined pose is more than TRN_FAIL_RADIUS_CELLS from the answer's
 * weighed against the answer by its refined ln L (divided by infl, as the
 * grid's), sum_b e^(d_b) / (1 + sum_b e^(d_b)), d_b = (ll_b - ll) / infl. A
 * basin whose peak lies between integer poses scores low on the grid, so
 * the grid's mass alone can miss a competitor the refinement sees. */
double trn_loc_basins_failure_(const trn_loc_basins_t *b, double infl, const trn_loc_result_t *out)
{
    double sum = 0.0;
    int32_t i;
    for (i = 0; i < b->n; ++i) {
        double dx = b->px[i] - out->refinement.x, dy = b->py[i] - out->refinement.y;
        if (b->ok[i] && dx * dx + dy * dy > TRN_FAIL_RADIUS_CELLS * TRN_FAIL_RADIUS_CELLS) {
            sum += exp(fmin(700.0, (b->rll[i] - out->refinement.ll) / infl));
        }
    }
    return sum / (1.0 + sum);
}

/* 1 if (x, y, slice s) is a local maximum of the 3-D grid: no neighbour
 * higher, none equal before it in (slice, row, column) order. */
static int grid_peak3(const double *grid, const trn_window_t *win, int32_t half_steps, size_t poses,
                      int32_t x, int32_t y, int32_t s, double v)
{
    int32_t n;
    for (n = 0; n < 27; ++n) {
        int32_t nx = x + n % 3 - 1, ny = y + (n / 3) % 3 - 1, ns = s + n / 9 - 1;
        double w;
        if (n == 13 || nx < win->x0 || nx > win->x1 || ny < win->y0 || ny > win->y1 || ns < 0 ||
            ns > 2 * half_steps) {
            continue;
        }
        w = grid_at(grid + (size_t)ns * poses, win, nx, ny);
        if (w > v || (w == v && n < 13)) {
            return 0;
        }
    }
    return 1;
}

void trn_loc_find_basins3_(const double *grid, const trn_window_t *win, int32_t half_steps,
                           int32_t radius, int32_t bx, int32_t by, trn_loc_basins_t *b)
{
    const size_t poses = (size_t)(win->x1 - win->x0 + 1) * (size_t)(win->y1 - win->y0 + 1);
    int32_t x, y, s;
    b->n = 0;
    b->moved = 0;
    for (s = 0; s <= 2 * half_steps; ++s) {
        for (y = win->y0; y <= win->y1; ++y) {
            for (x = win->x0; x <= win->x1; ++x) {
                double v = grid_at(grid + (size_t)s * poses, win, x, y);
                int32_t k, pos = 0, last;
                if (!isfinite(v) || (abs(x - bx) <= radius && abs(y - by) <= radius) ||
                    (b->n == TRN_REFINE_BASINS && v <= b->ll[TRN_REFINE_BASINS - 1]) ||
                    !grid_peak3(grid, win, half_steps, poses, x, y, s, v)) {
                    continue;
                }
                last = b->n < TRN_REFINE_BASINS ? b->n++ : TRN_REFINE_BASINS - 1;
                for (k = 0; k < last; ++k) {
                    if (b->ll[k] >= v) {
                        pos = k + 1;
                    }
                }
                for (k = last; k > pos; --k) {
                    b->x[k] = b->x[k - 1];
                    b->y[k] = b->y[k - 1];
                    b->k[k] = b->k[k - 1];
                    b->ll[k] = b->ll[k - 1];
                }
                b->x[pos] = x;
                b->y[pos] = y;
                b->k[pos] = s;
                b->ll[pos] = v;
            }
        }
    }
}

trn_status_t trn_prob_beyond(const double cov[3], double r, double *p)
{
    /* cos and sin of 2 pi / 128: the angles by rotation, no libm call */
    const double c1 = 0.9987954562051724, s1 = 0.049067674327418015;
    double a, b, c, m, d, cs = 1.0, sn = 0.0, sum = 0.0;
    int32_t k;
    if (cov == NULL || p == NULL) {
        return TRN_E_NULL;
    }
    a = cov[0];
    b = cov[1];
    c = cov[2];
    if (!(r > 0.0) || !isfinite(r) || !isfinite(a) || !isfinite(b) || !isfinite(c) || a < 0.0 ||
        b < 0.0 || c * c > a * b * (1.0 + 1e-12)) {
        return TRN_E_ARG;
    }
    m = 0.5 * (a + b);
    d = sqrt(0.25 * (a - b) * (a - b) + c * c);
    for (k = 0; k < 128; ++k) {
        const double g = m + d * cs, t = cs * c1 - sn * s1;
        if (g > 0.0) {
            sum += exp(-0.5 * r * r / g);
        }
        sn = sn * c1 + cs * s1;
        cs = t;
    }
    *p = sum / 128.0;
    return TRN_OK;
}

double trn_loc_tail_failure_(const double cov_cells[3])
{
    double tail = 1.0;
    if (trn_prob_beyond(cov_cells, TRN_FAIL_RADIUS_CELLS, &tail) != TRN_OK) {
        tail = 1.0; /* a covariance that bounds nothing */
    }
    return tail;
}
