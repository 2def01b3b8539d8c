/* SPDX-License-Identifier: Apache-2.0 */
/* refine.c - the height model's arithmetic under the refinement
 * (refine_pose.c): the interpolants and their mix, the relief rule's
 * weight, the model variance's moments, the noise model's rescale, and
 * trn_height_search, the exhaustive search read straight from the grids
 * (the reference of height_score.c), with trn_height_mass (trn/refine.h). */
#include "trn/refine.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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
    double wx[4], dwx[4];
    int32_t x0, y0, i, j;
    if (!(x >= 1.0 && y >= 1.0 && x < (double)(g->width - 2) && y < (double)(g->height - 2))) {
        return sample_bilinear(g, x, y, out);
    }
    x0 = (int32_t)floor(x);
    y0 = (int32_t)floor(y);
    for (i = 0; i < 4; ++i) {
        keys(x - (double)(x0 - 1 + i), &wx[i], &dwx[i]);
    }
    out[0] = out[1] = out[2] = 0.0;
    /* row by row: each row's sums over x, then weighted by the row's y
     * weights (no table of the y weights: the frame stays small) */
    for (j = 0; j < 4; ++j) {
        double wy, dwy, r0 = 0.0, r1 = 0.0;
        keys(y - (double)(y0 - 1 + j), &wy, &dwy);
        for (i = 0; i < 4; ++i) {
            double v = (double)TRN_GRID_AT(g, x0 - 1 + i, y0 - 1 + j);
            if (!isfinite(v)) {
                return sample_bilinear(g, x, y, out);
            }
            r0 += wx[i] * v;
            r1 += dwx[i] * v;
        }
        out[0] += wy * r0;
        out[1] += wy * r1;
        out[2] += dwy * r0;
    }
    return 1;
}

/* The interpolating cubic B-spline's weights (its cardinal function eta)
 * at the TRN_SPLINE_TAPS taps k0 + t of fractional position x along an
 * axis of n samples, k0 = floor(x) - TRN_SPLINE_HALF + 1:
 * eta(f + n) = sum over m = -1..2 of c_{n+m} beta3(f - m), f = x - floor(x),
 * c_k = sqrt(3) z^|k| (z = sqrt(3) - 2, the pole of the sampled B-spline's
 * inverse filter), normalised to sum 1, so that a constant is exact (the
 * taps cut eta where it is below 3e-5 of its peak). spline_axis gives k0
 * and the four beta3 values (0 where the taps leave the axis), spline_tap
 * tap t's weight before the normalisation. */
#define TRN_SPLINE_HALF 8
#define TRN_SPLINE_TAPS (2 * TRN_SPLINE_HALF)
static int spline_axis(double x, int32_t n, int32_t *k0, double b[4])
{
    double f, e;
    int32_t fl;
    /* floor(x) by truncation: x is checked non-negative first (no libm call
     * on the deepest stack) */
    if (!(x >= (double)(TRN_SPLINE_HALF - 1) && x < (double)n - (double)(TRN_SPLINE_HALF))) {
        return 0;
    }
    fl = (int32_t)x;
    f = x - (double)fl;
    e = 1.0 - f;
    *k0 = fl - (TRN_SPLINE_HALF - 1);
    b[0] = e * e * e / 6.0; /* beta3(f + 1), beta3(f), beta3(f - 1), beta3(f - 2) */
    b[1] = 2.0 / 3.0 - f * f + 0.5 * f * f * f;
    b[2] = 2.0 / 3.0 - e * e + 0.5 * e * e * e;
    b[3] = f * f * f / 6.0;
    return 1;
}

static double spline_tap(const double b[4], int32_t t)
{
    static const double k_spline_c[TRN_SPLINE_HALF + 2] = {
        1.7320508075688772,     -0.4641016151377547,     0.12435565298214114,
        -0.033320996790809666,  0.008928334181097486,    -0.0023923399335802615,
        0.000641025553223557,   -0.00017176227931396584, 4.602356403230609e-05,
        -1.2331976815258487e-05}; /* sqrt(3) z^k */
    /* tap k0 + t is at offset a = t - (TRN_SPLINE_HALF - 1) from floor(x): eta(f - a) */
    const int32_t a = t - (TRN_SPLINE_HALF - 1);
    double v = 0.0;
    int32_t m;
    for (m = 0; m < 4; ++m) {
        const int32_t k = m - 1 - a;
        v += k_spline_c[k < 0 ? -k : k] * b[m];
    }
    return v;
}

int trn_refine_spline_(const trn_grid_f32_t *g, double x, double y, double *h)
{
    /* the x weights kept in float, the y weights one row at a time, the
     * heights taken about the first tap's and the sum divided by the
     * weights' own: a constant is exact, and the frame, which is on the
     * deepest stack (the covariance's fit reads the spline under every
     * cell), keeps 64 bytes of weights */
    float wx[TRN_SPLINE_TAPS];
    double bx[4], by[4], s = 0.0, sx = 0.0, sy = 0.0, ref;
    int32_t i0, j0, i, j;
    if (!spline_axis(x, g->width, &i0, bx) || !spline_axis(y, g->height, &j0, by)) {
        return 0;
    }
    for (i = 0; i < TRN_SPLINE_TAPS; ++i) {
        wx[i] = (float)spline_tap(bx, i);
        sx += (double)wx[i];
    }
    ref = (double)TRN_GRID_AT(g, i0, j0);
    for (j = 0; j < TRN_SPLINE_TAPS; ++j) {
        const double wy = spline_tap(by, j);
        double r = 0.0;
        for (i = 0; i < TRN_SPLINE_TAPS; ++i) {
            const double v = (double)TRN_GRID_AT(g, i0 + i, j0 + j);
            if (!isfinite(v)) {
                return 0;
            }
            r += (double)wx[i] * (v - ref);
        }
        s += wy * r;
        sy += wy;
    }
    *h = ref + s / (sx * sy);
    return 1;
}

double trn_refine_model2_(double rr, double noise2, double q)
{
    double m = (rr - noise2) / q;
    return m > 0.0 ? m : 0.0;
}

double trn_refine_excess_(double ratio, double rel_sd)
{
    return ratio > 1.0 + TRN_REFINE_SYS_Z * rel_sd ? ratio : 1.0;
}

static double local_spread(const trn_grid_f32_t *local, int32_t *n_seen);

/* The checks trn_height_search and the refinements share: the grids, the
 * noise model and the rover cell (each caller checks its own inlier
 * probability). */
int trn_refine_centroids_ok_(const trn_grid_f32_t *local, const float *cx, const float *cy)
{
    int32_t i, j;
    if (cx == NULL || cy == NULL) {
        return cx == cy;
    }
    for (j = 0; j < local->height; ++j) {
        for (i = 0; i < local->width; ++i) {
            const size_t k = (size_t)j * (size_t)local->stride + (size_t)i;
            if (isfinite(local->data[k]) && !(fabsf(cx[k]) <= (float)TRN_CENTROID_MAX &&
                                              fabsf(cy[k]) <= (float)TRN_CENTROID_MAX)) {
                return 0;
            }
        }
    }
    return 1;
}

int trn_refine_counts_ok_(const trn_grid_f32_t *local, const float *n)
{
    int32_t i, j;
    if (n == NULL) {
        return 1;
    }
    for (j = 0; j < local->height; ++j) {
        for (i = 0; i < local->width; ++i) {
            const size_t k = (size_t)j * (size_t)local->stride + (size_t)i;
            if (isfinite(local->data[k]) &&
                !(n[k] >= 1.0f && (double)n[k] <= TRN_POINT_COUNT_MAX)) {
                return 0;
            }
        }
    }
    return 1;
}

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
    if ((cfg->centroid_x == NULL) != (cfg->centroid_y == NULL)) {
        return TRN_E_NULL;
    }
    if (!(cfg->cell_m > 0.0f && cfg->cell_m <= TRN_CELL_MAX_M) ||
        !(cfg->noise_m > 0.0f && cfg->noise_m <= 1000.0f) ||
        !(cfg->noise_k_per_m >= 0.0f && cfg->noise_k_per_m <= 1000.0f) ||
        (cfg->fit_noise != 0 && cfg->fit_noise != 1) || rover_x < -TRN_MAX_DIM ||
        rover_y < -TRN_MAX_DIM || rover_x > local->width - 1 + TRN_MAX_DIM ||
        rover_y > local->height - 1 + TRN_MAX_DIM) {
        return TRN_E_ARG;
    }
    return trn_refine_centroids_ok_(local, cfg->centroid_x, cfg->centroid_y) &&
                   trn_refine_counts_ok_(local, cfg->point_count)
               ? TRN_OK
               : TRN_E_ARG;
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
            double h = (double)TRN_GRID_AT(local, i, j), s3[3], dcb, s2, v, r2, q, o[2];
            if (!isfinite(h)) {
                continue;
            }
            trn_refine_offset_(cfg, local, i, j, rx, ry, o);
            /* the offset turned by the heading, as trn_refine_pose_heading's */
            if (!trn_refine_sample_mix_(global, at->x + o[0] * cs_sn[0] + o[1] * cs_sn[1],
                                        at->y - o[0] * cs_sn[1] + o[1] * cs_sn[0], at->interp_mix,
                                        s3, &dcb)) {
                continue;
            }
            s2 = trn_refine_cell_var_(cfg, local, i, j, rx, ry);
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
    double h, s3[3], dcb, r, o[2];
    if (i >= local->width || j >= local->height) {
        return (double)NAN;
    }
    h = (double)TRN_GRID_AT(local, i, j);
    if (!isfinite(h)) {
        return (double)NAN;
    }
    trn_refine_offset_(cfg, local, i, j, rx, ry, o);
    if (!trn_refine_sample_mix_(global, at->x + o[0] * cs_sn[0] + o[1] * cs_sn[1],
                                at->y - o[0] * cs_sn[1] + o[1] * cs_sn[0], at->interp_mix, s3,
                                &dcb)) {
        return (double)NAN;
    }
    r = h - at->dz_m - s3[0];
    *s2 = trn_refine_cell_var_(cfg, local, i, j, rx, ry);
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

/* The relief test's sums: the normal equations of local = a + b x + c y +
 * g M (the upper triangle of a[4][4], the right-hand side v) over the cells
 * within the clip; their count. */
static int32_t relief_pass(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                           int32_t ry, const trn_refine_t *at, const double cs_sn[2],
                           const trn_refine_cfg_t *cfg, double a[4][4], double v[4])
{
    const double m2 = at->model_m * at->model_m;
    double ref = 0.0;
    int32_t i, j, p, q, cnt = 0;
    for (p = 0; p < 4; ++p) {
        v[p] = 0.0;
        for (q = 0; q < 4; ++q) {
            a[p][q] = 0.0;
        }
    }
    for (j = 0; j < local->height; ++j) {
        for (i = 0; i < local->width; ++i) {
            const double h = (double)TRN_GRID_AT(local, i, j);
            double s3[3], b3[3], s2, r, w, x[4], o[2], gx, gy;
            if (!isfinite(h)) {
                continue;
            }
            trn_refine_offset_(cfg, local, i, j, rx, ry, o);
            /* the offset turned by the heading, as trn_refine_pose_heading's */
            gx = at->x + o[0] * cs_sn[0] + o[1] * cs_sn[1];
            gy = at->y - o[0] * cs_sn[1] + o[1] * cs_sn[0];
            if (!trn_refine_sample_bilinear_(global, gx, gy, b3)) {
                continue;
            }
            /* the model's mixed height (trn_refine_sample_mix_'s, from the
             * same two samples) for the clip; the bilinear one for the fit */
            (void)trn_refine_sample_(global, gx, gy, s3);
            s2 = trn_refine_cell_var_(cfg, local, i, j, rx, ry);
            r = h - at->dz_m - (b3[0] + at->interp_mix * (s3[0] - b3[0]));
            if (!(r * r <= TRN_REFINE_CLIP * TRN_REFINE_CLIP * (s2 + m2))) {
                continue;
            }
            if (cnt == 0) {
                ref = b3[0]; /* heights about the first: no cancellation */
            }
            w = 1.0 / (s2 + m2);
            x[0] = 1.0;
            x[1] = o[0];
            x[2] = o[1];
            x[3] = b3[0] - ref;
            for (p = 0; p < 4; ++p) {
                v[p] += w * x[p] * (h - at->dz_m - ref);
                for (q = p; q < 4; ++q) {
                    a[p][q] += w * x[p] * x[q];
                }
            }
            cnt += 1;
        }
    }
    return cnt;
}

double trn_refine_relief_z_(const trn_grid_f32_t *global, const trn_grid_f32_t *local, int32_t rx,
                            int32_t ry, const trn_refine_t *at, double heading_rad,
                            const trn_refine_cfg_t *cfg)
{
    double cs_sn[2], a[4][4], v[4], l[4][4], y[4];
    int32_t p, q, k;
    trn_heading_trig_(heading_rad, &cs_sn[0], &cs_sn[1]);
    if (relief_pass(global, local, rx, ry, at, cs_sn, cfg, a, v) < 8) {
        return (double)INFINITY;
    }
    /* Cholesky of the normal matrix, g last: g = y3 / L33 and sd(g) =
     * 1 / L33, so (g - 1) / sd(g) = y3 - L33 */
    for (p = 0; p < 4; ++p) {
        for (q = p; q < 4; ++q) {
            double s = a[p][q];
            for (k = 0; k < p; ++k) {
                s -= l[q][k] * l[p][k];
            }
            if (q == p) {
                if (!(s > 1e-12 * a[p][p])) {
                    return (double)INFINITY; /* no relief (or no plane) to fit */
                }
                l[p][p] = sqrt(s);
            } else {
                l[q][p] = s / l[p][p];
            }
        }
        y[p] = v[p];
        for (k = 0; k < p; ++k) {
            y[p] -= l[p][k] * y[k];
        }
        y[p] /= l[p][p];
    }
    return y[3] - l[3][3];
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

/* Weighted offset and variances (the noise scale k2 with cfg->fit_noise,
 * the model variance m2) of the residuals at pose (px, py), over the points
 * within clip standard deviations of (dz, k2, m2) (clip < 0: every point).
 * Returns the number of points used. */
static int32_t pose_fit(const trn_grid_f32_t *g, const trn_grid_f32_t *l, int32_t rx, int32_t ry,
                        int32_t px, int32_t py, const trn_refine_cfg_t *cfg, double clip,
                        double *dz, double *k2, double *m2)
{
    int32_t x, y;
    trn_pose_mom_t a;
    (void)memset(&a, 0, sizeof(a));
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
            if (clip >= 0.0 && fabs(r - *dz) > clip * sqrt(*k2 * v + *m2)) {
                continue;
            }
            trn_pose_mom_add_(&a, r, v, *k2, *m2);
        }
    }
    return trn_pose_mom_end_(&a, cfg->fit_noise, dz, k2, m2);
}

/* Log-likelihood of pose (px, py), nats: the model of height_score.c read
 * straight from the grids, the obvious reference the tests hold it to. */
static double pose_ll(const trn_grid_f32_t *g, const trn_grid_f32_t *l, int32_t rx, int32_t ry,
                      int32_t px, int32_t py, const trn_refine_cfg_t *cfg, double a, double k,
                      double *dz_out, double *m_out)
{
    const double two_pi = 6.283185307179586;
    int32_t x, y, n_all;
    double dz = 0.0, k2 = 1.0, m2 = 0.0, ll = 0.0, lout = log((1.0 - a) * k);
    /* dz, k2 and m2: over every point (the model's weights, then those of
     * the first fit), then over the points within the clip of that fit */
    n_all = pose_fit(g, l, rx, ry, px, py, cfg, -1.0, &dz, &k2, &m2);
    if (n_all > 0 && pose_fit(g, l, rx, ry, px, py, cfg, -1.0, &dz, &k2, &m2) > 0) {
        /* then within the clip of the last fit, again while that drops
         * points (trn_clip_again_) */
        double dz1 = dz, k21 = k2, m21 = m2;
        int32_t n_prev = n_all, n, again;
        for (again = 0; again <= TRN_CLIP_AGAIN; ++again) {
            n = pose_fit(g, l, rx, ry, px, py, cfg, TRN_REFINE_CLIP, &dz1, &k21, &m21);
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
            v = k2 * trn_refine_noise_var_(cfg, x, y, rx, ry) + m2;
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
    best->poses = 0u;
    best->lse_all = best->lse_out = -(double)INFINITY;
    for (y = win->y0; y <= win->y1; ++y) {
        for (x = win->x0; x <= win->x1; ++x) {
            double ll, dz, m, q;
            int inside = ex != NULL && abs(x - ex->cx) <= ex->radius &&
                         abs(y - ex->cy) <= ex->radius;
            ll = pose_ll(global, local, rover_x, rover_y, x, y, cfg, (double)inlier_prob, k, &dz,
                         &m);
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

/* The interpolants for the refinement (refine_int.h). */
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
