/* SPDX-License-Identifier: Apache-2.0 */
/* test_mast_errors.c - every argument check of mast.h, one assertion per
 * rejected clause (docs/assurance.md, "Coverage"): each geometry field
 * not finite, each joint limit out of its range, each pose and target
 * coordinate, the three targets no boresight can reach, each joint limit
 * side for TRN_E_RANGE, and the local DEM's placement checks and the points
 * it skips (off each edge of the grid, farther than 2 TRN_MAX_DIM cells,
 * not finite). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "trn/mast.h"

static void geom(trn_mast_geom_t *g)
{
    memset(g, 0, sizeof *g);
    g->pan_z_m = 1.0f;
    g->tilt_fwd_m = 0.05f;
    g->tilt_up_m = 0.1f;
    g->cam_fwd_m = 0.05f;
    g->cam_left_m = 0.1f;
    g->cam_up_m = 0.02f;
    g->pan_min_rad = -3.0f;
    g->pan_max_rad = 3.0f;
    g->tilt_min_rad = -1.5f;
    g->tilt_max_rad = 1.0f;
}

static void test_geom_check_each_field(void **state)
{
    trn_mast_geom_t g, b;
    float *f;
    size_t i;
    (void)state;
    geom(&g);
    assert_int_equal(trn_mast_geom_check(&g), TRN_OK);
    assert_int_equal(trn_mast_geom_check(NULL), TRN_E_NULL);
    /* the struct is 12 floats: each one NaN, then inf */
    for (i = 0; i < sizeof g / sizeof(float); ++i) {
        b = g;
        f = (float *)(void *)&b;
        f[i] = NAN;
        assert_int_equal(trn_mast_geom_check(&b), TRN_E_ARG);
        f[i] = INFINITY;
        assert_int_equal(trn_mast_geom_check(&b), TRN_E_ARG);
    }
    b = g;
    b.pan_min_rad = -3.2f;
    assert_int_equal(trn_mast_geom_check(&b), TRN_E_ARG);
    b = g;
    b.pan_max_rad = 3.2f;
    assert_int_equal(trn_mast_geom_check(&b), TRN_E_ARG);
    b = g;
    b.pan_min_rad = 1.0f;
    b.pan_max_rad = 0.5f;
    assert_int_equal(trn_mast_geom_check(&b), TRN_E_ARG);
    b = g;
    b.tilt_min_rad = -1.6f;
    assert_int_equal(trn_mast_geom_check(&b), TRN_E_ARG);
    b = g;
    b.tilt_max_rad = 1.6f;
    assert_int_equal(trn_mast_geom_check(&b), TRN_E_ARG);
    b = g;
    b.tilt_min_rad = 0.5f;
    b.tilt_max_rad = 0.2f;
    assert_int_equal(trn_mast_geom_check(&b), TRN_E_ARG);
}

static void test_point_at_each_argument(void **state)
{
    trn_mast_geom_t g, b;
    trn_rover_pose_t p = {1.0f, 2.0f, 0.0f, 0.3f}, pb;
    trn_vec3f_t t = {6.0f, 3.0f, 0.0f}, tb;
    float pan = 0.0f, tilt = 0.0f;
    (void)state;
    geom(&g);
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_OK);
    assert_int_equal(trn_mast_point_at(NULL, &p, &t, &pan, &tilt), TRN_E_NULL);
    assert_int_equal(trn_mast_point_at(&g, NULL, &t, &pan, &tilt), TRN_E_NULL);
    assert_int_equal(trn_mast_point_at(&g, &p, NULL, &pan, &tilt), TRN_E_NULL);
    assert_int_equal(trn_mast_point_at(&g, &p, &t, NULL, &tilt), TRN_E_NULL);
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, NULL), TRN_E_NULL);
    b = g;
    b.cam_up_m = NAN;
    assert_int_equal(trn_mast_point_at(&b, &p, &t, &pan, &tilt), TRN_E_ARG);
    pb = p;
    pb.x_m = NAN;
    assert_int_equal(trn_mast_point_at(&g, &pb, &t, &pan, &tilt), TRN_E_ARG);
    pb = p;
    pb.y_m = INFINITY;
    assert_int_equal(trn_mast_point_at(&g, &pb, &t, &pan, &tilt), TRN_E_ARG);
    pb = p;
    pb.z_m = NAN;
    assert_int_equal(trn_mast_point_at(&g, &pb, &t, &pan, &tilt), TRN_E_ARG);
    pb = p;
    pb.heading_rad = NAN;
    assert_int_equal(trn_mast_point_at(&g, &pb, &t, &pan, &tilt), TRN_E_ARG);
    tb = t;
    tb.x = NAN;
    assert_int_equal(trn_mast_point_at(&g, &p, &tb, &pan, &tilt), TRN_E_ARG);
    tb = t;
    tb.y = NAN;
    assert_int_equal(trn_mast_point_at(&g, &p, &tb, &pan, &tilt), TRN_E_ARG);
    tb = t;
    tb.z = INFINITY;
    assert_int_equal(trn_mast_point_at(&g, &p, &tb, &pan, &tilt), TRN_E_ARG);
    /* unreachable: on the pan axis (within cam_left of it) */
    tb.x = p.x_m;
    tb.y = p.y_m;
    tb.z = 0.0f;
    assert_int_equal(trn_mast_point_at(&g, &p, &tb, &pan, &tilt), TRN_E_ARG);
}

static void test_point_at_unreachable_and_limits(void **state)
{
    trn_mast_geom_t g, b;
    const trn_rover_pose_t p = {0.0f, 0.0f, 0.0f, 0.0f};
    trn_vec3f_t t;
    float pan = 0.0f, tilt = 0.0f;
    (void)state;
    geom(&g);
    /* within cam_up of the tilt axis: straight ahead, at the axis height */
    b = g;
    b.cam_left_m = 0.0f;
    b.cam_up_m = 0.3f;
    t.x = b.tilt_fwd_m + 0.1f;
    t.y = 0.0f;
    t.z = b.pan_z_m + b.tilt_up_m;
    assert_int_equal(trn_mast_point_at(&b, &p, &t, &pan, &tilt), TRN_E_ARG);
    /* reachable in angle but not ahead of the optical centre */
    b = g;
    b.cam_left_m = 0.0f;
    b.cam_up_m = 0.0f;
    b.cam_fwd_m = 2.0f;
    t.x = 1.0f;
    t.z = b.pan_z_m + b.tilt_up_m;
    assert_int_equal(trn_mast_point_at(&b, &p, &t, &pan, &tilt), TRN_E_ARG);
    /* each joint limit side: the angles are written with TRN_E_RANGE */
    b = g;
    b.cam_left_m = 0.0f;
    b.pan_min_rad = 0.5f;
    t.x = 5.0f;
    t.y = 0.0f;
    t.z = 1.0f;
    assert_int_equal(trn_mast_point_at(&b, &p, &t, &pan, &tilt), TRN_E_RANGE);
    assert_true(pan < 0.5f);
    b = g;
    b.cam_left_m = 0.0f;
    b.pan_max_rad = -0.5f;
    b.pan_min_rad = -1.0f;
    assert_int_equal(trn_mast_point_at(&b, &p, &t, &pan, &tilt), TRN_E_RANGE);
    b = g;
    b.tilt_min_rad = 0.2f;
    b.tilt_max_rad = 0.4f;
    assert_int_equal(trn_mast_point_at(&b, &p, &t, &pan, &tilt), TRN_E_RANGE);
    assert_true(tilt < 0.2f);
    b = g;
    b.tilt_min_rad = -1.0f;
    b.tilt_max_rad = -0.8f;
    assert_int_equal(trn_mast_point_at(&b, &p, &t, &pan, &tilt), TRN_E_RANGE);
    /* a target behind and slightly right: pan wraps below -pi back into range */
    b = g;
    b.cam_left_m = 0.2f;
    b.pan_min_rad = -3.1415926f;
    b.pan_max_rad = 3.1415926f;
    t.x = -5.0f;
    t.y = -0.05f;
    assert_int_equal(trn_mast_point_at(&b, &p, &t, &pan, &tilt), TRN_OK);
    assert_true(pan > 0.0f && pan <= 3.1415927f);
}

/* fuzz_mast, crash-8d82e3590081e466674209ecc5dc1631d60d7b0a (a harness
 * invariant, not a code defect): the tilt axis 14.4 m ahead of the pan axis,
 * the target at the rover's origin behind it. atan2 gives about -pi and the
 * camera offset takes asin(12 / 13.9) more: tilt -4.18 rad, not wrapped, as
 * mast.h now states; the status is TRN_E_RANGE for every such tilt. */
static void test_point_at_target_behind_the_tilt_axis(void **state)
{
    trn_mast_geom_t g;
    const trn_rover_pose_t p = {0.0f, 0.0f, 0.0f, 0.0f};
    const trn_vec3f_t t = {0.0f, 0.0f, 0.0f};
    float pan = 0.0f, tilt = 0.0f;
    (void)state;
    memset(&g, 0, sizeof g);
    g.pan_x_m = 0.5f;
    g.pan_y_m = 0.1f;
    g.tilt_fwd_m = 14.4f;
    g.tilt_up_m = 1.0e-6f; /* the target slightly below the axis: atan2 near -pi, not +pi */
    g.cam_up_m = 12.0f;
    g.tilt_min_rad = -1.5f;
    g.tilt_max_rad = 1.5f;
    g.pan_min_rad = -3.1f;
    g.pan_max_rad = 3.1f;
    assert_int_equal(trn_mast_point_at(&g, &p, &t, &pan, &tilt), TRN_E_RANGE);
    assert_true(tilt < -3.1415927f && tilt > -4.7123890f);
    assert_true(fabsf(pan) <= 3.1415927f);
}

static void test_camera_to_map_each_argument(void **state)
{
    trn_mast_geom_t g, b;
    trn_rover_pose_t p = {1.0f, 2.0f, 0.5f, 0.3f}, pb;
    trn_rigid_t T;
    (void)state;
    geom(&g);
    assert_int_equal(trn_mast_camera_to_map(&g, &p, 0.1f, -0.2f, &T), TRN_OK);
    assert_int_equal(trn_mast_camera_to_map(NULL, &p, 0.1f, -0.2f, &T), TRN_E_NULL);
    assert_int_equal(trn_mast_camera_to_map(&g, NULL, 0.1f, -0.2f, &T), TRN_E_NULL);
    assert_int_equal(trn_mast_camera_to_map(&g, &p, 0.1f, -0.2f, NULL), TRN_E_NULL);
    b = g;
    b.pan_x_m = INFINITY;
    assert_int_equal(trn_mast_camera_to_map(&b, &p, 0.1f, -0.2f, &T), TRN_E_ARG);
    pb = p;
    pb.heading_rad = INFINITY;
    assert_int_equal(trn_mast_camera_to_map(&g, &pb, 0.1f, -0.2f, &T), TRN_E_ARG);
    assert_int_equal(trn_mast_camera_to_map(&g, &p, NAN, -0.2f, &T), TRN_E_ARG);
    assert_int_equal(trn_mast_camera_to_map(&g, &p, 0.1f, INFINITY, &T), TRN_E_ARG);
    assert_int_equal(trn_rigid_apply(NULL, NULL, 0u, NULL), TRN_E_NULL);
    assert_int_equal(trn_rigid_apply(&T, NULL, 1u, (trn_vec3f_t *)&p), TRN_E_NULL);
    assert_int_equal(trn_rigid_apply(&T, (const trn_vec3f_t *)&p, 1u, NULL), TRN_E_NULL);
    assert_int_equal(trn_rigid_apply(&T, NULL, 0u, NULL), TRN_OK);
}

static void test_local_dem_checks_and_skips(void **state)
{
    const trn_rover_pose_t p = {10.0f, 20.0f, 0.0f, 0.0f};
    trn_rover_pose_t pb = p;
    trn_local_dem_cfg_t c = {0.5f, 2, 2, 1}, cb;
    trn_vec3f_t pts[9];
    float cells[25];
    trn_grid_f32_t dem, db;
    size_t used = 0u;
    (void)state;
    assert_int_equal(trn_grid_f32_init(&dem, cells, 25u, 5, 5), TRN_OK);
    /* in the grid: the rover cell and one cell north-east */
    pts[0].x = 10.0f;
    pts[0].y = 20.0f;
    pts[0].z = 1.0f;
    pts[1].x = 10.5f;
    pts[1].y = 20.5f;
    pts[1].z = 2.0f;
    /* off each edge: west, east, south, north */
    pts[2].x = 8.5f;
    pts[2].y = 20.0f;
    pts[2].z = 3.0f;
    pts[3].x = 11.5f;
    pts[3].y = 20.0f;
    pts[3].z = 3.0f;
    pts[4].x = 10.0f;
    pts[4].y = 18.5f;
    pts[4].z = 3.0f;
    pts[5].x = 10.0f;
    pts[5].y = 21.5f;
    pts[5].z = 3.0f;
    /* farther than 2 TRN_MAX_DIM cells in x, then in y; not finite */
    pts[6].x = 1.0e9f;
    pts[6].y = 20.0f;
    pts[6].z = 3.0f;
    pts[7].x = 10.0f;
    pts[7].y = -1.0e9f;
    pts[7].z = 3.0f;
    pts[8].x = 10.0f;
    pts[8].y = 20.0f;
    pts[8].z = NAN;
    assert_int_equal(trn_mast_local_dem(pts, 9u, &p, &c, &dem, &used), TRN_OK);
    assert_int_equal((int)used, 2);
    assert_true(TRN_GRID_AT(&dem, 2, 2) == 1.0f);
    assert_true(TRN_GRID_AT(&dem, 3, 3) == 2.0f);
    assert_int_equal(trn_mast_local_dem(&pts[2], 7u, &p, &c, &dem, NULL), TRN_E_NODATA);
    assert_true(isnan(TRN_GRID_AT(&dem, 2, 2)));
    /* the arguments */
    assert_int_equal(trn_mast_local_dem(pts, 1u, &p, &c, NULL, &used), TRN_E_NULL);
    assert_int_equal(trn_mast_local_dem(pts, 1u, NULL, &c, &dem, &used), TRN_E_NULL);
    assert_int_equal(trn_mast_local_dem(pts, 1u, &p, NULL, &dem, &used), TRN_E_NULL);
    assert_int_equal(trn_mast_local_dem(NULL, 1u, &p, &c, &dem, &used), TRN_E_NULL);
    assert_int_equal(trn_mast_local_dem(NULL, 0u, &p, &c, &dem, &used), TRN_E_NODATA);
    db = dem;
    db.width = 0;
    assert_int_equal(trn_mast_local_dem(pts, 1u, &p, &c, &db, &used), TRN_E_SIZE);
    cb = c;
    cb.cell_m = INFINITY;
    assert_int_equal(trn_mast_local_dem(pts, 1u, &p, &cb, &dem, &used), TRN_E_ARG);
    cb.cell_m = 0.0f;
    assert_int_equal(trn_mast_local_dem(pts, 1u, &p, &cb, &dem, &used), TRN_E_ARG);
    cb = c;
    cb.row_north = 0;
    assert_int_equal(trn_mast_local_dem(pts, 1u, &p, &cb, &dem, &used), TRN_E_ARG);
    cb = c;
    cb.rover_col = -TRN_MAX_DIM - 1;
    assert_int_equal(trn_mast_local_dem(pts, 1u, &p, &cb, &dem, &used), TRN_E_ARG);
    cb = c;
    cb.rover_col = 5 + TRN_MAX_DIM + 1;
    assert_int_equal(trn_mast_local_dem(pts, 1u, &p, &cb, &dem, &used), TRN_E_ARG);
    cb = c;
    cb.rover_row = -TRN_MAX_DIM - 1;
    assert_int_equal(trn_mast_local_dem(pts, 1u, &p, &cb, &dem, &used), TRN_E_ARG);
    cb = c;
    cb.rover_row = 5 + TRN_MAX_DIM + 1;
    assert_int_equal(trn_mast_local_dem(pts, 1u, &p, &cb, &dem, &used), TRN_E_ARG);
    pb.x_m = NAN;
    assert_int_equal(trn_mast_local_dem(pts, 1u, &pb, &c, &dem, &used), TRN_E_ARG);
    pb.x_m = 10.0f;
    pb.y_m = INFINITY;
    assert_int_equal(trn_mast_local_dem(pts, 1u, &pb, &c, &dem, &used), TRN_E_ARG);
}

/* trn_mast_local_dem_mean: the mean of each cell's points (against the
 * obvious sum / count), the same skips and argument checks as the highest-
 * point builder, and its own two statuses. */
static void test_local_dem_mean(void **state)
{
    const trn_rover_pose_t p = {10.0f, 20.0f, 0.0f, 0.0f};
    trn_local_dem_cfg_t c = {0.5f, 2, 2, 1}, cb;
    trn_vec3f_t pts[8];
    float cells[25];
    uint32_t cnt[25];
    trn_grid_f32_t dem;
    size_t used = 0u;
    int i;
    (void)state;
    assert_int_equal(trn_grid_f32_init(&dem, cells, 25u, 5, 5), TRN_OK);
    /* rover cell: 1, 2, 6 (mean 3); one cell north-east: 4000.25, 4000.75
     * (mean 4000.5: absolute heights keep their precision); off the grid;
     * not finite */
    pts[0].x = 10.0f;
    pts[0].y = 20.0f;
    pts[0].z = 1.0f;
    pts[1].x = 10.1f;
    pts[1].y = 19.9f;
    pts[1].z = 2.0f;
    pts[2].x = 9.9f;
    pts[2].y = 20.2f;
    pts[2].z = 6.0f;
    pts[3].x = 10.5f;
    pts[3].y = 20.5f;
    pts[3].z = 4000.25f;
    pts[4].x = 10.6f;
    pts[4].y = 20.4f;
    pts[4].z = 4000.75f;
    pts[5].x = 8.5f;
    pts[5].y = 20.0f;
    pts[5].z = 9.0f;
    pts[6].x = 10.0f;
    pts[6].y = 20.0f;
    pts[6].z = NAN;
    pts[7].x = 1.0e9f;
    pts[7].y = 20.0f;
    pts[7].z = 9.0f;
    assert_int_equal(trn_mast_local_dem_mean(pts, 8u, &p, &c, &dem, cnt, 25u, &used), TRN_OK);
    assert_int_equal((int)used, 5);
    assert_true(fabsf(TRN_GRID_AT(&dem, 2, 2) - 3.0f) < 1e-6f);
    assert_true(fabsf(TRN_GRID_AT(&dem, 3, 3) - 4000.5f) < 1e-3f);
    assert_int_equal((int)cnt[2 * 5 + 2], 3);
    assert_int_equal((int)cnt[3 * 5 + 3], 2);
    for (i = 0; i < 25; ++i) {
        if (i != 12 && i != 18) {
            assert_true(isnan(cells[i]) && cnt[i] == 0u);
        }
    }
    /* the highest point of the same cells, for contrast */
    assert_int_equal(trn_mast_local_dem(pts, 8u, &p, &c, &dem, &used), TRN_OK);
    assert_true(TRN_GRID_AT(&dem, 2, 2) == 6.0f);
    /* statuses */
    assert_int_equal(trn_mast_local_dem_mean(&pts[5], 3u, &p, &c, &dem, cnt, 25u, NULL),
                     TRN_E_NODATA);
    assert_int_equal(trn_mast_local_dem_mean(pts, 1u, &p, &c, &dem, NULL, 25u, &used), TRN_E_NULL);
    assert_int_equal(trn_mast_local_dem_mean(pts, 1u, &p, &c, &dem, cnt, 24u, &used),
                     TRN_E_WORKSPACE);
    assert_int_equal(trn_mast_local_dem_mean(pts, 1u, NULL, &c, &dem, cnt, 25u, &used), TRN_E_NULL);
    assert_int_equal(trn_mast_local_dem_mean(NULL, 1u, &p, &c, &dem, cnt, 25u, &used), TRN_E_NULL);
    cb = c;
    cb.row_north = 0;
    assert_int_equal(trn_mast_local_dem_mean(pts, 1u, &p, &cb, &dem, cnt, 25u, &used), TRN_E_ARG);
    dem.width = 0;
    assert_int_equal(trn_mast_local_dem_mean(pts, 1u, &p, &c, &dem, cnt, 25u, &used), TRN_E_SIZE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_geom_check_each_field),
        cmocka_unit_test(test_point_at_each_argument),
        cmocka_unit_test(test_point_at_unreachable_and_limits),
        cmocka_unit_test(test_point_at_target_behind_the_tilt_axis),
        cmocka_unit_test(test_camera_to_map_each_argument),
        cmocka_unit_test(test_local_dem_checks_and_skips),
        cmocka_unit_test(test_local_dem_mean),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
