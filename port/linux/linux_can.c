/* SPDX-License-Identifier: Apache-2.0 */
/*
 * linux_can.c - SocketCAN raw and ISO-TP sockets (port/include/trn_port/linux_can.h).
 *
 * Waiting is always poll(2) against a CLOCK_MONOTONIC deadline; sockets are
 * used with MSG_DONTWAIT so no call blocks past it. Loops are bounded by the
 * deadline and, as a second guard, by TRN_LCAN_MAX_ROUNDS iterations.
 */
#include "trn_port/linux_can.h"

#include <errno.h>
#include <net/if.h>
#include <poll.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <time.h>
#include <unistd.h>

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/isotp.h>
#include <linux/can/raw.h>

#ifndef SO_RXQ_OVFL
#define SO_RXQ_OVFL 40
#endif

/* Guard on every wait loop besides the deadline: EINTR/EAGAIN storms end. */
#define TRN_LCAN_MAX_ROUNDS 100000u
/* Retry period while the transmit queue is full (ENOBUFS), ns. */
#define TRN_LCAN_TXQ_RETRY_NS 1000000L

/* ------------------------------------------------------------------------ */
/* time and polling functions                                                */

static int64_t now_ms(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_MONOTONIC, &ts) != 0) {
        return 0;
    }
    return (int64_t)ts.tv_sec * 1000 + (int64_t)(ts.tv_nsec / 1000000L);
}

static int remaining_ms(int64_t deadline_ms)
{
    int64_t left = deadline_ms - now_ms();
    if (left < 0) {
        return 0;
    }
    return (int)left;
}

trn_status_t trn_lcan_status_from_errno(int err)
{
    switch (err) {
    case 0: return TRN_OK;
    case ETIMEDOUT:
    case ECOMM: return TRN_E_TIMEOUT;
    case EILSEQ: return TRN_E_SEQ;
    case EBADMSG: return TRN_E_FORMAT;
    case EMSGSIZE: return TRN_E_CAPACITY;
    case ENETDOWN:
    case ENODEV:
    case ENXIO:
    case ENETUNREACH: return TRN_E_BUS;
    default: return TRN_E_IO;
    }
}

/* The pending socket error (SO_ERROR, which also clears it) as a status. */
static trn_status_t take_socket_error(int fd)
{
    int err = 0;
    socklen_t len = (socklen_t)sizeof err;
    if (getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len) != 0) {
        return TRN_E_IO;
    }
    return trn_lcan_status_from_errno(err);
}

/*
 * Wait until fd reports `events` or the deadline passes. A socket error
 * (POLLERR) is taken and returned as its status; TRN_OK means ready.
 */
static trn_status_t wait_fd(int fd, short events, int64_t deadline_ms)
{
    unsigned round;
    for (round = 0u; round < TRN_LCAN_MAX_ROUNDS; ++round) {
        struct pollfd p;
        int n;
        p.fd = fd;
        p.events = events;
        p.revents = 0;
        n = poll(&p, 1u, remaining_ms(deadline_ms));
        if (n < 0) {
            if (errno == EINTR) {
                continue;
            }
            return TRN_E_IO;
        }
        if (n == 0) {
            return TRN_E_TIMEOUT;
        }
        if ((p.revents & POLLERR) != 0) {
            trn_status_t st = take_socket_error(fd);
            if (st != TRN_OK) {
                return st;
            }
            continue; /* error already taken by someone else: look again */
        }
        if ((p.revents & POLLNVAL) != 0) {
            return TRN_E_IO;
        }
        if ((p.revents & events) != 0) {
            return TRN_OK;
        }
        if ((p.revents & POLLHUP) != 0) {
            return TRN_E_BUS;
        }
    }
    return TRN_E_TIMEOUT;
}

static trn_status_t check_ifname(const char *ifname)
{
    size_t n;
    if (ifname == NULL) {
        return TRN_E_NULL;
    }
    n = strnlen(ifname, TRN_LCAN_IFNAME_MAX + 1u);
    if (n == 0u || n > TRN_LCAN_IFNAME_MAX) {
        return TRN_E_SIZE;
    }
    return TRN_OK;
}

static int id_in_range(uint32_t id, uint8_t extended)
{
    return extended ? (id <= TRN_LCAN_EFF_MAX) : (id <= TRN_LCAN_SFF_MAX);
}

static int is_flag(uint8_t v) { return v == 0u || v == 1u; }

static int timeout_ok(int32_t timeout_ms)
{
    return timeout_ms >= 0 && timeout_ms <= TRN_LCAN_MAX_TIMEOUT_MS;
}

static trn_status_t open_status_from_errno(int err)
{
    if (err == ENODEV || err == ENXIO || err == ENETDOWN || err == EPROTONOSUPPORT ||
        err == EAFNOSUPPORT) {
        return TRN_E_BUS;
    }
    return TRN_E_IO;
}

/* ------------------------------------------------------------------------ */
/* raw CAN                                                                   */

trn_status_t trn_lcan_cfg_default(trn_lcan_cfg_t *cfg)
{
    if (cfg == NULL) {
        return TRN_E_NULL;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->ifname = "can0";
    cfg->filters = NULL;
    cfg->n_filters = 0u;
    cfg->rcvbuf_bytes = 0;
    cfg->recv_own = 0u;
    cfg->error_frames = 1u;
    return TRN_OK;
}

trn_status_t trn_lcan_cfg_check(const trn_lcan_cfg_t *cfg)
{
    size_t i;
    trn_status_t st;
    if (cfg == NULL) {
        return TRN_E_NULL;
    }
    st = check_ifname(cfg->ifname);
    if (st != TRN_OK) {
        return st;
    }
    if (cfg->n_filters > TRN_LCAN_MAX_FILTERS) {
        return TRN_E_SIZE;
    }
    if (cfg->n_filters > 0u && cfg->filters == NULL) {
        return TRN_E_NULL;
    }
    for (i = 0u; i < cfg->n_filters; ++i) {
        const trn_lcan_filter_t *f = &cfg->filters[i];
        if (!is_flag(f->extended) || !id_in_range(f->id, f->extended) ||
            !id_in_range(f->mask, f->extended)) {
            return TRN_E_ARG;
        }
    }
    if (cfg->rcvbuf_bytes < 0 || cfg->rcvbuf_bytes > (1 << 24)) {
        return TRN_E_ARG;
    }
    if (!is_flag(cfg->recv_own) || !is_flag(cfg->error_frames)) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}

static void lcan_reset(trn_lcan_t *can)
{
    memset(can, 0, sizeof *can);
    can->fd = -1;
    can->bus.state = TRN_LCAN_ERROR_ACTIVE;
}

/* setsockopt or fail: every option is checked. */
static int set_opt(int fd, int level, int name, const void *val, size_t len)
{
    return setsockopt(fd, level, name, val, (socklen_t)len);
}

trn_status_t trn_lcan_open(trn_lcan_t *can, const trn_lcan_cfg_t *cfg)
{
    struct can_filter kf[TRN_LCAN_MAX_FILTERS];
    struct sockaddr_can addr;
    size_t nf;
    size_t i;
    unsigned ifindex;
    int fd;
    int one = 1;
    int own;
    can_err_mask_t err_mask;
    trn_status_t st;
    int err;

    if (can == NULL) {
        return TRN_E_NULL;
    }
    lcan_reset(can);
    st = trn_lcan_cfg_check(cfg);
    if (st != TRN_OK) {
        return st;
    }

    ifindex = if_nametoindex(cfg->ifname);
    if (ifindex == 0u) {
        return open_status_from_errno(errno == 0 ? ENODEV : errno);
    }
    fd = socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
    if (fd < 0) {
        return open_status_from_errno(errno);
    }

    /* Filters: the format bit and RTR are always part of the mask, so a
     * standard filter never passes an extended frame nor a remote frame. */
    if (cfg->n_filters == 0u) {
        kf[0].can_id = 0u;
        kf[0].can_mask = 0u;
        nf = 1u;
    } else {
        for (i = 0u; i < cfg->n_filters; ++i) {
            const trn_lcan_filter_t *f = &cfg->filters[i];
            uint32_t eff = f->extended ? (uint32_t)CAN_EFF_FLAG : 0u;
            kf[i].can_id = (canid_t)(f->id | eff);
            kf[i].can_mask = (canid_t)(f->mask | (uint32_t)CAN_EFF_FLAG | (uint32_t)CAN_RTR_FLAG);
        }
        nf = cfg->n_filters;
    }
    err_mask = cfg->error_frames ? (can_err_mask_t)CAN_ERR_MASK : 0u;
    own = cfg->recv_own ? 1 : 0;

    if (set_opt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, kf, nf * sizeof kf[0]) != 0 ||
        set_opt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) != 0 ||
        set_opt(fd, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &own, sizeof own) != 0 ||
        set_opt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one) != 0) {
        err = errno;
        (void)close(fd);
        return open_status_from_errno(err);
    }
    if (cfg->rcvbuf_bytes > 0) {
        int rb = (int)cfg->rcvbuf_bytes;
        if (set_opt(fd, SOL_SOCKET, SO_RCVBUF, &rb, sizeof rb) != 0) {
            err = errno;
            (void)close(fd);
            return open_status_from_errno(err);
        }
    }

    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)ifindex;
    if (bind(fd, (const struct sockaddr *)(const void *)&addr, (socklen_t)sizeof addr) != 0) {
        err = errno;
        (void)close(fd);
        return open_status_from_errno(err);
    }
    can->fd = fd;
    return TRN_OK;
}

trn_status_t trn_lcan_close(trn_lcan_t *can)
{
    int rc = 0;
    if (can == NULL) {
        return TRN_E_NULL;
    }
    if (can->fd >= 0) {
        rc = close(can->fd);
    }
    lcan_reset(can);
    return rc == 0 ? TRN_OK : TRN_E_IO;
}

static int frame_ok(const trn_lcan_frame_t *f)
{
    return is_flag(f->extended) && id_in_range(f->id, f->extended) && f->len <= 8u;
}

trn_status_t trn_lcan_send(trn_lcan_t *can, const trn_lcan_frame_t *frame, int32_t timeout_ms)
{
    struct can_frame kf;
    int64_t deadline;
    unsigned round;

    if (can == NULL || frame == NULL) {
        return TRN_E_NULL;
    }
    if (can->fd < 0 || !timeout_ok(timeout_ms) || !frame_ok(frame)) {
        return TRN_E_ARG;
    }
    memset(&kf, 0, sizeof kf);
    kf.can_id = (canid_t)(frame->id | (frame->extended ? (uint32_t)CAN_EFF_FLAG : 0u));
    kf.can_dlc = frame->len;
    memcpy(kf.data, frame->data, frame->len);

    deadline = now_ms() + timeout_ms;
    for (round = 0u; round < TRN_LCAN_MAX_ROUNDS; ++round) {
        ssize_t n = send(can->fd, &kf, sizeof kf, MSG_DONTWAIT);
        if (n == (ssize_t)sizeof kf) {
            return TRN_OK;
        }
        if (n >= 0) {
            return TRN_E_IO; /* a raw CAN socket never takes part of a frame */
        }
        if (errno == EINTR) {
            continue;
        }
        if (errno == ENOBUFS || errno == EAGAIN) {
            /* Queue full: poll does not signal room on CAN, so retry. */
            struct timespec ts;
            if (remaining_ms(deadline) <= 0) {
                return TRN_E_TIMEOUT;
            }
            ts.tv_sec = 0;
            ts.tv_nsec = TRN_LCAN_TXQ_RETRY_NS;
            (void)nanosleep(&ts, NULL);
            continue;
        }
        return trn_lcan_status_from_errno(errno);
    }
    return TRN_E_TIMEOUT;
}

trn_status_t trn_lcan_decode_error(trn_lcan_bus_t *bus, uint32_t err_bits, const uint8_t data[8])
{
    if (bus == NULL || data == NULL) {
        return TRN_E_NULL;
    }
    if ((err_bits & ~(uint32_t)CAN_ERR_MASK) != 0u) {
        return TRN_E_ARG;
    }
    bus->error_frames++;
    bus->last_error_class = err_bits;
    memcpy(bus->last_error_data, data, 8u);
    if ((err_bits & (uint32_t)CAN_ERR_RESTARTED) != 0u) {
        bus->state = TRN_LCAN_ERROR_ACTIVE;
    }
    if ((err_bits & (uint32_t)CAN_ERR_CRTL) != 0u) {
        uint8_t c = data[1];
        if ((c & (CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW)) != 0u) {
            bus->ctrl_overflows++;
        }
        if ((c & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0u) {
            bus->state = TRN_LCAN_ERROR_PASSIVE;
        } else if ((c & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING)) != 0u) {
            bus->state = TRN_LCAN_ERROR_WARNING;
        } else if ((c & CAN_ERR_CRTL_ACTIVE) != 0u) {
            bus->state = TRN_LCAN_ERROR_ACTIVE;
        }
    }
    if ((err_bits & (uint32_t)CAN_ERR_BUSOFF) != 0u) {
        bus->state = TRN_LCAN_BUS_OFF;
    }
    return TRN_OK;
}

/* The SO_RXQ_OVFL count in a received message's control data, if any. */
static void read_drops(trn_lcan_bus_t *bus, struct msghdr *mh)
{
    struct cmsghdr *c;
    unsigned k = 0u;
    for (c = CMSG_FIRSTHDR(mh); c != NULL && k < 16u; c = CMSG_NXTHDR(mh, c), ++k) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL &&
            c->cmsg_len >= CMSG_LEN(sizeof(uint32_t))) {
            uint32_t d;
            memcpy(&d, CMSG_DATA(c), sizeof d);
            bus->rx_drops = d;
        }
    }
}

trn_status_t trn_lcan_recv(trn_lcan_t *can, trn_lcan_frame_t *frame, int32_t timeout_ms)
{
    int64_t deadline;
    unsigned round;

    if (can == NULL || frame == NULL) {
        return TRN_E_NULL;
    }
    if (can->fd < 0 || !timeout_ok(timeout_ms)) {
        return TRN_E_ARG;
    }
    deadline = now_ms() + timeout_ms;
    for (round = 0u; round < TRN_LCAN_MAX_ROUNDS; ++round) {
        struct can_frame kf;
        struct iovec iov;
        struct msghdr mh;
        union {
            char buf[CMSG_SPACE(sizeof(uint32_t)) * 2u];
            struct cmsghdr align;
        } ctl;
        ssize_t n;
        trn_status_t st;

        st = wait_fd(can->fd, POLLIN, deadline);
        if (st != TRN_OK) {
            return st;
        }
        iov.iov_base = &kf;
        iov.iov_len = sizeof kf;
        memset(&mh, 0, sizeof mh);
        mh.msg_iov = &iov;
        mh.msg_iovlen = 1u;
        mh.msg_control = ctl.buf;
        mh.msg_controllen = sizeof ctl.buf;
        n = recvmsg(can->fd, &mh, MSG_DONTWAIT);
        if (n < 0) {
            if (errno == EINTR || errno == EAGAIN) {
                continue;
            }
            return trn_lcan_status_from_errno(errno);
        }
        read_drops(&can->bus, &mh);
        if (n != (ssize_t)sizeof kf || (mh.msg_flags & MSG_TRUNC) != 0) {
            return TRN_E_FORMAT;
        }
        if ((kf.can_id & CAN_ERR_FLAG) != 0u) {
            uint8_t d[8];
            memcpy(d, kf.data, 8u);
            (void)trn_lcan_decode_error(&can->bus, (uint32_t)(kf.can_id & CAN_ERR_MASK), d);
            return TRN_E_BUS;
        }
        if ((kf.can_id & CAN_RTR_FLAG) != 0u) {
            continue; /* remote frames are not data; trn does not use them */
        }
        if (kf.can_dlc > 8u) {
            return TRN_E_FORMAT;
        }
        if ((kf.can_id & CAN_EFF_FLAG) != 0u) {
            frame->id = (uint32_t)(kf.can_id & CAN_EFF_MASK);
            frame->extended = 1u;
        } else {
            frame->id = (uint32_t)(kf.can_id & CAN_SFF_MASK);
            frame->extended = 0u;
        }
        frame->len = kf.can_dlc;
        memcpy(frame->data, kf.data, 8u);
        return TRN_OK;
    }
    return TRN_E_TIMEOUT;
}

trn_status_t trn_lcan_bus_status(const trn_lcan_t *can, trn_lcan_bus_t *bus)
{
    if (can == NULL || bus == NULL) {
        return TRN_E_NULL;
    }
    *bus = can->bus;
    return TRN_OK;
}

/* ------------------------------------------------------------------------ */
/* ISO-TP                                                                    */

static int stmin_ok(uint8_t s) { return s <= 0x7Fu || (s >= 0xF1u && s <= 0xF9u); }

trn_status_t trn_lisotp_cfg_default(trn_lisotp_cfg_t *cfg)
{
    if (cfg == NULL) {
        return TRN_E_NULL;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->ifname = "can0";
    cfg->tx_id = 0x7E0u;
    cfg->rx_id = 0x7E8u;
    cfg->extended = 0u;
    cfg->block_size = 0u;
    cfg->stmin = 0u;
    cfg->tx_padding = 1u;
    cfg->pad_byte = 0xCCu;
    cfg->frame_txtime_us = 0u;
    return TRN_OK;
}

trn_status_t trn_lisotp_cfg_check(const trn_lisotp_cfg_t *cfg)
{
    trn_status_t st;
    if (cfg == NULL) {
        return TRN_E_NULL;
    }
    st = check_ifname(cfg->ifname);
    if (st != TRN_OK) {
        return st;
    }
    if (!is_flag(cfg->extended) || !is_flag(cfg->tx_padding) ||
        !id_in_range(cfg->tx_id, cfg->extended) || !id_in_range(cfg->rx_id, cfg->extended) ||
        cfg->tx_id == cfg->rx_id || !stmin_ok(cfg->stmin) || cfg->frame_txtime_us > 100000u) {
        return TRN_E_ARG;
    }
    return TRN_OK;
}

trn_status_t trn_lisotp_open(trn_lisotp_t *tp, const trn_lisotp_cfg_t *cfg)
{
    struct can_isotp_options opts;
    struct can_isotp_fc_options fc;
    struct sockaddr_can addr;
    uint32_t eff;
    unsigned ifindex;
    int fd;
    int err;
    trn_status_t st;

    if (tp == NULL) {
        return TRN_E_NULL;
    }
    tp->fd = -1;
    st = trn_lisotp_cfg_check(cfg);
    if (st != TRN_OK) {
        return st;
    }
    ifindex = if_nametoindex(cfg->ifname);
    if (ifindex == 0u) {
        return open_status_from_errno(errno == 0 ? ENODEV : errno);
    }
    fd = socket(PF_CAN, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_ISOTP);
    if (fd < 0) {
        return open_status_from_errno(errno);
    }

    memset(&opts, 0, sizeof opts);
    opts.flags = cfg->tx_padding ? (uint32_t)CAN_ISOTP_TX_PADDING : 0u;
    opts.frame_txtime = cfg->frame_txtime_us == 0u ? (uint32_t)CAN_ISOTP_FRAME_TXTIME_ZERO
                                                   : cfg->frame_txtime_us * 1000u;
    opts.txpad_content = cfg->pad_byte;
    opts.rxpad_content = cfg->pad_byte;
    memset(&fc, 0, sizeof fc);
    fc.bs = cfg->block_size;
    fc.stmin = cfg->stmin;
    fc.wftmax = 0u;
    if (set_opt(fd, SOL_CAN_ISOTP, CAN_ISOTP_OPTS, &opts, sizeof opts) != 0 ||
        set_opt(fd, SOL_CAN_ISOTP, CAN_ISOTP_RECV_FC, &fc, sizeof fc) != 0) {
        err = errno;
        (void)close(fd);
        return open_status_from_errno(err);
    }

    eff = cfg->extended ? (uint32_t)CAN_EFF_FLAG : 0u;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)ifindex;
    addr.can_addr.tp.tx_id = (canid_t)(cfg->tx_id | eff);
    addr.can_addr.tp.rx_id = (canid_t)(cfg->rx_id | eff);
    if (bind(fd, (const struct sockaddr *)(const void *)&addr, (socklen_t)sizeof addr) != 0) {
        err = errno;
        (void)close(fd);
        return open_status_from_errno(err);
    }
    tp->fd = fd;
    return TRN_OK;
}

trn_status_t trn_lisotp_close(trn_lisotp_t *tp)
{
    int rc = 0;
    if (tp == NULL) {
        return TRN_E_NULL;
    }
    if (tp->fd >= 0) {
        rc = close(tp->fd);
    }
    tp->fd = -1;
    return rc == 0 ? TRN_OK : TRN_E_IO;
}

trn_status_t trn_lisotp_send(trn_lisotp_t *tp, const uint8_t *msg, size_t len, int32_t timeout_ms)
{
    int64_t deadline;
    unsigned round;

    if (tp == NULL || msg == NULL) {
        return TRN_E_NULL;
    }
    if (tp->fd < 0 || !timeout_ok(timeout_ms)) {
        return TRN_E_ARG;
    }
    if (len == 0u || len > TRN_LISOTP_MAX_MSG) {
        return TRN_E_SIZE;
    }
    deadline = now_ms() + timeout_ms;
    for (round = 0u; round < TRN_LCAN_MAX_ROUNDS; ++round) {
        ssize_t n;
        /* POLLOUT on an ISO-TP socket means "no transfer in progress". */
        trn_status_t st = wait_fd(tp->fd, POLLOUT, deadline);
        if (st != TRN_OK) {
            return st;
        }
        n = send(tp->fd, msg, len, MSG_DONTWAIT);
        if (n < 0) {
            if (errno == EINTR || errno == EAGAIN) {
                continue;
            }
            if (errno == EINVAL) {
                return TRN_E_SIZE; /* longer than this kernel takes */
            }
            return trn_lcan_status_from_errno(errno);
        }
        if ((size_t)n != len) {
            return TRN_E_IO;
        }
        /* Idle again = the kernel finished; a failure shows as POLLERR. */
        st = wait_fd(tp->fd, POLLOUT, deadline);
        if (st != TRN_OK) {
            return st;
        }
        return take_socket_error(tp->fd);
    }
    return TRN_E_TIMEOUT;
}

trn_status_t trn_lisotp_recv(trn_lisotp_t *tp, uint8_t *buf, size_t cap, size_t *len,
                             int32_t timeout_ms)
{
    int64_t deadline;
    unsigned round;

    if (tp == NULL || buf == NULL || len == NULL) {
        return TRN_E_NULL;
    }
    if (tp->fd < 0 || !timeout_ok(timeout_ms)) {
        return TRN_E_ARG;
    }
    if (cap == 0u || cap > TRN_LISOTP_MAX_MSG) {
        return TRN_E_SIZE;
    }
    deadline = now_ms() + timeout_ms;
    for (round = 0u; round < TRN_LCAN_MAX_ROUNDS; ++round) {
        uint8_t probe;
        ssize_t whole;
        ssize_t n;
        trn_status_t st = wait_fd(tp->fd, POLLIN, deadline);
        if (st != TRN_OK) {
            return st;
        }
        /* Peek the length first, so a too-long message never lands half in buf. */
        whole = recv(tp->fd, &probe, 1u, MSG_DONTWAIT | MSG_PEEK | MSG_TRUNC);
        if (whole < 0) {
            if (errno == EINTR || errno == EAGAIN) {
                continue;
            }
            return trn_lcan_status_from_errno(errno);
        }
        if ((size_t)whole > cap) {
            *len = (size_t)whole;
            (void)recv(tp->fd, &probe, 1u, MSG_DONTWAIT | MSG_TRUNC); /* discard it */
            return TRN_E_CAPACITY;
        }
        n = recv(tp->fd, buf, cap, MSG_DONTWAIT);
        if (n < 0) {
            if (errno == EINTR || errno == EAGAIN) {
                continue;
            }
            return trn_lcan_status_from_errno(errno);
        }
        if (n != whole) {
            return TRN_E_IO;
        }
        *len = (size_t)n;
        return TRN_OK;
    }
    return TRN_E_TIMEOUT;
}
