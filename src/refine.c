/* SPDX-License-Identifier: Apache-2.0 */
/* refine.c - continuous sub-cell pose refinement over heights (trn/refine.h). */
#include "trn/refine.h"

#include <math.h>
#include <stdlib.h>

#include "height_score.h"
#include "refine_int.h"

/* cos and sin of an angle (finite), by the Taylor series after reduction to
 * about [-pi, pi] (a - 2 pi round(a / 2 pi): exact for a = 0, within
 * 1e-15 rad for |a| <= 4 pi, the headings here; a turn of many revolutions
 * loses the bits of its multiple of 2 pi). libm's cos and sin reduce any
 * argument exactly (Payne-Hanek), which costs them 1 KiB of stack
 * (tools/stack/external.txt); this needs none. Error of the series below
 * 1e-14: its terms are at most pi^6 / 6! = 1.3 in size. */
void trn_heading_trig_(double a, double *c, double *s)
{
    const double two_pi = 6.283185307179586;
    double x = a - two_pi * floor(a / two_pi + 0.5), term_c = 1.0, term_s, sc = 0.0, ss = 0.0;
    int32_t n;
    term_s = x;
    for (n = 0; n < 30; ++n) {
        sc += term_c;
        ss += term_s;
        term_c *= -x * x / (double)((2 * n + 1) * (2 * n + 2));
        term_s *= -x * x / (double)((2 * n + 2) * (2 * n + 3));
    }
    *c = sc;
    *s = ss;
}

/* Bilinear height at fractional cell (x, y) (centres at integers) and its
 * exact gradient (per cell) inside the containing cell; 0 when a corner is
 * off the grid or missing. */
static int sample_bilinear(const trn_grid_f32_t *g, double x, double y, double out[3])
{
    double fx, fy, a, b, c, d;
    int32_t x0, y0;
    if (!(x >= 0.0 && y >= 0.0 && x <= (double)(g->width - 1) && y <= (double)(g->height - 1)) ||
        g->width < 2 || g->height < 2) {
        return 0;
    }
    x0 = (int32_t)floor(x);
    y0 = (int32_t)floor(y);
    x0 = x0 > g->width - 2 ? g->width - 2 : x0;
    y0 = y0 > g->height - 2 ? g->height - 2 : y0;
    fx = x - (double)x0;
    fy = y - (double)y0;
    a = (double)TRN_GRID_AT(g, x0, y0);
    b = (double)TRN_GRID_AT(g, x0 + 1, y0);
    c = (double)TRN_GRID_AT(g, x0, y0 + 1);
    d = (double)TRN_GRID_AT(g, x0 + 1, y0 + 1);
    if (!isfinite(a) || !isfinite(b) || !isfinite(c) || !isfinite(d)) {
        return 0;
    }
    out[0] = (a * (1.0 - fx) + b * fx) * (1.0 - fy) + (c * (1.0 - fx) + d * fx) * fy;
    out[1] = (b - a) * (1.0 - fy) + (d - c) * fy;
    out[2] = (c - a) * (1.0 - fx) + (d - b) * fx;
    return 1;
}

/* The weight rule of every refinement pass (a factor on 1 / sd^2): a
 * residual res of standard deviation sd at fractional cell (x, y) within
 * clip sds has weight 1; beyond clip sds plus the relief of the map's four
 * cells around (x, y) (their highest less their lowest) it is an outlier,
 * weight 0; between, Huber's weight clip sd / |res| (its pull on the pose
 * bounded at that of a residual of clip sds). Between its samples the
 * terrain may run anywhere the neighbouring samples span (a rock's edge, a
 * kerb the map cannot resolve), so such a residual is representation error
 * or a blunder of the terrain's own size: the former carry the most
 * information on the pose, and dropping them made the refined pose worse
 * whenever the local map was sensed from terrain finer than the map; the
 * bounded pull keeps the latter (a changed patch of the map) from moving
 * it (docs/method.md 9, "the clip"). A gross error beyond the local relief
 * is still clipped; on flat ground the rule is the plain clip.
 * A clip >= 0 is the plain clip (clip sds: the refinement's first phase;
 * from an integer start the linearization is poor on terrain a cell wide,
 * and the large residuals there are the start's, not the terrain's);
 * TRN_REFINE_CLIP_RELIEF (-TRN_REFINE_CLIP) is the rule above, the second
 * phase's, from the first phase's estimate. */
double trn_refine_weight_(const trn_grid_f32_t *g, double x, double y, double res, double sd,
                          double clip)
{
    int32_t x0, y0;
    float a, b, c, d, lo, hi;
    const double k = fabs(clip);
    if (clip >= 0.0) {
        return fabs(res) > k * sd ? 0.0 : 1.0; /* the plain clip */
    }
    if (!(fabs(res) > k * sd)) {
        return 1.0;
    }
    /* sample_bilinear's cell lookup, written out: a shared function added a
     * frame under the heading refinement's deepest chain, which then met
     * TRN_STACK_LIMIT_BYTES exactly (2048, host-release) */
    if (!(x >= 0.0 && y >= 0.0 && x <= (double)(g->width - 1) && y <= (double)(g->height - 1)) ||
        g->width < 2 || g->height < 2) {
        return 0.0;
    }
    x0 = (int32_t)floor(x);
    y0 = (int32_t)floor(y);
    x0 = x0 > g->width - 2 ? g->width - 2 : x0;
    y0 = y0 > g->height - 2 ? g->height - 2 : y0;
    a = TRN_GRID_AT(g, x0, y0);
    b = TRN_GRID_AT(g, x0 + 1, y0);
    c = TRN_GRID_AT(g, x0, y0 + 1);
    d = TRN_GRID_AT(g, x0 + 1, y0 + 1);
    lo = a < b ? a : b;
    lo = lo < c ? lo : c;
    lo = lo < d ? lo : d;
    hi = a > b ? a : b;
    hi = hi > c ? hi : c;
    hi = hi > d ? hi : d;
    return fabs(res) > k * sd + ((double)hi - (double)lo) ? 0.0 : k * sd / fabs(res);
}

/* Keys' cubic convolution kernel (a = -1/2) at t and its derivative. */
static void keys(double t, double *w, double *dw)
{
    double u = fabs(t), sg = t < 0.0 ? -1.0 : 1.0;
    if (u < 1.0) {
        *w = 1.5 * u * u * u - 2.5 * u * u + 1.0;
        *dw = sg * (4.5 * u * u - 5.0 * u);
    } else if (u < 2.0) {
        *w = -0.5 * u * u * u + 2.5 * u * u - 4.0 * u + 2.0;
        *dw = sg * (-1.5 * u * u + 5.0 * u - 4.0);
    } else {
        *w = 0.0;
        *dw = 0.0;
    }
}

/* Height and gradient at (x, y) by bicubic convolution over the 4 x 4 cells
 * around it (exact for quadratics, error O(h^3) on smooth terrain against
 * bilinear's O(h^2)); bilinear where the 4 x 4 support is incomplete. */
static int sample(const trn_grid_f32_t *g, double x, double y, double out[3])
{
    double wx[4], dwx[4], wy[4], dwy[4];
    int32_t x0, y0, i, j;
    if (!(x >= 1.0 && y >= 1.0 && x < (double)(g->width - 2) && y < (double)(g->height - 2))) {
        return sample_bilinear(g, x, y, out);
    }
    x0 = (int32_t)floor(x);
    y0 = (int32_t)floor(y);
    for (i = 0; i < 4; ++i) {
        keys(x - (double)(x0 - 1 + i), &wx[i], &dwx[i]);
        keys(y - (double)(y0 - 1 + i), &wy[i], &dwy[i]);
    }
    out[0] = out[1] = out[2] = 0.0;
    for (j = 0; j < 4; ++j) {
        for (i = 0; i < 4; ++i) {
            double v = (double)TRN_GRID_AT(g, x0 - 1 + i, y0 - 1 + j);
            if (!isfinite(v)) {
                return sample_bilinear(g, x, y, out);
            }
            out[0] += wx[i] * wy[j] * v;
            out[1] += dwx[i] * wy[j] * v;
            out[2] += wx[i] * dwy[j] * v;
        }
    }
    return 1;
}

/* Inverse of the symmetric 3x3 matrix a (a[0..8] row-major); 0 if singular
 * relative to its diagonal. */
static int inv3(const double a[9], double r[9])
{
    double c00 = a[4] * a[8] - a[5] * a[7];
    double c01 = a[5] * a[6] - a[3] * a[8];
    double c02 = a[3] * a[7] - a[4] * a[6];
    double det = a[0] * c00 + a[1] * c01 + a[2] * c02;
    double scale = a[0] * a[4] * a[8];
    if (!(scale > 0.0) || !(det > 1e-9 * scale) || !isfinite(det)) {
        return 0;
    }
    r[0] = c00 / det;
    r[1] = (a[2] * a[7] - a[1] * a[8]) / det;
    r[2] = (a[1] * a[5] - a[2] * a[4]) / det;
    r[3] = c01 / det;
    r[4] = (a[0] * a[8] - a[2] * a[6]) / det;
    r[5] = (a[2] * a[3] - a[0] * a[5]) / det;
    r[6] = c02 / det;
    r[7] = (a[1] * a[6] - a[0] * a[7]) / det;
    r[8] = (a[0] * a[4] - a[1] * a[3]) / det;
    return 1;
}

typedef struct {
    double a[9], b[3];   /* normal matrix and right-hand side */
    double ss;           /* sum of squared normalized residuals of the inliers */
    double rr, noise2;   /* sums of q r^2 and of q s^2 over the inliers, q = 1 / (s^2 + m^2)^2 */
    double q;            /* sum of q */
    double vv;           /* sum of q^2 2 s^4: the variance of rr - noise2 if m were 0 */
    double al[3], all;   /* the interpolants' mix column: its cross terms and its own term */
    double bl;           /* its right-hand side */
    int32_t n_in, n_all; /* inliers, points with a global height */
} accum_t;

/* Height and gradient of the mixed interpolant B + lam (C - B) at (x, y)
 * (B bilinear, C bicubic; they agree where the 4 x 4 support is
 * incomplete: there C - B = 0), and C - B, the derivative in lam. */
static int sample_mix(const trn_grid_f32_t *g, double x, double y, double lam, double out[3],
                      double *dcb)
{
    double b3[3];
    int32_t k;
    if (!sample(g, x, y, out)) {
        return 0;
    }
    *dcb = 0.0;
    if (sample_bilinear(g, x, y, b3)) {
        *dcb = out[0] - b3[0];
        for (k = 0; k < 3; ++k) {
            out[k] = b3[k] + lam * (out[k] - b3[k]);
        }
    }
    return 1;
}

/* One pass over the seen local points of local cells [i0, i1) x [j0, j1) at
 * pose (x, y) and offset dz: normal equations of the points within clip (in
 * normalized residual units). */
static void accumulate_rect(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                            int32_t ry, double x, double y, double dz, double lam, double clip,
                            double model2, const trn_refine_cfg_t *cfg, int32_t i0, int32_t j0,
                            int32_t i1, int32_t j1, accum_t *acc)
{
    int32_t i, j;
    for (i = 0; i < 9; ++i) {
        acc->a[i] = 0.0;
    }
    acc->b[0] = acc->b[1] = acc->b[2] = 0.0;
    acc->al[0] = acc->al[1] = acc->al[2] = acc->all = acc->bl = 0.0;
    acc->ss = acc->rr = acc->noise2 = acc->q = acc->vv = 0.0;
    acc->n_in = acc->n_all = 0;
    for (j = j0; j < j1; ++j) {
        for (i = i0; i < i1; ++i) {
            double h = (double)TRN_GRID_AT(local, i, j), s3[3], px, py, sd, w, res, u, jv[3], dcb,
                   hw;
            int32_t p, q;
            if (!isfinite(h)) {
                continue;
            }
            px = (double)(i - rx);
            py = (double)(j - ry);
            if (!sample_mix(global, x + px, y + py, lam, s3, &dcb)) {
                continue;
            }
            acc->n_all += 1;
            w = trn_refine_noise_var_(cfg, i, j, rx, ry);
            sd = sqrt(w + model2);
            res = h - dz - s3[0];
            u = res / sd;
            hw = trn_refine_weight_(global, x + px, y + py, res, sd, clip);
            if (!(hw > 0.0)) {
                continue;
            }
            if (hw >= 1.0) {
                /* precision-squared weights: the model variance is estimated
                 * mostly where the noise is small (near the rover), not
                 * swamped by the far points' large noise; from the points
                 * within the plain clip only */
                double qw = 1.0 / ((sd * sd) * (sd * sd));
                acc->noise2 += qw * w;
                acc->rr += qw * res * res;
                acc->q += qw;
                acc->vv += 2.0 * qw * qw * w * w;
            }
            w = hw / (sd * sd);
            jv[0] = s3[1];
            jv[1] = s3[2];
            jv[2] = 1.0;
            for (p = 0; p < 3; ++p) {
                for (q = 0; q < 3; ++q) {
                    acc->a[p * 3 + q] += w * jv[p] * jv[q];
                }
                acc->b[p] += w * jv[p] * res;
                acc->al[p] += w * jv[p] * dcb;
            }
            acc->all += w * dcb * dcb;
            acc->bl += w * dcb * res;
            acc->ss += hw * u * u;
            acc->n_in += 1;
        }
    }
}

static void accumulate(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                       int32_t ry, double x, double y, double dz, double lam, double clip,
                       double model2, const trn_refine_cfg_t *cfg, accum_t *acc)
{
    accumulate_rect(global, local, rx, ry, x, y, dz, lam, clip, model2, cfg, 0, 0, local->width,
                    local->height, acc);
}

/* Fold the mix out of the normal equations of (x, y, dz, mix) (Schur
 * complement), its prior (mean TRN_REFINE_MIX_MEAN, sd TRN_REFINE_MIX_SD)
 * added: a and b become those of (x, y, dz) with the mix at its
 * conditional best, so inv(a) is the marginal covariance of (x, y, dz).
 * g = al / all' (the mix's coupling). Returns the mix's step at d = 0;
 * for a step d of (x, y, dz) it is that minus g . d. */
static double fold_mix(accum_t *acc, double lam, double g[3])
{
    double pw = 1.0 / (TRN_REFINE_MIX_SD * TRN_REFINE_MIX_SD);
    double all = acc->all + pw, bl = acc->bl + pw * (TRN_REFINE_MIX_MEAN - lam);
    int32_t p, q;
    for (p = 0; p < 3; ++p) {
        g[p] = acc->al[p] / all;
    }
    for (p = 0; p < 3; ++p) {
        for (q = 0; q < 3; ++q) {
            acc->a[p * 3 + q] -= acc->al[p] * g[q];
        }
        acc->b[p] -= g[p] * bl;
    }
    return bl / all;
}

/* One Gauss-Newton pass of the bilinear surface at (bx, by, bz) onto the
 * bicubic model's own heights at the estimate (x, y, dz): normal equations
 * over the estimate's inliers, weights 1 / (noise + model variance). No
 * local height enters but through the inlier test, so the shift it leads
 * to is the model's, free of the data's noise. acc->ss is the weighted sum
 * of squares at (bx, by) with the best offset (closed form). */
static void model_pass(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                       int32_t ry, double x, double y, double dz, double bx, double by, double bz,
                       double model2, const trn_refine_cfg_t *cfg, accum_t *acc)
{
    int32_t i, j, p, q;
    for (p = 0; p < 9; ++p) {
        acc->a[p] = 0.0;
    }
    acc->b[0] = acc->b[1] = acc->b[2] = 0.0;
    acc->n_in = 0;
    acc->q = acc->rr = acc->noise2 = 0.0; /* sum w, sum w r0, sum w r0^2 */
    for (j = 0; j < local->height; ++j) {
        for (i = 0; i < local->width; ++i) {
            double h = (double)TRN_GRID_AT(local, i, j), s3[3], b3[3], px, py, v, w, res, jv[3];
            if (!isfinite(h)) {
                continue;
            }
            px = (double)(i - rx);
            py = (double)(j - ry);
            if (!sample(global, x + px, y + py, s3) ||
                !sample_bilinear(global, bx + px, by + py, b3)) {
                continue;
            }
            v = trn_refine_noise_var_(cfg, i, j, rx, ry) + model2;
            w = trn_refine_weight_(global, x + px, y + py, h - dz - s3[0], sqrt(v),
                                   TRN_REFINE_CLIP_RELIEF) /
                v;
            if (!(w > 0.0)) {
                continue;
            }
            res = (dz + s3[0]) - b3[0];
            acc->q += w;
            acc->rr += w * res;
            acc->noise2 += w * res * res;
            res -= bz;
            jv[0] = b3[1];
            jv[1] = b3[2];
            jv[2] = 1.0;
            for (p = 0; p < 3; ++p) {
                for (q = 0; q < 3; ++q) {
                    acc->a[p * 3 + q] += w * jv[p] * jv[q];
                }
                acc->b[p] += w * jv[p] * res;
            }
            acc->n_in += 1;
        }
    }
    acc->ss = acc->q > 0.0 ? acc->noise2 - acc->rr * acc->rr / acc->q : 0.0;
}

/* Shift of the estimate (x, y, dz) had the global heights been bilinear
 * instead of bicubic between cell centres: the pose where the bilinear
 * surface best fits the bicubic model's own heights at the estimate, minus
 * the estimate (model_pass, Gauss-Newton). The two interpolants bracket how
 * the DEM runs between its samples; their disagreement is a systematic
 * error of the model, common to all points, that no residual statistic
 * sees. The bilinear surface has kinks at cell edges, where a plain step
 * can overshoot and cycle: each step is halved until the sum of squares
 * drops over the same points, and the search stops when no halving does
 * (or the bilinear normal matrix is singular). */
static void interp_shift(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                         int32_t ry, double x, double y, double dz, double model2,
                         const trn_refine_cfg_t *cfg, accum_t *work, double bi[9], double shift[3])
{
    /* work and bi are the caller's, dead by now, and each trial step is
     * made in work itself (only the last accepted point's sums are kept
     * aside): the stack stays within TRN_STACK_LIMIT_BYTES */
    accum_t *acc = work;
    double bx = x, by = y, bz = dz, d[3];
    int32_t it, h;
    model_pass(global, local, rx, ry, x, y, dz, bx, by, bz, model2, cfg, acc);
    for (it = 0; it < TRN_REFINE_MAX_ITER && inv3(acc->a, bi); ++it) {
        double step = 1.0, ss0 = acc->ss;
        int32_t n0 = acc->n_in;
        d[0] = bi[0] * acc->b[0] + bi[1] * acc->b[1] + bi[2] * acc->b[2];
        d[1] = bi[3] * acc->b[0] + bi[4] * acc->b[1] + bi[5] * acc->b[2];
        d[2] = bi[6] * acc->b[0] + bi[7] * acc->b[1] + bi[8] * acc->b[2];
        for (h = 0; h < TRN_REFINE_HALVINGS; ++h) {
            model_pass(global, local, rx, ry, x, y, dz, bx + step * d[0], by + step * d[1],
                       bz + step * d[2], model2, cfg, acc);
            if (acc->n_in == n0 && acc->ss < ss0) {
                break;
            }
            step *= 0.5;
        }
        if (h == TRN_REFINE_HALVINGS) {
            break; /* acc holds a rejected trial: it is not used again */
        }
        bx += step * d[0];
        by += step * d[1];
        bz += step * d[2];
        if (fabs(step * d[0]) < 1e-4 && fabs(step * d[1]) < 1e-4) {
            break;
        }
    }
    shift[0] = bx - x;
    shift[1] = by - y;
    shift[2] = bz - dz;
}

/* The "meat" of the cluster-robust (sandwich) covariance: the sum over
 * TRN_REFINE_BLOCK x TRN_REFINE_BLOCK blocks of local cells of the outer
 * product of each block's score (sum of w r J over its inliers). Residuals
 * correlated within a block (the global DEM's interpolation error is smooth
 * over about a cell) add up there instead of averaging out. h0[p] is the sum
 * over the blocks of the squared variance each block's term of the
 * sandwich's position variance p, (inv score)[p]^2, would have if the
 * residuals were the noise model's alone: (inv V inv)[pp], V the block's
 * own normal matrix with the mix profiled out ([I, -g] N_b [I, -g]^T). So
 * sqrt(2 h0[p]) is that variance's sampling sd under the noise model. */
static void block_meat(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                       int32_t ry, double x, double y, double dz, double lam, const double g[3],
                       const double inv[9], double model2, const trn_refine_cfg_t *cfg,
                       accum_t *work, double meat[9], double h0[2])
{
    /* work is the caller's, dead by now (the stack, as in interp_shift) */
    accum_t *acc = work;
    int32_t bi, bj, p, q;
    for (p = 0; p < 9; ++p) {
        meat[p] = 0.0;
    }
    h0[0] = h0[1] = 0.0;
    for (bj = 0; bj < local->height; bj += TRN_REFINE_BLOCK) {
        for (bi = 0; bi < local->width; bi += TRN_REFINE_BLOCK) {
            int32_t i1 = bi + TRN_REFINE_BLOCK < local->width ? bi + TRN_REFINE_BLOCK
                                                              : local->width;
            int32_t j1 = bj + TRN_REFINE_BLOCK < local->height ? bj + TRN_REFINE_BLOCK
                                                               : local->height;
            accumulate_rect(global, local, rx, ry, x, y, dz, lam, TRN_REFINE_CLIP_RELIEF, model2,
                            cfg, bi, bj, i1, j1, acc);
            for (p = 0; p < 3; ++p) {
                acc->b[p] -= g[p] * acc->bl; /* the score with the mix profiled out */
            }
            for (p = 0; p < 3; ++p) {
                for (q = 0; q < 3; ++q) {
                    meat[p * 3 + q] += acc->b[p] * acc->b[q];
                }
            }
            for (p = 0; p < 2; ++p) {
                const double v = trn_refine_block_var_(acc->a, acc->al, acc->all, g,
                                                       &inv[(size_t)p * 3u], 3);
                h0[p] += v * v;
            }
        }
    }
}

/* Model variance that makes the inliers' squared residuals equal their
 * total variance (noise + model) on average, weighted by the squared
 * precision at the previous estimate (a fixed point of the weighted moment
 * equation), never negative. */
static double next_model2(const accum_t *acc)
{
    return trn_refine_model2_(acc->rr, acc->noise2, acc->q);
}

double trn_refine_model2_(double rr, double noise2, double q)
{
    double m = (rr - noise2) / q;
    return m > 0.0 ? m : 0.0;
}

double trn_refine_sys_weight_(double rr, double noise2, double q, double vv)
{
    double m2s = (rr - noise2 - TRN_REFINE_SYS_TERM_Z * sqrt(vv)) / q;
    m2s = m2s > 0.0 ? m2s : 0.0;
    return TRN_REFINE_SYS * m2s / (m2s + noise2 / q);
}

double trn_refine_excess_(double ratio, double rel_sd)
{
    return ratio > 1.0 + TRN_REFINE_SYS_Z * rel_sd ? ratio : 1.0;
}

double trn_refine_block_var_(const double *a, const double *al, double all, const double *g,
                             const double *u, int32_t n)
{
    /* u^T V u with V = A - al g^T - g al^T + all g g^T: the variance of
     * u . (b - g bl) when b and bl have the covariance [[A, al], [al^T, all]] */
    double ua = 0.0, ug = 0.0, v = 0.0;
    int32_t r, t;
    for (r = 0; r < n; ++r) {
        for (t = 0; t < n; ++t) {
            v += u[r] * a[r * n + t] * u[t];
        }
        ua += u[r] * al[r];
        ug += u[r] * g[r];
    }
    return v - 2.0 * ua * ug + all * ug * ug;
}

static double local_spread(const trn_grid_f32_t *local, int32_t *n_seen);

/* The checks trn_height_search and the refinements share: the grids, the
 * noise model and the rover cell (each caller checks its own inlier
 * probability). */
static trn_status_t common_args(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                                int32_t rover_x, int32_t rover_y, const trn_refine_cfg_t *cfg)
{
    trn_status_t st;
    if (global == NULL || local == NULL || cfg == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_grid_f32_check(global)) != TRN_OK || (st = trn_grid_f32_check(local)) != TRN_OK) {
        return st;
    }
    if (!(cfg->cell_m > 0.0f && cfg->cell_m <= 1000.0f) ||
        !(cfg->noise_m > 0.0f && cfg->noise_m <= 1000.0f) ||
        !(cfg->noise_k_per_m >= 0.0f && cfg->noise_k_per_m <= 1000.0f) || rover_x < -TRN_MAX_DIM ||
        rover_y < -TRN_MAX_DIM || rover_x > local->width - 1 + TRN_MAX_DIM ||
        rover_y > local->height - 1 + TRN_MAX_DIM) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}

/* The mixture log-likelihood of trn_height_search at a continuous pose,
 * the mixed interpolant's heights, offset dz and model variance model2. */
static double refined_ll(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                         int32_t ry, double x, double y, double dz, double lam, double model2,
                         const trn_refine_cfg_t *cfg)
{
    double a = (double)cfg->inlier_prob;
    const double two_pi = 6.283185307179586;
    int32_t i, j, n_seen = 0;
    double spread = local_spread(local, &n_seen), floor_m = (double)cfg->noise_m, k, lout, ll = 0.0;
    k = 1.0 / (10.0 * (spread > floor_m ? spread : floor_m));
    lout = log((1.0 - a) * k);
    for (j = 0; j < local->height; ++j) {
        for (i = 0; i < local->width; ++i) {
            double h = (double)TRN_GRID_AT(local, i, j), s3[3], dcb, v, u;
            if (!isfinite(h)) {
                continue;
            }
            if (!sample_mix(global, x + (double)(i - rx), y + (double)(j - ry), lam, s3, &dcb)) {
                ll += lout;
                continue;
            }
            v = trn_refine_noise_var_(cfg, i, j, rx, ry) + model2;
            u = h - dz - s3[0];
            ll += log(a * exp(-0.5 * u * u / v) / sqrt(two_pi * v) + (1.0 - a) * k);
        }
    }
    return ll;
}

static void set_fail(trn_refine_t *out, int32_t ix, int32_t iy)
{
    out->x = (double)ix;
    out->y = (double)iy;
    out->cov_cells[0] = out->cov_cells[1] = INFINITY;
    out->cov_cells[2] = 0.0;
    out->inflation = out->ll_inflation = 1.0;
    out->interp_shift[0] = out->interp_shift[1] = 0.0;
    out->interp_mix = TRN_REFINE_MIX_MEAN;
    out->sys_weight = 0.0;
    out->shoulders = 1.0;
    out->ll = -(double)INFINITY;
}

trn_status_t trn_refine_pose(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                             int32_t rover_x, int32_t rover_y, int32_t ix, int32_t iy,
                             const trn_refine_cfg_t *cfg, trn_refine_t *out)
{
    trn_status_t st;
    accum_t acc;
    double x = (double)ix, y = (double)iy, dz = 0.0, model2 = 0.0, inv[9], d[3], chi2, g[3];
    double lam = TRN_REFINE_MIX_MEAN;
    const double lam_lo = TRN_REFINE_MIX_MEAN - 2.0 * TRN_REFINE_MIX_SD;
    const double lam_hi = TRN_REFINE_MIX_MEAN + 2.0 * TRN_REFINE_MIX_SD;
    int32_t it, phase_end = TRN_REFINE_MAX_ITER;

    if ((st = trn_refine_args_(global, local, rover_x, rover_y, cfg, out)) != TRN_OK) {
        return st;
    }
    out->x = x;
    out->y = y;
    out->dz_m = 0.0;
    out->chi2_dof = 0.0;
    out->n_used = out->n_seen = out->iterations = 0;
    set_fail(out, ix, iy);
    if (ix < 0 || iy < 0 || ix >= global->width || iy >= global->height) {
        return TRN_E_RANGE;
    }
    /* Start: the offset alone, over every point; then the model variance
     * (what the residuals hold beyond the noise model: the global DEM's own
     * interpolation error, a stale map) from the residuals, re-estimated at
     * every step, so the weights and the clip follow the data. */
    accumulate(global, local, rover_x, rover_y, x, y, 0.0, lam, (double)INFINITY, 0.0, cfg, &acc);
    out->n_seen = acc.n_all;
    if (acc.n_all < 8) {
        return TRN_E_NODATA;
    }
    dz = acc.b[2] / acc.a[8];
    for (it = 0; it < 3; ++it) {
        accumulate(global, local, rover_x, rover_y, x, y, dz, lam,
                   it == 0 ? (double)INFINITY : TRN_REFINE_CLIP, model2, cfg, &acc);
        if (acc.n_in < 8) {
            break;
        }
        model2 = next_model2(&acc);
        dz += acc.b[2] / acc.a[8];
    }
    /* Two phases: the plain clip from the integer start, then the relief
     * rule (trn_refine_weight_) from the first phase's estimate. */
    for (it = 0; it < 2 * TRN_REFINE_MAX_ITER; ++it) {
        double dl, clip = it < phase_end ? TRN_REFINE_CLIP : TRN_REFINE_CLIP_RELIEF;
        accumulate(global, local, rover_x, rover_y, x, y, dz, lam, clip, model2, cfg, &acc);
        model2 = next_model2(&acc);
        dl = fold_mix(&acc, lam, g);
        if (acc.n_in < 8 || !inv3(acc.a, inv)) {
            set_fail(out, ix, iy);
            out->n_used = acc.n_in;
            return TRN_E_ILLCOND;
        }
        d[0] = inv[0] * acc.b[0] + inv[1] * acc.b[1] + inv[2] * acc.b[2];
        d[1] = inv[3] * acc.b[0] + inv[4] * acc.b[1] + inv[5] * acc.b[2];
        d[2] = inv[6] * acc.b[0] + inv[7] * acc.b[1] + inv[8] * acc.b[2];
        d[0] = d[0] > 0.5 ? 0.5 : d[0] < -0.5 ? -0.5 : d[0];
        d[1] = d[1] > 0.5 ? 0.5 : d[1] < -0.5 ? -0.5 : d[1];
        x += d[0];
        y += d[1];
        dz += d[2];
        lam += dl - (g[0] * d[0] + g[1] * d[1] + g[2] * d[2]);
        /* within two prior sds: beyond, the "mix" would be a free
         * sharpening that fits the map to anything */
        lam = lam > lam_hi ? lam_hi : lam < lam_lo ? lam_lo : lam;
        out->iterations = it + 1;
        if (fabs(x - (double)ix) > TRN_REFINE_MAX_SHIFT ||
            fabs(y - (double)iy) > TRN_REFINE_MAX_SHIFT) {
            set_fail(out, ix, iy);
            return TRN_E_ILLCOND;
        }
        if (it + 1 == phase_end || (fabs(d[0]) < 1e-4 && fabs(d[1]) < 1e-4)) {
            if (it >= phase_end) {
                break;
            }
            phase_end = it + 1; /* the first phase converged (or ran out) */
        }
    }
    /* Covariance at the final pose. */
    accumulate(global, local, rover_x, rover_y, x, y, dz, lam, TRN_REFINE_CLIP_RELIEF, model2, cfg,
               &acc);
    (void)fold_mix(&acc, lam, g);
    if (acc.n_in < 8 || 2 * acc.n_in < acc.n_all || !inv3(acc.a, inv)) {
        set_fail(out, ix, iy);
        out->n_used = acc.n_in;
        return TRN_E_ILLCOND;
    }
    chi2 = acc.ss / (double)(acc.n_in - 4);
    out->chi2_dof = chi2;
    /* the noise model's scale, raised only where the residuals exceed it
     * beyond TRN_REFINE_SYS_Z sampling sds (sqrt(2 / dof)) */
    chi2 = trn_refine_excess_(chi2, sqrt(2.0 / (double)(acc.n_in - 4)));
    out->x = x;
    out->y = y;
    out->dz_m = dz;
    out->model_m = sqrt(model2);
    out->interp_mix = lam;
    out->ll = refined_ll(global, local, rover_x, rover_y, x, y, dz, lam, model2, cfg);
    /* Sandwich A^-1 B A^-1 (B from blocks); the model-based A^-1 (times the
     * chi-square factor) is a lower bound on each variance: the block
     * estimate is noisy, and independent errors must not shrink it; nor
     * raise it by chance: a ratio counts only beyond TRN_REFINE_SYS_Z
     * sampling sds of 1 (docs/method.md 9, "the floors"). */
    {
        /* q > 0: at least 8 inliers, each noise variance > 0. The systematic
         * weight counts the misfit beyond TRN_REFINE_SYS_TERM_Z sampling sds of
         * what the noise alone would give (with no misfit, next_model2's
         * estimate is positive in about a third of the cases); taken before
         * block_meat reuses acc. */
        double meat[9], f, sw[2], h0[2];
        double w = trn_refine_sys_weight_(acc.rr, acc.noise2, acc.q, acc.vv);
        int32_t p, q, r;
        out->n_used = acc.n_in;
        block_meat(global, local, rover_x, rover_y, x, y, dz, lam, g, inv, model2, cfg, &acc, meat,
                   h0);
        /* the sandwich's two position variances, (inv meat inv)[pp] */
        for (p = 0; p < 2; ++p) {
            sw[p] = 0.0;
            for (q = 0; q < 3; ++q) {
                for (r = 0; r < 3; ++r) {
                    sw[p] += inv[p * 3 + q] * meat[q * 3 + r] * inv[r * 3 + p];
                }
            }
        }
        {
            /* one inflation factor for the position block, so the ellipse
             * keeps the model's shape: the larger of the two variance
             * ratios, each where beyond its sampling sd (h0) of 1. ln L's
             * factor (the failure probability) takes them whole: there a
             * factor low by chance would make a wrong answer confident */
            const double c1 = out->chi2_dof > 1.0 ? out->chi2_dof : 1.0;
            double fx = sw[0] / (inv[0] * c1), fy = sw[1] / (inv[4] * c1);
            f = fx > fy ? fx : fy;
            out->ll_inflation = f > 1.0 ? f : 1.0; /* as before the gate: max(1, chi2) */
            fx = sw[0] / (inv[0] * chi2);
            fy = sw[1] / (inv[4] * chi2);
            fx = trn_refine_excess_(fx, sqrt(2.0 * h0[0]) / inv[0]);
            fy = trn_refine_excess_(fy, sqrt(2.0 * h0[1]) / inv[4]);
            f = fx > fy ? fx : fy;
        }
        out->inflation = f;
        out->cov_cells[0] = inv[0] * chi2 * f;
        out->cov_cells[1] = inv[4] * chi2 * f;
        out->cov_cells[2] = inv[1] * chi2 * f;
        {
            /* The interpolants' disagreement, weighted by the share of the
             * misfit (beyond its sampling noise: w above) in the residuals'
             * (precision-squared weighted) variance: where a mix of the two
             * interpolants explains the data (m^2 ~ 0) the mix's own
             * uncertainty is in inv already;
             * where the data show a misfit beyond the noise, the map runs
             * between its samples in a way neither interpolant follows, a
             * systematic error the residuals cannot show. */
            double sh[3];
            interp_shift(global, local, rover_x, rover_y, x, y, dz, model2, cfg, &acc, inv, sh);
            out->interp_shift[0] = sh[0];
            out->interp_shift[1] = sh[1];
            out->sys_weight = w;
            out->cov_cells[0] += w * sh[0] * sh[0];
            out->cov_cells[1] += w * sh[1] * sh[1];
            out->cov_cells[2] += w * sh[0] * sh[1];
        }
    }
    return TRN_OK;
}

/* One pass of trn_refine_noise_scale at variance factor k2 and model
 * variance m2: the weighted normal equations of r^2 = k2 s^2 + m2 over the
 * points within the clip, in n[0..4] = sums of q s^4, q s^2, q, q r^2 s^2,
 * q r^2 (q = 1 / v^2, r^2 over TRN_CLIP_MEAN_SQUARE); returns the count. */
static int32_t noise_pass(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                          int32_t ry, const trn_refine_t *at, const double cs_sn[2],
                          const trn_refine_cfg_t *cfg, double k2, double m2, double n[5])
{
    int32_t i, j, cnt = 0;
    n[0] = n[1] = n[2] = n[3] = n[4] = 0.0;
    for (j = 0; j < local->height; ++j) {
        for (i = 0; i < local->width; ++i) {
            double h = (double)TRN_GRID_AT(local, i, j), s3[3], dcb, s2, v, r2, q;
            const double ox = (double)(i - rx), oy = (double)(j - ry);
            /* the offset turned by the heading, as trn_refine_pose_heading's */
            if (!isfinite(h) ||
                !sample_mix(global, at->x + ox * cs_sn[0] + oy * cs_sn[1],
                            at->y - ox * cs_sn[1] + oy * cs_sn[0], at->interp_mix, s3, &dcb)) {
                continue;
            }
            s2 = trn_refine_noise_var_(cfg, i, j, rx, ry);
            v = k2 * s2 + m2;
            r2 = h - at->dz_m - s3[0];
            r2 *= r2;
            if (!(r2 <= TRN_REFINE_CLIP * TRN_REFINE_CLIP * v)) {
                continue;
            }
            r2 /= TRN_CLIP_MEAN_SQUARE;
            q = 1.0 / (v * v);
            n[0] += q * s2 * s2;
            n[1] += q * s2;
            n[2] += q;
            n[3] += q * r2 * s2;
            n[4] += q * r2;
            cnt += 1;
        }
    }
    return cnt;
}

/* Residual of local cell (i, j), i, j >= 0, at `at`, and in *s2 its
 * configured noise variance; NaN where unseen, off the local grid, off the
 * map or beyond TRN_REFINE_CLIP sds of the level fit (k2 s2 + m2). */
static double resid_in_clip(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                            int32_t ry, const trn_refine_t *at, const double cs_sn[2],
                            const trn_refine_cfg_t *cfg, double k2, double m2, int32_t i, int32_t j,
                            double *s2)
{
    double h, s3[3], dcb, r;
    const double ox = (double)(i - rx), oy = (double)(j - ry);
    if (i >= local->width || j >= local->height) {
        return (double)NAN;
    }
    h = (double)TRN_GRID_AT(local, i, j);
    if (!isfinite(h) ||
        !sample_mix(global, at->x + ox * cs_sn[0] + oy * cs_sn[1],
                    at->y - ox * cs_sn[1] + oy * cs_sn[0], at->interp_mix, s3, &dcb)) {
        return (double)NAN;
    }
    r = h - at->dz_m - s3[0];
    *s2 = trn_refine_noise_var_(cfg, i, j, rx, ry);
    return r * r > TRN_REFINE_CLIP * TRN_REFINE_CLIP * (k2 * *s2 + m2) ? (double)NAN : r;
}

double trn_refine_noise_scale_diff_(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                                    int32_t rx, int32_t ry, const trn_refine_t *at,
                                    double heading_rad, const trn_refine_cfg_t *cfg, double k2,
                                    double m2, int32_t *pairs)
{
    int32_t i, j, d, n = 0;
    double sum = 0.0, cs_sn[2];
    trn_heading_trig_(heading_rad, &cs_sn[0], &cs_sn[1]);
    for (j = 0; j < local->height; ++j) {
        for (i = 0; i < local->width; ++i) {
            double s0 = 0.0;
            const double r0 = resid_in_clip(global, local, rx, ry, at, cs_sn, cfg, k2, m2, i, j,
                                            &s0);
            if (!isfinite(r0)) {
                continue;
            }
            for (d = 0; d < 2; ++d) { /* the neighbours to the right and below */
                double s1 = 0.0;
                const double r1 = resid_in_clip(global, local, rx, ry, at, cs_sn, cfg, k2, m2,
                                                i + (d == 0 ? 1 : 0), j + (d == 0 ? 0 : 1), &s1);
                if (isfinite(r1)) {
                    sum += (r1 - r0) * (r1 - r0) / (s0 + s1);
                    n += 1;
                }
            }
        }
    }
    *pairs = n;
    return n > 0 ? sum / (double)n : (double)NAN;
}

/* ln L on the line through (px, py) across the valley: the pose (px, py) +
 * o e2 with the perpendicular offset o and the offset dz at their best
 * (Gauss-Newton from *o, *dz, at most TRN_VALLEY_ITER steps, the relief
 * rule; the mix lam and the model variance model2 held). */
static double valley_point(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                           int32_t ry, const trn_refine_cfg_t *cfg, double px, double py,
                           const double e2[2], double lam, double model2, double *o, double *dz)
{
    accum_t acc;
    int32_t it;
    for (it = 0; it < TRN_VALLEY_ITER; ++it) {
        double aoo, aoz, azz, bo, det, step;
        accumulate(global, local, rx, ry, px + *o * e2[0], py + *o * e2[1], *dz, lam,
                   TRN_REFINE_CLIP_RELIEF, model2, cfg, &acc);
        aoo = e2[0] * e2[0] * acc.a[0] + 2.0 * e2[0] * e2[1] * acc.a[1] + e2[1] * e2[1] * acc.a[4];
        aoz = e2[0] * acc.a[2] + e2[1] * acc.a[5];
        azz = acc.a[8];
        bo = e2[0] * acc.b[0] + e2[1] * acc.b[1];
        det = aoo * azz - aoz * aoz;
        if (acc.n_in < 8 || !(det > 1e-12 * aoo * azz)) {
            break;
        }
        step = (azz * bo - aoz * acc.b[2]) / det;
        step = step > 0.5 ? 0.5 : step < -0.5 ? -0.5 : step;
        *dz += (aoo * acc.b[2] - aoz * bo) / det;
        *o += step;
        if (fabs(step) < 1e-3) {
            break;
        }
    }
    return refined_ll(global, local, rx, ry, px + *o * e2[0], py + *o * e2[1], *dz, lam, model2,
                      cfg);
}

/* The axes of a 2 x 2 covariance (var_x, var_y, cov_xy): lam[0] >= lam[1]
 * its eigenvalues, e1 the unit eigenvector of lam[0] (from the better
 * conditioned of the two rows of cov - lam[0] I; any axis for a round
 * ellipse), e2 = e1 turned by 90 degrees. */
static void cov_axes(const double cov[3], double lam[2], double e1[2], double e2[2])
{
    const double a = cov[0], b = cov[1], c = cov[2];
    const double d = sqrt(0.25 * (a - b) * (a - b) + c * c);
    double n;
    lam[0] = 0.5 * (a + b) + d;
    lam[1] = 0.5 * (a + b) - d;
    if (a >= b) {
        e1[0] = lam[0] - b;
        e1[1] = c;
    } else {
        e1[0] = c;
        e1[1] = lam[0] - a;
    }
    n = sqrt(e1[0] * e1[0] + e1[1] * e1[1]);
    if (!(n > 0.0) || !isfinite(n)) {
        e1[0] = 1.0;
        e1[1] = 0.0;
        n = 1.0;
    }
    e1[0] /= n;
    e1[1] /= n;
    e2[0] = -e1[1];
    e2[1] = e1[0];
}

double trn_refine_valley_fail_(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                               int32_t rx, int32_t ry, const trn_refine_cfg_t *cfg,
                               const trn_refine_t *at, double infl, const double lo[2],
                               const double hi[2])
{
    const double h = TRN_VALLEY_STEP_CELLS;
    const int32_t kmax = (int32_t)(TRN_VALLEY_REACH_CELLS / TRN_VALLEY_STEP_CELLS + 0.5);
    const double model2 = at->model_m * at->model_m;
    double in = 1.0, out = 0.0, d1[2] = {-INFINITY, -INFINITY}, q, lam[2], e1[2], e2[2];
    int32_t side, k;
    cov_axes(at->cov_cells, lam, e1, e2);
    if (!(infl >= 1.0) || !isfinite(at->ll) || !isfinite(lam[0])) {
        return 0.0;
    }
    for (side = 0; side < 2; ++side) {
        const double sg = side == 0 ? -1.0 : 1.0;
        double o = 0.0, dz = at->dz_m;
        for (k = 1; k <= kmax; ++k) {
            const double t = sg * (double)k * h;
            const double px = at->x + t * e1[0], py = at->y + t * e1[1];
            double d;
            if (px < lo[0] || px > hi[0] || py < lo[1] || py > hi[1]) {
                break; /* the window: the prior puts no mass beyond it */
            }
            d = (valley_point(global, local, rx, ry, cfg, px, py, e2, at->interp_mix, model2, &o,
                              &dz) -
                 at->ll) /
                infl;
            if (!isfinite(d)) {
                break;
            }
            if (k == 1) {
                d1[side] = d;
            }
            if ((double)k * h > TRN_FAIL_RADIUS_CELLS) {
                out += exp(fmin(d, 700.0));
            } else {
                in += exp(fmin(d, 700.0));
            }
            if (d < -TRN_VALLEY_NATS) {
                break;
            }
        }
    }
    /* A centre narrower than the step: its mass is the quadratic's through
     * t = -h, 0, h (Laplace), not the one sample at t = 0. */
    q = -(d1[0] + d1[1]) / (h * h);
    if (q > 0.0 && isfinite(q)) {
        in += fmin(1.0, sqrt(6.283185307179586 / q) / h) - 1.0;
    }
    return out / (in + out);
}

trn_status_t trn_refine_noise_scale(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                                    int32_t rover_x, int32_t rover_y, const trn_refine_t *at,
                                    double heading_rad, const trn_refine_cfg_t *cfg, double *k2,
                                    double *k2_sd)
{
    trn_status_t st;
    double kk = 1.0, mm, n[5], det, var = 0.0, cs_sn[2];
    int32_t it;
    if (k2 == NULL || k2_sd == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_refine_args_(global, local, rover_x, rover_y, cfg, at)) != TRN_OK) {
        return st;
    }
    if (!isfinite(at->x) || !isfinite(at->y) || !isfinite(at->dz_m) || !isfinite(at->interp_mix) ||
        !(at->model_m >= 0.0) || !isfinite(at->model_m) ||
        !(fabs(heading_rad) <= TRN_HEADING_MAX_WINDOW_RAD)) {
        return TRN_E_ARG;
    }
    trn_heading_trig_(heading_rad, &cs_sn[0], &cs_sn[1]);
    mm = at->model_m * at->model_m;
    for (it = 0; it < 4; ++it) {
        if (noise_pass(global, local, rover_x, rover_y, at, cs_sn, cfg, kk, mm, n) < 8) {
            return TRN_E_NODATA;
        }
        det = n[0] * n[2] - n[1] * n[1];
        if (!(det > 1e-12 * n[0] * n[2])) {
            return TRN_E_ILLCOND;
        }
        kk = (n[3] * n[2] - n[1] * n[4]) / det;
        mm = (n[0] * n[4] - n[1] * n[3]) / det;
        /* the sd of the unconstrained estimate, also where a bound below
         * is met: a bound pins no variance down */
        var = 2.0 * n[2] / det;
        if (mm < 0.0) {
            /* the model variance at its bound: the noise scale alone */
            mm = 0.0;
            kk = n[3] / n[0];
        }
        if (kk < TRN_NOISE_SCALE2_MIN) {
            kk = TRN_NOISE_SCALE2_MIN;
            mm = fmax(0.0, (n[4] - kk * n[1]) / n[2]);
        }
    }
    *k2 = kk;
    *k2_sd = sqrt(var);
    return TRN_OK;
}

/* Spread of the seen local heights (standard deviation about their mean), and
 * their count. */
static double local_spread(const trn_grid_f32_t *local, int32_t *n_seen)
{
    int32_t x, y, n = 0;
    double ref = 0.0, s1 = 0.0, s2 = 0.0, v;
    for (y = 0; y < local->height; ++y) {
        for (x = 0; x < local->width; ++x) {
            double h = (double)TRN_GRID_AT(local, x, y);
            if (isfinite(h)) {
                if (n == 0) {
                    ref = h;
                }
                s1 += h - ref;
                s2 += (h - ref) * (h - ref);
                ++n;
            }
        }
    }
    *n_seen = n;
    if (n == 0) {
        return 0.0;
    }
    v = s2 / (double)n - (s1 / (double)n) * (s1 / (double)n);
    return v > 0.0 ? sqrt(v) : 0.0;
}

/* Global height under local cell (x, y) at pose (px, py), or NaN. */
static double global_at(const trn_grid_f32_t *g, int32_t px, int32_t py, int32_t x, int32_t y,
                        int32_t rx, int32_t ry)
{
    int64_t gx = (int64_t)px + x - rx, gy = (int64_t)py + y - ry;
    if (gx < 0 || gy < 0 || gx >= g->width || gy >= g->height) {
        return (double)NAN;
    }
    return (double)TRN_GRID_AT(g, (int32_t)gx, (int32_t)gy);
}

/* Weighted offset and model variance of the residuals at pose (px, py),
 * over the points within clip standard deviations of (dz, m2) (clip < 0:
 * every point). Returns the number of points used. */
static int32_t pose_fit(const trn_grid_f32_t *g, const trn_grid_f32_t *l, int32_t rx, int32_t ry,
                        int32_t px, int32_t py, const trn_refine_cfg_t *cfg, double clip,
                        double *dz, double *m2)
{
    int32_t x, y;
    trn_pose_mom_t a = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0};
    for (y = 0; y < l->height; ++y) {
        for (x = 0; x < l->width; ++x) {
            double h = (double)TRN_GRID_AT(l, x, y), gv, r, v;
            if (!isfinite(h)) {
                continue;
            }
            gv = global_at(g, px, py, x, y, rx, ry);
            if (!isfinite(gv)) {
                continue;
            }
            r = h - gv;
            v = trn_refine_noise_var_(cfg, x, y, rx, ry);
            if (clip >= 0.0 && fabs(r - *dz) > clip * sqrt(v + *m2)) {
                continue;
            }
            trn_pose_mom_add_(&a, r, v, *m2);
        }
    }
    return trn_pose_mom_end_(&a, dz, m2);
}

/* Log-likelihood of pose (px, py), nats: the model of height_score.c read
 * straight from the grids, the obvious reference the tests hold it to. */
static double pose_ll(const trn_grid_f32_t *g, const trn_grid_f32_t *l, int32_t rx, int32_t ry,
                      int32_t px, int32_t py, const trn_refine_cfg_t *cfg, double a, double k,
                      double *dz_out, double *m_out)
{
    const double two_pi = 6.283185307179586;
    int32_t x, y, n_all;
    double dz = 0.0, m2 = 0.0, ll = 0.0, lout = log((1.0 - a) * k);
    /* dz and m2: over every point (m2 = 0 weights, then those of the first
     * m2), then over the points within the clip of that fit */
    n_all = pose_fit(g, l, rx, ry, px, py, cfg, -1.0, &dz, &m2);
    if (n_all > 0 && pose_fit(g, l, rx, ry, px, py, cfg, -1.0, &dz, &m2) > 0) {
        /* then within the clip of the last fit, again while that drops
         * points (trn_clip_again_) */
        double dz1 = dz, m21 = m2;
        int32_t n_prev = n_all, n, again;
        for (again = 0; again <= TRN_CLIP_AGAIN; ++again) {
            n = pose_fit(g, l, rx, ry, px, py, cfg, TRN_REFINE_CLIP, &dz1, &m21);
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
    for (y = 0; y < l->height; ++y) {
        for (x = 0; x < l->width; ++x) {
            double h = (double)TRN_GRID_AT(l, x, y), gv, v, u;
            if (!isfinite(h)) {
                continue;
            }
            gv = global_at(g, px, py, x, y, rx, ry);
            if (!isfinite(gv)) {
                ll += lout;
                continue;
            }
            v = trn_refine_noise_var_(cfg, x, y, rx, ry) + m2;
            u = h - dz - gv;
            ll += log(a * exp(-0.5 * u * u / v) / sqrt(two_pi * v) + (1.0 - a) * k);
        }
    }
    *dz_out = dz;
    *m_out = sqrt(m2);
    return ll;
}

/* ln(exp(a) + exp(b)) without overflow; a may be -inf. */
static double log_add(double a, double b)
{
    double hi = a > b ? a : b, lo = a > b ? b : a;
    if (isinf(hi) && hi < 0.0) {
        return hi;
    }
    return hi + log1p(exp(lo - hi));
}

trn_status_t trn_height_search(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                               int32_t rover_x, int32_t rover_y, const trn_window_t *win,
                               const trn_exclusion_t *ex, const trn_refine_cfg_t *cfg,
                               float inlier_prob, double ll_scale, double *ll_grid,
                               trn_height_best_t *best)
{
    return trn_height_search_ws_(global, local, rover_x, rover_y, win, ex, cfg, inlier_prob,
                                 ll_scale, ll_grid, NULL, best);
}

trn_status_t trn_height_search_ws_(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                                   int32_t rover_x, int32_t rover_y, const trn_window_t *win,
                                   const trn_exclusion_t *ex, const trn_refine_cfg_t *cfg,
                                   float inlier_prob, double ll_scale, double *ll_grid,
                                   void *scratch, trn_height_best_t *best)
{
    trn_hs_t hs;
    trn_status_t st;
    int32_t x, y, n_seen = 0;
    double spread, k, floor_m;
    int found = 0;

    if (win == NULL || best == NULL) {
        return TRN_E_NULL;
    }
    if ((st = common_args(global, local, rover_x, rover_y, cfg)) != TRN_OK) {
        return st;
    }
    if (!(inlier_prob > 0.0f && inlier_prob < 1.0f) || (ex != NULL && ex->radius < 0) ||
        !(ll_scale >= 1.0 && ll_scale <= 1e6)) {
        return TRN_E_ARG;
    }
    if (win->x0 > win->x1 || win->y0 > win->y1 || win->x0 < 0 || win->y0 < 0 ||
        win->x1 >= global->width || win->y1 >= global->height) {
        return TRN_E_RANGE;
    }
    spread = local_spread(local, &n_seen);
    if (n_seen < 8) {
        return TRN_E_NODATA;
    }
    floor_m = (double)cfg->noise_m;
    k = 1.0 / (10.0 * (spread > floor_m ? spread : floor_m));
    if (scratch != NULL) { /* the seen cells gathered once (height_score.c) */
        (void)trn_hs_init(&hs, scratch, global, local, rover_x, rover_y, cfg, (double)inlier_prob);
    }
    best->poses = 0u;
    best->lse_all = best->lse_out = -(double)INFINITY;
    for (y = win->y0; y <= win->y1; ++y) {
        for (x = win->x0; x <= win->x1; ++x) {
            double ll, dz, m, q;
            int inside = ex != NULL && abs(x - ex->cx) <= ex->radius &&
                         abs(y - ex->cy) <= ex->radius;
            ll = scratch != NULL ? trn_hs_ll(&hs, x, y, &dz, &m)
                                 : pose_ll(global, local, rover_x, rover_y, x, y, cfg,
                                           (double)inlier_prob, k, &dz, &m);
            if (ll_grid != NULL) {
                ll_grid[(size_t)(y - win->y0) * (size_t)(win->x1 - win->x0 + 1) +
                        (size_t)(x - win->x0)] = ll;
            }
            best->poses += 1u;
            q = ll / ll_scale;
            best->lse_all = log_add(best->lse_all, q);
            if (inside) {
                continue;
            }
            best->lse_out = log_add(best->lse_out, q);
            /* highest ln L; ties to the smallest y, then x (scan order) */
            if (!found || ll > best->ll) {
                best->x = x;
                best->y = y;
                best->ll = ll;
                best->dz_m = dz;
                best->model_m = m;
                found = 1;
            }
        }
    }
    return found ? TRN_OK : TRN_E_NODATA;
}

trn_status_t trn_height_mass(const double *ll_grid, const trn_window_t *win,
                             const trn_exclusion_t *ex, double ll_scale, trn_height_best_t *best)
{
    int32_t x, y;
    int found = 0;
    if (ll_grid == NULL || win == NULL || best == NULL) {
        return TRN_E_NULL;
    }
    if ((ex != NULL && ex->radius < 0) || !(ll_scale >= 1.0 && ll_scale <= 1e6)) {
        return TRN_E_ARG;
    }
    if (win->x0 > win->x1 || win->y0 > win->y1 || win->x0 < 0 || win->y0 < 0 ||
        win->x1 >= TRN_MAX_DIM || win->y1 >= TRN_MAX_DIM) {
        return TRN_E_RANGE;
    }
    best->poses = 0u;
    best->dz_m = (double)NAN;
    best->model_m = (double)NAN;
    best->lse_all = best->lse_out = -(double)INFINITY;
    for (y = win->y0; y <= win->y1; ++y) {
        for (x = win->x0; x <= win->x1; ++x) {
            double ll = ll_grid[(size_t)(y - win->y0) * (size_t)(win->x1 - win->x0 + 1) +
                                (size_t)(x - win->x0)];
            double q = ll / ll_scale;
            best->poses += 1u;
            best->lse_all = log_add(best->lse_all, q);
            if (ex != NULL && abs(x - ex->cx) <= ex->radius && abs(y - ex->cy) <= ex->radius) {
                continue;
            }
            best->lse_out = log_add(best->lse_out, q);
            if (!found || ll > best->ll) {
                best->x = x;
                best->y = y;
                best->ll = ll;
                found = 1;
            }
        }
    }
    return found ? TRN_OK : TRN_E_NODATA;
}

/* The interpolants for the heading refinement (refine_int.h). */
int trn_refine_sample_(const trn_grid_f32_t *g, double x, double y, double out[3])
{
    return sample(g, x, y, out);
}

int trn_refine_sample_bilinear_(const trn_grid_f32_t *g, double x, double y, double out[3])
{
    return sample_bilinear(g, x, y, out);
}

double trn_refine_local_spread_(const trn_grid_f32_t *local, int32_t *n_seen)
{
    return local_spread(local, n_seen);
}

trn_status_t trn_refine_args_(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                              int32_t rover_x, int32_t rover_y, const trn_refine_cfg_t *cfg,
                              const void *out)
{
    trn_status_t st;
    if (out == NULL) {
        return TRN_E_NULL;
    }
    if ((st = common_args(global, local, rover_x, rover_y, cfg)) != TRN_OK) {
        return st;
    }
    return cfg->inlier_prob > 0.0f && cfg->inlier_prob < 1.0f ? TRN_OK : TRN_E_ARG;
}

/* The mean of ln L's fall over the two sides of the answer at distance t
 * along the unit axis e, each point's offset along perp and dz at their
 * best (valley_point), over t^2: the curvature of the quadratic through
 * the answer and those two points. */
static double fall_per_t2(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                          int32_t ry, const trn_refine_cfg_t *cfg, const trn_refine_t *at,
                          const double e[2], const double perp[2], double t)
{
    const double model2 = at->model_m * at->model_m;
    double fall = 0.0;
    int32_t side;
    for (side = 0; side < 2; ++side) {
        const double sg = side == 0 ? -1.0 : 1.0;
        double o = 0.0, dz = at->dz_m;
        fall += at->ll - valley_point(global, local, rx, ry, cfg, at->x + sg * t * e[0],
                                      at->y + sg * t * e[1], perp, at->interp_mix, model2, &o, &dz);
    }
    return 0.5 * fall / (t * t);
}

void trn_refine_shoulders_(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                           int32_t ry, const trn_refine_cfg_t *cfg, trn_refine_t *at)
{
    double lam[2], e[2][2], kap[2];
    int32_t k;
    cov_axes(at->cov_cells, lam, e[0], e[1]);
    if (!isfinite(lam[0]) || !(lam[1] > 0.0) || !isfinite(at->ll)) {
        return;
    }
    for (k = 0; k < 2; ++k) {
        const double sd = sqrt(lam[k]);
        const double near = fall_per_t2(global, local, rx, ry, cfg, at, e[k], e[1 - k],
                                        TRN_SHOULDER_NEAR_SD * sd);
        const double far = fall_per_t2(global, local, rx, ry, cfg, at, e[k], e[1 - k],
                                       TRN_SHOULDER_FAR_SD * sd);
        /* NaN (a point with no data) or a profile that does not fall: no
         * factor from it (the failure probability sees a rising profile) */
        kap[k] = near > 0.0 && far > 0.0 ? near / far : 1.0;
        kap[k] = kap[k] < 1.0 ? 1.0 : kap[k] > TRN_SHOULDER_MAX ? TRN_SHOULDER_MAX : kap[k];
    }
    at->shoulders = kap[0] > kap[1] ? kap[0] : kap[1];
    at->cov_cells[0] = kap[0] * lam[0] * e[0][0] * e[0][0] + kap[1] * lam[1] * e[1][0] * e[1][0];
    at->cov_cells[1] = kap[0] * lam[0] * e[0][1] * e[0][1] + kap[1] * lam[1] * e[1][1] * e[1][1];
    at->cov_cells[2] = kap[0] * lam[0] * e[0][0] * e[0][1] + kap[1] * lam[1] * e[1][0] * e[1][1];
}
