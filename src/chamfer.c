/* chamfer.c - 3-D chamfer distance transform, Borgefors 3-4-5 weights
 * (see trn/chamfer.h and method.md 2.4).
 *
 * Algorithm. Two raster passes over the volume. The forward pass visits
 * voxels in z, y, x increasing order and relaxes each voxel against its 13
 * already-visited neighbours; the backward pass does the mirror image. Every
 * step of a forward (backward) pass goes to a later (earlier) voxel in raster
 * order, so one pass carries a value along any path made only of forward
 * (backward) steps. A shortest 3-4-5 path between two voxels can be taken
 * monotone in each axis and reordered as "all forward steps, then all
 * backward steps" without leaving the box spanned by its ends, so after the
 * two passes every voxel holds min(exact 26-neighbour chamfer distance, cap).
 *
 * Row decomposition (forward pass; the backward pass mirrors y and z). The
 * 12 causal neighbours of voxel (x, y, z) outside its own row lie in the rows
 *   P- = (y-1, z-1), P0 = (y, z-1), P+ = (y+1, z-1) and C- = (y-1, z).
 * Their 3-4-5 weights factor as
 *   min over them of (d + w) = A(T)(x) + 3, where
 *   T(x)    = min(min(P-[x], P+[x]) + 1, min(P0[x], C-[x]))      (per column)
 *   A(T)(x) = min(T[x], min(T[x-1], T[x+1]) + 1)                   (along x)
 * (check: P-[x] + 4 edge, P-[x+-1] + 5 corner, P0[x] + 3 face, P0[x+-1] + 4
 * edge, C-[x] + 3 face, C-[x+-1] + 4 edge). This is element-wise work over a
 * row, done in blocks of LANES bytes whose fixed-count inner loops compilers
 * turn into vector instructions (or tight scalar loops on cores without
 * SIMD). A missing neighbour row (volume face) is replaced by a row whose
 * term dominates it, so one kernel serves every row. The 13th neighbour,
 * (x-1, y, z), is then folded in by a sequential scan d[x] = min(d[x],
 * d[x-1] + 3).
 *
 * Arithmetic. Stored values never exceed cap <= TRN_CHAMFER_CAP_MAX <= 250,
 * so T <= cap + 1, A(T) + 3 <= cap + 5 <= 255 and a scan sum d + 3 <= 253:
 * every intermediate fits in uint8_t, and every stored value stays <= cap
 * because it is a minimum that includes the value already there.
 *
 * Memory: none beyond the caller's volume (one LANES-byte block on the stack).
 * No allocation, no recursion, no VLA; every loop is bounded by nx, ny, nz or
 * LANES.
 */
#include "trn/chamfer.h"

/** Bytes per block of the row kernels: one 128-bit vector register. */
#define LANES 16

static uint8_t min_u8(uint8_t a, uint8_t b) { return (a < b) ? a : b; }

/** a + k for small k; callers guarantee a + k <= 255 (see file comment). */
static uint8_t add_u8(uint8_t a, unsigned k) { return (uint8_t)((unsigned)a + k); }

/**
 * Forward init of one row: dst[x] = (src[x] != 0) ? 0 : cap. src may equal
 * dst (in place). Returns the OR of all src bytes (nonzero: some voxel
 * occupied).
 */
static unsigned init_row(uint8_t *dst, const uint8_t *src, size_t nx, uint8_t cap)
{
    uint8_t any = 0u;
    size_t x = 0u;
    /* Blocks: read into a local block first, then write, so in-place use
     * needs no alias reasoning from the compiler. */
    for (; x + LANES <= nx; x += LANES) {
        uint8_t v[LANES];
        size_t k;
        for (k = 0u; k < LANES; k++) {
            uint8_t s = src[x + k];
            any = (uint8_t)(any | s);
            v[k] = (s != 0u) ? (uint8_t)0u : cap;
        }
        for (k = 0u; k < LANES; k++) {
            dst[x + k] = v[k];
        }
    }
    for (; x < nx; x++) {
        uint8_t s = src[x];
        any = (uint8_t)(any | s);
        dst[x] = (s != 0u) ? (uint8_t)0u : cap;
    }
    return any;
}

/** T(x) of the file comment: a, b take +1 (edge rows), c, d take +0. */
static uint8_t col_min(const uint8_t *a, const uint8_t *b, const uint8_t *c,
                       const uint8_t *d, size_t x)
{
    return min_u8(add_u8(min_u8(a[x], b[x]), 1u), min_u8(c[x], d[x]));
}

/** row[x] = min(row[x], A(T)(x) + 3) for one x, any position. */
static void relax_one(uint8_t *row, const uint8_t *a, const uint8_t *b,
                      const uint8_t *c, const uint8_t *d, size_t x, size_t nx)
{
    uint8_t t = col_min(a, b, c, d, x);
    if (x > 0u) {
        t = min_u8(t, add_u8(col_min(a, b, c, d, x - 1u), 1u));
    }
    if (x + 1u < nx) {
        t = min_u8(t, add_u8(col_min(a, b, c, d, x + 1u), 1u));
    }
    row[x] = min_u8(row[x], add_u8(t, TRN_CHAMFER_FACE));
}

/** One block of relax_row: voxels [x, x + LANES), all with 0 < x, x+LANES < nx. */
static void relax_block(uint8_t *row, const uint8_t *a, const uint8_t *b,
                        const uint8_t *c, const uint8_t *d, size_t x)
{
    uint8_t v[LANES];
    size_t k;
    for (k = 0u; k < LANES; k++) {
        const size_t i = x + k;
        const uint8_t tm = col_min(a, b, c, d, i - 1u);
        const uint8_t t0 = col_min(a, b, c, d, i);
        const uint8_t tp = col_min(a, b, c, d, i + 1u);
        const uint8_t t = min_u8(t0, add_u8(min_u8(tm, tp), 1u));
        v[k] = min_u8(row[i], add_u8(t, TRN_CHAMFER_FACE));
    }
    for (k = 0u; k < LANES; k++) {
        row[x + k] = v[k];
    }
}

/**
 * Relax a whole row against its 12 out-of-row neighbours, given as four
 * rows (see file comment). The four rows never overlap row. Relaxing is
 * idempotent, so the last block may overlap the one before it.
 */
static void relax_row(uint8_t *row, const uint8_t *a, const uint8_t *b,
                      const uint8_t *c, const uint8_t *d, size_t nx)
{
    size_t x;
    relax_one(row, a, b, c, d, 0u, nx);
    if (nx >= LANES + 2u) {
        /* Interior [1, nx-1) in blocks; x-1 and x+1 exist for all of them. */
        const size_t last = nx - 1u - LANES;
        for (x = 1u; x < last; x += LANES) {
            relax_block(row, a, b, c, d, x);
        }
        relax_block(row, a, b, c, d, last);
        relax_one(row, a, b, c, d, nx - 1u, nx);
    } else {
        for (x = 1u; x < nx; x++) {
            relax_one(row, a, b, c, d, x, nx);
        }
    }
}

/**
 * In-row forward scan: row[x] = min(row[x], row[x-1] + 3) for x increasing.
 * The scan is a serial dependency chain, so it is skipped where it would
 * change nothing: a block of LANES voxels is left alone when no voxel in it
 * exceeds its left neighbour + 3 (checked with vectorizable block loops; the
 * left neighbour of the block's first voxel is already final). Only blocks
 * near a new in-row source fail the check and get the serial scan.
 */
static void scan_forward(uint8_t *row, size_t nx)
{
    size_t x = 1u;
    for (; x + LANES <= nx; x += LANES) {
        unsigned bad = 0u;
        size_t k;
        for (k = 0u; k < LANES; k++) {
            bad |= (add_u8(row[x + k - 1u], TRN_CHAMFER_FACE) < row[x + k]) ? 1u : 0u;
        }
        if (bad != 0u) {
            uint8_t prev = row[x - 1u];
            for (k = 0u; k < LANES; k++) {
                uint8_t cur = min_u8(row[x + k], add_u8(prev, TRN_CHAMFER_FACE));
                row[x + k] = cur;
                prev = cur;
            }
        }
    }
    for (; x < nx; x++) {
        row[x] = min_u8(row[x], add_u8(row[x - 1u], TRN_CHAMFER_FACE));
    }
}

/**
 * In-row backward scan: row[x] = min(row[x], row[x+1] + 3) for x decreasing,
 * with the same block skip as scan_forward. Voxels [hi, nx) are final.
 */
static void scan_backward(uint8_t *row, size_t nx)
{
    size_t hi = nx - 1u;
    size_t i;
    for (; hi >= LANES; hi -= LANES) {
        const size_t x0 = hi - LANES; /* block [x0, hi), right neighbour hi final */
        unsigned bad = 0u;
        size_t k;
        for (k = 0u; k < LANES; k++) {
            bad |= (add_u8(row[x0 + k + 1u], TRN_CHAMFER_FACE) < row[x0 + k]) ? 1u : 0u;
        }
        if (bad != 0u) {
            uint8_t prev = row[hi];
            for (k = 0u; k < LANES; k++) {
                const size_t x = hi - 1u - k;
                uint8_t cur = min_u8(row[x], add_u8(prev, TRN_CHAMFER_FACE));
                row[x] = cur;
                prev = cur;
            }
        }
    }
    for (i = 0u; i < hi; i++) {
        const size_t x = hi - 1u - i;
        row[x] = min_u8(row[x], add_u8(row[x + 1u], TRN_CHAMFER_FACE));
    }
}

/**
 * Relax row (y, z) against the out-of-row neighbours of one pass.
 * dy, dz = -1 (forward: previous row and plane) or +1 (backward: next ones);
 * the neighbours used are rows (y+dy, z), (y-1..y+1, z+dz) where they exist.
 * A missing row is replaced by one whose term dominates it (min is
 * idempotent, and a row with +1 dominates the same row with +0).
 */
static void relax_neighbours(uint8_t *vol, size_t nx, size_t ny, size_t nz,
                             size_t y, size_t z, int dir)
{
    const size_t plane = nx * ny;
    uint8_t *row = vol + (z * ny + y) * nx;
    const int has_row = (dir < 0) ? (y > 0u) : (y + 1u < ny);
    const int has_plane = (dir < 0) ? (z > 0u) : (z + 1u < nz);
    const uint8_t *c_prev = has_row ? ((dir < 0) ? row - nx : row + nx) : NULL;

    if (has_plane) {
        const uint8_t *p0 = (dir < 0) ? row - plane : row + plane;
        const uint8_t *pm = (y > 0u) ? p0 - nx : NULL;
        const uint8_t *pp = (y + 1u < ny) ? p0 + nx : NULL;
        /* +1 rows: pm and pp; stand-ins dominate (pp alone, or p0 + 1). */
        const uint8_t *a = (pm != NULL) ? pm : ((pp != NULL) ? pp : p0);
        const uint8_t *b = (pp != NULL) ? pp : a;
        /* +0 rows: p0 and the in-plane neighbour row. */
        const uint8_t *d = (c_prev != NULL) ? c_prev : p0;
        relax_row(row, a, b, p0, d, nx);
    } else if (c_prev != NULL) {
        /* Only the in-plane neighbour row: T = c_prev. */
        relax_row(row, c_prev, c_prev, c_prev, c_prev, nx);
    } else {
        /* First row of the pass: nothing outside the row. */
    }
}

trn_status_t trn_chamfer3d(const trn_vol_u8_t *occ, trn_vol_u8_t *dist, uint8_t cap)
{
    trn_status_t st;
    size_t nx;
    size_t ny;
    size_t nz;
    size_t total;
    size_t y;
    size_t z;
    unsigned any = 0u;
    uint8_t *vol;

    if (occ == NULL || dist == NULL || occ->data == NULL || dist->data == NULL) {
        return TRN_E_NULL;
    }
    st = trn_vol_u8_check(occ);
    if (st != TRN_OK) {
        return st;
    }
    st = trn_vol_u8_check(dist);
    if (st != TRN_OK) {
        return st;
    }
    if (occ->nx != dist->nx || occ->ny != dist->ny || occ->nz != dist->nz) {
        return TRN_E_SIZE;
    }
    if (cap < 3u || cap > TRN_CHAMFER_CAP_MAX) {
        return TRN_E_ARG;
    }
    nx = (size_t)dist->nx;
    ny = (size_t)dist->ny;
    nz = (size_t)dist->nz;
    total = nx * ny * nz;
    {
        /* occ and dist must be the same memory or disjoint: a partial overlap
         * would read occupancy the transform has already overwritten. */
        const uintptr_t o = (uintptr_t)(const void *)occ->data;
        const uintptr_t d = (uintptr_t)(void *)dist->data;
        if (o != d && o < d + total && d < o + total) {
            return TRN_E_ARG;
        }
    }
    vol = dist->data;

    /* Forward pass: z, y, x increasing. Row (y, z) of occ is read just before
     * row (y, z) of dist is written, so occ == dist works. */
    for (z = 0u; z < nz; z++) {
        for (y = 0u; y < ny; y++) {
            const size_t off = (z * ny + y) * nx;
            any |= init_row(vol + off, occ->data + off, nx, cap);
            relax_neighbours(vol, nx, ny, nz, y, z, -1);
            scan_forward(vol + off, nx);
        }
    }
    /* Backward pass: z, y, x decreasing. */
    for (z = 0u; z < nz; z++) {
        for (y = 0u; y < ny; y++) {
            const size_t zz = nz - 1u - z;
            const size_t yy = ny - 1u - y;
            relax_neighbours(vol, nx, ny, nz, yy, zz, +1);
            scan_backward(vol + (zz * ny + yy) * nx, nx);
        }
    }
    return (any != 0u) ? TRN_OK : TRN_E_NODATA;
}
