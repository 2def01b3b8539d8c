/* SPDX-License-Identifier: Apache-2.0 */
/* select_heights.c - the height matcher's prediction's tables (see
 * select_heights.h). */
#include "select_heights.h"
#include "ws.h"

#include <math.h>
#include <string.h>

#define SELH_QLIM 4.0e18 /* largest magnitude a region's int64 sum may reach */
#define SELH_NI 7        /* int64 tables: n, gx, gy, gxx, gxy, gyy, e2 */
#define SELH_ND 4        /* double tables: gt, gt gx, gt gy, gt^2 */
#define SELH_KMAX 40     /* finest quantum: 2^-40 (m per cell, m^2) */

/* The tables' header: the quanta's inverses (1 / (m per cell), 1 / m^2). */
typedef struct {
    double gq, eq;
} selh_head_t;

#define SELH_HEAD TRN_ALIGN_UP(sizeof(selh_head_t))

size_t trn_selh_bytes_(int32_t w, int32_t h, int heading)
{
    trn_ws_t c;
    const size_t cells = ((size_t)w + 1u) * ((size_t)h + 1u);
    trn_ws_begin(&c, NULL);
    (void)trn_ws_take(&c, sizeof(selh_head_t));
    (void)trn_ws_take(&c, (size_t)SELH_NI * cells * sizeof(int64_t));
    if (heading != 0) {
        (void)trn_ws_take(&c, (size_t)SELH_ND * cells * sizeof(double));
    }
    return c.total;
}

/* The terms of map cell (x, y): 1 with its four neighbours' heights known
 * (gradient by central differences, e against their mean), else 0. */
static int cell_terms(const trn_grid_f32_t *hg, int32_t x, int32_t y, double *gx, double *gy,
                      double *e)
{
    double c, l, r, d, u;
    if (x < 1 || y < 1 || x > hg->width - 2 || y > hg->height - 2) {
        return 0;
    }
    c = (double)TRN_GRID_AT(hg, x, y);
    l = (double)TRN_GRID_AT(hg, x - 1, y);
    r = (double)TRN_GRID_AT(hg, x + 1, y);
    d = (double)TRN_GRID_AT(hg, x, y - 1);
    u = (double)TRN_GRID_AT(hg, x, y + 1);
    if (!(isfinite(c) && isfinite(l) && isfinite(r) && isfinite(d) && isfinite(u))) {
        return 0;
    }
    *gx = 0.5 * (r - l);
    *gy = 0.5 * (u - d);
    *e = c - 0.25 * (l + r + d + u);
    return 1;
}

/* v in quanta of 1 / q, to the nearest (|v q| within SELH_QLIM by the
 * quantum's choice). */
static int64_t quant(double v, double q) { return (int64_t)floor(v * q + 0.5); }

/* 2^k, exactly (k in 0..SELH_KMAX). */
static double pow2(int32_t k)
{
    double p = 1.0;
    int32_t i;
    for (i = 0; i < k; ++i) {
        p *= 2.0;
    }
    return p;
}

/* The quantized terms of cell (x, y) into q[SELH_NI] (all 0 without terms). */
static void cell_q(const trn_grid_f32_t *hg, int32_t x, int32_t y, const selh_head_t *hd,
                   int64_t q[SELH_NI])
{
    double gx, gy, e;
    if (!cell_terms(hg, x, y, &gx, &gy, &e)) {
        memset(q, 0, (size_t)SELH_NI * sizeof q[0]);
        return;
    }
    q[0] = 1;
    q[1] = quant(gx, hd->gq);
    q[2] = quant(gy, hd->gq);
    q[3] = q[1] * q[1];
    q[4] = q[1] * q[2];
    q[5] = q[2] * q[2];
    q[6] = quant(e * e, hd->eq);
}

/* The finest power-of-two quantum 2^-k (k <= SELH_KMAX) with which the
 * region's sums of n terms of magnitude up to vmax stay within lim; -1 when
 * even a quantum of 1 does not. */
static int32_t quantum_exp(double vmax, double lim)
{
    int32_t k = SELH_KMAX;
    while (k >= 0 && vmax * pow2(k) > lim) {
        --k;
    }
    return k;
}

/* The quanta (hd) with which no sum over the region can leave SELH_QLIM: the
 * finest with the largest gradient squared, and e^2, times the region's
 * cells within it (exact sums as fine as the data allow); TRN_E_SIZE where
 * none is. */
static trn_status_t choose_quanta(const trn_grid_f32_t *hg, const trn_window_t *roi,
                                  selh_head_t *hd)
{
    double gmax = 0.0, emax = 0.0, cells;
    int32_t x, y, kg, ke;
    for (y = roi->y0; y <= roi->y1; ++y) {
        for (x = roi->x0; x <= roi->x1; ++x) {
            double gx, gy, e;
            if (cell_terms(hg, x, y, &gx, &gy, &e)) {
                gmax = fmax(gmax, fmax(fabs(gx), fabs(gy)));
                emax = fmax(emax, e * e);
            }
        }
    }
    cells = (double)(roi->x1 - roi->x0 + 1) * (double)(roi->y1 - roi->y0 + 1);
    /* |g| q + 1/2 after rounding: (gmax + 1) q bounds it for q >= 1 */
    kg = quantum_exp(gmax + 1.0, sqrt(SELH_QLIM / cells));
    ke = quantum_exp(emax + 1.0, SELH_QLIM / cells);
    if (kg < 0 || ke < 0) {
        return TRN_E_SIZE;
    }
    hd->gq = pow2(kg);
    hd->eq = pow2(ke);
    return TRN_OK;
}

trn_status_t trn_selh_build_(const trn_grid_f32_t *heights, const trn_window_t *roi, int heading,
                             double rxf, double ryf, void *base)
{
    const int32_t w = roi->x1 - roi->x0 + 1, h = roi->y1 - roi->y0 + 1;
    const size_t w1 = (size_t)w + 1u, cells = w1 * ((size_t)h + 1u);
    selh_head_t *hd = (selh_head_t *)base;
    int64_t *ti = (int64_t *)(void *)((uint8_t *)base + SELH_HEAD);
    double *td = (double *)(void *)((uint8_t *)base + SELH_HEAD +
                                    TRN_ALIGN_UP((size_t)SELH_NI * cells * sizeof(int64_t)));
    int32_t x, y, k;
    trn_status_t st = choose_quanta(heights, roi, hd);
    if (st != TRN_OK) {
        return st;
    }
    for (k = 0; k < SELH_NI; ++k) {
        memset(ti + (size_t)k * cells, 0, w1 * sizeof(int64_t));
    }
    for (k = 0; heading != 0 && k < SELH_ND; ++k) {
        memset(td + (size_t)k * cells, 0, w1 * sizeof(double));
    }
    for (y = 0; y < h; ++y) {
        int64_t run[SELH_NI] = {0, 0, 0, 0, 0, 0, 0};
        double rund[SELH_ND] = {0.0, 0.0, 0.0, 0.0};
        const size_t r0 = (size_t)y * w1, r1 = (size_t)(y + 1) * w1;
        for (k = 0; k < SELH_NI; ++k) {
            ti[(size_t)k * cells + r1] = 0;
        }
        for (k = 0; heading != 0 && k < SELH_ND; ++k) {
            td[(size_t)k * cells + r1] = 0.0;
        }
        for (x = 0; x < w; ++x) {
            int64_t q[SELH_NI];
            cell_q(heights, roi->x0 + x, roi->y0 + y, hd, q);
            for (k = 0; k < SELH_NI; ++k) {
                int64_t *t = ti + (size_t)k * cells;
                run[k] += q[k];
                t[r1 + (size_t)x + 1u] = t[r0 + (size_t)x + 1u] + run[k];
            }
            if (heading != 0) {
                /* the heading's column g . J u, u the offset from the rover */
                const double gx = (double)q[1] / hd->gq, gy = (double)q[2] / hd->gq;
                const double ux = (double)(roi->x0 + x) - rxf, uy = (double)(roi->y0 + y) - ryf;
                const double gt = q[0] != 0 ? gy * ux - gx * uy : 0.0;
                rund[0] += gt;
                rund[1] += gt * gx;
                rund[2] += gt * gy;
                rund[3] += gt * gt;
                for (k = 0; k < SELH_ND; ++k) {
                    double *t = td + (size_t)k * cells;
                    t[r1 + (size_t)x + 1u] = t[r0 + (size_t)x + 1u] + rund[k];
                }
            }
        }
    }
    return TRN_OK;
}

void trn_selh_sums_(const void *base, const trn_window_t *roi, const trn_window_t *pw, int heading,
                    trn_selh_sums_t *s)
{
    const size_t w1 = (size_t)(roi->x1 - roi->x0) + 2u;
    const size_t cells = w1 * ((size_t)(roi->y1 - roi->y0) + 2u);
    const size_t x0 = (size_t)(pw->x0 - roi->x0), x1 = (size_t)(pw->x1 - roi->x0) + 1u;
    const size_t y0 = (size_t)(pw->y0 - roi->y0), y1 = (size_t)(pw->y1 - roi->y0) + 1u;
    const size_t a = y1 * w1 + x1, b = y0 * w1 + x1, c = y1 * w1 + x0, d = y0 * w1 + x0;
    const selh_head_t *hd = (const selh_head_t *)base;
    const int64_t *ti = (const int64_t *)(const void *)((const uint8_t *)base + SELH_HEAD);
    const double *td = (const double *)(const void *)((const uint8_t *)base + SELH_HEAD +
                                                      TRN_ALIGN_UP((size_t)SELH_NI * cells *
                                                                   sizeof(int64_t)));
    int64_t v[SELH_NI];
    const double q2 = hd->gq * hd->gq;
    double n, sx, sy;
    int32_t k;
    for (k = 0; k < SELH_NI; ++k) {
        const int64_t *t = ti + (size_t)k * cells;
        v[k] = t[a] - t[b] - t[c] + t[d];
    }
    memset(s, 0, sizeof *s);
    s->n = n = (double)v[0];
    if (v[0] < 1) {
        return;
    }
    sx = (double)v[1];
    sy = (double)v[2];
    /* profiled: sum g g^T - (sum g)(sum g)^T / n */
    s->axx = ((double)v[3] - sx * sx / n) / q2;
    s->axy = ((double)v[4] - sx * sy / n) / q2;
    s->ayy = ((double)v[5] - sy * sy / n) / q2;
    s->raw = ((double)v[3] + (double)v[5]) / q2;
    s->e2 = (double)v[6] / hd->eq / n;
    if (heading != 0) {
        double e[SELH_ND];
        for (k = 0; k < SELH_ND; ++k) {
            const double *t = td + (size_t)k * cells;
            e[k] = t[a] - t[b] - t[c] + t[d];
        }
        s->bx = e[1] - e[0] * (sx / hd->gq) / n;
        s->by = e[2] - e[0] * (sy / hd->gq) / n;
        s->cc = e[3] - e[0] * e[0] / n;
    }
}
