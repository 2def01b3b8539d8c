/* SPDX-License-Identifier: Apache-2.0 */
/* trn_bench - speed of the trn core against naive references, in one run.
 *
 *   trn_bench [--sizes 256,512] [--repeats N] [--seed S] [--quick] [--help]
 *
 * For each global map size N (N x N cells of 0.1 m, synthetic rocky terrain
 * from tools/support/synth.h, trn_map_cfg_default: 16 height bins, cap 60):
 *
 *   chamfer   trn_chamfer3d on the map's occupancy volume, against
 *             - two plain streaming passes over the same voxels, forward
 *               v[i] = min(init(occ[i]), v[i-nx] + 1) reading occ and
 *               writing v, backward v[i] = min(v[i], v[i+nx] + 1) in place,
 *               element-wise along a row so they vectorise: the memory-bound
 *               limit of two passes, the reference of the "<= 3x" target;
 *             - the same two passes along i-1 / i+1 (a 1-D transform of the
 *               flattened volume): a scalar min/add dependency chain, not
 *               memory-bound at all (trn_chamfer3d beats it), info only;
 *             - the naive Dijkstra oracle ref_chamfer3d_dijkstra (whose
 *               answer must equal trn_chamfer3d's);
 *             - with OpenCV: cv::distanceTransform (DIST_L2, mask 3, 5 and
 *               DIST_MASK_PRECISE) on each of the nz 2-D slices, summed.
 *   map       trn_map_build and its parts, and trn_map_bytes.
 *   search    a 64 x 64 local map rendered at a random true pose, the prior
 *             off by up to 10 cells, windows +-25 and +-50 cells: exhaustive
 *             search against branch-and-bound (answers must be identical).
 *   localize  one whole trn_localize_dem call per window, and its parts.
 *   pmap, select, field  the landmark-selection rows (bench_select.c), with
 *             trn_field against trn_field_fast (the ground path) in the same run.
 *
 * Timing: CLOCK_MONOTONIC, one warm-up call, then `repeats` timed calls;
 * median and minimum reported. Ratios compare medians measured in the same
 * run (the machine may be shared and noisy). Single thread throughout.
 *
 * Exit status: 0 success (whether or not the speed targets are met), 1 a
 * wrong answer (branch-and-bound != exhaustive, localize != exhaustive, or
 * trn_chamfer3d != Dijkstra), 2 bad usage, 3 a setup failure (memory, a
 * library call that should have worked).
 */
#define _POSIX_C_SOURCE 199309L

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_floor.h"
#include "bench_select.h"
#include "bench_heading.h"
#include "bench_heights.h"
#include "ref_chamfer.h"
#include "rng.h"
#include "synth.h"
#include "trn/trn.h"

#ifdef TRN_HAVE_OPENCV
#include "opencv/bench_cv.h"
#endif

#define PI 3.14159265358979323846
#define CELL_M 0.1
#define LOCAL_CELLS 64     /* local map side */
#define PRIOR_ERR_CELLS 10 /* largest prior error per axis */
#define MAX_SIZES 8
#define MAX_REPEATS 100
#define N_WINDOWS 2
#define NAIVE_BUDGET_S 3.0 /* the Dijkstra oracle stops repeating after this */
#define NAIVE_BUDGET_TXT "3 s"

static const int32_t k_windows[N_WINDOWS] = {25, 50};

/* Sink for checksums, so no timed work is dead code. */
static volatile unsigned long long g_sink;

/* ------------------------------------------------------------------------ */
/* Options                                                                  */
/* ------------------------------------------------------------------------ */

typedef struct {
    int32_t sizes[MAX_SIZES];
    int nsizes;
    int repeats;
    unsigned long long seed;
    int quick;
    int heights; /* the height matcher's rows (bench_heights.c) */
} opts_t;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: trn_bench [--sizes N[,N...]] [--repeats R] [--seed S] [--quick]\n"
            "  --sizes N,...  global map sides in cells of 0.1 m, 64..%d (default 256,512)\n"
            "  --repeats R    timed runs per measurement, median and min reported, 1..%d\n"
            "                 (default 7)\n"
            "  --seed S       terrain and pose seed (default 1)\n"
            "  --quick        smoke run: --sizes 128 --repeats 1, height rows at +-10 only\n"
            "  --no-heights   leave out the height matcher's rows (about 2 minutes)\n"
            "Exit status: 0 ok (speed targets never fail the run), 1 wrong answer,\n"
            "2 bad usage, 3 setup failure.\n",
            TRN_MAX_DIM, MAX_REPEATS);
}

static int parse_long(const char *name, const char *v, long lo, long hi, long *out,
                      const char **rest)
{
    char *end;
    long x;
    if (v == NULL) {
        fprintf(stderr, "trn_bench: %s needs a value\n", name);
        return 0;
    }
    errno = 0;
    x = strtol(v, &end, 10);
    if (errno != 0 || end == v || (rest == NULL && *end != '\0') || x < lo || x > hi) {
        fprintf(stderr, "trn_bench: %s must be an integer in [%ld, %ld], got '%s'\n", name, lo, hi,
                v);
        return 0;
    }
    if (rest != NULL) {
        *rest = end;
    }
    *out = x;
    return 1;
}

static int parse_sizes(const char *v, opts_t *o)
{
    const char *p = v;
    o->nsizes = 0;
    if (v == NULL) {
        fprintf(stderr, "trn_bench: --sizes needs a value\n");
        return 0;
    }
    for (;;) {
        long n;
        const char *rest;
        if (o->nsizes == MAX_SIZES) {
            fprintf(stderr, "trn_bench: at most %d sizes\n", MAX_SIZES);
            return 0;
        }
        if (!parse_long("--sizes", p, 64, TRN_MAX_DIM, &n, &rest)) {
            return 0;
        }
        o->sizes[o->nsizes++] = (int32_t)n;
        if (*rest == '\0') {
            return 1;
        }
        if (*rest != ',') {
            fprintf(stderr, "trn_bench: --sizes takes a comma-separated list, got '%s'\n", v);
            return 0;
        }
        p = rest + 1;
    }
}

static int parse(int argc, char **argv, opts_t *o)
{
    int i, have_sizes = 0, have_repeats = 0;
    long x;
    o->sizes[0] = 256;
    o->sizes[1] = 512;
    o->nsizes = 2;
    o->repeats = 7;
    o->seed = 1u;
    o->quick = 0;
    o->heights = 1;
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            exit(0);
        } else if (strcmp(a, "--quick") == 0) {
            o->quick = 1;
            continue;
        } else if (strcmp(a, "--no-heights") == 0) {
            o->heights = 0;
            continue;
        } else if (strcmp(a, "--sizes") == 0) {
            if (!parse_sizes(v, o)) {
                return 0;
            }
            have_sizes = 1;
        } else if (strcmp(a, "--repeats") == 0) {
            if (!parse_long(a, v, 1, MAX_REPEATS, &x, NULL)) {
                return 0;
            }
            o->repeats = (int)x;
            have_repeats = 1;
        } else if (strcmp(a, "--seed") == 0) {
            if (!parse_long(a, v, 0, 2147483647L, &x, NULL)) {
                return 0;
            }
            o->seed = (unsigned long long)x;
        } else {
            fprintf(stderr, "trn_bench: unknown argument '%s' (try --help)\n", a);
            return 0;
        }
        ++i;
    }
    if (o->quick) {
        if (!have_sizes) {
            o->sizes[0] = 128;
            o->nsizes = 1;
        }
        if (!have_repeats) {
            o->repeats = 1;
        }
    }
    return 1;
}

/* ------------------------------------------------------------------------ */
/* Timing                                                                   */
/* ------------------------------------------------------------------------ */

/** A measured operation: returns 0 on success. */
typedef int (*bench_fn_t)(void *ctx);

typedef struct {
    int reps;      /* timed runs */
    double med_ms; /* median */
    double min_ms; /* minimum */
} timing_t;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/**
 * One untimed warm-up call (if warmup), then up to reps timed calls; stops
 * early once budget_s (> 0) seconds of timed calls have passed.
 */
static int time_fn(bench_fn_t fn, void *ctx, int warmup, int reps, double budget_s, timing_t *t)
{
    double s[MAX_REPEATS], start;
    int n = 0;
    if (warmup && fn(ctx) != 0) {
        return -1;
    }
    start = now_s();
    while (n < reps) {
        double t0 = now_s(), t1;
        if (fn(ctx) != 0) {
            return -1;
        }
        t1 = now_s();
        s[n++] = (t1 - t0) * 1e3;
        if (budget_s > 0.0 && t1 - start > budget_s) {
            break;
        }
    }
    qsort(s, (size_t)n, sizeof s[0], cmp_double);
    t->reps = n;
    t->min_ms = s[0];
    t->med_ms = (n % 2) ? s[n / 2] : 0.5 * (s[n / 2 - 1] + s[n / 2]);
    return 0;
}

/* ------------------------------------------------------------------------ */
/* Output                                                                   */
/* ------------------------------------------------------------------------ */

static void print_header(void)
{
    printf("%-5s %-50s %4s %11s %11s  %s\n", "size", "measurement", "reps", "median ms", "min ms",
           "notes");
    printf("%-5s %-50s %4s %11s %11s  %s\n", "-----",
           "--------------------------------------------------", "----", "-----------",
           "-----------", "-----");
}

static void print_row(int32_t n, const char *name, const timing_t *t, const char *note)
{
    printf("%-5d %-50s %4d %11.3f %11.3f  %s\n", (int)n, name, t->reps, t->med_ms, t->min_ms,
           note != NULL ? note : "");
    fflush(stdout);
}

static void print_ratio(const char *what, const timing_t *num, const timing_t *den,
                        const char *note)
{
    printf("      ratio %-56s %8.2fx (min/min %.2fx)%s%s\n", what, num->med_ms / den->med_ms,
           num->min_ms / den->min_ms, note != NULL ? "  " : "", note != NULL ? note : "");
    fflush(stdout);
}

static int fail(const char *what, trn_status_t st)
{
    fprintf(stderr, "trn_bench: %s failed: %s\n", what, trn_strerror(st));
    return 3;
}

/* ------------------------------------------------------------------------ */
/* Chamfer and its references                                               */
/* ------------------------------------------------------------------------ */

typedef struct {
    const trn_vol_u8_t *occ;
    trn_vol_u8_t *dist;
    uint8_t cap;
} chamfer_ctx_t;

static int run_chamfer(void *p)
{
    chamfer_ctx_t *c = (chamfer_ctx_t *)p;
    return trn_chamfer3d(c->occ, c->dist, c->cap) == TRN_OK ? 0 : -1;
}

typedef struct {
    const uint8_t *occ;
    uint8_t *v;
    size_t n;  /* voxels */
    size_t nx; /* row length (for the row-to-row variant) */
    uint8_t cap;
} stream_ctx_t;

static uint8_t min_u8(uint8_t a, uint8_t b) { return a < b ? a : b; }

/*
 * Info only: two plain passes over the same nx*ny*nz bytes, the forward one
 * reading occ and writing v (as trn_chamfer3d's first pass reads occ and
 * writes dist), the backward one in place. Each element depends on the
 * previous one (a 1-D distance transform of the flattened volume), so this
 * runs at the latency of a scalar min/add chain (~1 ns per byte), far
 * slower than memory. Values stay <= cap <= 250: no overflow.
 */
static int run_stream_scan(void *p)
{
    stream_ctx_t *c = (stream_ctx_t *)p;
    const uint8_t *occ = c->occ;
    uint8_t *v = c->v;
    uint8_t prev = c->cap;
    size_t i;
    for (i = 0; i < c->n; ++i) {
        uint8_t a = occ[i] != 0u ? (uint8_t)0u : c->cap;
        prev = min_u8(a, (uint8_t)(prev + 1u));
        v[i] = prev;
    }
    for (i = c->n - 1u; i-- > 0u;) {
        prev = min_u8(v[i], (uint8_t)(prev + 1u));
        v[i] = prev;
    }
    g_sink += v[c->n / 2u];
    return 0;
}

#define SLANES 16

/*
 * The reference of the "chamfer <= 3x streaming" target: the same traffic
 * as above (forward pass occ -> v, backward pass in place) with the
 * dependency one row back (v[i - nx] forward, v[i + nx] backward), so the
 * work is element-wise within a row; fixed 16-byte blocks copied through
 * locals let the compiler vectorise it at -O2 (pminub on x86-64). This is
 * about the memory-bandwidth floor of any two-pass transform of the volume.
 */
static int run_stream_rows(void *p)
{
    stream_ctx_t *c = (stream_ctx_t *)p;
    const uint8_t *occ = c->occ;
    uint8_t *v = c->v;
    const size_t n = c->n, nx = c->nx;
    const uint8_t cap = c->cap;
    size_t i;
    for (i = 0; i < nx; ++i) {
        v[i] = occ[i] != 0u ? (uint8_t)0u : cap;
    }
    for (i = nx; i + SLANES <= n; i += SLANES) {
        uint8_t up[SLANES], out[SLANES];
        size_t k;
        for (k = 0; k < SLANES; ++k) {
            up[k] = v[i - nx + k];
        }
        for (k = 0; k < SLANES; ++k) {
            uint8_t a = occ[i + k] != 0u ? (uint8_t)0u : cap;
            out[k] = min_u8(a, (uint8_t)(up[k] + 1u));
        }
        for (k = 0; k < SLANES; ++k) {
            v[i + k] = out[k];
        }
    }
    for (; i < n; ++i) {
        uint8_t a = occ[i] != 0u ? (uint8_t)0u : cap;
        v[i] = min_u8(a, (uint8_t)(v[i - nx] + 1u));
    }
    /* backward: i runs over [0, n - nx) from the top, blocks end at i */
    i = n - nx;
    while (i >= SLANES) {
        uint8_t dn[SLANES], cur[SLANES];
        size_t k, b = i - SLANES;
        for (k = 0; k < SLANES; ++k) {
            dn[k] = v[b + nx + k];
            cur[k] = v[b + k];
        }
        for (k = 0; k < SLANES; ++k) {
            cur[k] = min_u8(cur[k], (uint8_t)(dn[k] + 1u));
        }
        for (k = 0; k < SLANES; ++k) {
            v[b + k] = cur[k];
        }
        i = b;
    }
    while (i-- > 0u) {
        v[i] = min_u8(v[i], (uint8_t)(v[i + nx] + 1u));
    }
    g_sink += v[n / 2u];
    return 0;
}

typedef struct {
    const uint8_t *occ;
    uint8_t *v;
    size_t nx, ny, nz;
    uint8_t cap;
    uint8_t *scratch;
} floor_ctx_t;

/* The relaxation-only floor of a two-pass transform (bench_floor.c). */
static int run_relax_floor(void *p)
{
    floor_ctx_t *c = (floor_ctx_t *)p;
    bench_relax_floor(c->occ, c->v, c->nx, c->ny, c->nz, c->cap, c->scratch);
    g_sink += c->v[(c->nx * c->ny * c->nz) / 2u];
    return 0;
}

typedef struct {
    const uint8_t *occ;
    uint8_t *out;
    int nx, ny, nz;
    unsigned cap;
} dijkstra_ctx_t;

static int run_dijkstra(void *p)
{
    dijkstra_ctx_t *c = (dijkstra_ctx_t *)p;
    ref_chamfer3d_dijkstra(c->occ, c->out, c->nx, c->ny, c->nz, c->cap);
    return 0;
}

#ifdef TRN_HAVE_OPENCV
typedef struct {
    bench_cv_dt_t *cv;
    int mask;
} cv_ctx_t;

static int run_cv(void *p)
{
    cv_ctx_t *c = (cv_ctx_t *)p;
    return bench_cv_dt_run(c->cv, c->mask);
}
#endif

/* ------------------------------------------------------------------------ */
/* Map preparation                                                          */
/* ------------------------------------------------------------------------ */

typedef struct {
    const trn_map_cfg_t *cfg;
    const trn_grid_f32_t *dem;
    void *buf;
    size_t len;
    trn_map_t map;
} map_ctx_t;

static int run_map_build(void *p)
{
    map_ctx_t *c = (map_ctx_t *)p;
    return trn_map_build(&c->map, c->cfg, c->dem, c->buf, c->len) == TRN_OK ? 0 : -1;
}

typedef struct {
    const trn_grid_f32_t *dem;
    const trn_terrain_cfg_t *tc;
    trn_grid_f32_t *hp;
    void *ws;
    size_t wsb;
} highpass_ctx_t;

static int run_highpass(void *p)
{
    highpass_ctx_t *c = (highpass_ctx_t *)p;
    return trn_highpass(c->dem, c->tc, c->hp, c->ws, c->wsb) == TRN_OK ? 0 : -1;
}

typedef struct {
    const trn_grid_f32_t *hp;
    const trn_terrain_cfg_t *tc;
    trn_vol_u8_t *occ;
    uint32_t n_occ;
} occupancy_ctx_t;

static int run_occupancy(void *p)
{
    occupancy_ctx_t *c = (occupancy_ctx_t *)p;
    return trn_occupancy(c->hp, c->tc, c->occ, &c->n_occ) == TRN_OK ? 0 : -1;
}

typedef struct {
    const trn_vol_u8_t *dist;
    const trn_lik_cfg_t *lik;
    double k;
    trn_lnp_table_t table;
} outlier_ctx_t;

static int run_outlier(void *p)
{
    outlier_ctx_t *c = (outlier_ctx_t *)p;
    return trn_outlier_density(c->dist, c->lik, &c->k) == TRN_OK ? 0 : -1;
}

static int run_lnp_table(void *p)
{
    outlier_ctx_t *c = (outlier_ctx_t *)p;
    return trn_lnp_table_build(&c->table, c->lik, c->k) == TRN_OK ? 0 : -1;
}

typedef struct {
    const trn_vol_u8_t *dist;
    uint8_t cap;
    int32_t levels;
    void *buf;
    size_t len;
    trn_pyramid_t pyr;
} pyramid_ctx_t;

static int run_pyramid(void *p)
{
    pyramid_ctx_t *c = (pyramid_ctx_t *)p;
    return trn_pyramid_build(&c->pyr, c->dist, c->cap, c->levels, c->buf, c->len) == TRN_OK ? 0
                                                                                            : -1;
}

/* ------------------------------------------------------------------------ */
/* Search and localization                                                  */
/* ------------------------------------------------------------------------ */

typedef struct {
    const trn_map_t *map;
    const trn_point_t *pts;
    size_t n;
    const trn_window_t *win;
    const trn_exclusion_t *ex;
    void *ws;
    size_t wsb;
    trn_best_t best;
    trn_search_stats_t stats;
} search_ctx_t;

static int run_exhaustive(void *p)
{
    search_ctx_t *c = (search_ctx_t *)p;
    return trn_search_exhaustive(&c->map->dist, &c->map->lnp, c->pts, c->n, c->win, c->ex, &c->best,
                                 &c->stats) == TRN_OK
               ? 0
               : -1;
}

static int run_bb(void *p)
{
    search_ctx_t *c = (search_ctx_t *)p;
    return trn_search_bb(&c->map->pyr, &c->map->lnp, c->pts, c->n, c->win, c->ex, c->ws, c->wsb,
                         &c->best, &c->stats) == TRN_OK
               ? 0
               : -1;
}

/* The 8 neighbour scores trn_localize_points computes for the eq. 6 fit. */
static int run_score9(void *p)
{
    search_ctx_t *c = (search_ctx_t *)p;
    int i;
    for (i = 0; i < 9; ++i) {
        int64_t s;
        if (i == 4) {
            continue;
        }
        if (trn_score_pose(&c->map->dist, &c->map->lnp, c->pts, c->n, c->best.x + i % 3 - 1,
                           c->best.y + i / 3 - 1, &s) != TRN_OK) {
            return -1;
        }
        g_sink += (unsigned long long)s;
    }
    return 0;
}

typedef struct {
    const trn_grid_f32_t *hp;
    const trn_terrain_cfg_t *tc;
    int32_t rx, ry;
    trn_point_t *pts;
    size_t cap, n;
} points_ctx_t;

static int run_points(void *p)
{
    points_ctx_t *c = (points_ctx_t *)p;
    return trn_occupancy_points(c->hp, c->tc, c->rx, c->ry, c->pts, c->cap, &c->n) == TRN_OK ? 0
                                                                                             : -1;
}

typedef struct {
    const trn_map_t *map;
    const trn_grid_f32_t *local;
    int32_t rx, ry;
    size_t max_pts;
    const trn_window_t *win;
    void *ws;
    size_t wsb;
    trn_loc_result_t res;
    trn_status_t st;
} loc_ctx_t;

static int run_localize(void *p)
{
    loc_ctx_t *c = (loc_ctx_t *)p;
    c->st = trn_localize_dem(c->map, c->local, c->rx, c->ry, c->max_pts, c->win, c->ws, c->wsb,
                             &c->res);
    return (c->st == TRN_OK || c->st == TRN_E_ILLCOND) ? 0 : -1;
}

/* ------------------------------------------------------------------------ */
/* One map size                                                             */
/* ------------------------------------------------------------------------ */

typedef struct {
    int32_t n;
    int wrong;                        /* a wrong answer was seen */
    double chamfer_vs_stream;         /* median trn_chamfer3d / median SIMD streaming passes */
    double chamfer_vs_scan;           /* median trn_chamfer3d / median scalar scan passes */
    double floor_vs_stream;           /* median relaxation floor / median SIMD streaming passes */
    int32_t win[N_WINDOWS];           /* half-widths used (clamped on small maps) */
    double search_speedup[N_WINDOWS]; /* median exhaustive / median branch-and-bound */
    bench_select_result_t sel;        /* landmark selection rows */
    bench_heading_result_t head;      /* the (x, y, heading) search row */
} size_result_t;

/* One global map size: its memory (freed in one place) and shared state. */
typedef struct {
    int32_t n, nz;
    size_t cells, nvox, nrocks, hpwsb, lhpwsb, mapb, pyrb, max_pts, n_pts;
    trn_map_cfg_t cfg;
    trn_lik_cfg_t lik;
    synth_terrain_t terrain;
    trn_grid_f32_t gdem, ghp, glocal, glhp;
    trn_vol_u8_t vocc, vdist;
    map_ctx_t mc;          /* the prepared map the searches use */
    timing_t t_hp, t_occ;  /* global trn_highpass, trn_occupancy */
    timing_t t_ch;         /* trn_chamfer3d */
    timing_t t_lhp, t_pts; /* local trn_highpass, trn_occupancy_points */
    double tx, ty;         /* true rover pose, cells */
    int32_t px, py;        /* prior pose, cells */
    int32_t wfit;          /* largest window half-width that fits the map */
    /* heap memory */
    synth_rock_t *rocks;
    float *dem, *hp, *loc, *lhp;
    void *hpws, *lhpws, *mapbuf, *pyrbuf, *bbws, *locws;
    uint8_t *occ, *dist, *scratch;
    trn_point_t *pts;
#ifdef TRN_HAVE_OPENCV
    bench_cv_dt_t *cv;
#endif
} world_t;

static void world_free(world_t *m)
{
    free(m->rocks);
    free(m->dem);
    free(m->hp);
    free(m->loc);
    free(m->lhp);
    free(m->hpws);
    free(m->lhpws);
    free(m->mapbuf);
    free(m->pyrbuf);
    free(m->bbws);
    free(m->locws);
    free(m->occ);
    free(m->dist);
    free(m->scratch);
    free(m->pts);
#ifdef TRN_HAVE_OPENCV
    bench_cv_dt_destroy(m->cv);
#endif
}

static unsigned long long sum_u8(const uint8_t *v, size_t n)
{
    unsigned long long s = 0u;
    size_t i;
    for (i = 0; i < n; ++i) {
        s += v[i];
    }
    return s;
}

static double mib(size_t bytes) { return (double)bytes / (1024.0 * 1024.0); }

/* Terrain, global DEM and buffers of size n. Returns 0 or an exit status. */
static int world_init(world_t *w, const opts_t *o, int32_t n)
{
    trn_status_t st;
    memset(w, 0, sizeof *w);
    w->n = n;
    trn_map_cfg_default(&w->cfg);
    w->nz = w->cfg.terrain.nz;
    w->cells = (size_t)n * (size_t)n;
    w->nvox = w->cells * (size_t)w->nz;
    w->lik.cell_m = w->cfg.terrain.cell_m;
    w->lik.sigma_m = w->cfg.sigma_m;
    w->lik.inlier_prob = w->cfg.inlier_prob;
    w->lik.cap = w->cfg.cap;
    /* Terrain as in trn_demo: 15 % rock cover, radii 5-30 cm, height half
     * the diameter, 0.2 m rolling background. */
    w->nrocks = (size_t)((double)w->cells * CELL_M * CELL_M * 0.15 / (PI * 0.15 * 0.15));
    w->hpwsb = trn_highpass_workspace_bytes(n, n);
    w->mapb = trn_map_bytes(&w->cfg, n, n);
    w->pyrb = trn_pyramid_bytes(n, n, w->nz, w->cfg.levels);
    w->lhpwsb = trn_highpass_workspace_bytes(LOCAL_CELLS, LOCAL_CELLS);
    w->max_pts = (size_t)LOCAL_CELLS * LOCAL_CELLS * (size_t)w->nz;
    w->rocks = malloc(sizeof *w->rocks * (w->nrocks + 1u));
    w->dem = malloc(sizeof *w->dem * w->cells);
    w->hp = malloc(sizeof *w->hp * w->cells);
    w->hpws = malloc(w->hpwsb);
    w->mapbuf = malloc(w->mapb);
    w->pyrbuf = malloc(w->pyrb);
    w->occ = malloc(w->nvox);
    w->dist = malloc(w->nvox);
    w->scratch = malloc(w->nvox);
    w->loc = malloc(sizeof *w->loc * LOCAL_CELLS * LOCAL_CELLS);
    w->lhp = malloc(sizeof *w->lhp * LOCAL_CELLS * LOCAL_CELLS);
    w->lhpws = malloc(w->lhpwsb);
    w->pts = malloc(sizeof *w->pts * w->max_pts);
    if (w->rocks == NULL || w->dem == NULL || w->hp == NULL || w->hpws == NULL ||
        w->mapbuf == NULL || w->pyrbuf == NULL || w->occ == NULL || w->dist == NULL ||
        w->scratch == NULL || w->loc == NULL || w->lhp == NULL || w->lhpws == NULL ||
        w->pts == NULL) {
        fprintf(stderr, "trn_bench: out of memory at size %d\n", (int)n);
        return 3;
    }
    synth_make(&w->terrain, w->rocks, w->nrocks, (double)n * CELL_M, 0.05, 0.3, 0.5, 0.2,
               o->seed + (unsigned long long)n);
    synth_render(&w->terrain, w->dem, (int)n, (int)n, 0.0, 0.0, CELL_M);
    if ((st = trn_grid_f32_init(&w->gdem, w->dem, w->cells, n, n)) != TRN_OK ||
        (st = trn_grid_f32_init(&w->ghp, w->hp, w->cells, n, n)) != TRN_OK ||
        (st = trn_vol_u8_init(&w->vocc, w->occ, w->nvox, n, n, w->nz)) != TRN_OK ||
        (st = trn_vol_u8_init(&w->vdist, w->dist, w->nvox, n, n, w->nz)) != TRN_OK ||
        (st = trn_grid_f32_init(&w->glocal, w->loc, (size_t)LOCAL_CELLS * LOCAL_CELLS, LOCAL_CELLS,
                                LOCAL_CELLS)) != TRN_OK ||
        (st = trn_grid_f32_init(&w->glhp, w->lhp, (size_t)LOCAL_CELLS * LOCAL_CELLS, LOCAL_CELLS,
                                LOCAL_CELLS)) != TRN_OK) {
        return fail("grid setup", st);
    }
    w->mc.cfg = &w->cfg;
    w->mc.dem = &w->gdem;
    w->mc.buf = w->mapbuf;
    w->mc.len = w->mapb;
    return 0;
}

/* The global occupancy: trn_highpass + trn_occupancy, timed (map parts). */
static int bench_occupancy(world_t *w, const opts_t *o)
{
    highpass_ctx_t hc;
    occupancy_ctx_t oc;
    hc.dem = &w->gdem;
    hc.tc = &w->cfg.terrain;
    hc.hp = &w->ghp;
    hc.ws = w->hpws;
    hc.wsb = w->hpwsb;
    if (time_fn(run_highpass, &hc, 1, o->repeats, 0.0, &w->t_hp) != 0) {
        return fail("trn_highpass", trn_highpass(hc.dem, hc.tc, hc.hp, hc.ws, hc.wsb));
    }
    oc.hp = &w->ghp;
    oc.tc = &w->cfg.terrain;
    oc.occ = &w->vocc;
    oc.n_occ = 0u;
    if (time_fn(run_occupancy, &oc, 1, o->repeats, 0.0, &w->t_occ) != 0) {
        return fail("trn_occupancy", trn_occupancy(oc.hp, oc.tc, oc.occ, NULL));
    }
    printf("occupied voxels: %u (%.1f %%)\n\n", (unsigned)oc.n_occ,
           100.0 * (double)oc.n_occ / (double)w->nvox);
    return 0;
}

/* trn_chamfer3d against the streaming passes, Dijkstra and OpenCV. */
/* The memory-bound references of the chamfer transform: two streaming
 * passes (SIMD), the relaxation alone (the floor), a scalar scan. 0 or 3. */
static int chamfer_refs(world_t *w, const opts_t *o, timing_t *t_rows, timing_t *t_floor,
                        timing_t *t_scan)
{
    const int32_t n = w->n;
    stream_ctx_t sc;

    sc.occ = w->occ;
    sc.v = w->scratch;
    sc.n = w->nvox;
    sc.nx = (size_t)n;
    sc.cap = w->cfg.cap;
    (void)time_fn(run_stream_rows, &sc, 1, o->repeats, 0.0, t_rows);
    g_sink += sum_u8(w->scratch, w->nvox);
    print_row(n, "chamfer: streaming 2 passes, SIMD (target ref)", t_rows,
              "v[i]=min(v[i],v[i-+nx]+1): memory-bound floor");
    {
        floor_ctx_t fc;
        uint8_t *fscratch = malloc(bench_relax_floor_scratch((size_t)n));
        if (fscratch == NULL) {
            fprintf(stderr, "trn_bench: out of memory at size %d\n", (int)n);
            return 3;
        }
        fc.occ = w->occ;
        fc.v = w->scratch;
        fc.nx = (size_t)n;
        fc.ny = (size_t)n;
        fc.nz = (size_t)w->nz;
        fc.cap = w->cfg.cap;
        fc.scratch = fscratch;
        (void)time_fn(run_relax_floor, &fc, 1, o->repeats, 0.0, t_floor);
        free(fscratch);
        print_row(n, "chamfer: relaxation only, 2 passes (floor)", t_floor,
                  "no in-row steps, wrong distances: timing only");
    }
    (void)time_fn(run_stream_scan, &sc, 1, o->repeats, 0.0, t_scan);
    g_sink += sum_u8(w->scratch, w->nvox);
    print_row(n, "chamfer: streaming 2 passes, scalar scan (info)", t_scan,
              "v[i]=min(v[i],v[i-+1]+1): latency-bound chain");
    return 0;
}

/* The naive oracle (Dijkstra) against trn_chamfer3d's answer in w->dist. */
static void chamfer_oracle(world_t *w, const opts_t *o, size_result_t *r, timing_t *t_dij)
{
    const int32_t n = w->n;
    dijkstra_ctx_t dc;
    char note[160];
    int same;

    /* The naive oracle: slow, so no warm-up and a time budget. */
    dc.occ = w->occ;
    dc.out = w->scratch;
    dc.nx = (int)n;
    dc.ny = (int)n;
    dc.nz = (int)w->nz;
    dc.cap = w->cfg.cap;
    (void)time_fn(run_dijkstra, &dc, 0, o->repeats, NAIVE_BUDGET_S, t_dij);
    same = memcmp(w->scratch, w->dist, w->nvox) == 0;
    snprintf(note, sizeof note, "no warm-up%s; same answer: %s",
             t_dij->reps < o->repeats ? ", stopped after " NAIVE_BUDGET_TXT : "",
             same ? "yes" : "NO");
    print_row(n, "chamfer: naive Dijkstra (ref_chamfer3d_dijkstra)", t_dij, note);
    if (!same) {
        fprintf(stderr, "trn_bench: trn_chamfer3d differs from the Dijkstra oracle\n");
        r->wrong = 1;
    }
}

static int bench_chamfer(world_t *w, const opts_t *o, size_result_t *r)
{
    const int32_t n = w->n;
    chamfer_ctx_t cc;
    timing_t t_scan = {0}, t_rows = {0}, t_dij = {0}, t_floor = {0};
    char note[160];

    cc.occ = &w->vocc;
    cc.dist = &w->vdist;
    cc.cap = w->cfg.cap;
    if (time_fn(run_chamfer, &cc, 1, o->repeats, 0.0, &w->t_ch) != 0) {
        return fail("trn_chamfer3d", trn_chamfer3d(cc.occ, cc.dist, cc.cap));
    }
    snprintf(note, sizeof note, "3-D 3-4-5, cap %u, %.2f ns/voxel", (unsigned)w->cfg.cap,
             w->t_ch.med_ms * 1e6 / (double)w->nvox);
    print_row(n, "chamfer: trn_chamfer3d (occ -> dist)", &w->t_ch, note);

    if (chamfer_refs(w, o, &t_rows, &t_floor, &t_scan) != 0) {
        return 3;
    }
    chamfer_oracle(w, o, r, &t_dij);

#ifdef TRN_HAVE_OPENCV
    {
        static const int masks[3] = {3, 5, 0};
        static const char *const names[3] = {"chamfer: OpenCV L2 mask 3, 16 slices",
                                             "chamfer: OpenCV L2 mask 5, 16 slices",
                                             "chamfer: OpenCV L2 MASK_PRECISE, 16 slices"};
        static const char *const ratios[3] = {"OpenCV mask 3 (all slices) / trn_chamfer3d",
                                              "OpenCV mask 5 (all slices) / trn_chamfer3d",
                                              "OpenCV PRECISE (all slices) / trn_chamfer3d"};
        timing_t t_cv[3];
        cv_ctx_t cvc;
        int k;
        w->cv = bench_cv_dt_create(w->occ, (int)n, (int)n, (int)w->nz);
        if (w->cv == NULL) {
            fprintf(stderr, "trn_bench: OpenCV slice setup failed\n");
            return 3;
        }
        cvc.cv = w->cv;
        for (k = 0; k < 3; ++k) {
            cvc.mask = masks[k];
            if (time_fn(run_cv, &cvc, 1, o->repeats, 0.0, &t_cv[k]) != 0) {
                fprintf(stderr, "trn_bench: cv::distanceTransform failed\n");
                return 3;
            }
            g_sink += (unsigned long long)bench_cv_dt_checksum(w->cv);
            snprintf(note, sizeof note, "2-D per z-slice, CV_32F out, %.3f ms/slice",
                     t_cv[k].med_ms / (double)w->nz);
            print_row(n, names[k], &t_cv[k], note);
        }
        print_ratio("trn_chamfer3d / streaming SIMD (memory-bound)", &w->t_ch, &t_rows,
                    "(target <= 3)");
        print_ratio("relaxation floor / streaming SIMD", &t_floor, &t_rows,
                    "(trn_chamfer3d's relaxation, no in-row steps)");
        print_ratio("trn_chamfer3d / streaming scalar scan", &w->t_ch, &t_scan, NULL);
        print_ratio("naive Dijkstra / trn_chamfer3d", &t_dij, &w->t_ch, NULL);
        for (k = 0; k < 3; ++k) {
            print_ratio(ratios[k], &t_cv[k], &w->t_ch, "(> 1: trn faster)");
        }
    }
#else
    print_ratio("trn_chamfer3d / streaming SIMD (memory-bound)", &w->t_ch, &t_rows,
                "(target <= 3)");
    print_ratio("relaxation floor / streaming SIMD", &t_floor, &t_rows,
                "(trn_chamfer3d's relaxation, no in-row steps)");
    print_ratio("trn_chamfer3d / streaming scalar scan", &w->t_ch, &t_scan, NULL);
    print_ratio("naive Dijkstra / trn_chamfer3d", &t_dij, &w->t_ch, NULL);
    printf("      (OpenCV reference not built: OpenCV not found at configure time)\n");
#endif
    r->chamfer_vs_stream = w->t_ch.med_ms / t_rows.med_ms;
    r->chamfer_vs_scan = w->t_ch.med_ms / t_scan.med_ms;
    r->floor_vs_stream = t_floor.med_ms / t_rows.med_ms;
    return 0;
}

/* trn_map_build and the parts not timed yet; leaves w->mc.map built. */
static int bench_map(world_t *w, const opts_t *o)
{
    const int32_t n = w->n;
    map_ctx_t *mc = &w->mc;
    outlier_ctx_t lc;
    pyramid_ctx_t pc;
    timing_t t_build, t_k, t_lnp, t_pyr;
    char note[160];

    if (time_fn(run_map_build, mc, 1, o->repeats, 0.0, &t_build) != 0) {
        return fail("trn_map_build", trn_map_build(&mc->map, mc->cfg, mc->dem, mc->buf, mc->len));
    }
    lc.dist = &w->vdist;
    lc.lik = &w->lik;
    if (time_fn(run_outlier, &lc, 1, o->repeats, 0.0, &t_k) != 0 ||
        time_fn(run_lnp_table, &lc, 1, o->repeats, 0.0, &t_lnp) != 0) {
        fprintf(stderr, "trn_bench: trn_outlier_density / trn_lnp_table_build failed\n");
        return 3;
    }
    pc.dist = &w->vdist;
    pc.cap = w->cfg.cap;
    pc.levels = w->cfg.levels;
    pc.buf = w->pyrbuf;
    pc.len = w->pyrb;
    if (time_fn(run_pyramid, &pc, 1, o->repeats, 0.0, &t_pyr) != 0) {
        return fail("trn_pyramid_build",
                    trn_pyramid_build(&pc.pyr, pc.dist, pc.cap, pc.levels, pc.buf, pc.len));
    }
    snprintf(note, sizeof note, "once per global map; trn_map_bytes %zu (%.2f MiB)", w->mapb,
             mib(w->mapb));
    print_row(n, "map: trn_map_build (total)", &t_build, note);
    snprintf(note, sizeof note, "%.0f %% of build", 100.0 * w->t_hp.med_ms / t_build.med_ms);
    print_row(n, "map:   trn_highpass", &w->t_hp, note);
    snprintf(note, sizeof note, "%.0f %% of build", 100.0 * w->t_occ.med_ms / t_build.med_ms);
    print_row(n, "map:   trn_occupancy", &w->t_occ, note);
    snprintf(note, sizeof note, "%.0f %% of build (chamfer row above)",
             100.0 * w->t_ch.med_ms / t_build.med_ms);
    print_row(n, "map:   trn_chamfer3d", &w->t_ch, note);
    snprintf(note, sizeof note, "%.0f %% of build; K = %.4g /m",
             100.0 * t_k.med_ms / t_build.med_ms, lc.k);
    print_row(n, "map:   trn_outlier_density", &t_k, note);
    snprintf(note, sizeof note, "%.0f %% of build", 100.0 * t_lnp.med_ms / t_build.med_ms);
    print_row(n, "map:   trn_lnp_table_build", &t_lnp, note);
    snprintf(note, sizeof note, "%.0f %% of build; %d levels, %.2f MiB",
             100.0 * t_pyr.med_ms / t_build.med_ms, (int)w->cfg.levels, mib(w->pyrb));
    print_row(n, "map:   trn_pyramid_build", &t_pyr, note);
    return 0;
}

/* The local map at a random true pose and its points (local parts timed). */
static int bench_local(world_t *w, const opts_t *o)
{
    const int32_t n = w->n, half = LOCAL_CELLS / 2;
    int32_t wmax, margin;
    highpass_ctx_t hc;
    points_ctx_t ptc;
    trn_rng_t rng;

    w->wfit = (n - 1) / 2 - PRIOR_ERR_CELLS - 2;
    wmax = k_windows[N_WINDOWS - 1] < w->wfit ? k_windows[N_WINDOWS - 1] : w->wfit;
    margin = wmax + PRIOR_ERR_CELLS + 1;
    trn_rng_seed(&rng, o->seed * 7919u + (unsigned long long)n);
    w->tx = (double)trn_rng_int(&rng, margin, n - 1 - margin) + trn_rng_unit(&rng) - 0.5;
    w->ty = (double)trn_rng_int(&rng, margin, n - 1 - margin) + trn_rng_unit(&rng) - 0.5;
    w->px = (int32_t)lround(w->tx) + trn_rng_int(&rng, -PRIOR_ERR_CELLS, PRIOR_ERR_CELLS);
    w->py = (int32_t)lround(w->ty) + trn_rng_int(&rng, -PRIOR_ERR_CELLS, PRIOR_ERR_CELLS);
    /* The rover's own grid (rover at cell (half, half)): a sub-cell resampling. */
    synth_render(&w->terrain, w->loc, LOCAL_CELLS, LOCAL_CELLS, (w->tx - half) * CELL_M,
                 (w->ty - half) * CELL_M, CELL_M);
    hc.dem = &w->glocal;
    hc.tc = &w->cfg.terrain;
    hc.hp = &w->glhp;
    hc.ws = w->lhpws;
    hc.wsb = w->lhpwsb;
    if (time_fn(run_highpass, &hc, 1, o->repeats, 0.0, &w->t_lhp) != 0) {
        return fail("trn_highpass (local)", trn_highpass(hc.dem, hc.tc, hc.hp, hc.ws, hc.wsb));
    }
    ptc.hp = &w->glhp;
    ptc.tc = &w->cfg.terrain;
    ptc.rx = half;
    ptc.ry = half;
    ptc.pts = w->pts;
    ptc.cap = w->max_pts;
    ptc.n = 0u;
    if (time_fn(run_points, &ptc, 1, o->repeats, 0.0, &w->t_pts) != 0) {
        return fail("trn_occupancy_points",
                    trn_occupancy_points(ptc.hp, ptc.tc, half, half, w->pts, w->max_pts, &ptc.n));
    }
    w->n_pts = ptc.n;
    /* as trn_localize_dem does: rare height bins first (same answers, the
     * branch-and-bound early exits come sooner) */
    if (trn_points_order(w->pts, w->n_pts, w->cfg.terrain.nz) != TRN_OK) {
        return fail("trn_points_order", trn_points_order(w->pts, w->n_pts, w->cfg.terrain.nz));
    }
    printf("\nlocal map %d x %d cells, %zu occupied voxels (rare height bins first); "
           "true pose (%.2f, %.2f), prior (%d, %d)\n",
           LOCAL_CELLS, LOCAL_CELLS, w->n_pts, w->tx, w->ty, (int)w->px, (int)w->py);
    return 0;
}

/* Exhaustive vs branch-and-bound and one trn_localize_dem, window k. */
/* Exhaustive search against branch-and-bound over the window of half-side
 * W (entry k of k_windows); r->search_speedup[k]. 0 or 3. */
static int window_search(world_t *w, const opts_t *o, int k, int32_t W, search_ctx_t *ex,
                         search_ctx_t *bb, timing_t *t_ex, timing_t *t_bb, size_result_t *r)
{
    const int32_t n = w->n;
    int same;
    char name[64], note[160];

    if (time_fn(run_exhaustive, ex, 1, o->repeats, 0.0, t_ex) != 0) {
        fprintf(stderr, "trn_bench: trn_search_exhaustive failed\n");
        return 3;
    }
    snprintf(note, sizeof note, "%llu poses scored (%dx%d window%s)",
             (unsigned long long)ex->stats.poses_scored, (int)(2 * W + 1), (int)(2 * W + 1),
             W < k_windows[k] ? ", clamped to fit the map" : "");
    snprintf(name, sizeof name, "search +-%d: trn_search_exhaustive", (int)W);
    print_row(n, name, t_ex, note);
    if (time_fn(run_bb, bb, 1, o->repeats, 0.0, t_bb) != 0) {
        fprintf(stderr, "trn_bench: trn_search_bb failed\n");
        return 3;
    }
    same = ex->best.x == bb->best.x && ex->best.y == bb->best.y && ex->best.score == bb->best.score;
    snprintf(note, sizeof note, "%llu poses scored, %llu blocks bounded; same answer: %s",
             (unsigned long long)bb->stats.poses_scored,
             (unsigned long long)bb->stats.blocks_bounded, same ? "yes" : "NO");
    snprintf(name, sizeof name, "search +-%d: trn_search_bb", (int)W);
    print_row(n, name, t_bb, note);
    if (!same) {
        fprintf(stderr, "trn_bench: branch-and-bound (%d, %d, %lld) != exhaustive (%d, %d, %lld)\n",
                (int)bb->best.x, (int)bb->best.y, (long long)bb->best.score, (int)ex->best.x,
                (int)ex->best.y, (long long)ex->best.score);
        r->wrong = 1;
    }
    r->search_speedup[k] = t_ex->med_ms / t_bb->med_ms;
    return 0;
}

/* The parts of trn_localize_dem (lo, timed t_loc): the local map's
 * high-pass and points, the best-pose search (t_bb), the second search for
 * the competing hypothesis outside the exclusion zone and the fit's 8 extra
 * scores. 0 or 3. */
static int window_parts(world_t *w, const opts_t *o, const search_ctx_t *bb, const loc_ctx_t *lo,
                        const timing_t *t_bb, const timing_t *t_loc)
{
    const int32_t n = w->n;
    search_ctx_t sec, b9 = *bb;
    trn_exclusion_t exz;
    timing_t t_sec, t_s9;
    char note[160];

    /* its parts: the second search trn_localize_points runs (the competing
     * hypothesis, outside the exclusion zone) and the fit's 8 extra scores */
    sec = *bb;
    exz.cx = lo->res.ix;
    exz.cy = lo->res.iy;
    exz.radius = lo->res.exclusion_cells;
    sec.ex = &exz;
    if (time_fn(run_bb, &sec, 1, o->repeats, 0.0, &t_sec) != 0 ||
        time_fn(run_score9, &b9, 1, o->repeats, 0.0, &t_s9) != 0) {
        fprintf(stderr, "trn_bench: localization parts failed\n");
        return 3;
    }
    snprintf(note, sizeof note, "%.0f %%", 100.0 * w->t_lhp.med_ms / t_loc->med_ms);
    print_row(n, "localize:   trn_highpass (64x64 local)", &w->t_lhp, note);
    snprintf(note, sizeof note, "%.0f %%", 100.0 * w->t_pts.med_ms / t_loc->med_ms);
    print_row(n, "localize:   trn_occupancy_points", &w->t_pts, note);
    snprintf(note, sizeof note, "%.0f %% (search row above)", 100.0 * t_bb->med_ms / t_loc->med_ms);
    print_row(n, "localize:   trn_search_bb, best pose", t_bb, note);
    snprintf(
        note, sizeof note, "%.0f %%; exclusion radius %d, %llu poses scored, %llu blocks bounded",
        100.0 * t_sec.med_ms / t_loc->med_ms, (int)exz.radius,
        (unsigned long long)sec.stats.poses_scored, (unsigned long long)sec.stats.blocks_bounded);
    print_row(n, "localize:   trn_search_bb, second peak", &t_sec, note);
    snprintf(note, sizeof note, "%.0f %%", 100.0 * t_s9.med_ms / t_loc->med_ms);
    print_row(n, "localize:   8 x trn_score_pose (eq. 6 fit)", &t_s9, note);
    return 0;
}

static int bench_window(world_t *w, const opts_t *o, int k, size_result_t *r)
{
    const int32_t n = w->n, half = LOCAL_CELLS / 2;
    const int32_t W = k_windows[k] < w->wfit ? k_windows[k] : w->wfit;
    trn_window_t win;
    search_ctx_t ex, bb;
    loc_ctx_t lo;
    timing_t t_ex, t_bb, t_loc;
    size_t wb, lwb;
    int loc_same;
    char name[64], note[160];

    r->win[k] = W;
    win.x0 = w->px - W;
    win.y0 = w->py - W;
    win.x1 = w->px + W;
    win.y1 = w->py + W;
    wb = trn_search_bb_workspace_bytes(&w->mc.map.pyr, &win);
    lwb = trn_localize_dem_workspace_bytes(&w->mc.map, LOCAL_CELLS, LOCAL_CELLS, w->max_pts, &win);
    free(w->bbws);
    free(w->locws);
    w->bbws = malloc(wb);
    w->locws = malloc(lwb);
    if (wb == 0u || lwb == 0u || w->bbws == NULL || w->locws == NULL) {
        fprintf(stderr, "trn_bench: search workspace (%zu, %zu bytes) failed\n", wb, lwb);
        return 3;
    }
    memset(&ex, 0, sizeof ex);
    ex.map = &w->mc.map;
    ex.pts = w->pts;
    ex.n = w->n_pts;
    ex.win = &win;
    ex.ex = NULL;
    bb = ex;
    bb.ws = w->bbws;
    bb.wsb = wb;

    printf("\n");
    if (window_search(w, o, k, W, &ex, &bb, &t_ex, &t_bb, r) != 0) {
        return 3;
    }

    /* the whole localization: the same points are made inside it */
    lo.map = &w->mc.map;
    lo.local = &w->glocal;
    lo.rx = half;
    lo.ry = half;
    lo.max_pts = w->max_pts;
    lo.win = &win;
    lo.ws = w->locws;
    lo.wsb = lwb;
    if (time_fn(run_localize, &lo, 1, o->repeats, 0.0, &t_loc) != 0) {
        return fail("trn_localize_dem", lo.st);
    }
    loc_same = lo.res.ix == ex.best.x && lo.res.iy == ex.best.y;
    snprintf(note, sizeof note, "%s; error %.2f cells, sigma %.3f m; = exhaustive pose: %s",
             trn_strerror(lo.st), hypot(lo.res.x - w->tx, lo.res.y - w->ty),
             lo.res.sigma_x_m > lo.res.sigma_y_m ? lo.res.sigma_x_m : lo.res.sigma_y_m,
             loc_same ? "yes" : "NO");
    snprintf(name, sizeof name, "localize +-%d: trn_localize_dem", (int)W);
    print_row(n, name, &t_loc, note);
    if (!loc_same) {
        fprintf(stderr, "trn_bench: trn_localize_dem pose (%d, %d) != exhaustive (%d, %d)\n",
                (int)lo.res.ix, (int)lo.res.iy, (int)ex.best.x, (int)ex.best.y);
        r->wrong = 1;
    }

    if (window_parts(w, o, &bb, &lo, &t_bb, &t_loc) != 0) {
        return 3;
    }
    snprintf(name, sizeof name, "exhaustive / branch-and-bound, +-%d", (int)W);
    print_ratio(name, &t_ex, &t_bb, "(target >= 10)");
    return 0;
}

static int bench_size(const opts_t *o, int32_t n, size_result_t *r)
{
    world_t w;
    int rc, k;
    memset(r, 0, sizeof *r);
    r->n = n;
    if ((rc = world_init(&w, o, n)) == 0) {
        printf("\n== %d x %d cells of %.1f m, %d bins: %zu voxels (%.1f MiB), %zu rocks ==\n",
               (int)n, (int)n, CELL_M, (int)w.nz, w.nvox, mib(w.nvox), w.nrocks);
        if ((rc = bench_occupancy(&w, o)) == 0) {
            print_header();
            if ((rc = bench_chamfer(&w, o, r)) == 0 && (rc = bench_map(&w, o)) == 0) {
                rc = bench_local(&w, o);
            }
        }
    }
    for (k = 0; rc == 0 && k < N_WINDOWS; ++k) {
        rc = bench_window(&w, o, k, r);
    }
    if (rc == 0) {
        rc = bench_select_run(&w.mc.map, n, o->repeats, &r->sel);
        r->wrong |= r->sel.wrong;
    }
    if (rc == 0) {
        rc = bench_heading_run(&w.mc.map, w.pts, w.n_pts, w.px, w.py,
                               k_windows[0] < w.wfit ? k_windows[0] : w.wfit, n, o->repeats,
                               &r->head);
        r->wrong |= r->head.wrong;
    }
    world_free(&w);
    return rc;
}

/* ------------------------------------------------------------------------ */

/** printf-append to buf[*len..cap), never past the end (output truncated). */
static void append(char *buf, size_t cap, size_t *len, const char *fmt, double a, int n, int w)
{
    int k;
    if (*len + 1u >= cap) {
        return;
    }
    k = w >= 0 ? snprintf(buf + *len, cap - *len, fmt, *len ? ", " : "", n, w, a)
               : snprintf(buf + *len, cap - *len, fmt, *len ? ", " : "", n, a);
    if (k > 0) {
        *len += (size_t)k < cap - *len ? (size_t)k : cap - *len - 1u;
    }
}

/* The selection rows' target lines. */
static void print_select_targets(const opts_t *o, const size_result_t *res)
{
    int i;
    for (i = 0; i < o->nsizes; ++i) {
        const bench_select_result_t *b = &res[i].sel;
        if (b->pmap_cv_ms > 0.0) {
            printf("target probability map (eq. 8) no slower than cv::sepFilter2D%s: %s "
                   "(%d: %.2fx = sepFilter2D / trn_prob_global_map)\n",
                   res[i].n >= 512 ? "" : " (info below 512)",
                   b->pmap_cv_ms >= b->pmap_ms ? "PASS" : "MISS", (int)res[i].n,
                   b->pmap_cv_ms / b->pmap_ms);
        }
        printf("target all candidates of one rover position < 20 ms%s: %s (%d: %.2f ms)\n",
               res[i].n >= 512 ? "" : " (info below 512)", b->select_ms < 20.0 ? "PASS" : "MISS",
               (int)res[i].n, b->select_ms);
        printf("target trn_field_fast >= 10x trn_field (paper defaults, %dx%d area, same "
               "field)%s: %s (%d: %.2fx; small reach, whole map: %.2fx)\n",
               (int)b->fpaper_side, (int)b->fpaper_side,
               b->fpaper_side == res[i].n ? "" : " (info: the target is the whole 256 map)",
               b->fpaper_ms >= 10.0 * b->fpaper_fast_ms ? "PASS" : "MISS", (int)res[i].n,
               b->fpaper_ms / b->fpaper_fast_ms, b->field_ms / b->field_fast_ms);
    }
}

/* The height matcher's target lines (tools/bench/bench_heights.c). */
static void print_height_targets(const opts_t *o, const bench_heights_result_t *hres)
{
    int w;
    for (w = 0; w < (o->quick ? 1 : 2); ++w) {
        printf("target height matcher <= 3x the voxel matcher (README case, +-%d): %s "
               "(bounded %.1fx, exhaustive %.1fx)\n",
               (int)hres->win[w], hres->bnd_ms[w] <= 3.0 * hres->voxel_ms[w] ? "PASS" : "MISS",
               hres->bnd_ms[w] / hres->voxel_ms[w], hres->exh_ms[w] / hres->voxel_ms[w]);
    }
    if (!o->quick) {
        printf("target height matcher +-50 <= 4x its +-25: %s (bounded %.2fx, exhaustive "
               "%.2fx)\n",
               hres->bnd_ms[1] <= 4.0 * hres->bnd_ms[0] ? "PASS" : "MISS",
               hres->bnd_ms[1] / hres->bnd_ms[0], hres->exh_ms[1] / hres->exh_ms[0]);
    }
    printf("target height matcher's worst case (flat, periodic, 5x5 local) bounded <= 1.2x "
           "exhaustive: %s (%.2fx worst)\n",
           hres->worst_ratio <= 1.2 ? "PASS" : "MISS", hres->worst_ratio);
}

int main(int argc, char **argv)
{
    opts_t o;
    size_result_t res[MAX_SIZES];
    bench_heights_result_t hres;
    double t0, worst_ch = 0.0, worst_bb = 1e300;
    int i, w, wrong = 0, rc;
    char buf[512];
    size_t len;

    if (!parse(argc, argv, &o)) {
        usage(stderr);
        return 2;
    }
    t0 = now_s();
    printf("trn_bench: sizes");
    for (i = 0; i < o.nsizes; ++i) {
        printf("%s%d", i ? "," : " ", (int)o.sizes[i]);
    }
    printf(", %d repeat%s per row (median and min of them, after one warm-up), seed %llu,\n"
           "single thread, CLOCK_MONOTONIC; ratios compare medians from this run.\n",
           o.repeats, o.repeats == 1 ? "" : "s", o.seed);
#ifdef TRN_HAVE_OPENCV
    printf("OpenCV %s reference, cv::getNumThreads() = %d after cv::setNumThreads(1).\n",
           bench_cv_version(), bench_cv_single_thread());
#else
    printf("OpenCV reference not built.\n");
#endif
    for (i = 0; i < o.nsizes; ++i) {
        if ((rc = bench_size(&o, o.sizes[i], &res[i])) != 0) {
            return rc;
        }
        wrong |= res[i].wrong;
    }

    if (o.heights) {
        if ((rc = bench_heights_run(o.repeats, o.quick, &hres)) != 0) {
            return rc;
        }
        wrong |= hres.wrong;
    }

    printf("\n");
    len = 0u;
    buf[0] = '\0';
    for (i = 0; i < o.nsizes; ++i) {
        if (res[i].chamfer_vs_stream > worst_ch) {
            worst_ch = res[i].chamfer_vs_stream;
        }
        append(buf, sizeof buf, &len, "%s%d: %.2fx", res[i].chamfer_vs_stream, (int)res[i].n, -1);
    }
    printf("target chamfer <= 3x streaming: %s (%.2fx worst vs 2 SIMD streaming passes, the "
           "memory-bound limit: %s; vs the scalar v[i-1] scan:",
           worst_ch <= 3.0 ? "PASS" : "MISS", worst_ch, buf);
    for (i = 0; i < o.nsizes; ++i) {
        printf("%s%d: %.2fx", i ? ", " : " ", (int)res[i].n, res[i].chamfer_vs_scan);
    }
    printf("; the out-of-row relaxation alone, no in-row steps:");
    for (i = 0; i < o.nsizes; ++i) {
        printf("%s%d: %.2fx", i ? ", " : " ", (int)res[i].n, res[i].floor_vs_stream);
    }
    printf(")\n");
    len = 0u;
    buf[0] = '\0';
    for (i = 0; i < o.nsizes; ++i) {
        for (w = 0; w < N_WINDOWS; ++w) {
            if (res[i].search_speedup[w] < worst_bb) {
                worst_bb = res[i].search_speedup[w];
            }
            append(buf, sizeof buf, &len, "%s%d +-%d: %.1fx", res[i].search_speedup[w],
                   (int)res[i].n, (int)res[i].win[w]);
        }
    }
    printf("target fast search >= 10x exhaustive: %s (%.1fx worst; %s)\n",
           worst_bb >= 10.0 ? "PASS" : "MISS", worst_bb, buf);
    print_select_targets(&o, res);
    for (i = 0; i < o.nsizes; ++i) {
        printf("target (x, y, heading) search <= 0.2 of the 2-DOF search x headings: %s (%d: %.3f, "
               "%d headings)\n",
               res[i].head.ratio <= 0.2 ? "PASS" : "MISS", (int)res[i].n, res[i].head.ratio,
               (int)res[i].head.steps);
    }
    if (o.heights) {
        print_height_targets(&o, &hres);
    }
    printf("same answer (branch-and-bound = exhaustive = localize, chamfer = Dijkstra, "
           "selection = naive, trn_field_fast = trn_field, height bounded = exhaustive): %s\n",
           wrong ? "NO" : "yes");
    printf("total run time %.1f s\n", now_s() - t0);
    (void)g_sink;
    return wrong ? 1 : 0;
}
