/* SPDX-License-Identifier: Apache-2.0 */
/* fuzz_mast.c - mast kinematics (mast.h) with arbitrary floats: geometry
 * check, pointing, camera-to-map transform, rigid apply, local DEM binning.
 *
 * Input: a mode byte; the geometry (14 floats), pose (4), target (3), two
 * measured angles, the local DEM placement and size, up to 32 points. In
 * "sane" mode (mode bit 0) each float is folded into a plausible range
 * (lengths +-2 m, pose +-100 m, target +-50 m, limits inside their ranges),
 * otherwise the raw bits are used (NaN, inf, 3.4e38, subnormals).
 * Invariants:
 * - only the documented statuses;
 * - point_at: on OK / RANGE both angles are finite, pan in [-pi, pi], tilt
 *   in [-3pi/2, 3pi/2] and beyond +-pi only with RANGE (+ float slack); OK
 *   only inside the joint limits, RANGE only outside; in sane
 *   mode, OK means the boresight from the camera_to_map transform at those
 *   angles passes within 1 mm per metre (+ 1 mm) of the target, ahead;
 * - camera_to_map: R orthonormal with det +1 (1e-5) for any finite angles;
 * - rigid_apply in place equals rigid_apply into another array;
 * - local_dem: OK exactly when n_used > 0, n_used <= n, every cell NaN or
 *   the z of some point, NODATA leaves every cell NaN.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_input.h"
#include "trn/trn.h"

#define FZ_CHECK(c) \
    do { \
        if (!(c)) { \
            abort(); \
        } \
    } while (0)
#define MAXP 32
#define MAXD 16

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* A float: raw bits, or in sane mode folded into [lo, hi]. */
static float val(fz_t *in, int sane, float lo, float hi)
{
    if (sane) {
        uint16_t u = (uint16_t)(fz_u8(in) | (fz_u8(in) << 8));
        return lo + (hi - lo) * ((float)u / 65535.0f);
    }
    return fz_f32(in);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_t in = {data, size};
    const uint8_t mode = fz_u8(&in);
    const int sane = (mode & 1u) != 0u;
    trn_mast_geom_t g;
    trn_rover_pose_t pose;
    trn_vec3f_t target, pts[MAXP], a[MAXP], b[MAXP];
    trn_rigid_t T;
    trn_local_dem_cfg_t cfg;
    float cells[MAXD * MAXD], pan = 0.0f, tilt = 0.0f, mpan, mtilt;
    trn_grid_f32_t dem;
    trn_status_t st, gst;
    size_t n, i, used = 999u;
    int32_t x, y;

    g.pan_x_m = val(&in, sane, -2.0f, 2.0f);
    g.pan_y_m = val(&in, sane, -2.0f, 2.0f);
    g.pan_z_m = val(&in, sane, -2.0f, 2.0f);
    g.tilt_fwd_m = val(&in, sane, -0.5f, 0.5f);
    g.tilt_up_m = val(&in, sane, -0.5f, 0.5f);
    g.cam_fwd_m = val(&in, sane, -0.3f, 0.3f);
    g.cam_left_m = val(&in, sane, -0.3f, 0.3f);
    g.cam_up_m = val(&in, sane, -0.3f, 0.3f);
    g.pan_min_rad = val(&in, sane, -3.1415926f, 0.0f);
    g.pan_max_rad = val(&in, sane, 0.0f, 3.1415926f);
    g.tilt_min_rad = val(&in, sane, -1.5707963f, 0.0f);
    g.tilt_max_rad = val(&in, sane, 0.0f, 1.5707963f);
    pose.x_m = val(&in, sane, -100.0f, 100.0f);
    pose.y_m = val(&in, sane, -100.0f, 100.0f);
    pose.z_m = val(&in, sane, -10.0f, 10.0f);
    pose.heading_rad = val(&in, sane, -7.0f, 7.0f);
    target.x = pose.x_m + val(&in, sane, -50.0f, 50.0f);
    target.y = pose.y_m + val(&in, sane, -50.0f, 50.0f);
    target.z = pose.z_m + val(&in, sane, -20.0f, 20.0f);
    mpan = val(&in, sane, -4.0f, 4.0f);
    mtilt = val(&in, sane, -2.0f, 2.0f);

    gst = trn_mast_geom_check(&g);
    FZ_CHECK(gst == TRN_OK || gst == TRN_E_ARG);

    /* pointing */
    st = trn_mast_point_at(&g, &pose, &target, &pan, &tilt);
    FZ_CHECK(st == TRN_OK || st == TRN_E_RANGE || st == TRN_E_ARG);
    if (gst != TRN_OK) {
        FZ_CHECK(st == TRN_E_ARG);
    }
    if (st == TRN_OK || st == TRN_E_RANGE) {
        int inside = pan >= g.pan_min_rad && pan <= g.pan_max_rad && tilt >= g.tilt_min_rad &&
                     tilt <= g.tilt_max_rad;
        FZ_CHECK(isfinite(pan) && isfinite(tilt));
        /* pan wrapped to [-pi, pi]; tilt atan2 - asin, not wrapped (mast.h) */
        FZ_CHECK(fabsf(pan) <= 3.1416f && fabsf(tilt) <= 4.7124f);
        if (fabsf(tilt) > 3.1416f) {
            FZ_CHECK(st == TRN_E_RANGE);
        }
        FZ_CHECK(inside == (st == TRN_OK));
    }
    if (st == TRN_OK && sane) {
        /* the target seen from the camera: on the boresight (+z), ahead */
        double d[3], c[3], dist;
        int k;
        FZ_CHECK(trn_mast_camera_to_map(&g, &pose, pan, tilt, &T) == TRN_OK);
        d[0] = (double)target.x - (double)T.t.x;
        d[1] = (double)target.y - (double)T.t.y;
        d[2] = (double)target.z - (double)T.t.z;
        for (k = 0; k < 3; ++k) { /* c = R^T d */
            c[k] = (double)T.r[k] * d[0] + (double)T.r[3 + k] * d[1] + (double)T.r[6 + k] * d[2];
        }
        dist = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        FZ_CHECK(c[2] > 0.0);
        FZ_CHECK(sqrt(c[0] * c[0] + c[1] * c[1]) <= 1.0e-3 * dist + 1.0e-3);
    }

    /* the transform at measured angles */
    st = trn_mast_camera_to_map(&g, &pose, mpan, mtilt, &T);
    FZ_CHECK(st == TRN_OK || st == TRN_E_ARG);
    if (st == TRN_OK) {
        int r, s, k;
        double det;
        for (r = 0; r < 3; ++r) {
            for (s = 0; s < 3; ++s) {
                double dot = 0.0;
                for (k = 0; k < 3; ++k) {
                    dot += (double)T.r[3 * k + r] * (double)T.r[3 * k + s];
                }
                FZ_CHECK(fabs(dot - (r == s ? 1.0 : 0.0)) <= 1.0e-5);
            }
        }
        det = (double)T.r[0] * ((double)T.r[4] * T.r[8] - (double)T.r[5] * T.r[7]) -
              (double)T.r[1] * ((double)T.r[3] * T.r[8] - (double)T.r[5] * T.r[6]) +
              (double)T.r[2] * ((double)T.r[3] * T.r[7] - (double)T.r[4] * T.r[6]);
        FZ_CHECK(fabs(det - 1.0) <= 1.0e-5);
    } else {
        memset(&T, 0, sizeof T);
        T.r[0] = T.r[4] = T.r[8] = 1.0f;
    }

    /* points: camera frame -> map, in place and out of place agree */
    n = (size_t)fz_range(&in, 0, MAXP);
    for (i = 0; i < n; ++i) {
        pts[i].x = val(&in, sane, -5.0f, 5.0f);
        pts[i].y = val(&in, sane, -3.0f, 3.0f);
        pts[i].z = val(&in, sane, 0.5f, 30.0f);
    }
    memcpy(a, pts, sizeof a);
    FZ_CHECK(trn_rigid_apply(&T, pts, n, b) == TRN_OK);
    FZ_CHECK(trn_rigid_apply(&T, a, n, a) == TRN_OK);
    FZ_CHECK(memcmp(a, b, n * sizeof a[0]) == 0);

    /* local DEM */
    cfg.cell_m = sane ? val(&in, 1, 0.05f, 2.0f) : fz_f32(&in);
    cfg.rover_col = fz_range(&in, -4, MAXD + 3);
    cfg.rover_row = fz_range(&in, -4, MAXD + 3);
    cfg.row_north = fz_range(&in, -2, 1);
    if (cfg.row_north == 0) {
        cfg.row_north = 1;
    }
    st = trn_grid_f32_init(&dem, cells, MAXD * MAXD, fz_range(&in, 1, MAXD),
                           fz_range(&in, 1, MAXD));
    FZ_CHECK(st == TRN_OK);
    used = 999u;
    st = trn_mast_local_dem(b, n, &pose, &cfg, &dem, &used);
    FZ_CHECK(st == TRN_OK || st == TRN_E_NODATA || st == TRN_E_ARG);
    if (st == TRN_OK || st == TRN_E_NODATA) {
        size_t filled = 0u;
        FZ_CHECK(used <= n && (st == TRN_OK) == (used > 0u));
        for (y = 0; y < dem.height; ++y) {
            for (x = 0; x < dem.width; ++x) {
                const float v = TRN_GRID_AT(&dem, x, y);
                if (!isnan(v)) {
                    int found = 0;
                    for (i = 0; i < n && !found; ++i) {
                        found = (b[i].z == v);
                    }
                    FZ_CHECK(found);
                    ++filled;
                }
            }
        }
        FZ_CHECK(filled <= used);
    } else {
        FZ_CHECK(used == 999u);
    }
    return 0;
}
