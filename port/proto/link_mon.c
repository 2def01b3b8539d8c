/* SPDX-License-Identifier: Apache-2.0 */
/* link_mon.c - liveness and loss of a periodic counter message (link_mon.h). */
#include "trn_port/link_mon.h"

#include "trn_port/can_msg.h"

static void set_u8(uint8_t *p, uint8_t v)
{
    if (p != NULL) {
        *p = v;
    }
}

trn_status_t trn_link_mon_init(trn_link_mon_t *m, uint32_t timeout_ms)
{
    if (m == NULL) {
        return TRN_E_NULL;
    }
    if (timeout_ms == 0u || timeout_ms > 600000u) {
        return TRN_E_ARG;
    }
    m->timeout_ms = timeout_ms;
    m->state = (uint8_t)TRN_LINK_NEVER_SEEN;
    m->last_counter = 0u;
    m->last_ms = 0u;
    m->n_frames = 0u;
    m->n_lost = 0u;
    m->n_gaps = 0u;
    m->n_repeats = 0u;
    m->n_silences = 0u;
    m->n_recoveries = 0u;
    return TRN_OK;
}

/* ALIVE -> SILENT when the timeout passed; returns 1 on the transition. */
static int check_silence(trn_link_mon_t *m, uint32_t now_ms)
{
    if (m->state == (uint8_t)TRN_LINK_ALIVE && (uint32_t)(now_ms - m->last_ms) > m->timeout_ms) {
        m->state = (uint8_t)TRN_LINK_SILENT;
        m->n_silences += 1u;
        return 1;
    }
    return 0;
}

trn_status_t trn_link_mon_poll(trn_link_mon_t *m, uint32_t now_ms, uint8_t *events)
{
    if (m == NULL) {
        return TRN_E_NULL;
    }
    if (check_silence(m, now_ms)) {
        set_u8(events, TRN_LINK_EV_SILENT);
        return TRN_E_TIMEOUT;
    }
    set_u8(events, 0u);
    return TRN_OK;
}

trn_status_t trn_link_mon_frame(trn_link_mon_t *m, uint8_t counter, uint32_t now_ms,
                                uint8_t *events, uint8_t *gap)
{
    uint8_t ev = 0u, g = 0u;
    trn_status_t st = TRN_OK;
    if (m == NULL) {
        return TRN_E_NULL;
    }
    if (check_silence(m, now_ms)) {
        ev |= TRN_LINK_EV_SILENT;
    }
    if (m->state == (uint8_t)TRN_LINK_NEVER_SEEN) {
        ev |= TRN_LINK_EV_FIRST;
    } else if (m->state == (uint8_t)TRN_LINK_SILENT) {
        ev |= TRN_LINK_EV_RECOVERED;
        m->n_recoveries += 1u;
    } else {
        g = trn_can_counter_gap(m->last_counter, counter);
        if (g == 255u) {
            ev |= TRN_LINK_EV_REPEAT;
            m->n_repeats += 1u;
            g = 0u;
            st = TRN_E_SEQ;
        } else if (g != 0u) {
            ev |= TRN_LINK_EV_GAP;
            m->n_gaps += 1u;
            m->n_lost += g;
            st = TRN_E_SEQ;
        }
    }
    m->state = (uint8_t)TRN_LINK_ALIVE;
    m->last_counter = counter;
    m->last_ms = now_ms;
    m->n_frames += 1u;
    set_u8(events, ev);
    set_u8(gap, g);
    return st;
}
