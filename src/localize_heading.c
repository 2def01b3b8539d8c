/* SPDX-License-Identifier: Apache-2.0 */
/* localize_heading.c - the entry of localization over heading from a local
 * DEM (trn_localize_dem_heading and its workspace sizes, see
 * trn/localize.h, trn/heading.h and trn/height_heading.h): the checks, then
 * one of two paths, each in a file below this one (docs/architecture.md,
 * "The localization stack"): the voxel search over heading
 * (src/heading.c) or the height matcher's one path (src/localize_heights.c,
 * trn_localize_dem's too: with W = 0 at centre 0 the answer is its). */
#include "trn/heading.h"
#include "trn/height_heading.h"
#include "trn/localize.h"

#include "localize_int.h"
#include "refine_int.h"
#include "ws.h"

/* Layout of trn_localize_dem_heading's workspace: [hp grid | highpass ws |
 * points | trn_localize_points_heading's workspace]. */
typedef struct {
    size_t hp, hpws, pts, heading, total;
} head_layout_t;

static int head_layout(const trn_map_t *map, int32_t w, int32_t h, size_t max_points,
                       const trn_window_t *win, head_layout_t *lay)
{
    size_t hpws = trn_highpass_workspace_bytes(w, h);
    size_t hw = trn_localize_heading_workspace_bytes(map, max_points, win);
    trn_ws_t ws;
    if (hpws == 0u || hw == 0u) {
        return 0;
    }
    trn_ws_begin(&ws, NULL);
    lay->hp = trn_ws_offset(&ws, (size_t)w * (size_t)h * sizeof(float));
    lay->hpws = trn_ws_offset(&ws, hpws);
    lay->pts = trn_ws_offset(&ws, max_points * sizeof(trn_point_t));
    lay->heading = trn_ws_offset(&ws, hw);
    lay->total = ws.total;
    return 1;
}

size_t trn_localize_dem_heading_workspace_bytes(const trn_map_t *map, int32_t width, int32_t height,
                                                size_t max_points, const trn_window_t *win)
{
    head_layout_t lay;
    if (map == NULL || win == NULL || !trn_loc_map_ok_(map) ||
        map->cfg.match == TRN_MATCH_HEIGHTS || !trn_loc_window_ok_(map, win) || max_points == 0u ||
        max_points > (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM) {
        return 0u;
    }
    return head_layout(map, width, height, max_points, win, &lay) ? lay.total : 0u;
}

/* trn_localize_dem_heading's voxel path up to the search: window, layout,
 * workspace, the local high-pass and occupancy; the points' count and the
 * offsets of the points and of the search's workspace. Out of line: the
 * search's stack does not carry this frame. */
trn_status_t trn_localize_dem_heading_prep_(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                            int32_t rover_x, int32_t rover_y, size_t max_points,
                                            const trn_window_t *win, void *ws, size_t ws_bytes,
                                            size_t *n, size_t at[2])
{
    trn_status_t st;
    head_layout_t lay;
    uint8_t *b = (uint8_t *)ws;
    trn_grid_f32_t hp;

    if (!trn_loc_window_ok_(map, win) ||
        !head_layout(map, local_dem->width, local_dem->height, max_points, win, &lay)) {
        return TRN_E_RANGE;
    }
    if ((st = trn_ws_check(ws, ws_bytes, lay.total)) != TRN_OK) {
        return st;
    }
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
    at[0] = lay.pts;
    at[1] = lay.heading;
    return st != TRN_OK ? st
                        : trn_occupancy_points(&hp, &map->cfg.terrain, rover_x, rover_y,
                                               (trn_point_t *)(void *)(b + lay.pts), max_points, n);
}

/* trn_localize_dem_heading with a voxel map, after its argument checks (out
 * of line: the height map's W = 0 path, trn_localize_dem, does not carry
 * this frame). */
trn_status_t trn_localize_dem_heading_voxel_(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                             int32_t rover_x, int32_t rover_y, size_t max_points,
                                             const trn_window_t *win, const trn_heading_cfg_t *cfg,
                                             void *ws, size_t ws_bytes, trn_heading_result_t *out)
{
    trn_status_t st;
    uint8_t *b = (uint8_t *)ws;
    size_t n = 0, at[2];

    if ((st = trn_localize_dem_heading_prep_(map, local_dem, rover_x, rover_y, max_points, win, ws,
                                             ws_bytes, &n, at)) != TRN_OK) {
        return st;
    }
    return trn_localize_points_heading(map, (const trn_point_t *)(void *)(b + at[0]), n, win, cfg,
                                       b + at[1], ws_bytes - at[1], out);
}

/* trn_localize_dem_heading but W = 0 at centre 0 with a height map (out of
 * line: that path, trn_localize_dem, does not carry this frame). */
trn_status_t trn_localize_dem_heading_checked_(const trn_map_t *map,
                                               const trn_grid_f32_t *local_dem, int32_t rover_x,
                                               int32_t rover_y, size_t max_points,
                                               const trn_window_t *win,
                                               const trn_heading_cfg_t *cfg, void *ws,
                                               size_t ws_bytes, trn_heading_result_t *out)
{
    trn_status_t st;

    if (map == NULL || local_dem == NULL || win == NULL || cfg == NULL || ws == NULL ||
        out == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_grid_f32_check(local_dem)) != TRN_OK) {
        return st;
    }
    if (!trn_loc_map_ok_(map) || (map->cfg.match == TRN_MATCH_VOXEL && map->cfg.refine != 0) ||
        max_points == 0u || max_points > (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM) {
        return TRN_E_ARG;
    }
    out->loc.noise_scale = 1.0;                /* the voxel path keeps the configured model */
    if (map->cfg.match == TRN_MATCH_HEIGHTS) { /* src/localize_heights.c */
        return trn_loc_heights_(map, local_dem, NULL, rover_x, rover_y, win, cfg, ws, ws_bytes,
                                out);
    }
    return trn_localize_dem_heading_voxel_(map, local_dem, rover_x, rover_y, max_points, win, cfg,
                                           ws, ws_bytes, out);
}

trn_status_t trn_localize_dem_heading(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                      int32_t rover_x, int32_t rover_y, size_t max_points,
                                      const trn_window_t *win, const trn_heading_cfg_t *cfg,
                                      void *ws, size_t ws_bytes, trn_heading_result_t *out)
{
    return trn_localize_dem_heading_checked_(map, local_dem, rover_x, rover_y, max_points, win, cfg,
                                             ws, ws_bytes, out);
}

size_t trn_localize_dem_heading_workspace_bytes_cfg(const trn_map_t *map,
                                                    const trn_grid_f32_t *local_dem,
                                                    int32_t rover_x, int32_t rover_y,
                                                    size_t max_points, const trn_window_t *win,
                                                    const trn_heading_cfg_t *cfg)
{
    double step;
    int32_t kk;
    if (map == NULL || local_dem == NULL || win == NULL || cfg == NULL ||
        trn_grid_f32_check(local_dem) != TRN_OK) {
        return 0u;
    }
    if (map->cfg.match != TRN_MATCH_HEIGHTS) {
        return trn_localize_dem_heading_workspace_bytes(map, local_dem->width, local_dem->height,
                                                        max_points, win);
    }
    if (!trn_loc_map_ok_(map) || max_points == 0u ||
        max_points > (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM ||
        trn_height_heading_steps(local_dem, rover_x, rover_y, cfg, &step, &kk) != TRN_OK) {
        return 0u;
    }
    return trn_loc_heights_bytes_(map, local_dem->width, local_dem->height, win, kk, cfg);
}
