/* SPDX-License-Identifier: Apache-2.0 */
/* fuzz_can_msg.c - every CAN message decoder of port/proto (can_msg.h) on
 * arbitrary frames, the angle conversion on arbitrary floats, the counter gap.
 *
 * Input: a frame (id u32, dlc u8, flags u8, 8 data bytes), then a float.
 * Invariants:
 * - every decoder returns only TRN_OK, TRN_E_FORMAT (or TRN_E_NULL for a
 *   NULL argument, checked once per run);
 * - a decoder's TRN_OK needs a standard data frame (flags 0) with that
 *   message's ID and DLC, and trn_can_classify names that message;
 * - out is untouched unless TRN_OK (filled with a pattern before);
 * - decode then encode gives back the same ID, DLC, flags and the DLC bytes
 *   (the messages have no don't-care bits: reserved bits are rejected);
 * - trn_can_msg_name is never NULL for any kind value;
 * - trn_can_angle_to_raw: TRN_OK only for a finite angle, and then the
 *   counts are within half a count (plus float rounding) of rad * 1e4.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_input.h"
#include "trn_port/can_msg.h"

#define FZ_CHECK(c) \
    do { \
        if (!(c)) { \
            abort(); \
        } \
    } while (0)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The frame an encoder produced equals the decoded one on id, dlc, flags, bytes. */
static void same_frame(const trn_can_frame_t *a, const trn_can_frame_t *b)
{
    FZ_CHECK(a->id == b->id && a->dlc == b->dlc && a->flags == b->flags);
    FZ_CHECK(memcmp(a->data, b->data, a->dlc) == 0);
}

static int std_data(const trn_can_frame_t *f, uint32_t id, uint8_t dlc)
{
    return f->id == id && f->dlc == dlc && f->flags == 0u;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_t in = {data, size};
    trn_can_frame_t f, g;
    trn_can_msg_kind_t kind;
    trn_status_t st;
    int16_t raw = 0x5A5A;
    float rad;
    uint8_t sel;
    int ok_count = 0;

    memset(&f, 0, sizeof f);
    sel = fz_u8(&in);
    /* mostly one of our IDs, so the decoders get past the ID check */
    switch (sel & 7u) {
    case 0: f.id = TRN_CAN_ID_MAST_CMD; break;
    case 1: f.id = TRN_CAN_ID_MAST_STATUS; break;
    case 2: f.id = TRN_CAN_ID_CAPTURE_CMD; break;
    case 3: f.id = TRN_CAN_ID_MAST_HB; break;
    case 4: f.id = TRN_CAN_ID_STEREO_HB; break;
    case 5: f.id = TRN_CAN_ID_CAPTURE_DATA + (sel >> 7); break;
    default: f.id = (uint32_t)fz_i32(&in); break;
    }
    f.dlc = fz_u8(&in);
    if ((sel & 0x08u) == 0u) {
        f.dlc = (uint8_t)(f.dlc % 9u);
    }
    f.flags = ((sel & 0x30u) == 0x30u) ? fz_u8(&in) : 0u;
    fz_bytes(&in, f.data, sizeof f.data);
    rad = fz_f32(&in);

    kind = trn_can_classify(&f);
    FZ_CHECK((int)kind >= (int)TRN_CAN_MSG_NONE && (int)kind <= (int)TRN_CAN_MSG_STEREO_HB);
    FZ_CHECK(trn_can_msg_name(kind) != NULL);
    FZ_CHECK(trn_can_msg_name((trn_can_msg_kind_t)sel) != NULL);
    if ((f.flags & (TRN_CAN_FLAG_EXT | TRN_CAN_FLAG_RTR)) != 0u) {
        FZ_CHECK(kind == TRN_CAN_MSG_NONE);
    }

    {
        trn_mast_cmd_t m;
        memset(&m, 0xA5, sizeof m);
        st = trn_can_mast_cmd_decode(&f, &m);
        FZ_CHECK(st == TRN_OK || st == TRN_E_FORMAT);
        if (st == TRN_OK) {
            ++ok_count;
            FZ_CHECK(std_data(&f, TRN_CAN_ID_MAST_CMD, TRN_CAN_DLC_MAST_CMD));
            FZ_CHECK(kind == TRN_CAN_MSG_MAST_CMD && m.mode <= (uint8_t)TRN_MAST_MODE_STOP);
            FZ_CHECK(trn_can_mast_cmd_encode(&m, &g) == TRN_OK);
            same_frame(&f, &g);
        } else {
            trn_mast_cmd_t z;
            memset(&z, 0xA5, sizeof z);
            FZ_CHECK(memcmp(&m, &z, sizeof m) == 0);
        }
    }
    {
        trn_mast_status_t m;
        memset(&m, 0xA5, sizeof m);
        st = trn_can_mast_status_decode(&f, &m);
        FZ_CHECK(st == TRN_OK || st == TRN_E_FORMAT);
        if (st == TRN_OK) {
            ++ok_count;
            FZ_CHECK(std_data(&f, TRN_CAN_ID_MAST_STATUS, TRN_CAN_DLC_MAST_STATUS));
            FZ_CHECK(kind == TRN_CAN_MSG_MAST_STATUS);
            FZ_CHECK((m.state & TRN_MAST_ST_RESERVED) == 0u &&
                     (m.faults & TRN_MAST_FLT_RESERVED) == 0u);
            FZ_CHECK(trn_can_mast_status_encode(&m, &g) == TRN_OK);
            same_frame(&f, &g);
        } else {
            trn_mast_status_t z;
            memset(&z, 0xA5, sizeof z);
            FZ_CHECK(memcmp(&m, &z, sizeof m) == 0);
        }
    }
    {
        trn_capture_cmd_t m;
        memset(&m, 0xA5, sizeof m);
        st = trn_can_capture_cmd_decode(&f, &m);
        FZ_CHECK(st == TRN_OK || st == TRN_E_FORMAT);
        if (st == TRN_OK) {
            ++ok_count;
            FZ_CHECK(std_data(&f, TRN_CAN_ID_CAPTURE_CMD, TRN_CAN_DLC_CAPTURE_CMD));
            FZ_CHECK(kind == TRN_CAN_MSG_CAPTURE_CMD);
            FZ_CHECK(trn_can_capture_cmd_encode(&m, &g) == TRN_OK);
            same_frame(&f, &g);
        } else {
            trn_capture_cmd_t z;
            memset(&z, 0xA5, sizeof z);
            FZ_CHECK(memcmp(&m, &z, sizeof m) == 0);
        }
    }
    {
        trn_heartbeat_t m;
        memset(&m, 0xA5, sizeof m);
        st = trn_can_heartbeat_decode(&f, &m);
        FZ_CHECK(st == TRN_OK || st == TRN_E_FORMAT);
        if (st == TRN_OK) {
            ++ok_count;
            FZ_CHECK(std_data(&f, TRN_CAN_ID_MAST_HB, TRN_CAN_DLC_HEARTBEAT) ||
                     std_data(&f, TRN_CAN_ID_STEREO_HB, TRN_CAN_DLC_HEARTBEAT));
            FZ_CHECK(kind == TRN_CAN_MSG_MAST_HB || kind == TRN_CAN_MSG_STEREO_HB);
            FZ_CHECK(m.state <= (uint8_t)TRN_NODE_FAULT);
            FZ_CHECK(trn_can_heartbeat_encode(f.id, &m, &g) == TRN_OK);
            same_frame(&f, &g);
        } else {
            trn_heartbeat_t z;
            memset(&z, 0xA5, sizeof z);
            FZ_CHECK(memcmp(&m, &z, sizeof m) == 0);
        }
    }
    /* one frame is at most one message */
    FZ_CHECK(ok_count <= 1);

    /* the gap of a counter pair: (now - prev - 1) mod 256 */
    FZ_CHECK(trn_can_counter_gap(f.data[0], f.data[1]) ==
             (uint8_t)((unsigned)f.data[1] + 255u - f.data[0]));

    st = trn_can_angle_to_raw(rad, &raw);
    FZ_CHECK(st == TRN_OK || st == TRN_E_ARG);
    if (st == TRN_OK) {
        double want = (double)rad * 1.0e4, back;
        FZ_CHECK(isfinite(rad));
        /* rad * 1e4 is rounded to float once before the rounding to counts */
        FZ_CHECK(fabs((double)raw - want) <= 0.5 + fabs(want) * 1.2e-7);
        back = (double)trn_can_angle_from_raw(raw);
        /* raw / 10000 with both exact in float: one correct rounding, half an ulp */
        FZ_CHECK(fabs(back - (double)raw * 1.0e-4) <= fabs((double)raw * 1.0e-4) * 0x1p-24);
    } else {
        FZ_CHECK(raw == 0x5A5A);
    }
    return 0;
}
