/* SPDX-License-Identifier: Apache-2.0 */
/* likelihood.c - ln p(d) table, K, pose scoring and the two pose searches
 * (see trn/likelihood.h). */
#include "trn/likelihood.h"

#include <math.h>

#include "likelihood_int.h"
#include "ws.h"

#define TRN_SQRT_2PI 2.5066282746310002

/* One level of distances as the scorer sees it: voxel (x, y, z) of the map
 * is d[((z * dimy) + y + off) * dimx + x + off]; outside -> cap. */
typedef struct {
    const uint8_t *d;
    int32_t dimx, dimy, nz, off;
    uint8_t cap;
} level_view_t;

typedef struct {
    int32_t minx, maxx, miny, maxy;
} bbox_t;

trn_status_t trn_lik_cfg_check(const trn_lik_cfg_t *cfg)
{
    if (cfg == NULL) {
        return TRN_E_NULL;
    }
    if (!(cfg->cell_m > 0.0f && cfg->cell_m <= TRN_CELL_MAX_M) ||
        !(cfg->sigma_m > 0.0f && cfg->sigma_m <= TRN_CELL_MAX_M) ||
        !(cfg->inlier_prob > 0.0f && cfg->inlier_prob < 1.0f) || cfg->cap < 3u ||
        cfg->cap > TRN_CHAMFER_CAP_MAX) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}

/* ln p1(d) for a distance in chamfer units. */
static double ln_p1(uint32_t dc, const trn_lik_cfg_t *cfg)
{
    double d_m = (double)dc / 3.0 * (double)cfg->cell_m;
    double s = (double)cfg->sigma_m;
    return -(d_m * d_m) / (2.0 * s * s) - log(s * TRN_SQRT_2PI);
}

trn_status_t trn_outlier_density(const trn_vol_u8_t *dist, const trn_lik_cfg_t *cfg,
                                 double *k_per_m)
{
    /* One histogram (about 1 KiB of stack, TRN_STACK_LIMIT_BYTES). Voxels at
     * the cap, most of the volume, are not counted one by one: blocks of 16
     * that are all cap are skipped by a vectorizable test, and hist[cap] is
     * what remains of the total. Counts fit in uint32_t: at most
     * TRN_MAX_DIM^2 * TRN_MAX_ZBINS voxels (2^31). */
    uint32_t hist[TRN_CHAMFER_CAP_MAX + 1];
    trn_status_t st;
    size_t i, total, others = 0u;
    double k = 0.0;
    uint32_t d;
    uint8_t capb;
    const uint8_t *v;

    if (dist == NULL || cfg == NULL || k_per_m == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_vol_u8_check(dist)) != TRN_OK || (st = trn_lik_cfg_check(cfg)) != TRN_OK) {
        return st;
    }
    for (d = 0; d <= TRN_CHAMFER_CAP_MAX; ++d) {
        hist[d] = 0u;
    }
    capb = (uint8_t)cfg->cap;
    total = (size_t)dist->nx * (size_t)dist->ny * (size_t)dist->nz;
    v = dist->data;
    for (i = 0u; i + 16u <= total; i += 16u) {
        size_t j;
        uint8_t diff = 0u;
        for (j = 0u; j < 16u; ++j) {
            diff = (uint8_t)(diff | (uint8_t)(v[i + j] ^ capb));
        }
        if (diff != 0u) { /* not all 16 at the cap */
            for (j = 0u; j < 16u; ++j) {
                const uint8_t c = v[i + j];
                if (c > capb) {
                    return TRN_E_ARG; /* above the cap: not this table's transform */
                }
                if (c != capb) {
                    hist[c] += 1u;
                    ++others;
                }
            }
        }
    }
    for (; i < total; ++i) { /* the last total % 16 voxels */
        const uint8_t c = v[i];
        if (c > capb) {
            return TRN_E_ARG;
        }
        if (c != capb) {
            hist[c] += 1u;
            ++others;
        }
    }
    hist[capb] = (uint32_t)(total - others);
    for (d = 0; d <= cfg->cap; ++d) {
        const double n = (double)hist[d];
        if (n != 0.0) {
            k += n * exp(ln_p1(d, cfg));
        }
    }
    *k_per_m = k / (double)total;
    return TRN_OK;
}

trn_status_t trn_lnp_table_build(trn_lnp_table_t *t, const trn_lik_cfg_t *cfg, double k_per_m)
{
    trn_status_t st;
    uint32_t d;
    double la, lb;

    if (t == NULL || cfg == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_lik_cfg_check(cfg)) != TRN_OK) {
        return st;
    }
    if (!(k_per_m > 0.0) || !isfinite(k_per_m)) {
        return TRN_E_ARG;
    }
    lb = log(1.0 - (double)cfg->inlier_prob) + log(k_per_m);
    for (d = 0; d <= TRN_CHAMFER_CAP_MAX; ++d) {
        double v, hi, lo;
        la = log((double)cfg->inlier_prob) + ln_p1(d <= cfg->cap ? d : cfg->cap, cfg);
        /* ln(e^la + e^lb) without overflow or underflow */
        hi = la > lb ? la : lb;
        lo = la > lb ? lb : la;
        v = (hi + log1p(exp(lo - hi))) * (double)TRN_LNP_SCALE;
        if (v > 2.0e9) {
            v = 2.0e9;
        }
        if (v < -2.0e9) {
            v = -2.0e9;
        }
        t->lnp[d] = (int32_t)lround(v);
    }
    t->k_per_m = k_per_m;
    t->cap = cfg->cap;
    return TRN_OK;
}

/* ------------------------------------------------------------------ scoring */

static bbox_t points_bbox(const trn_point_t *pts, size_t n)
{
    bbox_t b = {0, 0, 0, 0};
    size_t i;
    if (n > 0u) {
        b.minx = b.maxx = pts[0].x;
        b.miny = b.maxy = pts[0].y;
    }
    for (i = 1; i < n; ++i) {
        if (pts[i].x < b.minx) {
            b.minx = pts[i].x;
        }
        if (pts[i].x > b.maxx) {
            b.maxx = pts[i].x;
        }
        if (pts[i].y < b.miny) {
            b.miny = pts[i].y;
        }
        if (pts[i].y > b.maxy) {
            b.maxy = pts[i].y;
        }
    }
    return b;
}

static int points_z_ok(const trn_point_t *pts, size_t n, int32_t nz)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        if (pts[i].z < 0 || pts[i].z >= nz) {
            return 0;
        }
    }
    return 1;
}

/* Sum of lnp over the points at pose (px, py) on level L. The sum is exact
 * (int64), so the fast and checked paths agree bit for bit. */
static int64_t score_level(const level_view_t *L, const int32_t *lnp, const trn_point_t *pts,
                           size_t n, const bbox_t *bb, int32_t px, int32_t py)
{
    int64_t s = 0;
    size_t i;
    int32_t ox = px + L->off, oy = py + L->off;
    if (ox + bb->minx >= 0 && ox + bb->maxx < L->dimx && oy + bb->miny >= 0 &&
        oy + bb->maxy < L->dimy) {
        for (i = 0; i < n; ++i) {
            size_t idx = ((size_t)pts[i].z * (size_t)L->dimy + (size_t)(oy + pts[i].y)) *
                             (size_t)L->dimx +
                         (size_t)(ox + pts[i].x);
            s += lnp[L->d[idx]];
        }
    } else {
        int32_t capv = lnp[L->cap];
        for (i = 0; i < n; ++i) {
            int32_t x = ox + pts[i].x, y = oy + pts[i].y;
            if (x < 0 || y < 0 || x >= L->dimx || y >= L->dimy) {
                s += capv;
            } else {
                size_t idx = ((size_t)pts[i].z * (size_t)L->dimy + (size_t)y) * (size_t)L->dimx +
                             (size_t)x;
                s += lnp[L->d[idx]];
            }
        }
    }
    return s;
}

/*
 * Early exit for branch-and-bound. The points are split into BB_NCH chunks
 * (chunk c = [chunk_lo(c), chunk_lo(c + 1))). A block or pose is scored
 * chunk by chunk against `up`, upper bounds of the sums of chunks c.. on:
 * after chunk c, if the sum so far plus up[c + 1] is below `cut` (the best
 * score so far), the full sum is too, and the block or pose is discarded
 * unread: the decision the full sum would give, so results do not change.
 * The bounds: for a top-level block, (points left) x the table's largest
 * entry; for a child, its parent's own chunk sums, which bound the child's
 * term by term (the child's block lies inside the parent's, so its minimum
 * distance per point is no smaller, and ln p does not increase).
 */
#define BB_NCH 32u

/** Sums of chunks c..BB_NCH-1 for c = 0..BB_NCH (s[BB_NCH] = 0). */
typedef struct {
    int64_t s[BB_NCH + 1u];
} suffix_t;

static size_t chunk_lo(size_t n, size_t c)
{
    const size_t q = n / BB_NCH, r = n % BB_NCH;
    return c * q + (c < r ? c : r);
}

/* Score (px, py) on L by chunks. up: upper bounds as above, or NULL for no
 * exit. Returns 0 when proven below cut; else 1 with the sum in *total and,
 * if suf is not NULL, the chunk suffix sums in *suf. */
static int score_chunks(const level_view_t *L, const int32_t *lnp, const trn_point_t *pts, size_t n,
                        const bbox_t *bb, int32_t px, int32_t py, const suffix_t *up, int64_t cut,
                        int64_t *total, suffix_t *suf)
{
    int64_t cs[BB_NCH];
    int64_t s = 0;
    size_t c;
    for (c = 0; c < BB_NCH; ++c) {
        const size_t lo = chunk_lo(n, c), hi = chunk_lo(n, c + 1u);
        cs[c] = hi > lo ? score_level(L, lnp, pts + lo, hi - lo, bb, px, py) : 0;
        s += cs[c];
        if (up != NULL && c + 1u < BB_NCH && s + up->s[c + 1u] < cut) {
            return 0;
        }
    }
    *total = s;
    if (suf != NULL) {
        suf->s[BB_NCH] = 0;
        for (c = BB_NCH; c-- > 0u;) {
            suf->s[c] = suf->s[c + 1u] + cs[c];
        }
    }
    return 1;
}

static level_view_t base_view(const trn_vol_u8_t *dist, uint8_t cap)
{
    level_view_t L;
    L.d = dist->data;
    L.dimx = dist->nx;
    L.dimy = dist->ny;
    L.nz = dist->nz;
    L.off = 0;
    L.cap = cap;
    return L;
}

/* Common argument checks of the searches and the scorer. */
static trn_status_t check_search_args(const trn_vol_u8_t *dist, const trn_lnp_table_t *t,
                                      const trn_point_t *pts, size_t n)
{
    trn_status_t st;
    if (dist == NULL || t == NULL || pts == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_vol_u8_check(dist)) != TRN_OK) {
        return st;
    }
    if (t->cap < 3u || t->cap > TRN_CHAMFER_CAP_MAX) {
        return TRN_E_ARG;
    }
    if (n == 0u) {
        return TRN_E_NODATA;
    }
    if (!points_z_ok(pts, n, dist->nz)) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}

static trn_status_t check_window(const trn_window_t *win, const trn_exclusion_t *ex, int32_t nx,
                                 int32_t ny)
{
    if (win == NULL) {
        return TRN_E_NULL;
    }
    if (win->x0 > win->x1 || win->y0 > win->y1 || win->x0 < 0 || win->y0 < 0 || win->x1 >= nx ||
        win->y1 >= ny) {
        return TRN_E_RANGE;
    }
    if (ex != NULL && ex->radius < 0) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}

trn_status_t trn_score_pose(const trn_vol_u8_t *dist, const trn_lnp_table_t *t,
                            const trn_point_t *pts, size_t n, int32_t px, int32_t py,
                            int64_t *score)
{
    trn_status_t st;
    level_view_t L;
    bbox_t bb;
    if (score == NULL) {
        return TRN_E_NULL;
    }
    if ((st = check_search_args(dist, t, pts, n)) != TRN_OK) {
        return st;
    }
    if (px < -2 * TRN_MAX_DIM || px > 2 * TRN_MAX_DIM || py < -2 * TRN_MAX_DIM ||
        py > 2 * TRN_MAX_DIM) {
        return TRN_E_RANGE;
    }
    L = base_view(dist, t->cap);
    bb = points_bbox(pts, n);
    *score = score_level(&L, t->lnp, pts, n, &bb, px, py);
    return TRN_OK;
}

static int excluded(const trn_exclusion_t *ex, int32_t x, int32_t y)
{
    int32_t dx, dy;
    if (ex == NULL) {
        return 0;
    }
    dx = x > ex->cx ? x - ex->cx : ex->cx - x;
    dy = y > ex->cy ? y - ex->cy : ex->cy - y;
    return dx <= ex->radius && dy <= ex->radius;
}

/* Does (x, y, s) beat the current best? Highest score, then smallest y, x. */
static int better(int found, const trn_best_t *b, int64_t s, int32_t x, int32_t y)
{
    if (!found || s > b->score) {
        return 1;
    }
    if (s < b->score) {
        return 0;
    }
    return y < b->y || (y == b->y && x < b->x);
}

/* Keep (x, y, s) if it beats the current best. */
static void consider(trn_best_t *best, int *found, int64_t s, int32_t x, int32_t y)
{
    if (better(*found, best, s, x, y)) {
        best->x = x;
        best->y = y;
        best->score = s;
        *found = 1;
    }
}

trn_status_t trn_search_exhaustive(const trn_vol_u8_t *dist, const trn_lnp_table_t *t,
                                   const trn_point_t *pts, size_t n, const trn_window_t *win,
                                   const trn_exclusion_t *ex, trn_best_t *best,
                                   trn_search_stats_t *stats)
{
    trn_status_t st;
    level_view_t L;
    bbox_t bb;
    int32_t x, y;
    int found = 0;
    uint64_t scored = 0;

    if (best == NULL) {
        return TRN_E_NULL;
    }
    if ((st = check_search_args(dist, t, pts, n)) != TRN_OK) {
        return st;
    }
    if ((st = check_window(win, ex, dist->nx, dist->ny)) != TRN_OK) {
        return st;
    }
    L = base_view(dist, t->cap);
    bb = points_bbox(pts, n);
    for (y = win->y0; y <= win->y1; ++y) {
        for (x = win->x0; x <= win->x1; ++x) {
            int64_t s;
            if (excluded(ex, x, y)) {
                continue;
            }
            s = score_level(&L, t->lnp, pts, n, &bb, x, y);
            ++scored;
            consider(best, &found, s, x, y);
        }
    }
    if (stats != NULL) {
        stats->poses_scored = scored;
        stats->blocks_bounded = 0u;
    }
    return found ? TRN_OK : TRN_E_NODATA;
}

/* ------------------------------------------------------------------ pyramid */

/* The pyramid's carve: one slice a level (level[] NULL when sizing only).
 * Returns the bytes, 0 if the arguments are out of range. */
static size_t pyramid_carve(int32_t nx, int32_t ny, int32_t nz, int32_t nlevels, void *buf,
                            uint8_t *level[TRN_MAX_LEVELS])
{
    size_t pad, per;
    int32_t lv;
    trn_ws_t w;
    if (nx < 1 || ny < 1 || nz < 1 || nx > TRN_MAX_DIM || ny > TRN_MAX_DIM || nz > TRN_MAX_ZBINS ||
        nlevels < 1 || nlevels > TRN_MAX_LEVELS) {
        return 0u;
    }
    pad = ((size_t)1u << (unsigned)nlevels) - 1u;
    per = ((size_t)nx + pad) * ((size_t)ny + pad) * (size_t)nz;
    trn_ws_begin(&w, buf);
    for (lv = 0; lv < TRN_MAX_LEVELS; ++lv) {
        void *slice = lv < nlevels ? trn_ws_take(&w, per) : NULL;
        if (level != NULL) {
            level[lv] = (uint8_t *)slice;
        }
    }
    return w.total;
}

size_t trn_pyramid_bytes(int32_t nx, int32_t ny, int32_t nz, int32_t nlevels)
{
    return pyramid_carve(nx, ny, nz, nlevels, NULL, NULL);
}

static uint8_t min_u8(uint8_t a, uint8_t b) { return a < b ? a : b; }

#define PYR_LANES 16

/* out[k] = min(a[k], a[k+h], b[k], b[k+h]) for k < PYR_LANES (a fixed-count
 * loop over non-overlapping arrays: compilers vectorize it at -O2). */
static void pyr_block(uint8_t *restrict out, const uint8_t *restrict a, const uint8_t *restrict b,
                      size_t h)
{
    size_t k;
    for (k = 0; k < PYR_LANES; ++k) {
        out[k] = min_u8(min_u8(a[k], a[k + h]), min_u8(b[k], b[k + h]));
    }
}

/* Source value at map column x of a row covering columns [lo, nx), cap elsewhere. */
static uint8_t pyr_src(const uint8_t *r, int32_t lo, int32_t nx, int32_t x, uint8_t cap)
{
    return (r != NULL && x >= lo && x < nx) ? r[x - lo] : cap;
}

/*
 * One output row of a pyramid level: for map column x in [-pad, nx), stored
 * at row[x + pad], the minimum of S0 and S1 at x and x + h, where S0, S1 are
 * the source rows r0, r1 (map columns [lo, nx), NULL = off the map) and
 * anything off the map is cap. The interior, where every read is in range,
 * goes by PYR_LANES-wide blocks (the last one may overlap the one before:
 * the output never aliases a source); the few columns at each end one by one.
 */
static void pyr_row(uint8_t *row, const uint8_t *r0_in, const uint8_t *r1_in, int32_t lo,
                    int32_t nx, int32_t pad, int32_t h, uint8_t cap)
{
    const int32_t pnx = nx + pad;
    const uint8_t *r0 = r0_in, *r1 = r1_in;
    int32_t x, a, b;
    if (r0 == NULL && r1 == NULL) {
        for (x = 0; x < pnx; ++x) {
            row[x] = cap;
        }
        return;
    }
    if (r0 == NULL) {
        r0 = r1;
    } else if (r1 == NULL) {
        r1 = r0;
    }
    /* interior: lo <= x and x + h < nx */
    a = lo > -pad ? lo : -pad;
    b = nx - h; /* exclusive */
    for (x = -pad; x < pnx - pad; ++x) {
        if (x == a && b - a >= PYR_LANES) {
            int32_t i;
            for (i = a; i < b; i += PYR_LANES) {
                const int32_t i0 = i + PYR_LANES <= b ? i : b - PYR_LANES;
                pyr_block(row + (i0 + pad), r0 + (i0 - lo), r1 + (i0 - lo), (size_t)h);
            }
            x = b - 1;
            continue;
        }
        row[x + pad] = min_u8(min_u8(pyr_src(r0, lo, nx, x, cap), pyr_src(r0, lo, nx, x + h, cap)),
                              min_u8(pyr_src(r1, lo, nx, x, cap), pyr_src(r1, lo, nx, x + h, cap)));
    }
}

trn_status_t trn_pyramid_build(trn_pyramid_t *p, const trn_vol_u8_t *dist, uint8_t cap,
                               int32_t nlevels, void *buf, size_t len)
{
    trn_status_t st;
    size_t need;
    int32_t lv, y, z;

    if (p == NULL || buf == NULL) {
        return TRN_E_NULL;
    }
    if ((st = trn_vol_u8_check(dist)) != TRN_OK) {
        return st;
    }
    if (nlevels < 1 || nlevels > TRN_MAX_LEVELS || cap < 3u || cap > TRN_CHAMFER_CAP_MAX) {
        return TRN_E_ARG;
    }
    need = trn_pyramid_bytes(dist->nx, dist->ny, dist->nz, nlevels);
    if ((st = trn_ws_check(buf, len, need)) != TRN_OK) {
        return st;
    }
    p->base = *dist;
    p->nlevels = nlevels;
    p->pad = (int32_t)((1u << (unsigned)nlevels) - 1u);
    p->pnx = dist->nx + p->pad;
    p->pny = dist->ny + p->pad;
    p->cap = cap;
    (void)pyramid_carve(dist->nx, dist->ny, dist->nz, nlevels, buf, p->level);
    /* Level 1 = min of the base over 2x2 blocks; level l = min of level l-1
     * at (x, y), (x+h, y), (x, y+h), (x+h, y+h), h = 2^(l-1): the minimum over
     * a 2^l x 2^l block. Stored with `pad` cells on the low side in x and y;
     * anything off the map is cap. Built a row at a time (pyr_row). */
    for (lv = 1; lv <= nlevels; ++lv) {
        int32_t h = (int32_t)(1u << (unsigned)(lv - 1));
        uint8_t *out = p->level[lv - 1];
        for (z = 0; z < dist->nz; ++z) {
            for (y = -p->pad; y < dist->ny; ++y) {
                uint8_t *row = out +
                               ((size_t)z * (size_t)p->pny + (size_t)(y + p->pad)) * (size_t)p->pnx;
                const uint8_t *src[2];
                int32_t k, lo;
                for (k = 0; k < 2; ++k) {
                    int32_t sy = y + k * h; /* source row, map coordinates */
                    src[k] = NULL;
                    if (lv == 1) {
                        /* base: rows 0..ny-1, columns 0..nx-1, no padding */
                        if (sy >= 0 && sy < dist->ny) {
                            src[k] = dist->data +
                                     ((size_t)z * (size_t)dist->ny + (size_t)sy) * (size_t)dist->nx;
                        }
                    } else if (sy < dist->ny) { /* sy >= -pad always */
                        src[k] = p->level[lv - 2] +
                                 ((size_t)z * (size_t)p->pny + (size_t)(sy + p->pad)) *
                                     (size_t)p->pnx;
                    }
                }
                lo = lv == 1 ? 0 : -p->pad;
                pyr_row(row, src[0], src[1], lo, dist->nx, p->pad, h, cap);
            }
        }
    }
    return TRN_OK;
}

/* ----------------------------------------------------------- branch & bound */

typedef struct {
    int32_t x, y;
    int32_t level;
    int32_t slot; /* where its chunk sums are (tops: tops_suf; kids: kid_suf) */
    int64_t bound;
} block_t;

static level_view_t pyr_view(const trn_pyramid_t *p, int32_t lv)
{
    level_view_t L;
    if (lv == 0) {
        return base_view(&p->base, p->cap);
    }
    L.d = p->level[lv - 1];
    L.dimx = p->pnx;
    L.dimy = p->pny;
    L.nz = p->base.nz;
    L.off = p->pad;
    L.cap = p->cap;
    return L;
}

static int32_t ceil_div(int32_t a, int32_t b) { return (a + b - 1) / b; }

#define TRN_BB_STACK (4u * TRN_MAX_LEVELS + 4u)

/* The branch-and-bound workspace: top-level blocks, their suffix bounds,
 * the stack's suffix bounds (and four children's), the block stack. */
typedef struct {
    block_t *tops, *stack;
    suffix_t *tops_suf, *stack_suf;
    size_t ntop_max;
} bb_layout_t;

/* The carve of trn_search_bb's workspace (base NULL: sizing only); returns
 * the bytes, 0 if the arguments are out of range. */
static size_t bb_carve(const trn_pyramid_t *p, const trn_window_t *win, void *base,
                       bb_layout_t *lay)
{
    int32_t bs;
    trn_ws_t w;
    lay->tops = lay->stack = NULL;
    lay->tops_suf = lay->stack_suf = NULL;
    lay->ntop_max = 0u;
    if (p == NULL || win == NULL || p->nlevels < 1 || p->nlevels > TRN_MAX_LEVELS ||
        win->x1 < win->x0 || win->y1 < win->y0 || win->x1 - win->x0 >= TRN_MAX_DIM ||
        win->y1 - win->y0 >= TRN_MAX_DIM) {
        return 0u;
    }
    bs = (int32_t)(1u << (unsigned)p->nlevels);
    lay->ntop_max = (size_t)ceil_div(win->x1 - win->x0 + 1, bs) *
                    (size_t)ceil_div(win->y1 - win->y0 + 1, bs);
    trn_ws_begin(&w, base);
    lay->tops = (block_t *)trn_ws_take(&w, lay->ntop_max * sizeof(block_t));
    lay->tops_suf = (suffix_t *)trn_ws_take(&w, lay->ntop_max * sizeof(suffix_t));
    lay->stack_suf = (suffix_t *)trn_ws_take(&w, (TRN_BB_STACK + 4u) * sizeof(suffix_t));
    lay->stack = (block_t *)trn_ws_take(&w, TRN_BB_STACK * sizeof(block_t));
    return w.total;
}

size_t trn_search_bb_workspace_bytes(const trn_pyramid_t *p, const trn_window_t *win)
{
    bb_layout_t lay;
    return bb_carve(p, win, NULL, &lay);
}

/* Is every pose of block (x, y, size s) that lies in the window excluded? */
static int block_excluded(const trn_exclusion_t *ex, const trn_window_t *w, int32_t x, int32_t y,
                          int32_t s)
{
    int32_t xe = x + s - 1 < w->x1 ? x + s - 1 : w->x1;
    int32_t ye = y + s - 1 < w->y1 ? y + s - 1 : w->y1;
    if (ex == NULL) {
        return 0;
    }
    return x >= ex->cx - ex->radius && xe <= ex->cx + ex->radius && y >= ex->cy - ex->radius &&
           ye <= ex->cy + ex->radius;
}

/* Order for the top-level list: larger bound first, then smaller y, x. */
static int block_before(const block_t *a, const block_t *b)
{
    if (a->bound != b->bound) {
        return a->bound > b->bound;
    }
    return a->y < b->y || (a->y == b->y && a->x < b->x);
}

static void sift_down(block_t *a, size_t start, size_t n)
{
    size_t root = start;
    while (2u * root + 1u < n) {
        size_t child = 2u * root + 1u, swap = root;
        block_t tmp;
        /* max-heap on "comes later", so the sorted array runs first..last */
        if (block_before(&a[swap], &a[child])) {
            swap = child;
        }
        if (child + 1u < n && block_before(&a[swap], &a[child + 1u])) {
            swap = child + 1u;
        }
        if (swap == root) {
            return;
        }
        tmp = a[root];
        a[root] = a[swap];
        a[swap] = tmp;
        root = swap;
    }
}

static void sort_blocks(block_t *a, size_t n)
{
    size_t start, end;
    if (n < 2u) {
        return;
    }
    for (start = n / 2u; start-- > 0u;) {
        sift_down(a, start, n);
    }
    for (end = n - 1u; end > 0u; --end) {
        block_t tmp = a[0];
        a[0] = a[end];
        a[end] = tmp;
        sift_down(a, 0u, end);
    }
}

/* Does pose a come before pose b (score, then tie rank, then y, x)? */
static int kept_before(const trn_kept_pose_t *a, const trn_kept_pose_t *b)
{
    if (a->score != b->score) {
        return a->score > b->score;
    }
    if (a->rank != b->rank) {
        return a->rank < b->rank;
    }
    return a->y < b->y || (a->y == b->y && a->x < b->x);
}

/* keep's threshold: its best's score minus the margin, or the last kept
 * pose's score when the list is full and that is higher (scores are sums
 * of fewer than 2^31 int32 entries: no wrap). */
static int64_t keep_cut(const trn_bb_keep_t *kp)
{
    const int64_t c = kp->best.score - kp->margin;
    return (kp->len == kp->cap && kp->list[0].score > c) ? kp->list[0].score : c;
}

/* Restore the min-heap (the last kept pose at the root) below slot at. */
static void keep_sift(trn_kept_pose_t *h, size_t len, size_t at)
{
    size_t i = at;
    for (;;) {
        size_t l = 2u * i + 1u, m = i;
        trn_kept_pose_t tmp;
        if (l < len && kept_before(&h[m], &h[l])) {
            m = l;
        }
        if (l + 1u < len && kept_before(&h[m], &h[l + 1u])) {
            m = l + 1u;
        }
        if (m == i) {
            return;
        }
        tmp = h[i];
        h[i] = h[m];
        h[m] = tmp;
        i = m;
    }
}

/* Offer pose (x, y) of score s (at or above keep_cut, or nothing found
 * yet) to keep: it may become the best; it replaces its position's entry
 * if it comes before it, or else is kept if the list has room or it comes
 * before the last kept position. */
static void keep_offer(trn_bb_keep_t *kp, int64_t s, int32_t x, int32_t y)
{
    trn_kept_pose_t e;
    size_t i;
    e.score = s;
    e.x = x;
    e.y = y;
    e.k = kp->k;
    e.rank = kp->rank;
    if (!kp->found || s > kp->best.score ||
        (s == kp->best.score &&
         (kp->rank < kp->best_rank || (kp->rank == kp->best_rank &&
                                       (y < kp->best.y || (y == kp->best.y && x < kp->best.x)))))) {
        kp->best.x = x;
        kp->best.y = y;
        kp->best.score = s;
        kp->best_k = kp->k;
        kp->best_rank = kp->rank;
        kp->found = 1;
    }
    for (i = 0; i < kp->len; ++i) {
        if (kp->list[i].x == x && kp->list[i].y == y) { /* this position: keep the first */
            if (kept_before(&e, &kp->list[i])) {
                kp->list[i] = e;
                keep_sift(kp->list, kp->len, i);
            }
            return;
        }
    }
    if (kp->len < kp->cap) { /* room: sift up */
        i = kp->len++;
        while (i > 0u && kept_before(&kp->list[(i - 1u) / 2u], &e)) {
            kp->list[i] = kp->list[(i - 1u) / 2u];
            i = (i - 1u) / 2u;
        }
        kp->list[i] = e;
    } else if (kept_before(&e, &kp->list[0])) { /* full: replace the last kept */
        kp->list[0] = e;
        keep_sift(kp->list, kp->len, 0u);
    }
}

/* The branch-and-bound search of trn_search_bb; with floor, only poses
 * scoring above *floor count (the search starts as if one had been found
 * with that score, so blocks that cannot beat it are never opened); with
 * keep (floor NULL), blocks are pruned below keep's threshold (keep_cut,
 * rising as poses are offered) and every pose at or above it is offered to
 * keep (trn_search_bb_keep_). */
static trn_status_t bb_run(const trn_pyramid_t *p, const trn_lnp_table_t *t, const trn_point_t *pts,
                           size_t n, const trn_window_t *win, const trn_exclusion_t *ex, void *ws,
                           size_t ws_bytes, const int64_t *floor, trn_bb_keep_t *kp,
                           trn_best_t *best, trn_search_stats_t *stats)
{
    trn_status_t st;
    block_t *tops;
    suffix_t *tops_suf, *stack_suf, *kid_suf;
    block_t *stack; /* in the workspace: keeps the frame under TRN_STACK_LIMIT_BYTES */
    bb_layout_t lay;
    level_view_t L0;
    size_t ntop = 0, i;
    int32_t top_lv, bs, x, y;
    bbox_t bb;
    int found = 0, have_cut;
    int64_t cut; /* with have_cut: blocks and poses below it are pruned */
    uint64_t scored = 0, bounded = 0;

    if (p == NULL || t == NULL || best == NULL || ws == NULL) {
        return TRN_E_NULL;
    }
    if (p->nlevels < 1 || p->nlevels > TRN_MAX_LEVELS || p->cap != t->cap) {
        return TRN_E_ARG;
    }
    if ((st = check_search_args(&p->base, t, pts, n)) != TRN_OK) {
        return st;
    }
    if ((st = check_window(win, ex, p->base.nx, p->base.ny)) != TRN_OK) {
        return st;
    }
    if ((st = trn_ws_check(ws, ws_bytes, trn_search_bb_workspace_bytes(p, win))) != TRN_OK) {
        return st;
    }
    top_lv = p->nlevels;
    bs = (int32_t)(1u << (unsigned)top_lv);
    if (floor != NULL) {
        best->x = INT32_MAX; /* a tie with the floor is no improvement (checked at the end) */
        best->y = INT32_MAX;
        best->score = *floor;
        found = 1;
    }
    have_cut = found;
    cut = found ? best->score : 0;
    if (kp != NULL) {
        have_cut = kp->found;
        cut = kp->found ? keep_cut(kp) : 0;
    }
    (void)bb_carve(p, win, ws, &lay);
    tops = lay.tops;
    tops_suf = lay.tops_suf;
    stack_suf = lay.stack_suf;
    kid_suf = stack_suf + TRN_BB_STACK;
    stack = lay.stack;
    bb = points_bbox(pts, n);
    L0 = pyr_view(p, 0);
    {
        level_view_t L = pyr_view(p, top_lv);
        for (y = win->y0; y <= win->y1; y += bs) {
            for (x = win->x0; x <= win->x1; x += bs) {
                block_t *tb = &tops[ntop];
                if (block_excluded(ex, win, x, y, bs)) {
                    continue;
                }
                ++bounded;
                tb->x = x;
                tb->y = y;
                tb->level = top_lv;
                tb->slot = (int32_t)ntop;
                /* no early exit: every top block is scored whole (before
                 * anything is found there is no bound; with a floor or
                 * keep's threshold, the bench's top blocks all score above
                 * it, 2026-12-02) */
                if (score_chunks(&L, t->lnp, pts, n, &bb, x, y, NULL, cut, &tb->bound,
                                 &tops_suf[ntop])) {
                    ++ntop;
                }
            }
        }
    }
    sort_blocks(tops, ntop);
    for (i = 0; i < ntop; ++i) {
        size_t sp = 0;
        if (have_cut && tops[i].bound < cut) {
            break; /* sorted: no later block can hold a better pose */
        }
        stack_suf[0] = tops_suf[tops[i].slot];
        stack[sp++] = tops[i];
        while (sp > 0u) {
            block_t e = stack[--sp];
            const suffix_t *eup = &stack_suf[sp]; /* e's chunk sums, until kids are pushed */
            block_t kids[4];
            level_view_t Lc;
            size_t nk = 0, a, b;
            int32_t h, cl, k;
            if (have_cut && e.bound < cut) {
                continue;
            }
            h = (int32_t)(1u << (unsigned)(e.level - 1));
            cl = e.level - 1;
            Lc = pyr_view(p, cl);
            for (k = 0; k < 4; ++k) {
                int32_t cx = e.x + ((k & 1) ? h : 0), cy = e.y + ((k & 2) ? h : 0);
                int64_t s;
                if (cx > win->x1 || cy > win->y1) {
                    continue;
                }
                if (cl == 0) {
                    if (excluded(ex, cx, cy)) {
                        continue;
                    }
                    ++scored;
                    if (!score_chunks(&L0, t->lnp, pts, n, &bb, cx, cy, have_cut ? eup : NULL, cut,
                                      &s, NULL)) {
                        continue;
                    }
                    if (kp == NULL) {
                        consider(best, &found, s, cx, cy);
                        have_cut = found;
                        cut = best->score;
                    } else if (!have_cut || s >= cut) {
                        keep_offer(kp, s, cx, cy);
                        have_cut = 1;
                        cut = keep_cut(kp);
                    }
                } else {
                    if (block_excluded(ex, win, cx, cy, h)) {
                        continue;
                    }
                    ++bounded;
                    kids[nk].x = cx;
                    kids[nk].y = cy;
                    kids[nk].level = cl;
                    kids[nk].slot = k;
                    if (score_chunks(&Lc, t->lnp, pts, n, &bb, cx, cy, have_cut ? eup : NULL, cut,
                                     &kids[nk].bound, &kid_suf[k])) {
                        ++nk;
                    }
                }
            }
            /* insertion sort, then push worst first so the best pops next */
            for (a = 1; a < nk; ++a) {
                block_t v = kids[a];
                b = a;
                while (b > 0u && block_before(&v, &kids[b - 1u])) {
                    kids[b] = kids[b - 1u];
                    --b;
                }
                kids[b] = v;
            }
            for (a = nk; a-- > 0u;) {
                stack_suf[sp] = kid_suf[kids[a].slot];
                stack[sp++] = kids[a];
            }
        }
    }
    if (stats != NULL) {
        stats->poses_scored = scored;
        stats->blocks_bounded = bounded;
    }
    if (floor != NULL) {
        return best->score > *floor ? TRN_OK : TRN_E_NODATA;
    }
    if (kp != NULL) {
        return TRN_OK; /* found or not: in keep */
    }
    return found ? TRN_OK : TRN_E_NODATA;
}

trn_status_t trn_search_bb(const trn_pyramid_t *p, const trn_lnp_table_t *t, const trn_point_t *pts,
                           size_t n, const trn_window_t *win, const trn_exclusion_t *ex, void *ws,
                           size_t ws_bytes, trn_best_t *best, trn_search_stats_t *stats)
{
    return bb_run(p, t, pts, n, win, ex, ws, ws_bytes, NULL, NULL, best, stats);
}

trn_status_t trn_search_bb_above(const trn_pyramid_t *p, const trn_lnp_table_t *t,
                                 const trn_point_t *pts, size_t n, const trn_window_t *win,
                                 const trn_exclusion_t *ex, int64_t floor, void *ws,
                                 size_t ws_bytes, trn_best_t *best, trn_search_stats_t *stats)
{
    trn_best_t b;
    trn_status_t st;
    if (best == NULL) {
        return TRN_E_NULL;
    }
    st = bb_run(p, t, pts, n, win, ex, ws, ws_bytes, &floor, NULL, &b, stats);
    if (st == TRN_OK) {
        *best = b;
    }
    return st;
}

trn_status_t trn_search_bb_keep_(const trn_pyramid_t *p, const trn_lnp_table_t *t,
                                 const trn_point_t *pts, size_t n, const trn_window_t *win,
                                 void *ws, size_t ws_bytes, trn_bb_keep_t *keep,
                                 trn_search_stats_t *stats)
{
    trn_best_t b;
    return bb_run(p, t, pts, n, win, NULL, ws, ws_bytes, NULL, keep, &b, stats);
}

/* ------------------------------------------------------------ point order */

trn_status_t trn_points_order(trn_point_t *pts, size_t n, int32_t nz)
{
    /* uint32_t bookkeeping (n <= UINT32_MAX is checked), and count[] reused
     * as each bin's end once the starts are known, keep the frame near
     * 1.2 KiB on every target (TRN_STACK_LIMIT_BYTES). */
    uint32_t count[TRN_MAX_ZBINS], next[TRN_MAX_ZBINS];
    uint32_t *const end = count; /* after the prefix sums: end of each bin */
    uint8_t rank[TRN_MAX_ZBINS];
    uint32_t pos;
    size_t i, moves;
    int32_t a, b, z;

    if (pts == NULL) {
        return TRN_E_NULL;
    }
    if (nz < 1 || nz > TRN_MAX_ZBINS) {
        return TRN_E_ARG;
    }
#if SIZE_MAX > UINT32_MAX
    if (n > (size_t)UINT32_MAX) {
        return TRN_E_SIZE;
    }
#endif
    if (!points_z_ok(pts, n, nz)) {
        return TRN_E_ARG;
    }
    for (z = 0; z < nz; ++z) {
        count[z] = 0u;
        rank[z] = (uint8_t)z;
    }
    for (i = 0; i < n; ++i) {
        ++count[pts[i].z];
    }
    /* bins by increasing population, ties by bin: a stable insertion sort of
     * the bins in increasing order (nz <= 255) */
    for (a = 1; a < nz; ++a) {
        const uint8_t v = rank[a];
        b = a;
        while (b > 0 && count[rank[b - 1]] > count[v]) {
            rank[b] = rank[b - 1];
            --b;
        }
        rank[b] = v;
    }
    pos = 0u;
    for (a = 0; a < nz; ++a) {
        next[rank[a]] = pos;
        pos += count[rank[a]];
        end[rank[a]] = pos; /* overwrites count[rank[a]], read just above */
    }
    /* In-place bucket permutation: every inner step puts one point into its
     * bin's next free slot for good, so there are at most n of them. */
    moves = 0u;
    for (a = 0; a < nz; ++a) {
        const int32_t bin = rank[a];
        while (next[bin] < end[bin] && moves <= n) {
            trn_point_t p = pts[next[bin]];
            while (p.z != bin && moves <= n) {
                const uint32_t slot = next[p.z]++;
                trn_point_t q = pts[slot];
                pts[slot] = p;
                p = q;
                ++moves;
            }
            pts[next[bin]++] = p;
            ++moves;
        }
    }
    return TRN_OK;
}
