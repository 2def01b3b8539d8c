/* SPDX-License-Identifier: Apache-2.0 */
/* test_link_mon.c - liveness and loss of periodic counter messages (link_mon.h).
 *
 * A simulated heartbeat stream (100 ms period) with the faults the
 * simulator will inject: dropped frames, a repeated frame, a silent node and
 * its recovery, the counter and the clock wrapping. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include "trn_port/link_mon.h"

static void test_args(void **state)
{
    trn_link_mon_t m;
    uint8_t ev;
    (void)state;
    assert_int_equal(trn_link_mon_init(NULL, 300), TRN_E_NULL);
    assert_int_equal(trn_link_mon_init(&m, 0), TRN_E_ARG);
    assert_int_equal(trn_link_mon_init(&m, 600001), TRN_E_ARG);
    assert_int_equal(trn_link_mon_init(&m, 300), TRN_OK);
    assert_int_equal(trn_link_mon_frame(NULL, 0, 0, &ev, NULL), TRN_E_NULL);
    assert_int_equal(trn_link_mon_poll(NULL, 0, &ev), TRN_E_NULL);
    /* outputs are optional */
    assert_int_equal(trn_link_mon_frame(&m, 0, 0, NULL, NULL), TRN_OK);
    assert_int_equal(trn_link_mon_poll(&m, 1000, NULL), TRN_E_TIMEOUT);
}

static void test_stream_with_faults(void **state)
{
    trn_link_mon_t m;
    uint8_t ev = 0, gap = 0, c = 250;
    uint32_t t = 0xFFFFFF00u; /* the clock wraps during the stream */
    int i;
    (void)state;
    assert_int_equal(trn_link_mon_init(&m, 300), TRN_OK);
    assert_int_equal(trn_link_mon_poll(&m, t + 10000, &ev), TRN_OK); /* never seen: not silent */
    assert_int_equal(m.state, TRN_LINK_NEVER_SEEN);
    assert_int_equal(trn_link_mon_frame(&m, c, t, &ev, &gap), TRN_OK);
    assert_int_equal(ev, TRN_LINK_EV_FIRST);
    /* 10 clean frames, the counter wraps 255 -> 0 */
    for (i = 0; i < 10; ++i) {
        t += 100;
        ++c;
        assert_int_equal(trn_link_mon_frame(&m, c, t, &ev, &gap), TRN_OK);
        assert_int_equal(ev, 0);
        assert_int_equal(gap, 0);
    }
    /* two frames dropped */
    t += 300;
    c += 3;
    assert_int_equal(trn_link_mon_frame(&m, c, t, &ev, &gap), TRN_E_SEQ);
    assert_int_equal(ev, TRN_LINK_EV_GAP);
    assert_int_equal(gap, 2);
    /* a repeated frame */
    assert_int_equal(trn_link_mon_frame(&m, c, t + 1, &ev, &gap), TRN_E_SEQ);
    assert_int_equal(ev, TRN_LINK_EV_REPEAT);
    t += 1;
    /* the node goes quiet: exactly 300 ms is still alive, 301 is silent, once */
    assert_int_equal(trn_link_mon_poll(&m, t + 300, &ev), TRN_OK);
    assert_int_equal(m.state, TRN_LINK_ALIVE);
    assert_int_equal(trn_link_mon_poll(&m, t + 301, &ev), TRN_E_TIMEOUT);
    assert_int_equal(ev, TRN_LINK_EV_SILENT);
    assert_int_equal(trn_link_mon_poll(&m, t + 5000, &ev), TRN_OK);
    assert_int_equal(ev, 0);
    /* it comes back with a counter far ahead: recovered, no gap counted */
    c += 40;
    assert_int_equal(trn_link_mon_frame(&m, c, t + 5000, &ev, &gap), TRN_OK);
    assert_int_equal(ev, TRN_LINK_EV_RECOVERED);
    assert_int_equal(gap, 0);
    t += 5000;
    /* silent without a poll: the next frame reports both */
    assert_int_equal(trn_link_mon_frame(&m, (uint8_t)(c + 1), t + 1000, &ev, &gap), TRN_OK);
    assert_int_equal(ev, TRN_LINK_EV_SILENT | TRN_LINK_EV_RECOVERED);
    assert_int_equal(m.n_frames, 15);
    assert_int_equal(m.n_lost, 2);
    assert_int_equal(m.n_gaps, 1);
    assert_int_equal(m.n_repeats, 1);
    assert_int_equal(m.n_silences, 2);
    assert_int_equal(m.n_recoveries, 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_args),
        cmocka_unit_test(test_stream_with_faults),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
