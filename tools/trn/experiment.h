/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/experiment.h - the paper's section 5 Monte Carlo (`trn experiment`):
 * localization success and accuracy with and without landmark selection on a
 * synthetic Golombek & Rapp terrain (docs/method.md section 8 states every
 * decision and its reason).
 *
 * One trial:
 *  1. Rover start S and finish F: cells uniform over the map. The rover is at
 *     F. Its prior P = F + an offset uniform in +-prior_error_m per axis
 *     (whole cells). Heading: the direction S -> P (irrelevant with full pan).
 *  2. Fixed targets ("without selection"): the cell midway between S and P
 *     and the eight around it on a square grid of grid_spacing_m. The pair
 *     (S, F) and the offset are redrawn until all nine are targets the
 *     selection itself could choose from P (range, footprint, patch inside the
 *     map) and their sensed patches (below) lie inside the map.
 *  3. With selection: trn_select from the prior P; its best target.
 *  4. Sensing a target T: the rover aims from where it believes it is, so the
 *     patch actually sensed is centred on T + (F - P). The local map is drawn
 *     from the probability map of that patch seen from the true F (eq. 8 once,
 *     eq. 9 for the patch, trn_prob_local): voxel v occupied with probability
 *     min(P(v), 1), independently. Points are relative to F's cell.
 *  5. trn_localize_points in the window P +- window_m; error = distance from
 *     the subpixel estimate to F (metres); success = error <= success_cells.
 *
 * With the height matcher (the map configuration's match is
 * TRN_MATCH_HEIGHTS) steps 4-5 are instead: the local map is a height grid
 * over the sensed patch, the DEM's true heights plus Gaussian noise of sd
 * noise_m + noise_k_per_m r^2 (r metres from F; the configuration's noise
 * model, the one the matcher assumes), one normal per cell from the trial's
 * stream; trn_localize_dem localizes it in the same window (selection and
 * the trials' draws as above). Its status is counted too (fixes, ambiguous).
 *
 * Without selection every one of the nine targets is a localization of its
 * own (9 per trial); its confidence intervals account for the nine sharing a
 * trial (effective sample size / cluster-robust variance, see exp_arm_t).
 *
 * Determinism: each trial has its own splitmix64 stream derived from (seed,
 * trial index); the terrain is `trn terrain`'s for (coverage, terrain_seed). */
#ifndef TRN_TOOLS_EXPERIMENT_H
#define TRN_TOOLS_EXPERIMENT_H

#include <stddef.h>
#include <stdint.h>

#include "trn/trn.h"

/* ---- seeded random numbers (splitmix64) ------------------------------- */
typedef struct {
    uint64_t s;
} exp_rng_t;

/* Stream of trial `index` of a run seeded with `seed`. */
void exp_rng_seed(exp_rng_t *r, uint64_t seed, uint64_t index);
uint64_t exp_rng_u64(exp_rng_t *r);
double exp_rng_unit(exp_rng_t *r);                  /* [0, 1), 53 bits */
long exp_rng_range(exp_rng_t *r, long lo, long hi); /* integer in [lo, hi] */

/* ---- the sensor model: a local map sampled from a probability map ------ */
/* p: w x h x nz voxels, p[(z*h + y)*w + x]. Voxel (x, y, z) becomes the point
 * (x + off_x, y + off_y, z) with probability min(p, 1) (p <= 0 or NaN: never).
 * One uniform is drawn per voxel, in storage order. Returns the number of
 * points; at most cap are written (the count goes on past cap). */
size_t exp_sample_points(const float *p, int w, int h, int nz, int off_x, int off_y, exp_rng_t *r,
                         trn_point_t *pts, size_t cap);

/* ---- interval statistics ----------------------------------------------- */
#define EXP_Z95 1.959963984540054 /* two-sided 95 % normal quantile */

/* Wilson score interval of a proportion: k successes of n (n may be an
 * effective, non-integer size > 0), normal quantile z. */
void exp_wilson(double k, double n, double z, double ci[2]);

/* P(|T| <= t) for Student's t with integer df >= 1 (closed-form series). */
double exp_t_abs_cdf(double t, long df);

/* Two-sided quantile: t with P(|T| <= t) = conf (0 < conf < 1), df >= 1. */
double exp_t_quantile(double conf, long df);

/* Success rate and mean error of clustered data: cluster i has m[i] units,
 * k[i] successes and e[i] = sum of the successes' errors. Fills
 *  rate        sum k / sum m
 *  rate_ci     Wilson with the effective size n_eff = rate (1 - rate) / var,
 *              var = the between-cluster variance of the rate (ratio
 *              estimator, linearized); n_eff = sum m when var = 0 or the rate
 *              is 0 or 1, capped at sum m. With one unit per cluster this is
 *              the plain Wilson interval on n = number of clusters.
 *  mean        sum e / sum k (NaN if no success)
 *  mean_ci     mean +- t(df) * se: one unit per cluster -> se = s / sqrt(k),
 *              df = k - 1 (the plain t interval); otherwise se from the
 *              linearized between-cluster variance, df = clusters with a
 *              success - 1. NaN when df < 1. */
typedef struct {
    double rate, rate_ci[2], n_eff;
    double mean, mean_ci[2], sd;
} exp_stats_t;

void exp_cluster_stats(const long *m, const long *k, const double *e, const double *e2,
                       long n_clusters, exp_stats_t *out);

/* ---- the experiment ---------------------------------------------------- */
typedef struct {
    int size_cells;        /* terrain side, cells (default 256) */
    double cell_m;         /* 0.1 */
    double coverage_k;     /* rock coverage k (0.1) */
    uint64_t terrain_seed; /* `trn terrain --seed` (1) */
    double d_min_m;        /* smallest rock drawn, m (0: 2 cells, as `trn terrain`) */
    double relief_m;       /* RMS of the smooth background relief (0.05, as `trn terrain`) */
    long trials;           /* 1000 */
    uint64_t seed;         /* trial streams (1) */
    double window_m;       /* prior window half-width per axis (2.0) */
    double prior_error_m;  /* prior offset bound per axis (1.0) */
    double grid_spacing_m; /* spacing of the nine fixed targets (2.0 = one patch) */
    double success_cells;  /* success radius, cells (2.0) */
    int sensor;            /* EXP_SENSOR_PROB (the paper's) or EXP_SENSOR_DEM (diagnostic) */
    double height_noise_m; /* EXP_SENSOR_DEM: per-cell Gaussian height noise, m (0) */
    /* A given DEM instead of the generated terrain (NULL: generate). Not
   * copied into the result; read during exp_run only. width x height cells of
   * cell_m, north-up rows, NaN = no data (a sensed patch or the finish never
   * lies on one). */
    const float *dem;
    int dem_width, dem_height;
    /* The map configuration: NULL = the paper's scaled to the cell (bins and s
   * one cell, high-pass 10 cells); else called once with the DEM. Its match
   * picks the localizer: TRN_MATCH_HEIGHTS the height matcher (above; then
   * the sensor must be EXP_SENSOR_PROB's default and no heading error), else
   * the voxel search. */
    int (*map_cfg)(void *ctx, const float *dem, int width, int height, double cell_m,
                   trn_map_cfg_t *cfg, char *err, size_t err_len);
    void *map_cfg_ctx;
    /* Ranges in metres; 0 (footprint: < 0) = trn_select_cfg_default's, scaled
   * by cell_m / 0.1 (the same cells as the paper's 0.1 m: 10-100 cells, a
   * 21-cell patch, a 5-cell footprint). The local error model (eq. 9) and the
   * default global one (eq. 8) scale likewise: constant x f, r^2 term / f
   * (eq. 8's r^2 term is 0 on a DEM: experiment.c world_prob). */
    double min_range_m, max_range_m, patch_m, footprint_m;
    double global_sigma_m,
        global_sigma_k;        /* eq. 8 model; < 0: default (scaled; no r^2 term on a DEM) */
    const float *global_error; /* per-cell eq. 8 sigma, m, the DEM's grid (NaN: model) or NULL */
    /* Heading error (issue 14): each trial's local maps are turned about the
     * rover by an error drawn N(0, heading_error_deg) before matching; besides
     * the x-y search (the paper's, the arms with / without), the 3-DOF search
     * trn_localize_points_heading over +-heading_window_deg (0: 3 x the error,
     * at most TRN_HEADING_MAX_WINDOW_RAD) localizes the same points (arms
     * with3 / without3). 0 (the default): no error, no 3-DOF arms; the
     * paper's experiment bit for bit. The 3-DOF arm with selection ranks its
     * own target with trn_select_cfg_t.heading_search = select_heading_search
     * (1, the default: the selection that knows the heading is searched,
     * sensed from the trial's random state before the x-y arm's sensing, so
     * the same target gives the same points; 0: the x-y arm's target). */
    double heading_error_deg, heading_window_deg;
    long select_heading_search;
} exp_params_t;

/* Sensor models. PROB: the paper's, voxels sampled from the probability map
 * (eq. 9 of the patch). DEM (diagnostic, not the paper's): the true DEM over
 * the patch grown by the high-pass half-width, plus independent Gaussian
 * height noise per cell, high-passed and turned into occupancy on its own
 * (trn_highpass, trn_occupancy_points); the points inside the patch are the
 * local map. No horizontal error. */
#define EXP_SENSOR_PROB 0
#define EXP_SENSOR_DEM 1

void exp_params_default(exp_params_t *p);
/* NULL if valid, else a one-line reason. */
const char *exp_params_check(const exp_params_t *p);

/* One strategy's results. */
typedef struct {
    long localizations; /* trials (with) or 9 x trials (without) */
    long successes;
    long no_target;       /* trn_select found no informative target (counted as failures) */
    long no_points;       /* a sampled local map came out empty (failures) */
    long ill_conditioned; /* localizations whose eq. 6 fit failed (integer pose used); the
                             height matcher: status TRN_E_ILLCOND (the window's edge, a
                             misfit or a failed refinement; its pose is used) */
    long fixes;           /* the height matcher: status TRN_OK (accepted answers) */
    long wrong_fixes;     /* ... of those, the ones beyond the success radius */
    long ambiguous;       /* ... status TRN_E_AMBIGUOUS (failure probability above the limit) */
    long noise_rescaled;  /* ... answers whose noise model the residuals rescaled (noise_auto) */
    long success_1cell, success_5cells; /* sensitivity of the threshold */
    exp_stats_t st;
    double mean_points;  /* sampled local voxels per localization */
    double mean_range_m; /* rover-target distance */
} exp_arm_t;

typedef struct {
    exp_arm_t with, without;
    exp_arm_t with3, without3; /* the 3-DOF search on the same points (heading_error_deg > 0;
                                  with3: its own selection's target, select_heading_search) */
    long with3_other_target;   /* trials whose 3-DOF arm sensed another target than the x-y arm */
    double heading_window_deg; /* the 3-DOF search's half-window used (0 without a heading error) */
    size_t rocks;
    double d_min_m;         /* smallest rock drawn */
    long draws;             /* (S, F, offset) draws, accepted ones included */
    double mean_traverse_m; /* |S - F| of the accepted trials */
    int patch_cells, grid_cells, window_cells, prior_cells;
    double success_radius_m;
    int heights;                    /* 1: localized with the height matcher (map_cfg.match) */
    trn_map_cfg_t map_cfg;          /* the map configuration used */
    trn_sigma_model_t global_sigma; /* eq. 8's model used (raster aside) */
    trn_select_cfg_t scfg;          /* the selection rules used (ranges in metres) */
} exp_result_t;

/* Progress and cancel callback: trials done of total, after every trial;
 * a nonzero return stops the run (exp_run returns -1, err says cancelled). */
typedef int (*exp_progress_fn)(void *ctx, long done, long total);

/* Run the experiment. Returns 0, or -1 with a one-line reason in err
 * (also when the progress callback cancelled it). */
int exp_run(const exp_params_t *p, exp_result_t *out, exp_progress_fn progress, void *ctx,
            char *err, size_t err_len);

#endif /* TRN_TOOLS_EXPERIMENT_H */
