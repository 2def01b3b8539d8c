/* SPDX-License-Identifier: Apache-2.0 */
/* bench_heights.c - trn_bench's height-matcher rows (bench_heights.h).
 *
 * The case is the README's localize example, made in-process: the terrain
 * generator of `trn terrain` (tools/trn/terrain_gen.c) with coverage 0.15 and
 * seed 3 on 256 x 256 cells of 0.1 m; the rover's 64 x 64 local map is the
 * crop at rows 88..151, columns 108..171 (the rover at its cell (32, 32), so
 * the true pose is (140, 120)) plus seeded Gaussian noise of 1 cm; the prior
 * is cell (147, 125) (README: 1014.75, 2013.05 with the origin 1000, 2000).
 * Maps: the voxel matcher's is `trn localize --map-config paper`'s
 * (trn_map_cfg_default), the height matcher's the default localizer's
 * (trn_map_cfg_auto with the tools' noise model 0.01 m + 0.004 / m r^2).
 * Both localize the same local DEM in the same window with
 * trn_localize_dem, one after the other, in this run; the height matcher
 * with cfg.search = TRN_SEARCH_EXHAUSTIVE and TRN_SEARCH_BOUNDED (pose and
 * status must agree: else a wrong answer).
 *
 * Worst cases of a bound (at +-25 cells, the height matcher only): a flat
 * map (every height 0; the local map 1 cm noise), a periodic map (0.2 m
 * sin(2 pi x / 1 m) sin(2 pi y / 1 m), a 10-cell period in both axes), and a
 * local map of 5 x 5 cells cut from the README terrain at the true pose. */
#define _POSIX_C_SOURCE 200112L

#include "bench_heights.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "rng.h"
#include "../trn/terrain_gen.h" /* `trn terrain`'s generator */
#include "trn/trn.h"

#define BH_N 256
#define BH_L 64
#define BH_CELL 0.1
#define BH_PI 3.14159265358979323846
#define BH_MAX_REPS 100

typedef struct {
    const trn_map_t *map;
    const trn_grid_f32_t *local;
    int32_t rx, ry;
    size_t max_pts;
    trn_window_t win;
    void *ws;
    size_t wsb;
    trn_loc_result_t res;
    trn_status_t st;
    double med_ms, min_ms;
    int reps;
} bh_call_t;

static double bh_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static int bh_cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* An answer (a fix or not) rather than a refused call. */
static int bh_answer(trn_status_t st)
{
    return st == TRN_OK || st == TRN_E_ILLCOND || st == TRN_E_AMBIGUOUS || st == TRN_E_NODATA;
}

/* One warm-up, then up to reps timed trn_localize_dem calls, stopping once
 * budget_ms of timed calls have passed. 0, or 3 (workspace, a refused call). */
static int bh_time(bh_call_t *c, int reps, double budget_ms)
{
    double s[BH_MAX_REPS], start;
    int n = 0;
    c->wsb = trn_localize_dem_workspace_bytes(c->map, c->local->width, c->local->height, c->max_pts,
                                              &c->win);
    free(c->ws);
    c->ws = NULL;
    if (c->wsb == 0u || posix_memalign(&c->ws, 16u, c->wsb) != 0) {
        c->ws = NULL;
        fprintf(stderr, "trn_bench: height rows: workspace of %zu bytes failed\n", c->wsb);
        return 3;
    }
    c->st = trn_localize_dem(c->map, c->local, c->rx, c->ry, c->max_pts, &c->win, c->ws, c->wsb,
                             &c->res);
    if (!bh_answer(c->st)) {
        fprintf(stderr, "trn_bench: height rows: trn_localize_dem refused: %s\n",
                trn_strerror(c->st));
        return 3;
    }
    start = bh_now();
    while (n < reps && n < BH_MAX_REPS) {
        double t0 = bh_now();
        c->st = trn_localize_dem(c->map, c->local, c->rx, c->ry, c->max_pts, &c->win, c->ws, c->wsb,
                                 &c->res);
        s[n++] = bh_now() - t0;
        if (budget_ms > 0.0 && bh_now() - start > budget_ms) {
            break;
        }
    }
    qsort(s, (size_t)n, sizeof s[0], bh_cmp);
    c->reps = n;
    c->min_ms = s[0];
    c->med_ms = (n % 2) ? s[n / 2] : 0.5 * (s[n / 2 - 1] + s[n / 2]);
    return 0;
}

static void bh_row(const char *name, const bh_call_t *c, const char *note)
{
    printf("%-5d %-50s %4d %11.3f %11.3f  %s\n", BH_N, name, c->reps, c->med_ms, c->min_ms, note);
    fflush(stdout);
}

static void bh_ratio(const char *what, const bh_call_t *num, const bh_call_t *den, const char *note)
{
    printf("      ratio %-56s %8.2fx (min/min %.2fx)%s%s\n", what, num->med_ms / den->med_ms,
           num->min_ms / den->min_ms, note[0] ? "  " : "", note);
    fflush(stdout);
}

/* The two maps of one DEM: the voxel matcher's (NULL: not built) and the
 * height matcher's, its bounded twin a copy with cfg.search changed. */
typedef struct {
    void *vbuf, *hbuf;
    trn_map_t vmap, hmap, hmap_b;
} bh_maps_t;

static int bh_maps(const float *dem, int voxel, bh_maps_t *m)
{
    trn_grid_f32_t g;
    trn_map_cfg_t vc, hc;
    size_t vb, hb, ab;
    void *aws = NULL;
    trn_status_t st;
    memset(m, 0, sizeof *m);
    if (trn_grid_f32_init(&g, (float *)dem, (size_t)BH_N * BH_N, BH_N, BH_N) != TRN_OK) {
        return 3;
    }
    trn_map_cfg_default(&vc);
    vc.noise_m = 0.01f;                /* the tools' noise model (tools/trn/mapopt.c) */
    vc.noise_k_per_m = 0.0004f / 0.1f; /* 0.0004 / cell */
    hc = vc;
    ab = trn_map_cfg_auto_workspace_bytes(BH_N, BH_N);
    if (ab == 0u || posix_memalign(&aws, 16u, ab) != 0) {
        return 3;
    }
    st = trn_map_cfg_auto(&hc, &g, (float)BH_CELL, aws, ab, NULL);
    free(aws);
    if (st != TRN_OK) {
        fprintf(stderr, "trn_bench: height rows: trn_map_cfg_auto: %s\n", trn_strerror(st));
        return 3;
    }
    hb = trn_map_bytes(&hc, BH_N, BH_N);
    if (hb == 0u || posix_memalign(&m->hbuf, 16u, hb) != 0) {
        m->hbuf = NULL;
        return 3;
    }
    if ((st = trn_map_build(&m->hmap, &hc, &g, m->hbuf, hb)) != TRN_OK) {
        fprintf(stderr, "trn_bench: height rows: trn_map_build: %s\n", trn_strerror(st));
        return 3;
    }
    m->hmap.cfg.search = TRN_SEARCH_EXHAUSTIVE;
    m->hmap_b = m->hmap;
    m->hmap_b.cfg.search = TRN_SEARCH_BOUNDED;
    if (voxel) {
        vb = trn_map_bytes(&vc, BH_N, BH_N);
        if (vb == 0u || posix_memalign(&m->vbuf, 16u, vb) != 0) {
            m->vbuf = NULL;
            return 3;
        }
        if ((st = trn_map_build(&m->vmap, &vc, &g, m->vbuf, vb)) != TRN_OK) {
            fprintf(stderr, "trn_bench: height rows: voxel trn_map_build: %s\n", trn_strerror(st));
            return 3;
        }
    }
    return 0;
}

static void bh_maps_free(bh_maps_t *m)
{
    free(m->vbuf);
    free(m->hbuf);
}

/* The note of a height-matcher row: status, error, poses scored, and
 * whether the bounded answer equals the exhaustive one (when both given). */
static void bh_note(char *note, size_t len, const bh_call_t *c, double tx, double ty,
                    const bh_call_t *exh, int *wrong)
{
    int same = 1;
    if (exh != NULL) {
        same = c->st == exh->st && c->res.ix == exh->res.ix && c->res.iy == exh->res.iy;
        if (!same) {
            *wrong = 1;
        }
    }
    snprintf(note, len, "%s; error %.2f cells; %llu poses scored, %llu blocks bounded%s%s",
             trn_strerror(c->st), hypot(c->res.x - tx, c->res.y - ty),
             (unsigned long long)c->res.stats.poses_scored,
             (unsigned long long)c->res.stats.blocks_bounded,
             exh == NULL ? "" : "; = exhaustive pose, status: ",
             exh == NULL ? ""
             : same      ? "yes"
                         : "NO");
}

/* The README case at window +-W: voxel, exhaustive, bounded; k its index. */
static int bh_window(bh_maps_t *m, int32_t W, int k, int repeats, bh_call_t *vx, bh_call_t *ex,
                     bh_call_t *bd, bench_heights_result_t *r)
{
    const double tx = 140.0, ty = 120.0;
    const double budget = 20000.0; /* ms of timed calls per row at most */
    char name[64], note[200];
    vx->win.x0 = 147 - W;
    vx->win.x1 = 147 + W;
    vx->win.y0 = 125 - W;
    vx->win.y1 = 125 + W;
    ex->win = bd->win = vx->win;
    vx->map = &m->vmap;
    ex->map = &m->hmap;
    bd->map = &m->hmap_b;
    if (bh_time(vx, repeats, 0.0) != 0 || bh_time(ex, repeats, budget) != 0 ||
        bh_time(bd, repeats, budget) != 0) {
        return 3;
    }
    printf("\n");
    snprintf(name, sizeof name, "heights +-%d: voxel trn_localize_dem (paper)", (int)W);
    snprintf(note, sizeof note, "%s; error %.2f cells; %dx%d window", trn_strerror(vx->st),
             hypot(vx->res.x - tx, vx->res.y - ty), (int)(2 * W + 1), (int)(2 * W + 1));
    bh_row(name, vx, note);
    snprintf(name, sizeof name, "heights +-%d: height matcher, exhaustive", (int)W);
    bh_note(note, sizeof note, ex, tx, ty, NULL, &r->wrong);
    bh_row(name, ex, note);
    snprintf(name, sizeof name, "heights +-%d: height matcher, bounded", (int)W);
    bh_note(note, sizeof note, bd, tx, ty, ex, &r->wrong);
    bh_row(name, bd, note);
    snprintf(name, sizeof name, "height exhaustive / voxel, +-%d", (int)W);
    bh_ratio(name, ex, vx, "(goal <= 3, bounded)");
    snprintf(name, sizeof name, "height bounded / voxel, +-%d", (int)W);
    bh_ratio(name, bd, vx, "(goal <= 3)");
    snprintf(name, sizeof name, "height bounded / exhaustive, +-%d", (int)W);
    bh_ratio(name, bd, ex, "");
    r->win[k] = W;
    r->voxel_ms[k] = vx->med_ms;
    r->exh_ms[k] = ex->med_ms;
    r->bnd_ms[k] = bd->med_ms;
    return 0;
}

/* One worst case: the height matcher exhaustive and bounded on map dem
 * with the local grid `local` (rover at rx, ry), window +-W at (px, py). */
static int bh_worst(const char *what, const float *dem, const trn_grid_f32_t *local, int32_t rx,
                    int32_t ry, int32_t px, int32_t py, int32_t W, int repeats,
                    bench_heights_result_t *r)
{
    bh_maps_t m;
    bh_call_t ex, bd;
    char name[64], note[200];
    int rc = bh_maps(dem, 0, &m);
    memset(&ex, 0, sizeof ex);
    memset(&bd, 0, sizeof bd);
    if (rc == 0) {
        ex.local = local;
        ex.rx = rx;
        ex.ry = ry;
        ex.max_pts = (size_t)local->width * (size_t)local->height * 64u;
        ex.win.x0 = px - W;
        ex.win.x1 = px + W;
        ex.win.y0 = py - W;
        ex.win.y1 = py + W;
        bd = ex;
        ex.map = &m.hmap;
        bd.map = &m.hmap_b;
        if (bh_time(&ex, repeats, 10000.0) != 0 || bh_time(&bd, repeats, 10000.0) != 0) {
            rc = 3;
        }
    }
    if (rc == 0) {
        double ratio = bd.med_ms / ex.med_ms;
        snprintf(name, sizeof name, "worst +-%d: %s, exhaustive", (int)W, what);
        bh_note(note, sizeof note, &ex, (double)px, (double)py, NULL, &r->wrong);
        bh_row(name, &ex, note);
        snprintf(name, sizeof name, "worst +-%d: %s, bounded", (int)W, what);
        bh_note(note, sizeof note, &bd, (double)px, (double)py, &ex, &r->wrong);
        bh_row(name, &bd, note);
        snprintf(name, sizeof name, "height bounded / exhaustive, %s", what);
        bh_ratio(name, &bd, &ex, "(goal <= 1.2)");
        if (ratio > r->worst_ratio) {
            r->worst_ratio = ratio;
        }
    }
    free(ex.ws);
    free(bd.ws);
    bh_maps_free(&m);
    return rc;
}

/* The README terrain: `trn terrain --coverage 0.15 --seed 3` (256 x 256 of 0.1 m). */
static float *bh_terrain(void)
{
    tg_params_t p;
    tg_rock_t *rocks;
    size_t n;
    float *dem = malloc(sizeof *dem * (size_t)BH_N * BH_N);
    tg_default(&p, BH_N, BH_N, BH_CELL);
    p.coverage_k = 0.15;
    p.d_min_m = 2.0 * BH_CELL;
    p.d_max_m = tg_auto_d_max(p.coverage_k);
    p.seed = 3u;
    n = tg_draw_rocks(&p, NULL, 0u);
    rocks = malloc(sizeof *rocks * (n + 1u));
    if (dem == NULL || rocks == NULL || tg_check(&p) != NULL) {
        free(dem);
        free(rocks);
        return NULL;
    }
    tg_draw_rocks(&p, rocks, n);
    tg_render(&p, rocks, n, dem, NULL, NULL);
    free(rocks);
    return dem;
}

/* side x side cells of dem from (c0, r0), plus noise_m Gaussian noise. */
static void bh_crop(const float *dem, int32_t c0, int32_t r0, int32_t side, double noise_m,
                    uint64_t seed, float *out)
{
    trn_rng_t rng;
    int32_t r, c;
    trn_rng_seed(&rng, seed);
    for (r = 0; r < side; ++r) {
        for (c = 0; c < side; ++c) {
            out[r * side + c] = (float)((double)dem[(r0 + r) * BH_N + (c0 + c)] +
                                        noise_m * trn_rng_gauss(&rng));
        }
    }
}

int bench_heights_run(int repeats, int quick, bench_heights_result_t *r)
{
    static const int32_t wins[2] = {25, 50};
    float *dem = bh_terrain(), *loc = malloc(sizeof(float) * BH_L * BH_L);
    float *flat = calloc((size_t)BH_N * BH_N, sizeof(float));
    float *per = malloc(sizeof(float) * BH_N * BH_N);
    float small[25];
    trn_grid_f32_t lg, sg;
    bh_maps_t m;
    bh_call_t vx, ex, bd;
    int rc = 0, k, x, y;
    const int32_t wq = quick ? 10 : 25;

    memset(r, 0, sizeof *r);
    memset(&m, 0, sizeof m);
    memset(&vx, 0, sizeof vx);
    memset(&ex, 0, sizeof ex);
    memset(&bd, 0, sizeof bd);
    if (dem == NULL || loc == NULL || flat == NULL || per == NULL) {
        fprintf(stderr, "trn_bench: height rows: out of memory\n");
        rc = 3;
        goto done;
    }
    bh_crop(dem, 108, 88, BH_L, 0.01, 1u, loc);
    bh_crop(dem, 140 - 2, 120 - 2, 5, 0.01, 2u, small);
    if (trn_grid_f32_init(&lg, loc, (size_t)BH_L * BH_L, BH_L, BH_L) != TRN_OK ||
        trn_grid_f32_init(&sg, small, 25u, 5, 5) != TRN_OK || (rc = bh_maps(dem, 1, &m)) != 0) {
        rc = 3;
        goto done;
    }
    printf("\nheight matcher: the README localize case (trn terrain --coverage 0.15 --seed 3, "
           "%d x %d of %.1f m; local %d x %d + 1 cm noise, true pose (140, 120), prior (147, "
           "125)); %d height bins (trn_map_cfg_auto)\n",
           BH_N, BH_N, BH_CELL, BH_L, BH_L, (int)m.hmap.cfg.terrain.nz);
    vx.local = &lg;
    vx.rx = BH_L / 2;
    vx.ry = BH_L / 2;
    vx.max_pts = (size_t)BH_L * BH_L * 64u;
    ex = vx;
    bd = vx;
    for (k = 0; k < (quick ? 1 : 2) && rc == 0; ++k) {
        rc = bh_window(&m, quick ? wq : wins[k], k, repeats, &vx, &ex, &bd, r);
    }
    if (rc == 0 && !quick) {
        const double e = log(r->exh_ms[1] / r->exh_ms[0]) / log(101.0 * 101.0 / (51.0 * 51.0));
        const double b = log(r->bnd_ms[1] / r->bnd_ms[0]) / log(101.0 * 101.0 / (51.0 * 51.0));
        printf("      height matcher +-50 / +-25: exhaustive %.2fx, bounded %.2fx (goal <= 4); "
               "exponent of cost against window area: exhaustive %.2f, bounded %.2f\n",
               r->exh_ms[1] / r->exh_ms[0], r->bnd_ms[1] / r->bnd_ms[0], e, b);
    }
    if (rc != 0) {
        goto done;
    }
    /* the worst cases of a bound */
    for (y = 0; y < BH_N; ++y) {
        for (x = 0; x < BH_N; ++x) {
            per[y * BH_N + x] = (float)(0.2 * sin(2.0 * BH_PI * x * BH_CELL) *
                                        sin(2.0 * BH_PI * y * BH_CELL));
        }
    }
    printf("\n");
    bh_crop(flat, 108, 88, BH_L, 0.01, 3u, loc);
    rc = bh_worst("flat map", flat, &lg, BH_L / 2, BH_L / 2, 147, 125, wq, repeats, r);
    if (rc == 0) {
        bh_crop(per, 108, 88, BH_L, 0.01, 4u, loc);
        rc = bh_worst("periodic map (1 m)", per, &lg, BH_L / 2, BH_L / 2, 147, 125, wq, repeats, r);
    }
    if (rc == 0) {
        rc = bh_worst("5x5-cell local map", dem, &sg, 2, 2, 147, 125, wq, repeats, r);
    }
done:
    free(vx.ws);
    free(ex.ws);
    free(bd.ws);
    bh_maps_free(&m);
    free(dem);
    free(loc);
    free(flat);
    free(per);
    return rc;
}
