/* SPDX-License-Identifier: Apache-2.0 */
/* abi.c - the library's struct sizes against a caller's (see trn/abi.h). */
#include "trn/abi.h"

trn_status_t trn_abi_check(size_t kernels_bytes, size_t lnp_table_bytes, size_t pyramid_bytes,
                           size_t map_bytes)
{
    if (kernels_bytes != sizeof(trn_kernels_t) || lnp_table_bytes != sizeof(trn_lnp_table_t) ||
        pyramid_bytes != sizeof(trn_pyramid_t) || map_bytes != sizeof(trn_map_t)) {
        return TRN_E_SIZE;
    }
    return TRN_OK;
}
