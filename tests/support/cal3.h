/* SPDX-License-Identifier: Apache-2.0 */
/* cal3.h - tallying a localization over (x, y, heading) against its truth for
 * the calibration tests (tests/test_heading.c, tests/test_height_heading.c). */
#ifndef TRN_TEST_CAL3_H
#define TRN_TEST_CAL3_H

#include "trn/heading.h"

/* res against the truth (rx, ry global cells, delta rad; cell metres): 0 when
 * its position is more than 1.5 cells off (wrong, nothing counted); else 1,
 * and ch[k] counts the heading error within k+1 sigma_heading, cp[k] the
 * position error inside the (k+1)-sigma ellipse of cov3's position block
 * (squared Mahalanobis distance under (k+1)^2). */
int cal3_tally(const trn_heading_result_t *res, double rx, double ry, double delta, double cell,
               int ch[3], int cp[3]);

#endif /* TRN_TEST_CAL3_H */
