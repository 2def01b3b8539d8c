/* SPDX-License-Identifier: Apache-2.0 */
/* fuzz_peakfit.c - trn_peak_fit on arbitrary 3x3 patches of doubles (NaN,
 * inf, huge, subnormal) and trn_failure_probability on arbitrary pairs.
 * Invariants: only documented statuses; on TRN_OK finite positive variances,
 * |rho| < 1, |dx|, |dy| <= 1; on TRN_E_ILLCOND infinite sigmas; p in [0, 1]. */
#include <math.h>
#include <stdlib.h>

#include "fuzz_input.h"
#include "trn/trn.h"

#define FZ_CHECK(c) \
    do { \
        if (!(c)) { \
            abort(); \
        } \
    } while (0)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_t f = {data, size};
    double ll[9], p = -1.0, a, b;
    trn_peak_t pk;
    trn_status_t st;
    int i;

    for (i = 0; i < 9; ++i) {
        ll[i] = fz_f64(&f);
    }
    st = trn_peak_fit(ll, &pk);
    FZ_CHECK(st == TRN_OK || st == TRN_E_ARG || st == TRN_E_ILLCOND);
    if (st == TRN_OK) {
        FZ_CHECK(isfinite(pk.var_x) && pk.var_x > 0.0 && isfinite(pk.var_y) && pk.var_y > 0.0);
        FZ_CHECK(isfinite(pk.sigma_x) && isfinite(pk.sigma_y));
        FZ_CHECK(fabs(pk.rho) < 1.0 && fabs(pk.dx) <= 1.0 && fabs(pk.dy) <= 1.0);
    } else if (st == TRN_E_ILLCOND) {
        FZ_CHECK(isinf(pk.sigma_x) && isinf(pk.sigma_y));
    }
    a = fz_f64(&f);
    b = fz_f64(&f);
    st = trn_failure_probability(a, b, &p);
    FZ_CHECK(st == TRN_OK || st == TRN_E_ARG);
    if (st == TRN_OK) {
        FZ_CHECK(p >= 0.0 && p <= 1.0);
    }
    return 0;
}
