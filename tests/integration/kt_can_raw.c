/* SPDX-License-Identifier: Apache-2.0 */
/*
 * kt_can_raw.c - raw SocketCAN port against the real kernel (vcan), run in the VM.
 *
 * Interface: $TRN_CAN_IF (default vcan0), created by the VM's /init.
 * Error frames are written by a plain raw socket of this test (the port
 * itself refuses to send them): can_id | CAN_ERR_FLAG with the class bits,
 * delivered by vcan's loopback to every socket whose error mask matches.
 */
#include <errno.h>
#include <stdint.h>
#include <string.h>
#include <sys/socket.h>
#include <net/if.h>
#include <unistd.h>

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>

#include "ktest.h"
#include "trn_port/linux_can.h"

static const char *ifname;

static trn_lcan_cfg_t base_cfg(void)
{
    trn_lcan_cfg_t c;
    trn_lcan_cfg_default(&c);
    c.ifname = ifname;
    return c;
}

static trn_lcan_frame_t mk(uint32_t id, uint8_t ext, uint8_t len, uint8_t seed)
{
    trn_lcan_frame_t f;
    uint8_t i;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.extended = ext;
    f.len = len;
    for (i = 0; i < len && i < sizeof f.data; ++i) { /* len 9: the refused frame */
        f.data[i] = (uint8_t)(seed * 31u + i * 7u + 1u);
    }
    return f;
}

static int same(const trn_lcan_frame_t *a, const trn_lcan_frame_t *b)
{
    return a->id == b->id && a->extended == b->extended && a->len == b->len &&
           memcmp(a->data, b->data, a->len) == 0;
}

/* A raw socket outside the port, to write what the port must not send. */
static int plain_socket(void)
{
    struct sockaddr_can addr;
    int fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (fd < 0) {
        return -1;
    }
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)if_nametoindex(ifname);
    if (bind(fd, (struct sockaddr *)&addr, sizeof addr) != 0) {
        close(fd);
        return -1;
    }
    return fd;
}

static int write_error_frame(int fd, uint32_t cls, uint8_t d1)
{
    struct can_frame f;
    memset(&f, 0, sizeof f);
    f.can_id = CAN_ERR_FLAG | cls;
    f.can_dlc = CAN_ERR_DLC;
    f.data[1] = d1;
    return write(fd, &f, sizeof f) == (ssize_t)sizeof f ? 0 : -1;
}

static void round_trip_with_filters(void)
{
    trn_lcan_filter_t flt[2] = {{0x123u, 0x7FFu, 0u}, {0x1ABCDE00u, 0x1FFFFF00u, 1u}};
    trn_lcan_cfg_t ca = base_cfg();
    trn_lcan_cfg_t cb = base_cfg();
    trn_lcan_t a, b;
    trn_lcan_frame_t sent[5], got;
    int i;

    cb.filters = flt;
    cb.n_filters = 2u;
    KT_ST(trn_lcan_open(&a, &ca), TRN_OK);
    KT_ST(trn_lcan_open(&b, &cb), TRN_OK);

    sent[0] = mk(0x100u, 0u, 8u, 1u);      /* filtered out: other id */
    sent[1] = mk(0x123u, 0u, 8u, 2u);      /* passes */
    sent[2] = mk(0x123u, 1u, 3u, 3u);      /* extended 0x123: wrong format */
    sent[3] = mk(0x1ABCDE42u, 1u, 5u, 4u); /* passes the extended filter */
    sent[4] = mk(0x124u, 0u, 0u, 5u);      /* filtered out, empty frame */
    for (i = 0; i < 5; ++i) {
        KT_ST(trn_lcan_send(&a, &sent[i], 100), TRN_OK);
    }
    KT_ST(trn_lcan_recv(&b, &got, 1000), TRN_OK);
    KT_CHECK(same(&got, &sent[1]));
    KT_ST(trn_lcan_recv(&b, &got, 1000), TRN_OK);
    KT_CHECK(same(&got, &sent[3]));
    KT_ST(trn_lcan_recv(&b, &got, 50), TRN_E_TIMEOUT);

    /* a has no filter: it hears b, but not itself (recv_own off). */
    KT_ST(trn_lcan_send(&b, &sent[4], 100), TRN_OK);
    KT_ST(trn_lcan_recv(&a, &got, 1000), TRN_OK);
    KT_CHECK(same(&got, &sent[4]));
    KT_ST(trn_lcan_recv(&a, &got, 50), TRN_E_TIMEOUT);
    KT_ST(trn_lcan_close(&a), TRN_OK);
    KT_ST(trn_lcan_close(&b), TRN_OK);
}

static void recv_own_when_asked(void)
{
    trn_lcan_cfg_t c = base_cfg();
    trn_lcan_t a;
    trn_lcan_frame_t f = mk(0x55u, 0u, 2u, 9u), got;
    c.recv_own = 1u;
    KT_ST(trn_lcan_open(&a, &c), TRN_OK);
    KT_ST(trn_lcan_send(&a, &f, 100), TRN_OK);
    KT_ST(trn_lcan_recv(&a, &got, 1000), TRN_OK);
    KT_CHECK(same(&got, &f));
    trn_lcan_close(&a);
}

static void receive_timeout(void)
{
    trn_lcan_cfg_t c = base_cfg();
    trn_lcan_t a;
    trn_lcan_frame_t got;
    long long t0;
    memset(&got, 0xA5, sizeof got);
    KT_ST(trn_lcan_open(&a, &c), TRN_OK);
    t0 = kt_now_ms();
    KT_ST(trn_lcan_recv(&a, &got, 150), TRN_E_TIMEOUT);
    KT_CHECK(kt_now_ms() - t0 >= 150); /* never early */
    KT_ST(trn_lcan_recv(&a, &got, 0), TRN_E_TIMEOUT);
    KT_CHECK(got.id == 0xA5A5A5A5u); /* untouched */
    trn_lcan_close(&a);
}

static void error_frames_are_bus_status(void)
{
    trn_lcan_cfg_t c = base_cfg();
    trn_lcan_cfg_t cq = base_cfg();
    trn_lcan_t a, quiet, tx;
    trn_lcan_bus_t bus;
    trn_lcan_frame_t got, f = mk(0x321u, 0u, 4u, 7u);
    int efd = plain_socket();

    KT_CHECK(efd >= 0);
    cq.error_frames = 0u;
    KT_ST(trn_lcan_open(&a, &c), TRN_OK);
    KT_ST(trn_lcan_open(&quiet, &cq), TRN_OK);
    KT_ST(trn_lcan_open(&tx, &c), TRN_OK);

    KT_CHECK(write_error_frame(efd, CAN_ERR_CRTL, CAN_ERR_CRTL_TX_WARNING) == 0);
    KT_ST(trn_lcan_recv(&a, &got, 1000), TRN_E_BUS);
    trn_lcan_bus_status(&a, &bus);
    KT_CHECK(bus.state == TRN_LCAN_ERROR_WARNING);
    KT_CHECK(bus.error_frames == 1u);

    KT_CHECK(write_error_frame(efd, CAN_ERR_CRTL, CAN_ERR_CRTL_RX_PASSIVE) == 0);
    KT_ST(trn_lcan_recv(&a, &got, 1000), TRN_E_BUS);
    trn_lcan_bus_status(&a, &bus);
    KT_CHECK(bus.state == TRN_LCAN_ERROR_PASSIVE);
    KT_CHECK(bus.last_error_class == CAN_ERR_CRTL);
    KT_CHECK(bus.last_error_data[1] == CAN_ERR_CRTL_RX_PASSIVE);

    KT_CHECK(write_error_frame(efd, CAN_ERR_BUSOFF, 0u) == 0);
    /* A data frame after the bus-off report: the error comes first, in order. */
    KT_ST(trn_lcan_send(&tx, &f, 100), TRN_OK);
    KT_ST(trn_lcan_recv(&a, &got, 1000), TRN_E_BUS);
    trn_lcan_bus_status(&a, &bus);
    KT_CHECK(bus.state == TRN_LCAN_BUS_OFF);
    KT_CHECK(bus.error_frames == 3u);
    KT_ST(trn_lcan_recv(&a, &got, 1000), TRN_OK);
    KT_CHECK(same(&got, &f));

    KT_CHECK(write_error_frame(efd, CAN_ERR_RESTARTED, 0u) == 0);
    KT_ST(trn_lcan_recv(&a, &got, 1000), TRN_E_BUS);
    trn_lcan_bus_status(&a, &bus);
    KT_CHECK(bus.state == TRN_LCAN_ERROR_ACTIVE);
    KT_CHECK(bus.error_frames == 4u);

    KT_CHECK(write_error_frame(efd, CAN_ERR_CRTL, CAN_ERR_CRTL_RX_OVERFLOW) == 0);
    KT_ST(trn_lcan_recv(&a, &got, 1000), TRN_E_BUS);
    trn_lcan_bus_status(&a, &bus);
    KT_CHECK(bus.ctrl_overflows == 1u);
    KT_CHECK(bus.state == TRN_LCAN_ERROR_ACTIVE);

    /* With error frames off, the socket sees only the data frame. */
    KT_ST(trn_lcan_recv(&quiet, &got, 1000), TRN_OK);
    KT_CHECK(same(&got, &f));
    KT_ST(trn_lcan_recv(&quiet, &got, 50), TRN_E_TIMEOUT);
    trn_lcan_bus_status(&quiet, &bus);
    KT_CHECK(bus.error_frames == 0u);

    close(efd);
    trn_lcan_close(&a);
    trn_lcan_close(&quiet);
    trn_lcan_close(&tx);
}

static uint32_t bus_drops_before_marker(const trn_lcan_t *c)
{
    trn_lcan_bus_t b;
    trn_lcan_bus_status(c, &b);
    return b.rx_drops;
}

/* A tiny receive buffer overflows; SO_RXQ_OVFL counts exactly what was lost. */
static void drops_counted(void)
{
    enum { N = 300 };
    trn_lcan_cfg_t ctx = base_cfg();
    trn_lcan_cfg_t crx = base_cfg();
    trn_lcan_filter_t flt = {0x42u, 0x7FFu, 0u};
    trn_lcan_t tx, rx;
    trn_lcan_bus_t bus;
    trn_lcan_frame_t got;
    uint32_t received = 0u;
    int last = -1, ordered = 1;
    int i;

    crx.rcvbuf_bytes = 1; /* the kernel rounds up to its minimum */
    crx.filters = &flt;
    crx.n_filters = 1u;
    KT_ST(trn_lcan_open(&tx, &ctx), TRN_OK);
    KT_ST(trn_lcan_open(&rx, &crx), TRN_OK);
    for (i = 0; i < N; ++i) {
        trn_lcan_frame_t f = mk(0x42u, 0u, 2u, 0u);
        f.data[0] = (uint8_t)(i >> 8);
        f.data[1] = (uint8_t)i;
        KT_ST(trn_lcan_send(&tx, &f, 1000), TRN_OK);
    }
    for (i = 0; i < N + 1; ++i) {
        trn_status_t st = trn_lcan_recv(&rx, &got, 200);
        int seq;
        if (st != TRN_OK) {
            KT_ST(st, TRN_E_TIMEOUT);
            break;
        }
        seq = (got.data[0] << 8) | got.data[1];
        if (seq <= last) {
            ordered = 0;
        }
        last = seq;
        ++received;
    }
    /* The kernel stamps each frame with the drop count at the time it was
     * queued, so losses after the last queued frame show on the next one. */
    KT_CHECK(bus_drops_before_marker(&rx) == 0u);
    {
        trn_lcan_frame_t marker = mk(0x42u, 0u, 2u, 0u);
        marker.data[0] = 0xFFu;
        marker.data[1] = 0xFFu;
        KT_ST(trn_lcan_send(&tx, &marker, 1000), TRN_OK);
        KT_ST(trn_lcan_recv(&rx, &got, 1000), TRN_OK);
        KT_CHECK(got.data[0] == 0xFFu && got.data[1] == 0xFFu);
    }
    trn_lcan_bus_status(&rx, &bus);
    printf("drops: sent %d received %u dropped %u\n", N, (unsigned)received,
           (unsigned)bus.rx_drops);
    KT_CHECK(bus.rx_drops > 0u);
    KT_CHECK(received > 0u);
    KT_CHECK(received + bus.rx_drops == (uint32_t)N);
    KT_CHECK(ordered);
    trn_lcan_close(&tx);
    trn_lcan_close(&rx);
}

static void bad_arguments_and_states(void)
{
    trn_lcan_cfg_t c = base_cfg();
    trn_lcan_t a;
    trn_lcan_frame_t f = mk(0x800u, 0u, 1u, 0u);
    KT_ST(trn_lcan_open(&a, &c), TRN_OK);
    KT_ST(trn_lcan_send(&a, &f, 10), TRN_E_ARG); /* 0x800 is not an 11-bit id */
    f = mk(0x7FFu, 0u, 9u, 0u);
    KT_ST(trn_lcan_send(&a, &f, 10), TRN_E_ARG); /* 9 data bytes */
    f = mk(0x7FFu, 0u, 8u, 0u);
    KT_ST(trn_lcan_send(&a, &f, -1), TRN_E_ARG);
    trn_lcan_close(&a);
    KT_ST(trn_lcan_send(&a, &f, 10), TRN_E_ARG); /* closed */
    c.ifname = "nosuchcan9";
    KT_ST(trn_lcan_open(&a, &c), TRN_E_BUS);
    KT_CHECK(a.fd == -1);
}

static int sh(const char *cmd) { return system(cmd); }

static void interface_down_is_bus(void)
{
    char cmd[96];
    trn_lcan_cfg_t c = base_cfg();
    trn_lcan_t a;
    trn_lcan_frame_t f = mk(0x10u, 0u, 1u, 0u);
    KT_ST(trn_lcan_open(&a, &c), TRN_OK);
    snprintf(cmd, sizeof cmd, "ip link set %s down", ifname);
    KT_CHECK(sh(cmd) == 0);
    KT_ST(trn_lcan_send(&a, &f, 10), TRN_E_BUS);
    snprintf(cmd, sizeof cmd, "ip link set %s up", ifname);
    KT_CHECK(sh(cmd) == 0);
    KT_ST(trn_lcan_send(&a, &f, 10), TRN_OK);
    trn_lcan_close(&a);
}

int main(void)
{
    ifname = kt_env("TRN_CAN_IF", "vcan0");
    KT_RUN(round_trip_with_filters);
    KT_RUN(recv_own_when_asked);
    KT_RUN(receive_timeout);
    KT_RUN(error_frames_are_bus_status);
    KT_RUN(drops_counted);
    KT_RUN(bad_arguments_and_states);
    KT_RUN(interface_down_is_bus);
    return kt_finish("kt_can_raw");
}
