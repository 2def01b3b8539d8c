/* SPDX-License-Identifier: Apache-2.0 */
/*
 * linux_gpio.c - mast power, stereo trigger and deployed switch through
 * libgpiod 1.6 (port/include/trn_port/linux_gpio.h).
 */
#include "trn_port/linux_gpio.h"

#include <errno.h>
#include <string.h>
#include <time.h>

#include <gpiod.h>

/* Events drained or read per wait, at most (a bouncing switch ends here). */
#define TRN_LGPIO_MAX_EVENTS 4096u

static void lgpio_reset(trn_lgpio_t *g)
{
    g->chip = NULL;
    g->power = NULL;
    g->trigger = NULL;
    g->deployed = NULL;
    g->pulse_us = 0u;
}

static int active_low_flag(uint8_t active_low)
{
    return active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
}

trn_status_t trn_lgpio_close(trn_lgpio_t *g)
{
    if (g == NULL) {
        return TRN_E_NULL;
    }
    if (g->power != NULL) {
        gpiod_line_release(g->power);
    }
    if (g->trigger != NULL) {
        gpiod_line_release(g->trigger);
    }
    if (g->deployed != NULL) {
        gpiod_line_release(g->deployed);
    }
    if (g->chip != NULL) {
        gpiod_chip_close(g->chip);
    }
    lgpio_reset(g);
    return TRN_OK;
}

trn_status_t trn_lgpio_open(trn_lgpio_t *g, const trn_lgpio_cfg_t *cfg)
{
    struct gpiod_line *line;
    unsigned int nlines;
    trn_status_t st;

    if (g == NULL) {
        return TRN_E_NULL;
    }
    lgpio_reset(g);
    st = trn_lgpio_cfg_check(cfg);
    if (st != TRN_OK) {
        return st;
    }
    g->chip = gpiod_chip_open_lookup(cfg->chip);
    if (g->chip == NULL) {
        return TRN_E_IO;
    }
    nlines = gpiod_chip_num_lines(g->chip);
    if (cfg->power_offset >= nlines || cfg->trigger_offset >= nlines ||
        cfg->deployed_offset >= nlines) {
        (void)trn_lgpio_close(g);
        return TRN_E_RANGE;
    }

    /* Each line is kept in g only once requested, so close releases exactly those. */
    line = gpiod_chip_get_line(g->chip, cfg->power_offset);
    if (line == NULL || gpiod_line_request_output_flags(
                            line, cfg->consumer, active_low_flag(cfg->power_active_low), 0) != 0) {
        (void)trn_lgpio_close(g);
        return TRN_E_IO;
    }
    g->power = line;

    line = gpiod_chip_get_line(g->chip, cfg->trigger_offset);
    if (line == NULL ||
        gpiod_line_request_output_flags(line, cfg->consumer,
                                        active_low_flag(cfg->trigger_active_low), 0) != 0) {
        (void)trn_lgpio_close(g);
        return TRN_E_IO;
    }
    g->trigger = line;

    line = gpiod_chip_get_line(g->chip, cfg->deployed_offset);
    if (line == NULL || gpiod_line_request_both_edges_events_flags(
                            line, cfg->consumer, active_low_flag(cfg->deployed_active_low)) != 0) {
        (void)trn_lgpio_close(g);
        return TRN_E_IO;
    }
    g->deployed = line;
    g->pulse_us = cfg->trigger_pulse_us;
    return TRN_OK;
}

static int is_open(const trn_lgpio_t *g)
{
    return g->chip != NULL && g->power != NULL && g->trigger != NULL && g->deployed != NULL;
}

trn_status_t trn_lgpio_set_power(trn_lgpio_t *g, int on)
{
    if (g == NULL) {
        return TRN_E_NULL;
    }
    if (!is_open(g) || (on != 0 && on != 1)) {
        return TRN_E_ARG;
    }
    return gpiod_line_set_value(g->power, on) == 0 ? TRN_OK : TRN_E_IO;
}

trn_status_t trn_lgpio_trigger(trn_lgpio_t *g)
{
    struct timespec until;
    unsigned round;
    int slept = 0;
    trn_status_t st = TRN_OK;

    if (g == NULL) {
        return TRN_E_NULL;
    }
    if (!is_open(g)) {
        return TRN_E_ARG;
    }
    if (clock_gettime(CLOCK_MONOTONIC, &until) != 0) {
        return TRN_E_IO;
    }
    if (gpiod_line_set_value(g->trigger, 1) != 0) {
        return TRN_E_IO;
    }
    until.tv_nsec += (long)(g->pulse_us % 1000000u) * 1000L;
    until.tv_sec += (time_t)(g->pulse_us / 1000000u);
    if (until.tv_nsec >= 1000000000L) {
        until.tv_nsec -= 1000000000L;
        until.tv_sec += 1;
    }
    /* Absolute deadline: an interrupted sleep resumes without stretching. */
    for (round = 0u; round < 1000u && !slept; ++round) {
        int rc = clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, NULL);
        if (rc == 0) {
            slept = 1;
        } else if (rc != EINTR) {
            st = TRN_E_IO;
            break;
        }
    }
    if (gpiod_line_set_value(g->trigger, 0) != 0) {
        return TRN_E_IO;
    }
    return st;
}

trn_status_t trn_lgpio_read_deployed(trn_lgpio_t *g, int *deployed)
{
    int v;
    if (g == NULL || deployed == NULL) {
        return TRN_E_NULL;
    }
    if (!is_open(g)) {
        return TRN_E_ARG;
    }
    v = gpiod_line_get_value(g->deployed);
    if (v < 0) {
        return TRN_E_IO;
    }
    *deployed = v != 0;
    return TRN_OK;
}

static int64_t now_ms(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_MONOTONIC, &ts) != 0) {
        return 0;
    }
    return (int64_t)ts.tv_sec * 1000 + (int64_t)(ts.tv_nsec / 1000000L);
}

/* Wait up to ms for an event: 1 event pending, 0 none, -1 error. */
static int wait_event_ms(struct gpiod_line *line, int64_t ms)
{
    struct timespec ts;
    if (ms < 0) {
        ms = 0;
    }
    ts.tv_sec = (time_t)(ms / 1000);
    ts.tv_nsec = (long)(ms % 1000) * 1000000L;
    return gpiod_line_event_wait(line, &ts);
}

trn_status_t trn_lgpio_wait_deployed(trn_lgpio_t *g, int32_t timeout_ms)
{
    struct gpiod_line_event ev;
    int64_t deadline;
    unsigned i;
    int v;

    if (g == NULL) {
        return TRN_E_NULL;
    }
    if (!is_open(g) || timeout_ms < 0 || timeout_ms > TRN_LGPIO_MAX_TIMEOUT_MS) {
        return TRN_E_ARG;
    }
    /* Forget edges from before the call. */
    for (i = 0u; i < TRN_LGPIO_MAX_EVENTS; ++i) {
        int r = wait_event_ms(g->deployed, 0);
        if (r < 0) {
            return TRN_E_IO;
        }
        if (r == 0) {
            break;
        }
        if (gpiod_line_event_read(g->deployed, &ev) != 0) {
            return TRN_E_IO;
        }
    }
    /* Already deployed? (Read after draining: an edge from now on is queued.) */
    v = gpiod_line_get_value(g->deployed);
    if (v < 0) {
        return TRN_E_IO;
    }
    if (v != 0) {
        return TRN_OK;
    }
    deadline = now_ms() + timeout_ms;
    for (i = 0u; i < TRN_LGPIO_MAX_EVENTS; ++i) {
        int r = wait_event_ms(g->deployed, deadline - now_ms());
        if (r < 0) {
            if (errno == EINTR) {
                continue;
            }
            return TRN_E_IO;
        }
        if (r == 0) {
            return TRN_E_TIMEOUT;
        }
        if (gpiod_line_event_read(g->deployed, &ev) != 0) {
            return TRN_E_IO;
        }
        if (ev.event_type == GPIOD_LINE_EVENT_RISING_EDGE) {
            return TRN_OK; /* rising = became active (active-low applied by the kernel) */
        }
    }
    return TRN_E_TIMEOUT;
}
