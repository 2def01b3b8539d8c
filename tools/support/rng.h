/* SPDX-License-Identifier: Apache-2.0 */
/* rng.h - deterministic seeded generator for tests, tools and benchmarks
 * (splitmix64). The core itself has no random state. */
#ifndef TRN_SUPPORT_RNG_H
#define TRN_SUPPORT_RNG_H
#include <math.h>
#include <stdint.h>

typedef struct {
    uint64_t s;
} trn_rng_t;

static inline void trn_rng_seed(trn_rng_t *r, uint64_t seed) { r->s = seed; }

static inline uint64_t trn_rng_u64(trn_rng_t *r)
{
    uint64_t z = (r->s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/** Uniform in [0, 1). */
static inline double trn_rng_unit(trn_rng_t *r)
{
    return (double)(trn_rng_u64(r) >> 11) * (1.0 / 9007199254740992.0);
}

/** Uniform integer in [lo, hi]. */
static inline int32_t trn_rng_int(trn_rng_t *r, int32_t lo, int32_t hi)
{
    uint64_t span = (uint64_t)((int64_t)hi - (int64_t)lo + 1);
    return (int32_t)((int64_t)lo + (int64_t)(trn_rng_u64(r) % span));
}
/** Standard normal (Box-Muller, two uniforms per draw). */
static inline double trn_rng_gauss(trn_rng_t *r)
{
    double u1 = trn_rng_unit(r), u2 = trn_rng_unit(r);
    u1 = u1 < 1e-300 ? 1e-300 : u1;
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}
#endif
