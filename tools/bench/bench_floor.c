/* SPDX-License-Identifier: Apache-2.0 */
/* bench_floor.c - the relaxation-only floor of a two-pass 3-4-5 chamfer
 * transform (bench_floor.h), timed by trn_bench beside trn_chamfer3d.
 *
 * Each interior row gets exactly the out-of-row work of src/chamfer.c's
 * passes, in the same form (fixed 16-byte blocks that GCC -O2 vectorizes):
 *   T(x) = min(min(a[x], b[x]) + 1, min(c[x], d[x]))   from 4 neighbour rows,
 *   row[x] = min(start, min(T[x], min(T[x-1], T[x+1]) + 1) + 3),
 * start being 0/cap from the occupancy (forward) or the row itself
 * (backward). What it leaves out: the volume's faces (plane 0 and rows 0
 * and ny-1 only get their start value) and every in-row step, so it is
 * cheaper than any exact transform of this form. */
#include "bench_floor.h"

#define FLANES 16u
#define T_EDGE 251u /* T beyond the row: T + 1 + 3 = 255 > cap never wins */

static uint8_t fmin8(uint8_t a, uint8_t b) { return a < b ? a : b; }

size_t bench_relax_floor_scratch(size_t nx) { return nx + 2u; }

/* t[1 + x] = T(x) for x in [0, nx); t[0] = t[nx + 1] = T_EDGE. */
static void col_min(uint8_t *t, const uint8_t *a, const uint8_t *b, const uint8_t *c,
                    const uint8_t *d, size_t nx)
{
    size_t x, k;
    t[0] = (uint8_t)T_EDGE;
    t[nx + 1u] = (uint8_t)T_EDGE;
    for (x = 0u; x < nx; x += FLANES) {
        const size_t x0 = (x + FLANES <= nx) ? x : nx - FLANES;
        uint8_t v[FLANES];
        for (k = 0u; k < FLANES; ++k) {
            v[k] = fmin8((uint8_t)(fmin8(a[x0 + k], b[x0 + k]) + 1u), fmin8(c[x0 + k], d[x0 + k]));
        }
        for (k = 0u; k < FLANES; ++k) {
            t[1u + x0 + k] = v[k];
        }
    }
}

/* A(T)(x) + 3 for the block at x0, into a. */
static void a_block(uint8_t *a, const uint8_t *t, size_t x0)
{
    size_t k;
    for (k = 0u; k < FLANES; ++k) {
        a[k] = (uint8_t)(fmin8(t[1u + x0 + k], (uint8_t)(fmin8(t[x0 + k], t[2u + x0 + k]) + 1u)) +
                         3u);
    }
}

/* Forward: row[x] = min(occ[x] ? 0 : cap, A(T)(x) + 3). */
static void apply_fwd(uint8_t *row, const uint8_t *occ, const uint8_t *t, size_t nx, uint8_t cap)
{
    size_t x, k;
    for (x = 0u; x < nx; x += FLANES) {
        const size_t x0 = (x + FLANES <= nx) ? x : nx - FLANES;
        uint8_t a[FLANES];
        a_block(a, t, x0);
        for (k = 0u; k < FLANES; ++k) {
            a[k] = fmin8((occ[x0 + k] != 0u) ? (uint8_t)0u : cap, a[k]);
        }
        for (k = 0u; k < FLANES; ++k) {
            row[x0 + k] = a[k];
        }
    }
}

/* Backward: row[x] = min(row[x], A(T)(x) + 3). */
static void apply_bwd(uint8_t *row, const uint8_t *t, size_t nx)
{
    size_t x, k;
    for (x = 0u; x < nx; x += FLANES) {
        const size_t x0 = (x + FLANES <= nx) ? x : nx - FLANES;
        uint8_t a[FLANES];
        a_block(a, t, x0);
        for (k = 0u; k < FLANES; ++k) {
            a[k] = fmin8(row[x0 + k], a[k]);
        }
        for (k = 0u; k < FLANES; ++k) {
            row[x0 + k] = a[k];
        }
    }
}

void bench_relax_floor(const uint8_t *occ, uint8_t *v, size_t nx, size_t ny, size_t nz, uint8_t cap,
                       uint8_t *scratch)
{
    const size_t plane = nx * ny;
    size_t y, z, x;
    for (z = 0u; z < nz; ++z) {
        for (y = 0u; y < ny; ++y) {
            const size_t off = z * plane + y * nx;
            uint8_t *row = v + off;
            if (z == 0u || y == 0u || y + 1u == ny) {
                for (x = 0u; x < nx; ++x) {
                    row[x] = (occ[off + x] != 0u) ? (uint8_t)0u : cap;
                }
                continue;
            }
            col_min(scratch, row - plane - nx, row - plane + nx, row - plane, row - nx, nx);
            apply_fwd(row, occ + off, scratch, nx, cap);
        }
    }
    for (z = nz - 1u; z-- > 0u;) {
        for (y = ny - 1u; y-- > 1u;) {
            uint8_t *row = v + z * plane + y * nx;
            col_min(scratch, row + plane - nx, row + plane + nx, row + plane, row + nx, nx);
            apply_bwd(row, scratch, nx);
        }
    }
}
