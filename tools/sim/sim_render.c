/* SPDX-License-Identifier: Apache-2.0 */
/* sim_render.c - see sim_render.h. */
#include "sim_render.h"

#include <math.h>
#include <string.h>

#define SIM_BISECTIONS 30

static int finite_f(float v) { return v == v && v - v == 0.0f; }

static uint64_t rng_u64(sim_rng_t *r)
{
    uint64_t z = (r->s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

double sim_rng_normal(sim_rng_t *rng)
{
    double u1, u2;
    if (rng == NULL) {
        return 0.0;
    }
    /* (0, 1]: never log(0) */
    u1 = ((double)(rng_u64(rng) >> 11) + 1.0) * (1.0 / 9007199254740992.0);
    u2 = (double)(rng_u64(rng) >> 11) * (1.0 / 9007199254740992.0);
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

/* Bilinear height; 0 outside (the caller checks inside first). */
static int dem_h(const sim_dem_t *d, double x, double y, double *h)
{
    double fx = (x - (double)d->x0_m) / (double)d->cell_m;
    double fy = (y - (double)d->y0_m) / (double)d->cell_m;
    int32_t i, j;
    double ax, ay;
    const float *p;
    if (!(fx >= 0.0 && fy >= 0.0 && fx <= (double)(d->width - 1) &&
          fy <= (double)(d->height - 1))) {
        return 0;
    }
    i = (int32_t)fx;
    j = (int32_t)fy;
    if (i > d->width - 2) {
        i = d->width - 2;
    }
    if (j > d->height - 2) {
        j = d->height - 2;
    }
    ax = fx - (double)i;
    ay = fy - (double)j;
    p = d->heights + (size_t)j * (size_t)d->width + (size_t)i;
    *h = (1.0 - ay) * ((1.0 - ax) * (double)p[0] + ax * (double)p[1]) +
         ay * ((1.0 - ax) * (double)p[d->width] + ax * (double)p[d->width + 1]);
    return 1;
}

static int dem_ok(const sim_dem_t *d)
{
    return d->heights != NULL && d->width >= 2 && d->height >= 2 && finite_f(d->cell_m) &&
           d->cell_m > 0.0f && finite_f(d->x0_m) && finite_f(d->y0_m);
}

trn_status_t sim_dem_height(const sim_dem_t *dem, float x_m, float y_m, float *h_m)
{
    double h = 0.0;
    if (dem == NULL || h_m == NULL || dem->heights == NULL) {
        return TRN_E_NULL;
    }
    if (!dem_ok(dem)) {
        return TRN_E_ARG;
    }
    if (!dem_h(dem, (double)x_m, (double)y_m, &h)) {
        return TRN_E_RANGE;
    }
    *h_m = (float)h;
    return TRN_OK;
}

/* The camera and its pose usable (finite, within the limits). */
static int camera_ok(const sim_camera_t *cam, const trn_rigid_t *cam_to_map)
{
    int32_t k;
    if (!finite_f(cam->hfov_rad) || !finite_f(cam->vfov_rad) || cam->hfov_rad <= 0.0f ||
        cam->hfov_rad >= 3.0f || cam->vfov_rad <= 0.0f || cam->vfov_rad >= 3.0f || cam->cols < 1 ||
        cam->rows < 1 || cam->cols > SIM_MAX_RAYS_SIDE || cam->rows > SIM_MAX_RAYS_SIDE ||
        !finite_f(cam->min_range_m) || !finite_f(cam->max_range_m) || cam->min_range_m < 0.0f ||
        cam->max_range_m <= cam->min_range_m || !finite_f(cam->noise_k_per_m) ||
        cam->noise_k_per_m < 0.0f) {
        return 0;
    }
    for (k = 0; k < 9; ++k) {
        if (!finite_f(cam_to_map->r[k])) {
            return 0;
        }
    }
    return finite_f(cam_to_map->t.x) && finite_f(cam_to_map->t.y) && finite_f(cam_to_map->t.z);
}

/* March the ray of map direction dm from the camera in nsteps steps of step
 * metres, then bisect: the range of its first hit in *range. 0: no hit (it
 * starts off the DEM or under the ground, leaves the DEM, or reaches the
 * maximum range). */
static int cast_ray(const sim_dem_t *dem, const sim_camera_t *cam, const trn_rigid_t *cam_to_map,
                    const double dm[3], int32_t nsteps, double step, double *range)
{
    double r0, r1, h = 0.0;
    int found = 0, s;
    /* march: above the surface at r0, first sample at or below at r1 */
    r0 = (double)cam->min_range_m;
    if (!dem_h(dem, (double)cam_to_map->t.x + r0 * dm[0], (double)cam_to_map->t.y + r0 * dm[1],
               &h) ||
        (double)cam_to_map->t.z + r0 * dm[2] <= h) {
        return 0; /* starts off the DEM or under the ground */
    }
    r1 = r0;
    for (s = 1; s <= nsteps; ++s) {
        r1 = (double)cam->min_range_m + step * (double)s;
        if (r1 > (double)cam->max_range_m) {
            r1 = (double)cam->max_range_m;
        }
        if (!dem_h(dem, (double)cam_to_map->t.x + r1 * dm[0], (double)cam_to_map->t.y + r1 * dm[1],
                   &h)) {
            break; /* left the DEM */
        }
        if ((double)cam_to_map->t.z + r1 * dm[2] <= h) {
            found = 1;
            break;
        }
        r0 = r1;
    }
    if (!found) {
        return 0;
    }
    for (s = 0; s < SIM_BISECTIONS; ++s) {
        double rm = 0.5 * (r0 + r1);
        (void)dem_h(dem, (double)cam_to_map->t.x + rm * dm[0], (double)cam_to_map->t.y + rm * dm[1],
                    &h);
        if ((double)cam_to_map->t.z + rm * dm[2] <= h) {
            r1 = rm;
        } else {
            r0 = rm;
        }
    }
    *range = 0.5 * (r0 + r1);
    return 1;
}

trn_status_t sim_render_rows(const sim_dem_t *dem, const sim_camera_t *cam,
                             const trn_rigid_t *cam_to_map, sim_rng_t *rng, int32_t row0,
                             int32_t row1, trn_vec3f_t *out, size_t capacity, size_t *n)
{
    double step, tx, ty;
    int32_t i, j, k, nsteps;
    size_t cnt;
    const float *R;
    if (dem == NULL || cam == NULL || cam_to_map == NULL || rng == NULL || out == NULL ||
        n == NULL || dem->heights == NULL) {
        return TRN_E_NULL;
    }
    cnt = *n;
    if (!dem_ok(dem) || !camera_ok(cam, cam_to_map)) {
        return TRN_E_ARG;
    }
    if (row0 < 0 || row1 < row0 || row1 > cam->rows || cnt > capacity) {
        return TRN_E_RANGE;
    }
    step = 0.5 * (double)dem->cell_m;
    if ((double)(cam->max_range_m - cam->min_range_m) / step > (double)SIM_MAX_STEPS) {
        return TRN_E_ARG;
    }
    nsteps = (int32_t)ceil((double)(cam->max_range_m - cam->min_range_m) / step);
    tx = tan(0.5 * (double)cam->hfov_rad);
    ty = tan(0.5 * (double)cam->vfov_rad);
    R = cam_to_map->r;
    for (j = row0; j < row1; ++j) {
        for (i = 0; i < cam->cols; ++i) {
            double dc[3], dm[3], norm, rr = 0.0;
            dc[0] = tx * (2.0 * ((double)i + 0.5) / (double)cam->cols - 1.0);
            dc[1] = ty * (2.0 * ((double)j + 0.5) / (double)cam->rows - 1.0);
            dc[2] = 1.0;
            norm = sqrt(dc[0] * dc[0] + dc[1] * dc[1] + 1.0);
            for (k = 0; k < 3; ++k) {
                dc[k] /= norm;
            }
            for (k = 0; k < 3; ++k) {
                const size_t row = (size_t)3 * (size_t)k;
                dm[k] = (double)R[row] * dc[0] + (double)R[row + 1u] * dc[1] +
                        (double)R[row + 2u] * dc[2];
            }
            if (!cast_ray(dem, cam, cam_to_map, dm, nsteps, step, &rr)) {
                continue;
            }
            if (cam->noise_k_per_m > 0.0f) {
                rr += (double)cam->noise_k_per_m * rr * rr * sim_rng_normal(rng);
            }
            if (cnt >= capacity) {
                *n = cnt;
                return TRN_E_CAPACITY;
            }
            out[cnt].x = (float)(rr * dc[0]);
            out[cnt].y = (float)(rr * dc[1]);
            out[cnt].z = (float)(rr * dc[2]);
            ++cnt;
        }
    }
    *n = cnt;
    return TRN_OK;
}

trn_status_t sim_render(const sim_dem_t *dem, const sim_camera_t *cam,
                        const trn_rigid_t *cam_to_map, sim_rng_t *rng, trn_vec3f_t *out,
                        size_t capacity, size_t *n)
{
    if (n == NULL || cam == NULL) {
        return TRN_E_NULL;
    }
    *n = 0u;
    return sim_render_rows(dem, cam, cam_to_map, rng, 0, cam->rows, out, capacity, n);
}

void sim_camera_default(sim_camera_t *cam)
{
    if (cam == NULL) {
        return;
    }
    cam->hfov_rad = 1.0471976f; /* 60 deg */
    cam->vfov_rad = 0.7853982f; /* 45 deg */
    cam->cols = 64;
    cam->rows = 48;
    cam->min_range_m = 0.5f;
    cam->max_range_m = 12.0f;
    cam->noise_k_per_m = 0.002f;
}

void sim_geom_default(trn_mast_geom_t *geom)
{
    if (geom == NULL) {
        return;
    }
    memset(geom, 0, sizeof *geom);
    geom->pan_x_m = 0.2f;
    geom->pan_z_m = 1.4f;
    geom->tilt_fwd_m = 0.05f;
    geom->tilt_up_m = 0.0f;
    geom->cam_fwd_m = 0.05f;
    geom->cam_left_m = 0.1f;
    geom->cam_up_m = 0.03f;
    geom->pan_min_rad = -3.0f;
    geom->pan_max_rad = 3.0f;
    geom->tilt_min_rad = -1.2f;
    geom->tilt_max_rad = 0.8f;
}
