/* SPDX-License-Identifier: Apache-2.0 */
/* test_sim_render.c - the simulator's stereo rendering (tools/sim/sim_render.h)
 * against analytic answers: ranges to a plane, points on a sloped plane,
 * the k r^2 noise statistics, the range limits, seeds, bad input. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "sim_render.h"

enum { W = 200, H = 200, MAXP = 8192 };
static float g_dem[W * H];
static trn_vec3f_t g_a[MAXP], g_b[MAXP];

/* plane h = a x + b y + c over [-10, 10)^2 at 0.1 m */
static sim_dem_t plane(float a, float b, float c)
{
    sim_dem_t d;
    int i, j;
    for (j = 0; j < H; ++j) {
        for (i = 0; i < W; ++i) {
            float x = -10.0f + 0.1f * (float)i, y = -10.0f + 0.1f * (float)j;
            g_dem[j * W + i] = a * x + b * y + c;
        }
    }
    d.heights = g_dem;
    d.width = W;
    d.height = H;
    d.cell_m = 0.1f;
    d.x0_m = -10.0f;
    d.y0_m = -10.0f;
    return d;
}

static sim_camera_t camera(float k)
{
    sim_camera_t c;
    c.hfov_rad = 1.0f;
    c.vfov_rad = 0.75f;
    c.cols = 64;
    c.rows = 48;
    c.min_range_m = 0.2f;
    c.max_range_m = 15.0f;
    c.noise_k_per_m = k;
    return c;
}

/* camera at (0, 0, 2) looking along map +x with tilt (negative = down) */
static trn_rigid_t pose(float tilt, float pan)
{
    trn_mast_geom_t g;
    trn_rover_pose_t p = {0.0f, 0.0f, 0.0f, 0.0f};
    trn_rigid_t T;
    memset(&g, 0, sizeof g);
    g.pan_z_m = 2.0f;
    g.pan_min_rad = -3.0f;
    g.pan_max_rad = 3.0f;
    g.tilt_min_rad = -1.5f;
    g.tilt_max_rad = 1.5f;
    assert_int_equal(trn_mast_camera_to_map(&g, &p, pan, tilt, &T), TRN_OK);
    return T;
}

static trn_vec3f_t to_map(const trn_rigid_t *T, trn_vec3f_t c)
{
    trn_vec3f_t m;
    assert_int_equal(trn_rigid_apply(T, &c, 1, &m), TRN_OK);
    return m;
}

static double norm3(trn_vec3f_t v)
{
    return sqrt((double)v.x * v.x + (double)v.y * v.y + (double)v.z * v.z);
}

/* Flat ground 2 m below the camera: every ray hits at r = 2 / (-d_z), d the
 * map direction of the ray; the point lies on z = 0. */
static void test_flat_ranges_analytic(void **state)
{
    sim_dem_t d = plane(0.0f, 0.0f, 0.0f);
    sim_camera_t c = camera(0.0f);
    trn_rigid_t T = pose(-0.6f, 0.3f);
    sim_rng_t rng = {1u};
    size_t n = 0, i;
    (void)state;
    assert_int_equal(sim_render(&d, &c, &T, &rng, g_a, MAXP, &n), TRN_OK);
    assert_true(n > 1000);
    for (i = 0; i < n; ++i) {
        trn_vec3f_t m = to_map(&T, g_a[i]);
        double r = norm3(g_a[i]);
        double dz = ((double)m.z - (double)T.t.z) / r; /* map z of the unit ray */
        assert_true(dz < 0.0);
        assert_float_equal(r, 2.0 / -dz, 1e-3 * r);
        assert_float_equal(m.z, 0.0f, 1e-3f);
        assert_true(g_a[i].z > 0.0f); /* in front of the camera */
    }
}

/* A sloped plane (bilinear interpolation is exact on it). */
static void test_sloped_plane(void **state)
{
    sim_dem_t d = plane(0.15f, -0.1f, 0.3f);
    sim_camera_t c = camera(0.0f);
    trn_rigid_t T = pose(-0.5f, -0.4f);
    sim_rng_t rng = {1u};
    size_t n = 0, i;
    (void)state;
    assert_int_equal(sim_render(&d, &c, &T, &rng, g_a, MAXP, &n), TRN_OK);
    assert_true(n > 1000);
    for (i = 0; i < n; ++i) {
        trn_vec3f_t m = to_map(&T, g_a[i]);
        assert_float_equal(m.z, 0.15f * m.x - 0.1f * m.y + 0.3f, 2e-3f);
    }
}

/* Range noise: (r_noisy - r) / (k r^2) is standard normal. */
static void test_noise_grows_with_range_squared(void **state)
{
    sim_dem_t d = plane(0.0f, 0.0f, 0.0f);
    sim_camera_t c0 = camera(0.0f), c1 = camera(0.01f);
    trn_rigid_t T = pose(-0.35f, 0.0f);
    sim_rng_t r0 = {7u}, r1 = {7u};
    size_t n0 = 0, n1 = 0, i, m = 0;
    double s = 0.0, s2 = 0.0, far = 0.0, near = 1e9;
    (void)state;
    assert_int_equal(sim_render(&d, &c0, &T, &r0, g_a, MAXP, &n0), TRN_OK);
    assert_int_equal(sim_render(&d, &c1, &T, &r1, g_b, MAXP, &n1), TRN_OK);
    assert_int_equal(n0, n1); /* noise never removes a ray (range limits are on the true range) */
    for (i = 0; i < n0; ++i) {
        double r = norm3(g_a[i]), rn = norm3(g_b[i]);
        double z = (rn - r) / (0.01 * r * r);
        /* same ray direction */
        assert_float_equal(g_b[i].x / rn, g_a[i].x / r, 1e-5);
        s += z;
        s2 += z * z;
        ++m;
        far = r > far ? r : far;
        near = r < near ? r : near;
    }
    assert_true(far > 2.5 * near); /* ranges span enough to tell r^2 from r */
    s /= (double)m;
    s2 = s2 / (double)m - s * s;
    assert_true(fabs(s) < 4.0 / sqrt((double)m));
    assert_true(fabs(sqrt(s2) - 1.0) < 0.08);
}

static void test_seeds_and_limits(void **state)
{
    sim_dem_t d = plane(0.0f, 0.0f, 0.0f);
    sim_camera_t c = camera(0.005f);
    trn_rigid_t T = pose(-0.6f, 0.0f);
    sim_rng_t a = {3u}, b = {3u}, e = {4u};
    size_t na = 0, nb = 0, i;
    (void)state;
    assert_int_equal(sim_render(&d, &c, &T, &a, g_a, MAXP, &na), TRN_OK);
    assert_int_equal(sim_render(&d, &c, &T, &b, g_b, MAXP, &nb), TRN_OK);
    assert_int_equal(na, nb);
    assert_memory_equal(g_a, g_b, na * sizeof g_a[0]);
    assert_int_equal(sim_render(&d, &c, &T, &e, g_b, MAXP, &nb), TRN_OK);
    assert_memory_not_equal(g_a, g_b, na * sizeof g_a[0]);
    /* looking up: nothing */
    T = pose(0.5f, 0.0f);
    assert_int_equal(sim_render(&d, &c, &T, &a, g_a, MAXP, &na), TRN_OK);
    assert_int_equal(na, 0);
    /* max range: no true range beyond it (noise-free) */
    c = camera(0.0f);
    c.max_range_m = 3.0f;
    T = pose(-0.4f, 0.0f);
    assert_int_equal(sim_render(&d, &c, &T, &a, g_a, MAXP, &na), TRN_OK);
    assert_true(na > 0 && na < (size_t)(c.cols * c.rows));
    for (i = 0; i < na; ++i) {
        assert_true(norm3(g_a[i]) <= 3.0 + 1e-4);
    }
    /* off the DEM: a camera outside it sees nothing */
    T = pose(-0.6f, 0.0f);
    T.t.x = 50.0f;
    assert_int_equal(sim_render(&d, &c, &T, &a, g_a, MAXP, &na), TRN_OK);
    assert_int_equal(na, 0);
}

/* Rows rendered in chunks give exactly the whole image (points and noise). */
static void test_rows_in_chunks(void **state)
{
    sim_dem_t d = plane(0.05f, 0.02f, 0.0f);
    sim_camera_t c = camera(0.004f);
    trn_rigid_t T = pose(-0.5f, 0.7f);
    sim_rng_t a = {11u}, b = {11u};
    size_t na = 0, nb = 0;
    int32_t r;
    (void)state;
    assert_int_equal(sim_render(&d, &c, &T, &a, g_a, MAXP, &na), TRN_OK);
    for (r = 0; r < c.rows; r += 5) {
        assert_int_equal(
            sim_render_rows(&d, &c, &T, &b, r, r + 5 > c.rows ? c.rows : r + 5, g_b, MAXP, &nb),
            TRN_OK);
    }
    assert_int_equal(na, nb);
    assert_memory_equal(g_a, g_b, na * sizeof g_a[0]);
    assert_int_equal(sim_render_rows(&d, &c, &T, &b, 5, 4, g_b, MAXP, &nb), TRN_E_RANGE);
    assert_int_equal(sim_render_rows(&d, &c, &T, &b, 0, c.rows + 1, g_b, MAXP, &nb), TRN_E_RANGE);
    nb = MAXP + 1u;
    assert_int_equal(sim_render_rows(&d, &c, &T, &b, 0, 1, g_b, MAXP, &nb), TRN_E_RANGE);
}

static void test_dem_height(void **state)
{
    sim_dem_t d = plane(0.0f, 0.0f, 0.0f);
    float h = -1.0f;
    (void)state;
    g_dem[0] = 1.0f;
    g_dem[1] = 3.0f;
    g_dem[W] = 5.0f;
    g_dem[W + 1] = 7.0f;
    assert_int_equal(sim_dem_height(&d, -10.0f + 0.05f, -10.0f + 0.05f, &h), TRN_OK);
    assert_float_equal(h, 4.0f, 1e-4f); /* mean of the four */
    assert_int_equal(sim_dem_height(&d, -10.0f + 0.1f * 0.25f, -10.0f, &h), TRN_OK);
    assert_float_equal(h, 1.5f, 1e-4f);
    assert_int_equal(sim_dem_height(&d, -10.5f, 0.0f, &h), TRN_E_RANGE);
    assert_int_equal(sim_dem_height(&d, 0.0f, 10.0f, &h), TRN_E_RANGE); /* last centre is 9.9 */
    assert_int_equal(sim_dem_height(NULL, 0.0f, 0.0f, &h), TRN_E_NULL);
    assert_int_equal(sim_dem_height(&d, 0.0f, 0.0f, NULL), TRN_E_NULL);
    d.cell_m = 0.0f;
    assert_int_equal(sim_dem_height(&d, 0.0f, 0.0f, &h), TRN_E_ARG);
}

static void test_bad_input(void **state)
{
    sim_dem_t d = plane(0.0f, 0.0f, 0.0f), bd;
    sim_camera_t c = camera(0.0f), bc;
    trn_rigid_t T = pose(-0.6f, 0.0f), bT;
    sim_rng_t rng = {1u};
    size_t n = 99;
    (void)state;
    assert_int_equal(sim_render(NULL, &c, &T, &rng, g_a, MAXP, &n), TRN_E_NULL);
    assert_int_equal(sim_render(&d, NULL, &T, &rng, g_a, MAXP, &n), TRN_E_NULL);
    assert_int_equal(sim_render(&d, &c, NULL, &rng, g_a, MAXP, &n), TRN_E_NULL);
    assert_int_equal(sim_render(&d, &c, &T, NULL, g_a, MAXP, &n), TRN_E_NULL);
    assert_int_equal(sim_render(&d, &c, &T, &rng, NULL, MAXP, &n), TRN_E_NULL);
    assert_int_equal(sim_render(&d, &c, &T, &rng, g_a, MAXP, NULL), TRN_E_NULL);
    bd = d;
    bd.width = 1;
    assert_int_equal(sim_render(&bd, &c, &T, &rng, g_a, MAXP, &n), TRN_E_ARG);
    bd = d;
    bd.cell_m = NAN;
    assert_int_equal(sim_render(&bd, &c, &T, &rng, g_a, MAXP, &n), TRN_E_ARG);
    bc = c;
    bc.hfov_rad = 0.0f;
    assert_int_equal(sim_render(&d, &bc, &T, &rng, g_a, MAXP, &n), TRN_E_ARG);
    bc = c;
    bc.cols = 0;
    assert_int_equal(sim_render(&d, &bc, &T, &rng, g_a, MAXP, &n), TRN_E_ARG);
    bc = c;
    bc.rows = SIM_MAX_RAYS_SIDE + 1;
    assert_int_equal(sim_render(&d, &bc, &T, &rng, g_a, MAXP, &n), TRN_E_ARG);
    bc = c;
    bc.max_range_m = bc.min_range_m;
    assert_int_equal(sim_render(&d, &bc, &T, &rng, g_a, MAXP, &n), TRN_E_ARG);
    bc = c;
    bc.noise_k_per_m = -1.0f;
    assert_int_equal(sim_render(&d, &bc, &T, &rng, g_a, MAXP, &n), TRN_E_ARG);
    bc = c;
    bc.max_range_m = 1e6f; /* too many steps */
    assert_int_equal(sim_render(&d, &bc, &T, &rng, g_a, MAXP, &n), TRN_E_ARG);
    bT = T;
    bT.r[4] = INFINITY;
    assert_int_equal(sim_render(&d, &c, &bT, &rng, g_a, MAXP, &n), TRN_E_ARG);
    /* capacity: the first capacity points are written */
    assert_int_equal(sim_render(&d, &c, &T, &rng, g_a, 10, &n), TRN_E_CAPACITY);
    assert_int_equal(n, 10);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flat_ranges_analytic),
        cmocka_unit_test(test_sloped_plane),
        cmocka_unit_test(test_noise_grows_with_range_squared),
        cmocka_unit_test(test_seeds_and_limits),
        cmocka_unit_test(test_rows_in_chunks),
        cmocka_unit_test(test_dem_height),
        cmocka_unit_test(test_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
