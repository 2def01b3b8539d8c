/* SPDX-License-Identifier: Apache-2.0 */
/* test_mast.c - mast kinematics, camera -> map transform, local DEM (mast.h).
 *
 * Hand-computed poses (zero offsets, and offsets chosen so that the answer
 * is a round angle), a round trip on seeded random geometries (target ->
 * pan/tilt -> the boresight ray hits the target), orthonormal rotations, and
 * an end-to-end check: heights of an analytic terrain seen from the mast,
 * carried into the camera frame at millimetre resolution and back, land in
 * the local DEM cell of their map position with their height.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "trn/localize.h"
#include "trn/mast.h"
#include "rng.h"
#include "synth.h"

#define PI 3.14159265358979323846

/* The capture's angle encoding (1e-4 rad counts, round to nearest); the
 * port's own converter is tested in test_can_msg.c. */
static int trn_can_angle_to_raw_for_test(float rad, int16_t *raw)
{
    double c = floor((double)rad * 10000.0 + 0.5);
    if (c < -32768.0 || c > 32767.0) {
        return -1;
    }
    *raw = (int16_t)c;
    return 0;
}

static trn_mast_geom_t plain_geom(void)
{
    trn_mast_geom_t g;
    memset(&g, 0, sizeof g);
    g.pan_z_m = 1.5f;
    g.pan_min_rad = (float)-PI;
    g.pan_max_rad = (float)PI;
    g.tilt_min_rad = (float)(-PI / 2);
    g.tilt_max_rad = (float)(PI / 2);
    return g;
}

static void test_point_at_hand(void **state)
{
    trn_mast_geom_t g = plain_geom();
    trn_rover_pose_t p = {10.0f, 20.0f, 1.0f, (float)(PI / 2)}; /* facing north */
    trn_vec3f_t t;
    float pan = 9, tilt = 9;
    (void)state;
    t = (trn_vec3f_t){10.0f, 30.0f, 2.5f}; /* 10 m ahead, level */
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_OK);
    assert_float_equal(pan, 0.0f, 1e-6f);
    assert_float_equal(tilt, 0.0f, 1e-6f);
    t = (trn_vec3f_t){0.0f, 20.0f, 2.5f}; /* west = left of a north-facing rover */
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_OK);
    assert_float_equal(pan, (float)(PI / 2), 1e-6f);
    t = (trn_vec3f_t){20.0f, 20.0f, 2.5f}; /* east = right */
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_OK);
    assert_float_equal(pan, (float)(-PI / 2), 1e-6f);
    t = (trn_vec3f_t){10.0f, 30.0f, -7.5f}; /* 10 m ahead, 10 m below the joint */
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_OK);
    assert_float_equal(pan, 0.0f, 1e-6f);
    assert_float_equal(tilt, (float)(-PI / 4), 1e-6f);
    t = (trn_vec3f_t){10.0f, 10.0f, 2.5f + 10.0f * sqrtf(3.0f)}; /* behind, 60 deg up */
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_OK);
    assert_float_equal(fabsf(pan), (float)PI, 1e-6f);
    assert_float_equal(tilt, (float)(PI / 3), 1e-6f);
}

static void test_point_at_offsets_hand(void **state)
{
    /* camera 0.3 m left of and 0.3 m above the tilt axis: a target 0.4 m
     * ahead and 0.3 m left of the pan axis, at camera height, is straight
     * ahead of the camera at pan 0, tilt 0 */
    trn_mast_geom_t g = plain_geom();
    trn_rover_pose_t p = {0.0f, 0.0f, 0.0f, 0.0f};
    trn_vec3f_t t;
    float pan, tilt;
    (void)state;
    g.pan_x_m = 1.0f;
    g.pan_y_m = -0.5f;
    g.tilt_up_m = 0.2f;
    g.cam_left_m = 0.3f;
    g.cam_up_m = 0.3f;
    g.cam_fwd_m = 0.05f;
    /* (0.4, 0.3) from the pan axis: atan2(0.3, 0.4) = asin(0.3 / 0.5) */
    t = (trn_vec3f_t){1.0f + 0.4f, -0.5f + 0.3f, 1.5f + 0.2f + 0.3f};
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_OK);
    assert_float_equal(pan, 0.0f, 1e-6f);
    assert_float_equal(tilt, 0.0f, 1e-6f);
    /* the same target from a rover turned by 30 degrees, placed so that
     * body point (1.4, -0.2) is still the target */
    {
        float h = (float)(PI / 6);
        trn_rover_pose_t q;
        q.x_m = t.x - (1.4f * cosf(h) - (-0.2f) * sinf(h));
        q.y_m = t.y - (1.4f * sinf(h) + (-0.2f) * cosf(h));
        q.z_m = 0.0f;
        q.heading_rad = h;
        assert_int_equal(trn_mast_point_at(&g, &q, &t, &pan, &tilt), TRN_OK);
        assert_float_equal(pan, 0.0f, 1e-5f);
        assert_float_equal(tilt, 0.0f, 1e-5f);
    }
}

static void test_point_at_limits_and_args(void **state)
{
    trn_mast_geom_t g = plain_geom();
    trn_rover_pose_t p = {0.0f, 0.0f, 0.0f, 0.0f};
    trn_vec3f_t t = {0.0f, 10.0f, 1.5f}; /* pan +90 deg */
    float pan = 0, tilt = 0;
    (void)state;
    g.pan_max_rad = 1.0f;
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_E_RANGE);
    assert_float_equal(pan, (float)(PI / 2), 1e-6f); /* still reported */
    g = plain_geom();
    g.tilt_min_rad = -0.5f;
    t = (trn_vec3f_t){1.0f, 0.0f, 0.0f}; /* 56 deg down */
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_E_RANGE);
    assert_float_equal(tilt, (float)-atan(1.5), 1e-6f);
    g = plain_geom();
    g.cam_left_m = 0.3f;
    t = (trn_vec3f_t){0.1f, 0.1f, 5.0f}; /* inside the blind radius */
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_E_ARG);
    g = plain_geom();
    g.cam_up_m = 0.3f;
    t = (trn_vec3f_t){0.1f, 0.0f, 1.6f}; /* within cam_up of the tilt axis */
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_E_ARG);
    g = plain_geom();
    g.cam_fwd_m = 2.0f;
    t = (trn_vec3f_t){1.0f, 0.0f, 1.5f}; /* between tilt axis and camera */
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_E_ARG);
    g = plain_geom();
    t = (trn_vec3f_t){NAN, 0.0f, 0.0f};
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_E_ARG);
    t = (trn_vec3f_t){5.0f, 0.0f, 0.0f};
    p.heading_rad = INFINITY;
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_E_ARG);
    p.heading_rad = 0.0f;
    assert_int_equal(trn_mast_point_at(NULL, &p, &t, &pan, &tilt), TRN_E_NULL);
    assert_int_equal(trn_mast_point_at(&g, NULL, &t, &pan, &tilt), TRN_E_NULL);
    assert_int_equal(trn_mast_point_at(&g, &p, NULL, &pan, &tilt), TRN_E_NULL);
    assert_int_equal(trn_mast_point_at(&g, &p, &t, NULL, &tilt), TRN_E_NULL);
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, NULL), TRN_E_NULL);
}

static void test_geom_check(void **state)
{
    trn_mast_geom_t g = plain_geom(), b;
    (void)state;
    assert_int_equal(trn_mast_geom_check(&g), TRN_OK);
    assert_int_equal(trn_mast_geom_check(NULL), TRN_E_NULL);
    b = g;
    b.cam_up_m = NAN;
    assert_int_equal(trn_mast_geom_check(&b), TRN_E_ARG);
    b = g;
    b.pan_min_rad = 1.0f;
    b.pan_max_rad = 0.5f;
    assert_int_equal(trn_mast_geom_check(&b), TRN_E_ARG);
    b = g;
    b.pan_max_rad = 3.2f;
    assert_int_equal(trn_mast_geom_check(&b), TRN_E_ARG);
    b = g;
    b.tilt_min_rad = -1.6f;
    assert_int_equal(trn_mast_geom_check(&b), TRN_E_ARG);
    b = g;
    b.tilt_min_rad = 0.5f;
    b.tilt_max_rad = 0.4f;
    assert_int_equal(trn_mast_geom_check(&b), TRN_E_ARG);
    b = g;
    b.pan_x_m = INFINITY;
    assert_int_equal(trn_mast_geom_check(&b), TRN_E_ARG);
}

static void apply1(const trn_rigid_t *T, float x, float y, float z, trn_vec3f_t *o)
{
    trn_vec3f_t in = {x, y, z};
    assert_int_equal(trn_rigid_apply(T, &in, 1, o), TRN_OK);
}

static void test_camera_to_map_hand(void **state)
{
    trn_mast_geom_t g = plain_geom();
    trn_rover_pose_t p = {0.0f, 0.0f, 0.5f, 0.0f};
    trn_rigid_t T;
    trn_vec3f_t o;
    (void)state;
    assert_int_equal(trn_mast_camera_to_map(&g, &p, 0.0f, 0.0f, &T), TRN_OK);
    apply1(&T, 0, 0, 5, &o); /* 5 m along the boresight = east */
    assert_float_equal(o.x, 5.0f, 1e-6f);
    assert_float_equal(o.y, 0.0f, 1e-6f);
    assert_float_equal(o.z, 2.0f, 1e-6f);
    apply1(&T, 1, 0, 0, &o); /* camera right = south when facing east */
    assert_float_equal(o.x, 0.0f, 1e-6f);
    assert_float_equal(o.y, -1.0f, 1e-6f);
    apply1(&T, 0, 1, 0, &o); /* camera down */
    assert_float_equal(o.z, 1.0f, 1e-6f);
    p.heading_rad = (float)(PI / 2);
    assert_int_equal(trn_mast_camera_to_map(&g, &p, 0.0f, 0.0f, &T), TRN_OK);
    apply1(&T, 0, 0, 5, &o); /* now north */
    assert_float_equal(o.x, 0.0f, 1e-6f);
    assert_float_equal(o.y, 5.0f, 1e-6f);
    assert_int_equal(trn_mast_camera_to_map(&g, &p, (float)(PI / 2), 0.0f, &T), TRN_OK);
    apply1(&T, 0, 0, 5, &o); /* pan left of north = west */
    assert_float_equal(o.x, -5.0f, 1e-5f);
    assert_float_equal(o.y, 0.0f, 1e-5f);
    assert_int_equal(trn_mast_camera_to_map(&g, &p, 0.0f, (float)(-PI / 2), &T), TRN_OK);
    apply1(&T, 0, 0, 2, &o); /* straight down 2 m from 2 m up */
    assert_float_equal(o.x, 0.0f, 1e-6f);
    assert_float_equal(o.y, 0.0f, 1e-5f);
    assert_float_equal(o.z, 0.0f, 1e-5f);
    /* offsets: tilt axis 0.2 ahead, camera 0.1 ahead of it and 0.05 left;
     * tilted down 90 deg the camera sits 0.1 below the axis */
    g.tilt_fwd_m = 0.2f;
    g.cam_fwd_m = 0.1f;
    g.cam_left_m = 0.05f;
    p.heading_rad = 0.0f;
    assert_int_equal(trn_mast_camera_to_map(&g, &p, 0.0f, (float)(-PI / 2), &T), TRN_OK);
    assert_float_equal(T.t.x, 0.2f, 1e-6f);
    assert_float_equal(T.t.y, 0.05f, 1e-6f);
    assert_float_equal(T.t.z, 0.5f + 1.5f - 0.1f, 1e-6f);
    assert_int_equal(trn_mast_camera_to_map(NULL, &p, 0, 0, &T), TRN_E_NULL);
    assert_int_equal(trn_mast_camera_to_map(&g, NULL, 0, 0, &T), TRN_E_NULL);
    assert_int_equal(trn_mast_camera_to_map(&g, &p, 0, 0, NULL), TRN_E_NULL);
    assert_int_equal(trn_mast_camera_to_map(&g, &p, NAN, 0, &T), TRN_E_ARG);
    assert_int_equal(trn_mast_camera_to_map(&g, &p, 0, INFINITY, &T), TRN_E_ARG);
    assert_int_equal(trn_rigid_apply(NULL, &o, 1, &o), TRN_E_NULL);
    assert_int_equal(trn_rigid_apply(&T, NULL, 1, &o), TRN_E_NULL);
    assert_int_equal(trn_rigid_apply(&T, &o, 1, NULL), TRN_E_NULL);
    assert_int_equal(trn_rigid_apply(&T, NULL, 0, NULL), TRN_OK);
}

static float frand(trn_rng_t *r, double lo, double hi)
{
    return (float)(lo + (hi - lo) * trn_rng_unit(r));
}

static void test_round_trip_boresight(void **state)
{
    trn_rng_t r;
    int i, n_ok = 0;
    double worst = 0.0;
    (void)state;
    trn_rng_seed(&r, 11);
    for (i = 0; i < 5000; ++i) {
        trn_mast_geom_t g = plain_geom();
        trn_rover_pose_t p;
        trn_vec3f_t t;
        trn_rigid_t T;
        float pan, tilt, d[3], c[3], dist;
        trn_status_t st;
        int k;
        g.pan_x_m = frand(&r, -0.5, 0.5);
        g.pan_y_m = frand(&r, -0.5, 0.5);
        g.pan_z_m = frand(&r, 0.5, 2.0);
        g.tilt_fwd_m = frand(&r, -0.1, 0.2);
        g.tilt_up_m = frand(&r, 0.0, 0.3);
        g.cam_fwd_m = frand(&r, 0.0, 0.1);
        g.cam_left_m = frand(&r, -0.2, 0.2);
        g.cam_up_m = frand(&r, -0.1, 0.1);
        p.x_m = frand(&r, -100, 100);
        p.y_m = frand(&r, -100, 100);
        p.z_m = frand(&r, -5, 5);
        p.heading_rad = frand(&r, -PI, PI);
        t.x = p.x_m + frand(&r, -20, 20);
        t.y = p.y_m + frand(&r, -20, 20);
        t.z = p.z_m + frand(&r, -3, 3);
        st = trn_mast_point_at(&g, &p, &t, &pan, &tilt);
        if (st == TRN_E_ARG) {
            continue; /* inside the mast's blind zone */
        }
        assert_int_equal(st, TRN_OK);
        assert_int_equal(trn_mast_camera_to_map(&g, &p, pan, tilt, &T), TRN_OK);
        /* target in the camera frame: R^T (t - c) */
        d[0] = t.x - T.t.x;
        d[1] = t.y - T.t.y;
        d[2] = t.z - T.t.z;
        for (k = 0; k < 3; ++k) {
            c[k] = T.r[k] * d[0] + T.r[3 + k] * d[1] + T.r[6 + k] * d[2];
        }
        dist = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        assert_true(c[2] > 0.0f);
        if (fabs(c[0]) / dist > worst) {
            worst = fabs(c[0]) / dist;
        }
        if (fabs(c[1]) / dist > worst) {
            worst = fabs(c[1]) / dist;
        }
        /* off-axis error, as an angle: float rounding only */
        assert_true(fabsf(c[0]) < 1e-4f * dist + 1e-4f);
        assert_true(fabsf(c[1]) < 1e-4f * dist + 1e-4f);
        /* R is a rotation */
        for (k = 0; k < 3; ++k) {
            int m;
            for (m = 0; m < 3; ++m) {
                float dot = T.r[k] * T.r[m] + T.r[3 + k] * T.r[3 + m] + T.r[6 + k] * T.r[6 + m];
                assert_float_equal(dot, k == m ? 1.0f : 0.0f, 1e-5f);
            }
        }
        ++n_ok;
    }
    assert_true(n_ok > 4500);
    print_message("boresight round trip: %d targets, worst off-axis %.3g rad\n", n_ok, worst);
}

static float g_dem[64 * 48];

static void test_local_dem_hand(void **state)
{
    trn_grid_f32_t dem;
    trn_rover_pose_t p = {100.0f, 200.0f, 0.0f, 1.0f}; /* heading does not matter */
    trn_local_dem_cfg_t cfg = {0.5f, 10, 20, 1};
    trn_vec3f_t pts[7] = {
        {100.0f, 200.0f, 1.0f},    /* rover cell (10, 20) */
        {100.2f, 200.2f, 3.0f},    /* same cell, higher */
        {100.1f, 199.9f, 2.0f},    /* same cell, lower */
        {101.0f, 199.0f, -1.0f},   /* 2 east, 2 south: (12, 18) */
        {NAN, 200.0f, 5.0f},       /* skipped */
        {50.0f, 200.0f, 5.0f},     /* 100 cells west: off the grid */
        {100.0f, 200.0f, INFINITY} /* skipped */
    };
    size_t used = 0;
    int x, y, n_nan = 0;
    (void)state;
    assert_int_equal(trn_grid_f32_init(&dem, g_dem, 64 * 48, 64, 48), TRN_OK);
    assert_int_equal(trn_mast_local_dem(pts, 7, &p, &cfg, &dem, &used), TRN_OK);
    assert_int_equal(used, 4);
    assert_float_equal(TRN_GRID_AT(&dem, 10, 20), 3.0f, 0.0f);
    assert_float_equal(TRN_GRID_AT(&dem, 12, 18), -1.0f, 0.0f);
    for (y = 0; y < 48; ++y) {
        for (x = 0; x < 64; ++x) {
            n_nan += isnan(TRN_GRID_AT(&dem, x, y)) ? 1 : 0;
        }
    }
    assert_int_equal(n_nan, 64 * 48 - 2);
    /* north-up rows: south is +row */
    cfg.row_north = -1;
    assert_int_equal(trn_mast_local_dem(pts, 7, &p, &cfg, &dem, &used), TRN_OK);
    assert_float_equal(TRN_GRID_AT(&dem, 12, 22), -1.0f, 0.0f);
    assert_true(isnan(TRN_GRID_AT(&dem, 12, 18)));
    /* cell boundaries: +0.25 m rounds up (half up), just below stays */
    cfg.row_north = 1;
    pts[0] = (trn_vec3f_t){100.25f, 200.0f, 7.0f};
    pts[1] = (trn_vec3f_t){100.2499f, 200.0f, 8.0f};
    assert_int_equal(trn_mast_local_dem(pts, 2, &p, &cfg, &dem, &used), TRN_OK);
    assert_float_equal(TRN_GRID_AT(&dem, 11, 20), 7.0f, 0.0f);
    assert_float_equal(TRN_GRID_AT(&dem, 10, 20), 8.0f, 0.0f);
    /* nothing on the grid */
    assert_int_equal(trn_mast_local_dem(pts + 5, 1, &p, &cfg, &dem, &used), TRN_E_NODATA);
    assert_int_equal(used, 0);
    assert_true(isnan(TRN_GRID_AT(&dem, 10, 20)));
    assert_int_equal(trn_mast_local_dem(NULL, 0, &p, &cfg, &dem, NULL), TRN_E_NODATA);
    /* arguments */
    assert_int_equal(trn_mast_local_dem(NULL, 1, &p, &cfg, &dem, NULL), TRN_E_NULL);
    assert_int_equal(trn_mast_local_dem(pts, 1, NULL, &cfg, &dem, NULL), TRN_E_NULL);
    assert_int_equal(trn_mast_local_dem(pts, 1, &p, NULL, &dem, NULL), TRN_E_NULL);
    assert_int_equal(trn_mast_local_dem(pts, 1, &p, &cfg, NULL, NULL), TRN_E_NULL);
    cfg.row_north = 0;
    assert_int_equal(trn_mast_local_dem(pts, 1, &p, &cfg, &dem, NULL), TRN_E_ARG);
    cfg.row_north = 1;
    cfg.cell_m = 0.0f;
    assert_int_equal(trn_mast_local_dem(pts, 1, &p, &cfg, &dem, NULL), TRN_E_ARG);
    cfg.cell_m = NAN;
    assert_int_equal(trn_mast_local_dem(pts, 1, &p, &cfg, &dem, NULL), TRN_E_ARG);
    cfg.cell_m = 0.5f;
    cfg.rover_col = -TRN_MAX_DIM - 1;
    assert_int_equal(trn_mast_local_dem(pts, 1, &p, &cfg, &dem, NULL), TRN_E_ARG);
    cfg.rover_col = 10;
    p.x_m = NAN;
    assert_int_equal(trn_mast_local_dem(pts, 1, &p, &cfg, &dem, NULL), TRN_E_ARG);
    p.x_m = 100.0f;
    dem.width = 0;
    assert_int_equal(trn_mast_local_dem(pts, 1, &p, &cfg, &dem, NULL), TRN_E_SIZE);
}

/* Terrain seen from the mast -> camera frame in whole millimetres (the
 * capture's resolution) -> back to the map -> local DEM: every terrain cell
 * centre comes back in its cell with its height. */
static void test_end_to_end_terrain(void **state)
{
    static synth_rock_t rocks[20];
    static trn_vec3f_t cam[64 * 48];
    static float truth[64 * 48];
    synth_terrain_t terr;
    trn_mast_geom_t g = plain_geom();
    trn_rover_pose_t p = {12.3f, 7.9f, 0.0f, 0.7f};
    trn_local_dem_cfg_t cfg = {0.1f, 32, 24, 1};
    trn_vec3f_t target;
    trn_rigid_t T;
    trn_grid_f32_t dem;
    float pan, tilt;
    size_t n = 0, used = 0, i;
    int x, y;
    (void)state;
    synth_make(&terr, rocks, 20, 25.0, 0.1, 0.4, 0.5, 0.2, 5);
    g.pan_x_m = 0.3f;
    g.tilt_fwd_m = 0.05f;
    g.tilt_up_m = 0.1f;
    g.cam_fwd_m = 0.04f;
    g.cam_left_m = 0.06f;
    g.cam_up_m = 0.02f;
    p.z_m = (float)synth_height(&terr, p.x_m, p.y_m);
    target.x = p.x_m + 2.0f;
    target.y = p.y_m + 1.0f;
    target.z = (float)synth_height(&terr, target.x, target.y);
    assert_int_equal(trn_mast_point_at(&g, &p, &target, &pan, &tilt), TRN_OK);
    assert_int_equal(trn_mast_camera_to_map(&g, &p, pan, tilt, &T), TRN_OK);
    for (y = 0; y < 48; ++y) {
        for (x = 0; x < 64; ++x) {
            double mx = p.x_m + (float)(x - cfg.rover_col) * cfg.cell_m;
            double my = p.y_m + (float)(y - cfg.rover_row) * cfg.cell_m;
            double h = synth_height(&terr, mx, my);
            const double d[3] = {mx - T.t.x, my - T.t.y, h - T.t.z};
            double c[3];
            int k;
            for (k = 0; k < 3; ++k) {
                c[k] = T.r[k] * d[0] + T.r[3 + k] * d[1] + T.r[6 + k] * d[2];
            }
            truth[y * 64 + x] = (float)h;
            /* whole millimetres, as a capture carries them */
            cam[n].x = (float)(floor(c[0] * 1000.0 + 0.5) / 1000.0);
            cam[n].y = (float)(floor(c[1] * 1000.0 + 0.5) / 1000.0);
            cam[n].z = (float)(floor(c[2] * 1000.0 + 0.5) / 1000.0);
            ++n;
        }
    }
    assert_int_equal(trn_rigid_apply(&T, cam, n, cam), TRN_OK); /* in place */
    assert_int_equal(trn_grid_f32_init(&dem, g_dem, 64 * 48, 64, 48), TRN_OK);
    assert_int_equal(trn_mast_local_dem(cam, n, &p, &cfg, &dem, &used), TRN_OK);
    assert_int_equal(used, n);
    for (i = 0; i < n; ++i) {
        /* mm quantization (<= 0.87 mm) plus float rounding at ~20 m */
        assert_float_equal(g_dem[i], truth[i], 2e-3f);
    }
}

/* The loop of issue 6 without the bus: point the mast at four targets
 * around the rover, take stereo points of the terrain there (camera frame,
 * whole millimetres, angles in 1e-4 rad counts as the capture carries
 * them), build the local DEM in the rover's frame and localize it in the
 * global map. The rover's map position is unknown to the local map (it is
 * built around (0, 0)): only heading and the mast are used, as on the rover.
 * The same transform makes and reads the camera points, so this checks the
 * frames of the local DEM against localize (axes, rows, rover cell; with
 * rows flipped the estimate is 8 cells off) - the transform itself is
 * checked by the hand-computed tests above. */
static void test_localize_from_mast_views(void **state)
{
    enum { N = 192, L = 96, MAXP = 40000 };
    const double cell = 0.1;
    static synth_rock_t rocks[1000];
    static float gdem[N * N], ldem[L * L];
    static trn_vec3f_t pts[MAXP];
    synth_terrain_t terr;
    trn_grid_f32_t g, lg;
    trn_map_cfg_t cfg;
    trn_map_t map;
    trn_window_t win;
    trn_loc_result_t res;
    trn_mast_geom_t geo = plain_geom();
    const trn_rover_pose_t truth = {9.63f, 9.47f, 0.0f, 0.5f};
    trn_rover_pose_t known = truth; /* what the rover knows: heading only */
    trn_local_dem_cfg_t dcfg = {0.1f, L / 2, L / 2, 1};
    size_t nrocks = (size_t)(N * N * cell * cell * 0.15 / (PI * 0.15 * 0.15)), mb, wb, n = 0,
           used = 0;
    void *mbuf, *ws;
    int view;
    trn_status_t st;
    (void)state;
    assert_true(nrocks <= 1000);
    synth_make(&terr, rocks, nrocks, N * cell, 0.05, 0.3, 0.5, 0.2, 12);
    synth_render(&terr, gdem, N, N, 0.0, 0.0, cell);
    assert_int_equal(trn_grid_f32_init(&g, gdem, N * N, N, N), TRN_OK);
    trn_map_cfg_default(&cfg);
    mb = trn_map_bytes(&cfg, N, N);
    mbuf = malloc(mb); /* malloc aligns to 16 bytes on the test hosts */
    assert_non_null(mbuf);
    assert_int_equal(trn_map_build(&map, &cfg, &g, mbuf, mb), TRN_OK);

    geo.pan_x_m = 0.2f;
    geo.pan_z_m = 1.4f;
    geo.tilt_fwd_m = 0.05f;
    geo.cam_left_m = 0.1f;
    geo.cam_up_m = 0.03f;
    known.x_m = 0.0f;
    known.y_m = 0.0f;
    known.z_m = 0.0f;
    for (view = 0; view < 4; ++view) {
        double a = truth.heading_rad + view * PI / 2;
        int kx, ky;
        trn_vec3f_t target;
        trn_rigid_t Ttrue, Tknown;
        float pan, tilt;
        int16_t pan_raw = 0, tilt_raw = 0;
        target.x = truth.x_m + (float)(2.5 * cos(a));
        target.y = truth.y_m + (float)(2.5 * sin(a));
        target.z = (float)synth_height(&terr, target.x, target.y);
        assert_int_equal(trn_mast_point_at(&geo, &truth, &target, &pan, &tilt), TRN_OK);
        assert_int_equal(trn_can_angle_to_raw_for_test(pan, &pan_raw), 0);
        assert_int_equal(trn_can_angle_to_raw_for_test(tilt, &tilt_raw), 0);
        /* the world as the head sees it at the measured angles */
        assert_int_equal(
            trn_mast_camera_to_map(&geo, &truth, pan_raw * 1e-4f, tilt_raw * 1e-4f, &Ttrue),
            TRN_OK);
        assert_int_equal(
            trn_mast_camera_to_map(&geo, &known, pan_raw * 1e-4f, tilt_raw * 1e-4f, &Tknown),
            TRN_OK);
        /* stereo footprint: terrain within 1.6 m of the target, 4 cm spacing */
        for (ky = 0; ky < 80; ++ky) { /* -1.6 to 1.56 m */
            const double iy = -1.6 + 0.04 * ky;
            for (kx = 0; kx < 80; ++kx) {
                const double ix = -1.6 + 0.04 * kx;
                double mx = target.x + ix, my = target.y + iy, h, d[3], c[3];
                int k;
                if (ix * ix + iy * iy > 1.6 * 1.6) {
                    continue;
                }
                h = synth_height(&terr, mx, my);
                d[0] = mx - Ttrue.t.x;
                d[1] = my - Ttrue.t.y;
                d[2] = h - Ttrue.t.z;
                for (k = 0; k < 3; ++k) {
                    c[k] = Ttrue.r[k] * d[0] + Ttrue.r[3 + k] * d[1] + Ttrue.r[6 + k] * d[2];
                }
                assert_true(n < MAXP);
                pts[n].x = (float)(floor(c[0] * 1000.0 + 0.5) / 1000.0);
                pts[n].y = (float)(floor(c[1] * 1000.0 + 0.5) / 1000.0);
                pts[n].z = (float)(floor(c[2] * 1000.0 + 0.5) / 1000.0);
                /* the rover maps them with what it knows */
                assert_int_equal(trn_rigid_apply(&Tknown, &pts[n], 1, &pts[n]), TRN_OK);
                ++n;
            }
        }
    }
    assert_int_equal(trn_grid_f32_init(&lg, ldem, L * L, L, L), TRN_OK);
    assert_int_equal(trn_mast_local_dem(pts, n, &known, &dcfg, &lg, &used), TRN_OK);
    assert_int_equal(used, n);

    /* prior: 6 cells off, window +-15 cells */
    win.x0 = 96 + 6 - 15;
    win.x1 = 96 + 6 + 15;
    win.y0 = 95 - 6 - 15;
    win.y1 = 95 - 6 + 15;
    wb = trn_localize_dem_workspace_bytes(&map, L, L, (size_t)L * L * cfg.terrain.nz, &win);
    assert_true(wb > 0);
    ws = malloc(wb);
    assert_non_null(ws);
    st = trn_localize_dem(&map, &lg, L / 2, L / 2, (size_t)L * L * cfg.terrain.nz, &win, ws, wb,
                          &res);
    assert_true(st == TRN_OK || st == TRN_E_ILLCOND);
    print_message("mast views: %zu points, estimate (%.2f, %.2f) cells, truth (%.2f, %.2f), sigma "
                  "%.3f/%.3f m, "
                  "P_fail %.3g\n",
                  n, res.x, res.y, truth.x_m / cell, truth.y_m / cell, res.sigma_x_m, res.sigma_y_m,
                  res.failure_probability);
    assert_true(fabs(res.x - truth.x_m / cell) < 1.0);
    assert_true(fabs(res.y - truth.y_m / cell) < 1.0);
    free(ws);
    free(mbuf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_point_at_hand),
        cmocka_unit_test(test_point_at_offsets_hand),
        cmocka_unit_test(test_point_at_limits_and_args),
        cmocka_unit_test(test_geom_check),
        cmocka_unit_test(test_camera_to_map_hand),
        cmocka_unit_test(test_round_trip_boresight),
        cmocka_unit_test(test_local_dem_hand),
        cmocka_unit_test(test_end_to_end_terrain),
        cmocka_unit_test(test_localize_from_mast_views),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
