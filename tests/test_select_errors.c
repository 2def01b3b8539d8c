/* SPDX-License-Identifier: Apache-2.0 */
/* test_select_errors.c - every argument check of spread.h, select.h and
 * field.h, one assertion per rejected clause (OSAL style, docs/assurance.md
 * "Coverage"), and the paths the functional tests do not take: a sensor or
 * rover so far away that the spread saturates, a kernel table that was
 * never built, a featureless map for the uncertainty field (no position has
 * an informative target: the field is +inf everywhere). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "selworld.h"
#include "synth.h"

#define CELL 0.1f
#define N 40

static synth_rock_t g_rocks[64];

static void make_world(selworld_t *w, size_t nrocks, double bg)
{
    synth_terrain_t t;
    float *dem = malloc(sizeof(float) * N * N);
    trn_sigma_model_t gm;
    trn_xy_t s = {(float)N / 2.0f, (float)N / 2.0f};
    synth_make(&t, g_rocks, nrocks, N * (double)CELL, 0.05, 0.3, 0.5, bg, 5);
    synth_render(&t, dem, N, N, 0.0, 0.0, (double)CELL);
    trn_sigma_global_default(&gm);
    assert_int_equal(selworld_init(w, N, dem, &gm, &s, 1), TRN_OK);
    free(dem);
}

static void small_cfg(trn_select_cfg_t *c)
{
    trn_select_cfg_default(c);
    c->min_range_m = 0.5f;
    c->max_range_m = 1.2f;
    c->footprint_radius_m = 0.3f;
    c->patch_m = 0.5f;
    c->stride_cells = 2;
    c->min_separation_m = 0.3f;
}

static void test_defaults_ignore_null(void **state)
{
    trn_sigma_model_t m;
    (void)state;
    trn_sigma_global_default(NULL);
    trn_sigma_local_default(NULL);
    trn_select_cfg_default(NULL);
    trn_field_cfg_default(NULL);
    trn_sigma_local_default(&m);
    assert_int_equal(trn_sigma_model_check(&m), TRN_OK);
}

static void test_sigma_model_clauses(void **state)
{
    trn_sigma_model_t m, b;
    (void)state;
    trn_sigma_global_default(&m);
    assert_int_equal(trn_sigma_model_check(&m), TRN_OK);
    b = m;
    b.sigma_min_m = -0.1f;
    assert_int_equal(trn_sigma_model_check(&b), TRN_E_ARG);
    b = m;
    b.sigma_min_m = 1.0e5f;
    assert_int_equal(trn_sigma_model_check(&b), TRN_OK);
    b.sigma_min_m = 1.01e5f;
    assert_int_equal(trn_sigma_model_check(&b), TRN_E_ARG);
    b = m;
    b.k_per_m = -0.1f;
    assert_int_equal(trn_sigma_model_check(&b), TRN_E_ARG);
    b = m;
    b.k_per_m = 100.5f;
    assert_int_equal(trn_sigma_model_check(&b), TRN_E_ARG);
}

static void test_kernel_map_clauses(void **state)
{
    static trn_kernels_t k, kb;
    trn_sigma_model_t m, mb;
    trn_xy_t s[TRN_SPREAD_MAX_SENSORS + 1];
    trn_window_t win = {0, 0, 9, 7}, wb;
    uint8_t idx[80];
    size_t i;
    (void)state;
    assert_int_equal(trn_kernels_build(&k, TRN_KERNEL_SIGMA0_DEFAULT_CELLS), TRN_OK);
    trn_sigma_global_default(&m);
    for (i = 0; i <= TRN_SPREAD_MAX_SENSORS; ++i) {
        s[i].x_cells = 3.0f;
        s[i].y_cells = 4.0f;
    }
#define KM(kk, mm, c, ss, n, ww, ii, il) trn_spread_kernel_map(kk, mm, c, ss, n, ww, ii, il)
    assert_int_equal(KM(&k, &m, CELL, s, 1, &win, idx, 80), TRN_OK);
    assert_int_equal(KM(&k, &m, CELL, NULL, 1, &win, idx, 80), TRN_E_NULL);
    assert_int_equal(KM(&k, &m, CELL, s, 1, NULL, idx, 80), TRN_E_NULL);
    assert_int_equal(KM(&k, &m, CELL, s, 1, &win, NULL, 80), TRN_E_NULL);
    assert_int_equal(KM(NULL, &m, CELL, s, 1, &win, idx, 80), TRN_E_NULL);
    assert_int_equal(KM(&k, NULL, CELL, s, 1, &win, idx, 80), TRN_E_NULL);
    /* a table that was never built, clause by clause */
    kb = k;
    kb.sigma0_cells = 0.0f;
    assert_int_equal(KM(&kb, &m, CELL, s, 1, &win, idx, 80), TRN_E_ARG);
    kb = k;
    kb.radius[TRN_KERNEL_COUNT - 1] = 0;
    assert_int_equal(KM(&kb, &m, CELL, s, 1, &win, idx, 80), TRN_E_ARG);
    kb.radius[TRN_KERNEL_COUNT - 1] = TRN_KERNEL_MAX_RADIUS + 1;
    assert_int_equal(KM(&kb, &m, CELL, s, 1, &win, idx, 80), TRN_E_ARG);
    mb = m;
    mb.k_per_m = NAN;
    assert_int_equal(KM(&k, &mb, CELL, s, 1, &win, idx, 80), TRN_E_ARG);
    assert_int_equal(KM(&k, &m, 0.0f, s, 1, &win, idx, 80), TRN_E_ARG);
    assert_int_equal(KM(&k, &m, TRN_CELL_MAX_M, s, 1, &win, idx, 80), TRN_OK);
    assert_int_equal(KM(&k, &m, nextafterf(TRN_CELL_MAX_M, INFINITY), s, 1, &win, idx, 80),
                     TRN_E_ARG);
    assert_int_equal(KM(&k, &m, CELL, s, 0, &win, idx, 80), TRN_E_SIZE);
    assert_int_equal(KM(&k, &m, CELL, s, TRN_SPREAD_MAX_SENSORS + 1, &win, idx, 80), TRN_E_SIZE);
    wb = win;
    wb.x1 = -1;
    assert_int_equal(KM(&k, &m, CELL, s, 1, &wb, idx, 80), TRN_E_SIZE);
    wb = win;
    wb.y1 = -1;
    assert_int_equal(KM(&k, &m, CELL, s, 1, &wb, idx, 80), TRN_E_SIZE);
    wb = win;
    wb.x1 = TRN_MAX_DIM;
    assert_int_equal(KM(&k, &m, CELL, s, 1, &wb, idx, 80), TRN_E_SIZE);
    wb = win;
    wb.y1 = TRN_MAX_DIM;
    assert_int_equal(KM(&k, &m, CELL, s, 1, &wb, idx, 80), TRN_E_SIZE);
    s[1].x_cells = NAN;
    assert_int_equal(KM(&k, &m, CELL, s, 2, &win, idx, 80), TRN_E_ARG);
    s[1].x_cells = 3.0f;
    s[1].y_cells = INFINITY;
    assert_int_equal(KM(&k, &m, CELL, s, 2, &win, idx, 80), TRN_E_ARG);
    assert_int_equal(KM(&k, &m, CELL, s, 1, &win, idx, 79), TRN_E_WORKSPACE);
    /* a sensor 1e35 cells away: sigma saturates, every cell takes the widest kernel */
    s[1].x_cells = 1.0e35f;
    s[1].y_cells = 0.0f;
    assert_int_equal(KM(&k, &m, CELL, &s[1], 1, &win, idx, 80), TRN_OK);
    for (i = 0; i < 80; ++i) {
        assert_int_equal(idx[i], TRN_KERNEL_COUNT - 1);
    }
#undef KM
}

static void test_prob_global_clauses(void **state)
{
    selworld_t w;
    trn_sigma_model_t m, mb;
    trn_xy_t s[TRN_SPREAD_MAX_SENSORS + 1];
    trn_vol_u8_t occ;
    trn_vol_f32_t pg, pb;
    uint8_t *ob;
    float *pd;
    size_t wsb, i, nv;
    uint8_t *ws;
    (void)state;
    make_world(&w, 8, 0.1);
    trn_sigma_global_default(&m);
    for (i = 0; i <= TRN_SPREAD_MAX_SENSORS; ++i) {
        s[i].x_cells = 20.0f;
        s[i].y_cells = 20.0f;
    }
    nv = (size_t)w.map.dist.nx * (size_t)w.map.dist.ny * (size_t)w.map.dist.nz;
    ob = malloc(nv);
    for (i = 0; i < nv; ++i) {
        ob[i] = (uint8_t)(w.map.dist.data[i] == 0u);
    }
    occ = w.map.dist;
    occ.data = ob;
    pd = malloc(nv * sizeof(float));
    pg = w.pg;
    pg.data = pd;
    wsb = trn_prob_global_workspace_bytes(occ.nx, occ.ny);
    assert_true(wsb > 0u);
    ws = selworld_alloc(wsb + 16u);
    assert_int_equal(trn_prob_global_workspace_bytes(0, 1), 0u);
    assert_int_equal(trn_prob_global_workspace_bytes(1, 0), 0u);
    assert_int_equal(trn_prob_global_workspace_bytes(TRN_MAX_DIM + 1, 1), 0u);
    assert_int_equal(trn_prob_global_workspace_bytes(1, TRN_MAX_DIM + 1), 0u);
#define PGL(ss, n, oo, pp, wp, wb) trn_prob_global(&w.k, &m, CELL, ss, n, oo, pp, wp, wb)
    assert_int_equal(PGL(s, 1, &occ, &pg, ws, wsb), TRN_OK);
    assert_int_equal(PGL(NULL, 1, &occ, &pg, ws, wsb), TRN_E_NULL);
    assert_int_equal(PGL(s, 1, NULL, &pg, ws, wsb), TRN_E_NULL);
    assert_int_equal(PGL(s, 1, &occ, NULL, ws, wsb), TRN_E_NULL);
    assert_int_equal(PGL(s, 1, &occ, &pg, NULL, wsb), TRN_E_NULL);
    pb = pg;
    pb.data = NULL;
    assert_int_equal(PGL(s, 1, &occ, &pb, ws, wsb), TRN_E_NULL);
    assert_int_equal(trn_prob_global(&w.k, &m, 0.0f, s, 1, &occ, &pg, ws, wsb), TRN_E_ARG);
    {
        trn_vol_u8_t ob2 = occ;
        ob2.nz = 0;
        assert_int_not_equal(PGL(s, 1, &ob2, &pg, ws, wsb), TRN_OK);
    }
    pb = pg;
    pb.nx -= 1;
    assert_int_equal(PGL(s, 1, &occ, &pb, ws, wsb), TRN_E_SIZE);
    pb = pg;
    pb.ny -= 1;
    assert_int_equal(PGL(s, 1, &occ, &pb, ws, wsb), TRN_E_SIZE);
    pb = pg;
    pb.nz -= 1;
    assert_int_equal(PGL(s, 1, &occ, &pb, ws, wsb), TRN_E_SIZE);
    assert_int_equal(PGL(s, 0, &occ, &pg, ws, wsb), TRN_E_SIZE);
    assert_int_equal(PGL(s, TRN_SPREAD_MAX_SENSORS + 1, &occ, &pg, ws, wsb), TRN_E_SIZE);
    s[0].y_cells = NAN;
    assert_int_equal(PGL(s, 1, &occ, &pg, ws, wsb), TRN_E_ARG);
    s[0].y_cells = 20.0f;
    assert_int_equal(PGL(s, 1, &occ, &pg, ws, wsb - 1u), TRN_E_WORKSPACE);
    assert_int_equal(PGL(s, 1, &occ, &pg, ws + 1, wsb), TRN_E_WORKSPACE);
#undef PGL
    /* the map form: same checks on the map's distance volume */
#define PGM(mm, n, pp, wp, wb) trn_prob_global_map(&w.k, mm, s, n, &w.map, pp, wp, wb)
    assert_int_equal(PGM(&m, 1, &pg, ws, wsb), TRN_OK);
    mb = m;
    mb.sigma_min_m = -1.0f;
    assert_int_equal(PGM(&mb, 1, &pg, ws, wsb), TRN_E_ARG);
    pb = pg;
    pb.nz -= 1;
    assert_int_equal(PGM(&m, 1, &pb, ws, wsb), TRN_E_SIZE);
    assert_int_equal(PGM(&m, 1, &pg, ws, wsb - 1u), TRN_E_WORKSPACE);
    assert_int_equal(PGM(&m, 1, &pg, ws + 1, wsb), TRN_E_WORKSPACE); /* misaligned */
#undef PGM
    free(ws);
    free(pd);
    free(ob);
    selworld_free(&w);
}

static void test_prob_local_clauses(void **state)
{
    selworld_t w;
    trn_sigma_model_t m;
    trn_window_t roi = {10, 12, 17, 19}, rb;
    trn_vol_f32_t p, pb, gb;
    trn_xy_t rv = {15.0f, 15.0f}, far = {1.0e35f, 0.0f}, bad = {15.0f, NAN};
    static trn_kernels_t kb;
    size_t wsb;
    uint8_t *ws;
    (void)state;
    make_world(&w, 8, 0.1);
    trn_sigma_local_default(&m);
    p.nx = 8;
    p.ny = 8;
    p.nz = w.pg.nz;
    p.data = malloc(sizeof(float) * 64u * (size_t)p.nz);
    wsb = trn_prob_local_workspace_bytes(&w.k, &roi);
    assert_true(wsb > 0u);
    ws = selworld_alloc(wsb + 16u);
    assert_int_equal(trn_prob_local_workspace_bytes(NULL, &roi), 0u);
    assert_int_equal(trn_prob_local_workspace_bytes(&w.k, NULL), 0u);
    kb = w.k;
    kb.radius[TRN_KERNEL_COUNT - 1] = -1;
    assert_int_equal(trn_prob_local_workspace_bytes(&kb, &roi), 0u);
    kb.radius[TRN_KERNEL_COUNT - 1] = TRN_KERNEL_MAX_RADIUS + 1;
    assert_int_equal(trn_prob_local_workspace_bytes(&kb, &roi), 0u);
#define PL(r, gg, ro, pp, wp, wb) trn_prob_local(&w.k, &m, CELL, r, gg, ro, pp, wp, wb)
    assert_int_equal(PL(rv, &w.pg, &roi, &p, ws, wsb), TRN_OK);
    /* a rover far off the map: the saturated (widest) kernel everywhere, still OK */
    assert_int_equal(PL(far, &w.pg, &roi, &p, ws, wsb), TRN_OK);
    assert_int_equal(PL(rv, NULL, &roi, &p, ws, wsb), TRN_E_NULL);
    assert_int_equal(PL(rv, &w.pg, NULL, &p, ws, wsb), TRN_E_NULL);
    assert_int_equal(PL(rv, &w.pg, &roi, NULL, ws, wsb), TRN_E_NULL);
    assert_int_equal(PL(rv, &w.pg, &roi, &p, NULL, wsb), TRN_E_NULL);
    gb = w.pg;
    gb.data = NULL;
    assert_int_equal(PL(rv, &gb, &roi, &p, ws, wsb), TRN_E_NULL);
    pb = p;
    pb.data = NULL;
    assert_int_equal(PL(rv, &w.pg, &roi, &pb, ws, wsb), TRN_E_NULL);
    assert_int_equal(trn_prob_local(NULL, &m, CELL, rv, &w.pg, &roi, &p, ws, wsb), TRN_E_NULL);
    assert_int_equal(PL(bad, &w.pg, &roi, &p, ws, wsb), TRN_E_ARG);
    bad.x_cells = INFINITY;
    bad.y_cells = 1.0f;
    assert_int_equal(PL(bad, &w.pg, &roi, &p, ws, wsb), TRN_E_ARG);
    gb = w.pg;
    gb.nx = 0;
    assert_int_equal(PL(rv, &gb, &roi, &p, ws, wsb), TRN_E_SIZE);
    gb = w.pg;
    gb.ny = 0;
    assert_int_equal(PL(rv, &gb, &roi, &p, ws, wsb), TRN_E_SIZE);
    gb = w.pg;
    gb.nz = 0;
    assert_int_equal(PL(rv, &gb, &roi, &p, ws, wsb), TRN_E_SIZE);
    gb = w.pg;
    gb.nx = TRN_MAX_DIM + 1;
    assert_int_equal(PL(rv, &gb, &roi, &p, ws, wsb), TRN_E_SIZE);
    gb = w.pg;
    gb.ny = TRN_MAX_DIM + 1;
    assert_int_equal(PL(rv, &gb, &roi, &p, ws, wsb), TRN_E_SIZE);
    gb = w.pg;
    gb.nz = TRN_MAX_ZBINS + 1;
    assert_int_equal(PL(rv, &gb, &roi, &p, ws, wsb), TRN_E_SIZE);
    rb = roi;
    rb.x1 = rb.x0 - 1;
    assert_int_equal(PL(rv, &w.pg, &rb, &p, ws, wsb), TRN_E_RANGE);
    rb = roi;
    rb.x0 = -1;
    rb.x1 = 6;
    assert_int_equal(PL(rv, &w.pg, &rb, &p, ws, wsb), TRN_E_RANGE);
    rb = roi;
    rb.y0 = -1;
    rb.y1 = 6;
    assert_int_equal(PL(rv, &w.pg, &rb, &p, ws, wsb), TRN_E_RANGE);
    rb.x0 = N - 4;
    rb.x1 = N + 3;
    rb.y0 = 0;
    rb.y1 = 7;
    assert_int_equal(PL(rv, &w.pg, &rb, &p, ws, wsb), TRN_E_RANGE);
    rb.x0 = 0;
    rb.x1 = 7;
    rb.y0 = N - 4;
    rb.y1 = N + 3;
    assert_int_equal(PL(rv, &w.pg, &rb, &p, ws, wsb), TRN_E_RANGE);
    pb = p;
    pb.nx = 7;
    assert_int_equal(PL(rv, &w.pg, &roi, &pb, ws, wsb), TRN_E_SIZE);
    pb = p;
    pb.ny = 7;
    assert_int_equal(PL(rv, &w.pg, &roi, &pb, ws, wsb), TRN_E_SIZE);
    pb = p;
    pb.nz = p.nz - 1;
    assert_int_equal(PL(rv, &w.pg, &roi, &pb, ws, wsb), TRN_E_SIZE);
    assert_int_equal(PL(rv, &w.pg, &roi, &p, ws, wsb - 1u), TRN_E_WORKSPACE);
    assert_int_equal(PL(rv, &w.pg, &roi, &p, ws + 1, wsb), TRN_E_WORKSPACE);
#undef PL
    free(ws);
    free(p.data);
    selworld_free(&w);
}

static void test_select_cfg_clauses(void **state)
{
    trn_select_cfg_t c, b;
    (void)state;
    small_cfg(&c);
    assert_int_equal(trn_select_cfg_check(&c, CELL), TRN_OK);
    assert_int_equal(trn_select_cfg_check(&c, nextafterf(TRN_CELL_MAX_M, INFINITY)), TRN_E_ARG);
    b = c;
    b.max_range_m = 0.0f;
    assert_int_equal(trn_select_cfg_check(&b, CELL), TRN_E_ARG);
    b.max_range_m = 1.01e6f;
    assert_int_equal(trn_select_cfg_check(&b, 1000.0f), TRN_E_ARG);
    b.max_range_m = 1.0e6f; /* 1000 cells of 1 km, a 5-cell patch: accepted */
    b.patch_m = 5000.0f;
    assert_int_equal(trn_select_cfg_check(&b, 1000.0f), TRN_OK);
    b.patch_m = 5.0f * TRN_CELL_MAX_M; /* the coarsest cell the core takes, a 5-cell patch */
    assert_int_equal(trn_select_cfg_check(&b, TRN_CELL_MAX_M), TRN_OK);
    b = c;
    b.min_range_m = -0.1f;
    assert_int_equal(trn_select_cfg_check(&b, CELL), TRN_E_ARG);
    b = c;
    b.pan_min_rad = -3.2f;
    assert_int_equal(trn_select_cfg_check(&b, CELL), TRN_E_ARG);
    b = c;
    b.pan_max_rad = 3.2f;
    assert_int_equal(trn_select_cfg_check(&b, CELL), TRN_E_ARG);
    b = c;
    b.footprint_radius_m = -0.1f;
    assert_int_equal(trn_select_cfg_check(&b, CELL), TRN_E_ARG);
    b.footprint_radius_m = 1.01e5f;
    assert_int_equal(trn_select_cfg_check(&b, CELL), TRN_E_ARG);
    b = c;
    b.patch_m = 0.0f;
    assert_int_equal(trn_select_cfg_check(&b, CELL), TRN_E_ARG);
    b.patch_m = 1.01e6f;
    assert_int_equal(trn_select_cfg_check(&b, 1000.0f), TRN_E_ARG);
    b = c;
    b.min_separation_m = -0.1f;
    assert_int_equal(trn_select_cfg_check(&b, CELL), TRN_E_ARG);
    b.min_separation_m = 1.01e6f;
    assert_int_equal(trn_select_cfg_check(&b, CELL), TRN_E_ARG);
    b = c;
    b.stride_cells = 65;
    assert_int_equal(trn_select_cfg_check(&b, CELL), TRN_E_ARG);
    /* more than TRN_MAX_DIM cells: the patch, then the reach */
    b = c;
    b.patch_m = 500.0f;
    assert_int_equal(trn_select_cfg_check(&b, CELL), TRN_E_ARG);
    b = c;
    b.max_range_m = 999.0f;
    assert_int_equal(trn_select_cfg_check(&b, CELL), TRN_E_ARG);
}

static void test_select_clauses(void **state)
{
    selworld_t w;
    trn_select_cfg_t cfg;
    trn_rover_t rv = {{20.0f, 20.0f}, 0.0f}, rb;
    trn_candidate_t *c;
    trn_select_result_t res;
    trn_vol_f32_t pb;
    trn_map_t mb;
    static trn_kernels_t kb;
    size_t cap, wsb, rk[4];
    uint8_t *ws;
    (void)state;
    small_cfg(&cfg);
    make_world(&w, 20, 0.1);
    cap = trn_select_max_candidates(&cfg, CELL);
    wsb = trn_select_workspace_bytes(&cfg, &w.map, &w.k);
    assert_true(cap > 0u && wsb > 0u);
    c = malloc(cap * sizeof *c);
    ws = selworld_alloc(wsb + 16u);
    assert_int_equal(trn_select_workspace_bytes(NULL, &w.map, &w.k), 0u);
    assert_int_equal(trn_select_workspace_bytes(&cfg, NULL, &w.k), 0u);
    assert_int_equal(trn_select_workspace_bytes(&cfg, &w.map, NULL), 0u);
    mb = w.map;
    mb.dist.nz = 0;
    assert_int_equal(trn_select_workspace_bytes(&cfg, &mb, &w.k), 0u);
    kb = w.k;
    kb.radius[TRN_KERNEL_COUNT - 1] = -1;
    assert_int_equal(trn_select_workspace_bytes(&cfg, &w.map, &kb), 0u);
#define SEL(mm, pp, r, wp, wb) trn_select(mm, &w.k, pp, &cfg, r, c, cap, rk, 4, &res, wp, wb)
    assert_int_equal(SEL(&w.map, &w.pg, &rv, ws, wsb), TRN_OK);
    pb = w.pg;
    pb.data = NULL;
    assert_int_equal(SEL(&w.map, &pb, &rv, ws, wsb), TRN_E_NULL);
    mb = w.map;
    mb.dist.data = NULL;
    assert_int_equal(SEL(&mb, &w.pg, &rv, ws, wsb), TRN_E_NULL);
    rb = rv;
    rb.pos.x_cells = NAN;
    assert_int_equal(SEL(&w.map, &w.pg, &rb, ws, wsb), TRN_E_ARG);
    rb = rv;
    rb.pos.y_cells = INFINITY;
    assert_int_equal(SEL(&w.map, &w.pg, &rb, ws, wsb), TRN_E_ARG);
    mb = w.map;
    mb.dist.nx = 0;
    assert_int_not_equal(SEL(&mb, &w.pg, &rv, ws, wsb), TRN_OK);
    pb = w.pg;
    pb.nx -= 1;
    assert_int_equal(SEL(&w.map, &pb, &rv, ws, wsb), TRN_E_SIZE);
    pb = w.pg;
    pb.ny -= 1;
    assert_int_equal(SEL(&w.map, &pb, &rv, ws, wsb), TRN_E_SIZE);
    mb = w.map;
    mb.lnp.cap = 0u;
    assert_int_equal(SEL(&mb, &w.pg, &rv, ws, wsb), TRN_E_SIZE);
    rb = rv;
    rb.pos.x_cells = -0.6f;
    assert_int_equal(SEL(&w.map, &w.pg, &rb, ws, wsb), TRN_E_RANGE);
    rb = rv;
    rb.pos.y_cells = -0.6f;
    assert_int_equal(SEL(&w.map, &w.pg, &rb, ws, wsb), TRN_E_RANGE);
    rb = rv;
    rb.pos.y_cells = (float)N - 0.4f;
    assert_int_equal(SEL(&w.map, &w.pg, &rb, ws, wsb), TRN_E_RANGE);
    assert_int_equal(SEL(&w.map, &w.pg, &rv, ws + 1, wsb), TRN_E_WORKSPACE);
    mb = w.map;
    mb.lnp.cap = (uint8_t)(TRN_CHAMFER_CAP_MAX + 1);
    assert_int_equal(SEL(&mb, &w.pg, &rv, ws, wsb), TRN_E_SIZE);
    /* a kernel table that was never built has no workspace size */
    assert_int_equal(trn_select(&w.map, &kb, &w.pg, &cfg, &rv, c, cap, rk, 4, &res, ws, wsb),
                     TRN_E_WORKSPACE);
    assert_int_equal(trn_select(&w.map, &w.k, &w.pg, &cfg, &rv, c, 0u, rk, 4, &res, ws, wsb),
                     TRN_E_CAPACITY);
#undef SEL
    /* more ranks asked than there are separated informative targets: the
     * ranking stops early, each rank at least min_separation from the others */
    {
        size_t *all = malloc(cap * sizeof *all), a, b2;
        double sep = (double)cfg.min_separation_m / (double)CELL;
        assert_int_equal(
            trn_select(&w.map, &w.k, &w.pg, &cfg, &rv, c, cap, all, cap, &res, ws, wsb), TRN_OK);
        assert_true(res.n_ranked >= 1u && res.n_ranked < cap && res.n_ranked <= res.n_informative);
        for (a = 0; a < res.n_ranked; ++a) {
            for (b2 = 0; b2 < a; ++b2) {
                const double ex = (double)(c[all[a]].x - c[all[b2]].x);
                const double ey = (double)(c[all[a]].y - c[all[b2]].y);
                assert_true(ex * ex + ey * ey >= sep * sep);
            }
        }
        free(all);
    }
    free(c);
    free(ws);
    selworld_free(&w);
}

static void test_field_cfg_and_size_clauses(void **state)
{
    trn_field_cfg_t f, b;
    trn_select_cfg_t sc;
    (void)state;
    trn_field_cfg_default(&f);
    assert_int_equal(trn_field_cfg_check(&f), TRN_OK);
    b = f;
    b.coarse_step_cells = 0;
    assert_int_equal(trn_field_cfg_check(&b), TRN_E_ARG);
    b.coarse_step_cells = 512;
    assert_int_equal(trn_field_cfg_check(&b), TRN_E_ARG);
    b = f;
    b.margin_rel = 100.5f;
    assert_int_equal(trn_field_cfg_check(&b), TRN_E_ARG);
    b = f;
    b.change_rel = 100.5f;
    assert_int_equal(trn_field_cfg_check(&b), TRN_E_ARG);
    small_cfg(&sc);
    assert_int_equal(trn_field_workspace_bytes(&sc, NULL, NULL), 0u);
}

static void test_field_clauses_and_featureless(void **state)
{
    selworld_t w;
    trn_select_cfg_t sc;
    trn_field_cfg_t fc;
    trn_field_stats_t st;
    trn_window_t area = {16, 16, 23, 21}, ab;
    trn_grid_f32_t g, gb;
    trn_map_t mb;
    float out[48];
    uint8_t ev[48];
    size_t wsb, i;
    uint8_t *ws;
    (void)state;
    small_cfg(&sc);
    trn_field_cfg_default(&fc);
    fc.coarse_step_cells = 4;
    make_world(&w, 0, 0.0); /* a featureless plain: no informative target anywhere */
    assert_int_equal(trn_grid_f32_init(&g, out, 48, 8, 6), TRN_OK);
    wsb = trn_field_workspace_bytes(&sc, &w.map, &w.k);
    assert_true(wsb > 0u);
    ws = selworld_alloc(wsb + 16u);
#define F(mm, kk, pp, a, o, wp, wb) trn_field(mm, kk, pp, &sc, &fc, 0.0f, a, o, ev, 48, &st, wp, wb)
    assert_int_equal(F(&w.map, &w.k, &w.pg, &area, &g, ws, wsb), TRN_OK);
    assert_true(isinf(st.best_m));
    for (i = 0; i < 48; ++i) {
        assert_true(isinf(out[i]) && out[i] > 0.0f);
    }
    assert_int_equal(F(&w.map, NULL, &w.pg, &area, &g, ws, wsb), TRN_E_NULL);
    assert_int_equal(F(&w.map, &w.k, NULL, &area, &g, ws, wsb), TRN_E_NULL);
    gb = g;
    gb.data = NULL;
    assert_int_not_equal(F(&w.map, &w.k, &w.pg, &area, &gb, ws, wsb), TRN_OK);
    mb = w.map;
    mb.dist.nz = 0;
    assert_int_not_equal(F(&mb, &w.k, &w.pg, &area, &g, ws, wsb), TRN_OK);
    ab = area;
    ab.y1 = ab.y0 - 1;
    assert_int_equal(F(&w.map, &w.k, &w.pg, &ab, &g, ws, wsb), TRN_E_RANGE);
    ab = area;
    ab.x0 = -1;
    ab.x1 = 6;
    assert_int_equal(F(&w.map, &w.k, &w.pg, &ab, &g, ws, wsb), TRN_E_RANGE);
    ab = area;
    ab.y0 = -1;
    ab.y1 = 4;
    assert_int_equal(F(&w.map, &w.k, &w.pg, &ab, &g, ws, wsb), TRN_E_RANGE);
    ab = area;
    ab.y0 = N - 3;
    ab.y1 = N + 2;
    assert_int_equal(F(&w.map, &w.k, &w.pg, &ab, &g, ws, wsb), TRN_E_RANGE);
    gb = g;
    gb.height = 5;
    assert_int_equal(F(&w.map, &w.k, &w.pg, &area, &gb, ws, wsb), TRN_E_SIZE);
    /* one column and one row wide: the fill has no interval to interpolate over */
    ab = area;
    ab.x1 = ab.x0;
    assert_int_equal(trn_grid_f32_init(&gb, out, 48, 1, 6), TRN_OK);
    assert_int_equal(F(&w.map, &w.k, &w.pg, &ab, &gb, ws, wsb), TRN_OK);
    assert_true(isinf(out[0]) && isinf(out[5]));
    ab = area;
    ab.y1 = ab.y0;
    assert_int_equal(trn_grid_f32_init(&gb, out, 48, 8, 1), TRN_OK);
    assert_int_equal(F(&w.map, &w.k, &w.pg, &ab, &gb, ws, wsb), TRN_OK);
    assert_true(isinf(out[0]) && isinf(out[7]));
    assert_int_equal(F(&w.map, &w.k, &w.pg, &area, &g, ws + 1, wsb), TRN_E_WORKSPACE);
#undef F
    free(ws);
    selworld_free(&w);
}

/* One rock on a flat plain: rover positions within reach of it have an
 * informative target, positions far from it have none, so some coarse
 * squares of the field have one to three informative corners. The field is
 * finite near the rock, +inf far from it, and never below its minimum. */
static void test_field_one_rock_on_a_plain(void **state)
{
    selworld_t w;
    synth_terrain_t t;
    synth_rock_t rock = {1.0, 1.0, 0.2, 0.3};
    float *dem = malloc(sizeof(float) * N * N);
    trn_sigma_model_t gm;
    trn_xy_t sp = {10.0f, 10.0f};
    trn_select_cfg_t sc;
    trn_field_cfg_t fc;
    trn_field_stats_t st;
    trn_window_t area = {6, 6, 33, 33};
    trn_grid_f32_t g;
    float out[28 * 28];
    uint8_t ev[28 * 28];
    size_t wsb, i, nfin = 0u, ninf = 0u;
    uint8_t *ws;
    (void)state;
    memset(&t, 0, sizeof t);
    t.rocks = &rock;
    t.n_rocks = 1u;
    t.bg_wave_m = 7.0; /* no background: bg_amp_m is 0 */
    synth_render(&t, dem, N, N, 0.0, 0.0, (double)CELL);
    trn_sigma_global_default(&gm);
    assert_int_equal(selworld_init(&w, N, dem, &gm, &sp, 1), TRN_OK);
    free(dem);
    small_cfg(&sc);
    trn_field_cfg_default(&fc);
    fc.coarse_step_cells = 8;
    assert_int_equal(trn_grid_f32_init(&g, out, 28u * 28u, 28, 28), TRN_OK);
    wsb = trn_field_workspace_bytes(&sc, &w.map, &w.k);
    ws = selworld_alloc(wsb);
    assert_int_equal(
        trn_field(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 28u * 28u, &st, ws, wsb),
        TRN_OK);
    assert_true(isfinite(st.best_m));
    for (i = 0; i < 28u * 28u; ++i) {
        if (isfinite(out[i])) {
            ++nfin;
            assert_true((double)out[i] >= st.best_m - 1e-6);
        } else {
            ++ninf;
        }
    }
    assert_true(nfin > 0u && ninf > 0u);
    /* the best position sees the rock: within reach plus half a patch of it */
    assert_true(hypot((double)st.best_x - 10.0, (double)st.best_y - 10.0) * (double)CELL <=
                (double)sc.max_range_m + (double)sc.patch_m);
    free(ws);
    selworld_free(&w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_defaults_ignore_null),
        cmocka_unit_test(test_sigma_model_clauses),
        cmocka_unit_test(test_kernel_map_clauses),
        cmocka_unit_test(test_prob_global_clauses),
        cmocka_unit_test(test_prob_local_clauses),
        cmocka_unit_test(test_select_cfg_clauses),
        cmocka_unit_test(test_select_clauses),
        cmocka_unit_test(test_field_cfg_and_size_clauses),
        cmocka_unit_test(test_field_clauses_and_featureless),
        cmocka_unit_test(test_field_one_rock_on_a_plain),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
