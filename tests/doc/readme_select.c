/* SPDX-License-Identifier: Apache-2.0 */
/* tests/doc/readme_select.c - the README's "Using the library for selection"
 * example, compiled and run so it cannot rot. CMake extracts the C block that
 * follows the marker `<!-- readme-example: select -->` in README.md into
 * readme_select_snippet.c (build tree), included below. The example must give
 * the same target as trn_select driven by the test support (selworld) with
 * the same defaults, and TRN_E_NOTARGET on flat ground. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "selworld.h"
#include "synth.h"
#include "trn/trn.h"

trn_status_t select_landmark(const trn_grid_f32_t *dem, float col, float row,
                             trn_candidate_t *best);

#include "readme_select_snippet.c"

#define N 128

static synth_rock_t g_rocks[200];

static void test_readme_example_matches_select(void **state)
{
    synth_terrain_t t;
    float *dem = malloc(sizeof(float) * N * N);
    trn_grid_f32_t g;
    trn_candidate_t got, *c;
    selworld_t w;
    trn_sigma_model_t gm;
    trn_xy_t s = {(float)N / 2.0f, (float)N / 2.0f};
    trn_select_cfg_t cfg;
    trn_rover_t rv = {{60.0f, 70.0f}, 0.0f};
    trn_select_result_t res;
    size_t cap, wsb, ranked;
    void *ws;
    (void)state;
    memset(&got, 0, sizeof got); /* select_landmark writes it on TRN_OK only */
    assert_non_null(dem);
    synth_make(&t, g_rocks, 150, N * 0.1, 0.05, 0.3, 0.5, 0.02, 11);
    synth_render(&t, dem, N, N, 0.0, 0.0, 0.1);
    assert_int_equal(trn_grid_f32_init(&g, dem, (size_t)N * N, N, N), TRN_OK);
    assert_int_equal(select_landmark(&g, 60.0f, 70.0f, &got), TRN_OK);

    trn_sigma_global_default(&gm);
    assert_int_equal(selworld_init(&w, N, dem, &gm, &s, 1), TRN_OK);
    trn_select_cfg_default(&cfg);
    cap = trn_select_max_candidates(&cfg, 0.1f);
    wsb = trn_select_workspace_bytes(&cfg, &w.map, &w.k);
    c = malloc(cap * sizeof *c);
    ws = selworld_alloc(wsb);
    assert_non_null(c);
    assert_non_null(ws);
    assert_int_equal(trn_select(&w.map, &w.k, &w.pg, &cfg, &rv, c, cap, &ranked, 1, &res, ws, wsb),
                     TRN_OK);
    assert_int_equal(got.x, c[res.best].x);
    assert_int_equal(got.y, c[res.best].y);
    assert_true(got.uncertainty_m == c[res.best].uncertainty_m);
    assert_true(got.informative == 1 && got.uncertainty_m > 0.0 && got.uncertainty_m < 1.0);
    free(c);
    free(ws);
    selworld_free(&w);
    free(dem);
}

static void test_readme_example_flat_ground(void **state)
{
    float *dem = calloc((size_t)N * N, sizeof(float));
    trn_grid_f32_t g;
    trn_candidate_t got;
    (void)state;
    assert_non_null(dem);
    assert_int_equal(trn_grid_f32_init(&g, dem, (size_t)N * N, N, N), TRN_OK);
    assert_int_equal(select_landmark(&g, 64.0f, 64.0f, &got), TRN_E_NOTARGET);
    free(dem);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_readme_example_matches_select),
        cmocka_unit_test(test_readme_example_flat_ground),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
