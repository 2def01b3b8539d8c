/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/mapopt.h - the map configuration as command-line options, shared
 * by the commands that prepare a map (docs/method.md section 9).
 *
 * Default (--map-config auto): trn_map_cfg_auto chooses the height bin and
 * the number of bins from the DEM (its cell, the spread of its high-passed
 * heights, the local map's height noise), the local DEM is high-passed
 * against the map (TRN_LOCAL_HP_MAP), the local heights are matched against
 * the map's heights (TRN_MATCH_HEIGHTS) and the pose is refined over heights.
 * --map-config paper: the paper's configuration scaled to the cell (bins and
 * inlier sigma one cell, high-pass half-width ten cells, the local DEM
 * filtered on its own, voxel matching, no refinement), as trn did before. Any option given
 * explicitly overrides either. */
#ifndef TRN_MAPOPT_H
#define TRN_MAPOPT_H

#include <stddef.h>

#include "cli.h"
#include "trn/trn.h"

#define MAPOPT_N 13 /* cli_opt_t entries mapopt_cli writes */

/* The tools' local height noise: 1 cm plus 0.04 % of r^2 / cell (issue 12's
 * sensor model); the help texts print these same macros. */
#define MAPOPT_NOISE_M 0.01
#define MAPOPT_NOISE_K_PER_CELL 0.0004
#define MAPOPT_STR_(x) #x
#define MAPOPT_STR(x) MAPOPT_STR_(x)

typedef struct {
    const char *config;      /* "auto" | "paper" */
    double zbin_m;           /* height bin, metres; 0 = from the configuration */
    long nz;                 /* height bins; 0 = from the configuration */
    double highpass_m;       /* high-pass half-width, metres; 0 = 10 cells */
    double sigma_m;          /* inlier sigma s, metres; 0 = one cell */
    double inlier_prob;      /* a; 0 = 0.95 */
    double noise_m;          /* local height noise, constant part, metres; 0 = 0.01 */
    double noise_k;          /* local height noise, r^2 part, 1/m; < 0 = 0.0004 / cell */
    const char *local_hp;    /* NULL = from the configuration; "box" | "map" */
    long refine;             /* -1 = from the configuration; 0 | 1 */
    long noise_auto;         /* -1 = from the configuration; 0 | 1 */
    const char *match;       /* NULL = from the configuration; "voxel" | "heights" */
    double max_failure_prob; /* acceptance limit; 0 = from the configuration */
} mapopt_t;

/* Defaults (everything from the configuration, --map-config auto). */
void mapopt_init(mapopt_t *m);

/* Write MAPOPT_N option entries for m into out. */
void mapopt_cli(mapopt_t *m, cli_opt_t *out);

/* The map configuration for a DEM of width x height cells of cell_m metres
 * (data: its heights, NaN = unknown). Returns 0, or -1 with a one-line
 * reason in err. sigma_h (may be NULL) gets the DEM's high-passed height
 * spread when the auto configuration ran (else NaN). */
int mapopt_config(const mapopt_t *m, const float *data, int width, int height, double cell_m,
                  trn_map_cfg_t *cfg, double *sigma_h, char *err, size_t err_len);

/* What a command does with the map: which of the options above apply.
 *   MAPOPT_USE_LOCALIZE      trn localize: a local DEM matched by either matcher
 *                            (every option, each where that matcher reads it);
 *   MAPOPT_USE_EXPERIMENT    trn experiment: the map for the selection, and
 *                            either matcher on simulated local maps: with the
 *                            voxel matcher sampled points and the voxel search
 *                            alone (no refinement, no acceptance); with the
 *                            height matcher trn_localize_dem on height grids
 *                            (its noise model, noise rescale and acceptance
 *                            limit; never the local filter) and the height
 *                            prediction for the selection;
 *   MAPOPT_USE_PREDICT       trn select, trn field: the prediction of the
 *                            matcher the configuration resolves to (--match:
 *                            heights or voxel), no localization. */
typedef enum { MAPOPT_USE_LOCALIZE, MAPOPT_USE_EXPERIMENT, MAPOPT_USE_PREDICT } mapopt_use_t;

/* 1 if the configuration resolves to the height matcher (--match, else
 * --map-config auto). */
int mapopt_heights(const mapopt_t *m);

/* The options a command of this use never reads (NULL-terminated names):
 * they are left out of its table (cli_remove), so its --help does not offer
 * them and cli_parse refuses them as unknown. */
const char *const *mapopt_not_taken(mapopt_use_t use);

/* After cli_parse: 0 if every map option given on the command line applies
 * to use under the configuration it resolves to (--map-config, --match,
 * --refine), else -1 with the one-line reason in err (a usage error: the
 * command exits CLI_USAGE). An option that would change nothing is refused,
 * never silently ignored: with the height matcher in trn localize the voxel
 * map's --zbin-m, --nz, --highpass-m, --sigma-m, --local-highpass and
 * --refine (in the experiment the voxel map shapes the selection); with the
 * voxel matcher --noise-auto, and --noise-m / --noise-k unless --refine 1 or
 * the auto configuration's bins read them; in the experiment with the voxel
 * matcher also --max-failure-prob (its voxel search has no acceptance test).
 * Values that are not one of the choices pass here and are refused by
 * mapopt_config as before. */
int mapopt_check_use(const mapopt_t *m, mapopt_use_t use, char *err, size_t err_len);

/* 1 if the options resolve to the height matcher (--match heights, or
 * --map-config auto without --match), else 0. */
int mapopt_heights(const mapopt_t *m);

/* Write the configuration as the JSON object "map_config". */
void mapopt_json(json_t *j, const trn_map_cfg_t *cfg);

#endif /* TRN_MAPOPT_H */
