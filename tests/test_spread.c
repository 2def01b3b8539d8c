/* SPDX-License-Identifier: Apache-2.0 */
/* test_spread.c - eqs. 8 and 9, separable position-variant scatter (spread.h).
 *
 * Oracles: a direct 2-D convolution (constant sigma), a direct 2-D
 * position-variant scatter in double where each source cell spreads with the
 * 2-D kernel k_j(x) k_j(y) of its own sigma (varying sigma), mass counts,
 * nearest-in-log-sigma computed with logs, and eq. 9 over the whole map
 * against the on-demand region. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rng.h"
#include "selworld.h"
#include "trn/spread.h"

/* The separable pass picks the y kernel by the intermediate cell's sigma,
 * the direct sum by the source's: measured worst absolute difference 0.0155
 * on the varying-sigma test below (all ten kernels in use, single-voxel peaks
 * up to 0.62): asserted bound 0.03. */
#define VARYING_TOL 0.03
/* same kernels everywhere: float rounding only (measured 7e-8) */
#define CONST_TOL 1e-6

static trn_kernels_t g_k;

static int setup(void **state)
{
    (void)state;
    return trn_kernels_build(&g_k, 0.5f) == TRN_OK ? 0 : -1;
}

static void random_occ(uint8_t *occ, int nx, int ny, int nz, double frac, int border, uint64_t seed)
{
    trn_rng_t r;
    int x, y, z;
    trn_rng_seed(&r, seed);
    memset(occ, 0, (size_t)nx * ny * nz);
    for (z = 0; z < nz; ++z) {
        for (y = border; y < ny - border; ++y) {
            for (x = border; x < nx - border; ++x) {
                if (trn_rng_unit(&r) < frac) {
                    occ[((size_t)z * ny + y) * nx + x] = 1;
                }
            }
        }
    }
}

/* Direct 2-D position-variant scatter; kernel of source cell = kidx[y*nx+x]. */
static void direct_scatter_k(const trn_kernels_t *k, const uint8_t *occ, const uint8_t *kidx,
                             int nx, int ny, int nz, double *out)
{
    int x, y, z, a, b;
    memset(out, 0, sizeof(double) * (size_t)nx * ny * nz);
    for (z = 0; z < nz; ++z) {
        for (y = 0; y < ny; ++y) {
            for (x = 0; x < nx; ++x) {
                const int j = kidx[y * nx + x], r = k->radius[j];
                if (!occ[((size_t)z * ny + y) * nx + x]) {
                    continue;
                }
                for (b = -r; b <= r; ++b) {
                    for (a = -r; a <= r; ++a) {
                        if (x + a < 0 || x + a >= nx || y + b < 0 || y + b >= ny) {
                            continue;
                        }
                        out[((size_t)z * ny + y + b) * nx + x + a] +=
                            (double)k->taps[j][TRN_KERNEL_MAX_RADIUS + a] *
                            (double)k->taps[j][TRN_KERNEL_MAX_RADIUS + b];
                    }
                }
            }
        }
    }
}

static void direct_scatter(const uint8_t *occ, const uint8_t *kidx, int nx, int ny, int nz,
                           double *out)
{
    direct_scatter_k(&g_k, occ, kidx, nx, ny, nz, out);
}

static double run_global(const uint8_t *occ, int nx, int ny, int nz, const trn_sigma_model_t *m,
                         const trn_xy_t *s, size_t ns, float *pg)
{
    trn_vol_u8_t v;
    trn_vol_f32_t p;
    size_t wb = trn_prob_global_workspace_bytes(nx, ny);
    void *ws = selworld_alloc(wb);
    assert_non_null(ws);
    assert_int_equal(trn_vol_u8_init(&v, (uint8_t *)occ, (size_t)nx * ny * nz, nx, ny, nz), TRN_OK);
    p.data = pg;
    p.nx = nx;
    p.ny = ny;
    p.nz = nz;
    assert_int_equal(trn_prob_global(&g_k, m, 0.1f, s, ns, &v, &p, ws, wb), TRN_OK);
    free(ws);
    return 0.0;
}

static void test_constant_sigma_equals_2d(void **state)
{
    const int nx = 57, ny = 44, nz = 3;
    int j;
    (void)state;
    for (j = 0; j < TRN_KERNEL_COUNT; j += 3) {
        uint8_t *occ = malloc((size_t)nx * ny * nz), *kidx = malloc((size_t)nx * ny);
        float *pg = malloc(sizeof(float) * nx * ny * nz);
        double *ref = malloc(sizeof(double) * nx * ny * nz), worst = 0.0;
        trn_sigma_model_t m = {g_k.sigma_cells[j] * 0.1f, 0.0f};
        trn_xy_t s = {10.0f, 10.0f};
        size_t i;
        random_occ(occ, nx, ny, nz, 0.05, 0, 100 + (uint64_t)j);
        memset(kidx, j, (size_t)nx * ny);
        run_global(occ, nx, ny, nz, &m, &s, 1, pg);
        direct_scatter(occ, kidx, nx, ny, nz, ref);
        for (i = 0; i < (size_t)nx * ny * nz; ++i) {
            const double e = fabs((double)pg[i] - ref[i]);
            worst = e > worst ? e : worst;
        }
        printf("constant sigma %.3f cells: worst |separable - direct 2-D| = %.3g\n",
               (double)g_k.sigma_cells[j], worst);
        assert_true(worst < CONST_TOL);
        free(occ);
        free(kidx);
        free(pg);
        free(ref);
    }
}

static void test_varying_sigma_and_mass(void **state)
{
    const int nx = 120, ny = 110, nz = 2, border = 36; /* > R_9 = 34 */
    uint8_t *occ = malloc((size_t)nx * ny * nz), *kidx = malloc((size_t)nx * ny);
    float *pg = malloc(sizeof(float) * nx * ny * nz);
    double *ref = malloc(sizeof(double) * nx * ny * nz), worst = 0.0, mass = 0.0;
    /* sensor off the map's corner: sigma spans the whole table over the map */
    trn_sigma_model_t m = {0.02f, 0.004f};
    trn_xy_t s[2] = {{-5.0f, -5.0f}, {-40.0f, 150.0f}};
    trn_window_t win = {0, 0, nx - 1, ny - 1};
    size_t i, n_occ = 0;
    int x, y, used[TRN_KERNEL_COUNT] = {0}, nused = 0;
    (void)state;
    random_occ(occ, nx, ny, nz, 0.04, border, 7);
    assert_int_equal(trn_spread_kernel_map(&g_k, &m, 0.1f, s, 2, &win, kidx, (size_t)nx * ny),
                     TRN_OK);
    /* each cell's kernel is the nearest in log-sigma to sigma(nearest sensor) */
    for (y = 0; y < ny; ++y) {
        for (x = 0; x < nx; ++x) {
            double d2 = HUGE_VAL, sig, best = HUGE_VAL, jj;
            int k, bj = 0;
            for (k = 0; k < 2; ++k) {
                const double ex = (float)x - s[k].x_cells, ey = (float)y - s[k].y_cells;
                d2 = fmin(d2, ex * ex + ey * ey);
            }
            sig = (0.02 + 0.004 * d2 * 0.01) / 0.1;
            for (k = 0; k < TRN_KERNEL_COUNT; ++k) {
                const double dl = fabs(log(sig) - log((double)g_k.sigma_cells[k]));
                if (dl < best) {
                    best = dl;
                    bj = k;
                }
            }
            jj = 2.0 * log2(sig / 0.5);
            if (fabs(jj - floor(jj) - 0.5) > 1e-4 || jj > 9.5) {
                assert_int_equal(kidx[y * nx + x], bj);
            }
            if (!used[bj]) {
                used[bj] = 1;
                ++nused;
            }
        }
    }
    assert_true(nused >= 8);
    run_global(occ, nx, ny, nz, &m, s, 2, pg);
    direct_scatter(occ, kidx, nx, ny, nz, ref);
    for (i = 0; i < (size_t)nx * ny * nz; ++i) {
        const double e = fabs((double)pg[i] - ref[i]);
        worst = e > worst ? e : worst;
        mass += pg[i];
        n_occ += occ[i];
    }
    printf("varying sigma (%d kernels in use): worst |separable - direct 2-D| = %.3g; "
           "mass %.4f for %zu occupied voxels\n",
           nused, worst, mass, n_occ);
    assert_true(worst < VARYING_TOL);
    assert_true(fabs(mass / (double)n_occ - 1.0) < 1e-5); /* nothing near a border */
    free(occ);
    free(kidx);
    free(pg);
    free(ref);
}

static void test_local_region_equals_whole(void **state)
{
    const int nx = 90, ny = 80, nz = 3;
    uint8_t *occ = malloc((size_t)nx * ny * nz);
    float *pg = malloc(sizeof(float) * nx * ny * nz), *full = malloc(sizeof(float) * nx * ny * nz);
    trn_sigma_model_t gm = {0.02f, 0.003f}, lm;
    trn_xy_t s = {45.0f, 40.0f}, rover = {20.3f, 61.7f};
    trn_window_t whole = {0, 0, nx - 1, ny - 1}, roi = {30, 12, 71, 49};
    trn_vol_f32_t vpg = {pg, nx, ny, nz}, vfull = {full, nx, ny, nz}, vroi;
    size_t wb;
    void *ws;
    int x, y, z;
    double worst = 0.0;
    (void)state;
    trn_sigma_local_default(&lm);
    lm.k_per_m = 0.02f; /* wide kernels at this small scale */
    random_occ(occ, nx, ny, nz, 0.06, 0, 3);
    run_global(occ, nx, ny, nz, &gm, &s, 1, pg);
    wb = trn_prob_local_workspace_bytes(&g_k, &whole);
    ws = selworld_alloc(wb);
    assert_int_equal(trn_prob_local(&g_k, &lm, 0.1f, rover, &vpg, &whole, &vfull, ws, wb), TRN_OK);
    free(ws);
    vroi.nx = roi.x1 - roi.x0 + 1;
    vroi.ny = roi.y1 - roi.y0 + 1;
    vroi.nz = nz;
    vroi.data = malloc(sizeof(float) * vroi.nx * vroi.ny * nz);
    wb = trn_prob_local_workspace_bytes(&g_k, &roi);
    ws = selworld_alloc(wb);
    assert_int_equal(trn_prob_local(&g_k, &lm, 0.1f, rover, &vpg, &roi, &vroi, ws, wb), TRN_OK);
    for (z = 0; z < nz; ++z) {
        for (y = 0; y < vroi.ny; ++y) {
            for (x = 0; x < vroi.nx; ++x) {
                const double a = vroi.data[((size_t)z * vroi.ny + y) * vroi.nx + x];
                const double b = full[((size_t)z * ny + y + roi.y0) * nx + x + roi.x0];
                worst = fmax(worst, fabs(a - b));
            }
        }
    }
    assert_true(worst <= 1e-6);
    /* the bad inputs of trn_prob_local */
    assert_int_equal(trn_prob_local(NULL, &lm, 0.1f, rover, &vpg, &roi, &vroi, ws, wb), TRN_E_NULL);
    assert_int_equal(trn_prob_local(&g_k, &lm, 0.1f, rover, NULL, &roi, &vroi, ws, wb), TRN_E_NULL);
    assert_int_equal(trn_prob_local(&g_k, &lm, 0.1f, rover, &vpg, &roi, &vroi, NULL, wb),
                     TRN_E_NULL);
    assert_int_equal(trn_prob_local(&g_k, NULL, 0.1f, rover, &vpg, &roi, &vroi, ws, wb),
                     TRN_E_NULL);
    assert_int_equal(trn_prob_local(&g_k, &lm, 0.0f, rover, &vpg, &roi, &vroi, ws, wb), TRN_E_ARG);
    {
        trn_xy_t bad = {NAN, 1.0f};
        trn_window_t off = {80, 0, 95, 10}, empty = {5, 5, 4, 9};
        assert_int_equal(trn_prob_local(&g_k, &lm, 0.1f, bad, &vpg, &roi, &vroi, ws, wb),
                         TRN_E_ARG);
        assert_int_equal(trn_prob_local(&g_k, &lm, 0.1f, rover, &vpg, &off, &vroi, ws, wb),
                         TRN_E_RANGE);
        assert_int_equal(trn_prob_local(&g_k, &lm, 0.1f, rover, &vpg, &empty, &vroi, ws, wb),
                         TRN_E_RANGE);
    }
    vroi.nx -= 1;
    assert_int_equal(trn_prob_local(&g_k, &lm, 0.1f, rover, &vpg, &roi, &vroi, ws, wb), TRN_E_SIZE);
    vroi.nx += 1;
    assert_int_equal(trn_prob_local(&g_k, &lm, 0.1f, rover, &vpg, &roi, &vroi, ws, wb - 1),
                     TRN_E_WORKSPACE);
    free(ws);
    free(vroi.data);
    free(occ);
    free(pg);
    free(full);
}

/* trn_prob_global_map reads the occupancy from the distance volume (D = 0):
 * it must equal trn_prob_global on the occupancy trn_map_build made. */
static void test_map_variant_equals_occupancy(void **state)
{
    const int n = 64;
    float *dem = malloc(sizeof(float) * n * n), *hp = malloc(sizeof(float) * n * n);
    float *pg = malloc(sizeof(float) * n * n * 16);
    uint8_t *occ;
    selworld_t w;
    trn_sigma_model_t gm;
    trn_xy_t s = {20.0f, 40.0f};
    trn_grid_f32_t gd, gh;
    size_t hb, i, nvox;
    void *hws;
    int x, y;
    (void)state;
    for (y = 0; y < n; ++y) {
        for (x = 0; x < n; ++x) { /* bumps and a ramp */
            dem[y * n + x] = (float)(0.3 * sin(0.4 * x) * cos(0.3 * y) + 0.01 * x);
        }
    }
    trn_sigma_global_default(&gm);
    assert_int_equal(selworld_init(&w, n, dem, &gm, &s, 1), TRN_OK);
    nvox = (size_t)n * n * w.map.dist.nz;
    occ = malloc(nvox);
    assert_int_equal(trn_grid_f32_init(&gd, dem, (size_t)n * n, n, n), TRN_OK);
    assert_int_equal(trn_grid_f32_init(&gh, hp, (size_t)n * n, n, n), TRN_OK);
    hb = trn_highpass_workspace_bytes(n, n);
    hws = selworld_alloc(hb);
    assert_int_equal(trn_highpass(&gd, &w.cfg.terrain, &gh, hws, hb), TRN_OK);
    {
        trn_vol_u8_t v;
        assert_int_equal(trn_vol_u8_init(&v, occ, nvox, n, n, w.map.dist.nz), TRN_OK);
        assert_int_equal(trn_occupancy(&gh, &w.cfg.terrain, &v, NULL), TRN_OK);
    }
    run_global(occ, n, n, w.map.dist.nz, &gm, &s, 1, pg);
    for (i = 0; i < nvox; ++i) {
        assert_true((occ[i] != 0) == (w.map.dist.data[i] == 0));
        assert_true(pg[i] == w.pg.data[i]);
    }
    free(hws);
    free(occ);
    free(dem);
    free(hp);
    free(pg);
    selworld_free(&w);
}


/* ---- trn_prob_global_raster: a per-cell error raster (metres) -------------- */

/* Kernel index by the obvious rule: sigma in cells, nearest table sigma in
 * log space (computed with logs, not trn_kernel_pick). */
static int log_nearest(const trn_kernels_t *k, double sig_cells)
{
    double best = HUGE_VAL;
    int j, bj = 0;
    if (!(sig_cells > 0.0)) {
        return 0;
    }
    for (j = 0; j < TRN_KERNEL_COUNT; ++j) {
        const double dl = fabs(log(sig_cells) - log((double)k->sigma_cells[j]));
        if (dl < best) {
            best = dl;
            bj = j;
        }
    }
    return bj;
}

/* The separable scatter written out per source: source (x, y) puts
 * t_j(x,y)[a] into the intermediate cell (x + a, y), which spreads it along y
 * with its own kernel: out(x + a, y + b) += t_j(x,y)[a] t_j(x+a,y)[b]. */
static void direct_separable(const trn_kernels_t *k, const uint8_t *occ, const uint8_t *kidx,
                             int nx, int ny, int nz, double *out)
{
    int x, y, z, a, b;
    memset(out, 0, sizeof(double) * (size_t)nx * ny * nz);
    for (z = 0; z < nz; ++z) {
        for (y = 0; y < ny; ++y) {
            for (x = 0; x < nx; ++x) {
                const int j = kidx[y * nx + x], r = k->radius[j];
                if (!occ[((size_t)z * ny + y) * nx + x]) {
                    continue;
                }
                for (a = -r; a <= r; ++a) {
                    int ji, ri;
                    if (x + a < 0 || x + a >= nx) {
                        continue;
                    }
                    ji = kidx[y * nx + x + a];
                    ri = k->radius[ji];
                    for (b = -ri; b <= ri; ++b) {
                        if (y + b < 0 || y + b >= ny) {
                            continue;
                        }
                        out[((size_t)z * ny + y + b) * nx + x + a] +=
                            (double)k->taps[j][TRN_KERNEL_MAX_RADIUS + a] *
                            (double)k->taps[ji][TRN_KERNEL_MAX_RADIUS + b];
                    }
                }
            }
        }
    }
}

/* A DEM with rocks of several sizes on a ramp: occupancy in several bins. */
static void raster_world(selworld_t *w, int n, const trn_sigma_model_t *gm, const trn_xy_t *s)
{
    float *dem = malloc(sizeof(float) * n * n);
    int x, y;
    assert_non_null(dem);
    for (y = 0; y < n; ++y) {
        for (x = 0; x < n; ++x) {
            dem[y * n + x] = (float)(0.25 * sin(0.45 * x) * cos(0.35 * y) +
                                     0.12 * sin(1.3 * x + 0.7 * y) + 0.005 * x);
        }
    }
    assert_int_equal(selworld_init(w, n, dem, gm, s, 1), TRN_OK);
    free(dem);
}

static void test_raster_equals_direct_scatter(void **state)
{
    const int n = 96;
    const float cell = 0.1f;
    trn_sigma_model_t gm = {0.02f, 0.004f};
    trn_xy_t s = {-10.0f, -10.0f};
    selworld_t w;
    float *sg, *pg;
    uint8_t *kidx, *occ;
    double *ref, *ref2d, worst = 0.0, worst2d = 0.0;
    trn_grid_f32_t g;
    trn_vol_f32_t p;
    trn_rng_t r;
    size_t wb, i, nvox;
    void *ws;
    int x, y, used[TRN_KERNEL_COUNT] = {0}, nused = 0, n_raster = 0;
    (void)state;
    raster_world(&w, n, &gm, &s);
    nvox = (size_t)n * n * w.map.dist.nz;
    sg = malloc(sizeof(float) * n * n);
    kidx = malloc((size_t)n * n);
    occ = malloc(nvox);
    pg = malloc(sizeof(float) * nvox);
    ref = malloc(sizeof(double) * nvox);
    ref2d = malloc(sizeof(double) * nvox);
    trn_rng_seed(&r, 12);
    for (y = 0; y < n; ++y) {
        for (x = 0; x < n; ++x) {
            double sig;
            float v;
            /* blocks of 8 x 8 cells: a third NaN (the model), the rest raster
             * values log-uniform over 0.03 .. 2 m, a few 0 and a few huge */
            const int blk = ((x / 8) * 7 + (y / 8) * 3) % 3;
            if (blk == 0) {
                v = NAN;
            } else if (x % 17 == 3 && y % 13 == 5) {
                v = 0.0f;
            } else if (x % 19 == 7 && y % 11 == 2) {
                v = 3.0e38f;
            } else {
                double jj;
                do { /* keep clear of the boundaries between two kernels */
                    v = (float)(0.03 * exp(trn_rng_unit(&r) * log(2.0 / 0.03)));
                    jj = 2.0 * log2((double)v / (double)cell / (double)w.k.sigma0_cells);
                } while (fabs(jj - floor(jj) - 0.5) < 1e-3);
            }
            sg[y * n + x] = v;
            if (isnan(v)) {
                const double ex = (float)x - s.x_cells, ey = (float)y - s.y_cells;
                sig = (0.02 + 0.004 * (ex * ex + ey * ey) * 0.01) / 0.1;
            } else {
                sig = (double)v / (double)cell;
                ++n_raster;
            }
            kidx[y * n + x] = (uint8_t)log_nearest(&w.k, sig);
            if (!used[kidx[y * n + x]]) {
                used[kidx[y * n + x]] = 1;
                ++nused;
            }
        }
    }
    assert_true(nused == TRN_KERNEL_COUNT);
    assert_true(n_raster > n * n / 2);
    for (i = 0; i < nvox; ++i) {
        occ[i] = w.map.dist.data[i] == 0;
    }
    assert_int_equal(trn_grid_f32_init(&g, sg, (size_t)n * n, n, n), TRN_OK);
    p.data = pg;
    p.nx = n;
    p.ny = n;
    p.nz = w.map.dist.nz;
    wb = trn_prob_global_workspace_bytes(n, n);
    ws = selworld_alloc(wb);
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &g, &w.map, &p, ws, wb), TRN_OK);
    direct_separable(&w.k, occ, kidx, n, n, p.nz, ref);
    direct_scatter_k(&w.k, occ, kidx, n, n, p.nz, ref2d);
    for (i = 0; i < nvox; ++i) {
        worst = fmax(worst, fabs((double)pg[i] - ref[i]));
        worst2d = fmax(worst2d, fabs((double)pg[i] - ref2d[i]));
    }
    printf("error raster (%d of %d cells from the raster, all %d kernels): worst |core - direct "
           "per-source separable| = %.3g, |core - direct 2-D| = %.3g\n",
           n_raster, n * n, nused, worst, worst2d);
    /* The core is exactly the per-source separable scatter (float rounding).
     * Against a per-source 2-D Gaussian (the source's kernel in y too) it
     * differs where neighbouring cells' errors differ: this raster changes
     * kernel from cell to cell (measured 0.36), unlike the model's smooth
     * sigma (0.0155 above); printed, not asserted (docs/modules/spread.md). */
    assert_true(worst < CONST_TOL);
    free(ws);
    free(sg);
    free(kidx);
    free(occ);
    free(pg);
    free(ref);
    free(ref2d);
    selworld_free(&w);
}

/* An all-NaN raster is the model (bitwise); a constant raster is a model with
 * that constant and no range term; a strided view reads the same cells. */
static void test_raster_nan_and_constant(void **state)
{
    const int n = 64;
    trn_sigma_model_t gm, cm = {0.25f, 0.0f};
    trn_xy_t s = {20.0f, 40.0f};
    selworld_t w;
    float *sg = malloc(sizeof(float) * (n + 5) * n), *pg, *pm;
    trn_grid_f32_t g;
    trn_vol_f32_t p, q;
    size_t wb = trn_prob_global_workspace_bytes(n, n), i, nvox;
    void *ws = selworld_alloc(wb);
    int x, y;
    (void)state;
    trn_sigma_global_default(&gm);
    raster_world(&w, n, &gm, &s);
    nvox = (size_t)n * n * w.map.dist.nz;
    pg = malloc(sizeof(float) * nvox);
    pm = malloc(sizeof(float) * nvox);
    p.data = pg;
    q.data = pm;
    p.nx = q.nx = n;
    p.ny = q.ny = n;
    p.nz = q.nz = w.map.dist.nz;
    for (i = 0; i < (size_t)(n + 5) * n; ++i) {
        sg[i] = NAN;
    }
    assert_int_equal(trn_grid_f32_init(&g, sg, (size_t)n * n, n, n), TRN_OK);
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &g, &w.map, &p, ws, wb), TRN_OK);
    for (i = 0; i < nvox; ++i) {
        assert_true(pg[i] == w.pg.data[i]);
    }
    /* strided: rows of n + 5, the 5 extra cells hold junk the core must not read */
    g.stride = n + 5;
    for (y = 0; y < n; ++y) {
        for (x = 0; x < n + 5; ++x) {
            sg[(size_t)y * (n + 5) + x] = x < n ? 0.25f : -7.0f;
        }
    }
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &g, &w.map, &p, ws, wb), TRN_OK);
    assert_int_equal(trn_prob_global_map(&w.k, &cm, &s, 1, &w.map, &q, ws, wb), TRN_OK);
    for (i = 0; i < nvox; ++i) {
        assert_true(pg[i] == pm[i]);
    }
    free(ws);
    free(sg);
    free(pg);
    free(pm);
    selworld_free(&w);
}

/* One assertion per documented status of trn_prob_global_raster. */
static void test_raster_statuses(void **state)
{
    const int n = 32;
    trn_sigma_model_t gm, bad;
    trn_xy_t s = {16.0f, 16.0f}, sn = {NAN, 1.0f};
    selworld_t w;
    float sg[32 * 32], *pg;
    trn_grid_f32_t g, gs;
    trn_vol_f32_t p;
    size_t wb = trn_prob_global_workspace_bytes(n, n), i;
    unsigned char *ws = selworld_alloc(wb + 16u);
    (void)state;
    trn_sigma_global_default(&gm);
    bad = gm;
    bad.k_per_m = -1.0f;
    raster_world(&w, n, &gm, &s);
    pg = malloc(sizeof(float) * (size_t)n * n * w.map.dist.nz);
    p.data = pg;
    p.nx = n;
    p.ny = n;
    p.nz = w.map.dist.nz;
    for (i = 0; i < (size_t)n * n; ++i) {
        sg[i] = i % 3 == 0 ? NAN : 0.05f;
    }
    assert_int_equal(trn_grid_f32_init(&g, sg, (size_t)n * n, n, n), TRN_OK);
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &g, &w.map, &p, ws, wb), TRN_OK);
    /* TRN_E_NULL */
    assert_int_equal(trn_prob_global_raster(NULL, &gm, &s, 1, &g, &w.map, &p, ws, wb), TRN_E_NULL);
    assert_int_equal(trn_prob_global_raster(&w.k, NULL, &s, 1, &g, &w.map, &p, ws, wb), TRN_E_NULL);
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, NULL, 1, &g, &w.map, &p, ws, wb),
                     TRN_E_NULL);
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, NULL, &w.map, &p, ws, wb),
                     TRN_E_NULL);
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &g, NULL, &p, ws, wb), TRN_E_NULL);
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &g, &w.map, NULL, ws, wb),
                     TRN_E_NULL);
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &g, &w.map, &p, NULL, wb),
                     TRN_E_NULL);
    gs = g;
    gs.data = NULL;
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &gs, &w.map, &p, ws, wb), TRN_E_NULL);
    p.data = NULL;
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &g, &w.map, &p, ws, wb), TRN_E_NULL);
    p.data = pg;
    /* TRN_E_ARG: the model, the cell's sensor, a raster cell */
    assert_int_equal(trn_prob_global_raster(&w.k, &bad, &s, 1, &g, &w.map, &p, ws, wb), TRN_E_ARG);
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &sn, 1, &g, &w.map, &p, ws, wb), TRN_E_ARG);
    sg[5] = -0.01f;
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &g, &w.map, &p, ws, wb), TRN_E_ARG);
    sg[5] = INFINITY;
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &g, &w.map, &p, ws, wb), TRN_E_ARG);
    sg[5] = 0.05f;
    /* TRN_E_SIZE: raster size, a bad view, pg's size, the sensor count */
    gs = g;
    gs.width = n - 1;
    gs.stride = n - 1;
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &gs, &w.map, &p, ws, wb), TRN_E_SIZE);
    gs = g;
    gs.height = n - 1;
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &gs, &w.map, &p, ws, wb), TRN_E_SIZE);
    gs = g;
    gs.stride = n - 1;
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &gs, &w.map, &p, ws, wb), TRN_E_SIZE);
    p.nz = 1;
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &g, &w.map, &p, ws, wb), TRN_E_SIZE);
    p.nz = w.map.dist.nz;
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 0, &g, &w.map, &p, ws, wb), TRN_E_SIZE);
    assert_int_equal(
        trn_prob_global_raster(&w.k, &gm, &s, TRN_SPREAD_MAX_SENSORS + 1u, &g, &w.map, &p, ws, wb),
        TRN_E_SIZE);
    /* TRN_E_WORKSPACE: short, misaligned */
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &g, &w.map, &p, ws, wb - 1),
                     TRN_E_WORKSPACE);
    assert_int_equal(trn_prob_global_raster(&w.k, &gm, &s, 1, &g, &w.map, &p, ws + 4, wb),
                     TRN_E_WORKSPACE);
    free(ws);
    free(pg);
    selworld_free(&w);
}

static void test_bad_inputs(void **state)
{
    const int nx = 16, ny = 12, nz = 2;
    uint8_t occ[16 * 12 * 2] = {0}, idx[16 * 12];
    float pgd[16 * 12 * 2];
    trn_vol_u8_t v = {occ, nx, ny, nz};
    trn_vol_f32_t p = {pgd, nx, ny, nz};
    trn_sigma_model_t m, bad;
    trn_xy_t s = {1.0f, 1.0f}, sn = {NAN, 0.0f};
    trn_window_t win = {0, 0, nx - 1, ny - 1}, empty = {3, 0, 2, 5};
    static trn_kernels_t unbuilt;
    size_t wb = trn_prob_global_workspace_bytes(nx, ny);
    void *ws = selworld_alloc(wb);
    (void)state;
    trn_sigma_global_default(&m);
    assert_int_equal(trn_sigma_model_check(NULL), TRN_E_NULL);
    bad = m;
    bad.sigma_min_m = NAN;
    assert_int_equal(trn_sigma_model_check(&bad), TRN_E_ARG);
    bad = m;
    bad.k_per_m = -1.0f;
    assert_int_equal(trn_sigma_model_check(&bad), TRN_E_ARG);
    assert_int_equal(trn_sigma_model_check(&m), TRN_OK);

    assert_int_equal(trn_spread_kernel_map(&g_k, &m, 0.1f, &s, 1, &win, idx, sizeof idx), TRN_OK);
    assert_int_equal(trn_spread_kernel_map(NULL, &m, 0.1f, &s, 1, &win, idx, sizeof idx),
                     TRN_E_NULL);
    assert_int_equal(trn_spread_kernel_map(&g_k, &m, 0.1f, NULL, 1, &win, idx, sizeof idx),
                     TRN_E_NULL);
    assert_int_equal(trn_spread_kernel_map(&unbuilt, &m, 0.1f, &s, 1, &win, idx, sizeof idx),
                     TRN_E_ARG);
    assert_int_equal(trn_spread_kernel_map(&g_k, &bad, 0.1f, &s, 1, &win, idx, sizeof idx),
                     TRN_E_ARG);
    assert_int_equal(trn_spread_kernel_map(&g_k, &m, -0.1f, &s, 1, &win, idx, sizeof idx),
                     TRN_E_ARG);
    assert_int_equal(trn_spread_kernel_map(&g_k, &m, 0.1f, &sn, 1, &win, idx, sizeof idx),
                     TRN_E_ARG);
    assert_int_equal(trn_spread_kernel_map(&g_k, &m, 0.1f, &s, 0, &win, idx, sizeof idx),
                     TRN_E_SIZE);
    assert_int_equal(trn_spread_kernel_map(&g_k, &m, 0.1f, &s, TRN_SPREAD_MAX_SENSORS + 1u, &win,
                                           idx, sizeof idx),
                     TRN_E_SIZE);
    assert_int_equal(trn_spread_kernel_map(&g_k, &m, 0.1f, &s, 1, &empty, idx, sizeof idx),
                     TRN_E_SIZE);
    assert_int_equal(trn_spread_kernel_map(&g_k, &m, 0.1f, &s, 1, &win, idx, sizeof idx - 1),
                     TRN_E_WORKSPACE);

    assert_int_equal(trn_prob_global(&g_k, &m, 0.1f, &s, 1, &v, &p, ws, wb), TRN_OK);
    assert_int_equal(trn_prob_global(&g_k, &m, 0.1f, &s, 1, NULL, &p, ws, wb), TRN_E_NULL);
    assert_int_equal(trn_prob_global(&g_k, &m, 0.1f, &s, 1, &v, NULL, ws, wb), TRN_E_NULL);
    assert_int_equal(trn_prob_global(&g_k, &m, 0.1f, &s, 1, &v, &p, NULL, wb), TRN_E_NULL);
    assert_int_equal(trn_prob_global(&g_k, &bad, 0.1f, &s, 1, &v, &p, ws, wb), TRN_E_ARG);
    assert_int_equal(trn_prob_global(&g_k, &m, 0.1f, &sn, 1, &v, &p, ws, wb), TRN_E_ARG);
    assert_int_equal(trn_prob_global(&g_k, &m, 0.1f, &s, 0, &v, &p, ws, wb), TRN_E_SIZE);
    p.nz = 1;
    assert_int_equal(trn_prob_global(&g_k, &m, 0.1f, &s, 1, &v, &p, ws, wb), TRN_E_SIZE);
    p.nz = nz;
    v.nx = 0;
    assert_int_equal(trn_prob_global(&g_k, &m, 0.1f, &s, 1, &v, &p, ws, wb), TRN_E_SIZE);
    v.nx = nx;
    assert_int_equal(trn_prob_global(&g_k, &m, 0.1f, &s, 1, &v, &p, ws, wb - 1), TRN_E_WORKSPACE);
    assert_int_equal(trn_prob_global_map(&g_k, &m, &s, 1, NULL, &p, ws, wb), TRN_E_NULL);
    assert_int_equal(trn_prob_global_workspace_bytes(0, 5), 0u);
    assert_int_equal(trn_prob_local_workspace_bytes(&g_k, &empty), 0u);
    free(ws);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_constant_sigma_equals_2d),
        cmocka_unit_test(test_varying_sigma_and_mass),
        cmocka_unit_test(test_local_region_equals_whole),
        cmocka_unit_test(test_map_variant_equals_occupancy),
        cmocka_unit_test(test_raster_equals_direct_scatter),
        cmocka_unit_test(test_raster_nan_and_constant),
        cmocka_unit_test(test_raster_statuses),
        cmocka_unit_test(test_bad_inputs),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
