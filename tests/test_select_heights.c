/* SPDX-License-Identifier: Apache-2.0 */
/* test_select_heights.c - the height matcher's prediction in trn_select
 * (select.h, docs/method.md 4, "The height matcher's prediction").
 *
 * Oracles: (1) slow code written out here that forms each candidate's
 * information from the map's heights cell by cell in double, with the
 * gradients unquantized (the core quantizes them to 2^-16 m per cell, hence
 * the relative tolerance); (2) the analytic covariance of a paraboloid,
 * whose central differences and representation residual are exact;
 * (3) flat ground and a plane, which no shift can be told from a height
 * offset on; (4) trn_field against trn_field_fast, bit for bit. Then the
 * statuses of bad input. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "selworld.h"
#include "trn/trn.h"

#define N 72
#define CELL 0.1f

typedef struct {
    float dem[N * N];
    trn_grid_f32_t g;
    trn_map_cfg_t cfg;
    trn_map_t map;
    void *buf;
} hmap_t;

static float g_noise_k = 0.002f; /* the noise model's range term of the next hmap_init */

/* A heights map of dem (N x N). */
static void hmap_init(hmap_t *h, const float *dem)
{
    size_t mb;
    memcpy(h->dem, dem, sizeof h->dem);
    assert_int_equal(trn_grid_f32_init(&h->g, h->dem, (size_t)N * N, N, N), TRN_OK);
    trn_map_cfg_default(&h->cfg);
    h->cfg.terrain.cell_m = CELL;
    h->cfg.match = TRN_MATCH_HEIGHTS;
    h->cfg.noise_m = 0.01f;
    h->cfg.noise_k_per_m = g_noise_k;
    mb = trn_map_bytes(&h->cfg, N, N);
    assert_true(mb > 0u);
    h->buf = selworld_alloc(mb);
    assert_non_null(h->buf);
    assert_int_equal(trn_map_build(&h->map, &h->cfg, &h->g, h->buf, mb), TRN_OK);
}

static uint64_t g_rng;
static double urand(void)
{
    g_rng = g_rng * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(g_rng >> 11) / 9007199254740992.0;
}

/* Rough ground: bumps of random size on a gentle wave; holes (NaN) when asked. */
static void rough_dem(float *dem, uint64_t seed, int holes)
{
    double bx[40], by[40], ba[40], bs[40];
    int i, x, y;
    g_rng = seed;
    for (i = 0; i < 40; ++i) {
        bx[i] = urand() * N;
        by[i] = urand() * N;
        ba[i] = 0.05 + 0.3 * urand();
        bs[i] = 1.5 + 4.0 * urand();
    }
    for (y = 0; y < N; ++y) {
        for (x = 0; x < N; ++x) {
            double v = 0.2 * sin(0.11 * x) * cos(0.07 * y);
            for (i = 0; i < 40; ++i) {
                const double dx = x - bx[i], dy = y - by[i];
                v += ba[i] * exp(-(dx * dx + dy * dy) / (2.0 * bs[i] * bs[i]));
            }
            dem[y * N + x] = (float)v;
        }
    }
    for (i = 0; holes && i < 25; ++i) {
        x = (int)(urand() * N);
        y = (int)(urand() * N);
        dem[y * N + x] = NAN;
    }
}

static void small_cfg(trn_select_cfg_t *c)
{
    trn_select_cfg_default(c);
    c->min_range_m = 0.5f;
    c->max_range_m = 2.5f;
    c->footprint_radius_m = 0.3f;
    c->patch_m = 0.9f;
    c->stride_cells = 1;
    c->min_separation_m = 0.45f;
}

typedef struct {
    trn_candidate_t *cands;
    size_t cap, ranked[8];
    trn_select_result_t res;
    void *ws;
} run_t;

static trn_status_t run_select(const hmap_t *h, const trn_select_cfg_t *c, float rx, float ry,
                               float heading, run_t *r)
{
    const size_t wb = trn_select_workspace_bytes(c, &h->map, NULL);
    trn_rover_t rv;
    assert_true(wb > 0u);
    r->cap = trn_select_max_candidates(c, CELL);
    r->cands = calloc(r->cap, sizeof *r->cands);
    r->ws = selworld_alloc(wb);
    assert_non_null(r->cands);
    assert_non_null(r->ws);
    rv.pos.x_cells = rx;
    rv.pos.y_cells = ry;
    rv.heading_rad = heading;
    return trn_select(&h->map, NULL, NULL, c, &rv, r->cands, r->cap, r->ranked, 8u, &r->res, r->ws,
                      wb);
}

static void run_free(run_t *r)
{
    free(r->cands);
    free(r->ws);
}

/* The slow prediction of candidate c: the 2 x 2 (or, heading searched, 3 x 3)
 * profiled information summed cell by cell, each cell weighted by its own
 * variance, its covariance in m^2. Returns 0 when uninformative. */
static int slow_cov(const hmap_t *h, const trn_select_cfg_t *sc, const trn_candidate_t *c,
                    double rx, double ry, double cov[3])
{
    const int half = (int)floor(sc->patch_m / CELL + 0.5) / 2;
    const double ms = sc->map_sigma_m;
    /* a binned local map of pn points a cell: the noise over pn, the centroid's jitter */
    const double pn = sc->points_per_cell > 0.0f ? (double)sc->points_per_cell : 1.0;
    const double jit = sc->points_per_cell > 0.0f ? 1.0 / (12.0 * pn) : 0.0;
    double s[3] = {0, 0, 0}, ss[3][3], n = 0, sw = 0, a, b, d, det, sh, raw;
    double inv[3];
    int x, y, i, j;
    memset(ss, 0, sizeof ss);
    for (y = c->y - half; y <= c->y + half; ++y) {
        for (x = c->x - half; x <= c->x + half; ++x) {
            const double v = h->dem[y * N + x], l = h->dem[y * N + x - 1],
                         r = h->dem[y * N + x + 1], dn = h->dem[(y - 1) * N + x],
                         up = h->dem[(y + 1) * N + x];
            const double ux = (x - rx) * CELL, uy = (y - ry) * CELL;
            double j3[3], e, sd, w;
            if (!(isfinite(v) && isfinite(l) && isfinite(r) && isfinite(dn) && isfinite(up))) {
                continue;
            }
            j3[0] = 0.5 * (r - l);
            j3[1] = 0.5 * (up - dn);
            /* each cell's own variance: the noise at its range (of the mean of pn points, plus
             * their centroid's jitter), the map's error, e^2 / 4 */
            e = v - 0.25 * (l + r + dn + up);
            sd = h->cfg.noise_m + h->cfg.noise_k_per_m * (ux * ux + uy * uy);
            w = 1.0 /
                (sd * sd / pn + jit * (j3[0] * j3[0] + j3[1] * j3[1]) + ms * ms + 0.25 * e * e);
            j3[2] = j3[1] * (x - rx) - j3[0] * (y - ry);
            for (i = 0; i < 3; ++i) {
                s[i] += w * j3[i];
                for (j = 0; j < 3; ++j) {
                    ss[i][j] += w * j3[i] * j3[j];
                }
            }
            sw += w;
            n += 1.0;
        }
    }
    if (n < 3) {
        return 0;
    }
    raw = ss[0][0] + ss[1][1];
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) {
            ss[i][j] -= s[i] * s[j] / sw;
        }
    }
    a = ss[0][0];
    b = ss[0][1];
    d = ss[1][1];
    det = a * d - b * b;
    if (!(det > 1e-12 * raw * raw)) {
        return 0;
    }
    inv[0] = d / det;
    inv[1] = a / det;
    inv[2] = -b / det;
    sh = sc->sigma_heading_rad;
    if (sc->heading_search == 1 && sh > 0.0) {
        const double bx = ss[0][2], by = ss[1][2], cc = ss[2][2];
        const double gx = inv[0] * bx + inv[2] * by, gy = inv[2] * bx + inv[1] * by;
        double info = cc - (bx * gx + by * gy), den;
        info = info > 0 ? info : 0;
        den = 1.0 / (sh * sh) + info;
        inv[0] += gx * gx / den;
        inv[1] += gy * gy / den;
        inv[2] += gx * gy / den;
    } else if (sh > 0.0) {
        const double dx = c->x - rx, dy = c->y - ry;
        inv[0] += sh * sh * dy * dy;
        inv[1] += sh * sh * dx * dx;
        inv[2] -= sh * sh * dx * dy;
    }
    for (i = 0; i < 3; ++i) {
        cov[i] = inv[i] * (double)CELL * (double)CELL;
    }
    return 1;
}

/* Every candidate against the slow prediction; returns the worst relative
 * difference of the covariance (to its trace). */
static double against_slow(const hmap_t *h, const trn_select_cfg_t *sc, float rx, float ry)
{
    run_t r;
    size_t i, ninf = 0;
    double worst = 0.0;
    trn_status_t st = run_select(h, sc, rx, ry, 0.3f, &r);
    assert_int_equal(st, TRN_OK);
    assert_true(r.res.n_candidates > 100u);
    for (i = 0; i < r.res.n_candidates; ++i) {
        const trn_candidate_t *c = &r.cands[i];
        double cov[3];
        int inf = slow_cov(h, sc, c, rx, ry, cov);
        assert_int_equal(inf, c->informative);
        if (inf) {
            const double tr = cov[0] + cov[1];
            int k;
            for (k = 0; k < 3; ++k) {
                const double rel = fabs(cov[k] - c->cov_m2[k]) / tr;
                worst = rel > worst ? rel : worst;
            }
            assert_true(fabs(c->uncertainty_m - sqrt(tr)) <= 1e-4 * sqrt(tr));
            ++ninf;
        }
    }
    assert_true(ninf > 100u);
    /* ranked[0] is the smallest uncertainty */
    for (i = 0; i < r.res.n_candidates; ++i) {
        if (r.cands[i].informative) {
            assert_true(r.cands[r.res.best].uncertainty_m <= r.cands[i].uncertainty_m);
        }
    }
    run_free(&r);
    return worst;
}

static void test_against_slow(void **state)
{
    hmap_t *h = malloc(sizeof *h);
    trn_select_cfg_t sc;
    double w;
    (void)state;
    rough_dem(h->dem, 7u, 1);
    hmap_init(h, h->dem);
    small_cfg(&sc);
    w = against_slow(h, &sc, 35.0f, 33.4f);
    print_message("worst relative difference, x-y: %.3g\n", w);
    assert_true(w < 1e-4);
    sc.map_sigma_m = 0.05f;
    sc.sigma_heading_rad = 0.03f;
    w = against_slow(h, &sc, 30.3f, 40.0f);
    assert_true(w < 1e-4);
    sc.heading_search = 1;
    w = against_slow(h, &sc, 30.3f, 40.0f);
    print_message("worst relative difference, heading searched: %.3g\n", w);
    assert_true(w < 1e-4);
    /* a binned local map: 4 and 1 points a cell, with the heading searched and without */
    sc.points_per_cell = 4.0f;
    w = against_slow(h, &sc, 30.3f, 40.0f);
    assert_true(w < 1e-4);
    sc.heading_search = 0;
    sc.points_per_cell = 1.0f;
    w = against_slow(h, &sc, 35.0f, 33.4f);
    print_message("worst relative difference, 1 point a cell: %.3g\n", w);
    assert_true(w < 1e-4);
    free(h->buf);
    free(h);
}

/* A binned local map's prediction (points_per_cell n): 0 is the unbinned
 * prediction bit for bit. Each cell's variance is s^2 / n + |g|^2 / (12 n)
 * + map + e^2 / 4; on a paraboloid (e = -c at every cell) with no range
 * term and no map error that is V_i / n + c^2 / 4, V_i = s0^2 + |g_i|^2 /
 * 12. Each cell's weight at n = 4 is then 4 (V_i + c^2 / 4) / (V_i + c^2)
 * times its weight at n = 1, between 4 (s0^2 + c^2 / 4) / (s0^2 + c^2) and
 * 4, and the profiled information (a minimum over the offset of weighted
 * squares) keeps the bounds: the covariance at n = 1 over that at n = 4
 * lies between them. Left out, the jitter's 1 / n takes the ratio towards
 * 1 where |g|^2 / 12 outweighs s0^2 (most cells here). Against the unbinned
 * s0^2 the jitter widens every candidate. */
static void test_points_per_cell(void **state)
{
    hmap_t *h = malloc(sizeof *h);
    float *dem = malloc(sizeof(float) * N * N);
    trn_select_cfg_t sc, s0;
    run_t r0, r1, r4, rz;
    size_t i;
    int x, y;
    (void)state;
    rough_dem(h->dem, 7u, 0);
    hmap_init(h, h->dem);
    small_cfg(&s0);
    sc = s0;
    sc.points_per_cell = 0.0f;
    assert_int_equal(run_select(h, &s0, 35.0f, 33.4f, 0.0f, &r0), TRN_OK);
    assert_int_equal(run_select(h, &sc, 35.0f, 33.4f, 0.0f, &rz), TRN_OK);
    assert_int_equal(r0.res.n_candidates, rz.res.n_candidates);
    assert_memory_equal(r0.cands, rz.cands, r0.res.n_candidates * sizeof *r0.cands);
    run_free(&rz);
    run_free(&r0);
    free(h->buf);
    for (y = 0; y < N; ++y) {
        for (x = 0; x < N; ++x) {
            dem[y * N + x] = (float)(0.001 * ((x - 30) * (x - 30) + (y - 41) * (y - 41)));
        }
    }
    g_noise_k = 0.0f;
    hmap_init(h, dem);
    g_noise_k = 0.002f;
    small_cfg(&sc);
    sc.map_sigma_m = 0.0f;
    sc.points_per_cell = 1.0f;
    assert_int_equal(run_select(h, &sc, 36.0f, 36.0f, 0.0f, &r1), TRN_OK);
    sc.points_per_cell = 4.0f;
    assert_int_equal(run_select(h, &sc, 36.0f, 36.0f, 0.0f, &r4), TRN_OK);
    sc.points_per_cell = 0.0f;
    assert_int_equal(run_select(h, &sc, 36.0f, 36.0f, 0.0f, &r0), TRN_OK);
    assert_int_equal(r1.res.n_candidates, r4.res.n_candidates);
    assert_true(r1.res.n_informative > 100u);
    for (i = 0; i < r1.res.n_candidates; ++i) {
        const trn_candidate_t *a = &r1.cands[i], *b = &r4.cands[i], *c = &r0.cands[i];
        const double c2 = 0.001 * 0.001, s02 = (double)0.01f * (double)0.01f;
        const double lo = 4.0 * (s02 + 0.25 * c2) / (s02 + c2); /* 3.970 */
        int k;
        if (!a->informative) {
            continue;
        }
        assert_true(b->informative);
        for (k = 0; k < 2; ++k) {
            assert_true(a->cov_m2[k] / b->cov_m2[k] >= lo * (1.0 - 1e-6));
            assert_true(a->cov_m2[k] / b->cov_m2[k] <= 4.0 * (1.0 + 1e-6));
        }
        /* the jitter widens the prediction against one unbinned measurement a cell */
        assert_true(a->cov_m2[0] > c->cov_m2[0] && a->cov_m2[1] > c->cov_m2[1]);
    }
    run_free(&r0);
    run_free(&r1);
    run_free(&r4);
    free(h->buf);
    free(dem);
    free(h);
}

/* The expected ln L at the nine offsets is the quadratic whose eq. 6 fit
 * gives the covariance back. */
static void test_ll_is_the_quadratic(void **state)
{
    hmap_t *h = malloc(sizeof *h);
    trn_select_cfg_t sc;
    run_t r;
    size_t i, checked = 0;
    (void)state;
    rough_dem(h->dem, 11u, 0);
    hmap_init(h, h->dem);
    small_cfg(&sc);
    assert_int_equal(run_select(h, &sc, 36.0f, 36.0f, 0.0f, &r), TRN_OK);
    for (i = 0; i < r.res.n_candidates; ++i) {
        trn_peak_t pk;
        const trn_candidate_t *c = &r.cands[i];
        if (!c->informative) {
            continue;
        }
        assert_true(c->ll[4] == 0.0);
        if (trn_peak_fit(c->ll, &pk) == TRN_OK) {
            const double s = c->cov_m2[0] + c->cov_m2[1];
            assert_true(fabs(pk.var_x * CELL * CELL - c->cov_m2[0]) <= 1e-9 * s);
            assert_true(fabs(pk.cov_xy * CELL * CELL - c->cov_m2[2]) <= 1e-9 * s);
            ++checked;
        }
    }
    assert_true(checked > 100u);
    run_free(&r);
    free(h->buf);
    free(h);
}

/* h = c ((x - x0)^2 + (y - y0)^2): gx = 2 c (x - x0) exactly, e = -c, so with
 * a noise without range term (every cell's variance s^2 = s0^2 + S0^2 +
 * c^2 / 4) the profiled information of a P x P patch (P = 2 m + 1) is
 * 4 c^2 P m (m + 1) (2 m + 1) / 3 / s^2 on each axis, none across. */
static void test_paraboloid(void **state)
{
    hmap_t *h = malloc(sizeof *h);
    float *dem = malloc(sizeof(float) * N * N);
    const double cc = 0.001;
    trn_select_cfg_t sc;
    run_t r;
    size_t i;
    int x, y, m;
    double info;
    (void)state;
    for (y = 0; y < N; ++y) {
        for (x = 0; x < N; ++x) {
            dem[y * N + x] = (float)(cc * ((x - 30) * (x - 30) + (y - 41) * (y - 41)));
        }
    }
    g_noise_k = 0.0f;
    hmap_init(h, dem);
    g_noise_k = 0.002f;
    small_cfg(&sc);
    sc.map_sigma_m = 0.03f;
    assert_int_equal(run_select(h, &sc, 36.0f, 36.0f, 0.0f, &r), TRN_OK);
    m = r.res.patch_cells / 2;
    info = 4.0 * cc * cc * (2 * m + 1) * m * (m + 1) * (2 * m + 1) / 3.0;
    assert_int_equal(r.res.n_informative, r.res.n_candidates);
    for (i = 0; i < r.res.n_candidates; ++i) {
        const trn_candidate_t *c = &r.cands[i];
        const double sn = (double)0.01f;
        const double var = sn * sn + (double)0.03f * (double)0.03f + 0.25 * cc * cc;
        const double want = var / info * (double)CELL * (double)CELL;
        assert_true(fabs(c->cov_m2[0] - want) <= 1e-4 * want);
        assert_true(fabs(c->cov_m2[1] - want) <= 1e-4 * want);
        assert_true(fabs(c->cov_m2[2]) <= 1e-4 * want);
    }
    run_free(&r);
    /* with the range term the noise grows with the range: the nearest candidate wins */
    free(h->buf);
    hmap_init(h, dem);
    assert_int_equal(run_select(h, &sc, 36.0f, 36.0f, 0.0f, &r), TRN_OK);
    for (i = 0; i < r.res.n_candidates; ++i) {
        assert_true(r.cands[r.res.best].range_m <= r.cands[i].range_m + 0.15f);
    }
    run_free(&r);
    free(dem);
    free(h->buf);
    free(h);
}

/* Flat ground and a plane: a shift is a height offset, nothing localizes. */
static void test_flat_and_plane(void **state)
{
    hmap_t *h = malloc(sizeof *h);
    float *dem = malloc(sizeof(float) * N * N);
    trn_select_cfg_t sc;
    run_t r;
    int x, y, k;
    (void)state;
    small_cfg(&sc);
    for (k = 0; k < 2; ++k) {
        for (y = 0; y < N; ++y) {
            for (x = 0; x < N; ++x) {
                dem[y * N + x] = k == 0 ? 1.5f : (float)(0.25 * x + 0.125 * y);
            }
        }
        hmap_init(h, dem);
        assert_int_equal(run_select(h, &sc, 36.0f, 36.0f, 0.0f, &r), TRN_E_NOTARGET);
        assert_true(r.res.n_candidates > 100u);
        assert_int_equal(r.res.n_informative, 0u);
        assert_true(isinf(r.cands[0].uncertainty_m));
        run_free(&r);
        free(h->buf);
    }
    /* one bump on the plane: only the patches that hold it localize */
    dem[36 * N + 48] += 0.5f;
    hmap_init(h, dem);
    assert_int_equal(run_select(h, &sc, 36.0f, 36.0f, 0.0f, &r), TRN_OK);
    assert_true(r.res.n_informative > 0u && r.res.n_informative < r.res.n_candidates / 4u);
    assert_true(abs(r.cands[r.res.best].x - 48) <= r.res.patch_cells / 2 &&
                abs(r.cands[r.res.best].y - 36) <= r.res.patch_cells / 2);
    run_free(&r);
    free(h->buf);
    free(dem);
    free(h);
}

/* Holes: patches with no cell whose four neighbours are known, or fewer
 * than 3, are uninformative; the rest as the slow prediction says. */
static void test_holes(void **state)
{
    hmap_t *h = malloc(sizeof *h);
    float *dem = malloc(sizeof(float) * N * N);
    trn_select_cfg_t sc;
    run_t r;
    size_t i, none = 0, few = 0, inf = 0;
    int x, y;
    (void)state;
    rough_dem(dem, 13u, 0);
    for (y = 0; y < N; ++y) {
        for (x = 0; x < N; ++x) {
            /* known only in a 9 x 9 block and along a thin cross of 3 cells */
            const int block = x >= 44 && x < 53 && y >= 30 && y < 39;
            const int cross = (x == 20 && y >= 20 && y < 23) || (y == 21 && x >= 19 && x < 22);
            if (!block && !cross) {
                dem[y * N + x] = NAN;
            }
        }
    }
    hmap_init(h, dem);
    small_cfg(&sc);
    assert_int_equal(run_select(h, &sc, 36.0f, 36.0f, 0.0f, &r), TRN_OK);
    for (i = 0; i < r.res.n_candidates; ++i) {
        const trn_candidate_t *c = &r.cands[i];
        double cov[3];
        const int want = slow_cov(h, &sc, c, 36.0, 36.0, cov);
        assert_int_equal(c->informative, want);
        inf += (size_t)want;
        none += !want && abs(c->x - 20) > 5 && abs(c->x - 48) > 5 ? 1u : 0u;
        few += !want && abs(c->x - 20) <= 4 && abs(c->y - 21) <= 4 ? 1u : 0u;
    }
    assert_true(inf > 0u && none > 0u && few > 0u);
    run_free(&r);
    free(h->buf);
    free(dem);
    free(h);
}

/* trn_field and trn_field_fast on a heights map: the same bits. */
static void test_field_same_bits(void **state)
{
    selworld_t w;
    float *dem = malloc(sizeof(float) * N * N);
    trn_sigma_model_t gm;
    trn_xy_t s = {N / 2.0f, N / 2.0f};
    trn_select_cfg_t sc;
    trn_field_cfg_t fc;
    trn_window_t area = {10, 12, 60, 58};
    const size_t n = (size_t)51 * 47;
    float *o1 = malloc(n * sizeof(float)), *o2 = malloc(n * sizeof(float));
    uint8_t *e1 = malloc(n), *e2 = malloc(n);
    trn_grid_f32_t g1, g2;
    trn_field_stats_t s1, s2;
    size_t b1, b2, mb;
    void *ws1, *ws2;
    (void)state;
    rough_dem(dem, 5u, 0);
    trn_sigma_global_default(&gm);
    assert_int_equal(selworld_init(&w, N, dem, &gm, &s, 1), TRN_OK);
    /* the same terrain as a map that matches heights */
    w.cfg.match = TRN_MATCH_HEIGHTS;
    free(w.mapbuf);
    mb = trn_map_bytes(&w.cfg, N, N);
    w.mapbuf = selworld_alloc(mb);
    assert_int_equal(trn_map_build(&w.map, &w.cfg, &w.g, w.mapbuf, mb), TRN_OK);
    small_cfg(&sc);
    sc.stride_cells = 2;
    trn_field_cfg_default(&fc);
    fc.coarse_step_cells = 8;
    b1 = trn_field_workspace_bytes(&sc, &w.map, &w.k);
    b2 = trn_field_fast_workspace_bytes(&sc, &w.map, &w.k, &w.pg);
    assert_true(b1 > 0u && b2 > 0u);
    ws1 = selworld_alloc(b1);
    ws2 = selworld_alloc(b2);
    assert_int_equal(trn_grid_f32_init(&g1, o1, n, 51, 47), TRN_OK);
    assert_int_equal(trn_grid_f32_init(&g2, o2, n, 51, 47), TRN_OK);
    assert_int_equal(
        trn_field(&w.map, &w.k, &w.pg, &sc, &fc, 0.2f, &area, &g1, e1, n, &s1, ws1, b1), TRN_OK);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.2f, &area, &g2, e2, n, &s2, ws2, b2),
        TRN_OK);
    {
        /* the sizing functions without a map: refused, also for the heading-searched prediction */
        trn_select_cfg_t hs = sc;
        hs.heading_search = 1;
        hs.sigma_heading_rad = 0.05f;
        assert_int_equal(trn_field_fast_workspace_bytes(&hs, NULL, &w.k, &w.pg), 0u);
        assert_int_equal(trn_field_workspace_bytes(&hs, NULL, &w.k), 0u);
    }
    assert_memory_equal(o1, o2, n * sizeof(float));
    assert_memory_equal(e1, e2, n);
    assert_int_equal(s1.evaluations, s2.evaluations);
    assert_true(s1.best_m == s2.best_m && isfinite(s1.best_m));
    {
        /* a rover that bins 4 points a cell: the two paths still agree, and the field differs */
        const double unbinned_best = s1.best_m;
        sc.points_per_cell = 4.0f;
        assert_int_equal(
            trn_field(&w.map, &w.k, &w.pg, &sc, &fc, 0.2f, &area, &g1, e1, n, &s1, ws1, b1),
            TRN_OK);
        assert_int_equal(
            trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.2f, &area, &g2, e2, n, &s2, ws2, b2),
            TRN_OK);
        assert_memory_equal(o1, o2, n * sizeof(float));
        assert_memory_equal(e1, e2, n);
        assert_true(s1.best_m == s2.best_m && s1.best_m != unbinned_best);
    }
    free(ws1);
    free(ws2);
    free(o1);
    free(o2);
    free(e1);
    free(e2);
    free(dem);
    selworld_free(&w);
}

/* Bad input, each class: the named status, nothing written past it. */
static void test_errors(void **state)
{
    hmap_t *h = malloc(sizeof *h);
    trn_select_cfg_t sc;
    run_t r;
    trn_rover_t rv = {{36.0f, 36.0f}, 0.0f};
    trn_map_t m;
    size_t wb, ranked[2];
    trn_select_result_t res;
    float *dem = malloc(sizeof(float) * N * N);
    int x, y;
    (void)state;
    rough_dem(h->dem, 3u, 0);
    hmap_init(h, h->dem);
    small_cfg(&sc);
    wb = trn_select_workspace_bytes(&sc, &h->map, NULL);
    r.cap = trn_select_max_candidates(&sc, CELL);
    r.cands = calloc(r.cap, sizeof *r.cands);
    r.ws = selworld_alloc(wb);
    /* the map's sigma NaN or negative */
    sc.map_sigma_m = NAN;
    assert_int_equal(trn_select_cfg_check(&sc, CELL), TRN_E_ARG);
    assert_int_equal(trn_select_workspace_bytes(&sc, &h->map, NULL), 0u);
    sc.map_sigma_m = -0.01f;
    assert_int_equal(
        trn_select(&h->map, NULL, NULL, &sc, &rv, r.cands, r.cap, ranked, 2u, &res, r.ws, wb),
        TRN_E_ARG);
    small_cfg(&sc);
    /* the points a cell NaN, negative, between 0 and 1, above TRN_POINT_COUNT_MAX */
    {
        const float bad[4] = {NAN, -1.0f, 0.5f, 2.0e6f};
        for (x = 0; x < 4; ++x) {
            sc.points_per_cell = bad[x];
            assert_int_equal(trn_select_cfg_check(&sc, CELL), TRN_E_ARG);
            assert_int_equal(trn_select(&h->map, NULL, NULL, &sc, &rv, r.cands, r.cap, ranked, 2u,
                                        &res, r.ws, wb),
                             TRN_E_ARG);
        }
        sc.points_per_cell = (float)TRN_POINT_COUNT_MAX;
        assert_int_equal(trn_select_cfg_check(&sc, CELL), TRN_OK);
        sc.points_per_cell = 1.0f;
        assert_int_equal(trn_select_cfg_check(&sc, CELL), TRN_OK);
    }
    small_cfg(&sc);
    /* a heights map without its heights */
    m = h->map;
    m.heights.data = NULL;
    assert_int_equal(
        trn_select(&m, NULL, NULL, &sc, &rv, r.cands, r.cap, ranked, 2u, &res, r.ws, wb),
        TRN_E_NULL);
    /* the workspace one byte short, or misaligned */
    assert_int_equal(
        trn_select(&h->map, NULL, NULL, &sc, &rv, r.cands, r.cap, ranked, 2u, &res, r.ws, wb - 1u),
        TRN_E_WORKSPACE);
    assert_int_equal(trn_select(&h->map, NULL, NULL, &sc, &rv, r.cands, r.cap, ranked, 2u, &res,
                                (uint8_t *)r.ws + 1, wb - 1u),
                     TRN_E_WORKSPACE);
    /* the rover off the map */
    rv.pos.x_cells = (float)N + 1.0f;
    assert_int_equal(
        trn_select(&h->map, NULL, NULL, &sc, &rv, r.cands, r.cap, ranked, 2u, &res, r.ws, wb),
        TRN_E_RANGE);
    rv.pos.x_cells = 36.0f;
    /* gradients too large for exact int64 sums over the region (w gx^2 about
     * 1e28 per cell even at a quantum of 1) */
    for (y = 0; y < N; ++y) {
        for (x = 0; x < N; ++x) {
            dem[y * N + x] = (float)(1.0e12 * x + 3.0e11 * ((x * 7 + y * 3) % 5));
        }
    }
    free(h->buf);
    hmap_init(h, dem);
    assert_int_equal(
        trn_select(&h->map, NULL, NULL, &sc, &rv, r.cands, r.cap, ranked, 2u, &res, r.ws, wb),
        TRN_E_SIZE);
    free(r.cands);
    free(r.ws);
    free(dem);
    free(h->buf);
    free(h);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_against_slow),        cmocka_unit_test(test_points_per_cell),
        cmocka_unit_test(test_ll_is_the_quadratic), cmocka_unit_test(test_paraboloid),
        cmocka_unit_test(test_flat_and_plane),      cmocka_unit_test(test_holes),
        cmocka_unit_test(test_field_same_bits),     cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
