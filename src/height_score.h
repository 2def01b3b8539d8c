/* SPDX-License-Identifier: Apache-2.0 */
/* height_score.h - the height matcher's score of one integer pose, one copy
 * for every search that scores poses from a workspace: the search over
 * heading (trn_height_search_heading; trn_localize_dem's is its case of one
 * heading) and the bounded search (height_bound.c).
 * Internal (docs/method.md 9.3, "The pose score").
 *
 * The model is trn_height_search's (trn/refine.h): over the seen local cells
 * i, ln L = sum ln(a N(r_i - dz; k2 v_i + m2) + (1 - a) k), r_i = h_i - g_i
 * the local height less the map's under it, dz, m2 >= 0 and (with the
 * configuration's fit_noise, else k2 = 1) the noise scale k2 fitted by
 * weighted moments (all points at k2 = 1, m2 = 0, all points at that fit,
 * then within TRN_REFINE_CLIP sds while a pass drops more than 1 % of them;
 * trn_var_fit_ in refine_int.h), a cell off
 * the map or over a missing map cell scoring ln((1 - a) k). trn_height_search,
 * which has no workspace, scores the same model straight from the grids: it is
 * the obvious reference the tests hold this to (within rounding).
 *
 * What makes this one fast: the seen cells are gathered once per search and
 * ordered by their distance from the rover, so that the cells of one
 * distance, which share one noise variance (a noise class: 457 for a 64 x 64
 * local map), are one run; a pass over the cells sums per class a count,
 * the residuals and their squares, comparing squares in the clip (no
 * square root; one comparison keeps out the cells off the map), and a fit
 * from those sums takes one division a class; the two fits over every
 * point share one pass, since their variances change the weights, not
 * which points count; ln L takes one exp a cell and one log per some
 * hundred cells (the log of running products). The map's heights under the
 * cells are read once per pose into one array of residuals, without bounds
 * checks where the whole local map lies on the map. */
#ifndef TRN_HEIGHT_SCORE_H
#define TRN_HEIGHT_SCORE_H

#include <stddef.h>
#include <stdint.h>

#include "trn/grid.h"
#include "trn/refine.h"

typedef struct {
    const trn_grid_f32_t *g; /* the map */
    double *h;               /* seen local cells, nearest the rover first: height */
    double *r;               /* per pose: residual h - map height, NaN where none */
    int32_t *ox, *oy;        /* offset of each seen cell from the rover cell */
    int32_t *tx, *ty;        /* the offsets turned to the heading scored */
    int64_t *off;            /* ty * stride + tx */
    double *cv;              /* per noise class (one distance from the rover): variance */
    double *c1, *c2;         /* per class, the last pass: the kept residuals' sum less the
                              * first residual, and the sum of their squares */
    int32_t *ck;             /* ... and their count */
    int32_t *cs;             /* class c's cells: cs[c] .. cs[c + 1] - 1 */
    int32_t nc;              /* noise classes */
    size_t n;                /* seen cells */
    int32_t x0, x1, y0, y1;  /* extent of (tx, ty) */
    double a, k, b, lout;    /* inlier probability, outlier density, (1 - a) k, ln b */
    double k2;               /* the noise scale (variance factor) of the last pose scored */
    int32_t fitk;            /* 1: the score fits the noise scale (trn_refine_cfg_t.fit_noise) */
} trn_hs_t;

/* Workspace bytes for a local map of lw x lh cells (1..TRN_MAX_DIM each;
 * 0 outside). */
size_t trn_hs_bytes(int32_t lw, int32_t lh);

/* Carves s's arrays from ws (trn_hs_bytes of local's size), gathers local's
 * seen cells with their noise variances (cfg's model around rover cell
 * (rx, ry)), turns them to heading 0 and sets the outlier density k from
 * their spread (trn_height_search's). Returns the seen cells' count (the
 * caller's NODATA rule). Arguments are the caller's to check. */
size_t trn_hs_init(trn_hs_t *s, void *ws, const trn_grid_f32_t *global, const trn_grid_f32_t *local,
                   int32_t rx, int32_t ry, const trn_refine_cfg_t *cfg, double inlier_prob);

/* Turns the offsets by the heading whose cosine and sine are c, sn, rounded
 * to the cell (trn_points_rotate's rounding); c = 1, sn = 0 gives the
 * offsets themselves. */
void trn_hs_turn(trn_hs_t *s, double c, double sn);

/* ln L of integer pose (px, py) (the rover cell on map cell (px, py)), its
 * fitted offset dz (metres) and model sd (metres); its noise scale in
 * s->k2. */
double trn_hs_ll(trn_hs_t *s, int32_t px, int32_t py, double *dz, double *model_m);

#endif
