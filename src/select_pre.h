/* SPDX-License-Identifier: Apache-2.0 */
/* select_pre.h - internal to the core (not installed): landmark selection
 * from rover-independent map data prepared once, for the ground path of the
 * sensor uncertainty field (trn_field_fast, field.c). The answer of one
 * rover cell is the best uncertainty trn_select gives there, bit for bit:
 *
 *  - the kernel index of eq. 9 depends only on the integer offset of a cell
 *    from the rover cell, so it is tabulated once (joff), and so is the
 *    interval of kernels that can reach a cell and its cone distance;
 *  - eq. 6's trace is linear in the quantized P of the patch (sum q A, A the
 *    trace's 3 x 3 stencil of ln p), and P of a cell lies between P_G
 *    smoothed by the pointwise minimum and maximum of the kernels of its
 *    interval: per interval a map-sized int32 table of each cell's bound of
 *    sum_z q A is built once, and per position one summed-area table of the
 *    cells' bounds gives every candidate a lower bound on its uncertainty;
 *  - candidates are evaluated exactly in rising bound: eq. 9 of a patch cell
 *    gathered from the nonzero P_G voxels with trn_prob_local's products in
 *    its order (so the same floats), its nine C_d cached (exact int64: the
 *    values of trn_select's summed-area tables), the computed cells' exact
 *    sums replacing their bounds in the later candidates' bounds, until the
 *    lowest bound left cannot beat the best found: the same minimum.
 *
 * Memory (trn_selpre_bytes): the P_G nonzeros (8 bytes each), ln p per voxel
 * (4 bytes), the offset tables (8 bytes per offset), 4 bytes per map cell
 * per kernel interval, the build's scratch (40 bytes per map cell), and one
 * position's caches (4 bytes per bin per x-pass cell, 92 per region cell). */
#ifndef TRN_SELECT_PRE_H
#define TRN_SELECT_PRE_H

#include "trn/select.h"

typedef struct {
    int32_t x;
    float v;
} trn_selpre_src_t;

/* One bound table per interval [a, b] of kernel indices. */
typedef struct {
    uint8_t a, b; /* kernels a..b */
} trn_selpre_int_t;

typedef struct {
    const trn_map_t *map;
    const trn_kernels_t *k;
    const trn_select_cfg_t *cfg;
    int32_t nx, ny, nz, half, n, m, rmax, side_w, side_h, src_h;
    int32_t lmax;
    const uint8_t *joff;         /* kernel index by offset, (2m+1)^2, row-major */
    const size_t *rowptr;        /* nz * ny + 1 */
    const trn_selpre_src_t *src; /* nonzero P_G by (z, y) row, ascending x */
    const int32_t *lnpv;         /* lnp[min(D, cap)], index (y * nx + x) * nz + z */
    int32_t *cxy;                /* candidate centres, 2 per candidate */
    size_t ncap;
    int32_t *latlo, *lathi; /* per lattice row: leftmost, rightmost centre */
    int32_t *nlo, *nhi;     /* per region row: columns inside some patch */
    const uint8_t *lok;     /* per lattice offset: range and footprint rules hold */
    const double *latan;    /* per lattice offset: atan2(dy, dx) */
    int full_pan;           /* pan limits are the whole circle: no bearing test */
    /* the pruning (see above) */
    int32_t nint;                 /* kernel intervals with a table */
    const trn_selpre_int_t *ints; /* their kernels */
    const uint8_t *jid;           /* interval of a patch cell by offset, (2m+1)^2 (0 off patches) */
    const int32_t *jnext;  /* per offset: the next column of its table row where jid changes */
    const uint16_t *dcone; /* per offset: the Chebyshev distance eq. 9 reaches it from */
    int32_t rcone;         /* the largest radius in any patch cell's cone (<= rmax) */
    const int32_t *bval;   /* nint tables, ny x nx: each cell's bound of sum_z q A, in
                                    units of 2^bshift rounded up */
    int32_t bshift;
    double bunit;     /* 2^bshift */
    int64_t bunit_i;  /* the same, int64 */
    int refine;       /* 1: computed cells refine the bounds (int64 sums fit) */
    int64_t *bsat;    /* one position's summed-area table of its cells' bounds */
    float *tc;        /* x-pass cache, src_h x side_w cells x nz bins */
    uint32_t *tstamp; /* its stamps (the position's epoch when computed) */
    int64_t *cdc;     /* C_d cache, side_h x side_w cells x 10 (C_d, excess) */
    uint32_t *cstamp; /* its stamps */
    float *pcol;      /* one cell's eq. 9, nz */
    int64_t *esum;    /* one candidate's nine window sums */
    double *ell;      /* and its nine ll */
    double *lb2;      /* per candidate: its lower bound (m^2) */
    int64_t *tbu;     /* its bound's sum (units of 2^bshift) */
    uint32_t *rst;    /* the cells computed when its bound was last formed */
    uint32_t *heap;   /* candidates by rising bound */
    uint32_t *epoch;  /* the position counter */
} trn_selpre_t;

/* Bytes of trn_selpre_init's memory for this map and P_G (0 if invalid). */
size_t trn_selpre_bytes(const trn_select_cfg_t *cfg, const trn_map_t *map, const trn_kernels_t *k,
                        const trn_vol_f32_t *pg);

/* Prepare s (arguments checked as trn_select does; mem 16-byte aligned). */
trn_status_t trn_selpre_init(trn_selpre_t *s, const trn_map_t *map, const trn_kernels_t *k,
                             const trn_vol_f32_t *pg, const trn_select_cfg_t *cfg, void *mem,
                             size_t bytes);

/* Best uncertainty (m) from rover cell (rx, ry), on the map, heading finite:
 * TRN_OK, TRN_E_NOTARGET (as trn_select) or TRN_E_SIZE (int64 bound). */
trn_status_t trn_selpre_best(const trn_selpre_t *s, int32_t rx, int32_t ry, float heading_rad,
                             double *best_m);

/* trn_select's heading-searched prediction (select.h), out of line so that
 * trn_select's own frame, on the deepest stack path, stays as it was: the
 * seven moment sums of a candidate's patch for pose offset d, and the
 * covariance and scalar from them (select.c). */
void trn_sel_moment_sums_(const int64_t *sat, const double *rp1, const double *rp2,
                          const trn_window_t *roi, const trn_window_t *pw, int32_t d, double scale,
                          double q7[7]);
double trn_sel_search_cov_(const trn_peak_t *pk, const double ll[9], const double q7[7],
                           double cell, double sh, double ox, double oy, double cov[3],
                           double *head_m);

#endif /* TRN_SELECT_PRE_H */
