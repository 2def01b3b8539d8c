/* SPDX-License-Identifier: Apache-2.0 */
/* localize.c - prepared maps and end-to-end localization (see trn/localize.h). */
#include "trn/localize.h"
#include "trn/heading.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>

#include "height_bound.h"
#include "height_score.h"
#include "localize_int.h"
#include "refine_int.h"
#include "ws.h"

void trn_map_cfg_default(trn_map_cfg_t *cfg)
{
    if (cfg == NULL) {
        return;
    }
    cfg->terrain.cell_m = 0.1f;
    cfg->terrain.zbin_m = 0.1f;
    cfg->terrain.highpass_half_m = 1.0f;
    cfg->terrain.nz = 16;
    cfg->sigma_m = 0.1f;
    cfg->inlier_prob = (float)TRN_MAP_INLIER_PROB_DEFAULT;
    cfg->cap = 60u;
    cfg->levels = 4;
    cfg->min_exclusion_cells = 2;
    cfg->local_highpass = TRN_LOCAL_HP_BOX;
    cfg->refine = 0;
    cfg->noise_m = 0.01f;
    cfg->noise_k_per_m = 0.004f;
    cfg->match = TRN_MATCH_VOXEL;
    cfg->max_failure_prob = 1.0f;
    cfg->noise_auto = 0;
    cfg->search = TRN_SEARCH_EXHAUSTIVE;
    cfg->node_budget = 0u;
}

static trn_lik_cfg_t lik_of(const trn_map_cfg_t *cfg)
{
    trn_lik_cfg_t l;
    l.cell_m = cfg->terrain.cell_m;
    l.sigma_m = cfg->sigma_m;
    l.inlier_prob = cfg->inlier_prob;
    l.cap = cfg->cap;
    return l;
}

trn_status_t trn_map_cfg_check(const trn_map_cfg_t *cfg)
{
    trn_status_t st;
    trn_lik_cfg_t l;
    if (cfg == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_terrain_cfg_check(&cfg->terrain)) != TRN_OK) {
        return st;
    }
    l = lik_of(cfg);
    if ((st = trn_lik_cfg_check(&l)) != TRN_OK) {
        return st;
    }
    if (cfg->levels < 1 || cfg->levels > TRN_MAX_LEVELS || cfg->min_exclusion_cells < 1 ||
        cfg->min_exclusion_cells > TRN_MAX_DIM ||
        (cfg->local_highpass != TRN_LOCAL_HP_BOX && cfg->local_highpass != TRN_LOCAL_HP_MAP) ||
        (cfg->refine != 0 && cfg->refine != 1) || (cfg->noise_auto != 0 && cfg->noise_auto != 1) ||
        (cfg->match != TRN_MATCH_VOXEL && cfg->match != TRN_MATCH_HEIGHTS) ||
        (cfg->search != TRN_SEARCH_BOUNDED && cfg->search != TRN_SEARCH_EXHAUSTIVE) ||
        !(cfg->noise_m > 0.0f && cfg->noise_m <= 1000.0f) ||
        !(cfg->noise_k_per_m >= 0.0f && cfg->noise_k_per_m <= 1000.0f) ||
        !(cfg->max_failure_prob > 0.0f && cfg->max_failure_prob <= 1.0f)) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}

/* The configuration keeps the DEM's heights and low-pass in the map. */
static int needs_heights(const trn_map_cfg_t *cfg)
{
    return cfg->refine != 0 || cfg->local_highpass == TRN_LOCAL_HP_MAP ||
           cfg->match == TRN_MATCH_HEIGHTS;
}

/* Layout of the map buffer: [dist | pyramid | heights | lowpass | hp grid |
 * highpass scratch]; heights and lowpass only when needs_heights(), the last
 * two are scratch used only while building. */
typedef struct {
    size_t dist, pyr, heights, lowpass, hp, hpws, total;
} map_layout_t;

static int map_layout(const trn_map_cfg_t *cfg, int32_t w, int32_t h, map_layout_t *lay)
{
    size_t cells;
    trn_ws_t ws;
    if (trn_map_cfg_check(cfg) != TRN_OK || w < 1 || h < 1 || w > TRN_MAX_DIM || h > TRN_MAX_DIM) {
        return 0;
    }
    cells = (size_t)w * (size_t)h;
    trn_ws_begin(&ws, NULL);
    lay->dist = trn_ws_offset(&ws, cells * (size_t)cfg->terrain.nz);
    lay->pyr = trn_ws_offset(&ws, trn_pyramid_bytes(w, h, cfg->terrain.nz, cfg->levels));
    lay->heights = lay->lowpass = lay->hp = ws.total;
    if (needs_heights(cfg)) {
        lay->heights = trn_ws_offset(&ws, cells * sizeof(float));
        lay->lowpass = trn_ws_offset(&ws, cells * sizeof(float));
    }
    lay->hp = trn_ws_offset(&ws, cells * sizeof(float));
    lay->hpws = trn_ws_offset(&ws, trn_highpass_workspace_bytes(w, h));
    lay->total = ws.total;
    return 1;
}

size_t trn_map_bytes(const trn_map_cfg_t *cfg, int32_t width, int32_t height)
{
    map_layout_t lay;
    return map_layout(cfg, width, height, &lay) ? lay.total : 0u;
}

/* RMS of (height - mean of its 4 neighbours) over the cells whose four
 * neighbours are known. */
static double roughness(const trn_grid_f32_t *g)
{
    int32_t x, y;
    double s = 0.0;
    size_t n = 0;
    for (y = 1; y + 1 < g->height; ++y) {
        for (x = 1; x + 1 < g->width; ++x) {
            double c = (double)TRN_GRID_AT(g, x, y);
            double m = 0.25 * ((double)TRN_GRID_AT(g, x - 1, y) + (double)TRN_GRID_AT(g, x + 1, y) +
                               (double)TRN_GRID_AT(g, x, y - 1) + (double)TRN_GRID_AT(g, x, y + 1));
            if (isfinite(c) && isfinite(m)) {
                s += (c - m) * (c - m);
                ++n;
            }
        }
    }
    return n > 0u ? sqrt(s / (double)n) : 0.0;
}

trn_status_t trn_map_build(trn_map_t *map, const trn_map_cfg_t *cfg, const trn_grid_f32_t *dem,
                           void *buf, size_t len)
{
    trn_status_t st;
    map_layout_t lay;
    uint8_t *b = (uint8_t *)buf;
    trn_grid_f32_t hp;
    trn_lik_cfg_t lik;
    double k;

    if (map == NULL || cfg == NULL || dem == NULL || buf == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_grid_f32_check(dem)) != TRN_OK || (st = trn_map_cfg_check(cfg)) != TRN_OK) {
        return st;
    }
    if (!map_layout(cfg, dem->width, dem->height, &lay)) {
        return TRN_E_ARG;
    }
    if ((st = trn_ws_check(buf, len, lay.total)) != TRN_OK) {
        return st;
    }
    map->cfg = *cfg;
    if ((st = trn_grid_f32_init(&hp, (float *)(void *)(b + lay.hp),
                                (size_t)dem->width * (size_t)dem->height, dem->width,
                                dem->height)) != TRN_OK ||
        (st = trn_highpass(dem, &cfg->terrain, &hp, b + lay.hpws, lay.total - lay.hpws)) !=
            TRN_OK ||
        (st = trn_vol_u8_init(&map->dist, b + lay.dist, lay.pyr, dem->width, dem->height,
                              cfg->terrain.nz)) != TRN_OK ||
        (st = trn_occupancy(&hp, &cfg->terrain, &map->dist, &map->n_occupied)) != TRN_OK ||
        (st = trn_chamfer3d(&map->dist, &map->dist, cfg->cap)) != TRN_OK) {
        return st;
    }
    map->heights.data = NULL;
    map->lowpass.data = NULL;
    map->roughness_m = 0.0;
    map->heights.width = map->heights.height = map->heights.stride = 0;
    map->lowpass = map->heights;
    if (needs_heights(cfg)) {
        int32_t x, y;
        size_t cells = (size_t)dem->width * (size_t)dem->height;
        if ((st = trn_grid_f32_init(&map->heights, (float *)(void *)(b + lay.heights), cells,
                                    dem->width, dem->height)) != TRN_OK ||
            (st = trn_grid_f32_init(&map->lowpass, (float *)(void *)(b + lay.lowpass), cells,
                                    dem->width, dem->height)) != TRN_OK) {
            return st;
        }
        for (y = 0; y < dem->height; ++y) {
            for (x = 0; x < dem->width; ++x) {
                float v = TRN_GRID_AT(dem, x, y);
                float f = TRN_GRID_AT(&hp, x, y);
                int ok = isfinite(v) && isfinite(f);
                TRN_GRID_AT(&map->heights, x, y) = ok ? v : NAN;
                TRN_GRID_AT(&map->lowpass, x, y) = ok ? (float)((double)v - (double)f) : NAN;
            }
        }
        map->roughness_m = roughness(&map->heights);
    }
    lik = lik_of(cfg);
    if ((st = trn_outlier_density(&map->dist, &lik, &k)) != TRN_OK ||
        (st = trn_lnp_table_build(&map->lnp, &lik, k)) != TRN_OK ||
        (st = trn_pyramid_build(&map->pyr, &map->dist, cfg->cap, cfg->levels, b + lay.pyr,
                                lay.heights - lay.pyr)) != TRN_OK) {
        return st;
    }
    return TRN_OK;
}

/* trn_map_cfg_auto's carve: the high-passed grid, then trn_highpass's
 * scratch (offsets in *hp_at, *hpws_at). Returns the bytes, 0 if the size
 * is out of range. */
static size_t cfg_auto_carve(int32_t width, int32_t height, size_t *hp_at, size_t *hpws_at)
{
    size_t hpws = trn_highpass_workspace_bytes(width, height);
    trn_ws_t w;
    if (hpws == 0u) {
        return 0u;
    }
    trn_ws_begin(&w, NULL);
    *hp_at = trn_ws_offset(&w, (size_t)width * (size_t)height * sizeof(float));
    *hpws_at = trn_ws_offset(&w, hpws);
    return w.total;
}

size_t trn_map_cfg_auto_workspace_bytes(int32_t width, int32_t height)
{
    size_t hp_at, hpws_at;
    return cfg_auto_carve(width, height, &hp_at, &hpws_at);
}

trn_status_t trn_map_cfg_auto(trn_map_cfg_t *cfg, const trn_grid_f32_t *dem, float cell_m, void *ws,
                              size_t ws_bytes, double *sigma_h_m)
{
    trn_status_t st;
    trn_map_cfg_t c;
    trn_grid_f32_t hp;
    size_t need, cells, hp_at, hpws_at, n = 0;
    double s1 = 0.0, s2 = 0.0, sig, zb, noise10, r10;
    int32_t x, y;
    long nz;

    if (cfg == NULL || dem == NULL || ws == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_grid_f32_check(dem)) != TRN_OK) {
        return st;
    }
    trn_map_cfg_default(&c);
    c.noise_m = cfg->noise_m;
    c.noise_k_per_m = cfg->noise_k_per_m;
    c.terrain.cell_m = cell_m;
    c.terrain.zbin_m = cell_m;
    c.terrain.highpass_half_m = (float)TRN_MAP_HIGHPASS_CELLS * cell_m;
    c.sigma_m = cell_m;
    c.local_highpass = TRN_LOCAL_HP_MAP;
    c.refine = 1;
    c.match = TRN_MATCH_HEIGHTS;
    c.min_exclusion_cells = 1; /* failure: the answer 2 or more cells off (1.5 radial) */
    c.max_failure_prob = (float)TRN_MAP_MAX_FAILURE_PROB_AUTO;
    c.noise_auto = 1;
    if (!(cell_m > 0.0f && cell_m <= 1000.0f) || trn_map_cfg_check(&c) != TRN_OK) {
        return TRN_E_ARG;
    }
    need = cfg_auto_carve(dem->width, dem->height, &hp_at, &hpws_at);
    if (need == 0u) {
        return TRN_E_SIZE;
    }
    if ((st = trn_ws_check(ws, ws_bytes, need)) != TRN_OK) {
        return st;
    }
    cells = (size_t)dem->width * (size_t)dem->height;
    if ((st = trn_grid_f32_init(&hp, (float *)(void *)((uint8_t *)ws + hp_at), cells, dem->width,
                                dem->height)) != TRN_OK ||
        (st = trn_highpass(dem, &c.terrain, &hp, (uint8_t *)ws + hpws_at, ws_bytes - hpws_at)) !=
            TRN_OK) {
        return st;
    }
    for (y = 0; y < dem->height; ++y) {
        for (x = 0; x < dem->width; ++x) {
            float v = TRN_GRID_AT(&hp, x, y);
            if (isfinite(v)) {
                s1 += (double)v;
                s2 += (double)v * (double)v;
                ++n;
            }
        }
    }
    if (n == 0u) {
        return TRN_E_NODATA;
    }
    sig = s2 / (double)n - (s1 / (double)n) * (s1 / (double)n);
    sig = sig > 0.0 ? sqrt(sig) : 0.0;
    r10 = 10.0 * (double)cell_m;
    noise10 = (double)c.noise_m + (double)c.noise_k_per_m * r10 * r10;
    zb = 0.5 * sig > 2.0 * noise10 ? 0.5 * sig : 2.0 * noise10;
    zb = zb < (double)cell_m ? zb : (double)cell_m;
    /* half-bins over +-4 spreads, clamped in double before the conversion
     * (a spread of 1e30 m must not overflow a long) */
    {
        double half = ceil(4.0 * sig / zb);
        half = half > 64.0 ? 64.0 : half;
        nz = 2L * (long)half + 1L;
    }
    nz = nz < 16L ? 16L : nz;
    nz = nz > 64L ? 64L : nz;
    nz = nz > (long)TRN_MAX_ZBINS ? (long)TRN_MAX_ZBINS : nz;
    c.terrain.zbin_m = (float)zb;
    c.terrain.nz = (int32_t)nz;
    if ((st = trn_map_cfg_check(&c)) != TRN_OK) {
        return st;
    }
    *cfg = c;
    if (sigma_h_m != NULL) {
        *sigma_h_m = sig;
    }
    return TRN_OK;
}

int trn_loc_map_ok_(const trn_map_t *map)
{
    return trn_map_cfg_check(&map->cfg) == TRN_OK && trn_vol_u8_check(&map->dist) == TRN_OK &&
           map->pyr.nlevels == map->cfg.levels && map->lnp.cap == map->cfg.cap &&
           (!needs_heights(&map->cfg) ||
            (trn_grid_f32_check(&map->heights) == TRN_OK &&
             trn_grid_f32_check(&map->lowpass) == TRN_OK && map->heights.width == map->dist.nx &&
             map->heights.height == map->dist.ny && map->lowpass.width == map->dist.nx &&
             map->lowpass.height == map->dist.ny));
}

size_t trn_localize_workspace_bytes(const trn_map_t *map, const trn_window_t *win)
{
    if (map == NULL || win == NULL || !trn_loc_map_ok_(map)) {
        return 0u;
    }
    return trn_search_bb_workspace_bytes(&map->pyr, win);
}

static double nats(int64_t score) { return (double)score / (double)TRN_LNP_SCALE; }

/* The window holds no pose outside the zone around the answer: no competing
 * hypothesis, failure probability 0 (documented in trn_loc_result_t). */
static void no_competitor(trn_loc_result_t *out)
{
    out->has_second = 0;
    out->second_x = out->ix;
    out->second_y = out->iy;
    out->ll_second = out->ll_best;
    out->failure_probability = 0.0;
}

trn_status_t trn_localize_points(const trn_map_t *map, const trn_point_t *pts, size_t n,
                                 const trn_window_t *win, void *ws, size_t ws_bytes,
                                 trn_loc_result_t *out)
{
    trn_status_t st, fit_st;
    trn_best_t best, second;
    trn_exclusion_t ex;
    trn_peak_t pk;
    double ll[9], cell, smax;
    int32_t i, radius;

    if (map == NULL || pts == NULL || win == NULL || ws == NULL || out == NULL) {
        return TRN_E_NULL;
    }
    if (!trn_loc_map_ok_(map)) {
        return TRN_E_ARG;
    }
    if (!trn_loc_window_ok_(map, win)) {
        return TRN_E_RANGE;
    }
    if ((st = trn_ws_check(ws, ws_bytes, trn_localize_workspace_bytes(map, win))) != TRN_OK) {
        return st;
    }
    st = trn_search_bb(&map->pyr, &map->lnp, pts, n, win, NULL, ws, ws_bytes, &best, &out->stats);
    if (st != TRN_OK) {
        return st;
    }
    out->refined = 0;
    out->misfit = 0;
    out->ix = best.x;
    out->iy = best.y;
    out->ll_best = nats(best.score);
    out->n_points = n;
    out->on_window_edge = trn_loc_on_edge_(win, best.x, best.y);
    for (i = 0; i < 9; ++i) {
        int64_t s;
        if (i == 4) {
            s = best.score;
        } else if ((st = trn_score_pose(&map->dist, &map->lnp, pts, n, best.x + i % 3 - 1,
                                        best.y + i / 3 - 1, &s)) != TRN_OK) {
            return st;
        }
        ll[i] = nats(s);
    }
    cell = (double)map->cfg.terrain.cell_m;
    fit_st = trn_peak_fit(ll, &pk);
    out->x = (double)best.x + pk.dx;
    out->y = (double)best.y + pk.dy;
    out->sigma_x_m = pk.sigma_x * cell;
    out->sigma_y_m = pk.sigma_y * cell;
    out->rho = pk.rho;
    out->cov_m2[0] = pk.var_x * cell * cell;
    out->cov_m2[1] = pk.var_y * cell * cell;
    out->cov_m2[2] = pk.cov_xy * cell * cell;

    /* Competing hypothesis: best pose outside ~4 sigma of the peak. */
    radius = map->cfg.min_exclusion_cells;
    if (fit_st == TRN_OK) {
        smax = pk.sigma_x > pk.sigma_y ? pk.sigma_x : pk.sigma_y;
        if (4.0 * smax > (double)radius) {
            radius = 4.0 * smax < (double)TRN_MAX_DIM ? (int32_t)ceil(4.0 * smax) : TRN_MAX_DIM;
        }
    }
    ex.cx = best.x;
    ex.cy = best.y;
    ex.radius = radius;
    out->exclusion_cells = radius;
    st = trn_search_bb(&map->pyr, &map->lnp, pts, n, win, &ex, ws, ws_bytes, &second, NULL);
    if (st == TRN_OK) {
        out->has_second = 1;
        out->second_x = second.x;
        out->second_y = second.y;
        out->ll_second = nats(second.score);
        if ((st = trn_failure_probability(out->ll_best, out->ll_second,
                                          &out->failure_probability)) != TRN_OK) {
            return st;
        }
    } else if (st == TRN_E_NODATA) {
        no_competitor(out);
    } else {
        return st;
    }
    return fit_st == TRN_OK ? TRN_OK : TRN_E_ILLCOND;
}

/* Layout of trn_localize_dem's workspace: [hp grid | highpass ws | points | search ws | ln L grid
 * (TRN_MATCH_HEIGHTS only)]. */

typedef struct {
    size_t hp, hpws, pts, search, llgrid, cand, basins, hb, total;
} loc_layout_t;

static int loc_layout(const trn_map_t *map, int32_t w, int32_t h, size_t max_points,
                      const trn_window_t *win, loc_layout_t *lay)
{
    size_t hpws = trn_highpass_workspace_bytes(w, h);
    size_t sw = trn_localize_workspace_bytes(map, win);
    trn_ws_t ws;
    if (hpws == 0u || sw == 0u || max_points == 0u ||
        max_points > (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM) {
        return 0;
    }
    trn_ws_begin(&ws, NULL);
    lay->hp = trn_ws_offset(&ws, (size_t)w * (size_t)h * sizeof(float));
    lay->hpws = trn_ws_offset(&ws, hpws);
    lay->pts = trn_ws_offset(&ws, max_points * sizeof(trn_point_t));
    lay->search = trn_ws_offset(&ws, sw);
    lay->llgrid = lay->cand = lay->basins = lay->hb = ws.total;
    if (map->cfg.match == TRN_MATCH_HEIGHTS) { /* every pose's ln L (trn_height_search) */
        lay->llgrid = trn_ws_offset(&ws, (size_t)(win->x1 - win->x0 + 1) *
                                             (size_t)(win->y1 - win->y0 + 1) * sizeof(double));
        /* a refinement from a neighbouring start (refine_result) */
        lay->cand = trn_ws_offset(&ws, sizeof(trn_refine_t));
        lay->basins = trn_ws_offset(&ws, trn_loc_basins_bytes_()); /* far basins (refine_basins) */
        if (map->cfg.search == TRN_SEARCH_BOUNDED) {               /* the bounded search's state */
            const size_t hbb = trn_hb_bytes(win, w, h);
            if (hbb == 0u) {
                return 0;
            }
            lay->hb = trn_ws_offset(&ws, hbb);
        } else { /* the exhaustive search's scratch (trn_height_search_ws_) */
            lay->hb = trn_ws_offset(&ws, trn_hs_bytes(w, h));
        }
    }
    lay->total = ws.total;
    return 1;
}

size_t trn_localize_dem_workspace_bytes(const trn_map_t *map, int32_t width, int32_t height,
                                        size_t max_points, const trn_window_t *win)
{
    loc_layout_t lay;
    if (map == NULL || win == NULL) {
        return 0u;
    }
    return loc_layout(map, width, height, max_points, win, &lay) ? lay.total : 0u;
}

/* Local high-pass against the global low-pass (TRN_LOCAL_HP_MAP): cell
 * (x, y) of the local DEM lies on global cell (cx + x - rx, cy + y - ry) at
 * the reference pose (cx, cy); its filtered height is its height minus the
 * global low-pass there minus the mean of that difference over the seen
 * cells. A cell with no global low-pass under it is left unseen. */
trn_status_t trn_loc_highpass_by_map_(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx,
                                      int32_t ry, int32_t cx, int32_t cy, trn_grid_f32_t *out)
{
    int32_t x, y;
    double sum = 0.0, ref = 0.0;
    size_t n = 0;
    for (y = 0; y < local->height; ++y) {
        for (x = 0; x < local->width; ++x) {
            int64_t gx = (int64_t)cx + x - rx, gy = (int64_t)cy + y - ry;
            float h = TRN_GRID_AT(local, x, y), v = NAN;
            if (isfinite(h) && gx >= 0 && gy >= 0 && gx < map->lowpass.width &&
                gy < map->lowpass.height) {
                float lp = TRN_GRID_AT(&map->lowpass, (int32_t)gx, (int32_t)gy);
                if (isfinite(lp)) {
                    double d = (double)h - (double)lp;
                    if (n == 0u) {
                        ref = d;
                    }
                    sum += d - ref;
                    ++n;
                    v = (float)d;
                }
            }
            TRN_GRID_AT(out, x, y) = v;
        }
    }
    if (n == 0u) {
        return TRN_E_NODATA;
    }
    {
        double mean = ref + sum / (double)n;
        for (y = 0; y < local->height; ++y) {
            for (x = 0; x < local->width; ++x) {
                float v = TRN_GRID_AT(out, x, y);
                if (isfinite(v)) {
                    double f = (double)v - mean;
                    f = f > (double)FLT_MAX    ? (double)FLT_MAX
                        : f < -(double)FLT_MAX ? -(double)FLT_MAX
                                               : f;
                    TRN_GRID_AT(out, x, y) = (float)f;
                }
            }
        }
    }
    return TRN_OK;
}

/* 1 if the integer pose (sx, sy) is a start for the refinement beside the
 * best one: inside the window, its ln L in the grid within
 * TRN_REFINE_START_NATS of the best's. */
static int refine_start(const trn_window_t *win, const double *ll_grid, double ll_best, int32_t sx,
                        int32_t sy)
{
    if (sx < win->x0 || sx > win->x1 || sy < win->y0 || sy > win->y1) {
        return 0;
    }
    return ll_grid[(size_t)(sy - win->y0) * (size_t)(win->x1 - win->x0 + 1) +
                   (size_t)(sx - win->x0)] > ll_best - TRN_REFINE_START_NATS;
}

/* trn_refine_pose from the search's integer pose, and from each neighbour
 * refine_start takes (with the ln L grid of the height search): on terrain
 * a cell or two wide the best integer pose can lie in the basin of a lesser
 * sub-cell peak. The refinement with the highest refined ln L is kept (ties:
 * the best integer pose's); on success its pose and covariance replace
 * eq. 6's. */
static void refine_result(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx, int32_t ry,
                          const trn_window_t *win, const double *ll_grid, trn_refine_t *cand,
                          trn_loc_result_t *out)
{
    trn_refine_cfg_t rc;
    int32_t found, k;
    trn_loc_refine_cfg_(map, out, &rc);
    out->refined = 0;
    out->misfit = 0;
    found = trn_refine_pose(&map->heights, local, rx, ry, out->ix, out->iy, &rc,
                            &out->refinement) == TRN_OK;
    for (k = 0; k < 9 && cand != NULL; ++k) {
        int32_t sx = out->ix + k % 3 - 1, sy = out->iy + k / 3 - 1;
        if (k == 4 || !refine_start(win, ll_grid, out->ll_best, sx, sy)) {
            continue;
        }
        if (trn_refine_pose(&map->heights, local, rx, ry, sx, sy, &rc, cand) == TRN_OK &&
            (!found || cand->ll > out->refinement.ll)) {
            out->refinement = *cand;
            found = 1;
        }
    }
    if (!found) {
        return;
    }
    trn_loc_take_refinement_(map, out);
}

/* 1 (out->noise_scale set) if the residuals at the answer reject the noise
 * model rc (trn_loc_noise_rejected_), else 0. The answer is the refinement,
 * or where it failed the search's best integer pose with its offset and
 * model variance (at an integer pose the mix does not enter); tmp is
 * scratch for that. */
static int rescale_noise(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx, int32_t ry,
                         const trn_refine_cfg_t *rc, const trn_height_best_t *best,
                         trn_refine_t *tmp, trn_loc_result_t *out)
{
    const trn_refine_t *at = &out->refinement;
    if (!out->refined) {
        *tmp = out->refinement;
        tmp->x = (double)best->x;
        tmp->y = (double)best->y;
        tmp->dz_m = best->dz_m;
        tmp->model_m = best->model_m;
        tmp->interp_mix = TRN_REFINE_MIX_MEAN;
        at = tmp;
    }
    return trn_loc_noise_rejected_(map, local, rx, ry, at, 0.0, rc, &out->noise_scale);
}

/* One search of the window with the noise model rc: every pose scored
 * (hbws the scratch), or the bounded search in hbws (*hb its state), the
 * best pose's neighbours scored too (the second starts read them). */
static trn_status_t search_window(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx,
                                  int32_t ry, const trn_window_t *win, const trn_refine_cfg_t *rc,
                                  double *ll_grid, void *hbws, uint64_t *work, trn_hb_t **hb,
                                  trn_height_best_t *best)
{
    trn_status_t st;
    int32_t k;
    if (map->cfg.search == TRN_SEARCH_EXHAUSTIVE) {
        const uint64_t poses = (uint64_t)(win->x1 - win->x0 + 1) *
                               (uint64_t)(win->y1 - win->y0 + 1);
        if (map->cfg.node_budget != 0u && *work + poses > (uint64_t)map->cfg.node_budget) {
            return TRN_E_BUDGET; /* before the pass: its cost is its poses */
        }
        *work += poses;
        return trn_height_search_ws_(&map->heights, local, rx, ry, win, NULL, rc,
                                     map->cfg.inlier_prob, 1.0, ll_grid, hbws, best);
    }
    if ((st = trn_hb_init(hb, hbws, &map->heights, local, rx, ry, win, rc, map->cfg.inlier_prob,
                          ll_grid, work, (uint64_t)map->cfg.node_budget)) != TRN_OK ||
        (st = trn_hb_best(*hb, NULL, best)) != TRN_OK) {
        return st;
    }
    for (k = 0; k < 9; ++k) {
        const int32_t sx = best->x + k % 3 - 1, sy = best->y + k / 3 - 1;
        if (sx >= win->x0 && sx <= win->x1 && sy >= win->y0 && sy <= win->y1 &&
            (st = trn_hb_eval(*hb, sx, sy)) != TRN_OK) {
            return st;
        }
    }
    best->poses = (*hb)->evals;
    return TRN_OK;
}

/* The bounded search's far basins: the zone around the answer's start and
 * every pose that could be one of the exhaustive search's (the
 * TRN_REFINE_BASINS highest local maxima of the grid outside the zone, at
 * any level: a basin's refined ln L is not bounded by its grid ln L) scored,
 * then trn_loc_find_basins_ on the grid; their zones scored. */
static trn_status_t bounded_basins(trn_hb_t *hb, const trn_window_t *win, int32_t radius,
                                   const double *ll_grid, const trn_loc_result_t *out,
                                   trn_loc_basins_t *bs)
{
    trn_status_t st;
    int32_t i;
    if ((st = trn_hb_eval_zone(hb, out->ix, out->iy, radius)) != TRN_OK ||
        (st = trn_hb_basins(hb, -(double)INFINITY, out->ix, out->iy, radius, TRN_REFINE_BASINS)) !=
            TRN_OK) {
        return st;
    }
    trn_loc_find_basins_(ll_grid, win, radius, out, bs);
    for (i = 0; i < bs->n; ++i) {
        if ((st = trn_hb_eval_zone(hb, bs->x[i], bs->y[i], radius)) != TRN_OK) {
            return st;
        }
    }
    return TRN_OK;
}

/* The competitor and the masses (trn_height_mass's) of the bounded search:
 * the zone ex scored, the best pose outside it found exactly, the masses
 * within *err. */
static trn_status_t bounded_mass(trn_hb_t *hb, const trn_exclusion_t *ex, double infl,
                                 trn_height_best_t *second, double *err)
{
    trn_status_t st;
    double lse_all, lse_out;
    if ((st = trn_hb_eval_zone(hb, ex->cx, ex->cy, ex->radius)) != TRN_OK ||
        (st = trn_hb_best(hb, ex, second)) != TRN_OK ||
        (st = trn_hb_mass(hb, ex, infl, TRN_BOUND_EPS, &lse_all, &lse_out, err)) != TRN_OK) {
        return st;
    }
    second->lse_all = lse_all;
    second->lse_out = lse_out;
    return TRN_OK;
}

/* TRN_MATCH_HEIGHTS: height search, refinement, competing hypothesis; the
 * search exhaustive or bounded (map->cfg.search), its workspace in hbws. */
static trn_status_t localize_heights(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx,
                                     int32_t ry, const trn_window_t *win, double *ll_grid,
                                     trn_refine_t *cand, trn_loc_basins_t *bs, void *hbws,
                                     trn_loc_result_t *out)
{
    trn_status_t st;
    trn_height_best_t best; /* the search's best, then the competitor (one frame slot:
                               the stack limit of docs/architecture.md) */
    trn_refine_cfg_t rc;
    trn_exclusion_t ex;
    trn_hb_t *hb = NULL;
    uint64_t work = 0u;
    double infl = 1.0, err = 0.0;
    int32_t radius = map->cfg.min_exclusion_cells, pass;

    out->noise_scale = 1.0;
    out->failure_prob_bound = 0.0;
    out->search = map->cfg.search;
    pass = 0;
    do {
        /* the configured noise model; once more, rescaled, if the residuals
         * at the answer reject it (docs/method.md 9, "the sensor's noise
         * from the data") */
        trn_loc_refine_cfg_(map, out, &rc);
        if ((st = search_window(map, local, rx, ry, win, &rc, ll_grid, hbws, &work, &hb, &best)) !=
            TRN_OK) {
            return st;
        }
        out->ix = best.x;
        out->iy = best.y;
        out->ll_best = best.ll;
        out->n_points = 0u;
        out->stats.poses_scored = best.poses;
        out->stats.blocks_bounded = 0u;
        out->on_window_edge = trn_loc_on_edge_(win, best.x, best.y);
        out->x = (double)best.x;
        out->y = (double)best.y;
        out->sigma_x_m = out->sigma_y_m = (double)INFINITY;
        out->rho = 0.0;
        out->cov_m2[0] = out->cov_m2[1] = (double)INFINITY;
        out->cov_m2[2] = 0.0;
        refine_result(map, local, rx, ry, win, ll_grid, cand, out);
        pass += 1;
    } while (pass == 1 && map->cfg.noise_auto != 0 &&
             rescale_noise(map, local, rx, ry, &rc, &best, cand, out) != 0);
    if (out->refined) {
        if (hb != NULL) {
            if ((st = bounded_basins(hb, win, radius, ll_grid, out, bs)) != TRN_OK) {
                return st;
            }
        } else {
            trn_loc_find_basins_(ll_grid, win, radius, out, bs);
        }
        trn_loc_refine_basins_(map, local, rx, ry, ll_grid, win, bs, cand, out);
    }
    out->n_points = (size_t)(out->refinement.n_seen > 0 ? out->refinement.n_seen : 0);
    /* The zone is min_exclusion_cells, not 4 sigma as for eq. 6: the failure
     * probability is the posterior mass of poses that far from the answer,
     * so a broad peak (large sigma) shows as a large probability instead of
     * hiding its competitors inside a wide zone. */
    if (out->refined) {
        infl = out->refinement.ll_inflation;
        /* the final answer's ellipse: ln L's fall at 2 sds, not only its
         * peak's curvature (docs/method.md 9, "The shoulders") */
        trn_loc_shoulders_(map, local, rx, ry, out);
    }
    ex.cx = out->ix; /* the answer's start (refine_basins may move it) */
    ex.cy = out->iy;
    ex.radius = radius;
    out->exclusion_cells = radius;
    if (hb != NULL) {
        /* the bounded search: the competitor exactly, the masses within err */
        st = bounded_mass(hb, &ex, infl, &best, &err);
        out->stats.poses_scored = hb->evals;
        out->stats.blocks_bounded = hb->bounds;
        /* ... and the sums' rounding (another order than the grid's, of
         * ln L values up to 1e4 and more: a few ulps of those) */
        out->failure_prob_bound = err + 1e-9;
    } else {
        /* every pose was scored once: the competitor and the masses come
         * from the stored grid */
        st = trn_height_mass(ll_grid, win, &ex, infl, &best);
    }
    if (st == TRN_OK) {
        /* The posterior mass outside the zone around the peak (uniform prior
         * over the window), not only the best competitor: many near-ties far
         * away add up. ln L is divided by the block sandwich's ratio first
         * (ll_inflation, ungated): correlated residuals make ln L differences
         * too large by about that factor (a composite likelihood's
         * adjustment). */
        double pf = fmax(exp(best.lse_out - best.lse_all),
                         out->refined ? trn_loc_basins_failure_(bs, infl, out) : 0.0);
        if (out->refined) {
            /* ... and the answer's own peak's: mass along its major axis
             * that the integer grid misses, and its covariance's tail
             * beyond the failure radius (docs/method.md 9, "the valley") */
            pf = fmax(pf, trn_loc_peak_failure_(map, local, rx, ry, win, infl, out));
        }
        out->has_second = 1;
        out->second_x = best.x;
        out->second_y = best.y;
        out->ll_second = best.ll;
        out->failure_probability = pf < 0.0 ? 0.0 : pf > 1.0 ? 1.0 : pf;
    } else if (st == TRN_E_NODATA) {
        no_competitor(out);
    } else {
        return st;
    }
    /* an answer on the window's edge is no fix: the likelihood may rise beyond
     * the window, where neither the search nor the failure probability looks
     * (a prior that missed the truth; docs/method.md 9, "the window's edge") */
    return out->refined && !out->misfit && !out->on_window_edge ? TRN_OK : TRN_E_ILLCOND;
}

/* The acceptance test: an answer otherwise good whose failure probability
 * is above the map's limit is not a fix (TRN_E_AMBIGUOUS, out filled in). */
static trn_status_t accept(const trn_map_t *map, trn_status_t st, const trn_loc_result_t *out)
{
    if (st == TRN_OK && out->failure_probability > (double)map->cfg.max_failure_prob) {
        return TRN_E_AMBIGUOUS;
    }
    return st;
}

trn_status_t trn_localize_dem(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                              int32_t rover_x, int32_t rover_y, size_t max_points,
                              const trn_window_t *win, void *ws, size_t ws_bytes,
                              trn_loc_result_t *out)
{
    trn_status_t st;
    loc_layout_t lay;
    uint8_t *b = (uint8_t *)ws;
    trn_grid_f32_t hp;
    trn_point_t *pts;
    size_t n = 0;

    if (map == NULL || local_dem == NULL || win == NULL || ws == NULL || out == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_grid_f32_check(local_dem)) != TRN_OK) {
        return st;
    }
    if (!trn_loc_map_ok_(map)) {
        return TRN_E_ARG;
    }
    if (max_points == 0u || max_points > (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM) {
        return TRN_E_ARG;
    }
    if (!trn_loc_window_ok_(map, win) ||
        !loc_layout(map, local_dem->width, local_dem->height, max_points, win, &lay)) {
        return TRN_E_RANGE;
    }
    if ((st = trn_ws_check(ws, ws_bytes, lay.total)) != TRN_OK) {
        return st;
    }
    out->noise_scale = 1.0;
    if (map->cfg.match == TRN_MATCH_HEIGHTS) {
        st = localize_heights(
            map, local_dem, rover_x, rover_y, win, (double *)(void *)(b + lay.llgrid),
            (trn_refine_t *)(void *)(b + lay.cand), (trn_loc_basins_t *)(void *)(b + lay.basins),
            (void *)(b + lay.hb), out);
        return accept(map, st, out);
    }
    pts = (trn_point_t *)(void *)(b + lay.pts);
    if ((st = trn_grid_f32_init(&hp, (float *)(void *)(b + lay.hp),
                                (size_t)local_dem->width * (size_t)local_dem->height,
                                local_dem->width, local_dem->height)) != TRN_OK) {
        return st;
    }
    if (map->cfg.local_highpass == TRN_LOCAL_HP_MAP) {
        st = trn_loc_highpass_by_map_(map, local_dem, rover_x, rover_y, (win->x0 + win->x1) / 2,
                                      (win->y0 + win->y1) / 2, &hp);
    } else {
        st = trn_highpass(local_dem, &map->cfg.terrain, &hp, b + lay.hpws, lay.pts - lay.hpws);
    }
    if (st != TRN_OK || (st = trn_occupancy_points(&hp, &map->cfg.terrain, rover_x, rover_y, pts,
                                                   max_points, &n)) != TRN_OK) {
        return st;
    }
    /* rare height bins first: same result, earlier branch-and-bound exits */
    if ((st = trn_points_order(pts, n, map->cfg.terrain.nz)) != TRN_OK) {
        return st;
    }
    st = trn_localize_points(map, pts, n, win, b + lay.search, ws_bytes - lay.search, out);
    if ((st == TRN_OK || st == TRN_E_ILLCOND) && map->cfg.local_highpass == TRN_LOCAL_HP_MAP &&
        (out->ix != (win->x0 + win->x1) / 2 || out->iy != (win->y0 + win->y1) / 2)) {
        /* Second pass: the local filter referred to the pose just found
         * (the low-pass's curvature times the prior's error is gone there). */
        if ((st = trn_loc_highpass_by_map_(map, local_dem, rover_x, rover_y, out->ix, out->iy,
                                           &hp)) != TRN_OK ||
            (st = trn_occupancy_points(&hp, &map->cfg.terrain, rover_x, rover_y, pts, max_points,
                                       &n)) != TRN_OK ||
            (st = trn_points_order(pts, n, map->cfg.terrain.nz)) != TRN_OK) {
            return st;
        }
        st = trn_localize_points(map, pts, n, win, b + lay.search, ws_bytes - lay.search, out);
    }
    if ((st == TRN_OK || st == TRN_E_ILLCOND) && map->cfg.refine != 0) {
        out->noise_scale = 1.0;
        refine_result(map, local_dem, rover_x, rover_y, win, NULL, NULL, out);
        /* No consistent height match around the voxel optimum: flag it. */
        st = out->refined && !out->misfit ? TRN_OK : TRN_E_ILLCOND;
    }
    return accept(map, st, out);
}
