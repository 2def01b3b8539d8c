/* SPDX-License-Identifier: Apache-2.0 */
/* localize_common.c - the functions shared by the height matcher's
 * localization (src/localize_heights.c) and the voxel path's refinement
 * (src/localize.c): the refinement's noise model, the refinement taken as
 * the answer, the test of the noise model at the answer. Below both, so
 * that their calls go one way
 * (docs/architecture.md, "The localization stack"). */
#include "trn/localize.h"

#include <math.h>

#include "localize_int.h"
#include "refine_int.h"

/* The refinement in out->refinement becomes the answer: pose, covariance,
 * sigmas and the misfit flag. */
void trn_loc_take_refinement_(const trn_map_t *map, trn_loc_result_t *out)
{
    double cell = (double)map->cfg.terrain.cell_m;
    /* the configured noise, not the rescaled one: a rescale must not make
     * the flag more lenient */
    double lim = map->roughness_m > (double)map->cfg.noise_m ? map->roughness_m
                                                             : (double)map->cfg.noise_m;
    out->refined = 1;
    out->misfit = out->refinement.model_m > TRN_MISFIT_ROUGHNESS * lim ? 1 : 0;
    /* the answer: the refinement's estimate and its spline step
     * (docs/method.md 9.4) */
    out->x = out->refinement.x + out->refinement.spline_step[0];
    out->y = out->refinement.y + out->refinement.spline_step[1];
    out->cov_m2[0] = out->refinement.cov_cells[0] * cell * cell;
    out->cov_m2[1] = out->refinement.cov_cells[1] * cell * cell;
    out->cov_m2[2] = out->refinement.cov_cells[2] * cell * cell;
    out->sigma_x_m = sqrt(out->cov_m2[0]);
    out->sigma_y_m = sqrt(out->cov_m2[1]);
    out->rho = out->cov_m2[2] / (out->sigma_x_m * out->sigma_y_m);
}

void trn_loc_refine_cfg_(const trn_map_t *map, const trn_loc_result_t *out,
                         const trn_local_cells_t *cells, trn_refine_cfg_t *rc)
{
    rc->centroid_x = cells != NULL ? cells->centroid_x : NULL;
    rc->centroid_y = cells != NULL ? cells->centroid_y : NULL;
    rc->point_count = cells != NULL ? cells->point_count : NULL;
    rc->cell_m = map->cfg.terrain.cell_m;
    rc->noise_m = (float)((double)map->cfg.noise_m * out->noise_scale);
    rc->noise_k_per_m = (float)((double)map->cfg.noise_k_per_m * out->noise_scale);
    rc->inlier_prob = map->cfg.inlier_prob;
    rc->fit_noise = map->cfg.noise_auto != 0 ? 1 : 0; /* the search's pose score */
}

int trn_loc_noise_rejected_(const trn_map_t *map, const trn_grid_f32_t *local, int32_t rx,
                            int32_t ry, const trn_refine_t *at, double heading_rad,
                            const trn_refine_cfg_t *rc, double *scale)
{
    double k2, sd;
    if (trn_refine_noise_scale(&map->heights, local, rx, ry, at, heading_rad, rc, &k2, &sd) !=
        TRN_OK) {
        return 0;
    }
    if (k2 > 1.0) {
        /* a rescale up: only as far as the neighbours' differences support */
        int32_t pairs = 0;
        const double kd = trn_refine_noise_scale_diff_(&map->heights, local, rx, ry, at,
                                                       heading_rad, rc, k2,
                                                       at->model_m * at->model_m, &pairs);
        if (pairs >= 8 && kd < k2) {
            k2 = kd > 1.0 ? kd : 1.0;
        }
    }
    if (!(fabs(k2 - 1.0) > TRN_NOISE_SCALE_Z * sd)) {
        return 0;
    }
    *scale = sqrt(k2);
    return 1;
}
