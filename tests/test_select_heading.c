/* SPDX-License-Identifier: Apache-2.0 */
/* test_select_heading.c - selection with an uncertain heading
 * (trn_select_cfg_t.sigma_heading_rad; select.h, method.md 4).
 *
 * Oracles: with sigma 0 every candidate's numbers are the paper's (the eq. 6
 * fit of its own ll[] in the old expressions, compared bit for bit) and a
 * configuration naming 0 gives the same bytes as the defaults; with sigma > 0
 * the expected log-likelihoods are unchanged and each covariance is the fit's
 * plus s_h^2 r^2 t t^T with t from atan2 (independent of the code's
 * square-root-free form), the term zero along the line of sight, one value
 * checked by hand; the best target is the argmin of u0^2 + s_h^2 r^2 over the
 * sigma-0 run's candidates; a constructed terrain where a far rock cluster
 * wins with a known heading and a near rock with an uncertain one; the field
 * (trn_field against trn_field_fast, bit for bit) with sigma > 0. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "selworld.h"
#include "synth.h"

#define CELL 0.1
#define CELLM ((double)(float)CELL) /* the map's cell_m, as the core sees it */

static synth_rock_t g_rocks[400];
static synth_terrain_t g_t; /* the last world's terrain (heights anywhere) */

static void small_cfg(trn_select_cfg_t *c)
{
    trn_select_cfg_default(c);
    c->min_range_m = 0.5f;
    c->max_range_m = 2.0f;
    c->footprint_radius_m = 0.3f;
    c->patch_m = 0.9f; /* 9 cells */
    c->stride_cells = 2;
    c->min_separation_m = 0.45f;
}

/* Seeded rocks (nrocks > 0) or the given ones on flat ground. */
static void make_world(selworld_t *w, int n, size_t nrocks, uint64_t seed,
                       const synth_rock_t *fixed, size_t nfixed)
{
    synth_terrain_t t;
    float *dem = malloc(sizeof(float) * n * n);
    trn_sigma_model_t gm;
    trn_xy_t s = {(float)n / 2.0f, (float)n / 2.0f};
    synth_make(&t, g_rocks, nrocks > 0 ? nrocks : 1, n * CELL, 0.05, 0.3, 0.5,
               nrocks > 0 ? 0.15 : 0.0, seed);
    if (fixed != NULL) {
        memcpy(g_rocks, fixed, nfixed * sizeof *fixed);
        t.n_rocks = nfixed;
    }
    synth_render(&t, dem, n, n, 0.0, 0.0, CELL);
    g_t = t;
    trn_sigma_global_default(&gm);
    assert_int_equal(selworld_init(w, n, dem, &gm, &s, 1), TRN_OK);
    free(dem);
}

typedef struct {
    trn_candidate_t *c;
    size_t cap, ranked[8];
    trn_select_result_t res;
    void *ws;
    size_t wsb;
} sel_t;

static trn_status_t run_select(selworld_t *w, const trn_select_cfg_t *cfg, const trn_rover_t *rv,
                               sel_t *s)
{
    s->cap = trn_select_max_candidates(cfg, (float)CELL);
    s->wsb = trn_select_workspace_bytes(cfg, &w->map, &w->k);
    assert_true(s->cap > 0u && s->wsb > 0u);
    s->c = calloc(s->cap, sizeof *s->c);
    s->ws = selworld_alloc(s->wsb);
    return trn_select(&w->map, &w->k, &w->pg, cfg, rv, s->c, s->cap, s->ranked, 8u, &s->res, s->ws,
                      s->wsb);
}

static void sel_free(sel_t *s)
{
    free(s->c);
    free(s->ws);
}

/* Sigma 0 (the default, and named explicitly): the paper's prediction bit
 * for bit, every candidate's numbers from its own ll[] by the old expressions. */
static void test_zero_is_the_paper(void **state)
{
    selworld_t w;
    trn_select_cfg_t cfg, named;
    trn_rover_t rv = {{31.3f, 28.6f}, 0.4f};
    sel_t a, b;
    size_t i, ninf = 0u;
    (void)state;
    small_cfg(&cfg);
    assert_true(cfg.sigma_heading_rad == 0.0f);
    make_world(&w, 64, 40, 5, NULL, 0u);
    named = cfg;
    named.sigma_heading_rad = 0.0f;
    assert_int_equal(run_select(&w, &cfg, &rv, &a), TRN_OK);
    assert_int_equal(run_select(&w, &named, &rv, &b), TRN_OK);
    assert_int_equal(a.res.n_candidates, b.res.n_candidates);
    assert_memory_equal(a.c, b.c, a.res.n_candidates * sizeof *a.c);
    assert_memory_equal(a.ranked, b.ranked, a.res.n_ranked * sizeof a.ranked[0]);
    for (i = 0; i < a.res.n_candidates; ++i) {
        const trn_candidate_t *c = &a.c[i];
        trn_peak_t pk;
        double sx, sy, u, cv[3];
        assert_true(c->heading_m == 0.0);
        if (!c->informative) {
            continue;
        }
        ++ninf;
        assert_int_equal(trn_peak_fit(c->ll, &pk), TRN_OK);
        sx = pk.sigma_x * CELLM;
        sy = pk.sigma_y * CELLM;
        u = sqrt(sx * sx + sy * sy);
        cv[0] = pk.var_x * CELLM * CELLM;
        cv[1] = pk.var_y * CELLM * CELLM;
        cv[2] = pk.cov_xy * CELLM * CELLM;
        assert_memory_equal(&c->sigma_x_m, &sx, sizeof sx);
        assert_memory_equal(&c->sigma_y_m, &sy, sizeof sy);
        assert_memory_equal(&c->rho, &pk.rho, sizeof pk.rho);
        assert_memory_equal(c->cov_m2, cv, sizeof cv);
        assert_memory_equal(&c->uncertainty_m, &u, sizeof u);
    }
    assert_true(ninf > 50u);
    sel_free(&a);
    sel_free(&b);
    selworld_free(&w);
}

/* Sigma > 0: ll[] unchanged; cov = the sigma-0 cov + s_h^2 r^2 t t^T, t the
 * unit tangent from atan2 of the offset; nothing added along the line of
 * sight; the scalar^2 grows by s_h^2 r^2; heading_m = s_h * range. One
 * candidate by hand: offset (6, 8) cells = 1 m, s_h = 0.1 rad:
 * + [0.0064, -0.0048; -0.0048, 0.0036] m^2. */
static void test_added_term(void **state)
{
    selworld_t w;
    trn_select_cfg_t c0, ch;
    trn_rover_t rv = {{30.0f, 30.0f}, 0.0f};
    sel_t a, b;
    size_t i, hand = 0u;
    (void)state;
    small_cfg(&c0);
    ch = c0;
    ch.sigma_heading_rad = 0.1f;
    make_world(&w, 64, 40, 5, NULL, 0u);
    assert_int_equal(run_select(&w, &c0, &rv, &a), TRN_OK);
    assert_int_equal(run_select(&w, &ch, &rv, &b), TRN_OK);
    assert_int_equal(a.res.n_candidates, b.res.n_candidates);
    assert_int_equal(a.res.n_informative, b.res.n_informative);
    for (i = 0; i < a.res.n_candidates; ++i) {
        const trn_candidate_t *p = &a.c[i], *q = &b.c[i];
        const double s = (double)ch.sigma_heading_rad;
        const double dx = (double)q->x - 30.0, dy = (double)q->y - 30.0;
        const double r = hypot(dx, dy) * CELLM, al = atan2(dy, dx);
        const double tx = -sin(al), ty = cos(al);
        double d0, d1, d2, along_x, along_y;
        assert_int_equal(p->x, q->x);
        assert_int_equal(p->y, q->y);
        assert_memory_equal(p->ll, q->ll, sizeof p->ll);
        assert_int_equal(p->informative, q->informative);
        if (!q->informative) {
            assert_true(isinf(q->uncertainty_m) && q->heading_m == 0.0);
            continue;
        }
        d0 = q->cov_m2[0] - p->cov_m2[0];
        d1 = q->cov_m2[1] - p->cov_m2[1];
        d2 = q->cov_m2[2] - p->cov_m2[2];
        assert_true(fabs(d0 - s * s * r * r * tx * tx) <= 1e-12 * (1.0 + q->cov_m2[0]));
        assert_true(fabs(d1 - s * s * r * r * ty * ty) <= 1e-12 * (1.0 + q->cov_m2[1]));
        assert_true(fabs(d2 - s * s * r * r * tx * ty) <= 1e-12 * (1.0 + fabs(q->cov_m2[2])));
        /* along the line of sight (dx, dy) the term is zero */
        along_x = d0 * dx + d2 * dy;
        along_y = d2 * dx + d1 * dy;
        assert_true(fabs(along_x) + fabs(along_y) <= 1e-12 * (fabs(dx) + fabs(dy)));
        assert_true(fabs(q->uncertainty_m * q->uncertainty_m -
                         (p->uncertainty_m * p->uncertainty_m + s * s * r * r)) <=
                    1e-12 * q->uncertainty_m * q->uncertainty_m);
        assert_true(fabs(q->sigma_x_m * q->sigma_x_m - q->cov_m2[0]) <=
                    1e-15 + 1e-12 * q->cov_m2[0]);
        assert_true(fabs(q->sigma_y_m * q->sigma_y_m - q->cov_m2[1]) <=
                    1e-15 + 1e-12 * q->cov_m2[1]);
        assert_true(fabs(q->rho * q->sigma_x_m * q->sigma_y_m - q->cov_m2[2]) <= 1e-15);
        assert_true(q->rho > -1.0 && q->rho < 1.0);
        assert_true(fabs(q->heading_m - s * (double)q->range_m) <= 1e-15);
        if (q->x == 36 && q->y == 38) { /* offset (6, 8): 1 m */
            assert_true(fabs(d0 - 0.0064) <= 1e-9 && fabs(d1 - 0.0036) <= 1e-9 &&
                        fabs(d2 + 0.0048) <= 1e-9);
            ++hand;
        }
    }
    assert_int_equal(hand, 1u);
    sel_free(&a);
    sel_free(&b);
    selworld_free(&w);
}

/* The best target with sigma > 0 is the argmin of u0^2 + s_h^2 r^2 over the
 * sigma-0 candidates (ties to the earlier in lattice order), the ranked list
 * is ordered by the new scalar, and the best target's range does not grow
 * with the sigma. Prints the best target per sigma. */
static void test_best_is_argmin(void **state)
{
    static const float sig[] = {0.0f, 0.005f, 0.01f, 0.02f, 0.05f, 0.1f, 0.2f, 0.5f};
    selworld_t w;
    trn_select_cfg_t c0, ch;
    trn_rover_t rv = {{40.0f, 37.0f}, 0.0f};
    sel_t a;
    size_t j, i;
    double last_range = HUGE_VAL;
    (void)state;
    small_cfg(&c0);
    make_world(&w, 80, 60, 11, NULL, 0u);
    assert_int_equal(run_select(&w, &c0, &rv, &a), TRN_OK);
    for (j = 0; j < sizeof sig / sizeof sig[0]; ++j) {
        sel_t b;
        size_t arg = a.res.n_candidates, k;
        double vmin = HUGE_VAL;
        const double s = (double)sig[j];
        ch = c0;
        ch.sigma_heading_rad = sig[j];
        assert_int_equal(run_select(&w, &ch, &rv, &b), TRN_OK);
        for (i = 0; i < a.res.n_candidates; ++i) {
            const double dx = (double)a.c[i].x - 40.0, dy = (double)a.c[i].y - 37.0;
            const double v = a.c[i].uncertainty_m * a.c[i].uncertainty_m +
                             s * s * (dx * dx + dy * dy) * CELLM * CELLM;
            if (a.c[i].informative && v < vmin * (1.0 - 1e-12)) {
                vmin = v;
                arg = i;
            }
        }
        assert_true(arg < a.res.n_candidates);
        assert_true(fabs(b.c[b.res.best].uncertainty_m * b.c[b.res.best].uncertainty_m - vmin) <=
                    1e-12 * vmin);
        assert_int_equal(b.res.best, arg);
        for (k = 1; k < b.res.n_ranked; ++k) {
            assert_true(b.c[b.ranked[k]].uncertainty_m >= b.c[b.ranked[0]].uncertainty_m);
        }
        printf("  sigma_heading %.3f rad (%5.2f deg): best (%d, %d) at %.2f m, %.1f mm "
               "(fit %.1f mm, heading %.1f mm)\n",
               s, s * 180.0 / 3.14159265358979, (int)b.c[arg].x, (int)b.c[arg].y,
               (double)b.c[arg].range_m, 1e3 * b.c[arg].uncertainty_m, 1e3 * a.c[arg].uncertainty_m,
               1e3 * b.c[arg].heading_m);
        assert_true((double)b.c[arg].range_m <= last_range);
        last_range = (double)b.c[arg].range_m;
        sel_free(&b);
    }
    sel_free(&a);
    selworld_free(&w);
}

/* The model against the matcher itself: the patch of a ranked target is
 * sensed with the heading off by dtheta (its local DEM rendered from the
 * terrain at the rover-relative offsets turned by dtheta, grown by the
 * high-pass reach, high-passed, the patch's voxels kept) and localized by
 * trn_localize_points (x and y). The position error should be r dtheta
 * across the line of sight and nothing along it. The patch centre stands in
 * for the structure's centroid (method.md 4), so a lenient bound per case and
 * a tighter one on the mean ratio; the numbers are printed. */
#define HP_M 10 /* the map's high-pass half-width, cells (trn_map_cfg_default at 0.1 m) */
static trn_point_t g_pts[20000];

static void sensed_turned(const selworld_t *w, int rx, int ry, int ox, int oy, int half, double dth,
                          size_t *np)
{
    const int side = 2 * (half + HP_M) + 1;
    float *dem = malloc(sizeof(float) * side * side), *hp = malloc(sizeof(float) * side * side);
    const size_t hb = trn_highpass_workspace_bytes(side, side);
    void *hws = selworld_alloc(hb);
    trn_grid_f32_t dg, hg;
    const double c = cos(dth), sn = sin(dth);
    int i, j;
    for (j = 0; j < side; ++j) {
        for (i = 0; i < side; ++i) {
            const double a = (double)(ox - half - HP_M + i), b = (double)(oy - half - HP_M + j);
            const double mx = a * c - b * sn, my = a * sn + b * c;
            dem[j * side + i] = (float)synth_height(&g_t, ((double)rx + mx) * CELL,
                                                    ((double)ry + my) * CELL);
        }
    }
    assert_int_equal(trn_grid_f32_init(&dg, dem, (size_t)side * side, side, side), TRN_OK);
    assert_int_equal(trn_grid_f32_init(&hg, hp, (size_t)side * side, side, side), TRN_OK);
    assert_int_equal(trn_highpass(&dg, &w->cfg.terrain, &hg, hws, hb), TRN_OK);
    for (j = 0; j < side; ++j) { /* keep the patch: the margin only fed the filter */
        for (i = 0; i < side; ++i) {
            if (i < HP_M || j < HP_M || i >= side - HP_M || j >= side - HP_M) {
                hp[j * side + i] = NAN;
            }
        }
    }
    assert_int_equal(trn_occupancy_points(&hg, &w->cfg.terrain, half + HP_M - ox, half + HP_M - oy,
                                          g_pts, sizeof g_pts / sizeof g_pts[0], np),
                     TRN_OK);
    free(dem);
    free(hp);
    free(hws);
}

static void test_lever_arm_measured(void **state)
{
    static const double dth[] = {0.05, -0.05};
    selworld_t w;
    trn_select_cfg_t cfg;
    trn_rover_t rv = {{64.0f, 64.0f}, 0.0f};
    const trn_window_t win = {56, 56, 72, 72};
    sel_t a;
    size_t k, q, n = 0u, lb;
    double sum_ratio = 0.0, sum_along = 0.0, sum_res2 = 0.0;
    void *lws;
    (void)state;
    trn_select_cfg_default(&cfg);
    cfg.min_range_m = 1.5f;
    cfg.max_range_m = 4.0f;
    cfg.min_separation_m = 1.0f;
    make_world(&w, 128, 150, 17, NULL, 0u);
    assert_int_equal(run_select(&w, &cfg, &rv, &a), TRN_OK);
    lb = trn_localize_workspace_bytes(&w.map, &win);
    lws = selworld_alloc(lb);
    for (k = 0; k < a.res.n_ranked; ++k) {
        const trn_candidate_t *c = &a.c[a.ranked[k]];
        const int ox = c->x - 64, oy = c->y - 64;
        const double r = hypot((double)ox, (double)oy); /* cells */
        const double tx = -(double)oy / r, ty = (double)ox / r;
        for (q = 0; q < 2; ++q) {
            trn_loc_result_t res;
            size_t np;
            double ex, ey, across, along;
            sensed_turned(&w, 64, 64, ox, oy, a.res.patch_cells / 2, dth[q], &np);
            if (trn_localize_points(&w.map, g_pts, np, &win, lws, lb, &res) != TRN_OK) {
                continue; /* no finite fit: nothing to compare */
            }
            ex = res.x - 64.0;
            ey = res.y - 64.0;
            across = ex * tx + ey * ty;
            along = (ex * (double)ox + ey * (double)oy) / r;
            printf("  target %.2f m, fit %.1f mm, dtheta %+.2f rad: error across %+.2f cells "
                   "(model %+.2f), along %+.2f cells\n",
                   r * CELLM, 1e3 * c->uncertainty_m, dth[q], across, r * dth[q], along);
            /* the terrain seen at offsets turned by dtheta: the matcher moves
             * the rover by r dtheta across the line of sight */
            assert_true(fabs(across - r * dth[q]) <= 0.5 * r * fabs(dth[q]) + 0.5);
            assert_true(fabs(along) <= 1.0);
            sum_ratio += across / (r * dth[q]);
            sum_along += fabs(along);
            sum_res2 += (across - r * dth[q]) * (across - r * dth[q]);
            ++n;
        }
    }
    assert_true(n >= 8u);
    printf("  %zu cases: mean (error across) / (r dtheta) %.3f, RMS (error across - r dtheta) "
           "%.2f cells, mean |error along| %.2f cells\n",
           n, sum_ratio / (double)n, sqrt(sum_res2 / (double)n), sum_along / (double)n);
    assert_true(fabs(sum_ratio / (double)n - 1.0) <= 0.2);
    free(lws);
    sel_free(&a);
    selworld_free(&w);
}

/* Constructed: on flat ground, a cluster of three rocks 1.8 m west of the
 * rover and one rock 0.8 m east. With the heading known the cluster wins
 * (more structure: 75.5 against 116.5 mm); with a heading sigma of 0.1 rad
 * the near rock does (its lever arm 80 mm against 180 mm). */
static void test_nearer_preferred(void **state)
{
    static const synth_rock_t rocks[] = {
        {1.2, 3.0, 0.15, 0.15},  {1.05, 2.8, 0.12, 0.12},
        {1.3, 3.25, 0.14, 0.14}, {1.0, 3.2, 0.10, 0.10}, /* far cluster */
        {3.8, 3.0, 0.15, 0.15},                          /* near rock */
    };
    selworld_t w;
    trn_select_cfg_t cfg;
    trn_rover_t rv = {{30.0f, 30.0f}, 0.0f};
    sel_t a, b;
    const trn_candidate_t *ba, *bb;
    (void)state;
    small_cfg(&cfg);
    make_world(&w, 60, 0u, 1, rocks, sizeof rocks / sizeof rocks[0]);
    assert_int_equal(run_select(&w, &cfg, &rv, &a), TRN_OK);
    {
        static const float sw[] = {0.01f, 0.02f, 0.03f, 0.05f, 0.1f, 0.2f};
        size_t q;
        for (q = 0; q < 6; ++q) {
            sel_t t;
            cfg.sigma_heading_rad = sw[q];
            assert_int_equal(run_select(&w, &cfg, &rv, &t), TRN_OK);
            printf("  sigma_heading %.3f rad: best (%d, %d) %.2f m away, %.1f mm (fit %.1f mm)\n",
                   (double)sw[q], (int)t.c[t.res.best].x, (int)t.c[t.res.best].y,
                   (double)t.c[t.res.best].range_m, 1e3 * t.c[t.res.best].uncertainty_m,
                   1e3 * a.c[t.res.best].uncertainty_m);
            sel_free(&t);
        }
    }
    cfg.sigma_heading_rad = 0.1f; /* 5.7 deg */
    assert_int_equal(run_select(&w, &cfg, &rv, &b), TRN_OK);
    ba = &a.c[a.res.best];
    bb = &b.c[b.res.best];
    printf("  known heading: best (%d, %d) %.2f m away, %.1f mm; sigma_heading 0.1 rad: "
           "(%d, %d) %.2f m away, %.1f mm (heading part %.1f mm)\n",
           (int)ba->x, (int)ba->y, (double)ba->range_m, 1e3 * ba->uncertainty_m, (int)bb->x,
           (int)bb->y, (double)bb->range_m, 1e3 * bb->uncertainty_m, 1e3 * bb->heading_m);
    assert_true(ba->x < 30 && ba->range_m > 1.4f); /* the far cluster, west */
    assert_true(bb->x > 30 && bb->range_m < 1.1f); /* the near rock, east */
    /* the far winner is still the better fit: the heading's term decided */
    assert_true(a.c[b.res.best].uncertainty_m > ba->uncertainty_m);
    sel_free(&a);
    sel_free(&b);
    selworld_free(&w);
}

/* The field with an uncertain heading: trn_field and trn_field_fast agree
 * bit for bit (every position of a small map, then coarse to fine), the
 * value at a position is trn_select's best there, and the field is higher
 * than with a known heading. */
static void field_pair(const selworld_t *w, const trn_select_cfg_t *sc, const trn_field_cfg_t *fc,
                       float heading, const trn_window_t *area, trn_field_stats_t *st, float *out)
{
    const int32_t aw = area->x1 - area->x0 + 1, ah = area->y1 - area->y0 + 1;
    const size_t n = (size_t)aw * (size_t)ah;
    float *o2 = malloc(n * sizeof(float));
    uint8_t *e1 = malloc(n), *e2 = malloc(n);
    trn_grid_f32_t g1, g2;
    trn_field_stats_t s2;
    const size_t b1 = trn_field_workspace_bytes(sc, &w->map, &w->k);
    const size_t b2 = trn_field_fast_workspace_bytes(sc, &w->map, &w->k, &w->pg);
    void *ws1 = selworld_alloc(b1), *ws2 = selworld_alloc(b2);
    assert_int_equal(trn_grid_f32_init(&g1, out, n, aw, ah), TRN_OK);
    assert_int_equal(trn_grid_f32_init(&g2, o2, n, aw, ah), TRN_OK);
    assert_int_equal(
        trn_field(&w->map, &w->k, &w->pg, sc, fc, heading, area, &g1, e1, n, st, ws1, b1), TRN_OK);
    assert_int_equal(
        trn_field_fast(&w->map, &w->k, &w->pg, sc, fc, heading, area, &g2, e2, n, &s2, ws2, b2),
        TRN_OK);
    assert_memory_equal(out, o2, n * sizeof(float));
    assert_memory_equal(e1, e2, n);
    assert_int_equal(st->evaluations, s2.evaluations);
    assert_int_equal(st->best_x, s2.best_x);
    assert_int_equal(st->best_y, s2.best_y);
    assert_true(st->best_m == s2.best_m);
    printf("  sigma_heading %.3f rad, area (%d,%d)-(%d,%d): %u evaluations, best %.6f m at "
           "(%d, %d)\n",
           (double)sc->sigma_heading_rad, (int)area->x0, (int)area->y0, (int)area->x1,
           (int)area->y1, st->evaluations, st->best_m, (int)st->best_x, (int)st->best_y);
    free(o2);
    free(e1);
    free(e2);
    free(ws1);
    free(ws2);
}

static void test_field_equal(void **state)
{
    selworld_t w;
    trn_select_cfg_t sc;
    trn_field_cfg_t fc;
    trn_field_stats_t s0, s1;
    const trn_window_t all = {0, 0, 47, 47}, inner = {12, 10, 59, 57};
    float *f0 = malloc(80 * 80 * sizeof(float)), *f1 = malloc(80 * 80 * sizeof(float));
    trn_rover_t rv;
    sel_t a;
    (void)state;
    trn_field_cfg_default(&fc);

    /* every position of a 48 x 48 map */
    make_world(&w, 48, 30, 3, NULL, 0u);
    small_cfg(&sc);
    sc.max_range_m = 1.5f;
    fc.coarse_step_cells = 1;
    sc.sigma_heading_rad = 0.03f;
    field_pair(&w, &sc, &fc, 0.0f, &all, &s1, f1);
    assert_int_equal((int)s1.evaluations, 48 * 48);
    /* a position's value is trn_select's best there */
    rv.pos.x_cells = 20.0f;
    rv.pos.y_cells = 25.0f;
    rv.heading_rad = 0.0f;
    assert_int_equal(run_select(&w, &sc, &rv, &a), TRN_OK);
    assert_true(f1[25 * 48 + 20] == (float)a.c[a.res.best].uncertainty_m);
    sel_free(&a);
    sc.sigma_heading_rad = 0.0f;
    field_pair(&w, &sc, &fc, 0.0f, &all, &s0, f0);
    assert_true(s1.best_m > s0.best_m);
    selworld_free(&w);

    /* coarse to fine, restricted pan, large sigma (the skip bound dominated by the heading) */
    make_world(&w, 80, 60, 21, NULL, 0u);
    small_cfg(&sc);
    fc.coarse_step_cells = 8;
    sc.sigma_heading_rad = TRN_SELECT_MAX_SIGMA_HEADING_RAD;
    field_pair(&w, &sc, &fc, 0.0f, &inner, &s1, f1);
    sc.sigma_heading_rad = 0.01f;
    sc.pan_min_rad = -1.0f;
    sc.pan_max_rad = 2.0f;
    sc.stride_cells = 1;
    field_pair(&w, &sc, &fc, 0.7f, &inner, &s1, f1);
    selworld_free(&w);
    free(f0);
    free(f1);
}

/* Bad sigma: NaN, negative, above the largest, infinite -> TRN_E_ARG from
 * the check and from every entry that takes the configuration; the largest
 * itself is accepted. */
static void test_bad_sigma(void **state)
{
    static const float bad[] = {-1.0e-6f, -0.1f, 0.5000001f, 1.0f, 3.2f};
    selworld_t w;
    trn_select_cfg_t c, b;
    trn_field_cfg_t fc;
    trn_rover_t rv = {{30.0f, 30.0f}, 0.0f};
    const trn_window_t area = {28, 28, 31, 31};
    float out[16];
    uint8_t ev[16];
    trn_grid_f32_t g;
    trn_field_stats_t st;
    trn_candidate_t cands[4];
    trn_select_result_t res;
    size_t rk[2], i;
    uint8_t ws[64];
    (void)state;
    small_cfg(&c);
    trn_field_cfg_default(&fc);
    make_world(&w, 60, 20, 2, NULL, 0u);
    assert_int_equal(trn_grid_f32_init(&g, out, 16u, 4, 4), TRN_OK);
    b = c;
    b.sigma_heading_rad = TRN_SELECT_MAX_SIGMA_HEADING_RAD;
    assert_int_equal(trn_select_cfg_check(&b, (float)CELL), TRN_OK);
    for (i = 0; i < sizeof bad / sizeof bad[0] + 3u; ++i) {
        b = c;
        b.sigma_heading_rad = i < sizeof bad / sizeof bad[0]         ? bad[i]
                              : i == sizeof bad / sizeof bad[0]      ? NAN
                              : i == sizeof bad / sizeof bad[0] + 1u ? INFINITY
                                                                     : -INFINITY;
        assert_int_equal(trn_select_cfg_check(&b, (float)CELL), TRN_E_ARG);
        assert_int_equal(trn_select_max_candidates(&b, (float)CELL), 0u);
        assert_int_equal(trn_select_workspace_bytes(&b, &w.map, &w.k), 0u);
        assert_int_equal(
            trn_select(&w.map, &w.k, &w.pg, &b, &rv, cands, 4u, rk, 2u, &res, ws, sizeof ws),
            TRN_E_ARG);
        assert_int_equal(trn_field_workspace_bytes(&b, &w.map, &w.k), 0u);
        assert_int_equal(trn_field_fast_workspace_bytes(&b, &w.map, &w.k, &w.pg), 0u);
        assert_int_equal(
            trn_field(&w.map, &w.k, &w.pg, &b, &fc, 0.0f, &area, &g, ev, 16u, &st, ws, sizeof ws),
            TRN_E_ARG);
        assert_int_equal(trn_field_fast(&w.map, &w.k, &w.pg, &b, &fc, 0.0f, &area, &g, ev, 16u, &st,
                                        ws, sizeof ws),
                         TRN_E_ARG);
    }
    selworld_free(&w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_zero_is_the_paper), cmocka_unit_test(test_added_term),
        cmocka_unit_test(test_best_is_argmin),    cmocka_unit_test(test_lever_arm_measured),
        cmocka_unit_test(test_nearer_preferred),  cmocka_unit_test(test_field_equal),
        cmocka_unit_test(test_bad_sigma),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
