/* SPDX-License-Identifier: Apache-2.0 */
/* test_capture.c - stereo capture bytes, segments and reassembly (capture.h).
 *
 * The byte layout is checked against a hand-written vector; captures of
 * seeded random points round-trip through segments of several sizes; every
 * rejection class (missing, duplicate, out-of-order, restarted, bad CRC, too
 * many points, truncated, wrong length, version, id, segment count, short
 * segment, transport abort) returns its named error and counter, and the
 * caller's capture is never touched by a failed or partial transfer.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "trn/mast.h"
#include "trn_port/can_msg.h"
#include "trn_port/capture.h"
#include "trn_port/crc.h"
#include "rng.h"
#include "synth.h"

static trn_capture_t g_cap, g_out, g_sentinel;
static trn_capture_rx_t g_rx;
static uint8_t g_wire[2 * TRN_CAP_WIRE_MAX + 64];
static uint8_t g_segs[255][TRN_ISOTP_MAX_MSG];
static size_t g_seg_len[255];

/* Tests written for the default maximum skip themselves when a build sets
 * a smaller TRN_PORT_MAX_CAPTURE_POINTS. */
#define NEED_POINTS(n) \
    do { \
        if ((long)TRN_PORT_MAX_CAPTURE_POINTS < (long)(n)) { \
            print_message("skipped: needs TRN_PORT_MAX_CAPTURE_POINTS >= %d\n", (int)(n)); \
            skip(); \
        } \
    } while (0)

static void make_capture(trn_capture_t *c, uint16_t n, uint64_t seed)
{
    trn_rng_t r;
    uint16_t i;
    trn_rng_seed(&r, seed);
    memset(c, 0, sizeof *c);
    c->capture_id = (uint16_t)trn_rng_int(&r, 0, 65535);
    c->time_ms = (uint32_t)trn_rng_u64(&r);
    c->pan_100urad = (int16_t)trn_rng_int(&r, -32768, 32767);
    c->tilt_100urad = (int16_t)trn_rng_int(&r, -32768, 32767);
    c->mast_state = (uint8_t)trn_rng_int(&r, 0, 0x3F);
    c->mast_faults = (uint8_t)trn_rng_int(&r, 0, 0x3F);
    c->n_points = n;
    for (i = 0; i < n; ++i) {
        c->points[i].x_mm = (int16_t)trn_rng_int(&r, -32768, 32767);
        c->points[i].y_mm = (int16_t)trn_rng_int(&r, -32768, 32767);
        c->points[i].z_mm = (int16_t)trn_rng_int(&r, -32768, 32767);
    }
}

/* Split wire[0..len) into segments; returns their number. */
static uint8_t split(const uint8_t *wire, size_t len, size_t payload)
{
    uint8_t n = 0, i;
    assert_int_equal(trn_capture_segment_count(len, payload, &n), TRN_OK);
    for (i = 0; i < n; ++i) {
        assert_int_equal(
            trn_capture_segment(wire, len, payload, i, g_segs[i], TRN_ISOTP_MAX_MSG, &g_seg_len[i]),
            TRN_OK);
    }
    return n;
}

static void fresh(void)
{
    assert_int_equal(trn_capture_rx_init(&g_rx), TRN_OK);
    memset(&g_sentinel, 0xA5, sizeof g_sentinel);
    g_out = g_sentinel;
}

static void test_hand_vector(void **state)
{
    trn_capture_t *c = &g_cap;
    size_t len = 0;
    const uint8_t want[28] = {
        0x01, 0x00, 0x34, 0x12,             /* version, flags, id 0x1234 */
        0x04, 0x03, 0x02, 0x01,             /* time 0x01020304 */
        0xFF, 0xFF, 0x00, 0x80,             /* pan -1, tilt -32768 */
        0x21, 0x02, 0x02, 0x00,             /* state, faults, n = 2 */
        0x01, 0x00, 0xFE, 0xFF, 0xE8, 0x03, /* (1, -2, 1000) */
        0xFF, 0x7F, 0x00, 0x80, 0x00, 0x00, /* (32767, -32768, 0) */
    };
    uint32_t crc = trn_crc32(want, sizeof want);
    (void)state;
    memset(c, 0, sizeof *c);
    c->capture_id = 0x1234;
    c->time_ms = 0x01020304u;
    c->pan_100urad = -1;
    c->tilt_100urad = -32768;
    c->mast_state = 0x21;
    c->mast_faults = 0x02;
    c->n_points = 2;
    c->points[0].x_mm = 1;
    c->points[0].y_mm = -2;
    c->points[0].z_mm = 1000;
    c->points[1].x_mm = 32767;
    c->points[1].y_mm = -32768;
    c->points[1].z_mm = 0;
    assert_int_equal(trn_capture_encode(c, g_wire, sizeof g_wire, &len), TRN_OK);
    assert_int_equal(len, 32);
    assert_memory_equal(g_wire, want, sizeof want);
    assert_int_equal(g_wire[28], crc & 0xFF);
    assert_int_equal(g_wire[29], (crc >> 8) & 0xFF);
    assert_int_equal(g_wire[30], (crc >> 16) & 0xFF);
    assert_int_equal(g_wire[31], crc >> 24);
    assert_int_equal(trn_capture_decode(g_wire, len, &g_out, NULL), TRN_OK);
    assert_int_equal(g_out.crc, crc);
    assert_int_equal(g_out.points[1].y_mm, -32768);
    assert_int_equal(g_out.tilt_100urad, -32768);
}

static void test_encode_decode_args(void **state)
{
    size_t len = 0;
    trn_cap_err_t e;
    (void)state;
    make_capture(&g_cap, 3, 1);
    assert_int_equal(trn_capture_encode(NULL, g_wire, sizeof g_wire, &len), TRN_E_NULL);
    assert_int_equal(trn_capture_encode(&g_cap, NULL, sizeof g_wire, &len), TRN_E_NULL);
    assert_int_equal(trn_capture_encode(&g_cap, g_wire, sizeof g_wire, NULL), TRN_E_NULL);
    assert_int_equal(trn_capture_encode(&g_cap, g_wire, TRN_CAP_WIRE_BYTES(3) - 1, &len),
                     TRN_E_WORKSPACE);
    assert_int_equal(trn_capture_encode(&g_cap, g_wire, TRN_CAP_WIRE_BYTES(3), &len), TRN_OK);
    assert_int_equal(trn_capture_decode(NULL, len, &g_out, &e), TRN_E_NULL);
    assert_int_equal(trn_capture_decode(g_wire, len, NULL, &e), TRN_E_NULL);
#if TRN_PORT_MAX_CAPTURE_POINTS < 65535
    g_cap.n_points = TRN_PORT_MAX_CAPTURE_POINTS + 1;
    assert_int_equal(trn_capture_encode(&g_cap, g_wire, sizeof g_wire, &len), TRN_E_CAPACITY);
#endif
    assert_int_equal(trn_capture_segment_count(100, 0, &(uint8_t){0}), TRN_E_ARG);
    assert_int_equal(trn_capture_segment_count(100, TRN_CAP_SEG_PAYLOAD_MAX + 1, &(uint8_t){0}),
                     TRN_E_ARG);
    assert_int_equal(trn_capture_segment_count(0, 10, &(uint8_t){0}), TRN_E_ARG);
    assert_int_equal(trn_capture_segment_count(256, 1, &(uint8_t){0}), TRN_E_SIZE);
    assert_int_equal(trn_capture_segment_count(255, 1, &(uint8_t){0}), TRN_OK);
    assert_int_equal(trn_capture_segment_count(255, 1, NULL), TRN_E_NULL);
    {
        uint8_t seg[64];
        size_t sl;
        assert_int_equal(trn_capture_segment(g_wire, len, 10, 4, seg, sizeof seg, &sl),
                         TRN_E_RANGE);
        assert_int_equal(trn_capture_segment(g_wire, len, 0, 0, seg, sizeof seg, &sl), TRN_E_ARG);
        assert_int_equal(trn_capture_segment(g_wire, len, 10, 0, seg, 13, &sl), TRN_E_WORKSPACE);
        assert_int_equal(trn_capture_segment(g_wire, 15, 10, 0, seg, sizeof seg, &sl), TRN_E_ARG);
        assert_int_equal(trn_capture_segment(NULL, len, 10, 0, seg, sizeof seg, &sl), TRN_E_NULL);
        assert_int_equal(trn_capture_segment(g_wire, len, 10, 0, NULL, sizeof seg, &sl),
                         TRN_E_NULL);
        assert_int_equal(trn_capture_segment(g_wire, len, 10, 0, seg, sizeof seg, NULL),
                         TRN_E_NULL);
        assert_int_equal(trn_capture_segment(g_wire, len, 10, 3, seg, sizeof seg, &sl), TRN_OK);
        assert_int_equal(sl, 4 + 8); /* 38 bytes: the last of 4 segments holds 8 */
        assert_int_equal(seg[2], 3);
        assert_int_equal(seg[3], 4);
    }
    assert_int_equal(trn_capture_rx_init(NULL), TRN_E_NULL);
    assert_int_equal(trn_capture_rx_abort(NULL), TRN_E_NULL);
    fresh();
    {
        int done = 0;
        assert_int_equal(trn_capture_rx_segment(NULL, g_wire, 10, &g_out, &done, NULL), TRN_E_NULL);
        assert_int_equal(trn_capture_rx_segment(&g_rx, NULL, 10, &g_out, &done, NULL), TRN_E_NULL);
        assert_int_equal(trn_capture_rx_segment(&g_rx, g_wire, 10, NULL, &done, NULL), TRN_E_NULL);
        assert_int_equal(trn_capture_rx_segment(&g_rx, g_wire, 10, &g_out, NULL, NULL), TRN_E_NULL);
    }
    assert_string_equal(trn_cap_err_name(TRN_CAP_ERR_CRC), "CRC");
    assert_string_equal(trn_cap_err_name(TRN_CAP_ERR_COUNT), "UNKNOWN");
    assert_string_equal(trn_cap_err_name((trn_cap_err_t)99), "UNKNOWN");
    {
        int a, b;
        for (a = 0; a < TRN_CAP_ERR_COUNT; ++a) {
            assert_string_not_equal(trn_cap_err_name((trn_cap_err_t)a), "UNKNOWN");
            for (b = a + 1; b < TRN_CAP_ERR_COUNT; ++b) {
                assert_string_not_equal(trn_cap_err_name((trn_cap_err_t)a),
                                        trn_cap_err_name((trn_cap_err_t)b));
            }
        }
    }
}

/* Feed segments in the order given; returns the status of the last one. */
static trn_status_t feed(const int *order, int n, int *done, trn_cap_err_t *err)
{
    trn_status_t st = TRN_OK;
    int i;
    for (i = 0; i < n; ++i) {
        st = trn_capture_rx_segment(&g_rx, g_segs[order[i]], g_seg_len[order[i]], &g_out, done,
                                    err);
        if (i + 1 < n) {
            assert_int_equal(st, TRN_OK);
            assert_int_equal(*done, 0);
        }
    }
    return st;
}

static void test_round_trips(void **state)
{
    const uint16_t sizes[] = {0, 1, 2, 680, 681, 1000, TRN_PORT_MAX_CAPTURE_POINTS};
    const size_t payloads[] = {TRN_CAP_SEG_PAYLOAD_MAX, 1000, 97};
    size_t si, pi;
    (void)state;
    fresh();
    for (si = 0; si < sizeof sizes / sizeof sizes[0]; ++si) {
        for (pi = 0; pi < sizeof payloads / sizeof payloads[0]; ++pi) {
            size_t len = 0;
            uint8_t n, i;
            int done = 0;
            trn_cap_err_t err = TRN_CAP_ERR_COUNT;
            if (sizes[si] > TRN_PORT_MAX_CAPTURE_POINTS) {
                continue;
            }
            make_capture(&g_cap, sizes[si], 100 + si);
            assert_int_equal(trn_capture_encode(&g_cap, g_wire, sizeof g_wire, &len), TRN_OK);
            assert_int_equal(len, TRN_CAP_WIRE_BYTES(sizes[si]));
            if ((len + payloads[pi] - 1) / payloads[pi] > 255) {
                continue;
            }
            n = split(g_wire, len, payloads[pi]);
            for (i = 0; i < n; ++i) {
                assert_int_equal(
                    trn_capture_rx_segment(&g_rx, g_segs[i], g_seg_len[i], &g_out, &done, &err),
                    TRN_OK);
                assert_int_equal(err, TRN_CAP_ERR_NONE);
                assert_int_equal(done, i + 1 == n);
            }
            assert_int_equal(g_out.capture_id, g_cap.capture_id);
            assert_int_equal(g_out.time_ms, g_cap.time_ms);
            assert_int_equal(g_out.pan_100urad, g_cap.pan_100urad);
            assert_int_equal(g_out.tilt_100urad, g_cap.tilt_100urad);
            assert_int_equal(g_out.mast_state, g_cap.mast_state);
            assert_int_equal(g_out.mast_faults, g_cap.mast_faults);
            assert_int_equal(g_out.n_points, g_cap.n_points);
            assert_memory_equal(g_out.points, g_cap.points,
                                sizeof(trn_cap_point_t) * g_cap.n_points);
        }
    }
    for (si = 0; si < TRN_CAP_ERR_COUNT; ++si) {
        assert_int_equal(g_rx.err_count[si], 0);
    }
    assert_true(g_rx.n_complete >= (TRN_PORT_MAX_CAPTURE_POINTS >= 4096 ? 15u : 1u));
}

/* A capture of up to 1000 points (fewer when the build's maximum is
 * smaller) split into exactly 7 segments of g_seven_payload bytes. */
#define SEVEN_POINTS (TRN_PORT_MAX_CAPTURE_POINTS < 1000 ? TRN_PORT_MAX_CAPTURE_POINTS : 1000)
static size_t g_seven_payload, g_seven_len;

static uint8_t setup_seven(void)
{
    make_capture(&g_cap, SEVEN_POINTS, 9);
    assert_int_equal(trn_capture_encode(&g_cap, g_wire, sizeof g_wire, &g_seven_len), TRN_OK);
    g_seven_payload = (g_seven_len + 3u + 6u) / 7u; /* 7 segments also for len + 3 */
    fresh();
    return split(g_wire, g_seven_len, g_seven_payload);
}

static void expect_reject(trn_status_t st, trn_cap_err_t err, int done, trn_status_t want_st,
                          trn_cap_err_t want)
{
    assert_int_equal(st, want_st);
    assert_int_equal(err, want);
    assert_int_equal(done, 0);
    assert_int_equal(g_rx.err_count[want], 1);
    assert_int_equal(g_rx.n_complete, 0);
    assert_memory_equal(&g_out, &g_sentinel, sizeof g_out);
}

static void test_missing_duplicate_out_of_order(void **state)
{
    int done = 0;
    trn_cap_err_t err;
    trn_status_t st;
    (void)state;
    assert_int_equal(setup_seven(), 7);
    {
        const int order[] = {0, 1, 3};
        st = feed(order, 3, &done, &err);
        expect_reject(st, err, done, TRN_E_SEQ, TRN_CAP_ERR_MISSING);
    }
    setup_seven();
    {
        const int order[] = {0, 1, 2, 2};
        st = feed(order, 4, &done, &err);
        expect_reject(st, err, done, TRN_E_SEQ, TRN_CAP_ERR_DUPLICATE);
    }
    setup_seven();
    {
        const int order[] = {0, 1, 2, 1};
        st = feed(order, 4, &done, &err);
        expect_reject(st, err, done, TRN_E_SEQ, TRN_CAP_ERR_OUT_OF_ORDER);
    }
    setup_seven();
    {
        const int order[] = {1}; /* segment 0 lost */
        st = feed(order, 1, &done, &err);
        expect_reject(st, err, done, TRN_E_SEQ, TRN_CAP_ERR_MISSING);
    }
    /* after an error the rest of that capture is rejected too, and never
     * completes; a whole new capture afterwards is fine */
    setup_seven();
    {
        const int order[] = {0, 2};
        int i;
        (void)feed(order, 2, &done, &err);
        assert_int_equal(err, TRN_CAP_ERR_MISSING);
        for (i = 3; i < 7; ++i) {
            st = trn_capture_rx_segment(&g_rx, g_segs[i], g_seg_len[i], &g_out, &done, &err);
            assert_int_equal(st, TRN_E_SEQ);
            assert_int_equal(done, 0);
        }
        assert_memory_equal(&g_out, &g_sentinel, sizeof g_out);
        for (i = 0; i < 7; ++i) {
            st = trn_capture_rx_segment(&g_rx, g_segs[i], g_seg_len[i], &g_out, &done, &err);
            assert_int_equal(st, TRN_OK);
        }
        assert_int_equal(done, 1);
        assert_int_equal(g_out.n_points, SEVEN_POINTS);
    }
}

static void test_restart_and_abort(void **state)
{
    int done = 0, i;
    trn_cap_err_t err;
    trn_status_t st;
    (void)state;
    setup_seven();
    {
        const int order[] = {0, 1, 2};
        (void)feed(order, 3, &done, &err);
    }
    st = trn_capture_rx_segment(&g_rx, g_segs[0], g_seg_len[0], &g_out, &done, &err);
    assert_int_equal(st, TRN_E_SEQ);
    assert_int_equal(err, TRN_CAP_ERR_RESTARTED);
    assert_int_equal(g_rx.err_count[TRN_CAP_ERR_RESTARTED], 1);
    for (i = 1; i < 7; ++i) {
        st = trn_capture_rx_segment(&g_rx, g_segs[i], g_seg_len[i], &g_out, &done, &err);
        assert_int_equal(st, TRN_OK);
    }
    assert_int_equal(done, 1);

    setup_seven();
    assert_int_equal(trn_capture_rx_abort(&g_rx), TRN_OK); /* idle: nothing counted */
    assert_int_equal(g_rx.err_count[TRN_CAP_ERR_TRANSPORT], 0);
    {
        const int order[] = {0, 1};
        (void)feed(order, 2, &done, &err);
    }
    assert_int_equal(trn_capture_rx_abort(&g_rx), TRN_OK);
    assert_int_equal(g_rx.err_count[TRN_CAP_ERR_TRANSPORT], 1);
    (void)trn_capture_rx_segment(&g_rx, g_segs[2], g_seg_len[2], &g_out, &done, &err);
    assert_int_equal(err, TRN_CAP_ERR_MISSING);
    assert_memory_equal(&g_out, &g_sentinel, sizeof g_out);
}

static void test_bad_crc(void **state)
{
    int done = 0;
    trn_cap_err_t err;
    trn_status_t st;
    const int order[] = {0, 1, 2, 3, 4, 5, 6};
    (void)state;
    setup_seven();
    g_segs[3][g_seg_len[3] / 2] ^= 0x01; /* one bit of one point */
    st = feed(order, 7, &done, &err);
    expect_reject(st, err, done, TRN_E_CRC, TRN_CAP_ERR_CRC);
    setup_seven();
    g_segs[6][g_seg_len[6] - 1] ^= 0x80; /* the CRC itself */
    st = feed(order, 7, &done, &err);
    expect_reject(st, err, done, TRN_E_CRC, TRN_CAP_ERR_CRC);
}

static void test_header_rejects(void **state)
{
    int done = 0;
    trn_cap_err_t err;
    trn_status_t st;
    uint16_t bad_n = (uint16_t)(TRN_PORT_MAX_CAPTURE_POINTS + 1);
    (void)state;
    setup_seven();
    g_segs[0][4 + 0] = 2; /* version 2 */
    st = trn_capture_rx_segment(&g_rx, g_segs[0], g_seg_len[0], &g_out, &done, &err);
    expect_reject(st, err, done, TRN_E_FORMAT, TRN_CAP_ERR_VERSION);
    setup_seven();
    g_segs[0][4 + 1] = 1; /* reserved flags */
    st = trn_capture_rx_segment(&g_rx, g_segs[0], g_seg_len[0], &g_out, &done, &err);
    expect_reject(st, err, done, TRN_E_FORMAT, TRN_CAP_ERR_VERSION);
#if TRN_PORT_MAX_CAPTURE_POINTS < 65535
    setup_seven();
    g_segs[0][4 + 14] = (uint8_t)(bad_n & 0xFF);
    g_segs[0][4 + 15] = (uint8_t)(bad_n >> 8);
    st = trn_capture_rx_segment(&g_rx, g_segs[0], g_seg_len[0], &g_out, &done, &err);
    expect_reject(st, err, done, TRN_E_CAPACITY, TRN_CAP_ERR_TOO_MANY_POINTS);
#endif
    (void)bad_n;
    setup_seven();
    g_segs[0][4 + 2] ^= 0xFF; /* header id differs from the segment id */
    st = trn_capture_rx_segment(&g_rx, g_segs[0], g_seg_len[0], &g_out, &done, &err);
    expect_reject(st, err, done, TRN_E_FORMAT, TRN_CAP_ERR_ID_MISMATCH);
}

static void test_segment_rejects(void **state)
{
    int done = 0;
    trn_cap_err_t err;
    trn_status_t st;
    (void)state;
    setup_seven();
    st = trn_capture_rx_segment(&g_rx, g_segs[0], 4, &g_out, &done, &err);
    expect_reject(st, err, done, TRN_E_FORMAT, TRN_CAP_ERR_SHORT_SEGMENT);
    setup_seven();
    g_segs[0][3] = 0; /* seg_count 0 */
    st = trn_capture_rx_segment(&g_rx, g_segs[0], g_seg_len[0], &g_out, &done, &err);
    expect_reject(st, err, done, TRN_E_FORMAT, TRN_CAP_ERR_SEG_COUNT);
    setup_seven();
    g_segs[0][2] = 7; /* index == count */
    st = trn_capture_rx_segment(&g_rx, g_segs[0], g_seg_len[0], &g_out, &done, &err);
    expect_reject(st, err, done, TRN_E_FORMAT, TRN_CAP_ERR_SEG_COUNT);
    setup_seven();
    g_segs[1][3] = 8; /* count changes mid-capture */
    {
        const int order[] = {0, 1};
        st = feed(order, 2, &done, &err);
        expect_reject(st, err, done, TRN_E_FORMAT, TRN_CAP_ERR_SEG_COUNT);
    }
    setup_seven();
    g_segs[1][0] ^= 0x01; /* segment of another capture */
    {
        const int order[] = {0, 1};
        st = feed(order, 2, &done, &err);
        expect_reject(st, err, done, TRN_E_FORMAT, TRN_CAP_ERR_ID_MISMATCH);
    }
}

static void test_length_rejects(void **state)
{
    int done = 0;
    trn_cap_err_t err;
    trn_status_t st;
    size_t len, pay;
    uint8_t n;
    const int order[] = {0, 1, 2, 3, 4, 5, 6};
    (void)state;
    /* truncated: the sender stops 6 bytes early but marks the end */
    setup_seven();
    len = g_seven_len;
    pay = g_seven_payload;
    n = split(g_wire, len - 6, pay);
    assert_int_equal(n, 7);
    st = feed(order, 7, &done, &err);
    expect_reject(st, err, done, TRN_E_FORMAT, TRN_CAP_ERR_TRUNCATED);
    /* wrong length: 3 bytes more than the header announces */
    memset(g_wire + len, 0, 3);
    fresh();
    n = split(g_wire, len + 3, pay);
    assert_int_equal(n, 7);
    st = feed(order, 7, &done, &err);
    expect_reject(st, err, done, TRN_E_FORMAT, TRN_CAP_ERR_OVERFLOW);
    /* a whole extra segment beyond the capture */
    fresh();
    n = split(g_wire, len + pay + 3, pay); /* one segment more than the capture needs */
    assert_int_equal(n, 8);
    {
        const int order8[] = {0, 1, 2, 3, 4, 5, 6};
        st = feed(order8, 7, &done, &err);
        expect_reject(st, err, done, TRN_E_FORMAT, TRN_CAP_ERR_OVERFLOW);
    }
    /* decode of raw bytes: too short, truncated, too long */
    assert_int_equal(trn_capture_decode(g_wire, 19, &g_out, &err), TRN_E_FORMAT);
    assert_int_equal(err, TRN_CAP_ERR_TRUNCATED);
    assert_int_equal(trn_capture_decode(g_wire, len - 1, &g_out, &err), TRN_E_FORMAT);
    assert_int_equal(err, TRN_CAP_ERR_TRUNCATED);
    assert_int_equal(trn_capture_decode(g_wire, len + 1, &g_out, &err), TRN_E_FORMAT);
    assert_int_equal(err, TRN_CAP_ERR_OVERFLOW);
    assert_memory_equal(&g_out, &g_sentinel, sizeof g_out);
    assert_int_equal(trn_capture_decode(g_wire, len, &g_out, &err), TRN_OK);
    assert_int_equal(err, TRN_CAP_ERR_NONE);
}


static void test_points_m(void **state)
{
    static trn_vec3f_t pts[TRN_PORT_MAX_CAPTURE_POINTS];
    size_t n = 99;
    (void)state;
    memset(&g_cap, 0, sizeof g_cap);
    g_cap.n_points = 3;
    g_cap.points[0] = (trn_cap_point_t){1, -2, 1000};
    g_cap.points[1] = (trn_cap_point_t){-32768, 32767, 0};
    g_cap.points[2] = (trn_cap_point_t){123, 4567, -89};
    assert_int_equal(trn_capture_points_m(&g_cap, pts, 3, &n), TRN_OK);
    assert_int_equal(n, 3);
    assert_true(pts[0].x == 0.001f && pts[0].y == -0.002f && pts[0].z == 1.0f);
    assert_true(pts[1].x == -32.768f && pts[1].y == 32.767f && pts[1].z == 0.0f);
    assert_true(pts[2].x == 0.123f && pts[2].y == 4.567f && pts[2].z == -0.089f);
    assert_int_equal(trn_capture_points_m(&g_cap, pts, 2, &n), TRN_E_CAPACITY);
    assert_int_equal(trn_capture_points_m(NULL, pts, 3, &n), TRN_E_NULL);
    assert_int_equal(trn_capture_points_m(&g_cap, NULL, 3, &n), TRN_E_NULL);
    assert_int_equal(trn_capture_points_m(&g_cap, pts, 3, NULL), TRN_E_NULL);
#if TRN_PORT_MAX_CAPTURE_POINTS < 65535
    g_cap.n_points = TRN_PORT_MAX_CAPTURE_POINTS + 1;
    assert_int_equal(trn_capture_points_m(&g_cap, pts, 65535, &n), TRN_E_SIZE);
#endif
}

/* Property: whatever a faulty bus does to the segments (drop, duplicate,
 * swap, truncate, flip a bit, inject a stranger), a capture is delivered
 * only if it is exactly the one sent. 3000 seeded damaged transfers. */
static void test_damaged_streams_never_deliver_wrong_data(void **state)
{
    trn_rng_t r;
    int trial, delivered_ok = 0, rejected = 0;
    (void)state;
    trn_rng_seed(&r, 77);
    fresh();
    for (trial = 0; trial < 3000; ++trial) {
        size_t len = 0;
        uint8_t n, i;
        int done = 0, kind = trn_rng_int(&r, 0, 6), got = 0;
        uint8_t victim;
        trn_cap_err_t err;
        make_capture(
            &g_cap,
            (uint16_t)trn_rng_int(
                &r, 0, TRN_PORT_MAX_CAPTURE_POINTS < 400 ? TRN_PORT_MAX_CAPTURE_POINTS : 400),
            (uint64_t)trial);
        assert_int_equal(trn_capture_encode(&g_cap, g_wire, sizeof g_wire, &len), TRN_OK);
        n = split(g_wire, len, (size_t)trn_rng_int(&r, 16, 900));
        victim = n > 0u ? (uint8_t)trn_rng_int(&r, 0, n - 1) : 0u; /* n >= 1: len > 0 */
        g_out = g_sentinel;
        for (i = 0; i < n; ++i) {
            const uint8_t *seg = g_segs[i];
            size_t sl = g_seg_len[i];
            static uint8_t tmp[TRN_ISOTP_MAX_MSG];
            int feed_twice = 0;
            if (i == victim) {
                memcpy(tmp, seg, sl);
                switch (kind) {
                case 0: continue;                                            /* dropped */
                case 1: feed_twice = 1; break;                               /* duplicated */
                case 2: sl = (size_t)trn_rng_int(&r, 1, (int)sl - 1); break; /* truncated */
                case 3:
                    tmp[trn_rng_int(&r, 0, (int)sl - 1)] ^= (uint8_t)(1u << trn_rng_int(&r, 0, 7));
                    break;
                case 4:
                    if (i + 1 < n) {
                        seg = g_segs[i + 1];
                        sl = g_seg_len[i + 1];
                        memcpy(tmp, seg, sl);
                    }
                    break;
                case 5: tmp[0] ^= 0x01; break; /* stranger's id */
                default: break;                /* clean */
                }
                seg = tmp;
            }
            (void)trn_capture_rx_segment(&g_rx, seg, sl, &g_out, &done, &err);
            got |= done;
            if (feed_twice) {
                (void)trn_capture_rx_segment(&g_rx, seg, sl, &g_out, &done, &err);
                got |= done;
            }
        }
        (void)trn_capture_rx_abort(&g_rx);
        if (got) {
            /* delivered: must be exactly what was sent */
            assert_int_equal(g_out.capture_id, g_cap.capture_id);
            assert_int_equal(g_out.n_points, g_cap.n_points);
            assert_memory_equal(g_out.points, g_cap.points,
                                sizeof(trn_cap_point_t) * g_cap.n_points);
            ++delivered_ok;
        } else {
            assert_memory_equal(&g_out, &g_sentinel, sizeof g_out);
            ++rejected;
        }
    }
    print_message("damaged transfers: %d delivered intact, %d rejected\n", delivered_ok, rejected);
    assert_true(rejected > 1000);
    assert_true(delivered_ok > 300);
}

/* The whole chain: terrain seen by the stereo head -> capture on the wire
 * (segments, CRC) -> reassembled -> metres -> map with the pan/tilt the
 * capture carries -> local DEM equal to the terrain. */
static void test_capture_to_local_dem(void **state)
{
    static synth_rock_t rocks[10];
    static trn_vec3f_t pts[TRN_PORT_MAX_CAPTURE_POINTS];
    static float dem_mem[40 * 40], truth[40 * 40];
    synth_terrain_t terr;
    trn_mast_geom_t g;
    trn_rover_pose_t p = {5.0f, 6.0f, 0.0f, -0.4f};
    trn_local_dem_cfg_t cfg = {0.1f, 20, 20, 1};
    trn_vec3f_t target;
    trn_rigid_t T;
    trn_grid_f32_t dem;
    float pan, tilt;
    size_t len = 0, n = 0, used = 0, i;
    uint8_t nseg, s;
    int x, y, done = 0;
    trn_cap_err_t err;
    (void)state;
    NEED_POINTS(1600);
    memset(&g, 0, sizeof g);
    g.pan_x_m = 0.2f;
    g.pan_z_m = 1.4f;
    g.tilt_fwd_m = 0.05f;
    g.cam_left_m = 0.1f;
    g.cam_up_m = 0.03f;
    g.pan_min_rad = -3.0f;
    g.pan_max_rad = 3.0f;
    g.tilt_min_rad = -1.5f;
    g.tilt_max_rad = 0.5f;
    synth_make(&terr, rocks, 10, 12.0, 0.1, 0.3, 0.5, 0.1, 3);
    p.z_m = (float)synth_height(&terr, p.x_m, p.y_m);
    target = (trn_vec3f_t){p.x_m + 1.5f, p.y_m - 0.5f, 0.0f};
    target.z = (float)synth_height(&terr, target.x, target.y);
    assert_int_equal(trn_mast_point_at(&g, &p, &target, &pan, &tilt), TRN_OK);
    /* the head reports the angles it measured, in counts */
    memset(&g_cap, 0, sizeof g_cap);
    g_cap.capture_id = 7;
    assert_int_equal(trn_can_angle_to_raw(pan, &g_cap.pan_100urad), TRN_OK);
    assert_int_equal(trn_can_angle_to_raw(tilt, &g_cap.tilt_100urad), TRN_OK);
    assert_int_equal(trn_mast_camera_to_map(&g, &p, trn_can_angle_from_raw(g_cap.pan_100urad),
                                            trn_can_angle_from_raw(g_cap.tilt_100urad), &T),
                     TRN_OK);
    for (y = 0; y < 40; ++y) {
        for (x = 0; x < 40; ++x) {
            double mx = p.x_m + (x - 20) * 0.1, my = p.y_m + (y - 20) * 0.1,
                   h = synth_height(&terr, mx, my);
            const double d[3] = {mx - T.t.x, my - T.t.y, h - T.t.z};
            double c[3];
            int k;
            for (k = 0; k < 3; ++k) {
                c[k] = T.r[k] * d[0] + T.r[3 + k] * d[1] + T.r[6 + k] * d[2];
            }
            truth[y * 40 + x] = (float)h;
            g_cap.points[g_cap.n_points].x_mm = (int16_t)floor(c[0] * 1000.0 + 0.5);
            g_cap.points[g_cap.n_points].y_mm = (int16_t)floor(c[1] * 1000.0 + 0.5);
            g_cap.points[g_cap.n_points].z_mm = (int16_t)floor(c[2] * 1000.0 + 0.5);
            ++g_cap.n_points;
        }
    }
    assert_int_equal(trn_capture_encode(&g_cap, g_wire, sizeof g_wire, &len), TRN_OK);
    fresh();
    nseg = split(g_wire, len, TRN_CAP_SEG_PAYLOAD_MAX);
    assert_int_equal(nseg, 3); /* 1600 points = 9620 bytes */
    for (s = 0; s < nseg; ++s) {
        assert_int_equal(
            trn_capture_rx_segment(&g_rx, g_segs[s], g_seg_len[s], &g_out, &done, &err), TRN_OK);
    }
    assert_int_equal(done, 1);
    assert_int_equal(trn_capture_points_m(&g_out, pts, TRN_PORT_MAX_CAPTURE_POINTS, &n), TRN_OK);
    assert_int_equal(trn_mast_camera_to_map(&g, &p, trn_can_angle_from_raw(g_out.pan_100urad),
                                            trn_can_angle_from_raw(g_out.tilt_100urad), &T),
                     TRN_OK);
    assert_int_equal(trn_rigid_apply(&T, pts, n, pts), TRN_OK);
    assert_int_equal(trn_grid_f32_init(&dem, dem_mem, 40 * 40, 40, 40), TRN_OK);
    assert_int_equal(trn_mast_local_dem(pts, n, &p, &cfg, &dem, &used), TRN_OK);
    assert_int_equal(used, 1600);
    for (i = 0; i < 1600; ++i) {
        assert_float_equal(dem_mem[i], truth[i], 2e-3f);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hand_vector),
        cmocka_unit_test(test_encode_decode_args),
        cmocka_unit_test(test_round_trips),
        cmocka_unit_test(test_missing_duplicate_out_of_order),
        cmocka_unit_test(test_restart_and_abort),
        cmocka_unit_test(test_bad_crc),
        cmocka_unit_test(test_header_rejects),
        cmocka_unit_test(test_segment_rejects),
        cmocka_unit_test(test_length_rejects),
        cmocka_unit_test(test_points_m),
        cmocka_unit_test(test_damaged_streams_never_deliver_wrong_data),
        cmocka_unit_test(test_capture_to_local_dem),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
