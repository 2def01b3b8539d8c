/* SPDX-License-Identifier: Apache-2.0 */
/* refine_pose.c - the refinement over heights, one path (trn/refine.h,
 * trn/height_heading.h): Gauss-Newton over (x, y, heading, dz) and the
 * interpolants' mix, folded out of the normal equations. trn_refine_pose is
 * trn_refine_pose_heading with the heading held at 0 (its row of the normal
 * equations the unit one), not a second implementation. Also what is read
 * along the answer's axes after it: the valley's share of the failure
 * probability and the shoulders. A pose is p[5] = (x, y, heading, dz, mix). */
#include "trn/height_heading.h"
#include "trn/refine.h"

#include <math.h>

#include "refine_int.h"

/* Normal equations and moments of one pass: four parameters and the mix's
 * column. rr, noise2 and q are the sums of q r^2, q s^2 and q over the
 * inliers within the plain clip, q = 1 / (s^2 + m^2)^2 (precision-squared
 * weights: the model variance is estimated mostly where the noise is small,
 * near the rover, not swamped by the far points' large noise). */
typedef struct {
    double a[10], b[4]; /* the normal matrix (sym4) and right-hand side */
    double ss, rr, noise2, q;
    double vv;             /* steep_pass's sum of q |grad|^4 */
    double al[4], all, bl; /* the mix: cross terms, own term, right-hand side */
    int32_t n_in, n_all;
} acc4_t;

/* The fixed part of a refinement. */
typedef struct {
    const trn_grid_f32_t *g, *l;
    const trn_refine_cfg_t *cfg;
    int32_t rx, ry;
    int fit_h; /* 1: the heading is a parameter */
} rctx_t;

/* Index of entry (p, q) of a symmetric 4 x 4 matrix kept as its upper
 * triangle row by row, 10 entries (half the work of the full one in the
 * passes, and a smaller frame). */
static int32_t sym4(int32_t p, int32_t q)
{
    const int32_t lo = p < q ? p : q, hi = p < q ? q : p;
    return lo * (7 - lo) / 2 + hi;
}

static void acc_clear(acc4_t *acc)
{
    int32_t p;
    for (p = 0; p < 10; ++p) {
        acc->a[p] = 0.0;
    }
    for (p = 0; p < 4; ++p) {
        acc->b[p] = acc->al[p] = 0.0;
    }
    acc->all = acc->bl = 0.0;
    acc->ss = acc->rr = acc->noise2 = acc->q = acc->vv = 0.0;
    acc->n_in = acc->n_all = 0;
}

/* Add w J J^T and w J r to the normal equations. */
static void acc_add(acc4_t *acc, const double jv[4], double w, double res)
{
    int32_t p, q;
    for (p = 0; p < 4; ++p) {
        for (q = p; q < 4; ++q) {
            acc->a[sym4(p, q)] += w * jv[p] * jv[q];
        }
        acc->b[p] += w * jv[p] * res;
    }
}

/* Jacobian of the model height at a sample s3 (height, gradient) seen at the
 * turned offset (tx, ty): d/d heading of (tx, ty) is (ty, -tx). */
static void jacobian(const rctx_t *c, const double s3[3], double tx, double ty, double jv[4])
{
    jv[0] = s3[1];
    jv[1] = s3[2];
    jv[2] = c->fit_h ? s3[1] * ty - s3[2] * tx : 0.0;
    jv[3] = 1.0;
}

/* One pass over local cells [i0, i1) x [j0, j1) at (x, y, th, dz, mix):
 * normal equations of the points within clip (in normalized residual
 * units), the mix's column included. */
static void accumulate(const rctx_t *c, const double pose[5], double clip, double model2,
                       int32_t i0, int32_t j0, int32_t i1, int32_t j1, acc4_t *acc)
{
    double cs, sn;
    int32_t i, j;
    trn_heading_trig_(pose[2], &cs, &sn);
    acc_clear(acc);
    for (j = j0; j < j1; ++j) {
        for (i = i0; i < i1; ++i) {
            double h = (double)TRN_GRID_AT(c->l, i, j), s3[3], ox, oy, tx, ty, v, sd, res, u, qw,
                   hw, o[2];
            double jv[4], dcb, w;
            int32_t p;
            if (!isfinite(h)) {
                continue;
            }
            trn_refine_offset_(c->cfg, c->l, i, j, c->rx, c->ry, o);
            ox = o[0];
            oy = o[1];
            tx = ox * cs + oy * sn;
            ty = -ox * sn + oy * cs;
            if (!trn_refine_sample_mix_(c->g, pose[0] + tx, pose[1] + ty, pose[4], s3, &dcb)) {
                continue;
            }
            acc->n_all += 1;
            v = trn_refine_cell_var_(c->cfg, c->l, i, j, c->rx, c->ry);
            sd = sqrt(v + model2);
            res = h - pose[3] - s3[0];
            u = res / sd;
            hw = trn_refine_weight_(c->g, pose[0] + tx, pose[1] + ty, res, sd, clip);
            if (!(hw > 0.0)) {
                continue;
            }
            if (hw >= 1.0) {
                /* the model variance from the points within the plain clip */
                qw = 1.0 / ((sd * sd) * (sd * sd));
                acc->noise2 += qw * v;
                acc->rr += qw * res * res;
                acc->q += qw;
            }
            jacobian(c, s3, tx, ty, jv);
            w = hw / (sd * sd);
            acc_add(acc, jv, w, res);
            for (p = 0; p < 4; ++p) {
                acc->al[p] += w * jv[p] * dcb;
            }
            acc->all += w * dcb * dcb;
            acc->bl += w * dcb * res;
            acc->ss += hw * u * u;
            acc->n_in += 1;
        }
    }
}

static void accumulate_all(const rctx_t *c, const double pose[5], double clip, double model2,
                           acc4_t *acc)
{
    accumulate(c, pose, clip, model2, 0, 0, c->l->width, c->l->height, acc);
}

/* Inverse of the symmetric positive definite 4 x 4 matrix a (sym4) by Gauss-Jordan
 * elimination without pivoting; 0 when a pivot is not positive or the
 * determinant is below 1e-9 x the product of the diagonal. With the heading held fixed its row and column are the unit
 * ones here. */
static int inv4(const double a[10], int fit_h, double r[16])
{
    double m[16], det = 1.0, diag = 1.0;
    int32_t p, q, k;
    for (p = 0; p < 16; ++p) {
        m[p] = a[sym4(p / 4, p % 4)];
        r[p] = (p % 5 == 0) ? 1.0 : 0.0;
    }
    if (!fit_h) {
        for (p = 0; p < 4; ++p) {
            m[2 * 4 + p] = m[p * 4 + 2] = 0.0;
        }
        m[10] = 1.0;
    }
    for (p = 0; p < 4; ++p) {
        diag *= m[p + 4 * p];
    }
    for (k = 0; k < 4; ++k) {
        const double piv = m[k + 4 * k];
        if (!(piv > 0.0)) {
            return 0;
        }
        det *= piv;
        for (q = 0; q < 4; ++q) {
            m[k * 4 + q] /= piv;
            r[k * 4 + q] /= piv;
        }
        for (p = 0; p < 4; ++p) {
            const double f = m[p * 4 + k];
            if (p == k) {
                continue;
            }
            for (q = 0; q < 4; ++q) {
                m[p * 4 + q] -= f * m[k * 4 + q];
                r[p * 4 + q] -= f * r[k * 4 + q];
            }
        }
    }
    return det > 1e-9 * diag ? 1 : 0; /* the pivots were positive: so is diag */
}

static void solve(const double inv[16], const double b[4], double d[4])
{
    int32_t p, q;
    for (p = 0; p < 4; ++p) {
        d[p] = 0.0;
        for (q = 0; q < 4; ++q) {
            d[p] += inv[p * 4 + q] * b[q];
        }
    }
}

static double next_model2(const acc4_t *acc)
{
    return trn_refine_model2_(acc->rr, acc->noise2, acc->q);
}

static double clampd(double v, double lim) { return v > lim ? lim : v < -lim ? -lim : v; }

/* Fold the mix out of the normal equations of (x, y, heading, dz, mix)
 * (Schur complement, the mix's prior, mean TRN_REFINE_MIX_MEAN and sd
 * TRN_REFINE_MIX_SD, added): a and b
 * become those of the four with the mix at its conditional best, so inv(a)
 * is their marginal covariance. g = al / all' (the mix's coupling). Returns
 * the mix's step at d = 0; for a step d of the four it is that minus g . d.
 * With the heading held fixed its column al[2] is 0 (jacobian). */
static double fold_mix(acc4_t *acc, double lam, double g[4])
{
    const double pw = 1.0 / (TRN_REFINE_MIX_SD * TRN_REFINE_MIX_SD);
    const double all = acc->all + pw, bl = acc->bl + pw * (TRN_REFINE_MIX_MEAN - lam);
    int32_t p, q;
    for (p = 0; p < 4; ++p) {
        g[p] = acc->al[p] / all;
    }
    for (p = 0; p < 4; ++p) {
        for (q = p; q < 4; ++q) {
            acc->a[sym4(p, q)] -= acc->al[p] * g[q];
        }
        acc->b[p] -= g[p] * bl;
    }
    return bl / all;
}

/* The spline step (docs/method.md 9.4): the pose error the model's
 * interpolant makes where the ground runs as the interpolating cubic
 * B-spline of the map's samples, one Gauss-Newton step of the estimate p
 * with the spline's heights in place of the model's, over the estimate's
 * inliers (the relief rule) whose spline taps are all on the map; the mix's
 * column in the normal equations with its prior's information but no pull
 * (the step moves the pose, not the mix). d: the step of (x, y, heading,
 * dz), 0 for no step (fewer than half the inliers have the spline, or the
 * normal matrix is singular). acc and inv are the caller's (dead by now). */
static void spline_step(const rctx_t *c, const double p[5], double model2, acc4_t *acc,
                        double inv[16], double d[4])
{
    double cs, sn;
    int32_t i, j, q, n_in = 0, n_sp = 0;
    trn_heading_trig_(p[2], &cs, &sn);
    acc_clear(acc);
    for (q = 0; q < 4; ++q) {
        d[q] = 0.0;
    }
    for (j = 0; j < c->l->height; ++j) {
        for (i = 0; i < c->l->width; ++i) {
            double h = (double)TRN_GRID_AT(c->l, i, j), s3[3], ox, oy, tx, ty, v, w, sp, dcb, o[2];
            double jv[4];
            if (!isfinite(h)) {
                continue;
            }
            trn_refine_offset_(c->cfg, c->l, i, j, c->rx, c->ry, o);
            ox = o[0];
            oy = o[1];
            tx = ox * cs + oy * sn;
            ty = -ox * sn + oy * cs;
            if (!trn_refine_sample_mix_(c->g, p[0] + tx, p[1] + ty, p[4], s3, &dcb)) {
                continue;
            }
            v = trn_refine_cell_var_(c->cfg, c->l, i, j, c->rx, c->ry) + model2;
            w = trn_refine_weight_(c->g, p[0] + tx, p[1] + ty, h - p[3] - s3[0], sqrt(v),
                                   TRN_REFINE_CLIP_RELIEF) /
                v;
            if (!(w > 0.0)) {
                continue;
            }
            n_in += 1;
            if (!trn_refine_spline_(c->g, p[0] + tx, p[1] + ty, &sp)) {
                continue;
            }
            n_sp += 1;
            jacobian(c, s3, tx, ty, jv);
            acc_add(acc, jv, w, sp - s3[0]);
            for (q = 0; q < 4; ++q) {
                acc->al[q] += w * jv[q] * dcb;
            }
            acc->all += w * dcb * dcb;
            acc->bl += w * dcb * (sp - s3[0]);
        }
    }
    if (n_sp < 8 || 2 * n_sp < n_in) {
        return;
    }
    /* the mix folded out with its prior's information; taken at the prior's
     * mean, the prior pulls nothing (d is scratch until the solve) */
    (void)fold_mix(acc, TRN_REFINE_MIX_MEAN, d);
    if (inv4(acc->a, c->fit_h, inv)) {
        solve(inv, acc->b, d);
    } else {
        for (q = 0; q < 4; ++q) {
            d[q] = 0.0;
        }
    }
}

/* u^T V u, V = [I, -g] N_b [I, -g]^T with N_b = [[a, al], [al^T, all]], a
 * block's normal equations in acc: the variance, under the noise model, of
 * u . (b - g bl), a block's score with the mix profiled out. */
static double block_var(const acc4_t *acc, const double g[4], const double u[4])
{
    double ua = 0.0, ug = 0.0, v = 0.0;
    int32_t r, t;
    for (r = 0; r < 4; ++r) {
        for (t = 0; t < 4; ++t) {
            v += u[r] * acc->a[sym4(r, t)] * u[t];
        }
        ua += u[r] * acc->al[r];
        ug += u[r] * g[r];
    }
    return v - 2.0 * ua * ug + acc->all * ug * ug;
}

/* Block sandwich A^-1 B A^-1, B the sum over TRN_REFINE_BLOCK x
 * TRN_REFINE_BLOCK blocks of local cells of the outer product of each
 * block's score: residuals correlated within a block (the map's
 * interpolation error is smooth over about a cell) add up there instead of
 * averaging out. The model covariance is a lower bound: the block estimate
 * is noisy, and independent errors must not shrink it, nor raise it by
 * chance (docs/method.md 9, "the floors"). Returns the inflation
 * factor of the model covariance already in pos (and full: inv meat inv
 * with the cells' fitted variances, steep_pass; inv x the gated reduced
 * chi-square with TRN_REFINE_STEEP 0), the larger of its variance
 * ratios over x, y (and the heading when fitted), each where beyond
 * TRN_REFINE_SYS_Z of its sampling sds under the noise model (h0: the
 * variance each block's term would have under the noise model alone, its
 * own normal matrix with the mix profiled out), else 1; *ll_f the larger ratio ungated, against the model
 * times max(1, pos->chi2_dof), at least 1 (ln L's divisor, as before the gate).
 * Each block's score has the mix profiled out (b - g bl); (inv
 * meat inv)[q][q] is summed as the squares of (inv score)[q] block by
 * block, so no meat matrix is kept. acc is the caller's (the stack stays
 * small). */
static double sandwich(const rctx_t *c, const double p[5], double model2, const double inv[16],
                       const double g[4], const trn_refine_t *pos, const trn_refine3_t *full,
                       acc4_t *acc, double *ll_f)
{
    double f = 1.0, fg = 1.0, sw[3] = {0.0, 0.0, 0.0}, h0[3] = {0.0, 0.0, 0.0};
    const int32_t nq = c->fit_h ? 3 : 2;
    int32_t bi, bj, q, s;
    for (bj = 0; bj < c->l->height; bj += TRN_REFINE_BLOCK) {
        for (bi = 0; bi < c->l->width; bi += TRN_REFINE_BLOCK) {
            int32_t i1 = bi + TRN_REFINE_BLOCK < c->l->width ? bi + TRN_REFINE_BLOCK : c->l->width;
            int32_t j1 = bj + TRN_REFINE_BLOCK < c->l->height ? bj + TRN_REFINE_BLOCK
                                                              : c->l->height;
            accumulate(c, p, TRN_REFINE_CLIP_RELIEF, model2, bi, bj, i1, j1, acc);
            for (q = 0; q < nq; ++q) {
                double t = 0.0; /* (inv score)[q] */
                for (s = 0; s < 4; ++s) {
                    t += inv[q * 4 + s] * (acc->b[s] - g[s] * acc->bl);
                }
                sw[q] += t * t;
                t = block_var(acc, g, &inv[(size_t)q * 4u]);
                h0[q] += t * t;
            }
        }
    }
    for (q = 0; q < nq; ++q) {
        /* ln L's ratio against the model times max(1, chi2), as before the gate */
        const double ratio = sw[q] / (inv[q + 4 * q] * (pos->chi2_dof > 1.0 ? pos->chi2_dof : 1.0));
        /* the model's variance: x, y from pos, the heading (fitted: full is set) from full */
        const double den = (q == 2 && full != NULL) ? full->cov3[8] : pos->cov_cells[q % 2];
        const double gated = trn_refine_excess_(sw[q] / den, sqrt(2.0 * h0[q]) / inv[q + 4 * q]);
        f = ratio > f ? ratio : f;
        fg = gated > fg ? gated : fg;
    }
    *ll_f = f;
    return fg;
}

/* trn_height_search's mixture ln L at the refined pose p (the offsets
 * turned by the heading): the mixed interpolant,
 * offset and model variance; a point with no height under it counts
 * ln((1 - a) K), K = 1 / (10 sd of the seen local heights). */
static double refined_ll(const rctx_t *c, const double p[5], double model2)
{
    const double two_pi = 6.283185307179586, a = (double)c->cfg->inlier_prob;
    const double floor_m = (double)c->cfg->noise_m;
    int32_t i, j, n_seen = 0;
    double spread = trn_refine_local_spread_(c->l, &n_seen), k, lout, ll = 0.0, cs, sn;
    k = 1.0 / (10.0 * (spread > floor_m ? spread : floor_m));
    lout = log((1.0 - a) * k);
    trn_heading_trig_(p[2], &cs, &sn);
    for (j = 0; j < c->l->height; ++j) {
        for (i = 0; i < c->l->width; ++i) {
            double h = (double)TRN_GRID_AT(c->l, i, j), s3[3], dcb, ox, oy, v, u, o[2];
            if (!isfinite(h)) {
                continue;
            }
            trn_refine_offset_(c->cfg, c->l, i, j, c->rx, c->ry, o);
            ox = o[0];
            oy = o[1];
            if (!trn_refine_sample_mix_(c->g, p[0] + ox * cs + oy * sn, p[1] - ox * sn + oy * cs,
                                        p[4], s3, &dcb)) {
                ll += lout;
                continue;
            }
            v = trn_refine_cell_var_(c->cfg, c->l, i, j, c->rx, c->ry) + model2;
            u = h - p[3] - s3[0];
            ll += log(a * exp(-0.5 * u * u / v) / sqrt(two_pi * v) + (1.0 - a) * k);
        }
    }
    return ll;
}

/* The failed answer: the start, infinite variances. */
static void set_fail(trn_refine_t *pos, trn_refine3_t *full, int32_t ix, int32_t iy, double th)
{
    int32_t p;
    pos->x = (double)ix;
    pos->y = (double)iy;
    pos->cov_cells[0] = pos->cov_cells[1] = (double)INFINITY;
    pos->cov_cells[2] = 0.0;
    pos->inflation = pos->ll_inflation = 1.0;
    pos->spline_step[0] = pos->spline_step[1] = 0.0;
    pos->interp_mix = TRN_REFINE_MIX_MEAN;
    pos->shoulders = 1.0;
    pos->ll = -(double)INFINITY;
    if (full != NULL) {
        full->heading_rad = th;
        full->spline_step_heading_rad = 0.0;
        for (p = 0; p < 9; ++p) {
            full->cov3[p] = (p % 4 == 0) ? (double)INFINITY : 0.0;
        }
    }
}

/* Farthest seen local cell from the rover, cells (at least 1). */
static double far_cells(const rctx_t *c)
{
    int32_t i, j;
    double r2 = 1.0;
    for (j = 0; j < c->l->height; ++j) {
        for (i = 0; i < c->l->width; ++i) {
            const double ox = (double)(i - c->rx), oy = (double)(j - c->ry);
            if (isfinite(TRN_GRID_AT(c->l, i, j)) && ox * ox + oy * oy > r2) {
                r2 = ox * ox + oy * oy;
            }
        }
    }
    return sqrt(r2);
}


/* The start: the offset dz alone over every point, then dz and the model
 * variance (what the residuals hold beyond the noise model: the map's own
 * interpolation error, a stale map), re-estimated at every step after, so
 * the weights and the clip follow the data.
 * Returns the seen points with a global height. */
static int32_t start(const rctx_t *c, double p[5], double *model2, acc4_t *acc)
{
    int32_t it, n_all;
    accumulate_all(c, p, (double)INFINITY, 0.0, acc);
    n_all = acc->n_all;
    if (n_all < 8) {
        return n_all;
    }
    p[3] = acc->b[3] / acc->a[9];
    for (it = 0; it < 3; ++it) {
        accumulate_all(c, p, it == 0 ? (double)INFINITY : TRN_REFINE_CLIP, *model2, acc);
        if (acc->n_in < 8) {
            break;
        }
        *model2 = next_model2(acc);
        p[3] += acc->b[3] / acc->a[9];
    }
    return n_all;
}

/* Gauss-Newton to convergence, the mix folded out at each step and moved
 * by its conditional step, kept within two prior sds; 0 when it
 * fails (singular, or left the start's neighbourhood). */
static int iterate(const rctx_t *c, double x0, double y0, double th0, double max_turn, double p[5],
                   double *model2, acc4_t *acc, double inv[16], double g[4], trn_refine_t *pos)
{
    const double rmax = far_cells(c);
    const double lam_lo = TRN_REFINE_MIX_MEAN - 2.0 * TRN_REFINE_MIX_SD;
    const double lam_hi = TRN_REFINE_MIX_MEAN + 2.0 * TRN_REFINE_MIX_SD;
    double d[4], dl;
    int32_t it, q, phase_end = TRN_REFINE_MAX_ITER;
    /* two phases: the plain clip from the integer start, then the relief
     * rule (trn_refine_weight_) from the first phase's estimate */
    for (it = 0; it < 2 * TRN_REFINE_MAX_ITER; ++it) {
        accumulate_all(c, p, it < phase_end ? TRN_REFINE_CLIP : TRN_REFINE_CLIP_RELIEF, *model2,
                       acc);
        *model2 = next_model2(acc);
        dl = fold_mix(acc, p[4], g);
        if (acc->n_in < 8 || !inv4(acc->a, c->fit_h, inv)) {
            pos->n_used = acc->n_in;
            return 0;
        }
        solve(inv, acc->b, d);
        d[0] = clampd(d[0], 0.5);
        d[1] = clampd(d[1], 0.5);
        d[2] = c->fit_h ? clampd(d[2], 0.5 / rmax) : 0.0; /* half a cell of arc */
        for (q = 0; q < 4; ++q) {
            p[q] += d[q];
            dl -= g[q] * d[q];
        }
        /* within two prior sds: beyond, the "mix" would be a free
         * sharpening that fits the map to anything */
        p[4] += dl;
        p[4] = p[4] > lam_hi ? lam_hi : p[4] < lam_lo ? lam_lo : p[4];
        pos->iterations = it + 1;
        if (fabs(p[0] - x0) > TRN_REFINE_MAX_SHIFT || fabs(p[1] - y0) > TRN_REFINE_MAX_SHIFT ||
            fabs(p[2] - th0) > max_turn) {
            return 0;
        }
        if (it + 1 == phase_end ||
            (fabs(d[0]) < 1e-4 && fabs(d[1]) < 1e-4 && fabs(d[2]) * rmax < 1e-4)) {
            if (it >= phase_end) {
                break;
            }
            phase_end = it + 1; /* the first phase converged (or ran out) */
        }
    }
    return 1;
}

#if TRN_REFINE_STEEP
/* The cells' variances at the estimate p (docs/method.md 9.5): the noise
 * model's s^2, a model variance m^2 and the steep cells' sp2 |grad|^2, the
 * height error of a horizontal misplacement of variance sp2 (cells^2) on
 * the map's gradient under the cell: where the map cannot follow what a
 * cell averages (edges sharper than a cell) its error grows with the
 * slope, and the slope is where the pose's information is. var NULL: the
 * moments of y = r^2 / (1 - h) - s^2 on (1, |grad|^2) into acc's scalars
 * (no fields of their own: acc is on the deepest stack; q the weights' sum,
 * noise2 and vv those of q |grad|^2 and q |grad|^4, rr and ss those of q y
 * and q |grad|^2 y; weights
 * 1 / (s^2 + model2)^2, every inlier, those the relief rule down-weights
 * too, where the steep cells' residuals are; h the cell's
 * leverage w Jt^T inv Jt, the share of its residual the fit takes: the
 * steep cells are also those the pose leans on). var = (m^2, sp2): the
 * meat sum w^2 (s^2 + m^2 + sp2 |grad|^2) Jt Jt^T over the inliers into
 * acc->a (Jt the Jacobian with the mix profiled out, J - g dcb; w the
 * refinement's weight), so the covariance is inv meat inv. The moments
 * are those of the surface that fits the cells better: the model's
 * residual r, or the answer's, the answer being p plus the spline step
 * (lam sd, lam the mix held to [0, 1]) and its surface the model plus lam
 * (S - M), so r - lam (S - M - J . sd) (J . sd the part of S - M the step
 * moves the pose by; a cell without the spline keeps r). Where the step
 * removes an error the model's residuals still hold it; where the ground
 * is the bilinear surface and the mix small but not 0, the answer's
 * surface misfits. The smaller weighted sum of y is taken (docs/method.md
 * 9.5; the answer's sums in b[0], b[1], free in this pass). acc is the
 * caller's (dead by now). */
static void steep_pass(const rctx_t *c, const double p[5], double model2, const double inv[16],
                       const double g[4], const double sd[4], const double *var, acc4_t *acc)
{
    const double lam = p[4] < 0.0 ? 0.0 : p[4] > 1.0 ? 1.0 : p[4];
    double cs, sn;
    int32_t i, j, a, b;
    acc_clear(acc);
    trn_heading_trig_(p[2], &cs, &sn);
    for (j = 0; j < c->l->height; ++j) {
        for (i = 0; i < c->l->width; ++i) {
            double h = (double)TRN_GRID_AT(c->l, i, j), s3[3], tx, ty, s2, res, hw, jt[4], dcb, w,
                   lev = 0.0, gg, o[2], sp;
            if (!isfinite(h)) {
                continue;
            }
            trn_refine_offset_(c->cfg, c->l, i, j, c->rx, c->ry, o);
            tx = o[0] * cs + o[1] * sn;
            ty = -o[0] * sn + o[1] * cs;
            if (!trn_refine_sample_mix_(c->g, p[0] + tx, p[1] + ty, p[4], s3, &dcb)) {
                continue;
            }
            s2 = trn_refine_cell_var_(c->cfg, c->l, i, j, c->rx, c->ry);
            res = h - p[3] - s3[0];
            hw = trn_refine_weight_(c->g, p[0] + tx, p[1] + ty, res, sqrt(s2 + model2),
                                    TRN_REFINE_CLIP_RELIEF);
            if (!(hw > 0.0)) {
                continue;
            }
            jacobian(c, s3, tx, ty, jt);
            gg = jt[0] * jt[0] + jt[1] * jt[1];
            for (a = 0; a < 4; ++a) {
                jt[a] -= g[a] * dcb;
            }
            w = hw / (s2 + model2);
            /* the points' unknown centroid: a position error of the cell,
             * its height's error the slope times it (0 with the centroids
             * or without the counts); the fit (its y and weights) and the
             * covariance take it, the refinement's weights w do not */
            s2 += gg * trn_refine_cell_jitter_(c->cfg, c->l, i, j);
            if (var != NULL) {
                acc_add(acc, jt, w * w * (s2 + var[0] + var[1] * gg), 0.0);
                continue;
            }
            for (a = 0; a < 4; ++a) {
                for (b = 0; b < 4; ++b) {
                    lev += jt[a] * inv[a * 4 + b] * jt[b];
                }
            }
            lev *= w;
            if (lev < 1.0) {
                const double q = 1.0 / ((s2 + model2) * (s2 + model2));
                const double y = res * res / (1.0 - lev) - s2;
                acc->q += q;
                acc->noise2 += q * gg;
                acc->vv += q * gg * gg;
                acc->rr += q * y;
                acc->ss += q * gg * y;
                /* the answer's residual */
                if (lam > 0.0 && trn_refine_spline_(c->g, p[0] + tx, p[1] + ty, &sp)) {
                    jacobian(c, s3, tx, ty, jt);
                    res -= lam *
                           (sp - s3[0] - (jt[0] * sd[0] + jt[1] * sd[1] + jt[2] * sd[2] + sd[3]));
                }
                sp = res * res / (1.0 - lev) - s2;
                acc->b[0] += q * sp;
                acc->b[1] += q * gg * sp;
            }
        }
    }
    if (var == NULL && acc->b[0] < acc->rr) {
        /* the answer's surface fits the cells better than the model's */
        acc->rr = acc->b[0];
        acc->ss = acc->b[1];
    }
}

/* (m^2, sp2) from steep_pass's moments: the weighted least squares of y on
 * (1, |grad|^2), each at least 0 (the better one-term fit where the pair
 * has one negative). */
static void steep_fit(const acc4_t *acc, double var[2])
{
    const double qg = acc->noise2, qgg = acc->vv, rg = acc->ss; /* steep_pass's moments */
    const double det = acc->q * qgg - qg * qg;
    const double m0 = acc->q > 0.0 && acc->rr > 0.0 ? acc->rr / acc->q : 0.0;
    const double s0 = qgg > 0.0 && rg > 0.0 ? rg / qgg : 0.0;
    var[0] = det > 1e-12 * acc->q * qgg ? (qgg * acc->rr - qg * rg) / det : -1.0;
    var[1] = det > 1e-12 * acc->q * qgg ? (acc->q * rg - qg * acc->rr) / det : -1.0;
    if (!(var[0] >= 0.0 && var[1] >= 0.0)) {
        /* the one-term fits' sums of squares, less the common constant */
        const double e_m = acc->q * m0 * m0 - 2.0 * m0 * acc->rr;
        const double e_s = qgg * s0 * s0 - 2.0 * s0 * rg;
        var[0] = e_m <= e_s ? m0 : 0.0;
        var[1] = e_m <= e_s ? 0.0 : s0;
    }
}

/* (inv meat inv)[q][r], the meat in acc->a (sym4). */
static double sandwich_qr(const double inv[16], const acc4_t *acc, int32_t q, int32_t r)
{
    double t = 0.0;
    int32_t k, l;
    for (k = 0; k < 4; ++k) {
        for (l = 0; l < 4; ++l) {
            t += inv[q * 4 + k] * acc->a[sym4(k, l)] * inv[l * 4 + r];
        }
    }
    return t;
}
#endif

/* The covariance at the converged estimate p: the mix folded
 * out (the marginal of the four), inv meat inv with the cells' fitted
 * variances (steep_pass; inv x the gated reduced chi-square with
 * TRN_REFINE_STEEP 0) and the block sandwich's inflation. 0 when the
 * normal matrix is singular or under half the points are inliers. */
static int covariance(const rctx_t *c, const double p[5], double model2, const double sd[4],
                      acc4_t *acc, double inv[16], double g[4], trn_refine_t *pos,
                      trn_refine3_t *full)
{
    double f;
#if !TRN_REFINE_STEEP
    double chi2;
#endif
    int32_t q, r;
#if !TRN_REFINE_STEEP
    (void)sd; /* the answer's residuals feed the steep cells' fit only */
#endif
    accumulate_all(c, p, TRN_REFINE_CLIP_RELIEF, model2, acc);
    (void)fold_mix(acc, p[4], g);
    pos->n_used = acc->n_in;
    if (acc->n_in < 8 || 2 * acc->n_in < acc->n_all || !inv4(acc->a, c->fit_h, inv)) {
        return 0;
    }
    /* four parameters and the mix (three with the heading held) */
    pos->chi2_dof = acc->ss / (double)(acc->n_in - (c->fit_h ? 5 : 4));
#if !TRN_REFINE_STEEP
    chi2 = trn_refine_excess_(pos->chi2_dof, sqrt(2.0 / (double)(acc->n_in - (c->fit_h ? 5 : 4))));
#endif
#if TRN_REFINE_STEEP
    {
        double var[2];
        steep_pass(c, p, model2, inv, g, sd, NULL, acc);
        steep_fit(acc, var);
        steep_pass(c, p, model2, inv, g, sd, var, acc);
    }
#endif
    /* the model's covariance into the outputs, then the sandwich's factor
     * against it (no 3 x 3 copy: the frame is on the deepest stack) */
    for (q = 0; q < 3; ++q) {
        for (r = 0; r < 3; ++r) {
            /* the elimination's inverse is symmetric to rounding: its mean */
#if TRN_REFINE_STEEP
            const double v = (c->fit_h || (q < 2 && r < 2))
                                 ? 0.5 * (sandwich_qr(inv, acc, q, r) + sandwich_qr(inv, acc, r, q))
                                 : 0.0;
#else
            const double v = (c->fit_h || (q < 2 && r < 2))
                                 ? 0.5 * (inv[q * 4 + r] + inv[r * 4 + q]) * chi2
                                 : 0.0;
#endif
            if (full != NULL) {
                full->cov3[q * 3 + r] = v;
            }
            if (q <= r && r < 2) {
                pos->cov_cells[q == r ? q : 2] = v; /* xx, yy, xy */
            }
        }
    }
    f = sandwich(c, p, model2, inv, g, pos, full, acc, &pos->ll_inflation);
    if (c->cfg->point_count != NULL) {
        /* the cells' noise and their centroids' jitter known: the model's
         * covariance, without the block sandwich's guard against the
         * errors it did not know (docs/method.md 9.5, "the point counts") */
        f = 1.0;
    }
    pos->inflation = f;
    for (q = 0; q < 9 && full != NULL; ++q) {
        full->cov3[q] *= f;
    }
    for (q = 0; q < 3; ++q) {
        pos->cov_cells[q] *= f;
    }
    return 1;
}

/* The refinement's context with the heading held at 0. */
static void ctx_level(rctx_t *c, const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                      int32_t rx, int32_t ry, const trn_refine_cfg_t *cfg)
{
    c->g = global;
    c->l = local;
    c->cfg = cfg;
    c->rx = rx;
    c->ry = ry;
    c->fit_h = 0;
}

/* The refinement from (ix, iy) at heading_rad, the heading a parameter
 * when max_turn_rad > 0 (trn_refine_pose_heading's contract; the grids,
 * cfg and the output checked by the caller): the answer into pos, and with
 * full (whose pos is pos) the heading, cov3 and the heading's part of the
 * shift; full NULL with the heading held (trn_refine_pose). No struct of
 * outputs is built on the way: the (x, y) path is the deepest stack of
 * trn_localize_dem, whose refinements call it directly (refine_int.h). */
trn_status_t trn_refine_run_(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                             int32_t rover_x, int32_t rover_y, int32_t ix, int32_t iy,
                             double heading_rad, double max_turn_rad, const trn_refine_cfg_t *cfg,
                             trn_refine_t *pos, trn_refine3_t *full)
{
    rctx_t c;
    acc4_t acc;
    double p[5], model2 = 0.0, inv[16], g[4], sd[4] = {0.0, 0.0, 0.0, 0.0};
    int32_t q;
    int ok;

    if (!(fabs(heading_rad) <= TRN_HEADING_MAX_WINDOW_RAD) ||
        !(max_turn_rad >= 0.0 && max_turn_rad <= TRN_HEADING_MAX_WINDOW_RAD)) {
        return TRN_E_ARG;
    }
    ctx_level(&c, global, local, rover_x, rover_y, cfg);
    c.fit_h = max_turn_rad > 0.0 ? 1 : 0;
    pos->dz_m = 0.0;
    pos->model_m = 0.0;
    pos->chi2_dof = 0.0;
    pos->n_used = pos->n_seen = pos->iterations = 0;
    set_fail(pos, full, ix, iy, heading_rad);
    if (ix < 0 || iy < 0 || ix >= global->width || iy >= global->height) {
        return TRN_E_RANGE;
    }
    p[0] = (double)ix;
    p[1] = (double)iy;
    p[2] = heading_rad;
    p[3] = 0.0;
    p[4] = TRN_REFINE_MIX_MEAN;
    pos->n_seen = start(&c, p, &model2, &acc);
    if (pos->n_seen < 8) {
        return TRN_E_NODATA;
    }
    ok = iterate(&c, (double)ix, (double)iy, heading_rad, max_turn_rad, p, &model2, &acc, inv, g,
                 pos);
    /* the spline step first: the covariance's variances may be the
     * residuals of the answer it makes */
    if (ok) {
        spline_step(&c, p, model2, &acc, inv, sd);
    }
    if (!ok || !covariance(&c, p, model2, sd, &acc, inv, g, pos, full)) {
        q = pos->n_used;
        set_fail(pos, full, ix, iy, heading_rad);
        pos->n_used = q;
        return TRN_E_ILLCOND;
    }
    pos->x = p[0];
    pos->y = p[1];
    pos->dz_m = p[3];
    pos->model_m = sqrt(model2);
    pos->interp_mix = p[4];
    pos->ll = refined_ll(&c, p, model2);
    /* the spline step times the mix held to [0, 1]: none where the data
     * say bilinear, the whole step where they say bicubic or smoother */
    {
        const double lam = p[4] < 0.0 ? 0.0 : p[4] > 1.0 ? 1.0 : p[4];
        pos->spline_step[0] = -lam * sd[0];
        pos->spline_step[1] = -lam * sd[1];
        if (full != NULL) {
            full->heading_rad = p[2];
            full->spline_step_heading_rad = -lam * sd[2];
        }
    }
    return TRN_OK;
}

trn_status_t trn_refine_pose_heading(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                                     int32_t rover_x, int32_t rover_y, int32_t ix, int32_t iy,
                                     double heading_rad, double max_turn_rad,
                                     const trn_refine_cfg_t *cfg, trn_refine3_t *out)
{
    trn_status_t st;
    if ((st = trn_refine_args_(global, local, rover_x, rover_y, cfg, out)) != TRN_OK) {
        return st;
    }
    return trn_refine_run_(global, local, rover_x, rover_y, ix, iy, heading_rad, max_turn_rad, cfg,
                           &out->pos, out);
}

/* The same refinement with the heading held at 0: one path. */
trn_status_t trn_refine_pose(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                             int32_t rover_x, int32_t rover_y, int32_t ix, int32_t iy,
                             const trn_refine_cfg_t *cfg, trn_refine_t *out)
{
    trn_status_t st;
    /* bad arguments leave out as it was */
    if ((st = trn_refine_args_(global, local, rover_x, rover_y, cfg, out)) != TRN_OK) {
        return st;
    }
    return trn_refine_run_(global, local, rover_x, rover_y, ix, iy, 0.0, 0.0, cfg, out, NULL);
}

/* ln L on the line through (px, py) across the valley: the pose (px, py) +
 * o e2 with the perpendicular offset o and the offset dz at their best
 * (Gauss-Newton from *o, *dz, at most TRN_VALLEY_ITER steps, the relief
 * rule; the mix lam, the model variance model2 and the heading held): the
 * refinement's own normal equations and ln L. */
static double valley_point(const rctx_t *c, double heading, double px, double py,
                           const double e2[2], double lam, double model2, double *o, double *dz)
{
    acc4_t acc;
    double p[5];
    int32_t it;
    p[2] = heading;
    p[4] = lam;
    for (it = 0; it < TRN_VALLEY_ITER; ++it) {
        double aoo, aoz, azz, bo, det, step;
        p[0] = px + *o * e2[0];
        p[1] = py + *o * e2[1];
        p[3] = *dz;
        accumulate_all(c, p, TRN_REFINE_CLIP_RELIEF, model2, &acc);
        /* rows and columns 0, 1, 3 of the four: x, y, dz */
        aoo = e2[0] * e2[0] * acc.a[0] + 2.0 * e2[0] * e2[1] * acc.a[1] + e2[1] * e2[1] * acc.a[4];
        aoz = e2[0] * acc.a[3] + e2[1] * acc.a[6];
        azz = acc.a[9];
        bo = e2[0] * acc.b[0] + e2[1] * acc.b[1];
        det = aoo * azz - aoz * aoz;
        if (acc.n_in < 8 || !(det > 1e-12 * aoo * azz)) {
            break;
        }
        step = (azz * bo - aoz * acc.b[3]) / det;
        step = step > 0.5 ? 0.5 : step < -0.5 ? -0.5 : step;
        *dz += (aoo * acc.b[3] - aoz * bo) / det;
        *o += step;
        if (fabs(step) < 1e-3) {
            break;
        }
    }
    p[0] = px + *o * e2[0];
    p[1] = py + *o * e2[1];
    p[3] = *dz;
    return refined_ll(c, p, model2);
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
                               const trn_refine_t *at, double heading_rad, double infl,
                               const double lo[2], const double hi[2])
{
    rctx_t c;
    const double h = TRN_VALLEY_STEP_CELLS;
    const int32_t kmax = (int32_t)(TRN_VALLEY_REACH_CELLS / TRN_VALLEY_STEP_CELLS + 0.5);
    const double model2 = at->model_m * at->model_m;
    double in = 1.0, out = 0.0, d1[2] = {-INFINITY, -INFINITY}, q, lam[2], e1[2], e2[2];
    int32_t side, k;
    ctx_level(&c, global, local, rx, ry, cfg);
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
            d = (valley_point(&c, heading_rad, px, py, e2, at->interp_mix, model2, &o, &dz) -
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

/* The mean of ln L's fall over the two sides of the answer at distance t
 * along the unit axis e, each point's offset along perp and dz at their
 * best (valley_point), over t^2: the curvature of the quadratic through
 * the answer and those two points. */
static double fall_per_t2(const rctx_t *c, const trn_refine_t *at, double heading,
                          const double e[2], const double perp[2], double t)
{
    const double model2 = at->model_m * at->model_m;
    double fall = 0.0;
    int32_t side;
    for (side = 0; side < 2; ++side) {
        const double sg = side == 0 ? -1.0 : 1.0;
        double o = 0.0, dz = at->dz_m;
        fall += at->ll - valley_point(c, heading, at->x + sg * t * e[0], at->y + sg * t * e[1],
                                      perp, at->interp_mix, model2, &o, &dz);
    }
    return 0.5 * fall / (t * t);
}

void trn_refine_shoulders_(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                           int32_t ry, const trn_refine_cfg_t *cfg, double heading_rad,
                           trn_refine_t *at, double cov3[9])
{
    rctx_t c;
    double lam[2], e[2][2], kap[2], t[4];
    int32_t k, q;
    ctx_level(&c, global, local, rx, ry, cfg);
    cov_axes(at->cov_cells, lam, e[0], e[1]);
    if (!isfinite(lam[0]) || !(lam[1] > 0.0) || !isfinite(at->ll)) {
        return;
    }
    for (k = 0; k < 2; ++k) {
        const double sd = sqrt(lam[k]);
        const double near = fall_per_t2(&c, at, heading_rad, e[k], e[1 - k],
                                        TRN_SHOULDER_NEAR_SD * sd);
        const double far = fall_per_t2(&c, at, heading_rad, e[k], e[1 - k],
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
    if (cov3 == NULL) {
        return;
    }
    /* the (x, y, heading) covariance by the same stretch of the position,
     * T = sum_k sqrt(kap_k) e_k e_k^T on x and y (T C T^T is the 2 x 2
     * above), the heading untouched: cov3 <- T3 cov3 T3^T */
    for (q = 0; q < 4; ++q) {
        const int32_t r = q / 2, s = q % 2;
        t[q] = sqrt(kap[0]) * e[0][r] * e[0][s] + sqrt(kap[1]) * e[1][r] * e[1][s];
    }
    for (q = 0; q < 3; ++q) { /* columns: cov3 T3^T, row q */
        double *row = &cov3[(size_t)q * 3u];
        const double a = row[0], b = row[1];
        row[0] = a * t[0] + b * t[1];
        row[1] = a * t[2] + b * t[3];
    }
    for (q = 0; q < 3; ++q) { /* rows: T3 (cov3 T3^T) */
        const double a = cov3[q], b = cov3[3 + q];
        cov3[q] = t[0] * a + t[1] * b;
        cov3[3 + q] = t[2] * a + t[3] * b;
    }
}
