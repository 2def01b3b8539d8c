/* SPDX-License-Identifier: Apache-2.0 */
/* tests/cli/test_terrain_gen.c - the `trn terrain` generator against the
 * Golombek & Rapp model it claims to draw from (tools/trn/terrain_gen.h).
 *
 * Statistics are checked against analytic expectations with tolerances from
 * the model's own Poisson variance (4 sigma), over maps large enough that
 * sigma is a few percent of the expectation: a wrong density (a missing pi/4,
 * a diameter in cells instead of metres, a biased in-bin draw) fails. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "terrain_gen.h"

#define PI 3.14159265358979323846

/* Integral of f over [a, b], composite Simpson with n (even) intervals. */
static double simpson(double (*f)(double, double), double k, double a, double b, int n)
{
    double h = (b - a) / n, s = f(a, k) + f(b, k);
    int i;
    for (i = 1; i < n; ++i) {
        s += f(a + i * h, k) * (i % 2 ? 4.0 : 2.0);
    }
    return s * h / 3.0;
}

/* Number density per m^2 per m of diameter. */
static double n_of_d(double d, double k)
{
    double q = 1.79 + 0.152 / k;
    return k * q * exp(-q * d) / (PI * d * d / 4.0);
}

/* Area density times rock area: integrand of the variance of the area sum. */
static double area2_of_d(double d, double k)
{
    double q = 1.79 + 0.152 / k;
    return k * q * exp(-q * d) * (PI * d * d / 4.0);
}

typedef struct {
    tg_params_t p;
    tg_rock_t *rocks;
    size_t n;
} field_t;

static void make_field(field_t *f, int side, double cell, double k, uint64_t seed)
{
    tg_default(&f->p, side, side, cell);
    f->p.coverage_k = k;
    f->p.d_max_m = tg_auto_d_max(k);
    f->p.seed = seed;
    assert_null(tg_check(&f->p));
    f->n = tg_draw_rocks(&f->p, NULL, 0);
    f->rocks = malloc((f->n + 1) * sizeof *f->rocks);
    assert_non_null(f->rocks);
    assert_int_equal(tg_draw_rocks(&f->p, f->rocks, f->n), f->n);
}

static void test_model_functions(void **state)
{
    (void)state;
    assert_true(fabs(tg_q(0.1) - 3.31) < 1e-12);
    assert_true(fabs(tg_cum_area(0.1, 0.0) - 0.1) < 1e-15);
    assert_true(fabs(tg_cum_area(0.2, 1.0) - 0.2 * exp(-2.55)) < 1e-15);
    assert_true(fabs(tg_cum_area(0.1, tg_auto_d_max(0.1)) - 1e-5) < 1e-12);
}

/* Realised fractional area of rocks with D >= Dx (centres on the map)
 * against F_k(Dx) - F_k(Dmax), for two coverages. */
static void check_area_fractions(double k, uint64_t seed)
{
    static const double dx[] = {0.2, 0.3, 0.5, 0.8, 1.2};
    field_t f;
    const double cell = 0.1;
    const int side = 2048;
    double ext, area;
    size_t i, t;
    make_field(&f, side, cell, k, seed);
    ext = side * cell;
    area = ext * ext;
    for (t = 0; t < sizeof dx / sizeof dx[0]; ++t) {
        double got = 0.0, want, sigma;
        for (i = 0; i < f.n; ++i) {
            const tg_rock_t *r = &f.rocks[i];
            if (r->d_m >= dx[t] && r->x_m >= 0 && r->x_m < ext && r->y_m >= 0 && r->y_m < ext) {
                got += PI * r->d_m * r->d_m / 4.0;
            }
        }
        got /= area;
        want = tg_cum_area(k, dx[t]) - tg_cum_area(k, f.p.d_max_m);
        sigma = sqrt(simpson(area2_of_d, k, dx[t], f.p.d_max_m, 2000) / area);
        print_message("k=%.2f D>=%.1f m: area fraction %.5f, model %.5f, sigma %.5f (%.1f sigma)\n",
                      k, dx[t], got, want, sigma, (got - want) / sigma);
        assert_true(fabs(got - want) <= 4.0 * sigma);
        if (dx[t] <= 0.5) {
            assert_true(sigma < 0.05 * want); /* the test is sharp where most area is */
        }
    }
    free(f.rocks);
}

static void test_area_fraction_k010(void **state)
{
    (void)state;
    check_area_fractions(0.1, 11);
}

static void test_area_fraction_k020(void **state)
{
    (void)state;
    check_area_fractions(0.2, 12);
}

/* Rock counts per diameter range over the whole generation area against the
 * integral of n(D): Poisson, sigma = sqrt(expected). */
static void test_counts(void **state)
{
    static const double lo[] = {0.2, 0.25, 0.4, 0.7};
    static const double hi[] = {0.25, 0.4, 0.7, 1.5};
    field_t f;
    double margin, gen_area;
    size_t i, t;
    (void)state;
    make_field(&f, 1024, 0.1, 0.15, 3);
    margin = 0.5 * f.p.d_max_m;
    gen_area = (1024 * 0.1 + 2 * margin) * (1024 * 0.1 + 2 * margin);
    for (t = 0; t < 4; ++t) {
        double want = simpson(n_of_d, 0.15, lo[t], hi[t], 2000) * gen_area;
        size_t got = 0;
        for (i = 0; i < f.n; ++i) {
            got += f.rocks[i].d_m >= lo[t] && f.rocks[i].d_m < hi[t];
        }
        print_message("D in [%.2f, %.2f): %zu rocks, expected %.1f (%.1f sigma)\n", lo[t], hi[t],
                      got, want, ((double)got - want) / sqrt(want));
        assert_true(fabs((double)got - want) <= 5.0 * sqrt(want));
    }
    free(f.rocks);
}

/* The rendered map: fraction of cells under a rock against the Boolean-model
 * coverage 1 - exp(-(F(Dmin) - F(Dmax))) (random centres, overlaps counted
 * once), and heights bounded by height_ratio * D. */
static void test_rendered_coverage(void **state)
{
    field_t f;
    const int side = 2048;
    float *rock_h;
    size_t i, covered = 0, ncell = (size_t)side * side;
    double want, got, sigma, hmax = 0.0;
    (void)state;
    make_field(&f, side, 0.1, 0.1, 5);
    rock_h = malloc(ncell * sizeof *rock_h);
    assert_non_null(rock_h);
    tg_render_rocks(&f.p, f.rocks, f.n, rock_h);
    for (i = 0; i < ncell; ++i) {
        covered += rock_h[i] > 0.0f;
        hmax = rock_h[i] > hmax ? rock_h[i] : hmax;
    }
    got = (double)covered / (double)ncell;
    want = 1.0 - exp(-(tg_cum_area(0.1, f.p.d_min_m) - tg_cum_area(0.1, f.p.d_max_m)));
    sigma = sqrt(simpson(area2_of_d, 0.1, f.p.d_min_m, f.p.d_max_m, 2000) /
                 (side * 0.1 * side * 0.1));
    print_message("covered cells %.5f, Boolean model %.5f, sigma %.5f\n", got, want, sigma);
    assert_true(fabs(got - want) <= 4.0 * sigma + 0.001);
    assert_true(hmax <= 0.5 * f.p.d_max_m + 1e-6);
    assert_true(hmax > 0.0);
    free(rock_h);
    free(f.rocks);
}

/* One rock, analytic shape: hemisphere height at its centre, zero outside. */
static void test_single_rock_shape(void **state)
{
    tg_params_t p;
    tg_rock_t r = {1.05, 1.05, 0.8, 0.4}; /* centre of cell (10, 10) */
    float h[32 * 32];
    (void)state;
    tg_default(&p, 32, 32, 0.1);
    tg_render_rocks(&p, &r, 1, h);
    assert_true(fabs(h[10 * 32 + 10] - 0.4f) < 1e-6);
    /* 3 cells east: r = 0.3, z = 0.4 sqrt(1 - (0.6/0.8)^2) */
    assert_true(fabs(h[10 * 32 + 13] - 0.4 * sqrt(1.0 - 0.5625)) < 1e-6);
    assert_true(h[10 * 32 + 14] == 0.0f); /* r = 0.4 = D/2: on the rim, not inside */
    assert_true(h[14 * 32 + 14] == 0.0f);
    assert_true(h[0] == 0.0f);
}

static void test_deterministic(void **state)
{
    field_t a, b, c;
    float *da, *db;
    size_t ncell = 128 * 128;
    (void)state;
    make_field(&a, 128, 0.1, 0.1, 42);
    make_field(&b, 128, 0.1, 0.1, 42);
    make_field(&c, 128, 0.1, 0.1, 43);
    assert_int_equal(a.n, b.n);
    assert_memory_equal(a.rocks, b.rocks, a.n * sizeof *a.rocks);
    assert_true(a.n != c.n || memcmp(a.rocks, c.rocks, a.n * sizeof *a.rocks) != 0);
    da = malloc(ncell * sizeof *da);
    db = malloc(ncell * sizeof *db);
    tg_render(&a.p, a.rocks, a.n, da, NULL, NULL);
    tg_render(&b.p, b.rocks, b.n, db, NULL, NULL);
    assert_memory_equal(da, db, ncell * sizeof *da);
    free(da);
    free(db);
    free(a.rocks);
    free(b.rocks);
    free(c.rocks);
}

/* Background relief: RMS near relief_m with no rocks in range. */
static void test_relief_rms(void **state)
{
    tg_params_t p;
    float *d;
    size_t i, ncell = 1024 * 1024;
    double s2 = 0.0, s = 0.0, rms;
    (void)state;
    tg_default(&p, 1024, 1024, 0.25);
    p.relief_m = 0.2;
    d = malloc(ncell * sizeof *d);
    tg_render(&p, NULL, 0, d, NULL, NULL);
    for (i = 0; i < ncell; ++i) {
        s += d[i];
        s2 += (double)d[i] * d[i];
    }
    rms = sqrt(s2 / (double)ncell - (s / (double)ncell) * (s / (double)ncell));
    print_message("relief RMS %.4f m (asked 0.2)\n", rms);
    /* 12 waves over 256 m: the sample RMS of a few-wave field varies. */
    assert_true(rms > 0.14 && rms < 0.26);
    free(d);
}

static void test_check_rejects(void **state)
{
    tg_params_t p;
    (void)state;
    tg_default(&p, 64, 64, 0.1);
    assert_null(tg_check(&p));
    p.coverage_k = 0.0;
    assert_non_null(tg_check(&p));
    tg_default(&p, 64, 64, 0.1);
    p.cell_m = -1.0;
    assert_non_null(tg_check(&p));
    tg_default(&p, 64, 64, 0.1);
    p.d_max_m = 0.1;
    p.d_min_m = 0.2;
    assert_non_null(tg_check(&p));
    tg_default(&p, 64, 64, 0.1);
    p.height_ratio = NAN;
    assert_non_null(tg_check(&p));
    tg_default(&p, 0, 64, 0.1);
    assert_non_null(tg_check(&p));
    tg_default(&p, 64, 64, 0.1);
    p.relief_m = -0.1;
    assert_non_null(tg_check(&p));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_model_functions),    cmocka_unit_test(test_area_fraction_k010),
        cmocka_unit_test(test_area_fraction_k020), cmocka_unit_test(test_counts),
        cmocka_unit_test(test_rendered_coverage),  cmocka_unit_test(test_single_rock_shape),
        cmocka_unit_test(test_deterministic),      cmocka_unit_test(test_relief_rms),
        cmocka_unit_test(test_check_rejects),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
