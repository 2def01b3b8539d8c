/* SPDX-License-Identifier: Apache-2.0 */
/* test_port_linux_errors.c - the Linux port's own logic on the host, with a
 * Unix socket pair standing in for the kernel's CAN sockets (docs/
 * assurance.md, "Coverage").
 *
 * A handle's fd is one end of a socketpair(AF_UNIX, SOCK_SEQPACKET): the
 * test writes struct can_frame records (or ISO-TP messages) into the other
 * end, so trn_lcan_recv / trn_lisotp_recv run their real framing checks,
 * error-frame handling, timeouts and errno mapping on bytes the test chose.
 * System calls that fail by construction give TRN_E_IO: send/recv on a pipe
 * (ENOTSOCK), close of a descriptor that is not open (EBADF), opening with
 * every file descriptor of the process in use (EMFILE). What only a
 * CAN kernel can do (CAN socket options, filters, bus errors, can-isotp
 * flow control, GPIO lines) is tested in the VM (tests/integration), which
 * gcov does not see. */
#define _DEFAULT_SOURCE
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <fcntl.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <linux/can.h>
#include <linux/can/error.h>

#include "trn_port/linux_can.h"
#include "trn_port/linux_gpio.h"

static void pair(int sv[2]) { assert_int_equal(socketpair(AF_UNIX, SOCK_SEQPACKET, 0, sv), 0); }

static void put_frame(int fd, canid_t id, uint8_t dlc, uint8_t fill)
{
    struct can_frame kf;
    memset(&kf, 0, sizeof kf);
    kf.can_id = id;
    kf.can_dlc = dlc;
    memset(kf.data, fill, sizeof kf.data);
    assert_int_equal(send(fd, &kf, sizeof kf, 0), (ssize_t)sizeof kf);
}

/* A descriptor number that is certainly not open. */
static int closed_fd(void)
{
    int fd = dup(0);
    assert_true(fd >= 0);
    assert_int_equal(close(fd), 0);
    return fd;
}

static void test_lcan_recv_through_a_socket_pair(void **state)
{
    int sv[2];
    trn_lcan_t can;
    trn_lcan_frame_t f;
    uint8_t junk[5] = {1, 2, 3, 4, 5};
    (void)state;
    pair(sv);
    memset(&can, 0, sizeof can);
    can.fd = sv[0];
    /* nothing there: a timeout, also with 0 ms */
    assert_int_equal(trn_lcan_recv(&can, &f, 0), TRN_E_TIMEOUT);
    assert_int_equal(trn_lcan_recv(&can, &f, 20), TRN_E_TIMEOUT);
    /* a standard and an extended data frame */
    put_frame(sv[1], 0x121u, 8u, 0xAB);
    assert_int_equal(trn_lcan_recv(&can, &f, 100), TRN_OK);
    assert_int_equal(f.id, 0x121u);
    assert_int_equal(f.extended, 0);
    assert_int_equal(f.len, 8);
    assert_int_equal(f.data[7], 0xAB);
    put_frame(sv[1], 0x1234567u | CAN_EFF_FLAG, 3u, 0x11);
    assert_int_equal(trn_lcan_recv(&can, &f, 100), TRN_OK);
    assert_int_equal(f.id, 0x1234567u);
    assert_int_equal(f.extended, 1);
    assert_int_equal(f.len, 3);
    /* a remote frame is skipped, the data frame after it returned */
    put_frame(sv[1], 0x130u | CAN_RTR_FLAG, 4u, 0);
    put_frame(sv[1], 0x130u, 4u, 0x22);
    assert_int_equal(trn_lcan_recv(&can, &f, 100), TRN_OK);
    assert_int_equal(f.id, 0x130u);
    assert_int_equal(f.data[0], 0x22);
    /* an error frame: bus-off, counted, TRN_E_BUS */
    put_frame(sv[1], CAN_ERR_FLAG | CAN_ERR_BUSOFF, 8u, 0);
    assert_int_equal(trn_lcan_recv(&can, &f, 100), TRN_E_BUS);
    assert_int_equal(can.bus.state, TRN_LCAN_BUS_OFF);
    assert_int_equal(can.bus.error_frames, 1u);
    /* a DLC above 8, then a record that is not a whole can_frame */
    put_frame(sv[1], 0x121u, 9u, 0);
    assert_int_equal(trn_lcan_recv(&can, &f, 100), TRN_E_FORMAT);
    assert_int_equal(send(sv[1], junk, sizeof junk, 0), (ssize_t)sizeof junk);
    assert_int_equal(trn_lcan_recv(&can, &f, 100), TRN_E_FORMAT);
    assert_int_equal(close(sv[1]), 0);
    assert_int_equal(close(sv[0]), 0);
}

static void test_lcan_send_through_a_socket_pair(void **state)
{
    int sv[2], sndbuf = 1;
    trn_lcan_t can;
    trn_lcan_frame_t f;
    struct can_frame kf;
    unsigned i;
    trn_status_t st = TRN_OK;
    (void)state;
    pair(sv);
    memset(&can, 0, sizeof can);
    memset(&f, 0, sizeof f);
    can.fd = sv[0];
    f.id = 0x1A1u;
    f.len = 3u;
    f.data[0] = 0x30u;
    assert_int_equal(trn_lcan_send(&can, &f, 100), TRN_OK);
    assert_int_equal(recv(sv[1], &kf, sizeof kf, 0), (ssize_t)sizeof kf);
    assert_int_equal(kf.can_id, 0x1A1u);
    assert_int_equal(kf.can_dlc, 3);
    f.extended = 1u;
    f.id = 0x1ABCDEFu;
    assert_int_equal(trn_lcan_send(&can, &f, 100), TRN_OK);
    assert_int_equal(recv(sv[1], &kf, sizeof kf, 0), (ssize_t)sizeof kf);
    assert_int_equal(kf.can_id, 0x1ABCDEFu | CAN_EFF_FLAG);
    /* bad frames and timeouts: TRN_E_ARG before any system call */
    f.len = 9u;
    assert_int_equal(trn_lcan_send(&can, &f, 100), TRN_E_ARG);
    f.len = 1u;
    f.extended = 2u;
    assert_int_equal(trn_lcan_send(&can, &f, 100), TRN_E_ARG);
    f.extended = 0u;
    f.id = 0x800u;
    assert_int_equal(trn_lcan_send(&can, &f, 100), TRN_E_ARG);
    f.id = 0x100u;
    assert_int_equal(trn_lcan_send(&can, &f, -1), TRN_E_ARG);
    assert_int_equal(trn_lcan_send(&can, &f, TRN_LCAN_MAX_TIMEOUT_MS + 1), TRN_E_ARG);
    /* a queue that stays full: the send times out */
    assert_int_equal(setsockopt(sv[0], SOL_SOCKET, SO_SNDBUF, &sndbuf, sizeof sndbuf), 0);
    for (i = 0; i < 100000u && st == TRN_OK; ++i) {
        st = trn_lcan_send(&can, &f, 0);
    }
    assert_int_equal(st, TRN_E_TIMEOUT);
    assert_int_equal(trn_lcan_send(&can, &f, 5), TRN_E_TIMEOUT);
    assert_int_equal(close(sv[1]), 0);
    assert_int_equal(close(sv[0]), 0);
}

static void test_lcan_system_call_failures(void **state)
{
    int p[2];
    trn_lcan_t can;
    trn_lcan_frame_t f;
    trn_lcan_cfg_t c;
    trn_lcan_filter_t bad = {0x800u, 0x7FFu, 0u};
    uint8_t b = 1u;
    (void)state;
    memset(&can, 0, sizeof can);
    memset(&f, 0, sizeof f);
    assert_int_equal(pipe(p), 0);
    /* send on a pipe: ENOTSOCK */
    can.fd = p[1];
    assert_int_equal(trn_lcan_send(&can, &f, 10), TRN_E_IO);
    /* recv on a readable pipe: ENOTSOCK */
    assert_int_equal(write(p[1], &b, 1u), 1);
    can.fd = p[0];
    assert_int_equal(trn_lcan_recv(&can, &f, 10), TRN_E_IO);
    assert_int_equal(close(p[0]), 0);
    assert_int_equal(close(p[1]), 0);
    /* a descriptor that is not open: poll says POLLNVAL, close says EBADF */
    can.fd = closed_fd();
    assert_int_equal(trn_lcan_recv(&can, &f, 10), TRN_E_IO);
    assert_int_equal(trn_lcan_close(&can), TRN_E_IO);
    assert_int_equal(can.fd, -1); /* closed anyway */
    /* open with a configuration trn_lcan_cfg_check rejects */
    trn_lcan_cfg_default(&c);
    c.filters = &bad;
    c.n_filters = 1u;
    assert_int_equal(trn_lcan_open(&can, &c), TRN_E_ARG);
    assert_int_equal(can.fd, -1);
}

static void test_lisotp_through_a_socket_pair(void **state)
{
    int sv[2], p[2];
    trn_lisotp_t tp;
    uint8_t msg[300], buf[300];
    size_t len = 0u, i;
    (void)state;
    for (i = 0; i < sizeof msg; ++i) {
        msg[i] = (uint8_t)(i * 7u);
    }
    pair(sv);
    tp.fd = sv[0];
    assert_int_equal(trn_lisotp_send(&tp, msg, sizeof msg, 100), TRN_OK);
    tp.fd = sv[1];
    assert_int_equal(trn_lisotp_recv(&tp, buf, sizeof buf, &len, 100), TRN_OK);
    assert_int_equal((int)len, 300);
    assert_memory_equal(buf, msg, sizeof msg);
    /* longer than the caller's buffer: refused whole, its length told */
    tp.fd = sv[0];
    assert_int_equal(trn_lisotp_send(&tp, msg, sizeof msg, 100), TRN_OK);
    tp.fd = sv[1];
    len = 0u;
    assert_int_equal(trn_lisotp_recv(&tp, buf, 100u, &len, 100), TRN_E_CAPACITY);
    assert_int_equal((int)len, 300);
    assert_int_equal(trn_lisotp_recv(&tp, buf, sizeof buf, &len, 0), TRN_E_TIMEOUT);
    assert_int_equal(trn_lisotp_send(&tp, msg, 0u, 100), TRN_E_SIZE);
    assert_int_equal(trn_lisotp_send(&tp, msg, TRN_LISOTP_MAX_MSG + 1u, 100), TRN_E_SIZE);
    assert_int_equal(trn_lisotp_send(&tp, msg, 1u, -1), TRN_E_ARG);
    assert_int_equal(trn_lisotp_recv(&tp, buf, 0u, &len, 100), TRN_E_SIZE);
    assert_int_equal(trn_lisotp_recv(&tp, buf, 1u, &len, -1), TRN_E_ARG);
    assert_int_equal(close(sv[0]), 0);
    assert_int_equal(close(sv[1]), 0);
    /* pipes and a closed descriptor: ENOTSOCK and EBADF */
    assert_int_equal(pipe(p), 0);
    tp.fd = p[1];
    assert_int_equal(trn_lisotp_send(&tp, msg, 4u, 10), TRN_E_IO);
    assert_int_equal(write(p[1], msg, 4u), 4);
    tp.fd = p[0];
    assert_int_equal(trn_lisotp_recv(&tp, buf, sizeof buf, &len, 10), TRN_E_IO);
    assert_int_equal(close(p[0]), 0);
    assert_int_equal(close(p[1]), 0);
    tp.fd = closed_fd();
    assert_int_equal(trn_lisotp_close(&tp), TRN_E_IO);
    assert_int_equal(tp.fd, -1);
}

/* Every descriptor in use (a lowered RLIMIT_NOFILE, filled with dups): the
 * opens fail on a system call, not on the bus, so TRN_E_IO. */
static void test_opens_without_file_descriptors(void **state)
{
    struct rlimit old, low;
    int fds[64], n = 0, k;
    trn_lcan_t can;
    trn_lcan_cfg_t c;
    trn_lisotp_t tp;
    trn_lisotp_cfg_t ic;
    (void)state;
    assert_int_equal(getrlimit(RLIMIT_NOFILE, &old), 0);
    low = old;
    low.rlim_cur = 64;
    assert_int_equal(setrlimit(RLIMIT_NOFILE, &low), 0);
    while (n < 64) {
        int fd = dup(0);
        if (fd < 0) {
            break;
        }
        fds[n++] = fd;
    }
    trn_lcan_cfg_default(&c);
    c.ifname = "lo";
    trn_lisotp_cfg_default(&ic);
    ic.ifname = "lo";
    assert_int_equal(trn_lcan_open(&can, &c), TRN_E_IO);
    assert_int_equal(can.fd, -1);
    assert_int_equal(trn_lisotp_open(&tp, &ic), TRN_E_IO);
    assert_int_equal(tp.fd, -1);
    for (k = 0; k < n; ++k) {
        assert_int_equal(close(fds[k]), 0);
    }
    assert_int_equal(setrlimit(RLIMIT_NOFILE, &old), 0);
}

static void test_lgpio_open_rejects_bad_cfg(void **state)
{
    trn_lgpio_t g;
    trn_lgpio_cfg_t c;
    (void)state;
    trn_lgpio_cfg_default(&c);
    c.consumer = "";
    assert_int_equal(trn_lgpio_open(&g, &c), TRN_E_SIZE);
    assert_null(g.chip);
    trn_lgpio_cfg_default(&c);
    c.trigger_offset = c.power_offset; /* two equal offsets */
    assert_int_equal(trn_lgpio_open(&g, &c), TRN_E_ARG);
    assert_null(g.chip);
    /* a chip that does not exist */
    trn_lgpio_cfg_default(&c);
    c.chip = "trn-no-such-chip";
    assert_int_equal(trn_lgpio_open(&g, &c), TRN_E_IO);
    assert_null(g.chip);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lcan_recv_through_a_socket_pair),
        cmocka_unit_test(test_lcan_send_through_a_socket_pair),
        cmocka_unit_test(test_lcan_system_call_failures),
        cmocka_unit_test(test_lisotp_through_a_socket_pair),
        cmocka_unit_test(test_opens_without_file_descriptors),
        cmocka_unit_test(test_lgpio_open_rejects_bad_cfg),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
