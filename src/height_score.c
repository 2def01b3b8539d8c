/* SPDX-License-Identifier: Apache-2.0 */
/* height_score.c - the height matcher's score of one integer pose
 * (height_score.h). */
#include "height_score.h"

#include <float.h>
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
    s->r = (double *)trn_ws_take(&w, n * sizeof(double));
    s->cv = (double *)trn_ws_take(&w, n * sizeof(double));
    s->c1 = (double *)trn_ws_take(&w, n * sizeof(double));
    s->c2 = (double *)trn_ws_take(&w, n * sizeof(double));
    s->off = (int64_t *)trn_ws_take(&w, n * sizeof(int64_t));
    s->ox = (int32_t *)trn_ws_take(&w, n * sizeof(int32_t));
    s->oy = (int32_t *)trn_ws_take(&w, n * sizeof(int32_t));
    s->tx = (int32_t *)trn_ws_take(&w, n * sizeof(int32_t));
    s->ty = (int32_t *)trn_ws_take(&w, n * sizeof(int32_t));
    s->cs = (int32_t *)trn_ws_take(&w, (n + 1u) * sizeof(int32_t));
    s->ck = (int32_t *)trn_ws_take(&w, n * sizeof(int32_t));
    return w.total;
}

size_t trn_hs_bytes(int32_t lw, int32_t lh)
{
    trn_hs_t s;
    return carve(lw, lh, NULL, &s);
}

/* Squared distance of seen cell i from the rover, cells^2. */
static int64_t r2_of(const trn_hs_t *s, int32_t i)
{
    return (int64_t)s->ox[i] * s->ox[i] + (int64_t)s->oy[i] * s->oy[i];
}

/* Permutation p before q: nearer first, then scan order. */
static int before(const trn_hs_t *s, int32_t p, int32_t q)
{
    const int64_t a = r2_of(s, p), b = r2_of(s, q);
    return a < b || (a == b && p < q);
}

/* Moves perm[top] down the heap perm[0..end) (largest on top). */
static void sift(const trn_hs_t *s, int32_t *perm, int32_t top, int32_t end)
{
    int32_t root = top;
    while (2 * root + 1 < end) {
        int32_t c = 2 * root + 1;
        int32_t t;
        if (c + 1 < end && before(s, perm[c], perm[c + 1])) {
            ++c;
        }
        if (!before(s, perm[root], perm[c])) {
            return;
        }
        t = perm[root];
        perm[root] = perm[c];
        perm[c] = t;
        root = c;
    }
}

/* Heap sort of the permutation perm[0..n) by distance (no recursion, no
 * allocation). */
static void sort_by_range(const trn_hs_t *s, int32_t *perm, int32_t n)
{
    int32_t i;
    for (i = n / 2 - 1; i >= 0; --i) {
        sift(s, perm, i, n);
    }
    for (i = n - 1; i > 0; --i) {
        const int32_t t = perm[0];
        perm[0] = perm[i];
        perm[i] = t;
        sift(s, perm, 0, i);
    }
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

/* The seen cells in scan order into h, ox, oy; their count. */
static int32_t gather(trn_hs_t *s, const trn_grid_f32_t *local, int32_t rx, int32_t ry)
{
    int32_t x, y, n = 0;
    for (y = 0; y < local->height; ++y) {
        for (x = 0; x < local->width; ++x) {
            const double h = (double)TRN_GRID_AT(local, x, y);
            if (isfinite(h)) {
                s->h[n] = h;
                s->ox[n] = x - rx;
                s->oy[n] = y - ry;
                ++n;
            }
        }
    }
    return n;
}

/* The cells ordered by distance from the rover, and the noise classes: the
 * runs of one distance, which share one noise variance. */
static void classes(trn_hs_t *s, int32_t n, int32_t rx, int32_t ry, const trn_refine_cfg_t *cfg)
{
    int32_t i, c = 0;
    for (i = 0; i < n; ++i) {
        s->tx[i] = i;
    }
    sort_by_range(s, s->tx, n);
    for (i = 0; i < n; ++i) { /* apply the permutation through r and ty */
        s->r[i] = s->h[s->tx[i]];
        s->ty[i] = s->ox[s->tx[i]];
    }
    for (i = 0; i < n; ++i) {
        s->h[i] = s->r[i];
        s->ox[i] = s->ty[i];
        s->ty[i] = s->oy[s->tx[i]];
    }
    for (i = 0; i < n; ++i) {
        s->oy[i] = s->ty[i];
    }
    for (i = 0; i < n; ++i) {
        if (i == 0 || r2_of(s, i) != r2_of(s, i - 1)) {
            s->cs[c] = i;
            s->cv[c] = trn_refine_noise_var_(cfg, rx + s->ox[i], ry + s->oy[i], rx, ry);
            ++c;
        }
    }
    s->cs[c] = n;
    s->nc = c;
}

size_t trn_hs_init(trn_hs_t *s, void *ws, const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                   int32_t rx, int32_t ry, const trn_refine_cfg_t *cfg, double inlier_prob)
{
    int32_t n;
    double spread;
    (void)carve(local->width, local->height, ws, s);
    s->g = global;
    n = gather(s, local, rx, ry);
    s->n = (size_t)n;
    spread = spread_of(s->h, s->n); /* in scan order, as trn_height_search */
    classes(s, n, rx, ry, cfg);
    s->a = inlier_prob;
    s->k = 1.0 / (10.0 * (spread > (double)cfg->noise_m ? spread : (double)cfg->noise_m));
    s->b = (1.0 - s->a) * s->k;
    s->lout = log(s->b);
    s->fitk = cfg->fit_noise != 0 ? 1 : 0;
    s->k2 = 1.0;
    trn_hs_turn(s, 1.0, 0.0);
    return s->n;
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

/* Per noise class c, over its residuals r_i with (r_i - z)^2 <= c2 (kk v_c
 * + mm) (c2 = INFINITY: every finite one), their count into s->ck[c] and
 * the sum and the sum of squares of r_i - ref into s->c1[c], s->c2[c], in
 * two running sums, even and odd cells (half the additions' chain). The
 * limit is held to DBL_MAX, so that the one comparison
 * keeps out NaN (a cell off the map or over a missing map height) and an
 * infinite residual, and no finite one that the limit keeps: from float
 * heights |r_i - z| stays below 1e40, its square below 1e80. */
static void class_sums(trn_hs_t *s, double ref, double z, double c2, double kk, double mm)
{
    int32_t c;
    for (c = 0; c < s->nc; ++c) {
        const double l = c2 * (kk * s->cv[c] + mm), lim = l < DBL_MAX ? l : DBL_MAX;
        const int32_t end = s->cs[c + 1];
        double a1 = 0.0, a2 = 0.0, t1 = 0.0, t2 = 0.0;
        int32_t i, kn = 0;
        for (i = s->cs[c]; i + 1 < end; i += 2) {
            const double r = s->r[i], e = r - z, r1 = s->r[i + 1], e1 = r1 - z;
            if (e * e <= lim) {
                ++kn;
                a1 += r - ref;
                a2 += (r - ref) * (r - ref);
            }
            if (e1 * e1 <= lim) {
                ++kn;
                t1 += r1 - ref;
                t2 += (r1 - ref) * (r1 - ref);
            }
        }
        if (i < end) {
            const double r = s->r[i], e = r - z;
            if (e * e <= lim) {
                ++kn;
                a1 += r - ref;
                a2 += (r - ref) * (r - ref);
            }
        }
        s->ck[c] = kn;
        s->c1[c] = a1 + t1;
        s->c2[c] = a2 + t2;
    }
}

/* The weighted moments' fit at the variances (*k2, *m2) from class_sums'
 * sums: per class weighted by w = 1 / (k2 v + m2) for the offset and by w^2
 * for the variances (trn_var_fit_: the model variance, and with s->fitk the
 * noise scale) into dz, k2 and m2. The points' count (0: dz, k2 and m2
 * untouched). */
static int32_t fit_sums(const trn_hs_t *s, double ref, double *dz, double *k2, double *m2)
{
    double sw = 0.0, swr = 0.0, sq = 0.0, sqr = 0.0, sqrr = 0.0, sqv = 0.0, sqvv = 0.0;
    double sqvr = 0.0, sqvrr = 0.0, d;
    const double kk = *k2, mm = *m2;
    int32_t c, n = 0;
    for (c = 0; c < s->nc; ++c) {
        const double v = s->cv[c], w = 1.0 / (kk * v + mm), q = w * w, k = (double)s->ck[c];
        const double s1 = s->c1[c], s2 = s->c2[c];
        sw += w * k;
        swr += w * s1;
        sq += q * k;
        sqr += q * s1;
        sqrr += q * s2;
        sqv += q * v * k;
        sqvv += q * v * v * k;
        sqvr += q * v * s1;
        sqvrr += q * v * s2;
        n += s->ck[c];
    }
    if (n == 0) {
        return 0;
    }
    d = swr / sw;
    trn_var_fit_(sqrr - 2.0 * d * sqr + d * d * sq, sqvrr - 2.0 * d * sqvr + d * d * sqv, sq, sqv,
                 sqvv, s->fitk, k2, m2);
    *dz = d + ref;
    return n;
}

/* The fit within clip sds of *dz at the variances (*k2, *m2): class_sums,
 * then fit_sums. */
static int32_t fit(trn_hs_t *s, double ref, double clip, double *dz, double *k2, double *m2)
{
    class_sums(s, ref, *dz, clip * clip, *k2, *m2);
    return fit_sums(s, ref, dz, k2, m2);
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

/* ln L at the fitted (dz, k2, m2). The sum of logs as the log of products, one
 * log per many cells: a term lies within [b, a / sqrt(2 pi v) + b], b above
 * 1e-47 (a float inlier probability below 1, float heights' spread) and the
 * top below 1e45 (a float noise sd above 0), so a product kept within
 * 1e+-150 takes one more and stays a normal number (its rounding: 1e-16
 * relative a term, 1e-12 nats over 4,096 cells). */
static double mixture_ll(const trn_hs_t *s, double dz, double k2, double m2)
{
    const double inv_two_pi = 0.15915494309189535;
    double ll = 0.0, prod = 1.0;
    int32_t c;
    for (c = 0; c < s->nc; ++c) {
        const double iv = 1.0 / (k2 * s->cv[c] + m2), peak = s->a * sqrt(iv * inv_two_pi);
        const double half = -0.5 * iv;
        int32_t i;
        for (i = s->cs[c]; i < s->cs[c + 1]; ++i) {
            const double u = s->r[i] - dz;
            if (!isfinite(u)) {
                ll += s->lout;
                continue;
            }
            prod *= peak * exp(half * u * u) + s->b;
            if (prod < 1e-150 || prod > 1e150) {
                ll += log(prod);
                prod = 1.0;
            }
        }
    }
    return ll + log(prod);
}

double trn_hs_ll(trn_hs_t *s, int32_t px, int32_t py, double *dz_out, double *model_m)
{
    double dz = 0.0, k2 = 1.0, m2 = 0.0, ref;
    int32_t n_all;
    residuals(s, px, py);
    ref = first_residual(s);
    /* every point at the model's variances, then at that fit's: the
     * variances change the weights, not which points count, so one pass
     * over the points serves both */
    class_sums(s, ref, 0.0, (double)INFINITY, 1.0, 0.0);
    n_all = fit_sums(s, ref, &dz, &k2, &m2);
    if (n_all > 0 && fit_sums(s, ref, &dz, &k2, &m2) > 0) {
        /* then within the clip of the last fit, again while that drops
         * points (trn_clip_again_) */
        double dz1 = dz, k21 = k2, m21 = m2;
        int32_t n_prev = n_all, n, again;
        for (again = 0; again <= TRN_CLIP_AGAIN; ++again) {
            n = fit(s, ref, TRN_REFINE_CLIP, &dz1, &k21, &m21);
            if (n <= 0) {
                break;
            }
            dz = dz1;
            k2 = k21;
            m2 = m21;
            if (!trn_clip_again_(n_all, n_prev, n)) {
                break;
            }
            n_prev = n;
        }
    }
    s->k2 = k2;
    *dz_out = dz;
    *model_m = sqrt(m2);
    return mixture_ll(s, dz, k2, m2);
}
