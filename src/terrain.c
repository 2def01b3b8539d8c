/* SPDX-License-Identifier: Apache-2.0 */
/* terrain.c - high-pass filter and occupancy (see trn/terrain.h). */
#include "trn/terrain.h"

#include <float.h>
#include <math.h>

#include "ws.h"

static int pos_finite_le(float v, float max) { return v > 0.0f && v <= max; }

trn_status_t trn_terrain_cfg_check(const trn_terrain_cfg_t *cfg)
{
    if (cfg == NULL) {
        return TRN_E_NULL;
    }
    if (!pos_finite_le(cfg->cell_m, TRN_CELL_MAX_M) ||
        !pos_finite_le(cfg->zbin_m, TRN_CELL_MAX_M) ||
        !(cfg->highpass_half_m >= cfg->cell_m && cfg->highpass_half_m <= 1.0e6f)) {
        return TRN_E_ARG;
    }
    if (cfg->nz < 1 || cfg->nz > TRN_MAX_ZBINS) {
        return TRN_E_SIZE;
    }
    return TRN_OK;
}

/* The high-pass filter's carve: the summed-area tables of heights and of
 * the valid count, (width + 1) x (height + 1) each (base NULL: sizing
 * only). Returns the bytes, 0 if the size is out of range. */
static size_t highpass_carve(int32_t width, int32_t height, void *base, double **sum, int32_t **cnt)
{
    size_t cells;
    trn_ws_t w;
    *sum = NULL;
    *cnt = NULL;
    if (width < 1 || height < 1 || width > TRN_MAX_DIM || height > TRN_MAX_DIM) {
        return 0u;
    }
    cells = (size_t)(width + 1) * (size_t)(height + 1);
    trn_ws_begin(&w, base);
    *sum = (double *)trn_ws_take(&w, cells * sizeof(double));
    *cnt = (int32_t *)trn_ws_take(&w, cells * sizeof(int32_t));
    return w.total;
}

size_t trn_highpass_workspace_bytes(int32_t width, int32_t height)
{
    double *sum;
    int32_t *cnt;
    return highpass_carve(width, height, NULL, &sum, &cnt);
}

static int valid_h(float h) { return isfinite(h) ? 1 : 0; }

trn_status_t trn_highpass(const trn_grid_f32_t *dem, const trn_terrain_cfg_t *cfg,
                          trn_grid_f32_t *out, void *ws, size_t ws_bytes)
{
    trn_status_t st;
    int32_t w, h, x, y, r;
    size_t sw;
    double *sum;
    int32_t *cnt;
    double ref = 0.0;
    int have_ref = 0;

    if (dem == NULL || cfg == NULL || out == NULL || ws == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_grid_f32_check(dem)) != TRN_OK || (st = trn_grid_f32_check(out)) != TRN_OK) {
        return st;
    }
    if ((st = trn_terrain_cfg_check(cfg)) != TRN_OK) {
        return st;
    }
    w = dem->width;
    h = dem->height;
    if (out->width != w || out->height != h) {
        return TRN_E_SIZE;
    }
    if ((st = trn_ws_check(ws, ws_bytes, trn_highpass_workspace_bytes(w, h))) != TRN_OK) {
        return st;
    }
    sw = (size_t)w + 1u;
    (void)highpass_carve(w, h, ws, &sum, &cnt);

    /* Summed-area tables of (height - ref) and of the valid count; ref (the
     * first valid height) keeps the double sums small for absolute DTMs. */
    for (x = 0; x <= w; ++x) {
        sum[x] = 0.0;
        cnt[x] = 0;
    }
    for (y = 0; y < h; ++y) {
        double row_s = 0.0;
        int32_t row_c = 0;
        size_t o = ((size_t)y + 1u) * sw;
        sum[o] = 0.0;
        cnt[o] = 0;
        for (x = 0; x < w; ++x) {
            float v = TRN_GRID_AT(dem, x, y);
            if (valid_h(v)) {
                if (!have_ref) {
                    ref = (double)v;
                    have_ref = 1;
                }
                row_s += (double)v - ref;
                row_c += 1;
            }
            sum[o + (size_t)x + 1u] = sum[o - sw + (size_t)x + 1u] + row_s;
            cnt[o + (size_t)x + 1u] = cnt[o - sw + (size_t)x + 1u] + row_c;
        }
    }
    {
        /* A box wider than the grid is the whole grid: clamp before converting
         * so any accepted configuration gives a representable radius. */
        double ratio = (double)cfg->highpass_half_m / (double)cfg->cell_m;
        double rmax = (double)(w > h ? w : h);
        r = ratio >= rmax ? (int32_t)rmax : (int32_t)lround(ratio);
    }
    for (y = 0; y < h; ++y) {
        int32_t y0 = y - r < 0 ? 0 : y - r;
        int32_t y1 = y + r >= h ? h - 1 : y + r;
        size_t ra = (size_t)y0 * sw, rb = ((size_t)y1 + 1u) * sw;
        for (x = 0; x < w; ++x) {
            float v = TRN_GRID_AT(dem, x, y);
            float res = NAN;
            if (valid_h(v)) {
                int32_t x0 = x - r < 0 ? 0 : x - r;
                int32_t x1 = x + r >= w ? w - 1 : x + r;
                size_t a = (size_t)x0, b = (size_t)x1 + 1u;
                double s = sum[rb + b] - sum[rb + a] - sum[ra + b] + sum[ra + a];
                int32_t c = cnt[rb + b] - cnt[rb + a] - cnt[ra + b] + cnt[ra + a];
                /* c >= 1: the cell itself is valid and inside its own box.
                 * Heights near +-FLT_MAX can give |h'| > FLT_MAX: clamp, so
                 * a seen height stays seen (and the float conversion is
                 * defined); occupancy puts it in the end bin either way. */
                double hp = ((double)v - ref) - s / (double)c;
                hp = hp > (double)FLT_MAX ? (double)FLT_MAX : hp;
                hp = hp < -(double)FLT_MAX ? -(double)FLT_MAX : hp;
                res = (float)hp;
            }
            TRN_GRID_AT(out, x, y) = res;
        }
    }
    return have_ref ? TRN_OK : TRN_E_NODATA;
}

/* Bin of a filtered height, or -1 when missing. */
static int32_t bin_of(float hp, const trn_terrain_cfg_t *cfg)
{
    double k;
    const int32_t mid_bin = cfg->nz / 2; /* bin centred on h' = 0 (integer division intended) */
    if (!valid_h(hp)) {
        return -1;
    }
    /* Bins are centred on multiples of zbin_m: flat ground (h' = 0 after the
     * high-pass) sits mid-bin, not on a bin edge where millimetres flip it. */
    k = floor((double)hp / (double)cfg->zbin_m + 0.5) + (double)mid_bin;
    if (k < 0.0) {
        return 0;
    }
    if (k > (double)(cfg->nz - 1)) {
        return cfg->nz - 1;
    }
    return (int32_t)k;
}

/* Occupied bin range [*lo, *hi] of cell (x, y); returns 0 when missing. */
static int column_of(const trn_grid_f32_t *hp, const trn_terrain_cfg_t *cfg, int32_t x, int32_t y,
                     int32_t *lo, int32_t *hi)
{
    static const int32_t dx[4] = {1, -1, 0, 0};
    static const int32_t dy[4] = {0, 0, 1, -1};
    int32_t k = bin_of(TRN_GRID_AT(hp, x, y), cfg);
    int32_t low = k, i;
    if (k < 0) {
        return 0;
    }
    for (i = 0; i < 4; ++i) {
        int32_t nx = x + dx[i], ny = y + dy[i];
        if (nx >= 0 && ny >= 0 && nx < hp->width && ny < hp->height) {
            int32_t kn = bin_of(TRN_GRID_AT(hp, nx, ny), cfg);
            if (kn >= 0 && kn + 1 < low) {
                low = kn + 1;
            }
        }
    }
    *lo = low;
    *hi = k;
    return 1;
}

trn_status_t trn_occupancy(const trn_grid_f32_t *hp, const trn_terrain_cfg_t *cfg,
                           trn_vol_u8_t *occ, uint32_t *n_occupied)
{
    trn_status_t st;
    int32_t x, y, z;
    uint32_t n = 0;
    size_t i, total;

    if (hp == NULL || cfg == NULL || occ == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_grid_f32_check(hp)) != TRN_OK || (st = trn_vol_u8_check(occ)) != TRN_OK ||
        (st = trn_terrain_cfg_check(cfg)) != TRN_OK) {
        return st;
    }
    if (occ->nx != hp->width || occ->ny != hp->height || occ->nz != cfg->nz) {
        return TRN_E_SIZE;
    }
    total = (size_t)occ->nx * (size_t)occ->ny * (size_t)occ->nz;
    for (i = 0; i < total; ++i) {
        occ->data[i] = 0u;
    }
    for (y = 0; y < hp->height; ++y) {
        for (x = 0; x < hp->width; ++x) {
            int32_t lo, hi;
            if (column_of(hp, cfg, x, y, &lo, &hi)) {
                for (z = lo; z <= hi; ++z) {
                    occ->data[TRN_VOL_IDX(occ, x, y, z)] = 1u;
                    ++n;
                }
            }
        }
    }
    if (n_occupied != NULL) {
        *n_occupied = n;
    }
    return n > 0u ? TRN_OK : TRN_E_NODATA;
}

trn_status_t trn_occupancy_points(const trn_grid_f32_t *hp, const trn_terrain_cfg_t *cfg,
                                  int32_t rover_x, int32_t rover_y, trn_point_t *pts,
                                  size_t capacity, size_t *n_points)
{
    trn_status_t st;
    int32_t x, y, z;
    size_t n = 0;

    if (hp == NULL || cfg == NULL || pts == NULL || n_points == NULL) {
        return TRN_E_NULL;
    }
    *n_points = 0;
    if ((st = trn_grid_f32_check(hp)) != TRN_OK || (st = trn_terrain_cfg_check(cfg)) != TRN_OK) {
        return st;
    }
    if (rover_x < -TRN_MAX_DIM || rover_x > hp->width - 1 + TRN_MAX_DIM || rover_y < -TRN_MAX_DIM ||
        rover_y > hp->height - 1 + TRN_MAX_DIM) {
        return TRN_E_ARG;
    }
    /* Two passes so each column is computed twice, not nz times: count the
     * voxels per bin, then place each at its bin's next slot, which leaves
     * the list sorted (z, y, x), the distance volume's order. */
    {
        size_t start[TRN_MAX_ZBINS];
        int32_t lo, hi;
        for (z = 0; z < cfg->nz; ++z) {
            start[z] = 0u;
        }
        for (y = 0; y < hp->height; ++y) {
            for (x = 0; x < hp->width; ++x) {
                if (column_of(hp, cfg, x, y, &lo, &hi)) {
                    for (z = lo; z <= hi; ++z) {
                        start[z] += 1u;
                    }
                    n += (size_t)(hi - lo + 1);
                }
            }
        }
        if (n > capacity) {
            return TRN_E_CAPACITY;
        }
        {
            size_t acc = 0u;
            for (z = 0; z < cfg->nz; ++z) {
                size_t c = start[z];
                start[z] = acc;
                acc += c;
            }
        }
        for (y = 0; y < hp->height; ++y) {
            for (x = 0; x < hp->width; ++x) {
                if (column_of(hp, cfg, x, y, &lo, &hi)) {
                    for (z = lo; z <= hi; ++z) {
                        trn_point_t *q = &pts[start[z]++];
                        q->x = (int16_t)(x - rover_x);
                        q->y = (int16_t)(y - rover_y);
                        q->z = (int16_t)z;
                    }
                }
            }
        }
    }
    *n_points = n;
    return n > 0u ? TRN_OK : TRN_E_NODATA;
}
