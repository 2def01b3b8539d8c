/* SPDX-License-Identifier: Apache-2.0 */
/* height_bound.c - the height matcher's bounded search over (x, y)
 * (height_bound.h; docs/method.md 9.3, "The bounded search").
 *
 * The bound. A pose's ln L is a sum over the seen local cells i of
 * ln(a N(r_i - dz; k2 v_i + m2) + c), r_i = h_i - g_i(pose), with one offset
 * dz, one model variance m2 >= 0 and (trn_refine_cfg_t.fit_noise) one noise
 * scale k2 fitted per pose. Over a block of poses, g_i
 * lies between the map's least and greatest height over the block's square
 * shifted by cell i, so r_i lies in [lo_i, hi_i]. For a given dz and a class
 * [m_lo, m_hi] of m2, term i is at most F(d_i), d_i the distance of dz from
 * [lo_i, hi_i], F(d) = ln(a max_v N(d; v) + c) over v in
 * [k_lo v_i + m_lo, k_hi v_i + m_hi] (k the noise scale, fitted or 1), which
 * falls with d. F is bounded by a staircase
 * over steps t_j (in units of the cell's noise sd), and the number of cells
 * within t_j sds of any offset of a range of offset bins is read from
 * cumulative counts of the cells' low and high ends, so a bound over a range
 * of offsets costs O(steps) after one O(cells) pass. The block's bound is
 * the largest over the m2 classes and the offsets (a branch and bound over
 * offset ranges); the fitted dz and m2 always lie in the ranges searched (a
 * weighted mean of residuals, a mean square about it). Terms outside the map
 * are ln c, which F never falls below. */
#include "height_bound.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "localize_int.h"
#include "refine_int.h"
#include "ws.h"

/* Noise classes: sds within this ratio share a class. */
#define HB_Q_RATIO 1.5
/* Offset bins: at most half the least noise sd wide. */
#define HB_BIN_SD 0.5
/* Steps past 4 sds grow by this ratio. */
#define HB_STEP_RATIO 1.3
/* m2 classes: the first up to (sd / 4)^2, then by 4 in variance. */
#define HB_M2_FIRST 0.0625
#define HB_M2_RATIO 4.0
/* Nodes of this level or finer are scored pose by pose, not bounded. */
#define HB_LEAF 2
/* ... and so are nodes whose poses take fewer pose-cell visits than this to
 * score (the leaf level: 2 from 64 seen cells up, 3 from 16, else 4). A
 * bound's work beside the cells (its offset ranges, the counts' tables) is
 * fixed, about 1 us here, so on a local map of a few cells a bound that
 * prunes nothing costs more than its poses' scores could save (trn_bench's
 * 5 x 5 worst case: 70 nodes bounded where the fixed leaf bounded 239,
 * bounded / exhaustive 1.14x against 1.24x; docs/benchmarks.md). */
#define HB_LEAF_WORK 1024.0

/* 2^l for the tree's levels (multiplications and divisions, not shifts of
 * signed values). */
static const int32_t k_pow2[TRN_HB_MAX_LEVELS] = {1,   2,   4,    8,    16,   32,   64,   128,
                                                  256, 512, 1024, 2048, 4096, 8192, 16384};

typedef struct {
    size_t hb, dz, msd, done, ub[TRN_HB_MAX_LEVELS], mn[TRN_HB_MAX_LEVELS], mx[TRN_HB_MAX_LEVELS],
        cls, hs, cl, ch, cnt, stack, rstack, df, ft, total;
    int32_t levels, rw, rh, ww, wh;
} hb_layout_t;

static int hb_layout(const trn_window_t *win, int32_t lw, int32_t lh, hb_layout_t *lay)
{
    trn_ws_t ws;
    int32_t l, side = 1;
    if (win == NULL || win->x0 > win->x1 || win->y0 > win->y1 || lw < 1 || lh < 1 ||
        lw > TRN_MAX_DIM || lh > TRN_MAX_DIM || win->x1 - win->x0 >= TRN_MAX_DIM ||
        win->y1 - win->y0 >= TRN_MAX_DIM) {
        return 0;
    }
    lay->ww = win->x1 - win->x0 + 1;
    lay->wh = win->y1 - win->y0 + 1;
    lay->levels = 1;
    while (side < lay->ww || side < lay->wh) {
        side *= 2;
        lay->levels += 1;
    }
    lay->rw = side + lw;
    lay->rh = side + lh;
    trn_ws_begin(&ws, NULL);
    {
        const size_t poses = (size_t)lay->ww * (size_t)lay->wh;
        const size_t region = (size_t)lay->rw * (size_t)lay->rh;
        lay->hb = trn_ws_offset(&ws, sizeof(trn_hb_t));
        lay->dz = trn_ws_offset(&ws, poses * sizeof(double));
        lay->msd = trn_ws_offset(&ws, poses * sizeof(double));
        lay->done = trn_ws_offset(&ws, poses);
        for (l = 0; l < lay->levels; ++l) {
            const size_t nx = (size_t)((lay->ww + k_pow2[l] - 1) / k_pow2[l]);
            const size_t ny = (size_t)((lay->wh + k_pow2[l] - 1) / k_pow2[l]);
            lay->ub[l] = trn_ws_offset(&ws, nx * ny * sizeof(double));
            lay->mn[l] = trn_ws_offset(&ws, region * sizeof(float));
            lay->mx[l] = trn_ws_offset(&ws, region * sizeof(float));
        }
        lay->cls = trn_ws_offset(&ws, (size_t)lw * (size_t)lh);
        lay->hs = trn_ws_offset(&ws, trn_hs_bytes(lw, lh));
        lay->cl = trn_ws_offset(&ws, (size_t)TRN_HB_MAX_Q * TRN_HB_MAX_BINS * sizeof(uint32_t));
        lay->ch = trn_ws_offset(&ws, (size_t)TRN_HB_MAX_Q * TRN_HB_MAX_BINS * sizeof(uint32_t));
        lay->cnt = trn_ws_offset(&ws, (size_t)TRN_HB_MAX_Q * (TRN_HB_MAX_J + 1) * sizeof(int32_t));
        lay->stack = trn_ws_offset(&ws, (size_t)(4 * lay->levels + 8) * 3 * sizeof(int32_t));
        lay->rstack = trn_ws_offset(&ws, (size_t)(2 * 16 + 8) * 2 * sizeof(int32_t));
        lay->df = trn_ws_offset(&ws, (size_t)TRN_HB_MAX_Q * TRN_HB_MAX_C * TRN_HB_MAX_J *
                                         sizeof(double));
        lay->ft = trn_ws_offset(&ws, (size_t)TRN_HB_MAX_Q * TRN_HB_MAX_C * sizeof(double));
    }
    lay->total = ws.total;
    return lay->levels <= TRN_HB_MAX_LEVELS;
}

size_t trn_hb_bytes(const trn_window_t *win, int32_t local_w, int32_t local_h)
{
    hb_layout_t lay;
    return hb_layout(win, local_w, local_h, &lay) ? lay.total : 0u;
}

static size_t pidx(const trn_hb_t *hb, int32_t x, int32_t y)
{
    return (size_t)(y - hb->win.y0) * (size_t)hb->ww + (size_t)(x - hb->win.x0);
}

/* The map's extremes over squares of 2^l poses' cells, for every level. */
static void build_region(trn_hb_t *hb)
{
    int32_t i, j, l;
    for (j = 0; j < hb->rh; ++j) {
        for (i = 0; i < hb->rw; ++i) {
            const int32_t gx = hb->win.x0 - hb->rx + i, gy = hb->win.y0 - hb->ry + j;
            float v = (float)NAN;
            const size_t at = (size_t)j * (size_t)hb->rw + (size_t)i;
            if (gx >= 0 && gy >= 0 && gx < hb->global->width && gy < hb->global->height) {
                v = TRN_GRID_AT(hb->global, gx, gy);
            }
            hb->mn[0][at] = isfinite(v) ? v : (float)INFINITY;
            hb->mx[0][at] = isfinite(v) ? v : -(float)INFINITY;
        }
    }
    for (l = 1; l < hb->levels; ++l) {
        const int32_t h = k_pow2[l - 1];
        for (j = 0; j < hb->rh; ++j) {
            for (i = 0; i < hb->rw; ++i) {
                const size_t at = (size_t)j * (size_t)hb->rw + (size_t)i;
                float a = hb->mn[l - 1][at], b = hb->mx[l - 1][at];
                int32_t k;
                for (k = 1; k < 4; ++k) {
                    const int32_t ii = i + (k % 2) * h, jj = j + (k / 2) * h;
                    if (ii < hb->rw && jj < hb->rh) {
                        const size_t o = (size_t)jj * (size_t)hb->rw + (size_t)ii;
                        a = hb->mn[l - 1][o] < a ? hb->mn[l - 1][o] : a;
                        b = hb->mx[l - 1][o] > b ? hb->mx[l - 1][o] : b;
                    }
                }
                hb->mn[l][at] = a;
                hb->mx[l][at] = b;
            }
        }
    }
}

static int32_t bin_of(const trn_hb_t *hb, double z)
{
    const double b = floor((z - hb->z0) / hb->w);
    return b < 0.0 ? 0 : b > (double)(hb->nbins - 1) ? hb->nbins - 1 : (int32_t)b;
}

/* The staircase's value at distance d for noise class sds [s, s_hi] and m2
 * in [m_lo, m_hi]: ln(a max_v N(d; v) + c), v in [klo s^2 + m_lo, khi s_hi^2
 * + m_hi], [klo, khi] the noise scales the score may fit (1 without
 * fit_noise). */
static double f_step(const trn_hb_t *hb, double d, double s, double s_hi, double m_lo, double m_hi)
{
    const double two_pi = 6.283185307179586;
    const double klo = hb->cfg.fit_noise != 0 ? TRN_NOISE_SCALE2_MIN : 1.0;
    const double khi = hb->cfg.fit_noise != 0 ? TRN_NOISE_SCALE2_MAX : 1.0;
    const double vlo = klo * s * s + m_lo, vhi = khi * s_hi * s_hi + m_hi;
    double v = d * d;
    v = v < vlo ? vlo : v > vhi ? vhi : v;
    return log(hb->a * exp(-0.5 * d * d / v) / sqrt(two_pi * v) + (1.0 - hb->a) * hb->k);
}

/* Step j of the staircase, in noise sds: half an sd apart up to 4 sds, then
 * growing by HB_STEP_RATIO. */
static double step_sd(int32_t j)
{
    return j <= 8 ? 0.5 * (double)j : 4.0 * pow(HB_STEP_RATIO, (double)(j - 8));
}

/* Noise classes, offset bins, steps and the staircase tables. */
static void build_tables(trn_hb_t *hb, const double *sq_lo, const double *sq_hi, double z1)
{
    const double width = z1 - hb->z0;
    double mb[TRN_HB_MAX_C + 1], fmaxabs = fabs(hb->lout);
    int32_t q, c, j, npts = 0;
    /* m2 classes: [mb_c, mb_c+1]; m2 is at most the offsets' range squared */
    {
        const double top = (width + 2.0 * hb->w) * (width + 2.0 * hb->w);
        mb[0] = 0.0;
        hb->nc = 0;
        for (c = 1; c < TRN_HB_MAX_C; ++c) {
            const double m = HB_M2_FIRST * sq_lo[0] * sq_lo[0] * pow(HB_M2_RATIO, (double)(c - 1));
            if (!(m < top)) {
                break;
            }
            mb[c] = m;
            hb->nc = c;
        }
        hb->nc += 1;
        mb[hb->nc] = top > mb[hb->nc - 1] ? top : mb[hb->nc - 1];
    }
    for (q = 0; q < hb->nq; ++q) {
        const double s = sq_lo[q];
        npts += hb->npts[q];
        hb->steps[q][0] = 0;
        hb->nj[q] = 0;
        for (j = 1; j <= TRN_HB_MAX_J; ++j) { /* until a step reaches every offset */
            if (step_sd(j - 1) * s >= width + 2.0 * hb->w) {
                break;
            }
            hb->steps[q][j] = (int32_t)fmin(ceil(step_sd(j) * s / hb->w), (double)TRN_HB_MAX_BINS);
            hb->nj[q] = j;
        }
        for (c = 0; c < hb->nc; ++c) {
            double fprev = f_step(hb, 0.0, s, sq_hi[q], mb[c], mb[c + 1]);
            double *df = hb->df + ((size_t)q * TRN_HB_MAX_C + (size_t)c) * TRN_HB_MAX_J;
            fmaxabs = fmax(fmaxabs, fabs(fprev));
            for (j = 0; j < hb->nj[q]; ++j) {
                const double fn = f_step(hb, step_sd(j + 1) * s, s, sq_hi[q], mb[c], mb[c + 1]);
                df[j] = fprev - fn;
                fprev = fn;
            }
            hb->ft[(size_t)q * TRN_HB_MAX_C + (size_t)c] = fprev;
        }
    }
    /* rounding: the bound's sum and the score's differ by far less */
    hb->tol = 1e-9 * (double)(npts + 1) * (fmaxabs + 1.0) + 1e-9;
}

/* The bound over offset bins [b0, b1] of the node whose counts are in cl/ch
 * (cumulative over [bmin, bmax]), nq its points per class, nout its points
 * with no map. */
static double range_bound(trn_hb_t *hb, int32_t b0, int32_t b1, int32_t bmin, int32_t bmax,
                          const int32_t *nq, int32_t nout)
{
    double best = -(double)INFINITY;
    int32_t q, c, j;
    for (q = 0; q < hb->nq; ++q) {
        const uint32_t *cl = hb->cl + (size_t)q * TRN_HB_MAX_BINS;
        const uint32_t *ch = hb->ch + (size_t)q * TRN_HB_MAX_BINS;
        int32_t *cnt = hb->cnt + (size_t)q * (TRN_HB_MAX_J + 1);
        if (nq[q] == 0) {
            continue;
        }
        /* a cell may lie within t_j sds of an offset in the bins [b0, b1]
         * (its ends in bins L <= H) iff L <= b1 + s and H >= b0 - s, s =
         * t_j sd / w rounded up */
        for (j = 1; j <= hb->nj[q]; ++j) {
            const int32_t s = hb->steps[q][j];
            const int32_t hi = b1 + s, lo = b0 - s - 1;
            const int32_t a = hi >= bmax ? nq[q] : (int32_t)cl[hi];
            const int32_t b = lo < bmin ? 0 : (int32_t)ch[lo > bmax ? bmax : lo];
            cnt[j] = a - b;
        }
    }
    for (c = 0; c < hb->nc; ++c) {
        double sum = (double)nout * hb->lout;
        for (q = 0; q < hb->nq; ++q) {
            const double *df = hb->df + ((size_t)q * TRN_HB_MAX_C + (size_t)c) * TRN_HB_MAX_J;
            const int32_t *cnt = hb->cnt + (size_t)q * (TRN_HB_MAX_J + 1);
            if (nq[q] == 0) {
                continue;
            }
            sum += (double)nq[q] * hb->ft[(size_t)q * TRN_HB_MAX_C + (size_t)c];
            for (j = 0; j < hb->nj[q]; ++j) {
                sum += df[j] * (double)cnt[j + 1];
            }
        }
        best = sum > best ? sum : best;
    }
    return best;
}

/* An upper bound on ln L over the poses of node (l, bx, by); the search
 * over offsets stops once a single bin reaches t (the node is then not
 * pruned, and the bound of all its offsets is returned). */
static double node_bound(trn_hb_t *hb, int32_t l, int32_t bx, int32_t by, double t)
{
    const int32_t ox = bx * k_pow2[l], oy = by * k_pow2[l];
    const float *mn = hb->mn[l], *mx = hb->mx[l];
    int32_t nq[TRN_HB_MAX_Q], nout = 0, bmin = hb->nbins, bmax = -1, x, y, q, sp = 0;
    double best = -(double)INFINITY, root;
    for (q = 0; q < hb->nq; ++q) {
        nq[q] = 0;
    }
    hb->bounds += 1u;
    for (y = 0; y < hb->local->height; ++y) {
        const size_t row = (size_t)(oy + y) * (size_t)hb->rw + (size_t)ox;
        for (x = 0; x < hb->local->width; ++x) {
            const uint8_t k = hb->cls[(size_t)y * (size_t)hb->local->width + (size_t)x];
            double h;
            int32_t lb, hbn;
            if (k == 255u) {
                continue;
            }
            if (mn[row + (size_t)x] > mx[row + (size_t)x]) {
                ++nout;
                continue;
            }
            h = (double)TRN_GRID_AT(hb->local, x, y);
            lb = bin_of(hb, h - (double)mx[row + (size_t)x]);
            hbn = bin_of(hb, h - (double)mn[row + (size_t)x]);
            if (lb < bmin) {
                bmin = lb;
            }
            if (hbn > bmax) {
                bmax = hbn;
            }
            hb->cl[(size_t)k * TRN_HB_MAX_BINS + (size_t)lb] += 1u;
            hb->ch[(size_t)k * TRN_HB_MAX_BINS + (size_t)hbn] += 1u;
            nq[k] += 1;
        }
    }
    if (bmax < 0) { /* no cell over the map anywhere in the node */
        return (double)nout * hb->lout + hb->tol;
    }
    for (q = 0; q < hb->nq; ++q) { /* cumulative counts over [bmin, bmax] */
        uint32_t *cl = hb->cl + (size_t)q * TRN_HB_MAX_BINS,
                 *ch = hb->ch + (size_t)q * TRN_HB_MAX_BINS;
        int32_t b;
        for (b = bmin + 1; b <= bmax; ++b) {
            cl[b] += cl[b - 1];
            ch[b] += ch[b - 1];
        }
    }
    /* offset ranges whose bound is below t are done with (the node's
     * bound is then the highest of theirs); one bin at t or above: the
     * node is not pruned, and its bound is that of all its offsets */
    root = range_bound(hb, bmin, bmax, bmin, bmax, nq, nout);
    hb->rstack[sp++] = bmin;
    hb->rstack[sp++] = bmax;
    while (sp > 0) {
        const int32_t b1 = hb->rstack[--sp], b0 = hb->rstack[--sp];
        const double v = b0 == bmin && b1 == bmax ? root
                                                  : range_bound(hb, b0, b1, bmin, bmax, nq, nout);
        int32_t mid;
        if (v + hb->tol < t) {
            best = v > best ? v : best;
            continue;
        }
        if (b0 == b1) {
            best = root;
            break;
        }
        mid = b0 + (b1 - b0) / 2;
        hb->rstack[sp++] = b0;
        hb->rstack[sp++] = mid;
        hb->rstack[sp++] = mid + 1;
        hb->rstack[sp++] = b1;
    }
    for (q = 0; q < hb->nq; ++q) { /* clear the counts for the next node */
        memset(hb->cl + (size_t)q * TRN_HB_MAX_BINS + (size_t)bmin, 0,
               (size_t)(bmax - bmin + 1) * sizeof(uint32_t));
        memset(hb->ch + (size_t)q * TRN_HB_MAX_BINS + (size_t)bmin, 0,
               (size_t)(bmax - bmin + 1) * sizeof(uint32_t));
    }
    return best + hb->tol;
}

static size_t node_at(const trn_hb_t *hb, int32_t l, int32_t bx, int32_t by)
{
    const int32_t nx = (hb->ww + k_pow2[l] - 1) / k_pow2[l];
    return (size_t)by * (size_t)nx + (size_t)bx;
}

/* The node's bound (computed now if not yet, never above its parent's). */
static double node_ub(trn_hb_t *hb, int32_t l, int32_t bx, int32_t by, double t)
{
    double *u = &hb->ub[l][node_at(hb, l, bx, by)];
    if (isnan(*u)) {
        double v = node_bound(hb, l, bx, by, t);
        if (l + 1 < hb->levels) {
            const double p = hb->ub[l + 1][node_at(hb, l + 1, bx / 2, by / 2)];
            v = !isnan(p) && p < v ? p : v;
        }
        *u = v;
    }
    return *u;
}

/* The tightest bound computed for pose (x, y). */
static double pose_ub(const trn_hb_t *hb, int32_t x, int32_t y)
{
    const int32_t px = x - hb->win.x0, py = y - hb->win.y0;
    int32_t l;
    for (l = 0; l < hb->levels; ++l) {
        const double u = hb->ub[l][node_at(hb, l, px / k_pow2[l], py / k_pow2[l])];
        if (!isnan(u)) {
            return u;
        }
    }
    return (double)INFINITY;
}

static int in_zone(const trn_exclusion_t *ex, int32_t x, int32_t y)
{
    return ex != NULL && abs(x - ex->cx) <= ex->radius && abs(y - ex->cy) <= ex->radius;
}

trn_status_t trn_hb_eval(trn_hb_t *hb, int32_t x, int32_t y)
{
    const size_t at = pidx(hb, x, y);
    double dz = 0.0, m = 0.0;
    if (hb->done[at] != 0u) {
        return TRN_OK;
    }
    if (hb->budget != 0u && *hb->work >= hb->budget) {
        return TRN_E_BUDGET;
    }
    *hb->work += 1u;
    hb->evals += 1u;
    hb->ll[at] = trn_hs_ll(&hb->hs, x, y, &dz, &m);
    hb->dz[at] = dz;
    hb->msd[at] = m;
    hb->done[at] = 1u;
    return TRN_OK;
}

trn_status_t trn_hb_eval_zone(trn_hb_t *hb, int32_t cx, int32_t cy, int32_t radius)
{
    int32_t x, y;
    trn_status_t st;
    for (y = cy - radius; y <= cy + radius; ++y) {
        for (x = cx - radius; x <= cx + radius; ++x) {
            if (x >= hb->win.x0 && x <= hb->win.x1 && y >= hb->win.y0 && y <= hb->win.y1 &&
                (st = trn_hb_eval(hb, x, y)) != TRN_OK) {
                return st;
            }
        }
    }
    return TRN_OK;
}

/* The highest scored pose outside ex (ties: scan order); 0 if none. */
static int scored_best(const trn_hb_t *hb, const trn_exclusion_t *ex, int32_t *bx, int32_t *by)
{
    int32_t x, y, found = 0;
    double v = 0.0;
    for (y = hb->win.y0; y <= hb->win.y1; ++y) {
        for (x = hb->win.x0; x <= hb->win.x1; ++x) {
            const size_t at = pidx(hb, x, y);
            if (hb->done[at] == 0u || in_zone(ex, x, y)) {
                continue;
            }
            if (!found || hb->ll[at] > v) {
                v = hb->ll[at];
                *bx = x;
                *by = y;
                found = 1;
            }
        }
    }
    return found;
}

/* 1 if node (l, bx, by) lies inside the zone ex. */
static int node_in_zone(const trn_hb_t *hb, const trn_exclusion_t *ex, int32_t l, int32_t bx,
                        int32_t by)
{
    const int32_t x0 = hb->win.x0 + bx * k_pow2[l], y0 = hb->win.y0 + by * k_pow2[l];
    int32_t x1 = x0 + k_pow2[l] - 1, y1 = y0 + k_pow2[l] - 1;
    x1 = x1 > hb->win.x1 ? hb->win.x1 : x1;
    y1 = y1 > hb->win.y1 ? hb->win.y1 : y1;
    return ex != NULL && x0 >= ex->cx - ex->radius && x1 <= ex->cx + ex->radius &&
           y0 >= ex->cy - ex->radius && y1 <= ex->cy + ex->radius;
}

/* Score every pose outside ex whose bound reaches t, or (dynamic) the
 * highest scored pose outside ex, whichever is higher. */
static trn_status_t walk(trn_hb_t *hb, double t, const trn_exclusion_t *ex, int dynamic)
{
    int32_t sp = 0, top = hb->levels - 1;
    double inc = -(double)INFINITY;
    trn_status_t st;
    if (dynamic) {
        int32_t ix = 0, iy = 0;
        if (scored_best(hb, ex, &ix, &iy)) {
            inc = hb->ll[pidx(hb, ix, iy)];
        }
    }
    hb->stack[sp++] = top;
    hb->stack[sp++] = 0;
    hb->stack[sp++] = 0;
    while (sp > 0) {
        const int32_t by = hb->stack[--sp], bx = hb->stack[--sp], l = hb->stack[--sp];
        const double thr = inc > t ? inc : t;
        double cu[4];
        int32_t cx[4], cy[4], n = 0, i, j;
        if (node_in_zone(hb, ex, l, bx, by) || node_ub(hb, l, bx, by, thr) < thr) {
            continue;
        }
        if (l <= hb->leaf) {
            const int32_t x0 = hb->win.x0 + bx * k_pow2[l], y0 = hb->win.y0 + by * k_pow2[l];
            int32_t x, y;
            for (y = y0; y < y0 + k_pow2[l] && y <= hb->win.y1; ++y) {
                for (x = x0; x < x0 + k_pow2[l] && x <= hb->win.x1; ++x) {
                    if (in_zone(ex, x, y)) {
                        continue;
                    }
                    if ((st = trn_hb_eval(hb, x, y)) != TRN_OK) {
                        return st;
                    }
                    if (dynamic && hb->ll[pidx(hb, x, y)] > inc) {
                        inc = hb->ll[pidx(hb, x, y)];
                    }
                }
            }
            continue;
        }
        for (i = 0; i < 4; ++i) { /* the children inside the window, bounded */
            const int32_t x = 2 * bx + i % 2, y = 2 * by + i / 2;
            if (x * k_pow2[l - 1] >= hb->ww || y * k_pow2[l - 1] >= hb->wh) {
                continue;
            }
            if (isnan(hb->ub[l - 1][node_at(hb, l - 1, x, y)])) {
                if (hb->budget != 0u && *hb->work >= hb->budget) {
                    return TRN_E_BUDGET;
                }
                *hb->work += 1u;
            }
            cu[n] = node_ub(hb, l - 1, x, y, thr);
            cx[n] = x;
            cy[n] = y;
            ++n;
        }
        for (i = 1; i < n; ++i) { /* ascending, so the highest is taken first */
            for (j = i; j > 0 && cu[j - 1] > cu[j]; --j) {
                const double u = cu[j];
                const int32_t a = cx[j], b = cy[j];
                cu[j] = cu[j - 1];
                cx[j] = cx[j - 1];
                cy[j] = cy[j - 1];
                cu[j - 1] = u;
                cx[j - 1] = a;
                cy[j - 1] = b;
            }
        }
        for (i = 0; i < n; ++i) {
            hb->stack[sp++] = l - 1;
            hb->stack[sp++] = cx[i];
            hb->stack[sp++] = cy[i];
        }
    }
    return TRN_OK;
}

trn_status_t trn_hb_resolve(trn_hb_t *hb, double t, const trn_exclusion_t *ex)
{
    return walk(hb, t, ex, 0);
}

trn_status_t trn_hb_best(trn_hb_t *hb, const trn_exclusion_t *ex, trn_height_best_t *best)
{
    trn_status_t st;
    int32_t x = 0, y = 0;
    if ((st = walk(hb, -(double)INFINITY, ex, 1)) != TRN_OK) {
        return st;
    }
    best->poses = hb->evals;
    best->lse_all = best->lse_out = (double)NAN;
    if (!scored_best(hb, ex, &x, &y)) {
        return TRN_E_NODATA;
    }
    best->x = x;
    best->y = y;
    best->ll = hb->ll[pidx(hb, x, y)];
    best->dz_m = hb->dz[pidx(hb, x, y)];
    best->model_m = hb->msd[pidx(hb, x, y)];
    return TRN_OK;
}

trn_status_t trn_hb_basins(trn_hb_t *hb, double t, int32_t bx, int32_t by, int32_t radius,
                           int32_t nbasins)
{
    trn_exclusion_t ex;
    trn_status_t st;
    uint64_t before;
    /* at most the slots of trn_loc_basins_t */
    const int32_t nb = nbasins < 0 ? 0 : nbasins > TRN_REFINE_BASINS ? TRN_REFINE_BASINS : nbasins;
    ex.cx = bx;
    ex.cy = by;
    ex.radius = radius;
    do {
        double top[TRN_REFINE_BASINS], thr = t;
        int32_t n = 0, x, y, i;
        for (i = 0; i < TRN_REFINE_BASINS; ++i) {
            top[i] = -(double)INFINITY;
        }
        before = hb->evals;
        /* the nb-th highest local maximum outside the zone, so far */
        for (y = hb->win.y0; y <= hb->win.y1; ++y) {
            for (x = hb->win.x0; x <= hb->win.x1; ++x) {
                const double v = hb->ll[pidx(hb, x, y)];
                if (hb->done[pidx(hb, x, y)] == 0u || in_zone(&ex, x, y) || v < t ||
                    !trn_loc_grid_peak_(hb->ll, &hb->win, x, y, v)) {
                    continue;
                }
                if (n < nb) {
                    top[n++] = v;
                } else {
                    int32_t lo = 0;
                    for (i = 1; i < n; ++i) {
                        lo = top[i] < top[lo] ? i : lo;
                    }
                    top[lo] = v > top[lo] ? v : top[lo];
                }
            }
        }
        if (n == nb && n > 0) {
            double lo = top[0];
            for (i = 1; i < n; ++i) {
                lo = top[i] < lo ? top[i] : lo;
            }
            thr = lo > thr ? lo : thr;
        }
        if ((st = walk(hb, thr, &ex, 0)) != TRN_OK) {
            return st;
        }
        /* a scored pose that may be one: its neighbours that could be
         * higher are scored */
        for (y = hb->win.y0; y <= hb->win.y1; ++y) {
            for (x = hb->win.x0; x <= hb->win.x1; ++x) {
                const double v = hb->ll[pidx(hb, x, y)];
                int32_t k;
                if (hb->done[pidx(hb, x, y)] == 0u || in_zone(&ex, x, y) || v < thr) {
                    continue;
                }
                for (k = 0; k < 9; ++k) {
                    const int32_t nx = x + k % 3 - 1, ny = y + k / 3 - 1;
                    if (k == 4 || nx < hb->win.x0 || nx > hb->win.x1 || ny < hb->win.y0 ||
                        ny > hb->win.y1 || hb->done[pidx(hb, nx, ny)] != 0u) {
                        continue;
                    }
                    if (pose_ub(hb, nx, ny) >= v && (st = trn_hb_eval(hb, nx, ny)) != TRN_OK) {
                        return st;
                    }
                }
            }
        }
    } while (hb->evals != before);
    return TRN_OK;
}

/* Sums of exp(ln L / infl - top) over the scored poses, all and outside ex. */
static double scored_mass(const trn_hb_t *hb, const trn_exclusion_t *ex, double infl, double *s_all,
                          double *s_out)
{
    double top = -(double)INFINITY;
    size_t i;
    const size_t poses = (size_t)hb->ww * (size_t)hb->wh;
    for (i = 0; i < poses; ++i) {
        if (hb->done[i] != 0u && hb->ll[i] / infl > top) {
            top = hb->ll[i] / infl;
        }
    }
    *s_all = *s_out = 0.0;
    for (i = 0; i < poses; ++i) {
        if (hb->done[i] != 0u) {
            const double e = exp(hb->ll[i] / infl - top);
            const int32_t x = hb->win.x0 + (int32_t)(i % (size_t)hb->ww);
            const int32_t y = hb->win.y0 + (int32_t)(i / (size_t)hb->ww);
            *s_all += e;
            if (!in_zone(ex, x, y)) {
                *s_out += e;
            }
        }
    }
    return top;
}

trn_status_t trn_hb_mass(trn_hb_t *hb, const trn_exclusion_t *ex, double infl, double eps,
                         double *lse_all, double *lse_out, double *err)
{
    const double poses = (double)hb->ww * (double)hb->wh;
    double s_all, s_out, top, u = 0.0;
    int32_t sp = 0;
    trn_status_t st;
    top = scored_mass(hb, ex, infl, &s_all, &s_out);
    if (!isfinite(top)) {
        return TRN_E_NODATA;
    }
    if ((st = walk(hb, infl * (top + log(s_all) + log(eps / poses)), NULL, 0)) != TRN_OK) {
        return st;
    }
    top = scored_mass(hb, ex, infl, &s_all, &s_out);
    /* the unscored poses' mass: each at the bound of the finest node
     * bounded over it */
    hb->stack[sp++] = hb->levels - 1;
    hb->stack[sp++] = 0;
    hb->stack[sp++] = 0;
    while (sp > 0) {
        const int32_t by = hb->stack[--sp], bx = hb->stack[--sp], l = hb->stack[--sp];
        int32_t i, split = l > 0, x, y, left = 0;
        for (i = 0; i < 4 && split; ++i) {
            const int32_t cx = 2 * bx + i % 2, cy = 2 * by + i / 2;
            if (cx * k_pow2[l - 1] < hb->ww && cy * k_pow2[l - 1] < hb->wh &&
                isnan(hb->ub[l - 1][node_at(hb, l - 1, cx, cy)])) {
                split = 0;
            }
        }
        if (split) {
            for (i = 0; i < 4; ++i) {
                const int32_t cx = 2 * bx + i % 2, cy = 2 * by + i / 2;
                if (cx * k_pow2[l - 1] < hb->ww && cy * k_pow2[l - 1] < hb->wh) {
                    hb->stack[sp++] = l - 1;
                    hb->stack[sp++] = cx;
                    hb->stack[sp++] = cy;
                }
            }
            continue;
        }
        for (y = by * k_pow2[l]; y < (by + 1) * k_pow2[l] && y < hb->wh; ++y) {
            for (x = bx * k_pow2[l]; x < (bx + 1) * k_pow2[l] && x < hb->ww; ++x) {
                left += hb->done[(size_t)y * (size_t)hb->ww + (size_t)x] == 0u;
            }
        }
        if (left > 0) {
            const double b = hb->ub[l][node_at(hb, l, bx, by)];
            u += (double)left * exp((isnan(b) ? (double)INFINITY : b) / infl - top);
        }
    }
    *lse_all = top + log(s_all + u);
    *lse_out = top + log(s_out + u);
    *err = u / s_all;
    return TRN_OK;
}

trn_status_t trn_hb_init(trn_hb_t **out, void *ws, const trn_grid_f32_t *global,
                         const trn_grid_f32_t *local, int32_t rx, int32_t ry,
                         const trn_window_t *win, const trn_refine_cfg_t *cfg, float inlier_prob,
                         double *ll_grid, uint64_t *work, uint64_t budget)
{
    hb_layout_t lay;
    uint8_t *b = (uint8_t *)ws;
    trn_hb_t *hb;
    double sq_lo[TRN_HB_MAX_Q], sq_hi[TRN_HB_MAX_Q], smin = (double)INFINITY, spread, z1;
    int32_t x, y, l, q, n_seen = 0;
    size_t i, poses;
    if (!hb_layout(win, local->width, local->height, &lay)) {
        return TRN_E_RANGE;
    }
    hb = (trn_hb_t *)(void *)(b + lay.hb);
    *out = hb;
    hb->global = global;
    hb->local = local;
    hb->rx = rx;
    hb->ry = ry;
    hb->win = *win;
    hb->cfg = *cfg;
    hb->a = (double)inlier_prob;
    hb->ww = lay.ww;
    hb->wh = lay.wh;
    hb->levels = lay.levels;
    hb->rw = lay.rw;
    hb->rh = lay.rh;
    hb->ll = ll_grid;
    hb->dz = (double *)(void *)(b + lay.dz);
    hb->msd = (double *)(void *)(b + lay.msd);
    hb->done = b + lay.done;
    for (l = 0; l < lay.levels; ++l) {
        const size_t nx = (size_t)((lay.ww + k_pow2[l] - 1) / k_pow2[l]);
        const size_t ny = (size_t)((lay.wh + k_pow2[l] - 1) / k_pow2[l]);
        hb->ub[l] = (double *)(void *)(b + lay.ub[l]);
        hb->mn[l] = (float *)(void *)(b + lay.mn[l]);
        hb->mx[l] = (float *)(void *)(b + lay.mx[l]);
        for (i = 0; i < nx * ny; ++i) {
            hb->ub[l][i] = (double)NAN;
        }
    }
    hb->cls = b + lay.cls;
    (void)trn_hs_init(&hb->hs, b + lay.hs, global, local, rx, ry, cfg, hb->a);
    hb->cl = (uint32_t *)(void *)(b + lay.cl);
    hb->ch = (uint32_t *)(void *)(b + lay.ch);
    hb->cnt = (int32_t *)(void *)(b + lay.cnt);
    hb->stack = (int32_t *)(void *)(b + lay.stack);
    hb->rstack = (int32_t *)(void *)(b + lay.rstack);
    hb->df = (double *)(void *)(b + lay.df);
    hb->ft = (double *)(void *)(b + lay.ft);
    hb->evals = hb->bounds = 0u;
    hb->work = work;
    hb->budget = budget;
    memset(hb->cl, 0, (size_t)TRN_HB_MAX_Q * TRN_HB_MAX_BINS * sizeof(uint32_t));
    memset(hb->ch, 0, (size_t)TRN_HB_MAX_Q * TRN_HB_MAX_BINS * sizeof(uint32_t));
    poses = (size_t)lay.ww * (size_t)lay.wh;
    for (i = 0; i < poses; ++i) {
        hb->ll[i] = -(double)INFINITY;
        hb->done[i] = 0u;
    }
    /* the exhaustive search's outlier density and its NODATA rule */
    spread = trn_refine_local_spread_(local, &n_seen);
    if (n_seen < 8) {
        return TRN_E_NODATA;
    }
    hb->leaf = HB_LEAF;
    while (hb->leaf < lay.levels - 1 &&
           (double)k_pow2[hb->leaf] * (double)k_pow2[hb->leaf] * (double)n_seen < HB_LEAF_WORK) {
        hb->leaf += 1;
    }
    hb->k = 1.0 / (10.0 * (spread > (double)cfg->noise_m ? spread : (double)cfg->noise_m));
    hb->lout = log((1.0 - hb->a) * hb->k);
    /* noise classes: sds within HB_Q_RATIO of the least */
    for (y = 0; y < local->height; ++y) {
        for (x = 0; x < local->width; ++x) {
            if (isfinite(TRN_GRID_AT(local, x, y))) {
                const double s = sqrt(trn_refine_noise_var_(cfg, x, y, rx, ry));
                smin = s < smin ? s : smin;
            }
        }
    }
    hb->nq = 1;
    for (q = 0; q < TRN_HB_MAX_Q; ++q) {
        sq_lo[q] = (double)INFINITY;
        sq_hi[q] = 0.0;
        hb->npts[q] = 0;
    }
    for (y = 0; y < local->height; ++y) {
        for (x = 0; x < local->width; ++x) {
            const size_t at = (size_t)y * (size_t)local->width + (size_t)x;
            double s;
            if (!isfinite(TRN_GRID_AT(local, x, y))) {
                hb->cls[at] = 255u;
                continue;
            }
            s = sqrt(trn_refine_noise_var_(cfg, x, y, rx, ry));
            q = (int32_t)floor(log(s / smin) / log(HB_Q_RATIO));
            q = q < 0 ? 0 : q >= TRN_HB_MAX_Q ? TRN_HB_MAX_Q - 1 : q;
            hb->cls[at] = (uint8_t)q;
            sq_lo[q] = s < sq_lo[q] ? s : sq_lo[q];
            sq_hi[q] = s > sq_hi[q] ? s : sq_hi[q];
            hb->npts[q] += 1;
            hb->nq = q + 1 > hb->nq ? q + 1 : hb->nq;
        }
    }
    for (q = 0; q < hb->nq; ++q) { /* an empty class: any sd (it has no points) */
        if (hb->npts[q] == 0) {
            sq_lo[q] = sq_hi[q] = smin;
        }
    }
    build_region(hb);
    /* the offsets: every residual over the whole window */
    hb->z0 = (double)INFINITY;
    z1 = -(double)INFINITY;
    {
        const int32_t top = lay.levels - 1;
        for (y = 0; y < local->height; ++y) {
            for (x = 0; x < local->width; ++x) {
                const size_t at = (size_t)y * (size_t)lay.rw + (size_t)x;
                const double h = (double)TRN_GRID_AT(local, x, y);
                if (!isfinite(h) || hb->mn[top][at] > hb->mx[top][at]) {
                    continue;
                }
                hb->z0 = fmin(hb->z0, h - (double)hb->mx[top][at]);
                z1 = fmax(z1, h - (double)hb->mn[top][at]);
            }
        }
    }
    if (!isfinite(hb->z0)) { /* no seen cell over the map at any pose */
        hb->z0 = z1 = 0.0;
    }
    hb->w = fmax((z1 - hb->z0) / (double)(TRN_HB_MAX_BINS - 8), HB_BIN_SD * smin);
    hb->nbins = (int32_t)floor((z1 - hb->z0) / hb->w) + 2;
    hb->nbins = hb->nbins > TRN_HB_MAX_BINS ? TRN_HB_MAX_BINS : hb->nbins;
    build_tables(hb, sq_lo, sq_hi, z1);
    return TRN_OK;
}
