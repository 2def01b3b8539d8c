/* SPDX-License-Identifier: Apache-2.0 */
/* test_field.c - coarse-to-fine sensor uncertainty field (field.h).
 *
 * Oracle: the brute-force field (trn_select's best uncertainty at every
 * rover cell of the area). Small reach and patch keep it quick. */
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

static void make_world(selworld_t *w, int n, size_t nrocks, uint64_t seed)
{
    synth_terrain_t t;
    float *dem = malloc(sizeof(float) * n * n);
    trn_sigma_model_t gm;
    trn_xy_t s = {(float)n / 2.0f, (float)n / 2.0f};
    synth_make(&t, g_rocks, nrocks, n * CELL, 0.05, 0.3, 0.5, 0.15, seed);
    synth_render(&t, dem, n, n, 0.0, 0.0, CELL);
    trn_sigma_global_default(&gm);
    assert_int_equal(selworld_init(w, n, dem, &gm, &s, 1), TRN_OK);
    free(dem);
}

typedef struct {
    float *out;
    uint8_t *ev;
    trn_grid_f32_t g;
    void *ws;
    size_t wsb;
    trn_field_stats_t st;
} fld_t;

static trn_status_t run_field(selworld_t *w, const trn_select_cfg_t *sc, const trn_field_cfg_t *fc,
                              const trn_window_t *area, fld_t *f)
{
    const int32_t aw = area->x1 - area->x0 + 1, ah = area->y1 - area->y0 + 1;
    f->out = malloc(sizeof(float) * aw * ah);
    f->ev = malloc((size_t)aw * ah);
    assert_int_equal(trn_grid_f32_init(&f->g, f->out, (size_t)aw * ah, aw, ah), TRN_OK);
    f->wsb = trn_field_workspace_bytes(sc, &w->map, &w->k);
    assert_true(f->wsb > 0u);
    f->ws = selworld_alloc(f->wsb);
    return trn_field(&w->map, &w->k, &w->pg, sc, fc, 0.0f, area, &f->g, f->ev, (size_t)aw * ah,
                     &f->st, f->ws, f->wsb);
}

static void fld_free(fld_t *f)
{
    free(f->out);
    free(f->ev);
    free(f->ws);
}

static void test_matches_brute_force(void **state)
{
    selworld_t w;
    trn_select_cfg_t sc;
    trn_field_cfg_t fc;
    const trn_window_t area = {20, 16, 59, 55}; /* 40 x 40 rover cells */
    const int aw = 40, ah = 40;
    fld_t f;
    trn_candidate_t *c;
    size_t cap, wsb, rk;
    void *ws;
    double *bf = malloc(sizeof(double) * aw * ah), bmin = HUGE_VAL, interp_worst = 0.0;
    int x, y, bx = -1, by = -1, nexact = 0;
    (void)state;
    small_cfg(&sc);
    trn_field_cfg_default(&fc);
    fc.coarse_step_cells = 8;
    make_world(&w, 80, 60, 21);
    assert_int_equal(run_field(&w, &sc, &fc, &area, &f), TRN_OK);
    /* brute force */
    cap = trn_select_max_candidates(&sc, (float)CELL);
    wsb = trn_select_workspace_bytes(&sc, &w.map, &w.k);
    c = malloc(cap * sizeof *c);
    ws = selworld_alloc(wsb);
    for (y = 0; y < ah; ++y) {
        for (x = 0; x < aw; ++x) {
            trn_rover_t rv = {{(float)(area.x0 + x), (float)(area.y0 + y)}, 0.0f};
            trn_select_result_t r;
            trn_status_t s = trn_select(&w.map, &w.k, &w.pg, &sc, &rv, c, cap, &rk, 1, &r, ws, wsb);
            double v;
            assert_true(s == TRN_OK || s == TRN_E_NOTARGET);
            v = s == TRN_OK ? c[r.best].uncertainty_m : HUGE_VAL;
            bf[y * aw + x] = v;
            if (v < bmin) {
                bmin = v;
                bx = x;
                by = y;
            }
        }
    }
    for (y = 0; y < ah; ++y) {
        for (x = 0; x < aw; ++x) {
            const double v = f.out[y * aw + x], b = bf[y * aw + x];
            if (f.ev[y * aw + x]) { /* evaluated cells are exact */
                assert_true((float)b == (float)v);
                ++nexact;
            } else if (isfinite(b) && isfinite(v)) {
                interp_worst = fmax(interp_worst, fabs(v - b) / b);
            }
        }
    }
    printf("field 40x40: %u evaluations (%.1f %% of %u), min %.4f m at (%d, %d); brute force "
           "min %.4f m at (%d, %d); worst interpolated cell off by %.0f %%\n",
           f.st.evaluations, 100.0 * f.st.evaluations / f.st.cells, f.st.cells, f.st.best_m,
           (int)f.st.best_x, (int)f.st.best_y, bmin, area.x0 + bx, area.y0 + by,
           100.0 * interp_worst);
    assert_int_equal((int)f.st.evaluations, nexact);
    assert_true(f.st.evaluations < f.st.cells);
    assert_true(abs(f.st.best_x - (area.x0 + bx)) <= fc.coarse_step_cells &&
                abs(f.st.best_y - (area.y0 + by)) <= fc.coarse_step_cells);
    assert_true(f.st.best_m >= bmin);
    free(c);
    free(ws);
    free(bf);
    fld_free(&f);
    selworld_free(&w);
}

static void test_evaluations_256(void **state)
{
    selworld_t w;
    trn_select_cfg_t sc;
    trn_field_cfg_t fc;
    const trn_window_t area = {0, 0, 255, 255};
    fld_t f;
    (void)state;
    small_cfg(&sc);
    trn_field_cfg_default(&fc);
    make_world(&w, 256, 1000, 4);
    assert_int_equal(run_field(&w, &sc, &fc, &area, &f), TRN_OK);
    printf("field 256x256: %u evaluations of %u cells (%.1fx fewer), min %.4f m at (%d, %d)\n",
           f.st.evaluations, f.st.cells, (double)f.st.cells / f.st.evaluations, f.st.best_m,
           (int)f.st.best_x, (int)f.st.best_y);
    assert_true((uint64_t)f.st.evaluations * 10u <= f.st.cells);
    assert_true(isfinite(f.st.best_m));
    fld_free(&f);
    selworld_free(&w);
}

static void test_bad_inputs(void **state)
{
    selworld_t w;
    trn_select_cfg_t sc, sb;
    trn_field_cfg_t fc, fb;
    const trn_window_t area = {30, 30, 37, 35}, off = {70, 70, 90, 75}, empty = {5, 5, 4, 4};
    float out[8 * 6];
    uint8_t ev[8 * 6];
    trn_grid_f32_t g;
    trn_field_stats_t st;
    size_t wsb;
    void *ws;
    (void)state;
    small_cfg(&sc);
    trn_field_cfg_default(&fc);
    make_world(&w, 80, 40, 9);
    assert_int_equal(trn_grid_f32_init(&g, out, 48, 8, 6), TRN_OK);
    wsb = trn_field_workspace_bytes(&sc, &w.map, &w.k);
    ws = selworld_alloc(wsb);
#define F(m, k, pg, s, f, h, a, o, e, el, stt, wp, wb) \
    trn_field(m, k, pg, s, f, h, a, o, e, el, stt, wp, wb)
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
                     TRN_OK);
    assert_int_equal(F(NULL, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
                     TRN_E_NULL);
    assert_int_equal(F(&w.map, &w.k, &w.pg, NULL, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
                     TRN_E_NULL);
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sc, NULL, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
                     TRN_E_NULL);
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, NULL, &g, ev, 48, &st, ws, wsb),
                     TRN_E_NULL);
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, NULL, ev, 48, &st, ws, wsb),
                     TRN_E_NULL);
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, NULL, 48, &st, ws, wsb),
                     TRN_E_NULL);
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, NULL, ws, wsb),
                     TRN_E_NULL);
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, NULL, wsb),
                     TRN_E_NULL);
    fb = fc;
    fb.coarse_step_cells = 12;
    assert_int_equal(trn_field_cfg_check(&fb), TRN_E_ARG);
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sc, &fb, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
                     TRN_E_ARG);
    fb = fc;
    fb.margin_rel = NAN;
    assert_int_equal(trn_field_cfg_check(&fb), TRN_E_ARG);
    fb = fc;
    fb.change_rel = -1.0f;
    assert_int_equal(trn_field_cfg_check(&fb), TRN_E_ARG);
    assert_int_equal(trn_field_cfg_check(NULL), TRN_E_NULL);
    sb = sc;
    sb.stride_cells = -2;
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sb, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
                     TRN_E_ARG);
    assert_int_equal(trn_field_workspace_bytes(&sb, &w.map, &w.k), 0u);
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sc, &fc, NAN, &area, &g, ev, 48, &st, ws, wsb),
                     TRN_E_ARG);
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &off, &g, ev, 48, &st, ws, wsb),
                     TRN_E_RANGE);
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &empty, &g, ev, 48, &st, ws, wsb),
                     TRN_E_RANGE);
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 47, &st, ws, wsb),
                     TRN_E_SIZE);
    g.width = 7;
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb),
                     TRN_E_SIZE);
    g.width = 8;
    assert_int_equal(F(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g, ev, 48, &st, ws, wsb - 1),
                     TRN_E_WORKSPACE);
#undef F
    free(ws);
    selworld_free(&w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_matches_brute_force),
        cmocka_unit_test(test_evaluations_256),
        cmocka_unit_test(test_bad_inputs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
