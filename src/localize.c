/* SPDX-License-Identifier: Apache-2.0 */
/* localize.c - prepared maps, the voxel matcher's localization
 * (trn_localize_points) and its path from a local DEM (see trn/localize.h;
 * trn_localize_dem's entry is src/localize_dem.c, the height matcher's path
 * src/localize_heights.c). */
#include "trn/localize.h"
#include "trn/heading.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>

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
    if (!(cell_m > 0.0f && cell_m <= TRN_CELL_MAX_M) || trn_map_cfg_check(&c) != TRN_OK) {
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
    out->relief_z = (double)INFINITY;
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

/* Layout of the voxel path's workspace: [hp grid | highpass ws | points |
 * trn_localize_points' workspace]. */
typedef struct {
    size_t hp, hpws, pts, search, total;
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
    lay->total = ws.total;
    return 1;
}

size_t trn_loc_voxel_dem_bytes_(const trn_map_t *map, int32_t width, int32_t height,
                                size_t max_points, const trn_window_t *win)
{
    loc_layout_t lay;
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

/* The refinement from the voxel search's integer pose (map->cfg.refine):
 * on success its pose and covariance replace eq. 6's. */
static void refine_voxel(const trn_map_t *map, const trn_grid_f32_t *local,
                         const trn_local_cells_t *cells, int32_t rx, int32_t ry,
                         trn_loc_result_t *out)
{
    trn_refine_cfg_t rc;
    trn_loc_refine_cfg_(map, out, cells, &rc);
    out->refined = 0;
    out->misfit = 0;
    if (trn_refine_pose(&map->heights, local, rx, ry, out->ix, out->iy, &rc, &out->refinement) ==
        TRN_OK) {
        trn_loc_take_refinement_(map, out);
    }
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

trn_status_t trn_loc_voxel_dem_(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                const trn_local_cells_t *cells, int32_t rover_x, int32_t rover_y,
                                size_t max_points, const trn_window_t *win, void *ws,
                                size_t ws_bytes, trn_loc_result_t *out)
{
    trn_status_t st;
    loc_layout_t lay;
    uint8_t *b = (uint8_t *)ws;
    trn_grid_f32_t hp;
    trn_point_t *pts;
    size_t n = 0;

    if (!loc_layout(map, local_dem->width, local_dem->height, max_points, win, &lay)) {
        return TRN_E_RANGE;
    }
    if ((st = trn_ws_check(ws, ws_bytes, lay.total)) != TRN_OK) {
        return st;
    }
    out->noise_scale = 1.0;
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
        refine_voxel(map, local_dem, cells, rover_x, rover_y, out);
        /* No consistent height match around the voxel optimum: flag it. */
        st = out->refined && !out->misfit ? TRN_OK : TRN_E_ILLCOND;
    }
    return accept(map, st, out);
}
