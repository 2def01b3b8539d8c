/* SPDX-License-Identifier: Apache-2.0 */
/* test_relief.c - the height matcher's relief test (trn_refine_relief_z_,
 * src/refine_int.h; docs/method.md 9.4, "The relief test").
 *
 * Oracles: the weighted least squares of local = a + b x + c y + g M
 * written out here (normal equations solved by Gauss-Jordan with partial
 * pivoting, the inverse's last diagonal for g's variance; weights
 * 1 / (s^2 + m^2), the clip at 3 sds) gives z within 1e-7 (its normal
 * equations uncentred, the core's about the first cell), at heading 0 and
 * turned; with g = 1 and the noise model's noise the statistic is centred
 * with at most a standard normal's spread (the model variance m^2 fitted
 * by moments widens sd(g) where it comes out above 0), over 400 local
 * maps; a local map with a weaker copy of the relief (g = 0.7) is below
 * -TRN_RELIEF_Z every time; with no relief or fewer than 8 cells there is
 * nothing to test (+inf).
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "refine_int.h"
#include "rng.h"
#include "trn/localize.h"
#include "trn/refine.h"

#define GW 64
#define LW 21 /* local side; rover at its centre cell */
#define LR (LW / 2)

static float g_data[GW * GW];
static float l_data[LW * LW];

/* A height per cell (0.3 m uniform) on a slope, or flat. */
static void make_global(trn_grid_f32_t *g, int flat, trn_rng_t *r)
{
    int x, y;
    for (y = 0; y < GW; ++y) {
        for (x = 0; x < GW; ++x) {
            g_data[y * GW + x] = (float)(flat ? 5.0 : 10.0 + 0.02 * x + 0.3 * trn_rng_unit(r));
        }
    }
    assert_int_equal(trn_grid_f32_init(g, g_data, GW * GW, GW, GW), TRN_OK);
}

static double lin(double x, double y)
{
    int x0 = (int)floor(x), y0 = (int)floor(y);
    double fx = x - x0, fy = y - y0;
    return (1.0 - fy) * ((1.0 - fx) * g_data[y0 * GW + x0] + fx * g_data[y0 * GW + x0 + 1]) +
           fy * ((1.0 - fx) * g_data[(y0 + 1) * GW + x0] + fx * g_data[(y0 + 1) * GW + x0 + 1]);
}

static trn_refine_cfg_t rcfg(void)
{
    trn_refine_cfg_t c;
    c.cell_m = 1.0f;
    c.noise_m = 0.01f;
    c.noise_k_per_m = 0.0004f;
    c.inlier_prob = 0.95f;
    c.fit_noise = 0;
    c.centroid_x = NULL; /* the cells' centres */
    c.centroid_y = NULL;
    c.point_count = NULL; /* one measurement a cell */
    return c;
}

/* The cell's offset turned by the heading, as the core turns it. */
static void turned(int i, int j, double px, double py, double cs, double sn, double *gx, double *gy)
{
    const double ox = (double)(i - LR), oy = (double)(j - LR);
    *gx = px + ox * cs + oy * sn;
    *gy = py - ox * sn + oy * cs;
}

/* local = a + b x + c y + g M(pose) + the noise model's noise (times nf);
 * the plane (b, c) only with plane 1. */
static void make_local(trn_grid_f32_t *l, double px, double py, double heading, double g, double nf,
                       int plane, trn_rng_t *r)
{
    const trn_refine_cfg_t c = rcfg();
    double cs, sn;
    int i, j;
    trn_heading_trig_(heading, &cs, &sn);
    for (j = 0; j < LW; ++j) {
        for (i = 0; i < LW; ++i) {
            double gx, gy;
            const double s = sqrt(trn_refine_noise_var_(&c, i, j, LR, LR));
            turned(i, j, px, py, cs, sn, &gx, &gy);
            l_data[j * LW + i] = (float)(2.0 + plane * (0.003 * (i - LR) - 0.002 * (j - LR)) +
                                         g * lin(gx, gy) + nf * s * trn_rng_gauss(r));
        }
    }
    assert_int_equal(trn_grid_f32_init(l, l_data, LW * LW, LW, LW), TRN_OK);
}

/* The answer at (px, py), the bilinear interpolant: dz and the model error
 * by moments, as the model's fit takes them (the mean of local less map,
 * the mean square about it beyond the noise's). */
static trn_refine_t answer(double px, double py, double heading)
{
    const trn_refine_cfg_t c = rcfg();
    trn_refine_t at;
    double cs, sn, s1 = 0.0, s2 = 0.0, sv = 0.0;
    int i, j, n = 0;
    memset(&at, 0, sizeof at);
    trn_heading_trig_(heading, &cs, &sn);
    for (j = 0; j < LW; ++j) {
        for (i = 0; i < LW; ++i) {
            double gx, gy, d;
            if (!isfinite(l_data[j * LW + i])) {
                continue;
            }
            turned(i, j, px, py, cs, sn, &gx, &gy);
            d = (double)l_data[j * LW + i] - lin(gx, gy);
            s1 += d;
            s2 += d * d;
            sv += trn_refine_noise_var_(&c, i, j, LR, LR);
            n += 1;
        }
    }
    at.x = px;
    at.y = py;
    at.dz_m = n > 0 ? s1 / n : 0.0;
    at.model_m = n > 0 ? sqrt(fmax(0.0, s2 / n - at.dz_m * at.dz_m - sv / n)) : 0.0;
    at.interp_mix = 0.0;
    return at;
}

/* The oracle: the weighted least squares written out, over the cells
 * within 3 sds (noise and model variance) of the answer's model. */
static double oracle_z(const trn_refine_t *at, double heading)
{
    const trn_refine_cfg_t c = rcfg();
    double a[4][8], cs, sn;
    int i, j, p, q;
    trn_heading_trig_(heading, &cs, &sn);
    for (p = 0; p < 4; ++p) {
        for (q = 0; q < 8; ++q) {
            a[p][q] = (q == p + 4) ? 1.0 : 0.0;
        }
    }
    {
        double v[4] = {0.0, 0.0, 0.0, 0.0};
        double g;
        for (j = 0; j < LW; ++j) {
            for (i = 0; i < LW; ++i) {
                double gx, gy, x[4], r;
                const double var = trn_refine_noise_var_(&c, i, j, LR, LR) +
                                   at->model_m * at->model_m;
                const double w = 1.0 / var;
                turned(i, j, at->x, at->y, cs, sn, &gx, &gy);
                r = (double)l_data[j * LW + i] - at->dz_m - lin(gx, gy);
                if (!(r * r <= 9.0 * var)) {
                    continue;
                }
                x[0] = 1.0;
                x[1] = (double)(i - LR);
                x[2] = (double)(j - LR);
                x[3] = lin(gx, gy);
                for (p = 0; p < 4; ++p) {
                    v[p] += w * x[p] * (double)l_data[j * LW + i];
                    for (q = 0; q < 4; ++q) {
                        a[p][q] += w * x[p] * x[q];
                    }
                }
            }
        }
        /* Gauss-Jordan on [A | I] with partial pivoting: A^-1 */
        for (p = 0; p < 4; ++p) {
            int best = p;
            for (q = p + 1; q < 4; ++q) {
                if (fabs(a[q][p]) > fabs(a[best][p])) {
                    best = q;
                }
            }
            for (q = 0; q < 8; ++q) {
                const double t = a[p][q];
                a[p][q] = a[best][q];
                a[best][q] = t;
            }
            for (q = 7; q >= 0; --q) {
                a[p][q] /= a[p][p];
            }
            for (i = 0; i < 4; ++i) {
                if (i != p) {
                    const double f = a[i][p];
                    for (q = 0; q < 8; ++q) {
                        a[i][q] -= f * a[p][q];
                    }
                }
            }
        }
        g = 0.0;
        for (q = 0; q < 4; ++q) {
            g += a[3][4 + q] * v[q];
        }
        return (g - 1.0) / sqrt(a[3][7]);
    }
}

static void test_relief_oracle(void **state)
{
    trn_rng_t r;
    trn_grid_f32_t g, l;
    const trn_refine_cfg_t c = rcfg();
    int k;
    (void)state;
    trn_rng_seed(&r, 3u);
    make_global(&g, 0, &r);
    for (k = 0; k < 6; ++k) {
        const double px = 30.0 + 4.0 * trn_rng_unit(&r), py = 28.0 + 4.0 * trn_rng_unit(&r);
        const double h = (k % 2 == 0) ? 0.0 : 0.05 * (trn_rng_unit(&r) - 0.5);
        const double gain = 0.6 + 0.2 * k;
        trn_refine_t at;
        double z, zo;
        make_local(&l, px, py, h, gain, 1.0, 1, &r);
        at = answer(px, py, h);
        z = trn_refine_relief_z_(&g, &l, LR, LR, &at, h, &c);
        zo = oracle_z(&at, h);
        assert_true(isfinite(z));
        assert_true(fabs(z - zo) <= 1e-7 * fmax(1.0, fabs(zo)));
        assert_true(gain < 0.9 ? z < -TRN_RELIEF_Z : 1);
        assert_true(gain > 1.1 ? z > TRN_RELIEF_Z : 1);
    }
}

/* g = 1 under the noise model: z centred, its spread at most a standard
 * normal's; g = 0.7 always below -TRN_RELIEF_Z. */
static void test_relief_calibrated(void **state)
{
    trn_rng_t r;
    trn_grid_f32_t g, l;
    const trn_refine_cfg_t c = rcfg();
    double s1 = 0.0, s2 = 0.0;
    int k, below = 0, n = 400;
    (void)state;
    trn_rng_seed(&r, 17u);
    make_global(&g, 0, &r);
    for (k = 0; k < n; ++k) {
        const double px = 25.0 + 12.0 * trn_rng_unit(&r), py = 25.0 + 12.0 * trn_rng_unit(&r);
        trn_refine_t at;
        double z;
        make_local(&l, px, py, 0.0, 1.0, 1.0, 0, &r);
        at = answer(px, py, 0.0);
        z = trn_refine_relief_z_(&g, &l, LR, LR, &at, 0.0, &c);
        s1 += z;
        s2 += z * z;
        below += z < -TRN_RELIEF_Z;
        make_local(&l, px, py, 0.0, 0.7, 1.0, 1, &r);
        at = answer(px, py, 0.0); /* the misfit in its model error */
        assert_true(trn_refine_relief_z_(&g, &l, LR, LR, &at, 0.0, &c) < -TRN_RELIEF_Z);
    }
    s1 /= n;
    s2 = sqrt(s2 / n - s1 * s1);
    printf("relief z under the model, %d local maps: mean %.3f, sd %.3f, %d below -%.0f\n", n, s1,
           s2, below, TRN_RELIEF_Z);
    assert_true(fabs(s1) < 0.15 && s2 > 0.7 && s2 < 1.1 && below <= 3);
}

/* Nothing to test: a flat map (no relief) and fewer than 8 seen cells. */
static void test_relief_none(void **state)
{
    trn_rng_t r;
    trn_grid_f32_t g, l;
    const trn_refine_cfg_t c = rcfg();
    trn_refine_t at;
    int i;
    (void)state;
    trn_rng_seed(&r, 5u);
    make_global(&g, 1, &r);
    make_local(&l, 30.2, 30.7, 0.0, 1.0, 1.0, 1, &r);
    at = answer(30.2, 30.7, 0.0);
    assert_true(isinf(trn_refine_relief_z_(&g, &l, LR, LR, &at, 0.0, &c)));
    make_global(&g, 0, &r);
    make_local(&l, 30.2, 30.7, 0.0, 1.0, 1.0, 1, &r);
    at = answer(30.2, 30.7, 0.0);
    for (i = 7; i < LW * LW; ++i) {
        l_data[i] = (float)NAN;
    }
    assert_true(isinf(trn_refine_relief_z_(&g, &l, LR, LR, &at, 0.0, &c)));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_relief_oracle),
        cmocka_unit_test(test_relief_calibrated),
        cmocka_unit_test(test_relief_none),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
