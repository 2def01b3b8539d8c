/* SPDX-License-Identifier: Apache-2.0 */
/* bench_select.c - see bench_select.h.
 *
 *   pmap     trn_prob_global_map (eq. 8, one sensing position at the map
 *            centre, trn_sigma_global_default) against a direct 2-D
 *            position-variant scatter (each occupied voxel spreads the 2-D
 *            kernel k_j x k_j of its own sigma: the obvious slow version),
 *            and with OpenCV against cv::sepFilter2D on each of the nz float
 *            slices with the widest kernel the map uses (fixed sigma).
 *   select   trn_select with trn_select_cfg_default (1-10 m, 2 m patches,
 *            stride 2) at a rover near the map centre, against a naive
 *            version: the same eq. 9 region, then for every candidate and
 *            every pose offset the patch sum over its voxels, then the fit.
 *   field    trn_field with a small reach (0.5-2 m, 0.9 m patches, stride 2)
 *            over the whole map, against brute force (trn_select at every
 *            rover cell): brute force is timed on a 32 x 32 block and
 *            scaled by the cell count (printed as an estimate); and
 *            trn_field_fast (the ground path) on the same field.
 *   field    the paper's defaults (trn_select_cfg_default: 1-10 m, 2 m
 *   (paper)  patches, stride 2; trn_field_cfg_default), as `trn field` runs
 *            them, over a 64 x 64 area at the map's centre: trn_field against
 *            trn_field_fast in the same run. Both fields must be identical
 *            (raster, evaluated cells, statistics), else a wrong answer.
 */
#define _POSIX_C_SOURCE 200112L

#include "bench_select.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#ifdef TRN_HAVE_OPENCV
#include "opencv/bench_cv.h"
#endif

#define BS_MAX_REPS 100

static volatile double g_bs_sink;

static double bs_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static int bs_cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

typedef int (*bs_fn_t)(void *);

typedef struct {
    int reps;
    double med, min;
} bs_t;

/* warm-up (if asked), then up to reps timed calls, stopping after budget_s */
static int bs_time(bs_fn_t fn, void *ctx, int warm, int reps, double budget_s, bs_t *t)
{
    double s[BS_MAX_REPS], start;
    int n = 0;
    if (warm && fn(ctx) != 0) {
        return -1;
    }
    start = bs_now();
    while (n < reps && n < BS_MAX_REPS) {
        double t0 = bs_now(), t1;
        if (fn(ctx) != 0) {
            return -1;
        }
        t1 = bs_now();
        s[n++] = (t1 - t0) * 1e3;
        if (budget_s > 0.0 && t1 - start > budget_s) {
            break;
        }
    }
    qsort(s, (size_t)n, sizeof s[0], bs_cmp);
    t->reps = n;
    t->min = s[0];
    t->med = (n % 2) ? s[n / 2] : 0.5 * (s[n / 2 - 1] + s[n / 2]);
    return 0;
}

static void bs_row(int32_t n, const char *name, const bs_t *t, const char *note)
{
    printf("%-5d %-50s %4d %11.3f %11.3f  %s\n", (int)n, name, t->reps, t->med, t->min,
           note != NULL ? note : "");
    fflush(stdout);
}

static void bs_ratio(const char *what, double num, double den, const char *note)
{
    printf("      ratio %-56s %8.2fx%s%s\n", what, num / den, note ? "  " : "", note ? note : "");
    fflush(stdout);
}

static void *bs_alloc(size_t b)
{
    void *p = NULL;
    return posix_memalign(&p, 16u, b ? b : 16u) == 0 ? p : NULL;
}

/* ---- eq. 8 ---------------------------------------------------------------- */

typedef struct {
    const trn_map_t *map;
    const trn_kernels_t *k;
    trn_sigma_model_t gm;
    trn_xy_t s;
    trn_vol_f32_t pg;
    void *ws;
    size_t wsb;
    const uint8_t *kidx; /* naive: kernel per cell */
    double *naive;       /* naive output */
} pmap_ctx_t;

static int run_pmap(void *p)
{
    pmap_ctx_t *c = (pmap_ctx_t *)p;
    return trn_prob_global_map(c->k, &c->gm, &c->s, 1, c->map, &c->pg, c->ws, c->wsb) == TRN_OK
               ? 0
               : -1;
}

static int run_pmap_naive(void *p)
{
    pmap_ctx_t *c = (pmap_ctx_t *)p;
    const trn_vol_u8_t *d = &c->map->dist;
    const int32_t nx = d->nx, ny = d->ny;
    int32_t x, y, z, a, b;
    memset(c->naive, 0, sizeof(double) * (size_t)nx * ny * d->nz);
    for (z = 0; z < d->nz; ++z) {
        for (y = 0; y < ny; ++y) {
            for (x = 0; x < nx; ++x) {
                int32_t j, r;
                if (d->data[TRN_VOL_IDX(d, x, y, z)] != 0u) {
                    continue;
                }
                j = c->kidx[(size_t)y * nx + x];
                r = c->k->radius[j];
                for (b = -r; b <= r; ++b) {
                    double *orow;
                    if (y + b < 0 || y + b >= ny) {
                        continue;
                    }
                    orow = c->naive + ((size_t)z * ny + (size_t)(y + b)) * nx;
                    for (a = -r; a <= r; ++a) {
                        if (x + a >= 0 && x + a < nx) {
                            orow[x + a] += (double)c->k->taps[j][TRN_KERNEL_MAX_RADIUS + a] *
                                           (double)c->k->taps[j][TRN_KERNEL_MAX_RADIUS + b];
                        }
                    }
                }
            }
        }
    }
    g_bs_sink += c->naive[(size_t)nx * ny / 2];
    return 0;
}

#ifdef TRN_HAVE_OPENCV
static int run_cv_sep(void *p) { return bench_cv_sep_run((bench_cv_sep_t *)p); }
#endif

/* ---- one rover position ------------------------------------------------------ */

typedef struct {
    const trn_map_t *map;
    const trn_kernels_t *k;
    const trn_vol_f32_t *pg;
    trn_select_cfg_t cfg;
    trn_rover_t rv;
    trn_candidate_t *c;
    size_t cap, ranked[8];
    trn_select_result_t res;
    void *ws;
    size_t wsb;
    /* naive */
    trn_vol_f32_t p;
    void *lws;
    size_t lwsb;
    double naive_best;
    size_t naive_best_i;
} sel_ctx_t;

static int run_select(void *p)
{
    sel_ctx_t *c = (sel_ctx_t *)p;
    trn_status_t st = trn_select(c->map, c->k, c->pg, &c->cfg, &c->rv, c->c, c->cap, c->ranked, 8,
                                 &c->res, c->ws, c->wsb);
    return (st == TRN_OK || st == TRN_E_NOTARGET) ? 0 : -1;
}

/* Naive: eq. 9 on the same region, then every patch summed voxel by voxel. */
static int run_select_naive(void *p)
{
    sel_ctx_t *c = (sel_ctx_t *)p;
    const trn_vol_u8_t *D = &c->map->dist;
    const trn_window_t *roi = &c->res.roi;
    const int32_t half = c->res.patch_cells / 2, cap = c->map->lnp.cap;
    size_t i;
    c->p.nx = roi->x1 - roi->x0 + 1;
    c->p.ny = roi->y1 - roi->y0 + 1;
    c->p.nz = D->nz;
    if (trn_prob_local(c->k, &c->cfg.local_sigma, c->map->cfg.terrain.cell_m, c->rv.pos, c->pg, roi,
                       &c->p, c->lws, c->lwsb) != TRN_OK) {
        return -1;
    }
    c->naive_best = HUGE_VAL;
    c->naive_best_i = (size_t)-1;
    for (i = 0; i < c->res.n_candidates; ++i) {
        double ll[9];
        trn_peak_t pk;
        int d;
        for (d = 0; d < 9; ++d) {
            const int32_t dx = d % 3 - 1, dy = d / 3 - 1;
            double s = 0.0;
            int32_t x, y, z;
            for (z = 0; z < D->nz; ++z) {
                for (y = c->c[i].y - half; y <= c->c[i].y + half; ++y) {
                    for (x = c->c[i].x - half; x <= c->c[i].x + half; ++x) {
                        const float pv =
                            c->p.data[((size_t)z * c->p.ny + (size_t)(y - roi->y0)) * c->p.nx +
                                      (size_t)(x - roi->x0)];
                        int32_t dv = D->data[TRN_VOL_IDX(D, x + dx, y + dy, z)];
                        dv = dv < cap ? dv : cap;
                        s += (double)pv * (double)c->map->lnp.lnp[dv];
                    }
                }
            }
            ll[d] = s / TRN_LNP_SCALE;
        }
        if (trn_peak_fit(ll, &pk) == TRN_OK) {
            const double u = sqrt(pk.sigma_x * pk.sigma_x + pk.sigma_y * pk.sigma_y) *
                             (double)c->map->cfg.terrain.cell_m;
            if (u < c->naive_best) {
                c->naive_best = u;
                c->naive_best_i = i;
            }
        }
    }
    g_bs_sink += c->naive_best;
    return 0;
}

/* ---- field ------------------------------------------------------------------- */

typedef struct {
    const trn_map_t *map;
    const trn_kernels_t *k;
    const trn_vol_f32_t *pg;
    trn_select_cfg_t scfg;
    trn_field_cfg_t fcfg;
    trn_window_t area, block;
    trn_grid_f32_t g;
    uint8_t *ev;
    trn_field_stats_t st;
    void *ws;
    size_t wsb;
    trn_candidate_t *c;
    size_t cap;
    void *sws;
    size_t swsb;
    int fast; /* run trn_field_fast (ws of its size) */
} field_ctx_t;

static int run_field(void *p)
{
    field_ctx_t *c = (field_ctx_t *)p;
    const size_t n = (size_t)c->g.width * (size_t)c->g.height;
    trn_status_t s;
    if (c->fast) {
        s = trn_field_fast(c->map, c->k, c->pg, &c->scfg, &c->fcfg, 0.0f, &c->area, &c->g, c->ev, n,
                           &c->st, c->ws, c->wsb);
    } else {
        s = trn_field(c->map, c->k, c->pg, &c->scfg, &c->fcfg, 0.0f, &c->area, &c->g, c->ev, n,
                      &c->st, c->ws, c->wsb);
    }
    return s == TRN_OK ? 0 : -1;
}

/* Run the field of c with both algorithms (timed, at most reps each); 0 when
 * both ran, *same = 1 when their answers are identical bit for bit. */
static int field_pair(field_ctx_t *c, int reps, double budget_s, bs_t *t_old, bs_t *t_new,
                      size_t *ws_old, size_t *ws_new, int *same)
{
    const size_t n = (size_t)c->g.width * (size_t)c->g.height;
    float *o_old = (float *)malloc(n * sizeof(float));
    uint8_t *e_old = (uint8_t *)malloc(n);
    trn_field_stats_t s_old;
    int rc = -1;
    *same = 0;
    *ws_old = trn_field_workspace_bytes(&c->scfg, c->map, c->k);
    *ws_new = trn_field_fast_workspace_bytes(&c->scfg, c->map, c->k, c->pg);
    c->fast = 0;
    c->wsb = *ws_old > *ws_new ? *ws_old : *ws_new;
    c->ws = bs_alloc(c->wsb);
    if (o_old == NULL || e_old == NULL || c->ws == NULL || *ws_old == 0u || *ws_new == 0u ||
        bs_time(run_field, c, 0, reps, budget_s, t_old) != 0) {
        goto done;
    }
    memcpy(o_old, c->g.data, n * sizeof(float));
    memcpy(e_old, c->ev, n);
    s_old = c->st;
    c->fast = 1;
    if (bs_time(run_field, c, 0, reps, budget_s, t_new) != 0) {
        goto done;
    }
    *same = memcmp(o_old, c->g.data, n * sizeof(float)) == 0 && memcmp(e_old, c->ev, n) == 0 &&
            s_old.evaluations == c->st.evaluations && s_old.best_x == c->st.best_x &&
            s_old.best_y == c->st.best_y &&
            (s_old.best_m == c->st.best_m || (isinf(s_old.best_m) && isinf(c->st.best_m)));
    rc = 0;
done:
    free(o_old);
    free(e_old);
    free(c->ws);
    c->ws = NULL;
    return rc;
}

static int run_field_block(void *p)
{
    field_ctx_t *c = (field_ctx_t *)p;
    int32_t x, y;
    size_t rk;
    for (y = c->block.y0; y <= c->block.y1; ++y) {
        for (x = c->block.x0; x <= c->block.x1; ++x) {
            trn_rover_t rv;
            trn_select_result_t r;
            trn_status_t s;
            rv.pos.x_cells = (float)x;
            rv.pos.y_cells = (float)y;
            rv.heading_rad = 0.0f;
            s = trn_select(c->map, c->k, c->pg, &c->scfg, &rv, c->c, c->cap, &rk, 1, &r, c->sws,
                           c->swsb);
            if (s != TRN_OK && s != TRN_E_NOTARGET) {
                return -1;
            }
            g_bs_sink += s == TRN_OK ? c->c[r.best].uncertainty_m : 0.0;
        }
    }
    return 0;
}

/* Eq. 8: trn_prob_global_map against the naive scatter (and OpenCV's
 * separable filter when built with it); pc's buffers and *kidx are the
 * caller's to free. 0, or nonzero when the setup failed. */
static int bench_pmap(pmap_ctx_t *pc, const trn_kernels_t *k, const trn_map_t *map, int32_t n,
                      int repeats, uint8_t **kidx, bench_select_result_t *r)
{
    bs_t t_p, t_pn;
    const size_t nvox = (size_t)map->dist.nx * map->dist.ny * map->dist.nz;
    trn_window_t whole;
    int32_t jmax = 0;
    size_t i;
    double worst = 0.0;
    char note[200];

    pc->map = map;
    pc->k = k;
    trn_sigma_global_default(&pc->gm);
    pc->s.x_cells = (float)n / 2.0f;
    pc->s.y_cells = (float)n / 2.0f;
    pc->pg.nx = map->dist.nx;
    pc->pg.ny = map->dist.ny;
    pc->pg.nz = map->dist.nz;
    pc->pg.data = (float *)bs_alloc(nvox * sizeof(float));
    pc->wsb = trn_prob_global_workspace_bytes(n, n);
    pc->ws = bs_alloc(pc->wsb);
    pc->naive = (double *)malloc(nvox * sizeof(double));
    *kidx = (uint8_t *)malloc((size_t)n * n);
    pc->kidx = *kidx;
    whole.x0 = 0;
    whole.y0 = 0;
    whole.x1 = n - 1;
    whole.y1 = n - 1;
    if (pc->pg.data == NULL || pc->ws == NULL || pc->naive == NULL || *kidx == NULL ||
        trn_spread_kernel_map(k, &pc->gm, map->cfg.terrain.cell_m, &pc->s, 1, &whole, *kidx,
                              (size_t)n * n) != TRN_OK) {
        return 1;
    }
    for (i = 0; i < (size_t)n * n; ++i) {
        jmax = (*kidx)[i] > jmax ? (*kidx)[i] : jmax;
    }
    printf("\n");
    if (bs_time(run_pmap, pc, 1, repeats, 0.0, &t_p) != 0 ||
        bs_time(run_pmap_naive, pc, 0, repeats, 3.0, &t_pn) != 0) {
        return 1;
    }
    for (i = 0; i < nvox; ++i) {
        worst = fmax(worst, fabs((double)pc->pg.data[i] - pc->naive[i]));
    }
    snprintf(note, sizeof note,
             "eq. 8, sensor at the centre, kernels 0..%d (sigma up to %.2f "
             "cells)",
             (int)jmax, (double)k->sigma_cells[jmax]);
    bs_row(n, "pmap: trn_prob_global_map", &t_p, note);
    snprintf(note, sizeof note, "direct 2-D scatter; max |separable - direct| %.3g", worst);
    bs_row(n, "pmap: naive position-variant 2-D scatter", &t_pn, note);
    r->pmap_ms = t_p.med;
    r->pmap_naive_ms = t_pn.med;
    r->pmap_cv_ms = -1.0;
    bs_ratio("naive 2-D / trn_prob_global_map", t_pn.med, t_p.med, NULL);
#ifdef TRN_HAVE_OPENCV
    {
        const int32_t rad = k->radius[jmax];
        bench_cv_sep_t *cv = bench_cv_sep_create(map->dist.data, 1, n, n, map->dist.nz,
                                                 k->taps[jmax] + (TRN_KERNEL_MAX_RADIUS - rad),
                                                 2 * rad + 1);
        bs_t t_cv;
        if (cv == NULL || bs_time(run_cv_sep, cv, 1, repeats, 0.0, &t_cv) != 0) {
            bench_cv_sep_destroy(cv);
            return 1;
        }
        g_bs_sink += bench_cv_sep_checksum(cv);
        bench_cv_sep_destroy(cv);
        snprintf(note, sizeof note, "%d slices, %d taps (kernel %d), CV_32F in and out",
                 (int)map->dist.nz, (int)(2 * rad + 1), (int)jmax);
        bs_row(n, "pmap: cv::sepFilter2D per z slice", &t_cv, note);
        r->pmap_cv_ms = t_cv.med;
        bs_ratio("cv::sepFilter2D / trn_prob_global_map", t_cv.med, t_p.med,
                 "(target >= 1 at 512)");
    }
#endif
    return 0;
}

/* All candidates of one rover position, default (paper-like) rules:
 * trn_select against the naive per-candidate sums; sc's buffers are the
 * caller's to free. 0, or nonzero when the setup failed. */
static int bench_sel(sel_ctx_t *sc, const trn_kernels_t *k, const trn_map_t *map,
                     const trn_vol_f32_t *pg, int32_t n, int repeats, bench_select_result_t *r)
{
    bs_t t_s, t_sn;
    char note[200];
    int same;

    sc->map = map;
    sc->k = k;
    sc->pg = pg;
    trn_select_cfg_default(&sc->cfg);
    sc->rv.pos.x_cells = (float)n / 2.0f + 3.3f;
    sc->rv.pos.y_cells = (float)n / 2.0f - 7.6f;
    sc->rv.heading_rad = 0.4f;
    sc->cap = trn_select_max_candidates(&sc->cfg, map->cfg.terrain.cell_m);
    sc->wsb = trn_select_workspace_bytes(&sc->cfg, map, k);
    sc->c = (trn_candidate_t *)malloc(sc->cap * sizeof *sc->c);
    sc->ws = bs_alloc(sc->wsb);
    if (sc->c == NULL || sc->ws == NULL || bs_time(run_select, sc, 1, repeats, 0.0, &t_s) != 0) {
        return 1;
    }
    sc->lwsb = trn_prob_local_workspace_bytes(k, &sc->res.roi);
    sc->lws = bs_alloc(sc->lwsb);
    sc->p.data = (float *)malloc(sizeof(float) * (size_t)(sc->res.roi.x1 - sc->res.roi.x0 + 1) *
                                 (size_t)(sc->res.roi.y1 - sc->res.roi.y0 + 1) * map->dist.nz);
    if (sc->lws == NULL || sc->p.data == NULL ||
        bs_time(run_select_naive, sc, 0, repeats, 3.0, &t_sn) != 0) {
        return 1;
    }
    same = sc->res.n_informative > 0 &&
           (sc->naive_best_i == sc->res.best ||
            fabs(sc->naive_best - sc->c[sc->res.best].uncertainty_m) <= 1e-6 * sc->naive_best);
    snprintf(note, sizeof note,
             "%zu candidates (%zu informative), region %dx%d; best (%d, %d) "
             "%.4f m",
             sc->res.n_candidates, sc->res.n_informative,
             (int)(sc->res.roi.x1 - sc->res.roi.x0 + 1), (int)(sc->res.roi.y1 - sc->res.roi.y0 + 1),
             sc->res.n_informative ? (int)sc->c[sc->res.best].x : -1,
             sc->res.n_informative ? (int)sc->c[sc->res.best].y : -1,
             sc->res.n_informative ? sc->c[sc->res.best].uncertainty_m : HUGE_VAL);
    bs_row(n, "select: trn_select, all candidates", &t_s, note);
    snprintf(note, sizeof note, "per-patch sums; same best: %s", same ? "yes" : "NO");
    bs_row(n, "select: naive per-candidate sums", &t_sn, note);
    if (!same) {
        r->wrong = 1;
    }
    r->select_ms = t_s.med;
    r->select_naive_ms = t_sn.med;
    bs_ratio("naive / trn_select", t_sn.med, t_s.med, "(target: trn_select < 20 ms at 512)");
    return 0;
}

/* The field, small reach, whole map: trn_field, brute force on a block and
 * trn_field_fast; fc's buffers (allocated here) are the caller's to free.
 * 0, or nonzero when the setup failed. */
static int bench_field_whole(field_ctx_t *fc, const trn_kernels_t *k, const trn_map_t *map,
                             const trn_vol_f32_t *pg, int32_t n, int repeats,
                             bench_select_result_t *r)
{
    bs_t t_f, t_fb, t_ff;
    size_t wso, wsn;
    int same = 0;
    char note[200];

    fc->map = map;
    fc->k = k;
    fc->pg = pg;
    trn_select_cfg_default(&fc->scfg);
    fc->scfg.min_range_m = 0.5f;
    fc->scfg.max_range_m = 2.0f;
    fc->scfg.footprint_radius_m = 0.3f;
    fc->scfg.patch_m = 0.9f;
    fc->scfg.min_separation_m = 0.45f;
    trn_field_cfg_default(&fc->fcfg);
    fc->area.x0 = 0;
    fc->area.y0 = 0;
    fc->area.x1 = n - 1;
    fc->area.y1 = n - 1;
    fc->block.x0 = n / 2 - 16;
    fc->block.y0 = n / 2 - 16;
    fc->block.x1 = n / 2 + 15;
    fc->block.y1 = n / 2 + 15;
    fc->ev = (uint8_t *)malloc((size_t)n * n);
    fc->g.data = (float *)malloc(sizeof(float) * (size_t)n * n);
    fc->g.width = n;
    fc->g.height = n;
    fc->g.stride = n;
    fc->cap = trn_select_max_candidates(&fc->scfg, map->cfg.terrain.cell_m);
    fc->c = (trn_candidate_t *)malloc(fc->cap * sizeof *fc->c);
    fc->swsb = trn_select_workspace_bytes(&fc->scfg, map, k);
    fc->sws = bs_alloc(fc->swsb);
    if (fc->ev == NULL || fc->g.data == NULL || fc->c == NULL || fc->sws == NULL ||
        field_pair(fc, repeats < 3 ? repeats : 3, 20.0, &t_f, &t_ff, &wso, &wsn, &same) != 0 ||
        bs_time(run_field_block, fc, 0, repeats < 3 ? repeats : 3, 10.0, &t_fb) != 0) {
        return 1;
    }
    r->field_ms = t_f.med;
    r->field_fast_ms = t_ff.med;
    r->field_evals = fc->st.evaluations;
    r->field_cells = fc->st.cells;
    r->field_naive_est_ms = t_fb.med * (double)n * (double)n / (32.0 * 32.0);
    snprintf(note, sizeof note,
             "reach 0.5-2 m, 0.9 m patches; %u evaluations of %u cells "
             "(%.1fx fewer); min %.4f m at (%d, %d)",
             fc->st.evaluations, fc->st.cells, (double)fc->st.cells / fc->st.evaluations,
             fc->st.best_m, (int)fc->st.best_x, (int)fc->st.best_y);
    bs_row(n, "field: trn_field, whole map", &t_f, note);
    snprintf(note, sizeof note,
             "brute force on a 32x32 block: %.3f ms per position; whole map "
             "estimated %.0f ms",
             t_fb.med / 1024.0, r->field_naive_est_ms);
    bs_row(n, "field: brute force, 32x32 block", &t_fb, note);
    snprintf(note, sizeof note,
             "same field as trn_field: %s; workspace %.1f MB (trn_field "
             "%.2f MB)",
             same ? "yes" : "NO", (double)wsn / 1048576.0, (double)wso / 1048576.0);
    bs_row(n, "field: trn_field_fast (ground path), whole map", &t_ff, note);
    if (!same) {
        r->wrong = 1;
    }
    bs_ratio("brute force (estimated) / trn_field", r->field_naive_est_ms, t_f.med, NULL);
    bs_ratio("trn_field / trn_field_fast", t_f.med, t_ff.med, NULL);
    return 0;
}

/* The paper's defaults, as `trn field` runs them: over the whole map up to
 * 256 x 256 (the default field: the main job's), a 64 x 64 area in
 * the middle of larger maps (trn_field alone would take minutes there); fc's
 * buffers from bench_field_whole. 0, or nonzero when the setup failed. */
static int bench_field_paper(field_ctx_t *fc, int32_t n, bench_select_result_t *r)
{
    bs_t t_fo, t_fn;
    size_t wso, wsn;
    int same = 0;
    char note[200];

    trn_select_cfg_default(&fc->scfg);
    trn_field_cfg_default(&fc->fcfg);
    r->fpaper_side = n <= 256 ? n : 64;
    fc->area.x0 = n / 2 - r->fpaper_side / 2;
    fc->area.y0 = n / 2 - r->fpaper_side / 2;
    fc->area.x1 = fc->area.x0 + r->fpaper_side - 1;
    fc->area.y1 = fc->area.y0 + r->fpaper_side - 1;
    fc->g.width = r->fpaper_side;
    fc->g.height = r->fpaper_side;
    fc->g.stride = r->fpaper_side;
    if (field_pair(fc, 1, 0.0, &t_fo, &t_fn, &wso, &wsn, &same) != 0) {
        return 1;
    }
    r->fpaper_ms = t_fo.med;
    r->fpaper_fast_ms = t_fn.med;
    r->fpaper_evals = fc->st.evaluations;
    r->fpaper_ws = wso;
    r->fpaper_fast_ws = wsn;
    snprintf(note, sizeof note,
             "%dx%d area, 1-10 m, 2 m patches, stride 2, coarse 16: %u evaluations of "
             "%u cells (%.2f ms each); workspace %.2f MB",
             (int)r->fpaper_side, (int)r->fpaper_side, fc->st.evaluations, fc->st.cells,
             t_fo.med / fc->st.evaluations, (double)wso / 1048576.0);
    bs_row(n, "field (paper): trn_field", &t_fo, note);
    snprintf(note, sizeof note, "same field: %s (%.2f ms each); workspace %.1f MB",
             same ? "yes" : "NO", t_fn.med / fc->st.evaluations, (double)wsn / 1048576.0);
    bs_row(n, "field (paper): trn_field_fast", &t_fn, note);
    if (!same) {
        r->wrong = 1;
    }
    bs_ratio("trn_field / trn_field_fast (paper defaults)", t_fo.med, t_fn.med, "(target >= 10x)");
    return 0;
}

int bench_select_run(const trn_map_t *map, int32_t n, int repeats, bench_select_result_t *r)
{
    static trn_kernels_t k;
    pmap_ctx_t pc;
    sel_ctx_t sc;
    field_ctx_t fc;
    uint8_t *kidx = NULL;
    int rc = 3;

    memset(r, 0, sizeof *r);
    memset(&pc, 0, sizeof pc);
    memset(&sc, 0, sizeof sc);
    memset(&fc, 0, sizeof fc);
    if (trn_kernels_build(&k, TRN_KERNEL_SIGMA0_DEFAULT_CELLS) != TRN_OK) {
        return 3;
    }
    if (bench_pmap(&pc, &k, map, n, repeats, &kidx, r) == 0 &&
        bench_sel(&sc, &k, map, &pc.pg, n, repeats, r) == 0 &&
        bench_field_whole(&fc, &k, map, &pc.pg, n, repeats, r) == 0 &&
        bench_field_paper(&fc, n, r) == 0) {
        rc = 0;
    }
    if (rc != 0) {
        fprintf(stderr, "trn_bench: landmark-selection benchmark setup failed\n");
    }
    free(fc.ev);
    free(fc.g.data);
    free(fc.c);
    free(fc.sws);
    free(pc.pg.data);
    free(pc.ws);
    free(pc.naive);
    free(kidx);
    free(sc.c);
    free(sc.ws);
    free(sc.lws);
    free(sc.p.data);
    (void)g_bs_sink;
    return rc;
}
