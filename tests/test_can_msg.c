/* SPDX-License-Identifier: Apache-2.0 */
/* test_can_msg.c - CRC-32 (crc.h) and the mast / stereo-head CAN messages
 * (can_msg.h).
 *
 * Byte order is checked against hand-written byte vectors (little-endian on
 * the wire whatever the host), every message round-trips on seeded random
 * values, field limits encode exactly, and every decoder rejection class
 * (ID, extended, remote, DLC, reserved bits, enumeration) has an assertion.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "trn_port/can_msg.h"
#include "trn_port/crc.h"
#include "rng.h"

/* ---- CRC ------------------------------------------------------------------ */

/* Slow obvious reference: MSB-first over the polynomial with explicit
 * bit reflection of input and output. */
static uint32_t reflect(uint32_t v, int bits)
{
    uint32_t r = 0u;
    int i;
    for (i = 0; i < bits; ++i) {
        if (v & (1u << i)) {
            r |= 1u << (bits - 1 - i);
        }
    }
    return r;
}

static uint32_t crc_ref(const uint8_t *d, size_t n)
{
    uint32_t crc = 0xFFFFFFFFu;
    size_t i;
    int b;
    for (i = 0; i < n; ++i) {
        crc ^= reflect(d[i], 8) << 24;
        for (b = 0; b < 8; ++b) {
            crc = (crc & 0x80000000u) ? (crc << 1) ^ 0x04C11DB7u : (crc << 1);
        }
    }
    return reflect(crc, 32) ^ 0xFFFFFFFFu;
}

static void test_crc_check_value(void **state)
{
    (void)state;
    assert_int_equal(trn_crc32((const uint8_t *)"123456789", 9), 0xCBF43926u);
    assert_int_equal(trn_crc32(NULL, 0), 0x00000000u);
    /* NULL data leaves the running value alone */
    assert_int_equal(trn_crc32_update(0x12345678u, NULL, 5), 0x12345678u);
}

static void test_crc_vs_reference_and_incremental(void **state)
{
    uint8_t buf[300];
    trn_rng_t r;
    size_t n, cut;
    (void)state;
    trn_rng_seed(&r, 7);
    for (n = 0; n < sizeof buf; ++n) {
        buf[n] = (uint8_t)trn_rng_u64(&r);
    }
    for (n = 0; n <= sizeof buf; n += 13) {
        uint32_t whole = trn_crc32(buf, n);
        assert_int_equal(whole, crc_ref(buf, n));
        for (cut = 0; cut <= n; cut += 7) {
            uint32_t c = trn_crc32_update(TRN_CRC32_INIT, buf, cut);
            c = trn_crc32_update(c, buf + cut, n - cut);
            assert_int_equal(trn_crc32_final(c), whole);
        }
    }
}

/* ---- hand-written byte vectors ---------------------------------------------- */

static void test_mast_cmd_bytes(void **state)
{
    trn_mast_cmd_t m = {-2, 0x1234, 0xBEEF, 0x7F, TRN_MAST_MODE_MOVE};
    trn_can_frame_t f;
    const uint8_t want[8] = {0xFE, 0xFF, 0x34, 0x12, 0xEF, 0xBE, 0x7F, 0x01};
    (void)state;
    assert_int_equal(trn_can_mast_cmd_encode(&m, &f), TRN_OK);
    assert_int_equal(f.id, 0x120u);
    assert_int_equal(f.dlc, 8);
    assert_int_equal(f.flags, 0);
    assert_memory_equal(f.data, want, 8);
}

static void test_mast_status_bytes(void **state)
{
    trn_mast_status_t m = {-32768,
                           32767,
                           TRN_MAST_ST_MOVING | TRN_MAST_ST_TILT_LIM_MAX,
                           TRN_MAST_FLT_PAN_STALL | TRN_MAST_FLT_CMD_INVALID,
                           9,
                           250};
    trn_can_frame_t f;
    const uint8_t want[8] = {0x00, 0x80, 0xFF, 0x7F, 0x11, 0x21, 0x09, 0xFA};
    trn_mast_status_t back;
    (void)state;
    assert_int_equal(trn_can_mast_status_encode(&m, &f), TRN_OK);
    assert_int_equal(f.id, 0x121u);
    assert_memory_equal(f.data, want, 8);
    /* and the other way, from bytes alone */
    memset(&f, 0, sizeof f);
    f.id = 0x121u;
    f.dlc = 8;
    memcpy(f.data, want, 8);
    assert_int_equal(trn_can_mast_status_decode(&f, &back), TRN_OK);
    assert_int_equal(back.pan_100urad, -32768);
    assert_int_equal(back.tilt_100urad, 32767);
    assert_int_equal(back.state, 0x11);
    assert_int_equal(back.faults, 0x21);
    assert_int_equal(back.cmd_seq_ack, 9);
    assert_int_equal(back.counter, 250);
}

static void test_capture_cmd_and_heartbeat_bytes(void **state)
{
    trn_capture_cmd_t c = {0xA55A, 0x0102};
    trn_heartbeat_t h = {TRN_NODE_FAULT, 0x80, 0xFFFE};
    trn_can_frame_t f;
    const uint8_t want_c[4] = {0x5A, 0xA5, 0x02, 0x01};
    const uint8_t want_h[4] = {0x03, 0x80, 0xFE, 0xFF};
    (void)state;
    assert_int_equal(trn_can_capture_cmd_encode(&c, &f), TRN_OK);
    assert_int_equal(f.id, 0x130u);
    assert_int_equal(f.dlc, 4);
    assert_memory_equal(f.data, want_c, 4);
    assert_int_equal(trn_can_heartbeat_encode(TRN_CAN_ID_STEREO_HB, &h, &f), TRN_OK);
    assert_int_equal(f.id, 0x702u);
    assert_int_equal(f.dlc, 4);
    assert_memory_equal(f.data, want_h, 4);
}

/* ---- round trips on seeded values ------------------------------------------ */

static void test_round_trips(void **state)
{
    trn_rng_t r;
    int i;
    (void)state;
    trn_rng_seed(&r, 42);
    for (i = 0; i < 2000; ++i) {
        trn_can_frame_t f;
        trn_mast_cmd_t c = {(int16_t)trn_rng_int(&r, -32768, 32767),
                            (int16_t)trn_rng_int(&r, -32768, 32767),
                            (uint16_t)trn_rng_int(&r, 0, 65535), (uint8_t)trn_rng_int(&r, 0, 255),
                            (uint8_t)trn_rng_int(&r, 0, 2)};
        trn_mast_cmd_t c2;
        trn_mast_status_t s = {
            (int16_t)trn_rng_int(&r, -32768, 32767), (int16_t)trn_rng_int(&r, -32768, 32767),
            (uint8_t)trn_rng_int(&r, 0, 0x3F),       (uint8_t)trn_rng_int(&r, 0, 0x3F),
            (uint8_t)trn_rng_int(&r, 0, 255),        (uint8_t)trn_rng_int(&r, 0, 255)};
        trn_mast_status_t s2;
        trn_capture_cmd_t k = {(uint16_t)trn_rng_int(&r, 0, 65535),
                               (uint16_t)trn_rng_int(&r, 0, 65535)};
        trn_capture_cmd_t k2;
        trn_heartbeat_t h = {(uint8_t)trn_rng_int(&r, 0, 3), (uint8_t)trn_rng_int(&r, 0, 255),
                             (uint16_t)trn_rng_int(&r, 0, 65535)};
        trn_heartbeat_t h2;
        uint32_t hb_id = (i & 1) ? TRN_CAN_ID_MAST_HB : TRN_CAN_ID_STEREO_HB;

        assert_int_equal(trn_can_mast_cmd_encode(&c, &f), TRN_OK);
        assert_int_equal(trn_can_classify(&f), TRN_CAN_MSG_MAST_CMD);
        assert_int_equal(trn_can_mast_cmd_decode(&f, &c2), TRN_OK);
        assert_memory_equal(&c, &c2, sizeof c);

        assert_int_equal(trn_can_mast_status_encode(&s, &f), TRN_OK);
        assert_int_equal(trn_can_classify(&f), TRN_CAN_MSG_MAST_STATUS);
        assert_int_equal(trn_can_mast_status_decode(&f, &s2), TRN_OK);
        assert_memory_equal(&s, &s2, sizeof s);

        assert_int_equal(trn_can_capture_cmd_encode(&k, &f), TRN_OK);
        assert_int_equal(trn_can_classify(&f), TRN_CAN_MSG_CAPTURE_CMD);
        assert_int_equal(trn_can_capture_cmd_decode(&f, &k2), TRN_OK);
        assert_memory_equal(&k, &k2, sizeof k);

        assert_int_equal(trn_can_heartbeat_encode(hb_id, &h, &f), TRN_OK);
        assert_int_equal(trn_can_classify(&f),
                         (i & 1) ? TRN_CAN_MSG_MAST_HB : TRN_CAN_MSG_STEREO_HB);
        assert_int_equal(trn_can_heartbeat_decode(&f, &h2), TRN_OK);
        assert_memory_equal(&h, &h2, sizeof h);
    }
}

/* ---- angles ------------------------------------------------------------------- */

static void test_angle_conversion(void **state)
{
    int16_t raw = 0;
    int32_t v;
    (void)state;
    assert_int_equal(trn_can_angle_to_raw(0.00005f, &raw), TRN_OK); /* tie rounds away */
    assert_true(raw == 0 || raw == 1); /* 0.00005f is not exactly half a count */
    assert_int_equal(trn_can_angle_to_raw(1.0f, &raw), TRN_OK);
    assert_int_equal(raw, 10000);
    assert_int_equal(trn_can_angle_to_raw(-1.23456f, &raw), TRN_OK);
    assert_int_equal(raw, -12346);
    assert_int_equal(trn_can_angle_to_raw(3.2767f, &raw), TRN_OK);
    assert_int_equal(raw, 32767);
    assert_int_equal(trn_can_angle_to_raw(-3.2768f, &raw), TRN_OK);
    assert_int_equal(raw, -32768);
    assert_int_equal(trn_can_angle_to_raw(3.2768f, &raw), TRN_E_ARG);
    assert_int_equal(trn_can_angle_to_raw(-3.2770f, &raw), TRN_E_ARG);
    assert_int_equal(trn_can_angle_to_raw(-3.27685f, &raw), TRN_E_ARG); /* rounds to -32769 */
    assert_int_equal(trn_can_angle_to_raw(NAN, &raw), TRN_E_ARG);
    assert_int_equal(trn_can_angle_to_raw(INFINITY, &raw), TRN_E_ARG);
    assert_int_equal(trn_can_angle_to_raw(1.0f, NULL), TRN_E_NULL);
    /* every count survives raw -> rad -> raw */
    for (v = -32768; v <= 32767; ++v) {
        assert_int_equal(trn_can_angle_to_raw(trn_can_angle_from_raw((int16_t)v), &raw), TRN_OK);
        assert_int_equal(raw, v);
    }
    assert_true(fabsf(trn_can_angle_from_raw(-32768) + 3.2768f) < 1e-6f);
}

/* ---- rejections ---------------------------------------------------------------- */

static void test_decoders_reject(void **state)
{
    trn_can_frame_t f, g;
    trn_mast_cmd_t c = {1, 2, 3, 4, TRN_MAST_MODE_STOP};
    trn_mast_status_t s = {0, 0, 0, 0, 0, 0};
    trn_capture_cmd_t k = {1, 2};
    trn_heartbeat_t h = {TRN_NODE_READY, 1, 2};
    (void)state;

    assert_int_equal(trn_can_mast_cmd_encode(&c, &f), TRN_OK);
    g = f;
    g.dlc = 7;
    assert_int_equal(trn_can_mast_cmd_decode(&g, &c), TRN_E_FORMAT);
    g = f;
    g.flags = TRN_CAN_FLAG_EXT;
    assert_int_equal(trn_can_mast_cmd_decode(&g, &c), TRN_E_FORMAT);
    assert_int_equal(trn_can_classify(&g), TRN_CAN_MSG_NONE);
    g = f;
    g.flags = TRN_CAN_FLAG_RTR;
    assert_int_equal(trn_can_mast_cmd_decode(&g, &c), TRN_E_FORMAT);
    assert_int_equal(trn_can_classify(&g), TRN_CAN_MSG_NONE);
    g = f;
    g.id = 0x121u;
    assert_int_equal(trn_can_mast_cmd_decode(&g, &c), TRN_E_FORMAT);
    g = f;
    g.data[7] = 3;
    assert_int_equal(trn_can_mast_cmd_decode(&g, &c), TRN_E_FORMAT);
    assert_int_equal(trn_can_mast_cmd_decode(NULL, &c), TRN_E_NULL);
    assert_int_equal(trn_can_mast_cmd_decode(&f, NULL), TRN_E_NULL);
    c.mode = 3;
    assert_int_equal(trn_can_mast_cmd_encode(&c, &f), TRN_E_ARG);
    assert_int_equal(trn_can_mast_cmd_encode(NULL, &f), TRN_E_NULL);
    assert_int_equal(trn_can_mast_cmd_encode(&c, NULL), TRN_E_NULL);

    assert_int_equal(trn_can_mast_status_encode(&s, &f), TRN_OK);
    g = f;
    g.data[4] = 0x40;
    assert_int_equal(trn_can_mast_status_decode(&g, &s), TRN_E_FORMAT);
    g = f;
    g.data[5] = 0x80;
    assert_int_equal(trn_can_mast_status_decode(&g, &s), TRN_E_FORMAT);
    g = f;
    g.dlc = 6;
    assert_int_equal(trn_can_mast_status_decode(&g, &s), TRN_E_FORMAT);
    g = f;
    g.id = 0x120u;
    assert_int_equal(trn_can_mast_status_decode(&g, &s), TRN_E_FORMAT);
    assert_int_equal(trn_can_mast_status_decode(NULL, &s), TRN_E_NULL);
    assert_int_equal(trn_can_mast_status_decode(&f, NULL), TRN_E_NULL);
    s.state = 0x80;
    assert_int_equal(trn_can_mast_status_encode(&s, &f), TRN_E_ARG);
    s.state = 0;
    s.faults = 0x40;
    assert_int_equal(trn_can_mast_status_encode(&s, &f), TRN_E_ARG);
    assert_int_equal(trn_can_mast_status_encode(NULL, &f), TRN_E_NULL);
    assert_int_equal(trn_can_mast_status_encode(&s, NULL), TRN_E_NULL);

    assert_int_equal(trn_can_capture_cmd_encode(&k, &f), TRN_OK);
    g = f;
    g.dlc = 8;
    assert_int_equal(trn_can_capture_cmd_decode(&g, &k), TRN_E_FORMAT);
    g = f;
    g.id = 0x131u;
    assert_int_equal(trn_can_capture_cmd_decode(&g, &k), TRN_E_FORMAT);
    assert_int_equal(trn_can_capture_cmd_decode(NULL, &k), TRN_E_NULL);
    assert_int_equal(trn_can_capture_cmd_decode(&f, NULL), TRN_E_NULL);
    assert_int_equal(trn_can_capture_cmd_encode(NULL, &f), TRN_E_NULL);
    assert_int_equal(trn_can_capture_cmd_encode(&k, NULL), TRN_E_NULL);

    assert_int_equal(trn_can_heartbeat_encode(TRN_CAN_ID_MAST_HB, &h, &f), TRN_OK);
    g = f;
    g.data[0] = 4;
    assert_int_equal(trn_can_heartbeat_decode(&g, &h), TRN_E_FORMAT);
    g = f;
    g.dlc = 3;
    assert_int_equal(trn_can_heartbeat_decode(&g, &h), TRN_E_FORMAT);
    g = f;
    g.id = 0x700u;
    assert_int_equal(trn_can_heartbeat_decode(&g, &h), TRN_E_FORMAT);
    assert_int_equal(trn_can_heartbeat_decode(NULL, &h), TRN_E_NULL);
    assert_int_equal(trn_can_heartbeat_decode(&f, NULL), TRN_E_NULL);
    assert_int_equal(trn_can_heartbeat_encode(0x700u, &h, &f), TRN_E_ARG);
    h.state = 4;
    assert_int_equal(trn_can_heartbeat_encode(TRN_CAN_ID_MAST_HB, &h, &f), TRN_E_ARG);
    assert_int_equal(trn_can_heartbeat_encode(TRN_CAN_ID_MAST_HB, NULL, &f), TRN_E_NULL);
    assert_int_equal(trn_can_heartbeat_encode(TRN_CAN_ID_MAST_HB, &h, NULL), TRN_E_NULL);
}

static void test_decode_failure_leaves_output(void **state)
{
    trn_can_frame_t f;
    trn_mast_status_t s = {1, 2, 0, 0, 3, 4}, keep;
    (void)state;
    assert_int_equal(trn_can_mast_status_encode(&s, &f), TRN_OK);
    f.data[4] = 0xFF;
    memset(&keep, 0x5A, sizeof keep);
    s = keep;
    assert_int_equal(trn_can_mast_status_decode(&f, &s), TRN_E_FORMAT);
    assert_memory_equal(&s, &keep, sizeof s);
}

static void test_classify_names_counter(void **state)
{
    trn_can_frame_t f;
    (void)state;
    memset(&f, 0, sizeof f);
    assert_int_equal(trn_can_classify(NULL), TRN_CAN_MSG_NONE);
    f.id = 0x1A0u;
    assert_int_equal(trn_can_classify(&f), TRN_CAN_MSG_CAPTURE_DATA);
    f.id = 0x1A1u;
    assert_int_equal(trn_can_classify(&f), TRN_CAN_MSG_CAPTURE_FC);
    f.id = 0x123u;
    assert_int_equal(trn_can_classify(&f), TRN_CAN_MSG_NONE);
    assert_string_equal(trn_can_msg_name(TRN_CAN_MSG_MAST_STATUS), "MAST_STATUS");
    assert_string_equal(trn_can_msg_name(TRN_CAN_MSG_NONE), "NONE");
    {
        /* every kind has its own name */
        int a, b;
        for (a = TRN_CAN_MSG_MAST_CMD; a <= TRN_CAN_MSG_STEREO_HB; ++a) {
            assert_string_not_equal(trn_can_msg_name((trn_can_msg_kind_t)a), "NONE");
            for (b = a + 1; b <= TRN_CAN_MSG_STEREO_HB; ++b) {
                assert_string_not_equal(trn_can_msg_name((trn_can_msg_kind_t)a),
                                        trn_can_msg_name((trn_can_msg_kind_t)b));
            }
        }
    }
    assert_string_equal(trn_can_msg_name((trn_can_msg_kind_t)99), "NONE");
    assert_int_equal(trn_can_counter_gap(4, 5), 0);
    assert_int_equal(trn_can_counter_gap(255, 0), 0);
    assert_int_equal(trn_can_counter_gap(250, 3), 8);
    assert_int_equal(trn_can_counter_gap(7, 7), 255);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crc_check_value),
        cmocka_unit_test(test_crc_vs_reference_and_incremental),
        cmocka_unit_test(test_mast_cmd_bytes),
        cmocka_unit_test(test_mast_status_bytes),
        cmocka_unit_test(test_capture_cmd_and_heartbeat_bytes),
        cmocka_unit_test(test_round_trips),
        cmocka_unit_test(test_angle_conversion),
        cmocka_unit_test(test_decoders_reject),
        cmocka_unit_test(test_decode_failure_leaves_output),
        cmocka_unit_test(test_classify_names_counter),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
