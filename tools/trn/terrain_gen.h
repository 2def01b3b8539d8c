/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/terrain_gen.h - synthetic Mars terrain: rocks drawn from the
 * Golombek & Rapp (1997) size-frequency model on a smooth background.
 *
 * Model. The cumulative fractional area covered by rocks of diameter >= D
 * (metres) is F_k(D) = k exp(-q(k) D), q(k) = 1.79 + 0.152 / k, k the total
 * rock coverage. The area density per unit diameter is -dF/dD = k q e^{-qD},
 * so the number of rocks per square metre per metre of diameter is
 *     n(D) = k q e^{-qD} / (pi D^2 / 4).
 * Rocks are drawn for D in [d_min, d_max]: the expected count in each 1 mm
 * diameter bin over the generation area is n(D_mid) * 1 mm * area, the
 * realised count Poisson, the diameter uniform within the bin, the centre
 * uniform over the generation area (the map plus a margin of d_max / 2 on
 * every side, so rocks crossing the edges are there and coverage is the same
 * near the edges as inside).
 *
 * Shape: a half-ellipsoid (a hemisphere when height_ratio = 0.5) of
 * diameter D and height h = height_ratio * D:
 *     z(r) = h sqrt(1 - (2r/D)^2)  for r < D/2.
 * Where rocks overlap the higher one wins (max, not sum).
 *
 * Background: relief_m RMS of TG_RELIEF_WAVES plane waves of equal amplitude,
 * random directions and phases, wavelengths log-uniform in
 * [TG_RELIEF_MIN_WAVELENGTH_M, TG_RELIEF_MAX_WAVELENGTH_M].
 *
 * Frame: "grid metres": x east from the map's western edge, y SOUTH from its
 * northern edge; cell (c, r) is centred at ((c + 0.5) cell, (r + 0.5) cell),
 * the layout of dem_t (dem_io.h).
 *
 * Determinism: a seeded splitmix64 stream written here; the same seed gives
 * the same rocks and the same heights. Rock rendering uses only IEEE-exact
 * operations (+ - * / sqrt); the expected counts (exp) and the background
 * (sin) call libm, whose last-bit results may differ between C libraries. */
#ifndef TRN_TERRAIN_GEN_H
#define TRN_TERRAIN_GEN_H

#include <stddef.h>
#include <stdint.h>

#define TG_BIN_M 0.001 /* diameter bin width */
#define TG_RELIEF_WAVES 12
#define TG_RELIEF_MIN_WAVELENGTH_M 4.0
#define TG_RELIEF_MAX_WAVELENGTH_M 64.0

typedef struct {
    int width, height;   /* cells */
    double cell_m;       /* cell size */
    double coverage_k;   /* k of the model, (0, 1) */
    double height_ratio; /* rock height / diameter */
    double d_min_m;      /* smallest rock drawn */
    double d_max_m;      /* largest rock drawn (tg_default: F_k(d_max) = 1e-4 k) */
    double relief_m;     /* RMS of the background relief */
    uint64_t seed;
} tg_params_t;

typedef struct {
    double x_m, y_m; /* centre, grid metres (may lie in the margin outside the map) */
    double d_m;      /* diameter */
    double h_m;      /* height */
} tg_rock_t;

/* Defaults for a width x height map of cell_m cells: k = 0.1,
 * height_ratio 0.5, d_min = 2 cells, d_max from F_k(d_max) = 1e-4 k,
 * relief 0.05 m, seed 1. */
void tg_default(tg_params_t *p, int width, int height, double cell_m);

/* d_max where F_k(d_max) = 1e-4 k, i.e. ln(1e4) / q(k). */
double tg_auto_d_max(double k);

/* NULL if p is valid, else a one-line reason. */
const char *tg_check(const tg_params_t *p);

double tg_q(double k);                    /* q(k) = 1.79 + 0.152 / k */
double tg_cum_area(double k, double d_m); /* F_k(D) */

/* Draw the rocks. With rocks == NULL only counts them. Returns the number of
 * rocks drawn (the same for the same parameters whether or not rocks is
 * NULL); at most cap are stored. */
size_t tg_draw_rocks(const tg_params_t *p, tg_rock_t *rocks, size_t cap);

/* Heights of the map: background plus rocks, width*height floats row-major.
 * progress (may be NULL) is called with (done, total), total = n + height:
 * one step per rock, then one per row of background. */
void tg_render(const tg_params_t *p, const tg_rock_t *rocks, size_t n, float *dem,
               void (*progress)(void *ctx, long done, long total), void *ctx);

/* Height of the rocks alone at each cell (0 where no rock): for tests. */
void tg_render_rocks(const tg_params_t *p, const tg_rock_t *rocks, size_t n, float *rock_h);

#endif /* TRN_TERRAIN_GEN_H */
