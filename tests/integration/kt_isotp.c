/* SPDX-License-Identifier: Apache-2.0 */
/*
 * kt_isotp.c - ISO-TP port on the kernel's can-isotp over vcan, run in the VM.
 *
 * Round trips of long messages between two port sockets, and faults the
 * kernel detects, each ending in its named status with nothing partial
 * delivered: a wrong consecutive-frame sequence number (TRN_E_SEQ), a sender
 * that stops mid-message (TRN_E_TIMEOUT), no flow control from the peer
 * (TRN_E_TIMEOUT), a flow control saying overflow (TRN_E_CAPACITY), and a
 * message longer than the caller's buffer (TRN_E_CAPACITY). Faulty peers are
 * played by a raw socket of the port.
 */
#include <stdint.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "ktest.h"
#include "trn_port/linux_can.h"

static const char *ifname;
static uint8_t tx_buf[TRN_LISOTP_MAX_MSG];
static uint8_t rx_buf[TRN_LISOTP_MAX_MSG];

static void fill(uint8_t *p, size_t n, uint32_t seed)
{
    size_t i;
    uint32_t s = seed * 2654435761u + 1u;
    for (i = 0; i < n; ++i) {
        s = s * 1664525u + 1013904223u;
        p[i] = (uint8_t)(s >> 24);
    }
}

static trn_lisotp_cfg_t tp_cfg(uint32_t tx, uint32_t rx, uint8_t ext)
{
    trn_lisotp_cfg_t c;
    trn_lisotp_cfg_default(&c);
    c.ifname = ifname;
    c.tx_id = tx;
    c.rx_id = rx;
    c.extended = ext;
    return c;
}

static void raw_open(trn_lcan_t *r, const trn_lcan_filter_t *f)
{
    trn_lcan_cfg_t c;
    trn_lcan_cfg_default(&c);
    c.ifname = ifname;
    c.filters = f;
    c.n_filters = f != NULL ? 1u : 0u;
    KT_ST(trn_lcan_open(r, &c), TRN_OK);
}

static trn_lcan_frame_t frame8(uint32_t id, const uint8_t d[8])
{
    trn_lcan_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.len = 8u;
    memcpy(f.data, d, 8u);
    return f;
}

static void round_trip(size_t len, uint8_t ext, uint8_t bs, uint8_t stmin, uint32_t seed)
{
    uint32_t ida = ext ? 0x18DA10F1u : 0x7E0u;
    uint32_t idb = ext ? 0x18DAF110u : 0x7E8u;
    trn_lisotp_cfg_t ca = tp_cfg(ida, idb, ext);
    trn_lisotp_cfg_t cb = tp_cfg(idb, ida, ext);
    trn_lisotp_t a, b;
    size_t got = 0u;

    cb.block_size = bs;
    cb.stmin = stmin;
    KT_ST(trn_lisotp_open(&a, &ca), TRN_OK);
    KT_ST(trn_lisotp_open(&b, &cb), TRN_OK);
    fill(tx_buf, len, seed);
    memset(rx_buf, 0, sizeof rx_buf);
    /* The kernel of b answers flow control by itself; a's send returns when done. */
    KT_ST(trn_lisotp_send(&a, tx_buf, len, 20000), TRN_OK);
    KT_ST(trn_lisotp_recv(&b, rx_buf, sizeof rx_buf, &got, 5000), TRN_OK);
    KT_CHECK(got == len);
    KT_CHECK(memcmp(tx_buf, rx_buf, len) == 0);
    /* and back */
    fill(tx_buf, 7u, seed + 1u);
    KT_ST(trn_lisotp_send(&b, tx_buf, 7u, 5000), TRN_OK);
    KT_ST(trn_lisotp_recv(&a, rx_buf, sizeof rx_buf, &got, 5000), TRN_OK);
    KT_CHECK(got == 7u && memcmp(tx_buf, rx_buf, 7u) == 0);
    KT_ST(trn_lisotp_recv(&b, rx_buf, sizeof rx_buf, &got, 0), TRN_E_TIMEOUT);
    trn_lisotp_close(&a);
    trn_lisotp_close(&b);
}

static void round_trip_10k(void) { round_trip(10000u, 0u, 0u, 0u, 1u); }

static void round_trip_extended_ids_with_blocks(void) { round_trip(4095u, 1u, 8u, 0u, 2u); }

static void round_trip_single_frame(void) { round_trip(7u, 0u, 0u, 0u, 3u); }

static void receive_timeout_and_sizes(void)
{
    trn_lisotp_cfg_t c = tp_cfg(0x7E0u, 0x7E8u, 0u);
    trn_lisotp_t a;
    size_t got = 0u;
    long long t0;
    KT_ST(trn_lisotp_open(&a, &c), TRN_OK);
    t0 = kt_now_ms();
    KT_ST(trn_lisotp_recv(&a, rx_buf, sizeof rx_buf, &got, 120), TRN_E_TIMEOUT);
    KT_CHECK(kt_now_ms() - t0 >= 120);
    KT_ST(trn_lisotp_send(&a, tx_buf, 0u, 10), TRN_E_SIZE);
    KT_ST(trn_lisotp_send(&a, tx_buf, TRN_LISOTP_MAX_MSG + 1u, 10), TRN_E_SIZE);
    KT_ST(trn_lisotp_recv(&a, rx_buf, 0u, &got, 10), TRN_E_SIZE);
    trn_lisotp_close(&a);
    KT_ST(trn_lisotp_send(&a, tx_buf, 1u, 10), TRN_E_ARG);
    c.ifname = "nosuchcan9";
    KT_ST(trn_lisotp_open(&a, &c), TRN_E_BUS);
}

/* A message longer than the buffer is refused whole, buffer untouched, and gone. */
static void too_long_for_buffer(void)
{
    trn_lisotp_cfg_t ca = tp_cfg(0x710u, 0x718u, 0u);
    trn_lisotp_cfg_t cb = tp_cfg(0x718u, 0x710u, 0u);
    trn_lisotp_t a, b;
    uint8_t small[100];
    size_t got = 0u;
    size_t i;
    int untouched = 1;
    KT_ST(trn_lisotp_open(&a, &ca), TRN_OK);
    KT_ST(trn_lisotp_open(&b, &cb), TRN_OK);
    fill(tx_buf, 1000u, 5u);
    memset(small, 0xEE, sizeof small);
    KT_ST(trn_lisotp_send(&a, tx_buf, 1000u, 5000), TRN_OK);
    KT_ST(trn_lisotp_recv(&b, small, sizeof small, &got, 5000), TRN_E_CAPACITY);
    KT_CHECK(got == 1000u);
    for (i = 0; i < sizeof small; ++i) {
        untouched = untouched && small[i] == 0xEE;
    }
    KT_CHECK(untouched);
    KT_ST(trn_lisotp_recv(&b, small, sizeof small, &got, 100), TRN_E_TIMEOUT);
    trn_lisotp_close(&a);
    trn_lisotp_close(&b);
}

/* A raw peer sends a first frame, reads our flow control, then a consecutive
 * frame with the wrong sequence number. */
static void wrong_sequence_number(void)
{
    trn_lisotp_cfg_t cb = tp_cfg(0x728u, 0x720u, 0u);
    trn_lcan_filter_t fc_only = {0x728u, 0x7FFu, 0u};
    trn_lisotp_t b;
    trn_lcan_t raw;
    trn_lcan_frame_t f;
    uint8_t ff[8] = {0x10, 20, 1, 2, 3, 4, 5, 6};
    uint8_t cf_bad[8] = {0x22, 7, 8, 9, 10, 11, 12, 13}; /* SN 2, expected 1 */
    size_t got = 0u;
    KT_ST(trn_lisotp_open(&b, &cb), TRN_OK);
    raw_open(&raw, &fc_only);
    f = frame8(0x720u, ff);
    KT_ST(trn_lcan_send(&raw, &f, 100), TRN_OK);
    KT_ST(trn_lcan_recv(&raw, &f, 2000), TRN_OK); /* b's flow control */
    KT_CHECK(f.id == 0x728u && (f.data[0] & 0xF0u) == 0x30u);
    f = frame8(0x720u, cf_bad);
    KT_ST(trn_lcan_send(&raw, &f, 100), TRN_OK);
    KT_ST(trn_lisotp_recv(&b, rx_buf, sizeof rx_buf, &got, 3000), TRN_E_SEQ);
    KT_ST(trn_lisotp_recv(&b, rx_buf, sizeof rx_buf, &got, 100), TRN_E_TIMEOUT);
    trn_lcan_close(&raw);
    trn_lisotp_close(&b);
}

/* A raw peer sends a first frame and then nothing: the kernel's N_Cr (1 s). */
static void sender_stops_mid_message(void)
{
    trn_lisotp_cfg_t cb = tp_cfg(0x738u, 0x730u, 0u);
    trn_lisotp_t b;
    trn_lcan_t raw;
    trn_lcan_frame_t f;
    uint8_t ff[8] = {0x10, 20, 1, 2, 3, 4, 5, 6};
    size_t got = 0u;
    long long t0;
    KT_ST(trn_lisotp_open(&b, &cb), TRN_OK);
    raw_open(&raw, NULL);
    f = frame8(0x730u, ff);
    KT_ST(trn_lcan_send(&raw, &f, 100), TRN_OK);
    t0 = kt_now_ms();
    KT_ST(trn_lisotp_recv(&b, rx_buf, sizeof rx_buf, &got, 5000), TRN_E_TIMEOUT);
    /* ended by the kernel's timer, well before our own 5 s */
    KT_CHECK(kt_now_ms() - t0 < 4500);
    KT_ST(trn_lisotp_recv(&b, rx_buf, sizeof rx_buf, &got, 100), TRN_E_TIMEOUT);
    trn_lcan_close(&raw);
    trn_lisotp_close(&b);
}

/* Nobody answers our first frame: the kernel's N_Bs (1 s) fails the send. */
static void no_flow_control(void)
{
    trn_lisotp_cfg_t ca = tp_cfg(0x740u, 0x748u, 0u);
    trn_lisotp_t a;
    long long t0;
    KT_ST(trn_lisotp_open(&a, &ca), TRN_OK);
    fill(tx_buf, 100u, 7u);
    t0 = kt_now_ms();
    KT_ST(trn_lisotp_send(&a, tx_buf, 100u, 5000), TRN_E_TIMEOUT);
    KT_CHECK(kt_now_ms() - t0 < 4500);
    trn_lisotp_close(&a);
}

/* The peer answers with flow status "overflow". The raw peer runs in a child
 * process while our send waits. */
static void flow_control_overflow(void)
{
    trn_lisotp_cfg_t ca = tp_cfg(0x750u, 0x758u, 0u);
    trn_lcan_filter_t ff_only = {0x750u, 0x7FFu, 0u};
    trn_lisotp_t a;
    trn_lcan_t raw;
    pid_t pid;
    int wst = 0;
    raw_open(&raw, &ff_only);
    KT_ST(trn_lisotp_open(&a, &ca), TRN_OK);
    pid = fork();
    if (pid == 0) {
        trn_lcan_frame_t f;
        uint8_t fc[8] = {0x32, 0, 0, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC};
        int ok = trn_lcan_recv(&raw, &f, 3000) == TRN_OK && (f.data[0] & 0xF0u) == 0x10u;
        f = frame8(0x758u, fc);
        ok = ok && trn_lcan_send(&raw, &f, 100) == TRN_OK;
        _exit(ok ? 0 : 1);
    }
    fill(tx_buf, 100u, 8u);
    KT_ST(trn_lisotp_send(&a, tx_buf, 100u, 5000), TRN_E_CAPACITY);
    KT_CHECK(pid > 0 && waitpid(pid, &wst, 0) == pid && WIFEXITED(wst) && WEXITSTATUS(wst) == 0);
    trn_lcan_close(&raw);
    trn_lisotp_close(&a);
}

int main(void)
{
    ifname = kt_env("TRN_CAN_IF", "vcan0");
    KT_RUN(round_trip_10k);
    KT_RUN(round_trip_extended_ids_with_blocks);
    KT_RUN(round_trip_single_frame);
    KT_RUN(receive_timeout_and_sizes);
    KT_RUN(too_long_for_buffer);
    KT_RUN(wrong_sequence_number);
    KT_RUN(sender_stops_mid_message);
    KT_RUN(no_flow_control);
    KT_RUN(flow_control_overflow);
    return kt_finish("kt_isotp");
}
