/* SPDX-License-Identifier: Apache-2.0 */
/* selworld.c - see selworld.h. */
#define _POSIX_C_SOURCE 200112L
#include "selworld.h"

#include <stdlib.h>
#include <string.h>

void *selworld_alloc(size_t bytes)
{
    void *p = NULL;
    if (posix_memalign(&p, 16u, bytes == 0u ? 16u : bytes) != 0) {
        return NULL;
    }
    return p;
}

trn_status_t selworld_init(selworld_t *w, int32_t n, const float *dem, const trn_sigma_model_t *gm,
                           const trn_xy_t *sensors, size_t ns)
{
    trn_status_t st;
    size_t mb, wb, nvox;
    void *ws;
    memset(w, 0, sizeof *w);
    w->n = n;
    w->dem = (float *)malloc(sizeof(float) * (size_t)n * (size_t)n);
    if (w->dem == NULL) {
        return TRN_E_WORKSPACE;
    }
    memcpy(w->dem, dem, sizeof(float) * (size_t)n * (size_t)n);
    if ((st = trn_grid_f32_init(&w->g, w->dem, (size_t)n * (size_t)n, n, n)) != TRN_OK) {
        return st;
    }
    trn_map_cfg_default(&w->cfg);
    mb = trn_map_bytes(&w->cfg, n, n);
    w->mapbuf = selworld_alloc(mb);
    if (w->mapbuf == NULL) {
        return TRN_E_WORKSPACE;
    }
    if ((st = trn_map_build(&w->map, &w->cfg, &w->g, w->mapbuf, mb)) != TRN_OK) {
        return st;
    }
    if ((st = trn_kernels_build(&w->k, TRN_KERNEL_SIGMA0_DEFAULT_CELLS)) != TRN_OK) {
        return st;
    }
    nvox = (size_t)n * (size_t)n * (size_t)w->map.dist.nz;
    w->pgdata = (float *)selworld_alloc(nvox * sizeof(float));
    wb = trn_prob_global_workspace_bytes(n, n);
    ws = selworld_alloc(wb);
    if (w->pgdata == NULL || ws == NULL) {
        free(ws);
        return TRN_E_WORKSPACE;
    }
    w->pg.data = w->pgdata;
    w->pg.nx = n;
    w->pg.ny = n;
    w->pg.nz = w->map.dist.nz;
    st = trn_prob_global_map(&w->k, gm, sensors, ns, &w->map, &w->pg, ws, wb);
    free(ws);
    return st;
}

void selworld_free(selworld_t *w)
{
    free(w->dem);
    free(w->mapbuf);
    free(w->pgdata);
    memset(w, 0, sizeof *w);
}
