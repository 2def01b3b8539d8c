/* SPDX-License-Identifier: Apache-2.0 */
/* test_select_search.c - selection for a matcher that searches the heading
 * too (trn_select_cfg_t.heading_search; select.h, method.md 4, "Patches that
 * pin the heading down").
 *
 * Oracles: a slow, obvious computation of the (x, y, heading) information
 * voxel by voxel (eq. 9 from trn_prob_local, each voxel's nine terms, its
 * share A_v = -L(terms) of eq. 6's Hessian, b = sum A_v J u_v, c = sum
 * (J u_v)^T A_v J u_v with u_v from the rover, the marginal by a 3 x 3
 * inverse) against trn_select's moment tables for every candidate; the
 * limits (sigma 0: the known heading's bytes; a lone rock at the patch
 * centre: the lever arm's term; structure spread across the patch: a
 * smaller heading part); the field (trn_field_fast runs trn_field's path:
 * equal bytes); every bad value of the flag. */
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
#define CELLM ((double)(float)CELL)

static synth_rock_t g_rocks[400];
static size_t g_negative;   /* candidates whose heading information was floored */
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

/* The slow oracle for candidate c: cov (m^2) and the heading part (m). */
static void oracle(const selworld_t *w, const trn_vol_f32_t *p, const trn_window_t *roi,
                   const trn_candidate_t *c, int32_t half, double rxf, double ryf, double sh,
                   double cov[3], double *head_m)
{
    const trn_vol_u8_t *d = &w->map.dist;
    const uint8_t cap = w->map.lnp.cap;
    const double sc = 1.0 / ((double)TRN_SELECT_PROB_SCALE * (double)TRN_LNP_SCALE);
    double a[3][3] = {{0.0}}, inv[3][3], det;
    int32_t x, y, z, k;
    for (y = c->y - half; y <= c->y + half; ++y) {
        for (x = c->x - half; x <= c->x + half; ++x) {
            for (z = 0; z < p->nz; ++z) {
                const float pv =
                    p->data[((size_t)z * (size_t)p->ny + (size_t)(y - roi->y0)) * (size_t)p->nx +
                            (size_t)(x - roi->x0)];
                double t[9], hxx = 0.0, hyy = 0.0, hxy = 0.0, ux, uy, jx, jy;
                int32_t q;
                if (!(pv > 0.0f)) {
                    continue;
                }
                q = pv >= 4.0f ? 4 * TRN_SELECT_PROB_SCALE
                               : (int32_t)(pv * (float)TRN_SELECT_PROB_SCALE + 0.5f);
                for (k = 0; k < 9; ++k) {
                    const int32_t gx = x + k % 3 - 1, gy = y + k / 3 - 1;
                    uint8_t dv = cap;
                    if (gx >= 0 && gy >= 0 && gx < d->nx && gy < d->ny) {
                        dv = d->data[TRN_VOL_IDX(d, gx, gy, z)];
                    }
                    dv = dv < cap ? dv : cap;
                    t[k] = (double)q * (double)w->map.lnp.lnp[dv] * sc;
                }
                for (k = 0; k < 9; ++k) { /* eq. 6's Hessian, voxel v's share */
                    const double lx = (double)(k % 3 - 1), ly = (double)(k / 3 - 1);
                    hxx += (lx * lx - 2.0 / 3.0) * t[k];
                    hyy += (ly * ly - 2.0 / 3.0) * t[k];
                    hxy += lx * ly / 4.0 * t[k];
                }
                ux = (double)x - rxf;
                uy = (double)y - ryf;
                jx = -uy; /* J u */
                jy = ux;
                /* information of (dx, dy, theta): A_v on [I, J u] */
                a[0][0] -= hxx;
                a[0][1] -= hxy;
                a[1][1] -= hyy;
                a[0][2] -= hxx * jx + hxy * jy;
                a[1][2] -= hxy * jx + hyy * jy;
                a[2][2] -= jx * (hxx * jx + hxy * jy) + jy * (hxy * jx + hyy * jy);
            }
        }
    }
    a[1][0] = a[0][1];
    a[2][0] = a[0][2];
    a[2][1] = a[1][2];
    {
        /* the heading information beyond the translation's, taken at least
         * 0 (the voxels' shares of eq. 6's fit need not be definite, so the
         * sum's Schur complement can fall below 0; the model floors it) */
        const double d2 = a[0][0] * a[1][1] - a[0][1] * a[0][1];
        const double gx = (a[1][1] * a[0][2] - a[0][1] * a[1][2]) / d2;
        const double gy = (a[0][0] * a[1][2] - a[0][1] * a[0][2]) / d2;
        const double info = a[2][2] - (a[0][2] * gx + a[1][2] * gy);
        if (info < 0.0) {
            a[2][2] -= info;
            ++g_negative;
        }
        *head_m = sqrt((gx * gx + gy * gy) / (1.0 / (sh * sh) + (info > 0.0 ? info : 0.0))) * CELLM;
    }
    a[2][2] += 1.0 / (sh * sh); /* the heading prior */
    det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
          a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
          a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    inv[0][0] = (a[1][1] * a[2][2] - a[1][2] * a[2][1]) / det;
    inv[1][1] = (a[0][0] * a[2][2] - a[0][2] * a[2][0]) / det;
    inv[0][1] = -(a[0][1] * a[2][2] - a[0][2] * a[2][1]) / det;
    cov[0] = inv[0][0] * CELLM * CELLM;
    cov[1] = inv[1][1] * CELLM * CELLM;
    cov[2] = inv[0][1] * CELLM * CELLM;
}

static int close_rel(double a, double b, double rel, double abs_tol)
{
    return fabs(a - b) <= rel * fabs(b) + abs_tol;
}

/* Every informative candidate against the slow oracle; the expected
 * log-likelihoods are the known heading's, bit for bit. */
static void test_against_oracle(void **state)
{
    static const float sig[] = {0.01f, 0.05f, 0.3f};
    static const trn_rover_t rovers[] = {{{31.0f, 28.0f}, 0.4f}, {{20.0f, 41.0f}, -2.0f}};
    selworld_t w;
    trn_select_cfg_t cfg, known;
    size_t q, r, i, checked = 0u;
    double worst = 0.0;
    (void)state;
    make_world(&w, 64, 40, 5, NULL, 0u);
    for (r = 0; r < 2; ++r) {
        for (q = 0; q < 3; ++q) {
            sel_t s, s0;
            trn_vol_f32_t p;
            size_t lw;
            void *lws;
            int32_t half;
            small_cfg(&cfg);
            cfg.sigma_heading_rad = sig[q];
            cfg.heading_search = 1;
            known = cfg;
            known.heading_search = 0;
            assert_int_equal(run_select(&w, &cfg, &rovers[r], &s), TRN_OK);
            assert_int_equal(run_select(&w, &known, &rovers[r], &s0), TRN_OK);
            assert_int_equal(s.res.n_candidates, s0.res.n_candidates);
            p.nx = s.res.roi.x1 - s.res.roi.x0 + 1;
            p.ny = s.res.roi.y1 - s.res.roi.y0 + 1;
            p.nz = w.pg.nz;
            p.data = malloc((size_t)p.nx * (size_t)p.ny * (size_t)p.nz * sizeof(float));
            lw = trn_prob_local_workspace_bytes(&w.k, &s.res.roi);
            lws = selworld_alloc(lw);
            assert_int_equal(trn_prob_local(&w.k, &cfg.local_sigma, (float)CELL, rovers[r].pos,
                                            &w.pg, &s.res.roi, &p, lws, lw),
                             TRN_OK);
            half = s.res.patch_cells / 2;
            for (i = 0; i < s.res.n_candidates; ++i) {
                const trn_candidate_t *c = &s.c[i];
                double cov[3], hm;
                assert_memory_equal(c->ll, s0.c[i].ll, sizeof c->ll);
                assert_int_equal(c->informative, s0.c[i].informative);
                if (!c->informative) {
                    continue;
                }
                oracle(&w, &p, &s.res.roi, c, half, (double)rovers[r].pos.x_cells,
                       (double)rovers[r].pos.y_cells, (double)sig[q], cov, &hm);
                assert_true(close_rel(c->cov_m2[0], cov[0], 1e-7, 1e-15));
                assert_true(close_rel(c->cov_m2[1], cov[1], 1e-7, 1e-15));
                assert_true(close_rel(c->cov_m2[2], cov[2], 1e-7, 1e-15 + 1e-7 * fabs(cov[0])));
                assert_true(close_rel(c->heading_m, hm, 1e-6, 1e-12));
                assert_true(close_rel(c->uncertainty_m, sqrt(cov[0] + cov[1]), 1e-7, 0.0));
                worst = fmax(worst, fabs(c->cov_m2[0] - cov[0]) / cov[0]);
                ++checked;
            }
            free(p.data);
            free(lws);
            sel_free(&s);
            sel_free(&s0);
        }
    }
    printf("  %zu candidates against the voxel-by-voxel oracle, worst relative var_x %.2e; "
           "heading information floored at 0 in %zu\n",
           checked, worst, g_negative);
    assert_true(checked > 300u);
    selworld_free(&w);
}

/* Sigma 0 with the flag: the known heading's bytes (the flag alone changes
 * nothing); the flag 0 with sigma > 0: the lever arm (test_select_heading). */
static void test_zero_sigma(void **state)
{
    selworld_t w;
    trn_select_cfg_t a, b;
    trn_rover_t rv = {{31.3f, 28.6f}, 0.4f};
    sel_t sa, sb;
    (void)state;
    make_world(&w, 64, 40, 7, NULL, 0u);
    small_cfg(&a);
    b = a;
    b.heading_search = 1;
    assert_int_equal(trn_select_workspace_bytes(&a, &w.map, &w.k),
                     trn_select_workspace_bytes(&b, &w.map, &w.k));
    assert_int_equal(run_select(&w, &a, &rv, &sa), TRN_OK);
    assert_int_equal(run_select(&w, &b, &rv, &sb), TRN_OK);
    assert_memory_equal(sa.c, sb.c, sa.res.n_candidates * sizeof *sa.c);
    assert_memory_equal(sa.ranked, sb.ranked, sa.res.n_ranked * sizeof sa.ranked[0]);
    sel_free(&sa);
    sel_free(&sb);
    selworld_free(&w);
}

/* The candidate centred at (cx, cy), or NULL. */
static const trn_candidate_t *at(const sel_t *s, int32_t cx, int32_t cy)
{
    size_t i;
    for (i = 0; i < s->res.n_candidates; ++i) {
        if (s->c[i].x == cx && s->c[i].y == cy) {
            return &s->c[i];
        }
    }
    return NULL;
}

/* Flat ground with a lone rock 1.6 m east of the rover and four rocks spread
 * across a 2 m patch 1.6 m west. 2 m patches, s_h = 0.1 rad. The lone rock's
 * patch centred on it: its heading part is the lever arm s_h r within a few
 * per cent (structure at the centre: g = J offset, no heading information);
 * the spread patch pins the heading: its heading part is well below s_h r
 * and below what the lever arm predicts for it, and it is preferred. */
static void test_spread_pins_heading(void **state)
{
    static const synth_rock_t rocks[] = {
        {4.6, 3.0, 0.12, 0.12},                           /* lone rock, east */
        {0.7, 2.3, 0.12, 0.12},  {0.75, 3.7, 0.12, 0.12}, /* spread, west */
        {1.7, 2.35, 0.12, 0.12}, {1.65, 3.65, 0.12, 0.12},
    };
    selworld_t w;
    trn_select_cfg_t cfg, lever;
    trn_rover_t rv = {{30.0f, 30.0f}, 0.0f};
    sel_t s, sl;
    const trn_candidate_t *lone, *spread, *lone_l, *spread_l;
    (void)state;
    make_world(&w, 60, 0u, 1, rocks, sizeof rocks / sizeof rocks[0]);
    trn_select_cfg_default(&cfg);
    cfg.min_range_m = 1.0f;
    cfg.max_range_m = 2.0f;
    cfg.stride_cells = 1;
    cfg.sigma_heading_rad = 0.1f;
    lever = cfg;
    cfg.heading_search = 1;
    assert_int_equal(run_select(&w, &cfg, &rv, &s), TRN_OK);
    assert_int_equal(run_select(&w, &lever, &rv, &sl), TRN_OK);
    lone = at(&s, 46, 30);
    spread = at(&s, 14, 30);
    lone_l = at(&sl, 46, 30);
    spread_l = at(&sl, 14, 30);
    assert_non_null(lone);
    assert_non_null(spread);
    assert_true(lone->informative && spread->informative);
    printf("  lone rock 1.6 m: heading part %.1f mm (lever arm %.1f mm), total %.1f mm (%.1f)\n",
           1e3 * lone->heading_m, 1e3 * lone_l->heading_m, 1e3 * lone->uncertainty_m,
           1e3 * lone_l->uncertainty_m);
    printf("  spread rocks 1.6 m: heading part %.1f mm (lever arm %.1f mm), total %.1f mm "
           "(%.1f)\n",
           1e3 * spread->heading_m, 1e3 * spread_l->heading_m, 1e3 * spread->uncertainty_m,
           1e3 * spread_l->uncertainty_m);
    printf("  best: (%d, %d) %.1f mm; with the lever arm (%d, %d) %.1f mm\n",
           (int)s.c[s.res.best].x, (int)s.c[s.res.best].y, 1e3 * s.c[s.res.best].uncertainty_m,
           (int)sl.c[sl.res.best].x, (int)sl.c[sl.res.best].y,
           1e3 * sl.c[sl.res.best].uncertainty_m);
    assert_true(fabs(lone->heading_m / lone_l->heading_m - 1.0) < 0.05);
    assert_true(spread->heading_m < 0.75 * spread_l->heading_m);
    assert_true(spread->uncertainty_m < spread_l->uncertainty_m);
    assert_true(lone->uncertainty_m <= lone_l->uncertainty_m * 1.05);
    assert_true(s.c[s.res.best].x < 30); /* the spread patch side wins */
    sel_free(&s);
    sel_free(&sl);
    selworld_free(&w);
}

/* The 3-DOF matcher itself on the two patches of test_spread_pins_heading,
 * each sensed alone with the heading off by dtheta (the terrain rendered at
 * the rover-relative offsets turned by dtheta, high-passed, the patch's
 * voxels kept, as test_select_heading's lever-arm check), matched by
 * trn_localize_points_heading over +-0.3 rad: the spread patch gives back
 * the heading and the position (error far below the lever arm r dtheta, as
 * predicted); the lone rock cannot pin the heading: a turn about the rover
 * and a shift along the tangent look alike, and the matcher's own failure
 * probability says so (0.27-0.5), the lever arm's case. */
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
    for (j = 0; j < side; ++j) {
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

static void test_matcher_agrees(void **state)
{
    static const synth_rock_t rocks[] = {
        {4.6, 3.0, 0.2, 0.2},     {0.7, 2.3, 0.2, 0.2},   {0.75, 3.7, 0.2, 0.2},
        {1.7, 2.35, 0.2, 0.2},    {1.65, 3.65, 0.2, 0.2}, {1.2, 2.25, 0.15, 0.15},
        {1.25, 3.75, 0.15, 0.15},
    };
    static const double dth[] = {-0.2, -0.1, 0.1, 0.2};
    static const int pox[] = {-16, 16}; /* the spread patch (west), the lone rock (east) */
    const trn_window_t win = {22, 22, 38, 38};
    trn_heading_cfg_t hc = {0.0, 0.3, 0.0};
    selworld_t w;
    size_t q, p, lb;
    void *lws;
    (void)state;
    make_world(&w, 60, 0u, 1, rocks, sizeof rocks / sizeof rocks[0]);
    lb = trn_localize_heading_workspace_bytes(&w.map, sizeof g_pts / sizeof g_pts[0], &win);
    assert_true(lb > 0u);
    lws = selworld_alloc(lb);
    for (p = 0; p < 2; ++p) {
        double worst_h = 0.0, worst_e = 0.0, pf_min = 1.0;
        for (q = 0; q < 4; ++q) {
            trn_heading_result_t res;
            size_t np;
            trn_status_t st;
            double h, err;
            sensed_turned(&w, 30, 30, pox[p], 0, 10, dth[q], &np);
            st = trn_localize_points_heading(&w.map, g_pts, np, &win, &hc, lws, lb, &res);
            /* the best integer pose is valid when the 3-D fit is not
             * (TRN_E_ILLCOND): a noise-free patch 1.6 m away couples a
             * heading step with a shift of 0.6-0.9 cells, a ridge for the
             * 3 x 3 x 3 fit */
            assert_true(st == TRN_OK || st == TRN_E_ILLCOND);
            h = (double)res.best_step * res.step_rad;
            err = hypot((double)res.loc.ix - 30.0, (double)res.loc.iy - 30.0);
            printf("  %s, dtheta %+.2f rad: heading %+.3f rad, position error %.2f cells (lever "
                   "arm %.2f), failure probability %.3f (%s)\n",
                   p == 0 ? "spread" : "lone rock", dth[q], h, err, 16.0 * fabs(dth[q]),
                   res.loc.failure_probability, trn_strerror(st));
            worst_h = fmax(worst_h, fabs(h + dth[q]));
            worst_e = fmax(worst_e, err / (16.0 * fabs(dth[q])));
            pf_min = fmin(pf_min, res.loc.failure_probability);
        }
        if (p == 0) { /* pinned: the heading back within 2 steps, the position far inside the
                         lever arm r dtheta */
            assert_true(worst_h <= 0.075);
            assert_true(worst_e <= 0.35);
            assert_true(pf_min < 0.01);
        } else { /* not pinned: a turn about the rover and a shift look alike; the
                    matcher says so itself */
            assert_true(pf_min >= 0.2);
        }
    }
    free(lws);
    selworld_free(&w);
}

/* The field: trn_field_fast runs trn_field's path for this prediction (no
 * ground path yet), so equal bytes; and it differs from the lever arm's. */
static void test_field(void **state)
{
    selworld_t w;
    trn_select_cfg_t sc;
    trn_field_cfg_t fc;
    const trn_window_t area = {10, 10, 37, 37};
    const size_t n = 28u * 28u;
    float *o1 = malloc(n * sizeof(float)), *o2 = malloc(n * sizeof(float));
    uint8_t *e1 = malloc(n), *e2 = malloc(n);
    trn_grid_f32_t g1, g2;
    trn_field_stats_t s1, s2;
    size_t b1, b2;
    void *ws1, *ws2;
    (void)state;
    make_world(&w, 48, 30, 3, NULL, 0u);
    small_cfg(&sc);
    sc.max_range_m = 1.5f;
    sc.sigma_heading_rad = 0.05f;
    sc.heading_search = 1;
    trn_field_cfg_default(&fc);
    fc.coarse_step_cells = 4;
    b1 = trn_field_workspace_bytes(&sc, &w.map, &w.k);
    b2 = trn_field_fast_workspace_bytes(&sc, &w.map, &w.k, &w.pg);
    assert_true(b1 > 0u && b2 == b1);
    ws1 = selworld_alloc(b1);
    ws2 = selworld_alloc(b2);
    assert_int_equal(trn_grid_f32_init(&g1, o1, n, 28, 28), TRN_OK);
    assert_int_equal(trn_grid_f32_init(&g2, o2, n, 28, 28), TRN_OK);
    assert_int_equal(
        trn_field(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g1, e1, n, &s1, ws1, b1), TRN_OK);
    assert_int_equal(
        trn_field_fast(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g2, e2, n, &s2, ws2, b2),
        TRN_OK);
    assert_memory_equal(o1, o2, n * sizeof(float));
    assert_memory_equal(e1, e2, n);
    assert_true(s1.best_m == s2.best_m);
    sc.heading_search = 0; /* the lever arm: another field (the same evaluated cells here) */
    assert_int_equal(
        trn_field(&w.map, &w.k, &w.pg, &sc, &fc, 0.0f, &area, &g2, e2, n, &s2, ws1, b1), TRN_OK);
    {
        size_t i, lower = 0u, both = 0u;
        for (i = 0; i < n; ++i) {
            if (e1[i] && e2[i] && isfinite(o1[i])) {
                ++both;
                lower += o1[i] < o2[i];
            }
        }
        printf("  %zu positions evaluated in both; the searched heading's lower at %zu\n", both,
               lower);
        assert_true(both > 20u && lower > both / 2u);
    }
    free(o1);
    free(o2);
    free(e1);
    free(e2);
    free(ws1);
    free(ws2);
    selworld_free(&w);
}

/* The flag takes 0 or 1: anything else is TRN_E_ARG from the check and from
 * every entry that takes the configuration. */
static void test_bad_flag(void **state)
{
    static const int32_t bad[] = {-1, 2, 7, INT32_MIN, INT32_MAX};
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
    c.sigma_heading_rad = 0.05f;
    trn_field_cfg_default(&fc);
    make_world(&w, 60, 20, 2, NULL, 0u);
    assert_int_equal(trn_grid_f32_init(&g, out, 16u, 4, 4), TRN_OK);
    for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        b = c;
        b.heading_search = bad[i];
        assert_int_equal(trn_select_cfg_check(&b, (float)CELL), TRN_E_ARG);
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
        cmocka_unit_test(test_against_oracle),
        cmocka_unit_test(test_zero_sigma),
        cmocka_unit_test(test_spread_pins_heading),
        cmocka_unit_test(test_matcher_agrees),
        cmocka_unit_test(test_field),
        cmocka_unit_test(test_bad_flag),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
