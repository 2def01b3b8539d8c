/* SPDX-License-Identifier: Apache-2.0 */
/* field.c - coarse-to-fine sensor uncertainty field (see trn/field.h). */
#include "trn/field.h"
#include "select_pre.h"
#include "ws.h"

#include <math.h>
#include <string.h>

void trn_field_cfg_default(trn_field_cfg_t *cfg)
{
    if (cfg != NULL) {
        cfg->coarse_step_cells = 16;
        cfg->margin_rel = 0.4f;
        cfg->change_rel = 1.5f;
        cfg->progress = NULL;
        cfg->progress_user = NULL;
    }
}

trn_status_t trn_field_cfg_check(const trn_field_cfg_t *cfg)
{
    if (cfg == NULL) {
        return TRN_E_NULL;
    }
    if (cfg->coarse_step_cells < 1 || cfg->coarse_step_cells > 256 ||
        (cfg->coarse_step_cells & (cfg->coarse_step_cells - 1)) != 0 ||
        !(cfg->margin_rel >= 0.0f && cfg->margin_rel <= 100.0f) ||
        !(cfg->change_rel >= 0.0f && cfg->change_rel <= 100.0f)) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}

/* trn_field's carve: the candidate list, then trn_select's workspace
 * (base NULL: sizing only). Returns the bytes, 0 if refused. */
static size_t field_carve(const trn_select_cfg_t *scfg, const trn_map_t *map,
                          const trn_kernels_t *k, void *base, trn_candidate_t **cands, size_t *ncap,
                          void **sws, size_t *swsb)
{
    size_t sw, nc;
    trn_ws_t w;
    *cands = NULL;
    *sws = NULL;
    *ncap = *swsb = 0u;
    if (map == NULL) {
        return 0u;
    }
    sw = trn_select_workspace_bytes(scfg, map, k);
    nc = trn_select_max_candidates(scfg, map->cfg.terrain.cell_m);
    if (sw == 0u || nc == 0u) {
        return 0u;
    }
    trn_ws_begin(&w, base);
    *cands = (trn_candidate_t *)trn_ws_take(&w, nc * sizeof(trn_candidate_t));
    *sws = trn_ws_take(&w, sw);
    *ncap = nc;
    *swsb = sw;
    return w.total;
}

size_t trn_field_workspace_bytes(const trn_select_cfg_t *scfg, const trn_map_t *map,
                                 const trn_kernels_t *k)
{
    trn_candidate_t *c;
    void *s;
    size_t nc, sb;
    return field_carve(scfg, map, k, NULL, &c, &nc, &s, &sb);
}

typedef struct {
    const trn_map_t *map;
    const trn_kernels_t *k;
    const trn_vol_f32_t *pg;
    const trn_select_cfg_t *scfg;
    float heading;
    trn_window_t area;
    int32_t w, h;
    trn_grid_f32_t *out;
    uint8_t *ev;
    trn_candidate_t *cands;
    size_t ncap;
    void *sws;
    size_t swsb;
    trn_field_stats_t *st;
    const trn_selpre_t *pre; /* ground path (trn_field_fast) or NULL */
    trn_field_progress_fn_t progress;
    void *progress_user;
} field_t;

/* Evaluate area cell (x, y) unless known. */
static trn_status_t eval_cell(field_t *f, int32_t x, int32_t y)
{
    trn_rover_t rv;
    trn_select_result_t r;
    size_t ranked;
    trn_status_t s;
    double v = HUGE_VAL;
    const size_t i = (size_t)y * (size_t)f->w + (size_t)x;
    if (f->ev[i] != 0u) {
        return TRN_OK;
    }
    if (f->pre != NULL) {
        s = trn_selpre_best(f->pre, f->area.x0 + x, f->area.y0 + y, f->heading, &v);
    } else {
        rv.pos.x_cells = (float)(f->area.x0 + x);
        rv.pos.y_cells = (float)(f->area.y0 + y);
        rv.heading_rad = f->heading;
        s = trn_select(f->map, f->k, f->pg, f->scfg, &rv, f->cands, f->ncap, &ranked, 1u, &r,
                       f->sws, f->swsb);
        if (s == TRN_OK) {
            v = f->cands[r.best].uncertainty_m;
        }
    }
    if (s == TRN_E_NOTARGET) {
        v = HUGE_VAL;
    } else if (s != TRN_OK) {
        return s;
    }
    f->ev[i] = 1u;
    TRN_GRID_AT(f->out, x, y) = (float)v;
    f->st->evaluations++;
    if (v < f->st->best_m) {
        f->st->best_m = v;
        f->st->best_x = f->area.x0 + x;
        f->st->best_y = f->area.y0 + y;
    }
    if (f->progress != NULL &&
        f->progress(f->progress_user, f->st->evaluations, f->st->cells) != 0) {
        return TRN_E_CANCELLED;
    }
    return TRN_OK;
}

static int32_t lat(int32_t i, int32_t s, int32_t n)
{
    const int32_t v = i * s;
    return v < n - 1 ? v : n - 1;
}

/* Number of lattice intervals of step s over n cells. */
static int32_t nint(int32_t s, int32_t n) { return (n - 1 + s - 1) / s; }

/* Checks common to trn_field and trn_field_fast (not the workspace). */
static trn_status_t field_check(const trn_map_t *map, const trn_kernels_t *k,
                                const trn_vol_f32_t *pg, const trn_select_cfg_t *scfg,
                                const trn_field_cfg_t *fcfg, float heading_rad,
                                const trn_window_t *area, const trn_grid_f32_t *out,
                                const uint8_t *evaluated, size_t evaluated_len,
                                const trn_field_stats_t *stats, const void *ws)
{
    trn_status_t s;
    if (map == NULL || k == NULL || pg == NULL || scfg == NULL || fcfg == NULL || area == NULL ||
        out == NULL || evaluated == NULL || stats == NULL || ws == NULL) {
        return TRN_E_NULL;
    }
    if ((s = trn_field_cfg_check(fcfg)) != TRN_OK) {
        return s;
    }
    if ((s = trn_select_cfg_check(scfg, map->cfg.terrain.cell_m)) != TRN_OK) {
        return s;
    }
    if (!isfinite(heading_rad)) {
        return TRN_E_ARG;
    }
    if ((s = trn_grid_f32_check(out)) != TRN_OK) {
        return s;
    }
    if ((s = trn_vol_u8_check(&map->dist)) != TRN_OK) {
        return s;
    }
    if (area->x1 < area->x0 || area->y1 < area->y0 || area->x0 < 0 || area->y0 < 0 ||
        area->x1 >= map->dist.nx || area->y1 >= map->dist.ny) {
        return TRN_E_RANGE;
    }
    if (out->width != area->x1 - area->x0 + 1 || out->height != area->y1 - area->y0 + 1 ||
        evaluated_len < (size_t)out->width * (size_t)out->height) {
        return TRN_E_SIZE;
    }
    return TRN_OK;
}

/* The coarse-to-fine rule (field.h) over f, set up by the caller. */
static trn_status_t field_run(field_t *f, const trn_field_cfg_t *fcfg)
{
    trn_status_t s;
    const int32_t w = f->w, h = f->h;
    trn_grid_f32_t *out = f->out;
    uint8_t *evaluated = f->ev;
    trn_field_stats_t *stats = f->st;
    int32_t step, i, j, x, y;
    double spread;

    memset(evaluated, 0, (size_t)w * (size_t)h);
    stats->evaluations = 0u;
    stats->cells = (uint32_t)w * (uint32_t)h;
    stats->best_x = -1;
    stats->best_y = -1;
    stats->best_m = HUGE_VAL;
    f->progress = fcfg->progress;
    f->progress_user = fcfg->progress_user;

    /* coarse lattice */
    step = fcfg->coarse_step_cells;
    for (j = 0; j <= nint(step, h); ++j) {
        for (i = 0; i <= nint(step, w); ++i) {
            if ((s = eval_cell(f, lat(i, step, w), lat(j, step, h))) != TRN_OK) {
                return s;
            }
        }
    }
    /* the coarse field's spread: its mean finite value minus its minimum */
    {
        double sum = 0.0;
        uint32_t nf = 0u;
        for (j = 0; j <= nint(step, h); ++j) {
            for (i = 0; i <= nint(step, w); ++i) {
                const double v = (double)TRN_GRID_AT(out, lat(i, step, w), lat(j, step, h));
                if (isfinite(v)) {
                    sum += v;
                    ++nf;
                }
            }
        }
        spread = nf > 0u ? sum / (double)nf - stats->best_m : 0.0;
    }
    /* refinement levels */
    for (; step > 1; step /= 2) {
        const double best = stats->best_m;
        const int32_t half = step / 2;
        /* the low band narrows with the step: margin_rel * S at the coarse
         * level, half of it at the next, ... */
        const double band = (double)fcfg->margin_rel * spread * (double)step /
                            (double)fcfg->coarse_step_cells;
        for (j = 0; j < nint(step, h); ++j) {
            for (i = 0; i < nint(step, w); ++i) {
                const int32_t xa = lat(i, step, w), xb = lat(i + 1, step, w);
                const int32_t ya = lat(j, step, h), yb = lat(j + 1, step, h);
                const int32_t xm = lat(2 * i + 1, half, w), ym = lat(2 * j + 1, half, h);
                const int32_t cx[4] = {xa, xb, xa, xb}, cy[4] = {ya, ya, yb, yb};
                double vmin = HUGE_VAL, vmax = -HUGE_VAL;
                int c, nfin = 0, known = 1, refine;
                for (c = 0; c < 4; ++c) {
                    const size_t id = (size_t)cy[c] * (size_t)w + (size_t)cx[c];
                    double v;
                    if (evaluated[id] == 0u) {
                        known = 0;
                        break;
                    }
                    v = (double)TRN_GRID_AT(out, cx[c], cy[c]);
                    if (isfinite(v)) {
                        ++nfin;
                        vmin = v < vmin ? v : vmin;
                        vmax = v > vmax ? v : vmax;
                    }
                }
                if (!known || nfin == 0) {
                    continue;
                }
                /* low squares are refined down to single cells; squares that
                 * only change fast (or are partly uninformative) down to a
                 * quarter of the coarse step: enough to place the edge of a
                 * rock's shadow, without resolving cell-to-cell noise */
                refine = vmin <= best + band ||
                         (4 * step > fcfg->coarse_step_cells &&
                          (nfin < 4 || vmax - vmin > (double)fcfg->change_rel * spread));
                if (!refine) {
                    continue;
                }
                if ((s = eval_cell(f, xm, ya)) != TRN_OK || (s = eval_cell(f, xa, ym)) != TRN_OK ||
                    (s = eval_cell(f, xm, ym)) != TRN_OK || (s = eval_cell(f, xb, ym)) != TRN_OK ||
                    (s = eval_cell(f, xm, yb)) != TRN_OK) {
                    return s;
                }
            }
        }
    }
    /* fill: bilinear in the finest enclosing square with known corners */
    for (y = 0; y < h; ++y) {
        for (x = 0; x < w; ++x) {
            int32_t st;
            if (evaluated[(size_t)y * (size_t)w + (size_t)x] != 0u) {
                continue;
            }
            TRN_GRID_AT(out, x, y) = HUGE_VALF;
            for (st = 2; st <= fcfg->coarse_step_cells; st *= 2) {
                const int32_t xa = lat(x / st, st, w), xb = lat(x / st + 1, st, w);
                const int32_t ya = lat(y / st, st, h), yb = lat(y / st + 1, st, h);
                if (evaluated[(size_t)ya * (size_t)w + (size_t)xa] &&
                    evaluated[(size_t)ya * (size_t)w + (size_t)xb] &&
                    evaluated[(size_t)yb * (size_t)w + (size_t)xa] &&
                    evaluated[(size_t)yb * (size_t)w + (size_t)xb]) {
                    const double tx = xb > xa ? (double)(x - xa) / (double)(xb - xa) : 0.0;
                    const double ty = yb > ya ? (double)(y - ya) / (double)(yb - ya) : 0.0;
                    const double v00 = (double)TRN_GRID_AT(out, xa, ya);
                    const double v10 = (double)TRN_GRID_AT(out, xb, ya);
                    const double v01 = (double)TRN_GRID_AT(out, xa, yb);
                    const double v11 = (double)TRN_GRID_AT(out, xb, yb);
                    const double v = (1.0 - ty) * ((1.0 - tx) * v00 + tx * v10) +
                                     ty * ((1.0 - tx) * v01 + tx * v11);
                    TRN_GRID_AT(out, x, y) = isfinite(v) ? (float)v : HUGE_VALF;
                    break;
                }
            }
        }
    }
    if (f->progress != NULL) {
        (void)f->progress(f->progress_user, stats->cells, stats->cells);
    }
    return TRN_OK;
}

/* The run's arguments (what trn_field and trn_field_fast share). */
static void field_setup(field_t *f, const trn_map_t *map, const trn_kernels_t *k,
                        const trn_vol_f32_t *pg, const trn_select_cfg_t *scfg, float heading_rad,
                        const trn_window_t *area, trn_grid_f32_t *out, uint8_t *evaluated,
                        trn_field_stats_t *stats)
{
    memset(f, 0, sizeof *f);
    f->map = map;
    f->k = k;
    f->pg = pg;
    f->scfg = scfg;
    f->heading = heading_rad;
    f->area = *area;
    f->w = out->width;
    f->h = out->height;
    f->out = out;
    f->ev = evaluated;
    f->st = stats;
}

trn_status_t trn_field(const trn_map_t *map, const trn_kernels_t *k, const trn_vol_f32_t *pg,
                       const trn_select_cfg_t *scfg, const trn_field_cfg_t *fcfg, float heading_rad,
                       const trn_window_t *area, trn_grid_f32_t *out, uint8_t *evaluated,
                       size_t evaluated_len, trn_field_stats_t *stats, void *ws, size_t ws_bytes)
{
    field_t f;
    trn_status_t s;
    size_t need;

    if ((s = field_check(map, k, pg, scfg, fcfg, heading_rad, area, out, evaluated, evaluated_len,
                         stats, ws)) != TRN_OK) {
        return s;
    }
    need = trn_field_workspace_bytes(scfg, map, k);
    if ((s = trn_ws_check(ws, ws_bytes, need)) != TRN_OK) {
        return s;
    }
    field_setup(&f, map, k, pg, scfg, heading_rad, area, out, evaluated, stats);
    (void)field_carve(scfg, map, k, ws, &f.cands, &f.ncap, &f.sws, &f.swsb);
    f.pre = NULL;
    return field_run(&f, fcfg);
}

/* trn_field_fast's carve: the precomputation's header, then its tables
 * (base NULL: sizing only). Returns the bytes, 0 if refused. */
static size_t field_fast_carve(const trn_select_cfg_t *scfg, const trn_map_t *map,
                               const trn_kernels_t *k, const trn_vol_f32_t *pg, void *base,
                               trn_selpre_t **pre, void **tables, size_t *tables_bytes)
{
    const size_t b = trn_selpre_bytes(scfg, map, k, pg);
    trn_ws_t w;
    *pre = NULL;
    *tables = NULL;
    *tables_bytes = b;
    if (b == 0u) {
        return 0u;
    }
    trn_ws_begin(&w, base);
    *pre = (trn_selpre_t *)trn_ws_take(&w, sizeof(trn_selpre_t));
    *tables = trn_ws_take(&w, b);
    return w.total;
}

/* The heading-searched prediction and the height prediction (select.h)
 * have no ground path: trn_field_fast runs trn_field's for them, in
 * trn_field's workspace (the height prediction's tables are already O(1)
 * per candidate, and so the two give the same bits). */
static int field_fast_delegates(const trn_select_cfg_t *scfg, const trn_map_t *map)
{
    return (scfg != NULL && scfg->heading_search == 1 && scfg->sigma_heading_rad > 0.0f) ||
           (map != NULL && map->cfg.match == (int32_t)TRN_MATCH_HEIGHTS);
}

size_t trn_field_fast_workspace_bytes(const trn_select_cfg_t *scfg, const trn_map_t *map,
                                      const trn_kernels_t *k, const trn_vol_f32_t *pg)
{
    trn_selpre_t *pre;
    void *t;
    size_t tb;
    if (map != NULL && map->cfg.match == (int32_t)TRN_MATCH_HEIGHTS) {
        return trn_field_workspace_bytes(scfg, map, k);
    }
    if (field_fast_delegates(scfg, map) && pg != NULL && trn_selpre_bytes(scfg, map, k, pg) != 0u) {
        return trn_field_workspace_bytes(scfg, map, k);
    }
    return field_fast_carve(scfg, map, k, pg, NULL, &pre, &t, &tb);
}

trn_status_t trn_field_fast(const trn_map_t *map, const trn_kernels_t *k, const trn_vol_f32_t *pg,
                            const trn_select_cfg_t *scfg, const trn_field_cfg_t *fcfg,
                            float heading_rad, const trn_window_t *area, trn_grid_f32_t *out,
                            uint8_t *evaluated, size_t evaluated_len, trn_field_stats_t *stats,
                            void *ws, size_t ws_bytes)
{
    field_t f;
    trn_status_t s;
    trn_selpre_t *pre;
    void *tables;
    size_t need, tb;
    const size_t hb = TRN_ALIGN_UP(sizeof(trn_selpre_t));

    if ((s = field_check(map, k, pg, scfg, fcfg, heading_rad, area, out, evaluated, evaluated_len,
                         stats, ws)) != TRN_OK) {
        return s;
    }
    if (field_fast_delegates(scfg, map)) { /* trn_field's path, inline (one frame less deep) */
        need = trn_field_workspace_bytes(scfg, map, k);
        if ((s = trn_ws_check(ws, ws_bytes, need)) != TRN_OK) {
            return s;
        }
        field_setup(&f, map, k, pg, scfg, heading_rad, area, out, evaluated, stats);
        (void)field_carve(scfg, map, k, ws, &f.cands, &f.ncap, &f.sws, &f.swsb);
        f.pre = NULL;
        return field_run(&f, fcfg);
    }
    /* sizes refused (need 0): the header at least, and trn_selpre_init says why */
    need = field_fast_carve(scfg, map, k, pg, NULL, &pre, &tables, &tb);
    if ((s = trn_ws_check(ws, ws_bytes, need != 0u ? need : hb)) != TRN_OK) {
        return s;
    }
    (void)field_fast_carve(scfg, map, k, pg, ws, &pre, &tables, &tb);
    if (pre == NULL) {
        pre = (trn_selpre_t *)ws;
        tables = (uint8_t *)ws + hb;
    }
    if ((s = trn_selpre_init(pre, map, k, pg, scfg, tables, ws_bytes - hb)) != TRN_OK) {
        return s;
    }
    field_setup(&f, map, k, pg, scfg, heading_rad, area, out, evaluated, stats);
    f.pre = pre;
    return field_run(&f, fcfg);
}
