/* SPDX-License-Identifier: Apache-2.0 */
/* likelihood_int.h - the branch-and-bound search that keeps every pose
 * near the best (src/likelihood.c), internal to the core: the search over
 * (x, y, heading) of src/heading.c finds its best pose and its competitor
 * in one pass with it. */
#ifndef TRN_LIKELIHOOD_INT_H
#define TRN_LIKELIHOOD_INT_H

#include "trn/likelihood.h"

/* A pose kept: score, pose, heading tag and its tie rank. */
typedef struct {
    int64_t score;
    int32_t x, y, k, rank;
} trn_kept_pose_t;

/* The state of a search over several point sets (headings), carried from
 * one call of trn_search_bb_keep_ to the next. Poses are ordered by score,
 * then lower tie rank, then smaller y, then smaller x. `best` is the first
 * of every pose searched. `list` keeps positions (x, y), each with the
 * first pose offered there: the first `cap` positions of the poses offered
 * (a min-heap: list[0] is the last kept). Poses are offered when they
 * score at least the threshold: best - margin, or list[0]'s score once the
 * list is full if that is higher. So a pose not kept comes after a kept
 * pose at its position, or after every pose kept, or scores below
 * (final best - margin). */
typedef struct {
    int64_t margin;        /* >= 0 */
    int found;             /* best is set */
    trn_best_t best;       /* the best so far */
    int32_t best_k;        /* its heading tag */
    int32_t best_rank;     /* its tie rank */
    int32_t k, rank;       /* the point set being searched: tag and tie rank */
    trn_kept_pose_t *list; /* cap > 0 entries, len used */
    size_t cap, len;
} trn_bb_keep_t;

/* trn_search_bb over the window (no exclusion) with the points of tag
 * keep->k: blocks are pruned below keep's threshold (carried from earlier
 * calls), every pose at or above it is offered to keep (not NULL). Statuses as
 * trn_search_bb's argument checks (TRN_OK otherwise; found or not is in
 * keep). */
trn_status_t trn_search_bb_keep_(const trn_pyramid_t *p, const trn_lnp_table_t *t,
                                 const trn_point_t *pts, size_t n, const trn_window_t *win,
                                 void *ws, size_t ws_bytes, trn_bb_keep_t *keep,
                                 trn_search_stats_t *stats);

#endif /* TRN_LIKELIHOOD_INT_H */
