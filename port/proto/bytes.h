/* SPDX-License-Identifier: Apache-2.0 */
/* bytes.h - explicit byte order for port/proto (private).
 * Shifts only, never struct overlays or pointer casts, so the result does
 * not depend on the processor's byte order. */
#ifndef TRN_PROTO_BYTES_H
#define TRN_PROTO_BYTES_H

#include <stdint.h>

static inline void trn_put_u16le(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)(v >> 8);
}

static inline uint16_t trn_get_u16le(const uint8_t *p)
{
    return (uint16_t)((uint16_t)p[0] | (uint16_t)((uint16_t)p[1] << 8));
}

static inline void trn_put_u32le(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v & 0xFFu);
    p[1] = (uint8_t)((v >> 8) & 0xFFu);
    p[2] = (uint8_t)((v >> 16) & 0xFFu);
    p[3] = (uint8_t)(v >> 24);
}

static inline uint32_t trn_get_u32le(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

/* Two's complement through uint16_t: well defined in both directions for
 * every int16_t value (C99 6.3.1.3: conversion to unsigned is modular; the
 * signed result is rebuilt arithmetically, not by an implementation-defined
 * conversion). */
static inline void trn_put_i16le(uint8_t *p, int16_t v) { trn_put_u16le(p, (uint16_t)v); }

static inline int16_t trn_get_i16le(const uint8_t *p)
{
    uint16_t u = trn_get_u16le(p);
    int32_t s = (u >= 0x8000u) ? ((int32_t)u - 65536) : (int32_t)u;
    return (int16_t)s;
}

#endif /* TRN_PROTO_BYTES_H */
