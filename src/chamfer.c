/* SPDX-License-Identifier: Apache-2.0 */
/* chamfer.c - 3-D chamfer distance transform, Borgefors 3-4-5 weights
 * (see trn/chamfer.h and method.md 2.4).
 *
 * Algorithm. Two raster passes over the volume. The forward pass visits
 * rows in z, y increasing order and relaxes each voxel against its 12
 * already-visited neighbours outside its own row ("causal" steps); a row
 * that holds an occupied voxel is then closed along x in both directions
 * (the in-row scans below). The backward pass visits rows in z, y
 * decreasing order and relaxes each voxel against its 12 neighbours in
 * later rows ("anti-causal" steps), with no in-row work at all.
 *
 * Why that is exact. A shortest 3-4-5 path from an occupied voxel s to a
 * voxel p can be taken monotone in each axis, so its steps can be reordered
 * at will without leaving the box spanned by s and p: take first its in-row
 * steps (+-x, ending at q1 in the row of s), then its causal out-of-row
 * steps (ending at q2), then its anti-causal ones. The row of s holds an
 * occupied voxel, so its closure gives forward(q1) <= 3 |q1 - s|; every
 * causal step goes to a later row, whose relaxation accounts for it, so
 * forward(q2) <= forward(q1) + (their weights); the backward pass likewise
 * adds the anti-causal steps. Every stored value is the length of some path
 * (or cap), so after the two passes every voxel holds min(exact
 * 26-neighbour chamfer distance, cap). Rows without an occupied voxel never
 * need the closure: the argument only uses the rows of sources.
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
 * row. A missing neighbour row (volume face) is replaced by a row whose term
 * dominates it, so one kernel serves every row. The in-row steps
 * (x+-1, y, z) are the in-row scans d[x] = min(d[x], d[x-+1] + 3), done
 * without a serial chain where it matters (see "In-row scans" below).
 *
 * Speed. Every kernel is written as blocks of LANES bytes whose fixed-count
 * inner loops compilers turn into 128-bit vector instructions at -O2 (SSE2
 * on x86-64, NEON on AArch64; GCC's -O2 cost model vectorizes only loops
 * with a known trip count) and into short scalar loops on cores without
 * SIMD. A block reads everything it needs before it writes, so in-place use
 * needs no aliasing analysis. Per row and pass the work is two passes over
 * L1-resident rows: T into a scratch, then A (fused with the
 * occupancy-to-0/cap start in the forward pass); rows with an occupied
 * voxel (about a third on terrain) add two dirty checks and a few doubling
 * steps. Measured on the project's x86-64 machine (GCC 12, -O2, cap 60,
 * synthetic terrain, 256^2 and 512^2 x 16 voxels): see docs/benchmarks.md
 * ("Chamfer"). The relaxation alone, T and A, costs 3.7-3.9x one SIMD
 * row-to-row streaming pass on one L1-resident row, and 3.1-3.2x two such
 * passes over the whole volume (trn_bench's floor row): it does 7 loads and
 * 2 stores per 16 voxels against 2 and 1, its 12 out-of-row neighbours
 * lying in 4 rows and needing their x-neighbours. That is why the transform
 * stays above 3x two streaming passes.
 *
 * Arithmetic. Stored values never exceed cap <= TRN_CHAMFER_CAP_MAX <= 250,
 * so T <= cap + 1, A(T) + 3 <= cap + 5 <= 255 and a scan sum d + 3 <= 253:
 * every intermediate fits in uint8_t, and every stored value stays <= cap
 * because it is a minimum that includes the value already there.
 *
 * Memory: none beyond the caller's volume, apart from fixed-size stack
 * scratch (CHUNK + 2 bytes of T and a few LANES-byte blocks; the deepest call
 * chain uses under 700 bytes of stack on x86-64, AArch64 and Cortex-R5 per
 * -fstack-usage). No allocation, no recursion, no VLA, no static state; every
 * loop is bounded by nx, ny, nz, CHUNK, LANES or SCAN_MAX_STEPS.
 */
#include "trn/chamfer.h"
#include <string.h>

/** Bytes per block of the row kernels: one 128-bit vector register. */
#define LANES 16u

static uint8_t min_u8(uint8_t a, uint8_t b) { return (a < b) ? a : b; }

/** a + k for small k; callers guarantee a + k <= 255 (see file comment). */
static uint8_t add_u8(uint8_t a, unsigned k) { return (uint8_t)((unsigned)a + k); }

/** Start value of a voxel in the forward pass: 0 if occupied, else cap. */
static uint8_t init_of(uint8_t occ, uint8_t cap) { return (occ != 0u) ? (uint8_t)0u : cap; }

/** OR of the LANES bytes of acc (nonzero iff some byte is). */
static uint8_t or_lanes(const uint8_t *acc)
{
    uint8_t r = 0u;
    size_t k;
    for (k = 0u; k < LANES; k++) {
        r = (uint8_t)(r | acc[k]);
    }
    return r;
}

/**
 * Forward start of a row with no neighbour rows (the very first row):
 * dst[x] = init_of(src[x]). src may equal dst. Returns nonzero iff some
 * voxel of the row is occupied.
 */
static unsigned init_row(uint8_t *dst, const uint8_t *src, size_t nx, uint8_t cap)
{
    uint8_t acc[LANES] = {0u};
    uint8_t any = 0u;
    size_t x = 0u;
    for (; x + LANES <= nx; x += LANES) {
        uint8_t v[LANES];
        size_t k;
        for (k = 0u; k < LANES; k++) {
            const uint8_t s = src[x + k];
            acc[k] = (uint8_t)(acc[k] | s);
            v[k] = init_of(s, cap);
        }
        for (k = 0u; k < LANES; k++) {
            dst[x + k] = v[k];
        }
    }
    for (; x < nx; x++) {
        const uint8_t s = src[x];
        any = (uint8_t)(any | s);
        dst[x] = init_of(s, cap);
    }
    return (unsigned)(any | or_lanes(acc));
}

/** T(x) of the file comment: a, b take +1 (edge rows), c, d take +0. */
static uint8_t col_min(const uint8_t *a, const uint8_t *b, const uint8_t *c, const uint8_t *d,
                       size_t x)
{
    return min_u8(add_u8(min_u8(a[x], b[x]), 1u), min_u8(c[x], d[x]));
}

/** Voxels of a row handled per chunk of relax_row (its stack scratch). */
#define CHUNK 256u
/** T of a column outside the volume's x range: it only enters A as
 * T + 1, and T_OUTSIDE + 1 + 3 = 255 > cap never wins yet fits in uint8_t. */
#define T_OUTSIDE 251u

/**
 * Relax a whole row against its 12 out-of-row neighbours, given as the four
 * rows a, b (+1) and c, d (+0) of the file comment, which never overlap row:
 * row[x] = min(start(x), A(T)(x) + 3), where start(x) is init_of(src[x]) in
 * the forward pass (src: the occupancy row, possibly the same memory as row)
 * and row[x] itself in the backward pass (src NULL). Returns nonzero iff
 * some src voxel is occupied (0 when src is NULL).
 *
 * Per chunk of up to CHUNK voxels, T is first written to a small scratch
 * (with T_OUTSIDE beyond the volume's x ends), then A is applied from it:
 * about half the work of recomputing T at x-1, x and x+1. The T loop is a
 * block loop whose last block may overlap the one before (T is a pure
 * function of the neighbour rows); the A loop has a scalar tail instead,
 * because re-reading src after an in-place write would be wrong.
 */
static unsigned relax_row(uint8_t *row, const uint8_t *src, uint8_t cap, const uint8_t *a,
                          const uint8_t *b, const uint8_t *c, const uint8_t *d, size_t nx)
{
    uint8_t tb[CHUNK + 2u]; /* tb[1 + x - c0] = T(x) for x in [c0 - 1, c1] */
    uint8_t acc[LANES] = {0u};
    uint8_t any = 0u;
    size_t c0;
    for (c0 = 0u; c0 < nx; c0 += CHUNK) {
        const size_t c1 = (nx - c0 > CHUNK) ? c0 + CHUNK : nx; /* chunk [c0, c1) */
        const size_t t0 = (c0 > 0u) ? c0 - 1u : 0u;            /* T needed on [t0, t1) */
        const size_t t1 = (c1 < nx) ? c1 + 1u : nx;
        uint8_t *const tt = tb + (1u + t0 - c0); /* tt[x - t0] = T(x) */
        const uint8_t *const tm = tb;            /* tm[x - c0] = T(x - 1) */
        const uint8_t *const t0p = tb + 1u;      /* t0p[x - c0] = T(x) */
        const uint8_t *const tp = tb + 2u;       /* tp[x - c0] = T(x + 1) */
        size_t x;
        size_t k;
        tb[0] = (uint8_t)T_OUTSIDE;
        tb[1u + (c1 - c0)] = (uint8_t)T_OUTSIDE;
        if (t1 - t0 >= LANES) {
            for (x = t0; x < t1; x += LANES) {
                const size_t x0 = (x + LANES <= t1) ? x : t1 - LANES;
                for (k = 0u; k < LANES; k++) {
                    tt[x0 - t0 + k] = col_min(a, b, c, d, x0 + k);
                }
            }
        } else {
            for (x = t0; x < t1; x++) {
                tt[x - t0] = col_min(a, b, c, d, x);
            }
        }
        x = c0;
        if (src != NULL) {
            for (; x + LANES <= c1; x += LANES) {
                const size_t j0 = x - c0;
                uint8_t v[LANES];
                for (k = 0u; k < LANES; k++) {
                    const uint8_t s = src[x + k];
                    const uint8_t t = min_u8(t0p[j0 + k],
                                             add_u8(min_u8(tm[j0 + k], tp[j0 + k]), 1u));
                    acc[k] = (uint8_t)(acc[k] | s);
                    v[k] = min_u8(init_of(s, cap), add_u8(t, TRN_CHAMFER_FACE));
                }
                for (k = 0u; k < LANES; k++) {
                    row[x + k] = v[k];
                }
            }
        } else {
            for (; x + LANES <= c1; x += LANES) {
                const size_t j0 = x - c0;
                uint8_t v[LANES];
                for (k = 0u; k < LANES; k++) {
                    const uint8_t t = min_u8(t0p[j0 + k],
                                             add_u8(min_u8(tm[j0 + k], tp[j0 + k]), 1u));
                    v[k] = min_u8(row[x + k], add_u8(t, TRN_CHAMFER_FACE));
                }
                for (k = 0u; k < LANES; k++) {
                    row[x + k] = v[k];
                }
            }
        }
        for (; x < c1; x++) {
            const size_t j = x - c0;
            const uint8_t t = min_u8(t0p[j], add_u8(min_u8(tm[j], tp[j]), 1u));
            uint8_t start = row[x];
            if (src != NULL) {
                any = (uint8_t)(any | src[x]);
                start = init_of(src[x], cap);
            }
            row[x] = min_u8(start, add_u8(t, TRN_CHAMFER_FACE));
        }
    }
    return (unsigned)(any | or_lanes(acc));
}

/*
 * In-row scans. The forward scan is row[x] = min(row[x], row[x-1] + 3) for x
 * increasing, i.e. row[x] = min over j >= 0 of (row0[x-j] + 3j). Done one
 * voxel at a time it is a serial dependency chain (about 3 cycles a voxel),
 * so instead:
 *  1. find the voxels that break row[x] <= row[x-1] + 3 ("dirty"), with
 *     vectorizable block checks. A row with none is already final (the bound
 *     then holds for every j, by induction), as are most rows of a smooth
 *     field. Otherwise let f be the first and L the last dirty voxel. A
 *     term row0[x-j] + 3j can only win if 3j < row0[x] - row0[x-j], so j is
 *     at most reach = (spread - 1) / 3, spread being max - min of the values
 *     involved (<= cap, so reach <= 83). Only [f, L + reach) can change,
 *     and terms from before f - 1 never win because [0, f) is clean;
 *  2. run Hillis-Steele doubling on [f - 1, min(nx, L + reach + 1)): step s
 *     (s = 1, 2, 4, ...) sets row[x] = min(row[x], row[x-s] + 3s), after
 *     which every offset j < 2s is covered, so scan_steps(reach) steps
 *     (2^steps > reach) give the exact scan. Each step is element-wise
 *     and runs in place from the high end down (row[x-s] is read before it
 *     is written); a sum row + 3s that would pass 255 is clamped to 255,
 *     which is > cap and so changes nothing. Reading a value some earlier
 *     block of the same step already lowered only tightens the bound and
 *     never goes below the exact scan, so the last block may overlap.
 * The backward scan is the mirror image. Both run only on rows with an
 * occupied voxel, in the forward pass, right after the row's relaxation.
 * Most such rows have a dirty voxel (measured: 81-84 % on the benchmark
 * terrain, 2.7 doubling steps over about 70 % of the row on average), but
 * the spread bound keeps the step count near 2 in dense volumes and the span
 * bound keeps the range short in sparse ones.
 */

/** Most doubling steps ever needed: shifts 1..64 cover offsets up to 127. */
#define SCAN_MAX_STEPS 7u
#if ((TRN_CHAMFER_CAP_MAX - 1) / 3) >= (1 << 7)
#error "SCAN_MAX_STEPS too small for TRN_CHAMFER_CAP_MAX"
#endif

/** Number of doubling steps for a reach: smallest m with 2^m > reach. */
static unsigned scan_steps(size_t reach)
{
    unsigned m;
    for (m = 0u; m < SCAN_MAX_STEPS; m++) {
        if (((size_t)1u << m) > reach) {
            break;
        }
    }
    return m;
}

/**
 * 1 if some i in [i0, i0 + LANES) has cur[i] > nb[i] + 3. The excess
 * cur - min(cur, nb + 3) is nonzero exactly there; its 16 bytes are OR-ed as
 * two 64-bit words (cheaper than a byte-wise horizontal reduction).
 */
static unsigned dirty_block(const uint8_t *cur, const uint8_t *nb, size_t i0)
{
    uint8_t e[LANES];
    uint64_t w0, w1;
    size_t k;
    for (k = 0u; k < LANES; k++) {
        const uint8_t c = cur[i0 + k];
        e[k] = (uint8_t)(c - min_u8(c, add_u8(nb[i0 + k], TRN_CHAMFER_FACE)));
    }
    memcpy(&w0, e, sizeof w0);
    memcpy(&w1, e + 8, sizeof w1);
    return ((w0 | w1) != 0u) ? 1u : 0u;
}

/**
 * Dirty span of i in [0, m): cur[i] > nb[i] + 3. Returns 0 if there is none;
 * else 1 with every dirty i inside [*first, *end) (block granularity).
 */
static int dirty_span(const uint8_t *cur, const uint8_t *nb, size_t m, size_t *first, size_t *end)
{
    size_t i;
    if (m < LANES) {
        int found = 0;
        for (i = 0u; i < m; i++) {
            if (add_u8(nb[i], TRN_CHAMFER_FACE) < cur[i]) {
                if (found == 0) {
                    *first = i;
                    found = 1;
                }
                *end = i + 1u;
            }
        }
        return found;
    } else {
        /* Blocks [b * LANES, ...), the last one overlapping: [m - LANES, m). */
        const size_t nblk = (m + LANES - 1u) / LANES;
        size_t b;
        size_t bf = nblk; /* first dirty block */
        for (b = 0u; b < nblk; b++) {
            if (b + 1u == nblk) {
                if (dirty_block(cur, nb, m - LANES) == 0u) {
                    return 0;
                }
                bf = b;
                *first = m - LANES;
                break;
            }
            if (dirty_block(cur, nb, LANES * b) != 0u) {
                bf = b;
                *first = LANES * b;
                break;
            }
        }
        *end = *first + LANES;
        for (b = nblk; b > bf + 1u; b--) {
            /* Block b - 1, from the last down to just above block bf. */
            const size_t i0 = (b < nblk) ? LANES * (b - 1u) : m - LANES;
            if (dirty_block(cur, nb, i0) != 0u) {
                *end = i0 + LANES;
                break;
            }
        }
        return 1;
    }
}

/** Doubling step forward: row[x] = min(row[x], row[x-sh] + 3 sh), x in [sh, n). */
static void step_fwd(uint8_t *row, size_t n, size_t sh)
{
    const unsigned w = TRN_CHAMFER_FACE * (unsigned)sh; /* <= 192 */
    const uint8_t lim = (uint8_t)(255u - w);
    if (n - sh >= LANES) {
        const size_t nblk = (n - sh + LANES - 1u) / LANES;
        size_t b;
        for (b = 0u; b < nblk; b++) {
            /* Blocks from the high end down; the last one starts at sh. */
            const size_t x0 = (b + 1u < nblk) ? n - LANES * (b + 1u) : sh;
            uint8_t v[LANES];
            size_t k;
            for (k = 0u; k < LANES; k++) {
                v[k] = min_u8(row[x0 + k], add_u8(min_u8(row[x0 + k - sh], lim), w));
            }
            for (k = 0u; k < LANES; k++) {
                row[x0 + k] = v[k];
            }
        }
    } else {
        size_t i;
        for (i = 0u; i < n - sh; i++) {
            const size_t x = n - 1u - i;
            row[x] = min_u8(row[x], add_u8(min_u8(row[x - sh], lim), w));
        }
    }
}

/** Doubling step backward: row[x] = min(row[x], row[x+sh] + 3 sh), x in [0, n-sh). */
static void step_bwd(uint8_t *row, size_t n, size_t sh)
{
    const unsigned w = TRN_CHAMFER_FACE * (unsigned)sh;
    const uint8_t lim = (uint8_t)(255u - w);
    if (n - sh >= LANES) {
        const size_t nblk = (n - sh + LANES - 1u) / LANES;
        size_t b;
        for (b = 0u; b < nblk; b++) {
            /* Blocks from the low end up; the last one ends at n - sh. */
            const size_t x0 = (b + 1u < nblk) ? LANES * b : n - sh - LANES;
            uint8_t v[LANES];
            size_t k;
            for (k = 0u; k < LANES; k++) {
                v[k] = min_u8(row[x0 + k], add_u8(min_u8(row[x0 + k + sh], lim), w));
            }
            for (k = 0u; k < LANES; k++) {
                row[x0 + k] = v[k];
            }
        }
    } else {
        size_t x;
        for (x = 0u; x < n - sh; x++) {
            row[x] = min_u8(row[x], add_u8(min_u8(row[x + sh], lim), w));
        }
    }
}

/** max - min of row[lo, hi), hi > lo (vector max/min per lane, then across). */
static unsigned row_spread(const uint8_t *row, size_t lo, size_t hi)
{
    uint8_t mx[LANES];
    uint8_t mn[LANES];
    uint8_t big = 0u;
    uint8_t small = 255u;
    size_t x = lo;
    size_t k;
    for (k = 0u; k < LANES; k++) {
        mx[k] = 0u;
        mn[k] = 255u;
    }
    for (; x + LANES <= hi; x += LANES) {
        for (k = 0u; k < LANES; k++) {
            const uint8_t v = row[x + k];
            mx[k] = (v > mx[k]) ? v : mx[k];
            mn[k] = (v < mn[k]) ? v : mn[k];
        }
    }
    for (k = 0u; k < LANES; k++) {
        big = (mx[k] > big) ? mx[k] : big;
        small = (mn[k] < small) ? mn[k] : small;
    }
    for (; x < hi; x++) {
        big = (row[x] > big) ? row[x] : big;
        small = (row[x] < small) ? row[x] : small;
    }
    return (unsigned)big - (unsigned)small;
}

/** Largest offset j that can win in a dirty range whose values span `spread`
 * (max - min, >= 4 when there is a dirty voxel): 3j < spread. */
static size_t reach_of(unsigned spread)
{
    return (spread > 0u) ? ((size_t)spread - 1u) / TRN_CHAMFER_FACE : 0u;
}

/** Forward in-row scan of row[0, nx) (see above). */
static void scan_forward(uint8_t *row, size_t nx)
{
    size_t first = 0u;
    size_t end = 0u;
    size_t lo;
    size_t n;
    size_t reach;
    unsigned steps;
    unsigned m;
    /* Voxel x = i + 1 is dirty if row[i+1] > row[i] + 3, i in [0, nx-1). */
    if (nx < 2u || dirty_span(row + 1u, row, nx - 1u, &first, &end) == 0) {
        return; /* already final */
    }
    lo = first; /* the voxel before the first dirty one: final */
    reach = reach_of(row_spread(row, lo, nx));
    steps = scan_steps(reach);
    /* Dirty voxels are <= end, so voxels from end + reach on cannot change. */
    n = (end + reach + 1u < nx) ? end + reach + 1u - lo : nx - lo; /* [lo, lo + n) */
    for (m = 0u; m < steps; m++) {
        const size_t sh = (size_t)1u << m;
        if (sh >= n) {
            break;
        }
        step_fwd(row + lo, n, sh);
    }
}

/** Backward in-row scan of row[0, nx) (see above). */
static void scan_backward(uint8_t *row, size_t nx)
{
    size_t first = 0u;
    size_t end = 0u;
    size_t lo;
    size_t n;
    size_t reach;
    unsigned steps;
    unsigned m;
    /* Voxel x = i is dirty if row[i] > row[i+1] + 3, i in [0, nx-1). */
    if (nx < 2u || dirty_span(row, row + 1u, nx - 1u, &first, &end) == 0) {
        return; /* already final */
    }
    reach = reach_of(row_spread(row, 0u, end + 1u));
    steps = scan_steps(reach);
    /* Dirty voxels are in [first, end): voxels below first - reach cannot
     * change, and row[end] is clean and after every dirty voxel: final. */
    lo = (first > reach) ? first - reach : 0u;
    n = end + 1u - lo; /* [lo, end] */
    for (m = 0u; m < steps; m++) {
        const size_t sh = (size_t)1u << m;
        if (sh >= n) {
            break;
        }
        step_bwd(row + lo, n, sh);
    }
}

/**
 * One row (y, z) of a pass, before any in-row scan: relax it against the
 * out-of-row neighbours of the pass. dir = -1 (forward: previous row and
 * plane) or +1 (backward: next ones); the neighbours used are rows
 * (y+dir, z) and (y-1..y+1, z+dir) where they exist. A missing row is
 * replaced by one whose term dominates it (min is idempotent, and a row with
 * +1 dominates the same row with +0). src: the occupancy row in the forward
 * pass (the row starts from init_of(src)), NULL in the backward pass.
 * Returns nonzero iff some src voxel is occupied.
 */
static unsigned relax_neighbours(uint8_t *vol, const uint8_t *src, uint8_t cap, size_t nx,
                                 size_t ny, size_t nz, size_t y, size_t z, int dir)
{
    const size_t plane = nx * ny;
    uint8_t *row = vol + (z * ny + y) * nx;
    const int has_row = (dir < 0) ? (y > 0u) : (y + 1u < ny);
    const int has_plane = (dir < 0) ? (z > 0u) : (z + 1u < nz);
    const uint8_t *c_prev = has_row ? ((dir < 0) ? row - nx : row + nx) : NULL;
    unsigned any = 0u;

    if (has_plane) {
        const uint8_t *p0 = (dir < 0) ? row - plane : row + plane;
        const uint8_t *pm = (y > 0u) ? p0 - nx : NULL;
        const uint8_t *pp = (y + 1u < ny) ? p0 + nx : NULL;
        /* +1 rows: pm and pp; stand-ins dominate (pp alone, or p0 + 1). */
        const uint8_t *a = (pm != NULL) ? pm : ((pp != NULL) ? pp : p0);
        const uint8_t *b = (pp != NULL) ? pp : a;
        /* +0 rows: p0 and the in-plane neighbour row. */
        const uint8_t *d = (c_prev != NULL) ? c_prev : p0;
        any = relax_row(row, src, cap, a, b, p0, d, nx);
    } else if (c_prev != NULL) {
        /* Only the in-plane neighbour row: T = c_prev. */
        any = relax_row(row, src, cap, c_prev, c_prev, c_prev, c_prev, nx);
    } else if (src != NULL) {
        /* First row of the forward pass: nothing outside the row. */
        any = init_row(row, src, nx, cap);
    } else {
        /* First row of the backward pass: nothing outside the row. */
    }
    return any;
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

    /* Forward pass: z, y, x increasing. Each block of row (y, z) of occ is
     * read before the same block of dist is written, and never again, so
     * occ == dist works. */
    for (z = 0u; z < nz; z++) {
        for (y = 0u; y < ny; y++) {
            const size_t off = (z * ny + y) * nx;
            const unsigned row_any = relax_neighbours(vol, occ->data + off, cap, nx, ny, nz, y, z,
                                                      -1);
            /* Only the rows of occupied voxels are closed along x (see the
             * file comment); the others are already closed anyway, as
             * min(cap, A(T) + 3) of closed rows. */
            any |= row_any;
            if (row_any != 0u) {
                scan_forward(vol + off, nx);
                scan_backward(vol + off, nx);
            }
        }
    }
    /* Backward pass: rows in z, y decreasing, out-of-row steps only. */
    for (z = 0u; z < nz; z++) {
        for (y = 0u; y < ny; y++) {
            (void)relax_neighbours(vol, NULL, cap, nx, ny, nz, ny - 1u - y, nz - 1u - z, +1);
        }
    }
    return (any != 0u) ? TRN_OK : TRN_E_NODATA;
}
