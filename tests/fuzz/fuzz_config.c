/* fuzz_config.c - configuration and view validation with arbitrary values:
 * trn_terrain_cfg_check, trn_lik_cfg_check, trn_map_cfg_check, the grid and
 * volume view checks and constructors, and the sizing functions
 * (trn_highpass_workspace_bytes, trn_pyramid_bytes, trn_map_bytes). They take
 * numbers straight from a configuration file or a link, so they must accept
 * every bit pattern: no UB (UBSan aborts on signed overflow, bad shifts,
 * float-to-int overflow), and a size only for a configuration that checks OK. */
#include <stdlib.h>

#include "fuzz_input.h"
#include "trn/trn.h"

#define FZ_CHECK(c) do { if (!(c)) { abort(); } } while (0)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_t f = { data, size };
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
    FZ_CHECK((bytes > 0u) == (st == TRN_OK && w >= 1 && h >= 1 && w <= TRN_MAX_DIM && h <= TRN_MAX_DIM));
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
    return 0;
}
