/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/mapopt.c - the map configuration as options (mapopt.h). */
#include "mapopt.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void mapopt_init(mapopt_t *m)
{
    m->config = "auto";
    m->zbin_m = 0.0;
    m->nz = 0;
    m->highpass_m = 0.0;
    m->sigma_m = 0.0;
    m->inlier_prob = 0.0;
    m->noise_m = 0.0;
    m->noise_k = -1.0;
    m->local_hp = NULL;
    m->refine = -1;
    m->noise_auto = -1;
    m->match = NULL;
    m->max_failure_prob = 0.0;
}

void mapopt_cli(mapopt_t *m, cli_opt_t *o)
{
    const cli_opt_t t[MAPOPT_N] = {
        {"--map-config", CLI_STRING, &m->config, 0, 0, 0, "auto|paper",
         "map configuration: auto (from the DEM, docs/method.md 9; default) or paper (as in the "
         "paper, scaled to the cell)",
         0},
        {"--zbin-m", CLI_DOUBLE, &m->zbin_m, 1e-6, (double)TRN_CELL_MAX_M, 0, "M",
         "height bin, metres (default: from --map-config)", 0},
        {"--nz", CLI_LONG, &m->nz, 1, TRN_MAX_ZBINS, 0, "N",
         "number of height bins (default: from --map-config)", 0},
        {"--highpass-m", CLI_DOUBLE, &m->highpass_m, 1e-6, 1e6, 0, "M",
         "high-pass half-width, metres (default " MAPOPT_STR(TRN_MAP_HIGHPASS_CELLS) " cells)", 0},
        {"--sigma-m", CLI_DOUBLE, &m->sigma_m, 1e-6, (double)TRN_CELL_MAX_M, 0, "M",
         "inlier standard deviation s, metres (default one cell)", 0},
        {"--inlier-prob", CLI_DOUBLE, &m->inlier_prob, 0.01, 0.99, 0, "A",
         "inlier probability a (default " MAPOPT_STR(TRN_MAP_INLIER_PROB_DEFAULT) ")", 0},
        {"--noise-m", CLI_DOUBLE, &m->noise_m, 1e-6, 1000.0, 0, "M",
         "local map height noise, constant part, metres (default " MAPOPT_STR(MAPOPT_NOISE_M) ")",
         0},
        {"--noise-k", CLI_DOUBLE, &m->noise_k, 0.0, 1000.0, 0, "K",
         "local map height noise, range-squared part, 1/m (default " MAPOPT_STR(
             MAPOPT_NOISE_K_PER_CELL) "/cell)",
         0},
        {"--local-highpass", CLI_STRING, &m->local_hp, 0, 0, 0, "box|map",
         "local DEM filter: box (its own, the paper) or map (the map's low-pass; auto) (default: "
         "--map-config's)",
         0},
        {"--refine", CLI_LONG, &m->refine, 0, 1, 0, "0|1",
         "refine the pose over heights (default 1 with auto, 0 with paper)", 0},
        {"--noise-auto", CLI_LONG, &m->noise_auto, 0, 1, 0, "0|1",
         "height matcher: fit the noise model's scale per pose in the search, and refine with "
         "it rescaled when the residuals reject it (default 1 with auto, 0 with paper)",
         0},
        {"--match", CLI_STRING, &m->match, 0, 0, 0, "voxel|heights",
         "the matcher (localized with, or predicted): voxel occupancy (paper) or heights (auto) "
         "(default: "
         "--map-config's)",
         0},
        {"--max-failure-prob", CLI_DOUBLE, &m->max_failure_prob, 1e-6, 1.0, 0, "P",
         "acceptance limit: localize's answer is 'ambiguous', not a fix, when its failure "
         "probability is above P (default " MAPOPT_STR(
             TRN_MAP_MAX_FAILURE_PROB_AUTO) " with auto, 1 = never with paper)",
         0},
    };
    memcpy(o, t, sizeof t);
}

const char *const *mapopt_not_taken(mapopt_use_t use)
{
    /* the local filter and the voxel refinement: read only where trn_localize_dem
     * matches a local DEM's voxels; the noise rescale and the acceptance limit:
     * only by trn_localize_dem */
    static const char *const k_exp[] = {"--local-highpass", "--refine", NULL};
    static const char *const k_pred[] = {"--local-highpass", "--refine", "--noise-auto",
                                         "--max-failure-prob", NULL};
    static const char *const k_none[] = {NULL};
    return use == MAPOPT_USE_PREDICT ? k_pred : use == MAPOPT_USE_EXPERIMENT ? k_exp : k_none;
}

int mapopt_heights(const mapopt_t *m)
{
    return m->match != NULL ? strcmp(m->match, "heights") == 0 : strcmp(m->config, "auto") == 0;
}

int mapopt_check_use(const mapopt_t *m, mapopt_use_t use, char *err, size_t err_len)
{
    const char *voxel_only = NULL;
    int auto_cfg, heights, refine, auto_bins;
    if ((strcmp(m->config, "auto") != 0 && strcmp(m->config, "paper") != 0) ||
        (m->match != NULL && strcmp(m->match, "voxel") != 0 && strcmp(m->match, "heights") != 0) ||
        (m->local_hp != NULL && strcmp(m->local_hp, "box") != 0 &&
         strcmp(m->local_hp, "map") != 0)) {
        return 0; /* not a choice: mapopt_config says so (bad input) */
    }
    auto_cfg = strcmp(m->config, "auto") == 0;
    heights = mapopt_heights(m);
    refine = m->refine >= 0 ? m->refine != 0 : auto_cfg;
    /* the auto configuration's height bin and bin count come from the noise model */
    auto_bins = auto_cfg && !(m->zbin_m > 0.0 && m->nz > 0);
    /* with the height matcher the selection predicts it too (trn_select on a
     * map that matches heights): the voxel map's options are refused below,
     * as trn localize's */
    if (use != MAPOPT_USE_LOCALIZE && !heights) {
        if (use == MAPOPT_USE_EXPERIMENT && (m->noise_auto >= 0 || m->max_failure_prob > 0.0)) {
            snprintf(err, err_len,
                     "%s applies to the height matcher (--match heights); the experiment's voxel "
                     "search has neither a noise rescale nor an acceptance test",
                     m->noise_auto >= 0 ? "--noise-auto" : "--max-failure-prob");
            return -1;
        }
        if ((m->noise_m > 0.0 || m->noise_k >= 0.0) && !auto_bins) {
            snprintf(err, err_len,
                     "%s: the local noise model only sets the height bins of --map-config auto "
                     "(without both --zbin-m and --nz) here; it changes nothing else",
                     m->noise_m > 0.0 ? "--noise-m" : "--noise-k");
            return -1;
        }
        return 0;
    }
    if (heights) {
        voxel_only = m->zbin_m > 0.0       ? "--zbin-m"
                     : m->nz > 0           ? "--nz"
                     : m->highpass_m > 0.0 ? "--highpass-m"
                     : m->sigma_m > 0.0    ? "--sigma-m"
                     : m->local_hp != NULL ? "--local-highpass"
                     : m->refine >= 0      ? "--refine"
                                           : NULL;
        if (voxel_only != NULL) {
            snprintf(err, err_len,
                     "%s applies to the voxel matcher (--match voxel, or --map-config paper); the "
                     "height matcher %s",
                     voxel_only,
                     use == MAPOPT_USE_LOCALIZE ? "matches the DEM's heights and always refines"
                                                : "and its prediction read the DEM's heights");
            return -1;
        }
        return 0;
    }
    if (m->noise_auto >= 0) {
        snprintf(err, err_len,
                 "--noise-auto applies to the height matcher (--match heights); the voxel matcher "
                 "keeps the configured noise model (also with --refine 1)");
        return -1;
    }
    if ((m->noise_m > 0.0 || m->noise_k >= 0.0) && !refine && !auto_bins) {
        snprintf(err, err_len,
                 "%s: the voxel matcher reads the local noise model only in its refinement "
                 "(--refine 1) or for the auto configuration's height bins",
                 m->noise_m > 0.0 ? "--noise-m" : "--noise-k");
        return -1;
    }
    return 0;
}

static void *alloc16(size_t n, void **raw)
{
    uint8_t *p = malloc(n + 16u);
    *raw = p;
    if (p == NULL) {
        return NULL;
    }
    return p + ((16u - ((uintptr_t)p & 15u)) & 15u);
}

int mapopt_config(const mapopt_t *m, const float *data, int width, int height, double cell_m,
                  trn_map_cfg_t *cfg, double *sigma_h, char *err, size_t err_len)
{
    trn_status_t st;
    trn_grid_f32_t g;
    double sh = NAN;
    if (strcmp(m->config, "auto") != 0 && strcmp(m->config, "paper") != 0) {
        snprintf(err, err_len, "--map-config must be auto or paper, not '%s'", m->config);
        return -1;
    }
    if (m->local_hp != NULL && strcmp(m->local_hp, "box") != 0 && strcmp(m->local_hp, "map") != 0) {
        snprintf(err, err_len, "--local-highpass must be box or map, not '%s'", m->local_hp);
        return -1;
    }
    if (m->match != NULL && strcmp(m->match, "voxel") != 0 && strcmp(m->match, "heights") != 0) {
        snprintf(err, err_len, "--match must be voxel or heights, not '%s'", m->match);
        return -1;
    }
    if (!(cell_m > 0.0 && cell_m <= (double)TRN_CELL_MAX_M)) {
        snprintf(err, err_len, "cell size %g m is outside the (0, %g] m the core accepts", cell_m,
                 (double)TRN_CELL_MAX_M);
        return -1;
    }
    trn_map_cfg_default(cfg);
    cfg->noise_m = (float)(m->noise_m > 0.0 ? m->noise_m : MAPOPT_NOISE_M);
    cfg->noise_k_per_m = (float)(m->noise_k >= 0.0 ? m->noise_k : MAPOPT_NOISE_K_PER_CELL / cell_m);
    if (strcmp(m->config, "auto") == 0) {
        size_t wb = trn_map_cfg_auto_workspace_bytes(width, height);
        void *raw = NULL, *ws = wb > 0 ? alloc16(wb, &raw) : NULL;
        if (ws == NULL || trn_grid_f32_init(&g, (float *)data, (size_t)width * (size_t)height,
                                            width, height) != TRN_OK) {
            free(raw);
            snprintf(err, err_len,
                     "cannot prepare the automatic map configuration for %d x %d cells", width,
                     height);
            return -1;
        }
        st = trn_map_cfg_auto(cfg, &g, (float)cell_m, ws, wb, &sh);
        free(raw);
        if (st != TRN_OK) {
            snprintf(err, err_len, "automatic map configuration: %s", trn_strerror(st));
            return -1;
        }
    } else {
        cfg->terrain.cell_m = (float)cell_m;
        cfg->terrain.zbin_m = (float)cell_m;
        cfg->terrain.highpass_half_m = (float)((double)TRN_MAP_HIGHPASS_CELLS * cell_m);
        cfg->sigma_m = (float)cell_m;
    }
    if (m->zbin_m > 0.0) {
        cfg->terrain.zbin_m = (float)m->zbin_m;
    }
    if (m->nz > 0) {
        cfg->terrain.nz = (int32_t)m->nz;
    }
    if (m->highpass_m > 0.0) {
        cfg->terrain.highpass_half_m = (float)m->highpass_m;
    }
    if (m->sigma_m > 0.0) {
        cfg->sigma_m = (float)m->sigma_m;
    }
    if (m->inlier_prob > 0.0) {
        cfg->inlier_prob = (float)m->inlier_prob;
    }
    if (m->local_hp != NULL) {
        cfg->local_highpass = strcmp(m->local_hp, "map") == 0 ? TRN_LOCAL_HP_MAP : TRN_LOCAL_HP_BOX;
    }
    if (m->refine >= 0) {
        cfg->refine = (int32_t)m->refine;
    }
    if (m->noise_auto >= 0) {
        cfg->noise_auto = (int32_t)m->noise_auto;
    }
    if (m->match != NULL) {
        cfg->match = strcmp(m->match, "heights") == 0 ? TRN_MATCH_HEIGHTS : TRN_MATCH_VOXEL;
    }
    if (m->max_failure_prob > 0.0) {
        cfg->max_failure_prob = (float)m->max_failure_prob;
    }
    if ((st = trn_map_cfg_check(cfg)) != TRN_OK) {
        snprintf(err, err_len,
                 "map configuration rejected (%s): cell %g m, bin %g m, %d bins, high-pass %g m "
                 "(at least one cell), s %g m",
                 trn_strerror(st), cell_m, (double)cfg->terrain.zbin_m, (int)cfg->terrain.nz,
                 (double)cfg->terrain.highpass_half_m, (double)cfg->sigma_m);
        return -1;
    }
    if (sigma_h != NULL) {
        *sigma_h = sh;
    }
    return 0;
}

void mapopt_json(json_t *j, const trn_map_cfg_t *cfg)
{
    json_obj(j, "map_config");
    json_num(j, "zbin_m", cfg->terrain.zbin_m);
    json_int(j, "nz", cfg->terrain.nz);
    json_num(j, "highpass_m", cfg->terrain.highpass_half_m);
    json_num(j, "sigma_m", cfg->sigma_m);
    json_num(j, "inlier_prob", cfg->inlier_prob);
    json_num(j, "noise_m", cfg->noise_m);
    json_num(j, "noise_k_per_m", cfg->noise_k_per_m);
    json_str(j, "local_highpass", cfg->local_highpass == TRN_LOCAL_HP_MAP ? "map" : "box");
    json_int(j, "refine", cfg->refine);
    json_int(j, "noise_auto", cfg->noise_auto);
    json_str(j, "match", cfg->match == TRN_MATCH_HEIGHTS ? "heights" : "voxel");
    json_num(j, "max_failure_prob", cfg->max_failure_prob);
    json_obj_end(j);
}
