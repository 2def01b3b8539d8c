/* SPDX-License-Identifier: Apache-2.0 */
/* fuzz_isotp.c - the ISO-TP frame decoder and the receiver and sender state
 * machines of port/proto (isotp.h), frames and times from the input.
 *
 * Input: receiver configuration (cap, bs, stmin, N_Cr), then up to 64
 * operations, each one selector byte:
 *   0 raw frame: dlc, 8 bytes, time step -> trn_isotp_decode + trn_isotp_rx_frame
 *   1 poll: time step -> trn_isotp_rx_poll
 *   2 message: length, fill seed, time step per frame; every frame of a
 *     sender (trn_isotp_encode_frame) into the receiver, in order
 *   3 loopback: length, seed, bs/stmin of a second receiver, per-step delays;
 *     trn_isotp_tx_* feeds a second receiver, its flow control goes back
 * (at most 4 operations 2 and 3 per input, so an execution stays short)
 * Invariants:
 * - decode: TRN_OK fields match the PCI rules of isotp.h; an SF and an FC
 *   re-encode to the same bytes; other statuses only TRN_E_FORMAT / TRN_E_ARG;
 * - receiver: only documented statuses; got <= msg_len <= cap while
 *   receiving; idle otherwise; a MESSAGE event has 1..cap bytes and
 *   n_messages counts exactly the MESSAGE events; SEND_FC gives a 3-byte FC
 *   that decodes;
 * - op 2: a message that fits and whose frames come within N_Cr is delivered
 *   whole and equal; one that does not fit is refused with an overflow FC;
 * - op 3: whatever the receiver delivers equals the message sent (no
 *   partial or mixed message), and with delays below both timeouts both
 *   sides finish.
 */
#include <stdlib.h>
#include <string.h>

#include "fuzz_input.h"
#include "trn_port/isotp.h"

#define FZ_CHECK(c) \
    do { \
        if (!(c)) { \
            abort(); \
        } \
    } while (0)
#define MAX_OPS 64
/* whole messages (ops 2 and 3) per input: up to 586 frames each */
#define MAX_MSGS 4

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static uint8_t rxbuf[TRN_ISOTP_MAX_MSG];
static uint8_t rxbuf2[TRN_ISOTP_MAX_MSG];
static uint8_t msg[TRN_ISOTP_MAX_MSG];
static uint32_t n_events_msg;

static void fill(uint8_t *m, size_t len, uint8_t seed)
{
    size_t i;
    for (i = 0; i < len; ++i) {
        m[i] = (uint8_t)(seed + 31u * (uint8_t)i + (uint8_t)(i >> 8));
    }
}

static void check_decode(const uint8_t *d, uint8_t dlc)
{
    trn_isotp_frame_t fr;
    trn_status_t st;
    uint8_t out[8], odlc = 0;
    memset(&fr, 0xA5, sizeof fr);
    st = trn_isotp_decode(d, dlc, &fr);
    if (dlc > 8u) {
        FZ_CHECK(st == TRN_E_ARG);
        return;
    }
    FZ_CHECK(st == TRN_OK || st == TRN_E_FORMAT);
    if (st != TRN_OK) {
        return;
    }
    FZ_CHECK(dlc >= 1u && fr.type == (uint8_t)(d[0] >> 4));
    switch (fr.type) {
    case TRN_ISOTP_SF:
        FZ_CHECK(fr.msg_len >= 1u && fr.msg_len <= 7u && fr.msg_len + 1u <= dlc);
        FZ_CHECK(fr.data_off == 1u && fr.data_len == fr.msg_len);
        FZ_CHECK(trn_isotp_encode_frame(&d[1], fr.msg_len, 0u, out, &odlc) == TRN_OK);
        FZ_CHECK(odlc == fr.msg_len + 1u && memcmp(out, d, odlc) == 0);
        break;
    case TRN_ISOTP_FF:
        FZ_CHECK(dlc == 8u && fr.msg_len >= 8u && fr.msg_len <= TRN_ISOTP_MAX_MSG);
        FZ_CHECK(fr.data_off == 2u && fr.data_len == 6u);
        break;
    case TRN_ISOTP_CF:
        FZ_CHECK(dlc >= 2u && fr.sn <= 15u && fr.data_off == 1u && fr.data_len == dlc - 1u);
        break;
    case TRN_ISOTP_FC:
        FZ_CHECK(dlc >= 3u && fr.fs <= (uint8_t)TRN_ISOTP_FS_OVFLW);
        FZ_CHECK(trn_isotp_encode_fc(fr.fs, fr.bs, fr.stmin, out, &odlc) == TRN_OK);
        FZ_CHECK(odlc == 3u && memcmp(out, d, 3) == 0);
        break;
    default: FZ_CHECK(0);
    }
}

/* Invariants of a receiver after any call, and of what the call returned. */
static void check_rx(const trn_isotp_rx_t *rx, trn_status_t st, const trn_isotp_rx_result_t *res)
{
    FZ_CHECK(st == TRN_OK || st == TRN_E_FORMAT || st == TRN_E_SEQ || st == TRN_E_CAPACITY ||
             st == TRN_E_TIMEOUT);
    if (rx->state == (uint8_t)TRN_ISOTP_RX_RECEIVING) {
        FZ_CHECK(rx->got < rx->msg_len && rx->msg_len <= rx->cap && rx->next_sn <= 15u);
    } else {
        FZ_CHECK(rx->state == (uint8_t)TRN_ISOTP_RX_IDLE);
    }
    if ((res->events & TRN_ISOTP_EV_MESSAGE) != 0u) {
        FZ_CHECK(res->msg_len >= 1u && res->msg_len <= rx->cap);
        ++n_events_msg;
    }
    if ((res->events & TRN_ISOTP_EV_SEND_FC) != 0u) {
        trn_isotp_frame_t fr;
        FZ_CHECK(res->fc_dlc == 3u && trn_isotp_decode(res->fc, res->fc_dlc, &fr) == TRN_OK);
        FZ_CHECK(fr.type == (uint8_t)TRN_ISOTP_FC && fr.bs == rx->bs && fr.stmin == rx->stmin);
    }
    if ((res->events & TRN_ISOTP_EV_ERROR) != 0u) {
        FZ_CHECK(res->error > (uint8_t)TRN_ISOTP_ERR_NONE &&
                 res->error < (uint8_t)TRN_ISOTP_ERR_COUNT);
        FZ_CHECK(st != TRN_OK);
    } else {
        FZ_CHECK(st == TRN_OK);
    }
    FZ_CHECK(rx->n_messages == n_events_msg);
}

static uint8_t pick_stmin(uint8_t v)
{
    return (v & 0x80u) ? (uint8_t)(0xF1u + v % 9u) : (uint8_t)(v & 0x03u);
}

/* op 3: sender -> receiver 2 -> flow control -> sender, times from the
 * input (the sender's microsecond clock starts at 0; the receiver gets
 * t_us / 1000). "slow": some delay, or STmin, reaches a quarter of the
 * shorter timeout, so an abort is allowed; otherwise both sides must finish. */
static void loopback(fz_t *in)
{
    trn_isotp_tx_t tx;
    trn_isotp_rx_t rx;
    trn_isotp_tx_result_t tres;
    trn_isotp_rx_result_t rres;
    size_t len = 1u + (size_t)((uint16_t)(fz_u8(in) | (fz_u8(in) << 8)) % TRN_ISOTP_MAX_MSG);
    uint8_t seed = fz_u8(in), bs = fz_u8(in) % 4u, stmin = pick_stmin(fz_u8(in));
    uint32_t n_bs_ms = 1u + fz_u8(in), n_cr_ms = 1u + fz_u8(in);
    uint32_t t_us = 0u, saved_events = n_events_msg;
    uint32_t quarter_us = 1000u * (n_cr_ms < n_bs_ms ? n_cr_ms : n_bs_ms) / 4u;
    int steps, delivered = 0, done = 0, slow;
    trn_status_t st;

    slow = (n_cr_ms < 8u || n_bs_ms < 8u || trn_isotp_stmin_us(stmin) >= quarter_us) ? 1 : 0;
    fill(msg, len, seed);
    FZ_CHECK(trn_isotp_tx_init(&tx, n_bs_ms, 2u) == TRN_OK);
    FZ_CHECK(trn_isotp_rx_init(&rx, rxbuf2, TRN_ISOTP_MAX_MSG, bs, stmin, n_cr_ms) == TRN_OK);
    FZ_CHECK(trn_isotp_tx_start(&tx, msg, len) == TRN_OK);
    n_events_msg = 0u;
    for (steps = 0; steps < 4000 && !done; ++steps) {
        uint32_t delay_us = (uint32_t)fz_u8(in) * 40u; /* 0..10.2 ms per step */
        if (delay_us >= quarter_us) {
            slow = 1;
        }
        t_us += delay_us;
        st = trn_isotp_tx_step(&tx, t_us, &tres);
        FZ_CHECK(st == TRN_OK || st == TRN_E_TIMEOUT);
        if (st == TRN_E_TIMEOUT) {
            FZ_CHECK(tres.error == (uint8_t)TRN_ISOTP_TX_ERR_TIMEOUT_BS &&
                     tx.state == TRN_ISOTP_TX_IDLE);
            break; /* aborted */
        }
        if ((tres.events & TRN_ISOTP_TX_EV_FRAME) == 0u) {
            /* nothing due yet: STmin pacing jumps to the wake time */
            if (tx.state == TRN_ISOTP_TX_SENDING) {
                FZ_CHECK(tres.wake_us - t_us <= 127000u);
                t_us = tres.wake_us;
            }
            continue;
        }
        FZ_CHECK(tres.dlc >= 2u && tres.dlc <= 8u);
        st = trn_isotp_rx_frame(&rx, tres.frame, tres.dlc, t_us / 1000u, &rres);
        check_rx(&rx, st, &rres);
        if ((rres.events & TRN_ISOTP_EV_MESSAGE) != 0u) {
            /* the only message ever delivered is the one sent, whole */
            FZ_CHECK(rres.msg_len == len && memcmp(rx.buf, msg, len) == 0);
            delivered = 1;
        }
        if ((tres.events & TRN_ISOTP_TX_EV_DONE) != 0u) {
            done = 1;
        }
        if ((rres.events & TRN_ISOTP_EV_SEND_FC) != 0u) {
            uint32_t d = (uint32_t)fz_u8(in) * 40u;
            if (d >= quarter_us) {
                slow = 1;
            }
            t_us += d;
            st = trn_isotp_tx_fc(&tx, rres.fc, rres.fc_dlc, t_us, &tres);
            FZ_CHECK(st == TRN_OK || st == TRN_E_FORMAT);
        }
    }
    if (!slow) {
        FZ_CHECK(delivered && done && rx.err_count[TRN_ISOTP_ERR_TIMEOUT_CR] == 0u);
    }
    FZ_CHECK(tx.n_messages == (uint32_t)done);
    n_events_msg = saved_events;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_t in = {data, size};
    trn_isotp_rx_t rx;
    trn_isotp_rx_result_t res;
    uint32_t now_ms = (uint32_t)fz_i32(&in);
    uint16_t cap = (uint16_t)(7u + (uint16_t)(fz_u8(&in) | (fz_u8(&in) << 8)) %
                                       (TRN_ISOTP_MAX_MSG - 6u));
    uint8_t bs = fz_u8(&in) % 5u, stmin = pick_stmin(fz_u8(&in));
    uint32_t n_cr_ms = 1u + fz_u8(&in) * 4u;
    trn_status_t st;
    int op, msgs = 0;

    n_events_msg = 0u;
    FZ_CHECK(trn_isotp_rx_init(&rx, rxbuf, cap, bs, stmin, n_cr_ms) == TRN_OK);
    for (op = 0; op < MAX_OPS && in.n > 0u; ++op) {
        uint8_t sel = fz_u8(&in);
        if ((sel & 2u) != 0u && ++msgs > MAX_MSGS) {
            sel = (uint8_t)(sel & ~3u); /* a raw frame instead */
        }
        switch (sel & 3u) {
        case 0: {
            uint8_t d[8], dlc = fz_u8(&in);
            if ((sel & 4u) == 0u) {
                dlc = (uint8_t)(dlc % 9u);
            }
            fz_bytes(&in, d, sizeof d);
            now_ms += fz_u8(&in);
            check_decode(d, dlc);
            st = trn_isotp_rx_frame(&rx, d, dlc, now_ms, &res);
            if (dlc > 8u) {
                FZ_CHECK(st == TRN_E_ARG);
            } else {
                check_rx(&rx, st, &res);
            }
            break;
        }
        case 1:
            now_ms += (uint32_t)fz_u8(&in) * 8u;
            st = trn_isotp_rx_poll(&rx, now_ms, &res);
            FZ_CHECK(st == TRN_OK || st == TRN_E_TIMEOUT);
            check_rx(&rx, st, &res);
            break;
        case 2: {
            size_t len = 1u +
                         (size_t)((uint16_t)(fz_u8(&in) | (fz_u8(&in) << 8)) % TRN_ISOTP_MAX_MSG);
            uint8_t seed = fz_u8(&in), step = fz_u8(&in);
            uint16_t k, n = trn_isotp_frame_count(len);
            int delivered = 0, was_busy = rx.state == (uint8_t)TRN_ISOTP_RX_RECEIVING;
            fill(msg, len, seed);
            for (k = 0; k < n; ++k) {
                uint8_t fr[8], dlc = 0;
                FZ_CHECK(trn_isotp_encode_frame(msg, len, k, fr, &dlc) == TRN_OK);
                now_ms += step;
                st = trn_isotp_rx_frame(&rx, fr, dlc, now_ms, &res);
                check_rx(&rx, st, &res);
                if ((res.events & TRN_ISOTP_EV_MESSAGE) != 0u) {
                    FZ_CHECK(k == n - 1u && res.msg_len == len && memcmp(rx.buf, msg, len) == 0);
                    delivered = 1;
                }
                if (k == 0u && len > cap) {
                    FZ_CHECK(res.error == (uint8_t)TRN_ISOTP_ERR_OVERFLOW && res.fc[0] == 0x32u);
                }
            }
            if (len <= cap && (n == 1u || step <= n_cr_ms)) {
                FZ_CHECK(delivered);
            }
            if (len > cap) {
                FZ_CHECK(!delivered && rx.state == (uint8_t)TRN_ISOTP_RX_IDLE);
            }
            (void)was_busy;
            break;
        }
        default: loopback(&in); break;
        }
    }
    return 0;
}
