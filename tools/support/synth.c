/* SPDX-License-Identifier: Apache-2.0 */
/* synth.c - see synth.h. */
#include "synth.h"

#include <math.h>

#include "rng.h"

void synth_make(synth_terrain_t *t, synth_rock_t *rocks, size_t n, double extent_m, double rmin_m,
                double rmax_m, double height_ratio, double bg_amp_m, uint64_t seed)
{
    trn_rng_t r;
    size_t i;
    trn_rng_seed(&r, seed);
    t->rocks = rocks;
    t->n_rocks = n;
    t->bg_amp_m = bg_amp_m;
    t->bg_wave_m = 7.0;
    for (i = 0; i < 4; ++i) {
        t->phase[i] = 6.283185307179586 * trn_rng_unit(&r);
    }
    for (i = 0; i < n; ++i) {
        rocks[i].x_m = extent_m * trn_rng_unit(&r);
        rocks[i].y_m = extent_m * trn_rng_unit(&r);
        rocks[i].r_m = rmin_m + (rmax_m - rmin_m) * trn_rng_unit(&r);
        rocks[i].h_m = height_ratio * 2.0 * rocks[i].r_m;
    }
}

static double background(const synth_terrain_t *t, double x, double y)
{
    double k = 6.283185307179586 / t->bg_wave_m;
    return t->bg_amp_m * (sin(k * x + t->phase[0]) * cos(0.7 * k * y + t->phase[1]) +
                          0.5 * sin(1.9 * k * (x + y) + t->phase[2]) + 0.05 * x / t->bg_wave_m +
                          0.03 * y / t->bg_wave_m);
}

static double rock_at(const synth_rock_t *rk, double x, double y)
{
    double dx = x - rk->x_m, dy = y - rk->y_m, q = (dx * dx + dy * dy) / (rk->r_m * rk->r_m);
    return q < 1.0 ? rk->h_m * sqrt(1.0 - q) : 0.0;
}

double synth_height(const synth_terrain_t *t, double x_m, double y_m)
{
    double top = 0.0;
    size_t i;
    for (i = 0; i < t->n_rocks; ++i) {
        double v = rock_at(&t->rocks[i], x_m, y_m);
        if (v > top) {
            top = v;
        }
    }
    return background(t, x_m, y_m) + top;
}

void synth_render(const synth_terrain_t *t, float *out, int w, int h, double ox_m, double oy_m,
                  double cell_m)
{
    int i, j;
    size_t k;
    /* background everywhere, then each rock over its bounding box (max) */
    for (j = 0; j < h; ++j) {
        for (i = 0; i < w; ++i) {
            out[(size_t)j * (size_t)w + (size_t)i] = 0.0f;
        }
    }
    for (k = 0; k < t->n_rocks; ++k) {
        const synth_rock_t *rk = &t->rocks[k];
        int i0 = (int)floor((rk->x_m - rk->r_m - ox_m) / cell_m) - 1;
        int i1 = (int)ceil((rk->x_m + rk->r_m - ox_m) / cell_m) + 1;
        int j0 = (int)floor((rk->y_m - rk->r_m - oy_m) / cell_m) - 1;
        int j1 = (int)ceil((rk->y_m + rk->r_m - oy_m) / cell_m) + 1;
        if (i0 < 0) {
            i0 = 0;
        }
        if (j0 < 0) {
            j0 = 0;
        }
        if (i1 > w - 1) {
            i1 = w - 1;
        }
        if (j1 > h - 1) {
            j1 = h - 1;
        }
        for (j = j0; j <= j1; ++j) {
            for (i = i0; i <= i1; ++i) {
                float v = (float)rock_at(rk, ox_m + i * cell_m, oy_m + j * cell_m);
                float *o = &out[(size_t)j * (size_t)w + (size_t)i];
                if (v > *o) {
                    *o = v;
                }
            }
        }
    }
    for (j = 0; j < h; ++j) {
        for (i = 0; i < w; ++i) {
            out[(size_t)j * (size_t)w + (size_t)i] += (float)background(t, ox_m + i * cell_m,
                                                                        oy_m + j * cell_m);
        }
    }
}
