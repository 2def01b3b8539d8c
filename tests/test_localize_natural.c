/* SPDX-License-Identifier: Apache-2.0 */
/* test_localize_natural.c - natural-terrain localization (docs/method.md
 * section 9): TRN_LOCAL_HP_MAP, the height refinement inside
 * trn_localize_dem, trn_map_cfg_auto, and the edges of trn_refine_pose.
 *
 * Oracles:
 * - a smooth analytic global DEM (1 m cells: sinusoids plus a slope) and a
 *   local DEM that is a 120 degree wedge (radius 20 cells, rover cell unseen)
 *   of its bilinear interpolation at a known integer or sub-cell pose plus a
 *   vertical offset: with trn_map_cfg_auto the pose comes back within 0.05
 *   cell, refined, with a finite positive definite covariance whose sigmas
 *   and rho are those of cov_m2;
 * - the paper's box filter on the same wedges over a steep slope is biased,
 *   the map filter is not (measured errors of the voxel search compared);
 * - invariance: a constant added to the local heights changes nothing but
 *   the refined offset dz (the map filter removes it exactly);
 * - the second pass: from a prior 4 cells off, the eq. 6 result equals the
 *   one from a prior centred on the found pose (the second pass refers the
 *   local filter to that pose);
 * - a local cell off the map or over an unknown low-pass gives the same
 *   result as the same cell marked unseen;
 * - trn_map_cfg_auto's three regimes in closed form (relief: zbin = sigma_H/2,
 *   nz = 17; noise floor: zbin = 2 s(10 cells), nz = 16; cell cap: zbin =
 *   cell, nz = min(64, 2 ceil(4 sigma_H / cell) + 1)); the map's stored
 *   heights and low-pass (a plane's low-pass is the plane in the interior);
 * - trn_refine_pose's branches built from its model: a rejected majority,
 *   too few inliers, a Gauss-Newton cycle at a cell edge (12 iterations), a
 *   step clamped downwards, a shift out of range in y, grids of one row or
 *   column, local cells off the global grid or over NaN;
 * - one assertion per documented @retval and per field check.
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

#include "rng.h"
#include "trn/localize.h"
#include "trn/refine.h"

#define GW 96           /* global side, cells of 1 m */
#define LR 20           /* wedge radius, cells */
#define LW (2 * LR + 1) /* local side; rover at its centre cell */
#define MAXPTS 40000
#define PI 3.14159265358979323846

static float g_data[GW * GW];
static float l_data[LW * LW];

/* The surface: sinusoids plus a slope (gx, gy per cell). */
static double g_sx = 0.3, g_sy = -0.2;

static double surface(double x, double y)
{
    return 100.0 + g_sx * x + g_sy * y + 4.0 * sin(x * 0.37) * cos(y * 0.23) +
           2.5 * sin(0.51 * x + 0.44 * y);
}

static void make_global(trn_grid_f32_t *g)
{
    int x, y;
    for (y = 0; y < GW; ++y) {
        for (x = 0; x < GW; ++x) {
            g_data[y * GW + x] = (float)surface(x, y);
        }
    }
    assert_int_equal(trn_grid_f32_init(g, g_data, GW * GW, GW, GW), TRN_OK);
}

/* Bilinear interpolation of the global DEM (nonsense, -7 km, off it). */
static double bilin(double x, double y)
{
    int x0 = (int)floor(x), y0 = (int)floor(y);
    double fx, fy, a, b, c, d;
    if (!(x >= 0.0 && y >= 0.0 && x <= GW - 1 && y <= GW - 1)) {
        return -7.0e3;
    }
    x0 = x0 > GW - 2 ? GW - 2 : x0;
    y0 = y0 > GW - 2 ? GW - 2 : y0;
    fx = x - x0;
    fy = y - y0;
    a = g_data[y0 * GW + x0];
    b = g_data[y0 * GW + x0 + 1];
    c = g_data[(y0 + 1) * GW + x0];
    d = g_data[(y0 + 1) * GW + x0 + 1];
    return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy;
}

/* Local DEM seen from (tx, ty): the wedge of half-angle 60 degrees around
 * heading `head` (radians), radius LR, rover cell unseen, heights the
 * analytic surface plus dz (nonsense, -7 km, off the global grid): at an
 * integer pose exactly the global nodes, at a sub-cell pose not any
 * interpolation of them. Returns the number of seen cells. */
static int make_wedge(trn_grid_f32_t *l, double tx, double ty, double dz, double head)
{
    int x, y, n = 0;
    for (y = 0; y < LW; ++y) {
        for (x = 0; x < LW; ++x) {
            double dx = x - LR, dy = y - LR, r = sqrt(dx * dx + dy * dy), a = atan2(dy, dx) - head;
            float v = NAN;
            a = atan2(sin(a), cos(a));
            if (r > 0.0 && r <= LR && fabs(a) <= PI / 3.0) {
                double gx = tx + dx, gy = ty + dy;
                v = (float)((gx >= 0.0 && gy >= 0.0 && gx <= GW - 1 && gy <= GW - 1
                                 ? surface(gx, gy)
                                 : -7.0e3) +
                            dz);
                ++n;
            }
            l_data[y * LW + x] = v;
        }
    }
    assert_int_equal(trn_grid_f32_init(l, l_data, LW * LW, LW, LW), TRN_OK);
    return n;
}

typedef struct {
    trn_map_cfg_t cfg;
    trn_map_t map;
    void *buf;
    void *ws;
    size_t wb;
} nat_t;

/* Zero centroids: the cells' centres (trn_localize_dem_centroids gives
 * trn_localize_dem's answer and status). */
static const float g_zero_c[LW * LW];
/* Counts of 1 beside zero centroids (filled in main): one measurement a
 * cell at its centre, trn_localize_dem_cells's statuses as
 * trn_localize_dem's. */
static float g_one_n[LW * LW];
static const trn_local_cells_t g_one_cells = {g_zero_c, g_zero_c, g_one_n};
/* Nothing known of the cells: trn_localize_dem, bit for bit. */
static const trn_local_cells_t g_no_cells = {NULL, NULL, NULL};

static void nat_build(nat_t *w, const trn_map_cfg_t *cfg, const trn_grid_f32_t *g)
{
    size_t mb = trn_map_bytes(cfg, g->width, g->height);
    assert_true(mb > 0u);
    w->cfg = *cfg;
    w->buf = malloc(mb);
    assert_non_null(w->buf);
    assert_int_equal(trn_map_build(&w->map, cfg, g, w->buf, mb), TRN_OK);
    w->ws = NULL;
    w->wb = 0u;
}

static void nat_free(nat_t *w)
{
    free(w->buf);
    free(w->ws);
}

static trn_status_t nat_localize(nat_t *w, const trn_grid_f32_t *local, int rx, int ry,
                                 const trn_window_t *win, trn_loc_result_t *res)
{
    size_t wb = trn_localize_dem_workspace_bytes(&w->map, local->width, local->height, MAXPTS, win);
    assert_true(wb > 0u);
    if (wb > w->wb) {
        free(w->ws);
        w->ws = malloc(wb);
        assert_non_null(w->ws);
        w->wb = wb;
    }
    memset(res, 0, sizeof *res);
    return trn_localize_dem(&w->map, local, rx, ry, MAXPTS, win, w->ws, wb, res);
}

static trn_window_t window_at(int cx, int cy, int half)
{
    trn_window_t win;
    win.x0 = cx - half;
    win.y0 = cy - half;
    win.x1 = cx + half;
    win.y1 = cy + half;
    return win;
}

TRN_WORKSPACE_DECLARE(auto_ws, ((GW + 1) * (GW + 1) * 2 + GW * GW) * sizeof(double));

/* trn_map_cfg_auto with the noise model (1 cm + 0.0004 r^2 / cell). */
static void auto_cfg(trn_map_cfg_t *cfg, const trn_grid_f32_t *g, double *sh)
{
    size_t wb = trn_map_cfg_auto_workspace_bytes(g->width, g->height);
    assert_true(wb > 0u && wb <= sizeof auto_ws);
    trn_map_cfg_default(cfg);
    cfg->noise_m = 0.01f;
    cfg->noise_k_per_m = 0.0004f;
    assert_int_equal(trn_map_cfg_auto(cfg, g, 1.0f, auto_ws, wb, sh), TRN_OK);
}

/* The natural-terrain configuration of trn_map_cfg_auto on the voxel
 * matcher (the paper's search, then TRN_LOCAL_HP_MAP's second pass and the
 * refinement): trn_map_cfg_default with auto's terrain, s, filter,
 * refinement and noise copied over, so the matcher stays the default's
 * whatever auto picks. */
static void voxel_cfg(trn_map_cfg_t *cfg, const trn_grid_f32_t *g, double *sh)
{
    trn_map_cfg_t a;
    auto_cfg(&a, g, sh);
    trn_map_cfg_default(cfg);
    cfg->terrain = a.terrain;
    cfg->sigma_m = a.sigma_m;
    cfg->local_highpass = a.local_highpass;
    cfg->refine = a.refine;
    cfg->noise_m = a.noise_m;
    cfg->noise_k_per_m = a.noise_k_per_m;
    assert_int_equal(cfg->local_highpass, TRN_LOCAL_HP_MAP);
    assert_int_equal(cfg->refine, 1);
}

static void check_cov(const trn_loc_result_t *res)
{
    double det = res->cov_m2[0] * res->cov_m2[1] - res->cov_m2[2] * res->cov_m2[2];
    assert_true(isfinite(res->cov_m2[0]) && isfinite(res->cov_m2[1]) && isfinite(res->cov_m2[2]));
    assert_true(res->cov_m2[0] > 0.0 && res->cov_m2[1] > 0.0 && det > 0.0);
    assert_true(res->sigma_x_m == sqrt(res->cov_m2[0]));
    assert_true(res->sigma_y_m == sqrt(res->cov_m2[1]));
    assert_true(fabs(res->rho - res->cov_m2[2] / (res->sigma_x_m * res->sigma_y_m)) < 1e-12);
    assert_true(fabs(res->rho) < 1.0);
    /* cell = 1 m: cov_m2 is the refinement's cov_cells */
    assert_true(res->cov_m2[0] == res->refinement.cov_cells[0] &&
                res->cov_m2[2] == res->refinement.cov_cells[2]);
}

/* Wedges at integer and sub-cell poses, offset -37.5 m, prior up to 3 cells
 * off: pose within 0.05 cell, refined, covariance positive definite. */
static void wedges(const trn_map_cfg_t *cfg, const trn_grid_f32_t *g, const char *name)
{
    trn_grid_f32_t l;
    nat_t w;
    trn_rng_t r;
    double worst = 0.0, wdz = 0.0;
    int k;
    nat_build(&w, cfg, g);
    assert_non_null(w.map.heights.data);
    assert_non_null(w.map.lowpass.data);
    trn_rng_seed(&r, 21);
    for (k = 0; k < 10; ++k) {
        trn_loc_result_t res;
        trn_window_t win;
        double tx = trn_rng_int(&r, 30, 65), ty = trn_rng_int(&r, 30, 65);
        int seen;
        if (k % 2 == 1) { /* sub-cell */
            tx += trn_rng_unit(&r) - 0.5;
            ty += trn_rng_unit(&r) - 0.5;
        }
        seen = make_wedge(&l, tx, ty, -37.5, 2.0 * PI * trn_rng_unit(&r));
        win = window_at((int)floor(tx + 0.5) + trn_rng_int(&r, -3, 3),
                        (int)floor(ty + 0.5) + trn_rng_int(&r, -3, 3), 6);
        assert_int_equal(nat_localize(&w, &l, LR, LR, &win, &res), TRN_OK);
        assert_int_equal(res.refined, 1);
        worst = fmax(worst, fmax(fabs(res.x - tx), fabs(res.y - ty)));
        wdz = fmax(wdz, fabs(res.refinement.dz_m + 37.5));
        assert_true(fabs(res.x - tx) < 0.05 && fabs(res.y - ty) < 0.05);
        assert_true(fabs(res.refinement.dz_m + 37.5) < 0.01);
        assert_int_equal(res.refinement.n_seen, seen);
        assert_true(res.x == res.refinement.x + res.refinement.spline_step[0] &&
                    res.y == res.refinement.y + res.refinement.spline_step[1]);
        assert_true(res.failure_probability >= 0.0 && res.failure_probability < 0.01);
        check_cov(&res);
    }
    printf("wedges, %s config (zbin %.3f m x %d): worst pose error %.2e cells, dz %.2e m over 10\n",
           name, (double)cfg->terrain.zbin_m, cfg->terrain.nz, worst, wdz);
    nat_free(&w);
}

static void test_wedge_recovers_pose(void **state)
{
    trn_grid_f32_t g;
    trn_map_cfg_t cfg;
    double sh;
    (void)state;
    make_global(&g);
    voxel_cfg(&cfg, &g, &sh);
    wedges(&cfg, &g, "voxel matcher, auto");
    auto_cfg(&cfg, &g, &sh);
    wedges(&cfg, &g, "auto");
}

/* The sensor's noise from the data (trn_map_cfg_t.noise_auto, docs/method.md
 * 9): wedges with noise k times the configured model (1 cm + 0.0004 r^2 /
 * cell). With the model right (k = 1) the height matcher keeps it in at
 * least 8 of 10 cases; with k = 3, unknown to it, it finds the scale within
 * 20 % in at least 8 of 10 and stays within 0.5 cell of the truth, where the
 * configured model alone (noise_auto 0) keeps noise_scale 1. With `smooth`
 * the same errors are spatially smooth (white noise box-averaged over 5 x 5
 * cells, rescaled to the same sd per cell), as a wrong pose or heading leaves
 * them: not sensor noise, so the scale follows their neighbours'
 * differences (a fifth of the variance here), not their level. */
static int noise_auto_run(nat_t *w, double k, int smooth, int *near_k, double *worst)
{
    static double field[(LW + 4) * (LW + 4)];
    trn_rng_t r;
    int i, kept = 0;
    trn_rng_seed(&r, 41);
    *near_k = 0;
    *worst = 0.0;
    for (i = 0; i < 10; ++i) {
        trn_loc_result_t res;
        trn_window_t win;
        double tx = trn_rng_int(&r, 30, 65) + trn_rng_unit(&r) - 0.5,
               ty = trn_rng_int(&r, 30, 65) + trn_rng_unit(&r) - 0.5;
        int x, y;
        trn_grid_f32_t l;
        trn_status_t st;
        (void)make_wedge(&l, tx, ty, 12.0, 2.0 * PI * trn_rng_unit(&r));
        for (y = 0; y < (LW + 4) * (LW + 4); ++y) {
            field[y] = trn_rng_gauss(&r);
        }
        for (y = 0; y < LW; ++y) {
            for (x = 0; x < LW; ++x) {
                double rr = (double)((x - LR) * (x - LR) + (y - LR) * (y - LR)), e = 0.0;
                int a, b;
                if (smooth) { /* the 5 x 5 mean times 5: unit variance, smooth */
                    for (b = 0; b < 5; ++b) {
                        for (a = 0; a < 5; ++a) {
                            e += field[(y + b) * (LW + 4) + x + a] / 5.0;
                        }
                    }
                } else {
                    e = field[(y + 2) * (LW + 4) + x + 2];
                }
                if (!isnan(l_data[y * LW + x])) {
                    l_data[y * LW + x] += (float)(k * (0.01 + 0.0004 * rr) * e);
                }
            }
        }
        win = window_at((int)floor(tx + 0.5) + trn_rng_int(&r, -3, 3),
                        (int)floor(ty + 0.5) + trn_rng_int(&r, -3, 3), 6);
        st = nat_localize(w, &l, LR, LR, &win, &res);
        assert_true(st == TRN_OK || st == TRN_E_AMBIGUOUS || st == TRN_E_ILLCOND);
        assert_true(res.noise_scale > 0.0 && isfinite(res.noise_scale));
        kept += res.noise_scale == 1.0;
        *near_k += fabs(res.noise_scale - k) <= 0.2 * k;
        *worst = fmax(*worst, fmax(fabs(res.x - tx), fabs(res.y - ty)));
    }
    return kept;
}

static void test_noise_auto(void **state)
{
    trn_grid_f32_t g;
    trn_map_cfg_t cfg;
    nat_t w;
    double sh, worst;
    int kept, near_k;
    (void)state;
    make_global(&g);
    auto_cfg(&cfg, &g, &sh);
    assert_int_equal(cfg.noise_auto, 1);
    nat_build(&w, &cfg, &g);
    kept = noise_auto_run(&w, 1.0, 0, &near_k, &worst);
    printf("noise auto, k = 1: model kept in %d of 10, worst error %.3f cells\n", kept, worst);
    assert_true(kept >= 8 && worst < 0.5);
    kept = noise_auto_run(&w, 3.0, 0, &near_k, &worst);
    printf("noise auto, k = 3: scale within 20 %% of 3 in %d of 10 (1 in %d), worst error %.3f "
           "cells\n",
           near_k, kept, worst);
    assert_true(near_k >= 8 && kept <= 2 && worst < 0.5);
    (void)noise_auto_run(&w, 3.0, 1, &near_k, &worst);
    printf("noise auto, k = 3, smooth errors: scale within 20 %% of 3 in %d of 10\n", near_k);
    assert_true(near_k <= 1);
    nat_free(&w);
    cfg.noise_auto = 0;
    nat_build(&w, &cfg, &g);
    kept = noise_auto_run(&w, 3.0, 0, &near_k, &worst);
    printf("noise auto off, k = 3: noise_scale 1 in %d of 10\n", kept);
    assert_int_equal(kept, 10);
    nat_free(&w);
    /* one noise level for every point (noise_k_per_m 0): no scale can be
     * estimated, the model is kept */
    cfg.noise_auto = 1;
    cfg.noise_k_per_m = 0.0f;
    nat_build(&w, &cfg, &g);
    kept = noise_auto_run(&w, 3.0, 0, &near_k, &worst);
    assert_int_equal(kept, 10);
    nat_free(&w);
}

/* noise_auto where the refinement fails (flat ground): the scale is taken at
 * the search's best integer pose; noise-free heights ask for the floor, and
 * the second pass is ill-conditioned as well. */
static void test_noise_auto_flat(void **state)
{
    trn_grid_f32_t g, l;
    trn_map_cfg_t cfg;
    trn_loc_result_t res;
    trn_window_t win = window_at(48, 48, 4);
    nat_t w;
    double sh;
    int i;
    (void)state;
    make_global(&g);
    auto_cfg(&cfg, &g, &sh);
    for (i = 0; i < GW * GW; ++i) {
        g_data[i] = 5.0f;
    }
    nat_build(&w, &cfg, &g);
    (void)make_wedge(&l, 48.0, 48.0, 0.0, 0.0);
    for (i = 0; i < LW * LW; ++i) {
        l_data[i] = isnan(l_data[i]) ? NAN : 5.0f;
    }
    assert_int_equal(nat_localize(&w, &l, LR, LR, &win, &res), TRN_E_ILLCOND);
    assert_int_equal(res.refined, 0);
    assert_true(res.noise_scale == sqrt(TRN_NOISE_SCALE2_MIN));
    nat_free(&w);
}

/* The paper's local filter on a partial view is biased on a slope
 * (docs/method.md section 9, cause 1); the map's low-pass is not. Same
 * wedges on three slopes, each map's own auto bins, refinement off so the
 * voxel search's own pose (eq. 6) is measured. Measured (16 sub-cell wedges,
 * prior on the truth): map filter 0.096 / 0.095 / 0.095 cell mean error on
 * every slope; box filter 0.104 / 0.547 / 4.008, 0 / 1 / 13 cases over 1.5
 * cells. */
static void box_vs_map(double sx, double sy, double *em, double *eb, int *bad_b)
{
    trn_grid_f32_t g, l;
    trn_map_cfg_t cfg;
    nat_t wm, wb;
    trn_rng_t r;
    double sh;
    int k, n = 16, bad_m = 0;
    g_sx = sx;
    g_sy = sy;
    make_global(&g);
    voxel_cfg(&cfg, &g, &sh);
    cfg.refine = 0;
    nat_build(&wm, &cfg, &g);
    cfg.local_highpass = TRN_LOCAL_HP_BOX;
    nat_build(&wb, &cfg, &g);
    trn_rng_seed(&r, 8);
    *em = *eb = 0.0;
    *bad_b = 0;
    for (k = 0; k < n; ++k) {
        trn_loc_result_t rm, rb;
        trn_window_t win;
        double tx = trn_rng_int(&r, 30, 65) + trn_rng_unit(&r) - 0.5,
               ty = trn_rng_int(&r, 30, 65) + trn_rng_unit(&r) - 0.5;
        double e1, e2;
        (void)make_wedge(&l, tx, ty, 5.0, 2.0 * PI * trn_rng_unit(&r));
        win = window_at((int)floor(tx + 0.5), (int)floor(ty + 0.5), 6);
        (void)nat_localize(&wm, &l, LR, LR, &win, &rm);
        (void)nat_localize(&wb, &l, LR, LR, &win, &rb);
        assert_int_equal(rm.refined, 0);
        assert_int_equal(rb.refined, 0);
        e1 = hypot(rm.x - tx, rm.y - ty);
        e2 = hypot(rb.x - tx, rb.y - ty);
        *em += e1 / n;
        *eb += e2 / n;
        bad_m += e1 > 1.5;
        *bad_b += e2 > 1.5;
    }
    printf("wedge on a %.1f / %.1f slope, eq. 6 pose: mean error map filter %.3f, box filter %.3f "
           "cells; "
           "over 1.5 cells %d / %d of %d\n",
           sx, sy, *em, *eb, bad_m, *bad_b, n);
    assert_int_equal(bad_m, 0);
    nat_free(&wm);
    nat_free(&wb);
    g_sx = 0.3;
    g_sy = -0.2;
}

static void test_box_bias_on_slope(void **state)
{
    double em0, eb0, em1, eb1, em2, eb2;
    int b0, b1, b2;
    (void)state;
    box_vs_map(0.0, 0.0, &em0, &eb0, &b0);
    box_vs_map(0.6, 0.3, &em1, &eb1, &b1);
    box_vs_map(1.2, 0.6, &em2, &eb2, &b2); /* 53 degrees */
    /* the map filter does not see the slope (it cancels exactly) */
    assert_true(fabs(em1 - em0) < 0.02 && fabs(em2 - em0) < 0.02 && em0 < 0.2);
    /* the box filter is as good on flat ground, worse with every slope */
    assert_true(fabs(eb0 - em0) < 0.05);
    assert_true(eb1 > em1 + 0.2 && eb2 > eb1 && eb2 > 1.0);
    assert_true(b0 == 0 && b2 >= 8);
}

/* A constant added to the local heights is removed exactly by the map
 * filter (the mean difference) and absorbed by the refinement's dz: same
 * points, same voxel pose and likelihood, the same refined pose to float
 * rounding of the heights, dz moved by the constant. (A plane is not removed
 * exactly: only the map's own slope cancels.) */
static void test_constant_offset_invariance(void **state)
{
    trn_grid_f32_t g, l;
    trn_map_cfg_t cfg;
    nat_t w;
    trn_rng_t r;
    double sh;
    static float base[LW * LW];
    int k, i;
    (void)state;
    make_global(&g);
    voxel_cfg(&cfg, &g, &sh);
    nat_build(&w, &cfg, &g);
    trn_rng_seed(&r, 4);
    for (k = 0; k < 6; ++k) {
        trn_loc_result_t a, b;
        trn_status_t sa, sb;
        double tx = trn_rng_int(&r, 30, 65) + trn_rng_unit(&r) - 0.5,
               ty = trn_rng_int(&r, 30, 65) + trn_rng_unit(&r) - 0.5;
        trn_window_t win;
        (void)make_wedge(&l, tx, ty, 0.0, 2.0 * PI * trn_rng_unit(&r));
        win = window_at((int)floor(tx + 0.5) + 2, (int)floor(ty + 0.5) - 1, 6);
        memcpy(base, l_data, sizeof base);
        sa = nat_localize(&w, &l, LR, LR, &win, &a);
        for (i = 0; i < LW * LW; ++i) {
            l_data[i] = base[i] + 64.0f;
        }
        sb = nat_localize(&w, &l, LR, LR, &win, &b);
        assert_int_equal(sa, TRN_OK);
        assert_int_equal(sb, TRN_OK);
        assert_int_equal(a.ix, b.ix);
        assert_int_equal(a.iy, b.iy);
        assert_true(a.n_points == b.n_points);
        assert_true(a.ll_best == b.ll_best);
        assert_true(fabs(a.x - b.x) < 1e-4 && fabs(a.y - b.y) < 1e-4);
        assert_true(fabs(b.refinement.dz_m - a.refinement.dz_m - 64.0) < 1e-3);
        assert_true(fabs(a.x - tx) < 0.05 && fabs(a.y - ty) < 0.05);
    }
    nat_free(&w);
}

/* TRN_LOCAL_HP_MAP as documented, on the public blocks: local cell (x, y)
 * minus the map's low-pass at (cx + x - LR, cy + y - LR), minus the mean
 * difference (same arithmetic as the library), occupancy, ordering, then
 * trn_localize_points over win. */
static trn_status_t emulate_pass(const nat_t *w, const trn_grid_f32_t *l, int cx, int cy,
                                 const trn_window_t *win, trn_loc_result_t *out)
{
    static float hpd[LW * LW];
    static trn_point_t pts[MAXPTS];
    trn_grid_f32_t hp;
    double sum = 0.0, ref = 0.0, mean;
    size_t n = 0, np = 0;
    size_t wb = trn_localize_workspace_bytes(&w->map, win);
    void *ws;
    trn_status_t st;
    int x, y;
    for (y = 0; y < LW; ++y) {
        for (x = 0; x < LW; ++x) {
            int gx = cx + x - LR, gy = cy + y - LR;
            float h = l->data[y * LW + x], v = NAN;
            if (isfinite(h) && gx >= 0 && gy >= 0 && gx < GW && gy < GW &&
                isfinite(TRN_GRID_AT(&w->map.lowpass, gx, gy))) {
                double d = (double)h - (double)TRN_GRID_AT(&w->map.lowpass, gx, gy);
                if (n == 0u) {
                    ref = d;
                }
                sum += d - ref;
                ++n;
                v = (float)d;
            }
            hpd[y * LW + x] = v;
        }
    }
    mean = ref + sum / (double)n;
    for (x = 0; x < LW * LW; ++x) {
        if (isfinite(hpd[x])) {
            hpd[x] = (float)((double)hpd[x] - mean);
        }
    }
    assert_int_equal(trn_grid_f32_init(&hp, hpd, LW * LW, LW, LW), TRN_OK);
    assert_int_equal(trn_occupancy_points(&hp, &w->map.cfg.terrain, LR, LR, pts, MAXPTS, &np),
                     TRN_OK);
    assert_int_equal(trn_points_order(pts, np, w->map.cfg.terrain.nz), TRN_OK);
    ws = malloc(wb);
    assert_non_null(ws);
    memset(out, 0, sizeof *out);
    st = trn_localize_points(&w->map, pts, np, win, ws, wb, out);
    free(ws);
    return st;
}

/* The second pass: from a prior window centred 4 cells off the truth, the
 * first pass filters at the window centre; when its pose differs, the filter
 * is referred to that pose and the search runs again. Oracle: the two passes
 * emulated on the public blocks give trn_localize_dem's result to the bit
 * (refinement off, so eq. 6, which depends on the filter, is compared); the
 * first pass alone differs from it in some case; with the refinement on,
 * the pose comes back within 0.05 cell from the same prior. */
static void test_second_pass(void **state)
{
    trn_grid_f32_t g, l;
    trn_map_cfg_t cfg;
    nat_t w, wr;
    trn_rng_t r;
    double sh, e1 = 0.0, e2 = 0.0;
    int k, differ = 0, n = 8;
    (void)state;
    make_global(&g);
    voxel_cfg(&cfg, &g, &sh);
    nat_build(&wr, &cfg, &g);
    cfg.refine = 0;
    nat_build(&w, &cfg, &g);
    trn_rng_seed(&r, 12);
    for (k = 0; k < n; ++k) {
        trn_loc_result_t a, p1, p2, c;
        double tx = trn_rng_int(&r, 30, 65) + trn_rng_unit(&r) - 0.5,
               ty = trn_rng_int(&r, 30, 65) + trn_rng_unit(&r) - 0.5;
        int px = (int)floor(tx + 0.5) + (k % 2 ? 4 : -4),
            py = (int)floor(ty + 0.5) + (k / 2 % 2 ? 4 : -4);
        trn_window_t far = window_at(px, py, 6);
        (void)make_wedge(&l, tx, ty, 2.0, 2.0 * PI * trn_rng_unit(&r));
        assert_int_equal(nat_localize(&w, &l, LR, LR, &far, &a), TRN_OK);
        assert_int_equal(emulate_pass(&w, &l, px, py, &far, &p1), TRN_OK);
        assert_true(p1.ix != px || p1.iy != py); /* the second pass runs */
        assert_int_equal(emulate_pass(&w, &l, p1.ix, p1.iy, &far, &p2), TRN_OK);
        assert_int_equal(a.ix, p2.ix);
        assert_int_equal(a.iy, p2.iy);
        assert_true(a.x == p2.x && a.y == p2.y && a.ll_best == p2.ll_best &&
                    a.n_points == p2.n_points);
        assert_true(a.cov_m2[0] == p2.cov_m2[0] && a.cov_m2[2] == p2.cov_m2[2]);
        differ += p1.x != a.x || p1.y != a.y;
        e1 += hypot(p1.x - tx, p1.y - ty) / n;
        e2 += hypot(a.x - tx, a.y - ty) / n;
        assert_true(fabs(a.x - tx) < 0.5 && fabs(a.y - ty) < 0.5);
        assert_int_equal(nat_localize(&wr, &l, LR, LR, &far, &c), TRN_OK);
        assert_int_equal(c.refined, 1);
        assert_true(fabs(c.x - tx) < 0.05 && fabs(c.y - ty) < 0.05);
    }
    printf("prior 4 cells off: eq. 6 mean error first pass %.3f, after the second %.3f cells; "
           "changed in %d of %d\n",
           e1, e2, differ, n);
    assert_true(differ > 0);
    assert_true(e2 < e1); /* measured 0.118 -> 0.091 */
    nat_free(&w);
    nat_free(&wr);
}

/* A local cell with no global low-pass under it at the window centre (off
 * the map, or over a NaN of the DEM) is left unseen: the result equals the
 * one with those cells marked NaN by hand. With no cell on the low-pass at
 * all: TRN_E_NODATA. */
static void test_map_filter_unseen_cells(void **state)
{
    trn_grid_f32_t g, l;
    trn_map_cfg_t cfg;
    nat_t w;
    double sh;
    static float base[LW * LW];
    trn_loc_result_t a, b;
    trn_status_t sa, sb;
    trn_window_t win;
    int x, y, cut;
    (void)state;
    make_global(&g);
    voxel_cfg(&cfg, &g, &sh);
    cfg.refine = 0; /* the refinement reads the raw local heights */
    /* a 6 x 6 NaN hole in the DEM at cells [40, 46) x [50, 56) */
    for (y = 50; y < 56; ++y) {
        for (x = 40; x < 46; ++x) {
            g_data[y * GW + x] = NAN;
        }
    }
    nat_build(&w, &cfg, &g);
    for (y = 0; y < GW; ++y) {
        for (x = 0; x < GW; ++x) {
            int hole = x >= 40 && x < 46 && y >= 50 && y < 56;
            assert_true(hole ? isnan(TRN_GRID_AT(&w.map.heights, x, y)) &&
                                   isnan(TRN_GRID_AT(&w.map.lowpass, x, y))
                             : TRN_GRID_AT(&w.map.heights, x, y) == g_data[y * GW + x] &&
                                   isfinite(TRN_GRID_AT(&w.map.lowpass, x, y)));
        }
    }
    make_global(&g); /* the local heights come from the full surface */

    /* (1) over the hole: rover at (40, 40), wedge towards +y covers the hole */
    (void)make_wedge(&l, 40.0, 40.0, 1.0, PI / 2.0);
    win = window_at(40, 40, 0); /* one pose: no second pass */
    memcpy(base, l_data, sizeof base);
    sa = nat_localize(&w, &l, LR, LR, &win, &a);
    for (cut = 0, y = 0; y < LW; ++y) {
        for (x = 0; x < LW; ++x) {
            int gx = 40 + x - LR, gy = 40 + y - LR;
            if (gx >= 40 && gx < 46 && gy >= 50 && gy < 56 && isfinite(l_data[y * LW + x])) {
                l_data[y * LW + x] = NAN;
                ++cut;
            }
        }
    }
    assert_true(cut > 20);
    sb = nat_localize(&w, &l, LR, LR, &win, &b);
    assert_int_equal(sa, sb);
    assert_int_equal(a.ix, b.ix);
    assert_int_equal(a.iy, b.iy);
    assert_true(a.x == b.x && a.y == b.y && a.n_points == b.n_points && a.ll_best == b.ll_best);

    /* (2) off the map: rover at (8, 60), wedge towards -x: cells at x < 0 */
    (void)make_wedge(&l, 8.0, 60.0, 1.0, PI);
    for (cut = 0, y = 0; y < LW; ++y) {
        for (x = 0; x < LW; ++x) {
            if (8 + x - LR < 0 && isfinite(l_data[y * LW + x])) {
                l_data[y * LW + x] = 3.0e3f; /* nonsense heights: they must not matter */
                ++cut;
            }
        }
    }
    assert_true(cut > 20);
    win = window_at(8, 60, 0);
    sa = nat_localize(&w, &l, LR, LR, &win, &a);
    for (y = 0; y < LW; ++y) {
        for (x = 0; x < LW; ++x) {
            if (8 + x - LR < 0) {
                l_data[y * LW + x] = NAN;
            }
        }
    }
    sb = nat_localize(&w, &l, LR, LR, &win, &b);
    assert_int_equal(sa, TRN_OK);
    assert_int_equal(sb, TRN_OK);
    assert_true(a.ix == 8 && a.iy == 60);
    assert_true(a.x == b.x && a.y == b.y && a.n_points == b.n_points && a.ll_best == b.ll_best);

    /* (3) nothing on the low-pass: every local cell off the map (rover far
     * outside its grid), or every seen cell over the hole */
    (void)make_wedge(&l, 40.0, 40.0, 1.0, 0.0);
    assert_int_equal(nat_localize(&w, &l, LR - 200, LR, &win, &a), TRN_E_NODATA);
    for (y = 0; y < LW; ++y) {
        for (x = 0; x < LW; ++x) {
            l_data[y * LW + x] = (x == LR + 1 && y == LR) || (x == LR + 2 && y == LR) ? 100.0f
                                                                                      : NAN;
        }
    }
    win = window_at(42, 52, 2); /* rover + (1..2, 0) lands in the hole */
    assert_int_equal(nat_localize(&w, &l, LR, LR, &win, &a), TRN_E_NODATA);
    nat_free(&w);
}

/* Refinement failure inside trn_localize_dem: TRN_E_ILLCOND, refined = 0,
 * the eq. 6 pose and covariance kept (equal to the run without refinement).
 * Cases: local DEMs from another place (truth 22 cells outside the window),
 * and pure noise over flat ground.
 * Measured on the first (8 cases), before the misfit flag: 5 failed the
 * refinement (ILLCOND); 3 were refined with every point an inlier and came
 * back TRN_OK, 30 cells wrong, failure probability < 1e-36, their model
 * error (1.3-2.3 m) the only sign. Since the misfit flag (model error above
 * TRN_MISFIT_ROUGHNESS x the map's roughness) all 8 are TRN_E_ILLCOND;
 * asserted. */
static void test_refine_failure_is_illcond(void **state)
{
    trn_grid_f32_t g, l;
    trn_map_cfg_t cfg;
    nat_t w, w0;
    trn_rng_t r;
    double sh;
    int k, i, fails = 0, n = 8;
    (void)state;
    make_global(&g);
    voxel_cfg(&cfg, &g, &sh);
    nat_build(&w, &cfg, &g);
    cfg.refine = 0;
    nat_build(&w0, &cfg, &g);
    trn_rng_seed(&r, 31);
    for (k = 0; k < n; ++k) {
        trn_loc_result_t a, b;
        trn_status_t sa, sb;
        double tx = trn_rng_int(&r, 25, 70), ty = trn_rng_int(&r, 25, 70);
        trn_window_t win = window_at(tx < 47 ? (int)tx + 22 : (int)tx - 22,
                                     ty < 47 ? (int)ty + 22 : (int)ty - 22, 4);
        (void)make_wedge(&l, tx, ty, 0.0, 2.0 * PI * trn_rng_unit(&r));
        sa = nat_localize(&w, &l, LR, LR, &win, &a);
        sb = nat_localize(&w0, &l, LR, LR, &win, &b);
        assert_true(sb == TRN_OK || sb == TRN_E_ILLCOND);
        assert_int_equal(a.ix, b.ix);
        assert_int_equal(a.iy, b.iy);
        if (sa == TRN_E_ILLCOND && a.refined == 0) {
            ++fails;
            assert_true(a.x == b.x && a.y == b.y && a.sigma_x_m == b.sigma_x_m &&
                        a.cov_m2[1] == b.cov_m2[1]);
            assert_true(isinf(a.refinement.cov_cells[0]));
        } else if (sa == TRN_E_ILLCOND) {
            /* refined, but flagged: the model error is beyond the map's roughness */
            ++fails;
            assert_int_equal(a.misfit, 1);
            assert_true(a.refinement.model_m > TRN_MISFIT_ROUGHNESS * w.map.roughness_m);
        } else {
            assert_int_equal(sa, TRN_OK);
            assert_int_equal(a.refined, 1);
            printf("local DEM from elsewhere accepted: error %.1f cells, P_fail %.2g, model error "
                   "%.2f m "
                   "(voxel search alone: status %d)\n",
                   hypot(a.x - tx, a.y - ty), a.failure_probability, a.refinement.model_m, sb);
            assert_true(a.refinement.model_m > 1.0);
        }
    }
    printf("local DEM from another place: refinement failed %d of %d\n", fails, n);
    assert_int_equal(fails, n); /* every one flagged (misfit or failed refinement) */
    nat_free(&w);
    nat_free(&w0);
    /* pure noise over flat ground */
    for (i = 0; i < GW * GW; ++i) {
        g_data[i] = 12.0f;
    }
    voxel_cfg(&cfg, &g, &sh);
    assert_true(sh < 1e-6);
    nat_build(&w, &cfg, &g);
    {
        trn_loc_result_t a;
        trn_window_t win = window_at(48, 48, 4);
        int x, y;
        (void)make_wedge(&l, 48.0, 48.0, 0.0, 0.0);
        for (y = 0; y < LW; ++y) {
            for (x = 0; x < LW; ++x) {
                if (isfinite(l_data[y * LW + x])) {
                    l_data[y * LW + x] = (float)(12.0 + 0.5 * (trn_rng_unit(&r) - 0.5));
                }
            }
        }
        assert_int_equal(nat_localize(&w, &l, LR, LR, &win, &a), TRN_E_ILLCOND);
        assert_int_equal(a.refined, 0);
        assert_true(isinf(a.refinement.cov_cells[0]));
        assert_int_equal(trn_localize_dem_centroids(&w.map, &l, g_zero_c, g_zero_c, LR, LR, MAXPTS,
                                                    &win, w.ws, w.wb, &a),
                         TRN_E_ILLCOND);
        assert_int_equal(
            trn_localize_dem_cells(&w.map, &l, &g_one_cells, LR, LR, MAXPTS, &win, w.ws, w.wb, &a),
            TRN_E_ILLCOND);
    }
    nat_free(&w);
}

/* trn_map_cfg_check: each new field out of range, and its boundaries. */
static void test_cfg_check_new_fields(void **state)
{
    trn_map_cfg_t c, b;
    (void)state;
    trn_map_cfg_default(&c);
    assert_int_equal(c.local_highpass, TRN_LOCAL_HP_BOX);
    assert_int_equal(c.refine, 0);
    assert_int_equal(trn_map_cfg_check(&c), TRN_OK);
    b = c;
    b.local_highpass = TRN_LOCAL_HP_MAP;
    assert_int_equal(trn_map_cfg_check(&b), TRN_OK);
    b = c;
    b.local_highpass = 2;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    assert_int_equal(c.noise_auto, 0);
    b = c;
    b.noise_auto = 1;
    assert_int_equal(trn_map_cfg_check(&b), TRN_OK);
    b.noise_auto = 2;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b.noise_auto = -1;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.local_highpass = -1;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.refine = 1;
    assert_int_equal(trn_map_cfg_check(&b), TRN_OK);
    b = c;
    b.refine = 2;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.refine = -1;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.noise_m = NAN;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.noise_m = 0.0f;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.noise_m = -0.01f;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.noise_m = 1e-30f;
    assert_int_equal(trn_map_cfg_check(&b), TRN_OK);
    b = c;
    b.noise_m = 1000.0f;
    assert_int_equal(trn_map_cfg_check(&b), TRN_OK);
    b = c;
    b.noise_m = 1000.0001f;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.noise_m = INFINITY;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.noise_k_per_m = NAN;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.noise_k_per_m = -1e-30f;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.noise_k_per_m = 0.0f;
    assert_int_equal(trn_map_cfg_check(&b), TRN_OK);
    b = c;
    b.noise_k_per_m = 1000.0f;
    assert_int_equal(trn_map_cfg_check(&b), TRN_OK);
    b = c;
    b.noise_k_per_m = 1000.0001f;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    assert_true(c.max_failure_prob == 1.0f);
    b = c;
    b.max_failure_prob = NAN;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.max_failure_prob = 0.0f;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.max_failure_prob = -0.05f;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.max_failure_prob = 1.0001f;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.max_failure_prob = INFINITY;
    assert_int_equal(trn_map_cfg_check(&b), TRN_E_ARG);
    b = c;
    b.max_failure_prob = 1e-6f;
    assert_int_equal(trn_map_cfg_check(&b), TRN_OK);
    /* the map sizing and building refuse the same configurations */
    b = c;
    b.refine = 2;
    assert_int_equal(trn_map_bytes(&b, 8, 8), 0u);
}

/* The acceptance test. A DEM that repeats every 3 cells along x (and not
 * along y): a local map taken exactly from it matches equally well 3 cells
 * either side, so the failure probability is about 2/3. With auto's limit
 * (TRN_MAP_MAX_FAILURE_PROB_AUTO) the answer is TRN_E_AMBIGUOUS with
 * everything filled in; with the limit 1 the same answer is TRN_OK; the
 * limit is strict (a failure probability equal to it passes). */
static void test_ambiguous_acceptance(void **state)
{
    trn_grid_f32_t g, l;
    trn_map_cfg_t cfg;
    nat_t w;
    trn_loc_result_t amb, ok, edge;
    trn_status_t st;
    trn_window_t win = window_at(48, 48, 4);
    double sh;
    int x, y;
    (void)state;
    for (y = 0; y < GW; ++y) {
        for (x = 0; x < GW; ++x) {
            g_data[y * GW + x] = (float)(3.0 * sin(2.0 * PI * x / 3.0) + 4.0 * sin(0.37 * y) +
                                         1.5 * cos(0.61 * y));
        }
    }
    assert_int_equal(trn_grid_f32_init(&g, g_data, GW * GW, GW, GW), TRN_OK);
    for (y = 0; y < LW; ++y) {
        for (x = 0; x < LW; ++x) {
            l_data[y * LW + x] = g_data[(48 - LR + y) * GW + 48 - LR + x] + 2.0f;
        }
    }
    l_data[LR * LW + LR] = NAN;
    assert_int_equal(trn_grid_f32_init(&l, l_data, LW * LW, LW, LW), TRN_OK);
    auto_cfg(&cfg, &g, &sh);
    assert_true(cfg.max_failure_prob == (float)TRN_MAP_MAX_FAILURE_PROB_AUTO);
    nat_build(&w, &cfg, &g);
    assert_int_equal(nat_localize(&w, &l, LR, LR, &win, &amb), TRN_E_AMBIGUOUS);
    assert_int_equal(trn_localize_dem_centroids(&w.map, &l, g_zero_c, g_zero_c, LR, LR, MAXPTS,
                                                &win, w.ws, w.wb, &amb),
                     TRN_E_AMBIGUOUS);
    assert_int_equal(
        trn_localize_dem_cells(&w.map, &l, &g_one_cells, LR, LR, MAXPTS, &win, w.ws, w.wb, &amb),
        TRN_E_AMBIGUOUS);
    nat_free(&w);
    printf("periodic DEM: answer (%.3f, %.3f), failure probability %.3f\n", amb.x, amb.y,
           amb.failure_probability);
    assert_true(amb.failure_probability > 0.5 && amb.failure_probability < 0.8);
    assert_true(amb.refined == 1 && amb.misfit == 0 && isfinite(amb.cov_m2[0]));
    assert_true(fabs(amb.y - 48.0) < 1e-3 && fmod(fabs(amb.x - 48.0) + 1e-3, 3.0) < 2e-3);
    cfg.max_failure_prob = 1.0f;
    nat_build(&w, &cfg, &g);
    assert_int_equal(nat_localize(&w, &l, LR, LR, &win, &ok), TRN_OK);
    nat_free(&w);
    assert_true(ok.x == amb.x && ok.y == amb.y &&
                ok.failure_probability == amb.failure_probability);
    assert_true(ok.cov_m2[0] == amb.cov_m2[0] && ok.cov_m2[1] == amb.cov_m2[1]);
    cfg.max_failure_prob = (float)amb.failure_probability;
    nat_build(&w, &cfg, &g);
    st = nat_localize(&w, &l, LR, LR, &win, &edge);
    assert_int_equal(st, edge.failure_probability > (double)cfg.max_failure_prob ? TRN_E_AMBIGUOUS
                                                                                 : TRN_OK);
    cfg.max_failure_prob = nextafterf((float)amb.failure_probability, 0.0f);
    w.map.cfg.max_failure_prob = cfg.max_failure_prob;
    assert_int_equal(trn_localize_dem(&w.map, &l, LR, LR, MAXPTS, &win, w.ws, w.wb, &edge),
                     TRN_E_AMBIGUOUS);
    nat_free(&w);
}

/* P(|e| > r) of a 2-D normal written out: the density summed over a grid
 * of step h (midpoints) on +-8 of the larger sd, outside the circle. */
static double slow_beyond(const double cov[3], double r, double h)
{
    const double det = cov[0] * cov[1] - cov[2] * cov[2];
    const double span = 8.0 * sqrt(fmax(cov[0], cov[1]));
    const int n = (int)ceil(2.0 * span / h);
    double sum = 0.0;
    int i, j;
    for (j = 0; j < n; ++j) {
        const double y = -span + (j + 0.5) * h;
        for (i = 0; i < n; ++i) {
            const double x = -span + (i + 0.5) * h;
            if (x * x + y * y > r * r) {
                const double q = (cov[1] * x * x - 2.0 * cov[2] * x * y + cov[0] * y * y) / det;
                sum += exp(-0.5 * q);
            }
        }
    }
    return sum * h * h / (2.0 * PI * sqrt(det));
}

/* trn_prob_beyond against closed forms and a slow sum: an isotropic error
 * (exp(-r^2 / 2 sigma^2), the Rayleigh tail) for several sigmas; one
 * variance 0 (the 1-D tail, erfc(r / (sqrt 2 sigma))), along each axis and
 * turned; elongated and turned ellipses against slow_beyond. */
static void test_prob_beyond(void **state)
{
    const double ell[4][3] = {
        {0.8, 0.25, 0.3}, {0.04, 0.9, -0.1}, {0.5, 0.5, 0.45}, {2.0, 1.0, 0.0}};
    double p, cov[3], worst = 0.0;
    int i;
    (void)state;
    for (i = 1; i <= 8; ++i) {
        const double s = 0.25 * i;
        cov[0] = cov[1] = s * s;
        cov[2] = 0.0;
        assert_int_equal(trn_prob_beyond(cov, 1.5, &p), TRN_OK);
        assert_true(fabs(p - exp(-1.125 / (s * s))) < 1e-12);
    }
    for (i = 0; i < 3; ++i) {
        const double s = 0.7, th = 0.4 * i;
        cov[0] = s * s * cos(th) * cos(th);
        cov[1] = s * s * sin(th) * sin(th);
        cov[2] = s * s * cos(th) * sin(th);
        assert_int_equal(trn_prob_beyond(cov, 1.5, &p), TRN_OK);
        worst = fmax(worst, fabs(p - erfc(1.5 / (sqrt(2.0) * s))));
    }
    for (i = 0; i < 4; ++i) {
        const double want = slow_beyond(ell[i], 1.5, 0.005);
        assert_int_equal(trn_prob_beyond(ell[i], 1.5, &p), TRN_OK);
        printf("ellipse %d: P(|e| > 1.5) %.6f, written out %.6f\n", i, p, want);
        worst = fmax(worst, fabs(p - want));
    }
    printf("trn_prob_beyond: worst difference %.2e\n", worst);
    assert_true(worst < 1e-4);
}

/* A straight kerb across the map's centre at 0.5 rad to the grid: tanh
 * across it, 3 cells wide, its height 1 m + 1e-4 m v^2 (v cells along it
 * from the centre): along the kerb a pose is pinned down to about a cell,
 * across it to a few hundredths. */
static double kerb(double x, double y)
{
    const double c = cos(0.5), sn = sin(0.5);
    const double u = (x - 48.0) * sn - (y - 48.0) * c, v = (x - 48.0) * c + (y - 48.0) * sn;
    return 10.0 + (1.0 + 1e-4 * v * v) * tanh(u / 3.0);
}

/* Keys' cubic convolution weight (a = -1/2). */
static double keys_w(double t)
{
    double u = fabs(t);
    return u < 1.0   ? 1.5 * u * u * u - 2.5 * u * u + 1.0
           : u < 2.0 ? -0.5 * u * u * u + 2.5 * u * u - 4.0 * u + 2.0
                     : 0.0;
}

/* The refinement's interpolant of the global DEM at (x, y): bilinear plus
 * mix times (Keys - bilinear), written out (interior points only). */
static double mixed(double x, double y, double mix)
{
    int x0 = (int)floor(x), y0 = (int)floor(y), i, j;
    double c = 0.0;
    for (j = -1; j <= 2; ++j) {
        for (i = -1; i <= 2; ++i) {
            c += keys_w(x - (x0 + i)) * keys_w(y - (y0 + j)) * g_data[(y0 + j) * GW + x0 + i];
        }
    }
    return bilin(x, y) + mix * (c - bilin(x, y));
}

/* Local cell c's residual at pose (x, y) under the refinement's mix, and in
 * *v its noise variance plus the model variance; NaN where unseen. */
static double slow_resid(const trn_map_cfg_t *cfg, const trn_refine_t *at, double x, double y,
                         int c, double *v)
{
    const int dx = c % LW - LR, dy = c / LW - LR;
    const double s = (double)cfg->noise_m +
                     (double)cfg->noise_k_per_m * (double)(dx * dx + dy * dy);
    *v = s * s + at->model_m * at->model_m;
    return isfinite(l_data[c]) ? l_data[c] - mixed(x + dx, y + dy, at->interp_mix) : (double)NAN;
}

/* The mixture ln L of the local map at pose (x, y) (global cells of the
 * rover cell) with the refinement's mix and model variance, the offset
 * the noise-weighted mean of the residuals: written out, slowly. */
static double slow_pose_ll(const trn_map_cfg_t *cfg, const trn_refine_t *at, double x, double y)
{
    double mean = 0.0, var = 0.0, sw = 0.0, swr = 0.0, dz, k, ll = 0.0, v, r;
    const double a = (double)cfg->inlier_prob;
    int i, n = 0;
    for (i = 0; i < LW * LW; ++i) {
        if (isfinite(l_data[i])) {
            mean += l_data[i];
            ++n;
        }
    }
    mean /= n;
    for (i = 0; i < LW * LW; ++i) {
        if (isfinite(l_data[i])) {
            var += (l_data[i] - mean) * (l_data[i] - mean);
        }
    }
    k = 1.0 / (10.0 * fmax(sqrt(var / n), (double)cfg->noise_m));
    for (i = 0; i < LW * LW; ++i) { /* the offset */
        r = slow_resid(cfg, at, x, y, i, &v);
        if (isfinite(r)) {
            sw += 1.0 / v;
            swr += r / v;
        }
    }
    dz = swr / sw;
    for (i = 0; i < LW * LW; ++i) {
        r = slow_resid(cfg, at, x, y, i, &v);
        if (isfinite(r)) {
            ll += log(a * exp(-0.5 * (r - dz) * (r - dz) / v) / sqrt(2.0 * PI * v) + (1.0 - a) * k);
        }
    }
    return ll;
}

/* The valley's failure probability written out: ln L along the major axis
 * of the answer's covariance every quarter cell out to 4 cells (or the
 * window), each point's perpendicular offset the best of a 0.005-cell
 * scan, the mass beyond 1.5 cells over the whole (the centre's by the
 * quadratic through its first steps where narrower than a step). */
static double slow_valley(const trn_map_cfg_t *cfg, const trn_refine_t *at, const trn_window_t *win)
{
    const double th = 0.5 * atan2(2.0 * at->cov_cells[2], at->cov_cells[0] - at->cov_cells[1]);
    const double e1x = cos(th), e1y = sin(th);
    double in = 1.0, out = 0.0, d1[2] = {0.0, 0.0}, q;
    int side, kk, m;
    for (side = 0; side < 2; ++side) {
        for (kk = 1; kk <= 16; ++kk) {
            const double t = (side == 0 ? -0.25 : 0.25) * kk;
            const double px = at->x + t * e1x, py = at->y + t * e1y;
            double best = -INFINITY;
            if (px < win->x0 || px > win->x1 || py < win->y0 || py > win->y1) {
                break;
            }
            for (m = -50; m <= 50; ++m) {
                best = fmax(best,
                            slow_pose_ll(cfg, at, px - 0.005 * m * e1y, py + 0.005 * m * e1x));
            }
            best -= at->ll;
            if (kk == 1) {
                d1[side] = best;
            }
            if (kk > 6) {
                out += exp(best);
            } else {
                in += exp(best);
            }
            if (best < -30.0) {
                break;
            }
        }
    }
    q = -(d1[0] + d1[1]) / 0.0625;
    if (q > 0.0) {
        in += fmin(1.0, sqrt(2.0 * PI / q) / 0.25) - 1.0;
    }
    return out / (in + out);
}

/* The valley (docs/method.md 9): along a straight kerb a pose is known to
 * about a cell, across it to hundredths, so the integer poses sample the
 * valley only where it passes close to them, and its mass beyond the
 * failure radius can vanish from the grid (measured before the valley's
 * share: answers 0.88 and 2.65 cells off were fixes at failure
 * probabilities 3e-9 and 3e-12, where the valley's share is 0.44 and
 * 0.31). Local maps of the kerb (a disc of radius 20, the
 * noise model's noise) from 8 truths within a cell of its centre: every
 * refined answer's failure probability is at least the valley's, written
 * out (slow_valley), and where that is above 0.05, equal to the larger of
 * it and the reported ellipse's tail within 0.01 + 5 % (measured: within
 * 0.002); every answer more than 1.5 cells off is no fix. */
static void test_valley_failure(void **state)
{
    trn_grid_f32_t g, l;
    trn_map_cfg_t cfg;
    nat_t w;
    trn_loc_result_t res;
    trn_window_t win = window_at(48, 48, 8);
    trn_rng_t r;
    double sh;
    int x, y, i, checked = 0;
    (void)state;
    for (y = 0; y < GW; ++y) {
        for (x = 0; x < GW; ++x) {
            g_data[y * GW + x] = (float)kerb(x, y);
        }
    }
    assert_int_equal(trn_grid_f32_init(&g, g_data, GW * GW, GW, GW), TRN_OK);
    auto_cfg(&cfg, &g, &sh);
    nat_build(&w, &cfg, &g);
    trn_rng_seed(&r, 5);
    for (i = 0; i < 8; ++i) {
        const double tx = 48.0 + trn_rng_unit(&r), ty = 48.0 + trn_rng_unit(&r);
        trn_status_t st;
        double err, slow;
        for (y = 0; y < LW; ++y) {
            for (x = 0; x < LW; ++x) {
                const double dx = x - LR, dy = y - LR;
                const double s = 0.01 + 0.0004 * (dx * dx + dy * dy);
                l_data[y * LW + x] = dx * dx + dy * dy <= LR * LR
                                         ? (float)(bilin(tx + dx, ty + dy) + 1.0 +
                                                   s * trn_rng_gauss(&r))
                                         : NAN;
            }
        }
        l_data[LR * LW + LR] = NAN;
        assert_int_equal(trn_grid_f32_init(&l, l_data, LW * LW, LW, LW), TRN_OK);
        st = nat_localize(&w, &l, LR, LR, &win, &res);
        err = hypot(res.x - tx, res.y - ty);
        slow = res.refined ? slow_valley(&cfg, &res.refinement, &win) : 0.0;
        printf("kerb %d: status %d, error %.2f cells, sigmas (%.2f, %.2f), failure probability "
               "%.3g, the valley's written out %.3g\n",
               i, (int)st, err, res.sigma_x_m, res.sigma_y_m, res.failure_probability, slow);
        if (err > TRN_FAIL_RADIUS_CELLS) {
            assert_int_not_equal(st, TRN_OK);
        }
        if (st == TRN_OK || st == TRN_E_AMBIGUOUS) {
            double tail = 0.0;
            assert_true(res.refined == 1 && res.noise_scale == 1.0);
            assert_int_equal(
                trn_prob_beyond(res.refinement.cov_cells, TRN_FAIL_RADIUS_CELLS, &tail), TRN_OK);
            assert_true(res.failure_probability >= tail);
            assert_true(res.failure_probability >= slow - 0.01 - 0.05 * slow);
            if (slow > 0.05) {
                /* here the grid's and the far basins' shares are below it:
                 * the larger of the valley's and the ellipse's tail (the
                 * ellipse widened by its shoulders along the valley,
                 * docs/method.md 9) */
                const double top = fmax(slow, tail);
                assert_true(fabs(res.failure_probability - top) < 0.01 + 0.05 * top);
                checked += 1;
            }
        }
    }
    assert_true(checked >= 2); /* the construction does make valleys */
    nat_free(&w);
}

/* The height matcher's answer on the window's edge is no fix: a wedge of
 * the natural surface at a sub-cell truth, windows whose edge passes 1-3
 * cells short of it (the prior missed it) on each side: the best pose lies
 * on that edge, refined, status TRN_E_ILLCOND; the same window moved to
 * hold the truth 2 or more cells inside its edges: TRN_OK and right. */
static void test_window_edge_not_a_fix(void **state)
{
    trn_grid_f32_t g, l;
    trn_map_cfg_t cfg;
    nat_t w;
    double sh;
    int k;
    (void)state;
    make_global(&g);
    auto_cfg(&cfg, &g, &sh);
    nat_build(&w, &cfg, &g);
    (void)make_wedge(&l, 48.3, 47.6, 1.0, 0.7);
    for (k = 0; k < 12; ++k) {
        const int side = k % 4, gap = 1 + k / 4; /* the truth beyond the edge */
        trn_window_t win = window_at(48, 48, 4);
        trn_loc_result_t res;
        trn_status_t st;
        if (side == 0) { /* x1 = 48 - gap */
            win.x0 -= 4 + gap;
            win.x1 -= 4 + gap;
        } else if (side == 1) {
            win.x0 += 4 + gap;
            win.x1 += 4 + gap;
        } else if (side == 2) {
            win.y0 -= 4 + gap;
            win.y1 -= 4 + gap;
        } else {
            win.y0 += 4 + gap;
            win.y1 += 4 + gap;
        }
        st = nat_localize(&w, &l, LR, LR, &win, &res);
        printf("truth %d cells beyond edge %d: status %d, pose (%d, %d), refined %d, failure "
               "probability %.3g\n",
               gap, side, (int)st, (int)res.ix, (int)res.iy, res.refined, res.failure_probability);
        assert_int_equal(st, TRN_E_ILLCOND);
        assert_int_equal(res.on_window_edge, 1);
    }
    {
        trn_window_t win = window_at(48, 48, 4);
        trn_loc_result_t res;
        assert_int_equal(nat_localize(&w, &l, LR, LR, &win, &res), TRN_OK);
        assert_true(res.on_window_edge == 0 && fabs(res.x - 48.3) < 0.1 &&
                    fabs(res.y - 47.6) < 0.1);
    }
    nat_free(&w);
}

/* sigma_H by the documented rule on the public filter: standard deviation
 * of trn_highpass with a 10-cell half-width. */
static double sigma_h_of(const trn_grid_f32_t *g, float cell)
{
    static float hpd[GW * GW];
    TRN_WORKSPACE_DECLARE(hws, ((GW + 1) * (GW + 1) * 2) * sizeof(double));
    trn_terrain_cfg_t t;
    trn_grid_f32_t hp;
    double s1 = 0.0, s2 = 0.0;
    int i, n = 0;
    t.cell_m = cell;
    t.zbin_m = cell;
    t.highpass_half_m = 10.0f * cell;
    t.nz = 16;
    assert_int_equal(trn_grid_f32_init(&hp, hpd, GW * GW, g->width, g->height), TRN_OK);
    assert_int_equal(trn_highpass(g, &t, &hp, hws, sizeof hws), TRN_OK);
    for (i = 0; i < g->width * g->height; ++i) {
        if (isfinite(hpd[i])) {
            s1 += hpd[i];
            s2 += (double)hpd[i] * hpd[i];
            ++n;
        }
    }
    return sqrt(s2 / n - (s1 / n) * (s1 / n));
}

static void scale_global(double k)
{
    int i;
    for (i = 0; i < GW * GW; ++i) {
        g_data[i] = (float)(g_data[i] * k);
    }
}

/* trn_map_cfg_auto's three regimes in closed form, the clamps of nz, what is
 * kept and written, and every @retval. */
static void test_cfg_auto_regimes(void **state)
{
    trn_grid_f32_t g;
    trn_map_cfg_t c;
    size_t wb = trn_map_cfg_auto_workspace_bytes(GW, GW);
    double sh, s;
    int i;
    (void)state;
    assert_true(wb > 0u && wb <= sizeof auto_ws);
    assert_int_equal(trn_map_cfg_auto_workspace_bytes(0, GW), 0u);
    assert_int_equal(trn_map_cfg_auto_workspace_bytes(GW, TRN_MAX_DIM + 1), 0u);

    /* relief: sigma_H / 2 between 2 s(10) = 0.1 m and the cell: nz = 17 */
    make_global(&g);
    scale_global(0.25); /* also brings the mean height near 25 m */
    s = sigma_h_of(&g, 1.0f);
    trn_map_cfg_default(&c);
    c.noise_m = 0.01f;
    c.noise_k_per_m = 0.0004f;
    c.levels = 99; /* garbage on entry: written */
    c.local_highpass = 7;
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, auto_ws, wb, &sh), TRN_OK);
    printf("auto: relief sigma_H %.4f m (rule %.4f): zbin %.4f x %d\n", sh, s,
           (double)c.terrain.zbin_m, c.terrain.nz);
    assert_true(fabs(sh - s) < 1e-9 * s);
    assert_true(sh / 2.0 > 0.1 && sh / 2.0 < 1.0);
    assert_true(c.terrain.zbin_m == (float)(sh / 2.0));
    assert_int_equal(c.terrain.nz, 17);
    assert_true(c.terrain.cell_m == 1.0f && c.terrain.highpass_half_m == 10.0f &&
                c.sigma_m == 1.0f);
    assert_true(c.noise_m == 0.01f && c.noise_k_per_m == 0.0004f);
    assert_int_equal(c.local_highpass, TRN_LOCAL_HP_MAP);
    assert_int_equal(c.refine, 1);
    assert_int_equal(c.levels, 4);
    assert_int_equal(trn_map_cfg_check(&c), TRN_OK);

    /* noise floor: sigma_H / 2 below 2 s(10 cells); nz = 2 ceil(...) + 1 < 16 -> 16 */
    make_global(&g);
    scale_global(0.01);
    c.noise_m = 0.02f;
    c.noise_k_per_m = 0.001f; /* s(10 m) = 0.12 m */
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, auto_ws, wb, NULL), TRN_OK);
    assert_true(c.terrain.zbin_m == (float)(2.0 * ((double)0.02f + (double)0.001f * 100.0)));
    assert_int_equal(c.terrain.nz, 16);
    assert_true(c.noise_m == 0.02f && c.noise_k_per_m == 0.001f);
    /* flat: sigma_H = 0, nz 1 -> 16 */
    for (i = 0; i < GW * GW; ++i) {
        g_data[i] = -3.0f;
    }
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, auto_ws, wb, &sh), TRN_OK);
    assert_true(sh == 0.0);
    assert_int_equal(c.terrain.nz, 16);

    /* cell cap: sigma_H / 2 above the cell */
    make_global(&g);
    s = sigma_h_of(&g, 1.0f);
    c.noise_m = 0.01f;
    c.noise_k_per_m = 0.0004f;
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, auto_ws, wb, &sh), TRN_OK);
    assert_true(fabs(sh - s) < 1e-9 * s && sh > 2.0);
    assert_true(c.terrain.zbin_m == 1.0f);
    assert_int_equal(c.terrain.nz, 2 * (int)ceil(4.0 * sh) + 1);
    assert_true(c.terrain.nz > 17 && c.terrain.nz < 64);
    /* ... and nz clamped to 64 */
    scale_global(4.0);
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, auto_ws, wb, &sh), TRN_OK);
    assert_true(2 * (int)ceil(4.0 * sh) + 1 > 64);
    assert_true(c.terrain.zbin_m == 1.0f);
    assert_int_equal(c.terrain.nz, 64);
    /* the same DEM read at 10 m cells, range-independent noise: relief regime */
    c.noise_k_per_m = 0.0f;
    assert_int_equal(trn_map_cfg_auto(&c, &g, 10.0f, auto_ws, wb, &sh), TRN_OK);
    assert_true(c.terrain.cell_m == 10.0f && c.terrain.highpass_half_m == 100.0f &&
                c.sigma_m == 10.0f);
    assert_true(c.terrain.zbin_m == (float)(sh / 2.0));
    assert_int_equal(c.terrain.nz, 17);
    /* with the range term, s(100 m) = 4.01 m: the noise floor wins */
    c.noise_k_per_m = 0.0004f;
    assert_int_equal(trn_map_cfg_auto(&c, &g, 10.0f, auto_ws, wb, &sh), TRN_OK);
    assert_true(sh / 2.0 < 2.0 * 4.01 &&
                c.terrain.zbin_m == (float)(2.0 * ((double)0.01f + (double)0.0004f * 1.0e4)));
    assert_int_equal(c.terrain.nz, 16);
    /* NaN cells are ignored */
    make_global(&g);
    for (i = 0; i < GW * GW; i += 7) {
        g_data[i] = NAN;
    }
    s = sigma_h_of(&g, 1.0f);
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, auto_ws, wb, &sh), TRN_OK);
    assert_true(fabs(sh - s) < 1e-9 * s);

    /* statuses */
    make_global(&g);
    assert_int_equal(trn_map_cfg_auto(NULL, &g, 1.0f, auto_ws, wb, &sh), TRN_E_NULL);
    assert_int_equal(trn_map_cfg_auto(&c, NULL, 1.0f, auto_ws, wb, &sh), TRN_E_NULL);
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, NULL, wb, &sh), TRN_E_NULL);
    assert_int_equal(trn_map_cfg_auto(&c, &g, 0.0f, auto_ws, wb, &sh), TRN_E_ARG);
    assert_int_equal(trn_map_cfg_auto(&c, &g, NAN, auto_ws, wb, &sh), TRN_E_ARG);
    assert_int_equal(trn_map_cfg_auto(&c, &g, -1.0f, auto_ws, wb, &sh), TRN_E_ARG);
    c.noise_m = NAN;
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, auto_ws, wb, &sh), TRN_E_ARG);
    c.noise_m = 0.01f;
    c.noise_k_per_m = -1.0f;
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, auto_ws, wb, &sh), TRN_E_ARG);
    c.noise_k_per_m = 0.0f; /* boundary: accepted */
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, auto_ws, wb, &sh), TRN_OK);
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, auto_ws, wb - 1u, &sh), TRN_E_WORKSPACE);
    assert_true(wb + 8u <= sizeof auto_ws); /* misaligned, large enough */
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, auto_ws + 8, sizeof auto_ws - 8u, &sh),
                     TRN_E_WORKSPACE);
    g.width = 0;
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, auto_ws, wb, &sh), TRN_E_SIZE);
    g.width = GW;
    g.stride = GW - 1;
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, auto_ws, wb, &sh), TRN_E_SIZE);
    g.stride = GW;
    for (i = 0; i < GW * GW; ++i) {
        g_data[i] = i % 2 ? NAN : INFINITY;
    }
    sh = -1.0;
    assert_int_equal(trn_map_cfg_auto(&c, &g, 1.0f, auto_ws, wb, &sh), TRN_E_NODATA);
    assert_true(sh == -1.0); /* untouched */
}

/* trn_map_bytes and trn_map_build with stored heights: 8 bytes per cell
 * more (aligned) exactly when the filter or the refinement needs them; the
 * heights are the DEM (NaN and inf -> NaN); the low-pass of a plane is the
 * plane wherever the filter's box is whole; every @retval. */
static void test_map_build_heights(void **state)
{
    enum { N = 40 };
    static float dem[N * N];
    TRN_WORKSPACE_DECLARE(buf, 1 << 21);
    trn_grid_f32_t g;
    trn_map_cfg_t paper, c;
    trn_map_t map;
    size_t mb0, mb, extra = 2u * TRN_ALIGN_UP((size_t)N * N * sizeof(float));
    int x, y, i;
    (void)state;
    for (y = 0; y < N; ++y) {
        for (x = 0; x < N; ++x) {
            dem[y * N + x] = (float)(5.0 + 0.25 * x - 0.5 * y);
        }
    }
    dem[3 * N + 4] = NAN;
    dem[30 * N + 31] = INFINITY;
    dem[31 * N + 30] = -INFINITY;
    assert_int_equal(trn_grid_f32_init(&g, dem, N * N, N, N), TRN_OK);
    trn_map_cfg_default(&paper);
    paper.terrain.cell_m = 1.0f;
    paper.terrain.zbin_m = 1.0f;
    paper.terrain.highpass_half_m = 3.0f;
    paper.sigma_m = 1.0f;
    mb0 = trn_map_bytes(&paper, N, N);
    assert_true(mb0 > 0u);
    assert_int_equal(trn_map_build(&map, &paper, &g, buf, mb0), TRN_OK);
    assert_null(map.heights.data);
    assert_null(map.lowpass.data);
    for (i = 0; i < 3; ++i) {
        c = paper;
        c.refine = i != 1;
        c.local_highpass = i >= 1 ? TRN_LOCAL_HP_MAP : TRN_LOCAL_HP_BOX;
        mb = trn_map_bytes(&c, N, N);
        assert_true(mb == mb0 + extra);
        assert_true(mb <= sizeof buf);
        assert_int_equal(trn_map_build(&map, &c, &g, buf, mb - 1u), TRN_E_WORKSPACE);
        assert_int_equal(trn_map_build(&map, &c, &g, buf, mb), TRN_OK);
        assert_non_null(map.heights.data);
        assert_true(map.heights.width == N && map.heights.height == N && map.lowpass.width == N &&
                    map.lowpass.height == N);
        for (y = 0; y < N; ++y) {
            for (x = 0; x < N; ++x) {
                float v = dem[y * N + x], h = TRN_GRID_AT(&map.heights, x, y),
                      lp = TRN_GRID_AT(&map.lowpass, x, y);
                if (!isfinite(v)) {
                    assert_true(isnan(h) && isnan(lp));
                    continue;
                }
                assert_true(h == v && isfinite(lp));
                /* a whole 7 x 7 box clear of the missing cells: plane in, plane out */
                if (x >= 3 && y >= 3 && x < N - 3 && y < N - 3 &&
                    !(abs(x - 4) <= 3 && abs(y - 3) <= 3) &&
                    !(x >= 27 && y >= 27 && x <= 34 && y <= 34)) {
                    assert_true(fabs((double)lp - (double)v) < 1e-4);
                }
            }
        }
    }
    /* statuses with the new configuration */
    c = paper;
    c.refine = 1;
    c.local_highpass = TRN_LOCAL_HP_MAP;
    mb = trn_map_bytes(&c, N, N);
    assert_int_equal(trn_map_build(NULL, &c, &g, buf, mb), TRN_E_NULL);
    assert_int_equal(trn_map_build(&map, NULL, &g, buf, mb), TRN_E_NULL);
    assert_int_equal(trn_map_build(&map, &c, NULL, buf, mb), TRN_E_NULL);
    assert_int_equal(trn_map_build(&map, &c, &g, NULL, mb), TRN_E_NULL);
    c.noise_m = NAN;
    assert_int_equal(trn_map_build(&map, &c, &g, buf, mb), TRN_E_ARG);
    c.noise_m = 0.01f;
    c.local_highpass = 2;
    assert_int_equal(trn_map_build(&map, &c, &g, buf, mb), TRN_E_ARG);
    c.local_highpass = TRN_LOCAL_HP_MAP;
    g.height = 0;
    assert_int_equal(trn_map_build(&map, &c, &g, buf, mb), TRN_E_SIZE);
    g.height = N;
    for (i = 0; i < N * N; ++i) {
        dem[i] = NAN;
    }
    assert_int_equal(trn_map_build(&map, &c, &g, buf, mb), TRN_E_NODATA);
}

/* A map whose stored heights or low-pass disagree with it is refused
 * (TRN_E_ARG, workspace 0), clause by clause; a map that does not need them
 * is not checked for them. */
static void test_corrupt_heights(void **state)
{
    trn_grid_f32_t g, l;
    trn_map_cfg_t cfg;
    nat_t w;
    trn_map_t bad;
    trn_loc_result_t res;
    trn_point_t pts[2] = {{0, 0, 8}, {1, 0, 8}};
    trn_window_t win = window_at(48, 48, 3);
    double sh;
    TRN_WORKSPACE_DECLARE(ws, 1 << 20);
    int i;
    (void)state;
    make_global(&g);
    voxel_cfg(&cfg, &g, &sh);
    nat_build(&w, &cfg, &g);
    (void)make_wedge(&l, 48.0, 48.0, 0.0, 0.0);
    assert_true(trn_localize_dem_workspace_bytes(&w.map, LW, LW, MAXPTS, &win) <= sizeof ws);
    for (i = 0; i < 10; ++i) {
        bad = w.map;
        switch (i) {
        case 0: bad.heights.data = NULL; break;
        case 1: bad.lowpass.width = 0; break;
        case 2: bad.heights.width = GW - 1; break;
        case 3: bad.heights.height = GW - 1; break;
        case 4: bad.lowpass.width = GW - 1; break;
        case 5: bad.lowpass.height = GW - 1; break;
        case 6: bad.lowpass.stride = GW - 1; break;
        case 7:
            bad.heights.width = GW + 1;
            bad.heights.stride = GW + 1;
            break;
        case 8:
            bad.cfg.refine = 0;
            bad.heights.data = NULL;
            break; /* still TRN_LOCAL_HP_MAP */
        default:
            bad.cfg.local_highpass = TRN_LOCAL_HP_BOX;
            bad.lowpass.data = NULL;
            break; /* still refine */
        }
        assert_int_equal(trn_localize_workspace_bytes(&bad, &win), 0u);
        assert_int_equal(trn_localize_dem_workspace_bytes(&bad, LW, LW, MAXPTS, &win), 0u);
        assert_int_equal(trn_localize_points(&bad, pts, 2, &win, ws, sizeof ws, &res), TRN_E_ARG);
        assert_int_equal(trn_localize_dem(&bad, &l, LR, LR, MAXPTS, &win, ws, sizeof ws, &res),
                         TRN_E_ARG);
    }
    /* neither needed: the paper's map runs without them */
    bad = w.map;
    bad.cfg.refine = 0;
    bad.cfg.local_highpass = TRN_LOCAL_HP_BOX;
    bad.heights.data = NULL;
    bad.lowpass.width = 0;
    assert_true(trn_localize_workspace_bytes(&bad, &win) > 0u);
    assert_int_equal(trn_localize_points(&bad, pts, 2, &win, ws, sizeof ws, &res) == TRN_E_ARG, 0);
    nat_free(&w);
}

/* Every documented @retval of trn_localize_dem with the natural
 * configuration (voxel matcher, TRN_LOCAL_HP_MAP, refinement). */
static void test_localize_dem_statuses(void **state)
{
    trn_grid_f32_t g, l, big;
    trn_map_cfg_t cfg;
    nat_t w;
    trn_loc_result_t res;
    trn_window_t win = window_at(48, 48, 3), off = {90, 40, GW, 44};
    TRN_WORKSPACE_DECLARE(ws, 1 << 21);
    size_t wb;
    double sh;
    int i;
    (void)state;
    make_global(&g);
    voxel_cfg(&cfg, &g, &sh);
    nat_build(&w, &cfg, &g);
    (void)make_wedge(&l, 48.0, 48.0, 0.0, 0.3);
    wb = trn_localize_dem_workspace_bytes(&w.map, LW, LW, MAXPTS, &win);
    assert_true(wb > 0u && wb <= sizeof ws);
    assert_int_equal(trn_localize_dem(&w.map, &l, LR, LR, MAXPTS, &win, ws, wb, &res), TRN_OK);
    assert_true(res.ix == 48 && res.iy == 48 && res.refined == 1 && fabs(res.x - 48.0) < 1e-4);
    assert_int_equal(trn_localize_dem(NULL, &l, LR, LR, MAXPTS, &win, ws, wb, &res), TRN_E_NULL);
    assert_int_equal(trn_localize_dem(&w.map, NULL, LR, LR, MAXPTS, &win, ws, wb, &res),
                     TRN_E_NULL);
    assert_int_equal(trn_localize_dem(&w.map, &l, LR, LR, MAXPTS, NULL, ws, wb, &res), TRN_E_NULL);
    assert_int_equal(trn_localize_dem(&w.map, &l, LR, LR, MAXPTS, &win, NULL, wb, &res),
                     TRN_E_NULL);
    assert_int_equal(trn_localize_dem(&w.map, &l, LR, LR, MAXPTS, &win, ws, wb, NULL), TRN_E_NULL);
    big = l;
    big.width = 0;
    assert_int_equal(trn_localize_dem(&w.map, &big, LR, LR, MAXPTS, &win, ws, wb, &res),
                     TRN_E_SIZE);
    assert_int_equal(trn_localize_dem(&w.map, &l, LR, LR, 0, &win, ws, wb, &res), TRN_E_ARG);
    assert_int_equal(trn_localize_dem(&w.map, &l, LR, LR, MAXPTS, &off, ws, wb, &res), TRN_E_RANGE);
    assert_int_equal(trn_localize_dem(&w.map, &l, LR, LR, MAXPTS, &win, ws, wb - 1u, &res),
                     TRN_E_WORKSPACE);
    assert_int_equal(trn_localize_dem(&w.map, &l, LR, LR, 10, &win, ws, wb, &res), TRN_E_CAPACITY);
    /* the same through trn_localize_dem_centroids (zero centroids: the centres) */
    assert_int_equal(trn_localize_dem_centroids(&w.map, &big, g_zero_c, g_zero_c, LR, LR, MAXPTS,
                                                &win, ws, wb, &res),
                     TRN_E_SIZE);
    assert_int_equal(trn_localize_dem_centroids(&w.map, &l, g_zero_c, g_zero_c, LR, LR, MAXPTS,
                                                &off, ws, wb, &res),
                     TRN_E_RANGE);
    assert_int_equal(trn_localize_dem_centroids(&w.map, &l, g_zero_c, g_zero_c, LR, LR, MAXPTS,
                                                &win, ws, wb - 1u, &res),
                     TRN_E_WORKSPACE);
    assert_int_equal(
        trn_localize_dem_centroids(&w.map, &l, g_zero_c, g_zero_c, LR, LR, 10, &win, ws, wb, &res),
        TRN_E_CAPACITY);
    assert_int_equal(trn_localize_dem_centroids(&w.map, &l, g_zero_c, g_zero_c, LR, LR, MAXPTS,
                                                &win, ws, wb, &res),
                     TRN_OK);
    /* and through trn_localize_dem_cells (counts of 1 beside zero centroids) */
    assert_int_equal(
        trn_localize_dem_cells(&w.map, &big, &g_one_cells, LR, LR, MAXPTS, &win, ws, wb, &res),
        TRN_E_SIZE);
    assert_int_equal(
        trn_localize_dem_cells(&w.map, &l, &g_one_cells, LR, LR, MAXPTS, &off, ws, wb, &res),
        TRN_E_RANGE);
    assert_int_equal(
        trn_localize_dem_cells(&w.map, &l, &g_one_cells, LR, LR, MAXPTS, &win, ws, wb - 1u, &res),
        TRN_E_WORKSPACE);
    assert_int_equal(
        trn_localize_dem_cells(&w.map, &l, &g_one_cells, LR, LR, 10, &win, ws, wb, &res),
        TRN_E_CAPACITY);
    assert_int_equal(
        trn_localize_dem_cells(&w.map, &l, &g_one_cells, LR, LR, MAXPTS, &win, ws, wb, &res),
        TRN_OK);
    for (i = 0; i < LW * LW; ++i) {
        l_data[i] = NAN;
    }
    assert_int_equal(
        trn_localize_dem_cells(&w.map, &l, &g_one_cells, LR, LR, MAXPTS, &win, ws, wb, &res),
        TRN_E_NODATA);
    assert_int_equal(trn_localize_dem(&w.map, &l, LR, LR, MAXPTS, &win, ws, wb, &res),
                     TRN_E_NODATA);
    assert_int_equal(trn_localize_dem_centroids(&w.map, &l, g_zero_c, g_zero_c, LR, LR, MAXPTS,
                                                &win, ws, wb, &res),
                     TRN_E_NODATA);
    /* TRN_E_ILLCOND: test_refine_failure_is_illcond */
    nat_free(&w);
}

/* A binned local map: the wedge of make_wedge with each seen cell the
 * analytic ground at its points' centroid, a common (0.25, -0.15) cells
 * plus up to 0.1 more per cell; cx, cy those centroids. */
static void make_binned(trn_grid_f32_t *l, float *cx, float *cy, double tx, double ty, trn_rng_t *r)
{
    int i;
    (void)make_wedge(l, tx, ty, 3.0, 0.4);
    for (i = 0; i < LW * LW; ++i) {
        cx[i] = (float)(0.25 + 0.2 * (trn_rng_unit(r) - 0.5));
        cy[i] = (float)(-0.15 + 0.2 * (trn_rng_unit(r) - 0.5));
        if (isfinite(l_data[i])) {
            l_data[i] = (float)(surface(tx + (i % LW) - LR + cx[i], ty + (i / LW) - LR + cy[i]) +
                                3.0);
        } else {
            cx[i] = cy[i] = NAN; /* unseen: not read */
        }
    }
}

/* trn_localize_dem_centroids: on a binned local map the answer given the
 * centroids is the truth's within the interpolant's error, where without
 * them it is moved by their common offset (0.29 cells), on both matchers
 * (the voxel matcher's refinement reads them too); zero centroids are
 * trn_localize_dem's answer bit for bit, as is trn_localize_dem_cells knowing
 * nothing of the cells; and its argument checks. */
static void test_localize_dem_centroids(void **state)
{
    static float cx[LW * LW], cy[LW * LW], zero[LW * LW];
    trn_grid_f32_t g, l;
    trn_map_cfg_t cfg;
    nat_t w;
    trn_loc_result_t with, without, a, b;
    trn_window_t win = window_at(48, 47, 3);
    trn_rng_t r;
    double sh, e_with[2] = {0.0, 0.0}, e_without[2] = {1.0, 1.0};
    int m, k;
    (void)state;
    trn_rng_seed(&r, 31);
    make_global(&g);
    for (m = 0; m < 2; ++m) { /* the height matcher, then the voxel matcher refined */
        if (m == 0) {
            auto_cfg(&cfg, &g, &sh);
            assert_int_equal(cfg.match, TRN_MATCH_HEIGHTS);
        } else {
            voxel_cfg(&cfg, &g, &sh);
        }
        nat_build(&w, &cfg, &g);
        for (k = 0; k < 4; ++k) {
            const double tx = 47.6 + 0.25 * k, ty = 47.3 + 0.2 * k;
            make_binned(&l, cx, cy, tx, ty, &r);
            (void)nat_localize(&w, &l, LR, LR, &win, &a); /* sizes the workspace */
            assert_int_equal(trn_localize_dem_centroids(&w.map, &l, cx, cy, LR, LR, MAXPTS, &win,
                                                        w.ws, w.wb, &with),
                             TRN_OK);
            assert_int_equal(
                trn_localize_dem(&w.map, &l, LR, LR, MAXPTS, &win, w.ws, w.wb, &without), TRN_OK);
            e_with[m] = fmax(e_with[m], hypot(with.x - tx, with.y - ty));
            e_without[m] = fmin(e_without[m], hypot(without.x - tx, without.y - ty));
        }
        printf("centroids (%s): worst error %.4f cells given them, least %.4f without\n",
               m == 0 ? "heights" : "voxel, refined", e_with[m], e_without[m]);
        assert_true(e_with[m] < 0.05);
        assert_true(e_without[m] > 0.2);
        nat_free(&w);
    }
    /* zero centroids: trn_localize_dem's answer, bit for bit */
    auto_cfg(&cfg, &g, &sh);
    nat_build(&w, &cfg, &g);
    (void)make_wedge(&l, 48.3, 47.4, 1.0, 0.4);
    assert_int_equal(nat_localize(&w, &l, LR, LR, &win, &a), TRN_OK);
    memset(&b, 0, sizeof b);
    assert_int_equal(
        trn_localize_dem_centroids(&w.map, &l, zero, zero, LR, LR, MAXPTS, &win, w.ws, w.wb, &b),
        TRN_OK);
    assert_memory_equal(&a, &b, sizeof a);
    /* and trn_localize_dem_cells knowing nothing of the cells */
    memset(&b, 0, sizeof b);
    assert_int_equal(
        trn_localize_dem_cells(&w.map, &l, &g_no_cells, LR, LR, MAXPTS, &win, w.ws, w.wb, &b),
        TRN_OK);
    assert_memory_equal(&a, &b, sizeof a);
    /* the checks: both or neither; seen cells finite and within half a cell */
    make_binned(&l, cx, cy, 48.0, 47.0, &r);
    assert_int_equal(
        trn_localize_dem_centroids(&w.map, &l, cx, NULL, LR, LR, MAXPTS, &win, w.ws, w.wb, &b),
        TRN_E_NULL);
    assert_int_equal(
        trn_localize_dem_centroids(&w.map, &l, NULL, cy, LR, LR, MAXPTS, &win, w.ws, w.wb, &b),
        TRN_E_NULL);
    k = LR * LW + LR + 5; /* 5 cells east of the rover: in the wedge (heading 0.4 rad) */
    assert_true(isfinite(l_data[k]));
    cx[k] = NAN;
    assert_int_equal(
        trn_localize_dem_centroids(&w.map, &l, cx, cy, LR, LR, MAXPTS, &win, w.ws, w.wb, &b),
        TRN_E_ARG);
    cx[k] = 0.0f;
    cy[k] = -0.6f;
    assert_int_equal(
        trn_localize_dem_centroids(&w.map, &l, cx, cy, LR, LR, MAXPTS, &win, w.ws, w.wb, &b),
        TRN_E_ARG);
    cy[k] = 0.5f;
    assert_int_equal(
        trn_localize_dem_centroids(&w.map, &l, cx, cy, LR, LR, MAXPTS, &win, w.ws, w.wb, &b),
        TRN_OK);
    nat_free(&w);
}

/* trn_localize_dem_cells: the centroids alone are trn_localize_dem_centroids,
 * bit for bit (nothing known is trn_localize_dem: test_localize_dem_centroids);
 * the point counts
 * reach the refinement (16 points a cell: another covariance, the same
 * answer within the interpolant's error; on these exact heights the fitted
 * model variance, not the noise, holds most of it: test_refine.c
 * test_point_counts has the counts' analytic checks); and its argument
 * checks. */
static void test_localize_dem_cells(void **state)
{
    static float cx[LW * LW], cy[LW * LW], n[LW * LW];
    trn_grid_f32_t g, l;
    trn_map_cfg_t cfg;
    nat_t w;
    trn_loc_result_t a, b;
    trn_local_cells_t cells = {NULL, NULL, NULL};
    trn_window_t win = window_at(48, 47, 3);
    trn_rng_t r;
    double sh, tr_one;
    int i, k;
    (void)state;
    trn_rng_seed(&r, 37);
    make_global(&g);
    auto_cfg(&cfg, &g, &sh);
    nat_build(&w, &cfg, &g);
    make_binned(&l, cx, cy, 48.2, 47.3, &r);
    (void)nat_localize(&w, &l, LR, LR, &win, &a); /* sizes the workspace */
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    assert_int_equal(
        trn_localize_dem_centroids(&w.map, &l, cx, cy, LR, LR, MAXPTS, &win, w.ws, w.wb, &a),
        TRN_OK);
    cells.centroid_x = cx;
    cells.centroid_y = cy;
    assert_int_equal(
        trn_localize_dem_cells(&w.map, &l, &cells, LR, LR, MAXPTS, &win, w.ws, w.wb, &b), TRN_OK);
    assert_memory_equal(&a, &b, sizeof a);
    tr_one = a.cov_m2[0] + a.cov_m2[1];
    for (i = 0; i < LW * LW; ++i) {
        n[i] = isfinite(l_data[i]) ? 16.0f : NAN; /* unseen: not read */
    }
    cells.point_count = n;
    assert_int_equal(
        trn_localize_dem_cells(&w.map, &l, &cells, LR, LR, MAXPTS, &win, w.ws, w.wb, &b), TRN_OK);
    printf("cells: covariance trace %.3g m^2 with 16 points a cell, %.3g with one\n",
           b.cov_m2[0] + b.cov_m2[1], tr_one);
    assert_true(b.cov_m2[0] != a.cov_m2[0] && b.cov_m2[1] != a.cov_m2[1]);
    assert_true(hypot(b.x - 48.2, b.y - 47.3) < 0.05);
    /* the checks: the cells NULL; a seen cell's count below 1 or missing */
    assert_int_equal(trn_localize_dem_cells(&w.map, &l, NULL, LR, LR, MAXPTS, &win, w.ws, w.wb, &b),
                     TRN_E_NULL);
    cells.centroid_y = NULL;
    assert_int_equal(
        trn_localize_dem_cells(&w.map, &l, &cells, LR, LR, MAXPTS, &win, w.ws, w.wb, &b),
        TRN_E_NULL);
    cells.centroid_y = cy;
    k = LR * LW + LR + 5; /* in the wedge */
    assert_true(isfinite(l_data[k]));
    n[k] = 0.0f;
    assert_int_equal(
        trn_localize_dem_cells(&w.map, &l, &cells, LR, LR, MAXPTS, &win, w.ws, w.wb, &b),
        TRN_E_ARG);
    n[k] = NAN;
    assert_int_equal(
        trn_localize_dem_cells(&w.map, &l, &cells, LR, LR, MAXPTS, &win, w.ws, w.wb, &b),
        TRN_E_ARG);
    n[k] = 1.0f;
    assert_int_equal(
        trn_localize_dem_cells(&w.map, &l, &cells, LR, LR, MAXPTS, &win, w.ws, w.wb, &b), TRN_OK);
    nat_free(&w);
}

static trn_refine_cfg_t rcfg(float k)
{
    trn_refine_cfg_t c;
    c.cell_m = 1.0f;
    c.noise_m = 0.01f;
    c.noise_k_per_m = k;
    c.inlier_prob = 0.95f;
    c.fit_noise = 0;
    c.centroid_x = NULL; /* the cells' centres */
    c.centroid_y = NULL;
    c.point_count = NULL; /* one measurement a cell */
    return c;
}

/* trn_refine_pose at the edges of its grids: local cells off the global grid
 * (and exactly on its last row and column), over a NaN hole of the global
 * DEM (each of the four bilinear corners), grids of one row or one column.
 * Oracle: the pose of the exact model still comes back, and n_seen counts
 * exactly the cells whose four corners are on the grid and known. */
static void test_refine_grid_edges(void **state)
{
    trn_grid_f32_t g, l, one;
    trn_refine_cfg_t c = rcfg(0.0004f);
    trn_refine_t out;
    static float col[GW];
    int x, y, seen, expect;
    (void)state;
    make_global(&g);
    /* pose (90, 88), integer, wedge towards +x +y: cells beyond column and
     * row 95 are off the grid (heights there are nonsense), cells on 95 use
     * the last cell's corners */
    (void)make_wedge(&l, 90.0, 88.0, 1.5, PI / 4.0);
    for (expect = 0, y = 0; y < LW; ++y) {
        for (x = 0; x < LW; ++x) {
            int gx = 90 + x - LR, gy = 88 + y - LR;
            if (!isfinite(l_data[y * LW + x])) {
                continue;
            }
            if (gx > GW - 1 || gy > GW - 1) {
                l_data[y * LW + x] = -7.0e3f;
            } else {
                ++expect;
            }
        }
    }
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 90, 88, &c, &out), TRN_OK);
    assert_int_equal(out.n_seen, expect);
    assert_true(fabs(out.x - 90.0) < 1e-4 && fabs(out.y - 88.0) < 1e-4 &&
                fabs(out.dz_m - 1.5) < 1e-3);
    /* near the origin: cells at negative columns and rows (nonsense there) */
    (void)make_wedge(&l, 5.0, 6.0, 0.0, -3.0 * PI / 4.0);
    for (expect = 0, y = 0; y < LW; ++y) {
        for (x = 0; x < LW; ++x) {
            if (isfinite(l_data[y * LW + x]) && 5 + x - LR >= 0 && 6 + y - LR >= 0) {
                ++expect;
            }
        }
    }
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 5, 6, &c, &out), TRN_OK);
    assert_int_equal(out.n_seen, expect);
    assert_true(expect >= 8 && fabs(out.x - 5.0) < 1e-4 && fabs(out.y - 6.0) < 1e-4);
    /* start a row below the truth: the first step is clamped to -0.5 */
    (void)make_wedge(&l, 40.0, 40.0, 0.0, 1.0);
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 41, &c, &out), TRN_OK);
    assert_true(out.iterations >= 3);
    assert_true(fabs(out.x - 40.0) < 1e-4 && fabs(out.y - 40.0) < 1e-4);
    /* a 2 x 2 NaN hole under the wedge: every corner position excluded once */
    seen = make_wedge(&l, 40.0, 40.0, 0.0, 0.0);
    g_data[41 * GW + 50] = g_data[41 * GW + 51] = g_data[42 * GW + 50] = g_data[42 * GW + 51] = NAN;
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &c, &out), TRN_OK);
    /* start at (40, 40): the cell at global (X, Y) uses corners X..X+1, Y..Y+1 */
    for (expect = 0, y = 0; y < LW; ++y) {
        for (x = 0; x < LW; ++x) {
            int gx = 40 + x - LR, gy = 40 + y - LR;
            if (isfinite(l_data[y * LW + x]) && gx >= 49 && gx <= 51 && gy >= 40 && gy <= 42) {
                ++expect;
            }
        }
    }
    assert_int_equal(expect, 9);
    assert_int_equal(out.n_seen, seen - expect);
    assert_true(fabs(out.x - 40.0) < 1e-4 && fabs(out.y - 40.0) < 1e-4);
    make_global(&g);
    /* one column / one row: nothing can be interpolated (no bilinear cell) */
    for (y = 0; y < GW; ++y) {
        col[y] = (float)surface(0.0, y);
    }
    (void)make_wedge(&l, 40.0, 40.0, 0.0, PI / 2.0); /* has cells on the rover's column */
    assert_int_equal(trn_grid_f32_init(&one, col, GW, 1, GW), TRN_OK);
    assert_int_equal(trn_refine_pose(&one, &l, LR, LR, 0, 40, &c, &out), TRN_E_NODATA);
    assert_int_equal(out.n_seen, 0);
    (void)make_wedge(&l, 40.0, 40.0, 0.0, 0.0); /* has cells on the rover's row */
    assert_int_equal(trn_grid_f32_init(&one, col, GW, GW, 1), TRN_OK);
    assert_int_equal(trn_refine_pose(&one, &l, LR, LR, 40, 0, &c, &out), TRN_E_NODATA);
    assert_int_equal(out.n_seen, 0);
}

/* The inlier-majority rule of trn_refine_pose. Local cells: n_near cells
 * within 2 of the rover with the global heights exactly (noise 0.02-0.05 m),
 * and nfar cells 20 away (noise 4 m) 1000 m off (a gross error no model
 * variance estimated where the noise is small can absorb: the weighted
 * moments are dominated by the near cells). 12 near + 12 far: exactly half
 * inliers, accepted; 12 + 13: fewer than half, TRN_E_ILLCOND after the
 * iterations; 6 + 2: fewer than 8 inliers from the start, TRN_E_ILLCOND
 * before any step. */
static int near_far(int n_near, int nfar)
{
    int x, y, k, n = 0;
    for (k = 0; k < LW * LW; ++k) {
        l_data[k] = NAN;
    }
    for (y = LR - 2; y <= LR + 2; ++y) {
        for (x = LR - 2; x <= LR + 2; ++x) {
            int dx = x - LR, dy = y - LR;
            if ((dx || dy) && dx * dx + dy * dy <= 4 && n < n_near) {
                l_data[y * LW + x] = (float)bilin(40 + dx, 40 + dy);
                ++n;
            }
        }
    }
    assert_int_equal(n, n_near);
    for (k = 0; k < nfar; ++k) {
        double a = 2.0 * PI * k / nfar;
        int dx = (int)lround(LR * cos(a)), dy = (int)lround(LR * sin(a));
        assert_true(isnan(l_data[(LR + dy) * LW + LR + dx]));
        l_data[(LR + dy) * LW + LR + dx] = (float)(bilin(40 + dx, 40 + dy) + 1000.0);
    }
    return n + nfar;
}

static void test_refine_inlier_majority(void **state)
{
    trn_grid_f32_t g, l;
    trn_refine_cfg_t c = rcfg(0.01f);
    trn_refine_t out;
    int n;
    (void)state;
    make_global(&g);
    assert_int_equal(trn_grid_f32_init(&l, l_data, LW * LW, LW, LW), TRN_OK);
    n = near_far(12, 12);
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &c, &out), TRN_OK);
    assert_int_equal(out.n_seen, n);
    assert_int_equal(out.n_used, 12);
    assert_true(fabs(out.x - 40.0) < 0.05 && fabs(out.y - 40.0) < 0.05);
    n = near_far(12, 13);
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &c, &out), TRN_E_ILLCOND);
    assert_int_equal(out.n_seen, n);
    assert_int_equal(out.n_used, 12);
    assert_true(out.x == 40.0 && isinf(out.cov_cells[0]) && isinf(out.cov_cells[1]));
    n = near_far(6, 2);
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &c, &out), TRN_E_ILLCOND);
    assert_int_equal(out.n_seen, n);
    assert_true(out.n_used < 8);
    assert_int_equal(out.iterations, 0);
    assert_true(out.y == 40.0 && isinf(out.cov_cells[1]));
}

/* Gauss-Newton at a cell edge: local heights = the global nodes at an
 * integer pose minus eps times their second difference along x make the
 * cost's minimum a kink at the integer column (each cell's linear model has
 * its optimum in the other cell) under bilinear sampling, so the steps cycle
 * and the iteration ends at TRN_REFINE_MAX_ITER near the kink; under a
 * smooth (bicubic) sampling it converges there. Either way: within 0.1. A
 * start 7 rows off leaves the neighbourhood in y: TRN_E_ILLCOND (from 6
 * rows off, the interpolants' mix at its bound holds it at 2 cells). */
static void test_refine_iteration_limits(void **state)
{
    trn_grid_f32_t g, l;
    trn_refine_cfg_t c = rcfg(0.0004f);
    trn_refine_t out;
    int x, y;
    const double eps = 0.3;
    (void)state;
    make_global(&g);
    (void)make_wedge(&l, 40.0, 40.0, 0.0, 0.0);
    for (y = 0; y < LW; ++y) {
        for (x = 0; x < LW; ++x) {
            if (isfinite(l_data[y * LW + x])) {
                int gx = 40 + x - LR, gy = 40 + y - LR;
                double d2 = g_data[gy * GW + gx + 1] - 2.0 * g_data[gy * GW + gx] +
                            g_data[gy * GW + gx - 1];
                l_data[y * LW + x] = (float)(g_data[gy * GW + gx] - eps * d2);
            }
        }
    }
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &c, &out), TRN_OK);
    printf("kink at a cell edge: %d iterations, stopped at (%.4f, %.4f)\n", out.iterations, out.x,
           out.y);
    /* bilinear sampling: 12 iterations, stopped at (40.025, 40.010); with the
     * bicubic sampling the cost is smooth at the edge and it converges */
    /* two phases (the plain clip, then the relief rule), each at most
     * TRN_REFINE_MAX_ITER */
    assert_true(out.iterations >= 1 && out.iterations <= 2 * TRN_REFINE_MAX_ITER);
    assert_true(fabs(out.x - 40.0) < 0.1 && fabs(out.y - 40.0) < 0.1);
    (void)make_wedge(&l, 40.0, 40.0, 0.0, PI / 2.0);
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 47, &c, &out), TRN_E_ILLCOND);
    assert_true(out.x == 40.0 && out.y == 47.0 && isinf(out.cov_cells[1]) && out.iterations > 0);
}

/* trn_refine_pose's argument checks, one clause at a time, with their
 * boundaries (a boundary value passes the check: the rover cells far from
 * the grid then find no global height, TRN_E_NODATA). */
static void test_refine_args(void **state)
{
    trn_grid_f32_t g, l, bad;
    trn_refine_cfg_t c = rcfg(0.0004f), b;
    trn_refine_t out;
    (void)state;
    make_global(&g);
    (void)make_wedge(&l, 40.0, 40.0, 0.0, 0.0);
    b = c;
    b.cell_m = TRN_CELL_MAX_M;
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &b, &out), TRN_OK);
    b = c;
    b.cell_m = nextafterf(TRN_CELL_MAX_M, INFINITY);
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &b, &out), TRN_E_ARG);
    b = c;
    b.cell_m = NAN;
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &b, &out), TRN_E_ARG);
    b = c;
    b.noise_m = 1000.0f;
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &b, &out), TRN_OK);
    b = c;
    b.noise_m = 1000.5f;
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &b, &out), TRN_E_ARG);
    b = c;
    b.noise_k_per_m = 1000.0f;
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &b, &out), TRN_OK);
    b = c;
    b.noise_k_per_m = 1000.5f;
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &b, &out), TRN_E_ARG);
    b = c;
    b.noise_k_per_m = -1.0f;
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &b, &out), TRN_E_ARG);
    b = c;
    b.inlier_prob = 0.0f;
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &b, &out), TRN_E_ARG);
    b.inlier_prob = 1.0f;
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &b, &out), TRN_E_ARG);
    b.inlier_prob = NAN;
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &b, &out), TRN_E_ARG);
    b.inlier_prob = 0.999f;
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, 40, &b, &out), TRN_OK);
    assert_int_equal(trn_refine_pose(&g, &l, -TRN_MAX_DIM, LR, 40, 40, &c, &out), TRN_E_NODATA);
    assert_int_equal(trn_refine_pose(&g, &l, -TRN_MAX_DIM - 1, LR, 40, 40, &c, &out), TRN_E_ARG);
    assert_int_equal(trn_refine_pose(&g, &l, LR, -TRN_MAX_DIM, 40, 40, &c, &out), TRN_E_NODATA);
    assert_int_equal(trn_refine_pose(&g, &l, LR, -TRN_MAX_DIM - 1, 40, 40, &c, &out), TRN_E_ARG);
    assert_int_equal(trn_refine_pose(&g, &l, LW - 1 + TRN_MAX_DIM, LR, 40, 40, &c, &out),
                     TRN_E_NODATA);
    assert_int_equal(trn_refine_pose(&g, &l, LW + TRN_MAX_DIM, LR, 40, 40, &c, &out), TRN_E_ARG);
    assert_int_equal(trn_refine_pose(&g, &l, LR, LW - 1 + TRN_MAX_DIM, 40, 40, &c, &out),
                     TRN_E_NODATA);
    assert_int_equal(trn_refine_pose(&g, &l, LR, LW + TRN_MAX_DIM, 40, 40, &c, &out), TRN_E_ARG);
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, -1, 40, &c, &out), TRN_E_RANGE);
    assert_true(out.x == -1.0 && isinf(out.cov_cells[0]));
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, -1, &c, &out), TRN_E_RANGE);
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, GW, 40, &c, &out), TRN_E_RANGE);
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, 40, GW, &c, &out), TRN_E_RANGE);
    assert_int_equal(trn_refine_pose(&g, &l, LR, LR, GW - 1, GW - 1, &c, &out),
                     TRN_E_NODATA); /* wedge off the grid */
    bad = l;
    bad.stride = LW - 1;
    assert_int_equal(trn_refine_pose(&g, &bad, LR, LR, 40, 40, &c, &out), TRN_E_SIZE);
    bad = l;
    bad.data = NULL;
    assert_int_equal(trn_refine_pose(&g, &bad, LR, LR, 40, 40, &c, &out), TRN_E_NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wedge_recovers_pose),
        cmocka_unit_test(test_noise_auto),
        cmocka_unit_test(test_noise_auto_flat),
        cmocka_unit_test(test_box_bias_on_slope),
        cmocka_unit_test(test_constant_offset_invariance),
        cmocka_unit_test(test_second_pass),
        cmocka_unit_test(test_map_filter_unseen_cells),
        cmocka_unit_test(test_refine_failure_is_illcond),
        cmocka_unit_test(test_window_edge_not_a_fix),
        cmocka_unit_test(test_cfg_check_new_fields),
        cmocka_unit_test(test_cfg_auto_regimes),
        cmocka_unit_test(test_map_build_heights),
        cmocka_unit_test(test_corrupt_heights),
        cmocka_unit_test(test_localize_dem_statuses),
        cmocka_unit_test(test_localize_dem_centroids),
        cmocka_unit_test(test_localize_dem_cells),
        cmocka_unit_test(test_ambiguous_acceptance),
        cmocka_unit_test(test_valley_failure),
        cmocka_unit_test(test_prob_beyond),
        cmocka_unit_test(test_refine_grid_edges),
        cmocka_unit_test(test_refine_inlier_majority),
        cmocka_unit_test(test_refine_iteration_limits),
        cmocka_unit_test(test_refine_args),
    };
    int i;
    for (i = 0; i < LW * LW; ++i) {
        g_one_n[i] = 1.0f;
    }
    return cmocka_run_group_tests(tests, NULL, NULL);
}
