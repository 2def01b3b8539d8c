/* SPDX-License-Identifier: Apache-2.0 */
/* test_height_score.c - the height matcher's pose score (src/height_score.c)
 * against the model written out plainly here: per cell, the map height under
 * the turned offset read with bounds checks, the moments' fit with a square
 * root in the clip, one log per cell. Rough maps with holes, poses half off
 * the map and wholly off it, turned headings, and the extremes of the
 * arguments (a noise sd of 1e-6 m, an inlier probability next to 1, heights
 * spread over 1e6 m) that stress the score's log of products. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>

#include "height_score.h"
#include "refine_int.h"
#include "rng.h"
#include "trn/refine.h"

#define GW 48
#define LW 13
#define LR 6

static float g_map[GW * GW];
static float g_loc[LW * LW];
static unsigned char g_ws[LW * LW * 64];

/* The model, plainly: ln L of pose (px, py) with the local offsets turned by
 * (c, s); its dz and model sd. */
static double oracle_ll(const trn_grid_f32_t *g, const trn_grid_f32_t *l, double c, double s,
                        int32_t px, int32_t py, const trn_refine_cfg_t *cfg, double a,
                        double *dz_out, double *m_out)
{
    static double h[LW * LW], v[LW * LW], gv[LW * LW];
    int32_t x, y, n = 0, i, pass, n_all = 0, n_prev;
    double s1 = 0.0, s2 = 0.0, sp, k, dz = 0.0, m2 = 0.0, ll = 0.0;
    for (y = 0; y < l->height; ++y) {
        for (x = 0; x < l->width; ++x) {
            const double hh = (double)TRN_GRID_AT(l, x, y);
            const double ox = (double)(x - LR), oy = (double)(y - LR);
            int64_t gx, gy;
            if (!isfinite(hh)) {
                continue;
            }
            gx = (int64_t)px + (int64_t)floor(ox * c + oy * s + 0.5);
            gy = (int64_t)py + (int64_t)floor(-ox * s + oy * c + 0.5);
            h[n] = hh;
            v[n] = trn_refine_noise_var_(cfg, x, y, LR, LR);
            gv[n] = gx < 0 || gy < 0 || gx >= g->width || gy >= g->height
                        ? (double)NAN
                        : (double)TRN_GRID_AT(g, (int32_t)gx, (int32_t)gy);
            ++n;
        }
    }
    for (i = 0; i < n; ++i) {
        s1 += h[i] - h[0];
        s2 += (h[i] - h[0]) * (h[i] - h[0]);
    }
    sp = sqrt(fmax(s2 / n - (s1 / n) * (s1 / n), 0.0));
    k = 1.0 / (10.0 * fmax(sp, (double)cfg->noise_m));
    /* pass 0: all at m2 = 0; pass 1: all at that m2; then the clip while a
     * pass drops more than 1 % (at most 1 + TRN_CLIP_AGAIN clipped passes) */
    n_prev = 0;
    for (pass = 0; pass < 3 + TRN_CLIP_AGAIN; ++pass) {
        double sw = 0.0, swr = 0.0, sq = 0.0, sqr = 0.0, sqrr = 0.0, sqv = 0.0, d;
        int32_t used = 0;
        for (i = 0; i < n; ++i) {
            const double r = h[i] - gv[i], vm = v[i] + m2;
            if (!isfinite(r) || (pass >= 2 && fabs(r - dz) > TRN_REFINE_CLIP * sqrt(vm))) {
                continue;
            }
            sw += 1.0 / vm;
            swr += r / vm;
            sq += 1.0 / (vm * vm);
            sqr += r / (vm * vm);
            sqrr += r * r / (vm * vm);
            sqv += v[i] / (vm * vm);
            ++used;
        }
        if (used == 0) {
            break;
        }
        d = swr / sw;
        dz = d;
        m2 = fmax((sqrr - 2.0 * d * sqr + d * d * sq - sqv) / sq, 0.0);
        if (pass == 0) {
            n_all = n_prev = used;
        } else if (pass >= 2) {
            if (!(100 * (n_prev - used) > n_all)) {
                break;
            }
            n_prev = used;
        }
    }
    for (i = 0; i < n; ++i) {
        const double u = h[i] - gv[i] - dz, vm = v[i] + m2;
        ll += isfinite(u)
                  ? log(a * exp(-0.5 * u * u / vm) / sqrt(6.283185307179586 * vm) + (1.0 - a) * k)
                  : log((1.0 - a) * k);
    }
    *dz_out = dz;
    *m_out = sqrt(m2);
    return ll;
}

/* A rough map (heights scale m, holes where hole_p) and the local map cut
 * from it around (cx, cy) at heading 0 with noise sd nz and its own holes. */
static void make(trn_rng_t *r, double scale, double hole_p, int32_t cx, int32_t cy, double nz,
                 trn_grid_f32_t *g, trn_grid_f32_t *l)
{
    int32_t i, x, y;
    for (i = 0; i < GW * GW; ++i) {
        const double bump = sin(0.37 * (double)(i % GW)) * cos(0.23 * (double)(i / GW));
        g_map[i] = (float)(scale * (bump + 0.3 * trn_rng_gauss(r)));
        if (trn_rng_unit(r) < hole_p) {
            g_map[i] = NAN;
        }
    }
    for (y = 0; y < LW; ++y) {
        for (x = 0; x < LW; ++x) {
            const int32_t gx = cx + x - LR, gy = cy + y - LR;
            const float base = gx >= 0 && gy >= 0 && gx < GW && gy < GW ? g_map[gy * GW + gx]
                                                                        : (float)scale;
            g_loc[y * LW + x] = isfinite(base) ? (float)(base + nz * trn_rng_gauss(r) + 0.2)
                                               : (float)(scale * trn_rng_gauss(r));
            if (trn_rng_unit(r) < 0.05) {
                g_loc[y * LW + x] = NAN;
            }
        }
    }
    assert_int_equal(trn_grid_f32_init(g, g_map, GW * GW, GW, GW), TRN_OK);
    assert_int_equal(trn_grid_f32_init(l, g_loc, LW * LW, LW, LW), TRN_OK);
}

/* Every pose of the map and a margin beyond it, at 3 headings: the score and
 * its fit equal the plain model's within rounding. */
static void check_all(const trn_grid_f32_t *g, const trn_grid_f32_t *l, const trn_refine_cfg_t *c,
                      double a, double *worst)
{
    static const double k_ang[3] = {0.0, 0.05, -0.7};
    trn_hs_t s;
    int32_t px, py, t;
    assert_true(trn_hs_bytes(LW, LW) <= sizeof g_ws);
    assert_true(trn_hs_init(&s, g_ws, g, l, LR, LR, c, a) >= 8u);
    for (t = 0; t < 3; ++t) {
        const double cc = cos(k_ang[t]), ss = sin(k_ang[t]);
        if (t == 0) {
            assert_true(s.tx[0] == s.ox[0] && s.ty[0] == s.oy[0]); /* init turns to 0 */
        } else {
            trn_hs_turn(&s, cc, ss);
        }
        for (py = -LW; py < GW + LW; py += 3) {
            for (px = -LW; px < GW + LW; px += 2) {
                double dz, m, dz0, m0;
                const double got = trn_hs_ll(&s, px, py, &dz, &m);
                const double want = oracle_ll(g, l, t == 0 ? 1.0 : cc, t == 0 ? 0.0 : ss, px, py, c,
                                              a, &dz0, &m0);
                const double rel = fabs(got - want) / fabs(want);
                *worst = fmax(*worst, rel);
                assert_true(rel <= 1e-12);
                assert_true(fabs(dz - dz0) <= 1e-9 * (1.0 + fabs(dz0)));
                assert_true(fabs(m - m0) <= 1e-6 * (1e-9 + m0) + 1e-9);
            }
        }
    }
}

static void test_against_plain_model(void **state)
{
    trn_rng_t r;
    trn_grid_f32_t g, l;
    trn_refine_cfg_t c = {1.0f, 0.01f, 0.0004f, 0.95f};
    double worst = 0.0;
    int k;
    (void)state;
    trn_rng_seed(&r, 5);
    for (k = 0; k < 4; ++k) {
        make(&r, 0.5, k == 0 ? 0.0 : 0.08, 10 + 9 * k, 30 - 5 * k, 0.01, &g, &l);
        check_all(&g, &l, &c, 0.95, &worst);
    }
    printf("pose score against the plain model: worst ln L difference %.1e (relative)\n", worst);
}

/* The extremes the log of products must hold: the tiniest noise with an
 * inlier probability next to 1 (the largest terms, the smallest outlier
 * density), and heights spread over 1e6 m (the smallest density). */
static void test_extremes(void **state)
{
    trn_rng_t r;
    trn_grid_f32_t g, l;
    trn_refine_cfg_t tiny = {1.0f, 1e-6f, 0.0f, 0.95f}, wide = {1.0f, 0.01f, 0.0f, 0.95f};
    double worst = 0.0;
    (void)state;
    trn_rng_seed(&r, 9);
    make(&r, 0.5, 0.02, 20, 20, 1e-6, &g, &l);
    check_all(&g, &l, &tiny, 0.99999994, &worst);
    make(&r, 1e6, 0.02, 20, 20, 0.01, &g, &l);
    check_all(&g, &l, &wide, 0.5, &worst);
    check_all(&g, &l, &wide, 1e-6, &worst);
    printf("pose score at the extremes: worst ln L difference %.1e (relative)\n", worst);
}

/* A pose with no cell on the map scores every cell ln((1 - a) k); the sizes. */
static void test_off_map_and_sizes(void **state)
{
    trn_rng_t r;
    trn_grid_f32_t g, l;
    trn_refine_cfg_t c = {1.0f, 0.01f, 0.0004f, 0.95f};
    trn_hs_t s;
    double dz, m, ll;
    size_t n;
    (void)state;
    trn_rng_seed(&r, 3);
    make(&r, 0.5, 0.0, 24, 24, 0.01, &g, &l);
    n = trn_hs_init(&s, g_ws, &g, &l, LR, LR, &c, 0.95);
    ll = trn_hs_ll(&s, -100, 5, &dz, &m);
    assert_true(fabs(ll - (double)n * s.lout) <= 1e-12 * fabs(ll));
    assert_true(dz == 0.0 && m == 0.0);
    assert_true(s.lout == log((1.0 - 0.95) * s.k));
    assert_true(trn_hs_bytes(0, 5) == 0u && trn_hs_bytes(5, 0) == 0u);
    assert_true(trn_hs_bytes(TRN_MAX_DIM + 1, 5) == 0u);
    assert_true(trn_hs_bytes(LW, LW) >= (size_t)(LW * LW) * 4u * sizeof(double));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_against_plain_model),
        cmocka_unit_test(test_extremes),
        cmocka_unit_test(test_off_map_and_sizes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
