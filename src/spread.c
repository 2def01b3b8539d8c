/* SPDX-License-Identifier: Apache-2.0 */
/* spread.c - eqs. 8 and 9, separable position-variant scatter (see trn/spread.h). */
#include "trn/spread.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "ws.h"

void trn_sigma_global_default(trn_sigma_model_t *m)
{
    if (m != NULL) {
        m->sigma_min_m = 0.02f;
        m->k_per_m = 0.001f;
    }
}

void trn_sigma_local_default(trn_sigma_model_t *m)
{
    if (m != NULL) {
        m->sigma_min_m = 0.02f;
        m->k_per_m = 0.002f;
    }
}

trn_status_t trn_sigma_model_check(const trn_sigma_model_t *m)
{
    if (m == NULL) {
        return TRN_E_NULL;
    }
    if (!(m->sigma_min_m >= 0.0f && m->sigma_min_m <= 1.0e5f) ||
        !(m->k_per_m >= 0.0f && m->k_per_m <= 100.0f)) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}

static int win_dims(const trn_window_t *w, int32_t *width, int32_t *height)
{
    int64_t ww = (int64_t)w->x1 - (int64_t)w->x0 + 1, hh = (int64_t)w->y1 - (int64_t)w->y0 + 1;
    if (ww < 1 || hh < 1 || ww > TRN_MAX_DIM || hh > TRN_MAX_DIM) {
        return 0;
    }
    *width = (int32_t)ww;
    *height = (int32_t)hh;
    return 1;
}

static trn_status_t check_common(const trn_kernels_t *k, const trn_sigma_model_t *m, float cell_m)
{
    trn_status_t st;
    if (k == NULL) {
        return TRN_E_NULL;
    }
    if (!(k->sigma0_cells >= 0.05f) || k->radius[TRN_KERNEL_COUNT - 1] < 1 ||
        k->radius[TRN_KERNEL_COUNT - 1] > TRN_KERNEL_MAX_RADIUS) {
        return TRN_E_ARG; /* not a built table */
    }
    if ((st = trn_sigma_model_check(m)) != TRN_OK) {
        return st;
    }
    if (!(cell_m > 0.0f && cell_m <= TRN_CELL_MAX_M)) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}

/* The kernel map without argument checks. sg (may be NULL): per-cell sigma
 * in metres over the window's cells (row y at sg->data + y * sg->stride);
 * a NaN cell takes the model. */
static void kernel_map(const trn_kernels_t *k, const trn_sigma_model_t *m, float cell_m,
                       const trn_xy_t *sensors, size_t n_sensors, const trn_window_t *win,
                       int32_t width, int32_t height, const trn_grid_f32_t *sg, uint8_t *idx)
{
    const double c2 = (double)cell_m * (double)cell_m;
    int32_t x, y;
    for (y = 0; y < height; ++y) {
        for (x = 0; x < width; ++x) {
            const double gx = (double)(win->x0 + x), gy = (double)(win->y0 + y);
            double best = HUGE_VAL, sig;
            size_t s;
            if (sg != NULL) {
                const float v = sg->data[(size_t)y * (size_t)sg->stride + (size_t)x];
                if (!isnan(v)) {
                    sig = (double)v / (double)cell_m;
                    idx[(size_t)y * (size_t)width + (size_t)x] = (uint8_t)trn_kernel_pick(
                        k, sig < 1e30 ? (float)sig : 1e30f);
                    continue;
                }
            }
            for (s = 0; s < n_sensors; ++s) {
                const double ex = gx - (double)sensors[s].x_cells;
                const double ey = gy - (double)sensors[s].y_cells;
                const double d2 = ex * ex + ey * ey;
                if (d2 < best) {
                    best = d2;
                }
            }
            sig = ((double)m->sigma_min_m + (double)m->k_per_m * best * c2) / (double)cell_m;
            idx[(size_t)y * (size_t)width + (size_t)x] = (uint8_t)trn_kernel_pick(
                k, sig < 1e30 ? (float)sig : 1e30f);
        }
    }
}

trn_status_t trn_spread_kernel_map(const trn_kernels_t *k, const trn_sigma_model_t *m, float cell_m,
                                   const trn_xy_t *sensors, size_t n_sensors,
                                   const trn_window_t *win, uint8_t *idx, size_t idx_len)
{
    trn_status_t st;
    int32_t w, h;
    size_t s;
    if (sensors == NULL || win == NULL || idx == NULL) {
        return TRN_E_NULL;
    }
    if ((st = check_common(k, m, cell_m)) != TRN_OK) {
        return st;
    }
    if (n_sensors < 1u || n_sensors > (size_t)TRN_SPREAD_MAX_SENSORS || !win_dims(win, &w, &h)) {
        return TRN_E_SIZE;
    }
    for (s = 0; s < n_sensors; ++s) {
        if (!isfinite(sensors[s].x_cells) || !isfinite(sensors[s].y_cells)) {
            return TRN_E_ARG;
        }
    }
    if (idx_len < (size_t)w * (size_t)h) {
        return TRN_E_WORKSPACE;
    }
    kernel_map(k, m, cell_m, sensors, n_sensors, win, w, h, NULL, idx);
    return TRN_OK;
}

/* Geometry of one spreading: a source window (sw, kernel map idx over it),
 * a destination window (dw, inside sw), tmp = sw rows x dw columns. */
typedef struct {
    const trn_kernels_t *k;
    const uint8_t *idx;
    trn_window_t sw, dw;
    int32_t sww, swh, dww, dwh;
    float *tmp;
} pass_t;

/* y[i] += a * x[i], i < n (distinct arrays: restrict lets it vectorise). */
static void axpy(float *restrict y, const float *restrict x, float a, int32_t n)
{
    int32_t i;
    for (i = 0; i < n; ++i) {
        y[i] += a * x[i];
    }
}

/* Scatter v * kernel j centred at global column sx into trow (dw columns). */
static void scatter_x(const pass_t *p, float *trow, int32_t sx, int32_t j, float v)
{
    const int32_t r = p->k->radius[j];
    const float *t = p->k->taps[j] + (TRN_KERNEL_MAX_RADIUS - r); /* t[i]: offset i - r */
    const int32_t lo = sx - r > p->dw.x0 ? sx - r : p->dw.x0;
    const int32_t hi = sx + r < p->dw.x1 ? sx + r : p->dw.x1;
    if (lo <= hi) {
        axpy(trow + (lo - p->dw.x0), t + (lo - sx + r), v, hi - lo + 1);
    }
}

/* x pass from an 8-bit occupancy slice (stride nx), rows/cols of sw. */
static void xpass_u8(const pass_t *p, const uint8_t *slice, int32_t nx, int zero_occupied)
{
    const uint8_t flip = zero_occupied ? 1u : 0u;
    int32_t y, x;
    for (y = 0; y < p->swh; ++y) {
        const uint8_t *srow = slice + (size_t)(p->sw.y0 + y) * (size_t)nx;
        const uint8_t *irow = p->idx + (size_t)y * (size_t)p->sww;
        float *trow = p->tmp + (size_t)y * (size_t)p->dww;
        memset(trow, 0, (size_t)p->dww * sizeof *trow);
        for (x = 0; x < p->sww; ++x) {
            if ((uint8_t)(srow[p->sw.x0 + x] != 0u) != flip) {
                scatter_x(p, trow, p->sw.x0 + x, (int32_t)irow[x], 1.0f);
            }
        }
    }
}

/* x pass from a float slice (stride nx). */
static void xpass_f32(const pass_t *p, const float *slice, int32_t nx)
{
    int32_t y, x;
    for (y = 0; y < p->swh; ++y) {
        const float *srow = slice + (size_t)(p->sw.y0 + y) * (size_t)nx;
        const uint8_t *irow = p->idx + (size_t)y * (size_t)p->sww;
        float *trow = p->tmp + (size_t)y * (size_t)p->dww;
        memset(trow, 0, (size_t)p->dww * sizeof *trow);
        for (x = 0; x < p->sww; ++x) {
            const float v = srow[p->sw.x0 + x];
            if (v != 0.0f) {
                scatter_x(p, trow, p->sw.x0 + x, (int32_t)irow[x], v);
            }
        }
    }
}

/* y pass: tmp (sw rows x dw cols) into out (dw, dense dww x dwh). Runs of
 * nonzero intermediate cells sharing a kernel are spread as row axpys. */
static void ypass(const pass_t *p, float *out)
{
    const int32_t xoff = p->dw.x0 - p->sw.x0;
    int32_t y;
    memset(out, 0, (size_t)p->dww * (size_t)p->dwh * sizeof *out);
    for (y = 0; y < p->swh; ++y) {
        const int32_t ty = p->sw.y0 + y;
        const float *trow = p->tmp + (size_t)y * (size_t)p->dww;
        const uint8_t *irow = p->idx + (size_t)y * (size_t)p->sww + (size_t)xoff;
        int32_t x = 0;
        while (x < p->dww) {
            int32_t xe, j, r, lo, hi, g;
            const float *t;
            if (trow[x] == 0.0f) {
                ++x;
                continue;
            }
            j = (int32_t)irow[x];
            xe = x + 1;
            while (xe < p->dww && trow[xe] != 0.0f && (int32_t)irow[xe] == j) {
                ++xe;
            }
            r = p->k->radius[j];
            t = p->k->taps[j] + (TRN_KERNEL_MAX_RADIUS - r);
            lo = ty - r > p->dw.y0 ? ty - r : p->dw.y0;
            hi = ty + r < p->dw.y1 ? ty + r : p->dw.y1;
            for (g = lo; g <= hi; ++g) {
                axpy(out + (size_t)(g - p->dw.y0) * (size_t)p->dww + (size_t)x, trow + x,
                     t[g - ty + r], xe - x);
            }
            x = xe;
        }
    }
}

/* The separable pass's carve for a source of rows x cols cells, dest
 * width w: the x-pass rows (rows x w floats), then the kernel index of each
 * source cell (base NULL: sizing only). Returns the bytes. */
static size_t pass_carve(size_t rows, size_t w, size_t cols, void *base, float **tmp, uint8_t **idx)
{
    trn_ws_t c;
    trn_ws_begin(&c, base);
    *tmp = (float *)trn_ws_take(&c, rows * w * sizeof(float));
    *idx = (uint8_t *)trn_ws_take(&c, rows * cols);
    return c.total;
}

size_t trn_prob_global_workspace_bytes(int32_t nx, int32_t ny)
{
    float *t;
    uint8_t *i;
    if (nx < 1 || ny < 1 || nx > TRN_MAX_DIM || ny > TRN_MAX_DIM) {
        return 0u;
    }
    return pass_carve((size_t)ny, (size_t)nx, (size_t)nx, NULL, &t, &i);
}

static trn_status_t prob_global(const trn_kernels_t *k, const trn_sigma_model_t *m, float cell_m,
                                const trn_xy_t *sensors, size_t n_sensors, const trn_vol_u8_t *occ,
                                int zero_occupied, const trn_grid_f32_t *sg, trn_vol_f32_t *pg,
                                void *ws, size_t ws_bytes)
{
    trn_status_t st;
    pass_t p;
    size_t need, plane, s;
    uint8_t *idx;
    int32_t z;

    if (sensors == NULL || occ == NULL || pg == NULL || ws == NULL || pg->data == NULL) {
        return TRN_E_NULL;
    }
    if ((st = check_common(k, m, cell_m)) != TRN_OK) {
        return st;
    }
    if ((st = trn_vol_u8_check(occ)) != TRN_OK) {
        return st;
    }
    if (pg->nx != occ->nx || pg->ny != occ->ny || pg->nz != occ->nz || n_sensors < 1u ||
        n_sensors > (size_t)TRN_SPREAD_MAX_SENSORS) {
        return TRN_E_SIZE;
    }
    for (s = 0; s < n_sensors; ++s) {
        if (!isfinite(sensors[s].x_cells) || !isfinite(sensors[s].y_cells)) {
            return TRN_E_ARG;
        }
    }
    need = trn_prob_global_workspace_bytes(occ->nx, occ->ny);
    if ((st = trn_ws_check(ws, ws_bytes, need)) != TRN_OK) {
        return st;
    }
    plane = (size_t)occ->nx * (size_t)occ->ny;
    p.k = k;
    p.sw.x0 = 0;
    p.sw.y0 = 0;
    p.sw.x1 = occ->nx - 1;
    p.sw.y1 = occ->ny - 1;
    p.dw = p.sw;
    p.sww = p.dww = occ->nx;
    p.swh = p.dwh = occ->ny;
    (void)pass_carve((size_t)occ->ny, (size_t)occ->nx, (size_t)occ->nx, ws, &p.tmp, &idx);
    p.idx = idx;
    kernel_map(k, m, cell_m, sensors, n_sensors, &p.sw, p.sww, p.swh, sg, idx);
    for (z = 0; z < occ->nz; ++z) {
        xpass_u8(&p, occ->data + (size_t)z * plane, occ->nx, zero_occupied);
        ypass(&p, pg->data + (size_t)z * plane);
    }
    return TRN_OK;
}

trn_status_t trn_prob_global(const trn_kernels_t *k, const trn_sigma_model_t *m, float cell_m,
                             const trn_xy_t *sensors, size_t n_sensors, const trn_vol_u8_t *occ,
                             trn_vol_f32_t *pg, void *ws, size_t ws_bytes)
{
    return prob_global(k, m, cell_m, sensors, n_sensors, occ, 0, NULL, pg, ws, ws_bytes);
}

trn_status_t trn_prob_global_map(const trn_kernels_t *k, const trn_sigma_model_t *m,
                                 const trn_xy_t *sensors, size_t n_sensors, const trn_map_t *map,
                                 trn_vol_f32_t *pg, void *ws, size_t ws_bytes)
{
    if (map == NULL) {
        return TRN_E_NULL;
    }
    return prob_global(k, m, map->cfg.terrain.cell_m, sensors, n_sensors, &map->dist, 1, NULL, pg,
                       ws, ws_bytes);
}

trn_status_t trn_prob_global_raster(const trn_kernels_t *k, const trn_sigma_model_t *m,
                                    const trn_xy_t *sensors, size_t n_sensors,
                                    const trn_grid_f32_t *sigma_m, const trn_map_t *map,
                                    trn_vol_f32_t *pg, void *ws, size_t ws_bytes)
{
    trn_status_t st;
    int32_t x, y;
    if (map == NULL || sigma_m == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_grid_f32_check(sigma_m)) != TRN_OK) {
        return st;
    }
    if (sigma_m->width != map->dist.nx || sigma_m->height != map->dist.ny) {
        return TRN_E_SIZE;
    }
    for (y = 0; y < sigma_m->height; ++y) {
        const float *row = sigma_m->data + (size_t)y * (size_t)sigma_m->stride;
        for (x = 0; x < sigma_m->width; ++x) {
            /* NaN: the model; otherwise a finite error >= 0 m */
            if (!isnan(row[x]) && !(row[x] >= 0.0f && row[x] <= FLT_MAX)) {
                return TRN_E_ARG;
            }
        }
    }
    return prob_global(k, m, map->cfg.terrain.cell_m, sensors, n_sensors, &map->dist, 1, sigma_m,
                       pg, ws, ws_bytes);
}

/* Source window of roi: roi grown by the largest radius any source that
 * could reach roi uses, clipped to nx x ny. Sources farther than R_9 never
 * reach roi; within that box sigma grows with the distance to the rover, so
 * its farthest corner bounds every kernel used there. */
static void source_window(const trn_kernels_t *k, const trn_sigma_model_t *m, float cell_m,
                          trn_xy_t rover, const trn_window_t *roi, int32_t nx, int32_t ny,
                          trn_window_t *sw)
{
    const int32_t r9 = k->radius[TRN_KERNEL_COUNT - 1];
    const double ex = fmax(fabs((double)(roi->x0 - r9) - (double)rover.x_cells),
                           fabs((double)(roi->x1 + r9) - (double)rover.x_cells));
    const double ey = fmax(fabs((double)(roi->y0 - r9) - (double)rover.y_cells),
                           fabs((double)(roi->y1 + r9) - (double)rover.y_cells));
    const double c = (double)cell_m;
    const double sig = ((double)m->sigma_min_m + (double)m->k_per_m * (ex * ex + ey * ey) * c * c) /
                       c;
    const int32_t r = k->radius[trn_kernel_pick(k, sig < 1e30 ? (float)sig : 1e30f)];
    sw->x0 = roi->x0 - r > 0 ? roi->x0 - r : 0;
    sw->y0 = roi->y0 - r > 0 ? roi->y0 - r : 0;
    sw->x1 = roi->x1 + r < nx - 1 ? roi->x1 + r : nx - 1;
    sw->y1 = roi->y1 + r < ny - 1 ? roi->y1 + r : ny - 1;
}

size_t trn_prob_local_workspace_bytes(const trn_kernels_t *k, const trn_window_t *roi)
{
    int32_t w, h, r;
    if (k == NULL || roi == NULL || !win_dims(roi, &w, &h)) {
        return 0u;
    }
    r = k->radius[TRN_KERNEL_COUNT - 1];
    if (r < 0 || r > TRN_KERNEL_MAX_RADIUS) {
        return 0u;
    }
    /* source rows <= h + 2r, source cols <= w + 2r */
    {
        float *t;
        uint8_t *i;
        return pass_carve((size_t)h + 2u * (size_t)r, (size_t)w, (size_t)w + 2u * (size_t)r, NULL,
                          &t, &i);
    }
}

trn_status_t trn_prob_local(const trn_kernels_t *k, const trn_sigma_model_t *m, float cell_m,
                            trn_xy_t rover, const trn_vol_f32_t *pg, const trn_window_t *roi,
                            trn_vol_f32_t *p, void *ws, size_t ws_bytes)
{
    trn_status_t st;
    pass_t ps;
    size_t gplane, lplane;
    uint8_t *idx;
    int32_t w, h, z;

    if (pg == NULL || roi == NULL || p == NULL || ws == NULL || pg->data == NULL ||
        p->data == NULL) {
        return TRN_E_NULL;
    }
    if ((st = check_common(k, m, cell_m)) != TRN_OK) {
        return st;
    }
    if (!isfinite(rover.x_cells) || !isfinite(rover.y_cells)) {
        return TRN_E_ARG;
    }
    if (pg->nx < 1 || pg->ny < 1 || pg->nz < 1 || pg->nx > TRN_MAX_DIM || pg->ny > TRN_MAX_DIM ||
        pg->nz > TRN_MAX_ZBINS) {
        return TRN_E_SIZE;
    }
    if (!win_dims(roi, &w, &h) || roi->x0 < 0 || roi->y0 < 0 || roi->x1 >= pg->nx ||
        roi->y1 >= pg->ny) {
        return TRN_E_RANGE;
    }
    if (p->nx != w || p->ny != h || p->nz != pg->nz) {
        return TRN_E_SIZE;
    }
    if ((st = trn_ws_check(ws, ws_bytes, trn_prob_local_workspace_bytes(k, roi))) != TRN_OK) {
        return st;
    }
    ps.k = k;
    source_window(k, m, cell_m, rover, roi, pg->nx, pg->ny, &ps.sw);
    ps.dw = *roi;
    ps.sww = ps.sw.x1 - ps.sw.x0 + 1;
    ps.swh = ps.sw.y1 - ps.sw.y0 + 1;
    ps.dww = w;
    ps.dwh = h;
    /* this source's carve: within the sizing's (rows <= h + 2r, cols <= w + 2r) */
    (void)pass_carve((size_t)ps.swh, (size_t)w, (size_t)ps.sww, ws, &ps.tmp, &idx);
    ps.idx = idx;
    kernel_map(k, m, cell_m, &rover, 1u, &ps.sw, ps.sww, ps.swh, NULL, idx);
    gplane = (size_t)pg->nx * (size_t)pg->ny;
    lplane = (size_t)w * (size_t)h;
    for (z = 0; z < pg->nz; ++z) {
        xpass_f32(&ps, pg->data + (size_t)z * gplane, pg->nx);
        ypass(&ps, p->data + (size_t)z * lplane);
    }
    return TRN_OK;
}
