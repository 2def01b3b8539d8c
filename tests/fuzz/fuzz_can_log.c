/* SPDX-License-Identifier: Apache-2.0 */
/* fuzz_can_log.c - the candump log reader of `trn can-decode`
 * (tools/trn/can_log.c, can_log_parse: one line in, one parsed record out).
 *
 * Input: the bytes of one line (up to 255, cut at the first NUL).
 * Invariants:
 * - kind is one of the five; MALFORMED has a reason, the others none;
 * - FRAME: dlc <= 8, a standard id <= 0x7FF or (EXT) <= 0x1FFFFFFF, no
 *   flag bits besides EXT and RTR, usec < 10^6, an interface name of 1..16
 *   characters that appears in the line;
 * - a data frame printed back in candump syntax parses to the same frame,
 *   timestamp and interface (round trip).
 */
/* fuzz-extra: tools/trn/can_log.c */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "can_log.h"
#include "fuzz_input.h"

#define FZ_CHECK(c) \
    do { \
        if (!(c)) { \
            abort(); \
        } \
    } while (0)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char line[256], again[128];
    can_log_line_t r, r2;
    size_t n = size < sizeof line - 1u ? size : sizeof line - 1u;
    int k, pos;

    memcpy(line, data, n);
    line[n] = '\0';
    can_log_parse(line, &r);
    FZ_CHECK(r.kind == CAN_LOG_FRAME || r.kind == CAN_LOG_FD || r.kind == CAN_LOG_ERROR ||
             r.kind == CAN_LOG_SKIP || r.kind == CAN_LOG_MALFORMED);
    FZ_CHECK((r.kind == CAN_LOG_MALFORMED) == (r.reason != NULL));
    if (r.kind != CAN_LOG_FRAME) {
        return 0;
    }
    FZ_CHECK(r.frame.dlc <= 8u && r.usec < 1000000u);
    FZ_CHECK((r.frame.flags & ~(unsigned)(TRN_CAN_FLAG_EXT | TRN_CAN_FLAG_RTR)) == 0u);
    if ((r.frame.flags & TRN_CAN_FLAG_EXT) != 0u) {
        FZ_CHECK(r.frame.id <= 0x1FFFFFFFu);
    } else {
        FZ_CHECK(r.frame.id <= 0x7FFu);
    }
    FZ_CHECK(memchr(r.ifname, '\0', sizeof r.ifname) != NULL);
    FZ_CHECK(strlen(r.ifname) >= 1u && strlen(r.ifname) <= 16u && strstr(line, r.ifname) != NULL);
    if ((r.frame.flags & TRN_CAN_FLAG_RTR) != 0u) {
        return 0;
    }
    /* round trip of a data frame */
    pos = snprintf(again, sizeof again, "(%" PRIu64 ".%06" PRIu32 ") %s %0*" PRIX32 "#", r.sec,
                   r.usec, r.ifname, (r.frame.flags & TRN_CAN_FLAG_EXT) != 0u ? 8 : 3, r.frame.id);
    FZ_CHECK(pos > 0 && (size_t)pos < sizeof again - 20u);
    for (k = 0; k < r.frame.dlc; ++k) {
        pos += snprintf(again + pos, sizeof again - (size_t)pos, "%02X", r.frame.data[k]);
    }
    can_log_parse(again, &r2);
    FZ_CHECK(r2.kind == CAN_LOG_FRAME && r2.sec == r.sec && r2.usec == r.usec);
    FZ_CHECK(strcmp(r2.ifname, r.ifname) == 0);
    FZ_CHECK(r2.frame.id == r.frame.id && r2.frame.flags == r.frame.flags &&
             r2.frame.dlc == r.frame.dlc);
    FZ_CHECK(memcmp(r2.frame.data, r.frame.data, r.frame.dlc) == 0);
    return 0;
}
