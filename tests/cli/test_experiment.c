/* SPDX-License-Identifier: Apache-2.0 */
/* tests/cli/test_experiment.c - the pure parts of `trn experiment`
 * (tools/trn/experiment.h): interval statistics against analytic values, the
 * local-map sampler, the random streams, the parameter checks, and a tiny
 * end-to-end run (deterministic, internally consistent).
 *
 * Oracles: the Wilson bounds are the roots of (p_hat - p)^2 = z^2 p (1 - p) / n
 * (checked by substitution, not by re-evaluating the same formula); Student t
 * against closed forms (df 1, 2, 3) and printed tables (df 10, 30); the
 * clustered rate against the analytic effective size of fully correlated
 * clusters (C - 1); the sampler's counts against the binomial law (4 sigma). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "experiment.h"
#include "terrain_gen.h"

#define PI 3.14159265358979323846
#define Z EXP_Z95

/* ---- Wilson ------------------------------------------------------------- */
static double wilson_residual(double k, double n, double p)
{
    double ph = k / n;
    return (ph - p) * (ph - p) - Z * Z * p * (1.0 - p) / n;
}

static void test_wilson_roots(void **state)
{
    static const double cases[][2] = {{3, 10}, {978, 1000},  {295, 1000}, {1, 7},
                                      {6, 7},  {2655, 9000}, {12.5, 40.3}};
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        double ci[2], k = cases[i][0], n = cases[i][1];
        exp_wilson(k, n, Z, ci);
        assert_true(ci[0] < k / n && k / n < ci[1]);
        assert_true(fabs(wilson_residual(k, n, ci[0])) < 1e-12);
        assert_true(fabs(wilson_residual(k, n, ci[1])) < 1e-12);
    }
}

static void test_wilson_ends(void **state)
{
    double ci[2];
    (void)state;
    exp_wilson(0, 10, Z, ci); /* (0, z^2 / (n + z^2)) */
    assert_true(ci[0] == 0.0);
    assert_true(fabs(ci[1] - Z * Z / (10.0 + Z * Z)) < 1e-14);
    exp_wilson(10, 10, Z, ci); /* (n / (n + z^2), 1) */
    assert_true(fabs(ci[0] - 10.0 / (10.0 + Z * Z)) < 1e-14);
    assert_true(ci[1] == 1.0);
    exp_wilson(50, 100, Z, ci); /* symmetric about 1/2 */
    assert_true(fabs(ci[0] + ci[1] - 1.0) < 1e-14);
    exp_wilson(1, 0, Z, ci);
    assert_true(isnan(ci[0]) && isnan(ci[1]));
}

/* ---- Student t ---------------------------------------------------------- */
static void test_t_cdf_closed_forms(void **state)
{
    int i;
    (void)state;
    for (i = 0; i < 109; ++i) { /* t = 0, 0.37, ..., 39.96 */
        const double t = 0.37 * i;
        double th3 = atan(t / sqrt(3.0));
        /* df 1: Cauchy; df 2: t / sqrt(2 + t^2); df 3: 2 F - 1 with
     * F = 1/2 + (t / (sqrt 3 (1 + t^2/3)) + atan(t / sqrt 3)) / pi. */
        assert_true(fabs(exp_t_abs_cdf(t, 1) - 2.0 * atan(t) / PI) < 1e-14);
        assert_true(fabs(exp_t_abs_cdf(t, 2) - t / sqrt(2.0 + t * t)) < 1e-14);
        assert_true(fabs(exp_t_abs_cdf(t, 3) -
                         2.0 / PI * (t / (sqrt(3.0) * (1.0 + t * t / 3.0)) + th3)) < 1e-13);
        assert_true(fabs(exp_t_abs_cdf(-t, 7) - exp_t_abs_cdf(t, 7)) < 1e-15);
    }
    assert_true(exp_t_abs_cdf(0.0, 5) == 0.0);
    assert_true(exp_t_abs_cdf(INFINITY, 5) == 1.0);
    assert_true(isnan(exp_t_abs_cdf(1.0, 0)));
}

static void test_t_quantiles(void **state)
{
    (void)state;
    assert_true(fabs(exp_t_quantile(0.95, 1) - tan(0.475 * PI)) < 1e-9); /* 12.7062 */
    assert_true(fabs(exp_t_quantile(0.95, 2) - 0.95 * sqrt(2.0 / (1.0 - 0.9025))) <
                1e-9); /* 4.3027 */
    assert_true(fabs(exp_t_quantile(0.95, 10) - 2.228138852) < 1e-8);
    assert_true(fabs(exp_t_quantile(0.95, 30) - 2.042272456) < 1e-8);
    assert_true(fabs(exp_t_quantile(0.99, 10) - 3.169272673) < 1e-8);
    assert_true(fabs(exp_t_quantile(0.95, 1000000) - Z) < 2e-5);
    assert_true(isnan(exp_t_quantile(1.0, 5)) && isnan(exp_t_quantile(0.95, 0)));
}

/* ---- clustered statistics ----------------------------------------------- */
static void test_stats_single_units_are_plain(void **state)
{
    enum { N = 40 };
    long m[N], k[N];
    double e[N], e2[N], sum = 0.0, sum2 = 0.0, ci[2], mean, sd, tq;
    long i, ks = 0;
    exp_stats_t st;
    (void)state;
    for (i = 0; i < N; ++i) {
        m[i] = 1;
        k[i] = (i % 5) != 0; /* 32 of 40 */
        e[i] = k[i] ? 0.01 * (double)(i % 7) + 0.005 : 0.0;
        e2[i] = e[i] * e[i];
        sum += e[i];
        sum2 += e2[i];
        ks += k[i];
    }
    exp_cluster_stats(m, k, e, e2, N, &st);
    exp_wilson((double)ks, N, Z, ci);
    assert_true(st.rate == 32.0 / 40.0);
    assert_true(st.n_eff == N);
    assert_true(fabs(st.rate_ci[0] - ci[0]) < 1e-15 && fabs(st.rate_ci[1] - ci[1]) < 1e-15);
    mean = sum / (double)ks;
    sd = sqrt((sum2 - (double)ks * mean * mean) / (double)(ks - 1));
    tq = exp_t_quantile(0.95, ks - 1);
    assert_true(fabs(st.mean - mean) < 1e-15);
    assert_true(fabs(st.sd - sd) < 1e-12);
    assert_true(fabs(st.mean_ci[0] - (mean - tq * sd / sqrt((double)ks))) < 1e-12);
    assert_true(fabs(st.mean_ci[1] - (mean + tq * sd / sqrt((double)ks))) < 1e-12);
}

static void test_stats_correlated_clusters(void **state)
{
    /* Nine units per cluster that all succeed or all fail: the data hold only
   * C independent outcomes; the linearized variance gives n_eff = C - 1. */
    enum { C = 50 };
    long m[C], k[C];
    double e[C], e2[C];
    long i;
    exp_stats_t st;
    (void)state;
    for (i = 0; i < C; ++i) {
        m[i] = 9;
        k[i] = (i % 10) < 3 ? 9 : 0;  /* 30 % */
        e[i] = k[i] ? 9 * 0.04 : 0.0; /* every success has error 0.04 */
        e2[i] = k[i] ? 9 * 0.04 * 0.04 : 0.0;
    }
    exp_cluster_stats(m, k, e, e2, C, &st);
    assert_true(fabs(st.rate - 0.3) < 1e-15);
    assert_true(fabs(st.n_eff - (C - 1)) < 1e-9);
    assert_true(fabs(st.mean - 0.04) < 1e-15);
    /* every success has the same error: the cluster-robust interval is a point */
    assert_true(fabs(st.mean_ci[0] - 0.04) < 1e-12 && fabs(st.mean_ci[1] - 0.04) < 1e-12);
    /* identical clusters carry no between-cluster variance: n_eff = all units */
    for (i = 0; i < C; ++i) {
        k[i] = 3;
    }
    exp_cluster_stats(m, k, e, e2, C, &st);
    assert_true(st.n_eff == 9.0 * C);
    /* no success: no mean, rate interval still defined */
    for (i = 0; i < C; ++i) {
        k[i] = 0;
        e[i] = e2[i] = 0.0;
    }
    exp_cluster_stats(m, k, e, e2, C, &st);
    assert_true(st.rate == 0.0 && st.rate_ci[0] == 0.0 && st.rate_ci[1] > 0.0);
    assert_true(isnan(st.mean) && isnan(st.mean_ci[0]));
}

/* ---- the sampler ---------------------------------------------------------- */
static void test_sample_binomial(void **state)
{
    enum { W = 64, H = 64, NZ = 16, NV = W * H * NZ };
    float *p = malloc(NV * sizeof *p);
    trn_point_t *pts = malloc(NV * sizeof *pts);
    exp_rng_t r;
    size_t n, i, lo_hits = 0, hi_hits = 0;
    double sig;
    (void)state;
    assert_non_null(p);
    assert_non_null(pts);
    for (i = 0; i < NV; ++i) { /* half the voxels 0.1, half 0.9 (by x parity) */
        p[i] = (i % 2) ? 0.9f : 0.1f;
    }
    exp_rng_seed(&r, 42, 0);
    n = exp_sample_points(p, W, H, NZ, 0, 0, &r, pts, NV);
    for (i = 0; i < n; ++i) {
        if (pts[i].x % 2) {
            ++hi_hits;
        } else {
            ++lo_hits;
        }
    }
    sig = sqrt(NV / 2.0 * 0.1 * 0.9); /* same for both halves */
    assert_true(fabs((double)lo_hits - NV / 2.0 * 0.1) < 4.0 * sig);
    assert_true(fabs((double)hi_hits - NV / 2.0 * 0.9) < 4.0 * sig);
    /* certain and impossible voxels */
    for (i = 0; i < NV; ++i) {
        p[i] = (i % 3 == 0) ? 1.0f : (i % 3 == 1) ? 1.7f : 0.0f;
    }
    p[3] = -0.5f; /* was 1: negative is never occupied */
    p[4] = NAN;   /* was 1.7: NaN is never occupied */
    n = exp_sample_points(p, W, H, NZ, 0, 0, &r, pts, NV);
    /* of 65536 voxels 21846 hold 1 and 21845 hold 1.7; two of them changed */
    assert_int_equal(n, 21846 + 21845 - 2);
    free(p);
    free(pts);
}

static void test_sample_offsets_and_cap(void **state)
{
    enum { W = 7, H = 9, NZ = 4 };
    float p[W * H * NZ];
    trn_point_t pts[4];
    exp_rng_t r;
    size_t n;
    (void)state;
    memset(p, 0, sizeof p);
    p[(2 * H + 5) * W + 3] = 1.0f; /* voxel (3, 5, 2) */
    exp_rng_seed(&r, 1, 0);
    n = exp_sample_points(p, W, H, NZ, -10, 7, &r, pts, 4);
    assert_int_equal(n, 1);
    assert_int_equal(pts[0].x, -7);
    assert_int_equal(pts[0].y, 12);
    assert_int_equal(pts[0].z, 2);
    /* the count goes on past the capacity; nothing is written beyond it */
    {
        float all[W * H * NZ];
        trn_point_t few[3];
        trn_point_t guard = {99, 99, 99};
        size_t i;
        for (i = 0; i < W * H * NZ; ++i) {
            all[i] = 1.0f;
        }
        few[2] = guard;
        n = exp_sample_points(all, W, H, NZ, 0, 0, &r, few, 2);
        assert_int_equal(n, W * H * NZ);
        assert_int_equal(few[2].x, 99);
    }
}

static void test_sample_deterministic(void **state)
{
    enum { W = 21, H = 21, NZ = 16, NV = W * H * NZ };
    static float p[NV];
    static trn_point_t a[NV], b[NV];
    exp_rng_t r1, r2, r3;
    size_t i, na, nb, nc;
    (void)state;
    for (i = 0; i < NV; ++i) {
        p[i] = (float)((i * 37u) % 100u) / 100.0f;
    }
    exp_rng_seed(&r1, 7, 3);
    exp_rng_seed(&r2, 7, 3);
    exp_rng_seed(&r3, 7, 4);
    na = exp_sample_points(p, W, H, NZ, 1, 2, &r1, a, NV);
    nb = exp_sample_points(p, W, H, NZ, 1, 2, &r2, b, NV);
    assert_int_equal(na, nb);
    assert_memory_equal(a, b, na * sizeof a[0]);
    nc = exp_sample_points(p, W, H, NZ, 1, 2, &r3, b, NV);
    assert_true(nc != na || memcmp(a, b, na * sizeof a[0]) != 0); /* another stream */
}

/* ---- random streams ------------------------------------------------------ */
static void test_rng_range_uniform(void **state)
{
    enum { BINS = 10, DRAWS = 100000 };
    long cnt[BINS] = {0};
    exp_rng_t r;
    long i;
    double expect = (double)DRAWS / BINS, sig = sqrt(DRAWS * 0.1 * 0.9);
    (void)state;
    exp_rng_seed(&r, 123, 0);
    for (i = 0; i < DRAWS; ++i) {
        long v = exp_rng_range(&r, -3, 6);
        assert_true(v >= -3 && v <= 6);
        cnt[v + 3]++;
    }
    for (i = 0; i < BINS; ++i) {
        assert_true(fabs((double)cnt[i] - expect) < 5.0 * sig);
    }
    for (i = 0; i < 1000; ++i) {
        double u = exp_rng_unit(&r);
        assert_true(u >= 0.0 && u < 1.0);
    }
    assert_int_equal(exp_rng_range(&r, 5, 5), 5);
}

static void test_rng_streams_differ(void **state)
{
    exp_rng_t a, b, c;
    (void)state;
    exp_rng_seed(&a, 1, 0);
    exp_rng_seed(&b, 1, 1);
    exp_rng_seed(&c, 2, 0);
    assert_true(exp_rng_u64(&a) != exp_rng_u64(&b));
    exp_rng_seed(&a, 1, 0);
    assert_true(exp_rng_u64(&a) != exp_rng_u64(&c));
}

/* ---- parameters ---------------------------------------------------------- */
static void test_params_check(void **state)
{
    exp_params_t p;
    (void)state;
    exp_params_default(&p);
    assert_null(exp_params_check(&p));
#define BAD(field, value) \
    do { \
        exp_params_default(&p); \
        p.field = value; \
        assert_non_null(exp_params_check(&p)); \
    } while (0)
    BAD(trials, 0);
    BAD(size_cells, 10);
    BAD(cell_m, 0.0);
    BAD(coverage_k, 0.9);
    BAD(coverage_k, NAN);
    BAD(d_min_m, 0.01);
    BAD(relief_m, -1.0);
    BAD(prior_error_m, -0.1);
    BAD(window_m, 0.5); /* below the 1 m prior error */
    BAD(grid_spacing_m, 11.0);
    BAD(success_cells, 0.0);
    BAD(sensor, 2);
    BAD(height_noise_m, 0.01); /* only with the DEM sensor */
    p.sensor = EXP_SENSOR_DEM;
    p.height_noise_m = 0.02;
    assert_null(exp_params_check(&p));
    p.height_noise_m = -0.01;
    assert_non_null(exp_params_check(&p));
    /* a given DEM: its own size and cell limits; an error raster needs one */
    {
        static float d[16 * 16];
        exp_params_default(&p);
        p.global_error = d;
        assert_non_null(exp_params_check(&p)); /* raster without a DEM */
        p.dem = d;
        p.dem_width = 16;
        p.dem_height = 16;
        assert_null(exp_params_check(&p));
        p.dem_height = 15;
        assert_non_null(exp_params_check(&p));
        p.dem_height = 1025;
        assert_non_null(exp_params_check(&p));
        p.dem_height = 16;
        p.cell_m = 50.0; /* 83 m DEMs exist; lengths then in cells */
        p.window_m = 100.0;
        p.prior_error_m = 50.0;
        p.grid_spacing_m = 100.0;
        assert_null(exp_params_check(&p));
        p.window_m = 200.0 * 50.0 + 1.0;
        assert_non_null(exp_params_check(&p));
        p.window_m = 100.0;
        p.cell_m = 101.0;
        assert_non_null(exp_params_check(&p));
        {
            /* above the core's coarsest cell: the message names its bound */
            char want[64];
            p.cell_m = (double)TRN_CELL_MAX_M * 1.001;
            snprintf(want, sizeof want, "cell size must be in (0, %g] m", (double)TRN_CELL_MAX_M);
            assert_string_equal(exp_params_check(&p), want);
        }
        p.cell_m = 50.0;
        p.patch_m = NAN;
        assert_non_null(exp_params_check(&p));
        p.dem = NULL;
        p.global_error = NULL;
        p.patch_m = 0.0;
        assert_non_null(exp_params_check(&p)); /* 50 m cells: generated terrain only to 10 m */
    }
#undef BAD
}

/* ---- a given DEM ----------------------------------------------------------- */
/* The generated terrain handed over as a DEM gives the same experiment
 * (the same trials, the same numbers); the same terrain at 10x the cell and
 * 10x the heights (the paper's map configuration, every length scaled) gives
 * the same successes and errors x 10. */
typedef struct {
    long calls, last_done, last_total, stop_at;
} exp_prog_t;

static int exp_on_progress(void *ctx, long done, long total)
{
    exp_prog_t *c = (exp_prog_t *)ctx;
    ++c->calls;
    c->last_done = done;
    c->last_total = total;
    return c->stop_at > 0 && done >= c->stop_at;
}

/* The progress callback counts every trial up to the total; a nonzero
 * return cancels the run (-1, "cancelled" in err). */
static void test_run_progress_cancel(void **state)
{
    exp_params_t p;
    exp_result_t a;
    exp_prog_t c;
    char err[256];
    (void)state;
    exp_params_default(&p);
    p.size_cells = 128;
    p.trials = 4;
    memset(&c, 0, sizeof c);
    assert_int_equal(exp_run(&p, &a, exp_on_progress, &c, err, sizeof err), 0);
    assert_int_equal(c.calls, 4);
    assert_int_equal(c.last_done, 4);
    assert_int_equal(c.last_total, 4);
    memset(&c, 0, sizeof c);
    c.stop_at = 2;
    assert_int_equal(exp_run(&p, &a, exp_on_progress, &c, err, sizeof err), -1);
    assert_int_equal(c.calls, 2);
    assert_non_null(strstr(err, "cancelled after 2 of 4 trials"));
}

static void test_run_dem(void **state)
{
    const int n = 128;
    exp_params_t p;
    exp_result_t a, b;
    tg_params_t tp;
    tg_rock_t *rocks;
    float *dem = malloc(sizeof(float) * n * n), *big = malloc(sizeof(float) * n * n);
    size_t nr, i;
    char err[256];
    (void)state;
    exp_params_default(&p);
    p.size_cells = n;
    p.trials = 6;
    assert_int_equal(exp_run(&p, &a, NULL, NULL, err, sizeof err), 0);
    tg_default(&tp, n, n, 0.1);
    tp.coverage_k = p.coverage_k;
    tp.d_max_m = tg_auto_d_max(p.coverage_k);
    tp.seed = p.terrain_seed;
    tp.relief_m = p.relief_m;
    nr = tg_draw_rocks(&tp, NULL, 0);
    rocks = malloc((nr + 1) * sizeof *rocks);
    tg_draw_rocks(&tp, rocks, nr);
    tg_render(&tp, rocks, nr, dem, NULL, NULL);
    free(rocks);
    p.dem = dem;
    p.dem_width = n;
    p.dem_height = n;
    /* a DEM's global error has no range term by default (an overhead
     * product); the generated terrain's (the paper's, from the centre) given */
    assert_int_equal(exp_run(&p, &b, NULL, NULL, err, sizeof err), 0);
    assert_true(b.global_sigma.k_per_m == 0.0f &&
                b.global_sigma.sigma_min_m == a.global_sigma.sigma_min_m);
    assert_true(a.global_sigma.k_per_m > 0.0f);
    p.global_sigma_k = (double)a.global_sigma.k_per_m;
    assert_int_equal(exp_run(&p, &b, NULL, NULL, err, sizeof err), 0);
    assert_int_equal(a.draws, b.draws);
    assert_int_equal(a.with.successes, b.with.successes);
    assert_int_equal(a.without.successes, b.without.successes);
    assert_true(a.with.st.mean == b.with.st.mean);
    assert_true(a.without.st.mean == b.without.st.mean);
    /* x 10 */
    for (i = 0; i < (size_t)n * n; ++i) {
        big[i] = 10.0f * dem[i];
    }
    p.dem = big;
    p.cell_m = 1.0;
    p.window_m = 20.0;
    p.prior_error_m = 10.0;
    p.grid_spacing_m = 20.0;
    p.global_sigma_k = (double)a.global_sigma.k_per_m / 10.0; /* r^2 term / f */
    assert_int_equal(exp_run(&p, &b, NULL, NULL, err, sizeof err), 0);
    assert_int_equal(a.draws, b.draws);
    assert_int_equal(a.with.successes, b.with.successes);
    assert_int_equal(a.without.successes, b.without.successes);
    assert_true(fabs(b.with.st.mean - 10.0 * a.with.st.mean) <= 1e-4 * b.with.st.mean);
    assert_true(fabs(b.without.st.mean - 10.0 * a.without.st.mean) <= 1e-4 * b.without.st.mean);
    assert_true(fabs((double)b.scfg.max_range_m - 100.0) < 1e-3);
    /* no data: a NaN block; the run still works, and a DEM all no-data but
   * for too small an island has no trial (a reason, not a hang) */
    for (i = 0; i < (size_t)n * n; ++i) {
        if (i / n >= 10 && i / n < 30 && i % n >= 90 && i % n < 110) {
            big[i] = NAN;
        }
    }
    if (exp_run(&p, &b, NULL, NULL, err, sizeof err) != 0) {
        fail_msg("NaN block: %s", err);
    }
    for (i = 0; i < (size_t)n * n; ++i) {
        if (i / n >= 60 && i / n < 68) {
            big[i] = NAN; /* a band: no room for the nine patches above or below it */
        }
    }
    assert_int_equal(exp_run(&p, &b, NULL, NULL, err, sizeof err), -1);
    assert_non_null(strstr(err, "nine fixed targets"));
    for (i = 0; i < (size_t)n * n; ++i) {
        big[i] = 10.0f * dem[i];
    }
    /* too small for nine patches 20 cells apart */
    p.dem_width = 60;
    p.dem_height = 60;
    assert_int_equal(exp_run(&p, &b, NULL, NULL, err, sizeof err), -1);
    assert_non_null(strstr(err, "too small"));
    free(dem);
    free(big);
}

/* ---- end to end (tiny) ----------------------------------------------------- */
static void test_run_small(void **state)
{
    exp_params_t p;
    exp_result_t a, b;
    char err[256];
    (void)state;
    exp_params_default(&p);
    p.size_cells = 128;
    p.trials = 4;
    assert_int_equal(exp_run(&p, &a, NULL, NULL, err, sizeof err), 0);
    assert_int_equal(exp_run(&p, &b, NULL, NULL, err, sizeof err), 0);
    assert_int_equal(a.with.successes, b.with.successes);
    assert_int_equal(a.without.successes, b.without.successes);
    assert_true(a.with.st.mean == b.with.st.mean ||
                (isnan(a.with.st.mean) && isnan(b.with.st.mean)));
    assert_true(a.without.st.mean == b.without.st.mean);
    assert_int_equal(a.draws, b.draws);
    assert_int_equal(a.with.localizations, 4);
    assert_int_equal(a.without.localizations, 36);
    assert_true(a.with.successes <= a.with.localizations &&
                a.without.successes <= a.without.localizations);
    assert_true(a.with.st.rate_ci[0] <= a.with.st.rate && a.with.st.rate <= a.with.st.rate_ci[1]);
    assert_true(a.without.st.rate_ci[0] <= a.without.st.rate &&
                a.without.st.rate <= a.without.st.rate_ci[1]);
    assert_int_equal(a.patch_cells, 21);
    /* the diagnostic DEM sensor: exact terrain, no noise -> every localization
   * lands within a cell (the local map is a crop of the global occupancy,
   * re-filtered with the same context), and the run is deterministic */
    p.sensor = EXP_SENSOR_DEM;
    assert_int_equal(exp_run(&p, &a, NULL, NULL, err, sizeof err), 0);
    assert_int_equal(a.with.success_1cell + a.with.no_target, a.with.localizations);
    p.height_noise_m = 0.02;
    assert_int_equal(exp_run(&p, &a, NULL, NULL, err, sizeof err), 0);
    assert_int_equal(exp_run(&p, &b, NULL, NULL, err, sizeof err), 0);
    assert_int_equal(a.without.successes, b.without.successes);
    assert_true(a.without.st.mean == b.without.st.mean ||
                (isnan(a.without.st.mean) && isnan(b.without.st.mean)));
    p.sensor = EXP_SENSOR_PROB;
    p.height_noise_m = 0.0;
    /* a map too small for nine targets in reach: a reason, not a hang */
    p.size_cells = 64;
    assert_int_equal(exp_run(&p, &a, NULL, NULL, err, sizeof err), -1);
    assert_non_null(strstr(err, "nine fixed targets"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wilson_roots),
        cmocka_unit_test(test_wilson_ends),
        cmocka_unit_test(test_t_cdf_closed_forms),
        cmocka_unit_test(test_t_quantiles),
        cmocka_unit_test(test_stats_single_units_are_plain),
        cmocka_unit_test(test_stats_correlated_clusters),
        cmocka_unit_test(test_sample_binomial),
        cmocka_unit_test(test_sample_offsets_and_cap),
        cmocka_unit_test(test_sample_deterministic),
        cmocka_unit_test(test_rng_range_uniform),
        cmocka_unit_test(test_rng_streams_differ),
        cmocka_unit_test(test_params_check),
        cmocka_unit_test(test_run_small),
        cmocka_unit_test(test_run_dem),
        cmocka_unit_test(test_run_progress_cancel),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
