/* SPDX-License-Identifier: Apache-2.0 */
/* height_score.c - the height matcher's score of one integer pose
 * (height_score.h). */
#include "height_score.h"

#include <math.h>

#include "refine_int.h"
#include "ws.h"

static size_t carve(int32_t lw, int32_t lh, void *base, trn_hs_t *s)
{
    trn_ws_t w;
    size_t n;
    if (lw < 1 || lh < 1 || lw > TRN_MAX_DIM || lh > TRN_MAX_DIM) {
        return 0u;
    }
    n = (size_t)lw * (size_t)lh;
    trn_ws_begin(&w, base);
    s->h = (double *)trn_ws_take(&w, n * sizeof(double));
    s->v = (double *)trn_ws_take(&w, n * sizeof(double));
    s->w = (double *)trn_ws_take(&w, n * sizeof(double));
    s->r = (double *)trn_ws_take(&w, n * sizeof(double));
    s->off = (int64_t *)trn_ws_take(&w, n * sizeof(int64_t));
    s->ox = (int32_t *)trn_ws_take(&w, n * sizeof(int32_t));
    s->oy = (int32_t *)trn_ws_take(&w, n * sizeof(int32_t));
    s->tx = (int32_t *)trn_ws_take(&w, n * sizeof(int32_t));
    s->ty = (int32_t *)trn_ws_take(&w, n * sizeof(int32_t));
    return w.total;
}

size_t trn_hs_bytes(int32_t lw, int32_t lh)
{
    trn_hs_t s;
    return carve(lw, lh, NULL, &s);
}

/* Spread of the seen heights (standard deviation about their mean), the
 * arithmetic of trn_height_search's. */
static double spread_of(const double *h, size_t n)
{
    size_t i;
    double s1 = 0.0, s2 = 0.0, v;
    if (n == 0u) {
        return 0.0;
    }
    for (i = 0; i < n; ++i) {
        s1 += h[i] - h[0];
        s2 += (h[i] - h[0]) * (h[i] - h[0]);
    }
    v = s2 / (double)n - (s1 / (double)n) * (s1 / (double)n);
    return v > 0.0 ? sqrt(v) : 0.0;
}

size_t trn_hs_init(trn_hs_t *s, void *ws, const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                   int32_t rx, int32_t ry, const trn_refine_cfg_t *cfg, double inlier_prob)
{
    int32_t x, y;
    size_t n = 0;
    double spread;
    (void)carve(local->width, local->height, ws, s);
    s->g = global;
    for (y = 0; y < local->height; ++y) {
        for (x = 0; x < local->width; ++x) {
            const double h = (double)TRN_GRID_AT(local, x, y);
            if (!isfinite(h)) {
                continue;
            }
            s->h[n] = h;
            s->v[n] = trn_refine_noise_var_(cfg, x, y, rx, ry);
            s->w[n] = 1.0 / s->v[n];
            s->ox[n] = x - rx;
            s->oy[n] = y - ry;
            ++n;
        }
    }
    s->n = n;
    spread = spread_of(s->h, n);
    s->a = inlier_prob;
    s->k = 1.0 / (10.0 * (spread > (double)cfg->noise_m ? spread : (double)cfg->noise_m));
    s->b = (1.0 - s->a) * s->k;
    s->lout = log(s->b);
    trn_hs_turn(s, 1.0, 0.0);
    return n;
}

void trn_hs_turn(trn_hs_t *s, double c, double sn)
{
    size_t i;
    s->x0 = s->y0 = INT32_MAX;
    s->x1 = s->y1 = INT32_MIN;
    for (i = 0; i < s->n; ++i) {
        const double x = (double)s->ox[i], y = (double)s->oy[i];
        const int32_t tx = (int32_t)floor(x * c + y * sn + 0.5);
        const int32_t ty = (int32_t)floor(-x * sn + y * c + 0.5);
        s->tx[i] = tx;
        s->ty[i] = ty;
        s->off[i] = (int64_t)ty * (int64_t)s->g->stride + (int64_t)tx;
        s->x0 = tx < s->x0 ? tx : s->x0;
        s->x1 = tx > s->x1 ? tx : s->x1;
        s->y0 = ty < s->y0 ? ty : s->y0;
        s->y1 = ty > s->y1 ? ty : s->y1;
    }
}

/* The residuals at pose (px, py): NaN where the map has no height. */
static void residuals(trn_hs_t *s, int32_t px, int32_t py)
{
    const trn_grid_f32_t *g = s->g;
    size_t i;
    if (s->n > 0u && (int64_t)px + s->x0 >= 0 && (int64_t)py + s->y0 >= 0 &&
        (int64_t)px + s->x1 < g->width && (int64_t)py + s->y1 < g->height) {
        /* every cell on the map: no bounds to check */
        const float *at = g->data + ((size_t)py * (size_t)g->stride + (size_t)px);
        for (i = 0; i < s->n; ++i) {
            s->r[i] = s->h[i] - (double)at[s->off[i]];
        }
        return;
    }
    for (i = 0; i < s->n; ++i) {
        const int64_t gx = (int64_t)px + s->tx[i], gy = (int64_t)py + s->ty[i];
        s->r[i] = gx < 0 || gy < 0 || gx >= g->width || gy >= g->height
                      ? (double)NAN
                      : s->h[i] - (double)TRN_GRID_AT(g, (int32_t)gx, (int32_t)gy);
    }
}

/* The weighted moments' offset and model variance (trn_pose_mom_end_'s) from
 * sums relative to ref. */
static int32_t fit_end(const double m[6], double ref, int32_t n, double *dz, double *m2)
{
    double d, v;
    if (n == 0) {
        return 0;
    }
    d = m[1] / m[0];
    v = (m[4] - 2.0 * d * m[3] + d * d * m[2] - m[5]) / m[2];
    *dz = d + ref;
    *m2 = v > 0.0 ? v : 0.0;
    return n;
}

/* The fit over every residual at model variance m2 = 0 (weights 1 / v). */
static int32_t fit_first(const trn_hs_t *s, double ref, double *dz, double *m2)
{
    double m[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    int32_t n = 0;
    size_t i;
    for (i = 0; i < s->n; ++i) {
        const double d = s->r[i] - ref, w = s->w[i], q = w * w;
        if (!isfinite(d)) {
            continue;
        }
        m[0] += w;
        m[1] += w * d;
        m[2] += q;
        m[3] += q * d;
        m[4] += q * d * d;
        m[5] += w; /* q v */
        ++n;
    }
    return fit_end(m, ref, n, dz, m2);
}

/* The fit at model variance *m2 over the residuals within clip sds of *dz
 * (clip < 0: all of them); their count (0: dz and m2 untouched). */
static int32_t fit_pass(const trn_hs_t *s, double ref, double clip, double *dz, double *m2)
{
    double m[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    const double c2 = clip < 0.0 ? (double)INFINITY : clip * clip, z = *dz, mm = *m2;
    int32_t n = 0;
    size_t i;
    for (i = 0; i < s->n; ++i) {
        const double r = s->r[i], vm = s->v[i] + mm, e = r - z;
        double w, q, d;
        if (!isfinite(r) || e * e > c2 * vm) {
            continue;
        }
        w = 1.0 / vm;
        q = w * w;
        d = r - ref;
        m[0] += w;
        m[1] += w * d;
        m[2] += q;
        m[3] += q * d;
        m[4] += q * d * d;
        m[5] += q * s->v[i];
        ++n;
    }
    return fit_end(m, ref, n, dz, m2);
}

/* The first residual on the map (the moments' reference), 0 if none. */
static double first_residual(const trn_hs_t *s)
{
    size_t i;
    for (i = 0; i < s->n; ++i) {
        if (isfinite(s->r[i])) {
            return s->r[i];
        }
    }
    return 0.0;
}

double trn_hs_ll(trn_hs_t *s, int32_t px, int32_t py, double *dz_out, double *model_m)
{
    const double inv_two_pi = 0.15915494309189535;
    double dz = 0.0, m2 = 0.0, ll = 0.0, prod = 1.0, ref;
    int32_t n_all;
    size_t i;
    residuals(s, px, py);
    ref = first_residual(s);
    n_all = fit_first(s, ref, &dz, &m2);
    if (n_all > 0 && fit_pass(s, ref, -1.0, &dz, &m2) > 0) {
        /* then within the clip of the last fit, again while that drops
         * points (trn_clip_again_) */
        double dz1 = dz, m21 = m2;
        int32_t n_prev = n_all, n, again;
        for (again = 0; again <= TRN_CLIP_AGAIN; ++again) {
            n = fit_pass(s, ref, TRN_REFINE_CLIP, &dz1, &m21);
            if (n <= 0) {
                break;
            }
            dz = dz1;
            m2 = m21;
            if (!trn_clip_again_(n_all, n_prev, n)) {
                break;
            }
            n_prev = n;
        }
    }
    /* the sum of logs as the log of products, one log per many cells: a
     * term lies within [b, a / sqrt(2 pi v) + b], b above 1e-47 (a float
     * inlier probability below 1, float heights' spread) and the top below
     * 1e45 (a float noise sd above 0), so a product kept within 1e+-150
     * takes one more and stays a normal number (its rounding: 1e-16
     * relative a term, 1e-12 nats over 4,096 cells) */
    for (i = 0; i < s->n; ++i) {
        const double u = s->r[i] - dz, iv = 1.0 / (s->v[i] + m2);
        if (!isfinite(u)) {
            ll += s->lout;
            continue;
        }
        prod *= s->a * exp(-0.5 * u * u * iv) * sqrt(iv * inv_two_pi) + s->b;
        if (prod < 1e-150 || prod > 1e150) {
            ll += log(prod);
            prod = 1.0;
        }
    }
    ll += log(prod);
    *dz_out = dz;
    *model_m = sqrt(m2);
    return ll;
}
