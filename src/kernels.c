/* SPDX-License-Identifier: Apache-2.0 */
/* kernels.c - the ten sqrt(2)-spaced Gaussian kernels (see trn/kernels.h). */
#include "trn/kernels.h"

#include <math.h>
#include <stddef.h>

trn_status_t trn_kernels_build(trn_kernels_t *k, float sigma0_cells)
{
    const double s2 = sqrt(2.0);
    double s;
    int32_t j, i;

    if (k == NULL) {
        return TRN_E_NULL;
    }
    if (!(sigma0_cells >= 0.05f) || !isfinite(sigma0_cells)) {
        return TRN_E_ARG;
    }
    s = (double)sigma0_cells * pow(s2, (double)(TRN_KERNEL_COUNT - 1));
    if (ceil((double)TRN_KERNEL_TRUNC_SIGMAS * s) > (double)TRN_KERNEL_MAX_RADIUS) {
        return TRN_E_ARG;
    }
    k->sigma0_cells = sigma0_cells;
    for (j = 0; j < TRN_KERNEL_COUNT; ++j) {
        double sum = 0.0, w[2 * TRN_KERNEL_MAX_RADIUS + 1];
        int32_t r;
        s = (double)sigma0_cells * pow(2.0, 0.5 * (double)j);
        r = (int32_t)ceil((double)TRN_KERNEL_TRUNC_SIGMAS * s);
        k->sigma_cells[j] = (float)s;
        k->radius[j] = r;
        for (i = 0; i < 2 * TRN_KERNEL_MAX_RADIUS + 1; ++i) {
            const int32_t d = i - TRN_KERNEL_MAX_RADIUS;
            w[i] = (d >= -r && d <= r) ? exp(-(double)d * (double)d / (2.0 * s * s)) : 0.0;
            sum += w[i];
        }
        for (i = 0; i < 2 * TRN_KERNEL_MAX_RADIUS + 1; ++i) {
            k->taps[j][i] = (float)(w[i] / sum);
        }
        if (j < TRN_KERNEL_COUNT - 1) {
            k->bound_cells[j] = (float)((double)sigma0_cells * pow(2.0, 0.5 * ((double)j + 0.5)));
        }
    }
    return TRN_OK;
}

int32_t trn_kernel_pick(const trn_kernels_t *k, float sigma_cells)
{
    int32_t j = 0;
    while (j < TRN_KERNEL_COUNT - 1 && sigma_cells > k->bound_cells[j]) {
        ++j;
    }
    return j;
}
