/* SPDX-License-Identifier: Apache-2.0 */
/* synth.h - analytic synthetic terrain for tests, tools and benchmarks:
 * rolling background plus ellipsoidal rocks, evaluated at any position so a
 * local map can be rendered at sub-cell offsets ("resampled terrain"). */
#ifndef TRN_SUPPORT_SYNTH_H
#define TRN_SUPPORT_SYNTH_H
#include <stddef.h>
#include <stdint.h>

typedef struct {
    double x_m, y_m; /* centre */
    double r_m;      /* radius (half the diameter) */
    double h_m;      /* height above the background */
} synth_rock_t;

typedef struct {
    synth_rock_t *rocks; /* caller array */
    size_t n_rocks;
    double bg_amp_m;  /* amplitude of the rolling background */
    double bg_wave_m; /* its wavelength */
    double phase[4];
} synth_terrain_t;

/* n rocks uniformly over [0, extent_m]^2, radii uniform in [rmin, rmax],
 * height = height_ratio * diameter. */
void synth_make(synth_terrain_t *t, synth_rock_t *rocks, size_t n, double extent_m, double rmin_m,
                double rmax_m, double height_ratio, double bg_amp_m, uint64_t seed);

/* Height at a map position, metres. */
double synth_height(const synth_terrain_t *t, double x_m, double y_m);

/* Render w x h cells; cell (i, j) is sampled at (ox_m + i*cell_m, oy_m + j*cell_m). */
void synth_render(const synth_terrain_t *t, float *out, int w, int h, double ox_m, double oy_m,
                  double cell_m);
#endif
