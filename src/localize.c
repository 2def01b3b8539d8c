/* localize.c - prepared maps and end-to-end localization (see trn/localize.h). */
#include "trn/localize.h"

#include <math.h>

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
    cfg->inlier_prob = 0.95f;
    cfg->cap = 60u;
    cfg->levels = 4;
    cfg->min_exclusion_cells = 2;
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
        cfg->min_exclusion_cells > TRN_MAX_DIM) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}

/* Layout of the map buffer: [dist | pyramid | hp grid | highpass scratch];
 * the last two are scratch used only while building. */
typedef struct {
    size_t dist, pyr, hp, hpws, total;
} map_layout_t;

static int map_layout(const trn_map_cfg_t *cfg, int32_t w, int32_t h, map_layout_t *lay)
{
    size_t pyr, hpws;
    if (trn_map_cfg_check(cfg) != TRN_OK || w < 1 || h < 1 || w > TRN_MAX_DIM || h > TRN_MAX_DIM) {
        return 0;
    }
    pyr = trn_pyramid_bytes(w, h, cfg->terrain.nz, cfg->levels);
    hpws = trn_highpass_workspace_bytes(w, h);
    lay->dist = 0u;
    lay->pyr = TRN_ALIGN_UP((size_t)w * (size_t)h * (size_t)cfg->terrain.nz);
    lay->hp = lay->pyr + pyr;
    lay->hpws = lay->hp + TRN_ALIGN_UP((size_t)w * (size_t)h * sizeof(float));
    lay->total = lay->hpws + hpws;
    return 1;
}

size_t trn_map_bytes(const trn_map_cfg_t *cfg, int32_t width, int32_t height)
{
    map_layout_t lay;
    return map_layout(cfg, width, height, &lay) ? lay.total : 0u;
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
    if (len < lay.total) {
        return TRN_E_WORKSPACE;
    }
    map->cfg = *cfg;
    if ((st = trn_grid_f32_init(&hp, (float *)(void *)(b + lay.hp), (size_t)dem->width * (size_t)dem->height,
                                dem->width, dem->height)) != TRN_OK ||
        (st = trn_highpass(dem, &cfg->terrain, &hp, b + lay.hpws, lay.total - lay.hpws)) != TRN_OK ||
        (st = trn_vol_u8_init(&map->dist, b + lay.dist, lay.pyr, dem->width, dem->height,
                              cfg->terrain.nz)) != TRN_OK ||
        (st = trn_occupancy(&hp, &cfg->terrain, &map->dist, &map->n_occupied)) != TRN_OK ||
        (st = trn_chamfer3d(&map->dist, &map->dist, cfg->cap)) != TRN_OK) {
        return st;
    }
    lik = lik_of(cfg);
    if ((st = trn_outlier_density(&map->dist, &lik, &k)) != TRN_OK ||
        (st = trn_lnp_table_build(&map->lnp, &lik, k)) != TRN_OK ||
        (st = trn_pyramid_build(&map->pyr, &map->dist, cfg->cap, cfg->levels, b + lay.pyr,
                                lay.hp - lay.pyr)) != TRN_OK) {
        return st;
    }
    return TRN_OK;
}

static int map_ok(const trn_map_t *map)
{
    return trn_map_cfg_check(&map->cfg) == TRN_OK && trn_vol_u8_check(&map->dist) == TRN_OK &&
           map->pyr.nlevels == map->cfg.levels && map->lnp.cap == map->cfg.cap;
}

size_t trn_localize_workspace_bytes(const trn_map_t *map, const trn_window_t *win)
{
    if (map == NULL || win == NULL || !map_ok(map)) {
        return 0u;
    }
    return trn_search_bb_workspace_bytes(&map->pyr, win);
}

/* The window must be non-empty and inside the map (checked before any work). */
static int window_ok(const trn_map_t *map, const trn_window_t *win)
{
    return win->x0 <= win->x1 && win->y0 <= win->y1 && win->x0 >= 0 && win->y0 >= 0 &&
           win->x1 < map->dist.nx && win->y1 < map->dist.ny;
}

static double nats(int64_t score) { return (double)score / (double)TRN_LNP_SCALE; }

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
    if (!map_ok(map)) {
        return TRN_E_ARG;
    }
    if (!window_ok(map, win)) {
        return TRN_E_RANGE;
    }
    st = trn_search_bb(&map->pyr, &map->lnp, pts, n, win, NULL, ws, ws_bytes, &best, &out->stats);
    if (st != TRN_OK) {
        return st;
    }
    out->ix = best.x;
    out->iy = best.y;
    out->ll_best = nats(best.score);
    out->n_points = n;
    out->on_window_edge = (best.x == win->x0 || best.x == win->x1 || best.y == win->y0 ||
                           best.y == win->y1) ? 1 : 0;
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
        out->has_second = 0;
        out->second_x = best.x;
        out->second_y = best.y;
        out->ll_second = out->ll_best;
        out->failure_probability = 0.0;
    } else {
        return st;
    }
    return fit_st == TRN_OK ? TRN_OK : TRN_E_ILLCOND;
}

/* Layout of trn_localize_dem's workspace: [hp grid | highpass ws | points | search ws]. */
typedef struct {
    size_t hp, hpws, pts, search, total;
} loc_layout_t;

static int loc_layout(const trn_map_t *map, int32_t w, int32_t h, size_t max_points,
                      const trn_window_t *win, loc_layout_t *lay)
{
    size_t hpws = trn_highpass_workspace_bytes(w, h);
    size_t sw = trn_localize_workspace_bytes(map, win);
    if (hpws == 0u || sw == 0u || max_points == 0u ||
        max_points > (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM) {
        return 0;
    }
    lay->hp = 0u;
    lay->hpws = TRN_ALIGN_UP((size_t)w * (size_t)h * sizeof(float));
    lay->pts = lay->hpws + hpws;
    lay->search = lay->pts + TRN_ALIGN_UP(max_points * sizeof(trn_point_t));
    lay->total = lay->search + sw;
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
    if (!map_ok(map)) {
        return TRN_E_ARG;
    }
    if (max_points == 0u || max_points > (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM) {
        return TRN_E_ARG;
    }
    if (!window_ok(map, win) ||
        !loc_layout(map, local_dem->width, local_dem->height, max_points, win, &lay)) {
        return TRN_E_RANGE;
    }
    if (ws_bytes < lay.total) {
        return TRN_E_WORKSPACE;
    }
    pts = (trn_point_t *)(void *)(b + lay.pts);
    if ((st = trn_grid_f32_init(&hp, (float *)(void *)(b + lay.hp),
                                (size_t)local_dem->width * (size_t)local_dem->height,
                                local_dem->width, local_dem->height)) != TRN_OK ||
        (st = trn_highpass(local_dem, &map->cfg.terrain, &hp, b + lay.hpws, lay.pts - lay.hpws)) !=
            TRN_OK ||
        (st = trn_occupancy_points(&hp, &map->cfg.terrain, rover_x, rover_y, pts, max_points, &n)) !=
            TRN_OK) {
        return st;
    }
    /* rare height bins first: same result, earlier branch-and-bound exits */
    if ((st = trn_points_order(pts, n, map->cfg.terrain.nz)) != TRN_OK) {
        return st;
    }
    return trn_localize_points(map, pts, n, win, b + lay.search, ws_bytes - lay.search, out);
}
