/* SPDX-License-Identifier: Apache-2.0 */
/* fuzz_terrain.c - the DEM-to-occupancy path with arbitrary heights and
 * configurations: trn_highpass -> trn_occupancy -> trn_occupancy_points on a
 * DEM of up to 24 x 24 cells whose heights are raw float bit patterns (NaN,
 * +-inf, subnormals, +-3.4e38). Invariants: only documented statuses; the
 * filtered grid holds finite values or NaN (never inf); occupancy voxels are
 * 0/1 and their count matches n_occupied and the point list; points lie in
 * the grid relative to the rover cell. */
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
#define MAXW 24
#define MAXZ 16

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_t f = {data, size};
    static float dem_buf[MAXW * MAXW], hp_buf[MAXW * MAXW];
    TRN_WORKSPACE_DECLARE(ws, ((MAXW * MAXW * 16 + 4096) / sizeof(double)) * sizeof(double));
    static uint8_t occ_buf[MAXW * MAXW * MAXZ];
    static trn_point_t pts[MAXW * MAXW * MAXZ];
    trn_terrain_cfg_t cfg;
    trn_grid_f32_t dem, hp;
    trn_vol_u8_t occ;
    trn_status_t st;
    uint32_t n_occ = 0u, count = 0u;
    size_t n_pts = 0u, i, wsb;
    int32_t w = fz_range(&f, 1, MAXW), h = fz_range(&f, 1, MAXW), x, y, rx, ry;

    cfg.cell_m = fz_f32(&f);
    cfg.zbin_m = fz_f32(&f);
    cfg.highpass_half_m = fz_f32(&f);
    cfg.nz = fz_range(&f, 0, MAXZ + 1);
    rx = fz_i32(&f) % (2 * MAXW);
    ry = fz_i32(&f) % (2 * MAXW);
    if (fz_u8(&f) & 1u) {
        /* A sane configuration half the time, so the filter itself is reached. */
        cfg.cell_m = 0.1f;
        cfg.zbin_m = 0.1f;
        cfg.highpass_half_m = 0.1f * (float)fz_range(&f, 1, 8);
        cfg.nz = fz_range(&f, 1, MAXZ);
    }
    for (i = 0; i < (size_t)w * (size_t)h; ++i) {
        dem_buf[i] = fz_f32(&f);
    }
    FZ_CHECK(trn_grid_f32_init(&dem, dem_buf, MAXW * MAXW, w, h) == TRN_OK);
    FZ_CHECK(trn_grid_f32_init(&hp, hp_buf, MAXW * MAXW, w, h) == TRN_OK);
    wsb = trn_highpass_workspace_bytes(w, h);
    FZ_CHECK(wsb > 0u && wsb <= sizeof ws);

    st = trn_highpass(&dem, &cfg, &hp, ws, wsb);
    FZ_CHECK(fz_status_known(st));
    if (st != TRN_OK) {
        return 0;
    }
    for (i = 0; i < (size_t)w * (size_t)h; ++i) {
        FZ_CHECK(!isinf(hp_buf[i]));
    }
    FZ_CHECK(trn_vol_u8_init(&occ, occ_buf, sizeof occ_buf, w, h, cfg.nz) == TRN_OK);
    st = trn_occupancy(&hp, &cfg, &occ, &n_occ);
    FZ_CHECK(st == TRN_OK || st == TRN_E_NODATA);
    for (i = 0; i < (size_t)w * (size_t)h * (size_t)cfg.nz; ++i) {
        FZ_CHECK(occ_buf[i] <= 1u);
        count += occ_buf[i];
    }
    FZ_CHECK(count == n_occ);
    st = trn_occupancy_points(&hp, &cfg, rx, ry, pts, sizeof pts / sizeof pts[0], &n_pts);
    FZ_CHECK(fz_status_known(st));
    if (st == TRN_OK) {
        FZ_CHECK(n_pts == (size_t)n_occ);
        for (i = 0; i < n_pts; ++i) {
            x = rx + pts[i].x;
            y = ry + pts[i].y;
            FZ_CHECK(x >= 0 && x < w && y >= 0 && y < h && pts[i].z >= 0 && pts[i].z < cfg.nz);
            FZ_CHECK(occ_buf[TRN_VOL_IDX(&occ, x, y, pts[i].z)] == 1u);
        }
    }
    return 0;
}
