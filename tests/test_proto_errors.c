/* SPDX-License-Identifier: Apache-2.0 */
/* test_proto_errors.c - the statuses and branches of port/proto the
 * functional tests (test_capture.c, test_isotp.c, test_can_msg.c) leave
 * out, one assertion per error path (docs/assurance.md, "Coverage"):
 * capture header errors seen by trn_capture_decode, a CRC error at the end
 * of a reassembly, a segment longer than the largest capture, too many
 * segments; ISO-TP padding on the last consecutive frame, a reserved STmin,
 * a single frame, a flow control and a first frame arriving after N_Cr
 * expired; the angle
 * limits of the CAN encoding. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "trn_port/can_msg.h"
#include "trn_port/capture.h"
#include "trn_port/crc.h"
#include "trn_port/isotp.h"

static trn_capture_t g_cap, g_out;
static trn_capture_rx_t g_rx;
static uint8_t g_wire[TRN_CAP_WIRE_MAX + 64];
static uint8_t g_seg[TRN_CAP_WIRE_MAX + 64];

static size_t small_capture(uint16_t n)
{
    size_t len = 0u;
    uint16_t i;
    memset(&g_cap, 0, sizeof g_cap);
    g_cap.capture_id = 77u;
    g_cap.time_ms = 1234u;
    g_cap.n_points = n;
    for (i = 0; i < n; ++i) {
        g_cap.points[i].x_mm = (int16_t)i;
        g_cap.points[i].y_mm = (int16_t)-i;
        g_cap.points[i].z_mm = (int16_t)(1000 + i);
    }
    assert_int_equal(trn_capture_encode(&g_cap, g_wire, sizeof g_wire, &len), TRN_OK);
    return len;
}

static void test_capture_decode_header_errors(void **state)
{
    size_t len = small_capture(5);
    trn_cap_err_t e = TRN_CAP_ERR_NONE;
    uint32_t crc;
    (void)state;
    assert_int_equal(trn_capture_decode(g_wire, len, &g_out, &e), TRN_OK);
    g_wire[0] = 2u; /* unknown version */
    assert_int_equal(trn_capture_decode(g_wire, len, &g_out, &e), TRN_E_FORMAT);
    assert_int_equal(e, TRN_CAP_ERR_VERSION);
    g_wire[0] = (uint8_t)TRN_CAP_VERSION;
    g_wire[1] = 0x01u; /* reserved flags */
    assert_int_equal(trn_capture_decode(g_wire, len, &g_out, &e), TRN_E_FORMAT);
    assert_int_equal(e, TRN_CAP_ERR_VERSION);
    g_wire[1] = 0u;
    /* more points than this build takes: capacity, before any length check */
    g_wire[14] = (uint8_t)((TRN_PORT_MAX_CAPTURE_POINTS + 1) & 0xFF);
    g_wire[15] = (uint8_t)((TRN_PORT_MAX_CAPTURE_POINTS + 1) >> 8);
    assert_int_equal(trn_capture_decode(g_wire, len, &g_out, &e), TRN_E_CAPACITY);
    assert_int_equal(e, TRN_CAP_ERR_TOO_MANY_POINTS);
    len = small_capture(5);
    g_wire[20] ^= 0x10u; /* a point byte */
    assert_int_equal(trn_capture_decode(g_wire, len, &g_out, &e), TRN_E_CRC);
    assert_int_equal(e, TRN_CAP_ERR_CRC);
    /* a correct CRC over the damaged bytes decodes (the CRC is all that guards them) */
    crc = trn_crc32(g_wire, len - 4u);
    g_wire[len - 4u] = (uint8_t)(crc & 0xFFu);
    g_wire[len - 3u] = (uint8_t)((crc >> 8) & 0xFFu);
    g_wire[len - 2u] = (uint8_t)((crc >> 16) & 0xFFu);
    g_wire[len - 1u] = (uint8_t)(crc >> 24);
    assert_int_equal(trn_capture_decode(g_wire, len, &g_out, NULL), TRN_OK);
}

static void test_capture_segment_too_many(void **state)
{
    uint8_t count = 0u, out[16];
    size_t n = 0u, len = small_capture(60); /* 380 bytes */
    (void)state;
    assert_true(len > 255u);
    assert_int_equal(trn_capture_segment_count(len, 1u, &count), TRN_E_SIZE);
    assert_int_equal(trn_capture_segment(g_wire, len, 1u, 0u, out, sizeof out, &n), TRN_E_SIZE);
    assert_int_equal(trn_capture_segment(g_wire, len, 2u, 0u, out, sizeof out, &n), TRN_OK);
    assert_int_equal((int)n, 6);
}

static void test_capture_rx_crc_error_at_the_end(void **state)
{
    size_t len = small_capture(20), slen = 0u;
    trn_cap_err_t e = TRN_CAP_ERR_NONE;
    uint8_t seg[TRN_ISOTP_MAX_MSG];
    int complete = -1;
    (void)state;
    g_wire[len - 1u] ^= 0x80u; /* the CRC itself */
    assert_int_equal(trn_capture_rx_init(&g_rx), TRN_OK);
    assert_int_equal(trn_capture_segment(g_wire, len, 100u, 0u, seg, sizeof seg, &slen), TRN_OK);
    assert_int_equal(trn_capture_rx_segment(&g_rx, seg, slen, &g_out, &complete, &e), TRN_OK);
    assert_int_equal(trn_capture_segment(g_wire, len, 100u, 1u, seg, sizeof seg, &slen), TRN_OK);
    assert_int_equal(trn_capture_rx_segment(&g_rx, seg, slen, &g_out, &complete, &e), TRN_E_CRC);
    assert_int_equal(e, TRN_CAP_ERR_CRC);
    assert_int_equal(complete, 0);
    assert_int_equal(g_rx.err_count[TRN_CAP_ERR_CRC], 1u);
    assert_int_equal(g_rx.n_complete, 0u);
}

/* One segment longer than the largest capture, whose header announces the
 * largest capture: the bytes that do not fit make it an overflow, not a
 * silently cut capture. */
static void test_capture_rx_segment_longer_than_any_capture(void **state)
{
    const size_t plen = TRN_CAP_WIRE_MAX + 1u;
    trn_cap_err_t e = TRN_CAP_ERR_NONE;
    int complete = -1;
    (void)state;
    memset(g_seg, 0, sizeof g_seg);
    g_seg[0] = 5u; /* segment: capture 5, index 0 of 1 */
    g_seg[2] = 0u;
    g_seg[3] = 1u;
    g_seg[4] = (uint8_t)TRN_CAP_VERSION; /* capture header: id 5, n = the maximum */
    g_seg[6] = 5u;
    g_seg[4 + 14] = (uint8_t)(TRN_PORT_MAX_CAPTURE_POINTS & 0xFF);
    g_seg[4 + 15] = (uint8_t)(TRN_PORT_MAX_CAPTURE_POINTS >> 8);
    assert_int_equal(trn_capture_rx_init(&g_rx), TRN_OK);
    assert_int_equal(trn_capture_rx_segment(&g_rx, g_seg, TRN_CAP_SEG_HEADER_BYTES + plen, &g_out,
                                            &complete, &e),
                     TRN_E_FORMAT);
    assert_int_equal(e, TRN_CAP_ERR_OVERFLOW);
    assert_int_equal(complete, 0);
    assert_int_equal(g_rx.active, 0u);
    assert_int_equal(g_rx.got, 0u);
}

static void test_isotp_reserved_stmin(void **state)
{
    trn_isotp_rx_t rx;
    uint8_t buf[64];
    (void)state;
    assert_int_equal(trn_isotp_rx_init(&rx, buf, sizeof buf, 0u, 0xF9u, 100u), TRN_OK);
    assert_int_equal(trn_isotp_rx_init(&rx, buf, sizeof buf, 0u, 0xFAu, 100u), TRN_E_ARG);
    assert_int_equal(trn_isotp_rx_init(&rx, buf, sizeof buf, 0u, 0xF0u, 100u), TRN_E_ARG);
    assert_int_equal(trn_isotp_rx_init(&rx, buf, sizeof buf, 0u, 0x80u, 100u), TRN_E_ARG);
}

/* A sender that pads every frame to 8 bytes: the last consecutive frame
 * carries more bytes than the message has left; only those are taken. */
static void test_isotp_padded_last_cf(void **state)
{
    trn_isotp_rx_t rx;
    trn_isotp_rx_result_t res;
    uint8_t buf[64];
    const uint8_t ff[8] = {0x10, 10, 1, 2, 3, 4, 5, 6};
    const uint8_t cf[8] = {0x21, 7, 8, 9, 10, 0xCC, 0xCC, 0xCC};
    const uint8_t want[10] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
    (void)state;
    assert_int_equal(trn_isotp_rx_init(&rx, buf, sizeof buf, 0u, 0u, 100u), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&rx, ff, 8u, 0u, &res), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&rx, cf, 8u, 1u, &res), TRN_OK);
    assert_true((res.events & TRN_ISOTP_EV_MESSAGE) != 0u);
    assert_int_equal(res.msg_len, 10);
    assert_memory_equal(buf, want, sizeof want);
    assert_int_equal(rx.got, 10);
}

/* N_Cr runs out during a reception; the next frame is a single frame or a
 * flow control: the timeout is reported (TRN_E_TIMEOUT wins), the frame is
 * then handled from idle. */
static void test_isotp_frames_after_timeout(void **state)
{
    trn_isotp_rx_t rx;
    trn_isotp_rx_result_t res;
    uint8_t buf[64];
    const uint8_t ff[8] = {0x10, 20, 1, 2, 3, 4, 5, 6};
    const uint8_t sf[4] = {0x03, 7, 8, 9};
    const uint8_t fc[3] = {0x30, 0, 0};
    (void)state;
    assert_int_equal(trn_isotp_rx_init(&rx, buf, sizeof buf, 0u, 0u, 50u), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&rx, ff, 8u, 1000u, &res), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&rx, sf, 4u, 1051u, &res), TRN_E_TIMEOUT);
    assert_true((res.events & TRN_ISOTP_EV_MESSAGE) != 0u);
    assert_int_equal(res.msg_len, 3);
    assert_int_equal(buf[0], 7);
    assert_int_equal(rx.err_count[TRN_ISOTP_ERR_TIMEOUT_CR], 1u);
    assert_int_equal(rx.err_count[TRN_ISOTP_ERR_INTERRUPTED], 0u);
    assert_int_equal(trn_isotp_rx_frame(&rx, ff, 8u, 2000u, &res), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&rx, fc, 3u, 2051u, &res), TRN_E_TIMEOUT);
    assert_int_equal(rx.err_count[TRN_ISOTP_ERR_TIMEOUT_CR], 2u);
    assert_int_equal(rx.err_count[TRN_ISOTP_ERR_UNEXPECTED_FC], 1u);
    assert_int_equal(rx.state, TRN_ISOTP_RX_IDLE);
    /* a first frame after the timeout starts the new message at once */
    assert_int_equal(trn_isotp_rx_frame(&rx, ff, 8u, 3000u, &res), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&rx, ff, 8u, 3051u, &res), TRN_E_TIMEOUT);
    assert_true((res.events & TRN_ISOTP_EV_SEND_FC) != 0u);
    assert_int_equal(rx.state, TRN_ISOTP_RX_RECEIVING);
    assert_int_equal(rx.got, 6);
    assert_int_equal(rx.err_count[TRN_ISOTP_ERR_TIMEOUT_CR], 3u);
}

static void test_can_angle_limits(void **state)
{
    int16_t raw = 0;
    (void)state;
    assert_int_equal(trn_can_angle_to_raw(-3.2768f, &raw), TRN_OK);
    assert_int_equal(raw, -32768);
    assert_int_equal(trn_can_angle_to_raw(3.2767f, &raw), TRN_OK);
    assert_int_equal(raw, 32767);
    assert_int_equal(trn_can_angle_to_raw(-3.27685f, &raw), TRN_E_ARG); /* rounds to -32769 */
    assert_int_equal(trn_can_angle_to_raw(3.27675f, &raw), TRN_E_ARG);  /* rounds to 32768 */
    assert_int_equal(raw, 32767);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_capture_decode_header_errors),
        cmocka_unit_test(test_capture_segment_too_many),
        cmocka_unit_test(test_capture_rx_crc_error_at_the_end),
        cmocka_unit_test(test_capture_rx_segment_longer_than_any_capture),
        cmocka_unit_test(test_isotp_reserved_stmin),
        cmocka_unit_test(test_isotp_padded_last_cf),
        cmocka_unit_test(test_isotp_frames_after_timeout),
        cmocka_unit_test(test_can_angle_limits),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
