/* SPDX-License-Identifier: Apache-2.0 */
/* fuzz_config.c - configuration and view validation with arbitrary values:
 * trn_terrain_cfg_check, trn_lik_cfg_check, trn_map_cfg_check, the grid and
 * volume view checks and constructors, and the sizing functions
 * (trn_highpass_workspace_bytes, trn_pyramid_bytes, trn_map_bytes); then
 * trn_sigma_model_check, trn_kernels_build (taps sum to 1), trn_select_cfg_check
 * with trn_select_max_candidates, trn_field_cfg_check, trn_mast_geom_check. They take
 * numbers straight from a configuration file or a link, so they must accept
 * every bit pattern: no UB (UBSan aborts on signed overflow, bad shifts,
 * float-to-int overflow), and a size only for a configuration that checks OK. */
#include <stdlib.h>

#include "fuzz_input.h"
#include "trn/trn.h"

#define FZ_CHECK(c) \
    do { \
        if (!(c)) { \
            abort(); \
        } \
    } while (0)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_t f = {data, size};
    static float cells[64];
    static uint8_t vox[64];
    trn_map_cfg_t m;
    trn_lik_cfg_t l;
    trn_grid_f32_t g, sub;
    trn_vol_u8_t v;
    trn_status_t st;
    size_t bytes;
    int32_t w, h;

    m.terrain.cell_m = fz_f32(&f);
    m.terrain.zbin_m = fz_f32(&f);
    m.terrain.highpass_half_m = fz_f32(&f);
    m.terrain.nz = fz_i32(&f);
    m.sigma_m = fz_f32(&f);
    m.inlier_prob = fz_f32(&f);
    m.cap = fz_u8(&f);
    m.levels = fz_i32(&f);
    m.min_exclusion_cells = fz_i32(&f);
    w = fz_i32(&f);
    h = fz_i32(&f);

    st = trn_terrain_cfg_check(&m.terrain);
    FZ_CHECK(fz_status_known(st));
    l.cell_m = m.terrain.cell_m;
    l.sigma_m = m.sigma_m;
    l.inlier_prob = m.inlier_prob;
    l.cap = m.cap;
    st = trn_lik_cfg_check(&l);
    FZ_CHECK(fz_status_known(st));

    st = trn_map_cfg_check(&m);
    FZ_CHECK(fz_status_known(st));
    bytes = trn_map_bytes(&m, w, h);
    /* A size is given exactly for a valid configuration and dimensions. */
    FZ_CHECK((bytes > 0u) ==
             (st == TRN_OK && w >= 1 && h >= 1 && w <= TRN_MAX_DIM && h <= TRN_MAX_DIM));
    (void)trn_highpass_workspace_bytes(w, h);
    (void)trn_pyramid_bytes(w, h, m.terrain.nz, m.levels);

    /* Hand-filled views: the check must reject every inconsistent one. */
    g.data = cells;
    g.width = fz_i32(&f);
    g.height = fz_i32(&f);
    g.stride = fz_i32(&f);
    st = trn_grid_f32_check(&g);
    FZ_CHECK(fz_status_known(st));
    if (st == TRN_OK) {
        FZ_CHECK(g.width >= 1 && g.height >= 1 && g.width <= TRN_MAX_DIM &&
                 g.height <= TRN_MAX_DIM && g.stride >= g.width);
        st = trn_grid_f32_sub(&g, fz_i32(&f), fz_i32(&f), fz_i32(&f), fz_i32(&f), &sub);
        FZ_CHECK(fz_status_known(st));
        if (st == TRN_OK) {
            FZ_CHECK(sub.width >= 1 && sub.height >= 1 && sub.stride == g.stride &&
                     sub.data >= g.data);
        }
    }
    st = trn_grid_f32_init(&g, cells, (size_t)fz_u8(&f), fz_i32(&f), fz_i32(&f));
    FZ_CHECK(fz_status_known(st));
    if (st == TRN_OK) {
        FZ_CHECK((size_t)g.width * (size_t)g.height <= 255u);
    }
    v.data = vox;
    v.nx = fz_i32(&f);
    v.ny = fz_i32(&f);
    v.nz = fz_i32(&f);
    FZ_CHECK(fz_status_known(trn_vol_u8_check(&v)));
    st = trn_vol_u8_init(&v, vox, (size_t)fz_u8(&f) % 65u, fz_i32(&f), fz_i32(&f), fz_i32(&f));
    FZ_CHECK(fz_status_known(st));
    if (st == TRN_OK) {
        FZ_CHECK((size_t)v.nx * (size_t)v.ny * (size_t)v.nz <= 64u);
    }
    FZ_CHECK(trn_strerror((trn_status_t)fz_i32(&f)) != NULL);

    /* the configurations of spread, select, field and mast (appended, so
     * the older seed files still mean what they meant) */
    {
        static trn_kernels_t k;
        trn_sigma_model_t sm;
        trn_select_cfg_t sc;
        trn_field_cfg_t fc;
        trn_mast_geom_t mg;
        float cell, *gf = (float *)(void *)&mg;
        size_t i;
        int32_t j;

        sm.sigma_min_m = fz_f32(&f);
        sm.k_per_m = fz_f32(&f);
        st = trn_sigma_model_check(&sm);
        FZ_CHECK(st == TRN_OK || st == TRN_E_ARG);
        if (st == TRN_OK) {
            FZ_CHECK(sm.sigma_min_m >= 0.0f && sm.sigma_min_m <= 1.0e5f && sm.k_per_m >= 0.0f &&
                     sm.k_per_m <= 100.0f);
        }
        st = trn_kernels_build(&k, fz_f32(&f));
        FZ_CHECK(st == TRN_OK || st == TRN_E_ARG);
        if (st == TRN_OK) {
            for (j = 0; j < TRN_KERNEL_COUNT; ++j) {
                double sum = 0.0;
                FZ_CHECK(k.radius[j] >= 1 && k.radius[j] <= TRN_KERNEL_MAX_RADIUS);
                for (i = 0; i < 2u * TRN_KERNEL_MAX_RADIUS + 1u; ++i) {
                    FZ_CHECK(k.taps[j][i] >= 0.0f);
                    sum += (double)k.taps[j][i];
                }
                FZ_CHECK(sum > 1.0 - 1.0e-5 && sum < 1.0 + 1.0e-5);
            }
            FZ_CHECK(trn_kernel_pick(&k, fz_f32(&f)) < TRN_KERNEL_COUNT);
        }
        sc.min_range_m = fz_f32(&f);
        sc.max_range_m = fz_f32(&f);
        sc.pan_min_rad = fz_f32(&f);
        sc.pan_max_rad = fz_f32(&f);
        sc.footprint_radius_m = fz_f32(&f);
        sc.patch_m = fz_f32(&f);
        sc.stride_cells = fz_i32(&f);
        sc.min_separation_m = fz_f32(&f);
        sc.local_sigma = sm;
        sc.sigma_heading_rad = 0.0f; /* read at the end (appended) */
        sc.heading_search = 0;
        cell = fz_f32(&f);
        st = trn_select_cfg_check(&sc, cell);
        FZ_CHECK(st == TRN_OK || st == TRN_E_ARG);
        /* a count only for a configuration that checks OK */
        FZ_CHECK((trn_select_max_candidates(&sc, cell) > 0u) == (st == TRN_OK));
        fc.coarse_step_cells = fz_i32(&f);
        fc.margin_rel = fz_f32(&f);
        fc.change_rel = fz_f32(&f);
        st = trn_field_cfg_check(&fc);
        FZ_CHECK(st == TRN_OK || st == TRN_E_ARG);
        if (st == TRN_OK) {
            FZ_CHECK(fc.coarse_step_cells >= 1 && fc.coarse_step_cells <= 256 &&
                     (fc.coarse_step_cells & (fc.coarse_step_cells - 1)) == 0);
        }
        for (i = 0; i < sizeof mg / sizeof(float); ++i) {
            gf[i] = fz_f32(&f);
        }
        st = trn_mast_geom_check(&mg);
        FZ_CHECK(st == TRN_OK || st == TRN_E_ARG);
        if (st == TRN_OK) {
            FZ_CHECK(mg.pan_min_rad <= mg.pan_max_rad && mg.tilt_min_rad <= mg.tilt_max_rad);
        }
        /* the selection's heading sigma (appended after the mast's geometry) */
        sc.sigma_heading_rad = fz_f32(&f);
        st = trn_select_cfg_check(&sc, cell);
        FZ_CHECK(st == TRN_OK || st == TRN_E_ARG);
        if (st == TRN_OK) {
            FZ_CHECK(sc.sigma_heading_rad >= 0.0f &&
                     sc.sigma_heading_rad <= TRN_SELECT_MAX_SIGMA_HEADING_RAD);
        }
        /* the heading-search flag (appended after the heading sigma) */
        sc.heading_search = fz_i32(&f);
        st = trn_select_cfg_check(&sc, cell);
        FZ_CHECK(st == TRN_OK || st == TRN_E_ARG);
        if (st == TRN_OK) {
            FZ_CHECK(sc.heading_search == 0 || sc.heading_search == 1);
        }
    }
    return 0;
}
