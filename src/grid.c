/* SPDX-License-Identifier: Apache-2.0 */
/* grid.c - views over caller memory (see trn/grid.h). */
#include "trn/grid.h"

static int dim_ok(int32_t n, int32_t max) { return n >= 1 && n <= max; }

trn_status_t trn_grid_f32_init(trn_grid_f32_t *g, float *data, size_t capacity, int32_t width,
                               int32_t height)
{
    if (g == NULL || data == NULL) {
        return TRN_E_NULL;
    }
    if (!dim_ok(width, TRN_MAX_DIM) || !dim_ok(height, TRN_MAX_DIM)) {
        return TRN_E_SIZE;
    }
    if (capacity < (size_t)width * (size_t)height) {
        return TRN_E_WORKSPACE;
    }
    g->data = data;
    g->width = width;
    g->height = height;
    g->stride = width;
    return TRN_OK;
}

trn_status_t trn_grid_f32_check(const trn_grid_f32_t *g)
{
    if (g == NULL || g->data == NULL) {
        return TRN_E_NULL;
    }
    if (!dim_ok(g->width, TRN_MAX_DIM) || !dim_ok(g->height, TRN_MAX_DIM) || g->stride < g->width) {
        return TRN_E_SIZE;
    }
    return TRN_OK;
}

trn_status_t trn_grid_f32_sub(const trn_grid_f32_t *g, int32_t x0, int32_t y0, int32_t width,
                              int32_t height, trn_grid_f32_t *sub)
{
    trn_status_t st = trn_grid_f32_check(g);
    if (st != TRN_OK) {
        return st;
    }
    if (sub == NULL) {
        return TRN_E_NULL;
    }
    if (width < 1 || height < 1) {
        return TRN_E_SIZE;
    }
    if (x0 < 0 || y0 < 0 || x0 > g->width - width || y0 > g->height - height) {
        return TRN_E_RANGE;
    }
    sub->data = &TRN_GRID_AT(g, x0, y0);
    sub->width = width;
    sub->height = height;
    sub->stride = g->stride;
    return TRN_OK;
}

trn_status_t trn_vol_u8_init(trn_vol_u8_t *v, uint8_t *data, size_t capacity, int32_t nx,
                             int32_t ny, int32_t nz)
{
    if (v == NULL || data == NULL) {
        return TRN_E_NULL;
    }
    if (!dim_ok(nx, TRN_MAX_DIM) || !dim_ok(ny, TRN_MAX_DIM) || !dim_ok(nz, TRN_MAX_ZBINS)) {
        return TRN_E_SIZE;
    }
    if (capacity < (size_t)nx * (size_t)ny * (size_t)nz) {
        return TRN_E_WORKSPACE;
    }
    v->data = data;
    v->nx = nx;
    v->ny = ny;
    v->nz = nz;
    return TRN_OK;
}

trn_status_t trn_vol_u8_check(const trn_vol_u8_t *v)
{
    if (v == NULL || v->data == NULL) {
        return TRN_E_NULL;
    }
    if (!dim_ok(v->nx, TRN_MAX_DIM) || !dim_ok(v->ny, TRN_MAX_DIM) ||
        !dim_ok(v->nz, TRN_MAX_ZBINS)) {
        return TRN_E_SIZE;
    }
    return TRN_OK;
}
