/* SPDX-License-Identifier: Apache-2.0 */
/* test_likelihood.c - ln p table, K, pose scoring, pyramid, and the two pose
 * searches against slow obvious oracles. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rng.h"
#include "trn/chamfer.h"

#ifndef TRN_K_SUB
#define TRN_K_SUB 4
#endif
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include "trn/likelihood.h"

static trn_lik_cfg_t cfg_of(float cell, float sigma, float a, uint8_t cap)
{
    trn_lik_cfg_t c;
    c.cell_m = cell;
    c.sigma_m = sigma;
    c.inlier_prob = a;
    c.cap = cap;
    return c;
}

/* Slow, obvious ln p(d) in double. */
static double ref_lnp(const trn_lik_cfg_t *c, double k, unsigned dc)
{
    double d = dc / 3.0 * c->cell_m, s = c->sigma_m;
    double p1 = exp(-d * d / (2 * s * s)) / (s * sqrt(2 * M_PI));
    return log(c->inlier_prob * p1 + (1 - c->inlier_prob) * k);
}

static void test_lnp_table_matches_formula(void **state)
{
    trn_rng_t r;
    int trial;
    (void)state;
    trn_rng_seed(&r, 11);
    for (trial = 0; trial < 50; ++trial) {
        trn_lnp_table_t t;
        trn_lik_cfg_t c = cfg_of(
            (float)(0.02 + 0.3 * trn_rng_unit(&r)), (float)(0.01 + 0.5 * trn_rng_unit(&r)),
            (float)(0.05 + 0.9 * trn_rng_unit(&r)), (uint8_t)trn_rng_int(&r, 3, 250));
        double k = exp(-6.0 + 8.0 * trn_rng_unit(&r));
        unsigned d;
        assert_int_equal(trn_lnp_table_build(&t, &c, k), TRN_OK);
        assert_int_equal(t.cap, c.cap);
        for (d = 0; d <= c.cap; ++d) {
            double want = ref_lnp(&c, k, d) * TRN_LNP_SCALE;
            if (isfinite(want) && fabs(want) < 1e9) {
                assert_true(fabs((double)t.lnp[d] - want) <= 0.5 + 1e-6 * fabs(want));
            }
            if (d > 0) {
                assert_true(t.lnp[d] <= t.lnp[d - 1]); /* non-increasing: B&B relies on it */
            }
        }
    }
}

/* Occupied plane z = zk: chamfer distances are exact (3 per cell along z),
 * so K = mean over z of p1(|z - zk| cell) analytically. */
static void test_k_plane_analytic(void **state)
{
    enum { NX = 9, NY = 7, NZ = 11 };
    static uint8_t vol[NX * NY * NZ];
    trn_vol_u8_t v;
    trn_lik_cfg_t c = cfg_of(0.1f, 0.15f, 0.95f, 60);
    double k, want = 0.0;
    int x, y, z, zk = 3;
    (void)state;
    assert_int_equal(trn_vol_u8_init(&v, vol, sizeof vol, NX, NY, NZ), TRN_OK);
    memset(vol, 0, sizeof vol);
    for (y = 0; y < NY; ++y) {
        for (x = 0; x < NX; ++x) {
            vol[TRN_VOL_IDX(&v, x, y, zk)] = 1;
        }
    }
    assert_int_equal(trn_chamfer3d(&v, &v, c.cap), TRN_OK);
    assert_int_equal(trn_outlier_density(&v, &c, &k), TRN_OK);
    for (z = 0; z < NZ; ++z) {
        double d = abs(z - zk) * (double)c.cell_m, sg = (double)c.sigma_m;
        want += exp(-d * d / (2 * sg * sg)) / (sg * sqrt(2 * M_PI));
    }
    want /= NZ;
    assert_true(fabs(k - want) <= 1e-12 * want);
}

/* K of eq. 5 by numerical integration: p1 of the exact Euclidean distance
 * to the nearest occupied voxel centre, averaged over 4x4x4 sample points
 * per voxel, against K from the chamfer histogram. The two differ by the
 * 3-4-5 metric, which over-estimates most off-axis distances by a few per
 * cent (measured here: K 6.1-6.5 % low on sparse random occupancy, whether
 * the integral samples 1 or 6^3 points per voxel, so it is the metric and
 * not the sampling). Bound asserted: 8 %. */
static void test_k_against_integration(void **state)
{
    enum { NX = 20, NY = 20, NZ = 8, SUB = TRN_K_SUB };
    static uint8_t occ[NX * NY * NZ], dist[NX * NY * NZ];
    trn_vol_u8_t vo, vd;
    trn_lik_cfg_t c = cfg_of(0.1f, 0.2f, 0.95f, 250);
    trn_rng_t r;
    int trial;
    (void)state;
    trn_rng_seed(&r, 5);
    assert_int_equal(trn_vol_u8_init(&vo, occ, sizeof occ, NX, NY, NZ), TRN_OK);
    assert_int_equal(trn_vol_u8_init(&vd, dist, sizeof dist, NX, NY, NZ), TRN_OK);
    for (trial = 0; trial < 3; ++trial) {
        int i, x, y, z, n = 0;
        int ox[64], oy[64], oz[64];
        double k_dt, sum = 0.0, k_num, s = 0.2 / 0.1; /* sigma in cells */
        memset(occ, 0, sizeof occ);
        for (i = 0; i < 12 + 10 * trial; ++i) {
            ox[n] = trn_rng_int(&r, 0, NX - 1);
            oy[n] = trn_rng_int(&r, 0, NY - 1);
            oz[n] = trn_rng_int(&r, 0, NZ - 1);
            occ[TRN_VOL_IDX(&vo, ox[n], oy[n], oz[n])] = 1;
            ++n;
        }
        assert_int_equal(trn_chamfer3d(&vo, &vd, c.cap), TRN_OK);
        assert_int_equal(trn_outlier_density(&vd, &c, &k_dt), TRN_OK);
        for (z = 0; z < NZ * SUB; ++z) {
            for (y = 0; y < NY * SUB; ++y) {
                for (x = 0; x < NX * SUB; ++x) {
                    double px = (x + 0.5) / SUB - 0.5, py = (y + 0.5) / SUB - 0.5,
                           pz = (z + 0.5) / SUB - 0.5, best = 1e30;
                    for (i = 0; i < n; ++i) {
                        double dx = px - ox[i], dy = py - oy[i], dz = pz - oz[i];
                        double d2 = dx * dx + dy * dy + dz * dz;
                        if (d2 < best) {
                            best = d2;
                        }
                    }
                    sum += exp(-best / (2 * s * s)) / (0.2 * sqrt(2 * M_PI));
                }
            }
        }
        k_num = sum / ((double)NX * NY * NZ * SUB * SUB * SUB);
        printf("K chamfer %.6f  K integrated %.6f  rel %.4f\n", k_dt, k_num,
               (k_dt - k_num) / k_num);
        assert_true(fabs(k_dt - k_num) <= 0.08 * k_num);
    }
}

/* ---- scoring against a naive double sum of the formula ------------------ */

static void random_dist(trn_vol_u8_t *v, uint8_t *buf, size_t cap_bytes, int nx, int ny, int nz,
                        uint8_t cap, trn_rng_t *r)
{
    size_t i;
    assert_int_equal(trn_vol_u8_init(v, buf, cap_bytes, nx, ny, nz), TRN_OK);
    for (i = 0; i < (size_t)nx * ny * nz; ++i) {
        buf[i] = (uint8_t)trn_rng_int(r, 0, cap);
    }
}

static void test_score_pose_vs_naive(void **state)
{
    enum { NX = 23, NY = 17, NZ = 5, NP = 40 };
    static uint8_t buf[NX * NY * NZ];
    trn_vol_u8_t v;
    trn_lik_cfg_t c = cfg_of(0.1f, 0.1f, 0.9f, 30);
    trn_lnp_table_t t;
    trn_point_t pts[NP];
    trn_rng_t r;
    int trial, i;
    (void)state;
    trn_rng_seed(&r, 21);
    random_dist(&v, buf, sizeof buf, NX, NY, NZ, 30, &r);
    assert_int_equal(trn_lnp_table_build(&t, &c, 0.3), TRN_OK);
    for (trial = 0; trial < 200; ++trial) {
        int px = trn_rng_int(&r, -12, NX + 12), py = trn_rng_int(&r, -12, NY + 12);
        int64_t s;
        double naive = 0.0;
        for (i = 0; i < NP; ++i) {
            int x, y;
            unsigned d;
            pts[i].x = (int16_t)trn_rng_int(&r, -6, 6);
            pts[i].y = (int16_t)trn_rng_int(&r, -6, 6);
            pts[i].z = (int16_t)trn_rng_int(&r, 0, NZ - 1);
            x = px + pts[i].x;
            y = py + pts[i].y;
            d = (x < 0 || y < 0 || x >= NX || y >= NY) ? 30u : buf[TRN_VOL_IDX(&v, x, y, pts[i].z)];
            naive += ref_lnp(&c, 0.3, d);
        }
        assert_int_equal(trn_score_pose(&v, &t, pts, NP, px, py, &s), TRN_OK);
        assert_true(fabs((double)s / TRN_LNP_SCALE - naive) <= NP * 0.5 / TRN_LNP_SCALE + 1e-9);
    }
}

/* ---- pyramid: every level equals a brute-force block minimum ---------- */

/* Every level of one random volume against a brute-force block minimum. */
static void pyramid_case(int NX, int NY, int NZ, int max_levels, trn_rng_t *r)
{
    uint8_t *buf = malloc((size_t)NX * NY * NZ);
    trn_vol_u8_t v;
    trn_pyramid_t p;
    int lv, nl;
    assert_non_null(buf);
    random_dist(&v, buf, (size_t)NX * NY * NZ, NX, NY, NZ, 40, r);
    for (nl = 1; nl <= max_levels; ++nl) {
        size_t bytes = trn_pyramid_bytes(NX, NY, NZ, nl);
        uint8_t *pb = malloc(bytes);
        assert_non_null(pb);
        assert_int_equal(trn_pyramid_build(&p, &v, 40, nl, pb, bytes - 1), TRN_E_WORKSPACE);
        assert_int_equal(trn_pyramid_build(&p, &v, 40, nl, pb, bytes), TRN_OK);
        assert_int_equal(p.pad, (1 << nl) - 1);
        for (lv = 1; lv <= nl; ++lv) {
            int b = 1 << lv, x, y, z, sx, sy;
            for (z = 0; z < NZ; ++z) {
                for (y = -p.pad; y < NY; ++y) {
                    for (x = -p.pad; x < NX; ++x) {
                        int want = 40;
                        for (sy = 0; sy < b; ++sy) {
                            for (sx = 0; sx < b; ++sx) {
                                int qx = x + sx, qy = y + sy;
                                if (qx >= 0 && qy >= 0 && qx < NX && qy < NY &&
                                    buf[TRN_VOL_IDX(&v, qx, qy, z)] < want) {
                                    want = buf[TRN_VOL_IDX(&v, qx, qy, z)];
                                }
                            }
                        }
                        assert_int_equal(
                            p.level[lv - 1][((size_t)z * p.pny + (size_t)(y + p.pad)) * p.pnx +
                                            (size_t)(x + p.pad)],
                            want);
                    }
                }
            }
        }
        free(pb);
    }
    free(buf);
}

/* Shapes cover rows narrower than one 16-byte block, exactly one block,
 * one block plus a tail, several blocks, and levels whose shift h or
 * padding is wider than the row. */
/* K against a plain per-voxel double sum, on volumes whose voxel counts
 * are not multiples of 4 (the histogram's tail) and on all-cap ones. */
static void test_k_vs_naive_sum(void **state)
{
    static const int shapes[][3] = {{1, 1, 1}, {3, 1, 1}, {5, 7, 3}, {16, 9, 2}, {31, 17, 5}};
    trn_lik_cfg_t c = cfg_of(0.1f, 0.1f, 0.95f, 40);
    trn_rng_t r;
    size_t i, j;
    (void)state;
    trn_rng_seed(&r, 31);
    for (i = 0; i < sizeof shapes / sizeof shapes[0]; ++i) {
        size_t nv = (size_t)shapes[i][0] * shapes[i][1] * shapes[i][2];
        uint8_t *buf = malloc(nv);
        trn_vol_u8_t v;
        int rep;
        assert_non_null(buf);
        assert_int_equal(trn_vol_u8_init(&v, buf, nv, shapes[i][0], shapes[i][1], shapes[i][2]),
                         TRN_OK);
        for (rep = 0; rep < 2; ++rep) {
            double k = 0.0, want = 0.0;
            for (j = 0; j < nv; ++j) {
                double d, sg = (double)c.sigma_m;
                buf[j] = rep == 0 ? (uint8_t)trn_rng_int(&r, 0, 40) : (uint8_t)40;
                d = buf[j] / 3.0 * (double)c.cell_m;
                want += exp(-d * d / (2 * sg * sg)) / (sg * sqrt(2 * M_PI));
            }
            want /= (double)nv;
            assert_int_equal(trn_outlier_density(&v, &c, &k), TRN_OK);
            assert_true(fabs(k - want) <= 1e-9 * want);
        }
        free(buf);
    }
}

static int point_cmp(const void *a, const void *b)
{
    const trn_point_t *p = a, *q = b;
    if (p->z != q->z) {
        return p->z < q->z ? -1 : 1;
    }
    if (p->y != q->y) {
        return p->y < q->y ? -1 : 1;
    }
    return p->x < q->x ? -1 : (p->x > q->x ? 1 : 0);
}

/* trn_points_order: a permutation, bins contiguous by increasing population
 * (ties: lower bin first), and the same best pose and score from both
 * searches before and after. */
static void test_points_order(void **state)
{
    enum { N = 3000 };
    static trn_point_t pts[N], orig[N], sa[N], sb[N];
    trn_rng_t r;
    int trial;
    (void)state;
    trn_rng_seed(&r, 77);
    for (trial = 0; trial < 40; ++trial) {
        int nz = trn_rng_int(&r, 1, trial < 30 ? 16 : TRN_MAX_ZBINS);
        size_t n = (size_t)trn_rng_int(&r, 0, N), i, cnt[TRN_MAX_ZBINS] = {0};
        int skew = trn_rng_int(&r, 0, 2);
        for (i = 0; i < n; ++i) {
            int z = trn_rng_int(&r, 0, nz - 1);
            if (skew == 1 && trn_rng_unit(&r) < 0.7) {
                z = nz / 2; /* one crowded bin, as the ground is */
            }
            pts[i].x = (int16_t)trn_rng_int(&r, -20, 20);
            pts[i].y = (int16_t)trn_rng_int(&r, -20, 20);
            pts[i].z = (int16_t)z;
            ++cnt[z];
        }
        memcpy(orig, pts, n * sizeof pts[0]);
        assert_int_equal(trn_points_order(pts, n, nz), TRN_OK);
        /* a permutation */
        memcpy(sa, orig, n * sizeof pts[0]);
        memcpy(sb, pts, n * sizeof pts[0]);
        qsort(sa, n, sizeof sa[0], point_cmp);
        qsort(sb, n, sizeof sb[0], point_cmp);
        if (n > 0u) {
            assert_memory_equal(sa, sb, n * sizeof sa[0]);
        }
        /* bins contiguous, in order of population */
        for (i = 1; i < n; ++i) {
            int zp = pts[i - 1].z, zc = pts[i].z;
            if (zp != zc) {
                size_t j;
                assert_true(cnt[zp] < cnt[zc] || (cnt[zp] == cnt[zc] && zp < zc));
                for (j = i + 1; j < n; ++j) {
                    assert_true(pts[j].z != zp); /* zp's run has ended */
                }
            }
        }
    }
    /* bad inputs leave the points unchanged */
    pts[0].x = 1;
    pts[0].y = 2;
    pts[0].z = 3;
    pts[1].x = 4;
    pts[1].y = 5;
    pts[1].z = 0;
    memcpy(orig, pts, 2 * sizeof pts[0]);
    assert_int_equal(trn_points_order(NULL, 2, 4), TRN_E_NULL);
    assert_int_equal(trn_points_order(pts, 2, 0), TRN_E_ARG);
    assert_int_equal(trn_points_order(pts, 2, TRN_MAX_ZBINS + 1), TRN_E_ARG);
    assert_int_equal(trn_points_order(pts, 2, 3), TRN_E_ARG); /* z = 3 outside 0..2 */
    pts[1].z = -1;
    assert_int_equal(trn_points_order(pts, 2, 8), TRN_E_ARG);
    pts[1].z = 0;
    assert_memory_equal(pts, orig, 2 * sizeof pts[0]);
    assert_int_equal(trn_points_order(pts, 0, 8), TRN_OK);
#if SIZE_MAX > UINT32_MAX
    /* more points than the uint32 bookkeeping can index: refused before
     * any point is read */
    assert_int_equal(trn_points_order(pts, (size_t)UINT32_MAX + 1u, 8), TRN_E_SIZE);
#endif
}

static void test_pyramid_vs_bruteforce(void **state)
{
    static const int shapes[][3] = {{19, 13, 3}, {1, 1, 1},  {5, 40, 2},  {16, 3, 2},
                                    {17, 9, 1},  {33, 7, 2}, {47, 21, 2}, {70, 5, 1}};
    trn_rng_t r;
    size_t i;
    (void)state;
    trn_rng_seed(&r, 8);
    for (i = 0; i < sizeof shapes / sizeof shapes[0]; ++i) {
        pyramid_case(shapes[i][0], shapes[i][1], shapes[i][2], 5, &r);
    }
}

/* ---- fast search equals exhaustive search ----------------------------- */

typedef struct {
    int nx, ny, nz;
    uint8_t *occ, *dist;
    trn_vol_u8_t vd;
    trn_lnp_table_t t;
} scene_t;

/* A random rock-like scene: occupied surface voxels with random bumps. */
static void scene_make(scene_t *s, int nx, int ny, int nz, trn_rng_t *r)
{
    trn_vol_u8_t vo;
    trn_lik_cfg_t c = cfg_of(0.1f, 0.1f, 0.95f, 45);
    double k;
    int x, y;
    s->nx = nx;
    s->ny = ny;
    s->nz = nz;
    s->occ = calloc((size_t)nx * ny * nz, 1);
    s->dist = malloc((size_t)nx * ny * nz);
    assert_true(s->occ != NULL && s->dist != NULL);
    assert_int_equal(trn_vol_u8_init(&vo, s->occ, (size_t)nx * ny * nz, nx, ny, nz), TRN_OK);
    assert_int_equal(trn_vol_u8_init(&s->vd, s->dist, (size_t)nx * ny * nz, nx, ny, nz), TRN_OK);
    for (y = 0; y < ny; ++y) {
        for (x = 0; x < nx; ++x) {
            int z = nz / 2 + (trn_rng_unit(r) < 0.08 ? trn_rng_int(r, 1, nz / 2 - 1) : 0);
            s->occ[TRN_VOL_IDX(&vo, x, y, z)] = 1;
        }
    }
    assert_int_equal(trn_chamfer3d(&vo, &s->vd, c.cap), TRN_OK);
    assert_int_equal(trn_outlier_density(&s->vd, &c, &k), TRN_OK);
    assert_int_equal(trn_lnp_table_build(&s->t, &c, k), TRN_OK);
}

static void scene_free(scene_t *s)
{
    free(s->occ);
    free(s->dist);
}

/* Local points: the occupied voxels of a patch around (tx, ty), relative to
 * it, with some voxels dropped and some outliers added. */
static size_t local_points(const scene_t *s, int tx, int ty, int half, trn_point_t *pts, size_t cap,
                           trn_rng_t *r)
{
    size_t n = 0;
    int x, y, z;
    for (z = 0; z < s->nz; ++z) {
        for (y = -half; y <= half; ++y) {
            for (x = -half; x <= half; ++x) {
                int gx = tx + x, gy = ty + y;
                if (gx < 0 || gy < 0 || gx >= s->nx || gy >= s->ny || n >= cap) {
                    continue;
                }
                if (s->occ[((size_t)z * s->ny + gy) * s->nx + gx] && trn_rng_unit(r) < 0.9) {
                    pts[n].x = (int16_t)x;
                    pts[n].y = (int16_t)y;
                    pts[n].z = (int16_t)z;
                    ++n;
                }
            }
        }
    }
    for (x = 0; x < 5 && n < cap; ++x) {
        pts[n].x = (int16_t)trn_rng_int(r, -half, half);
        pts[n].y = (int16_t)trn_rng_int(r, -half, half);
        pts[n].z = (int16_t)trn_rng_int(r, 0, s->nz - 1);
        ++n;
    }
    return n;
}

static void test_bb_equals_exhaustive(void **state)
{
    enum { CAP = 4000 };
    static trn_point_t pts[CAP];
    trn_rng_t r;
    int trial, cases = 0;
    uint64_t ex_scored = 0, bb_scored = 0;
    (void)state;
    trn_rng_seed(&r, 1234);
    for (trial = 0; trial < 12; ++trial) {
        scene_t s;
        trn_pyramid_t p;
        int nl = 1 + trial % 5, q;
        size_t pb;
        uint8_t *pbuf;
        scene_make(&s, trn_rng_int(&r, 20, 70), trn_rng_int(&r, 20, 70), trn_rng_int(&r, 4, 9), &r);
        pb = trn_pyramid_bytes(s.nx, s.ny, s.nz, nl);
        pbuf = malloc(pb);
        assert_non_null(pbuf);
        assert_int_equal(trn_pyramid_build(&p, &s.vd, s.t.cap, nl, pbuf, pb), TRN_OK);
        for (q = 0; q < 10; ++q) {
            trn_window_t w;
            trn_exclusion_t ex, *exp_ = NULL;
            trn_best_t be, bf;
            trn_search_stats_t se, sf;
            size_t n, wsb;
            void *ws;
            int tx = trn_rng_int(&r, 0, s.nx - 1), ty = trn_rng_int(&r, 0, s.ny - 1);
            n = local_points(&s, tx, ty, trn_rng_int(&r, 2, 9), pts, CAP, &r);
            if (n == 0) {
                continue;
            }
            w.x0 = trn_rng_int(&r, 0, s.nx - 1);
            w.x1 = trn_rng_int(&r, w.x0, s.nx - 1);
            w.y0 = trn_rng_int(&r, 0, s.ny - 1);
            w.y1 = trn_rng_int(&r, w.y0, s.ny - 1);
            if (q % 3 == 2) {
                ex.cx = trn_rng_int(&r, w.x0, w.x1);
                ex.cy = trn_rng_int(&r, w.y0, w.y1);
                ex.radius = trn_rng_int(&r, 0, 6);
                exp_ = &ex;
            }
            wsb = trn_search_bb_workspace_bytes(&p, &w);
            ws = malloc(wsb);
            assert_non_null(ws);
            {
                trn_status_t a = trn_search_exhaustive(&s.vd, &s.t, pts, n, &w, exp_, &be, &se);
                trn_status_t b = trn_search_bb(&p, &s.t, pts, n, &w, exp_, ws, wsb, &bf, &sf);
                assert_int_equal(a, b);
                if (q % 2 == 1) {
                    /* rare bins first: the early exits change, the answer must not */
                    trn_best_t bo;
                    assert_int_equal(trn_points_order(pts, n, s.nz), TRN_OK);
                    assert_int_equal(trn_search_bb(&p, &s.t, pts, n, &w, exp_, ws, wsb, &bo, NULL),
                                     b);
                    if (b == TRN_OK) {
                        assert_true(bo.x == bf.x && bo.y == bf.y && bo.score == bf.score);
                    }
                }
                if (a == TRN_OK) {
                    assert_int_equal(be.x, bf.x);
                    assert_int_equal(be.y, bf.y);
                    assert_true(be.score == bf.score);
                    ex_scored += se.poses_scored;
                    bb_scored += sf.poses_scored;
                    ++cases;
                } else {
                    assert_int_equal(a, TRN_E_NODATA); /* whole window excluded */
                }
            }
            free(ws);
        }
        free(pbuf);
        scene_free(&s);
    }
    printf("bb == exhaustive on %d cases; poses scored %llu vs %llu\n", cases,
           (unsigned long long)bb_scored, (unsigned long long)ex_scored);
    assert_true(cases >= 100);
    assert_true(bb_scored < ex_scored);
}

/* With no information anywhere every pose ties: both searches must return
 * the documented tie-break, the smallest (y, x) of the window. */
static void test_ties_resolved_identically(void **state)
{
    enum { NX = 30, NY = 25, NZ = 4 };
    static uint8_t buf[NX * NY * NZ];
    trn_vol_u8_t v;
    trn_lnp_table_t t;
    trn_lik_cfg_t c = cfg_of(0.1f, 0.1f, 0.95f, 20);
    trn_pyramid_t p;
    trn_point_t pts[3] = {{0, 0, 1}, {2, 1, 2}, {-1, 3, 0}};
    trn_window_t w = {4, 6, 20, 19};
    trn_best_t be, bf;
    size_t pb;
    uint8_t *pbuf;
    void *ws;
    (void)state;
    memset(buf, 20, sizeof buf);
    assert_int_equal(trn_vol_u8_init(&v, buf, sizeof buf, NX, NY, NZ), TRN_OK);
    assert_int_equal(trn_lnp_table_build(&t, &c, 0.5), TRN_OK);
    pb = trn_pyramid_bytes(NX, NY, NZ, 3);
    pbuf = malloc(pb);
    assert_int_equal(trn_pyramid_build(&p, &v, 20, 3, pbuf, pb), TRN_OK);
    ws = malloc(trn_search_bb_workspace_bytes(&p, &w));
    assert_int_equal(trn_search_exhaustive(&v, &t, pts, 3, &w, NULL, &be, NULL), TRN_OK);
    assert_int_equal(trn_search_bb(&p, &t, pts, 3, &w, NULL, ws,
                                   trn_search_bb_workspace_bytes(&p, &w), &bf, NULL),
                     TRN_OK);
    assert_int_equal(be.x, 4);
    assert_int_equal(be.y, 6);
    assert_int_equal(bf.x, 4);
    assert_int_equal(bf.y, 6);
    free(ws);
    free(pbuf);
}

/* ---- every bad-input class -------------------------------------------- */

static void test_bad_inputs(void **state)
{
    enum { NX = 12, NY = 10, NZ = 3 };
    static uint8_t buf[NX * NY * NZ];
    trn_vol_u8_t v, bad;
    trn_lnp_table_t t;
    trn_lik_cfg_t c = cfg_of(0.1f, 0.1f, 0.95f, 20);
    trn_pyramid_t p;
    TRN_WORKSPACE_DECLARE(pbuf, 200000);
    trn_point_t pts[2] = {{0, 0, 1}, {1, 1, 2}}, badz[1] = {{0, 0, 3}};
    trn_window_t w = {1, 1, 8, 7}, off = {5, 5, NX, 6}, inv = {5, 5, 4, 6};
    trn_exclusion_t negr = {3, 3, -1}, all = {4, 4, 100};
    trn_best_t b;
    TRN_WORKSPACE_DECLARE(ws, 16384);
    double k;
    int64_t s;
    trn_lik_cfg_t bc;
    (void)state;
    memset(buf, 5, sizeof buf);
    assert_int_equal(trn_vol_u8_init(&v, buf, sizeof buf, NX, NY, NZ), TRN_OK);

    /* configuration */
    assert_int_equal(trn_lik_cfg_check(NULL), TRN_E_NULL);
    bc = c;
    bc.cell_m = 0.0f;
    assert_int_equal(trn_lik_cfg_check(&bc), TRN_E_ARG);
    bc = c;
    bc.cell_m = NAN;
    assert_int_equal(trn_lik_cfg_check(&bc), TRN_E_ARG);
    bc = c;
    bc.sigma_m = -1.0f;
    assert_int_equal(trn_lik_cfg_check(&bc), TRN_E_ARG);
    bc = c;
    bc.sigma_m = NAN;
    assert_int_equal(trn_lik_cfg_check(&bc), TRN_E_ARG);
    bc = c;
    bc.inlier_prob = 1.0f;
    assert_int_equal(trn_lik_cfg_check(&bc), TRN_E_ARG);
    bc = c;
    bc.inlier_prob = 0.0f;
    assert_int_equal(trn_lik_cfg_check(&bc), TRN_E_ARG);
    bc = c;
    bc.cap = 2;
    assert_int_equal(trn_lik_cfg_check(&bc), TRN_E_ARG);
    bc = c;
    bc.cap = TRN_CHAMFER_CAP_MAX + 1;
    assert_int_equal(trn_lik_cfg_check(&bc), TRN_E_ARG);

    /* K */
    assert_int_equal(trn_outlier_density(NULL, &c, &k), TRN_E_NULL);
    assert_int_equal(trn_outlier_density(&v, NULL, &k), TRN_E_NULL);
    assert_int_equal(trn_outlier_density(&v, &c, NULL), TRN_E_NULL);
    bad = v;
    bad.nz = 0;
    assert_int_equal(trn_outlier_density(&bad, &c, &k), TRN_E_SIZE);
    bc = c;
    bc.cap = 4;
    assert_int_equal(trn_outlier_density(&v, &bc, &k), TRN_E_ARG);
    {
        /* one voxel above cap (or above any table index) anywhere: each lane
         * of the first 4-voxel group, the middle, the last two voxels */
        static const size_t at[] = {0u, 1u, 2u, 3u, 181u, 358u, 359u};
        static const uint8_t val[] = {21u, 255u};
        size_t ia, iv;
        for (ia = 0; ia < sizeof at / sizeof at[0]; ++ia) {
            for (iv = 0; iv < 2u; ++iv) {
                buf[at[ia]] = val[iv];
                assert_int_equal(trn_outlier_density(&v, &c, &k), TRN_E_ARG);
                buf[at[ia]] = 5u;
            }
        }
        assert_int_equal(trn_outlier_density(&v, &c, &k), TRN_OK);
    }

    /* table */
    assert_int_equal(trn_lnp_table_build(NULL, &c, 1.0), TRN_E_NULL);
    assert_int_equal(trn_lnp_table_build(&t, NULL, 1.0), TRN_E_NULL);
    assert_int_equal(trn_lnp_table_build(&t, &c, 0.0), TRN_E_ARG);
    assert_int_equal(trn_lnp_table_build(&t, &c, NAN), TRN_E_ARG);
    assert_int_equal(trn_lnp_table_build(&t, &c, INFINITY), TRN_E_ARG);
    assert_int_equal(trn_lnp_table_build(&t, &c, 1.0), TRN_OK);

    /* scoring */
    assert_int_equal(trn_score_pose(NULL, &t, pts, 2, 0, 0, &s), TRN_E_NULL);
    assert_int_equal(trn_score_pose(&v, NULL, pts, 2, 0, 0, &s), TRN_E_NULL);
    assert_int_equal(trn_score_pose(&v, &t, NULL, 2, 0, 0, &s), TRN_E_NULL);
    assert_int_equal(trn_score_pose(&v, &t, pts, 2, 0, 0, NULL), TRN_E_NULL);
    assert_int_equal(trn_score_pose(&v, &t, pts, 0, 0, 0, &s), TRN_E_NODATA);
    assert_int_equal(trn_score_pose(&v, &t, badz, 1, 0, 0, &s), TRN_E_ARG);
    assert_int_equal(trn_score_pose(&v, &t, pts, 2, 3 * TRN_MAX_DIM, 0, &s), TRN_E_RANGE);
    bad = v;
    bad.nx = TRN_MAX_DIM + 1;
    assert_int_equal(trn_score_pose(&bad, &t, pts, 2, 0, 0, &s), TRN_E_SIZE);

    /* exhaustive */
    assert_int_equal(trn_search_exhaustive(&v, &t, pts, 2, NULL, NULL, &b, NULL), TRN_E_NULL);
    assert_int_equal(trn_search_exhaustive(&v, &t, pts, 2, &w, NULL, NULL, NULL), TRN_E_NULL);
    assert_int_equal(trn_search_exhaustive(&v, &t, pts, 2, &off, NULL, &b, NULL), TRN_E_RANGE);
    assert_int_equal(trn_search_exhaustive(&v, &t, pts, 2, &inv, NULL, &b, NULL), TRN_E_RANGE);
    assert_int_equal(trn_search_exhaustive(&v, &t, pts, 2, &w, &negr, &b, NULL), TRN_E_ARG);
    assert_int_equal(trn_search_exhaustive(&v, &t, pts, 2, &w, &all, &b, NULL), TRN_E_NODATA);
    assert_int_equal(trn_search_exhaustive(&v, &t, pts, 0, &w, NULL, &b, NULL), TRN_E_NODATA);
    assert_int_equal(trn_search_exhaustive(&v, &t, badz, 1, &w, NULL, &b, NULL), TRN_E_ARG);

    /* pyramid */
    assert_int_equal(trn_pyramid_bytes(0, NY, NZ, 2), 0u);
    assert_int_equal(trn_pyramid_bytes(NX, NY, NZ, 0), 0u);
    assert_int_equal(trn_pyramid_bytes(NX, NY, NZ, TRN_MAX_LEVELS + 1), 0u);
    assert_int_equal(trn_pyramid_build(NULL, &v, 20, 2, pbuf, sizeof pbuf), TRN_E_NULL);
    assert_int_equal(trn_pyramid_build(&p, &v, 20, 2, NULL, sizeof pbuf), TRN_E_NULL);
    assert_int_equal(trn_pyramid_build(&p, NULL, 20, 2, pbuf, sizeof pbuf), TRN_E_NULL);
    assert_int_equal(trn_pyramid_build(&p, &v, 20, 0, pbuf, sizeof pbuf), TRN_E_ARG);
    assert_int_equal(trn_pyramid_build(&p, &v, 2, 2, pbuf, sizeof pbuf), TRN_E_ARG);
    bad = v;
    bad.ny = 0;
    assert_int_equal(trn_pyramid_build(&p, &bad, 20, 2, pbuf, sizeof pbuf), TRN_E_SIZE);
    assert_int_equal(trn_pyramid_build(&p, &v, 20, 2, pbuf, 10), TRN_E_WORKSPACE);
    assert_true(trn_pyramid_bytes(NX, NY, NZ, 2) + 8u <=
                sizeof pbuf); /* misaligned, large enough */
    assert_int_equal(trn_pyramid_build(&p, &v, 20, 2, pbuf + 8, sizeof pbuf - 8u), TRN_E_WORKSPACE);
    assert_int_equal(trn_pyramid_build(&p, &v, 20, 2, pbuf, sizeof pbuf), TRN_OK);

    /* branch and bound */
    assert_true(trn_search_bb_workspace_bytes(&p, &w) <= sizeof ws);
    assert_int_equal(trn_search_bb_workspace_bytes(NULL, &w), 0u);
    assert_int_equal(trn_search_bb_workspace_bytes(&p, &inv), 0u);
    assert_int_equal(trn_search_bb(NULL, &t, pts, 2, &w, NULL, ws, sizeof ws, &b, NULL),
                     TRN_E_NULL);
    assert_int_equal(trn_search_bb(&p, NULL, pts, 2, &w, NULL, ws, sizeof ws, &b, NULL),
                     TRN_E_NULL);
    assert_int_equal(trn_search_bb(&p, &t, NULL, 2, &w, NULL, ws, sizeof ws, &b, NULL), TRN_E_NULL);
    assert_int_equal(trn_search_bb(&p, &t, pts, 2, NULL, NULL, ws, sizeof ws, &b, NULL),
                     TRN_E_NULL);
    assert_int_equal(trn_search_bb(&p, &t, pts, 2, &w, NULL, NULL, sizeof ws, &b, NULL),
                     TRN_E_NULL);
    assert_int_equal(trn_search_bb(&p, &t, pts, 2, &w, NULL, ws, sizeof ws, NULL, NULL),
                     TRN_E_NULL);
    assert_int_equal(trn_search_bb(&p, &t, pts, 2, &off, NULL, ws, sizeof ws, &b, NULL),
                     TRN_E_RANGE);
    assert_int_equal(trn_search_bb(&p, &t, pts, 2, &w, &negr, ws, sizeof ws, &b, NULL), TRN_E_ARG);
    assert_int_equal(trn_search_bb(&p, &t, pts, 2, &w, &all, ws, sizeof ws, &b, NULL),
                     TRN_E_NODATA);
    assert_int_equal(trn_search_bb(&p, &t, pts, 0, &w, NULL, ws, sizeof ws, &b, NULL),
                     TRN_E_NODATA);
    assert_int_equal(trn_search_bb(&p, &t, badz, 1, &w, NULL, ws, sizeof ws, &b, NULL), TRN_E_ARG);
    assert_int_equal(trn_search_bb(&p, &t, pts, 2, &w, NULL, ws, 1, &b, NULL), TRN_E_WORKSPACE);
    assert_true(trn_search_bb_workspace_bytes(&p, &w) + 8u <= sizeof ws);
    assert_int_equal(trn_search_bb(&p, &t, pts, 2, &w, NULL, ws + 8, sizeof ws - 8u, &b, NULL),
                     TRN_E_WORKSPACE);
    bc = c;
    bc.cap = 30;
    {
        trn_lnp_table_t t2;
        assert_int_equal(trn_lnp_table_build(&t2, &bc, 1.0), TRN_OK);
        /* a table built for another cap than the pyramid's */
        assert_int_equal(trn_search_bb(&p, &t2, pts, 2, &w, NULL, ws, sizeof ws, &b, NULL),
                         TRN_E_ARG);
    }
    assert_int_equal(trn_search_bb(&p, &t, pts, 2, &w, NULL, ws, sizeof ws, &b, NULL), TRN_OK);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lnp_table_matches_formula),
        cmocka_unit_test(test_k_plane_analytic),
        cmocka_unit_test(test_k_against_integration),
        cmocka_unit_test(test_score_pose_vs_naive),
        cmocka_unit_test(test_k_vs_naive_sum),
        cmocka_unit_test(test_points_order),
        cmocka_unit_test(test_pyramid_vs_bruteforce),
        cmocka_unit_test(test_bb_equals_exhaustive),
        cmocka_unit_test(test_ties_resolved_identically),
        cmocka_unit_test(test_bad_inputs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
