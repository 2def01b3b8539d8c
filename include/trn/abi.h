/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file abi.h
 * @brief Does the caller's view of the public structs match the library's?
 *
 * Compile-time maxima in trn_config.h size public structs. A file compiled
 * with another configuration than the library (TRN_USER_CONFIG_H set for
 * one and not the other) would pass structs of the wrong size without any
 * diagnostic. TRN_ABI_CHECK() compares this file's sizes with the library's;
 * call it once at start-up.
 */
#ifndef TRN_ABI_H
#define TRN_ABI_H

#include <stddef.h>

#include "trn/kernels.h"
#include "trn/likelihood.h"
#include "trn/localize.h"
#include "trn/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/**
 * @brief Compare struct sizes as a caller sees them with the library's.
 * @retval TRN_OK       every size matches
 * @retval TRN_E_SIZE   at least one differs: the caller and the library
 *                      were built with different trn_config.h values
 */
trn_status_t trn_abi_check(size_t kernels_bytes, size_t lnp_table_bytes, size_t pyramid_bytes,
                           size_t map_bytes);

/** trn_abi_check with this file's sizes. */
#define TRN_ABI_CHECK() \
    trn_abi_check(sizeof(trn_kernels_t), sizeof(trn_lnp_table_t), sizeof(trn_pyramid_t), \
                  sizeof(trn_map_t))

#ifdef __cplusplus
}
#endif
#endif /* TRN_ABI_H */
