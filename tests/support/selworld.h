/* SPDX-License-Identifier: Apache-2.0 */
/* selworld.h - a prepared global map with its eq. 8 probability map, for the
 * landmark-selection tests (heap memory; not core). Test-only: what the tools
 * share with the tests is tools/support/. */
#ifndef TRN_TEST_SELWORLD_H
#define TRN_TEST_SELWORLD_H
#include "trn/trn.h"

typedef struct {
    int32_t n;  /* map side, cells */
    float *dem; /* n x n heights */
    trn_grid_f32_t g;
    trn_map_cfg_t cfg; /* trn_map_cfg_default */
    trn_map_t map;
    void *mapbuf;
    trn_kernels_t k; /* sigma_0 = TRN_KERNEL_SIGMA0_DEFAULT_CELLS */
    float *pgdata;
    trn_vol_f32_t pg; /* eq. 8 */
} selworld_t;

/* Build from dem (n x n, copied): map, kernels, P_G with the global model gm
 * and the given sensing positions. Returns a trn status (TRN_E_WORKSPACE on
 * out of memory). */
trn_status_t selworld_init(selworld_t *w, int32_t n, const float *dem, const trn_sigma_model_t *gm,
                           const trn_xy_t *sensors, size_t ns);
void selworld_free(selworld_t *w);

/* Aligned heap block (16 bytes); free with free(). */
void *selworld_alloc(size_t bytes);
#endif
