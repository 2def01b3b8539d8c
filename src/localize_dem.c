/* SPDX-License-Identifier: Apache-2.0 */
/* localize_dem.c - the entry of localization from a local DEM
 * (trn_localize_dem, trn_localize_dem_centroids, trn_localize_dem_cells and
 * their workspace size, see
 * trn/localize.h): the
 * checks, then one of two paths, each in a file below this one
 * (docs/architecture.md, "The localization stack"): the height matcher
 * (src/localize_heights.c, its one path over heading at one heading, 0,
 * none searched) or the voxel matcher (src/localize.c). Its own frame is
 * small, so that neither path's stack carries the other's. */
#include "trn/localize.h"

#include <string.h>

#include "localize_int.h"
#include "refine_int.h"
#include "ws.h"

/* The heading known: 0, none searched (the height matcher's (x, y) case). */
static const trn_heading_cfg_t k_known = {0.0, 0.0, 0.0};

/* Layout of the height matcher's workspace: [its result over heading | the
 * localization's workspace]. 0 if refused. */
static size_t heights_bytes(const trn_map_t *map, int32_t w, int32_t h, const trn_window_t *win,
                            size_t *at)
{
    trn_ws_t ws;
    size_t core = trn_loc_heights_bytes_(map, w, h, win, 0, &k_known);
    if (core == 0u) {
        return 0u;
    }
    trn_ws_begin(&ws, NULL);
    (void)trn_ws_offset(&ws, sizeof(trn_heading_result_t));
    *at = trn_ws_offset(&ws, core);
    return ws.total;
}

size_t trn_localize_dem_workspace_bytes(const trn_map_t *map, int32_t width, int32_t height,
                                        size_t max_points, const trn_window_t *win)
{
    size_t at;
    if (map == NULL || win == NULL || trn_highpass_workspace_bytes(width, height) == 0u ||
        max_points == 0u || max_points > (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM) {
        return 0u;
    }
    if (map->cfg.match == TRN_MATCH_HEIGHTS) {
        return trn_loc_window_ok_(map, win) ? heights_bytes(map, width, height, win, &at) : 0u;
    }
    return trn_loc_voxel_dem_bytes_(map, width, height, max_points, win);
}

/* The three entries' one body (inline in each: a wrapper's frame would sit
 * on the deepest stack). cells NULL: nothing known of the local cells. */
static inline trn_status_t localize_dem(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                        const trn_local_cells_t *cells, int32_t rover_x,
                                        int32_t rover_y, size_t max_points, const trn_window_t *win,
                                        void *ws, size_t ws_bytes, trn_loc_result_t *out)
{
    trn_status_t st;
    trn_heading_result_t *res;
    size_t at, total;

    if (map == NULL || local_dem == NULL || win == NULL || ws == NULL || out == NULL ||
        (cells != NULL && (cells->centroid_x == NULL) != (cells->centroid_y == NULL))) {
        return TRN_E_NULL;
    }
    if ((st = trn_grid_f32_check(local_dem)) != TRN_OK) {
        return st;
    }
    if (!trn_loc_map_ok_(map) ||
        (cells != NULL &&
         (!trn_refine_centroids_ok_(local_dem, cells->centroid_x, cells->centroid_y) ||
          !trn_refine_counts_ok_(local_dem, cells->point_count)))) {
        return TRN_E_ARG;
    }
    if (max_points == 0u || max_points > (size_t)TRN_MAX_DIM * (size_t)TRN_MAX_DIM) {
        return TRN_E_ARG;
    }
    if (!trn_loc_window_ok_(map, win)) {
        return TRN_E_RANGE;
    }
    if (map->cfg.match != TRN_MATCH_HEIGHTS) {
        return trn_loc_voxel_dem_(map, local_dem, cells, rover_x, rover_y, max_points, win, ws,
                                  ws_bytes, out);
    }
    total = heights_bytes(map, local_dem->width, local_dem->height, win, &at);
    if (total == 0u) {
        return TRN_E_RANGE;
    }
    if ((st = trn_ws_check(ws, ws_bytes, total)) != TRN_OK) {
        return st;
    }
    res = (trn_heading_result_t *)ws;
    (void)memset(res, 0, sizeof(*res));
    st = trn_loc_heights_(map, local_dem, cells, rover_x, rover_y, win, &k_known,
                          (uint8_t *)ws + at, ws_bytes - at, res);
    (void)memcpy(out, &res->loc, sizeof(*out));
    return st;
}

trn_status_t trn_localize_dem_centroids(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                        const float *centroid_x, const float *centroid_y,
                                        int32_t rover_x, int32_t rover_y, size_t max_points,
                                        const trn_window_t *win, void *ws, size_t ws_bytes,
                                        trn_loc_result_t *out)
{
    trn_local_cells_t cells;
    cells.centroid_x = centroid_x;
    cells.centroid_y = centroid_y;
    cells.point_count = NULL;
    return localize_dem(map, local_dem, &cells, rover_x, rover_y, max_points, win, ws, ws_bytes,
                        out);
}

trn_status_t trn_localize_dem(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                              int32_t rover_x, int32_t rover_y, size_t max_points,
                              const trn_window_t *win, void *ws, size_t ws_bytes,
                              trn_loc_result_t *out)
{
    return localize_dem(map, local_dem, NULL, rover_x, rover_y, max_points, win, ws, ws_bytes, out);
}

trn_status_t trn_localize_dem_cells(const trn_map_t *map, const trn_grid_f32_t *local_dem,
                                    const trn_local_cells_t *cells, int32_t rover_x,
                                    int32_t rover_y, size_t max_points, const trn_window_t *win,
                                    void *ws, size_t ws_bytes, trn_loc_result_t *out)
{
    if (cells == NULL) {
        return TRN_E_NULL;
    }
    return localize_dem(map, local_dem, cells, rover_x, rover_y, max_points, win, ws, ws_bytes,
                        out);
}
