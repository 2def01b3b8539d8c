/* SPDX-License-Identifier: Apache-2.0 */
/* ws.h - the workspace rule, internal to the core (see docs/architecture.md,
 * "Workspace memory").
 *
 * Every function that takes a caller's workspace has a sizing function, and
 * both lay the workspace out with the same carve: a function of its
 * arguments that takes slices in order through trn_ws_take. The sizing
 * function runs the carve with no base and returns the total; the function
 * runs it on the caller's buffer after trn_ws_check. Every slice starts at a
 * multiple of TRN_WS_ALIGN from the base, and the base itself must be
 * TRN_WS_ALIGN-aligned, so every slice may hold any scalar type. */
#ifndef TRN_WS_H
#define TRN_WS_H

#include <stddef.h>
#include <stdint.h>

#include "trn/grid.h"
#include "trn/status.h"

/** A workspace being carved: base (NULL when only sizing) and bytes taken. */
typedef struct {
    uint8_t *base;
    size_t total;
} trn_ws_t;

/* Start a carve of base (NULL: sizing only). */
static inline void trn_ws_begin(trn_ws_t *w, void *base)
{
    w->base = (uint8_t *)base;
    w->total = 0u;
}

/* Next slice of n bytes (rounded up to TRN_WS_ALIGN): its offset from the
 * base (for layouts kept as offsets). */
static inline size_t trn_ws_offset(trn_ws_t *w, size_t n)
{
    size_t at = w->total;
    w->total += TRN_ALIGN_UP(n);
    return at;
}

/* Next slice of n bytes: its start, or NULL when sizing only. */
static inline void *trn_ws_take(trn_ws_t *w, size_t n)
{
    size_t at = trn_ws_offset(w, n);
    return (w->base != NULL) ? (void *)(w->base + at) : NULL;
}

/* TRN_OK when ws is TRN_WS_ALIGN-aligned and holds at least need bytes
 * (need 0: the sizing function refused the arguments); else TRN_E_WORKSPACE.
 * ws is not NULL (callers check that first, as TRN_E_NULL). */
static inline trn_status_t trn_ws_check(const void *ws, size_t ws_bytes, size_t need)
{
    if (need == 0u || ws_bytes < need || ((uintptr_t)ws % (uintptr_t)TRN_WS_ALIGN) != 0u) {
        return TRN_E_WORKSPACE;
    }
    return TRN_OK;
}

#endif /* TRN_WS_H */
