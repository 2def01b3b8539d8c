/* SPDX-License-Identifier: Apache-2.0 */
/* height_bound.h - internal: the height matcher's bounded search over
 * (x, y) (src/height_bound.c; docs/method.md 9.3, "The bounded search").
 *
 * The ln L grid of the window is filled lazily: a pose is scored exactly
 * (trn_refine_pose_ll_, the exhaustive search's value bit for bit) only
 * where an upper bound over a block of poses cannot rule it out. Every
 * other pose holds -inf in the grid and its block's bound in the tree, so
 * the consumers of the exhaustive grid (the second starts, the far basins,
 * the zones' masses, the competitor) read the same values wherever their
 * answer depends on them. */
#ifndef TRN_HEIGHT_BOUND_H
#define TRN_HEIGHT_BOUND_H

#include <stddef.h>
#include <stdint.h>

#include "trn/localize.h"
#include "trn/refine.h"

#include "height_score.h"

/* Most noise classes, m2 classes and distance steps of the bound. */
#define TRN_HB_MAX_Q 8
#define TRN_HB_MAX_C 40
#define TRN_HB_MAX_J 64
/* Most height-offset bins. */
#define TRN_HB_MAX_BINS 4096
/* Deepest pose tree: 2^(TRN_HB_MAX_LEVELS - 1) >= TRN_MAX_DIM. */
#define TRN_HB_MAX_LEVELS 15

/* The state of one bounded search (lives in the caller's workspace). */
typedef struct {
    const trn_grid_f32_t *global, *local;
    int32_t rx, ry;
    trn_window_t win;
    trn_refine_cfg_t cfg;
    double a, k, lout, tol;
    int32_t ww, wh;                /* window size, poses */
    int32_t levels;                /* tree levels 0..levels-1; 2^(levels-1) >= ww, wh */
    int32_t leaf;                  /* nodes of this level or finer: scored pose by pose */
    int32_t rw, rh;                /* region of map anchors: 2^(levels-1) + local size */
    double *ll;                    /* ww x wh: exact ln L where done, -inf elsewhere */
    double *dz, *msd;              /* ww x wh: the pose fit's offset and model sd where done */
    uint8_t *done;                 /* ww x wh: 1 scored */
    double *ub[TRN_HB_MAX_LEVELS]; /* per level: block bounds, NaN = not computed */
    float *mn[TRN_HB_MAX_LEVELS];  /* per level: the map's least height over the square */
    float *mx[TRN_HB_MAX_LEVELS];  /* ... and its greatest (mn > mx: none finite) */
    uint8_t *cls;                  /* local cells: noise class, 255 unseen */
    trn_hs_t hs;                   /* the pose score (height_score.c) */
    uint32_t *cl, *ch;             /* TRN_HB_MAX_Q x bins: counts of low / high ends */
    int32_t *cnt;                  /* TRN_HB_MAX_Q x TRN_HB_MAX_J */
    int32_t *stack;                /* the tree walk's nodes, 3 ints each */
    int32_t *rstack;               /* the offset walk's ranges, 2 ints each */
    double *df;                    /* [q][c][j]: F(t_j) - F(t_j+1) */
    double *ft;                    /* [q][c]: F at the last step */
    int32_t steps[TRN_HB_MAX_Q][TRN_HB_MAX_J + 1]; /* t_j in bins, rounded up */
    int32_t nq, nc, nj[TRN_HB_MAX_Q];
    int32_t npts[TRN_HB_MAX_Q];
    double z0, w; /* the offsets' bins: z0 + b w */
    int32_t nbins;
    uint64_t evals, bounds; /* this search's work */
    uint64_t *work;         /* the localization's work (node budget), shared */
    uint64_t budget;        /* 0: none */
} trn_hb_t;

/* Bytes of trn_hb_init's workspace for this window and local map (0 if out
 * of range). */
size_t trn_hb_bytes(const trn_window_t *win, int32_t local_w, int32_t local_h);

/* Lay the state out in ws (trn_hb_bytes of it; *out points into it) and prepare the bound for the
 * noise model cfg: the map's extremes over squares of poses, the noise and
 * model-variance classes, the offset bins. ll_grid: the window's ln L grid
 * (ww x wh doubles, set to -inf). work and budget: the node budget's
 * counter (shared over the localization) and limit (0: none). TRN_OK;
 * TRN_E_NODATA (fewer than 8 seen local cells: the exhaustive search's
 * answer too). */
trn_status_t trn_hb_init(trn_hb_t **out, void *ws, const trn_grid_f32_t *global,
                         const trn_grid_f32_t *local, int32_t rx, int32_t ry,
                         const trn_window_t *win, const trn_refine_cfg_t *cfg, float inlier_prob,
                         double *ll_grid, uint64_t *work, uint64_t budget);

/* Score pose (x, y) of the window if not done yet. TRN_OK or TRN_E_BUDGET. */
trn_status_t trn_hb_eval(trn_hb_t *hb, int32_t x, int32_t y);

/* Score every pose of the window within Chebyshev radius of (cx, cy). */
trn_status_t trn_hb_eval_zone(trn_hb_t *hb, int32_t cx, int32_t cy, int32_t radius);

/* The highest pose of the window (ties: scan order), as the exhaustive
 * search's best: x, y, ll, dz_m, model_m (poses: scored so far). Outside the
 * zone ex when ex is not NULL (the competitor). TRN_OK, TRN_E_NODATA (no
 * pose outside the zone), TRN_E_BUDGET. */
trn_status_t trn_hb_best(trn_hb_t *hb, const trn_exclusion_t *ex, trn_height_best_t *best);

/* Score every pose outside the zone ex (NULL: none) whose bound is at least
 * t. */
trn_status_t trn_hb_resolve(trn_hb_t *hb, double t, const trn_exclusion_t *ex);

/* The exhaustive far basins (trn_loc_find_basins3_'s, over the grid) among
 * the local maxima outside the zone of (bx, by, radius) with ln L of at
 * least t: every pose that could be one, or a neighbour above one, is
 * scored, so that trn_loc_find_basins3_ on the grid then finds them. */
trn_status_t trn_hb_basins(trn_hb_t *hb, double t, int32_t bx, int32_t by, int32_t radius,
                           int32_t nbasins);

/* ln of the posterior mass (ln L over infl) of the window and of its part
 * outside the zone ex, the scored poses' exact and the others' bounded:
 * every pose whose bound could add more than eps / poses of the scored mass
 * is scored first; *err is then an upper bound on the absolute error of
 * exp(lse_out - lse_all) (conservative: the unscored mass counted outside
 * the zone, in both). */
trn_status_t trn_hb_mass(trn_hb_t *hb, const trn_exclusion_t *ex, double infl, double eps,
                         double *lse_all, double *lse_out, double *err);

#endif /* TRN_HEIGHT_BOUND_H */
