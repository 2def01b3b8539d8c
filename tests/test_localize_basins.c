/* SPDX-License-Identifier: Apache-2.0 */
/* test_localize_basins.c - the height matcher's far basins (TRN_REFINE_BASINS,
 * docs/method.md 9): a sub-cell peak that scores low at its integer poses is
 * still refined, and becomes the answer when its refined ln L beats the
 * answer's by more than TRN_REFINE_FAR_NATS; the grid's failure
 * probability then flags it (the grid's mass lies with the basin it left).
 *
 * Oracles (a rock-like terrain of Gaussian bumps a cell or two wide on 1 m
 * cells; local maps are full discs of its bilinear interpolation, no noise):
 * - a decoy: the local heights written into the map on whole cells elsewhere
 *   in the window, each off by a fixed +-2 cm pattern. The decoy's integer
 *   pose scores higher than any integer pose of the truth (checked with
 *   trn_height_search: the precondition, where the search alone goes wrong,
 *   and where the code before far basins answered the decoy with a failure
 *   probability of 1e-144), yet the truth's refined ln L is higher by more
 *   than TRN_REFINE_FAR_NATS: the answer is the truth, within 0.02 cell,
 *   flagged TRN_E_AMBIGUOUS. Brought closer (10 down to 8 mm off) the
 *   decoy's ln L rises towards the truth's: the answer moves to the truth
 *   while it wins by more than TRN_REFINE_FAR_NATS over the inflation, then
 *   stays the decoy, flagged with the far basins' failure probability (the
 *   truth's refined ln L against it), at least 1/2 while the truth's is the
 *   higher: no confident wrong answer, and a margin of a few nats, a tie
 *   the data do not break, does not move the answer;
 * - a twin: the terrain around the truth copied 17 and 14 cells away, so two
 *   basins are equal to the last bit: neither replaces the other, the failure
 *   probability is 0.3-0.75, status TRN_E_AMBIGUOUS;
 * - the decoys at 2 cm through the search over heading (+-2 degrees): its
 *   far basins (src/height_heading.c) move the answer to the truth too,
 *   flagged by the grid's mass at the decoy;
 * - with no decoy and no twin the answer is the truth and nothing moves.
 */
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
#include "trn/height_heading.h"
#include "trn/localize.h"
#include "trn/refine.h"

#define GW 72           /* global side, cells of 1 m */
#define LR 7            /* local disc radius, cells */
#define LW (2 * LR + 1) /* local side; rover at its centre cell */
#define MAXPTS 4096

static float g_data[GW * GW];
static float l_data[LW * LW];

/* Gaussian bumps of sd 0.9-1.4 cells and 0.4-1.2 m on a gentle slope. */
static void make_terrain(uint64_t seed)
{
    trn_rng_t r;
    int k, x, y;
    trn_rng_seed(&r, seed);
    for (y = 0; y < GW; ++y) {
        for (x = 0; x < GW; ++x) {
            g_data[y * GW + x] = (float)(0.02 * x - 0.01 * y);
        }
    }
    for (k = 0; k < 600; ++k) {
        double cx = trn_rng_unit(&r) * GW, cy = trn_rng_unit(&r) * GW;
        double s = 0.9 + 0.5 * trn_rng_unit(&r), h = 0.4 + 0.8 * trn_rng_unit(&r);
        for (y = 0; y < GW; ++y) {
            for (x = 0; x < GW; ++x) {
                double d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
                if (d2 < 25.0 * s * s) {
                    g_data[y * GW + x] += (float)(h * exp(-0.5 * d2 / (s * s)));
                }
            }
        }
    }
}

static double bilin(double x, double y)
{
    int x0 = (int)floor(x), y0 = (int)floor(y);
    double fx = x - x0, fy = y - y0;
    const float *p = &g_data[y0 * GW + x0];
    return (1.0 - fy) * ((1.0 - fx) * p[0] + fx * p[1]) +
           fy * ((1.0 - fx) * p[GW] + fx * p[GW + 1]);
}

/* The local disc seen from (tx, ty) (global cells), the rover cell unseen. */
static void make_local(double tx, double ty, trn_grid_f32_t *l)
{
    int i, j;
    for (j = 0; j < LW; ++j) {
        for (i = 0; i < LW; ++i) {
            int dx = i - LR, dy = j - LR;
            l_data[j * LW + i] = (dx == 0 && dy == 0) || dx * dx + dy * dy > LR * LR
                                     ? NAN
                                     : (float)(bilin(tx + dx, ty + dy) + 3.0);
        }
    }
    assert_int_equal(trn_grid_f32_init(l, l_data, LW * LW, LW, LW), TRN_OK);
}

/* The local heights written into the map with the rover at cell (cx, cy),
 * each off by +-off metres (a checkerboard), the disc's outside untouched. */
static void plant(int cx, int cy, double off)
{
    int i, j;
    for (j = 0; j < LW; ++j) {
        for (i = 0; i < LW; ++i) {
            float v = l_data[j * LW + i];
            if (isfinite(v)) {
                g_data[(cy + j - LR) * GW + cx + i - LR] = (float)((double)v - 3.0 +
                                                                   ((i + j) % 2 ? off : -off));
            }
        }
    }
}

typedef struct {
    trn_map_t map;
    void *buf, *ws;
    size_t wb;
} world_t;

static void build(world_t *w, trn_grid_f32_t *g)
{
    trn_map_cfg_t cfg;
    size_t ab, mb;
    void *aws;
    double sh;
    assert_int_equal(trn_grid_f32_init(g, g_data, GW * GW, GW, GW), TRN_OK);
    ab = trn_map_cfg_auto_workspace_bytes(GW, GW);
    aws = malloc(ab);
    assert_non_null(aws);
    trn_map_cfg_default(&cfg);
    cfg.noise_m = 0.01f;
    cfg.noise_k_per_m = 0.0004f;
    assert_int_equal(trn_map_cfg_auto(&cfg, g, 1.0f, aws, ab, &sh), TRN_OK);
    assert_int_equal(cfg.noise_auto, 1);
    /* the local maps are noise-free, which would make the height matcher
     * rescale its noise model to the floor (trn_refine_noise_scale): the
     * oracles here are the configured model's likelihoods */
    cfg.noise_auto = 0;
    free(aws);
    assert_int_equal(cfg.match, TRN_MATCH_HEIGHTS);
    mb = trn_map_bytes(&cfg, GW, GW);
    w->buf = malloc(mb);
    assert_non_null(w->buf);
    assert_int_equal(trn_map_build(&w->map, &cfg, g, w->buf, mb), TRN_OK);
    w->ws = NULL;
    w->wb = 0u;
}

static trn_status_t run(world_t *w, const trn_grid_f32_t *l, const trn_window_t *win,
                        trn_loc_result_t *res)
{
    size_t wb = trn_localize_dem_workspace_bytes(&w->map, LW, LW, MAXPTS, win);
    assert_true(wb > 0u);
    w->ws = malloc(wb);
    assert_non_null(w->ws);
    w->wb = wb;
    memset(res, 0, sizeof *res);
    return trn_localize_dem(&w->map, l, LR, LR, MAXPTS, win, w->ws, wb, res);
}

static void done(world_t *w)
{
    free(w->buf);
    free(w->ws);
}

/* The search's best integer pose alone (no refinement). */
static void grid_best(const world_t *w, const trn_grid_f32_t *g, const trn_grid_f32_t *l,
                      const trn_window_t *win, trn_height_best_t *b)
{
    trn_refine_cfg_t rc;
    rc.cell_m = w->map.cfg.terrain.cell_m;
    rc.noise_m = w->map.cfg.noise_m;
    rc.noise_k_per_m = w->map.cfg.noise_k_per_m;
    rc.inlier_prob = w->map.cfg.inlier_prob;
    rc.fit_noise = w->map.cfg.noise_auto;
    rc.centroid_x = NULL; /* the cells' centres */
    rc.centroid_y = NULL;
    rc.point_count = NULL; /* one measurement a cell */
    assert_int_equal(
        trn_height_search(g, l, LR, LR, win, NULL, &rc, w->map.cfg.inlier_prob, 1.0, NULL, b),
        TRN_OK);
}

static const trn_window_t WIN = {24, 24, 48, 48}; /* x0, y0, x1, y1 */

/* One decoy case: 1 if the decoy wins the grid (the case holds), then the
 * answer's status checked against its failure probability and its result in
 * *res; moved: 1 if the answer is the truth, 0 if it stayed the decoy. */
static int decoy_case(int seed, double off, int *moved, trn_loc_result_t *res)
{
    static const double tx = 30.45, ty = 33.35; /* the truth, sub-cell */
    trn_grid_f32_t g, l;
    trn_height_best_t gb;
    trn_status_t st;
    world_t w;
    make_terrain((uint64_t)seed);
    make_local(tx, ty, &l);
    plant(42, 40, off);
    build(&w, &g);
    grid_best(&w, &g, &l, &WIN, &gb);
    st = run(&w, &l, &WIN, res);
    printf("seed %d, decoy %.5f m off: grid best (%d, %d) ln L %.2f; answer (%.3f, %.3f) status "
           "[%s], failure probability %.3g, refined ln L %.2f, inflation %.3f\n",
           seed, off, (int)gb.x, (int)gb.y, gb.ll, res->x, res->y, trn_strerror(st),
           res->failure_probability, res->refinement.ll, res->refinement.ll_inflation);
    done(&w);
    if (gb.x != 42 || gb.y != 40) {
        return 0; /* this terrain's truth scores best on the grid: not the case */
    }
    assert_int_equal(st, res->failure_probability > TRN_MAP_MAX_FAILURE_PROB_AUTO ? TRN_E_AMBIGUOUS
                                                                                  : TRN_OK);
    *moved = fabs(res->x - tx) < 0.02 && fabs(res->y - ty) < 0.02;
    assert_true(*moved || (fabs(res->x - 42.0) < 0.05 && fabs(res->y - 40.0) < 0.05));
    assert_true(*moved == (res->ix != 42 || res->iy != 40));
    return 1;
}

static void test_decoy_loses_to_subcell_truth(void **state)
{
    int s, held = 0, moved = 0, stayed = 0, tie_kept = 0, m;
    (void)state;
    for (s = 1; s <= 4; ++s) {
        trn_loc_result_t res;
        double truth_ll;
        int left = 0, k;
        /* 2 cm: the truth's refined ln L beats the decoy's by 59-74 nats on
         * these terrains, so the answer moves */
        if (!decoy_case(s, 0.02, &m, &res)) {
            continue;
        }
        ++held;
        assert_true(m);
        assert_true(res.failure_probability > 0.5); /* the grid's mass is at the decoy */
        truth_ll = res.refinement.ll;
        /* closer: the truth's margin falls through TRN_REFINE_FAR_NATS */
        for (k = 0; k <= 8; ++k) { /* 10 mm down to 8 mm, by 0.25 mm */
            double d, share;
            if (!decoy_case(s, 0.0100 - 0.00025 * k, &m, &res)) {
                continue;
            }
            if (m) {
                assert_true(res.failure_probability > 0.5); /* the grid's mass */
                assert_false(left); /* moves only while the decoy is the farther */
                /* the truth's basin; the decoy's cells, 5-7 cells away,
                 * touch its edge and move its ln L by a fraction of a nat */
                assert_true(fabs(res.refinement.ll - truth_ll) < 1.0);
                truth_ll = res.refinement.ll;
                ++moved;
                continue;
            }
            left = 1;
            ++stayed;
            /* stayed: the truth's margin over the decoy, over the inflation,
             * is at most TRN_REFINE_FAR_NATS, and the far basins' share of
             * the failure probability is its logistic */
            d = (truth_ll - res.refinement.ll) / fmax(1.0, res.refinement.ll_inflation);
            assert_true(d <= TRN_REFINE_FAR_NATS + 1e-9);
            share = 1.0 / (1.0 + exp(-d));
            assert_true(res.failure_probability >= share - 1e-9);
            tie_kept += d > 1.0;
        }
    }
    assert_true(held >= 3); /* the decoy wins the grid on most terrains */
    assert_true(moved >= 3 && stayed >= 3);
    assert_true(tie_kept >= 1); /* a truth 1-3 nats better does not move it */
}

/* A copy of the terrain around the truth, a whole number of cells away:
 * two basins equal to the last bit, one of them sub-cell at both. */
static void twin(int dx, int dy, int r)
{
    static float snap[GW * GW];
    int x, y;
    memcpy(snap, g_data, sizeof snap);
    for (y = 33 - r; y <= 33 + r; ++y) {
        for (x = 30 - r; x <= 30 + r; ++x) {
            g_data[(y + dy) * GW + x + dx] = snap[y * GW + x];
        }
    }
}

static void test_twin_is_ambiguous(void **state)
{
    static const double tx = 30.45, ty = 33.35;
    int s;
    (void)state;
    for (s = 1; s <= 4; ++s) {
        trn_grid_f32_t g, l;
        trn_loc_result_t res;
        trn_status_t st;
        world_t w;
        make_terrain((uint64_t)s);
        twin(17, 14, LR + 2);
        make_local(tx, ty, &l);
        build(&w, &g);
        st = run(&w, &l, &WIN, &res);
        printf("seed %d twin: answer (%.3f, %.3f) status [%s], failure probability %.3g\n", s,
               res.x, res.y, trn_strerror(st), res.failure_probability);
        done(&w);
        assert_int_equal(st, TRN_E_AMBIGUOUS);
        assert_true(res.failure_probability >= 0.3 && res.failure_probability <= 0.75);
        assert_true((fabs(res.x - tx) < 0.02 && fabs(res.y - ty) < 0.02) ||
                    (fabs(res.x - tx - 17.0) < 0.02 && fabs(res.y - ty - 14.0) < 0.02));
    }
}

/* The same decoys through the search over heading (+-2 degrees about 0;
 * W = 0 at centre 0 would be trn_localize_dem itself): its far basins
 * (src/height_heading.c's refine_starts), at their own headings, move the
 * answer to the truth by the same rule: within 0.02 cell of it, the
 * heading within 0.2 degree of 0, the start no longer the decoy's, and the
 * grid's mass, at the decoy, in the failure probability (above 1/2). */
static void test_decoy_over_heading(void **state)
{
    static const double tx = 30.45, ty = 33.35;
    int s, held = 0;
    (void)state;
    for (s = 1; s <= 4; ++s) {
        trn_grid_f32_t g, l;
        trn_heading_result_t hr;
        trn_heading_cfg_t hc;
        trn_height_best_t gb;
        trn_status_t sh;
        world_t w;
        size_t hb;
        void *hws;
        make_terrain((uint64_t)s);
        make_local(tx, ty, &l);
        plant(42, 40, 0.02);
        build(&w, &g);
        grid_best(&w, &g, &l, &WIN, &gb);
        hc.center_rad = 0.0;
        hc.window_rad = 2.0 * 3.14159265358979323846 / 180.0;
        hc.step_rad = 0.0;
        hb = trn_localize_dem_heading_workspace_bytes_cfg(&w.map, &l, LR, LR, MAXPTS, &WIN, &hc);
        assert_true(hb > 0u);
        hws = malloc(hb);
        assert_non_null(hws);
        memset(&hr, 0, sizeof hr);
        sh = trn_localize_dem_heading(&w.map, &l, LR, LR, MAXPTS, &WIN, &hc, hws, hb, &hr);
        printf("seed %d over heading: answer (%.3f, %.3f) at %.3f deg, start (%d, %d), status "
               "[%s], failure probability %.3g\n",
               s, hr.loc.x, hr.loc.y, hr.heading_rad * 180.0 / 3.14159265358979323846,
               (int)hr.loc.ix, (int)hr.loc.iy, trn_strerror(sh), hr.loc.failure_probability);
        free(hws);
        done(&w);
        if (gb.x != 42 || gb.y != 40) {
            continue; /* the truth scores best on the grid: not the case */
        }
        ++held;
        assert_int_equal(sh, TRN_E_AMBIGUOUS);
        assert_true(fabs(hr.loc.x - tx) < 0.02 && fabs(hr.loc.y - ty) < 0.02);
        assert_true(fabs(hr.heading_rad) < 0.2 * 3.14159265358979323846 / 180.0);
        assert_true(hr.loc.ix != 42 || hr.loc.iy != 40);
        assert_true(hr.loc.failure_probability > 0.5);
    }
    assert_true(held >= 3);
}

static void test_alone_unchanged(void **state)
{
    static const double tx = 30.45, ty = 33.35;
    int s;
    (void)state;
    for (s = 1; s <= 4; ++s) {
        trn_grid_f32_t g, l;
        trn_loc_result_t res;
        trn_status_t st;
        world_t w;
        make_terrain((uint64_t)s);
        make_local(tx, ty, &l);
        build(&w, &g);
        st = run(&w, &l, &WIN, &res);
        printf("seed %d alone: answer (%.3f, %.3f) status [%s], failure probability %.3g\n", s,
               res.x, res.y, trn_strerror(st), res.failure_probability);
        done(&w);
        assert_int_equal(st, TRN_OK);
        assert_true(fabs(res.x - tx) < 0.02 && fabs(res.y - ty) < 0.02);
        assert_true(res.failure_probability < 1e-3);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_decoy_loses_to_subcell_truth),
        cmocka_unit_test(test_decoy_over_heading),
        cmocka_unit_test(test_twin_is_ambiguous),
        cmocka_unit_test(test_alone_unchanged),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
