/* SPDX-License-Identifier: Apache-2.0 */
/* fuzz_input.h - read typed values from a libFuzzer input, for the harnesses
 * in tests/fuzz/. Past the end every read returns zero bytes, so any input
 * (including the empty one) is a valid sequence of values. Values are taken
 * raw: a float/double from bytes covers NaN, infinities, subnormals and huge
 * magnitudes, which is the point. */
#ifndef TRN_FUZZ_INPUT_H
#define TRN_FUZZ_INPUT_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

typedef struct {
    const uint8_t *p;
    size_t n;
} fz_t;

static void fz_bytes(fz_t *f, void *out, size_t k)
{
    size_t take = (f->n < k) ? f->n : k;
    memset(out, 0, k);
    if (take > 0u) {
        memcpy(out, f->p, take);
        f->p += take;
        f->n -= take;
    }
}

static uint8_t fz_u8(fz_t *f)
{
    uint8_t v;
    fz_bytes(f, &v, sizeof v);
    return v;
}

static int32_t fz_i32(fz_t *f)
{
    int32_t v;
    fz_bytes(f, &v, sizeof v);
    return v;
}

static float fz_f32(fz_t *f)
{
    float v;
    fz_bytes(f, &v, sizeof v);
    return v;
}

static double fz_f64(fz_t *f)
{
    double v;
    fz_bytes(f, &v, sizeof v);
    return v;
}

/* A small size in [lo, hi] from one byte. */
static int32_t fz_range(fz_t *f, int32_t lo, int32_t hi)
{
    return lo + (int32_t)(fz_u8(f) % (uint32_t)(hi - lo + 1));
}

/* A status any public function may return: the documented codes only. */
static int fz_status_known(int st) { return st <= 0 && st >= -15; }

#endif /* TRN_FUZZ_INPUT_H */
