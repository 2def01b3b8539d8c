/* SPDX-License-Identifier: Apache-2.0 */
/* can_log.h - one line of a candump log (can-utils `candump -l`), parsed.
 *
 *   (1700000000.123456) vcan0 121#0102030405060708
 *   (1700000000.123456) vcan0 12345678#R          extended id, remote frame
 *   (1700000000.123456) vcan0 123##1112233        CAN FD (flags nibble, data)
 *
 * Pure parsing (no I/O), so it is testable on its own. */
#ifndef TRN_TOOLS_CAN_LOG_H
#define TRN_TOOLS_CAN_LOG_H

#include <stddef.h>
#include <stdint.h>

#include "trn_port/can_msg.h"

typedef enum {
    CAN_LOG_FRAME = 0, /* a classic CAN data or remote frame: see frame */
    CAN_LOG_FD,        /* a CAN FD frame (not ours: the mast bus is classic CAN) */
    CAN_LOG_ERROR,     /* an error frame (CAN_ERR_FLAG in the id): bus errors, bus-off */
    CAN_LOG_SKIP,      /* blank line or comment ('#' first) */
    CAN_LOG_MALFORMED  /* see reason */
} can_log_kind_t;

typedef struct {
    can_log_kind_t kind;
    uint64_t sec;    /* timestamp seconds */
    uint32_t usec;   /* timestamp microseconds (fraction scaled to 6 digits) */
    char ifname[17]; /* interface name */
    trn_can_frame_t frame;
    const char *reason; /* static text when MALFORMED */
} can_log_line_t;

/* Parse one line (without or with its trailing newline). Always fills out. */
void can_log_parse(const char *line, can_log_line_t *out);

#endif
