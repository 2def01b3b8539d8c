/* SPDX-License-Identifier: Apache-2.0 */
/* height_heading.c - the height matcher's search over (x, y, heading) and
 * its heading steps (see trn/height_heading.h); the localization that uses
 * it is src/localize_heights.c. */
#include "trn/height_heading.h"

#include <math.h>
#include <stdlib.h>

#include "height_score.h"
#include "localize_int.h"
#include "refine_int.h"
#include "ws.h"

static int rcfg_ok(const trn_refine_cfg_t *cfg)
{
    return cfg->cell_m > 0.0f && cfg->cell_m <= TRN_CELL_MAX_M && cfg->noise_m > 0.0f &&
           cfg->noise_m <= 1000.0f && cfg->noise_k_per_m >= 0.0f && cfg->noise_k_per_m <= 1000.0f &&
           (cfg->fit_noise == 0 || cfg->fit_noise == 1);
}

static int rover_ok(const trn_grid_f32_t *l, int32_t rx, int32_t ry)
{
    return rx >= -TRN_MAX_DIM && ry >= -TRN_MAX_DIM && rx <= l->width - 1 + TRN_MAX_DIM &&
           ry <= l->height - 1 + TRN_MAX_DIM;
}

trn_status_t trn_height_heading_steps(const trn_grid_f32_t *local, int32_t rover_x, int32_t rover_y,
                                      const trn_heading_cfg_t *cfg, double *step_rad,
                                      int32_t *half_steps)
{
    trn_status_t st;
    trn_point_t far;
    int64_t r2 = -1;
    int32_t x, y;
    if (local == NULL || cfg == NULL || step_rad == NULL || half_steps == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_grid_f32_check(local)) != TRN_OK) {
        return st;
    }
    if (!rover_ok(local, rover_x, rover_y)) {
        return TRN_E_ARG;
    }
    far.x = 0;
    far.y = 0;
    far.z = 0;
    for (y = 0; y < local->height; ++y) {
        for (x = 0; x < local->width; ++x) {
            const int64_t ox = (int64_t)x - rover_x, oy = (int64_t)y - rover_y;
            if (isfinite(TRN_GRID_AT(local, x, y)) && ox * ox + oy * oy > r2) {
                r2 = ox * ox + oy * oy;
                far.x = (int16_t)ox;
                far.y = (int16_t)oy;
            }
        }
    }
    /* the offsets fit int16_t: |.| <= TRN_MAX_DIM - 1 + TRN_MAX_DIM; with no
     * seen cell, n = 0 gives trn_heading_steps' TRN_E_NODATA after its
     * argument checks */
    return trn_heading_steps(&far, r2 < 0 ? 0u : 1u, cfg, step_rad, half_steps);
}

size_t trn_height_heading_workspace_bytes(int32_t width, int32_t height)
{
    return trn_hs_bytes(width, height);
}

/* Score every pose of the window at heading step k (grid: its slice, may be
 * NULL), keeping a better best (strictly higher ln L). */
static void search_heading(trn_hs_t *s, const trn_window_t *win, int32_t k, double *grid,
                           int *found, trn_height_best3_t *best)
{
    int32_t x, y;
    for (y = win->y0; y <= win->y1; ++y) {
        for (x = win->x0; x <= win->x1; ++x) {
            double dz, m, ll = trn_hs_ll(s, x, y, &dz, &m);
            if (grid != NULL) {
                grid[(size_t)(y - win->y0) * (size_t)(win->x1 - win->x0 + 1) +
                     (size_t)(x - win->x0)] = ll;
            }
            best->poses += 1u;
            if (!*found || ll > best->ll) {
                best->x = x;
                best->y = y;
                best->k = k;
                best->ll = ll;
                best->dz_m = dz;
                best->model_m = m;
                *found = 1;
            }
        }
    }
}

trn_status_t trn_height_search_heading(const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                                       int32_t rover_x, int32_t rover_y, const trn_window_t *win,
                                       const trn_heading_cfg_t *hcfg, const trn_refine_cfg_t *rcfg,
                                       float inlier_prob, void *ws, size_t ws_bytes,
                                       double *ll_grid, trn_height_best3_t *best)
{
    trn_status_t st;
    trn_hs_t sc;
    double step;
    int32_t kk, i;
    size_t poses;
    int found = 0;

    if (global == NULL || local == NULL || win == NULL || hcfg == NULL || rcfg == NULL ||
        ws == NULL || best == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_grid_f32_check(global)) != TRN_OK) {
        return st;
    }
    if (!rcfg_ok(rcfg) || !(inlier_prob > 0.0f && inlier_prob < 1.0f)) {
        return TRN_E_ARG;
    }
    if ((st = trn_height_heading_steps(local, rover_x, rover_y, hcfg, &step, &kk)) != TRN_OK) {
        return st;
    }
    if (win->x0 > win->x1 || win->y0 > win->y1 || win->x0 < 0 || win->y0 < 0 ||
        win->x1 >= global->width || win->y1 >= global->height) {
        return TRN_E_RANGE;
    }
    if ((st = trn_ws_check(ws, ws_bytes, trn_hs_bytes(local->width, local->height))) != TRN_OK) {
        return st;
    }
    if (trn_hs_init(&sc, ws, global, local, rover_x, rover_y, rcfg, (double)inlier_prob) < 8u) {
        return TRN_E_NODATA;
    }
    poses = (size_t)(win->x1 - win->x0 + 1) * (size_t)(win->y1 - win->y0 + 1);
    best->poses = 0u;
    best->step_rad = step;
    best->half_steps = kk;
    for (i = 0; i < 2 * kk + 1; ++i) {
        const int32_t k = trn_heading_step_of_(i);
        double c, sn;
        trn_heading_trig_(hcfg->center_rad + (double)k * step, &c, &sn);
        trn_hs_turn(&sc, c, sn);
        search_heading(&sc, win, k, ll_grid != NULL ? ll_grid + (size_t)(k + kk) * poses : NULL,
                       &found, best);
    }
    return TRN_OK;
}
