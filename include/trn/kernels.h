/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file kernels.h
 * @brief The ten truncated 1-D Gaussian kernels of the probability map
 * (paper section 4: "ten precomputed kernels with standard deviations related
 * by powers of sqrt(2)"; method.md 3).
 *
 * Kernel j (j = 0..9) has sigma_j = sigma_0 * sqrt(2)^j cells, radius
 * R_j = ceil(TRN_KERNEL_TRUNC_SIGMAS * sigma_j) taps each side, and taps
 * exp(-i^2 / (2 sigma_j^2)), i = -R_j..R_j, normalized so they sum to 1
 * (the truncated mass is redistributed, so a convolution preserves mass).
 * The table is built once by trn_kernels_build into a caller-owned struct of
 * fixed size (no hidden state). A wanted sigma picks the kernel nearest in
 * log-sigma (trn_kernel_pick): boundaries at sigma_0 * sqrt(2)^(j + 1/2);
 * sigmas below sigma_0 take kernel 0 and above sigma_9 kernel 9 (clamped).
 */
#ifndef TRN_KERNELS_H
#define TRN_KERNELS_H

#include <stdint.h>
#include "trn/status.h"
#include "trn/trn_config.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Number of kernels in the table (the paper's ten). */
#define TRN_KERNEL_COUNT 10

/** Truncation radius in sigmas: R_j = ceil(3 sigma_j) (0.27 % of the mass cut, then renormalized). */
#define TRN_KERNEL_TRUNC_SIGMAS 3

/* The largest kernel radius, TRN_KERNEL_MAX_RADIUS, is in trn_config.h. */

/** Default sigma_0, cells: 0.5 cell, so sigma_9 = 11.3 cells (1.13 m at 0.1 m cells), R_9 = 34. */
#define TRN_KERNEL_SIGMA0_DEFAULT_CELLS 0.5f

/** The kernel table. Tap i of kernel j is taps[j][TRN_KERNEL_MAX_RADIUS + i], zero for |i| > R_j. */
typedef struct {
    float taps[TRN_KERNEL_COUNT][2 * TRN_KERNEL_MAX_RADIUS + 1];
    float sigma_cells[TRN_KERNEL_COUNT]; /**< sigma_j, cells */
    float
        bound_cells[TRN_KERNEL_COUNT - 1]; /**< sigma_0 sqrt(2)^(j+1/2): above it, j+1 is nearer */
    int32_t radius[TRN_KERNEL_COUNT];      /**< R_j, taps each side */
    float sigma0_cells;                    /**< sigma_0 */
} trn_kernels_t;

/**
 * @brief Build the ten kernels for sigma_0 (paper section 4).
 * @param[out] k            the table.
 * @param[in]  sigma0_cells sigma_0 in cells, > 0, with
 *                          ceil(3 sigma_0 sqrt(2)^9) <= TRN_KERNEL_MAX_RADIUS
 *                          (sigma_0 <= 0.94 with the default maximum) and >= 0.05.
 * @retval TRN_OK
 * @retval TRN_E_NULL k is NULL
 * @retval TRN_E_ARG  sigma0_cells NaN, too small or too large
 */
trn_status_t trn_kernels_build(trn_kernels_t *k, float sigma0_cells);

/**
 * @brief Index of the kernel nearest to sigma in log space (clamped to 0..9).
 * No argument check (hot path): k must be built; NaN or sigma <= 0 gives 0.
 * @param[in] k           a built table.
 * @param[in] sigma_cells wanted standard deviation, cells.
 * @return 0..TRN_KERNEL_COUNT-1.
 */
int32_t trn_kernel_pick(const trn_kernels_t *k, float sigma_cells);

#ifdef __cplusplus
}
#endif
#endif /* TRN_KERNELS_H */
