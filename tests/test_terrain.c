/* SPDX-License-Identifier: Apache-2.0 */
/* test_terrain.c - high-pass filter and occupancy (terrain.h).
 *
 * Oracles: a brute-force box mean in double over the valid cells of the
 * clipped box (trn_highpass), a naive re-implementation of the documented
 * occupancy rule (trn_occupancy), the occupancy volume itself read in (z, y, x)
 * order (trn_occupancy_points), analytic planes, and hand-worked small grids.
 * Inputs are seeded random DEMs with NaN and +-inf holes, at absolute heights
 * of +-3000 m, often given as sub-views (stride > width) of a larger buffer
 * whose other cells hold poison values that would show if they were read, and
 * whose output frame is checked to be left untouched. Every documented
 * @retval has its own assertion.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "trn/terrain.h"
#include "rng.h"

/* Absolute tolerance of trn_highpass against the double oracle, metres. */
#define HP_TOL_M 1e-4

/* Poison around sub-views: finite and far from the data, so a filter or an
 * occupancy column that read outside its view would be visibly wrong. */
#define POISON_IN 1.0e6f
/* Sentinel around output views: must survive untouched. */
#define SENTINEL_OUT 12345.25f

static double uniform(trn_rng_t *r, double lo, double hi)
{
    return lo + (hi - lo) * trn_rng_unit(r);
}

static trn_terrain_cfg_t make_cfg(float cell, float zbin, float half, int32_t nz)
{
    trn_terrain_cfg_t c;
    c.cell_m = cell;
    c.zbin_m = zbin;
    c.highpass_half_m = half;
    c.nz = nz;
    return c;
}

/* A w x h view at (ox, oy) inside a (w + padx) x (h + pady) parent buffer. */
typedef struct {
    float *buf;
    size_t n;
    trn_grid_f32_t parent;
    trn_grid_f32_t view;
} padded_t;

static void padded_make(padded_t *p, int32_t w, int32_t h, int32_t padx, int32_t pady, int32_t ox,
                        int32_t oy, float fill)
{
    size_t i;
    p->n = (size_t)(w + padx) * (size_t)(h + pady);
    p->buf = (float *)malloc(p->n * sizeof(float));
    assert_non_null(p->buf);
    for (i = 0; i < p->n; ++i) {
        p->buf[i] = fill;
    }
    assert_int_equal(trn_grid_f32_init(&p->parent, p->buf, p->n, w + padx, h + pady), TRN_OK);
    assert_int_equal(trn_grid_f32_sub(&p->parent, ox, oy, w, h, &p->view), TRN_OK);
}

static void padded_free(padded_t *p)
{
    free(p->buf);
    p->buf = NULL;
}

/* Every parent cell outside the view still holds the sentinel. */
static void assert_frame_untouched(const padded_t *p, float sentinel)
{
    const float *v0 = p->view.data;
    const ptrdiff_t off = v0 - p->buf;
    const int32_t ox = (int32_t)(off % p->parent.stride), oy = (int32_t)(off / p->parent.stride);
    int32_t x, y;
    for (y = 0; y < p->parent.height; ++y) {
        for (x = 0; x < p->parent.width; ++x) {
            const int inside = x >= ox && x < ox + p->view.width && y >= oy &&
                               y < oy + p->view.height;
            if (!inside) {
                assert_true(TRN_GRID_AT(&p->parent, x, y) == sentinel);
            }
        }
    }
}

/* r as documented: round(highpass_half_m / cell_m), the quotient in float
 * (C semantics of the two float fields), rounded half away from zero; a box
 * wider than any grid is the whole grid, so larger values are capped. */
static int32_t oracle_radius(const trn_terrain_cfg_t *cfg)
{
    const float q = cfg->highpass_half_m / cfg->cell_m;
    const double r = round((double)q);
    return r > 2.0 * TRN_MAX_DIM ? 2 * TRN_MAX_DIM : (int32_t)r;
}

/* Brute force: h - mean of the valid heights in the clipped box, in double;
 * NaN where h is missing. Returns the number of valid cells. */
static size_t oracle_highpass(const trn_grid_f32_t *dem, int32_t r, double *expect)
{
    int32_t x, y, xx, yy;
    size_t n_valid = 0;
    for (y = 0; y < dem->height; ++y) {
        for (x = 0; x < dem->width; ++x) {
            const float v = TRN_GRID_AT(dem, x, y);
            double s = 0.0;
            long n = 0;
            if (!isfinite(v)) {
                expect[(size_t)y * (size_t)dem->width + (size_t)x] = NAN;
                continue;
            }
            ++n_valid;
            for (yy = y - r; yy <= y + r; ++yy) {
                for (xx = x - r; xx <= x + r; ++xx) {
                    if (xx >= 0 && yy >= 0 && xx < dem->width && yy < dem->height) {
                        const float u = TRN_GRID_AT(dem, xx, yy);
                        if (isfinite(u)) {
                            s += (double)u;
                            ++n;
                        }
                    }
                }
            }
            expect[(size_t)y * (size_t)dem->width + (size_t)x] = (double)v - s / (double)n;
        }
    }
    return n_valid;
}

/* Run trn_highpass on dem into out with an exactly-sized heap workspace. */
static trn_status_t run_highpass(const trn_grid_f32_t *dem, const trn_terrain_cfg_t *cfg,
                                 trn_grid_f32_t *out)
{
    const size_t wb = trn_highpass_workspace_bytes(dem->width, dem->height);
    void *ws;
    trn_status_t st;
    assert_true(wb > 0u);
    ws = malloc(wb);
    assert_non_null(ws);
    st = trn_highpass(dem, cfg, out, ws, wb);
    free(ws);
    return st;
}

/* Compare out with the oracle: NaN exactly where expected, else |diff| <= tol.
 * Returns the largest |diff|. */
static double compare_hp(const trn_grid_f32_t *out, const double *expect, double tol)
{
    int32_t x, y;
    double worst = 0.0;
    for (y = 0; y < out->height; ++y) {
        for (x = 0; x < out->width; ++x) {
            const double e = expect[(size_t)y * (size_t)out->width + (size_t)x];
            const float o = TRN_GRID_AT(out, x, y);
            if (isnan(e)) {
                if (!isnan(o)) {
                    fail_msg("cell (%d, %d) is missing but filtered to %.9g", (int)x, (int)y,
                             (double)o);
                }
            } else {
                const double d = fabs((double)o - e);
                if (!(d <= tol)) {
                    fail_msg("cell (%d, %d): got %.9g, expected %.9g (|diff| %.3g > %.3g)", (int)x,
                             (int)y, (double)o, e, d, tol);
                }
                worst = fmax(worst, d);
            }
        }
    }
    return worst;
}

/* ------------------------------------------------------------------------ */
/* configuration and sizing                                                  */
/* ------------------------------------------------------------------------ */

static void test_cfg_check(void **state)
{
    trn_terrain_cfg_t c;
    (void)state;
    c = make_cfg(1.0f, 1.0f, 2.0f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_OK);
    assert_int_equal(trn_terrain_cfg_check(NULL), TRN_E_NULL);
    /* cell_m: (0, TRN_CELL_MAX_M] */
    c = make_cfg(0.0f, 1.0f, 2.0f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(-1.0f, 1.0f, 2.0f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(NAN, 1.0f, 2.0f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(INFINITY, 1.0f, 2.0f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(nextafterf(TRN_CELL_MAX_M, INFINITY), 1.0f, 2.0f * TRN_CELL_MAX_M, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(TRN_CELL_MAX_M, 1.0f, TRN_CELL_MAX_M, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_OK);
    /* zbin_m: (0, TRN_CELL_MAX_M], the cell's bound (= cell_m in the scaled configuration) */
    c = make_cfg(1.0f, 0.0f, 2.0f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(1.0f, -0.5f, 2.0f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(1.0f, NAN, 2.0f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(1.0f, INFINITY, 2.0f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(1.0f, nextafterf(TRN_CELL_MAX_M, INFINITY), 2.0f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(1.0f, TRN_CELL_MAX_M, 2.0f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_OK);
    /* highpass_half_m: [cell_m, 1e6] */
    c = make_cfg(1.0f, 1.0f, 0.99f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(0.5f, 1.0f, 0.25f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(1.0f, 1.0f, 1.0f, 16); /* = cell_m */
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_OK);
    c = make_cfg(1.0f, 1.0f, NAN, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(1.0f, 1.0f, INFINITY, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(1.0f, 1.0f, 1.0e6f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_OK);
    c = make_cfg(1.0f, 1.0f, 1.01e6f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    c = make_cfg(1.0f, 1.0f, -2.0f, 16);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_ARG);
    /* nz: 1..TRN_MAX_ZBINS, else TRN_E_SIZE */
    c = make_cfg(1.0f, 1.0f, 2.0f, 0);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_SIZE);
    c = make_cfg(1.0f, 1.0f, 2.0f, -1);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_SIZE);
    c = make_cfg(1.0f, 1.0f, 2.0f, TRN_MAX_ZBINS + 1);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_E_SIZE);
    c = make_cfg(1.0f, 1.0f, 2.0f, 1);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_OK);
    c = make_cfg(1.0f, 1.0f, 2.0f, TRN_MAX_ZBINS);
    assert_int_equal(trn_terrain_cfg_check(&c), TRN_OK);
}

static void test_highpass_workspace_bytes(void **state)
{
    (void)state;
    assert_int_equal(trn_highpass_workspace_bytes(0, 5), 0u);
    assert_int_equal(trn_highpass_workspace_bytes(5, 0), 0u);
    assert_int_equal(trn_highpass_workspace_bytes(-1, 5), 0u);
    assert_int_equal(trn_highpass_workspace_bytes(5, -1), 0u);
    assert_int_equal(trn_highpass_workspace_bytes(TRN_MAX_DIM + 1, 5), 0u);
    assert_int_equal(trn_highpass_workspace_bytes(5, TRN_MAX_DIM + 1), 0u);
    assert_true(trn_highpass_workspace_bytes(1, 1) > 0u);
    assert_true(trn_highpass_workspace_bytes(TRN_MAX_DIM, TRN_MAX_DIM) > 0u);
    /* grows with the grid */
    assert_true(trn_highpass_workspace_bytes(64, 64) > trn_highpass_workspace_bytes(32, 64));
    assert_true(trn_highpass_workspace_bytes(64, 64) > trn_highpass_workspace_bytes(64, 32));
}

/* ------------------------------------------------------------------------ */
/* trn_highpass                                                              */
/* ------------------------------------------------------------------------ */

static void test_highpass_errors(void **state)
{
    enum { W = 6, H = 5 };
    static float din[W * H], dout[W * H], dbig[(W + 1) * H];
    TRN_WORKSPACE_DECLARE(ws, 1024 * sizeof(double));
    trn_grid_f32_t dem, out, bad, big;
    trn_terrain_cfg_t cfg = make_cfg(1.0f, 1.0f, 1.0f, 8), badcfg;
    const size_t wb = trn_highpass_workspace_bytes(W, H);
    int32_t i;
    (void)state;
    assert_true(wb <= sizeof ws);
    for (i = 0; i < W * H; ++i) {
        din[i] = (float)(i % 7);
    }
    assert_int_equal(trn_grid_f32_init(&dem, din, W * H, W, H), TRN_OK);
    assert_int_equal(trn_grid_f32_init(&out, dout, W * H, W, H), TRN_OK);
    assert_int_equal(trn_highpass(&dem, &cfg, &out, ws, wb), TRN_OK);

    /* TRN_E_NULL: each pointer, and a view without data */
    assert_int_equal(trn_highpass(NULL, &cfg, &out, ws, wb), TRN_E_NULL);
    assert_int_equal(trn_highpass(&dem, NULL, &out, ws, wb), TRN_E_NULL);
    assert_int_equal(trn_highpass(&dem, &cfg, NULL, ws, wb), TRN_E_NULL);
    assert_int_equal(trn_highpass(&dem, &cfg, &out, NULL, wb), TRN_E_NULL);
    bad = dem;
    bad.data = NULL;
    assert_int_equal(trn_highpass(&bad, &cfg, &out, ws, wb), TRN_E_NULL);
    bad = out;
    bad.data = NULL;
    assert_int_equal(trn_highpass(&dem, &cfg, &bad, ws, wb), TRN_E_NULL);

    /* TRN_E_SIZE: bad input grid, bad output grid, size mismatch */
    bad = dem;
    bad.stride = W - 1;
    assert_int_equal(trn_highpass(&bad, &cfg, &out, ws, wb), TRN_E_SIZE);
    bad = dem;
    bad.width = 0;
    assert_int_equal(trn_highpass(&bad, &cfg, &out, ws, wb), TRN_E_SIZE);
    bad = dem;
    bad.height = TRN_MAX_DIM + 1;
    assert_int_equal(trn_highpass(&bad, &cfg, &out, ws, wb), TRN_E_SIZE);
    bad = out;
    bad.stride = W - 1;
    assert_int_equal(trn_highpass(&dem, &cfg, &bad, ws, wb), TRN_E_SIZE);
    bad = out;
    bad.height = -1;
    assert_int_equal(trn_highpass(&dem, &cfg, &bad, ws, wb), TRN_E_SIZE);
    assert_int_equal(trn_grid_f32_init(&big, dbig, (size_t)((W + 1) * H), W + 1, H), TRN_OK);
    assert_int_equal(trn_highpass(&dem, &cfg, &big, ws, sizeof ws), TRN_E_SIZE);
    assert_int_equal(trn_grid_f32_sub(&big, 0, 0, W, H - 1, &bad), TRN_OK);
    assert_int_equal(trn_highpass(&dem, &cfg, &bad, ws, sizeof ws), TRN_E_SIZE);
    /* ...while an output sub-view of the right size is fine */
    assert_int_equal(trn_grid_f32_sub(&big, 1, 0, W, H, &bad), TRN_OK);
    assert_int_equal(trn_highpass(&dem, &cfg, &bad, ws, wb), TRN_OK);

    /* TRN_E_ARG / TRN_E_SIZE from the configuration */
    badcfg = cfg;
    badcfg.cell_m = 0.0f;
    assert_int_equal(trn_highpass(&dem, &badcfg, &out, ws, wb), TRN_E_ARG);
    badcfg = cfg;
    badcfg.highpass_half_m = NAN;
    assert_int_equal(trn_highpass(&dem, &badcfg, &out, ws, wb), TRN_E_ARG);
    badcfg = cfg;
    badcfg.highpass_half_m = 0.5f; /* < cell_m */
    assert_int_equal(trn_highpass(&dem, &badcfg, &out, ws, wb), TRN_E_ARG);
    badcfg = cfg;
    badcfg.zbin_m = NAN;
    assert_int_equal(trn_highpass(&dem, &badcfg, &out, ws, wb), TRN_E_ARG);
    badcfg = cfg;
    badcfg.nz = 0;
    assert_int_equal(trn_highpass(&dem, &badcfg, &out, ws, wb), TRN_E_SIZE);
    badcfg.nz = TRN_MAX_ZBINS + 1;
    assert_int_equal(trn_highpass(&dem, &badcfg, &out, ws, wb), TRN_E_SIZE);

    /* TRN_E_WORKSPACE: exactly enough vs one byte less */
    assert_int_equal(trn_highpass(&dem, &cfg, &out, ws, wb), TRN_OK);
    assert_int_equal(trn_highpass(&dem, &cfg, &out, ws, wb - 1u), TRN_E_WORKSPACE);
    assert_int_equal(trn_highpass(&dem, &cfg, &out, ws, 0u), TRN_E_WORKSPACE);
    /* TRN_E_WORKSPACE: large enough but not TRN_WS_ALIGN-aligned */
    assert_true(wb + 8u <= sizeof ws);
    assert_int_equal(trn_highpass(&dem, &cfg, &out, ws + 8, sizeof ws - 8u), TRN_E_WORKSPACE);
    assert_int_equal(trn_highpass(&dem, &cfg, &out, ws + 16, sizeof ws - 16u), TRN_OK);
}

/* The workspace is used within its size: an exactly-sized heap block (ASan
 * red zones on both sides) for many shapes, including 1 x n and n x 1. */
static void test_highpass_workspace_exact(void **state)
{
    static const int32_t dims[][2] = {{1, 1}, {1, 17}, {17, 1}, {2, 3}, {31, 7}, {64, 65}};
    size_t i;
    (void)state;
    for (i = 0; i < sizeof dims / sizeof dims[0]; ++i) {
        const int32_t w = dims[i][0], h = dims[i][1];
        const trn_terrain_cfg_t cfg = make_cfg(1.0f, 1.0f, 2.0f, 8);
        padded_t dem, out;
        double *expect = (double *)malloc((size_t)w * (size_t)h * sizeof(double));
        int32_t x, y;
        assert_non_null(expect);
        padded_make(&dem, w, h, 0, 0, 0, 0, 0.0f);
        padded_make(&out, w, h, 0, 0, 0, 0, 0.0f);
        for (y = 0; y < h; ++y) {
            for (x = 0; x < w; ++x) {
                TRN_GRID_AT(&dem.view, x, y) = (float)((x * 7 + y * 3) % 11) - 2500.0f;
            }
        }
        assert_int_equal(run_highpass(&dem.view, &cfg, &out.view), TRN_OK);
        oracle_highpass(&dem.view, 2, expect);
        (void)compare_hp(&out.view, expect, HP_TOL_M);
        padded_free(&dem);
        padded_free(&out);
        free(expect);
    }
}

/* A random DEM: absolute offset, a tilt, noise, a few rocks and holes. */
static void fill_dem(trn_rng_t *rng, trn_grid_f32_t *g, double offset_m, double hole_p)
{
    const double gx = uniform(rng, -0.5, 0.5), gy = uniform(rng, -0.5, 0.5);
    int32_t x, y;
    for (y = 0; y < g->height; ++y) {
        for (x = 0; x < g->width; ++x) {
            double hgt = offset_m + gx * (double)x + gy * (double)y + uniform(rng, -1.0, 1.0);
            float v;
            if (trn_rng_unit(rng) < 0.05) {
                hgt += uniform(rng, 0.0, 3.0); /* a rock */
            }
            v = (float)hgt;
            if (trn_rng_unit(rng) < hole_p) {
                const int32_t kind = trn_rng_int(rng, 0, 2);
                v = kind == 0 ? NAN : (kind == 1 ? INFINITY : -INFINITY);
            }
            TRN_GRID_AT(g, x, y) = v;
        }
    }
}

static void test_highpass_random_vs_bruteforce(void **state)
{
    /* (cell, half): r = 1, 3 (2.5 rounds up), 2, 4, 2 (1.5 rounds up), 2,
     * and a box wider than any test grid. */
    static const float cfgs[][2] = {{1.0f, 1.0f}, {0.5f, 1.25f}, {1.0f, 2.0f}, {0.25f, 1.0f},
                                    {2.0f, 3.0f}, {0.1f, 0.2f},  {1.0f, 50.0f}};
    trn_rng_t rng;
    double worst = 0.0;
    int trial, n_sub = 0, n_nodata = 0;
    (void)state;
    trn_rng_seed(&rng, 0x686967687061ull);
    for (trial = 0; trial < 400; ++trial) {
        const int32_t w = trn_rng_int(&rng, 1, 40), h = trn_rng_int(&rng, 1, 40);
        const int32_t padx = trn_rng_int(&rng, 0, 1) ? trn_rng_int(&rng, 1, 6) : 0;
        const int32_t pady = trn_rng_int(&rng, 0, 3);
        const int32_t ci = trn_rng_int(&rng, 0, (int32_t)(sizeof cfgs / sizeof cfgs[0]) - 1);
        const trn_terrain_cfg_t cfg = make_cfg(cfgs[ci][0], 1.0f, cfgs[ci][1], 8);
        const double offset = uniform(&rng, -3000.0, 3000.0);
        const double hole_p = trial % 10 == 9 ? 0.9 : (trial % 10 == 8 ? 0.0 : 0.15);
        padded_t dem, out;
        double *expect = (double *)malloc((size_t)w * (size_t)h * sizeof(double));
        size_t n_valid;
        trn_status_t st;
        assert_non_null(expect);
        padded_make(&dem, w, h, padx, pady, trn_rng_int(&rng, 0, padx), trn_rng_int(&rng, 0, pady),
                    POISON_IN);
        padded_make(&out, w, h, pady, padx, trn_rng_int(&rng, 0, pady), trn_rng_int(&rng, 0, padx),
                    SENTINEL_OUT);
        n_sub += padx > 0 ? 1 : 0;
        fill_dem(&rng, &dem.view, offset, hole_p);
        n_valid = oracle_highpass(&dem.view, oracle_radius(&cfg), expect);
        st = run_highpass(&dem.view, &cfg, &out.view);
        if (n_valid == 0u) {
            assert_int_equal(st, TRN_E_NODATA);
            ++n_nodata;
        } else {
            assert_int_equal(st, TRN_OK);
        }
        worst = fmax(worst, compare_hp(&out.view, expect, HP_TOL_M));
        assert_frame_untouched(&out, SENTINEL_OUT);
        padded_free(&dem);
        padded_free(&out);
        free(expect);
    }
    assert_true(n_sub > 100); /* the sub-view path really was exercised */
    printf("    highpass vs brute force, 400 DEMs at +-3000 m (%d sub-views, %d all-missing): "
           "max |diff| = %.3g m (asserted <= %g m)\n",
           n_sub, n_nodata, worst, HP_TOL_M);
}

/* A big absolute DTM: one 512 x 512 grid spanning -3000 m .. +3000 m, so the
 * summed-area tables accumulate large values far from the reference height. */
static void test_highpass_large_absolute(void **state)
{
    enum { W = 512, H = 512 };
    const trn_terrain_cfg_t cfg = make_cfg(1.0f, 1.0f, 3.0f, 8);
    trn_rng_t rng;
    padded_t dem, out;
    double *expect = (double *)malloc((size_t)W * H * sizeof(double));
    double worst;
    int32_t x, y;
    (void)state;
    assert_non_null(expect);
    trn_rng_seed(&rng, 0x6c61726765ull);
    padded_make(&dem, W, H, 0, 0, 0, 0, 0.0f);
    padded_make(&out, W, H, 0, 0, 0, 0, 0.0f);
    for (y = 0; y < H; ++y) {
        for (x = 0; x < W; ++x) {
            const double hgt = -3000.0 + 6000.0 * (double)(x + y) / (double)(W + H - 2) +
                               uniform(&rng, -5.0, 5.0);
            TRN_GRID_AT(&dem.view, x, y) = trn_rng_unit(&rng) < 0.05 ? NAN : (float)hgt;
        }
    }
    oracle_highpass(&dem.view, 3, expect);
    assert_int_equal(run_highpass(&dem.view, &cfg, &out.view), TRN_OK);
    worst = compare_hp(&out.view, expect, HP_TOL_M);
    printf("    highpass 512x512, heights -3000..+3000 m: max |diff| = %.3g m\n", worst);
    padded_free(&dem);
    padded_free(&out);
    free(expect);
}

/* Heights uniform in [-3000, 3000] m cell by cell: the filtered values are
 * themselves ~1000 m, so the float output alone rounds by up to half an ulp
 * of the value (6e-5 m at 1000 m, 1.2e-4 m above 2048 m). The bound is
 * HP_TOL_M plus that half ulp: anything more is the filter's own error. */
static void test_highpass_wide_relief(void **state)
{
    enum { W = 64, H = 48 };
    const trn_terrain_cfg_t cfg = make_cfg(1.0f, 1.0f, 2.0f, 8);
    trn_rng_t rng;
    padded_t dem, out;
    double expect[W * H], worst = 0.0, worst_excess = 0.0;
    int32_t x, y;
    (void)state;
    trn_rng_seed(&rng, 0x77696465ull);
    padded_make(&dem, W, H, 3, 2, 1, 1, POISON_IN);
    padded_make(&out, W, H, 0, 0, 0, 0, 0.0f);
    for (y = 0; y < H; ++y) {
        for (x = 0; x < W; ++x) {
            TRN_GRID_AT(&dem.view, x, y) = (float)uniform(&rng, -3000.0, 3000.0);
        }
    }
    oracle_highpass(&dem.view, 2, expect);
    assert_int_equal(run_highpass(&dem.view, &cfg, &out.view), TRN_OK);
    for (y = 0; y < H; ++y) {
        for (x = 0; x < W; ++x) {
            const double e = expect[y * W + x];
            const double d = fabs((double)TRN_GRID_AT(&out.view, x, y) - e);
            const double half_ulp = fabs(e) * (double)FLT_EPSILON * 0.5;
            assert_true(d <= HP_TOL_M + half_ulp);
            worst = fmax(worst, d);
            worst_excess = fmax(worst_excess, d - half_ulp);
        }
    }
    printf("    highpass, white-noise heights +-3000 m: max |diff| = %.3g m, "
           "beyond float output rounding: %.3g m\n",
           worst, worst_excess);
    padded_free(&dem);
    padded_free(&out);
}

/* A plane of any slope filters to 0 wherever the full box fits. */
static void test_highpass_plane(void **state)
{
    trn_rng_t rng;
    double worst_any = 0.0, worst_exact = 0.0, worst_mars = 0.0;
    int trial;
    (void)state;
    trn_rng_seed(&rng, 0x706c616e65ull);
    for (trial = 0; trial < 60; ++trial) {
        const int32_t w = trn_rng_int(&rng, 8, 40), h = trn_rng_int(&rng, 8, 40);
        const int32_t r = trn_rng_int(&rng, 1, 3);
        const trn_terrain_cfg_t cfg = make_cfg(0.5f, 1.0f, 0.5f * (float)r, 8);
        const int kind = trial % 3;
        double gx, gy, off, tol, worst = 0.0;
        padded_t dem, out;
        int32_t x, y;
        if (kind == 0) { /* any slope, heights within a few hundred metres */
            gx = uniform(&rng, -2.0, 2.0);
            gy = uniform(&rng, -2.0, 2.0);
            off = uniform(&rng, -50.0, 50.0);
            tol = HP_TOL_M;
        } else if (kind == 1) { /* dyadic slope at +-3000 m: every height exact in float */
            gx = (double)trn_rng_int(&rng, -64, 64) / 64.0;
            gy = (double)trn_rng_int(&rng, -64, 64) / 64.0;
            off = (double)trn_rng_int(&rng, -3000, 3000);
            tol = 1e-6;
        } else { /* any slope at +-3000 m: the float DEM is only a plane to
                  * within half an ulp (1.2e-4 m), so the bound is one ulp */
            gx = uniform(&rng, -1.0, 1.0);
            gy = uniform(&rng, -1.0, 1.0);
            off = uniform(&rng, 2100.0, 3000.0) * (trn_rng_int(&rng, 0, 1) ? 1.0 : -1.0);
            tol = 4096.0 * (double)FLT_EPSILON * 0.5 * 2.0;
        }
        padded_make(&dem, w, h, 2, 1, 1, 0, POISON_IN);
        padded_make(&out, w, h, 1, 2, 0, 1, SENTINEL_OUT);
        for (y = 0; y < h; ++y) {
            for (x = 0; x < w; ++x) {
                TRN_GRID_AT(&dem.view, x, y) = (float)(off + gx * (double)x + gy * (double)y);
            }
        }
        assert_int_equal(oracle_radius(&cfg), r);
        assert_int_equal(run_highpass(&dem.view, &cfg, &out.view), TRN_OK);
        for (y = r; y < h - r; ++y) {
            for (x = r; x < w - r; ++x) {
                const double d = fabs((double)TRN_GRID_AT(&out.view, x, y));
                if (!(d <= tol)) {
                    fail_msg("plane kind %d slope (%g, %g) offset %g r %d: cell (%d, %d) "
                             "filtered to %.9g",
                             kind, gx, gy, off, (int)r, (int)x, (int)y, d);
                }
                worst = fmax(worst, d);
            }
        }
        /* everywhere, border cells included (lopsided clipped boxes), the
         * brute force on the same float DEM agrees */
        {
            double *expect = (double *)malloc((size_t)w * (size_t)h * sizeof(double));
            assert_non_null(expect);
            oracle_highpass(&dem.view, r, expect);
            (void)compare_hp(&out.view, expect, HP_TOL_M);
            free(expect);
        }
        assert_frame_untouched(&out, SENTINEL_OUT);
        if (kind == 0) {
            worst_any = fmax(worst_any, worst);
        } else if (kind == 1) {
            worst_exact = fmax(worst_exact, worst);
        } else {
            worst_mars = fmax(worst_mars, worst);
        }
        padded_free(&dem);
        padded_free(&out);
    }
    printf("    highpass of planes (interior): any slope |h|<300 m: max %.3g m; dyadic at "
           "+-3000 m: max %.3g m; any slope at +-3000 m: max %.3g m (float DEM quantisation)\n",
           worst_any, worst_exact, worst_mars);
}

static void test_highpass_missing(void **state)
{
    enum { W = 7, H = 5 };
    static float din[W * H], dout[W * H];
    TRN_WORKSPACE_DECLARE(ws, 512 * sizeof(double));
    const trn_terrain_cfg_t cfg = make_cfg(1.0f, 1.0f, 1.0f, 8);
    const size_t wb = trn_highpass_workspace_bytes(W, H);
    const float kinds[3] = {NAN, INFINITY, -INFINITY};
    trn_grid_f32_t dem, out;
    double expect[W * H];
    int32_t i;
    (void)state;
    assert_true(wb <= sizeof ws);
    assert_int_equal(trn_grid_f32_init(&dem, din, W * H, W, H), TRN_OK);
    assert_int_equal(trn_grid_f32_init(&out, dout, W * H, W, H), TRN_OK);

    /* all missing (a mix of NaN, +inf, -inf): TRN_E_NODATA and out all NaN */
    for (i = 0; i < W * H; ++i) {
        din[i] = kinds[i % 3];
        dout[i] = 0.0f;
    }
    assert_int_equal(trn_highpass(&dem, &cfg, &out, ws, wb), TRN_E_NODATA);
    for (i = 0; i < W * H; ++i) {
        assert_true(isnan(dout[i]));
    }
    /* every missing kind alone */
    for (i = 0; i < 3; ++i) {
        int32_t j;
        for (j = 0; j < W * H; ++j) {
            din[j] = kinds[i];
        }
        assert_int_equal(trn_highpass(&dem, &cfg, &out, ws, wb), TRN_E_NODATA);
    }
    /* one valid cell: it is its own mean, so 0; the rest stays NaN (never inf) */
    din[2 * W + 3] = -2750.0f;
    for (i = 0; i < W * H; ++i) {
        dout[i] = 1.0f;
    }
    assert_int_equal(trn_highpass(&dem, &cfg, &out, ws, wb), TRN_OK);
    for (i = 0; i < W * H; ++i) {
        if (i == 2 * W + 3) {
            assert_true(dout[i] == 0.0f);
        } else {
            assert_true(isnan(dout[i]));
        }
    }
    /* holes next to data: missing stays NaN, the rest ignores the holes */
    for (i = 0; i < W * H; ++i) {
        din[i] = (i % 4 == 1) ? kinds[(i / 4) % 3] : 3000.0f + (float)(i % 5);
    }
    assert_int_equal(trn_highpass(&dem, &cfg, &out, ws, wb), TRN_OK);
    oracle_highpass(&dem, 1, expect);
    (void)compare_hp(&out, expect, HP_TOL_M);
    for (i = 0; i < W * H; ++i) {
        assert_true((i % 4 == 1) == (isnan(dout[i]) != 0));
    }
}

/* A configuration trn_terrain_cfg_check accepts (cell_m in (0, TRN_CELL_MAX_M],
 * highpass_half_m in [cell_m, 1e6]) whose box is wider than any grid: the
 * box is then the whole grid and H' = H - mean(H). */
static void test_highpass_box_wider_than_grid(void **state)
{
    enum { W = 6, H = 5 };
    static float din[W * H], dout[W * H];
    TRN_WORKSPACE_DECLARE(ws, 512 * sizeof(double));
    static const float cells[] = {1.0f, 1e-3f, 1e-30f};
    const size_t wb = trn_highpass_workspace_bytes(W, H);
    trn_grid_f32_t dem, out;
    double expect[W * H];
    size_t k;
    int32_t i;
    (void)state;
    assert_true(wb <= sizeof ws);
    assert_int_equal(trn_grid_f32_init(&dem, din, W * H, W, H), TRN_OK);
    assert_int_equal(trn_grid_f32_init(&out, dout, W * H, W, H), TRN_OK);
    for (i = 0; i < W * H; ++i) {
        din[i] = (float)i;
    }
    oracle_highpass(&dem, W + H, expect); /* whole grid */
    for (k = 0; k < sizeof cells / sizeof cells[0]; ++k) {
        const trn_terrain_cfg_t cfg = make_cfg(cells[k], 1.0f, 1000.0f, 8);
        assert_int_equal(trn_terrain_cfg_check(&cfg), TRN_OK);
        assert_int_equal(trn_highpass(&dem, &cfg, &out, ws, wb), TRN_OK);
        for (i = 0; i < W * H; ++i) {
            if (!(fabs((double)dout[i] - expect[i]) <= HP_TOL_M)) {
                fail_msg("cell_m %g, highpass_half_m 1000: cell %d filtered to %.9g, "
                         "expected %.9g (box = whole grid)",
                         (double)cells[k], (int)i, (double)dout[i], expect[i]);
            }
        }
    }
}

/* ------------------------------------------------------------------------ */
/* occupancy                                                                 */
/* ------------------------------------------------------------------------ */

/* The documented bin: floor(h / zbin + 1/2) + nz/2, clamped; -1 when missing. The
 * quotient is taken in double (see docs/modules/terrain.md). */
static int32_t oracle_bin(float h, const trn_terrain_cfg_t *cfg)
{
    double k;
    if (!isfinite(h)) {
        return -1;
    }
    k = floor((double)h / (double)cfg->zbin_m + 0.5) + (double)(cfg->nz / 2);
    if (k < 0.0) {
        k = 0.0;
    }
    if (k > (double)(cfg->nz - 1)) {
        k = (double)(cfg->nz - 1);
    }
    return (int32_t)k;
}

/* The documented column rule, written out naively. Fills vol (w*h*nz, dense)
 * and returns the number of occupied voxels. */
static uint32_t oracle_occupancy(const trn_grid_f32_t *hp, const trn_terrain_cfg_t *cfg,
                                 uint8_t *vol)
{
    const int32_t w = hp->width, h = hp->height, nz = cfg->nz;
    uint32_t n = 0;
    int32_t x, y, z;
    memset(vol, 0, (size_t)w * (size_t)h * (size_t)nz);
    for (y = 0; y < h; ++y) {
        for (x = 0; x < w; ++x) {
            const int32_t k = oracle_bin(TRN_GRID_AT(hp, x, y), cfg);
            int32_t lowest = INT32_MAX, lo;
            if (k < 0) {
                continue; /* missing: never occupied */
            }
            if (x > 0 && oracle_bin(TRN_GRID_AT(hp, x - 1, y), cfg) >= 0) {
                lowest = oracle_bin(TRN_GRID_AT(hp, x - 1, y), cfg);
            }
            if (x + 1 < w && oracle_bin(TRN_GRID_AT(hp, x + 1, y), cfg) >= 0 &&
                oracle_bin(TRN_GRID_AT(hp, x + 1, y), cfg) < lowest) {
                lowest = oracle_bin(TRN_GRID_AT(hp, x + 1, y), cfg);
            }
            if (y > 0 && oracle_bin(TRN_GRID_AT(hp, x, y - 1), cfg) >= 0 &&
                oracle_bin(TRN_GRID_AT(hp, x, y - 1), cfg) < lowest) {
                lowest = oracle_bin(TRN_GRID_AT(hp, x, y - 1), cfg);
            }
            if (y + 1 < h && oracle_bin(TRN_GRID_AT(hp, x, y + 1), cfg) >= 0 &&
                oracle_bin(TRN_GRID_AT(hp, x, y + 1), cfg) < lowest) {
                lowest = oracle_bin(TRN_GRID_AT(hp, x, y + 1), cfg);
            }
            lo = (lowest < k) ? lowest + 1 : k;
            for (z = lo; z <= k; ++z) {
                vol[((size_t)z * (size_t)h + (size_t)y) * (size_t)w + (size_t)x] = 1u;
                ++n;
            }
        }
    }
    return n;
}

static void test_occupancy_analytic(void **state)
{
    /* 3 x 2 grid, zbin 1 m, nz 8 (bin of 0 m = 4):
     *   row 0:  0.0 (bin 4)   2.5 (bin 7)   NaN
     *   row 1: -0.5 (bin 4)  -100 (bin 0)   100 (bin 7)
     * (bins centred: -0.5 and 2.5 are the rounding edges, rounded up)
     * columns: (0,0) 4..4; (1,0) 1..7 (lowest neighbour (1,1) bin 0);
     * (0,1) 1..4; (1,1) 0..0; (2,1) 1..7; (2,0) none. 20 voxels. */
    static float d[6] = {0.0f, 2.5f, NAN, -0.5f, -100.0f, 100.0f};
    static const int32_t lo[6] = {4, 1, -1, 1, 0, 1}, hi[6] = {4, 7, -1, 4, 0, 7};
    static uint8_t vbuf[3 * 2 * 8];
    const trn_terrain_cfg_t cfg = make_cfg(1.0f, 1.0f, 1.0f, 8);
    trn_grid_f32_t hp;
    trn_vol_u8_t occ;
    trn_point_t pts[32];
    size_t np = 0, k = 0;
    uint32_t n = 0;
    int32_t x, y, z;
    (void)state;
    assert_int_equal(trn_grid_f32_init(&hp, d, 6u, 3, 2), TRN_OK);
    assert_int_equal(trn_vol_u8_init(&occ, vbuf, sizeof vbuf, 3, 2, 8), TRN_OK);
    memset(vbuf, 0xAB, sizeof vbuf);
    assert_int_equal(trn_occupancy(&hp, &cfg, &occ, &n), TRN_OK);
    assert_int_equal(n, 20u);
    for (z = 0; z < 8; ++z) {
        for (y = 0; y < 2; ++y) {
            for (x = 0; x < 3; ++x) {
                const int32_t c = y * 3 + x;
                const int on = lo[c] >= 0 && z >= lo[c] && z <= hi[c];
                assert_int_equal(occ.data[TRN_VOL_IDX(&occ, x, y, z)], on ? 1u : 0u);
            }
        }
    }
    /* points relative to rover cell (1, 1), in (z, y, x) order */
    assert_int_equal(trn_occupancy_points(&hp, &cfg, 1, 1, pts, 32u, &np), TRN_OK);
    assert_int_equal(np, 20u);
    for (z = 0; z < 8; ++z) {
        for (y = 0; y < 2; ++y) {
            for (x = 0; x < 3; ++x) {
                const int32_t c = y * 3 + x;
                if (lo[c] >= 0 && z >= lo[c] && z <= hi[c]) {
                    assert_true(k < np);
                    assert_int_equal(pts[k].x, x - 1);
                    assert_int_equal(pts[k].y, y - 1);
                    assert_int_equal(pts[k].z, z);
                    ++k;
                }
            }
        }
    }
    assert_int_equal(k, 20u);
}

static void test_occupancy_bins(void **state)
{
    /* one row, cells far apart in height do not interact downward here
     * because each is its own 1x1 grid */
    static const struct {
        float h, zbin;
        int32_t nz, bin;
    } cases[] = {
        /* bins centred on multiples of zbin: k = floor(h/zbin + 1/2) + nz/2 */
        {0.0f, 1.0f, 5, 2},
        {-0.0f, 1.0f, 5, 2},
        {0.999f, 1.0f, 5, 3},
        {1.0f, 1.0f, 5, 3},
        {-1e-6f, 1.0f, 5, 2},
        {-1.0f, 1.0f, 5, 1},
        {-1.5f, 1.0f, 5, 1},
        {-2.0f, 1.0f, 5, 0},
        {-2.5f, 1.0f, 5, 0},
        {2.999f, 1.0f, 5, 4},
        {3.0f, 1.0f, 5, 4},
        {1e30f, 1.0f, 5, 4},
        {-1e30f, 1.0f, 5, 0},
        {0.75f, 0.25f, 8, 7},
        {0.74f, 0.25f, 8, 7},
        {-1.0f, 0.25f, 8, 0},
        {-0.9f, 0.25f, 8, 0},
        {-0.74f, 0.25f, 8, 1},
        {5.0f, 1.0f, 1, 0},
        {-5.0f, 1.0f, 1, 0},
        {0.3f, 0.1f, 128, 67},
        {-12.75f, 0.5f, 64, 7},
        /* the rounding edges at +-zbin/2: ground flat within them stays in one bin */
        {0.5f, 1.0f, 5, 3},
        {0.4999f, 1.0f, 5, 2},
        {-0.5f, 1.0f, 5, 2},
        {-0.5001f, 1.0f, 5, 1},
        {0.049f, 0.1f, 16, 8},
        {-0.049f, 0.1f, 16, 8},
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        float d = cases[i].h;
        uint8_t v[TRN_MAX_ZBINS];
        trn_grid_f32_t hp;
        trn_vol_u8_t occ;
        trn_point_t pt;
        size_t np = 0;
        uint32_t n = 0;
        const trn_terrain_cfg_t cfg = make_cfg(1.0f, cases[i].zbin, 1.0f, cases[i].nz);
        int32_t z;
        assert_int_equal(oracle_bin(cases[i].h, &cfg), cases[i].bin);
        assert_int_equal(trn_grid_f32_init(&hp, &d, 1u, 1, 1), TRN_OK);
        assert_int_equal(trn_vol_u8_init(&occ, v, sizeof v, 1, 1, cases[i].nz), TRN_OK);
        assert_int_equal(trn_occupancy(&hp, &cfg, &occ, &n), TRN_OK);
        assert_int_equal(n, 1u);
        for (z = 0; z < cases[i].nz; ++z) {
            if (v[z] != (z == cases[i].bin ? 1u : 0u)) {
                fail_msg("h %g zbin %g nz %d: bin %d is %u (expected bin %d)", (double)cases[i].h,
                         (double)cases[i].zbin, (int)cases[i].nz, (int)z, (unsigned)v[z],
                         (int)cases[i].bin);
            }
        }
        assert_int_equal(trn_occupancy_points(&hp, &cfg, 0, 0, &pt, 1u, &np), TRN_OK);
        assert_int_equal(np, 1u);
        assert_int_equal(pt.z, cases[i].bin);
    }
}

/* Random filtered grids (sub-views with poison around) against the naive rule. */
static void test_occupancy_random_vs_naive(void **state)
{
    static const int32_t nzs[] = {1, 2, 5, 8, 17, 32, TRN_MAX_ZBINS};
    static const float zbins[] = {1.0f, 0.5f, 0.25f, 0.3f, 2.0f};
    trn_rng_t rng;
    int trial;
    uint64_t total = 0;
    (void)state;
    trn_rng_seed(&rng, 0x6f6363ull);
    for (trial = 0; trial < 300; ++trial) {
        const int32_t w = trn_rng_int(&rng, 1, 30), h = trn_rng_int(&rng, 1, 30);
        const int32_t nz = nzs[trn_rng_int(&rng, 0, (int32_t)(sizeof nzs / sizeof nzs[0]) - 1)];
        const float zb = zbins[trn_rng_int(&rng, 0, (int32_t)(sizeof zbins / sizeof zbins[0]) - 1)];
        const trn_terrain_cfg_t cfg = make_cfg(1.0f, zb, 1.0f, nz);
        const double span = ((double)(nz / 2) + 3.0) * (double)zb;
        const double hole_p = trial % 10 == 0 ? 0.0 : 0.2;
        const size_t nvox = (size_t)w * (size_t)h * (size_t)nz;
        uint8_t *vol = (uint8_t *)malloc(nvox), *ref = (uint8_t *)malloc(nvox);
        padded_t hp;
        trn_vol_u8_t occ;
        uint32_t n = 0, n_ref;
        int32_t x, y, z;
        assert_non_null(vol);
        assert_non_null(ref);
        /* poison is a very low finite height: a column that looked at a
         * neighbour outside the view would reach down to bin 1 */
        padded_make(&hp, w, h, 2, 2, 1, 1, -1e6f);
        for (y = 0; y < h; ++y) {
            for (x = 0; x < w; ++x) {
                float v;
                if (trn_rng_unit(&rng) < 0.1) {
                    /* exactly on a bin edge */
                    v = (float)((double)trn_rng_int(&rng, -nz / 2 - 2, nz / 2 + 2) * (double)zb);
                } else {
                    v = (float)uniform(&rng, -span, span);
                }
                if (trn_rng_unit(&rng) < hole_p) {
                    v = trn_rng_int(&rng, 0, 1) ? NAN : -INFINITY;
                }
                TRN_GRID_AT(&hp.view, x, y) = v;
            }
        }
        n_ref = oracle_occupancy(&hp.view, &cfg, ref);
        memset(vol, 0xAB, nvox);
        assert_int_equal(trn_vol_u8_init(&occ, vol, nvox, w, h, nz), TRN_OK);
        assert_int_equal(trn_occupancy(&hp.view, &cfg, &occ, &n),
                         n_ref > 0u ? TRN_OK : TRN_E_NODATA);
        assert_int_equal(n, n_ref);
        assert_memory_equal(vol, ref, nvox);
        /* missing cells are never occupied */
        for (y = 0; y < h; ++y) {
            for (x = 0; x < w; ++x) {
                if (!isfinite(TRN_GRID_AT(&hp.view, x, y))) {
                    for (z = 0; z < nz; ++z) {
                        assert_int_equal(vol[TRN_VOL_IDX(&occ, x, y, z)], 0u);
                    }
                }
            }
        }
        /* n_occupied may be NULL */
        assert_int_equal(trn_occupancy(&hp.view, &cfg, &occ, NULL),
                         n_ref > 0u ? TRN_OK : TRN_E_NODATA);
        assert_memory_equal(vol, ref, nvox);
        total += n_ref;
        padded_free(&hp);
        free(vol);
        free(ref);
    }
    assert_true(total > 10000u);
}

static void test_occupancy_errors(void **state)
{
    enum { W = 4, H = 3, NZ = 6 };
    static float d[W * H];
    static uint8_t v[W * H * NZ], vbig[(W + 1) * (H + 1) * (NZ + 1)];
    const trn_terrain_cfg_t cfg = make_cfg(1.0f, 1.0f, 1.0f, NZ);
    trn_terrain_cfg_t badcfg;
    trn_grid_f32_t hp, badg;
    trn_vol_u8_t occ, badv;
    uint32_t n = 99;
    int32_t i;
    (void)state;
    for (i = 0; i < W * H; ++i) {
        d[i] = (float)(i % 3) - 1.0f;
    }
    assert_int_equal(trn_grid_f32_init(&hp, d, W * H, W, H), TRN_OK);
    assert_int_equal(trn_vol_u8_init(&occ, v, sizeof v, W, H, NZ), TRN_OK);
    assert_int_equal(trn_occupancy(&hp, &cfg, &occ, &n), TRN_OK);

    /* TRN_E_NULL */
    assert_int_equal(trn_occupancy(NULL, &cfg, &occ, &n), TRN_E_NULL);
    assert_int_equal(trn_occupancy(&hp, NULL, &occ, &n), TRN_E_NULL);
    assert_int_equal(trn_occupancy(&hp, &cfg, NULL, &n), TRN_E_NULL);
    badg = hp;
    badg.data = NULL;
    assert_int_equal(trn_occupancy(&badg, &cfg, &occ, &n), TRN_E_NULL);
    badv = occ;
    badv.data = NULL;
    assert_int_equal(trn_occupancy(&hp, &cfg, &badv, &n), TRN_E_NULL);

    /* TRN_E_SIZE: bad grid, bad volume, each dimension mismatched */
    badg = hp;
    badg.stride = W - 1;
    assert_int_equal(trn_occupancy(&badg, &cfg, &occ, &n), TRN_E_SIZE);
    badg = hp;
    badg.height = 0;
    assert_int_equal(trn_occupancy(&badg, &cfg, &occ, &n), TRN_E_SIZE);
    badv = occ;
    badv.nz = TRN_MAX_ZBINS + 1;
    assert_int_equal(trn_occupancy(&hp, &cfg, &badv, &n), TRN_E_SIZE);
    badv = occ;
    badv.nx = 0;
    assert_int_equal(trn_occupancy(&hp, &cfg, &badv, &n), TRN_E_SIZE);
    assert_int_equal(trn_vol_u8_init(&badv, vbig, sizeof vbig, W + 1, H, NZ), TRN_OK);
    assert_int_equal(trn_occupancy(&hp, &cfg, &badv, &n), TRN_E_SIZE);
    assert_int_equal(trn_vol_u8_init(&badv, vbig, sizeof vbig, W, H + 1, NZ), TRN_OK);
    assert_int_equal(trn_occupancy(&hp, &cfg, &badv, &n), TRN_E_SIZE);
    assert_int_equal(trn_vol_u8_init(&badv, vbig, sizeof vbig, W, H, NZ + 1), TRN_OK);
    assert_int_equal(trn_occupancy(&hp, &cfg, &badv, &n), TRN_E_SIZE);
    assert_int_equal(trn_vol_u8_init(&badv, vbig, sizeof vbig, W, H, NZ - 1), TRN_OK);
    assert_int_equal(trn_occupancy(&hp, &cfg, &badv, &n), TRN_E_SIZE);

    /* TRN_E_ARG / TRN_E_SIZE from the configuration */
    badcfg = cfg;
    badcfg.zbin_m = 0.0f;
    assert_int_equal(trn_occupancy(&hp, &badcfg, &occ, &n), TRN_E_ARG);
    badcfg = cfg;
    badcfg.zbin_m = NAN;
    assert_int_equal(trn_occupancy(&hp, &badcfg, &occ, &n), TRN_E_ARG);
    badcfg = cfg;
    badcfg.cell_m = NAN;
    assert_int_equal(trn_occupancy(&hp, &badcfg, &occ, &n), TRN_E_ARG);
    badcfg = cfg;
    badcfg.nz = 0;
    assert_int_equal(trn_occupancy(&hp, &badcfg, &occ, &n), TRN_E_SIZE);

    /* TRN_E_NODATA: every height missing; count 0 and the volume cleared */
    for (i = 0; i < W * H; ++i) {
        d[i] = (i % 3 == 0) ? NAN : (i % 3 == 1 ? INFINITY : -INFINITY);
    }
    memset(v, 0xAB, sizeof v);
    n = 99;
    assert_int_equal(trn_occupancy(&hp, &cfg, &occ, &n), TRN_E_NODATA);
    assert_int_equal(n, 0u);
    for (i = 0; i < (int32_t)sizeof v; ++i) {
        assert_int_equal(v[i], 0u);
    }
    assert_int_equal(trn_occupancy(&hp, &cfg, &occ, NULL), TRN_E_NODATA);
}

/* ------------------------------------------------------------------------ */
/* occupancy points                                                          */
/* ------------------------------------------------------------------------ */

/* Lists exactly the occupied voxels of trn_occupancy, shifted by the rover
 * cell, in (z, y, x) order; capacity exact vs one short. */
static void test_points_vs_occupancy(void **state)
{
    static const int32_t nzs[] = {1, 3, 8, 16};
    trn_rng_t rng;
    int trial;
    (void)state;
    trn_rng_seed(&rng, 0x707473ull);
    for (trial = 0; trial < 200; ++trial) {
        const int32_t w = trn_rng_int(&rng, 1, 25), h = trn_rng_int(&rng, 1, 25);
        const int32_t nz = nzs[trn_rng_int(&rng, 0, 3)];
        const trn_terrain_cfg_t cfg = make_cfg(1.0f, 0.5f, 1.0f, nz);
        const int32_t rx = trn_rng_int(&rng, -30, w + 30), ry = trn_rng_int(&rng, -30, h + 30);
        const size_t nvox = (size_t)w * (size_t)h * (size_t)nz;
        uint8_t *vol = (uint8_t *)malloc(nvox);
        trn_point_t *pts;
        padded_t hp;
        trn_vol_u8_t occ;
        uint32_t n = 0;
        size_t np = 12345, k = 0, cap;
        int32_t x, y, z;
        trn_status_t st;
        assert_non_null(vol);
        padded_make(&hp, w, h, 3, 1, 2, 0, -1e6f);
        for (y = 0; y < h; ++y) {
            for (x = 0; x < w; ++x) {
                const float v = (float)uniform(&rng, -0.3 * (double)nz, 0.3 * (double)nz);
                TRN_GRID_AT(&hp.view, x, y) = trn_rng_unit(&rng) < 0.2 ? NAN : v;
            }
        }
        assert_int_equal(trn_vol_u8_init(&occ, vol, nvox, w, h, nz), TRN_OK);
        st = trn_occupancy(&hp.view, &cfg, &occ, &n);
        assert_true(st == TRN_OK || st == TRN_E_NODATA);
        cap = (size_t)n + 1u;
        pts = (trn_point_t *)malloc(cap * sizeof(trn_point_t));
        assert_non_null(pts);

        /* capacity exactly n */
        assert_int_equal(trn_occupancy_points(&hp.view, &cfg, rx, ry, pts, (size_t)n, &np), st);
        assert_int_equal(np, (size_t)n);
        for (z = 0; z < nz; ++z) {
            for (y = 0; y < h; ++y) {
                for (x = 0; x < w; ++x) {
                    if (vol[TRN_VOL_IDX(&occ, x, y, z)]) {
                        assert_true(k < np);
                        assert_int_equal(pts[k].x, x - rx);
                        assert_int_equal(pts[k].y, y - ry);
                        assert_int_equal(pts[k].z, z);
                        ++k;
                    }
                }
            }
        }
        assert_int_equal(k, np);
        /* strictly increasing in (z, y, x) */
        for (k = 1; k < np; ++k) {
            const trn_point_t *a = &pts[k - 1], *b = &pts[k];
            assert_true(a->z < b->z ||
                        (a->z == b->z && (a->y < b->y || (a->y == b->y && a->x < b->x))));
        }
        /* more room than needed: same answer */
        assert_int_equal(trn_occupancy_points(&hp.view, &cfg, rx, ry, pts, cap, &np), st);
        assert_int_equal(np, (size_t)n);
        /* one short: TRN_E_CAPACITY, nothing usable */
        if (n > 0u) {
            np = 12345;
            assert_int_equal(trn_occupancy_points(&hp.view, &cfg, rx, ry, pts, (size_t)n - 1u, &np),
                             TRN_E_CAPACITY);
            assert_int_equal(np, 0u);
            assert_int_equal(trn_occupancy_points(&hp.view, &cfg, rx, ry, pts, 0u, &np),
                             TRN_E_CAPACITY);
            assert_int_equal(np, 0u);
        }
        padded_free(&hp);
        free(vol);
        free(pts);
    }
}

static void test_points_errors(void **state)
{
    enum { W = 5, H = 4 };
    static float d[W * H];
    trn_point_t pts[W * H * 8];
    const trn_terrain_cfg_t cfg = make_cfg(1.0f, 1.0f, 1.0f, 8);
    trn_terrain_cfg_t badcfg;
    trn_grid_f32_t hp, bad;
    size_t np = 0;
    const size_t cap = sizeof pts / sizeof pts[0];
    int32_t i;
    (void)state;
    for (i = 0; i < W * H; ++i) {
        d[i] = 0.25f * (float)(i % 5);
    }
    assert_int_equal(trn_grid_f32_init(&hp, d, W * H, W, H), TRN_OK);
    assert_int_equal(trn_occupancy_points(&hp, &cfg, 2, 2, pts, cap, &np), TRN_OK);
    assert_true(np >= (size_t)(W * H));

    /* TRN_E_NULL */
    assert_int_equal(trn_occupancy_points(NULL, &cfg, 0, 0, pts, cap, &np), TRN_E_NULL);
    assert_int_equal(trn_occupancy_points(&hp, NULL, 0, 0, pts, cap, &np), TRN_E_NULL);
    assert_int_equal(trn_occupancy_points(&hp, &cfg, 0, 0, NULL, cap, &np), TRN_E_NULL);
    assert_int_equal(trn_occupancy_points(&hp, &cfg, 0, 0, pts, cap, NULL), TRN_E_NULL);
    bad = hp;
    bad.data = NULL;
    assert_int_equal(trn_occupancy_points(&bad, &cfg, 0, 0, pts, cap, &np), TRN_E_NULL);

    /* TRN_E_SIZE */
    bad = hp;
    bad.stride = W - 1;
    assert_int_equal(trn_occupancy_points(&bad, &cfg, 0, 0, pts, cap, &np), TRN_E_SIZE);
    bad = hp;
    bad.width = TRN_MAX_DIM + 1;
    bad.stride = TRN_MAX_DIM + 1;
    assert_int_equal(trn_occupancy_points(&bad, &cfg, 0, 0, pts, cap, &np), TRN_E_SIZE);
    badcfg = cfg;
    badcfg.nz = TRN_MAX_ZBINS + 1;
    assert_int_equal(trn_occupancy_points(&hp, &badcfg, 0, 0, pts, cap, &np), TRN_E_SIZE);

    /* TRN_E_ARG: configuration */
    badcfg = cfg;
    badcfg.cell_m = -1.0f;
    assert_int_equal(trn_occupancy_points(&hp, &badcfg, 0, 0, pts, cap, &np), TRN_E_ARG);
    badcfg = cfg;
    badcfg.zbin_m = INFINITY;
    assert_int_equal(trn_occupancy_points(&hp, &badcfg, 0, 0, pts, cap, &np), TRN_E_ARG);

    /* TRN_E_ARG: rover cell farther than TRN_MAX_DIM from the grid, below it */
    assert_int_equal(trn_occupancy_points(&hp, &cfg, -TRN_MAX_DIM, 0, pts, cap, &np), TRN_OK);
    assert_int_equal(trn_occupancy_points(&hp, &cfg, 0, -TRN_MAX_DIM, pts, cap, &np), TRN_OK);
    assert_int_equal(trn_occupancy_points(&hp, &cfg, -TRN_MAX_DIM - 1, 0, pts, cap, &np),
                     TRN_E_ARG);
    assert_int_equal(trn_occupancy_points(&hp, &cfg, 0, -TRN_MAX_DIM - 1, pts, cap, &np),
                     TRN_E_ARG);
    assert_int_equal(trn_occupancy_points(&hp, &cfg, INT32_MIN, 0, pts, cap, &np), TRN_E_ARG);
    assert_int_equal(trn_occupancy_points(&hp, &cfg, 0, INT32_MAX, pts, cap, &np), TRN_E_ARG);
    /* ...and above it: the last column is W-1, so W-1+TRN_MAX_DIM is the farthest allowed */
    assert_int_equal(trn_occupancy_points(&hp, &cfg, W - 1 + TRN_MAX_DIM, 0, pts, cap, &np),
                     TRN_OK);
    assert_int_equal(trn_occupancy_points(&hp, &cfg, 0, H - 1 + TRN_MAX_DIM, pts, cap, &np),
                     TRN_OK);

    /* TRN_E_NODATA: all missing */
    for (i = 0; i < W * H; ++i) {
        d[i] = (i % 2) ? NAN : INFINITY;
    }
    np = 77;
    assert_int_equal(trn_occupancy_points(&hp, &cfg, 0, 0, pts, cap, &np), TRN_E_NODATA);
    assert_int_equal(np, 0u);
    /* TRN_E_NODATA wins over capacity 0: there is nothing to overflow */
    assert_int_equal(trn_occupancy_points(&hp, &cfg, 0, 0, pts, 0u, &np), TRN_E_NODATA);
}

/* The documented upper bound on the rover cell: "farther than TRN_MAX_DIM from
 * the grid" is TRN_E_ARG on the high side too. */
static void test_points_rover_far_above(void **state)
{
    enum { W = 5, H = 4 };
    static float d[W * H];
    trn_point_t pts[W * H * 8];
    const trn_terrain_cfg_t cfg = make_cfg(1.0f, 1.0f, 1.0f, 8);
    trn_grid_f32_t hp;
    size_t np = 0;
    const size_t cap = sizeof pts / sizeof pts[0];
    (void)state;
    memset(d, 0, sizeof d);
    assert_int_equal(trn_grid_f32_init(&hp, d, W * H, W, H), TRN_OK);
    assert_int_equal(trn_occupancy_points(&hp, &cfg, W + TRN_MAX_DIM, 0, pts, cap, &np), TRN_E_ARG);
    assert_int_equal(trn_occupancy_points(&hp, &cfg, 0, H + TRN_MAX_DIM, pts, cap, &np), TRN_E_ARG);
    assert_int_equal(trn_occupancy_points(&hp, &cfg, 2 * TRN_MAX_DIM, 0, pts, cap, &np), TRN_E_ARG);
}

/* Offsets at the far end of the allowed rover range still fit trn_point_t
 * (int16_t): either the call is refused or every offset is exact. Passes for
 * the default TRN_MAX_DIM; checks any override of it too. */
static void test_points_offsets_exact_at_range_limit(void **state)
{
    static float d[2 * 2] = {0.0f, 0.0f, 0.0f, 0.0f};
    const trn_terrain_cfg_t cfg = make_cfg(1.0f, 1.0f, 1.0f, 1);
    static const int32_t rovers[][2] = {{-TRN_MAX_DIM, -TRN_MAX_DIM},
                                        {1 + TRN_MAX_DIM, 1 + TRN_MAX_DIM},
                                        {-TRN_MAX_DIM, 1 + TRN_MAX_DIM}};
    trn_grid_f32_t hp;
    trn_point_t pts[4];
    size_t np = 0, i, k;
    (void)state;
    assert_int_equal(trn_grid_f32_init(&hp, d, 4u, 2, 2), TRN_OK);
    for (i = 0; i < 3; ++i) {
        const int32_t rx = rovers[i][0], ry = rovers[i][1];
        const trn_status_t st = trn_occupancy_points(&hp, &cfg, rx, ry, pts, 4u, &np);
        if (st == TRN_E_ARG) {
            continue;
        }
        assert_int_equal(st, TRN_OK);
        assert_int_equal(np, 4u);
        for (k = 0; k < 4; ++k) {
            const int32_t x = (int32_t)(k % 2u), y = (int32_t)(k / 2u);
            assert_true((int32_t)pts[k].x == x - rx);
            assert_true((int32_t)pts[k].y == y - ry);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cfg_check),
        cmocka_unit_test(test_highpass_workspace_bytes),
        cmocka_unit_test(test_highpass_errors),
        cmocka_unit_test(test_highpass_workspace_exact),
        cmocka_unit_test(test_highpass_random_vs_bruteforce),
        cmocka_unit_test(test_highpass_large_absolute),
        cmocka_unit_test(test_highpass_wide_relief),
        cmocka_unit_test(test_highpass_plane),
        cmocka_unit_test(test_highpass_missing),
        cmocka_unit_test(test_highpass_box_wider_than_grid),
        cmocka_unit_test(test_occupancy_analytic),
        cmocka_unit_test(test_occupancy_bins),
        cmocka_unit_test(test_occupancy_random_vs_naive),
        cmocka_unit_test(test_occupancy_errors),
        cmocka_unit_test(test_points_vs_occupancy),
        cmocka_unit_test(test_points_errors),
        cmocka_unit_test(test_points_rover_far_above),
        cmocka_unit_test(test_points_offsets_exact_at_range_limit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
