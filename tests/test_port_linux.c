/* SPDX-License-Identifier: Apache-2.0 */
/* test_port_linux.c - host unit tests of the Linux port (linux_can.h,
 * linux_gpio.h): what runs without CAN or GPIO in the kernel.
 *
 * Configuration checks (one assertion per bad-input class), the error-frame
 * decoding against a table written from linux/can/error.h, the errno
 * mapping, NULL and closed-handle arguments of every call, and opens that
 * must fail by name on a machine without vcan or GPIO chips. What needs the
 * real kernel (round trips, timeouts, error frames on a bus, drops, gpio-sim)
 * is in tests/integration (CTest label `kernel`).
 */
#define _DEFAULT_SOURCE
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <errno.h>
#include <string.h>

#include <linux/can.h>
#include <linux/can/error.h>

#include "trn_port/linux_can.h"
#include "trn_port/linux_gpio.h"

/* ------------------------------------------------------------------ CAN cfg */

static void test_lcan_cfg_default_is_valid(void **state)
{
    trn_lcan_cfg_t c;
    (void)state;
    assert_int_equal(trn_lcan_cfg_default(&c), TRN_OK);
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_OK);
    assert_string_equal(c.ifname, "can0");
    assert_int_equal(c.error_frames, 1);
    assert_int_equal(trn_lcan_cfg_default(NULL), TRN_E_NULL);
}

static void test_lcan_cfg_check_classes(void **state)
{
    trn_lcan_filter_t f[TRN_LCAN_MAX_FILTERS + 1u];
    trn_lcan_cfg_t c;
    size_t i;
    (void)state;
    memset(f, 0, sizeof f);
    for (i = 0; i <= TRN_LCAN_MAX_FILTERS; ++i) {
        f[i].id = (uint32_t)i;
        f[i].mask = 0x7FFu;
    }
    assert_int_equal(trn_lcan_cfg_check(NULL), TRN_E_NULL);

    trn_lcan_cfg_default(&c);
    c.ifname = NULL;
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_E_NULL);
    c.ifname = "";
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_E_SIZE);
    c.ifname = "0123456789abcdef"; /* 16 chars: one too many */
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_E_SIZE);
    c.ifname = "0123456789abcde"; /* 15: the longest */
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_OK);

    trn_lcan_cfg_default(&c);
    c.n_filters = 1u;
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_E_NULL); /* filters NULL */
    c.filters = f;
    c.n_filters = TRN_LCAN_MAX_FILTERS;
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_OK);
    c.n_filters = TRN_LCAN_MAX_FILTERS + 1u;
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_E_SIZE);

    c.n_filters = 1u;
    f[0].id = 0x800u; /* not an 11-bit id */
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_E_ARG);
    f[0].extended = 1u; /* fine as a 29-bit id */
    f[0].mask = 0x1FFFFFFFu;
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_OK);
    f[0].mask = 0x20000000u;
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_E_ARG);
    f[0].mask = 0u;
    f[0].extended = 2u;
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_E_ARG);
    f[0].extended = 0u;
    f[0].id = 0u;

    c.rcvbuf_bytes = -1;
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_E_ARG);
    c.rcvbuf_bytes = (1 << 24) + 1;
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_E_ARG);
    c.rcvbuf_bytes = 1 << 24;
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_OK);
    c.recv_own = 2u;
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_E_ARG);
    c.recv_own = 0u;
    c.error_frames = 2u;
    assert_int_equal(trn_lcan_cfg_check(&c), TRN_E_ARG);
}

/* ------------------------------------------------------- error-frame decode */

typedef struct {
    uint32_t bits;
    uint8_t d1;
    trn_lcan_state_t before;
    trn_lcan_state_t after;
    uint32_t overflows;
} decode_case_t;

static void test_lcan_decode_error_table(void **state)
{
    static const decode_case_t cases[] = {
        {CAN_ERR_CRTL, CAN_ERR_CRTL_RX_WARNING, TRN_LCAN_ERROR_ACTIVE, TRN_LCAN_ERROR_WARNING, 0},
        {CAN_ERR_CRTL, CAN_ERR_CRTL_TX_WARNING, TRN_LCAN_ERROR_ACTIVE, TRN_LCAN_ERROR_WARNING, 0},
        {CAN_ERR_CRTL, CAN_ERR_CRTL_RX_PASSIVE, TRN_LCAN_ERROR_ACTIVE, TRN_LCAN_ERROR_PASSIVE, 0},
        {CAN_ERR_CRTL, CAN_ERR_CRTL_TX_PASSIVE, TRN_LCAN_ERROR_WARNING, TRN_LCAN_ERROR_PASSIVE, 0},
        /* passive wins over warning in one frame */
        {CAN_ERR_CRTL, CAN_ERR_CRTL_TX_PASSIVE | CAN_ERR_CRTL_RX_WARNING, TRN_LCAN_ERROR_ACTIVE,
         TRN_LCAN_ERROR_PASSIVE, 0},
        {CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE, TRN_LCAN_ERROR_PASSIVE, TRN_LCAN_ERROR_ACTIVE, 0},
        {CAN_ERR_CRTL, CAN_ERR_CRTL_RX_OVERFLOW, TRN_LCAN_ERROR_WARNING, TRN_LCAN_ERROR_WARNING, 1},
        {CAN_ERR_CRTL, CAN_ERR_CRTL_TX_OVERFLOW, TRN_LCAN_ERROR_ACTIVE, TRN_LCAN_ERROR_ACTIVE, 1},
        {CAN_ERR_BUSOFF, 0, TRN_LCAN_ERROR_PASSIVE, TRN_LCAN_BUS_OFF, 0},
        /* bus-off wins over anything else in the same frame */
        {CAN_ERR_BUSOFF | CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE, TRN_LCAN_ERROR_ACTIVE,
         TRN_LCAN_BUS_OFF, 0},
        {CAN_ERR_RESTARTED, 0, TRN_LCAN_BUS_OFF, TRN_LCAN_ERROR_ACTIVE, 0},
        /* classes that say nothing about the state keep it */
        {CAN_ERR_PROT, 0, TRN_LCAN_ERROR_WARNING, TRN_LCAN_ERROR_WARNING, 0},
        {CAN_ERR_ACK, 0, TRN_LCAN_ERROR_PASSIVE, TRN_LCAN_ERROR_PASSIVE, 0},
        {CAN_ERR_LOSTARB, 0, TRN_LCAN_BUS_OFF, TRN_LCAN_BUS_OFF, 0},
        {CAN_ERR_TX_TIMEOUT, 0, TRN_LCAN_ERROR_ACTIVE, TRN_LCAN_ERROR_ACTIVE, 0},
        {CAN_ERR_BUSERROR, 0, TRN_LCAN_ERROR_ACTIVE, TRN_LCAN_ERROR_ACTIVE, 0},
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        trn_lcan_bus_t bus;
        uint8_t d[8] = {0x11, 0, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88};
        memset(&bus, 0, sizeof bus);
        bus.state = cases[i].before;
        bus.error_frames = 5u;
        d[1] = cases[i].d1;
        assert_int_equal(trn_lcan_decode_error(&bus, cases[i].bits, d), TRN_OK);
        assert_int_equal(bus.state, cases[i].after);
        assert_int_equal(bus.error_frames, 6u);
        assert_int_equal(bus.ctrl_overflows, cases[i].overflows);
        assert_int_equal(bus.last_error_class, cases[i].bits);
        assert_memory_equal(bus.last_error_data, d, 8);
        assert_int_equal(bus.rx_drops, 0u); /* not the decoder's business */
    }
}

static void test_lcan_decode_error_args(void **state)
{
    trn_lcan_bus_t bus;
    uint8_t d[8] = {0};
    (void)state;
    memset(&bus, 0, sizeof bus);
    assert_int_equal(trn_lcan_decode_error(NULL, CAN_ERR_BUSOFF, d), TRN_E_NULL);
    assert_int_equal(trn_lcan_decode_error(&bus, CAN_ERR_BUSOFF, NULL), TRN_E_NULL);
    assert_int_equal(trn_lcan_decode_error(&bus, CAN_ERR_FLAG | CAN_ERR_BUSOFF, d), TRN_E_ARG);
    assert_int_equal(bus.error_frames, 0u); /* a refused frame changes nothing */
    assert_int_equal(bus.state, TRN_LCAN_ERROR_ACTIVE);
}

static void test_status_from_errno(void **state)
{
    (void)state;
    assert_int_equal(trn_lcan_status_from_errno(0), TRN_OK);
    assert_int_equal(trn_lcan_status_from_errno(ETIMEDOUT), TRN_E_TIMEOUT);
    assert_int_equal(trn_lcan_status_from_errno(ECOMM), TRN_E_TIMEOUT);
    assert_int_equal(trn_lcan_status_from_errno(EILSEQ), TRN_E_SEQ);
    assert_int_equal(trn_lcan_status_from_errno(EBADMSG), TRN_E_FORMAT);
    assert_int_equal(trn_lcan_status_from_errno(EMSGSIZE), TRN_E_CAPACITY);
    assert_int_equal(trn_lcan_status_from_errno(ENETDOWN), TRN_E_BUS);
    assert_int_equal(trn_lcan_status_from_errno(ENODEV), TRN_E_BUS);
    assert_int_equal(trn_lcan_status_from_errno(ENXIO), TRN_E_BUS);
    assert_int_equal(trn_lcan_status_from_errno(ENETUNREACH), TRN_E_BUS);
    assert_int_equal(trn_lcan_status_from_errno(EPERM), TRN_E_IO);
    assert_int_equal(trn_lcan_status_from_errno(EBADF), TRN_E_IO);
}

/* ------------------------------------------------------------- CAN handles */

static void test_lcan_calls_null_and_closed(void **state)
{
    trn_lcan_t can;
    trn_lcan_cfg_t c;
    trn_lcan_frame_t f;
    trn_lcan_bus_t bus;
    (void)state;
    memset(&f, 0, sizeof f);
    trn_lcan_cfg_default(&c);
    assert_int_equal(trn_lcan_open(NULL, &c), TRN_E_NULL);
    assert_int_equal(trn_lcan_open(&can, NULL), TRN_E_NULL);
    assert_int_equal(can.fd, -1);
    c.ifname = "";
    assert_int_equal(trn_lcan_open(&can, &c), TRN_E_SIZE);
    assert_int_equal(can.fd, -1);

    assert_int_equal(trn_lcan_close(NULL), TRN_E_NULL);
    assert_int_equal(trn_lcan_close(&can), TRN_OK); /* closed is fine */
    assert_int_equal(trn_lcan_send(NULL, &f, 0), TRN_E_NULL);
    assert_int_equal(trn_lcan_send(&can, NULL, 0), TRN_E_NULL);
    assert_int_equal(trn_lcan_send(&can, &f, 0), TRN_E_ARG); /* closed */
    assert_int_equal(trn_lcan_recv(NULL, &f, 0), TRN_E_NULL);
    assert_int_equal(trn_lcan_recv(&can, NULL, 0), TRN_E_NULL);
    assert_int_equal(trn_lcan_recv(&can, &f, 0), TRN_E_ARG);
    assert_int_equal(trn_lcan_bus_status(NULL, &bus), TRN_E_NULL);
    assert_int_equal(trn_lcan_bus_status(&can, NULL), TRN_E_NULL);
    assert_int_equal(trn_lcan_bus_status(&can, &bus), TRN_OK);
    assert_int_equal(bus.state, TRN_LCAN_ERROR_ACTIVE);
    assert_int_equal(bus.error_frames, 0u);
}

/* Without a CAN interface of that name, or on a non-CAN one, open fails as a
 * bus problem and leaves the handle closed. */
static void test_lcan_open_no_such_interface(void **state)
{
    trn_lcan_t can;
    trn_lcan_cfg_t c;
    (void)state;
    trn_lcan_cfg_default(&c);
    c.ifname = "trnnosuch0";
    assert_int_equal(trn_lcan_open(&can, &c), TRN_E_BUS);
    assert_int_equal(can.fd, -1);
    c.ifname = "lo"; /* exists, but is not a CAN device */
    assert_int_equal(trn_lcan_open(&can, &c), TRN_E_BUS);
    assert_int_equal(can.fd, -1);
}

/* ----------------------------------------------------------------- ISO-TP */

static void test_lisotp_cfg(void **state)
{
    trn_lisotp_cfg_t c;
    (void)state;
    assert_int_equal(trn_lisotp_cfg_default(NULL), TRN_E_NULL);
    assert_int_equal(trn_lisotp_cfg_default(&c), TRN_OK);
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_OK);
    assert_int_equal(trn_lisotp_cfg_check(NULL), TRN_E_NULL);
    c.ifname = NULL;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_E_NULL);
    c.ifname = "";
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_E_SIZE);

    trn_lisotp_cfg_default(&c);
    c.tx_id = 0x800u;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_E_ARG);
    c.extended = 1u;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_OK);
    c.rx_id = 0x20000000u;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_E_ARG);
    trn_lisotp_cfg_default(&c);
    c.rx_id = c.tx_id;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_E_ARG);
    trn_lisotp_cfg_default(&c);
    c.extended = 2u;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_E_ARG);
    trn_lisotp_cfg_default(&c);
    c.tx_padding = 2u;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_E_ARG);

    /* STmin: 0x00..0x7F and 0xF1..0xF9 are the ISO codes; the rest reserved */
    trn_lisotp_cfg_default(&c);
    c.stmin = 0x7Fu;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_OK);
    c.stmin = 0x80u;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_E_ARG);
    c.stmin = 0xF0u;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_E_ARG);
    c.stmin = 0xF1u;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_OK);
    c.stmin = 0xF9u;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_OK);
    c.stmin = 0xFAu;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_E_ARG);

    trn_lisotp_cfg_default(&c);
    c.frame_txtime_us = 100000u;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_OK);
    c.frame_txtime_us = 100001u;
    assert_int_equal(trn_lisotp_cfg_check(&c), TRN_E_ARG);
}

static void test_lisotp_calls_null_and_closed(void **state)
{
    static uint8_t buf[16];
    trn_lisotp_t tp;
    trn_lisotp_cfg_t c;
    size_t len = 0u;
    (void)state;
    trn_lisotp_cfg_default(&c);
    assert_int_equal(trn_lisotp_open(NULL, &c), TRN_E_NULL);
    assert_int_equal(trn_lisotp_open(&tp, NULL), TRN_E_NULL);
    assert_int_equal(tp.fd, -1);
    c.ifname = "trnnosuch0";
    assert_int_equal(trn_lisotp_open(&tp, &c), TRN_E_BUS);
    assert_int_equal(tp.fd, -1);
    assert_int_equal(trn_lisotp_close(NULL), TRN_E_NULL);
    assert_int_equal(trn_lisotp_close(&tp), TRN_OK);

    assert_int_equal(trn_lisotp_send(NULL, buf, 1u, 0), TRN_E_NULL);
    assert_int_equal(trn_lisotp_send(&tp, NULL, 1u, 0), TRN_E_NULL);
    assert_int_equal(trn_lisotp_send(&tp, buf, 1u, 0), TRN_E_ARG); /* closed */
    assert_int_equal(trn_lisotp_recv(NULL, buf, sizeof buf, &len, 0), TRN_E_NULL);
    assert_int_equal(trn_lisotp_recv(&tp, NULL, sizeof buf, &len, 0), TRN_E_NULL);
    assert_int_equal(trn_lisotp_recv(&tp, buf, sizeof buf, NULL, 0), TRN_E_NULL);
    assert_int_equal(trn_lisotp_recv(&tp, buf, sizeof buf, &len, 0), TRN_E_ARG);
}

/* ------------------------------------------------------------------- GPIO */

static void test_lgpio_cfg(void **state)
{
    trn_lgpio_cfg_t c;
    (void)state;
    assert_int_equal(trn_lgpio_cfg_default(NULL), TRN_E_NULL);
    assert_int_equal(trn_lgpio_cfg_default(&c), TRN_OK);
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_OK);
    assert_int_equal(trn_lgpio_cfg_check(NULL), TRN_E_NULL);
    c.chip = NULL;
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_E_NULL);
    trn_lgpio_cfg_default(&c);
    c.consumer = NULL;
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_E_NULL);
    c.consumer = "";
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_E_SIZE);
    trn_lgpio_cfg_default(&c);
    c.chip = "";
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_E_SIZE);

    trn_lgpio_cfg_default(&c);
    c.power_offset = TRN_LGPIO_MAX_OFFSET + 1u;
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_E_ARG);
    c.power_offset = TRN_LGPIO_MAX_OFFSET;
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_OK);
    /* every pair of equal offsets */
    trn_lgpio_cfg_default(&c);
    c.trigger_offset = c.power_offset;
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_E_ARG);
    trn_lgpio_cfg_default(&c);
    c.deployed_offset = c.power_offset;
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_E_ARG);
    trn_lgpio_cfg_default(&c);
    c.deployed_offset = c.trigger_offset;
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_E_ARG);

    trn_lgpio_cfg_default(&c);
    c.power_active_low = 2u;
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_E_ARG);
    trn_lgpio_cfg_default(&c);
    c.trigger_active_low = 2u;
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_E_ARG);
    trn_lgpio_cfg_default(&c);
    c.deployed_active_low = 2u;
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_E_ARG);

    trn_lgpio_cfg_default(&c);
    c.trigger_pulse_us = 0u;
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_E_ARG);
    c.trigger_pulse_us = TRN_LGPIO_MAX_PULSE_US + 1u;
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_E_ARG);
    c.trigger_pulse_us = TRN_LGPIO_MAX_PULSE_US;
    assert_int_equal(trn_lgpio_cfg_check(&c), TRN_OK);
}

static void test_lgpio_calls_null_and_closed(void **state)
{
    trn_lgpio_t g;
    trn_lgpio_cfg_t c;
    int v = 7;
    (void)state;
    trn_lgpio_cfg_default(&c);
    assert_int_equal(trn_lgpio_open(NULL, &c), TRN_E_NULL);
    assert_int_equal(trn_lgpio_open(&g, NULL), TRN_E_NULL);
    assert_null(g.chip);
    c.chip = "trn-no-such-chip";
    assert_int_equal(trn_lgpio_open(&g, &c), TRN_E_IO);
    assert_null(g.chip);
#if TRN_GPIOD_API == 2
    assert_null(g.request);
#else
    assert_null(g.power);
#endif

    assert_int_equal(trn_lgpio_close(NULL), TRN_E_NULL);
    assert_int_equal(trn_lgpio_close(&g), TRN_OK);
    assert_int_equal(trn_lgpio_set_power(NULL, 1), TRN_E_NULL);
    assert_int_equal(trn_lgpio_set_power(&g, 1), TRN_E_ARG);
    assert_int_equal(trn_lgpio_trigger(NULL), TRN_E_NULL);
    assert_int_equal(trn_lgpio_trigger(&g), TRN_E_ARG);
    assert_int_equal(trn_lgpio_read_deployed(NULL, &v), TRN_E_NULL);
    assert_int_equal(trn_lgpio_read_deployed(&g, NULL), TRN_E_NULL);
    assert_int_equal(trn_lgpio_read_deployed(&g, &v), TRN_E_ARG);
    assert_int_equal(v, 7);
    assert_int_equal(trn_lgpio_wait_deployed(NULL, 0), TRN_E_NULL);
    assert_int_equal(trn_lgpio_wait_deployed(&g, 0), TRN_E_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lcan_cfg_default_is_valid),
        cmocka_unit_test(test_lcan_cfg_check_classes),
        cmocka_unit_test(test_lcan_decode_error_table),
        cmocka_unit_test(test_lcan_decode_error_args),
        cmocka_unit_test(test_status_from_errno),
        cmocka_unit_test(test_lcan_calls_null_and_closed),
        cmocka_unit_test(test_lcan_open_no_such_interface),
        cmocka_unit_test(test_lisotp_cfg),
        cmocka_unit_test(test_lisotp_calls_null_and_closed),
        cmocka_unit_test(test_lgpio_cfg),
        cmocka_unit_test(test_lgpio_calls_null_and_closed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
