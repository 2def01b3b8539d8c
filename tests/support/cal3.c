/* SPDX-License-Identifier: Apache-2.0 */
/* cal3.c - see cal3.h. */
#include "cal3.h"

#include <math.h>

int cal3_tally(const trn_heading_result_t *res, double rx, double ry, double delta, double cell,
               int ch[3], int cp[3])
{
    double eh = res->heading_rad - delta, ex = (res->loc.x - rx) * cell,
           ey = (res->loc.y - ry) * cell, a = res->cov3[0], b = res->cov3[1], d = res->cov3[4];
    double m2, z;
    int k;
    if (hypot(ex, ey) > 1.5 * cell) {
        return 0;
    }
    m2 = (d * ex * ex - 2.0 * b * ex * ey + a * ey * ey) / (a * d - b * b);
    z = fabs(eh) / res->sigma_heading_rad;
    for (k = 0; k < 3; ++k) {
        ch[k] += z < (double)(k + 1);
        cp[k] += m2 < (double)((k + 1) * (k + 1));
    }
    return 1;
}
