/* SPDX-License-Identifier: Apache-2.0 */
/* user_opts.h - an integrator's trn configuration for the ABI tests
 * (tests/abi/CMakeLists.txt): maxima other than trn_config.h's defaults,
 * each of which changes the size of a public struct. */
#ifndef TRN_TEST_USER_OPTS_H
#define TRN_TEST_USER_OPTS_H

#define TRN_KERNEL_MAX_RADIUS 32 /* trn_kernels_t */
#define TRN_CHAMFER_CAP_MAX 120  /* trn_lnp_table_t */
#define TRN_MAX_LEVELS 4         /* trn_pyramid_t, trn_map_t */

#endif
