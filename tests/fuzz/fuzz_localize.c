/* SPDX-License-Identifier: Apache-2.0 */
/* fuzz_localize.c - end to end on arbitrary small DEMs: trn_map_build on a
 * global DEM of up to 20 x 20 cells, trn_localize_dem with a local DEM of up
 * to 8 x 8 cells, both of raw float heights (NaN, inf, huge), a fuzzed prior
 * window, rover cell and a few configuration values. Invariants: only
 * documented statuses; on TRN_OK / TRN_E_ILLCOND the best pose lies in the
 * window and the failure probability is in [0, 1]. */
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
#define GW 20
#define LW 8

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_t f = {data, size};
    static float gbuf[GW * GW], lbuf[LW * LW];
    TRN_WORKSPACE_DECLARE(map_buf, 1u << 20);
    TRN_WORKSPACE_DECLARE(ws, 1u << 20);
    trn_map_cfg_t cfg;
    trn_map_t map;
    trn_grid_f32_t g, l;
    trn_window_t win;
    trn_loc_result_t r;
    trn_status_t st;
    size_t need, i;
    int32_t gw = fz_range(&f, 1, GW), gh = fz_range(&f, 1, GW);
    int32_t lw = fz_range(&f, 1, LW), lh = fz_range(&f, 1, LW);
    int32_t rx, ry, maxp;

    trn_map_cfg_default(&cfg);
    cfg.terrain.nz = fz_range(&f, 1, 16);
    cfg.cap = (uint8_t)fz_range(&f, 3, 60);
    cfg.levels = fz_range(&f, 1, 4);
    cfg.min_exclusion_cells = fz_range(&f, 1, 4);
    cfg.terrain.highpass_half_m = 0.1f * (float)fz_range(&f, 1, 6);
    win.x0 = fz_range(&f, -2, GW);
    win.y0 = fz_range(&f, -2, GW);
    win.x1 = win.x0 + fz_range(&f, -1, GW);
    win.y1 = win.y0 + fz_range(&f, -1, GW);
    rx = fz_range(&f, -2, LW + 1);
    ry = fz_range(&f, -2, LW + 1);
    maxp = fz_range(&f, 0, LW * LW * 16);
    for (i = 0; i < (size_t)gw * (size_t)gh; ++i) {
        gbuf[i] = fz_f32(&f);
    }
    for (i = 0; i < (size_t)lw * (size_t)lh; ++i) {
        lbuf[i] = fz_f32(&f);
    }
    FZ_CHECK(trn_grid_f32_init(&g, gbuf, GW * GW, gw, gh) == TRN_OK);
    FZ_CHECK(trn_grid_f32_init(&l, lbuf, LW * LW, lw, lh) == TRN_OK);
    need = trn_map_bytes(&cfg, gw, gh);
    FZ_CHECK(need > 0u && need <= sizeof map_buf);
    st = trn_map_build(&map, &cfg, &g, map_buf, need);
    FZ_CHECK(fz_status_known(st));
    if (st != TRN_OK) {
        return 0;
    }
    need = trn_localize_dem_workspace_bytes(&map, lw, lh, (size_t)maxp, &win);
    if (need == 0u || need > sizeof ws) {
        return 0;
    }
    st = trn_localize_dem(&map, &l, rx, ry, (size_t)maxp, &win, ws, need, &r);
    FZ_CHECK(fz_status_known(st));
    if (st == TRN_OK || st == TRN_E_ILLCOND) {
        FZ_CHECK(r.ix >= win.x0 && r.ix <= win.x1 && r.iy >= win.y0 && r.iy <= win.y1);
        FZ_CHECK(r.failure_probability >= 0.0 && r.failure_probability <= 1.0);
        FZ_CHECK(isfinite(r.ll_best));
    }
    return 0;
}
