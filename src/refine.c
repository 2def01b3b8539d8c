/* refine.c - continuous sub-cell pose refinement over heights (trn/refine.h). */
#include "trn/refine.h"

#include <math.h>

/* Bilinear height at fractional cell (x, y) (centres at integers) and its
 * exact gradient (per cell) inside the containing cell; 0 when a corner is
 * off the grid or missing. */
static int sample(const trn_grid_f32_t *g, double x, double y, double out[3])
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
    double rr, noise2;   /* sums of squared residuals and of noise variances (inliers) */
    int32_t n_in, n_all; /* inliers, points with a global height */
} accum_t;

/* One pass over the seen local points at pose (x, y) and offset dz: normal
 * equations of the points within clip (in normalized residual units). */
static void accumulate(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                       int32_t ry, double x, double y, double dz, double clip, double model2,
                       const trn_refine_cfg_t *cfg, accum_t *acc)
{
    int32_t i, j;
    for (i = 0; i < 9; ++i) {
        acc->a[i] = 0.0;
    }
    acc->b[0] = acc->b[1] = acc->b[2] = 0.0;
    acc->ss = acc->rr = acc->noise2 = 0.0;
    acc->n_in = acc->n_all = 0;
    for (j = 0; j < local->height; ++j) {
        for (i = 0; i < local->width; ++i) {
            double h = (double)TRN_GRID_AT(local, i, j), s3[3], px, py, r_m, sd, w, res, u, jv[3];
            int32_t p, q;
            if (!isfinite(h)) {
                continue;
            }
            px = (double)(i - rx);
            py = (double)(j - ry);
            if (!sample(global, x + px, y + py, s3)) {
                continue;
            }
            acc->n_all += 1;
            r_m = (double)cfg->cell_m * sqrt(px * px + py * py);
            sd = (double)cfg->noise_m + (double)cfg->noise_k_per_m * r_m * r_m;
            w = sd * sd;
            sd = sqrt(w + model2);
            res = h - dz - s3[0];
            u = res / sd;
            if (fabs(u) > clip) {
                continue;
            }
            acc->noise2 += w;
            acc->rr += res * res;
            w = 1.0 / (sd * sd);
            jv[0] = s3[1];
            jv[1] = s3[2];
            jv[2] = 1.0;
            for (p = 0; p < 3; ++p) {
                for (q = 0; q < 3; ++q) {
                    acc->a[p * 3 + q] += w * jv[p] * jv[q];
                }
                acc->b[p] += w * jv[p] * res;
            }
            acc->ss += u * u;
            acc->n_in += 1;
        }
    }
}

/* Model variance that makes the inliers' mean squared residual equal their
 * mean total variance (noise + model), never negative. */
static double next_model2(const accum_t *acc)
{
    double m = (acc->rr - acc->noise2) / (double)acc->n_in;
    return m > 0.0 ? m : 0.0;
}

static void set_fail(trn_refine_t *out, int32_t ix, int32_t iy)
{
    out->x = (double)ix;
    out->y = (double)iy;
    out->cov_cells[0] = out->cov_cells[1] = INFINITY;
    out->cov_cells[2] = 0.0;
}

trn_status_t trn_refine_pose(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                             int32_t rover_x, int32_t rover_y, int32_t ix, int32_t iy,
                             const trn_refine_cfg_t *cfg, trn_refine_t *out)
{
    trn_status_t st;
    accum_t acc;
    double x = (double)ix, y = (double)iy, dz = 0.0, model2 = 0.0, inv[9], d[3], chi2;
    int32_t it;

    if (global == NULL || local == NULL || cfg == NULL || out == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_grid_f32_check(global)) != TRN_OK || (st = trn_grid_f32_check(local)) != TRN_OK) {
        return st;
    }
    if (!(cfg->cell_m > 0.0f && cfg->cell_m <= 1000.0f) || !(cfg->noise_m > 0.0f && cfg->noise_m <= 1000.0f) ||
        !(cfg->noise_k_per_m >= 0.0f && cfg->noise_k_per_m <= 1000.0f) || rover_x < -TRN_MAX_DIM ||
        rover_y < -TRN_MAX_DIM || rover_x > local->width - 1 + TRN_MAX_DIM ||
        rover_y > local->height - 1 + TRN_MAX_DIM) {
        return TRN_E_ARG;
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
    accumulate(global, local, rover_x, rover_y, x, y, 0.0, (double)INFINITY, 0.0, cfg, &acc);
    out->n_seen = acc.n_all;
    if (acc.n_all < 8) {
        return TRN_E_NODATA;
    }
    dz = acc.b[2] / acc.a[8];
    for (it = 0; it < 3; ++it) {
        accumulate(global, local, rover_x, rover_y, x, y, dz, it == 0 ? (double)INFINITY : TRN_REFINE_CLIP, model2, cfg,
                   &acc);
        if (acc.n_in < 8) {
            break;
        }
        model2 = next_model2(&acc);
        dz += acc.b[2] / acc.a[8];
    }
    for (it = 0; it < TRN_REFINE_MAX_ITER; ++it) {
        accumulate(global, local, rover_x, rover_y, x, y, dz, TRN_REFINE_CLIP, model2, cfg, &acc);
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
        model2 = next_model2(&acc);
        out->iterations = it + 1;
        if (fabs(x - (double)ix) > TRN_REFINE_MAX_SHIFT || fabs(y - (double)iy) > TRN_REFINE_MAX_SHIFT) {
            set_fail(out, ix, iy);
            return TRN_E_ILLCOND;
        }
        if (fabs(d[0]) < 1e-4 && fabs(d[1]) < 1e-4) {
            break;
        }
    }
    /* Covariance at the final pose. */
    accumulate(global, local, rover_x, rover_y, x, y, dz, TRN_REFINE_CLIP, model2, cfg, &acc);
    if (acc.n_in < 8 || 2 * acc.n_in < acc.n_all || !inv3(acc.a, inv)) {
        set_fail(out, ix, iy);
        out->n_used = acc.n_in;
        return TRN_E_ILLCOND;
    }
    chi2 = acc.ss / (double)(acc.n_in - 3);
    out->chi2_dof = chi2;
    chi2 = chi2 > 1.0 ? chi2 : 1.0;
    out->x = x;
    out->y = y;
    out->dz_m = dz;
    out->model_m = sqrt(model2);
    out->cov_cells[0] = inv[0] * chi2;
    out->cov_cells[1] = inv[4] * chi2;
    out->cov_cells[2] = inv[1] * chi2;
    out->n_used = acc.n_in;
    return TRN_OK;
}
