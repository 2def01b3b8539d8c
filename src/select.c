/* SPDX-License-Identifier: Apache-2.0 */
/* select.c - candidate targets, expected log-likelihood by summed-area
 * tables, eq. 6 fit, ranking (see trn/select.h). */
#include "trn/select.h"
#include "select_heights.h"
#include "select_pre.h"
#include "ws.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#define SEL_PI 3.14159265358979323846
#define SEL_QMAX (4 * TRN_SELECT_PROB_SCALE) /* P clamped to [0, 4] */
#define PRE_CDN 10 /* ground path, per cached cell: the nine C_d, the bound's excess */

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
    cfg->sigma_heading_rad = 0.0f;
    cfg->heading_search = 0;
    cfg->map_sigma_m = 0.02f;
    cfg->points_per_cell = 0.0f;
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
    if (!(cell_m > 0.0f && cell_m <= TRN_CELL_MAX_M) ||
        !(cfg->max_range_m > 0.0f && cfg->max_range_m <= 1.0e6f) ||
        !(cfg->min_range_m >= 0.0f && cfg->min_range_m <= cfg->max_range_m) ||
        !(cfg->pan_min_rad >= (float)-SEL_PI && cfg->pan_max_rad <= (float)SEL_PI &&
          cfg->pan_min_rad <= cfg->pan_max_rad) ||
        !(cfg->footprint_radius_m >= 0.0f && cfg->footprint_radius_m <= 1.0e5f) ||
        !(cfg->patch_m > 0.0f && cfg->patch_m <= 1.0e6f) ||
        !(cfg->min_separation_m >= 0.0f && cfg->min_separation_m <= 1.0e6f) ||
        !(cfg->sigma_heading_rad >= 0.0f &&
          cfg->sigma_heading_rad <= TRN_SELECT_MAX_SIGMA_HEADING_RAD) ||
        cfg->stride_cells < 1 || cfg->stride_cells > 64 ||
        (cfg->heading_search != 0 && cfg->heading_search != 1) ||
        !(cfg->map_sigma_m >= 0.0f && cfg->map_sigma_m <= 1000.0f) ||
        !(cfg->points_per_cell == 0.0f ||
          (cfg->points_per_cell >= 1.0f && (double)cfg->points_per_cell <= TRN_POINT_COUNT_MAX))) {
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

/* trn_select's carve for a region of w x h cells and nz bins: eq. 9's
 * volume, trn_prob_local's workspace (lw bytes), the summed-area table and
 * its row of column sums (base NULL: sizing only). Returns the bytes. The
 * sizing function carves the largest region, trn_select the one it has. */
typedef struct {
    float *p;
    void *lws;
    int64_t *sat, *crow;
    double *rp1, *rp2, *q7; /* heading searched: row moment prefixes, 7 sums per candidate */
} sel_layout_t;

/* The heading-searched prediction applies (select.h): its moments are kept. */
static int sel_moments(const trn_select_cfg_t *cfg)
{
    return cfg->heading_search == 1 && cfg->sigma_heading_rad > 0.0f;
}

/* ncap > 0: also the moment arrays of the heading-searched prediction. */
static size_t select_carve(int32_t w, int32_t h, int32_t nz, size_t lw, size_t ncap, void *base,
                           sel_layout_t *lay)
{
    trn_ws_t c;
    const size_t pre = (size_t)h * ((size_t)w + 1u) * sizeof(double);
    trn_ws_begin(&c, base);
    lay->p = (float *)trn_ws_take(&c, (size_t)w * (size_t)h * (size_t)nz * sizeof(float));
    lay->lws = trn_ws_take(&c, lw);
    lay->sat = (int64_t *)trn_ws_take(&c, ((size_t)w + 1u) * ((size_t)h + 1u) * sizeof(int64_t));
    lay->crow = (int64_t *)trn_ws_take(&c, (size_t)w * sizeof(int64_t));
    lay->rp1 = lay->rp2 = lay->q7 = NULL;
    if (ncap > 0u) {
        lay->rp1 = (double *)trn_ws_take(&c, pre);
        lay->rp2 = (double *)trn_ws_take(&c, pre);
        lay->q7 = (double *)trn_ws_take(&c, ncap * 7u * sizeof(double));
    }
    return c.total;
}

/* The map matches heights: trn_select predicts that matcher (select.h). */
static int sel_heights(const trn_map_t *map)
{
    return map->cfg.match == (int32_t)TRN_MATCH_HEIGHTS;
}

size_t trn_select_workspace_bytes(const trn_select_cfg_t *cfg, const trn_map_t *map,
                                  const trn_kernels_t *k)
{
    sel_layout_t lay;
    int32_t w, h;
    trn_window_t r;
    size_t lw;
    if (cfg != NULL && map != NULL && sel_heights(map)) {
        if (trn_select_cfg_check(cfg, map->cfg.terrain.cell_m) != TRN_OK ||
            trn_grid_f32_check(&map->heights) != TRN_OK) {
            return 0u;
        }
        w = roi_side(cfg, map->cfg.terrain.cell_m, map->heights.width);
        h = roi_side(cfg, map->cfg.terrain.cell_m, map->heights.height);
        return trn_selh_bytes_(w, h, sel_moments(cfg));
    }
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
    return select_carve(w, h, map->dist.nz, lw,
                        sel_moments(cfg) ? trn_select_max_candidates(cfg, map->cfg.terrain.cell_m)
                                         : 0u,
                        NULL, &lay);
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
                      int32_t dx, int32_t dy, int64_t *sat, int64_t *crow, double *rp1, double *rp2)
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
            const uint8_t *drow = (gy >= 0 && gy < d->ny) ? d->data + TRN_VOL_IDX(d, 0, gy, z)
                                                          : NULL;
            for (x = 0; x < w; ++x) {
                const float pv = prow[x];
                int32_t gx, q;
                uint8_t dv;
                if (!(pv > 0.0f)) {
                    continue;
                }
                q = pv >= 4.0f ? SEL_QMAX : (int32_t)(pv * (float)TRN_SELECT_PROB_SCALE + 0.5f);
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
        if (rp1 != NULL) { /* row prefixes of (x - w/2) C_d and (x - w/2)^2 C_d */
            double *r1 = rp1 + (size_t)y * w1, *r2 = rp2 + (size_t)y * w1;
            const double xm = 0.5 * (double)w;
            r1[0] = 0.0;
            r2[0] = 0.0;
            for (x = 0; x < w; ++x) {
                const double u = (double)x - xm, cv = (double)crow[x];
                r1[x + 1] = r1[x] + u * cv;
                r2[x + 1] = r2[x] + u * u * cv;
            }
        }
    }
}

/* The heading-searched prediction's seven sums of candidate c for pose
 * offset d (select.h): the patch's first and second moments of C_d about its
 * centre (w = voxel - centre, cells), each in nats, folded with eq. 6's
 * linear map for d (H_xx = sum (x_d^2 - 2/3) ll_d, H_yy likewise,
 * H_xy = sum x_d y_d ll_d / 4): q7 += [Lxx(M_wy), Lxy(M_wx), Lxy(M_wy),
 * Lyy(M_wx), Lxx(M_wyy), Lxy(M_wxy), Lyy(M_wxx)]. */
void trn_sel_moment_sums_(const int64_t *sat, const double *rp1, const double *rp2,
                          const trn_window_t *roi, const trn_window_t *pw, int32_t d, double scale,
                          double q7[7])
{
    /* the patch lies inside the map (one-cell margin), so pw is unclipped and
     * centred on the candidate; x measured from the region's middle as in
     * build_sat's prefixes */
    const size_t w1 = (size_t)(roi->x1 - roi->x0) + 2u;
    const int32_t cy = (pw->y0 + pw->y1) / 2;
    const int32_t cxr = (pw->x0 + pw->x1) / 2 - roi->x0; /* the centre column in the region */
    const double xc = (double)cxr - 0.5 * (double)(w1 - 1u);
    const size_t x0 = (size_t)(pw->x0 - roi->x0), x1 = (size_t)(pw->x1 - roi->x0) + 1u;
    const int32_t ix = d % 3 - 1, iy = d / 3 - 1; /* the pose offset */
    const double lx = (double)ix, ly = (double)iy;
    const double cxx = lx * lx - 2.0 / 3.0, cyy = ly * ly - 2.0 / 3.0, cxy = lx * ly / 4.0;
    double mx = 0.0, my = 0.0, mxx = 0.0, mxy = 0.0, myy = 0.0;
    int32_t y;
    for (y = pw->y0; y <= pw->y1; ++y) {
        const size_t r = (size_t)(y - roi->y0);
        const int64_t s0i = (sat[(r + 1u) * w1 + x1] - sat[r * w1 + x1]) -
                            (sat[(r + 1u) * w1 + x0] - sat[r * w1 + x0]);
        const double s0 = (double)s0i;
        const double s1 = rp1[r * w1 + x1] - rp1[r * w1 + x0];
        const double s2 = rp2[r * w1 + x1] - rp2[r * w1 + x0];
        const double wy = (double)(y - cy);
        const double m1 = s1 - xc * s0;
        mx += m1;
        my += wy * s0;
        mxx += s2 - 2.0 * xc * s1 + xc * xc * s0;
        mxy += wy * m1;
        myy += wy * wy * s0;
    }
    mx *= scale;
    my *= scale;
    mxx *= scale;
    mxy *= scale;
    myy *= scale;
    q7[0] += cxx * my;
    q7[1] += cxy * mx;
    q7[2] += cxy * my;
    q7[3] += cyy * mx;
    q7[4] += cxx * myy;
    q7[5] += cxy * mxy;
    q7[6] += cyy * mxx;
}

/* The position's marginal with the heading searched (select.h): cov (m^2) =
 * (A^-1 + g g^T / (s_h^-2 + I)) c^2, g = A^-1 b, I = max(0, cc - b^T g), from
 * the fit's A^-1 (pk, cells^2), the (x, y) x heading information b and the
 * heading's cc. Returns sqrt(var_x + var_y); *head_m |g| c / sqrt(s_h^-2 + I).
 * One function for the voxel and the height predictions. */
static double sel_marginal(const trn_peak_t *pk, double bx, double by, double cc, double cell,
                           double sh, double cov[3], double *head_m)
{
    const double gx = pk->var_x * bx + pk->cov_xy * by, gy = pk->cov_xy * bx + pk->var_y * by;
    double info = cc - (bx * gx + by * gy), den;
    info = info > 0.0 ? info : 0.0;
    den = 1.0 / (sh * sh) + info;
    cov[0] = (pk->var_x + gx * gx / den) * cell * cell;
    cov[1] = (pk->var_y + gy * gy / den) * cell * cell;
    cov[2] = (pk->cov_xy + gx * gy / den) * cell * cell;
    *head_m = sqrt((gx * gx + gy * gy) / den) * cell;
    return sqrt(cov[0] + cov[1]);
}

/* The heading-searched covariance (select.h) of a fitted candidate: cov
 * (m^2) = (A^-1 + g g^T / (s_h^-2 + I)) c^2 from the fit's A^-1, eq. 6's
 * Hessian of ll, the seven sums q7 and the rover-to-target offset (ox, oy)
 * in cells. Returns the scalar sqrt(var_x + var_y); *head_m the heading's
 * part |g| c / sqrt(s_h^-2 + I). */
double trn_sel_search_cov_(const trn_peak_t *pk, const double ll[9], const double q7[7],
                           double cell, double sh, double ox, double oy, double cov[3],
                           double *head_m)
{
    double hxx = 0.0, hyy = 0.0, hxy = 0.0, bx, by, cc;
    int32_t d;
    for (d = 0; d < 9; ++d) {
        const int32_t ix = d % 3 - 1, iy = d / 3 - 1;
        const double lx = (double)ix, ly = (double)iy;
        hxx += (lx * lx - 2.0 / 3.0) * ll[d];
        hyy += (ly * ly - 2.0 / 3.0) * ll[d];
        hxy += lx * ly / 4.0 * ll[d];
    }
    /* b = sum A_v J u_v, c = sum (J u_v)^T A_v J u_v with A_v = -L(v's terms),
     * u_v = w_v + (ox, oy): the centred moments q7 plus the offset's terms */
    bx = q7[0] + oy * hxx - q7[1] - ox * hxy;
    by = q7[2] + oy * hxy - q7[3] - ox * hyy;
    cc = -(q7[4] + 2.0 * oy * q7[0] + oy * oy * hxx) +
         2.0 * (q7[5] + ox * q7[2] + oy * q7[1] + ox * oy * hxy) -
         (q7[6] + 2.0 * ox * q7[3] + ox * ox * hyy);
    return sel_marginal(pk, bx, by, cc, cell, sh, cov, head_m);
}

static int64_t window_sum(const int64_t *sat, size_t w1, const trn_window_t *roi,
                          const trn_window_t *pw)
{
    const size_t x0 = (size_t)(pw->x0 - roi->x0), x1 = (size_t)(pw->x1 - roi->x0) + 1u;
    const size_t y0 = (size_t)(pw->y0 - roi->y0), y1 = (size_t)(pw->y1 - roi->y0) + 1u;
    return sat[y1 * w1 + x1] - sat[y0 * w1 + x1] - sat[y1 * w1 + x0] + sat[y0 * w1 + x0];
}

/* The heading's lever arm (select.h, method.md 4): the fit's covariance
 * (cells^2) in m^2 plus s_h^2 r^2 t t^T, t the unit tangent at the target,
 * written without a square root or division from the rover-to-target offset
 * (dx, dy) in cells: sh2c2 = s_h^2 c^2 times [dy^2, -dx dy; -dx dy, dx^2].
 * Returns the scalar sqrt(var_x + var_y). One function for trn_select and
 * the ground path, so both give the same bits. */
static double sel_heading_cov(const trn_peak_t *pk, double cell, double sh2c2, double dx, double dy,
                              double cov[3])
{
    cov[0] = pk->var_x * cell * cell + sh2c2 * (dy * dy);
    cov[1] = pk->var_y * cell * cell + sh2c2 * (dx * dx);
    cov[2] = pk->cov_xy * cell * cell - sh2c2 * (dx * dy);
    return sqrt(cov[0] + cov[1]);
}

/* Candidate c's covariance from its fit pk (cells^2), with the heading's
 * term when it is uncertain (q7: the heading-searched sums, or NULL). */
static void sel_finish(trn_candidate_t *c, const trn_peak_t *pk, const geom_t *g,
                       const trn_select_cfg_t *cfg, double sh2c2, const double *q7)
{
    c->informative = 1;
    if (q7 != NULL) {
        c->uncertainty_m = trn_sel_search_cov_(
            pk, c->ll, q7, g->cell, (double)cfg->sigma_heading_rad, (double)c->x - g->rxf,
            (double)c->y - g->ryf, c->cov_m2, &c->heading_m);
        c->sigma_x_m = sqrt(c->cov_m2[0]);
        c->sigma_y_m = sqrt(c->cov_m2[1]);
        c->rho = c->cov_m2[2] / (c->sigma_x_m * c->sigma_y_m);
    } else if (sh2c2 > 0.0) {
        c->uncertainty_m = sel_heading_cov(pk, g->cell, sh2c2, (double)c->x - g->rxf,
                                           (double)c->y - g->ryf, c->cov_m2);
        c->sigma_x_m = sqrt(c->cov_m2[0]);
        c->sigma_y_m = sqrt(c->cov_m2[1]);
        c->rho = c->cov_m2[2] / (c->sigma_x_m * c->sigma_y_m);
        c->heading_m = (double)cfg->sigma_heading_rad * (double)c->range_m;
    } else { /* the paper's prediction, bit for bit */
        c->sigma_x_m = pk->sigma_x * g->cell;
        c->sigma_y_m = pk->sigma_y * g->cell;
        c->rho = pk->rho;
        c->cov_m2[0] = pk->var_x * g->cell * g->cell;
        c->cov_m2[1] = pk->var_y * g->cell * g->cell;
        c->cov_m2[2] = pk->cov_xy * g->cell * g->cell;
        c->uncertainty_m = sqrt(c->sigma_x_m * c->sigma_x_m + c->sigma_y_m * c->sigma_y_m);
    }
}

static void sel_uninformative(trn_candidate_t *c)
{
    c->informative = 0;
    c->sigma_x_m = HUGE_VAL;
    c->sigma_y_m = HUGE_VAL;
    c->rho = 0.0;
    c->cov_m2[0] = HUGE_VAL;
    c->cov_m2[1] = HUGE_VAL;
    c->cov_m2[2] = 0.0;
    c->uncertainty_m = HUGE_VAL;
}

/* The voxel prediction of the nc candidates (select.h): eq. 9 over the
 * region, one summed-area table per pose offset, eq. 6 per candidate. */
static trn_status_t sel_voxel(const trn_map_t *map, const trn_kernels_t *k, const trn_vol_f32_t *pg,
                              const trn_select_cfg_t *cfg, const trn_rover_t *rover,
                              const geom_t *g, const trn_window_t *roi, trn_candidate_t *cands,
                              size_t nc, void *ws)
{
    trn_status_t st;
    trn_window_t pw;
    trn_vol_f32_t p;
    sel_layout_t lay;
    size_t i, lw, w1;
    int32_t d, lmax = 0;
    const int32_t side_w = roi->x1 - roi->x0 + 1, side_h = roi->y1 - roi->y0 + 1;
    double scale, sh2c2;

    /* exact int64 sums: |q lnp| summed over the region must fit */
    for (d = 0; d <= (int32_t)map->lnp.cap; ++d) {
        const int32_t a = map->lnp.lnp[d] < 0 ? -map->lnp.lnp[d] : map->lnp.lnp[d];
        lmax = a > lmax ? a : lmax;
    }
    if ((double)side_w * (double)side_h * (double)pg->nz * (double)SEL_QMAX * (double)lmax >
        9.0e18) {
        return TRN_E_SIZE;
    }

    /* eq. 9 over the region (this region's carve: within the largest one's) */
    lw = trn_prob_local_workspace_bytes(k, roi);
    (void)select_carve(
        side_w, side_h, pg->nz, lw,
        sel_moments(cfg) ? trn_select_max_candidates(cfg, map->cfg.terrain.cell_m) : 0u, ws, &lay);
    p.data = lay.p;
    p.nx = side_w;
    p.ny = side_h;
    p.nz = pg->nz;
    st = trn_prob_local(k, &cfg->local_sigma, map->cfg.terrain.cell_m, rover->pos, pg, roi, &p,
                        lay.lws, lw);
    if (st != TRN_OK) {
        return st;
    }
    w1 = (size_t)side_w + 1u;

    /* one summed-area table per pose offset, every window read from it */
    scale = 1.0 / ((double)TRN_SELECT_PROB_SCALE * (double)TRN_LNP_SCALE);
    if (lay.q7 != NULL) {
        memset(lay.q7, 0, nc * 7u * sizeof(double));
    }
    for (d = 0; d < 9; ++d) {
        build_sat(map, &p, roi, d % 3 - 1, d / 3 - 1, lay.sat, lay.crow, lay.rp1, lay.rp2);
        for (i = 0; i < nc; ++i) {
            patch_window(g, cands[i].x, cands[i].y, &pw);
            cands[i].ll[d] = (double)window_sum(lay.sat, w1, roi, &pw) * scale;
            if (lay.q7 != NULL) {
                trn_sel_moment_sums_(lay.sat, lay.rp1, lay.rp2, roi, &pw, d, scale,
                                     lay.q7 + 7u * i);
            }
        }
    }

    /* eq. 6 per candidate, plus the heading's lever arm when it is uncertain */
    sh2c2 = (double)cfg->sigma_heading_rad * (double)cfg->sigma_heading_rad * g->cell * g->cell;
    for (i = 0; i < nc; ++i) {
        trn_peak_t pk;
        if (trn_peak_fit(cands[i].ll, &pk) == TRN_OK) {
            sel_finish(&cands[i], &pk, g, cfg, sh2c2, lay.q7 != NULL ? lay.q7 + 7u * i : NULL);
        } else {
            sel_uninformative(&cands[i]);
        }
    }
    return TRN_OK;
}

/* The heading-searched marginal of the height prediction (select.h), with
 * the heights' b and c (sel_marginal). */
static void selh_search_cov(trn_candidate_t *c, const trn_peak_t *pk, const trn_selh_sums_t *s,
                            double sh, double cell)
{
    c->informative = 1;
    c->uncertainty_m = sel_marginal(pk, s->bx, s->by, s->cc, cell, sh, c->cov_m2, &c->heading_m);
    c->sigma_x_m = sqrt(c->cov_m2[0]);
    c->sigma_y_m = sqrt(c->cov_m2[1]);
    c->rho = c->cov_m2[2] / (c->sigma_x_m * c->sigma_y_m);
}

/* The height prediction of one candidate from its patch's sums (select.h). */
static void selh_candidate(const trn_select_cfg_t *cfg, const geom_t *g, const trn_selh_sums_t *s,
                           trn_candidate_t *c)
{
    const double det = s->axx * s->ayy - s->axy * s->axy;
    const double sh = (double)cfg->sigma_heading_rad;
    trn_peak_t pk;
    int32_t d;
    if (!(s->n >= 3.0) || !(s->axx > 0.0) || !(s->ayy > 0.0) || !(det > 1e-12 * s->raw * s->raw)) {
        sel_uninformative(c);
        return;
    }
    for (d = 0; d < 9; ++d) { /* the expected ln L at the nine offsets, about the centre */
        const int32_t ix = d % 3 - 1, iy = d / 3 - 1;
        const double lx = (double)ix, ly = (double)iy;
        c->ll[d] = -0.5 * (lx * lx * s->axx + 2.0 * lx * ly * s->axy + ly * ly * s->ayy);
    }
    memset(&pk, 0, sizeof pk);
    pk.var_x = s->ayy / det;
    pk.var_y = s->axx / det;
    pk.cov_xy = -s->axy / det;
    pk.sigma_x = sqrt(pk.var_x);
    pk.sigma_y = sqrt(pk.var_y);
    pk.rho = pk.cov_xy / (pk.sigma_x * pk.sigma_y);
    if (sel_moments(cfg)) {
        selh_search_cov(c, &pk, s, sh, g->cell);
    } else {
        sel_finish(c, &pk, g, cfg, sh * sh * g->cell * g->cell, NULL);
    }
}

/* The height prediction of the nc candidates: the tables over the region,
 * each candidate's sums from them. */
static trn_status_t sel_heights_all(const trn_map_t *map, const trn_select_cfg_t *cfg,
                                    const geom_t *g, const trn_window_t *roi,
                                    trn_candidate_t *cands, size_t nc, void *ws)
{
    const int heading = sel_moments(cfg);
    trn_selh_noise_t nm;
    trn_status_t st;
    size_t i;
    nm.rxf = g->rxf;
    nm.ryf = g->ryf;
    nm.cell = g->cell;
    nm.noise_m = (double)map->cfg.noise_m;
    nm.noise_k = (double)map->cfg.noise_k_per_m;
    nm.map_var = (double)cfg->map_sigma_m * (double)cfg->map_sigma_m;
    /* a binned local map: the mean of n points, and their centroid's jitter */
    nm.inv_n = cfg->points_per_cell > 0.0f ? 1.0 / (double)cfg->points_per_cell : 1.0;
    nm.jitter = cfg->points_per_cell > 0.0f ? nm.inv_n / 12.0 : 0.0;
    if ((st = trn_selh_build_(&map->heights, roi, heading, &nm, ws)) != TRN_OK) {
        return st;
    }
    for (i = 0; i < nc; ++i) {
        trn_window_t pw;
        trn_selh_sums_t s;
        patch_window(g, cands[i].x, cands[i].y, &pw);
        trn_selh_sums_(ws, roi, &pw, heading, &s);
        selh_candidate(cfg, g, &s, &cands[i]);
    }
    return TRN_OK;
}

/* Ranking: repeatedly the lowest uncertainty at least min_separation from
 * every target already ranked (ties: earlier in lattice order). Returns the
 * number ranked. */
static size_t sel_rank(const trn_candidate_t *cands, size_t nc, double sep_cells, size_t *ranked,
                       size_t ranked_cap)
{
    const double sep2_cells = sep_cells * sep_cells;
    size_t nr, i;
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
    return nr;
}

/* The voxel prediction's map: its distances valid, P_G of their size, the
 * cap in range (trn_select and the ground path). */
static trn_status_t sel_voxel_map_check(const trn_map_t *map, const trn_vol_f32_t *pg)
{
    trn_status_t st;
    if ((st = trn_vol_u8_check(&map->dist)) != TRN_OK) {
        return st;
    }
    if (pg->nx != map->dist.nx || pg->ny != map->dist.ny || pg->nz != map->dist.nz ||
        map->lnp.cap < 1u || map->lnp.cap > TRN_CHAMFER_CAP_MAX) {
        return TRN_E_SIZE;
    }
    return TRN_OK;
}

/* The arguments of trn_select that depend on the prediction: the voxel's
 * kernels, P_G and distances, or the heights. */
static trn_status_t sel_check_map(const trn_map_t *map, const trn_kernels_t *k,
                                  const trn_vol_f32_t *pg, int32_t *nx, int32_t *ny)
{
    trn_status_t st;
    if (sel_heights(map)) {
        if (map->heights.data == NULL) {
            return TRN_E_NULL;
        }
        if ((st = trn_grid_f32_check(&map->heights)) != TRN_OK) {
            return st;
        }
        *nx = map->heights.width;
        *ny = map->heights.height;
        return TRN_OK;
    }
    if (k == NULL || pg == NULL || pg->data == NULL || map->dist.data == NULL) {
        return TRN_E_NULL;
    }
    if ((st = sel_voxel_map_check(map, pg)) != TRN_OK) {
        return st;
    }
    *nx = map->dist.nx;
    *ny = map->dist.ny;
    return TRN_OK;
}

trn_status_t trn_select(const trn_map_t *map, const trn_kernels_t *k, const trn_vol_f32_t *pg,
                        const trn_select_cfg_t *cfg, const trn_rover_t *rover,
                        trn_candidate_t *cands, size_t capacity, size_t *ranked, size_t ranked_cap,
                        trn_select_result_t *res, void *ws, size_t ws_bytes)
{
    trn_status_t st;
    geom_t g;
    trn_window_t roi, pw;
    size_t need, nc = 0u, i, ninf = 0u;
    int32_t i_x, i_y, nx = 0, ny = 0;

    if (map == NULL || cfg == NULL || rover == NULL || cands == NULL || ranked == NULL ||
        res == NULL || ws == NULL) {
        return TRN_E_NULL;
    }
    if ((st = sel_check_map(map, k, pg, &nx, &ny)) != TRN_OK) {
        return st;
    }
    if ((st = trn_select_cfg_check(cfg, map->cfg.terrain.cell_m)) != TRN_OK) {
        return st;
    }
    if (!isfinite(rover->pos.x_cells) || !isfinite(rover->pos.y_cells) ||
        !isfinite(rover->heading_rad)) {
        return TRN_E_ARG;
    }
    if (rover->pos.x_cells < -0.5f || rover->pos.y_cells < -0.5f ||
        rover->pos.x_cells > (float)nx - 0.5f || rover->pos.y_cells > (float)ny - 0.5f) {
        return TRN_E_RANGE;
    }
    if (capacity == 0u || ranked_cap == 0u) {
        return TRN_E_CAPACITY;
    }
    need = trn_select_workspace_bytes(cfg, map, k);
    if ((st = trn_ws_check(ws, ws_bytes, need)) != TRN_OK) {
        return st;
    }

    g.nx = nx;
    g.ny = ny;
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

    /* 2. each candidate's prediction: the map's matcher */
    st = sel_heights(map) ? sel_heights_all(map, cfg, &g, &roi, cands, nc, ws)
                          : sel_voxel(map, k, pg, cfg, rover, &g, &roi, cands, nc, ws);
    if (st != TRN_OK) {
        return st;
    }
    for (i = 0; i < nc; ++i) {
        ninf += cands[i].informative != 0 ? 1u : 0u;
    }
    res->n_informative = ninf;
    if (ninf == 0u) {
        return TRN_E_NOTARGET;
    }

    /* 3. ranking */
    res->n_ranked = sel_rank(cands, nc, (double)cfg->min_separation_m / g.cell, ranked, ranked_cap);
    res->best = ranked[0];
    return TRN_OK;
}

/* ---- ground path: selection from prepared map data (select_pre.h) ------- */

/* Kernel of a cell at integer offset (ox, oy) from the rover: spread.c's
 * kernel_map expression (one sensing position), hence the same index. */
static uint8_t pre_kernel(const trn_kernels_t *k, const trn_sigma_model_t *m, float cell_m,
                          int32_t ox, int32_t oy)
{
    const double c2 = (double)cell_m * (double)cell_m;
    const double ex = (double)ox, ey = (double)oy;
    const double best = ex * ex + ey * ey;
    const double sig = ((double)m->sigma_min_m + (double)m->k_per_m * best * c2) / (double)cell_m;
    return (uint8_t)trn_kernel_pick(k, sig < 1e30 ? (float)sig : 1e30f);
}

/* The nearest and the farthest coordinate of [lo, hi] from 0. */
static int32_t pre_near(int32_t lo, int32_t hi) { return lo > 0 ? lo : (hi < 0 ? hi : 0); }

static int32_t pre_far(int32_t lo, int32_t hi) { return -lo > hi ? lo : hi; }

/* The kernels eq. 9 can bring to a cell at offset (ox, oy) from the rover
 * (trn_prob_local's passes: the x pass spreads a source along its row with
 * its own kernel, the y pass an intermediate cell along its column with its
 * own). A cell at Chebyshev distance d from the target reaches it only with
 * a radius >= d (the intermediate through its row offset, the source through
 * its column offset or through its intermediate's), and radii grow with the
 * range, so every cell that reaches lies within the distance D, the largest
 * d <= R_9 whose box's farthest cell has a radius >= d. The kernel index
 * grows with the range too (pre_kernel): the interval is [the kernel of the
 * box's nearest cell, that of its farthest]. */
static int32_t pre_interval(const trn_kernels_t *k, const trn_sigma_model_t *m, float cell_m,
                            int32_t ox, int32_t oy, uint8_t *ja, uint8_t *jb)
{
    int32_t d = k->radius[TRN_KERNEL_COUNT - 1];
    for (; d > 0; --d) {
        const uint8_t j = pre_kernel(k, m, cell_m, pre_far(ox - d, ox + d),
                                     pre_far(oy - d, oy + d));
        if (k->radius[j] >= d) {
            break;
        }
    }
    *ja = pre_kernel(k, m, cell_m, pre_near(ox - d, ox + d), pre_near(oy - d, oy + d));
    *jb = pre_kernel(k, m, cell_m, pre_far(ox - d, ox + d), pre_far(oy - d, oy + d));
    return d;
}

/* Can offset (ox, oy) be a cell of a candidate's patch? Its centre lies
 * within max_range of the rover and the cell within half a patch of it on
 * each axis (a conservative disc). */
static int pre_patch_offset(const trn_select_cfg_t *cfg, float cell_m, int32_t half, int32_t ox,
                            int32_t oy)
{
    const double r = (double)cfg->max_range_m / (double)cell_m + (double)half * 1.4142135623730951 +
                     1.0;
    return (double)ox * (double)ox + (double)oy * (double)oy <= r * r;
}

/* Which kernel intervals the patch cells' offsets use (used[a * 10 + b]);
 * returns how many. */
static int32_t pre_used_intervals(const trn_select_cfg_t *cfg, const trn_map_t *map,
                                  const trn_kernels_t *k, int32_t reach, int32_t half,
                                  uint8_t used[TRN_KERNEL_COUNT * TRN_KERNEL_COUNT])
{
    const float cell = map->cfg.terrain.cell_m;
    const int32_t e = reach + half;
    int32_t ox, oy, n = 0;
    memset(used, 0, (size_t)TRN_KERNEL_COUNT * (size_t)TRN_KERNEL_COUNT);
    for (oy = -e; oy <= e; ++oy) {
        for (ox = -e; ox <= e; ++ox) {
            uint8_t a, b;
            if (!pre_patch_offset(cfg, cell, half, ox, oy)) {
                continue;
            }
            (void)pre_interval(k, &cfg->local_sigma, cell, ox, oy, &a, &b);
            if (used[a * TRN_KERNEL_COUNT + b] == 0u) {
                used[a * TRN_KERNEL_COUNT + b] = 1u;
                ++n;
            }
        }
    }
    return n;
}

typedef struct {
    size_t joff, rowptr, src, lnpv, cxy, lat, nl, lok, latan;
    size_t ints, jid, jnext, dcone, bval, bscr, bsat, tc, tstamp, cdc, cstamp, pcol, lb2, heap;
    size_t epoch, total;
    int32_t half, n, m, side_w, side_h, src_h, nint;
    size_t ncap;
} pre_layout_t;

/* Slice sizes for nnz nonzero P_G voxels; 0 when the total does not fit. */
static int pre_layout(const trn_select_cfg_t *cfg, const trn_map_t *map, const trn_kernels_t *k,
                      size_t nnz, pre_layout_t *L)
{
    const float cell = map->cfg.terrain.cell_m;
    const int32_t nx = map->dist.nx, ny = map->dist.ny, nz = map->dist.nz;
    const int32_t r9 = k->radius[TRN_KERNEL_COUNT - 1];
    const int32_t reach = reach_cells(cfg, cell);
    uint8_t used[TRN_KERNEL_COUNT * TRN_KERNEL_COUNT];
    size_t plane, region, xcells;
    double mw, tot;
    L->half = patch_cells(cfg, cell) / 2;
    L->n = reach / cfg->stride_cells + 1;
    L->m = reach + L->half + r9 + 1;
    L->side_w = roi_side(cfg, cell, nx);
    L->side_h = roi_side(cfg, cell, ny);
    L->src_h = L->side_h + 2 * r9 < ny ? L->side_h + 2 * r9 : ny;
    L->ncap = trn_select_max_candidates(cfg, cell);
    L->nint = pre_used_intervals(cfg, map, k, reach, L->half, used);
    mw = 2.0 * (double)L->m + 1.0;
    /* the largest slice first, in double: no size_t overflow on 32-bit targets */
    tot = mw * mw * 8.0 + ((double)nz * (double)ny + 1.0) * (double)sizeof(size_t) +
          (double)nnz * (double)sizeof(trn_selpre_src_t) +
          (double)nx * (double)ny * ((double)nz * 4.0 + (double)L->nint * 4.0 + 40.0) +
          (double)L->src_h * (double)L->side_w * ((double)nz * 4.0 + 4.0) +
          ((double)L->side_w + 1.0) * ((double)L->side_h + 1.0) * 84.0 + (double)L->ncap * 41.0 +
          (double)nz * 4.0 + (double)L->side_h * 8.0 + 1.0e6;
    if (tot > (double)(SIZE_MAX / 2u)) {
        return 0;
    }
    plane = (size_t)nx * (size_t)ny;
    region = (size_t)L->side_w * (size_t)L->side_h;
    xcells = (size_t)L->src_h * (size_t)L->side_w;
    L->joff = TRN_ALIGN_UP((size_t)mw * (size_t)mw);
    L->rowptr = TRN_ALIGN_UP(((size_t)nz * (size_t)ny + 1u) * sizeof(size_t));
    L->src = TRN_ALIGN_UP(nnz * sizeof(trn_selpre_src_t));
    L->lnpv = TRN_ALIGN_UP(plane * (size_t)nz * sizeof(int32_t));
    L->cxy = TRN_ALIGN_UP(L->ncap * 2u * sizeof(int32_t));
    L->lat = TRN_ALIGN_UP((2u * (size_t)L->n + 1u) * 2u * sizeof(int32_t));
    L->nl = TRN_ALIGN_UP((size_t)L->side_h * 2u * sizeof(int32_t));
    L->lok = TRN_ALIGN_UP(L->ncap);
    L->latan = TRN_ALIGN_UP(L->ncap * sizeof(double));
    L->ints = TRN_ALIGN_UP((size_t)L->nint * sizeof(trn_selpre_int_t));
    L->jid = TRN_ALIGN_UP((size_t)mw * (size_t)mw);
    L->jnext = TRN_ALIGN_UP((size_t)mw * (size_t)mw * sizeof(int32_t));
    L->dcone = TRN_ALIGN_UP((size_t)mw * (size_t)mw * sizeof(uint16_t));
    L->bval = TRN_ALIGN_UP((size_t)L->nint * plane * sizeof(int32_t));
    L->bscr = TRN_ALIGN_UP((2u * (plane + (size_t)nx) + 4u * (size_t)TRN_KERNEL_MAX_RADIUS + 2u) *
                               sizeof(double) +
                           plane * sizeof(int64_t));
    L->bsat = TRN_ALIGN_UP(((size_t)L->side_w + 1u) * ((size_t)L->side_h + 1u) * sizeof(int64_t));
    L->tc = TRN_ALIGN_UP(xcells * (size_t)nz * sizeof(float));
    L->tstamp = TRN_ALIGN_UP(xcells * sizeof(uint32_t));
    L->cdc = TRN_ALIGN_UP(region * (size_t)PRE_CDN * sizeof(int64_t));
    L->cstamp = TRN_ALIGN_UP(region * sizeof(uint32_t));
    L->pcol = TRN_ALIGN_UP((size_t)nz * sizeof(float)) + TRN_ALIGN_UP(9u * sizeof(int64_t)) +
              TRN_ALIGN_UP(9u * sizeof(double));
    L->lb2 = TRN_ALIGN_UP(L->ncap * sizeof(double)) + TRN_ALIGN_UP(L->ncap * sizeof(int64_t)) +
             TRN_ALIGN_UP(L->ncap * sizeof(uint32_t));
    L->heap = TRN_ALIGN_UP(L->ncap * sizeof(uint32_t));
    L->epoch = TRN_ALIGN_UP(sizeof(uint32_t));
    L->total = L->joff + L->rowptr + L->src + L->lnpv + L->cxy + L->lat + L->nl + L->lok +
               L->latan + L->ints + L->jid + L->jnext + L->dcone + L->bval + L->bscr + L->bsat +
               L->tc + L->tstamp + L->cdc + L->cstamp + L->pcol + L->lb2 + L->heap + L->epoch;
    return 1;
}

static size_t pre_nnz(const trn_vol_f32_t *pg)
{
    const size_t nvox = (size_t)pg->nx * (size_t)pg->ny * (size_t)pg->nz;
    size_t i, nnz = 0u;
    for (i = 0; i < nvox; ++i) {
        if (pg->data[i] != 0.0f) {
            ++nnz;
        }
    }
    return nnz;
}

/* Arguments as trn_select checks them (no rover). */
static trn_status_t pre_check(const trn_select_cfg_t *cfg, const trn_map_t *map,
                              const trn_kernels_t *k, const trn_vol_f32_t *pg)
{
    trn_status_t st;
    if (map == NULL || k == NULL || pg == NULL || cfg == NULL || pg->data == NULL ||
        map->dist.data == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_select_cfg_check(cfg, map->cfg.terrain.cell_m)) != TRN_OK) {
        return st;
    }
    if (!(k->sigma0_cells >= 0.05f) || k->radius[TRN_KERNEL_COUNT - 1] < 1 ||
        k->radius[TRN_KERNEL_COUNT - 1] > TRN_KERNEL_MAX_RADIUS) {
        return TRN_E_ARG; /* not a built table (trn_prob_local's check) */
    }
    return sel_voxel_map_check(map, pg);
}

size_t trn_selpre_bytes(const trn_select_cfg_t *cfg, const trn_map_t *map, const trn_kernels_t *k,
                        const trn_vol_f32_t *pg)
{
    pre_layout_t L;
    if (pre_check(cfg, map, k, pg) != TRN_OK || !pre_layout(cfg, map, k, pre_nnz(pg), &L)) {
        return 0u;
    }
    return L.total;
}

/* The pruning's tables (select_pre.h), carved from b: the intervals, jid,
 * jnext and dcone over the offset table, the position caches, and per
 * interval [a, b] every cell's bound(x, y) = sum_z (A > 0 ? A qmax : A qmin),
 * where A = sum_d beta_d lnp(v + d) (beta: 4 at the centre, 1 on the edges,
 * -2 at the corners: 3 x eq. 6's trace coefficients, so that
 * 3 trace(-H) / scale = sum_v q A), and qmax, qmin bound the quantized eq. 9
 * of the voxel: P_G smoothed by the pointwise maximum (minimum) of the
 * interval's kernels along x then y, widened by 1e-4 (the float rounding of
 * trn_prob_local's at most 2 (2 R_9 + 1) positive terms is below 1e-5
 * relative) and by one unit of q for its rounding; stored as int32 in units
 * of 2^bshift, rounded up (so window sums stay upper bounds). Cells without
 * the 3 x 3 neighbourhood (the map's rim; never a patch cell) hold 0. */
static void pre_bounds_init(trn_selpre_t *s, const pre_layout_t *L, uint8_t *base)
{
    uint8_t *b = base;
    const trn_kernels_t *k = s->k;
    const trn_select_cfg_t *cfg = s->cfg;
    const float cell = s->map->cfg.terrain.cell_m;
    const int32_t nx = s->nx, ny = s->ny, nz = s->nz, mw = 2 * s->m + 1;
    const int32_t e = reach_cells(cfg, cell) + s->half;
    const size_t plane = (size_t)nx * (size_t)ny;
    const size_t lrow = (size_t)nx * (size_t)nz;
    uint8_t used[TRN_KERNEL_COUNT * TRN_KERNEL_COUNT], idx[TRN_KERNEL_COUNT * TRN_KERNEL_COUNT];
    trn_selpre_int_t *ints;
    uint8_t *jid;
    int32_t *jnext;
    uint16_t *dcone;
    int32_t *bval;
    int64_t *bt;
    double *tu, *td, *ru, *rd, *env;
    int32_t i, x, y, z, t, sh;

    ints = (trn_selpre_int_t *)(void *)b;
    b += L->ints;
    jid = b;
    b += L->jid;
    jnext = (int32_t *)(void *)b;
    b += L->jnext;
    dcone = (uint16_t *)(void *)b;
    b += L->dcone;
    bval = (int32_t *)(void *)b;
    b += L->bval;
    tu = (double *)(void *)b;
    td = tu + plane;
    ru = td + plane;
    rd = ru + nx;
    bt = (int64_t *)(void *)(rd + nx);
    env = (double *)(void *)(bt + plane);
    b += L->bscr;
    s->bsat = (int64_t *)(void *)b;
    b += L->bsat;
    s->tc = (float *)(void *)b;
    b += L->tc;
    s->tstamp = (uint32_t *)(void *)b;
    b += L->tstamp;
    s->cdc = (int64_t *)(void *)b;
    b += L->cdc;
    s->cstamp = (uint32_t *)(void *)b;
    b += L->cstamp;
    s->pcol = (float *)(void *)b;
    s->esum = (int64_t *)(void *)(b + TRN_ALIGN_UP((size_t)s->nz * sizeof(float)));
    s->ell = (double *)(void *)(b + TRN_ALIGN_UP((size_t)s->nz * sizeof(float)) +
                                TRN_ALIGN_UP(9u * sizeof(int64_t)));
    b += L->pcol;
    s->lb2 = (double *)(void *)b;
    s->tbu = (int64_t *)(void *)(b + TRN_ALIGN_UP(L->ncap * sizeof(double)));
    s->rst = (uint32_t *)(void *)(b + TRN_ALIGN_UP(L->ncap * sizeof(double)) +
                                  TRN_ALIGN_UP(L->ncap * sizeof(int64_t)));
    b += L->lb2;
    s->heap = (uint32_t *)(void *)b;
    b += L->heap;
    s->epoch = (uint32_t *)(void *)b;
    memset(s->tstamp, 0, (size_t)L->src_h * (size_t)L->side_w * sizeof(uint32_t));
    memset(s->cstamp, 0, (size_t)L->side_h * (size_t)L->side_w * sizeof(uint32_t));
    *s->epoch = 0u;

    /* |bound| of a cell <= nz 16 lmax QMAX: the shift that fits it in int32 (a
     * region's sum of int32 values then fits int64: <= TRN_MAX_DIM^2 2^31) */
    {
        const double amax = (double)nz * 16.0 * (double)s->lmax * (double)SEL_QMAX;
        sh = 0;
        s->bunit = 1.0;
        s->bunit_i = 1;
        while (amax / s->bunit + 1.0 > (double)INT32_MAX - 1.0) {
            ++sh;
            s->bunit *= 2.0;
            s->bunit_i *= 2;
        }
        s->bshift = sh;
        /* refinement by computed cells in int64: a patch's sums of cells'
         * excesses (each below 2^(32 + bshift)) and of its bound (int32
         * values times 2^bshift) stay below 2^62 */
        s->refine = (double)(2 * s->half + 1) * (double)(2 * s->half + 1) * s->bunit *
                        8589934592.0 <=
                    4.611686018427388e18;
    }
    /* each patch offset's interval, coded a * TRN_KERNEL_COUNT + b (< 100)
     * and then renumbered in the order of the codes; offsets that are no
     * patch cell's (pre_patch_offset is conservative, so no candidate's patch
     * reaches them) get interval 0: every lookup stays inside the tables */
    memset(used, 0, sizeof used);
    memset(jid, 0, (size_t)mw * (size_t)mw);
    memset(dcone, 0, (size_t)mw * (size_t)mw * sizeof *dcone);
    for (y = -e; y <= e; ++y) {
        for (x = -e; x <= e; ++x) {
            uint8_t a, bb;
            if (pre_patch_offset(cfg, cell, s->half, x, y)) {
                const size_t o = (size_t)(y + s->m) * (size_t)mw + (size_t)(x + s->m);
                dcone[o] = (uint16_t)pre_interval(k, &cfg->local_sigma, cell, x, y, &a, &bb);
                jid[o] = (uint8_t)(a * TRN_KERNEL_COUNT + bb);
                used[jid[o]] = 1u;
            }
        }
    }
    t = 0;
    for (i = 0; i < TRN_KERNEL_COUNT * TRN_KERNEL_COUNT; ++i) {
        idx[i] = 0u;
        if (used[i] != 0u) {
            ints[t].a = (uint8_t)(i / TRN_KERNEL_COUNT);
            ints[t].b = (uint8_t)(i % TRN_KERNEL_COUNT);
            idx[i] = (uint8_t)t;
            ++t;
        }
    }
    for (y = -e; y <= e; ++y) {
        for (x = -e; x <= e; ++x) {
            const size_t o = (size_t)(y + s->m) * (size_t)mw + (size_t)(x + s->m);
            jid[o] = idx[jid[o]];
        }
    }
    for (y = 0; y < mw; ++y) {
        const uint8_t *jr = jid + (size_t)y * (size_t)mw;
        int32_t *nr = jnext + (size_t)y * (size_t)mw;
        nr[mw - 1] = mw;
        for (x = mw - 2; x >= 0; --x) {
            nr[x] = jr[x + 1] != jr[x] ? x + 1 : nr[x + 1];
        }
    }

    /* per interval: the bound of every cell */
    for (t = 0; t < L->nint; ++t) {
        const int32_t ja = ints[t].a, jb = ints[t].b;
        const int32_t ru_r = k->radius[jb], rd_r = k->radius[ja];
        double *up = env, *dn = env + (2 * (size_t)TRN_KERNEL_MAX_RADIUS + 1u);
        int32_t *b32 = bval + (size_t)t * plane;
        size_t c;
        for (i = -ru_r; i <= ru_r; ++i) {
            double hi = 0.0, lo = HUGE_VAL;
            int32_t j;
            for (j = ja; j <= jb; ++j) {
                const double v = (i <= k->radius[j] && -i <= k->radius[j])
                                     ? (double)k->taps[j][TRN_KERNEL_MAX_RADIUS + i]
                                     : 0.0;
                hi = v > hi ? v : hi;
                lo = v < lo ? v : lo;
            }
            up[i + ru_r] = hi;
            dn[i + ru_r] = lo;
        }
        memset(bt, 0, plane * sizeof *bt);
        for (z = 0; z < nz; ++z) {
            memset(tu, 0, 2u * plane * sizeof *tu);
            for (y = 0; y < ny; ++y) { /* x pass from the nonzero sources */
                const size_t r0 = s->rowptr[(size_t)z * (size_t)ny + (size_t)y];
                const size_t r1 = s->rowptr[(size_t)z * (size_t)ny + (size_t)y + 1u];
                size_t q;
                for (q = r0; q < r1; ++q) {
                    const int32_t sx = s->src[q].x;
                    const double v = (double)s->src[q].v;
                    const int32_t lo = sx - ru_r > 0 ? sx - ru_r : 0;
                    const int32_t hi = sx + ru_r < nx - 1 ? sx + ru_r : nx - 1;
                    for (x = lo; x <= hi; ++x) {
                        tu[(size_t)y * (size_t)nx + (size_t)x] += up[x - sx + ru_r] * v;
                        td[(size_t)y * (size_t)nx + (size_t)x] += dn[x - sx + ru_r] * v;
                    }
                }
            }
            for (y = 1; y < ny - 1; ++y) { /* y pass, then the cells' bounds */
                int64_t *brow = bt + (size_t)y * (size_t)nx;
                memset(ru, 0, 2u * (size_t)nx * sizeof *ru);
                for (i = -ru_r; i <= ru_r; ++i) {
                    const int32_t sy = y - i;
                    const double cu = up[i + ru_r], cd = dn[i + ru_r];
                    const double *tur, *tdr;
                    if (sy < 0 || sy >= ny) {
                        continue;
                    }
                    tur = tu + (size_t)sy * (size_t)nx;
                    tdr = td + (size_t)sy * (size_t)nx;
                    for (x = 0; x < nx; ++x) {
                        ru[x] += cu * tur[x];
                    }
                    if (i <= rd_r && -i <= rd_r) { /* the minimum is 0 beyond R_a */
                        for (x = 0; x < nx; ++x) {
                            rd[x] += cd * tdr[x];
                        }
                    }
                }
                for (x = 1; x < nx - 1; ++x) {
                    const int32_t *l0, *l1, *l2;
                    double qd;
                    int64_t a, qb;
                    if (!(ru[x] > 0.0)) {
                        continue; /* every term 0: q is 0 */
                    }
                    l0 = s->lnpv + ((size_t)(y - 1) * (size_t)nx + (size_t)(x - 1)) * (size_t)nz +
                         (size_t)z;
                    l1 = l0 + lrow;
                    l2 = l1 + lrow;
                    a = 4 * (int64_t)l1[nz] + (int64_t)l0[nz] + (int64_t)l1[0] +
                        (int64_t)l1[2u * (size_t)nz] + (int64_t)l2[nz] -
                        2 * ((int64_t)l0[0] + (int64_t)l0[2u * (size_t)nz] + (int64_t)l2[0] +
                             (int64_t)l2[2u * (size_t)nz]);
                    if (a > 0) {
                        qd = ru[x] * (double)TRN_SELECT_PROB_SCALE * (1.0 + 1.0e-4);
                        qb = qd >= (double)SEL_QMAX ? (int64_t)SEL_QMAX : (int64_t)qd + 1;
                        qb = qb < (int64_t)SEL_QMAX ? qb : (int64_t)SEL_QMAX;
                    } else {
                        qd = rd[x] * (double)TRN_SELECT_PROB_SCALE * (1.0 - 1.0e-4) - 1.0;
                        qb = qd > 0.0 ? (int64_t)ceil(qd) : 0;
                        qb = qb < (int64_t)SEL_QMAX ? qb : (int64_t)SEL_QMAX;
                    }
                    brow[x] += a * qb;
                }
            }
        }
        /* int32 in units of 2^bshift, rounded up: the window sums stay upper bounds */
        for (c = 0; c < plane; ++c) {
            const int64_t v = bt[c];
            b32[c] = (int32_t)(v >= 0 ? (v + s->bunit_i - 1) / s->bunit_i : -((-v) / s->bunit_i));
        }
    }
    s->ints = ints;
    s->jid = jid;
    s->jnext = jnext;
    s->dcone = dcone;
    s->bval = bval;
    s->rcone = 0;
    for (t = 0; t < L->nint; ++t) {
        s->rcone = k->radius[ints[t].b] > s->rcone ? k->radius[ints[t].b] : s->rcone;
    }
    s->nint = L->nint;
}

trn_status_t trn_selpre_init(trn_selpre_t *s, const trn_map_t *map, const trn_kernels_t *k,
                             const trn_vol_f32_t *pg, const trn_select_cfg_t *cfg, void *mem,
                             size_t bytes)
{
    pre_layout_t L;
    trn_status_t st;
    uint8_t *b = (uint8_t *)mem;
    uint8_t *joff;
    size_t *rowptr, nnz, i;
    trn_selpre_src_t *src;
    int32_t *lnpv;
    uint8_t *lok;
    double *latan;
    int32_t x, y, z, d, mw;
    const uint8_t cap = map != NULL ? map->lnp.cap : 0u;

    if (s == NULL || mem == NULL) {
        return TRN_E_NULL;
    }
    if ((st = pre_check(cfg, map, k, pg)) != TRN_OK) {
        return st;
    }
    nnz = pre_nnz(pg);
    if (!pre_layout(cfg, map, k, nnz, &L)) {
        return TRN_E_WORKSPACE;
    }
    if ((st = trn_ws_check(mem, bytes, L.total)) != TRN_OK) {
        return st;
    }
    memset(s, 0, sizeof *s);
    s->map = map;
    s->k = k;
    s->cfg = cfg;
    s->nx = map->dist.nx;
    s->ny = map->dist.ny;
    s->nz = map->dist.nz;
    s->half = L.half;
    s->n = L.n;
    s->m = L.m;
    s->side_w = L.side_w;
    s->side_h = L.side_h;
    s->src_h = L.src_h;
    s->ncap = L.ncap;
    joff = b;
    b += L.joff;
    rowptr = (size_t *)(void *)b;
    b += L.rowptr;
    src = (trn_selpre_src_t *)(void *)b;
    b += L.src;
    lnpv = (int32_t *)(void *)b;
    b += L.lnpv;
    s->cxy = (int32_t *)(void *)b;
    b += L.cxy;
    s->latlo = (int32_t *)(void *)b;
    s->lathi = s->latlo + (2 * L.n + 1);
    b += L.lat;
    s->nlo = (int32_t *)(void *)b;
    s->nhi = s->nlo + L.side_h;
    b += L.nl;
    lok = b;
    b += L.lok;
    latan = (double *)(void *)b;
    b += L.latan;

    /* kernel index by offset, and the largest radius any offset uses */
    mw = 2 * L.m + 1;
    s->rmax = 0;
    for (y = 0; y < mw; ++y) {
        for (x = 0; x < mw; ++x) {
            const uint8_t j = pre_kernel(k, &cfg->local_sigma, map->cfg.terrain.cell_m, x - L.m,
                                         y - L.m);
            joff[(size_t)y * (size_t)mw + (size_t)x] = j;
            s->rmax = k->radius[j] > s->rmax ? k->radius[j] : s->rmax;
        }
    }
    /* nonzero P_G by (z, y) row, ascending x */
    i = 0u;
    for (z = 0; z < s->nz; ++z) {
        for (y = 0; y < s->ny; ++y) {
            const float *row = pg->data + ((size_t)z * (size_t)s->ny + (size_t)y) * (size_t)s->nx;
            rowptr[(size_t)z * (size_t)s->ny + (size_t)y] = i;
            for (x = 0; x < s->nx; ++x) {
                if (row[x] != 0.0f) {
                    src[i].x = x;
                    src[i].v = row[x];
                    ++i;
                }
            }
        }
    }
    rowptr[(size_t)s->nz * (size_t)s->ny] = i;
    /* ln p of the capped distance, z innermost */
    for (z = 0; z < s->nz; ++z) {
        for (y = 0; y < s->ny; ++y) {
            const uint8_t *drow = map->dist.data + TRN_VOL_IDX(&map->dist, 0, y, z);
            for (x = 0; x < s->nx; ++x) {
                const uint8_t dv = drow[x] < cap ? drow[x] : cap;
                lnpv[((size_t)y * (size_t)s->nx + (size_t)x) * (size_t)s->nz + (size_t)z] =
                    map->lnp.lnp[dv];
            }
        }
    }
    s->lmax = 0;
    for (d = 0; d <= (int32_t)cap; ++d) {
        const int32_t a = map->lnp.lnp[d] < 0 ? -map->lnp.lnp[d] : map->lnp.lnp[d];
        s->lmax = a > s->lmax ? a : s->lmax;
    }
    /* candidate rules that depend on the lattice offset only (trn_select's
     * candidate_ok expressions; the rover is on a whole cell) */
    {
        const double cellm = (double)map->cfg.terrain.cell_m;
        const double hx = (double)L.half + 0.5;
        const int32_t nl = 2 * L.n + 1;
        for (y = 0; y < nl; ++y) {
            for (x = 0; x < nl; ++x) {
                const double dx = (double)((x - L.n) * cfg->stride_cells);
                const double dy = (double)((y - L.n) * cfg->stride_cells);
                const double r = sqrt(dx * dx + dy * dy) * cellm;
                double ex = fabs(dx) - hx, ey = fabs(dy) - hx;
                const size_t i2 = (size_t)y * (size_t)nl + (size_t)x;
                ex = ex > 0.0 ? ex : 0.0;
                ey = ey > 0.0 ? ey : 0.0;
                lok[i2] = (uint8_t)(r >= (double)cfg->min_range_m &&
                                    r <= (double)cfg->max_range_m &&
                                    sqrt(ex * ex + ey * ey) * cellm >=
                                        (double)cfg->footprint_radius_m);
                latan[i2] = atan2(dy, dx);
            }
        }
        /* remainder(., 2 pi) lies in [-pi, pi] (double), inside the float
         * limits (float)-pi .. (float)pi: the whole circle passes every bearing */
        s->full_pan = cfg->pan_min_rad <= (float)-SEL_PI && cfg->pan_max_rad >= (float)SEL_PI;
    }
    s->lok = lok;
    s->latan = latan;
    s->joff = joff;
    s->rowptr = rowptr;
    s->src = src;
    s->lnpv = lnpv;
    pre_bounds_init(s, &L, b);
    return TRN_OK;
}

/* One position of the pruned path: the rover cell, the region and its epoch. */
typedef struct {
    int32_t rx, ry, x0, y0, sy0, w, nb; /* nb: x-pass blocks per row */
    uint32_t ep;
    uint32_t ncd; /* cells whose C_d this position has computed */
} pre_pos_t;

/* Columns per x-pass block (the cache's unit). */
#define PRE_TBLOCK 16

/* The x pass of trn_prob_local at cell (x, sy), every bin (s->tc, cached by
 * blocks of PRE_TBLOCK region columns): the sources of row sy in rising x,
 * each adding v * tap to the columns within its own kernel's radius, as
 * trn_prob_local's x pass does (spread.c's axpy: y += a x with a the source
 * value), so the same floats. */
static const float *pre_tcol(const trn_selpre_t *s, const pre_pos_t *pp, int32_t x, int32_t sy)
{
    const size_t nz = (size_t)s->nz;
    const size_t row = (size_t)(sy - pp->sy0);
    const int32_t bx = (x - pp->x0) / PRE_TBLOCK;
    const size_t st = row * (size_t)pp->nb + (size_t)bx;
    float *tr = s->tc + row * (size_t)pp->w * nz;
    if (s->tstamp[st] != pp->ep) {
        const trn_kernels_t *k = s->k;
        const size_t jb = (size_t)(sy - pp->ry + s->m) * (2u * (size_t)s->m + 1u);
        const int32_t xa = pp->x0 + bx * PRE_TBLOCK;
        const int32_t xb = xa + PRE_TBLOCK - 1 < pp->x0 + pp->w - 1 ? xa + PRE_TBLOCK - 1
                                                                    : pp->x0 + pp->w - 1;
        size_t z;
        s->tstamp[st] = pp->ep;
        memset(tr + (size_t)(xa - pp->x0) * nz, 0, (size_t)(xb - xa + 1) * nz * sizeof *tr);
        for (z = 0; z < nz; ++z) {
            const trn_selpre_src_t *e = s->src + s->rowptr[z * (size_t)s->ny + (size_t)sy];
            const trn_selpre_src_t *end = s->src + s->rowptr[z * (size_t)s->ny + (size_t)sy + 1u];
            size_t lo_i = 0u, hi_i = (size_t)(end - e);
            while (lo_i < hi_i) { /* first source at x >= xa - rcone */
                const size_t mid = lo_i + (hi_i - lo_i) / 2u;
                if (e[mid].x < xa - s->rcone) {
                    lo_i = mid + 1u;
                } else {
                    hi_i = mid;
                }
            }
            for (e += lo_i; e < end && e->x <= xb + s->rcone; ++e) {
                const int32_t j = (int32_t)s->joff[jb + (size_t)(e->x - pp->rx + s->m)];
                const int32_t rr = k->radius[j];
                const int32_t lo = e->x - rr > xa ? e->x - rr : xa;
                const int32_t hi = e->x + rr < xb ? e->x + rr : xb;
                const float *tap = k->taps[j] + TRN_KERNEL_MAX_RADIUS - e->x;
                int32_t c;
                for (c = lo; c <= hi; ++c) {
                    tr[(size_t)(c - pp->x0) * nz + z] += e->v * tap[c];
                }
            }
        }
    }
    return tr + (size_t)(x - pp->x0) * nz;
}

/* The nine C_d of region cell (x, y) (s->cdc, cached): eq. 9 of each bin by
 * trn_prob_local's y pass (the intermediate cells of column x within the
 * cell's cone distance, in rising row, each adding tap * T as trn_prob_local's
 * y pass does),
 * quantized as trn_select does, times ln p at the nine pose offsets (the
 * cell's 3 x 3 neighbours are on the map: it is a patch cell). */
static const int64_t *pre_cd(const trn_selpre_t *s, pre_pos_t *pp, int32_t x, int32_t y)
{
    const size_t c = (size_t)(y - pp->y0) * (size_t)pp->w + (size_t)(x - pp->x0);
    int64_t *cd = s->cdc + c * PRE_CDN;
    const trn_kernels_t *k = s->k;
    const size_t mw = 2u * (size_t)s->m + 1u, nz = (size_t)s->nz;
    const size_t lrow = (size_t)s->nx * nz;
    const int32_t jcol = x - pp->rx + s->m; /* the cell's offset-table column */
    const size_t jc = (size_t)jcol;
    const int32_t dc = (int32_t)s->dcone[(size_t)(y - pp->ry + s->m) * mw + jc];
    const int32_t sa = y - dc > 0 ? y - dc : 0;
    const int32_t sb = y + dc < s->ny - 1 ? y + dc : s->ny - 1;
    float *p = s->pcol;
    int32_t sy, d;
    size_t z;
    if (s->cstamp[c] == pp->ep) {
        return cd;
    }
    s->cstamp[c] = pp->ep;
    pp->ncd += (uint32_t)s->refine; /* stays 0 (no refinement) when the sums could overflow */
    memset(p, 0, nz * sizeof *p);
    for (sy = sa; sy <= sb; ++sy) {
        const int32_t j = (int32_t)s->joff[(size_t)(sy - pp->ry + s->m) * mw + jc];
        const int32_t dy = y - sy;
        const float *t;
        float tap;
        if (dy > k->radius[j] || -dy > k->radius[j]) {
            continue;
        }
        tap = k->taps[j][TRN_KERNEL_MAX_RADIUS + dy];
        t = pre_tcol(s, pp, x, sy);
        for (z = 0; z < nz; ++z) {
            p[z] += tap * t[z];
        }
    }
    for (d = 0; d < 9; ++d) {
        cd[d] = 0;
    }
    for (z = 0; z < nz; ++z) {
        const float v = p[z];
        const int32_t *l0, *l1, *l2;
        int64_t q;
        if (!(v > 0.0f)) {
            continue;
        }
        q = v >= 4.0f ? (int64_t)SEL_QMAX
                      : (int64_t)(int32_t)(v * (float)TRN_SELECT_PROB_SCALE + 0.5f);
        l0 = s->lnpv + ((size_t)(y - 1) * (size_t)s->nx + (size_t)(x - 1)) * nz + z;
        l1 = l0 + lrow;
        l2 = l1 + lrow;
        cd[0] += q * l0[0];
        cd[1] += q * l0[nz];
        cd[2] += q * l0[2u * nz];
        cd[3] += q * l1[0];
        cd[4] += q * l1[nz];
        cd[5] += q * l1[2u * nz];
        cd[6] += q * l2[0];
        cd[7] += q * l2[nz];
        cd[8] += q * l2[2u * nz];
    }
    /* the cell's bound less its exact sum_z q A (>= 0), for pre_refined */
    {
        const uint8_t t = s->jid[(size_t)(y - pp->ry + s->m) * mw + jc];
        const int64_t ex = 4 * cd[4] + cd[1] + cd[3] + cd[5] + cd[7] -
                           2 * (cd[0] + cd[2] + cd[6] + cd[8]);
        cd[9] = (int64_t)s->bval[(size_t)t * (size_t)s->nx * (size_t)s->ny +
                                 (size_t)y * (size_t)s->nx + (size_t)x] *
                    s->bunit_i -
                ex;
    }
    return cd;
}

/* This position's summed-area table of the cells' bounds over the region:
 * each patch cell's value from its interval's table (runs of one interval
 * along a row by jnext), 0 elsewhere. */
static void pre_bound_sat(const trn_selpre_t *s, const pre_pos_t *pp, int32_t h)
{
    const size_t mw = 2u * (size_t)s->m + 1u, w1 = (size_t)pp->w + 1u;
    const size_t plane = (size_t)s->nx * (size_t)s->ny;
    const int32_t off = s->m - pp->rx; /* table column of map column x: x + off */
    int64_t *sat = s->bsat;
    int32_t r, x;
    memset(sat, 0, w1 * sizeof *sat);
    for (r = 0; r < h; ++r) {
        const int32_t y = pp->y0 + r;
        const size_t rb = (size_t)(y - pp->ry + s->m) * mw;
        const int64_t *up = sat + (size_t)r * w1;
        int64_t *cur = sat + (size_t)(r + 1) * w1;
        int64_t run = 0;
        int32_t c = 0;
        cur[0] = 0;
        x = s->nlo[r] <= s->nhi[r] ? s->nlo[r] : pp->w;
        for (; c < x; ++c) {
            cur[c + 1] = up[c + 1];
        }
        while (x <= s->nhi[r]) {
            const size_t o = rb + (size_t)(pp->x0 + x + off);
            const uint8_t t = s->jid[o];
            const int32_t *bv;
            int32_t e;
            e = s->jnext[o] - off - pp->x0 - 1;
            e = e < s->nhi[r] ? e : s->nhi[r];
            bv = s->bval + (size_t)t * plane + (size_t)y * (size_t)s->nx + (size_t)pp->x0;
            for (; x <= e; ++x) {
                run += (int64_t)bv[x];
                cur[x + 1] = up[x + 1] + run;
            }
        }
        for (c = x; c < pp->w; ++c) {
            cur[c + 1] = up[c + 1] + run;
        }
    }
}

/* Binary min-heap of candidate indices by s->lb2. */
static void pre_sift(const trn_selpre_t *s, size_t n, size_t i0)
{
    uint32_t *h = s->heap;
    size_t i = i0;
    for (;;) {
        const size_t l = 2u * i + 1u, r = l + 1u;
        size_t m = i;
        uint32_t t;
        if (l < n && s->lb2[h[l]] < s->lb2[h[m]]) {
            m = l;
        }
        if (r < n && s->lb2[h[r]] < s->lb2[h[m]]) {
            m = r;
        }
        if (m == i) {
            return;
        }
        t = h[i];
        h[i] = h[m];
        h[m] = t;
        i = m;
    }
}

/* Candidate ci's bound refined by the cells this position has computed:
 * their exact sum_z q A replaces their bound (pre_cd's excess subtracted).
 * Returns the refined sum (units of 1; the int64 sums fit when s->refine,
 * the only case that calls it). */
static int64_t pre_refined(const trn_selpre_t *s, const pre_pos_t *pp, int32_t half, size_t ci)
{
    const int32_t cx = s->cxy[2u * ci], cy = s->cxy[2u * ci + 1u];
    int64_t ex = 0;
    int32_t x, y;
    for (y = cy - half; y <= cy + half; ++y) {
        const size_t r = (size_t)(y - pp->y0) * (size_t)pp->w;
        for (x = cx - half; x <= cx + half; ++x) {
            const size_t c = r + (size_t)(x - pp->x0);
            if (s->cstamp[c] == pp->ep) {
                ex += s->cdc[c * PRE_CDN + 9u];
            }
        }
    }
    return s->tbu[ci] * s->bunit_i - ex;
}

/* Insert candidate c into the heap of n. */
static void pre_push(const trn_selpre_t *s, size_t n, uint32_t c)
{
    uint32_t *h = s->heap;
    size_t i = n;
    h[i] = c;
    while (i > 0u) {
        const size_t up = (i - 1u) / 2u;
        if (!(s->lb2[h[i]] < s->lb2[h[up]])) {
            break;
        }
        h[i] = h[up];
        h[up] = c;
        i = up;
    }
}

/* Candidate ci exactly: its nine window sums from the cells' C_d (the
 * values trn_select's tables give), then the fit (its value against the
 * best: the minimum is trn_select's). */
static void pre_exact(const trn_selpre_t *s, pre_pos_t *pp, const geom_t *g, size_t ci,
                      double *best, int *found)
{
    const double sh2c2 = (double)s->cfg->sigma_heading_rad * (double)s->cfg->sigma_heading_rad *
                         g->cell * g->cell;
    const double scale = 1.0 / ((double)TRN_SELECT_PROB_SCALE * (double)TRN_LNP_SCALE);
    const int32_t cx = s->cxy[2u * ci], cy = s->cxy[2u * ci + 1u];
    const double ox = (double)cx - g->rxf, oy = (double)cy - g->ryf;
    int64_t *sum = s->esum; /* 9 sums and the 9 ll in the workspace: the deepest stack path */
    double *ll = s->ell, cov[3];
    trn_peak_t pk;
    int32_t x, y, d;
    for (d = 0; d < 9; ++d) {
        sum[d] = 0;
    }
    for (y = cy - g->half; y <= cy + g->half; ++y) {
        for (x = cx - g->half; x <= cx + g->half; ++x) {
            const int64_t *cd = pre_cd(s, pp, x, y);
            for (d = 0; d < 9; ++d) {
                sum[d] += cd[d];
            }
        }
    }
    for (d = 0; d < 9; ++d) {
        ll[d] = (double)sum[d] * scale;
    }
    if (trn_peak_fit(ll, &pk) == TRN_OK) {
        const double sx = pk.sigma_x * g->cell, sy = pk.sigma_y * g->cell;
        const double u = sh2c2 > 0.0 ? sel_heading_cov(&pk, g->cell, sh2c2, ox, oy, cov)
                                     : sqrt(sx * sx + sy * sy);
        if (!*found || u < *best) {
            *best = u;
            *found = 1;
        }
    }
}

/* The pruned path (select_pre.h) after trn_selpre_best's candidates and
 * region: every candidate's bound, then exact evaluations in rising bound
 * while the bound can beat the best. The bound: sigma_x^2 + sigma_y^2 =
 * trace(-H^-1) = 1/l1 + 1/l2 >= 4 / (l1 + l2) = 4 / trace(-H) for the
 * eigenvalues l1, l2 > 0 of -H (harmonic <= arithmetic mean; the fit fails
 * unless -H is positive definite), plus the heading's term s_h^2 r^2 when it
 * is uncertain (sel_heading_cov: the trace of s_h^2 r^2 t t^T), with an
 * upper bound on trace(-H); a candidate is passed over only when its bound
 * times (1 - 1e-6) exceeds the best found, a margin far beyond the rounding
 * of either computation, so it is never the lowest or a tie. */
static void pre_pruned(const trn_selpre_t *s, const trn_window_t *roi, const geom_t *g, size_t nc,
                       double *best, int *found)
{
    const double sh2c2 = (double)s->cfg->sigma_heading_rad * (double)s->cfg->sigma_heading_rad *
                         g->cell * g->cell;
    const double scale = 1.0 / ((double)TRN_SELECT_PROB_SCALE * (double)TRN_LNP_SCALE);
    pre_pos_t pp;
    size_t i, nh = 0u, first = 0u;
    pp.rx = g->rx;
    pp.ry = g->ry;
    pp.x0 = roi->x0;
    pp.y0 = roi->y0;
    pp.sy0 = roi->y0 - s->rcone > 0 ? roi->y0 - s->rcone : 0;
    pp.w = roi->x1 - roi->x0 + 1;
    pp.nb = (pp.w + PRE_TBLOCK - 1) / PRE_TBLOCK;
    pp.ncd = 0u;
    if (*s->epoch == UINT32_MAX) { /* about to wrap: every stamp is made old again */
        memset(s->tstamp, 0, (size_t)s->src_h * (size_t)s->side_w * sizeof(uint32_t));
        memset(s->cstamp, 0, (size_t)s->side_h * (size_t)s->side_w * sizeof(uint32_t));
        *s->epoch = 0u;
    }
    *s->epoch += 1u;
    pp.ep = *s->epoch;
    pre_bound_sat(s, &pp, roi->y1 - roi->y0 + 1);
    for (i = 0; i < nc; ++i) {
        const int32_t cx = s->cxy[2u * i], cy = s->cxy[2u * i + 1u];
        const double ox = (double)cx - g->rxf, oy = (double)cy - g->ryf;
        const size_t w1 = (size_t)pp.w + 1u;
        const size_t x0 = (size_t)(cx - g->half - pp.x0), x1 = (size_t)(cx + g->half - pp.x0) + 1u;
        const size_t y0 = (size_t)(cy - g->half - pp.y0), y1 = (size_t)(cy + g->half - pp.y0) + 1u;
        const int64_t tb = s->bsat[y1 * w1 + x1] - s->bsat[y0 * w1 + x1] - s->bsat[y1 * w1 + x0] +
                           s->bsat[y0 * w1 + x0];
        if (tb <= 0) {
            continue; /* trace(-H) <= 0: the fit fails (never informative) */
        }
        s->tbu[i] = tb;
        s->rst[i] = 0u;
        s->lb2[i] = 12.0 / ((double)tb * s->bunit * scale) * g->cell * g->cell +
                    sh2c2 * (ox * ox + oy * oy);
        if (nh == 0u || s->lb2[i] < s->lb2[first]) {
            first = i;
        }
        s->heap[nh++] = (uint32_t)i;
    }
    /* the lowest bound first; once it gave a best, only the candidates whose
     * bound can beat that best enter the heap */
    if (nh > 0u) {
        const size_t n0 = nh;
        pre_exact(s, &pp, g, first, best, found);
        if (*found) {
            size_t m = 0u;
            for (i = 0; i < n0; ++i) {
                const uint32_t c = s->heap[i];
                if ((size_t)c != first && !(s->lb2[c] * (1.0 - 1.0e-6) > *best * *best)) {
                    s->heap[m++] = c;
                }
            }
            nh = m;
        } else { /* no best yet: the others, the first taken out */
            for (i = 0; i < n0; ++i) {
                if ((size_t)s->heap[i] == first) {
                    s->heap[i] = s->heap[n0 - 1u];
                    break;
                }
            }
            nh = n0 - 1u;
        }
    }
    for (i = nh / 2u; i-- > 0u;) {
        pre_sift(s, nh, i);
    }
    while (nh > 0u) {
        const size_t ci = s->heap[0];
        if (*found && s->lb2[ci] * (1.0 - 1.0e-6) > *best * *best) {
            break; /* no candidate left can beat the best */
        }
        s->heap[0] = s->heap[--nh];
        pre_sift(s, nh, 0u);
        if (s->rst[ci] != pp.ncd) { /* cells computed since its bound (never without
                                       s->refine: ncd stays 0): refine it */
            const int64_t tr = pre_refined(s, &pp, g->half, ci);
            const double ox = (double)s->cxy[2u * ci] - g->rxf;
            const double oy = (double)s->cxy[2u * ci + 1u] - g->ryf;
            s->rst[ci] = pp.ncd;
            if (tr <= 0) {
                continue; /* trace(-H) <= 0: never informative */
            }
            s->lb2[ci] = 12.0 / ((double)tr * scale) * g->cell * g->cell +
                         sh2c2 * (ox * ox + oy * oy);
            if (*found && s->lb2[ci] * (1.0 - 1.0e-6) > *best * *best) {
                continue;
            }
            if (nh > 0u && s->lb2[ci] > s->lb2[s->heap[0]]) {
                pre_push(s, nh++, (uint32_t)ci); /* another bound is lower now */
                continue;
            }
        }
        pre_exact(s, &pp, g, ci, best, found);
    }
}

trn_status_t trn_selpre_best(const trn_selpre_t *s, int32_t rx, int32_t ry, float heading_rad,
                             double *best_m)
{
    geom_t g;
    trn_window_t roi, pw;
    size_t nc = 0u;
    int32_t i_x, i_y, r, side_w, side_h;
    double best = HUGE_VAL;
    int found = 0;
    const trn_select_cfg_t *cfg = s->cfg;

    g.nx = s->nx;
    g.ny = s->ny;
    g.half = s->half;
    g.rxf = (double)(float)rx;
    g.ryf = (double)(float)ry;
    g.rx = rx;
    g.ry = ry;
    g.cell = (double)s->map->cfg.terrain.cell_m;
    g.heading = (double)heading_rad;
    g.n = s->n;

    /* 1. candidates (trn_select's lattice and rules), region, patch columns */
    roi.x0 = g.nx;
    roi.y0 = g.ny;
    roi.x1 = -1;
    roi.y1 = -1;
    for (i_y = -g.n; i_y <= g.n; ++i_y) {
        int32_t *lo = &s->latlo[i_y + g.n], *hi = &s->lathi[i_y + g.n];
        *lo = g.nx;
        *hi = -1;
        for (i_x = -g.n; i_x <= g.n; ++i_x) {
            const int32_t cx = g.rx + i_x * cfg->stride_cells, cy = g.ry + i_y * cfg->stride_cells;
            const size_t oi = (size_t)(i_y + g.n) * (2u * (size_t)g.n + 1u) + (size_t)(i_x + g.n);
            /* candidate_ok: the map edge, then the offset's rules, then the bearing */
            if (cx - g.half - 1 < 0 || cy - g.half - 1 < 0 || cx + g.half + 1 > g.nx - 1 ||
                cy + g.half + 1 > g.ny - 1 || s->lok[oi] == 0u) {
                continue;
            }
            if (!s->full_pan) {
                const double b = remainder(s->latan[oi] - g.heading, 2.0 * SEL_PI);
                if (b < (double)cfg->pan_min_rad || b > (double)cfg->pan_max_rad) {
                    continue;
                }
            }
            s->cxy[2u * nc] = cx;
            s->cxy[2u * nc + 1u] = cy;
            patch_window(&g, cx, cy, &pw);
            roi.x0 = pw.x0 < roi.x0 ? pw.x0 : roi.x0;
            roi.y0 = pw.y0 < roi.y0 ? pw.y0 : roi.y0;
            roi.x1 = pw.x1 > roi.x1 ? pw.x1 : roi.x1;
            roi.y1 = pw.y1 > roi.y1 ? pw.y1 : roi.y1;
            *lo = cx < *lo ? cx : *lo;
            *hi = cx > *hi ? cx : *hi;
            ++nc;
        }
    }
    if (nc == 0u) {
        return TRN_E_NOTARGET;
    }
    side_w = roi.x1 - roi.x0 + 1;
    side_h = roi.y1 - roi.y0 + 1;
    if ((double)side_w * (double)side_h * (double)s->nz * (double)SEL_QMAX * (double)s->lmax >
        9.0e18) {
        return TRN_E_SIZE;
    }
    for (r = 0; r < side_h; ++r) {
        s->nlo[r] = side_w;
        s->nhi[r] = -1;
    }
    for (i_y = 0; i_y <= 2 * g.n; ++i_y) {
        const int32_t cy = g.ry + (i_y - g.n) * cfg->stride_cells;
        int32_t y;
        if (s->lathi[i_y] < 0) {
            continue;
        }
        for (y = cy - g.half; y <= cy + g.half; ++y) {
            const int32_t rr = y - roi.y0;
            const int32_t a = s->latlo[i_y] - g.half - roi.x0, b = s->lathi[i_y] + g.half - roi.x0;
            s->nlo[rr] = a < s->nlo[rr] ? a : s->nlo[rr];
            s->nhi[rr] = b > s->nhi[rr] ? b : s->nhi[rr];
        }
    }

    /* 2. bounds, then exact evaluations in rising bound */
    pre_pruned(s, &roi, &g, nc, &best, &found);
    if (!found) {
        return TRN_E_NOTARGET;
    }
    *best_m = best;
    return TRN_OK;
}
