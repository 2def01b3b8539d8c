/* SPDX-License-Identifier: Apache-2.0 */
/* select_heights.c - the height matcher's prediction's tables (see
 * select_heights.h). */
#include "select_heights.h"
#include "ws.h"

#include <math.h>
#include <string.h>

#define SELH_QLIM 4.0e18 /* largest magnitude a region's int64 sum may reach */
#define SELH_NI 7        /* int64 tables: n, w, w gx, w gy, w gx^2, w gx gy, w gy^2 */
#define SELH_ND 4        /* double tables: w gt, w gt gx, w gt gy, w gt^2 */
#define SELH_KMAX 40     /* finest quantum: 2^-40 of a table's unit */

/* The tables' header: each int64 table's quantum's inverse. */
typedef struct {
    double q[SELH_NI];
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

/* The terms of map cell (x, y) into t[SELH_NI] (t[0] = 1, t[1] = w, then w
 * times gx, gy, gx^2, gx gy, gy^2) and its gradient into g: 1 with its four
 * neighbours' heights known, else 0 (t all 0). w = 1 / (the noise model at
 * the cell's range from the rover, times inv_n, + the jitter times |g|^2 +
 * the map's error + e^2 / 4). */
static int cell_terms(const trn_grid_f32_t *hg, const trn_selh_noise_t *nm, int32_t x, int32_t y,
                      double t[SELH_NI], double g[2])
{
    double c, l, r, d, u, e, ux, uy, sd, w;
    memset(t, 0, (size_t)SELH_NI * sizeof t[0]);
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
    g[0] = 0.5 * (r - l);
    g[1] = 0.5 * (u - d);
    e = c - 0.25 * (l + r + d + u);
    ux = ((double)x - nm->rxf) * nm->cell;
    uy = ((double)y - nm->ryf) * nm->cell;
    sd = nm->noise_m + nm->noise_k * (ux * ux + uy * uy);
    w = 1.0 / (sd * sd * nm->inv_n + nm->jitter * (g[0] * g[0] + g[1] * g[1]) + nm->map_var +
               0.25 * e * e);
    t[0] = 1.0;
    t[1] = w;
    t[2] = w * g[0];
    t[3] = w * g[1];
    t[4] = w * g[0] * g[0];
    t[5] = w * g[0] * g[1];
    t[6] = w * g[1] * g[1];
    return 1;
}

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

/* The finest power-of-two quantum 2^-k (k <= SELH_KMAX) with which the
 * region's sums of terms of magnitude up to vmax stay within lim; -1 when
 * even a quantum of 1 does not. */
static int32_t quantum_exp(double vmax, double lim)
{
    int32_t k = SELH_KMAX;
    while (k >= 0 && vmax * pow2(k) > lim) {
        --k;
    }
    return k;
}

/* The quanta (hd) with which no table's sum over the region can leave
 * SELH_QLIM: per table the finest with its largest term (plus one for the
 * rounding) times the region's cells within it (exact sums as fine as the
 * data allow); TRN_E_SIZE where none is (a term too large or not finite). */
static trn_status_t choose_quanta(const trn_grid_f32_t *hg, const trn_window_t *roi,
                                  const trn_selh_noise_t *nm, selh_head_t *hd)
{
    double tmax[SELH_NI] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}, cells;
    int32_t x, y, k;
    for (y = roi->y0; y <= roi->y1; ++y) {
        for (x = roi->x0; x <= roi->x1; ++x) {
            double t[SELH_NI], g[2];
            if (cell_terms(hg, nm, x, y, t, g)) {
                for (k = 0; k < SELH_NI; ++k) {
                    /* a NaN term (an infinite gradient times w) refuses the region */
                    tmax[k] = isnan(t[k]) ? HUGE_VAL : fmax(tmax[k], fabs(t[k]));
                }
            }
        }
    }
    cells = (double)(roi->x1 - roi->x0 + 1) * (double)(roi->y1 - roi->y0 + 1);
    for (k = 0; k < SELH_NI; ++k) {
        const int32_t e = k == 0 ? 0 : quantum_exp(tmax[k] + 1.0, SELH_QLIM / cells);
        if (e < 0 || !(tmax[k] < HUGE_VAL)) {
            return TRN_E_SIZE;
        }
        hd->q[k] = pow2(e);
    }
    return TRN_OK;
}

/* One row of a table: t[r1 + x + 1] = t[r0 + x + 1] + the row's running sum. */
static void sat_row_i(int64_t *t, size_t r0, size_t r1, int32_t x, int64_t *run, int64_t v)
{
    *run += v;
    t[r1 + (size_t)x + 1u] = t[r0 + (size_t)x + 1u] + *run;
}

static void sat_row_d(double *t, size_t r0, size_t r1, int32_t x, double *run, double v)
{
    *run += v;
    t[r1 + (size_t)x + 1u] = t[r0 + (size_t)x + 1u] + *run;
}

trn_status_t trn_selh_build_(const trn_grid_f32_t *heights, const trn_window_t *roi, int heading,
                             const trn_selh_noise_t *nm, void *base)
{
    const int32_t w = roi->x1 - roi->x0 + 1, h = roi->y1 - roi->y0 + 1;
    const size_t w1 = (size_t)w + 1u, cells = w1 * ((size_t)h + 1u);
    selh_head_t *hd = (selh_head_t *)base;
    int64_t *ti = (int64_t *)(void *)((uint8_t *)base + SELH_HEAD);
    double *td = (double *)(void *)((uint8_t *)base + SELH_HEAD +
                                    TRN_ALIGN_UP((size_t)SELH_NI * cells * sizeof(int64_t)));
    int32_t x, y, k;
    trn_status_t st = choose_quanta(heights, roi, nm, hd);
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
            double t[SELH_NI], g[2] = {0.0, 0.0};
            const int seen = cell_terms(heights, nm, roi->x0 + x, roi->y0 + y, t, g);
            for (k = 0; k < SELH_NI; ++k) {
                sat_row_i(ti + (size_t)k * cells, r0, r1, x, &run[k],
                          (int64_t)floor(t[k] * hd->q[k] + 0.5));
            }
            if (heading != 0) {
                /* the heading's column g . J u, u the offset from the rover (cells) */
                const double ux = (double)(roi->x0 + x) - nm->rxf;
                const double uy = (double)(roi->y0 + y) - nm->ryf;
                const double gt = seen ? g[1] * ux - g[0] * uy : 0.0;
                sat_row_d(td, r0, r1, x, &rund[0], t[1] * gt);
                sat_row_d(td + cells, r0, r1, x, &rund[1], t[2] * gt);
                sat_row_d(td + 2u * cells, r0, r1, x, &rund[2], t[3] * gt);
                sat_row_d(td + 3u * cells, r0, r1, x, &rund[3], t[1] * gt * gt);
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
    double v[SELH_NI], sw;
    int32_t k;
    for (k = 0; k < SELH_NI; ++k) {
        const int64_t *t = ti + (size_t)k * cells;
        v[k] = (double)(t[a] - t[b] - t[c] + t[d]) / hd->q[k];
    }
    memset(s, 0, sizeof *s);
    s->n = v[0];
    sw = v[1];
    if (!(sw > 0.0)) {
        return;
    }
    /* profiled: sum w g g^T - (sum w g)(sum w g)^T / sum w */
    s->axx = v[4] - v[2] * v[2] / sw;
    s->axy = v[5] - v[2] * v[3] / sw;
    s->ayy = v[6] - v[3] * v[3] / sw;
    s->raw = v[4] + v[6];
    if (heading != 0) {
        double e[SELH_ND];
        for (k = 0; k < SELH_ND; ++k) {
            const double *t = td + (size_t)k * cells;
            e[k] = t[a] - t[b] - t[c] + t[d];
        }
        s->bx = e[1] - e[0] * v[2] / sw;
        s->by = e[2] - e[0] * v[3] / sw;
        s->cc = e[3] - e[0] * e[0] / sw;
    }
}
