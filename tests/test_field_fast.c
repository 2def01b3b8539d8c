/* SPDX-License-Identifier: Apache-2.0 */
/* test_field_fast.c - the ground path of the sensor uncertainty field
 * (trn_field_fast, trn_field_fast_workspace_bytes) and the progress/cancel
 * callback of both field functions (field.h).
 *
 * Oracle: trn_field, the onboard algorithm. The fast path must give the same
 * raster bit for bit (memcmp of the float grid), the same evaluated mask and
 * the same statistics (best_m compared as a double, ==), on seeded terrains
 * and configurations: areas touching every map edge, every cell evaluated
 * (coarse step 1: each position's value compared), several ranges, patch
 * sizes, strides (one wider than the patch), pan restricted on one or both
 * sides with a heading, a steeper local error model
 * (more kernels in the region), a terrain with featureless parts
 * (uninformative positions). Then every documented status of the new
 * functions, and the callback's counts. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "selworld.h"
#include "synth.h"

#define CELL 0.1

static synth_rock_t g_rocks[2000];

static void make_world(selworld_t *w, int n, size_t nrocks, double bg, uint64_t seed)
{
    synth_terrain_t t;
    float *dem = malloc(sizeof(float) * n * n);
    trn_sigma_model_t gm;
    trn_xy_t s = {(float)n / 2.0f, (float)n / 2.0f};
    synth_make(&t, g_rocks, nrocks, n * CELL, 0.05, 0.3, 0.5, bg, seed);
    synth_render(&t, dem, n, n, 0.0, 0.0, CELL);
    trn_sigma_global_default(&gm);
    assert_int_equal(selworld_init(w, n, dem, &gm, &s, 1), TRN_OK);
    free(dem);
}

static void small_cfg(trn_select_cfg_t *c)
{
    trn_select_cfg_default(c);
    c->min_range_m = 0.5f;
    c->max_range_m = 2.0f;
    c->footprint_radius_m = 0.3f;
    c->patch_m = 0.9f;
    c->stride_cells = 2;
    c->min_separation_m = 0.45f;
}

/* Both algorithms over area; asserts identical answers; returns the evaluations. */
static uint32_t compare(const selworld_t *w, const trn_select_cfg_t *sc, const trn_field_cfg_t *fc,
                        float heading, const trn_window_t *area)
{
    const int32_t aw = area->x1 - area->x0 + 1, ah = area->y1 - area->y0 + 1;
    const size_t n = (size_t)aw * (size_t)ah;
    float *o1 = malloc(n * sizeof(float)), *o2 = malloc(n * sizeof(float));
    uint8_t *e1 = malloc(n), *e2 = malloc(n);
    trn_grid_f32_t g1, g2;
    trn_field_stats_t s1, s2;
    const size_t b1 = trn_field_workspace_bytes(sc, &w->map, &w->k);
    const size_t b2 = trn_field_fast_workspace_bytes(sc, &w->map, &w->k, &w->pg);
    void *ws1, *ws2;
    assert_true(b1 > 0u && b2 > 0u);
    ws1 = selworld_alloc(b1);
    ws2 = selworld_alloc(b2);
    assert_int_equal(trn_grid_f32_init(&g1, o1, n, aw, ah), TRN_OK);
    assert_int_equal(trn_grid_f32_init(&g2, o2, n, aw, ah), TRN_OK);
    assert_int_equal(
        trn_field(&w->map, &w->k, &w->pg, sc, fc, heading, area, &g1, e1, n, &s1, ws1, b1), TRN_OK);
    assert_int_equal(
        trn_field_fast(&w->map, &w->k, &w->pg, sc, fc, heading, area, &g2, e2, n, &s2, ws2, b2),
        TRN_OK);
    assert_memory_equal(o1, o2, n * sizeof(float));
    assert_memory_equal(e1, e2, n);
    assert_int_equal(s1.evaluations, s2.evaluations);
    assert_int_equal(s1.cells, s2.cells);
    assert_int_equal(s1.best_x, s2.best_x);
    assert_int_equal(s1.best_y, s2.best_y);
    assert_true(s1.best_m == s2.best_m || (isinf(s1.best_m) && isinf(s2.best_m)));
    printf("  area (%d,%d)-(%d,%d): %u evaluations, best %.6f m at (%d, %d); workspace %zu B "
           "(onboard %zu B)\n",
           (int)area->x0, (int)area->y0, (int)area->x1, (int)area->y1, s1.evaluations, s1.best_m,
           (int)s1.best_x, (int)s1.best_y, b2, b1);
    free(o1);
    free(o2);
    free(e1);
    free(e2);
    free(ws1);
    free(ws2);
    return s1.evaluations;
}

/* Every cell of a 48 x 48 map evaluated (coarse step 1): each position's
 * value, the map's edges and corners included, equals trn_select's. */
static void test_every_position_equal(void **state)
{
    selworld_t w;
    trn_select_cfg_t sc;
    trn_field_cfg_t fc;
    const trn_window_t all = {0, 0, 47, 47};
    (void)state;
    small_cfg(&sc);
    sc.max_range_m = 1.5f;
    trn_field_cfg_default(&fc);
    fc.coarse_step_cells = 1;
    make_world(&w, 48, 30, 0.15, 3);
    assert_int_equal((int)compare(&w, &sc, &fc, 0.0f, &all), 48 * 48);
    selworld_free(&w);
}

/* Coarse to fine on several seeded terrains and configurations. */
static void test_coarse_to_fine_equal(void **state)
{
    selworld_t w;
    trn_select_cfg_t sc;
    trn_field_cfg_t fc;
    const trn_window_t all = {0, 0, 79, 79}, inner = {20, 16, 59, 55}, edge = {0, 50, 30, 79};
    (void)state;
    trn_field_cfg_default(&fc);
    fc.coarse_step_cells = 8;

    make_world(&w, 80, 60, 0.15, 21);
    small_cfg(&sc);
    compare(&w, &sc, &fc, 0.0f, &inner);
    compare(&w, &sc, &fc, 0.0f, &all);
    /* a longer reach, stride 1, the default 2 m patch */
    sc.max_range_m = 3.0f;
    sc.min_range_m = 1.0f;
    sc.stride_cells = 1;
    sc.patch_m = 2.0f;
    compare(&w, &sc, &fc, 0.0f, &edge);
    /* restricted pan and a heading: the bearing rule per candidate */
    small_cfg(&sc);
    sc.pan_min_rad = -1.0f;
    sc.pan_max_rad = 0.5f;
    compare(&w, &sc, &fc, 2.2f, &all);
    /* steeper local error: kernels up to the widest inside the region */
    small_cfg(&sc);
    sc.local_sigma.k_per_m = 0.05f;
    sc.stride_cells = 3;
    compare(&w, &sc, &fc, -0.7f, &inner);
    /* a lattice wider than the patch: region rows and columns no patch covers */
    small_cfg(&sc);
    sc.stride_cells = 6;
    sc.patch_m = 0.3f;
    compare(&w, &sc, &fc, 0.0f, &inner);
    /* pan limited on one side only */
    small_cfg(&sc);
    sc.pan_min_rad = (float)-3.14159265358979323846;
    sc.pan_max_rad = 1.0f;
    compare(&w, &sc, &fc, 0.9f, &inner);
    selworld_free(&w);

    /* few rocks, no background: featureless parts give +inf positions */
    make_world(&w, 72, 6, 0.0, 5);
    small_cfg(&sc);
    fc.coarse_step_cells = 4;
    compare(&w, &sc, &fc, 0.0f, &(trn_window_t){0, 0, 71, 71});
    selworld_free(&w);

    /* a different seed and the default field configuration */
    make_world(&w, 96, 120, 0.15, 77);
    small_cfg(&sc);
    trn_field_cfg_default(&fc);
    compare(&w, &sc, &fc, 0.3f, &(trn_window_t){0, 0, 95, 95});
    selworld_free(&w);
}

typedef struct {
    uint32_t calls, last_done, last_total, stop_after;
    int monotone;
} prog_t;

static int32_t on_progress(void *user, uint32_t done, uint32_t total)
{
    prog_t *p = (prog_t *)user;
    if (p->calls > 0u && done < p->last_done) {
        p->monotone = 0;
    }
    ++p->calls;
    p->last_done = done;
    p->last_total = total;
    return p->stop_after != 0u && p->calls >= p->stop_after;
}

/* The callback: done counts the evaluations, the last call has done = total
 * = the area's cells; a nonzero return cancels both algorithms. */
static void test_progress_and_cancel(void **state)
{
    selworld_t w;
    trn_select_cfg_t sc;
    trn_field_cfg_t fc;
    const trn_window_t area = {10, 10, 49, 39};
    const size_t n = 40u * 30u;
    float *out = malloc(n * sizeof(float));
    uint8_t *ev = malloc(n);
    trn_grid_f32_t g;
    trn_field_stats_t st;
    prog_t p;
    size_t b1, b2;
    void *ws1, *ws2;
    int alg;
    (void)state;
    make_world(&w, 60, 40, 0.15, 9);
    small_cfg(&sc);
    trn_field_cfg_default(&fc);
    fc.coarse_step_cells = 8;
    fc.progress = on_progress;
    fc.progress_user = &p;
    assert_int_equal(trn_grid_f32_init(&g, out, n, 40, 30), TRN_OK);
    b1 = trn_field_workspace_bytes(&sc, &w.map, &w.k);
    b2 = trn_field_fast_workspace_bytes(&sc, &w.map, &w.k, &w.pg);
    ws1 = selworld_alloc(b1);
    ws2 = selworld_alloc(b2);
    for (alg = 0; alg < 2; ++alg) {
        trn_status_t s;
        memset(&p, 0, sizeof p);
        p.monotone = 1;
        s = alg == 0
                ? trn_field(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, n, &st, ws1, b1)
                : trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, n, &st, ws2,
                                 b2);
        assert_int_equal(s, TRN_OK);
        assert_int_equal(p.calls, st.evaluations + 1u); /* each evaluation, then the end */
        assert_int_equal(p.last_done, p.last_total);
        assert_int_equal(p.last_total, (uint32_t)n);
        assert_true(p.monotone);
        /* cancel at the fifth evaluation */
        memset(&p, 0, sizeof p);
        p.stop_after = 5u;
        s = alg == 0
                ? trn_field(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, n, &st, ws1, b1)
                : trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, n, &st, ws2,
                                 b2);
        assert_int_equal(s, TRN_E_CANCELLED);
        assert_int_equal(st.evaluations, 5u);
        assert_int_equal(p.calls, 5u);
    }
    assert_string_equal(trn_strerror(TRN_E_CANCELLED), "cancelled by the caller");
    free(out);
    free(ev);
    free(ws1);
    free(ws2);
    selworld_free(&w);
}

/* Every documented status of trn_field_fast and the sizing function's 0. */
static void test_bad_inputs(void **state)
{
    selworld_t w;
    trn_select_cfg_t sc, sb;
    trn_field_cfg_t fc, fb;
    trn_kernels_t kb;
    trn_map_t mb;
    trn_vol_f32_t pb;
    const trn_window_t area = {30, 30, 37, 35}, off = {70, 70, 90, 75}, empty = {5, 5, 4, 4};
    float out[8 * 6];
    uint8_t ev[8 * 6];
    trn_grid_f32_t g;
    trn_field_stats_t st;
    size_t wsb;
    uint8_t *ws;
    (void)state;
    small_cfg(&sc);
    trn_field_cfg_default(&fc);
    make_world(&w, 80, 40, 0.15, 9);
    assert_int_equal(trn_grid_f32_init(&g, out, 48, 8, 6), TRN_OK);
    wsb = trn_field_fast_workspace_bytes(&sc, &w.map, &w.k, &w.pg);
    assert_true(wsb > trn_field_workspace_bytes(&sc, &w.map, &w.k));
    ws = selworld_alloc(wsb + 16u);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_OK);
    /* TRN_E_NULL */
    assert_int_equal(
        trn_field_fast(NULL, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_NULL);
    assert_int_equal(
        trn_field_fast(&w.map, NULL, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_NULL);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, NULL, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_NULL);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, NULL, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_NULL);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, NULL, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_NULL);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, NULL, &g, ev, 48, &st, ws, wsb),
        TRN_E_NULL);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, NULL, ev, 48, &st, ws, wsb),
        TRN_E_NULL);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, NULL, 48, &st, ws, wsb),
        TRN_E_NULL);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, NULL, ws, wsb),
        TRN_E_NULL);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, NULL, wsb),
        TRN_E_NULL);
    pb = w.pg;
    pb.data = NULL;
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &pb, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_NULL);
    assert_int_equal(trn_field_fast_workspace_bytes(&sc, &w.map, &w.k, &pb), 0u);
    mb = w.map;
    mb.dist.data = NULL;
    assert_int_equal(
        trn_field_fast(&mb, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_NULL);
    assert_int_equal(trn_field_fast_workspace_bytes(NULL, &w.map, &w.k, &w.pg), 0u);
    assert_int_equal(trn_field_fast_workspace_bytes(&sc, NULL, &w.k, &w.pg), 0u);
    assert_int_equal(trn_field_fast_workspace_bytes(&sc, &w.map, NULL, &w.pg), 0u);
    assert_int_equal(trn_field_fast_workspace_bytes(&sc, &w.map, &w.k, NULL), 0u);
    /* TRN_E_ARG: field and selection configurations, heading, kernel table */
    fb = fc;
    fb.coarse_step_cells = 12;
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fb, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_ARG);
    sb = sc;
    sb.stride_cells = 0;
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sb, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_ARG);
    assert_int_equal(trn_field_fast_workspace_bytes(&sb, &w.map, &w.k, &w.pg), 0u);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, NAN, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_ARG);
    kb = w.k;
    kb.sigma0_cells = 0.0f;
    assert_int_equal(
        trn_field_fast(&w.map, &kb, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_ARG);
    kb = w.k;
    kb.radius[TRN_KERNEL_COUNT - 1] = 0;
    assert_int_equal(
        trn_field_fast(&w.map, &kb, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_ARG);
    kb.radius[TRN_KERNEL_COUNT - 1] = TRN_KERNEL_MAX_RADIUS + 1;
    assert_int_equal(
        trn_field_fast(&w.map, &kb, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_ARG);
    /* TRN_E_RANGE */
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &off, &g, ev, 48, &st, ws, wsb),
        TRN_E_RANGE);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &empty, &g, ev, 48, &st, ws, wsb),
        TRN_E_RANGE);
    /* TRN_E_SIZE: out, evaluated, P_G, the map's distance cap, its volume */
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 47, &st, ws, wsb),
        TRN_E_SIZE);
    g.width = 7;
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_SIZE);
    g.width = 8;
    pb = w.pg;
    pb.nz = w.pg.nz - 1;
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &pb, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_SIZE);
    pb = w.pg;
    pb.nx = w.pg.nx - 1;
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &pb, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_SIZE);
    pb = w.pg;
    pb.ny = w.pg.ny - 1;
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &pb, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_SIZE);
    mb = w.map;
    mb.lnp.cap = 0u;
    assert_int_equal(
        trn_field_fast(&mb, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_SIZE);
    mb = w.map;
    mb.lnp.cap = (uint8_t)(TRN_CHAMFER_CAP_MAX + 1 > 255 ? 255 : TRN_CHAMFER_CAP_MAX + 1);
    if (TRN_CHAMFER_CAP_MAX < 255) {
        assert_int_equal(
            trn_field_fast(&mb, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
            TRN_E_SIZE);
    }
    mb = w.map;
    mb.dist.nz = 0;
    assert_int_not_equal(
        trn_field_fast(&mb, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb), TRN_OK);
    /* ln p so large that a region's exact int64 sum could overflow: as trn_select */
    mb = w.map;
    mb.lnp.lnp[0] = 2000000000;
    assert_int_equal(
        trn_field_fast(&mb, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
        TRN_E_SIZE);
    /* TRN_E_WORKSPACE: short, misaligned, shorter than the context header */
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb - 1),
        TRN_E_WORKSPACE);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws + 1, wsb),
        TRN_E_WORKSPACE);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, 8u),
        TRN_E_WORKSPACE);
    /* TRN_E_CANCELLED: the callback's first return stops it */
    fb = fc;
    fb.progress = on_progress;
    {
        prog_t p;
        memset(&p, 0, sizeof p);
        p.stop_after = 1u;
        fb.progress_user = &p;
        assert_int_equal(
            trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fb, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
            TRN_E_CANCELLED);
        memset(&p, 0, sizeof p);
        p.stop_after = 1u;
        assert_int_equal(
            trn_field(&w.map, &w.k, &w.pg, &sc, &fb, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
            TRN_E_CANCELLED);
    }
    free(ws);
    selworld_free(&w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_position_equal),
        cmocka_unit_test(test_coarse_to_fine_equal),
        cmocka_unit_test(test_progress_and_cancel),
        cmocka_unit_test(test_bad_inputs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
