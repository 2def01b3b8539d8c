/* SPDX-License-Identifier: Apache-2.0 */
/* test_chamfer.c - unit tests of trn_chamfer3d (method.md 2.4).
 *
 * Oracles:
 *  - ref_chamfer3d_dijkstra: exact shortest paths over the 26-neighbour
 *    3-4-5 voxel graph by Dijkstra, a different algorithm from the two raster
 *    passes under test; compared exactly on seeded random volumes of many
 *    shapes, densities and caps, out of place and in place;
 *  - the closed form for one occupied voxel: with |dx| >= |dy| >= |dz| sorted,
 *    D = 5 dz + 4 (dy - dz) + 3 (dx - dy);
 *  - brute-force Euclidean distance, for the analytic error bound of 3-4-5;
 *  - every bad-input class of the header.
 *
 * These tests can fail. A wrong weight is caught at once: face 2 or 4 breaks
 * the one-voxel closed form at (1,0,0); edge 3 or 5 at (1,1,0); corner 4 or 6
 * at (1,1,1) (each also breaks the Dijkstra comparison and the Euclidean
 * bound). Before this file was committed, 31 deliberate bugs were put into a
 * scratch copy of chamfer.c one at a time and every one failed at least one
 * test here: wrong weights in each kernel and scan; a dropped T[x-1] or
 * T[x+1]; a wrong stand-in for a missing face row; a wrong outside-x
 * sentinel; T not extended across a 256-voxel chunk edge; one doubling step
 * too few; a too small spread, reach or dirty span; a dirty check of > +4
 * instead of > +3, or of only half a block; the forward scan skipped always,
 * or on the wrong rows; off-by-one overlapping last blocks; no overflow
 * clamp; a missing scalar tail or forgotten occupancy start; NODATA, cap
 * range and overlap checks removed. Correct variants (other chunk sizes, no
 * scan skipping) pass. The later design moved all in-row work into the forward pass
 * (both directions, rows with an occupied voxel); against that design these
 * mutants each fail test_matches_dijkstra_random: the backward in-row scan
 * dropped, the forward one dropped, the closure skipped on plane 0, or on
 * row 0 of each plane; correct variants (the closure on every row, the
 * backward scan before the forward one) pass.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "trn/chamfer.h"
#include "ref_chamfer.h"
#include "rng.h"

/* ---------------------------------------------------------- support code */

static size_t vol_n(int nx, int ny, int nz) { return (size_t)nx * (size_t)ny * (size_t)nz; }

static size_t idx(int nx, int ny, int x, int y, int z)
{
    return ((size_t)z * (size_t)ny + (size_t)y) * (size_t)nx + (size_t)x;
}

static uint8_t *xmalloc(size_t n)
{
    uint8_t *p = malloc(n > 0u ? n : 1u);
    assert_non_null(p);
    return p;
}

/** Random occupancy: each voxel occupied with probability dens (any nonzero
 * byte value means occupied); with faces != 0 also the 8 corners and random
 * voxels on the 6 faces. */
static void fill_random(uint8_t *occ, int nx, int ny, int nz, double dens, int faces, trn_rng_t *r)
{
    size_t i;
    int x, y, z;
    for (i = 0u; i < vol_n(nx, ny, nz); i++) {
        occ[i] = (trn_rng_unit(r) < dens) ? (uint8_t)trn_rng_int(r, 1, 255) : 0u;
    }
    if (faces != 0) {
        for (z = 0; z < nz; z++) {
            for (y = 0; y < ny; y++) {
                for (x = 0; x < nx; x++) {
                    int on_face = (x == 0 || x == nx - 1 || y == 0 || y == ny - 1 || z == 0 ||
                                   z == nz - 1);
                    int corner = (x == 0 || x == nx - 1) && (y == 0 || y == ny - 1) &&
                                 (z == 0 || z == nz - 1);
                    if (corner || (on_face && trn_rng_unit(r) < 0.05)) {
                        occ[idx(nx, ny, x, y, z)] = 1u;
                    }
                }
            }
        }
    }
}

static int any_occupied(const uint8_t *occ, size_t n)
{
    size_t i;
    for (i = 0u; i < n; i++) {
        if (occ[i] != 0u) {
            return 1;
        }
    }
    return 0;
}

/** Compare with the Dijkstra oracle, out of place and in place. */
static void check_against_oracle(const uint8_t *occ, int nx, int ny, int nz, uint8_t cap,
                                 trn_rng_t *r)
{
    const size_t n = vol_n(nx, ny, nz);
    uint8_t *ref = xmalloc(n);
    uint8_t *out = xmalloc(n);
    uint8_t *inpl = xmalloc(n);
    trn_vol_u8_t vo, vd, vi;
    trn_status_t want = any_occupied(occ, n) ? TRN_OK : TRN_E_NODATA;
    size_t i;

    ref_chamfer3d_dijkstra(occ, ref, nx, ny, nz, cap);

    /* Out of place, dist prefilled with garbage that must not matter. */
    for (i = 0u; i < n; i++) {
        out[i] = (uint8_t)trn_rng_int(r, 0, 255);
    }
    assert_int_equal(trn_vol_u8_init(&vo, (uint8_t *)(uintptr_t)occ, n, nx, ny, nz), TRN_OK);
    assert_int_equal(trn_vol_u8_init(&vd, out, n, nx, ny, nz), TRN_OK);
    assert_int_equal(trn_chamfer3d(&vo, &vd, cap), want);

    /* In place. */
    memcpy(inpl, occ, n);
    assert_int_equal(trn_vol_u8_init(&vi, inpl, n, nx, ny, nz), TRN_OK);
    assert_int_equal(trn_chamfer3d(&vi, &vi, cap), want);

    for (i = 0u; i < n; i++) {
        if (out[i] != ref[i] || inpl[i] != ref[i]) {
            print_error("%dx%dx%d cap %u voxel %lu (x %d y %d z %d): got %u in place %u, "
                        "Dijkstra %u\n",
                        nx, ny, nz, (unsigned)cap, (unsigned long)i, (int)(i % (size_t)nx),
                        (int)((i / (size_t)nx) % (size_t)ny), (int)(i / ((size_t)nx * (size_t)ny)),
                        (unsigned)out[i], (unsigned)inpl[i], (unsigned)ref[i]);
            fail();
        }
        /* Contract: occupied voxels 0, all <= cap. */
        assert_true(out[i] <= cap);
        assert_true((occ[i] != 0u) == (out[i] == 0u));
    }
    free(inpl);
    free(out);
    free(ref);
}

/* -------------------------------------------------------- oracle comparison */

typedef struct {
    int nx, ny, nz;
} dims_t;

/* Odd sizes, degenerate lines and slabs, widths around the 16-voxel block
 * length (15..19, 31..35, 47, 48, 49) so every partial-block path runs, and
 * around the 256-voxel chunk of the row kernel (257, 271, 272, 520). Long
 * rows let cap-250 distances run 83 voxels along a row. */
static const dims_t k_dims[] = {
    {1, 1, 1},   {1, 1, 7},   {1, 9, 1},   {7, 1, 1},   {1, 13, 11}, {1, 5, 8},   {19, 1, 1},
    {33, 1, 1},  {300, 1, 1}, {1, 1, 128}, {1, 300, 1}, {7, 5, 3},   {17, 13, 6}, {33, 31, 9},
    {15, 9, 4},  {16, 7, 5},  {18, 3, 7},  {32, 5, 3},  {34, 4, 4},  {35, 6, 2},  {47, 3, 3},
    {48, 2, 5},  {49, 5, 2},  {31, 31, 1}, {40, 3, 2},  {2, 40, 3},  {3, 2, 40},  {129, 5, 2},
    {200, 3, 2}, {65, 17, 3}, {257, 3, 2}, {271, 2, 3}, {272, 3, 2}, {520, 2, 2},
};

static const double k_dens[] = {0.0005, 0.003, 0.02, 0.1, 0.35, 0.8, 0.995};
static const uint8_t k_caps[] = {3u, 4u, 10u, 50u, 250u};

static void test_matches_dijkstra_random(void **state)
{
    trn_rng_t r;
    size_t di, ci, ki;
    unsigned long cases = 0u;
    (void)state;
    trn_rng_seed(&r, 0x5EEDC4A3F3E12345ull);
    for (di = 0u; di < sizeof k_dims / sizeof k_dims[0]; di++) {
        const dims_t d = k_dims[di];
        uint8_t *occ = xmalloc(vol_n(d.nx, d.ny, d.nz));
        for (ki = 0u; ki < sizeof k_dens / sizeof k_dens[0]; ki++) {
            for (ci = 0u; ci < sizeof k_caps / sizeof k_caps[0]; ci++) {
                int faces;
                for (faces = 0; faces <= 1; faces++) {
                    fill_random(occ, d.nx, d.ny, d.nz, k_dens[ki], faces, &r);
                    check_against_oracle(occ, d.nx, d.ny, d.nz, k_caps[ci], &r);
                    cases++;
                }
            }
        }
        free(occ);
    }
    printf("chamfer: %lu random volumes equal the Dijkstra oracle\n", cases);
}

/* Sparse sources in long rows: distances of 80+ voxels along x, y and z,
 * where the in-row scan needs all its doubling steps. */
static void test_matches_dijkstra_long_range(void **state)
{
    static const dims_t dims[] = {{300, 2, 2}, {257, 3, 1}, {100, 4, 3}, {90, 90, 1}};
    trn_rng_t r;
    size_t di;
    int rep;
    (void)state;
    trn_rng_seed(&r, 77u);
    for (di = 0u; di < sizeof dims / sizeof dims[0]; di++) {
        const dims_t d = dims[di];
        const size_t n = vol_n(d.nx, d.ny, d.nz);
        uint8_t *occ = xmalloc(n);
        for (rep = 0; rep < 6; rep++) {
            int k;
            memset(occ, 0, n);
            for (k = 0; k <= rep % 3; k++) {
                occ[(size_t)trn_rng_int(&r, 0, (int32_t)n - 1)] = 1u;
            }
            check_against_oracle(occ, d.nx, d.ny, d.nz, 250u, &r);
            check_against_oracle(occ, d.nx, d.ny, d.nz, (uint8_t)trn_rng_int(&r, 3, 250), &r);
        }
        free(occ);
    }
}

/* ---------------------------------------------------- single voxel, analytic */

static unsigned chamfer_formula(int dx, int dy, int dz)
{
    int a = abs(dx), b = abs(dy), c = abs(dz), t;
    /* sort a >= b >= c */
    if (a < b) {
        t = a;
        a = b;
        b = t;
    }
    if (b < c) {
        t = b;
        b = c;
        c = t;
    }
    if (a < b) {
        t = a;
        a = b;
        b = t;
    }
    return 5u * (unsigned)c + 4u * (unsigned)(b - c) + 3u * (unsigned)(a - b);
}

static void test_single_voxel_analytic(void **state)
{
    static const dims_t dims[] = {{1, 1, 1}, {9, 7, 5}, {33, 17, 9}, {40, 3, 11}, {100, 1, 1}};
    static const uint8_t caps[] = {3u, 10u, 250u};
    trn_rng_t r;
    size_t di, ci;
    int rep;
    (void)state;
    trn_rng_seed(&r, 1234u);
    for (di = 0u; di < sizeof dims / sizeof dims[0]; di++) {
        const dims_t d = dims[di];
        const size_t n = vol_n(d.nx, d.ny, d.nz);
        uint8_t *buf = xmalloc(n);
        for (ci = 0u; ci < sizeof caps / sizeof caps[0]; ci++) {
            for (rep = 0; rep < 12; rep++) {
                /* First the 8 corners, then random positions. */
                int sx = (rep < 8) ? ((rep & 1) ? d.nx - 1 : 0) : trn_rng_int(&r, 0, d.nx - 1);
                int sy = (rep < 8) ? ((rep & 2) ? d.ny - 1 : 0) : trn_rng_int(&r, 0, d.ny - 1);
                int sz = (rep < 8) ? ((rep & 4) ? d.nz - 1 : 0) : trn_rng_int(&r, 0, d.nz - 1);
                trn_vol_u8_t v;
                int x, y, z;
                memset(buf, 0, n);
                buf[idx(d.nx, d.ny, sx, sy, sz)] = 200u;
                assert_int_equal(trn_vol_u8_init(&v, buf, n, d.nx, d.ny, d.nz), TRN_OK);
                assert_int_equal(trn_chamfer3d(&v, &v, caps[ci]), TRN_OK);
                for (z = 0; z < d.nz; z++) {
                    for (y = 0; y < d.ny; y++) {
                        for (x = 0; x < d.nx; x++) {
                            unsigned want = chamfer_formula(x - sx, y - sy, z - sz);
                            if (want > caps[ci]) {
                                want = caps[ci];
                            }
                            assert_int_equal(buf[idx(d.nx, d.ny, x, y, z)], want);
                        }
                    }
                }
            }
        }
        free(buf);
    }
    /* The three step weights themselves. */
    assert_int_equal(chamfer_formula(1, 0, 0), TRN_CHAMFER_FACE);
    assert_int_equal(chamfer_formula(0, -1, 1), TRN_CHAMFER_EDGE);
    assert_int_equal(chamfer_formula(-1, 1, -1), TRN_CHAMFER_CORNER);
}

/* ------------------------------------------------ error against Euclidean */

/*
 * Bound. For a displacement with sorted |components| a >= b >= c the 3-4-5
 * distance is 3a + b + c, i.e. (a + (b + c) / 3) voxels, against the
 * Euclidean sqrt(a^2 + b^2 + c^2). The ratio is a linear form over the norm:
 *  - its maximum over the cone a >= b >= c >= 0 is the norm of the form's
 *    coefficients, |(1, 1/3, 1/3)| = sqrt(11)/3 = 1.10554, reached along
 *    (3, 1, 1) (a lattice point at Euclidean distance 3.32);
 *  - a positive linear form is concave along great-circle arcs, so its
 *    minimum over the spherical triangle is at a corner: (1,0,0) -> 1,
 *    (1,1,0) -> 2 sqrt(2)/3 = 0.94281, (1,1,1) -> 5/(3 sqrt 3) = 0.96225.
 * The nearest-voxel distances inherit the same bounds (a minimum of values
 * each within [0.94281, 1.10554] times its Euclidean counterpart), and a
 * monotone shortest path never leaves the box, so volume faces change
 * nothing. So D/3 / E - 1 lies in [-5.72%, +10.55%] for every voxel, and the
 * worst relative error is 10.55%.
 */
#define CHAMFER_REL_ERR_OVER 0.1055415967851332  /* sqrt(11)/3 - 1 */
#define CHAMFER_REL_ERR_UNDER 0.0571909584179366 /* 1 - 2 sqrt(2)/3 */

static void test_error_against_euclid(void **state)
{
    const int nx = 41, ny = 37, nz = 19;
    const size_t n = vol_n(nx, ny, nz);
    uint8_t *occ = xmalloc(n);
    uint8_t *dist = xmalloc(n);
    trn_vol_u8_t vo, vd;
    trn_rng_t r;
    double worst = 0.0, worst_over = 0.0, worst_under = 0.0;
    unsigned long counted = 0u;
    int x, y, z, k;
    (void)state;
    trn_rng_seed(&r, 2024u);
    memset(occ, 0, n);
    for (k = 0; k < 12; k++) {
        occ[idx(nx, ny, trn_rng_int(&r, 0, nx - 1), trn_rng_int(&r, 0, ny - 1),
                trn_rng_int(&r, 0, nz - 1))] = 1u;
    }
    assert_int_equal(trn_vol_u8_init(&vo, occ, n, nx, ny, nz), TRN_OK);
    assert_int_equal(trn_vol_u8_init(&vd, dist, n, nx, ny, nz), TRN_OK);
    assert_int_equal(trn_chamfer3d(&vo, &vd, TRN_CHAMFER_CAP_MAX), TRN_OK);
    for (z = 0; z < nz; z++) {
        for (y = 0; y < ny; y++) {
            for (x = 0; x < nx; x++) {
                const uint8_t d = dist[idx(nx, ny, x, y, z)];
                const double e = ref_euclid_nearest(occ, nx, ny, nz, x, y, z);
                double rel;
                if (e < 3.0 || d >= TRN_CHAMFER_CAP_MAX) {
                    continue; /* near voxels and capped ones are not measured */
                }
                rel = ((double)d / (double)TRN_CHAMFER_FACE) / e - 1.0;
                if (rel > worst_over) {
                    worst_over = rel;
                }
                if (-rel > worst_under) {
                    worst_under = -rel;
                }
                counted++;
            }
        }
    }
    worst = (worst_over > worst_under) ? worst_over : worst_under;
    printf("chamfer 3-4-5 vs Euclidean (%lu voxels at >= 3 voxels): worst relative error "
           "%.4f%% (over %+.4f%%, under %+.4f%%); analytic bound +%.4f%% / -%.4f%%\n",
           counted, 100.0 * worst, 100.0 * worst_over, -100.0 * worst_under,
           100.0 * CHAMFER_REL_ERR_OVER, 100.0 * CHAMFER_REL_ERR_UNDER);
    assert_true(counted > 1000u);
    assert_true(worst_over <= CHAMFER_REL_ERR_OVER + 1e-12);
    assert_true(worst_under <= CHAMFER_REL_ERR_UNDER + 1e-12);
    /* The worst case is a lattice direction ((3,1,1), (1,1,0)): a grid this
     * size must show both extremes to within rounding. */
    assert_true(worst_over > CHAMFER_REL_ERR_OVER - 1e-9);
    assert_true(worst_under > CHAMFER_REL_ERR_UNDER - 1e-9);
    free(dist);
    free(occ);
}

/* ---------------------------------------------------------------- bad input */

static void test_bad_null(void **state)
{
    uint8_t a[8] = {1u}, b[8];
    trn_vol_u8_t vo = {a, 2, 2, 2}, vd = {b, 2, 2, 2};
    trn_vol_u8_t no = {NULL, 2, 2, 2}, nd = {NULL, 2, 2, 2};
    (void)state;
    memset(b, 0xAB, sizeof b);
    assert_int_equal(trn_chamfer3d(NULL, &vd, 10u), TRN_E_NULL);
    assert_int_equal(trn_chamfer3d(&vo, NULL, 10u), TRN_E_NULL);
    assert_int_equal(trn_chamfer3d(NULL, NULL, 10u), TRN_E_NULL);
    assert_int_equal(trn_chamfer3d(&no, &vd, 10u), TRN_E_NULL);
    assert_int_equal(trn_chamfer3d(&vo, &nd, 10u), TRN_E_NULL);
    /* NULL wins over other errors. */
    assert_int_equal(trn_chamfer3d(&no, &vd, 0u), TRN_E_NULL);
    {
        trn_vol_u8_t bad = {b, 0, 2, 2};
        assert_int_equal(trn_chamfer3d(&no, &bad, 10u), TRN_E_NULL);
    }
    /* dist untouched on error */
    {
        size_t i;
        for (i = 0u; i < sizeof b; i++) {
            assert_int_equal(b[i], 0xABu);
        }
    }
}

static void test_bad_size(void **state)
{
    static uint8_t a[64], b[64];
    static const int32_t bad[][3] = {
        {0, 2, 2},
        {2, 0, 2},
        {2, 2, 0},
        {-1, 2, 2},
        {2, -3, 2},
        {2, 2, -1},
        {TRN_MAX_DIM + 1, 1, 1},
        {1, TRN_MAX_DIM + 1, 1},
        {1, 1, TRN_MAX_ZBINS + 1},
        {INT32_MIN, 1, 1},
    };
    trn_vol_u8_t good = {a, 4, 4, 4};
    size_t i;
    (void)state;
    a[0] = 1u;
    memset(b, 0xCD, sizeof b);
    for (i = 0u; i < sizeof bad / sizeof bad[0]; i++) {
        trn_vol_u8_t v = {b, bad[i][0], bad[i][1], bad[i][2]};
        trn_vol_u8_t o = {a, bad[i][0], bad[i][1], bad[i][2]};
        trn_vol_u8_t d = {b, 4, 4, 4};
        assert_int_equal(trn_chamfer3d(&good, &v, 10u), TRN_E_SIZE);
        assert_int_equal(trn_chamfer3d(&o, &d, 10u), TRN_E_SIZE);
        assert_int_equal(trn_chamfer3d(&o, &o, 10u), TRN_E_SIZE);
    }
    /* Mismatched dimensions, each axis (same voxel count, so only the check
     * can tell). */
    {
        trn_vol_u8_t d1 = {b, 2, 8, 4}, d2 = {b, 4, 2, 8}, d3 = {b, 8, 4, 2}, d4 = {b, 4, 4, 3};
        assert_int_equal(trn_chamfer3d(&good, &d1, 10u), TRN_E_SIZE);
        assert_int_equal(trn_chamfer3d(&good, &d2, 10u), TRN_E_SIZE);
        assert_int_equal(trn_chamfer3d(&good, &d3, 10u), TRN_E_SIZE);
        assert_int_equal(trn_chamfer3d(&good, &d4, 10u), TRN_E_SIZE);
        assert_int_equal(trn_chamfer3d(&d4, &good, 10u), TRN_E_SIZE);
    }
    for (i = 0u; i < sizeof b; i++) {
        assert_int_equal(b[i], 0xCDu);
    }
}

static void test_bad_cap(void **state)
{
    static const unsigned bad[] = {0u, 1u, 2u, TRN_CHAMFER_CAP_MAX + 1u, 251u, 254u, 255u};
    uint8_t a[27] = {0u}, b[27];
    trn_vol_u8_t vo = {a, 3, 3, 3}, vd = {b, 3, 3, 3};
    size_t i;
    (void)state;
    a[13] = 1u;
    memset(b, 0xEE, sizeof b);
    for (i = 0u; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_equal(trn_chamfer3d(&vo, &vd, (uint8_t)bad[i]), TRN_E_ARG);
        assert_int_equal(trn_chamfer3d(&vo, &vo, (uint8_t)bad[i]), TRN_E_ARG);
    }
    for (i = 0u; i < sizeof b; i++) {
        assert_int_equal(b[i], 0xEEu);
    }
    assert_int_equal(a[13], 1u);
    /* The ends of the range work. */
    assert_int_equal(trn_chamfer3d(&vo, &vd, 3u), TRN_OK);
    assert_int_equal(b[0], 3u); /* corner step 5 capped to 3 */
    assert_int_equal(trn_chamfer3d(&vo, &vd, TRN_CHAMFER_CAP_MAX), TRN_OK);
    assert_int_equal(b[0], 5u);
    assert_int_equal(b[13], 0u);
}

static void test_partial_overlap(void **state)
{
    uint8_t buf[64] = {0u};
    trn_vol_u8_t vo = {buf, 4, 4, 2};      /* bytes [0, 32) */
    trn_vol_u8_t vd = {buf + 16, 4, 4, 2}; /* bytes [16, 48): overlaps */
    trn_vol_u8_t ve = {buf + 32, 4, 4, 2}; /* bytes [32, 64): disjoint */
    (void)state;
    buf[3] = 1u;
    assert_int_equal(trn_chamfer3d(&vo, &vd, 10u), TRN_E_ARG);
    assert_int_equal(trn_chamfer3d(&vd, &vo, 10u), TRN_E_ARG);
    {
        /* nothing written on the error */
        size_t i;
        for (i = 0u; i < sizeof buf; i++) {
            assert_int_equal(buf[i], (i == 3u) ? 1u : 0u);
        }
    }
    assert_int_equal(trn_chamfer3d(&vo, &ve, 10u), TRN_OK); /* adjacent is fine */
    assert_int_equal(buf[32 + 3], 0u);
    assert_int_equal(buf[32 + 2], 3u);
}

static void test_nodata(void **state)
{
    static const dims_t dims[] = {{1, 1, 1}, {7, 5, 3}, {40, 2, 2}};
    static const uint8_t caps[] = {3u, 77u, 250u};
    size_t di, ci, i;
    (void)state;
    for (di = 0u; di < sizeof dims / sizeof dims[0]; di++) {
        const dims_t d = dims[di];
        const size_t n = vol_n(d.nx, d.ny, d.nz);
        uint8_t *occ = xmalloc(n);
        uint8_t *out = xmalloc(n);
        for (ci = 0u; ci < sizeof caps / sizeof caps[0]; ci++) {
            trn_vol_u8_t vo = {occ, d.nx, d.ny, d.nz}, vd = {out, d.nx, d.ny, d.nz};
            memset(occ, 0, n);
            memset(out, 0x11, n);
            assert_int_equal(trn_chamfer3d(&vo, &vd, caps[ci]), TRN_E_NODATA);
            for (i = 0u; i < n; i++) {
                assert_int_equal(out[i], caps[ci]);
            }
            assert_int_equal(trn_chamfer3d(&vo, &vo, caps[ci]), TRN_E_NODATA); /* in place */
            for (i = 0u; i < n; i++) {
                assert_int_equal(occ[i], caps[ci]);
            }
        }
        free(out);
        free(occ);
    }
}

/* Same input, same output; and the transform of a transform's zero set is
 * itself (occupied = distance 0). */
static void test_deterministic_and_idempotent(void **state)
{
    const int nx = 37, ny = 11, nz = 5;
    const size_t n = vol_n(nx, ny, nz);
    uint8_t *occ = xmalloc(n), *d1 = xmalloc(n), *d2 = xmalloc(n), *z = xmalloc(n);
    trn_vol_u8_t vo = {occ, nx, ny, nz}, v1 = {d1, nx, ny, nz}, v2 = {d2, nx, ny, nz};
    trn_vol_u8_t vz = {z, nx, ny, nz};
    trn_rng_t r;
    size_t i;
    (void)state;
    trn_rng_seed(&r, 99u);
    fill_random(occ, nx, ny, nz, 0.01, 0, &r);
    occ[0] = 1u;
    assert_int_equal(trn_chamfer3d(&vo, &v1, 60u), TRN_OK);
    assert_int_equal(trn_chamfer3d(&vo, &v2, 60u), TRN_OK);
    assert_memory_equal(d1, d2, n);
    for (i = 0u; i < n; i++) {
        z[i] = (d1[i] == 0u) ? 1u : 0u;
    }
    assert_int_equal(trn_chamfer3d(&vz, &v2, 60u), TRN_OK);
    assert_memory_equal(d1, d2, n);
    free(z);
    free(d2);
    free(d1);
    free(occ);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_matches_dijkstra_random),
        cmocka_unit_test(test_matches_dijkstra_long_range),
        cmocka_unit_test(test_single_voxel_analytic),
        cmocka_unit_test(test_error_against_euclid),
        cmocka_unit_test(test_bad_null),
        cmocka_unit_test(test_bad_size),
        cmocka_unit_test(test_bad_cap),
        cmocka_unit_test(test_partial_overlap),
        cmocka_unit_test(test_nodata),
        cmocka_unit_test(test_deterministic_and_idempotent),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
