/* SPDX-License-Identifier: Apache-2.0 */
/* test_select.c - landmark selection (select.h).
 *
 * ln p(d) changes sign (p1's peak density exceeds 1 per metre), so a patch
 * sum can nearly cancel; the relative check is against sum |P ln p|.
 *
 * Oracles: brute-force per-candidate sums of P(v) ln p(D(v + d)) in double
 * over each patch (the dynamic programming must agree), the brute-force
 * argmin of the fitted uncertainty, an independent enumeration of the
 * candidate rules, a one-rock terrain (the target must cover the rock), a
 * featureless terrain (no informative target), greedy ranking re-checked. */
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
#define PI 3.14159265358979323846

static synth_rock_t g_rocks[1000];

/* Small reach so the brute force stays quick under ASan and qemu. */
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

static void make_world(selworld_t *w, int n, size_t nrocks, double bg, uint64_t seed,
                       const synth_rock_t *fixed)
{
    synth_terrain_t t;
    float *dem = malloc(sizeof(float) * n * n);
    trn_sigma_model_t gm;
    trn_xy_t s = {(float)n / 2.0f, (float)n / 2.0f};
    synth_make(&t, g_rocks, nrocks, n * CELL, 0.05, 0.3, 0.5, bg, seed);
    if (fixed != NULL) {
        g_rocks[0] = *fixed;
        t.n_rocks = 1;
    }
    synth_render(&t, dem, n, n, 0.0, 0.0, CELL);
    trn_sigma_global_default(&gm);
    assert_int_equal(selworld_init(w, n, dem, &gm, &s, 1), TRN_OK);
    free(dem);
}

typedef struct {
    trn_candidate_t *c;
    size_t cap, ranked[16];
    trn_select_result_t res;
    void *ws;
    size_t wsb;
} sel_t;

static trn_status_t run_select(selworld_t *w, const trn_select_cfg_t *cfg, const trn_rover_t *rv,
                               sel_t *s, size_t nrank)
{
    s->cap = trn_select_max_candidates(cfg, (float)CELL);
    s->wsb = trn_select_workspace_bytes(cfg, &w->map, &w->k);
    assert_true(s->cap > 0u && s->wsb > 0u);
    s->c = malloc(s->cap * sizeof *s->c);
    s->ws = selworld_alloc(s->wsb);
    return trn_select(&w->map, &w->k, &w->pg, cfg, rv, s->c, s->cap, s->ranked, nrank, &s->res,
                      s->ws, s->wsb);
}

static void sel_free(sel_t *s)
{
    free(s->c);
    free(s->ws);
}

/* P over the result's region, as trn_select computed it (eq. 9). */
static float *region_p(selworld_t *w, const trn_select_cfg_t *cfg, const trn_rover_t *rv,
                       const trn_window_t *roi, trn_vol_f32_t *p)
{
    size_t wb = trn_prob_local_workspace_bytes(&w->k, roi);
    void *ws = selworld_alloc(wb);
    p->nx = roi->x1 - roi->x0 + 1;
    p->ny = roi->y1 - roi->y0 + 1;
    p->nz = w->pg.nz;
    p->data = malloc(sizeof(float) * p->nx * p->ny * p->nz);
    assert_int_equal(
        trn_prob_local(&w->k, &cfg->local_sigma, (float)CELL, rv->pos, &w->pg, roi, p, ws, wb),
        TRN_OK);
    free(ws);
    return p->data;
}

/* Brute force: E[ln L(d)] of the patch centred at (cx, cy), double. */
static void brute_ll(const selworld_t *w, const trn_vol_f32_t *p, const trn_window_t *roi, int cx,
                     int cy, int half, double ll[9], double labs_sum[9], double *bound)
{
    const trn_vol_u8_t *D = &w->map.dist;
    const int cap = w->map.lnp.cap;
    double lmax = 0.0;
    int d, x, y, z, i;
    size_t nv = 0;
    for (i = 0; i <= cap; ++i) {
        lmax = fmax(lmax, fabs((double)w->map.lnp.lnp[i] / TRN_LNP_SCALE));
    }
    for (d = 0; d < 9; ++d) {
        const int dx = d % 3 - 1, dy = d / 3 - 1;
        double s = 0.0, sa = 0.0;
        nv = 0;
        for (z = 0; z < p->nz; ++z) {
            for (y = cy - half; y <= cy + half; ++y) {
                for (x = cx - half; x <= cx + half; ++x) {
                    int dv = cap;
                    double pv;
                    if (x < 0 || y < 0 || x >= D->nx || y >= D->ny) {
                        continue; /* patch clipped to the map */
                    }
                    pv = p->data[((size_t)z * p->ny + (y - roi->y0)) * p->nx + (x - roi->x0)];
                    if (x + dx >= 0 && x + dx < D->nx && y + dy >= 0 && y + dy < D->ny) {
                        dv = D->data[TRN_VOL_IDX(D, x + dx, y + dy, z)];
                        dv = dv < cap ? dv : cap;
                    }
                    s += pv * (double)w->map.lnp.lnp[dv] / TRN_LNP_SCALE;
                    sa += fabs(pv * (double)w->map.lnp.lnp[dv] / TRN_LNP_SCALE);
                    ++nv;
                }
            }
        }
        ll[d] = s;
        labs_sum[d] = sa;
    }
    /* P is rounded to 1/65536 in the DP: at most half of that per voxel */
    *bound = (double)nv * 0.5 / TRN_SELECT_PROB_SCALE * lmax + 1e-9;
}

static double fit_unc(const double ll[9])
{
    trn_peak_t pk;
    if (trn_peak_fit(ll, &pk) != TRN_OK) {
        return HUGE_VAL;
    }
    return sqrt(pk.sigma_x * pk.sigma_x + pk.sigma_y * pk.sigma_y) * CELL;
}

static void test_dp_equals_brute_force(void **state)
{
    selworld_t w;
    trn_select_cfg_t cfg;
    int t;
    double worst_rel = 0.0;
    (void)state;
    small_cfg(&cfg);
    make_world(&w, 80, 60, 0.15, 11, NULL);
    for (t = 0; t < 4; ++t) {
        trn_rover_t rv;
        sel_t s;
        trn_vol_f32_t p;
        size_t i, bf_best = (size_t)-1, n_inf = 0;
        double bf_min = HUGE_VAL;
        rv.pos.x_cells = 10.0f + 19.3f * (float)t; /* near a border first */
        rv.pos.y_cells = 70.0f - 17.6f * (float)t;
        rv.heading_rad = 0.3f * (float)t;
        assert_int_equal(run_select(&w, &cfg, &rv, &s, 3), TRN_OK);
        region_p(&w, &cfg, &rv, &s.res.roi, &p);
        for (i = 0; i < s.res.n_candidates; ++i) {
            double ll[9], labs_sum[9], bound, u;
            int d;
            brute_ll(&w, &p, &s.res.roi, s.c[i].x, s.c[i].y, s.res.patch_cells / 2, ll, labs_sum,
                     &bound);
            for (d = 0; d < 9; ++d) {
                const double e = fabs(ll[d] - s.c[i].ll[d]);
                assert_true(e <= bound);
                assert_true(e <= 1e-4 * labs_sum[d] + 1e-12);
                worst_rel = fmax(worst_rel, e / fmax(labs_sum[d], 1e-300));
            }
            u = fit_unc(ll);
            assert_int_equal(s.c[i].informative, isfinite(u) ? 1 : 0);
            if (isfinite(u)) {
                ++n_inf;
                assert_true(fabs(u - s.c[i].uncertainty_m) <= 1e-3 * u);
                if (u < bf_min) {
                    bf_min = u;
                    bf_best = i;
                }
            }
        }
        assert_int_equal(n_inf, s.res.n_informative);
        assert_true(n_inf > 0);
        /* the selected target is the brute-force argmin (or ties it to 1e-6) */
        assert_true(s.res.best == bf_best ||
                    fabs(s.c[s.res.best].uncertainty_m - bf_min) <= 1e-6 * bf_min);
        assert_true(s.res.best == s.ranked[0]);
        printf("rover (%.1f, %.1f): %zu candidates, %zu informative, best (%d, %d) %.4f m\n",
               (double)rv.pos.x_cells, (double)rv.pos.y_cells, s.res.n_candidates, n_inf,
               (int)s.c[s.res.best].x, (int)s.c[s.res.best].y, s.c[s.res.best].uncertainty_m);
        free(p.data);
        sel_free(&s);
    }
    printf("worst |DP - brute force| / sum |P ln p| = %.3g\n", worst_rel);
    selworld_free(&w);
}

/* The paper-like defaults (1-10 m, 2 m patches) on a 240 x 240 map, stride 4
 * to keep the brute force short: every 5th candidate re-summed, the best
 * must be the brute-force argmin over all of them. */
static void test_defaults_one_position(void **state)
{
    selworld_t w;
    trn_select_cfg_t cfg;
    trn_rover_t rv = {{118.6f, 121.2f}, 0.7f};
    sel_t s;
    trn_vol_f32_t p;
    size_t i, bf_best = (size_t)-1;
    double bf_min = HUGE_VAL;
    (void)state;
    trn_select_cfg_default(&cfg);
    cfg.stride_cells = 4;
    make_world(&w, 240, 900, 0.15, 17, NULL);
    assert_int_equal(run_select(&w, &cfg, &rv, &s, 5), TRN_OK);
    assert_int_equal(s.res.patch_cells, 21);
    region_p(&w, &cfg, &rv, &s.res.roi, &p);
    for (i = 0; i < s.res.n_candidates; ++i) {
        double ll[9], la[9], bound, u;
        int d;
        if (i % 5 != 0 && s.c[i].uncertainty_m > 1.5 * s.c[s.res.best].uncertainty_m) {
            continue; /* sampled, plus every candidate that could compete */
        }
        brute_ll(&w, &p, &s.res.roi, s.c[i].x, s.c[i].y, 10, ll, la, &bound);
        for (d = 0; d < 9; ++d) {
            assert_true(fabs(ll[d] - s.c[i].ll[d]) <= bound);
        }
        u = fit_unc(ll);
        if (u < bf_min) {
            bf_min = u;
            bf_best = i;
        }
    }
    printf("defaults: %zu candidates, %zu informative, region %dx%d, best (%d, %d) %.4f m\n",
           s.res.n_candidates, s.res.n_informative, (int)(s.res.roi.x1 - s.res.roi.x0 + 1),
           (int)(s.res.roi.y1 - s.res.roi.y0 + 1), (int)s.c[s.res.best].x, (int)s.c[s.res.best].y,
           s.c[s.res.best].uncertainty_m);
    assert_true(s.res.best == bf_best ||
                fabs(s.c[s.res.best].uncertainty_m - bf_min) <= 1e-6 * bf_min);
    for (i = 0; i < s.res.n_candidates; ++i) {
        assert_true(s.c[i].range_m >= 1.0f && s.c[i].range_m <= 10.0f);
    }
    free(p.data);
    sel_free(&s);
    selworld_free(&w);
}

static void test_candidate_rules_and_ranking(void **state)
{
    selworld_t w;
    trn_select_cfg_t cfg;
    trn_rover_t rv = {{40.4f, 37.8f}, 1.0f};
    sel_t s;
    size_t i, j, k, count = 0;
    int ix, iy;
    const int half = 4;
    (void)state;
    small_cfg(&cfg);
    cfg.pan_min_rad = -1.2f;
    cfg.pan_max_rad = 0.8f;
    make_world(&w, 80, 60, 0.15, 5, NULL);
    assert_int_equal(run_select(&w, &cfg, &rv, &s, 8), TRN_OK);
    /* independent enumeration */
    for (iy = -40; iy <= 40; ++iy) {
        for (ix = -40; ix <= 40; ++ix) {
            const int cx = 40 + 2 * ix, cy = 38 + 2 * iy;
            const double dx = cx - 40.4, dy = cy - 37.8, r = hypot(dx, dy) * CELL;
            double b = atan2(dy, dx) - 1.0, ex, ey;
            int found = 0;
            b = b > PI ? b - 2 * PI : (b < -PI ? b + 2 * PI : b);
            ex = fmax(fabs(dx) - half - 0.5, 0.0);
            ey = fmax(fabs(dy) - half - 0.5, 0.0);
            if (cx < half + 1 || cy < half + 1 || cx > 78 - half || cy > 78 - half || r < 0.5 ||
                r > 2.0 || hypot(ex, ey) * CELL < 0.3 || b < -1.2 || b > 0.8) {
                continue;
            }
            ++count;
            for (i = 0; i < s.res.n_candidates; ++i) {
                found |= s.c[i].x == cx && s.c[i].y == cy;
            }
            assert_true(found);
        }
    }
    assert_int_equal(count, s.res.n_candidates);
    for (i = 0; i < s.res.n_candidates; ++i) {
        assert_true(s.c[i].bearing_rad >= -1.2f && s.c[i].bearing_rad <= 0.8f);
    }
    /* ranking: greedy lowest-first with the separation, re-checked */
    assert_true(s.res.n_ranked >= 2);
    for (k = 0; k < s.res.n_ranked; ++k) {
        const trn_candidate_t *ck = &s.c[s.ranked[k]];
        assert_true(ck->informative);
        for (j = 0; j < k; ++j) {
            const trn_candidate_t *cj = &s.c[s.ranked[j]];
            assert_true(hypot(ck->x - cj->x, ck->y - cj->y) * CELL >= 0.45 - 1e-9);
            assert_true(cj->uncertainty_m <= ck->uncertainty_m);
        }
        for (i = 0; i < s.res.n_candidates; ++i) { /* nothing better was eligible */
            int eligible = s.c[i].informative;
            for (j = 0; j < k; ++j) {
                eligible &= i != s.ranked[j] &&
                            hypot(s.c[i].x - s.c[s.ranked[j]].x, s.c[i].y - s.c[s.ranked[j]].y) *
                                    CELL >=
                                0.45;
            }
            assert_true(!eligible || s.c[i].uncertainty_m >= ck->uncertainty_m);
        }
    }
    sel_free(&s);
    selworld_free(&w);
}

static void test_one_rock(void **state)
{
    selworld_t w;
    trn_select_cfg_t cfg;
    sel_t s;
    const synth_rock_t rock = {4.7, 3.1, 0.25, 0.25}; /* cell (47, 31) */
    trn_rover_t rv = {{32.0f, 32.0f}, 0.0f};
    const trn_candidate_t *b;
    (void)state;
    small_cfg(&cfg);
    make_world(&w, 64, 0, 0.0, 1, &rock);
    assert_int_equal(run_select(&w, &cfg, &rv, &s, 3), TRN_OK);
    b = &s.c[s.res.best];
    printf("one rock at (47, 31): best target (%d, %d), %.4f m; %zu of %zu informative\n",
           (int)b->x, (int)b->y, b->uncertainty_m, s.res.n_informative, s.res.n_candidates);
    assert_true(abs(b->x - 47) <= s.res.patch_cells / 2 && abs(b->y - 31) <= s.res.patch_cells / 2);
    sel_free(&s);
    selworld_free(&w);
}

static void test_featureless(void **state)
{
    selworld_t w;
    trn_select_cfg_t cfg;
    sel_t s;
    trn_rover_t rv = {{40.0f, 40.0f}, 0.0f};
    size_t i;
    (void)state;
    small_cfg(&cfg);
    make_world(&w, 80, 0, 0.0, 1, NULL);
    assert_int_equal(run_select(&w, &cfg, &rv, &s, 3), TRN_E_NOTARGET);
    assert_true(s.res.n_candidates > 0u);
    assert_int_equal(s.res.n_informative, 0u);
    assert_int_equal(s.res.n_ranked, 0u);
    for (i = 0; i < s.res.n_candidates; ++i) {
        assert_false(s.c[i].informative);
        assert_true(isinf(s.c[i].uncertainty_m));
    }
    sel_free(&s);
    selworld_free(&w);
}

static void test_bad_inputs(void **state)
{
    selworld_t w;
    trn_select_cfg_t cfg, bad;
    trn_rover_t rv = {{40.0f, 40.0f}, 0.0f}, rb;
    trn_candidate_t *c;
    trn_select_result_t res;
    trn_vol_f32_t pg2;
    size_t cap, wsb, rk[4];
    void *ws;
    (void)state;
    small_cfg(&cfg);
    make_world(&w, 80, 40, 0.1, 3, NULL);
    cap = trn_select_max_candidates(&cfg, (float)CELL);
    wsb = trn_select_workspace_bytes(&cfg, &w.map, &w.k);
    c = malloc(cap * sizeof *c);
    ws = selworld_alloc(wsb);
#define SEL(m, k, pg, cf, r, cc, cp, rr, rc, re, wp, wb) \
    trn_select(m, k, pg, cf, r, cc, cp, rr, rc, re, wp, wb)
    assert_int_equal(SEL(&w.map, &w.k, &w.pg, &cfg, &rv, c, cap, rk, 4, &res, ws, wsb), TRN_OK);
    assert_int_equal(SEL(NULL, &w.k, &w.pg, &cfg, &rv, c, cap, rk, 4, &res, ws, wsb), TRN_E_NULL);
    assert_int_equal(SEL(&w.map, NULL, &w.pg, &cfg, &rv, c, cap, rk, 4, &res, ws, wsb), TRN_E_NULL);
    assert_int_equal(SEL(&w.map, &w.k, NULL, &cfg, &rv, c, cap, rk, 4, &res, ws, wsb), TRN_E_NULL);
    assert_int_equal(SEL(&w.map, &w.k, &w.pg, NULL, &rv, c, cap, rk, 4, &res, ws, wsb), TRN_E_NULL);
    assert_int_equal(SEL(&w.map, &w.k, &w.pg, &cfg, NULL, c, cap, rk, 4, &res, ws, wsb),
                     TRN_E_NULL);
    assert_int_equal(SEL(&w.map, &w.k, &w.pg, &cfg, &rv, NULL, cap, rk, 4, &res, ws, wsb),
                     TRN_E_NULL);
    assert_int_equal(SEL(&w.map, &w.k, &w.pg, &cfg, &rv, c, cap, NULL, 4, &res, ws, wsb),
                     TRN_E_NULL);
    assert_int_equal(SEL(&w.map, &w.k, &w.pg, &cfg, &rv, c, cap, rk, 4, NULL, ws, wsb), TRN_E_NULL);
    assert_int_equal(SEL(&w.map, &w.k, &w.pg, &cfg, &rv, c, cap, rk, 4, &res, NULL, wsb),
                     TRN_E_NULL);
    bad = cfg;
    bad.max_range_m = NAN;
    assert_int_equal(SEL(&w.map, &w.k, &w.pg, &bad, &rv, c, cap, rk, 4, &res, ws, wsb), TRN_E_ARG);
    assert_int_equal(trn_select_cfg_check(&bad, 0.1f), TRN_E_ARG);
    assert_int_equal(trn_select_max_candidates(&bad, 0.1f), 0u);
    assert_int_equal(trn_select_workspace_bytes(&bad, &w.map, &w.k), 0u);
    bad = cfg;
    bad.min_range_m = 3.0f; /* > max */
    assert_int_equal(trn_select_cfg_check(&bad, 0.1f), TRN_E_ARG);
    bad = cfg;
    bad.pan_min_rad = 1.0f;
    bad.pan_max_rad = 0.5f;
    assert_int_equal(trn_select_cfg_check(&bad, 0.1f), TRN_E_ARG);
    bad = cfg;
    bad.stride_cells = 0;
    assert_int_equal(trn_select_cfg_check(&bad, 0.1f), TRN_E_ARG);
    bad = cfg;
    bad.patch_m = 0.14f; /* 1 cell < 3 */
    assert_int_equal(trn_select_cfg_check(&bad, 0.1f), TRN_E_ARG);
    bad = cfg;
    bad.local_sigma.k_per_m = -1.0f;
    assert_int_equal(trn_select_cfg_check(&bad, 0.1f), TRN_E_ARG);
    assert_int_equal(trn_select_cfg_check(NULL, 0.1f), TRN_E_NULL);
    assert_int_equal(trn_select_cfg_check(&cfg, 0.0f), TRN_E_ARG);
    rb = rv;
    rb.heading_rad = INFINITY;
    assert_int_equal(SEL(&w.map, &w.k, &w.pg, &cfg, &rb, c, cap, rk, 4, &res, ws, wsb), TRN_E_ARG);
    rb = rv;
    rb.pos.x_cells = 200.0f;
    assert_int_equal(SEL(&w.map, &w.k, &w.pg, &cfg, &rb, c, cap, rk, 4, &res, ws, wsb),
                     TRN_E_RANGE);
    pg2 = w.pg;
    pg2.nz -= 1;
    assert_int_equal(SEL(&w.map, &w.k, &pg2, &cfg, &rv, c, cap, rk, 4, &res, ws, wsb), TRN_E_SIZE);
    assert_int_equal(SEL(&w.map, &w.k, &w.pg, &cfg, &rv, c, 10, rk, 4, &res, ws, wsb),
                     TRN_E_CAPACITY);
    assert_int_equal(SEL(&w.map, &w.k, &w.pg, &cfg, &rv, c, cap, rk, 0, &res, ws, wsb),
                     TRN_E_CAPACITY);
    assert_int_equal(SEL(&w.map, &w.k, &w.pg, &cfg, &rv, c, cap, rk, 4, &res, ws, wsb - 1),
                     TRN_E_WORKSPACE);
    /* nothing within reach: the rover in a corner looking off the map */
    rb.pos.x_cells = 0.0f;
    rb.pos.y_cells = 0.0f;
    rb.heading_rad = (float)(-3.0 * PI / 4.0);
    bad = cfg;
    bad.pan_min_rad = -0.3f;
    bad.pan_max_rad = 0.3f;
    assert_int_equal(SEL(&w.map, &w.k, &w.pg, &bad, &rb, c, cap, rk, 4, &res, ws, wsb),
                     TRN_E_NOTARGET);
    assert_int_equal(res.n_candidates, 0u);
#undef SEL
    free(c);
    free(ws);
    selworld_free(&w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dp_equals_brute_force),
        cmocka_unit_test(test_defaults_one_position),
        cmocka_unit_test(test_candidate_rules_and_ranking),
        cmocka_unit_test(test_one_rock),
        cmocka_unit_test(test_featureless),
        cmocka_unit_test(test_bad_inputs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
