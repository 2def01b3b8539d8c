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

#include <string.h>

#include "trn_port/capture.h"
#include "trn_port/crc.h"
#include "rng.h"

static trn_capture_t g_cap, g_out, g_sentinel;
static trn_capture_rx_t g_rx;
static uint8_t g_wire[TRN_CAP_WIRE_MAX + 64];
static uint8_t g_segs[255][TRN_ISOTP_MAX_MSG];
static size_t g_seg_len[255];

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
        assert_int_equal(trn_capture_segment(wire, len, payload, i, g_segs[i], TRN_ISOTP_MAX_MSG, &g_seg_len[i]),
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
    c->points[0].x_mm = 1; c->points[0].y_mm = -2; c->points[0].z_mm = 1000;
    c->points[1].x_mm = 32767; c->points[1].y_mm = -32768; c->points[1].z_mm = 0;
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
    assert_int_equal(trn_capture_encode(&g_cap, g_wire, TRN_CAP_WIRE_BYTES(3) - 1, &len), TRN_E_WORKSPACE);
    assert_int_equal(trn_capture_encode(&g_cap, g_wire, TRN_CAP_WIRE_BYTES(3), &len), TRN_OK);
    assert_int_equal(trn_capture_decode(NULL, len, &g_out, &e), TRN_E_NULL);
    assert_int_equal(trn_capture_decode(g_wire, len, NULL, &e), TRN_E_NULL);
#if TRN_PORT_MAX_CAPTURE_POINTS < 65535
    g_cap.n_points = TRN_PORT_MAX_CAPTURE_POINTS + 1;
    assert_int_equal(trn_capture_encode(&g_cap, g_wire, sizeof g_wire, &len), TRN_E_CAPACITY);
#endif
    assert_int_equal(trn_capture_segment_count(100, 0, &(uint8_t){0}), TRN_E_ARG);
    assert_int_equal(trn_capture_segment_count(100, TRN_CAP_SEG_PAYLOAD_MAX + 1, &(uint8_t){0}), TRN_E_ARG);
    assert_int_equal(trn_capture_segment_count(0, 10, &(uint8_t){0}), TRN_E_ARG);
    assert_int_equal(trn_capture_segment_count(256, 1, &(uint8_t){0}), TRN_E_SIZE);
    assert_int_equal(trn_capture_segment_count(255, 1, &(uint8_t){0}), TRN_OK);
    assert_int_equal(trn_capture_segment_count(255, 1, NULL), TRN_E_NULL);
    {
        uint8_t seg[64];
        size_t sl;
        assert_int_equal(trn_capture_segment(g_wire, len, 10, 4, seg, sizeof seg, &sl), TRN_E_RANGE);
        assert_int_equal(trn_capture_segment(g_wire, len, 10, 0, seg, 13, &sl), TRN_E_WORKSPACE);
        assert_int_equal(trn_capture_segment(g_wire, 15, 10, 0, seg, sizeof seg, &sl), TRN_E_ARG);
        assert_int_equal(trn_capture_segment(NULL, len, 10, 0, seg, sizeof seg, &sl), TRN_E_NULL);
        assert_int_equal(trn_capture_segment(g_wire, len, 10, 0, NULL, sizeof seg, &sl), TRN_E_NULL);
        assert_int_equal(trn_capture_segment(g_wire, len, 10, 0, seg, sizeof seg, NULL), TRN_E_NULL);
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
}

/* Feed segments in the order given; returns the status of the last one. */
static trn_status_t feed(const int *order, int n, int *done, trn_cap_err_t *err)
{
    trn_status_t st = TRN_OK;
    int i;
    for (i = 0; i < n; ++i) {
        st = trn_capture_rx_segment(&g_rx, g_segs[order[i]], g_seg_len[order[i]], &g_out, done, err);
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
            make_capture(&g_cap, sizes[si], 100 + si);
            assert_int_equal(trn_capture_encode(&g_cap, g_wire, sizeof g_wire, &len), TRN_OK);
            assert_int_equal(len, TRN_CAP_WIRE_BYTES(sizes[si]));
            if ((len + payloads[pi] - 1) / payloads[pi] > 255) {
                continue;
            }
            n = split(g_wire, len, payloads[pi]);
            for (i = 0; i < n; ++i) {
                assert_int_equal(trn_capture_rx_segment(&g_rx, g_segs[i], g_seg_len[i], &g_out, &done, &err),
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
            assert_memory_equal(g_out.points, g_cap.points, sizeof(trn_cap_point_t) * g_cap.n_points);
        }
    }
    for (si = 0; si < TRN_CAP_ERR_COUNT; ++si) {
        assert_int_equal(g_rx.err_count[si], 0);
    }
    assert_true(g_rx.n_complete >= 15);
}

/* A 1000-point capture in 1000-byte segments (7 segments). */
static uint8_t setup_seven(void)
{
    size_t len = 0;
    make_capture(&g_cap, 1000, 9);
    assert_int_equal(trn_capture_encode(&g_cap, g_wire, sizeof g_wire, &len), TRN_OK);
    fresh();
    return split(g_wire, len, 1000);
}

static void expect_reject(trn_status_t st, trn_cap_err_t err, int done, trn_status_t want_st, trn_cap_err_t want)
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
        st = feed(order, 2, &done, &err);
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
        assert_int_equal(g_out.n_points, 1000);
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
        st = feed(order, 3, &done, &err);
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
        st = feed(order, 2, &done, &err);
    }
    assert_int_equal(trn_capture_rx_abort(&g_rx), TRN_OK);
    assert_int_equal(g_rx.err_count[TRN_CAP_ERR_TRANSPORT], 1);
    st = trn_capture_rx_segment(&g_rx, g_segs[2], g_seg_len[2], &g_out, &done, &err);
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
    g_segs[3][100] ^= 0x01; /* one bit of one point */
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
    size_t len = 0;
    uint8_t n;
    const int order[] = {0, 1, 2, 3, 4, 5, 6};
    (void)state;
    /* truncated: the sender stops 6 bytes early but marks the end */
    make_capture(&g_cap, 1000, 9);
    assert_int_equal(trn_capture_encode(&g_cap, g_wire, sizeof g_wire, &len), TRN_OK);
    fresh();
    n = split(g_wire, len - 6, 1000);
    assert_int_equal(n, 7);
    st = feed(order, 7, &done, &err);
    expect_reject(st, err, done, TRN_E_FORMAT, TRN_CAP_ERR_TRUNCATED);
    /* wrong length: 3 bytes more than the header announces */
    memset(g_wire + len, 0, 3);
    fresh();
    n = split(g_wire, len + 3, 1000);
    st = feed(order, 7, &done, &err);
    expect_reject(st, err, done, TRN_E_FORMAT, TRN_CAP_ERR_OVERFLOW);
    /* a whole extra segment beyond the capture */
    fresh();
    n = split(g_wire, 7000 + 3, 1000); /* 8 segments, the capture is 6020 bytes */
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
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
