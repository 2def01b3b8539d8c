/* SPDX-License-Identifier: Apache-2.0 */
/* test_port_linux_faults.c - the Linux port's OS-error paths, with the
 * failure injected at the library boundary (docs/assurance.md, "Coverage").
 *
 * Linked with -Wl,--wrap=... (tests/CMakeLists.txt): every call the port
 * makes to the wrapped functions lands in a __wrap_ function here.
 *
 * send/recv (linux_can.c): the wrapper calls the real function, unless the
 * test armed a one-shot failure, which returns -1 with the chosen errno
 * after letting `skip` calls through. The handle's fd is one end of a Unix
 * socket pair, as in test_port_linux_errors.c; the errno values are the ones
 * a can-isotp socket gives (ENETDOWN/ENODEV when the interface goes, EBADMSG
 * for a malformed flow control or padding).
 *
 * libgpiod (linux_gpio.c): the host has no GPIO chip, so the chip and line
 * calls are a small fake: three lines whose values the test sets, an event
 * queue, and the same one-shot failures. It runs the port's own logic; what
 * the real libgpiod and kernel do is tested in the VM (tests/integration).
 */
#define _DEFAULT_SOURCE
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <errno.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/types.h>
#include <unistd.h>

#include <gpiod.h>

#include "trn_port/linux_can.h"
#include "trn_port/linux_gpio.h"

/* ------------------------------------------------------------------------ */
/* one-shot faults                                                           */

enum { F_SEND, F_RECV, F_SET_VALUE, F_GET_VALUE, F_EVENT_WAIT, F_EVENT_READ, F_COUNT };

static struct {
    int armed;
    unsigned skip; /* calls let through before the failure */
    int err;
    unsigned calls; /* calls seen since the last reset */
} faults[F_COUNT];

static void arm(int which, unsigned skip, int err)
{
    faults[which].armed = 1;
    faults[which].skip = skip;
    faults[which].err = err;
}

/* 1 (errno set) if this call is to fail. */
static int fire(int which)
{
    faults[which].calls++;
    if (!faults[which].armed) {
        return 0;
    }
    if (faults[which].skip > 0u) {
        faults[which].skip--;
        return 0;
    }
    faults[which].armed = 0;
    errno = faults[which].err;
    return 1;
}

static void faults_reset(void) { memset(faults, 0, sizeof faults); }

/* ------------------------------------------------------------------------ */
/* send / recv: the real call unless armed                                   */

ssize_t __real_send(int fd, const void *buf, size_t n, int flags);
ssize_t __real_recv(int fd, void *buf, size_t n, int flags);
ssize_t __wrap_send(int fd, const void *buf, size_t n, int flags);
ssize_t __wrap_recv(int fd, void *buf, size_t n, int flags);

ssize_t __wrap_send(int fd, const void *buf, size_t n, int flags)
{
    if (fire(F_SEND)) {
        return -1;
    }
    return __real_send(fd, buf, n, flags);
}

ssize_t __wrap_recv(int fd, void *buf, size_t n, int flags)
{
    if (fire(F_RECV)) {
        return -1;
    }
    return __real_recv(fd, buf, n, flags);
}

/* ------------------------------------------------------------------------ */
/* libgpiod: a fake chip with FAKE_LINES lines                               */

#define FAKE_LINES 8u

/* Opaque to the port; only their addresses are used. */
static union {
    long align;
    unsigned char b[16];
} fake_chip_mem, fake_line_mem[FAKE_LINES];

static struct {
    int open;              /* chip open, not closed */
    int value[FAKE_LINES]; /* line values (logical) */
    int requested[FAKE_LINES];
    unsigned events;        /* queued events on the deployed line */
    int event_type;         /* their type */
    unsigned event_at_wait; /* an event is queued at this event_wait call (1-based; 0 never) */
} gp;

static unsigned line_index(const struct gpiod_line *line)
{
    unsigned i;
    for (i = 0u; i < FAKE_LINES; ++i) {
        if ((const void *)line == (const void *)&fake_line_mem[i]) {
            return i;
        }
    }
    fail_msg("not a fake line");
    return 0u;
}

struct gpiod_chip *__wrap_gpiod_chip_open_lookup(const char *descr);
void __wrap_gpiod_chip_close(struct gpiod_chip *chip);
unsigned int __wrap_gpiod_chip_num_lines(struct gpiod_chip *chip);
struct gpiod_line *__wrap_gpiod_chip_get_line(struct gpiod_chip *chip, unsigned int offset);
int __wrap_gpiod_line_request_output_flags(struct gpiod_line *line, const char *consumer, int flags,
                                           int default_val);
int __wrap_gpiod_line_request_both_edges_events_flags(struct gpiod_line *line, const char *consumer,
                                                      int flags);
void __wrap_gpiod_line_release(struct gpiod_line *line);
int __wrap_gpiod_line_set_value(struct gpiod_line *line, int value);
int __wrap_gpiod_line_get_value(struct gpiod_line *line);
int __wrap_gpiod_line_event_wait(struct gpiod_line *line, const struct timespec *timeout);
int __wrap_gpiod_line_event_read(struct gpiod_line *line, struct gpiod_line_event *event);

struct gpiod_chip *__wrap_gpiod_chip_open_lookup(const char *descr)
{
    assert_non_null(descr);
    assert_false(gp.open);
    gp.open = 1;
    return (struct gpiod_chip *)(void *)&fake_chip_mem;
}

void __wrap_gpiod_chip_close(struct gpiod_chip *chip)
{
    assert_ptr_equal(chip, (void *)&fake_chip_mem);
    gp.open = 0;
}

unsigned int __wrap_gpiod_chip_num_lines(struct gpiod_chip *chip)
{
    assert_ptr_equal(chip, (void *)&fake_chip_mem);
    return FAKE_LINES;
}

struct gpiod_line *__wrap_gpiod_chip_get_line(struct gpiod_chip *chip, unsigned int offset)
{
    assert_ptr_equal(chip, (void *)&fake_chip_mem);
    assert_true(offset < FAKE_LINES);
    return (struct gpiod_line *)(void *)&fake_line_mem[offset];
}

int __wrap_gpiod_line_request_output_flags(struct gpiod_line *line, const char *consumer, int flags,
                                           int default_val)
{
    unsigned i = line_index(line);
    (void)consumer;
    (void)flags;
    gp.requested[i] = 1;
    gp.value[i] = default_val;
    return 0;
}

int __wrap_gpiod_line_request_both_edges_events_flags(struct gpiod_line *line, const char *consumer,
                                                      int flags)
{
    (void)consumer;
    (void)flags;
    gp.requested[line_index(line)] = 1;
    return 0;
}

void __wrap_gpiod_line_release(struct gpiod_line *line) { gp.requested[line_index(line)] = 0; }

int __wrap_gpiod_line_set_value(struct gpiod_line *line, int value)
{
    unsigned i = line_index(line);
    assert_true(gp.requested[i]);
    if (fire(F_SET_VALUE)) {
        return -1;
    }
    gp.value[i] = value;
    return 0;
}

int __wrap_gpiod_line_get_value(struct gpiod_line *line)
{
    unsigned i = line_index(line);
    assert_true(gp.requested[i]);
    if (fire(F_GET_VALUE)) {
        return -1;
    }
    return gp.value[i];
}

int __wrap_gpiod_line_event_wait(struct gpiod_line *line, const struct timespec *timeout)
{
    assert_true(gp.requested[line_index(line)]);
    assert_non_null(timeout);
    if (fire(F_EVENT_WAIT)) {
        return -1;
    }
    if (gp.event_at_wait != 0u && faults[F_EVENT_WAIT].calls == gp.event_at_wait) {
        gp.events++;
    }
    return gp.events > 0u ? 1 : 0; /* no event: as if the timeout passed */
}

int __wrap_gpiod_line_event_read(struct gpiod_line *line, struct gpiod_line_event *event)
{
    assert_true(gp.requested[line_index(line)]);
    assert_non_null(event);
    if (fire(F_EVENT_READ)) {
        return -1;
    }
    assert_true(gp.events > 0u);
    gp.events--;
    memset(event, 0, sizeof *event);
    event->event_type = gp.event_type;
    return 0;
}

/* ------------------------------------------------------------------------ */
/* GPIO                                                                      */

static trn_lgpio_cfg_t gcfg;

static int gpio_setup(void **state)
{
    (void)state;
    faults_reset();
    memset(&gp, 0, sizeof gp);
    gp.event_type = GPIOD_LINE_EVENT_RISING_EDGE;
    if (trn_lgpio_cfg_default(&gcfg) != TRN_OK) {
        return -1;
    }
    return 0;
}

static void open_fake(trn_lgpio_t *g)
{
    assert_int_equal(trn_lgpio_open(g, &gcfg), TRN_OK);
    assert_true(gp.requested[gcfg.power_offset] && gp.requested[gcfg.trigger_offset] &&
                gp.requested[gcfg.deployed_offset]);
    faults_reset();
}

static void close_fake(trn_lgpio_t *g)
{
    assert_int_equal(trn_lgpio_close(g), TRN_OK);
    assert_false(gp.open);
    assert_false(gp.requested[gcfg.power_offset] || gp.requested[gcfg.trigger_offset] ||
                 gp.requested[gcfg.deployed_offset]);
}

static void test_set_power_line_fault(void **state)
{
    trn_lgpio_t g;
    (void)state;
    open_fake(&g);
    assert_int_equal(trn_lgpio_set_power(&g, 1), TRN_OK);
    assert_int_equal(gp.value[gcfg.power_offset], 1);
    arm(F_SET_VALUE, 0u, EIO);
    assert_int_equal(trn_lgpio_set_power(&g, 0), TRN_E_IO);
    assert_int_equal(gp.value[gcfg.power_offset], 1); /* not switched */
    /* one-shot: the next call goes through, the handle stays usable */
    assert_int_equal(trn_lgpio_set_power(&g, 0), TRN_OK);
    assert_int_equal(gp.value[gcfg.power_offset], 0);
    close_fake(&g);
}

static void test_trigger_line_fault_on_either_edge(void **state)
{
    trn_lgpio_t g;
    (void)state;
    gcfg.trigger_pulse_us = 200u;
    open_fake(&g);
    assert_int_equal(trn_lgpio_trigger(&g), TRN_OK);
    assert_int_equal((int)faults[F_SET_VALUE].calls, 2); /* active, then inactive */
    assert_int_equal(gp.value[gcfg.trigger_offset], 0);

    /* the rising edge fails: no pulse, nothing else driven */
    faults_reset();
    arm(F_SET_VALUE, 0u, EIO);
    assert_int_equal(trn_lgpio_trigger(&g), TRN_E_IO);
    assert_int_equal((int)faults[F_SET_VALUE].calls, 1);
    assert_int_equal(gp.value[gcfg.trigger_offset], 0);

    /* the falling edge fails: reported, the line is left as the controller has it */
    faults_reset();
    arm(F_SET_VALUE, 1u, EIO);
    assert_int_equal(trn_lgpio_trigger(&g), TRN_E_IO);
    assert_int_equal((int)faults[F_SET_VALUE].calls, 2);
    assert_int_equal(gp.value[gcfg.trigger_offset], 1);
    close_fake(&g);
}

static void test_read_deployed_line_fault(void **state)
{
    trn_lgpio_t g;
    int dep = 7;
    (void)state;
    open_fake(&g);
    gp.value[gcfg.deployed_offset] = 1;
    assert_int_equal(trn_lgpio_read_deployed(&g, &dep), TRN_OK);
    assert_int_equal(dep, 1);
    dep = 7;
    arm(F_GET_VALUE, 0u, EIO);
    assert_int_equal(trn_lgpio_read_deployed(&g, &dep), TRN_E_IO);
    assert_int_equal(dep, 7); /* not written */
    close_fake(&g);
}

static void test_wait_deployed_without_faults(void **state)
{
    trn_lgpio_t g;
    (void)state;
    open_fake(&g);
    /* a stale edge is drained; the input is inactive; a rising edge comes */
    gp.events = 1u;
    gp.event_at_wait = 3u; /* drain: wait 1 (stale), wait 2 (empty); main: wait 3 */
    assert_int_equal(trn_lgpio_wait_deployed(&g, 50), TRN_OK);
    assert_int_equal((int)faults[F_EVENT_READ].calls, 2);
    /* only a falling edge: not deployed, a timeout */
    faults_reset();
    gp.event_type = GPIOD_LINE_EVENT_FALLING_EDGE;
    gp.event_at_wait = 2u;
    assert_int_equal(trn_lgpio_wait_deployed(&g, 0), TRN_E_TIMEOUT);
    /* already active: at once, no wait */
    faults_reset();
    gp.event_at_wait = 0u;
    gp.value[gcfg.deployed_offset] = 1;
    assert_int_equal(trn_lgpio_wait_deployed(&g, 50), TRN_OK);
    assert_int_equal((int)faults[F_EVENT_WAIT].calls, 1); /* the drain's only */
    /* an interrupted wait (EINTR) is resumed, then times out */
    faults_reset();
    gp.value[gcfg.deployed_offset] = 0;
    arm(F_EVENT_WAIT, 1u, EINTR);
    assert_int_equal(trn_lgpio_wait_deployed(&g, 0), TRN_E_TIMEOUT);
    assert_int_equal((int)faults[F_EVENT_WAIT].calls, 3);
    close_fake(&g);
}

static void test_wait_deployed_line_faults(void **state)
{
    trn_lgpio_t g;
    (void)state;
    open_fake(&g);
    /* draining: the wait fails */
    arm(F_EVENT_WAIT, 0u, EIO);
    assert_int_equal(trn_lgpio_wait_deployed(&g, 50), TRN_E_IO);
    /* draining: a queued event cannot be read */
    faults_reset();
    gp.events = 1u;
    arm(F_EVENT_READ, 0u, EIO);
    assert_int_equal(trn_lgpio_wait_deployed(&g, 50), TRN_E_IO);
    assert_int_equal((int)gp.events, 1);
    gp.events = 0u;
    /* reading the input fails */
    faults_reset();
    arm(F_GET_VALUE, 0u, EIO);
    assert_int_equal(trn_lgpio_wait_deployed(&g, 50), TRN_E_IO);
    /* waiting for the edge fails (not EINTR) */
    faults_reset();
    arm(F_EVENT_WAIT, 1u, EIO);
    assert_int_equal(trn_lgpio_wait_deployed(&g, 50), TRN_E_IO);
    assert_int_equal((int)faults[F_EVENT_WAIT].calls, 2);
    /* the edge comes but cannot be read */
    faults_reset();
    gp.event_at_wait = 2u;
    arm(F_EVENT_READ, 0u, EIO);
    assert_int_equal(trn_lgpio_wait_deployed(&g, 50), TRN_E_IO);
    assert_int_equal((int)gp.events, 1);
    gp.events = 0u;
    close_fake(&g);
}

/* ------------------------------------------------------------------------ */
/* ISO-TP                                                                    */

static int sv[2];

static int tp_setup(void **state)
{
    (void)state;
    faults_reset();
    return socketpair(AF_UNIX, SOCK_SEQPACKET, 0, sv);
}

static int tp_teardown(void **state)
{
    (void)state;
    faults_reset();
    return close(sv[0]) == 0 && close(sv[1]) == 0 ? 0 : -1;
}

/* Nothing is waiting at fd. */
static void assert_empty(int fd)
{
    uint8_t b;
    errno = 0;
    assert_int_equal(recv(fd, &b, 1u, MSG_DONTWAIT), -1);
    assert_true(errno == EAGAIN || errno == EWOULDBLOCK);
}

static void test_lisotp_send_bus_and_format_faults(void **state)
{
    trn_lisotp_t tp;
    uint8_t msg[20], buf[32];
    size_t i;
    (void)state;
    for (i = 0; i < sizeof msg; ++i) {
        msg[i] = (uint8_t)(3u * i + 1u);
    }
    tp.fd = sv[0];
    /* the interface goes down, or away, while sending */
    arm(F_SEND, 0u, ENETDOWN);
    assert_int_equal(trn_lisotp_send(&tp, msg, sizeof msg, 100), TRN_E_BUS);
    assert_empty(sv[1]);
    arm(F_SEND, 0u, ENODEV);
    assert_int_equal(trn_lisotp_send(&tp, msg, sizeof msg, 100), TRN_E_BUS);
    assert_empty(sv[1]);
    /* the kernel found the peer's flow control malformed */
    arm(F_SEND, 0u, EBADMSG);
    assert_int_equal(trn_lisotp_send(&tp, msg, sizeof msg, 100), TRN_E_FORMAT);
    assert_empty(sv[1]);
    assert_int_equal(tp.fd, sv[0]); /* the handle stays open */
    /* an interrupted send is retried and the message goes whole */
    faults_reset();
    arm(F_SEND, 0u, EINTR);
    assert_int_equal(trn_lisotp_send(&tp, msg, sizeof msg, 100), TRN_OK);
    assert_int_equal((int)faults[F_SEND].calls, 2);
    assert_int_equal(recv(sv[1], buf, sizeof buf, MSG_DONTWAIT), (ssize_t)sizeof msg);
    assert_memory_equal(buf, msg, sizeof msg);
}

static void test_lisotp_recv_bus_and_format_faults(void **state)
{
    trn_lisotp_t tp;
    uint8_t msg[12], buf[32];
    size_t len = 999u, i;
    (void)state;
    for (i = 0; i < sizeof msg; ++i) {
        msg[i] = (uint8_t)(5u * i + 2u);
    }
    assert_int_equal(send(sv[1], msg, sizeof msg, 0), (ssize_t)sizeof msg);
    tp.fd = sv[0];
    /* the interface goes down while the length is peeked */
    arm(F_RECV, 0u, ENETDOWN);
    assert_int_equal(trn_lisotp_recv(&tp, buf, sizeof buf, &len, 100), TRN_E_BUS);
    assert_int_equal((int)len, 999);
    /* or is gone when the message is read */
    arm(F_RECV, 1u, ENODEV);
    assert_int_equal(trn_lisotp_recv(&tp, buf, sizeof buf, &len, 100), TRN_E_BUS);
    assert_int_equal((int)len, 999);
    /* wrong padding or layout from the peer, at either call */
    arm(F_RECV, 0u, EBADMSG);
    assert_int_equal(trn_lisotp_recv(&tp, buf, sizeof buf, &len, 100), TRN_E_FORMAT);
    arm(F_RECV, 1u, EBADMSG);
    assert_int_equal(trn_lisotp_recv(&tp, buf, sizeof buf, &len, 100), TRN_E_FORMAT);
    assert_int_equal((int)len, 999);
    assert_int_equal(tp.fd, sv[0]);
    /* the message was never taken by a failed call: an interrupted read
     * (EINTR) is retried and the message arrives whole */
    faults_reset();
    arm(F_RECV, 1u, EINTR);
    assert_int_equal(trn_lisotp_recv(&tp, buf, sizeof buf, &len, 100), TRN_OK);
    assert_int_equal((int)len, (int)sizeof msg);
    assert_memory_equal(buf, msg, sizeof msg);
    assert_int_equal((int)faults[F_RECV].calls, 4); /* peek, EINTR, peek, read */
    assert_empty(sv[0]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_set_power_line_fault, gpio_setup),
        cmocka_unit_test_setup(test_trigger_line_fault_on_either_edge, gpio_setup),
        cmocka_unit_test_setup(test_read_deployed_line_fault, gpio_setup),
        cmocka_unit_test_setup(test_wait_deployed_without_faults, gpio_setup),
        cmocka_unit_test_setup(test_wait_deployed_line_faults, gpio_setup),
        cmocka_unit_test_setup_teardown(test_lisotp_send_bus_and_format_faults, tp_setup,
                                        tp_teardown),
        cmocka_unit_test_setup_teardown(test_lisotp_recv_bus_and_format_faults, tp_setup,
                                        tp_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
