/* SPDX-License-Identifier: Apache-2.0 */
/* test_localize_zone.c - the far basins' rule by the zones' mass (internal:
 * trn_loc_zone_lse_ and trn_loc_basin_wins_ of src/localize_basins.c;
 * docs/method.md 9, "the zone's mass").
 *
 * Oracles:
 * - the zone's ln mass against a slow sum written out here (long double,
 *   every pose of the window tested for membership one by one), on a grid of
 *   two bumps, at zones inside, across the window's edge and off it, and at
 *   inflations 1 and 2.7; and over heading, three slices summed;
 * - the rule on a grid built for it: a sharp peak (the answer, best integer
 *   ln L) and, 6 cells away, a broad one 0.8 nats lower at its top whose 3 x
 *   3 zone holds more mass (written out: e^-0.8 (1 + 8 e^-0.05) against 1 +
 *   8 e^-6). With the refined ln L within TRN_REFINE_FAR_NATS the broad zone
 *   wins by mass (2); with the answer's refined ln L more than that margin
 *   above it loses (0); with its own more than that margin above it wins
 *   outright (1); refined back into the answer's radius it never wins; the
 *   margin scales with the inflation. Swapped (the broad zone the answer) the
 *   sharp one does not win by mass.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "localize_int.h"

#define W 21
#define H 17

static double grid[W * H];
static const trn_window_t WIN = {10, 20, 10 + W - 1, 20 + H - 1};

static double *at(int32_t x, int32_t y)
{
    return &grid[(size_t)(y - WIN.y0) * W + (size_t)(x - WIN.x0)];
}

/* A sharp peak at (sx, sy), ln L 0 there and -6 at its 8 neighbours, and a
 * broad one at (bx, by), -0.8 at its top and -0.85 around it; -60 elsewhere,
 * one pose unscored (-inf). */
static void two_peaks(int32_t sx, int32_t sy, int32_t bx, int32_t by)
{
    int32_t x, y;
    for (y = WIN.y0; y <= WIN.y1; ++y) {
        for (x = WIN.x0; x <= WIN.x1; ++x) {
            double v = -60.0;
            if (x == sx && y == sy) {
                v = 0.0;
            } else if (abs(x - sx) <= 1 && abs(y - sy) <= 1) {
                v = -6.0;
            } else if (x == bx && y == by) {
                v = -0.8;
            } else if (abs(x - bx) <= 1 && abs(y - by) <= 1) {
                v = -0.85;
            }
            *at(x, y) = v;
        }
    }
    *at(WIN.x1, WIN.y1) = -(double)INFINITY;
}

/* ln sum over the window's poses within radius of (cx, cy) of e^(g / infl). */
static double slow_lse(int32_t cx, int32_t cy, int32_t radius, double infl)
{
    long double sum = 0.0L;
    int32_t x, y;
    for (y = WIN.y0; y <= WIN.y1; ++y) {
        for (x = WIN.x0; x <= WIN.x1; ++x) {
            if (abs(x - cx) <= radius && abs(y - cy) <= radius && isfinite(*at(x, y))) {
                sum += expl((long double)(*at(x, y) / infl));
            }
        }
    }
    return sum > 0.0L ? (double)logl(sum) : -(double)INFINITY;
}

static void test_zone_lse_slow(void **state)
{
    static const int32_t c[][3] = {{15, 25, 1}, {22, 28, 1}, {10, 20, 1}, {30, 36, 2},
                                   {18, 30, 0}, {8, 18, 1},  {13, 27, 3}, {5, 5, 1}};
    static const double infl[] = {1.0, 2.7};
    size_t k, m;
    (void)state;
    two_peaks(15, 25, 22, 28);
    for (m = 0; m < 2; ++m) {
        for (k = 0; k < sizeof c / sizeof c[0]; ++k) {
            const double fast = trn_loc_zone_lse_(grid, &WIN, 1, c[k][0], c[k][1], c[k][2],
                                                  infl[m]);
            const double slow = slow_lse(c[k][0], c[k][1], c[k][2], infl[m]);
            if (isinf(slow)) {
                assert_true(isinf(fast) && fast < 0.0);
            } else {
                assert_true(fabs(fast - slow) <= 1e-12 * (1.0 + fabs(slow)));
            }
        }
    }
    /* over heading: three slices of poses, the zone summed over all of them */
    {
        static double g3[3 * W * H];
        for (k = 0; k < (size_t)(W * H); ++k) {
            g3[k] = grid[k];
            g3[W * H + k] = grid[k] - 1.5;
            g3[2 * W * H + k] = grid[(W * H - 1) - k] + 0.25;
        }
        for (m = 0; m < 2; ++m) {
            for (k = 0; k < sizeof c / sizeof c[0]; ++k) {
                const double fast = trn_loc_zone_lse_(g3, &WIN, 3, c[k][0], c[k][1], c[k][2],
                                                      infl[m]);
                long double sum = 0.0L;
                int32_t s, x, y;
                for (s = 0; s < 3; ++s) {
                    for (y = WIN.y0; y <= WIN.y1; ++y) {
                        for (x = WIN.x0; x <= WIN.x1; ++x) {
                            const double v = g3[(size_t)s * W * H + (size_t)(y - WIN.y0) * W +
                                                (size_t)(x - WIN.x0)];
                            if (abs(x - c[k][0]) <= c[k][2] && abs(y - c[k][1]) <= c[k][2] &&
                                isfinite(v)) {
                                sum += expl((long double)(v / infl[m]));
                            }
                        }
                    }
                }
                if (sum > 0.0L) {
                    assert_true(fabs(fast - (double)logl(sum)) <= 1e-12 * (1.0 + fabs(fast)));
                } else {
                    assert_true(isinf(fast) && fast < 0.0);
                }
            }
        }
    }
    /* the written-out masses of the two zones */
    assert_true(fabs(trn_loc_zone_lse_(grid, &WIN, 1, 15, 25, 1, 1.0) - log1p(8.0 * exp(-6.0))) <
                1e-12);
    assert_true(fabs(trn_loc_zone_lse_(grid, &WIN, 1, 22, 28, 1, 1.0) -
                     (-0.8 + log1p(8.0 * exp(-0.05)))) < 1e-12);
}

/* The rule with the answer at (ax, ay) refined to (ax + 0.2, ay), ln L all,
 * inflation infl, and basin 0 at (bx, by) refined to (cx, ay) with ln L cll. */
static int rule(int32_t ax, int32_t ay, int32_t bx, int32_t by, double cx, double all, double cll,
                double infl)
{
    trn_loc_basins_t b;
    trn_refine_t cand;
    trn_loc_result_t out;
    memset(&b, 0, sizeof b);
    memset(&cand, 0, sizeof cand);
    memset(&out, 0, sizeof out);
    b.n = 1;
    b.x[0] = bx;
    b.y[0] = by;
    b.ok[0] = 1;
    cand.x = cx;
    cand.y = (double)ay;
    cand.ll = cll;
    out.ix = ax;
    out.iy = ay;
    out.refinement.x = (double)ax + 0.2;
    out.refinement.y = (double)ay;
    out.refinement.ll = all;
    out.refinement.ll_inflation = infl;
    return trn_loc_basin_wins_(grid, &WIN, 1, 1, &b, 0, &cand, out.ix, out.iy, &out.refinement);
}

static void test_basin_wins(void **state)
{
    (void)state;
    two_peaks(15, 25, 21, 25);
    /* refined ln L within the margin: the broad zone's mass decides */
    assert_int_equal(rule(15, 25, 21, 25, 21.1, -100.0, -101.0, 1.0), 2);
    assert_int_equal(rule(15, 25, 21, 25, 21.1, -100.0, -97.5, 1.0), 2);
    /* the answer's refined ln L more than the margin above: no move */
    assert_int_equal(rule(15, 25, 21, 25, 21.1, -100.0, -100.0 - TRN_REFINE_FAR_NATS - 0.01, 1.0),
                     0);
    /* ... but within it over an inflation of 2 */
    assert_int_equal(rule(15, 25, 21, 25, 21.1, -100.0, -100.0 - TRN_REFINE_FAR_NATS - 0.01, 2.0),
                     2);
    /* the basin's refined ln L more than the margin above: it wins outright */
    assert_int_equal(rule(15, 25, 21, 25, 21.1, -100.0, -100.0 + TRN_REFINE_FAR_NATS + 0.01, 1.0),
                     1);
    /* refined back within TRN_FAIL_RADIUS_CELLS of the answer: never */
    assert_int_equal(rule(15, 25, 21, 25, 15.2 + TRN_FAIL_RADIUS_CELLS - 0.01, -100.0, -99.0, 1.0),
                     0);
    /* the broad zone the answer, the sharp one the basin: its mass is less */
    assert_int_equal(rule(21, 25, 15, 25, 15.1, -100.0, -99.0, 1.0), 0);
    /* an inflation flattens both: at 50 the sharp zone's 9 poses nearly
     * equal the broad one's, e^(-0.8/50) (1 + 8 e^(-0.001)) against
     * 1 + 8 e^(-0.12): the broad zone still holds more */
    assert_int_equal(rule(15, 25, 21, 25, 21.1, -100.0, -101.0, 50.0), 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_zone_lse_slow),
        cmocka_unit_test(test_basin_wins),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
