/* SPDX-License-Identifier: Apache-2.0 */
/* test_isotp.c - ISO 15765-2 frame codec and receiver (isotp.h).
 *
 * Hand-written frames check the PCI layout (big-endian 12-bit length, type
 * nibble); the stateless sender and the receiver round-trip every length
 * class; each named receiver error has its own test with its counter, and
 * none of them ever reports a message.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "trn_port/isotp.h"
#include "rng.h"

static void test_decode_hand_frames(void **state)
{
    trn_isotp_frame_t fr;
    const uint8_t sf[4] = {0x03, 0xAA, 0xBB, 0xCC};
    const uint8_t sf_pad[8] = {0x02, 0x11, 0x22, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC};
    const uint8_t ff[8] = {0x1F, 0xFF, 1, 2, 3, 4, 5, 6};
    const uint8_t ff8[8] = {0x10, 0x08, 1, 2, 3, 4, 5, 6};
    const uint8_t cf[5] = {0x25, 9, 8, 7, 6};
    const uint8_t fc[3] = {0x30, 0x08, 0xF3};
    (void)state;
    assert_int_equal(trn_isotp_decode(sf, 4, &fr), TRN_OK);
    assert_int_equal(fr.type, TRN_ISOTP_SF);
    assert_int_equal(fr.msg_len, 3);
    assert_int_equal(fr.data_off, 1);
    assert_int_equal(fr.data_len, 3);
    assert_int_equal(trn_isotp_decode(sf_pad, 8, &fr), TRN_OK);
    assert_int_equal(fr.msg_len, 2);
    assert_int_equal(trn_isotp_decode(ff, 8, &fr), TRN_OK);
    assert_int_equal(fr.type, TRN_ISOTP_FF);
    assert_int_equal(fr.msg_len, 4095);
    assert_int_equal(fr.data_off, 2);
    assert_int_equal(fr.data_len, 6);
    assert_int_equal(trn_isotp_decode(ff8, 8, &fr), TRN_OK);
    assert_int_equal(fr.msg_len, 8);
    assert_int_equal(trn_isotp_decode(cf, 5, &fr), TRN_OK);
    assert_int_equal(fr.type, TRN_ISOTP_CF);
    assert_int_equal(fr.sn, 5);
    assert_int_equal(fr.data_len, 4);
    assert_int_equal(trn_isotp_decode(fc, 3, &fr), TRN_OK);
    assert_int_equal(fr.type, TRN_ISOTP_FC);
    assert_int_equal(fr.fs, TRN_ISOTP_FS_CTS);
    assert_int_equal(fr.bs, 8);
    assert_int_equal(fr.stmin, 0xF3);
}

static void test_decode_rejects(void **state)
{
    trn_isotp_frame_t fr, keep;
    uint8_t d[8] = {0};
    (void)state;
    memset(&keep, 0x77, sizeof keep);
    fr = keep;
    assert_int_equal(trn_isotp_decode(NULL, 1, &fr), TRN_E_NULL);
    assert_int_equal(trn_isotp_decode(d, 1, NULL), TRN_E_NULL);
    assert_int_equal(trn_isotp_decode(d, 9, &fr), TRN_E_ARG);
    assert_int_equal(trn_isotp_decode(d, 0, &fr), TRN_E_FORMAT);
    d[0] = 0x00; /* SF length 0 */
    assert_int_equal(trn_isotp_decode(d, 8, &fr), TRN_E_FORMAT);
    d[0] = 0x05; /* SF length 5 in a 4-byte frame */
    assert_int_equal(trn_isotp_decode(d, 4, &fr), TRN_E_FORMAT);
    d[0] = 0x08; /* SF length 8: classic CAN has 7 at most */
    assert_int_equal(trn_isotp_decode(d, 8, &fr), TRN_E_FORMAT);
    d[0] = 0x10;
    d[1] = 0x20; /* FF in 7 bytes */
    assert_int_equal(trn_isotp_decode(d, 7, &fr), TRN_E_FORMAT);
    d[0] = 0x10;
    d[1] = 0x07; /* FF of 7 bytes would have been an SF */
    assert_int_equal(trn_isotp_decode(d, 8, &fr), TRN_E_FORMAT);
    d[0] = 0x10;
    d[1] = 0x00; /* 32-bit length escape: not supported */
    assert_int_equal(trn_isotp_decode(d, 8, &fr), TRN_E_FORMAT);
    d[0] = 0x21; /* CF without data */
    assert_int_equal(trn_isotp_decode(d, 1, &fr), TRN_E_FORMAT);
    d[0] = 0x30; /* FC too short */
    assert_int_equal(trn_isotp_decode(d, 2, &fr), TRN_E_FORMAT);
    d[0] = 0x33; /* FC reserved flow status */
    assert_int_equal(trn_isotp_decode(d, 3, &fr), TRN_E_FORMAT);
    d[0] = 0x40; /* reserved PCI type */
    assert_int_equal(trn_isotp_decode(d, 8, &fr), TRN_E_FORMAT);
    d[0] = 0xF0;
    assert_int_equal(trn_isotp_decode(d, 8, &fr), TRN_E_FORMAT);
    assert_memory_equal(&fr, &keep, sizeof fr);
}

static void test_frame_count(void **state)
{
    (void)state;
    assert_int_equal(trn_isotp_frame_count(0), 0);
    assert_int_equal(trn_isotp_frame_count(1), 1);
    assert_int_equal(trn_isotp_frame_count(7), 1);
    assert_int_equal(trn_isotp_frame_count(8), 2);
    assert_int_equal(trn_isotp_frame_count(13), 2);
    assert_int_equal(trn_isotp_frame_count(14), 3);
    assert_int_equal(trn_isotp_frame_count(4095), 1 + 585);
    assert_int_equal(trn_isotp_frame_count(4096), 0);
}

static void test_encode_hand_frames(void **state)
{
    uint8_t msg[20], out[8], dlc = 0;
    const uint8_t want_ff[8] = {0x10, 20, 0, 1, 2, 3, 4, 5};
    const uint8_t want_cf1[8] = {0x21, 6, 7, 8, 9, 10, 11, 12};
    const uint8_t want_cf2[8] = {0x22, 13, 14, 15, 16, 17, 18, 19};
    const uint8_t want_sf[4] = {0x03, 0, 1, 2};
    size_t i;
    (void)state;
    for (i = 0; i < sizeof msg; ++i) {
        msg[i] = (uint8_t)i;
    }
    assert_int_equal(trn_isotp_encode_frame(msg, 20, 0, out, &dlc), TRN_OK);
    assert_int_equal(dlc, 8);
    assert_memory_equal(out, want_ff, 8);
    assert_int_equal(trn_isotp_encode_frame(msg, 20, 1, out, &dlc), TRN_OK);
    assert_int_equal(dlc, 8);
    assert_memory_equal(out, want_cf1, 8);
    assert_int_equal(trn_isotp_encode_frame(msg, 20, 2, out, &dlc), TRN_OK);
    assert_int_equal(dlc, 8);
    assert_memory_equal(out, want_cf2, 8);
    assert_int_equal(trn_isotp_encode_frame(msg, 20, 3, out, &dlc), TRN_E_RANGE);
    assert_int_equal(trn_isotp_encode_frame(msg, 3, 0, out, &dlc), TRN_OK);
    assert_int_equal(dlc, 4);
    assert_memory_equal(out, want_sf, 4);
    assert_int_equal(trn_isotp_encode_frame(msg, 0, 0, out, &dlc), TRN_E_SIZE);
    assert_int_equal(trn_isotp_encode_frame(msg, 4096, 0, out, &dlc), TRN_E_SIZE);
    assert_int_equal(trn_isotp_encode_frame(NULL, 3, 0, out, &dlc), TRN_E_NULL);
    assert_int_equal(trn_isotp_encode_frame(msg, 3, 0, NULL, &dlc), TRN_E_NULL);
    assert_int_equal(trn_isotp_encode_frame(msg, 3, 0, out, NULL), TRN_E_NULL);
    /* a 12-bit length is big-endian in the FF */
    {
        static uint8_t big[4095];
        assert_int_equal(trn_isotp_encode_frame(big, 0xABC, 0, out, &dlc), TRN_OK);
        assert_int_equal(out[0], 0x1A);
        assert_int_equal(out[1], 0xBC);
        /* CF 16 wraps to sequence number 0, CF 17 is 1 */
        assert_int_equal(trn_isotp_encode_frame(big, 0xABC, 16, out, &dlc), TRN_OK);
        assert_int_equal(out[0], 0x20);
        assert_int_equal(trn_isotp_encode_frame(big, 0xABC, 17, out, &dlc), TRN_OK);
        assert_int_equal(out[0], 0x21);
    }
    assert_int_equal(trn_isotp_encode_fc(TRN_ISOTP_FS_WAIT, 4, 0x7F, out, &dlc), TRN_OK);
    assert_int_equal(dlc, 3);
    assert_int_equal(out[0], 0x31);
    assert_int_equal(out[1], 4);
    assert_int_equal(out[2], 0x7F);
    assert_int_equal(trn_isotp_encode_fc(3, 0, 0, out, &dlc), TRN_E_ARG);
    assert_int_equal(trn_isotp_encode_fc(0, 0, 0, NULL, &dlc), TRN_E_NULL);
    assert_int_equal(trn_isotp_encode_fc(0, 0, 0, out, NULL), TRN_E_NULL);
}

static void test_stmin(void **state)
{
    (void)state;
    assert_int_equal(trn_isotp_stmin_us(0x00), 0);
    assert_int_equal(trn_isotp_stmin_us(0x7F), 127000);
    assert_int_equal(trn_isotp_stmin_us(0x14), 20000);
    assert_int_equal(trn_isotp_stmin_us(0xF1), 100);
    assert_int_equal(trn_isotp_stmin_us(0xF9), 900);
    assert_int_equal(trn_isotp_stmin_us(0x80), 127000);
    assert_int_equal(trn_isotp_stmin_us(0xF0), 127000);
    assert_int_equal(trn_isotp_stmin_us(0xFA), 127000);
}

static uint8_t g_buf[TRN_ISOTP_MAX_MSG];

static void test_rx_init_args(void **state)
{
    trn_isotp_rx_t rx;
    trn_isotp_rx_result_t res;
    uint8_t d[8] = {0x01, 0};
    (void)state;
    assert_int_equal(trn_isotp_rx_init(NULL, g_buf, 100, 0, 0, 1000), TRN_E_NULL);
    assert_int_equal(trn_isotp_rx_init(&rx, NULL, 100, 0, 0, 1000), TRN_E_NULL);
    assert_int_equal(trn_isotp_rx_init(&rx, g_buf, 6, 0, 0, 1000), TRN_E_SIZE);
    assert_int_equal(trn_isotp_rx_init(&rx, g_buf, 4096, 0, 0, 1000), TRN_E_SIZE);
    assert_int_equal(trn_isotp_rx_init(&rx, g_buf, 100, 0, 0x80, 1000), TRN_E_ARG);
    assert_int_equal(trn_isotp_rx_init(&rx, g_buf, 100, 0, 0, 0), TRN_E_ARG);
    assert_int_equal(trn_isotp_rx_init(&rx, g_buf, 100, 0, 0, 60001), TRN_E_ARG);
    assert_int_equal(trn_isotp_rx_init(&rx, g_buf, 100, 0, 0xF5, 1000), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(NULL, d, 2, 0, &res), TRN_E_NULL);
    assert_int_equal(trn_isotp_rx_frame(&rx, NULL, 2, 0, &res), TRN_E_NULL);
    assert_int_equal(trn_isotp_rx_frame(&rx, d, 2, 0, NULL), TRN_E_NULL);
    assert_int_equal(trn_isotp_rx_frame(&rx, d, 9, 0, &res), TRN_E_ARG);
    assert_int_equal(trn_isotp_rx_poll(NULL, 0, &res), TRN_E_NULL);
    assert_int_equal(trn_isotp_rx_poll(&rx, 0, NULL), TRN_E_NULL);
    assert_string_equal(trn_isotp_err_name(TRN_ISOTP_ERR_WRONG_SN), "WRONG_SN");
    assert_string_equal(trn_isotp_err_name(TRN_ISOTP_ERR_COUNT), "UNKNOWN");
    assert_string_equal(trn_isotp_err_name((trn_isotp_err_t)99), "UNKNOWN");
    {
        int a, b;
        for (a = 0; a < TRN_ISOTP_ERR_COUNT; ++a) {
            assert_string_not_equal(trn_isotp_err_name((trn_isotp_err_t)a), "UNKNOWN");
            for (b = a + 1; b < TRN_ISOTP_ERR_COUNT; ++b) {
                assert_string_not_equal(trn_isotp_err_name((trn_isotp_err_t)a),
                                        trn_isotp_err_name((trn_isotp_err_t)b));
            }
        }
        for (a = 0; a < TRN_ISOTP_TX_ERR_COUNT; ++a) {
            assert_string_not_equal(trn_isotp_tx_err_name((trn_isotp_tx_err_t)a), "UNKNOWN");
            for (b = a + 1; b < TRN_ISOTP_TX_ERR_COUNT; ++b) {
                assert_string_not_equal(trn_isotp_tx_err_name((trn_isotp_tx_err_t)a),
                                        trn_isotp_tx_err_name((trn_isotp_tx_err_t)b));
            }
        }
        assert_string_equal(trn_isotp_tx_err_name((trn_isotp_tx_err_t)99), "UNKNOWN");
    }
}

/* Send msg through the stateless sender into rx; returns the number of FC
 * frames the receiver asked for, or -1 on any error. */
static int transfer(trn_isotp_rx_t *rx, const uint8_t *msg, size_t len, uint32_t t0,
                    uint32_t step_ms)
{
    uint16_t n = trn_isotp_frame_count(len), i;
    int n_fc = 0, got_msg = 0;
    for (i = 0; i < n; ++i) {
        uint8_t fr[8], dlc = 0;
        trn_isotp_rx_result_t res;
        if (trn_isotp_encode_frame(msg, len, i, fr, &dlc) != TRN_OK) {
            return -1;
        }
        if (trn_isotp_rx_frame(rx, fr, dlc, t0 + step_ms * i, &res) != TRN_OK) {
            return -1;
        }
        if (res.events & TRN_ISOTP_EV_SEND_FC) {
            assert_int_equal(res.fc_dlc, 3);
            assert_int_equal(res.fc[0], 0x30);
            assert_int_equal(res.fc[1], rx->bs);
            assert_int_equal(res.fc[2], rx->stmin);
            ++n_fc;
        }
        if (res.events & TRN_ISOTP_EV_MESSAGE) {
            assert_int_equal(i, n - 1);
            assert_int_equal(res.msg_len, len);
            got_msg = 1;
        }
    }
    return got_msg ? n_fc : -1;
}

static void test_rx_round_trip_all_lengths(void **state)
{
    static uint8_t msg[TRN_ISOTP_MAX_MSG];
    trn_isotp_rx_t rx;
    trn_rng_t r;
    size_t len, i;
    (void)state;
    trn_rng_seed(&r, 3);
    for (i = 0; i < sizeof msg; ++i) {
        msg[i] = (uint8_t)trn_rng_u64(&r);
    }
    assert_int_equal(trn_isotp_rx_init(&rx, g_buf, sizeof g_buf, 0, 0, 1000), TRN_OK);
    for (len = 1; len <= TRN_ISOTP_MAX_MSG; len += (len < 40) ? 1 : 97) {
        int n_fc = transfer(&rx, msg, len, 1000u * (uint32_t)len, 1);
        assert_int_equal(n_fc, len <= 7 ? 0 : 1);
        assert_memory_equal(g_buf, msg, len);
    }
    assert_int_equal(transfer(&rx, msg, 4095, 0, 1), 1);
    assert_memory_equal(g_buf, msg, 4095);
    for (i = 0; i < TRN_ISOTP_ERR_COUNT; ++i) {
        assert_int_equal(rx.err_count[i], 0);
    }
}

static void test_rx_block_size(void **state)
{
    static uint8_t msg[200];
    trn_isotp_rx_t rx;
    (void)state;
    memset(msg, 0x42, sizeof msg);
    assert_int_equal(trn_isotp_rx_init(&rx, g_buf, sizeof g_buf, 4, 0x0A, 1000), TRN_OK);
    /* 200 bytes: FF + 28 CFs; FC after the FF and after CF 4, 8, ..., 24
     * (not after CF 28, the last) = 1 + 6 */
    assert_int_equal(trn_isotp_frame_count(200), 29);
    assert_int_equal(transfer(&rx, msg, 200, 0, 1), 7);
    /* 34 bytes: FF + 4 CFs: the block ends with the message, one FC */
    assert_int_equal(transfer(&rx, msg, 34, 100, 1), 1);
}

static trn_isotp_rx_t g_rx;

static void rx_setup(uint16_t cap)
{
    assert_int_equal(trn_isotp_rx_init(&g_rx, g_buf, cap, 0, 0, 100), TRN_OK);
}

static void test_rx_wrong_sn(void **state)
{
    static uint8_t msg[30];
    trn_isotp_rx_result_t res;
    uint8_t fr[8], dlc;
    (void)state;
    rx_setup(100);
    assert_int_equal(trn_isotp_encode_frame(msg, 30, 0, fr, &dlc), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, dlc, 0, &res), TRN_OK);
    /* CF 2 instead of CF 1 (CF 1 lost) */
    assert_int_equal(trn_isotp_encode_frame(msg, 30, 2, fr, &dlc), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, dlc, 1, &res), TRN_E_SEQ);
    assert_int_equal(res.events, TRN_ISOTP_EV_ERROR);
    assert_int_equal(res.error, TRN_ISOTP_ERR_WRONG_SN);
    assert_int_equal(g_rx.err_count[TRN_ISOTP_ERR_WRONG_SN], 1);
    assert_int_equal(g_rx.state, TRN_ISOTP_RX_IDLE);
    /* the rest of the message is now unexpected; never a message */
    assert_int_equal(trn_isotp_encode_frame(msg, 30, 3, fr, &dlc), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, dlc, 2, &res), TRN_E_FORMAT);
    assert_int_equal(res.error, TRN_ISOTP_ERR_UNEXPECTED_CF);
    assert_false(res.events & TRN_ISOTP_EV_MESSAGE);
    assert_int_equal(g_rx.n_messages, 0);

    /* a duplicated CF is a wrong sequence number too */
    assert_int_equal(trn_isotp_encode_frame(msg, 30, 0, fr, &dlc), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, dlc, 3, &res), TRN_OK);
    assert_int_equal(trn_isotp_encode_frame(msg, 30, 1, fr, &dlc), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, dlc, 4, &res), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, dlc, 5, &res), TRN_E_SEQ);
    assert_int_equal(g_rx.err_count[TRN_ISOTP_ERR_WRONG_SN], 2);
}

static void test_rx_overflow(void **state)
{
    static uint8_t msg[101];
    trn_isotp_rx_result_t res;
    uint8_t fr[8], dlc;
    (void)state;
    rx_setup(100);
    assert_int_equal(trn_isotp_encode_frame(msg, 101, 0, fr, &dlc), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, dlc, 0, &res), TRN_E_CAPACITY);
    assert_int_equal(res.error, TRN_ISOTP_ERR_OVERFLOW);
    assert_true(res.events & TRN_ISOTP_EV_SEND_FC);
    assert_int_equal(res.fc[0], 0x32);
    assert_int_equal(g_rx.err_count[TRN_ISOTP_ERR_OVERFLOW], 1);
    assert_int_equal(g_rx.state, TRN_ISOTP_RX_IDLE);
    /* exactly the capacity is fine */
    assert_int_equal(transfer(&g_rx, msg, 100, 10, 1), 1);
}

static void test_rx_interrupted(void **state)
{
    static uint8_t msg[30];
    const uint8_t sf[3] = {0x02, 0xAB, 0xCD};
    trn_isotp_rx_result_t res;
    uint8_t fr[8], dlc;
    (void)state;
    rx_setup(100);
    assert_int_equal(trn_isotp_encode_frame(msg, 30, 0, fr, &dlc), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, dlc, 0, &res), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, sf, 3, 1, &res), TRN_E_SEQ);
    assert_int_equal(res.error, TRN_ISOTP_ERR_INTERRUPTED);
    /* the new single frame is delivered; the old message is gone */
    assert_true(res.events & TRN_ISOTP_EV_MESSAGE);
    assert_int_equal(res.msg_len, 2);
    assert_int_equal(g_buf[0], 0xAB);
    assert_int_equal(g_buf[1], 0xCD);
    assert_int_equal(g_rx.err_count[TRN_ISOTP_ERR_INTERRUPTED], 1);
    /* a new FF during a reception restarts with the new message */
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, dlc, 2, &res), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, dlc, 3, &res), TRN_E_SEQ);
    assert_true(res.events & TRN_ISOTP_EV_SEND_FC);
    assert_int_equal(g_rx.state, TRN_ISOTP_RX_RECEIVING);
    assert_int_equal(g_rx.err_count[TRN_ISOTP_ERR_INTERRUPTED], 2);
}

static void test_rx_timeouts(void **state)
{
    static uint8_t msg[30];
    trn_isotp_rx_result_t res;
    uint8_t fr[8], dlc;
    (void)state;
    rx_setup(100); /* N_Cr 100 ms */
    assert_int_equal(trn_isotp_encode_frame(msg, 30, 0, fr, &dlc), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, dlc, 1000, &res), TRN_OK);
    assert_int_equal(trn_isotp_rx_poll(&g_rx, 1100, &res), TRN_OK); /* exactly N_Cr: still fine */
    assert_int_equal(res.events, 0);
    assert_int_equal(trn_isotp_rx_poll(&g_rx, 1101, &res), TRN_E_TIMEOUT);
    assert_int_equal(res.error, TRN_ISOTP_ERR_TIMEOUT_CR);
    assert_int_equal(g_rx.state, TRN_ISOTP_RX_IDLE);
    assert_int_equal(trn_isotp_rx_poll(&g_rx, 5000, &res), TRN_OK); /* idle never times out */
    /* a late CF: timeout first, then the CF is unexpected */
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, dlc, 2000, &res), TRN_OK);
    assert_int_equal(trn_isotp_encode_frame(msg, 30, 1, fr, &dlc), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, dlc, 2200, &res), TRN_E_TIMEOUT);
    assert_int_equal(g_rx.err_count[TRN_ISOTP_ERR_TIMEOUT_CR], 2);
    assert_int_equal(g_rx.err_count[TRN_ISOTP_ERR_UNEXPECTED_CF], 1);
    /* the clock wraps: 0xFFFFFFF0 -> 0x10 is 32 ms, no timeout */
    assert_int_equal(transfer(&g_rx, msg, 30, 0xFFFFFFF0u, 8), 1);
    assert_int_equal(g_rx.err_count[TRN_ISOTP_ERR_TIMEOUT_CR], 2);
}

static void test_rx_short_cf_fc_bad_frame(void **state)
{
    static uint8_t msg[30];
    const uint8_t fc[3] = {0x30, 0, 0};
    const uint8_t bad[2] = {0x50, 0};
    trn_isotp_rx_result_t res;
    uint8_t fr[8], dlc;
    (void)state;
    rx_setup(100);
    assert_int_equal(trn_isotp_encode_frame(msg, 30, 0, fr, &dlc), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, dlc, 0, &res), TRN_OK);
    assert_int_equal(trn_isotp_encode_frame(msg, 30, 1, fr, &dlc), TRN_OK);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fr, 5, 1, &res), TRN_E_FORMAT); /* CF 1 cut short */
    assert_int_equal(res.error, TRN_ISOTP_ERR_SHORT_CF);
    assert_int_equal(g_rx.state, TRN_ISOTP_RX_IDLE);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, fc, 3, 2, &res), TRN_E_FORMAT);
    assert_int_equal(res.error, TRN_ISOTP_ERR_UNEXPECTED_FC);
    assert_int_equal(trn_isotp_rx_frame(&g_rx, bad, 2, 3, &res), TRN_E_FORMAT);
    assert_int_equal(res.error, TRN_ISOTP_ERR_BAD_FRAME);
    assert_int_equal(g_rx.err_count[TRN_ISOTP_ERR_SHORT_CF], 1);
    assert_int_equal(g_rx.err_count[TRN_ISOTP_ERR_UNEXPECTED_FC], 1);
    assert_int_equal(g_rx.err_count[TRN_ISOTP_ERR_BAD_FRAME], 1);
    assert_int_equal(g_rx.n_messages, 0);
}


/* Robustness: random frames (any DLC, any bytes) interleaved with real
 * transfers. The receiver never reads or writes outside its buffer (ASan),
 * and every message it reports is either the real one, complete, or began
 * with a noise SF/FF (ISO-TP cannot tell noise CFs that fit; the capture
 * CRC does). 20000 frames, seeded. */
static void test_rx_random_noise(void **state)
{
    static uint8_t msg[600];
    trn_isotp_rx_t rx;
    trn_rng_t r;
    uint32_t now = 0;
    int i, sent_ok = 0, got_real = 0, noise_sf = 0, start_noise = 0;
    (void)state;
    trn_rng_seed(&r, 99);
    for (i = 0; i < (int)sizeof msg; ++i) {
        msg[i] = (uint8_t)trn_rng_u64(&r);
    }
    assert_int_equal(trn_isotp_rx_init(&rx, g_buf, 300, 0, 0, 50), TRN_OK);
    for (i = 0; i < 20000; ++i) {
        trn_isotp_rx_result_t res;
        uint8_t fr[8], dlc;
        int k, from_noise = trn_rng_int(&r, 0, 3) == 0;
        now += (uint32_t)trn_rng_int(&r, 0, 20);
        if (from_noise) {
            dlc = (uint8_t)trn_rng_int(&r, 0, 8);
            for (k = 0; k < 8; ++k) {
                fr[k] = (uint8_t)trn_rng_u64(&r);
            }
        } else {
            /* the next frame of a 200-byte message, over and over */
            uint16_t idx = (uint16_t)(sent_ok % trn_isotp_frame_count(200));
            assert_int_equal(trn_isotp_encode_frame(msg, 200, idx, fr, &dlc), TRN_OK);
            ++sent_ok;
        }
        {
            trn_isotp_frame_t info;
            if (trn_isotp_decode(fr, dlc, &info) == TRN_OK &&
                (info.type == TRN_ISOTP_SF || info.type == TRN_ISOTP_FF)) {
                start_noise = from_noise;
            }
        }
        (void)trn_isotp_rx_frame(&rx, fr, dlc, now, &res);
        assert_true(rx.got <= rx.cap);
        if (res.events & TRN_ISOTP_EV_MESSAGE) {
            assert_true(res.msg_len >= 1 && res.msg_len <= rx.cap);
            if (res.msg_len == 200 && memcmp(g_buf, msg, 200) == 0) {
                ++got_real;
            } else {
                /* anything else began with a noise SF or FF */
                assert_true(start_noise);
                if (res.msg_len <= 7 && from_noise) {
                    assert_memory_equal(g_buf, fr + 1, res.msg_len);
                }
                ++noise_sf;
            }
        }
    }
    print_message("noise: %d real messages, %d from noise, %u wrong SN, %u bad frames\n", got_real,
                  noise_sf, rx.err_count[TRN_ISOTP_ERR_WRONG_SN],
                  rx.err_count[TRN_ISOTP_ERR_BAD_FRAME]);
    assert_true(got_real > 0);
}

/* ---- sender ------------------------------------------------------------------ */

/* Sender -> receiver loopback on a simulated clock: the sender is stepped at
 * its wake times, every frame reaches the receiver 50 us later, every FC the
 * receiver asks for reaches the sender 50 us after that. Returns the number
 * of frames; checks STmin between consecutive CFs of a block. */
static int loopback(const uint8_t *msg, size_t len, uint8_t bs, uint8_t stmin, uint32_t *t_end)
{
    static uint8_t rbuf[TRN_ISOTP_MAX_MSG];
    trn_isotp_tx_t tx;
    trn_isotp_rx_t rx;
    uint32_t now = 1000, last_cf = 0, stmin_us = trn_isotp_stmin_us(stmin);
    int frames = 0, guard, after_fc = 1, done = 0;
    assert_int_equal(trn_isotp_tx_init(&tx, 1000, 0), TRN_OK);
    assert_int_equal(trn_isotp_rx_init(&rx, rbuf, sizeof rbuf, bs, stmin, 1000), TRN_OK);
    assert_int_equal(trn_isotp_tx_start(&tx, msg, len), TRN_OK);
    for (guard = 0; guard < 100000 && !done; ++guard) {
        trn_isotp_tx_result_t tr;
        trn_isotp_rx_result_t rr;
        assert_int_equal(trn_isotp_tx_step(&tx, now, &tr), TRN_OK);
        if (!(tr.events & TRN_ISOTP_TX_EV_FRAME)) {
            assert_true(tr.wake_us > now || tx.state == TRN_ISOTP_TX_WAIT_FC);
            now = tr.wake_us > now ? tr.wake_us : now + 1;
            continue;
        }
        ++frames;
        if ((tr.frame[0] >> 4) == TRN_ISOTP_CF) {
            if (!after_fc) {
                assert_true(now - last_cf >= stmin_us); /* STmin honoured */
            }
            last_cf = now;
            after_fc = 0;
        }
        now += 50;
        assert_int_equal(trn_isotp_rx_frame(&rx, tr.frame, tr.dlc, now / 1000, &rr), TRN_OK);
        if (rr.events & TRN_ISOTP_EV_MESSAGE) {
            assert_true(tr.events & TRN_ISOTP_TX_EV_DONE);
            assert_int_equal(rr.msg_len, len);
            assert_memory_equal(rbuf, msg, len);
            done = 1;
        }
        if (rr.events & TRN_ISOTP_EV_SEND_FC) {
            now += 50;
            assert_int_equal(trn_isotp_tx_fc(&tx, rr.fc, rr.fc_dlc, now, &tr), TRN_OK);
            after_fc = 1;
        }
    }
    assert_true(done);
    assert_int_equal(tx.n_messages, 1);
    assert_int_equal(tx.state, TRN_ISOTP_TX_IDLE);
    *t_end = now;
    return frames;
}

static void test_tx_loopback(void **state)
{
    static uint8_t msg[TRN_ISOTP_MAX_MSG];
    const size_t lens[] = {1, 7, 8, 13, 14, 100, 1000, 4095};
    size_t i;
    uint32_t t_end;
    (void)state;
    for (i = 0; i < sizeof msg; ++i) {
        msg[i] = (uint8_t)(i * 7 + 3);
    }
    for (i = 0; i < sizeof lens / sizeof lens[0]; ++i) {
        assert_int_equal(loopback(msg, lens[i], 0, 0, &t_end), trn_isotp_frame_count(lens[i]));
        assert_int_equal(loopback(msg, lens[i], 3, 0x02, &t_end), trn_isotp_frame_count(lens[i]));
        assert_int_equal(loopback(msg, lens[i], 1, 0xF5, &t_end), trn_isotp_frame_count(lens[i]));
    }
    /* 100 bytes = FF + 14 CFs; BS 0, STmin 10 ms: 13 gaps of >= 10 ms */
    loopback(msg, 100, 0, 10, &t_end);
    assert_true(t_end - 1000 >= 13 * 10000);
    assert_true(t_end - 1000 < 13 * 10000 + 16 * 200);
}

static void test_tx_timeout_bs(void **state)
{
    static uint8_t msg[20];
    trn_isotp_tx_t tx;
    trn_isotp_tx_result_t r;
    (void)state;
    assert_int_equal(trn_isotp_tx_init(&tx, 1000, 0), TRN_OK);
    assert_int_equal(trn_isotp_tx_start(&tx, msg, 20), TRN_OK);
    assert_int_equal(trn_isotp_tx_step(&tx, 0xFFFFFF00u, &r), TRN_OK); /* FF, near the clock wrap */
    assert_true(r.events & TRN_ISOTP_TX_EV_FRAME);
    assert_int_equal(r.frame[0], 0x10);
    assert_int_equal(tx.state, TRN_ISOTP_TX_WAIT_FC);
    assert_int_equal(trn_isotp_tx_step(&tx, 0xFFFFFF00u + 1000000u, &r), TRN_OK); /* exactly N_Bs */
    assert_int_equal(r.events, 0);
    assert_int_equal(r.wake_us, 0xFFFFFF00u + 1000001u);
    assert_int_equal(trn_isotp_tx_step(&tx, 0xFFFFFF00u + 1000001u, &r), TRN_E_TIMEOUT);
    assert_int_equal(r.error, TRN_ISOTP_TX_ERR_TIMEOUT_BS);
    assert_int_equal(tx.err_count[TRN_ISOTP_TX_ERR_TIMEOUT_BS], 1);
    assert_int_equal(tx.state, TRN_ISOTP_TX_IDLE);
    assert_int_equal(tx.n_messages, 0);
    assert_int_equal(trn_isotp_tx_step(&tx, 5, &r), TRN_OK); /* idle: nothing */
    assert_int_equal(r.events, 0);
}

static void test_tx_fc_errors(void **state)
{
    static uint8_t msg[40];
    const uint8_t wait[3] = {0x31, 0, 0}, ovf[3] = {0x32, 0, 0}, bad[3] = {0x34, 0, 0},
                  cts[3] = {0x30, 0, 0};
    const uint8_t sf[2] = {0x01, 0x55};
    trn_isotp_tx_t tx;
    trn_isotp_tx_result_t r;
    (void)state;
    assert_int_equal(trn_isotp_tx_init(&tx, 100, 2), TRN_OK);
    /* two WAITs are fine (each restarts N_Bs), the third is one too many */
    assert_int_equal(trn_isotp_tx_start(&tx, msg, 40), TRN_OK);
    assert_int_equal(trn_isotp_tx_step(&tx, 0, &r), TRN_OK);
    assert_int_equal(trn_isotp_tx_fc(&tx, wait, 3, 90000, &r), TRN_OK);
    assert_int_equal(trn_isotp_tx_step(&tx, 180000, &r),
                     TRN_OK); /* 90 ms after the WAIT: no timeout */
    assert_int_equal(r.events, 0);
    assert_int_equal(trn_isotp_tx_fc(&tx, wait, 3, 180000, &r), TRN_OK);
    assert_int_equal(trn_isotp_tx_fc(&tx, wait, 3, 190000, &r), TRN_E_SEQ);
    assert_int_equal(r.error, TRN_ISOTP_TX_ERR_WFT_OVERRUN);
    assert_int_equal(tx.state, TRN_ISOTP_TX_IDLE);
    /* a CTS resets the WAIT count */
    assert_int_equal(trn_isotp_tx_start(&tx, msg, 40), TRN_OK);
    assert_int_equal(trn_isotp_tx_step(&tx, 0, &r), TRN_OK);
    assert_int_equal(trn_isotp_tx_fc(&tx, wait, 3, 1, &r), TRN_OK);
    assert_int_equal(trn_isotp_tx_fc(&tx, wait, 3, 2, &r), TRN_OK);
    assert_int_equal(trn_isotp_tx_fc(&tx, cts, 3, 3, &r), TRN_OK);
    assert_int_equal(tx.wft, 0);
    assert_int_equal(tx.state, TRN_ISOTP_TX_SENDING);
    /* FC while sending is unexpected and ignored */
    assert_int_equal(trn_isotp_tx_fc(&tx, cts, 3, 4, &r), TRN_E_FORMAT);
    assert_int_equal(r.error, TRN_ISOTP_TX_ERR_UNEXPECTED_FC);
    assert_int_equal(tx.state, TRN_ISOTP_TX_SENDING);
    /* overflow */
    assert_int_equal(trn_isotp_tx_start(&tx, msg, 40), TRN_OK);
    assert_int_equal(trn_isotp_tx_step(&tx, 0, &r), TRN_OK);
    assert_int_equal(trn_isotp_tx_fc(&tx, ovf, 3, 1, &r), TRN_E_CAPACITY);
    assert_int_equal(r.error, TRN_ISOTP_TX_ERR_OVERFLOW);
    assert_int_equal(tx.state, TRN_ISOTP_TX_IDLE);
    /* invalid flow status, short FC, a non-FC frame */
    assert_int_equal(trn_isotp_tx_start(&tx, msg, 40), TRN_OK);
    assert_int_equal(trn_isotp_tx_step(&tx, 0, &r), TRN_OK);
    assert_int_equal(trn_isotp_tx_fc(&tx, bad, 3, 1, &r), TRN_E_FORMAT);
    assert_int_equal(r.error, TRN_ISOTP_TX_ERR_INVALID_FC);
    assert_int_equal(tx.state, TRN_ISOTP_TX_IDLE);
    assert_int_equal(trn_isotp_tx_start(&tx, msg, 40), TRN_OK);
    assert_int_equal(trn_isotp_tx_step(&tx, 0, &r), TRN_OK);
    assert_int_equal(trn_isotp_tx_fc(&tx, cts, 2, 1, &r), TRN_E_FORMAT);
    assert_int_equal(trn_isotp_tx_start(&tx, msg, 40), TRN_OK);
    assert_int_equal(trn_isotp_tx_step(&tx, 0, &r), TRN_OK);
    assert_int_equal(trn_isotp_tx_fc(&tx, sf, 2, 1, &r), TRN_E_FORMAT);
    assert_int_equal(tx.err_count[TRN_ISOTP_TX_ERR_INVALID_FC], 3);
    assert_int_equal(tx.err_count[TRN_ISOTP_TX_ERR_OVERFLOW], 1);
    assert_int_equal(tx.err_count[TRN_ISOTP_TX_ERR_WFT_OVERRUN], 1);
    assert_int_equal(tx.err_count[TRN_ISOTP_TX_ERR_UNEXPECTED_FC], 1);
    assert_int_equal(tx.n_messages, 0);
    /* arguments */
    assert_int_equal(trn_isotp_tx_init(NULL, 100, 0), TRN_E_NULL);
    assert_int_equal(trn_isotp_tx_init(&tx, 0, 0), TRN_E_ARG);
    assert_int_equal(trn_isotp_tx_init(&tx, 60001, 0), TRN_E_ARG);
    assert_int_equal(trn_isotp_tx_start(NULL, msg, 4), TRN_E_NULL);
    assert_int_equal(trn_isotp_tx_start(&tx, NULL, 4), TRN_E_NULL);
    assert_int_equal(trn_isotp_tx_start(&tx, msg, 0), TRN_E_SIZE);
    assert_int_equal(trn_isotp_tx_start(&tx, msg, 4096), TRN_E_SIZE);
    assert_int_equal(trn_isotp_tx_step(NULL, 0, &r), TRN_E_NULL);
    assert_int_equal(trn_isotp_tx_step(&tx, 0, NULL), TRN_E_NULL);
    assert_int_equal(trn_isotp_tx_fc(NULL, cts, 3, 0, &r), TRN_E_NULL);
    assert_int_equal(trn_isotp_tx_fc(&tx, NULL, 3, 0, &r), TRN_E_NULL);
    assert_int_equal(trn_isotp_tx_fc(&tx, cts, 3, 0, NULL), TRN_E_NULL);
    assert_int_equal(trn_isotp_tx_fc(&tx, cts, 9, 0, &r), TRN_E_ARG);
    assert_string_equal(trn_isotp_tx_err_name(TRN_ISOTP_TX_ERR_WFT_OVERRUN), "WFT_OVERRUN");
    assert_string_equal(trn_isotp_tx_err_name(TRN_ISOTP_TX_ERR_COUNT), "UNKNOWN");
}

static void test_tx_block_pacing(void **state)
{
    /* BS 2: FF, FC, CF1, CF2, (wait FC), CF3 ... the sender stops after each block */
    static uint8_t msg[30]; /* FF + 4 CFs */
    const uint8_t cts[3] = {0x30, 2, 0x05};
    trn_isotp_tx_t tx;
    trn_isotp_tx_result_t r;
    (void)state;
    assert_int_equal(trn_isotp_tx_init(&tx, 1000, 0), TRN_OK);
    assert_int_equal(trn_isotp_tx_start(&tx, msg, 30), TRN_OK);
    assert_int_equal(trn_isotp_tx_step(&tx, 0, &r), TRN_OK);
    assert_int_equal(trn_isotp_tx_fc(&tx, cts, 3, 100, &r), TRN_OK);
    assert_int_equal(trn_isotp_tx_step(&tx, 100, &r), TRN_OK); /* CF1 at once after the FC */
    assert_int_equal(r.frame[0], 0x21);
    assert_int_equal(trn_isotp_tx_step(&tx, 5099, &r), TRN_OK); /* STmin 5 ms not over */
    assert_int_equal(r.events, 0);
    assert_int_equal(r.wake_us, 5100);
    assert_int_equal(trn_isotp_tx_step(&tx, 5100, &r), TRN_OK);
    assert_int_equal(r.frame[0], 0x22);
    assert_int_equal(tx.state, TRN_ISOTP_TX_WAIT_FC); /* block of 2 done */
    assert_int_equal(trn_isotp_tx_step(&tx, 20000, &r), TRN_OK);
    assert_int_equal(r.events, 0);
    assert_int_equal(trn_isotp_tx_fc(&tx, cts, 3, 20000, &r), TRN_OK);
    assert_int_equal(trn_isotp_tx_step(&tx, 20000, &r), TRN_OK);
    assert_int_equal(r.frame[0], 0x23);
    assert_int_equal(trn_isotp_tx_step(&tx, 25000, &r), TRN_OK);
    assert_int_equal(r.frame[0], 0x24);
    assert_true(r.events & TRN_ISOTP_TX_EV_DONE);
    assert_int_equal(r.dlc, 1 + (30 - 6 - 21));
    assert_int_equal(tx.state, TRN_ISOTP_TX_IDLE);
    assert_int_equal(tx.n_messages, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_decode_hand_frames),
        cmocka_unit_test(test_decode_rejects),
        cmocka_unit_test(test_frame_count),
        cmocka_unit_test(test_encode_hand_frames),
        cmocka_unit_test(test_stmin),
        cmocka_unit_test(test_rx_init_args),
        cmocka_unit_test(test_rx_round_trip_all_lengths),
        cmocka_unit_test(test_rx_block_size),
        cmocka_unit_test(test_rx_wrong_sn),
        cmocka_unit_test(test_rx_overflow),
        cmocka_unit_test(test_rx_interrupted),
        cmocka_unit_test(test_rx_timeouts),
        cmocka_unit_test(test_rx_short_cf_fc_bad_frame),
        cmocka_unit_test(test_rx_random_noise),
        cmocka_unit_test(test_tx_loopback),
        cmocka_unit_test(test_tx_timeout_bs),
        cmocka_unit_test(test_tx_fc_errors),
        cmocka_unit_test(test_tx_block_pacing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
