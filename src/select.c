/* SPDX-License-Identifier: Apache-2.0 */
/* select.c - candidate targets, expected log-likelihood by summed-area
 * tables, eq. 6 fit, ranking (see trn/select.h). */
#include "trn/select.h"

#include <math.h>
#include <string.h>

#define SEL_PI 3.14159265358979323846
#define SEL_QMAX (4 * TRN_SELECT_PROB_SCALE) /* P clamped to [0, 4] */

void trn_select_cfg_default(trn_select_cfg_t *cfg)
{
    if (cfg == NULL) {
        return;
    }
    cfg->min_range_m = 1.0f;
    cfg->max_range_m = 10.0f;
    cfg->pan_min_rad = (float)-SEL_PI;
    cfg->pan_max_rad = (float)SEL_PI;
    cfg->footprint_radius_m = 0.5f;
    cfg->patch_m = 2.0f;
    cfg->stride_cells = 2;
    cfg->min_separation_m = 1.0f;
    trn_sigma_local_default(&cfg->local_sigma);
}

/* patch_m in whole cells (nearest, so 2.0 m / 0.1f m is 20, not 19), then
 * up to the next odd number so the patch has a centre cell. */
static int32_t patch_cells(const trn_select_cfg_t *cfg, float cell_m)
{
    const int32_t n = (int32_t)floor((double)cfg->patch_m / (double)cell_m + 0.5);
    return (n % 2 == 0) ? n + 1 : n;
}

/* Candidate centres lie within reach cells of the rover cell on each axis. */
static int32_t reach_cells(const trn_select_cfg_t *cfg, float cell_m)
{
    return (int32_t)ceil((double)cfg->max_range_m / (double)cell_m) + 1;
}

trn_status_t trn_select_cfg_check(const trn_select_cfg_t *cfg, float cell_m)
{
    trn_status_t st;
    if (cfg == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_sigma_model_check(&cfg->local_sigma)) != TRN_OK) {
        return st;
    }
    if (!(cell_m > 0.0f && cell_m <= 1000.0f) ||
        !(cfg->max_range_m > 0.0f && cfg->max_range_m <= 1.0e6f) ||
        !(cfg->min_range_m >= 0.0f && cfg->min_range_m <= cfg->max_range_m) ||
        !(cfg->pan_min_rad >= (float)-SEL_PI && cfg->pan_max_rad <= (float)SEL_PI &&
          cfg->pan_min_rad <= cfg->pan_max_rad) ||
        !(cfg->footprint_radius_m >= 0.0f && cfg->footprint_radius_m <= 1.0e5f) ||
        !(cfg->patch_m > 0.0f && cfg->patch_m <= 1.0e6f) ||
        !(cfg->min_separation_m >= 0.0f && cfg->min_separation_m <= 1.0e6f) ||
        cfg->stride_cells < 1 || cfg->stride_cells > 64) {
        return TRN_E_ARG;
    }
    if ((double)cfg->patch_m / (double)cell_m > (double)TRN_MAX_DIM ||
        patch_cells(cfg, cell_m) < 3 ||
        (double)cfg->max_range_m / (double)cell_m > (double)TRN_MAX_DIM) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}

size_t trn_select_max_candidates(const trn_select_cfg_t *cfg, float cell_m)
{
    int32_t n;
    if (trn_select_cfg_check(cfg, cell_m) != TRN_OK) {
        return 0u;
    }
    n = reach_cells(cfg, cell_m) / cfg->stride_cells + 1;
    return (size_t)(2 * n + 1) * (size_t)(2 * n + 1);
}

/* Largest region side: every centre within reach, plus half a patch. */
static int32_t roi_side(const trn_select_cfg_t *cfg, float cell_m, int32_t dim)
{
    const int32_t s = 2 * (reach_cells(cfg, cell_m) + patch_cells(cfg, cell_m) / 2) + 1;
    return s < dim ? s : dim;
}

size_t trn_select_workspace_bytes(const trn_select_cfg_t *cfg, const trn_map_t *map,
                                  const trn_kernels_t *k)
{
    int32_t w, h;
    trn_window_t r;
    size_t lw;
    if (cfg == NULL || map == NULL || k == NULL || map->dist.nz < 1 ||
        trn_select_cfg_check(cfg, map->cfg.terrain.cell_m) != TRN_OK) {
        return 0u;
    }
    w = roi_side(cfg, map->cfg.terrain.cell_m, map->dist.nx);
    h = roi_side(cfg, map->cfg.terrain.cell_m, map->dist.ny);
    r.x0 = 0;
    r.y0 = 0;
    r.x1 = w - 1;
    r.y1 = h - 1;
    lw = trn_prob_local_workspace_bytes(k, &r);
    if (lw == 0u) {
        return 0u;
    }
    return TRN_ALIGN_UP((size_t)w * (size_t)h * (size_t)map->dist.nz * sizeof(float)) + lw +
           TRN_ALIGN_UP((size_t)(w + 1) * (size_t)(h + 1) * sizeof(int64_t)) +
           TRN_ALIGN_UP((size_t)w * sizeof(int64_t));
}

typedef struct {
    int32_t nx, ny, half, rx, ry, n;
    double rxf, ryf, cell, heading;
} geom_t;

/* Is lattice point (cx, cy) a candidate? Fills range and bearing. */
static int candidate_ok(const trn_select_cfg_t *cfg, const geom_t *g, int32_t cx, int32_t cy,
                        float *range_m, float *bearing_rad)
{
    const double dx = (double)cx - g->rxf, dy = (double)cy - g->ryf;
    const double r = sqrt(dx * dx + dy * dy) * g->cell;
    const double hx = (double)g->half + 0.5;
    double b, ex, ey;
    /* the patch and its one-cell pose margin inside the map: a patch cut by
     * the map's edge would look informative because of the edge alone */
    if (cx - g->half - 1 < 0 || cy - g->half - 1 < 0 || cx + g->half + 1 > g->nx - 1 ||
        cy + g->half + 1 > g->ny - 1) {
        return 0;
    }
    if (r < (double)cfg->min_range_m || r > (double)cfg->max_range_m) {
        return 0;
    }
    ex = fabs(dx) - hx;
    ey = fabs(dy) - hx;
    ex = ex > 0.0 ? ex : 0.0;
    ey = ey > 0.0 ? ey : 0.0;
    if (sqrt(ex * ex + ey * ey) * g->cell < (double)cfg->footprint_radius_m) {
        return 0;
    }
    b = atan2(dy, dx) - g->heading;
    b = remainder(b, 2.0 * SEL_PI); /* [-pi, pi] */
    if (b < (double)cfg->pan_min_rad || b > (double)cfg->pan_max_rad) {
        return 0;
    }
    *range_m = (float)r;
    *bearing_rad = (float)b;
    return 1;
}

/* Window of the patch centred at (cx, cy), clipped to the map. */
static void patch_window(const geom_t *g, int32_t cx, int32_t cy, trn_window_t *w)
{
    w->x0 = cx - g->half > 0 ? cx - g->half : 0;
    w->y0 = cy - g->half > 0 ? cy - g->half : 0;
    w->x1 = cx + g->half < g->nx - 1 ? cx + g->half : g->nx - 1;
    w->y1 = cy + g->half < g->ny - 1 ? cy + g->half : g->ny - 1;
}

/* Summed-area table of C_d over the region: sat[(y+1)(w+1) + x+1] = sum of
 * C_d over [0, x] x [0, y] of the region. */
static void build_sat(const trn_map_t *map, const trn_vol_f32_t *p, const trn_window_t *roi,
                      int32_t dx, int32_t dy, int64_t *sat, int64_t *crow)
{
    const trn_vol_u8_t *d = &map->dist;
    const int32_t *lnp = map->lnp.lnp;
    const int32_t w = p->nx, h = p->ny;
    const size_t w1 = (size_t)w + 1u;
    const size_t lplane = (size_t)w * (size_t)h;
    const uint8_t cap = map->lnp.cap;
    int32_t y, x, z;
    memset(sat, 0, w1 * sizeof *sat);
    for (y = 0; y < h; ++y) {
        const int32_t gy = roi->y0 + y + dy;
        int64_t run = 0;
        memset(crow, 0, (size_t)w * sizeof *crow);
        for (z = 0; z < p->nz; ++z) {
            const float *prow = p->data + (size_t)z * lplane + (size_t)y * (size_t)w;
            const uint8_t *drow =
                (gy >= 0 && gy < d->ny) ? d->data + TRN_VOL_IDX(d, 0, gy, z) : NULL;
            for (x = 0; x < w; ++x) {
                const float pv = prow[x];
                int32_t gx, q;
                uint8_t dv;
                if (!(pv > 0.0f)) {
                    continue;
                }
                q = pv >= 4.0f ? SEL_QMAX
                               : (int32_t)(pv * (float)TRN_SELECT_PROB_SCALE + 0.5f);
                gx = roi->x0 + x + dx;
                dv = (drow != NULL && gx >= 0 && gx < d->nx) ? drow[gx] : cap;
                dv = dv < cap ? dv : cap;
                crow[x] += (int64_t)q * (int64_t)lnp[dv];
            }
        }
        sat[(size_t)(y + 1) * w1] = 0;
        for (x = 0; x < w; ++x) {
            run += crow[x];
            sat[(size_t)(y + 1) * w1 + (size_t)x + 1u] = sat[(size_t)y * w1 + (size_t)x + 1u] + run;
        }
    }
}

static int64_t window_sum(const int64_t *sat, size_t w1, const trn_window_t *roi,
                          const trn_window_t *pw)
{
    const size_t x0 = (size_t)(pw->x0 - roi->x0), x1 = (size_t)(pw->x1 - roi->x0) + 1u;
    const size_t y0 = (size_t)(pw->y0 - roi->y0), y1 = (size_t)(pw->y1 - roi->y0) + 1u;
    return sat[y1 * w1 + x1] - sat[y0 * w1 + x1] - sat[y1 * w1 + x0] + sat[y0 * w1 + x0];
}

trn_status_t trn_select(const trn_map_t *map, const trn_kernels_t *k, const trn_vol_f32_t *pg,
                        const trn_select_cfg_t *cfg, const trn_rover_t *rover,
                        trn_candidate_t *cands, size_t capacity, size_t *ranked,
                        size_t ranked_cap, trn_select_result_t *res, void *ws, size_t ws_bytes)
{
    trn_status_t st;
    geom_t g;
    trn_window_t roi, pw;
    trn_vol_f32_t p;
    int64_t *sat, *crow;
    uint8_t *base;
    size_t need, nc = 0u, i, ninf = 0u, nr = 0u, lw, w1;
    int32_t i_x, i_y, d, side_w, side_h, lmax = 0;
    double scale, sep2_cells;

    if (map == NULL || k == NULL || pg == NULL || cfg == NULL || rover == NULL ||
        cands == NULL || ranked == NULL || res == NULL || ws == NULL || pg->data == NULL ||
        map->dist.data == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_select_cfg_check(cfg, map->cfg.terrain.cell_m)) != TRN_OK) {
        return st;
    }
    if (!isfinite(rover->pos.x_cells) || !isfinite(rover->pos.y_cells) ||
        !isfinite(rover->heading_rad)) {
        return TRN_E_ARG;
    }
    if ((st = trn_vol_u8_check(&map->dist)) != TRN_OK) {
        return st;
    }
    if (pg->nx != map->dist.nx || pg->ny != map->dist.ny || pg->nz != map->dist.nz ||
        map->lnp.cap < 1u || map->lnp.cap > TRN_CHAMFER_CAP_MAX) {
        return TRN_E_SIZE;
    }
    if (rover->pos.x_cells < -0.5f || rover->pos.y_cells < -0.5f ||
        rover->pos.x_cells > (float)map->dist.nx - 0.5f ||
        rover->pos.y_cells > (float)map->dist.ny - 0.5f) {
        return TRN_E_RANGE;
    }
    if (capacity == 0u || ranked_cap == 0u) {
        return TRN_E_CAPACITY;
    }
    need = trn_select_workspace_bytes(cfg, map, k);
    if (need == 0u || ws_bytes < need || ((uintptr_t)ws & 15u) != 0u) {
        return TRN_E_WORKSPACE;
    }

    g.nx = map->dist.nx;
    g.ny = map->dist.ny;
    g.half = patch_cells(cfg, map->cfg.terrain.cell_m) / 2;
    g.rxf = (double)rover->pos.x_cells;
    g.ryf = (double)rover->pos.y_cells;
    g.rx = (int32_t)floor(g.rxf + 0.5);
    g.ry = (int32_t)floor(g.ryf + 0.5);
    g.cell = (double)map->cfg.terrain.cell_m;
    g.heading = (double)rover->heading_rad;
    g.n = reach_cells(cfg, map->cfg.terrain.cell_m) / cfg->stride_cells + 1;

    /* 1. candidates and the region covering their patches */
    roi.x0 = g.nx;
    roi.y0 = g.ny;
    roi.x1 = -1;
    roi.y1 = -1;
    for (i_y = -g.n; i_y <= g.n; ++i_y) {
        for (i_x = -g.n; i_x <= g.n; ++i_x) {
            const int32_t cx = g.rx + i_x * cfg->stride_cells, cy = g.ry + i_y * cfg->stride_cells;
            float rm, bb;
            if (!candidate_ok(cfg, &g, cx, cy, &rm, &bb)) {
                continue;
            }
            if (nc >= capacity) {
                return TRN_E_CAPACITY;
            }
            memset(&cands[nc], 0, sizeof cands[nc]);
            cands[nc].x = cx;
            cands[nc].y = cy;
            cands[nc].range_m = rm;
            cands[nc].bearing_rad = bb;
            patch_window(&g, cx, cy, &pw);
            roi.x0 = pw.x0 < roi.x0 ? pw.x0 : roi.x0;
            roi.y0 = pw.y0 < roi.y0 ? pw.y0 : roi.y0;
            roi.x1 = pw.x1 > roi.x1 ? pw.x1 : roi.x1;
            roi.y1 = pw.y1 > roi.y1 ? pw.y1 : roi.y1;
            ++nc;
        }
    }
    memset(res, 0, sizeof *res);
    res->patch_cells = 2 * g.half + 1;
    if (nc == 0u) {
        return TRN_E_NOTARGET;
    }
    res->roi = roi;
    res->n_candidates = nc;
    side_w = roi.x1 - roi.x0 + 1;
    side_h = roi.y1 - roi.y0 + 1;

    /* exact int64 sums: |q lnp| summed over the region must fit */
    for (d = 0; d <= (int32_t)map->lnp.cap; ++d) {
        const int32_t a = map->lnp.lnp[d] < 0 ? -map->lnp.lnp[d] : map->lnp.lnp[d];
        lmax = a > lmax ? a : lmax;
    }
    if ((double)side_w * (double)side_h * (double)pg->nz * (double)SEL_QMAX * (double)lmax >
        9.0e18) {
        return TRN_E_SIZE;
    }

    /* 2. eq. 9 over the region */
    base = (uint8_t *)ws;
    p.data = (float *)(void *)base;
    p.nx = side_w;
    p.ny = side_h;
    p.nz = pg->nz;
    base += TRN_ALIGN_UP((size_t)side_w * (size_t)side_h * (size_t)pg->nz * sizeof(float));
    lw = trn_prob_local_workspace_bytes(k, &roi);
    st = trn_prob_local(k, &cfg->local_sigma, map->cfg.terrain.cell_m, rover->pos, pg, &roi, &p,
                        base, lw);
    if (st != TRN_OK) {
        return st;
    }
    base += lw;
    sat = (int64_t *)(void *)base;
    w1 = (size_t)side_w + 1u;
    base += TRN_ALIGN_UP(w1 * ((size_t)side_h + 1u) * sizeof(int64_t));
    crow = (int64_t *)(void *)base;

    /* 3. one summed-area table per pose offset, every window read from it */
    scale = 1.0 / ((double)TRN_SELECT_PROB_SCALE * (double)TRN_LNP_SCALE);
    for (d = 0; d < 9; ++d) {
        build_sat(map, &p, &roi, d % 3 - 1, d / 3 - 1, sat, crow);
        for (i = 0; i < nc; ++i) {
            patch_window(&g, cands[i].x, cands[i].y, &pw);
            cands[i].ll[d] = (double)window_sum(sat, w1, &roi, &pw) * scale;
        }
    }

    /* 4. eq. 6 per candidate */
    for (i = 0; i < nc; ++i) {
        trn_peak_t pk;
        trn_candidate_t *c = &cands[i];
        if (trn_peak_fit(c->ll, &pk) == TRN_OK) {
            c->informative = 1;
            c->sigma_x_m = pk.sigma_x * g.cell;
            c->sigma_y_m = pk.sigma_y * g.cell;
            c->rho = pk.rho;
            c->cov_m2[0] = pk.var_x * g.cell * g.cell;
            c->cov_m2[1] = pk.var_y * g.cell * g.cell;
            c->cov_m2[2] = pk.cov_xy * g.cell * g.cell;
            c->uncertainty_m = sqrt(c->sigma_x_m * c->sigma_x_m + c->sigma_y_m * c->sigma_y_m);
            ++ninf;
        } else {
            c->informative = 0;
            c->sigma_x_m = HUGE_VAL;
            c->sigma_y_m = HUGE_VAL;
            c->rho = 0.0;
            c->cov_m2[0] = HUGE_VAL;
            c->cov_m2[1] = HUGE_VAL;
            c->cov_m2[2] = 0.0;
            c->uncertainty_m = HUGE_VAL;
        }
    }
    res->n_informative = ninf;
    if (ninf == 0u) {
        return TRN_E_NOTARGET;
    }

    /* 5. ranking: repeatedly the lowest uncertainty at least min_separation
     * from every target already ranked (ties: earlier in lattice order) */
    sep2_cells = (double)cfg->min_separation_m / g.cell;
    sep2_cells *= sep2_cells;
    for (nr = 0u; nr < ranked_cap; ++nr) {
        size_t best = nc, j;
        for (i = 0; i < nc; ++i) {
            int ok = cands[i].informative;
            for (j = 0; ok && j < nr; ++j) {
                const double ex = (double)(cands[i].x - cands[ranked[j]].x);
                const double ey = (double)(cands[i].y - cands[ranked[j]].y);
                if (i == ranked[j] || ex * ex + ey * ey < sep2_cells) {
                    ok = 0;
                }
            }
            if (ok && (best == nc || cands[i].uncertainty_m < cands[best].uncertainty_m)) {
                best = i;
            }
        }
        if (best == nc) {
            break;
        }
        ranked[nr] = best;
    }
    res->n_ranked = nr;
    res->best = ranked[0];
    return TRN_OK;
}
