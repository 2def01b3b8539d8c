/* SPDX-License-Identifier: Apache-2.0 */
/* test_sim_loop.c - the whole loop without the bus, many times: is the
 * reported covariance honest? (issue 12: "the whole-loop test's 2.3x
 * optimism").
 *
 * Per seeded run, as tests/integration/kt_loop.c does over CAN in the VM: a
 * synthetic rock field (tools/support/synth) as the global DEM at 0.1 m and
 * as the simulator's truth at 0.05 m; a true rover pose and a believed one
 * up to 0.8 m off; the landmark selected from the belief (trn_select); the
 * mast pointed at it from the belief (trn_mast_point_at); the stereo head
 * rendered from the TRUE pose (tools/sim sim_render: ray-cast, range noise
 * k r^2); its points brought to the map with the believed heading
 * (trn_mast_camera_to_map), rounded to the wire's millimetres, binned into
 * a local DEM twice (the highest point per cell, trn_mast_local_dem; the mean,
 * trn_mast_local_dem_mean); each localized with the paper's configuration
 * (voxel matching, eq. 6) and with trn_map_cfg_auto's (height matching).
 *
 * Printed for the four: RMS error, the mean error along the view (toward
 * the target), and the share of runs inside the reported 1/2/3-sigma
 * ellipse (a 2-D normal: 39.3 / 86.5 / 98.9 %). Asserted: every run within 3
 * cells; the highest point biases both matchers toward the target by more
 * than 0.02 m on average; the mean halves that bias at least and lowers the
 * RMS error. Coverage is not asserted: it is what is being measured
 * (docs/method.md sections 2 and 9). 30 runs (60 measured once: the
 * numbers in method.md).
 */
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
#include "sim_render.h"
#include "synth.h"
#include "trn/trn.h"

enum { N = 192, SIM_N = 384, L = 128, RUNS = 30, MAXP = 64 * 48 };
static const double CELL = 0.1;
static float g_gdem[N * N];
static float g_simdem[SIM_N * SIM_N];
static float g_ldem[L * L];
static synth_rock_t g_rocks[2000];
static synth_terrain_t g_terr;
static selworld_t g_w;
static trn_vec3f_t g_pts[MAXP];
static uint32_t g_cnt[L * L];

static uint64_t g_rs = 0x5EEDull;
static double unit(void) /* splitmix64, [0, 1) */
{
    uint64_t z = (g_rs += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return (double)((z ^ (z >> 31)) >> 11) / 9007199254740992.0;
}

/* Mahalanobis^2 of the error (ex, ey) under cov (var_x, var_y, cov_xy). */
static double maha2(double ex, double ey, const double c[3])
{
    double det = c[0] * c[1] - c[2] * c[2];
    return (c[1] * ex * ex - 2.0 * c[2] * ex * ey + c[0] * ey * ey) / det;
}

typedef struct {
    int n, in[3], within3;
    double se, along; /* squared errors; the error along the view (toward the target), summed */
} tally_t;

static void tally(tally_t *t, trn_status_t st, const trn_loc_result_t *r,
                  const trn_rover_pose_t *truth, trn_vec3f_t target)
{
    double ex = r->x * CELL - truth->x_m, ey = r->y * CELL - truth->y_m, m2;
    double tx = target.x - truth->x_m, ty = target.y - truth->y_m, tr = hypot(tx, ty);
    t->n += 1;
    t->along += (ex * tx + ey * ty) / tr;
    t->within3 += (st == TRN_OK || st == TRN_E_ILLCOND) && hypot(ex, ey) <= 3.0 * CELL;
    t->se += ex * ex + ey * ey;
    if (st != TRN_OK || !isfinite(r->cov_m2[0])) {
        return;
    }
    m2 = maha2(ex, ey, r->cov_m2);
    t->in[0] += m2 <= 1.0;
    t->in[1] += m2 <= 4.0;
    t->in[2] += m2 <= 9.0;
}

static void test_loop_calibration(void **state)
{
    trn_mast_geom_t geom;
    sim_camera_t cam;
    sim_dem_t sdem;
    trn_map_cfg_t acfg;
    trn_map_t amap;
    void *abuf, *aws;
    trn_sigma_model_t gm;
    trn_xy_t sensor = {N / 2.0f, N / 2.0f};
    size_t nrocks = (size_t)(N * N * CELL * CELL * 0.15 / (3.14159265 * 0.15 * 0.15));
    tally_t t[2][2];
    static const char *bin_name[2] = {"highest point per cell", "mean per cell"};
    static const char *match_name[2] = {"paper (voxels, eq. 6)", "auto (heights)"};
    int v, m;
    size_t wb;
    double sh;
    int run;
    (void)state;

    memset(t, 0, sizeof t);
    sim_geom_default(&geom);
    sim_camera_default(&cam);
    synth_make(&g_terr, g_rocks, nrocks, N * CELL, 0.05, 0.3, 0.5, 0.2, 12u);
    synth_render(&g_terr, g_gdem, N, N, 0.0, 0.0, CELL);
    synth_render(&g_terr, g_simdem, SIM_N, SIM_N, 0.0, 0.0, CELL / 2.0);
    trn_sigma_global_default(&gm);
    assert_int_equal(selworld_init(&g_w, N, g_gdem, &gm, &sensor, 1u), TRN_OK);
    /* the height matcher's map: trn_map_cfg_auto with the stereo head's noise */
    trn_map_cfg_default(&acfg);
    acfg.noise_m = 0.01f;
    acfg.noise_k_per_m = 0.002f;
    wb = trn_map_cfg_auto_workspace_bytes(N, N);
    aws = selworld_alloc(wb);
    assert_non_null(aws);
    assert_int_equal(trn_map_cfg_auto(&acfg, &g_w.g, (float)CELL, aws, wb, &sh), TRN_OK);
    free(aws);
    wb = trn_map_bytes(&acfg, N, N);
    abuf = selworld_alloc(wb);
    assert_non_null(abuf);
    assert_int_equal(trn_map_build(&amap, &acfg, &g_w.g, abuf, wb), TRN_OK);
    sdem.heights = g_simdem;
    sdem.width = SIM_N;
    sdem.height = SIM_N;
    sdem.cell_m = (float)(CELL / 2.0);
    sdem.x0_m = 0.0f;
    sdem.y0_m = 0.0f;

    for (run = 0; run < RUNS; ++run) {
        trn_rover_pose_t truth, believed, known;
        trn_select_cfg_t scfg;
        trn_rover_t rv;
        trn_select_result_t sres;
        trn_candidate_t *cands;
        size_t cap, ranked[4], npts = 0u, used = 0u, i;
        void *ws;
        trn_vec3f_t target;
        float pan = 0.0f, tilt = 0.0f;
        trn_rigid_t Tt, T;
        sim_rng_t rng;
        trn_local_dem_cfg_t dcfg;
        trn_grid_f32_t lg;
        trn_window_t win;
        trn_loc_result_t res;
        trn_status_t st;
        int32_t bx, by;

        truth.x_m = (float)(8.0 + 3.0 * unit());
        truth.y_m = (float)(8.0 + 3.0 * unit());
        truth.heading_rad = (float)(-3.0 + 6.0 * unit());
        truth.z_m = (float)synth_height(&g_terr, truth.x_m, truth.y_m);
        believed = truth;
        believed.x_m += (float)(-0.8 + 1.6 * unit());
        believed.y_m += (float)(-0.8 + 1.6 * unit());
        bx = (int32_t)lround(believed.x_m / CELL);
        by = (int32_t)lround(believed.y_m / CELL);
        believed.z_m = g_gdem[by * N + bx];

        trn_select_cfg_default(&scfg);
        scfg.min_range_m = 2.0f;
        scfg.max_range_m = 4.5f;
        scfg.pan_min_rad = geom.pan_min_rad + 0.1f;
        scfg.pan_max_rad = geom.pan_max_rad - 0.1f;
        rv.pos.x_cells = (float)(believed.x_m / CELL);
        rv.pos.y_cells = (float)(believed.y_m / CELL);
        rv.heading_rad = believed.heading_rad;
        cap = trn_select_max_candidates(&scfg, (float)CELL);
        cands = (trn_candidate_t *)malloc(cap * sizeof *cands);
        wb = trn_select_workspace_bytes(&scfg, &g_w.map, &g_w.k);
        ws = selworld_alloc(wb);
        assert_true(cands != NULL && ws != NULL);
        assert_int_equal(
            trn_select(&g_w.map, &g_w.k, &g_w.pg, &scfg, &rv, cands, cap, ranked, 4, &sres, ws, wb),
            TRN_OK);
        free(ws);
        target.x = (float)(cands[ranked[0]].x * CELL);
        target.y = (float)(cands[ranked[0]].y * CELL);
        target.z = g_gdem[cands[ranked[0]].y * N + cands[ranked[0]].x];
        free(cands);

        /* point from the belief, see from the truth */
        assert_int_equal(trn_mast_point_at(&geom, &believed, &target, &pan, &tilt), TRN_OK);
        assert_int_equal(trn_mast_camera_to_map(&geom, &truth, pan, tilt, &Tt), TRN_OK);
        rng.s = 100u + (uint64_t)run;
        st = sim_render(&sdem, &cam, &Tt, &rng, g_pts, MAXP, &npts);
        assert_true(st == TRN_OK || st == TRN_E_CAPACITY);
        for (i = 0; i < npts; ++i) { /* the wire's int16 millimetres */
            g_pts[i].x = (float)(floor(g_pts[i].x * 1000.0 + 0.5) / 1000.0);
            g_pts[i].y = (float)(floor(g_pts[i].y * 1000.0 + 0.5) / 1000.0);
            g_pts[i].z = (float)(floor(g_pts[i].z * 1000.0 + 0.5) / 1000.0);
        }
        known = believed;
        known.x_m = 0.0f;
        known.y_m = 0.0f;
        assert_int_equal(trn_mast_camera_to_map(&geom, &known, pan, tilt, &T), TRN_OK);
        assert_int_equal(trn_rigid_apply(&T, g_pts, npts, g_pts), TRN_OK);
        memset(&dcfg, 0, sizeof dcfg);
        dcfg.cell_m = (float)CELL;
        dcfg.rover_col = L / 2;
        dcfg.rover_row = L / 2;
        dcfg.row_north = 1;
        assert_int_equal(trn_grid_f32_init(&lg, g_ldem, (size_t)L * L, L, L), TRN_OK);
        assert_int_equal(trn_mast_local_dem(g_pts, npts, &known, &dcfg, &lg, &used), TRN_OK);
        win.x0 = bx - 15;
        win.x1 = bx + 15;
        win.y0 = by - 15;
        win.y1 = by + 15;

        for (v = 0; v < 2; ++v) {
            if (v == 1) { /* the same points, each cell their mean */
                assert_int_equal(trn_mast_local_dem_mean(g_pts, npts, &known, &dcfg, &lg, g_cnt,
                                                         (size_t)L * L, &used),
                                 TRN_OK);
            }
            wb = trn_localize_dem_workspace_bytes(&g_w.map, L, L,
                                                  (size_t)L * L * g_w.cfg.terrain.nz, &win);
            ws = selworld_alloc(wb);
            assert_non_null(ws);
            memset(&res, 0, sizeof res);
            st = trn_localize_dem(&g_w.map, &lg, L / 2, L / 2, (size_t)L * L * g_w.cfg.terrain.nz,
                                  &win, ws, wb, &res);
            free(ws);
            tally(&t[v][0], st, &res, &truth, target);

            wb = trn_localize_dem_workspace_bytes(&amap, L, L, (size_t)L * L * acfg.terrain.nz,
                                                  &win);
            ws = selworld_alloc(wb);
            assert_non_null(ws);
            memset(&res, 0, sizeof res);
            st = trn_localize_dem(&amap, &lg, L / 2, L / 2, (size_t)L * L * acfg.terrain.nz, &win,
                                  ws, wb, &res);
            free(ws);
            tally(&t[v][1], st, &res, &truth, target);
        }
    }
    for (v = 0; v < 2; ++v) {
        for (m = 0; m < 2; ++m) {
            const tally_t *q = &t[v][m];
            printf("loop, %s, %s: %d runs, within 3 cells %d, RMS error %.4f m, mean error along "
                   "the view "
                   "%+.4f m, inside 1/2/3 sigma %.1f / %.1f / %.1f %%\n",
                   bin_name[v], match_name[m], q->n, q->within3, sqrt(q->se / q->n),
                   q->along / q->n, 100.0 * q->in[0] / q->n, 100.0 * q->in[1] / q->n,
                   100.0 * q->in[2] / q->n);
            assert_int_equal(q->within3, RUNS);
        }
    }
    printf("(a 2-D normal: 39.3 / 86.5 / 98.9 %%)\n");
    /* the highest point biases the estimate toward the target (measured
     * +0.03-0.04 m for both matchers); the mean removes most of it */
    for (m = 0; m < 2; ++m) {
        assert_true(t[0][m].along / RUNS > 0.02);
        assert_true(fabs(t[1][m].along / RUNS) < 0.5 * t[0][m].along / RUNS);
        assert_true(t[1][m].se < t[0][m].se);
    }
    free(abuf);
    selworld_free(&g_w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_loop_calibration),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
