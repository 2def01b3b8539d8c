/* SPDX-License-Identifier: Apache-2.0 */
/*
 * kt_fault_matrix.c - the bus fault matrix (docs/can-protocol.md "Fault
 * matrix"), run in the VM against the real kernel (vcan, can-isotp).
 *
 * Every case injects one fault, then checks the row of the matrix: the
 * status the rover sees, the counter that moved, the stated recovery, and
 * that no partial capture reached the caller (the capture struct is written
 * only by a complete, CRC-checked capture; `n_complete` does not move on a
 * fault; the next good capture after the fault arrives complete and equal to
 * what was sent).
 *
 * The rover's capture path on Linux is the kernel's CAN_ISOTP socket
 * (trn_lisotp_recv) feeding trn_capture_rx_segment, with
 * trn_capture_rx_abort on any receive error (docs/can-protocol.md "Using
 * it"); the bare-metal path is the pure receiver of port/proto
 * (trn_isotp_rx_frame / _poll) fed from raw frames. Both are tested. The
 * senders are the kernel's (trn_lisotp_send) and the pure one
 * (trn_isotp_tx_*), each against a raw-socket fake peer that plays the faulty
 * receiver; STmin is measured with kernel receive timestamps (SO_TIMESTAMPNS).
 *
 * The recovery policy the rover applies (rover_* below) is the documented
 * procedure: on any capture-transport error or a receive-queue drop the
 * capture in progress is dropped (trn_capture_rx_abort); on bus-off the
 * rover stops sending until the controller reports the restart.
 */
#include <errno.h>
#include <poll.h>
#include <stdint.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <sys/wait.h>
#include <net/if.h>
#include <unistd.h>

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>

#include "ktest.h"
#include "trn_port/capture.h"
#include "trn_port/isotp.h"
#include "trn_port/linux_can.h"

#define ID_DATA 0x1A0u /* CAPTURE_DATA: stereo head -> rover */
#define ID_FC 0x1A1u   /* CAPTURE_FC:   rover -> stereo head */
#define ID_CMD 0x120u  /* MAST_CMD, for the bus-state rows */
#define SEG_PAYLOAD 300u
#define N_POINTS 150u /* 920 bytes of capture, 4 segments of <= 300 bytes */

static const char *ifname;

/* ---- captures ----------------------------------------------------------- */

static trn_capture_t cap_sent;
static uint8_t wire[TRN_CAP_WIRE_MAX];
static size_t wire_len;
static uint8_t segs[8][TRN_ISOTP_MAX_MSG];
static size_t seg_len[8];
static uint8_t n_segs;

static uint16_t cap_points = N_POINTS; /* size of the next capture */
static size_t cap_seg_payload = SEG_PAYLOAD;

static void make_capture(uint16_t id)
{
    uint16_t i;
    memset(&cap_sent, 0, sizeof cap_sent);
    cap_sent.capture_id = id;
    cap_sent.time_ms = 1000u + id;
    cap_sent.pan_100urad = (int16_t)(100 + id);
    cap_sent.tilt_100urad = -200;
    cap_sent.n_points = cap_points;
    for (i = 0; i < cap_points; ++i) {
        cap_sent.points[i].x_mm = (int16_t)(i * 3 - 200);
        cap_sent.points[i].y_mm = (int16_t)(id + i);
        cap_sent.points[i].z_mm = (int16_t)(2000 + i * 7);
    }
    KT_ST(trn_capture_encode(&cap_sent, wire, sizeof wire, &wire_len), TRN_OK);
    KT_ST(trn_capture_segment_count(wire_len, cap_seg_payload, &n_segs), TRN_OK);
    KT_CHECK(n_segs >= 2u && n_segs <= 8u);
    for (i = 0; i < n_segs && i < 8u; ++i) {
        KT_ST(trn_capture_segment(wire, wire_len, cap_seg_payload, (uint8_t)i, segs[i],
                                  sizeof segs[i], &seg_len[i]),
              TRN_OK);
    }
}

static int same_capture(const trn_capture_t *a, const trn_capture_t *b)
{
    return a->capture_id == b->capture_id && a->time_ms == b->time_ms &&
           a->pan_100urad == b->pan_100urad && a->tilt_100urad == b->tilt_100urad &&
           a->n_points == b->n_points &&
           memcmp(a->points, b->points, sizeof a->points[0] * a->n_points) == 0;
}

/* ---- the rover's capture receiver on Linux (kernel ISO-TP) ---------------- */

typedef struct {
    trn_lisotp_t tp;
    trn_capture_rx_t rx;
    trn_capture_t out; /* written only by a complete capture */
    uint32_t transport_errors;
    trn_status_t last;
} rover_t;

static rover_t rover;
static uint8_t rbuf[TRN_ISOTP_MAX_MSG];

static void rover_open(void)
{
    trn_lisotp_cfg_t c;
    trn_lisotp_cfg_default(&c);
    c.ifname = ifname;
    c.tx_id = ID_FC;
    c.rx_id = ID_DATA;
    c.tx_padding = 0u; /* docs/can-protocol.md: unpadded */
    KT_ST(trn_lisotp_open(&rover.tp, &c), TRN_OK);
    KT_ST(trn_capture_rx_init(&rover.rx), TRN_OK);
    memset(&rover.out, 0xA5, sizeof rover.out);
    rover.transport_errors = 0u;
}

/* One receive step of the rover: a segment to the reassembly, or on any
 * transport error (timeout while a capture is in progress included) the
 * capture in progress is dropped. Returns 1 when a capture completed. */
static int rover_step(int32_t timeout_ms)
{
    size_t len = 0;
    int complete = 0;
    trn_cap_err_t err = TRN_CAP_ERR_NONE;
    trn_status_t st = trn_lisotp_recv(&rover.tp, rbuf, sizeof rbuf, &len, timeout_ms);
    rover.last = st;
    if (st != TRN_OK) {
        if (st != TRN_E_TIMEOUT || rover.rx.active) {
            ++rover.transport_errors;
            trn_capture_rx_abort(&rover.rx);
        }
        return 0;
    }
    (void)trn_capture_rx_segment(&rover.rx, rbuf, len, &rover.out, &complete, &err);
    return complete;
}

/* A good sender: the kernel's ISO-TP on the stereo head's side. */
static void stereo_send_good(uint16_t id)
{
    trn_lisotp_cfg_t c;
    trn_lisotp_t s;
    uint8_t i;
    trn_lisotp_cfg_default(&c);
    c.ifname = ifname;
    c.tx_id = ID_DATA;
    c.rx_id = ID_FC;
    c.tx_padding = 0u;
    make_capture(id);
    KT_ST(trn_lisotp_open(&s, &c), TRN_OK);
    for (i = 0; i < n_segs; ++i) {
        KT_ST(trn_lisotp_send(&s, segs[i], seg_len[i], 5000), TRN_OK);
    }
    trn_lisotp_close(&s);
}

/* One segment of the current capture through a good kernel sender. */
static void stereo_send_segment(uint8_t i)
{
    trn_lisotp_cfg_t c;
    trn_lisotp_t s;
    trn_lisotp_cfg_default(&c);
    c.ifname = ifname;
    c.tx_id = ID_DATA;
    c.rx_id = ID_FC;
    c.tx_padding = 0u;
    KT_ST(trn_lisotp_open(&s, &c), TRN_OK);
    KT_ST(trn_lisotp_send(&s, segs[i], seg_len[i], 5000), TRN_OK);
    trn_lisotp_close(&s);
}

/* A raw socket of the port for bus status: error frames, and only MAST_STATUS
 * (0x121, which nobody sends here) as data, so the capture traffic does not
 * come between the error reports. */
static void bus_open(trn_lcan_t *can)
{
    static const trn_lcan_filter_t f = {0x121u, 0x7FFu, 0u};
    trn_lcan_cfg_t c;
    trn_lcan_cfg_default(&c);
    c.ifname = ifname;
    c.filters = &f;
    c.n_filters = 1u;
    KT_ST(trn_lcan_open(can, &c), TRN_OK);
}

/* Recovery check: the next good capture arrives complete and equal. */
static void rover_receives_next_capture(uint16_t id)
{
    uint32_t before = rover.rx.n_complete;
    int done = 0, steps;
    stereo_send_good(id);
    for (steps = 0; steps < 16 && !done; ++steps) {
        done = rover_step(2000);
    }
    KT_CHECK(done);
    KT_CHECK(rover.rx.n_complete == before + 1u);
    KT_CHECK(same_capture(&rover.out, &cap_sent));
}

/* ---- raw sockets ---------------------------------------------------------- */

/* A plain raw socket (outside the port) with an optional id filter and
 * kernel receive timestamps. */
static int plain_socket(int filter_id)
{
    struct sockaddr_can addr;
    int one = 1;
    int fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (fd < 0) {
        return -1;
    }
    if (filter_id >= 0) {
        struct can_filter f;
        f.can_id = (canid_t)filter_id;
        f.can_mask = CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG;
        if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, &f, sizeof f) != 0) {
            close(fd);
            return -1;
        }
    }
    if (setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one) != 0) {
        close(fd);
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

static int raw_send(int fd, uint32_t id, const uint8_t *d, uint8_t dlc)
{
    struct can_frame f;
    memset(&f, 0, sizeof f);
    f.can_id = id;
    f.can_dlc = dlc;
    memcpy(f.data, d, dlc);
    return write(fd, &f, sizeof f) == (ssize_t)sizeof f ? 0 : -1;
}

/* Receive one frame within timeout_ms; t_ns gets the kernel's receive time.
 * Returns 0 or -1 (timeout / error). */
static int raw_recv(int fd, struct can_frame *f, long long *t_ns, int timeout_ms)
{
    struct pollfd p;
    struct iovec iov;
    struct msghdr m;
    char ctl[128];
    struct cmsghdr *c;
    p.fd = fd;
    p.events = POLLIN;
    if (poll(&p, 1, timeout_ms) != 1) {
        return -1;
    }
    iov.iov_base = f;
    iov.iov_len = sizeof *f;
    memset(&m, 0, sizeof m);
    m.msg_iov = &iov;
    m.msg_iovlen = 1;
    m.msg_control = ctl;
    m.msg_controllen = sizeof ctl;
    if (recvmsg(fd, &m, 0) != (ssize_t)sizeof *f) {
        return -1;
    }
    if (t_ns != NULL) {
        *t_ns = -1;
        for (c = CMSG_FIRSTHDR(&m); c != NULL; c = CMSG_NXTHDR(&m, c)) {
            if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_TIMESTAMPNS) {
                struct timespec ts;
                memcpy(&ts, CMSG_DATA(c), sizeof ts);
                *t_ns = (long long)ts.tv_sec * 1000000000LL + ts.tv_nsec;
            }
        }
    }
    return 0;
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

static long long now_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (long long)ts.tv_sec * 1000000LL + ts.tv_nsec / 1000;
}

/* ---- bus state rows --------------------------------------------------------- */

/* The rover's MAST_CMD sender: it stops sending while the bus is off. */
typedef struct {
    trn_lcan_t can;
    uint32_t held; /* commands not sent because the bus was off */
} rover_cmd_t;

static trn_status_t rover_cmd_send(rover_cmd_t *r, uint8_t seq)
{
    trn_lcan_frame_t f;
    trn_lcan_bus_t b;
    trn_lcan_bus_status(&r->can, &b);
    if (b.state == TRN_LCAN_BUS_OFF) {
        ++r->held;
        return TRN_E_BUS;
    }
    memset(&f, 0, sizeof f);
    f.id = ID_CMD;
    f.len = 8u;
    f.data[6] = seq;
    f.data[7] = 1u;
    return trn_lcan_send(&r->can, &f, 100);
}

/* Row "bus-off": error frame CAN_ERR_BUSOFF from the controller. Status
 * TRN_E_BUS, state BUS_OFF, error_frames + 1; the rover holds its commands
 * and drops the capture in progress; CAN_ERR_RESTARTED brings ERROR_ACTIVE
 * and the rover resumes. */
static void fm_bus_off(void)
{
    rover_cmd_t rc;
    trn_lcan_bus_t b;
    trn_lcan_frame_t got;
    int efd = plain_socket(-1);
    int peer = plain_socket((int)ID_CMD);
    struct can_frame pf;
    uint32_t e0;

    KT_CHECK(efd >= 0 && peer >= 0);
    bus_open(&rc.can);
    rc.held = 0u;
    rover_open();
    /* a capture in progress: its first segment */
    make_capture(11u);
    stereo_send_segment(0u);
    KT_CHECK(rover_step(2000) == 0);
    KT_CHECK(rover.rx.active == 1u);

    trn_lcan_bus_status(&rc.can, &b);
    e0 = b.error_frames;
    KT_CHECK(write_error_frame(efd, CAN_ERR_BUSOFF, 0u) == 0);
    KT_ST(trn_lcan_recv(&rc.can, &got, 1000), TRN_E_BUS);
    trn_lcan_bus_status(&rc.can, &b);
    KT_CHECK(b.state == TRN_LCAN_BUS_OFF);
    KT_CHECK(b.error_frames == e0 + 1u);
    /* recovery, part 1: the capture in progress is dropped, commands are held */
    KT_ST(trn_capture_rx_abort(&rover.rx), TRN_OK);
    KT_CHECK(rover.rx.err_count[TRN_CAP_ERR_TRANSPORT] == 1u);
    KT_ST(rover_cmd_send(&rc, 1u), TRN_E_BUS);
    KT_CHECK(rc.held == 1u);
    KT_CHECK(raw_recv(peer, &pf, NULL, 100) != 0); /* nothing went out */
    /* part 2: the controller restarts (restart-ms), the rover resumes */
    KT_CHECK(write_error_frame(efd, CAN_ERR_RESTARTED, 0u) == 0);
    KT_ST(trn_lcan_recv(&rc.can, &got, 1000), TRN_E_BUS);
    trn_lcan_bus_status(&rc.can, &b);
    KT_CHECK(b.state == TRN_LCAN_ERROR_ACTIVE);
    KT_CHECK(b.error_frames == e0 + 2u);
    KT_ST(rover_cmd_send(&rc, 2u), TRN_OK);
    KT_CHECK(raw_recv(peer, &pf, NULL, 1000) == 0 && pf.can_id == ID_CMD && pf.data[6] == 2u);
    /* the rest of the old capture never completes it; a new one does */
    KT_CHECK(rover.rx.n_complete == 0u);
    rover_receives_next_capture(12u);
    close(efd);
    close(peer);
    trn_lcan_close(&rc.can);
    trn_lisotp_close(&rover.tp);
}

/* Row "error-passive": CAN_ERR_CRTL with rx/tx passive. Status TRN_E_BUS,
 * state ERROR_PASSIVE, error_frames + 1; the node still sends and receives:
 * the rover keeps going (reports the state) and a capture completes;
 * CAN_ERR_CRTL_ACTIVE returns it to ERROR_ACTIVE. */
static void fm_error_passive(void)
{
    trn_lcan_t can;
    trn_lcan_bus_t b;
    trn_lcan_frame_t got;
    int efd = plain_socket(-1);
    KT_CHECK(efd >= 0);
    bus_open(&can);
    rover_open();
    KT_CHECK(write_error_frame(efd, CAN_ERR_CRTL,
                               CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE) == 0);
    KT_ST(trn_lcan_recv(&can, &got, 1000), TRN_E_BUS);
    trn_lcan_bus_status(&can, &b);
    KT_CHECK(b.state == TRN_LCAN_ERROR_PASSIVE);
    KT_CHECK(b.error_frames == 1u);
    rover_receives_next_capture(21u);
    KT_CHECK(write_error_frame(efd, CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE) == 0);
    KT_ST(trn_lcan_recv(&can, &got, 1000), TRN_E_BUS);
    trn_lcan_bus_status(&can, &b);
    KT_CHECK(b.state == TRN_LCAN_ERROR_ACTIVE);
    KT_CHECK(b.error_frames == 2u);
    close(efd);
    trn_lcan_close(&can);
    trn_lisotp_close(&rover.tp);
}

/* ---- the pure receiver on raw frames (bare-metal path) --------------------- */

typedef struct {
    trn_lcan_t can; /* raw socket on ID_DATA */
    trn_isotp_rx_t tp;
    uint8_t buf[TRN_ISOTP_MAX_MSG];
    trn_capture_rx_t rx;
    trn_capture_t out;
    uint32_t drops_seen;
    int got_frame; /* the last step received a frame */
} raw_rover_t;

static raw_rover_t rr;

static void raw_rover_open(int32_t rcvbuf, uint16_t cap)
{
    trn_lcan_cfg_t c;
    static trn_lcan_filter_t f = {ID_DATA, 0x7FFu, 0u};
    trn_lcan_cfg_default(&c);
    c.ifname = ifname;
    c.filters = &f;
    c.n_filters = 1u;
    c.rcvbuf_bytes = rcvbuf;
    c.error_frames = 0u;
    KT_ST(trn_lcan_open(&rr.can, &c), TRN_OK);
    KT_ST(trn_isotp_rx_init(&rr.tp, rr.buf, cap, 0u, 0u, 1000u), TRN_OK);
    KT_ST(trn_capture_rx_init(&rr.rx), TRN_OK);
    memset(&rr.out, 0xA5, sizeof rr.out);
    rr.drops_seen = 0u;
}

/* One step: a frame (or a poll for N_Cr) into the receiver; FC out on ID_FC
 * through fc_fd; a whole message into the capture reassembly; on a receiver
 * error that aborts a message, or on new receive-queue drops, the capture in
 * progress is dropped. Returns the receiver's status. */
static trn_status_t raw_rover_step(int fc_fd, int32_t timeout_ms, int *complete)
{
    trn_lcan_frame_t f;
    trn_lcan_bus_t b;
    trn_isotp_rx_result_t res;
    trn_status_t st, rs;
    uint32_t t;
    *complete = 0;
    rs = trn_lcan_recv(&rr.can, &f, timeout_ms);
    rr.got_frame = rs == TRN_OK;
    t = (uint32_t)(now_us() / 1000);
    trn_lcan_bus_status(&rr.can, &b);
    if (b.rx_drops != rr.drops_seen) {
        /* frames were lost before this one: the message and the capture in
         * progress are incomplete; drop both (and this frame with them) */
        rr.drops_seen = b.rx_drops;
        trn_capture_rx_abort(&rr.rx);
        KT_ST(trn_isotp_rx_init(&rr.tp, rr.buf, rr.tp.cap, 0u, 0u, 1000u), TRN_OK);
        return TRN_E_CAPACITY;
    }
    if (rs == TRN_OK) {
        st = trn_isotp_rx_frame(&rr.tp, f.data, f.len, t, &res);
    } else {
        st = trn_isotp_rx_poll(&rr.tp, t, &res);
    }
    if (res.events & TRN_ISOTP_EV_SEND_FC) {
        KT_CHECK(raw_send(fc_fd, ID_FC, res.fc, res.fc_dlc) == 0);
    }
    if ((res.events & TRN_ISOTP_EV_ERROR) &&
        (res.error == TRN_ISOTP_ERR_WRONG_SN || res.error == TRN_ISOTP_ERR_TIMEOUT_CR ||
         res.error == TRN_ISOTP_ERR_SHORT_CF || res.error == TRN_ISOTP_ERR_INTERRUPTED ||
         res.error == TRN_ISOTP_ERR_OVERFLOW)) {
        trn_capture_rx_abort(&rr.rx);
    }
    if (res.events & TRN_ISOTP_EV_MESSAGE) {
        trn_cap_err_t e;
        (void)trn_capture_rx_segment(&rr.rx, rr.buf, res.msg_len, &rr.out, complete, &e);
    }
    return st;
}

/* A raw fake stereo head: FF, wait for FC, then CFs 1..n_cf (sn_skip: the
 * CF index whose sequence number is made wrong; 0 = none). */
static void raw_send_segment(int fd, int fc_fd_peer, const uint8_t *msg, size_t len, uint16_t n_cf,
                             uint16_t sn_skip, int step_rover_fc)
{
    uint8_t fr[8], dlc;
    uint16_t k;
    int complete;
    KT_ST(trn_isotp_encode_frame(msg, len, 0u, fr, &dlc), TRN_OK);
    KT_CHECK(raw_send(fd, ID_DATA, fr, dlc) == 0);
    if (step_rover_fc) {
        KT_ST(raw_rover_step(fc_fd_peer, 1000, &complete), TRN_OK); /* FF -> FC */
    }
    for (k = 1; k <= n_cf; ++k) {
        KT_ST(trn_isotp_encode_frame(msg, len, k, fr, &dlc), TRN_OK);
        if (k == sn_skip) {
            fr[0] = (uint8_t)(0x20u | ((fr[0] + 1u) & 0x0Fu));
        }
        KT_CHECK(raw_send(fd, ID_DATA, fr, dlc) == 0);
    }
}

/* Recovery check of the pure receiver: a new capture, each frame read as it
 * is sent, arrives complete and equal. */
static void raw_rover_receives_next_capture(int fd, uint16_t id)
{
    uint32_t before = rr.rx.n_complete;
    int complete = 0;
    uint8_t i;
    make_capture(id);
    for (i = 0; i < n_segs; ++i) {
        uint16_t k, nf = trn_isotp_frame_count(seg_len[i]);
        uint8_t fr[8], dlc;
        for (k = 0; k < nf; ++k) {
            KT_ST(trn_isotp_encode_frame(segs[i], seg_len[i], k, fr, &dlc), TRN_OK);
            KT_CHECK(raw_send(fd, ID_DATA, fr, dlc) == 0);
            (void)raw_rover_step(fd, 1000, &complete);
        }
    }
    KT_CHECK(complete == 1 && rr.rx.n_complete == before + 1u && same_capture(&rr.out, &cap_sent));
}

/* Row "receiver timeout N_Cr", both receivers. Kernel: the sender stops
 * after the FF of segment 1; trn_lisotp_recv gives TRN_E_TIMEOUT (kernel
 * ETIMEDOUT) after ~1 s, the rover aborts the capture (TRANSPORT + 1).
 * Pure: trn_isotp_rx_poll after 1000 ms gives TRN_E_TIMEOUT, TIMEOUT_CR + 1,
 * capture aborted. Recovery: the next capture completes. */
static void fm_rx_timeout_ncr(void)
{
    int raw = plain_socket(-1);
    int fcr = plain_socket((int)ID_FC);
    struct can_frame f;
    uint8_t fr[8], dlc;
    long long t0;
    int complete = 0, i;
    trn_status_t st = TRN_OK;
    KT_CHECK(raw >= 0 && fcr >= 0);

    /* kernel receiver */
    rover_open();
    make_capture(31u);
    stereo_send_segment(0u); /* the first segment arrives whole ... */
    KT_CHECK(rover_step(2000) == 0);
    KT_CHECK(rover.rx.active == 1u);
    /* ... the second stops after its first frame */
    KT_ST(trn_isotp_encode_frame(segs[1], seg_len[1], 0u, fr, &dlc), TRN_OK);
    KT_CHECK(raw_send(raw, ID_DATA, fr, dlc) == 0);
    KT_CHECK(raw_recv(fcr, &f, NULL, 2000) == 0 && (f.data[0] & 0xF0u) == 0x30u); /* kernel's FC */
    t0 = kt_now_ms();
    KT_CHECK(rover_step(5000) == 0);
    KT_ST(rover.last, TRN_E_TIMEOUT);
    KT_CHECK(kt_now_ms() - t0 < 4500); /* the kernel's N_Cr, not our 5 s */
    KT_CHECK(rover.transport_errors == 1u);
    KT_CHECK(rover.rx.err_count[TRN_CAP_ERR_TRANSPORT] == 1u);
    KT_CHECK(rover.rx.active == 0u && rover.rx.n_complete == 0u);
    KT_CHECK(rover.out.capture_id == 0xA5A5u); /* untouched */
    rover_receives_next_capture(32u);
    trn_lisotp_close(&rover.tp);

    /* pure receiver */
    raw_rover_open(0, TRN_ISOTP_MAX_MSG);
    make_capture(33u);
    KT_ST(trn_capture_rx_segment(&rr.rx, segs[0], seg_len[0], &rr.out, &complete, NULL), TRN_OK);
    raw_send_segment(raw, raw, segs[1], seg_len[1], 2u, 0u, 1);
    for (i = 0; i < 2; ++i) {
        KT_ST(raw_rover_step(raw, 1000, &complete), TRN_OK); /* two CFs */
    }
    t0 = kt_now_ms();
    for (i = 0; i < 30 && st != TRN_E_TIMEOUT; ++i) {
        st = raw_rover_step(raw, 100, &complete);
    }
    KT_ST(st, TRN_E_TIMEOUT);
    KT_CHECK(kt_now_ms() - t0 >= 900);
    KT_CHECK(rr.tp.err_count[TRN_ISOTP_ERR_TIMEOUT_CR] == 1u);
    KT_CHECK(rr.rx.err_count[TRN_CAP_ERR_TRANSPORT] == 1u);
    KT_CHECK(rr.rx.active == 0u && rr.rx.n_complete == 0u && rr.out.capture_id == 0xA5A5u);
    raw_rover_receives_next_capture(raw, 34u);
    trn_lcan_close(&rr.can);
    close(raw);
    close(fcr);
}

/* Row "wrong sequence number", both receivers. Kernel: TRN_E_SEQ (EILSEQ);
 * pure: TRN_E_SEQ, WRONG_SN + 1; capture aborted (TRANSPORT + 1); the next
 * capture completes. */
static void fm_wrong_sn(void)
{
    int raw = plain_socket(-1);
    int fcr = plain_socket((int)ID_FC);
    struct can_frame f;
    int complete = 0, i;
    trn_status_t st = TRN_OK;
    uint8_t fr[8], dlc;
    KT_CHECK(raw >= 0 && fcr >= 0);

    rover_open();
    make_capture(41u);
    KT_ST(trn_capture_rx_segment(&rover.rx, segs[0], seg_len[0], &rover.out, &complete, NULL),
          TRN_OK);
    KT_ST(trn_isotp_encode_frame(segs[1], seg_len[1], 0u, fr, &dlc), TRN_OK);
    KT_CHECK(raw_send(raw, ID_DATA, fr, dlc) == 0);
    KT_CHECK(raw_recv(fcr, &f, NULL, 2000) == 0 && (f.data[0] & 0xF0u) == 0x30u);
    for (i = 1; i <= 3; ++i) {
        KT_ST(trn_isotp_encode_frame(segs[1], seg_len[1], (uint16_t)i, fr, &dlc), TRN_OK);
        if (i == 3) {
            fr[0] = 0x25u; /* SN 5, expected 3 */
        }
        KT_CHECK(raw_send(raw, ID_DATA, fr, dlc) == 0);
    }
    KT_CHECK(rover_step(3000) == 0);
    KT_ST(rover.last, TRN_E_SEQ);
    KT_CHECK(rover.rx.err_count[TRN_CAP_ERR_TRANSPORT] == 1u);
    KT_CHECK(rover.rx.active == 0u && rover.out.capture_id == 0xA5A5u);
    rover_receives_next_capture(42u);
    trn_lisotp_close(&rover.tp);

    raw_rover_open(0, TRN_ISOTP_MAX_MSG);
    make_capture(43u);
    KT_ST(trn_capture_rx_segment(&rr.rx, segs[0], seg_len[0], &rr.out, &complete, NULL), TRN_OK);
    raw_send_segment(raw, raw, segs[1], seg_len[1], 3u, 3u, 1);
    for (i = 0; i < 3 && st == TRN_OK; ++i) {
        st = raw_rover_step(raw, 1000, &complete);
    }
    KT_ST(st, TRN_E_SEQ);
    KT_CHECK(rr.tp.err_count[TRN_ISOTP_ERR_WRONG_SN] == 1u);
    KT_CHECK(rr.rx.err_count[TRN_CAP_ERR_TRANSPORT] == 1u);
    KT_CHECK(rr.rx.active == 0u && rr.out.capture_id == 0xA5A5u);
    raw_rover_receives_next_capture(raw, 44u);
    trn_lcan_close(&rr.can);
    close(raw);
    close(fcr);
}

/* Row "first frame longer than the receiver's buffer" (pure receiver; the
 * kernel's buffer is its own 66000 bytes): FC OVFLW goes out, TRN_E_CAPACITY,
 * OVERFLOW + 1, no message. */
static void fm_rx_overflow_fc(void)
{
    int raw = plain_socket(-1);
    int fcr = plain_socket((int)ID_FC);
    struct can_frame f;
    uint8_t fr[8], dlc;
    int complete = 0;
    KT_CHECK(raw >= 0 && fcr >= 0);
    raw_rover_open(0, 200u);
    make_capture(51u);
    KT_ST(trn_isotp_encode_frame(segs[0], seg_len[0], 0u, fr, &dlc), TRN_OK);
    KT_CHECK(raw_send(raw, ID_DATA, fr, dlc) == 0);
    KT_ST(raw_rover_step(raw, 1000, &complete), TRN_E_CAPACITY);
    KT_CHECK(raw_recv(fcr, &f, NULL, 1000) == 0 && f.data[0] == 0x32u); /* FC overflow */
    KT_CHECK(rr.tp.err_count[TRN_ISOTP_ERR_OVERFLOW] == 1u);
    KT_CHECK(rr.tp.n_messages == 0u && complete == 0 && rr.out.capture_id == 0xA5A5u);
    /* recovery: a capture whose segments fit the buffer (150-byte slices) completes */
    cap_seg_payload = 150u;
    raw_rover_receives_next_capture(raw, 52u);
    cap_seg_payload = SEG_PAYLOAD;
    trn_lcan_close(&rr.can);
    close(raw);
    close(fcr);
}

/* Row "receive-queue overflow": CFs blasted into a minimal socket buffer;
 * SO_RXQ_OVFL counts the drops (bus.rx_drops), the rover drops the capture in
 * progress (TRANSPORT + 1); no capture completes from the damaged frames; the
 * next capture, paced, completes. */
static void fm_rxq_overflow(void)
{
    int raw = plain_socket(-1);
    int fcr = plain_socket((int)ID_FC);
    int complete = 0, i, any_complete = 0;
    uint16_t n_cf;
    uint32_t kept = 0u;
    trn_status_t st = TRN_OK;
    KT_CHECK(raw >= 0 && fcr >= 0);
    raw_rover_open(1, TRN_ISOTP_MAX_MSG);
    /* a large capture: 1000 points, two segments, the first of 585 CFs */
    cap_points = 1000u;
    cap_seg_payload = TRN_CAP_SEG_PAYLOAD_MAX;
    make_capture(61u);
    /* segment 0 has arrived; segment 1 comes as one burst of CFs */
    KT_ST(trn_capture_rx_segment(&rr.rx, segs[0], seg_len[0], &rr.out, &complete, NULL), TRN_OK);
    n_cf = (uint16_t)(trn_isotp_frame_count(seg_len[1]) - 1u);
    raw_send_segment(raw, raw, segs[1], seg_len[1], n_cf, 0u, 1); /* all CFs at once */
    /* the rover reads what its queue kept ... */
    for (i = 0; i < 1000; ++i) {
        st = raw_rover_step(raw, 20, &complete);
        any_complete |= complete;
        if (!rr.got_frame || st != TRN_OK) {
            break;
        }
    }
    KT_ST(st, TRN_OK);
    printf("KT-NOTE rxq: the queue kept %d of %u CFs\n", i, (unsigned)n_cf);
    kept = (uint32_t)i;
    {
        /* ... while the head goes on (the first frame of its next capture):
         * it is queued after the drops and carries their count (SO_RXQ_OVFL) */
        uint8_t fr[8], dlc;
        KT_ST(trn_isotp_encode_frame(segs[0], seg_len[0], 0u, fr, &dlc), TRN_OK);
        KT_CHECK(raw_send(raw, ID_DATA, fr, dlc) == 0);
    }
    st = raw_rover_step(raw, 1000, &complete);
    KT_ST(st, TRN_E_CAPACITY);
    printf("KT-NOTE rxq: %u frames dropped of %u\n", (unsigned)rr.drops_seen, (unsigned)n_cf);
    KT_CHECK(rr.drops_seen > 0u);
    KT_CHECK(rr.drops_seen + kept == n_cf); /* every lost frame counted */
    KT_CHECK(rr.rx.err_count[TRN_CAP_ERR_TRANSPORT] == 1u);
    /* whatever frames are still queued cannot complete anything */
    for (i = 0; i < 100; ++i) {
        (void)raw_rover_step(raw, 20, &complete);
        any_complete |= complete;
    }
    KT_CHECK(!any_complete && rr.rx.n_complete == 0u && rr.out.capture_id == 0xA5A5u);
    /* recovery: a capture read as it comes completes */
    raw_rover_receives_next_capture(raw, 62u);
    cap_points = N_POINTS;
    cap_seg_payload = SEG_PAYLOAD;
    trn_lcan_close(&rr.can);
    close(raw);
    close(fcr);
}

/* ---- senders against a faulty receiver ------------------------------------- */

/* The peer in a child process: wait for the FF on ID_DATA, answer with the
 * given FC frames (gap_ms apart), then record the arrival times of up to
 * max_cf CFs (kernel timestamps) and write the smallest gap (us) and the
 * count to the pipe. */
static pid_t peer_start(int pipe_w, const uint8_t (*fcs)[3], int n_fc, int gap_ms, int max_cf)
{
    pid_t pid;
    int fd = plain_socket((int)ID_DATA);
    if (fd < 0) {
        return -1;
    }
    pid = fork();
    if (pid == 0) {
        struct can_frame f;
        long long t, prev = -1, min_gap = -1;
        int i, n = 0;
        long long out[2];
        if (raw_recv(fd, &f, NULL, 3000) != 0 || (f.data[0] & 0xF0u) != 0x10u) {
            _exit(2);
        }
        for (i = 0; i < n_fc; ++i) {
            if (i > 0) {
                kt_sleep_ms(gap_ms);
            }
            if (raw_send(fd, ID_FC, fcs[i], 3u) != 0) {
                _exit(3);
            }
        }
        while (n < max_cf && raw_recv(fd, &f, &t, 1500) == 0) {
            if ((f.data[0] & 0xF0u) != 0x20u) {
                continue;
            }
            if (prev >= 0 && (min_gap < 0 || t - prev < min_gap)) {
                min_gap = t - prev;
            }
            prev = t;
            ++n;
        }
        out[0] = min_gap < 0 ? -1 : min_gap / 1000;
        out[1] = n;
        if (write(pipe_w, out, sizeof out) != (ssize_t)sizeof out) {
            _exit(4);
        }
        _exit(0);
    }
    close(fd);
    return pid;
}

static void peer_finish(pid_t pid, int pipe_r, long long *min_gap_us, long long *n_cf)
{
    int wst = 0;
    long long in[2] = {-1, -1};
    KT_CHECK(pid > 0 && waitpid(pid, &wst, 0) == pid && WIFEXITED(wst) && WEXITSTATUS(wst) == 0);
    KT_CHECK(read(pipe_r, in, sizeof in) == (ssize_t)sizeof in);
    *min_gap_us = in[0];
    *n_cf = in[1];
}

/* Kernel sender against the peer: returns trn_lisotp_send's status. */
static trn_status_t kernel_send(const uint8_t (*fcs)[3], int n_fc, int gap_ms, size_t len,
                                long long *min_gap_us, long long *n_cf, long long *elapsed_ms)
{
    trn_lisotp_cfg_t c;
    trn_lisotp_t s;
    trn_status_t st;
    int p[2];
    pid_t pid;
    long long t0;
    KT_CHECK(pipe(p) == 0);
    trn_lisotp_cfg_default(&c);
    c.ifname = ifname;
    c.tx_id = ID_DATA;
    c.rx_id = ID_FC;
    c.tx_padding = 0u;
    KT_ST(trn_lisotp_open(&s, &c), TRN_OK);
    pid = peer_start(p[1], fcs, n_fc, gap_ms, (int)trn_isotp_frame_count(len));
    make_capture(71u);
    t0 = kt_now_ms();
    st = trn_lisotp_send(&s, wire, len, 10000);
    *elapsed_ms = kt_now_ms() - t0;
    peer_finish(pid, p[0], min_gap_us, n_cf);
    close(p[0]);
    close(p[1]);
    trn_lisotp_close(&s);
    return st;
}

/* Pure sender on raw frames against the peer: drives trn_isotp_tx_* with the
 * monotonic clock; returns the status of the step or FC that ended it. */
static trn_isotp_tx_t ptx;
static trn_status_t pure_send(const uint8_t (*fcs)[3], int n_fc, int gap_ms, size_t len,
                              uint32_t n_bs_ms, uint8_t max_wft, long long *min_gap_us,
                              long long *n_cf, long long *elapsed_ms)
{
    int p[2], fd = plain_socket((int)ID_FC), loops;
    pid_t pid;
    trn_status_t st = TRN_OK;
    long long t0;
    KT_CHECK(pipe(p) == 0 && fd >= 0);
    KT_ST(trn_isotp_tx_init(&ptx, n_bs_ms, max_wft), TRN_OK);
    pid = peer_start(p[1], fcs, n_fc, gap_ms, (int)trn_isotp_frame_count(len));
    make_capture(72u);
    KT_ST(trn_isotp_tx_start(&ptx, wire, len), TRN_OK);
    t0 = kt_now_ms();
    for (loops = 0; loops < 100000; ++loops) {
        trn_isotp_tx_result_t r;
        struct can_frame f;
        long long now = now_us();
        st = trn_isotp_tx_step(&ptx, (uint32_t)now, &r);
        if (r.events & TRN_ISOTP_TX_EV_FRAME) {
            KT_CHECK(raw_send(fd, ID_DATA, r.frame, r.dlc) == 0);
        }
        if (st != TRN_OK || (r.events & TRN_ISOTP_TX_EV_DONE) || ptx.state == TRN_ISOTP_TX_IDLE) {
            break;
        }
        if (r.events & TRN_ISOTP_TX_EV_FRAME) {
            continue;
        }
        /* wait for an FC or the wake time */
        {
            long long wait_us = (long long)(uint32_t)(r.wake_us - (uint32_t)now);
            int ms = (int)(wait_us / 1000);
            if (ptx.state == TRN_ISOTP_TX_WAIT_FC) {
                if (raw_recv(fd, &f, NULL, ms > 0 ? ms : 1) == 0) {
                    trn_isotp_tx_result_t fr;
                    st = trn_isotp_tx_fc(&ptx, f.data, f.can_dlc, (uint32_t)now_us(), &fr);
                    if (st != TRN_OK) {
                        break;
                    }
                }
            } else {
                struct timespec ts;
                ts.tv_sec = 0;
                ts.tv_nsec = wait_us > 0 ? (long)(wait_us * 1000) : 0;
                nanosleep(&ts, NULL);
            }
        }
    }
    *elapsed_ms = kt_now_ms() - t0;
    peer_finish(pid, p[0], min_gap_us, n_cf);
    close(p[0]);
    close(p[1]);
    close(fd);
    return st;
}

/* Row "sender timeout N_Bs": nobody answers the FF. Kernel: TRN_E_TIMEOUT
 * (ECOMM) after ~1 s; pure: TRN_E_TIMEOUT, TIMEOUT_BS + 1. No CF is sent. */
static void fm_tx_timeout_nbs(void)
{
    long long g, n, ms;
    KT_ST(kernel_send(NULL, 0, 0, 100u, &g, &n, &ms), TRN_E_TIMEOUT);
    KT_CHECK(n == 0 && ms >= 900 && ms < 4500);
    KT_ST(pure_send(NULL, 0, 0, 100u, 300u, 0u, &g, &n, &ms), TRN_E_TIMEOUT);
    KT_CHECK(ptx.err_count[TRN_ISOTP_TX_ERR_TIMEOUT_BS] == 1u && ptx.state == TRN_ISOTP_TX_IDLE);
    KT_CHECK(n == 0 && ms >= 290);
    printf("KT-NOTE nbs: pure sender gave up after %lld ms (N_Bs 300 ms)\n", ms);
}

/* Row "invalid flow status": FC with FS = 5. Kernel: TRN_E_FORMAT
 * (EBADMSG); pure: TRN_E_FORMAT, INVALID_FC + 1. No CF is sent. */
static void fm_tx_invalid_fs(void)
{
    static const uint8_t bad[1][3] = {{0x35u, 0u, 0u}};
    long long g, n, ms;
    trn_status_t st = kernel_send(bad, 1, 0, 100u, &g, &n, &ms);
    printf("KT-NOTE invalid-fs: kernel sender status %d (%s) after %lld ms\n", (int)st,
           trn_strerror(st), ms);
    KT_ST(st, TRN_E_FORMAT);
    KT_CHECK(n == 0);
    KT_ST(pure_send(bad, 1, 0, 100u, 1000u, 0u, &g, &n, &ms), TRN_E_FORMAT);
    KT_CHECK(ptx.err_count[TRN_ISOTP_TX_ERR_INVALID_FC] == 1u && ptx.state == TRN_ISOTP_TX_IDLE);
    KT_CHECK(n == 0);
}

/* Row "flow control overflow": FS = 2. Kernel: TRN_E_CAPACITY (EMSGSIZE);
 * pure: TRN_E_CAPACITY, OVERFLOW + 1. No CF is sent. */
static void fm_tx_fc_overflow(void)
{
    static const uint8_t ovf[1][3] = {{0x32u, 0u, 0u}};
    long long g, n, ms;
    KT_ST(kernel_send(ovf, 1, 0, 100u, &g, &n, &ms), TRN_E_CAPACITY);
    KT_CHECK(n == 0);
    KT_ST(pure_send(ovf, 1, 0, 100u, 1000u, 0u, &g, &n, &ms), TRN_E_CAPACITY);
    KT_CHECK(ptx.err_count[TRN_ISOTP_TX_ERR_OVERFLOW] == 1u && ptx.state == TRN_ISOTP_TX_IDLE);
    KT_CHECK(n == 0);
}

/* Row "too many FC WAIT": the peer sends WAIT frames 200 ms apart.
 * Pure (max_wft 2): the third WAIT gives TRN_E_SEQ, WFT_OVERRUN + 1, no CF.
 * Kernel: it has no WFTmax for its sender; every WAIT restarts its 1 s N_Bs,
 * so after the peer's last WAIT it fails with TRN_E_TIMEOUT (measured and
 * stated in the matrix). */
static void fm_tx_too_many_waits(void)
{
    static const uint8_t waits[5][3] = {
        {0x31u, 0u, 0u}, {0x31u, 0u, 0u}, {0x31u, 0u, 0u}, {0x31u, 0u, 0u}, {0x31u, 0u, 0u}};
    long long g, n, ms;
    trn_status_t st;
    KT_ST(pure_send(waits, 3, 200, 100u, 1000u, 2u, &g, &n, &ms), TRN_E_SEQ);
    KT_CHECK(ptx.err_count[TRN_ISOTP_TX_ERR_WFT_OVERRUN] == 1u && ptx.state == TRN_ISOTP_TX_IDLE);
    KT_CHECK(n == 0);
    st = kernel_send(waits, 5, 200, 100u, &g, &n, &ms);
    printf("KT-NOTE wait: kernel sender after 5 WAITs 200 ms apart: status %d (%s) after %lld ms\n",
           (int)st, trn_strerror(st), ms);
    KT_ST(st, TRN_E_TIMEOUT);
    KT_CHECK(n == 0);
    KT_CHECK(ms >= 1700); /* the WAITs kept it alive past one N_Bs */
}

/* Row "STmin honoured": FC CTS with STmin 5 ms (and 0xF5 = 500 us for the
 * pure sender); the smallest gap between consecutive frames, by kernel
 * receive timestamps, is at least STmin less 0.3 ms of timestamp jitter;
 * every CF arrives. */
static void fm_tx_stmin(void)
{
    static const uint8_t cts5[1][3] = {{0x30u, 0u, 5u}};
    static const uint8_t cts500us[1][3] = {{0x30u, 0u, 0xF5u}};
    long long g, n, ms;
    const size_t len = 100u; /* 15 CFs */
    const long long want_cf = (long long)trn_isotp_frame_count(len) - 1;
    KT_ST(kernel_send(cts5, 1, 0, len, &g, &n, &ms), TRN_OK);
    printf("KT-NOTE stmin: kernel sender, STmin 5 ms: %lld CFs, smallest gap %lld us\n", n, g);
    KT_CHECK(n == want_cf && g >= 4700);
    KT_ST(pure_send(cts5, 1, 0, len, 1000u, 0u, &g, &n, &ms), TRN_OK);
    printf("KT-NOTE stmin: pure sender, STmin 5 ms: %lld CFs, smallest gap %lld us\n", n, g);
    KT_CHECK(n == want_cf && g >= 4700);
    KT_CHECK(ptx.n_messages == 1u);
    KT_ST(pure_send(cts500us, 1, 0, len, 1000u, 0u, &g, &n, &ms), TRN_OK);
    printf("KT-NOTE stmin: pure sender, STmin 0xF5 (500 us): %lld CFs, smallest gap %lld us\n", n,
           g);
    KT_CHECK(n == want_cf && g >= 200);
}

int main(void)
{
    ifname = kt_env("TRN_CAN_IF", "vcan0");
    KT_RUN(fm_bus_off);
    KT_RUN(fm_error_passive);
    KT_RUN(fm_rxq_overflow);
    KT_RUN(fm_rx_timeout_ncr);
    KT_RUN(fm_wrong_sn);
    KT_RUN(fm_rx_overflow_fc);
    KT_RUN(fm_tx_timeout_nbs);
    KT_RUN(fm_tx_invalid_fs);
    KT_RUN(fm_tx_fc_overflow);
    KT_RUN(fm_tx_too_many_waits);
    KT_RUN(fm_tx_stmin);
    return kt_finish("kt_fault_matrix");
}
