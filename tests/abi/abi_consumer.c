/* SPDX-License-Identifier: Apache-2.0 */
/* abi_consumer.c - a program built against a trn library with a user
 * configuration (tests/abi/user_opts.h). Compiled twice:
 *   abi_agree     through the library target, so with its PUBLIC
 *                 TRN_USER_CONFIG_H: TRN_ABI_CHECK() must say TRN_OK and the
 *                 maxima must be the user's;
 *   abi_disagree  linked to the same archive but compiled without the
 *                 configuration (the mistake trn/abi.h guards against):
 *                 TRN_ABI_CHECK() must say TRN_E_SIZE.
 * Exit status 0 when the expectation (EXPECT_AGREE 1 or 0) holds. */
#include <stdio.h>

#include "trn/trn.h"

int main(void)
{
    trn_status_t st = TRN_ABI_CHECK();
#if EXPECT_AGREE
    if (TRN_KERNEL_MAX_RADIUS != 32 || TRN_CHAMFER_CAP_MAX != 120 || TRN_MAX_LEVELS != 4) {
        printf("abi_agree: the user configuration did not reach this file\n");
        return 1;
    }
    if (st != TRN_OK) {
        printf("abi_agree: TRN_ABI_CHECK() = %s, expected TRN_OK\n", trn_strerror(st));
        return 1;
    }
#else
    if (TRN_KERNEL_MAX_RADIUS != 64) {
        printf("abi_disagree: expected the default configuration here\n");
        return 1;
    }
    if (st != TRN_E_SIZE) {
        printf("abi_disagree: TRN_ABI_CHECK() = %s, expected TRN_E_SIZE\n", trn_strerror(st));
        return 1;
    }
#endif
    printf("ok: TRN_ABI_CHECK() = %s, sizeof(trn_map_t) = %lu here\n", trn_strerror(st),
           (unsigned long)sizeof(trn_map_t));
    return 0;
}
