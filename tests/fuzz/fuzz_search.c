/* SPDX-License-Identifier: Apache-2.0 */
/* fuzz_search.c - differential fuzzing of the matcher: an arbitrary
 * occupancy volume (up to 16 x 16 x 8, one bit per voxel from the input) ->
 * trn_chamfer3d -> trn_outlier_density -> trn_lnp_table_build ->
 * trn_pyramid_build, then an arbitrary point list (up to 32 points, z possibly
 * out of range), window and exclusion zone searched both exhaustively and by
 * branch-and-bound. Invariants: only documented statuses; both searches
 * return the same status, and on TRN_OK the same pose and score (likelihood.h
 * promises bit-identical results), the pose inside the window and outside the
 * exclusion zone, its score equal to trn_score_pose at that pose. */
#include <stdlib.h>

#include "fuzz_input.h"
#include "trn/trn.h"

#define FZ_CHECK(c) \
    do { \
        if (!(c)) { \
            abort(); \
        } \
    } while (0)
#define MAXXY 16
#define MAXZ 8
#define MAXP 32

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_t f = {data, size};
    static uint8_t occ_buf[MAXXY * MAXXY * MAXZ], dist_buf[MAXXY * MAXXY * MAXZ];
    TRN_WORKSPACE_DECLARE(pyr_buf, 1 << 18);
    TRN_WORKSPACE_DECLARE(ws, 1 << 16);
    trn_vol_u8_t occ, dist;
    trn_lik_cfg_t cfg;
    trn_lnp_table_t t;
    trn_pyramid_t p;
    trn_point_t pts[MAXP];
    trn_window_t win;
    trn_exclusion_t ex;
    const trn_exclusion_t *exp_;
    trn_best_t b1, b2;
    trn_status_t s1, s2, st;
    double k;
    int64_t sc;
    size_t i, n, nv, wsb;
    const int32_t nx = fz_range(&f, 1, MAXXY), ny = fz_range(&f, 1, MAXXY),
                  nz = fz_range(&f, 1, MAXZ);
    const int32_t levels = fz_range(&f, 1, 4);

    cfg.cell_m = 0.1f;
    cfg.sigma_m = 0.05f * (float)fz_range(&f, 1, 8);
    cfg.inlier_prob = 0.05f + 0.1f * (float)fz_range(&f, 0, 9);
    cfg.cap = (uint8_t)fz_range(&f, 3, 60);
    nv = (size_t)nx * (size_t)ny * (size_t)nz;
    for (i = 0; i < nv; i += 8u) {
        const uint8_t bits = fz_u8(&f);
        size_t j;
        for (j = 0; j < 8u && i + j < nv; ++j) {
            occ_buf[i + j] = (uint8_t)((bits >> j) & 1u);
        }
    }
    FZ_CHECK(trn_vol_u8_init(&occ, occ_buf, sizeof occ_buf, nx, ny, nz) == TRN_OK);
    FZ_CHECK(trn_vol_u8_init(&dist, dist_buf, sizeof dist_buf, nx, ny, nz) == TRN_OK);
    st = trn_chamfer3d(&occ, &dist, cfg.cap);
    FZ_CHECK(st == TRN_OK || st == TRN_E_NODATA);
    for (i = 0; i < nv; ++i) {
        FZ_CHECK(dist_buf[i] <= cfg.cap && ((dist_buf[i] == 0u) == (occ_buf[i] != 0u)));
    }
    if (st == TRN_E_NODATA) {
        /* An empty map has no matcher: K may underflow to 0, and
         * trn_lnp_table_build rightly refuses it (trn_map_build stops here). */
        FZ_CHECK(trn_outlier_density(&dist, &cfg, &k) == TRN_OK && k >= 0.0);
        return 0;
    }
    FZ_CHECK(trn_outlier_density(&dist, &cfg, &k) == TRN_OK);
    st = trn_lnp_table_build(&t, &cfg, k);
    FZ_CHECK(st == TRN_OK);
    FZ_CHECK(trn_pyramid_bytes(nx, ny, nz, levels) <= sizeof pyr_buf);
    FZ_CHECK(trn_pyramid_build(&p, &dist, cfg.cap, levels, pyr_buf, sizeof pyr_buf) == TRN_OK);

    n = (size_t)fz_range(&f, 0, MAXP);
    for (i = 0; i < n; ++i) {
        pts[i].x = (int16_t)fz_range(&f, -MAXXY, MAXXY);
        pts[i].y = (int16_t)fz_range(&f, -MAXXY, MAXXY);
        pts[i].z = (int16_t)fz_range(&f, -1, MAXZ);
    }
    win.x0 = fz_range(&f, -1, MAXXY);
    win.y0 = fz_range(&f, -1, MAXXY);
    win.x1 = win.x0 + fz_range(&f, -1, MAXXY);
    win.y1 = win.y0 + fz_range(&f, -1, MAXXY);
    ex.cx = fz_range(&f, -2, MAXXY + 2);
    ex.cy = fz_range(&f, -2, MAXXY + 2);
    ex.radius = fz_range(&f, -1, 6);
    exp_ = (fz_u8(&f) & 1u) ? &ex : NULL;

    s1 = trn_search_exhaustive(&dist, &t, pts, n, &win, exp_, &b1, NULL);
    wsb = trn_search_bb_workspace_bytes(&p, &win);
    FZ_CHECK(wsb <= sizeof ws);
    s2 = trn_search_bb(&p, &t, pts, n, &win, exp_, ws, sizeof ws, &b2, NULL);
    FZ_CHECK(fz_status_known(s1) && fz_status_known(s2));
    FZ_CHECK(s1 == s2);
    if (s1 == TRN_OK) {
        FZ_CHECK(b1.x == b2.x && b1.y == b2.y && b1.score == b2.score);
        FZ_CHECK(b1.x >= win.x0 && b1.x <= win.x1 && b1.y >= win.y0 && b1.y <= win.y1);
        if (exp_ != NULL) {
            FZ_CHECK(abs(b1.x - ex.cx) > ex.radius || abs(b1.y - ex.cy) > ex.radius);
        }
        FZ_CHECK(trn_score_pose(&dist, &t, pts, n, b1.x, b1.y, &sc) == TRN_OK && sc == b1.score);
    }
    return 0;
}
