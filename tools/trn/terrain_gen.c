/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/terrain_gen.c - Golombek & Rapp rock fields (see terrain_gen.h). */
#include "terrain_gen.h"

#include <math.h>
#include <string.h>

#define TG_PI 3.14159265358979323846

/* splitmix64: the generator's own seeded stream. */
typedef struct {
    uint64_t s;
} tg_rng_t;

static uint64_t rng_u64(tg_rng_t *r)
{
    uint64_t z = (r->s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Uniform in [0, 1), 53 bits. */
static double rng_unit(tg_rng_t *r)
{
    return (double)(rng_u64(r) >> 11) * (1.0 / 9007199254740992.0);
}

/* Poisson(lambda) by multiplying uniforms (Knuth), in chunks of at most 20
 * so exp(-chunk) never underflows; Poisson variables add. Bounded: each
 * chunk stops after 1000 factors (probability of reaching it < 1e-300). */
static uint64_t rng_poisson(tg_rng_t *r, double lambda)
{
    uint64_t n = 0;
    while (lambda > 0.0) {
        double chunk = lambda > 20.0 ? 20.0 : lambda;
        double limit = exp(-chunk);
        double prod = rng_unit(r);
        int i;
        lambda -= chunk;
        for (i = 0; i < 1000 && prod > limit; ++i) {
            ++n;
            prod *= rng_unit(r);
        }
    }
    return n;
}

double tg_q(double k) { return 1.79 + 0.152 / k; }

double tg_cum_area(double k, double d_m) { return k * exp(-tg_q(k) * d_m); }

double tg_auto_d_max(double k) { return log(1e4) / tg_q(k); }

void tg_default(tg_params_t *p, int width, int height, double cell_m)
{
    memset(p, 0, sizeof *p);
    p->width = width;
    p->height = height;
    p->cell_m = cell_m;
    p->coverage_k = 0.1;
    p->height_ratio = 0.5;
    p->d_min_m = 2.0 * cell_m;
    p->d_max_m = tg_auto_d_max(p->coverage_k);
    p->relief_m = 0.05;
    p->seed = 1;
}

const char *tg_check(const tg_params_t *p)
{
    if (p->width < 1 || p->height < 1) {
        return "map size must be at least 1 x 1 cells";
    }
    if (!(p->cell_m > 0.0) || !isfinite(p->cell_m)) {
        return "cell size must be positive";
    }
    if (!(p->coverage_k > 0.0 && p->coverage_k < 1.0)) {
        return "rock coverage k must be in (0, 1)";
    }
    if (!(p->height_ratio > 0.0) || !isfinite(p->height_ratio)) {
        return "rock height/diameter ratio must be positive";
    }
    if (!(p->d_min_m > 0.0) || !isfinite(p->d_min_m) || !(p->d_max_m >= p->d_min_m) ||
        !isfinite(p->d_max_m)) {
        return "rock diameters must satisfy 0 < d_min <= d_max";
    }
    if ((p->d_max_m - p->d_min_m) / TG_BIN_M > 1e6) {
        return "rock diameter range too wide (more than 1e6 bins of 1 mm)";
    }
    if (!(p->relief_m >= 0.0) || !isfinite(p->relief_m)) {
        return "background relief must be >= 0";
    }
    return NULL;
}

/* The generation area: the map plus a margin of d_max / 2. */
static void gen_area(const tg_params_t *p, double *x0, double *y0, double *wx, double *wy)
{
    double margin = 0.5 * p->d_max_m;
    *x0 = -margin;
    *y0 = -margin;
    *wx = (double)p->width * p->cell_m + 2.0 * margin;
    *wy = (double)p->height * p->cell_m + 2.0 * margin;
}

size_t tg_draw_rocks(const tg_params_t *p, tg_rock_t *rocks, size_t cap)
{
    tg_rng_t r;
    double x0, y0, wx, wy, area, q, k;
    long nbins, b;
    size_t n = 0;

    gen_area(p, &x0, &y0, &wx, &wy);
    area = wx * wy;
    k = p->coverage_k;
    q = tg_q(k);
    nbins = (long)ceil((p->d_max_m - p->d_min_m) / TG_BIN_M);
    r.s = p->seed ^ 0x5EEDF00D12345678ull;
    for (b = 0; b < nbins; ++b) {
        double lo = p->d_min_m + (double)b * TG_BIN_M;
        double hi = lo + TG_BIN_M > p->d_max_m ? p->d_max_m : lo + TG_BIN_M;
        double mid = 0.5 * (lo + hi);
        double lambda = k * q * exp(-q * mid) / (TG_PI * mid * mid / 4.0) * (hi - lo) * area;
        uint64_t m = rng_poisson(&r, lambda), i;
        for (i = 0; i < m; ++i) {
            double d = lo + (hi - lo) * rng_unit(&r);
            double x = x0 + wx * rng_unit(&r);
            double y = y0 + wy * rng_unit(&r);
            if (rocks != NULL && n < cap) {
                rocks[n].x_m = x;
                rocks[n].y_m = y;
                rocks[n].d_m = d;
                rocks[n].h_m = p->height_ratio * d;
            }
            ++n;
        }
    }
    return n;
}

/* Raise rock_h to rock k's height where its disc covers a cell centre. */
static void render_rock(const tg_params_t *p, const tg_rock_t *k, float *rock_h)
{
    double rad = 0.5 * k->d_m;
    /* Cells whose centres may lie inside the disc, clipped to the map. */
    long c0 = (long)floor((k->x_m - rad) / p->cell_m - 0.5);
    long c1 = (long)ceil((k->x_m + rad) / p->cell_m - 0.5);
    long r0 = (long)floor((k->y_m - rad) / p->cell_m - 0.5);
    long r1 = (long)ceil((k->y_m + rad) / p->cell_m - 0.5);
    long rr, cc;
    if (c0 < 0) {
        c0 = 0;
    }
    if (r0 < 0) {
        r0 = 0;
    }
    if (c1 > p->width - 1) {
        c1 = p->width - 1;
    }
    if (r1 > p->height - 1) {
        r1 = p->height - 1;
    }
    for (rr = r0; rr <= r1; ++rr) {
        double dy = ((double)rr + 0.5) * p->cell_m - k->y_m;
        for (cc = c0; cc <= c1; ++cc) {
            double dx = ((double)cc + 0.5) * p->cell_m - k->x_m;
            double u = (dx * dx + dy * dy) / (rad * rad);
            if (u < 1.0) {
                float z = (float)(k->h_m * sqrt(1.0 - u));
                float *cell = &rock_h[(size_t)rr * (size_t)p->width + (size_t)cc];
                if (z > *cell) {
                    *cell = z;
                }
            }
        }
    }
}

void tg_render_rocks(const tg_params_t *p, const tg_rock_t *rocks, size_t n, float *rock_h)
{
    size_t i;
    memset(rock_h, 0, sizeof *rock_h * (size_t)p->width * (size_t)p->height);
    for (i = 0; i < n; ++i) {
        render_rock(p, &rocks[i], rock_h);
    }
}

void tg_render(const tg_params_t *p, const tg_rock_t *rocks, size_t n, float *dem,
               void (*progress)(void *ctx, long done, long total), void *ctx)
{
    double amp[TG_RELIEF_WAVES], kx[TG_RELIEF_WAVES], ky[TG_RELIEF_WAVES], ph[TG_RELIEF_WAVES];
    tg_rng_t r;
    int w, row, col;
    size_t i, chunk;

    /* Rocks first (dem holds the rock heights, the higher rock wins), in
   * chunks so a progress bar can follow. */
    memset(dem, 0, sizeof *dem * (size_t)p->width * (size_t)p->height);
    chunk = n / 100 + 1;
    for (i = 0; i < n; i += chunk) {
        size_t j, end = i + chunk < n ? i + chunk : n;
        for (j = i; j < end; ++j) {
            render_rock(p, &rocks[j], dem);
        }
        if (progress != NULL) {
            progress(ctx, (long)end, (long)n + p->height);
        }
    }

    /* Background waves, from their own stream so the rocks do not depend on
   * them, added under the rocks. */
    r.s = p->seed ^ 0xBAC6D00DCAFE0001ull;
    for (w = 0; w < TG_RELIEF_WAVES; ++w) {
        double lam = TG_RELIEF_MIN_WAVELENGTH_M *
                     exp(rng_unit(&r) *
                         log(TG_RELIEF_MAX_WAVELENGTH_M / TG_RELIEF_MIN_WAVELENGTH_M));
        double dir = 2.0 * TG_PI * rng_unit(&r);
        amp[w] = p->relief_m * sqrt(2.0 / (double)TG_RELIEF_WAVES);
        kx[w] = 2.0 * TG_PI / lam * cos(dir);
        ky[w] = 2.0 * TG_PI / lam * sin(dir);
        ph[w] = 2.0 * TG_PI * rng_unit(&r);
    }
    for (row = 0; row < p->height; ++row) {
        double y = ((double)row + 0.5) * p->cell_m;
        for (col = 0; col < p->width; ++col) {
            double x = ((double)col + 0.5) * p->cell_m, z = 0.0;
            float *cell = &dem[(size_t)row * (size_t)p->width + (size_t)col];
            for (w = 0; w < TG_RELIEF_WAVES; ++w) {
                z += amp[w] * sin(kx[w] * x + ky[w] * y + ph[w]);
            }
            *cell = (float)((double)*cell + z);
        }
        if (progress != NULL) {
            progress(ctx, (long)n + row + 1, (long)n + p->height);
        }
    }
}
