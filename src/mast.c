/* SPDX-License-Identifier: Apache-2.0 */
/* mast.c - mast kinematics, camera -> map points, local DEM (mast.h). */
#include "trn/mast.h"

#include <math.h>

#define PI_F 3.14159265358979f
/* limits are compared with a little slack so that +-pi, +-pi/2 given as
 * float constants pass */
#define PI_SLACK_F 3.1415930f
#define HALF_PI_SLACK_F 1.5707965f

static int finite3(float a, float b, float c) { return isfinite(a) && isfinite(b) && isfinite(c); }

trn_status_t trn_mast_geom_check(const trn_mast_geom_t *g)
{
    if (g == NULL) {
        return TRN_E_NULL;
    }
    if (!finite3(g->pan_x_m, g->pan_y_m, g->pan_z_m) ||
        !finite3(g->tilt_fwd_m, g->tilt_up_m, g->cam_fwd_m) ||
        !finite3(g->cam_left_m, g->cam_up_m, g->pan_min_rad) ||
        !finite3(g->pan_max_rad, g->tilt_min_rad, g->tilt_max_rad)) {
        return TRN_E_ARG;
    }
    if (g->pan_min_rad < -PI_SLACK_F || g->pan_max_rad > PI_SLACK_F ||
        g->pan_min_rad > g->pan_max_rad || g->tilt_min_rad < -HALF_PI_SLACK_F ||
        g->tilt_max_rad > HALF_PI_SLACK_F || g->tilt_min_rad > g->tilt_max_rad) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}

static int pose_ok(const trn_rover_pose_t *p)
{
    return finite3(p->x_m, p->y_m, p->z_m) && isfinite(p->heading_rad);
}

trn_status_t trn_mast_point_at(const trn_mast_geom_t *g, const trn_rover_pose_t *pose,
                               const trn_vec3f_t *target, float *pan_rad, float *tilt_rad)
{
    float ch, sh, dx, dy, bx, by, px, py, r, pan, cp, sp, pf, a, b, rho, tilt, s;
    if (g == NULL || pose == NULL || target == NULL || pan_rad == NULL || tilt_rad == NULL) {
        return TRN_E_NULL;
    }
    if (trn_mast_geom_check(g) != TRN_OK || !pose_ok(pose) ||
        !finite3(target->x, target->y, target->z)) {
        return TRN_E_ARG;
    }
    /* target in the body frame */
    ch = cosf(pose->heading_rad);
    sh = sinf(pose->heading_rad);
    dx = target->x - pose->x_m;
    dy = target->y - pose->y_m;
    bx = dx * ch + dy * sh;
    by = -dx * sh + dy * ch;
    /* pan: the boresight's lateral offset cam_left must pass the target */
    px = bx - g->pan_x_m;
    py = by - g->pan_y_m;
    r = sqrtf(px * px + py * py);
    if (!(r > fabsf(g->cam_left_m))) {
        return TRN_E_ARG;
    }
    pan = atan2f(py, px) - asinf(g->cam_left_m / r);
    if (pan > PI_F) {
        pan -= 2.0f * PI_F;
    } else if (pan < -PI_F) {
        pan += 2.0f * PI_F;
    }
    /* tilt, in the panned vertical plane through the tilt axis */
    cp = cosf(pan);
    sp = sinf(pan);
    pf = px * cp + py * sp;
    a = pf - g->tilt_fwd_m;
    b = (target->z - pose->z_m) - g->pan_z_m - g->tilt_up_m;
    rho = sqrtf(a * a + b * b);
    if (!(rho > fabsf(g->cam_up_m))) {
        return TRN_E_ARG;
    }
    tilt = atan2f(b, a) - asinf(g->cam_up_m / rho);
    /* distance along the boresight from the tilt axis foot to the target */
    s = sqrtf(rho * rho - g->cam_up_m * g->cam_up_m);
    if (!(s > g->cam_fwd_m)) {
        return TRN_E_ARG;
    }
    *pan_rad = pan;
    *tilt_rad = tilt;
    if (pan < g->pan_min_rad || pan > g->pan_max_rad || tilt < g->tilt_min_rad ||
        tilt > g->tilt_max_rad) {
        return TRN_E_RANGE;
    }
    return TRN_OK;
}

/* Rotation of a head-frame vector (forward, left, up) into the map frame. */
static void head_dir_to_map(float cp, float sp, float ct, float st, float ch, float sh, float hf,
                            float hl, float hu, float out[3])
{
    /* head -> panned: forward = (ct, 0, st), up = (-st, 0, ct) */
    float pf = hf * ct - hu * st;
    float pl = hl;
    float pu = hf * st + hu * ct;
    /* panned -> body */
    float bx = pf * cp - pl * sp;
    float by = pf * sp + pl * cp;
    /* body -> map */
    out[0] = bx * ch - by * sh;
    out[1] = bx * sh + by * ch;
    out[2] = pu;
}

trn_status_t trn_mast_camera_to_map(const trn_mast_geom_t *g, const trn_rover_pose_t *pose,
                                    float pan_rad, float tilt_rad, trn_rigid_t *cam_to_map)
{
    float cp, sp, ct, st, ch, sh, ex[3], ey[3], ez[3], bx, by, bz, pf, pu;
    if (g == NULL || pose == NULL || cam_to_map == NULL) {
        return TRN_E_NULL;
    }
    if (trn_mast_geom_check(g) != TRN_OK || !pose_ok(pose) || !isfinite(pan_rad) ||
        !isfinite(tilt_rad)) {
        return TRN_E_ARG;
    }
    cp = cosf(pan_rad);
    sp = sinf(pan_rad);
    ct = cosf(tilt_rad);
    st = sinf(tilt_rad);
    ch = cosf(pose->heading_rad);
    sh = sinf(pose->heading_rad);
    /* camera axes in head terms: x right = -left, y down = -up, z = forward */
    head_dir_to_map(cp, sp, ct, st, ch, sh, 0.0f, -1.0f, 0.0f, ex);
    head_dir_to_map(cp, sp, ct, st, ch, sh, 0.0f, 0.0f, -1.0f, ey);
    head_dir_to_map(cp, sp, ct, st, ch, sh, 1.0f, 0.0f, 0.0f, ez);
    cam_to_map->r[0] = ex[0];
    cam_to_map->r[1] = ey[0];
    cam_to_map->r[2] = ez[0];
    cam_to_map->r[3] = ex[1];
    cam_to_map->r[4] = ey[1];
    cam_to_map->r[5] = ez[1];
    cam_to_map->r[6] = ex[2];
    cam_to_map->r[7] = ey[2];
    cam_to_map->r[8] = ez[2];
    /* optical centre: head offset -> panned (about the tilt axis) -> body */
    pf = g->tilt_fwd_m + g->cam_fwd_m * ct - g->cam_up_m * st;
    pu = g->tilt_up_m + g->cam_fwd_m * st + g->cam_up_m * ct;
    bx = g->pan_x_m + pf * cp - g->cam_left_m * sp;
    by = g->pan_y_m + pf * sp + g->cam_left_m * cp;
    bz = g->pan_z_m + pu;
    cam_to_map->t.x = pose->x_m + bx * ch - by * sh;
    cam_to_map->t.y = pose->y_m + bx * sh + by * ch;
    cam_to_map->t.z = pose->z_m + bz;
    return TRN_OK;
}

trn_status_t trn_rigid_apply(const trn_rigid_t *T, const trn_vec3f_t *in, size_t n,
                             trn_vec3f_t *out)
{
    size_t i;
    if (T == NULL || ((in == NULL || out == NULL) && n > 0u)) {
        return TRN_E_NULL;
    }
    for (i = 0u; i < n; ++i) {
        trn_vec3f_t p = in[i];
        out[i].x = T->r[0] * p.x + T->r[1] * p.y + T->r[2] * p.z + T->t.x;
        out[i].y = T->r[3] * p.x + T->r[4] * p.y + T->r[5] * p.z + T->t.y;
        out[i].z = T->r[6] * p.x + T->r[7] * p.y + T->r[8] * p.z + T->t.z;
    }
    return TRN_OK;
}

/* Argument checks shared by the two local DEM builders. */
static trn_status_t local_dem_args(const trn_vec3f_t *pts, size_t n, const trn_rover_pose_t *pose,
                                   const trn_local_dem_cfg_t *cfg, const trn_grid_f32_t *dem)
{
    if (dem == NULL || pose == NULL || cfg == NULL || (pts == NULL && n > 0u)) {
        return TRN_E_NULL;
    }
    if (trn_grid_f32_check(dem) != TRN_OK) {
        return TRN_E_SIZE;
    }
    if (!isfinite(cfg->cell_m) || !(cfg->cell_m > 0.0f) || !isfinite(1.0f / cfg->cell_m) ||
        (cfg->row_north != 1 && cfg->row_north != -1) || cfg->rover_col < -TRN_MAX_DIM ||
        cfg->rover_col > dem->width + TRN_MAX_DIM || cfg->rover_row < -TRN_MAX_DIM ||
        cfg->rover_row > dem->height + TRN_MAX_DIM || !isfinite(pose->x_m) ||
        !isfinite(pose->y_m)) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}

/* The cell (c, r) of point p; 0 when p is not finite or off the grid. */
static int local_cell(const trn_vec3f_t *p, const trn_rover_pose_t *pose,
                      const trn_local_dem_cfg_t *cfg, const trn_grid_f32_t *dem, float inv,
                      int32_t *c, int32_t *r)
{
    float fc, fr;
    if (!finite3(p->x, p->y, p->z)) {
        return 0;
    }
    fc = floorf((p->x - pose->x_m) * inv + 0.5f);
    fr = floorf((p->y - pose->y_m) * inv + 0.5f);
    /* outside +-2*TRN_MAX_DIM cells cannot be on the grid; keeps the
     * conversion to int32 defined (written so that NaN is skipped too) */
    if (!(fabsf(fc) <= (float)(2 * TRN_MAX_DIM)) || !(fabsf(fr) <= (float)(2 * TRN_MAX_DIM))) {
        return 0;
    }
    *c = cfg->rover_col + (int32_t)fc;
    *r = cfg->rover_row + cfg->row_north * (int32_t)fr;
    return *c >= 0 && *c < dem->width && *r >= 0 && *r < dem->height;
}

static void fill_nan(trn_grid_f32_t *dem)
{
    int32_t x, y;
    for (y = 0; y < dem->height; ++y) {
        for (x = 0; x < dem->width; ++x) {
            TRN_GRID_AT(dem, x, y) = NAN;
        }
    }
}

trn_status_t trn_mast_local_dem(const trn_vec3f_t *pts, size_t n, const trn_rover_pose_t *pose,
                                const trn_local_dem_cfg_t *cfg, trn_grid_f32_t *dem, size_t *n_used)
{
    size_t i, used = 0u;
    float inv;
    trn_status_t st = local_dem_args(pts, n, pose, cfg, dem);
    if (st != TRN_OK) {
        return st;
    }
    fill_nan(dem);
    inv = 1.0f / cfg->cell_m;
    for (i = 0u; i < n; ++i) {
        float *cell;
        int32_t c, r;
        if (!local_cell(&pts[i], pose, cfg, dem, inv, &c, &r)) {
            continue;
        }
        cell = &TRN_GRID_AT(dem, c, r);
        if (!(*cell >= pts[i].z)) { /* NaN or lower */
            *cell = pts[i].z;
        }
        ++used;
    }
    if (n_used != NULL) {
        *n_used = used;
    }
    return (used == 0u) ? TRN_E_NODATA : TRN_OK;
}

trn_status_t trn_mast_local_dem_mean(const trn_vec3f_t *pts, size_t n, const trn_rover_pose_t *pose,
                                     const trn_local_dem_cfg_t *cfg, trn_grid_f32_t *dem,
                                     uint32_t *counts, size_t counts_len, size_t *n_used)
{
    size_t i, used = 0u, k;
    float inv;
    trn_status_t st = local_dem_args(pts, n, pose, cfg, dem);
    if (st != TRN_OK) {
        return st;
    }
    if (counts == NULL) {
        return TRN_E_NULL;
    }
    if (counts_len < (size_t)dem->width * (size_t)dem->height) {
        return TRN_E_WORKSPACE;
    }
    fill_nan(dem);
    for (k = 0u; k < (size_t)dem->width * (size_t)dem->height; ++k) {
        counts[k] = 0u;
    }
    inv = 1.0f / cfg->cell_m;
    for (i = 0u; i < n; ++i) {
        float *cell;
        uint32_t *cnt;
        int32_t c, r;
        if (!local_cell(&pts[i], pose, cfg, dem, inv, &c, &r)) {
            continue;
        }
        cell = &TRN_GRID_AT(dem, c, r);
        cnt = &counts[(size_t)r * (size_t)dem->width + (size_t)c];
        /* running mean (Welford): no large sums, absolute heights keep
         * their precision */
        *cnt += 1u;
        if (*cnt == 1u) {
            *cell = pts[i].z;
        } else {
            *cell += (pts[i].z - *cell) / (float)*cnt;
        }
        ++used;
    }
    if (n_used != NULL) {
        *n_used = used;
    }
    return (used == 0u) ? TRN_E_NODATA : TRN_OK;
}
