/* SPDX-License-Identifier: Apache-2.0 */
/* test_height_score.c - the height matcher's pose score (src/height_score.c)
 * against the model written out plainly here: per cell, the map height under
 * the turned offset read with bounds checks, the moments' fit with a square
 * root in the clip and its variances solved in full (the noise scale with
 * them or not), one log per cell. Rough maps with holes, poses half off
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
static unsigned char g_ws[LW * LW * 96];

/* The variances, plainly: least squares of e^2 = k2 v + m2 over the cells,
 * weights q; k2 = 1 unless fitted; m2 < 0 or the two not separable: k2
 * alone (m2 = 0); k2 held to [TRN_NOISE_SCALE2_MIN, TRN_NOISE_SCALE2_MAX]
 * and m2 refitted at it, never below 0. */
static void oracle_var(const double *e2, const double *v, const double *q, const int *use,
                       int32_t n, int fit, double *k2, double *m2)
{
    double a[2][2] = {{0.0, 0.0}, {0.0, 0.0}}, b[2] = {0.0, 0.0}, det, k = 1.0, m;
    int32_t i;
    for (i = 0; i < n; ++i) {
        if (use[i]) {
            a[0][0] += q[i] * v[i] * v[i];
            a[0][1] += q[i] * v[i];
            a[1][1] += q[i];
            b[0] += q[i] * v[i] * e2[i];
            b[1] += q[i] * e2[i];
        }
    }
    if (fit) {
        det = a[0][0] * a[1][1] - a[0][1] * a[0][1];
        k = b[0] / a[0][0];
        if (det > 1e-9 * a[0][0] * a[1][1] && (a[0][0] * b[1] - a[0][1] * b[0]) / det >= 0.0) {
            k = (a[1][1] * b[0] - a[0][1] * b[1]) / det;
        }
        k = fmin(fmax(k, TRN_NOISE_SCALE2_MIN), TRN_NOISE_SCALE2_MAX);
    }
    m = (b[1] - k * a[0][1]) / a[1][1];
    *k2 = k;
    *m2 = fmax(m, 0.0);
}

/* The model, plainly: ln L of pose (px, py) with the local offsets turned by
 * (c, s); its dz, model sd and noise scale. */
static double oracle_ll(const trn_grid_f32_t *g, const trn_grid_f32_t *l, double c, double s,
                        int32_t px, int32_t py, const trn_refine_cfg_t *cfg, double a,
                        double *dz_out, double *m_out, double *k2_out)
{
    static double h[LW * LW], v[LW * LW], gv[LW * LW], e2[LW * LW], q[LW * LW];
    static int use[LW * LW];
    int32_t x, y, n = 0, i, pass, n_all = 0, n_prev;
    double s1 = 0.0, s2 = 0.0, sp, k, dz = 0.0, m2 = 0.0, k2 = 1.0, ll = 0.0;
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
        double sw = 0.0, swr = 0.0;
        int32_t used = 0;
        for (i = 0; i < n; ++i) {
            const double r = h[i] - gv[i], vm = k2 * v[i] + m2;
            use[i] = isfinite(r) && !(pass >= 2 && fabs(r - dz) > TRN_REFINE_CLIP * sqrt(vm));
            q[i] = 1.0 / (vm * vm);
            if (!use[i]) {
                continue;
            }
            sw += 1.0 / vm;
            swr += r / vm;
            ++used;
        }
        if (used == 0) {
            break;
        }
        dz = swr / sw;
        for (i = 0; i < n; ++i) {
            e2[i] = use[i] ? (h[i] - gv[i] - dz) * (h[i] - gv[i] - dz) : 0.0;
        }
        oracle_var(e2, v, q, use, n, cfg->fit_noise, &k2, &m2);
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
        const double u = h[i] - gv[i] - dz, vm = k2 * v[i] + m2;
        ll += isfinite(u)
                  ? log(a * exp(-0.5 * u * u / vm) / sqrt(6.283185307179586 * vm) + (1.0 - a) * k)
                  : log((1.0 - a) * k);
    }
    *dz_out = dz;
    *m_out = sqrt(m2);
    *k2_out = k2;
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
                double dz, m, dz0, m0, k0;
                const double got = trn_hs_ll(&s, px, py, &dz, &m);
                const double want = oracle_ll(g, l, t == 0 ? 1.0 : cc, t == 0 ? 0.0 : ss, px, py, c,
                                              a, &dz0, &m0, &k0);
                const double rel = fabs(got - want) / fabs(want);
                *worst = fmax(*worst, rel);
                assert_true(rel <= 1e-12);
                assert_true(fabs(dz - dz0) <= 1e-9 * (1.0 + fabs(dz0)));
                assert_true(fabs(m - m0) <= 1e-6 * (1e-9 + m0) + 1e-9);
                assert_true(fabs(s.k2 - k0) <= 1e-6 * k0);
            }
        }
    }
}

static void test_against_plain_model(void **state)
{
    trn_rng_t r;
    trn_grid_f32_t g, l;
    trn_refine_cfg_t c = {1.0f, 0.01f, 0.0004f, 0.95f, 0, NULL, NULL, NULL};
    double worst = 0.0;
    int k;
    (void)state;
    trn_rng_seed(&r, 5);
    for (k = 0; k < 8; ++k) { /* the noise scale fitted in half; local noise 0.003-0.03 m */
        c.fit_noise = k % 2;
        make(&r, 0.5, k < 2 ? 0.0 : 0.08, 10 + 4 * k, 30 - 3 * k, 0.003 * pow(10.0, k / 4), &g, &l);
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
    trn_refine_cfg_t tiny = {1.0f, 1e-6f, 0.0f, 0.95f, 0, NULL, NULL, NULL},
                     wide = {1.0f, 0.01f, 0.0f, 0.95f, 0, NULL, NULL, NULL};
    double worst = 0.0;
    int f;
    (void)state;
    trn_rng_seed(&r, 9);
    for (f = 0; f < 2; ++f) {
        tiny.fit_noise = wide.fit_noise = f;
        make(&r, 0.5, 0.02, 20, 20, 1e-6, &g, &l);
        check_all(&g, &l, &tiny, 0.99999994, &worst);
        make(&r, 1e6, 0.02, 20, 20, 0.01, &g, &l);
        check_all(&g, &l, &wide, 0.5, &worst);
        check_all(&g, &l, &wide, 1e-6, &worst);
    }
    printf("pose score at the extremes: worst ln L difference %.1e (relative)\n", worst);
}

/* A pose with no cell on the map scores every cell ln((1 - a) k); the sizes. */
static void test_off_map_and_sizes(void **state)
{
    trn_rng_t r;
    trn_grid_f32_t g, l;
    trn_refine_cfg_t c = {1.0f, 0.01f, 0.0004f, 0.95f, 0, NULL, NULL, NULL};
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

/* The noise scale at the true pose: a local map whose noise is f times the
 * model's (cut from a map with no noise of its own, so the residuals are
 * the local noise) fits k2 near f^2 (169 cells: a sampling sd of about
 * 0.11 f^2), f = 0.3, 1, 3; without fit_noise k2 is 1 and the excess goes
 * into the model variance; a local map with no noise fits the least
 * scale. */
static void test_noise_scale_fitted(void **state)
{
    static const double k_f[3] = {0.3, 1.0, 3.0};
    trn_rng_t r;
    trn_grid_f32_t g, l;
    trn_refine_cfg_t c = {1.0f, 0.01f, 0.0f, 0.95f, 1, NULL, NULL, NULL};
    trn_hs_t s;
    double dz, m;
    int32_t i, x, y;
    (void)state;
    trn_rng_seed(&r, 17);
    make(&r, 0.5, 0.0, 24, 24, 0.0, &g, &l);
    for (i = 0; i < GW * GW; ++i) { /* the map without its holes or noise */
        g_map[i] = (float)(0.5 * sin(0.37 * (double)(i % GW)) * cos(0.23 * (double)(i / GW)));
    }
    for (i = 0; i < 4; ++i) {
        const double f = i < 3 ? k_f[i] : 0.0;
        for (y = 0; y < LW; ++y) {
            for (x = 0; x < LW; ++x) {
                g_loc[y * LW + x] = (float)((double)g_map[(24 + y - LR) * GW + 24 + x - LR] +
                                            f * 0.01 * trn_rng_gauss(&r));
            }
        }
        c.fit_noise = 1;
        assert_true(trn_hs_init(&s, g_ws, &g, &l, LR, LR, &c, 0.95) == (size_t)(LW * LW));
        (void)trn_hs_ll(&s, 24, 24, &dz, &m);
        if (i < 3) {
            assert_true(fabs(s.k2 / (f * f) - 1.0) < 0.4);
        } else {
            assert_true(s.k2 == TRN_NOISE_SCALE2_MIN && m == 0.0);
        }
        c.fit_noise = 0;
        (void)trn_hs_init(&s, g_ws, &g, &l, LR, LR, &c, 0.95);
        (void)trn_hs_ll(&s, 24, 24, &dz, &m);
        assert_true(s.k2 == 1.0);
        if (i == 2) { /* the excess noise as model variance: about (9 - 1) 1e-4 */
            assert_true(m * m > 4e-4 && m * m < 1.6e-3);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_against_plain_model),
        cmocka_unit_test(test_extremes),
        cmocka_unit_test(test_off_map_and_sizes),
        cmocka_unit_test(test_noise_scale_fitted),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
