/* trn_demo - the main job until landmark selection lands: generate a rocky
 * synthetic terrain, let a rover at a random true position build a local map
 * of what it sees, localize it against the global map from a prior that is
 * off by a few cells, and print pose, covariance and the truth.
 *
 *   trn_demo [--size N] [--local N] [--window R] [--prior-error R] [--seed S] [--json]
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rng.h"
#include "synth.h"
#include "trn/trn.h"

#define PI 3.14159265358979323846

typedef struct {
    long size, local, window, prior_err;
    unsigned long long seed;
    int json;
} opts_t;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: trn_demo [--size N] [--local N] [--window R] [--prior-error R] [--seed S] [--json]\n"
            "  --size N         global map side, cells of 0.1 m (64..4096, default 256)\n"
            "  --local N        local map side, cells (16..256, default 64)\n"
            "  --window R       prior window half-width searched, cells (1..512, default 25)\n"
            "  --prior-error R  largest prior error per axis, cells (0..window, default 10)\n"
            "  --seed S         terrain and pose seed (default 1)\n"
            "  --json           one JSON object on stdout\n");
}

static int parse_long(const char *name, const char *v, long lo, long hi, long *out)
{
    char *end;
    long x;
    if (v == NULL) {
        fprintf(stderr, "trn_demo: %s needs a value\n", name);
        return 0;
    }
    errno = 0;
    x = strtol(v, &end, 10);
    if (errno != 0 || *end != '\0' || end == v || x < lo || x > hi) {
        fprintf(stderr, "trn_demo: %s must be an integer in [%ld, %ld], got '%s'\n", name, lo, hi, v);
        return 0;
    }
    *out = x;
    return 1;
}

static int parse(int argc, char **argv, opts_t *o)
{
    int i;
    long seed = 1;
    o->size = 256;
    o->local = 64;
    o->window = 25;
    o->prior_err = 10;
    o->json = 0;
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int ok = 1;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            exit(0);
        } else if (strcmp(a, "--json") == 0) {
            o->json = 1;
            continue;
        } else if (strcmp(a, "--size") == 0) {
            ok = parse_long(a, v, 64, TRN_MAX_DIM, &o->size);
        } else if (strcmp(a, "--local") == 0) {
            ok = parse_long(a, v, 16, 256, &o->local);
        } else if (strcmp(a, "--window") == 0) {
            ok = parse_long(a, v, 1, 512, &o->window);
        } else if (strcmp(a, "--prior-error") == 0) {
            ok = parse_long(a, v, 0, 512, &o->prior_err);
        } else if (strcmp(a, "--seed") == 0) {
            ok = parse_long(a, v, 0, 2147483647L, &seed);
        } else {
            fprintf(stderr, "trn_demo: unknown argument '%s' (try --help)\n", a);
            return 0;
        }
        if (!ok) {
            return 0;
        }
        ++i;
    }
    if (o->prior_err > o->window) {
        fprintf(stderr, "trn_demo: --prior-error (%ld) must not exceed --window (%ld)\n",
                o->prior_err, o->window);
        return 0;
    }
    if (o->size < o->local + 2 * o->window + 2) {
        fprintf(stderr, "trn_demo: --size %ld too small for --local %ld and --window %ld\n",
                o->size, o->local, o->window);
        return 0;
    }
    o->seed = (unsigned long long)seed;
    return 1;
}

int main(int argc, char **argv)
{
    opts_t o;
    const double cell = 0.1;
    synth_terrain_t t;
    synth_rock_t *rocks;
    size_t nrocks, mb, wb, max_pts;
    float *dem, *loc;
    trn_grid_f32_t g, lg;
    trn_map_cfg_t cfg;
    trn_map_t map;
    void *mbuf, *ws;
    trn_rng_t r;
    trn_window_t win;
    trn_loc_result_t res;
    trn_status_t st;
    double tx, ty, ex, ey;
    int px, py, half;

    if (!parse(argc, argv, &o)) {
        return 2;
    }
    /* Rock field: 15 % cover, radii 5-30 cm, height half the diameter. */
    nrocks = (size_t)((double)o.size * (double)o.size * cell * cell * 0.15 / (PI * 0.15 * 0.15));
    rocks = malloc(sizeof *rocks * (nrocks + 1));
    dem = malloc(sizeof *dem * (size_t)o.size * (size_t)o.size);
    loc = malloc(sizeof *loc * (size_t)o.local * (size_t)o.local);
    if (rocks == NULL || dem == NULL || loc == NULL) {
        fprintf(stderr, "trn_demo: out of memory\n");
        return 1;
    }
    synth_make(&t, rocks, nrocks, (double)o.size * cell, 0.05, 0.3, 0.5, 0.2, o.seed);
    synth_render(&t, dem, (int)o.size, (int)o.size, 0.0, 0.0, cell);
    trn_grid_f32_init(&g, dem, (size_t)o.size * (size_t)o.size, (int32_t)o.size, (int32_t)o.size);
    trn_map_cfg_default(&cfg);
    mb = trn_map_bytes(&cfg, g.width, g.height);
    mbuf = malloc(mb);
    if (mbuf == NULL) {
        fprintf(stderr, "trn_demo: out of memory for a %zu-byte map\n", mb);
        return 1;
    }
    if ((st = trn_map_build(&map, &cfg, &g, mbuf, mb)) != TRN_OK) {
        fprintf(stderr, "trn_demo: map build failed: %s\n", trn_strerror(st));
        return 1;
    }

    /* True rover position (sub-cell), a prior off by up to prior_err cells. */
    trn_rng_seed(&r, o.seed * 7919u + 1u);
    half = (int)(o.local / 2);
    tx = (double)trn_rng_int(&r, (int32_t)(o.window + half + 1), (int32_t)(o.size - o.window - half - 2)) +
         trn_rng_unit(&r) - 0.5;
    ty = (double)trn_rng_int(&r, (int32_t)(o.window + half + 1), (int32_t)(o.size - o.window - half - 2)) +
         trn_rng_unit(&r) - 0.5;
    px = (int)lround(tx) + trn_rng_int(&r, -(int32_t)o.prior_err, (int32_t)o.prior_err);
    py = (int)lround(ty) + trn_rng_int(&r, -(int32_t)o.prior_err, (int32_t)o.prior_err);
    win.x0 = px - (int)o.window;
    win.y0 = py - (int)o.window;
    win.x1 = px + (int)o.window;
    win.y1 = py + (int)o.window;

    /* The local map: the terrain around the rover, sampled in the rover's
     * own grid (rover at cell (half, half)), so it is a sub-cell resampling. */
    synth_render(&t, loc, (int)o.local, (int)o.local, (tx - half) * cell, (ty - half) * cell, cell);
    trn_grid_f32_init(&lg, loc, (size_t)o.local * (size_t)o.local, (int32_t)o.local, (int32_t)o.local);
    max_pts = (size_t)o.local * (size_t)o.local * (size_t)cfg.terrain.nz;
    wb = trn_localize_dem_workspace_bytes(&map, lg.width, lg.height, max_pts, &win);
    ws = malloc(wb);
    if (ws == NULL) {
        fprintf(stderr, "trn_demo: out of memory\n");
        return 1;
    }
    st = trn_localize_dem(&map, &lg, half, half, max_pts, &win, ws, wb, &res);
    if (st != TRN_OK && st != TRN_E_ILLCOND) {
        fprintf(stderr, "trn_demo: localization failed: %s\n", trn_strerror(st));
        return 1;
    }
    ex = (res.x - tx) * cell;
    ey = (res.y - ty) * cell;
    if (o.json) {
        printf("{\"seed\": %llu, \"map_cells\": %ld, \"cell_m\": %.3f, \"status\": \"%s\", "
               "\"truth\": {\"x_m\": %.4f, \"y_m\": %.4f}, \"prior\": {\"x_m\": %.4f, \"y_m\": %.4f}, "
               "\"x_m\": %.4f, \"y_m\": %.4f, \"sigma_x_m\": %.5f, \"sigma_y_m\": %.5f, \"rho\": %.4f, "
               "\"error_m\": %.5f, \"failure_probability\": %.3g, \"local_points\": %zu, "
               "\"poses_scored\": %llu}\n",
               o.seed, o.size, cell, trn_strerror(st), tx * cell, ty * cell, px * cell, py * cell,
               res.x * cell, res.y * cell, res.sigma_x_m, res.sigma_y_m, res.rho,
               sqrt(ex * ex + ey * ey), res.failure_probability, res.n_points,
               (unsigned long long)res.stats.poses_scored);
    } else {
        printf("terrain      %ld x %ld cells of %.2f m, %zu rocks, seed %llu\n", o.size, o.size,
               cell, nrocks, o.seed);
        printf("truth        x = %8.3f m   y = %8.3f m\n", tx * cell, ty * cell);
        printf("prior        x = %8.3f m   y = %8.3f m   (window +-%.1f m)\n", px * cell, py * cell,
               (double)o.window * cell);
        printf("estimate     x = %8.3f m   y = %8.3f m   status: %s\n", res.x * cell, res.y * cell,
               trn_strerror(st));
        printf("covariance   sigma_x = %.4f m  sigma_y = %.4f m  rho = %+.3f\n", res.sigma_x_m,
               res.sigma_y_m, res.rho);
        printf("error        %.4f m (%.2f cells)   failure probability %.3g\n",
               sqrt(ex * ex + ey * ey), sqrt(ex * ex + ey * ey) / cell, res.failure_probability);
        printf("search       %zu local voxels, %llu of %d poses scored exactly\n", res.n_points,
               (unsigned long long)res.stats.poses_scored,
               (2 * (int)o.window + 1) * (2 * (int)o.window + 1));
    }
    free(ws);
    free(mbuf);
    free(loc);
    free(dem);
    free(rocks);
    return 0;
}
