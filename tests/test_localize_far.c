/* SPDX-License-Identifier: Apache-2.0 */
/* test_localize_far.c - the far basins' rule (internal: trn_loc_far_wins_ of
 * src/localize_basins.c; docs/method.md 9, "Which basin is the answer").
 *
 * Oracle: the rule written out. A far basin refined to (cx, cy) with ln L
 * cll replaces the answer at (ax, ay) with ln L all exactly when it ends
 * more than TRN_FAIL_RADIUS_CELLS from the answer (Euclidean) and
 * (cll - all) exceeds TRN_REFINE_FAR_NATS times max(1, infl). Checked on
 * either side of each threshold: the distance (just inside and just
 * outside the radius, along an axis and a diagonal), the margin (just under
 * and just over), the inflation (below 1 counts as 1; 2.5 scales the
 * margin), and a basin that came back into the answer's radius with any
 * ln L (no move).
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>

#include "localize_int.h"

static int slow(double cx, double cy, double cll, double ax, double ay, double all, double infl)
{
    const double d = sqrt((cx - ax) * (cx - ax) + (cy - ay) * (cy - ay));
    const double f = infl > 1.0 ? infl : 1.0;
    return d > TRN_FAIL_RADIUS_CELLS && (cll - all) > TRN_REFINE_FAR_NATS * f;
}

static void test_far_wins_rule(void **state)
{
    /* offsets from the answer at (40.3, 22.7): just inside and outside the
     * radius along x, on a diagonal, and far */
    const double r = TRN_FAIL_RADIUS_CELLS, e = 1e-9, s = sqrt(0.5);
    const double off[6][2] = {{r - e, 0.0},
                              {r + e, 0.0},
                              {0.0, -(r + e)},
                              {(r - e) * s, (r - e) * s},
                              {(r + e) * s, -(r + e) * s},
                              {7.0, 3.0}};
    const double infl[4] = {0.5, 1.0, 2.5, 40.0};
    const double ax = 40.3, ay = 22.7, all = -1234.5;
    int i, j, k, moves = 0, n = 0;
    (void)state;
    for (i = 0; i < 6; ++i) {
        for (j = 0; j < 4; ++j) {
            const double f = infl[j] > 1.0 ? infl[j] : 1.0;
            const double margins[5] = {-10.0, 0.0, TRN_REFINE_FAR_NATS * f - 1e-6,
                                       TRN_REFINE_FAR_NATS * f + 1e-6, 500.0};
            for (k = 0; k < 5; ++k) {
                const double cx = ax + off[i][0], cy = ay + off[i][1], cll = all + margins[k];
                const int want = slow(cx, cy, cll, ax, ay, all, infl[j]);
                assert_int_equal(trn_loc_far_wins_(cx, cy, cll, ax, ay, all, infl[j]), want);
                moves += want;
                ++n;
            }
        }
    }
    /* the oracle itself splits the cases: 4 of the 6 offsets are beyond the
     * radius, 2 of the 5 margins beyond the threshold at every inflation */
    assert_int_equal(n, 120);
    assert_int_equal(moves, 4 * 4 * 2);
    /* back in the answer's own basin: no move, whatever its ln L */
    assert_int_equal(trn_loc_far_wins_(ax + 0.5, ay - 0.5, all + 1e6, ax, ay, all, 1.0), 0);
    /* the written-out thresholds */
    assert_int_equal(trn_loc_far_wins_(ax + 2.0, ay, all + 3.5, ax, ay, all, 1.0), 1);
    assert_int_equal(trn_loc_far_wins_(ax + 2.0, ay, all + 3.5, ax, ay, all, 2.0), 0);
    assert_int_equal(trn_loc_far_wins_(ax + 2.0, ay, all + 6.5, ax, ay, all, 2.0), 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_far_wins_rule),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
