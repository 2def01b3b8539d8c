/* SPDX-License-Identifier: Apache-2.0 */
/* fuzz_capture.c - capture reassembly of port/proto (capture.h): segments
 * from the input, fed to trn_capture_rx_segment; also trn_capture_decode on
 * the raw bytes.
 *
 * Two modes (first byte):
 *   raw         up to 64 segments of arbitrary bytes (length 0..4095);
 *   structured  a valid capture built from the input (0..300 points), split
 *               by trn_capture_segment with a fuzzed segment size, then
 *               played through up to 64 edits (deliver, skip, repeat, an
 *               earlier one, flip a byte, cut short, another capture id,
 *               transport abort) and the rest in order.
 * Invariants, after every call:
 * - status only OK, FORMAT, SEQ, CAPACITY, CRC, and it is the status of the
 *   named error (NONE exactly when OK, RESTARTED counted but the new capture
 *   kept);
 * - nothing partial is ever delivered: when complete is 0 the output capture
 *   is byte-for-byte untouched; when complete is 1, re-encoding it gives
 *   TRN_CAP_WIRE_BYTES(n_points) bytes whose CRC-32 is the CRC delivered,
 *   equal to the concatenation of the payloads the reassembler accepted for
 *   that capture (a shadow copy kept here);
 * - n_complete counts the completes; got equals the shadow length;
 * - structured mode without edits: exactly the capture built is delivered.
 */
#include <stdlib.h>
#include <string.h>

#include "fuzz_input.h"
#include "trn_port/capture.h"
#include "trn_port/crc.h"

#define FZ_CHECK(c) \
    do { \
        if (!(c)) { \
            abort(); \
        } \
    } while (0)
#define MAX_SEGS 64

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static trn_capture_rx_t rx;
static trn_capture_t out, sentinel, built;
static uint8_t shadow[TRN_CAP_WIRE_MAX];
static size_t shadow_len;
static uint8_t wire[TRN_CAP_WIRE_MAX], re[TRN_CAP_WIRE_MAX];
static uint8_t seg[TRN_ISOTP_MAX_MSG];
static uint32_t completes;

static trn_status_t status_of(trn_cap_err_t e)
{
    switch (e) {
    case TRN_CAP_ERR_NONE: return TRN_OK;
    case TRN_CAP_ERR_MISSING:
    case TRN_CAP_ERR_DUPLICATE:
    case TRN_CAP_ERR_OUT_OF_ORDER:
    case TRN_CAP_ERR_RESTARTED: return TRN_E_SEQ;
    case TRN_CAP_ERR_TOO_MANY_POINTS: return TRN_E_CAPACITY;
    case TRN_CAP_ERR_CRC: return TRN_E_CRC;
    default: return TRN_E_FORMAT;
    }
}

/* Feed one segment and check everything; returns complete. */
static int feed(const uint8_t *s, size_t len)
{
    trn_cap_err_t e = TRN_CAP_ERR_COUNT;
    int complete = -1;
    trn_status_t st;
    int accepted;

    memcpy(&out, &sentinel, sizeof out);
    st = trn_capture_rx_segment(&rx, s, len, &out, &complete, &e);
    FZ_CHECK(st == TRN_OK || st == TRN_E_FORMAT || st == TRN_E_SEQ || st == TRN_E_CAPACITY ||
             st == TRN_E_CRC);
    FZ_CHECK((int)e >= 0 && e < TRN_CAP_ERR_COUNT && e != TRN_CAP_ERR_TRANSPORT);
    FZ_CHECK(st == status_of(e));
    FZ_CHECK(complete == 0 || complete == 1);
    FZ_CHECK(trn_cap_err_name(e) != NULL);
    accepted = (st == TRN_OK || e == TRN_CAP_ERR_RESTARTED);
    if (complete == 0) {
        FZ_CHECK(memcmp(&out, &sentinel, sizeof out) == 0);
    }
    if (accepted) {
        size_t plen = len - TRN_CAP_SEG_HEADER_BYTES;
        if (s[2] == 0u) {
            shadow_len = 0u;
        }
        FZ_CHECK(shadow_len + plen <= TRN_CAP_WIRE_MAX);
        memcpy(&shadow[shadow_len], &s[TRN_CAP_SEG_HEADER_BYTES], plen);
        shadow_len += plen;
    } else {
        FZ_CHECK(complete == 0 && rx.active == 0u && rx.got == 0u);
        shadow_len = 0u;
    }
    if (complete == 1) {
        size_t n = 0u;
        FZ_CHECK(accepted);
        FZ_CHECK(out.n_points <= TRN_PORT_MAX_CAPTURE_POINTS);
        FZ_CHECK(trn_capture_encode(&out, re, sizeof re, &n) == TRN_OK);
        FZ_CHECK(n == TRN_CAP_WIRE_BYTES(out.n_points) && n == shadow_len);
        FZ_CHECK(trn_crc32(re, n - TRN_CAP_CRC_BYTES) == out.crc);
        FZ_CHECK(memcmp(re, shadow, n) == 0);
        ++completes;
        shadow_len = 0u;
        FZ_CHECK(rx.active == 0u);
    } else if (accepted) {
        FZ_CHECK(rx.active == 1u && rx.got == shadow_len);
    }
    FZ_CHECK(rx.n_complete == completes);
    return complete;
}

static void raw_mode(fz_t *in)
{
    int k;
    for (k = 0; k < MAX_SEGS && in->n > 0u; ++k) {
        size_t len = (size_t)((uint16_t)(fz_u8(in) | (fz_u8(in) << 8)) % (TRN_ISOTP_MAX_MSG + 1u));
        trn_capture_t d;
        trn_cap_err_t e;
        trn_status_t st;
        if (len > in->n + TRN_CAP_SEG_HEADER_BYTES + 64u) {
            len = in->n + TRN_CAP_SEG_HEADER_BYTES + 64u; /* short inputs: mostly short segments */
        }
        fz_bytes(in, seg, len);
        (void)feed(seg, len);
        /* the same bytes as a whole capture */
        if (len > TRN_CAP_SEG_HEADER_BYTES) {
            st = trn_capture_decode(&seg[TRN_CAP_SEG_HEADER_BYTES], len - TRN_CAP_SEG_HEADER_BYTES,
                                    &d, &e);
            FZ_CHECK(st == status_of(e));
            if (st == TRN_OK) {
                FZ_CHECK(len - TRN_CAP_SEG_HEADER_BYTES == TRN_CAP_WIRE_BYTES(d.n_points));
            }
        }
        if ((k & 15) == 15 && (fz_u8(in) & 1u) != 0u) {
            FZ_CHECK(trn_capture_rx_abort(&rx) == TRN_OK && rx.active == 0u);
            shadow_len = 0u;
        }
    }
}

static void structured_mode(fz_t *in)
{
    size_t wlen = 0u, seg_payload, slen;
    uint8_t count = 0u, next = 0u;
    int k, edited = 0, got_it = 0;
    uint16_t i;

    memset(&built, 0, sizeof built);
    built.capture_id = (uint16_t)(fz_u8(in) | (fz_u8(in) << 8));
    built.time_ms = (uint32_t)fz_i32(in);
    built.pan_100urad = (int16_t)(fz_u8(in) | (fz_u8(in) << 8));
    built.tilt_100urad = (int16_t)(fz_u8(in) | (fz_u8(in) << 8));
    built.mast_state = fz_u8(in);
    built.mast_faults = fz_u8(in);
    built.n_points = (uint16_t)((fz_u8(in) | (fz_u8(in) << 8)) % 301u);
    for (i = 0; i < built.n_points; ++i) {
        built.points[i].x_mm = (int16_t)(i * 7);
        built.points[i].y_mm = (int16_t)(fz_u8(in) - 128);
        built.points[i].z_mm = (int16_t)(1000 + i);
    }
    FZ_CHECK(trn_capture_encode(&built, wire, sizeof wire, &wlen) == TRN_OK);
    FZ_CHECK(wlen == TRN_CAP_WIRE_BYTES(built.n_points));
    seg_payload = 1u + (size_t)((uint16_t)(fz_u8(in) | (fz_u8(in) << 8)) % TRN_CAP_SEG_PAYLOAD_MAX);
    if (trn_capture_segment_count(wlen, seg_payload, &count) == TRN_E_SIZE) {
        seg_payload = (wlen + 254u) / 255u;
    }
    FZ_CHECK(trn_capture_segment_count(wlen, seg_payload, &count) == TRN_OK && count >= 1u);

    for (k = 0; k < MAX_SEGS && in->n > 0u && next < count; ++k) {
        uint8_t op = fz_u8(in), which = next;
        FZ_CHECK(trn_capture_segment(wire, wlen, seg_payload, which, seg, sizeof seg, &slen) ==
                 TRN_OK);
        switch (op & 7u) {
        case 0: /* in order */
            got_it |= feed(seg, slen);
            ++next;
            break;
        case 1: /* lost */
            ++next;
            edited = 1;
            break;
        case 2: /* the previous one again */
            if (next > 0u) {
                FZ_CHECK(trn_capture_segment(wire, wlen, seg_payload, (uint8_t)(next - 1u), seg,
                                             sizeof seg, &slen) == TRN_OK);
            }
            got_it |= feed(seg, slen);
            edited = 1;
            break;
        case 3: /* an earlier one */
            which = (uint8_t)(fz_u8(in) % (next + 1u));
            FZ_CHECK(trn_capture_segment(wire, wlen, seg_payload, which, seg, sizeof seg, &slen) ==
                     TRN_OK);
            got_it |= feed(seg, slen);
            edited = 1;
            break;
        case 4: { /* one byte flipped (header, payload or CRC) */
            size_t at = (size_t)((uint16_t)(fz_u8(in) | (fz_u8(in) << 8))) % slen;
            uint8_t x = fz_u8(in);
            seg[at] ^= (x == 0u) ? 1u : x;
            got_it |= feed(seg, slen);
            ++next;
            edited = 1;
            break;
        }
        case 5: /* cut short */
            slen = (size_t)fz_u8(in) % slen;
            got_it |= feed(seg, slen);
            ++next;
            edited = 1;
            break;
        case 6: /* another capture's id in the segment header */
            seg[0] ^= 0x5Au;
            got_it |= feed(seg, slen);
            ++next;
            edited = 1;
            break;
        default: /* transport abort */
            FZ_CHECK(trn_capture_rx_abort(&rx) == TRN_OK && rx.active == 0u);
            shadow_len = 0u;
            edited = 1;
            break;
        }
    }
    while (next < count) {
        FZ_CHECK(trn_capture_segment(wire, wlen, seg_payload, next, seg, sizeof seg, &slen) ==
                 TRN_OK);
        got_it |= feed(seg, slen);
        ++next;
    }
    if (!edited) {
        FZ_CHECK(got_it == 1);
        FZ_CHECK(
            out.capture_id == built.capture_id && out.time_ms == built.time_ms &&
            out.n_points == built.n_points &&
            memcmp(out.points, built.points, (size_t)built.n_points * sizeof built.points[0]) == 0);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_t in = {data, size};
    uint8_t mode = fz_u8(&in);

    memset(&sentinel, 0xA5, sizeof sentinel);
    FZ_CHECK(trn_capture_rx_init(&rx) == TRN_OK);
    shadow_len = 0u;
    completes = 0u;
    if ((mode & 1u) == 0u) {
        raw_mode(&in);
    } else {
        structured_mode(&in);
    }
    return 0;
}
