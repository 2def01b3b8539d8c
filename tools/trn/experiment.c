/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/experiment.c - the paper's section 5 Monte Carlo (see experiment.h). */
#include "experiment.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "terrain_gen.h"

#define EXP_PI 3.14159265358979323846
#define EXP_MAX_DRAWS 100000L /* (S, F, offset) draws per trial before giving up */

/* ------------------------------------------------------------------------ */
/* random numbers                                                            */
/* ------------------------------------------------------------------------ */
static uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

void exp_rng_seed(exp_rng_t *r, uint64_t seed, uint64_t index)
{
    /* Two mixing rounds so neighbouring (seed, index) pairs give unrelated streams. */
    r->s = mix64(mix64(seed ^ 0x6A09E667F3BCC909ull) + index * 0x9E3779B97F4A7C15ull);
}

uint64_t exp_rng_u64(exp_rng_t *r) { return mix64(r->s += 0x9E3779B97F4A7C15ull); }

double exp_rng_unit(exp_rng_t *r)
{
    return (double)(exp_rng_u64(r) >> 11) * (1.0 / 9007199254740992.0);
}

long exp_rng_range(exp_rng_t *r, long lo, long hi)
{
    /* Multiply-shift on 32 random bits: bias below 2^-32 relative for the
   * spans used here (at most a few thousand). */
    uint64_t span = (uint64_t)(hi - lo) + 1u;
    return lo + (long)(((exp_rng_u64(r) >> 32) * span) >> 32);
}

/* ------------------------------------------------------------------------ */
/* sensor model                                                              */
/* ------------------------------------------------------------------------ */
size_t exp_sample_points(const float *p, int w, int h, int nz, int off_x, int off_y, exp_rng_t *r,
                         trn_point_t *pts, size_t cap)
{
    size_t n = 0;
    int x, y, z;
    for (z = 0; z < nz; ++z) {
        for (y = 0; y < h; ++y) {
            const float *row = p + ((size_t)z * (size_t)h + (size_t)y) * (size_t)w;
            for (x = 0; x < w; ++x) {
                double u = exp_rng_unit(r);
                double q = (double)row[x];
                if (q > 0.0 && u < q) { /* u < 1 always: q >= 1 is certain; NaN fails q > 0 */
                    if (n < cap) {
                        pts[n].x = (int16_t)(x + off_x);
                        pts[n].y = (int16_t)(y + off_y);
                        pts[n].z = (int16_t)z;
                    }
                    ++n;
                }
            }
        }
    }
    return n;
}

/* ------------------------------------------------------------------------ */
/* interval statistics                                                       */
/* ------------------------------------------------------------------------ */
void exp_wilson(double k, double n, double z, double ci[2])
{
    double p, z2n, centre, half;
    if (!(n > 0.0)) {
        ci[0] = ci[1] = NAN;
        return;
    }
    p = k / n;
    z2n = z * z / n;
    centre = (p + 0.5 * z2n) / (1.0 + z2n);
    half = z / (1.0 + z2n) * sqrt(p * (1.0 - p) / n + 0.25 * z2n / n);
    ci[0] = centre - half;
    ci[1] = centre + half;
    /* Exact at the ends (rounding could leave -1e-17 or 1 + 1e-16). */
    if (k <= 0.0 || ci[0] < 0.0) {
        ci[0] = 0.0;
    }
    if (k >= n || ci[1] > 1.0) {
        ci[1] = 1.0;
    }
}

/* Abramowitz & Stegun 26.7.3 / 26.7.4: with theta = atan(t / sqrt(df)),
 * df odd:  A = 2/pi (theta + sin cos (1 + 2/3 c^2 + 2.4/(3.5) c^4 + ...)),
 *          the series up to c^(df-3) (empty for df = 1),
 * df even: A = sin (1 + 1/2 c^2 + 1.3/(2.4) c^4 + ...), up to c^(df-2),
 * c = cos(theta). */
double exp_t_abs_cdf(double t, long df)
{
    double th, s, c, c2, term, sum;
    long j, terms;
    if (df < 1 || isnan(t)) {
        return NAN;
    }
    if (t < 0.0) {
        t = -t;
    }
    if (isinf(t)) {
        return 1.0;
    }
    th = atan(t / sqrt((double)df));
    s = sin(th);
    c = cos(th);
    c2 = c * c;
    term = 1.0;
    sum = 1.0;
    if (df % 2 == 1) {
        terms = (df - 3) / 2;
        for (j = 1; j <= terms; ++j) {
            term *= (double)(2 * j) / (double)(2 * j + 1) * c2;
            sum += term;
        }
        return df == 1 ? 2.0 * th / EXP_PI : 2.0 / EXP_PI * (th + s * c * sum);
    }
    terms = (df - 2) / 2;
    for (j = 1; j <= terms; ++j) {
        term *= (double)(2 * j - 1) / (double)(2 * j) * c2;
        sum += term;
    }
    return s * sum;
}

double exp_t_quantile(double conf, long df)
{
    double lo = 0.0, hi = 1.0;
    int i;
    if (df < 1 || !(conf > 0.0 && conf < 1.0)) {
        return NAN;
    }
    if (df > 200000) { /* the series is O(df); beyond this t differs from it by < 1e-5 */
        df = 200000;
    }
    for (i = 0; i < 64 && exp_t_abs_cdf(hi, df) < conf; ++i) {
        lo = hi;
        hi *= 2.0;
    }
    for (i = 0; i < 80; ++i) {
        double mid = 0.5 * (lo + hi);
        if (exp_t_abs_cdf(mid, df) < conf) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return 0.5 * (lo + hi);
}

void exp_cluster_stats(const long *m, const long *k, const double *e, const double *e2,
                       long n_clusters, exp_stats_t *out)
{
    double M = 0.0, K = 0.0, E = 0.0, E2 = 0.0, vr = 0.0, vm = 0.0, se, tq;
    long i, with_success = 0;
    int single = 1;
    out->rate = out->n_eff = out->mean = out->sd = NAN;
    out->rate_ci[0] = out->rate_ci[1] = out->mean_ci[0] = out->mean_ci[1] = NAN;
    for (i = 0; i < n_clusters; ++i) {
        M += (double)m[i];
        K += (double)k[i];
        E += e[i];
        E2 += e2[i];
        single = single && m[i] == 1;
        with_success += k[i] > 0;
    }
    if (!(M > 0.0)) {
        return;
    }
    out->rate = K / M;
    out->n_eff = M;
    if (!single && n_clusters > 1 && K > 0.0 && K < M) {
        for (i = 0; i < n_clusters; ++i) {
            double r = (double)k[i] - out->rate * (double)m[i];
            vr += r * r;
        }
        vr *= (double)n_clusters / ((double)n_clusters - 1.0) / (M * M);
        if (vr > 0.0) {
            double ne = out->rate * (1.0 - out->rate) / vr;
            out->n_eff = ne < M ? ne : M;
        }
    }
    exp_wilson(out->rate * out->n_eff, out->n_eff, EXP_Z95, out->rate_ci);
    if (!(K > 0.0)) {
        return;
    }
    out->mean = E / K;
    if (K > 1.0) {
        double v = (E2 - K * out->mean * out->mean) / (K - 1.0);
        out->sd = sqrt(v > 0.0 ? v : 0.0);
    }
    if (single) {
        if (K < 2.0) {
            return;
        }
        se = out->sd / sqrt(K);
        tq = exp_t_quantile(0.95, (long)K - 1);
    } else {
        if (with_success < 2) {
            return;
        }
        for (i = 0; i < n_clusters; ++i) {
            double r = e[i] - out->mean * (double)k[i];
            vm += r * r;
        }
        vm *= (double)n_clusters / ((double)n_clusters - 1.0) / (K * K);
        se = sqrt(vm);
        tq = exp_t_quantile(0.95, with_success - 1);
    }
    out->mean_ci[0] = out->mean - tq * se;
    out->mean_ci[1] = out->mean + tq * se;
}

/* ------------------------------------------------------------------------ */
/* the experiment                                                            */
/* ------------------------------------------------------------------------ */
void exp_params_default(exp_params_t *p)
{
    memset(p, 0, sizeof *p);
    p->size_cells = 256;
    p->cell_m = 0.1;
    p->coverage_k = 0.1;
    p->terrain_seed = 1;
    p->relief_m = 0.05;
    p->trials = 1000;
    p->seed = 1;
    p->window_m = 2.0;
    p->prior_error_m = 1.0;
    p->grid_spacing_m = 2.0;
    p->success_cells = 2.0;
    p->footprint_m = -1.0;
    p->global_sigma_m = -1.0;
    p->global_sigma_k = -1.0;
    p->select_heading_search = 1;
}

const char *exp_params_check(const exp_params_t *p)
{
    double c;
    if (p->trials < 1 || p->trials > 1000000) {
        return "trials must be in 1..1000000";
    }
    if (p->dem == NULL &&
        (p->size_cells < 64 || p->size_cells > 1024)) { /* 1024: the eq. 8 map is 64 MiB */
        return "map side must be 64..1024 cells";
    }
    if (p->dem != NULL &&
        (p->dem_width < 16 || p->dem_height < 16 || p->dem_width > 1024 || p->dem_height > 1024)) {
        return "the DEM must be 16..1024 cells a side (cut a larger one, e.g. gdal_translate "
               "-srcwin)";
    }
    if (!(p->cell_m > 0.0 && p->cell_m <= (p->dem != NULL ? (double)TRN_CELL_MAX_M : 10.0))) {
        /* the core's bound, printed from its constant (trn_config.h) */
        static char cell_why[64];
        snprintf(cell_why, sizeof cell_why, "cell size must be in (0, %g] m",
                 p->dem != NULL ? (double)TRN_CELL_MAX_M : 10.0);
        return cell_why;
    }
    if (p->global_error != NULL && p->dem == NULL) {
        return "an error raster needs a given DEM";
    }
    c = p->cell_m;
    if (!(p->coverage_k >= 0.01 && p->coverage_k <= 0.5)) {
        return "rock coverage k must be in [0.01, 0.5]";
    }
    if (!(p->d_min_m == 0.0 || (p->d_min_m >= p->cell_m && p->d_min_m <= 10.0))) {
        return "smallest rock diameter must be in [one cell, 10 m]";
    }
    if (!(p->relief_m >= 0.0 && p->relief_m <= 10.0)) {
        return "background relief must be in [0, 10] m";
    }
    /* Window, prior and grid in cells (at 0.1 m: 20, 10, 10 m as before). */
    if (!(p->prior_error_m >= 0.0 && p->prior_error_m <= 100.0 * c + 1e-9)) {
        return "prior error must be in [0, 100 cells]";
    }
    if (!(p->window_m >= c - 1e-9 && p->window_m <= 200.0 * c + 1e-9)) {
        return "window half-width must be in [one cell, 200 cells]";
    }
    if (p->window_m < p->prior_error_m) {
        return "window half-width is below the prior error: the truth could lie outside the window";
    }
    if (!(p->grid_spacing_m >= 0.0 && p->grid_spacing_m <= 100.0 * c + 1e-9)) {
        return "grid spacing must be in [0, 100 cells]";
    }
    if (!(p->min_range_m >= 0.0 && p->max_range_m >= 0.0 && p->patch_m >= 0.0 &&
          p->footprint_m >= -1.0 &&
          isfinite(p->min_range_m + p->max_range_m + p->patch_m + p->footprint_m))) {
        return "ranges, patch and footprint must be finite and >= 0";
    }
    if (p->sensor != EXP_SENSOR_PROB && p->sensor != EXP_SENSOR_DEM) {
        return "sensor must be prob or dem";
    }
    if (!(p->height_noise_m >= 0.0 && p->height_noise_m <= 1.0)) {
        return "height noise must be in [0, 1] m";
    }
    if (p->sensor == EXP_SENSOR_PROB && p->height_noise_m != 0.0) {
        return "height noise applies only to the dem sensor";
    }
    if (!(p->success_cells > 0.0 && p->success_cells <= 100.0)) {
        return "success radius must be in (0, 100] cells";
    }
    if (!(p->heading_error_deg >= 0.0 && p->heading_error_deg <= 30.0)) {
        return "heading error must be in [0, 30] degrees";
    }
    if (!(p->heading_window_deg >= 0.0 &&
          p->heading_window_deg <= TRN_HEADING_MAX_WINDOW_RAD * 180.0 / EXP_PI)) {
        return "heading window must be in [0, 180] degrees";
    }
    if (p->select_heading_search != 0 && p->select_heading_search != 1) {
        return "the 3-DOF arm's selection flag must be 0 or 1";
    }
    return NULL;
}

/* 16-byte aligned heap block; free with free(*raw). */
static void *alloc16(size_t n, void **raw)
{
    unsigned char *q = malloc(n + 16u);
    *raw = q;
    if (q == NULL) {
        return NULL;
    }
    return q + ((16u - ((uintptr_t)q & 15u)) & 15u);
}

/* A workspace *ws of *have bytes grown to need (contents not kept): 0, or -1
 * with the reason naming what. */
static int grow_ws(void **ws, void **raw, size_t *have, size_t need, const char *what, char *err,
                   size_t err_len)
{
    if (need <= *have) {
        return 0;
    }
    free(*raw);
    *ws = alloc16(need, raw);
    *have = *ws == NULL ? 0 : need;
    if (*ws == NULL) {
        snprintf(err, err_len, "out of memory for %zu bytes of %s workspace", need, what);
        return -1;
    }
    return 0;
}

typedef struct {
    const exp_params_t *p;
    int nx, ny;     /* map size, cells */
    int has_nodata; /* a given DEM with NaN cells */
    float cellf;
    trn_map_t map;
    trn_kernels_t k;
    trn_vol_f32_t pg;
    trn_select_cfg_t scfg;
    trn_select_cfg_t scfg3; /* the 3-DOF arm's selection (heading_search from the params) */
    int half;               /* patch half-side, cells */
    int win_cells, prior_cells, grid_cells;
    trn_candidate_t *cands;
    size_t cap;
    void *sws, *lws, *pws, *lws_raw;
    size_t sws_b, lws_b, pws_b;
    void *h3ws, *h3ws_raw; /* the 3-DOF search's workspace, grown on demand */
    size_t h3ws_b;
    double h3win_rad; /* its half-window; 0: no 3-DOF search */
    float *pvol;
    trn_point_t *pts;
    size_t pts_cap;
    /* EXP_SENSOR_DEM */
    float *dem;        /* the true terrain, nx x ny (a copy; NaN = no data) */
    float *ldem, *lhp; /* local DEM and its high-pass, (patch + 2 hp) squared */
    void *hws;
    size_t hws_b;
    int hp_cells;
    trn_terrain_cfg_t tcfg;
    /* the height matcher (map.cfg.match == TRN_MATCH_HEIGHTS) */
    int heights;
    float *hgrid;        /* the sensed patch's heights, (patch side) squared */
    void *dws, *dws_raw; /* trn_localize_dem's workspace, grown on demand */
    size_t dws_b;
} world_t;

/* Would trn_select accept (tx, ty) as a candidate from the rover cell (px, py)?
 * The same rules as select.c's candidate_ok with full pan. */
static int target_ok(const world_t *w, int tx, int ty, int px, int py)
{
    double dx = tx - px, dy = ty - py, r = sqrt(dx * dx + dy * dy) * w->cellf, hx = w->half + 0.5,
           ex, ey;
    if (tx - w->half - 1 < 0 || ty - w->half - 1 < 0 || tx + w->half + 1 > w->nx - 1 ||
        ty + w->half + 1 > w->ny - 1) {
        return 0;
    }
    if (r < (double)w->scfg.min_range_m || r > (double)w->scfg.max_range_m) {
        return 0;
    }
    ex = fabs(dx) - hx;
    ey = fabs(dy) - hx;
    ex = ex > 0.0 ? ex : 0.0;
    ey = ey > 0.0 ? ey : 0.0;
    return sqrt(ex * ex + ey * ey) * w->cellf >= (double)w->scfg.footprint_radius_m;
}

static int patch_inside(const world_t *w, int cx, int cy)
{
    int x, y;
    if (!(cx - w->half >= 0 && cy - w->half >= 0 && cx + w->half <= w->nx - 1 &&
          cy + w->half <= w->ny - 1)) {
        return 0;
    }
    if (!w->has_nodata) {
        return 1;
    }
    /* A given DEM with no-data: the sensed patch must be terrain the map knows. */
    for (y = cy - w->half; y <= cy + w->half; ++y) {
        for (x = cx - w->half; x <= cx + w->half; ++x) {
            if (!isfinite(w->dem[(size_t)y * (size_t)w->nx + (size_t)x])) {
                return 0;
            }
        }
    }
    return 1;
}

typedef struct {
    int ok; /* localization ran */
    int no_points;
    int illcond;
    double err_m;
    size_t n_points;
    double err3_m; /* the 3-DOF search's error (w->h3win_rad > 0) */
    int illcond3;
    int fix, ambiguous; /* the height matcher's status: TRN_OK, TRN_E_AMBIGUOUS */
    int rescaled;       /* ... its noise model rescaled (trn_loc_result_t.noise_scale != 1) */
} sense_t;

/* Standard normal from two uniforms (Box-Muller, cosine branch). */
static double rng_normal(exp_rng_t *r)
{
    double u1 = exp_rng_unit(r), u2 = exp_rng_unit(r);
    return sqrt(-2.0 * log(1.0 - u1)) * cos(2.0 * EXP_PI * u2);
}

/* EXP_SENSOR_DEM (experiment.h): local map of the patch roi seen from the
 * true rover cell (fx, fy); points relative to it in w->pts, count in *n. */
static int dem_sensor(world_t *w, const trn_window_t *roi, int fx, int fy, exp_rng_t *r, size_t *n,
                      char *err, size_t err_len)
{
    int x0 = roi->x0 - w->hp_cells, y0 = roi->y0 - w->hp_cells;
    int x1 = roi->x1 + w->hp_cells, y1 = roi->y1 + w->hp_cells, x, y, lw, lh;
    trn_grid_f32_t lg, hg;
    trn_status_t st;
    size_t i, m = 0, np = 0;
    x0 = x0 < 0 ? 0 : x0;
    y0 = y0 < 0 ? 0 : y0;
    x1 = x1 > w->nx - 1 ? w->nx - 1 : x1;
    y1 = y1 > w->ny - 1 ? w->ny - 1 : y1;
    lw = x1 - x0 + 1;
    lh = y1 - y0 + 1;
    for (y = 0; y < lh; ++y) {
        for (x = 0; x < lw; ++x) {
            double hgt = (double)w->dem[(size_t)(y0 + y) * (size_t)w->nx + (size_t)(x0 + x)];
            if (w->p->height_noise_m > 0.0) {
                hgt += w->p->height_noise_m * rng_normal(r);
            }
            w->ldem[(size_t)y * (size_t)lw + (size_t)x] = (float)hgt;
        }
    }
    if (trn_grid_f32_init(&lg, w->ldem, (size_t)lw * (size_t)lh, lw, lh) != TRN_OK ||
        trn_grid_f32_init(&hg, w->lhp, (size_t)lw * (size_t)lh, lw, lh) != TRN_OK) {
        snprintf(err, err_len, "internal error: local DEM of %d x %d cells rejected", lw, lh);
        return -1;
    }
    if ((st = trn_highpass(&lg, &w->tcfg, &hg, w->hws, w->hws_b)) != TRN_OK) {
        snprintf(err, err_len, "trn_highpass: %s", trn_strerror(st));
        return -1;
    }
    st = trn_occupancy_points(&hg, &w->tcfg, fx - x0, fy - y0, w->pts, w->pts_cap, &np);
    if (st != TRN_OK && st != TRN_E_NODATA) {
        snprintf(err, err_len, "trn_occupancy_points: %s", trn_strerror(st));
        return -1;
    }
    for (i = 0; i < np; ++i) { /* keep the patch */
        int gx = fx + w->pts[i].x, gy = fy + w->pts[i].y;
        if (gx >= roi->x0 && gx <= roi->x1 && gy >= roi->y0 && gy <= roi->y1) {
            w->pts[m++] = w->pts[i];
        }
    }
    *n = m;
    return 0;
}

/* The 3-DOF search (trn_localize_points_heading, +-w->h3win_rad around the
 * believed heading) on the points just localized in x-y: s->err3_m. */
static int localize_3dof(world_t *w, size_t n, const trn_window_t *win, int fx, int fy, sense_t *s,
                         char *err, size_t err_len)
{
    trn_heading_cfg_t hc;
    trn_heading_result_t hr;
    trn_status_t st;
    size_t need = trn_localize_heading_workspace_bytes(&w->map, n, win);
    double ex, ey;
    if (need == 0) {
        snprintf(err, err_len, "internal error: 3-DOF workspace refused for %zu points", n);
        return -1;
    }
    if (grow_ws(&w->h3ws, &w->h3ws_raw, &w->h3ws_b, need, "3-DOF", err, err_len) != 0) {
        return -1;
    }
    hc.center_rad = 0.0;
    hc.window_rad = w->h3win_rad;
    hc.step_rad = 0.0;
    st = trn_localize_points_heading(&w->map, w->pts, n, win, &hc, w->h3ws, w->h3ws_b, &hr);
    if (st != TRN_OK && st != TRN_E_ILLCOND) {
        snprintf(err, err_len, "trn_localize_points_heading: %s", trn_strerror(st));
        return -1;
    }
    s->illcond3 = st == TRN_E_ILLCOND;
    ex = (st == TRN_OK ? hr.loc.x : (double)hr.loc.ix) - fx;
    ey = (st == TRN_OK ? hr.loc.y : (double)hr.loc.iy) - fy;
    s->err3_m = sqrt(ex * ex + ey * ey) * w->cellf;
    return 0;
}

/* The height matcher's trial (experiment.h): the true heights over roi plus
 * Gaussian noise of sd noise_m + noise_k_per_m r^2, r metres from the true
 * rover cell (fx, fy) (the map configuration's model, trn_refine_noise_var_'s),
 * one normal per cell with data, in row order; trn_localize_dem in win. */
static int heights_localize(world_t *w, const trn_window_t *roi, const trn_window_t *win, int fx,
                            int fy, exp_rng_t *r, sense_t *s, char *err, size_t err_len)
{
    const int pw = roi->x1 - roi->x0 + 1, ph = roi->y1 - roi->y0 + 1;
    const double nm = (double)w->map.cfg.noise_m, nk = (double)w->map.cfg.noise_k_per_m,
                 cell = (double)w->map.cfg.terrain.cell_m;
    const size_t max_pts = (size_t)pw * (size_t)ph * (size_t)w->pg.nz;
    trn_grid_f32_t lg;
    trn_loc_result_t res;
    trn_status_t st;
    size_t n = 0, need;
    int x, y;
    for (y = 0; y < ph; ++y) {
        for (x = 0; x < pw; ++x) {
            double h = (double)
                           w->dem[(size_t)(roi->y0 + y) * (size_t)w->nx + (size_t)(roi->x0 + x)];
            double dx = (double)(roi->x0 + x - fx) * cell, dy = (double)(roi->y0 + y - fy) * cell;
            float v = NAN;
            if (isfinite(h)) {
                v = (float)(h + (nm + nk * (dx * dx + dy * dy)) * rng_normal(r));
                ++n;
            }
            w->hgrid[(size_t)y * (size_t)pw + (size_t)x] = v;
        }
    }
    s->n_points = n;
    if (n == 0 || trn_grid_f32_init(&lg, w->hgrid, (size_t)pw * (size_t)ph, pw, ph) != TRN_OK) {
        s->no_points = 1;
        return 0;
    }
    need = trn_localize_dem_workspace_bytes(&w->map, pw, ph, max_pts, win);
    if (need == 0) {
        snprintf(err, err_len, "internal error: trn_localize_dem refused a %d x %d local map", pw,
                 ph);
        return -1;
    }
    if (grow_ws(&w->dws, &w->dws_raw, &w->dws_b, need, "height matcher", err, err_len) != 0) {
        return -1;
    }
    st = trn_localize_dem(&w->map, &lg, fx - roi->x0, fy - roi->y0, max_pts, win, w->dws, w->dws_b,
                          &res);
    if (st == TRN_E_NODATA) {
        s->no_points = 1;
        return 0;
    }
    if (st != TRN_OK && st != TRN_E_ILLCOND && st != TRN_E_AMBIGUOUS) {
        snprintf(err, err_len, "trn_localize_dem: %s", trn_strerror(st));
        return -1;
    }
    s->illcond = st == TRN_E_ILLCOND;
    s->fix = st == TRN_OK;
    s->ambiguous = st == TRN_E_AMBIGUOUS;
    s->rescaled = res.noise_scale != 1.0;
    s->err_m = sqrt((res.x - fx) * (res.x - fx) + (res.y - fy) * (res.y - fy)) * cell;
    s->ok = 1;
    return 0;
}

/* The prior window around (px, py), clipped to the map. */
static void prior_window(const world_t *w, int px, int py, trn_window_t *win)
{
    win->x0 = px - w->win_cells < 0 ? 0 : px - w->win_cells;
    win->y0 = py - w->win_cells < 0 ? 0 : py - w->win_cells;
    win->x1 = px + w->win_cells > w->nx - 1 ? w->nx - 1 : px + w->win_cells;
    win->y1 = py + w->win_cells > w->ny - 1 ? w->ny - 1 : py + w->win_cells;
}

/* Sense the patch centred on (cx, cy) (global cells, the patch actually seen)
 * from the true rover cell (fx, fy), localize in the window around (px, py). */
static int sense_and_localize(world_t *w, int cx, int cy, int fx, int fy, int px, int py,
                              double dtheta, exp_rng_t *r, sense_t *s, char *err, size_t err_len)
{
    trn_window_t roi, win;
    trn_vol_f32_t pv;
    trn_xy_t rover;
    trn_loc_result_t res;
    trn_status_t st;
    size_t n, need;
    int pw, ph;
    double ex, ey;
    memset(s, 0, sizeof *s);
    roi.x0 = cx - w->half < 0 ? 0 : cx - w->half;
    roi.y0 = cy - w->half < 0 ? 0 : cy - w->half;
    roi.x1 = cx + w->half > w->nx - 1 ? w->nx - 1 : cx + w->half;
    roi.y1 = cy + w->half > w->ny - 1 ? w->ny - 1 : cy + w->half;
    if (roi.x0 > roi.x1 || roi.y0 > roi.y1) {
        s->no_points = 1;
        return 0;
    }
    pw = roi.x1 - roi.x0 + 1;
    ph = roi.y1 - roi.y0 + 1;
    prior_window(w, px, py, &win);
    if (w->heights) {
        return heights_localize(w, &roi, &win, fx, fy, r, s, err, err_len);
    }
    if (w->p->sensor == EXP_SENSOR_DEM) {
        if (dem_sensor(w, &roi, fx, fy, r, &n, err, err_len) != 0) {
            return -1;
        }
        goto sensed;
    }
    pv.data = w->pvol;
    pv.nx = pw;
    pv.ny = ph;
    pv.nz = w->pg.nz;
    rover.x_cells = (float)fx;
    rover.y_cells = (float)fy;
    st = trn_prob_local(&w->k, &w->scfg.local_sigma, w->cellf, rover, &w->pg, &roi, &pv, w->pws,
                        w->pws_b);
    if (st != TRN_OK) {
        snprintf(err, err_len, "trn_prob_local: %s", trn_strerror(st));
        return -1;
    }
    n = exp_sample_points(pv.data, pw, ph, pv.nz, roi.x0 - fx, roi.y0 - fy, r, w->pts, w->pts_cap);
    if (n > w->pts_cap) {
        snprintf(err, err_len, "internal error: %zu sampled points for %zu places", n, w->pts_cap);
        return -1;
    }
sensed:
    s->n_points = n;
    if (n == 0) {
        s->no_points = 1;
        return 0;
    }
    /* the heading error: the sensed points turned about the rover */
    if (dtheta != 0.0 && (st = trn_points_rotate(w->pts, n, dtheta, w->pts)) != TRN_OK) {
        snprintf(err, err_len, "trn_points_rotate: %s", trn_strerror(st));
        return -1;
    }
    if ((st = trn_points_order(w->pts, n, w->pg.nz)) != TRN_OK) {
        snprintf(err, err_len, "trn_points_order: %s", trn_strerror(st));
        return -1;
    }
    need = trn_localize_workspace_bytes(&w->map, &win);
    if (need == 0) {
        snprintf(err, err_len, "internal error: window rejected by trn_localize_workspace_bytes");
        return -1;
    }
    /* grow (a clipped window never needs more, but do not rely on it) */
    if (grow_ws(&w->lws, &w->lws_raw, &w->lws_b, need, "localization", err, err_len) != 0) {
        return -1;
    }
    st = trn_localize_points(&w->map, w->pts, n, &win, w->lws, w->lws_b, &res);
    if (st != TRN_OK && st != TRN_E_ILLCOND) {
        snprintf(err, err_len, "trn_localize_points: %s", trn_strerror(st));
        return -1;
    }
    s->illcond = st == TRN_E_ILLCOND;
    ex = (st == TRN_OK ? res.x : (double)res.ix) - fx;
    ey = (st == TRN_OK ? res.y : (double)res.iy) - fy;
    s->err_m = sqrt(ex * ex + ey * ey) * w->cellf;
    s->ok = 1;
    return w->h3win_rad > 0.0 ? localize_3dof(w, n, &win, fx, fy, s, err, err_len) : 0;
}

/* Tally one localization into an arm and its trial's cluster. */
static void tally(exp_arm_t *a, const sense_t *s, double success_m, double cell, long *k, double *e,
                  double *e2);

/* The same localization's 3-DOF result into its arm. */
static void tally3(exp_arm_t *a, const sense_t *s, double success_m, double cell, long *k,
                   double *e, double *e2)
{
    sense_t s3 = *s;
    s3.err_m = s->err3_m;
    s3.illcond = s->illcond3;
    tally(a, &s3, success_m, cell, k, e, e2);
}

static void tally(exp_arm_t *a, const sense_t *s, double success_m, double cell, long *k, double *e,
                  double *e2)
{
    a->localizations++;
    a->mean_points += (double)s->n_points;
    if (s->no_points) {
        a->no_points++;
    }
    if (!s->ok) {
        return;
    }
    a->ill_conditioned += s->illcond;
    a->fixes += s->fix;
    a->ambiguous += s->ambiguous;
    a->noise_rescaled += s->rescaled;
    a->wrong_fixes += s->fix && !(s->err_m <= success_m + 1e-9);
    a->success_1cell += s->err_m <= 1.0 * cell + 1e-9;
    a->success_5cells += s->err_m <= 5.0 * cell + 1e-9;
    if (s->err_m <= success_m + 1e-9) {
        a->successes++;
        ++*k;
        *e += s->err_m;
        *e2 += s->err_m * s->err_m;
    }
}

/* The generated terrain (`trn terrain` with the experiment's parameters)
 * into a new nx x ny heights array (*dem). 0, or -1 with the reason. */
static int gen_terrain(const exp_params_t *p, exp_result_t *out, float **dem, char *err,
                       size_t err_len)
{
    tg_params_t tp;
    const char *why;
    tg_rock_t *rocks;
    size_t nr;
    int n = p->size_cells;

    tg_default(&tp, n, n, p->cell_m);
    tp.coverage_k = p->coverage_k;
    tp.d_max_m = tg_auto_d_max(p->coverage_k);
    tp.seed = p->terrain_seed;
    tp.relief_m = p->relief_m;
    if (p->d_min_m > 0.0) {
        tp.d_min_m = p->d_min_m;
    }
    if (tp.d_max_m < tp.d_min_m) {
        snprintf(err, err_len, "smallest rock diameter %g m is above the largest %g m", tp.d_min_m,
                 tp.d_max_m);
        return -1;
    }
    if ((why = tg_check(&tp)) != NULL) {
        snprintf(err, err_len, "terrain: %s", why);
        return -1;
    }
    nr = tg_draw_rocks(&tp, NULL, 0);
    rocks = malloc((nr + 1) * sizeof *rocks);
    *dem = malloc((size_t)n * (size_t)n * sizeof **dem);
    if (rocks == NULL || *dem == NULL) {
        free(rocks);
        free(*dem);
        *dem = NULL;
        snprintf(err, err_len, "out of memory for the terrain");
        return -1;
    }
    tg_draw_rocks(&tp, rocks, nr);
    tg_render(&tp, rocks, nr, *dem, NULL, NULL);
    free(rocks);
    out->rocks = nr;
    out->d_min_m = tp.d_min_m;
    return 0;
}

/* The heights: a copy of the given DEM or the generated terrain (w->dem,
 * kept for the DEM sensor and the no-data test; freed by exp_run). */
static int world_heights(world_t *w, const exp_params_t *p, exp_result_t *out, char *err,
                         size_t err_len)
{
    float *dem = NULL;
    size_t i;
    if (p->dem != NULL) {
        w->nx = p->dem_width;
        w->ny = p->dem_height;
        dem = malloc((size_t)w->nx * (size_t)w->ny * sizeof *dem);
        if (dem == NULL) {
            snprintf(err, err_len, "out of memory for the DEM");
            return -1;
        }
        memcpy(dem, p->dem, (size_t)w->nx * (size_t)w->ny * sizeof *dem);
        for (i = 0; i < (size_t)w->nx * (size_t)w->ny; ++i) {
            w->has_nodata |= !isfinite(dem[i]);
        }
    } else {
        w->nx = w->ny = p->size_cells;
        if (gen_terrain(p, out, &dem, err, err_len) != 0) {
            return -1;
        }
    }
    w->dem = dem;
    w->cellf = (float)p->cell_m;
    return 0;
}

/* The map (configuration: the caller's, or the paper's scaled to the cell) and the kernels. */
static int world_map(world_t *w, const exp_params_t *p, exp_result_t *out, void **raw, char *err,
                     size_t err_len)
{
    trn_map_cfg_t cfg;
    trn_grid_f32_t g;
    trn_status_t st;
    size_t mb;
    void *mbuf;
    int nx = w->nx, ny = w->ny;

    if (p->map_cfg != NULL) {
        if (p->map_cfg(p->map_cfg_ctx, w->dem, nx, ny, p->cell_m, &cfg, err, err_len) != 0) {
            return -1;
        }
    } else {
        trn_map_cfg_default(&cfg);
        cfg.terrain.cell_m = w->cellf;
        cfg.terrain.zbin_m = w->cellf;
        cfg.terrain.highpass_half_m = (float)(10.0 * p->cell_m);
        cfg.sigma_m = w->cellf;
    }
    out->map_cfg = cfg;
    w->heights = out->heights = cfg.match == TRN_MATCH_HEIGHTS;
    if (trn_grid_f32_init(&g, w->dem, (size_t)nx * (size_t)ny, nx, ny) != TRN_OK) {
        snprintf(err, err_len, "map of %d x %d cells rejected by the core", nx, ny);
        return -1;
    }
    mb = trn_map_bytes(&cfg, nx, ny);
    mbuf = mb > 0 ? alloc16(mb, &raw[0]) : NULL;
    if (mbuf == NULL) {
        snprintf(err, err_len, "cannot allocate %zu bytes for the prepared map", mb);
        return -1;
    }
    st = trn_map_build(&w->map, &cfg, &g, mbuf, mb);
    w->tcfg = cfg.terrain;
    if (st != TRN_OK) {
        snprintf(err, err_len, "trn_map_build: %s", trn_strerror(st));
        return -1;
    }
    if ((st = trn_kernels_build(&w->k, TRN_KERNEL_SIGMA0_DEFAULT_CELLS)) != TRN_OK) {
        snprintf(err, err_len, "trn_kernels_build: %s", trn_strerror(st));
        return -1;
    }
    return 0;
}

/* Eq. 8: one sensing position of the global map, at the map's centre; the
 * error model's constant scales with the cell. Its r^2 term: on the
 * generated terrain the paper's (a map sensed from its centre); on a DEM
 * (p->dem) none by default: a DEM file is an overhead product (orbital or
 * airborne), sensed from no point on it, so its error does not grow with
 * the distance from its centre (with the paper's term scaled to the cell,
 * the success rate fell with the DEM's extent: docs/method.md 9). */
static int world_prob(world_t *w, const exp_params_t *p, exp_result_t *out, void **raw, char *err,
                      size_t err_len)
{
    const double f = p->cell_m / 0.1;
    int nx = w->nx, ny = w->ny;
    size_t nvox = (size_t)nx * (size_t)ny * (size_t)w->map.dist.nz, wb;
    trn_sigma_model_t gm;
    trn_xy_t centre;
    trn_status_t st;
    void *gws, *graw = NULL;

    w->pg.data = alloc16(nvox * sizeof(float), &raw[1]);
    w->pg.nx = nx;
    w->pg.ny = ny;
    w->pg.nz = w->map.dist.nz;
    wb = trn_prob_global_workspace_bytes(nx, ny);
    gws = alloc16(wb, &graw);
    if (w->pg.data == NULL || gws == NULL) {
        free(graw);
        snprintf(err, err_len, "out of memory for the probability map");
        return -1;
    }
    trn_sigma_global_default(&gm);
    gm.sigma_min_m = (float)(p->global_sigma_m >= 0.0 ? p->global_sigma_m
                                                      : (double)gm.sigma_min_m * f);
    gm.k_per_m = (float)(p->global_sigma_k >= 0.0 ? p->global_sigma_k
                         : p->dem != NULL         ? 0.0
                                                  : (double)gm.k_per_m / f);
    out->global_sigma = gm;
    {
        const int mid_x = nx / 2, mid_y = ny / 2; /* the centre cell (integer division intended) */
        centre.x_cells = (float)mid_x;
        centre.y_cells = (float)mid_y;
    }
    if (p->global_error != NULL) {
        trn_grid_f32_t eg;
        st = trn_grid_f32_init(&eg, (float *)p->global_error, (size_t)nx * (size_t)ny, nx, ny);
        if (st == TRN_OK) {
            st = trn_prob_global_raster(&w->k, &gm, &centre, 1, &eg, &w->map, &w->pg, gws, wb);
        }
    } else {
        st = trn_prob_global_map(&w->k, &gm, &centre, 1, &w->map, &w->pg, gws, wb);
    }
    free(graw);
    if (st != TRN_OK) {
        snprintf(err, err_len, "probability map (eq. 8): %s", trn_strerror(st));
        return -1;
    }
    return 0;
}

/* The selection rules (lengths scaled by the cell unless given) and the experiment's lengths in cells. */
static int world_rules(world_t *w, const exp_params_t *p, exp_result_t *out, char *err,
                       size_t err_len)
{
    const double f = p->cell_m / 0.1; /* the paper's 0.1 m cells: ranges scale with the cell */
    trn_status_t st;
    int pc;

    trn_select_cfg_default(&w->scfg);
    w->scfg.min_range_m = (float)(p->min_range_m > 0.0 ? p->min_range_m
                                                       : (double)w->scfg.min_range_m * f);
    w->scfg.max_range_m = (float)(p->max_range_m > 0.0 ? p->max_range_m
                                                       : (double)w->scfg.max_range_m * f);
    w->scfg.patch_m = (float)(p->patch_m > 0.0 ? p->patch_m : (double)w->scfg.patch_m * f);
    w->scfg.footprint_radius_m = (float)(p->footprint_m >= 0.0
                                             ? p->footprint_m
                                             : (double)w->scfg.footprint_radius_m * f);
    w->scfg.min_separation_m = (float)((double)w->scfg.min_separation_m * f);
    w->scfg.local_sigma.sigma_min_m = (float)((double)w->scfg.local_sigma.sigma_min_m * f);
    w->scfg.local_sigma.k_per_m = (float)((double)w->scfg.local_sigma.k_per_m / f);
    /* the height prediction's DEM error: the global model's constant part, as P_G's */
    w->scfg.map_sigma_m = (float)(p->global_sigma_m >= 0.0 ? p->global_sigma_m
                                                           : (double)w->scfg.map_sigma_m * f);
    if (p->heading_error_deg > 0.0) {
        /* the heading error is known in distribution: selection counts its
         * lever arm (at most the core's 0.5 rad), and the 3-DOF arms search
         * +-3 sigma unless a window is given */
        double s = p->heading_error_deg * EXP_PI / 180.0;
        w->scfg.sigma_heading_rad = (float)(s < (double)TRN_SELECT_MAX_SIGMA_HEADING_RAD
                                                ? s
                                                : (double)TRN_SELECT_MAX_SIGMA_HEADING_RAD);
        w->h3win_rad = p->heading_window_deg > 0.0 ? p->heading_window_deg * EXP_PI / 180.0
                                                   : 3.0 * s;
        w->h3win_rad = w->h3win_rad < TRN_HEADING_MAX_WINDOW_RAD ? w->h3win_rad
                                                                 : TRN_HEADING_MAX_WINDOW_RAD;
        out->heading_window_deg = w->h3win_rad * 180.0 / EXP_PI;
    }
    out->scfg = w->scfg;
    w->scfg3 = w->scfg;
    w->scfg3.heading_search = (int32_t)p->select_heading_search;
    if ((st = trn_select_cfg_check(&w->scfg, w->cellf)) != TRN_OK) {
        snprintf(err, err_len,
                 "selection rules rejected for %g m cells (range %g..%g m, patch %g m, footprint "
                 "%g m): %s "
                 "(trn_select takes ranges and patches up to 1e6 m and %d cells, footprints up "
                 "to 1e5 m, patches of 3+ cells: give --max-range-m, --patch-m, --footprint-m)",
                 p->cell_m, (double)w->scfg.min_range_m, (double)w->scfg.max_range_m,
                 (double)w->scfg.patch_m, (double)w->scfg.footprint_radius_m, trn_strerror(st),
                 TRN_MAX_DIM);
        return -1;
    }
    pc = (int)floor((double)w->scfg.patch_m / (double)w->cellf + 0.5);
    pc = pc % 2 == 0 ? pc + 1 : pc;
    w->half = pc / 2;
    w->win_cells = (int)ceil(p->window_m / p->cell_m - 1e-9);
    w->prior_cells = (int)floor(p->prior_error_m / p->cell_m + 1e-9);
    w->grid_cells = (int)floor(p->grid_spacing_m / p->cell_m + 0.5);
    return 0;
}

/* The selection, local probability, localization and sensor workspaces. */
static int world_buffers(world_t *w, const exp_params_t *p, void **raw, char *err, size_t err_len)
{
    trn_window_t pr, lw;
    w->cap = trn_select_max_candidates(&w->scfg, w->cellf);
    w->cands = malloc((w->cap + 1) * sizeof *w->cands);
    /* the 3-DOF arm's selection needs at least the x-y arm's workspace */
    w->sws_b = trn_select_workspace_bytes(&w->scfg3, &w->map, &w->k);
    w->sws = alloc16(w->sws_b, &raw[2]);
    pr.x0 = pr.y0 = 0;
    pr.x1 = pr.y1 = 2 * w->half;
    w->pws_b = trn_prob_local_workspace_bytes(&w->k, &pr);
    w->pws = alloc16(w->pws_b, &raw[3]);
    /* Sized for the largest window; grown per call if a window needs more. */
    lw.x0 = lw.y0 = 0;
    lw.x1 = 2 * w->win_cells < w->nx - 1 ? 2 * w->win_cells : w->nx - 1;
    lw.y1 = 2 * w->win_cells < w->ny - 1 ? 2 * w->win_cells : w->ny - 1;
    w->lws_b = trn_localize_workspace_bytes(&w->map, &lw);
    w->lws = alloc16(w->lws_b, &w->lws_raw);
    w->pvol = alloc16((size_t)(2 * w->half + 1) * (size_t)(2 * w->half + 1) * (size_t)w->pg.nz *
                          sizeof(float),
                      &raw[5]);
    w->pts_cap = (size_t)(2 * w->half + 1) * (size_t)(2 * w->half + 1) * (size_t)w->pg.nz;
    w->pts = malloc(w->pts_cap * sizeof *w->pts);
    if (w->cap == 0 || w->cands == NULL || w->sws_b == 0 || w->sws == NULL || w->pws_b == 0 ||
        w->pws == NULL || w->lws == NULL || w->pvol == NULL || w->pts == NULL) {
        snprintf(err, err_len, "out of memory for the selection and localization workspaces");
        return -1;
    }
    if (w->heights) {
        w->hgrid = malloc((size_t)(2 * w->half + 1) * (size_t)(2 * w->half + 1) * sizeof(float));
        if (w->hgrid == NULL) {
            snprintf(err, err_len, "out of memory for the local height map");
            return -1;
        }
    }
    if (p->sensor == EXP_SENSOR_DEM) {
        int side;
        w->hp_cells = (int)floor((double)w->tcfg.highpass_half_m / (double)w->tcfg.cell_m + 0.5);
        side = 2 * (w->half + w->hp_cells) + 1;
        w->ldem = malloc((size_t)side * (size_t)side * sizeof(float));
        w->lhp = malloc((size_t)side * (size_t)side * sizeof(float));
        w->hws_b = trn_highpass_workspace_bytes(side, side);
        w->hws = alloc16(w->hws_b, &raw[6]);
        free(w->pts);
        w->pts_cap = (size_t)side * (size_t)side * (size_t)w->pg.nz;
        w->pts = malloc(w->pts_cap * sizeof *w->pts);
        if (w->ldem == NULL || w->lhp == NULL || w->hws == NULL || w->pts == NULL) {
            snprintf(err, err_len, "out of memory for the DEM sensor");
            return -1;
        }
    }
    return 0;
}

static int build_world(world_t *w, const exp_params_t *p, exp_result_t *out, void **raw, char *err,
                       size_t err_len)
{
    int need;
    if (world_heights(w, p, out, err, err_len) != 0 ||
        world_map(w, p, out, raw, err, err_len) != 0) {
        return -1;
    }
    if (w->heights && (p->sensor != EXP_SENSOR_PROB || p->heading_error_deg > 0.0)) {
        snprintf(err, err_len,
                 "the height matcher's local maps are the DEM's heights with the noise model: "
                 "no --sensor dem, no heading error (the 3-DOF search is the voxel search's)");
        return -1;
    }
    if (world_prob(w, p, out, raw, err, err_len) != 0 ||
        world_rules(w, p, out, err, err_len) != 0 || world_buffers(w, p, raw, err, err_len) != 0) {
        return -1;
    }
    need = 2 * w->grid_cells + 2 * w->half + 3;
    if (w->nx < need || w->ny < need) {
        snprintf(err, err_len,
                 "the map (%d x %d cells) is too small for the experiment: nine %d-cell patches %d "
                 "cells "
                 "apart need at least %d x %d cells (a larger DEM, or smaller --grid-spacing-m / "
                 "--patch-m)",
                 w->nx, w->ny, 2 * w->half + 1, w->grid_cells, need, need);
        return -1;
    }
    out->patch_cells = 2 * w->half + 1;
    out->grid_cells = w->grid_cells;
    out->window_cells = w->win_cells;
    out->prior_cells = w->prior_cells;
    out->success_radius_m = p->success_cells * p->cell_m;
    return 0;
}

/* Per trial (cluster) counts of each arm: localizations m, successes k,
 * error sums e and e2 of the successes (exp_cluster_stats). */
typedef struct {
    long *mw, *kw, *mo, *ko;
    double *ew, *e2w, *eo, *e2o;
    long *kw3, *ko3; /* the 3-DOF arms (same localizations per trial) */
    double *ew3, *e2w3, *eo3, *e2o3;
} clusters_t;

static int clusters_alloc(clusters_t *c, size_t nt)
{
    c->mw = calloc(nt, sizeof *c->mw);
    c->kw = calloc(nt, sizeof *c->kw);
    c->mo = calloc(nt, sizeof *c->mo);
    c->ko = calloc(nt, sizeof *c->ko);
    c->ew = calloc(nt, sizeof *c->ew);
    c->e2w = calloc(nt, sizeof *c->e2w);
    c->eo = calloc(nt, sizeof *c->eo);
    c->e2o = calloc(nt, sizeof *c->e2o);
    c->kw3 = calloc(nt, sizeof *c->kw3);
    c->ko3 = calloc(nt, sizeof *c->ko3);
    c->ew3 = calloc(nt, sizeof *c->ew3);
    c->e2w3 = calloc(nt, sizeof *c->e2w3);
    c->eo3 = calloc(nt, sizeof *c->eo3);
    c->e2o3 = calloc(nt, sizeof *c->e2o3);
    return c->mw && c->kw && c->mo && c->ko && c->ew && c->e2w && c->eo && c->e2o && c->kw3 &&
           c->ko3 && c->ew3 && c->e2w3 && c->eo3 && c->e2o3;
}

static void clusters_free(clusters_t *c)
{
    free(c->mw);
    free(c->kw);
    free(c->mo);
    free(c->ko);
    free(c->ew);
    free(c->e2w);
    free(c->eo);
    free(c->e2o);
    free(c->kw3);
    free(c->ko3);
    free(c->ew3);
    free(c->e2w3);
    free(c->eo3);
    free(c->e2o3);
}

/* One trial's draw: start S, finish F, prior P = F + O, the midpoint M of S and P (cells). */
typedef struct {
    int sx, sy, fx, fy, px, py, mx, my, ox, oy;
    double dtheta; /* the heading error of the trial's sensing, rad (0 without one) */
} trial_t;

/* 1-2: start, finish, prior; the nine fixed targets must be sensible. 1 if
 * a draw was accepted within EXP_MAX_DRAWS. */
static int draw_trial(const world_t *w, exp_rng_t *r, exp_result_t *out, trial_t *d)
{
    long k;
    int accepted = 0;
    for (k = 0; k < EXP_MAX_DRAWS && !accepted; ++k) {
        int gx, gy;
        out->draws++;
        d->sx = (int)exp_rng_range(r, 0, w->nx - 1);
        d->sy = (int)exp_rng_range(r, 0, w->ny - 1);
        d->fx = (int)exp_rng_range(r, 0, w->nx - 1);
        d->fy = (int)exp_rng_range(r, 0, w->ny - 1);
        d->ox = (int)exp_rng_range(r, -w->prior_cells, w->prior_cells);
        d->oy = (int)exp_rng_range(r, -w->prior_cells, w->prior_cells);
        d->px = d->fx + d->ox;
        d->py = d->fy + d->oy;
        if (d->px < 0 || d->py < 0 || d->px > w->nx - 1 || d->py > w->ny - 1 ||
            (w->has_nodata && !isfinite(w->dem[(size_t)d->fy * (size_t)w->nx + (size_t)d->fx]))) {
            continue;
        }
        d->mx = (d->sx + d->px) / 2;
        d->my = (d->sy + d->py) / 2;
        accepted = 1;
        for (gy = -1; gy <= 1 && accepted; ++gy) {
            for (gx = -1; gx <= 1 && accepted; ++gx) {
                int tx = d->mx + gx * w->grid_cells, ty = d->my + gy * w->grid_cells;
                accepted = target_ok(w, tx, ty, d->px, d->py) &&
                           patch_inside(w, tx - d->ox, ty - d->oy);
            }
        }
    }
    return accepted;
}

/* The 3-DOF arm with selection: its own target from w->scfg3 (a heading
 * search's selection, method.md 4) when the flag is on, sensed from r0, the
 * trial's random state before the x-y arm sensed (cx, cy), so the same target
 * is the same points (s2, not sensed again); 0, or -1 with the reason. */
static int trial_with3(world_t *w, const trial_t *d, long t, const trn_rover_t *rover, int32_t cx,
                       int32_t cy, double range, exp_rng_t *r0, const sense_t *s2,
                       exp_result_t *out, clusters_t *c, char *err, size_t err_len)
{
    const exp_params_t *p = w->p;
    const sense_t *s = s2;
    sense_t s3;
    if (w->scfg3.heading_search == 1) {
        trn_select_result_t sres;
        size_t ranked = 0;
        const trn_candidate_t *cand;
        trn_status_t st = trn_select(&w->map, &w->k, &w->pg, &w->scfg3, rover, w->cands, w->cap,
                                     &ranked, 1, &sres, w->sws, w->sws_b);
        if (st == TRN_E_NOTARGET) {
            out->with3.no_target++;
            out->with3.localizations++;
            return 0;
        }
        if (st != TRN_OK) {
            snprintf(err, err_len, "trial %ld: trn_select (3-DOF arm): %s", t, trn_strerror(st));
            return -1;
        }
        cand = &w->cands[ranked];
        range = (double)cand->range_m;
        if (cand->x != cx || cand->y != cy) {
            if (sense_and_localize(w, cand->x - d->ox, cand->y - d->oy, d->fx, d->fy, d->px, d->py,
                                   d->dtheta, r0, &s3, err, err_len) != 0) {
                return -1;
            }
            s = &s3;
            out->with3_other_target++;
        }
    }
    out->with3.mean_range_m += range;
    tally3(&out->with3, s, p->success_cells * p->cell_m, p->cell_m, &c->kw3[t], &c->ew3[t],
           &c->e2w3[t]);
    return 0;
}

/* 3-5: with selection, from the prior: trn_select's best target, sensed
 * shifted by the prior's error, localized. 0, or -1 with the reason. */
static int trial_with(world_t *w, const trial_t *d, long t, exp_rng_t *r, exp_result_t *out,
                      clusters_t *c, char *err, size_t err_len)
{
    const exp_params_t *p = w->p;
    trn_rover_t rover;
    trn_select_result_t sres;
    size_t ranked = 0;
    trn_status_t st;
    sense_t s;
    const trn_candidate_t *cand;
    exp_rng_t r0;
    int32_t cx, cy;
    double range;

    rover.pos.x_cells = (float)d->px;
    rover.pos.y_cells = (float)d->py;
    rover.heading_rad = (d->sx == d->px && d->sy == d->py)
                            ? 0.0f
                            : (float)atan2((double)(d->py - d->sy), (double)(d->px - d->sx));
    st = trn_select(&w->map, &w->k, &w->pg, &w->scfg, &rover, w->cands, w->cap, &ranked, 1, &sres,
                    w->sws, w->sws_b);
    c->mw[t] = 1;
    if (st == TRN_E_NOTARGET) {
        out->with.no_target++;
        out->with.localizations++;
        if (w->h3win_rad > 0.0) {
            out->with3.no_target++;
            out->with3.localizations++;
        }
        return 0;
    }
    if (st != TRN_OK) {
        snprintf(err, err_len, "trial %ld: trn_select: %s", t, trn_strerror(st));
        return -1;
    }
    cand = &w->cands[ranked];
    if (sres.patch_cells != 2 * w->half + 1) {
        snprintf(err, err_len, "internal error: patch of %d cells, trn_select used %d",
                 2 * w->half + 1, (int)sres.patch_cells);
        return -1;
    }
    out->with.mean_range_m += (double)cand->range_m;
    r0 = *r;
    cx = cand->x;
    cy = cand->y;
    range = (double)cand->range_m;
    if (sense_and_localize(w, cand->x - d->ox, cand->y - d->oy, d->fx, d->fy, d->px, d->py,
                           d->dtheta, r, &s, err, err_len) != 0) {
        return -1;
    }
    tally(&out->with, &s, p->success_cells * p->cell_m, p->cell_m, &c->kw[t], &c->ew[t],
          &c->e2w[t]);
    return w->h3win_rad > 0.0
               ? trial_with3(w, d, t, &rover, cx, cy, range, &r0, &s, out, c, err, err_len)
               : 0;
}

/* Without selection: the nine fixed targets around the midpoint, each its own localization. */
static int trial_without(world_t *w, const trial_t *d, long t, exp_rng_t *r, exp_result_t *out,
                         clusters_t *c, char *err, size_t err_len)
{
    const exp_params_t *p = w->p;
    sense_t s;
    int i;
    c->mo[t] = 9;
    for (i = 0; i < 9; ++i) {
        int tx = d->mx + (i % 3 - 1) * w->grid_cells, ty = d->my + (i / 3 - 1) * w->grid_cells;
        out->without.mean_range_m += sqrt((double)(tx - d->px) * (tx - d->px) +
                                          (double)(ty - d->py) * (ty - d->py)) *
                                     p->cell_m;
        if (sense_and_localize(w, tx - d->ox, ty - d->oy, d->fx, d->fy, d->px, d->py, d->dtheta, r,
                               &s, err, err_len) != 0) {
            return -1;
        }
        tally(&out->without, &s, p->success_cells * p->cell_m, p->cell_m, &c->ko[t], &c->eo[t],
              &c->e2o[t]);
        if (w->h3win_rad > 0.0) {
            tally3(&out->without3, &s, p->success_cells * p->cell_m, p->cell_m, &c->ko3[t],
                   &c->eo3[t], &c->e2o3[t]);
        }
    }
    return 0;
}

/* The arms' statistics and means from the per-trial counts. */
static void exp_summarise(const exp_params_t *p, const clusters_t *c, double sum_trav,
                          exp_result_t *out)
{
    exp_cluster_stats(c->mw, c->kw, c->ew, c->e2w, p->trials, &out->with.st);
    exp_cluster_stats(c->mo, c->ko, c->eo, c->e2o, p->trials, &out->without.st);
    if (out->with.localizations - out->with.no_target > 0) {
        out->with.mean_range_m /= (double)(out->with.localizations - out->with.no_target);
    }
    out->with.mean_points /= (double)out->with.localizations;
    out->without.mean_range_m /= (double)out->without.localizations;
    out->without.mean_points /= (double)out->without.localizations;
    out->mean_traverse_m = sum_trav / (double)p->trials;
    if (out->with3.localizations > 0) {
        exp_cluster_stats(c->mw, c->kw3, c->ew3, c->e2w3, p->trials, &out->with3.st);
        exp_cluster_stats(c->mo, c->ko3, c->eo3, c->e2o3, p->trials, &out->without3.st);
        if (out->with3.localizations - out->with3.no_target > 0) {
            out->with3.mean_range_m /= (double)(out->with3.localizations - out->with3.no_target);
        }
        out->with3.mean_points /= (double)out->with3.localizations;
        out->without3.mean_range_m = out->without.mean_range_m;
        out->without3.mean_points = out->without.mean_points;
    }
}

int exp_run(const exp_params_t *p, exp_result_t *out, exp_progress_fn progress, void *ctx,
            char *err, size_t err_len)
{
    world_t w;
    void *raw[7] = {NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    clusters_t c;
    long t;
    double sum_trav = 0.0;
    const char *why;
    int rc = -1, i;

    memset(out, 0, sizeof *out);
    memset(&w, 0, sizeof w);
    memset(&c, 0, sizeof c);
    w.p = p;
    if ((why = exp_params_check(p)) != NULL) {
        snprintf(err, err_len, "%s", why);
        return -1;
    }
    if (!clusters_alloc(&c, (size_t)p->trials)) {
        snprintf(err, err_len, "out of memory for %ld trials", p->trials);
        goto done;
    }
    if (build_world(&w, p, out, raw, err, err_len) != 0) {
        goto done;
    }
    for (t = 0; t < p->trials; ++t) {
        exp_rng_t r;
        trial_t d;
        memset(&d, 0, sizeof d);
        exp_rng_seed(&r, p->seed, (uint64_t)t);
        if (!draw_trial(&w, &r, out, &d)) {
            snprintf(err, err_len,
                     "trial %ld: no start/finish pair with all nine fixed targets in reach after "
                     "%ld draws "
                     "(map too small for the sensor's reach%s?)",
                     t, (long)EXP_MAX_DRAWS, w.has_nodata ? ", or too much of it no-data" : "");
            goto done;
        }
        if (p->heading_error_deg > 0.0) {
            d.dtheta = rng_normal(&r) * p->heading_error_deg * EXP_PI / 180.0;
        }
        sum_trav += sqrt((double)(d.sx - d.fx) * (d.sx - d.fx) +
                         (double)(d.sy - d.fy) * (d.sy - d.fy)) *
                    p->cell_m;
        if (trial_with(&w, &d, t, &r, out, &c, err, err_len) != 0 ||
            trial_without(&w, &d, t, &r, out, &c, err, err_len) != 0) {
            goto done;
        }
        if (progress != NULL && progress(ctx, t + 1, p->trials) != 0) {
            snprintf(err, err_len, "cancelled after %ld of %ld trials", t + 1, p->trials);
            goto done;
        }
    }
    exp_summarise(p, &c, sum_trav, out);
    rc = 0;

done:
    for (i = 0; i < 7; ++i) {
        free(raw[i]);
    }
    free(w.dem);
    free(w.ldem);
    free(w.lhp);
    free(w.lws_raw);
    free(w.h3ws_raw);
    free(w.dws_raw);
    free(w.hgrid);
    free(w.cands);
    free(w.pts);
    clusters_free(&c);
    return rc;
}
