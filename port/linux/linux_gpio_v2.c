/* SPDX-License-Identifier: Apache-2.0 */
/*
 * linux_gpio_v2.c - mast power, stereo trigger and deployed switch through
 * libgpiod 2.x (Debian 13, Ubuntu 24.04), the same contract as linux_gpio.c
 * (libgpiod 1.6; port/include/trn_port/linux_gpio.h). port/CMakeLists.txt
 * compiles one of the two, from the API it finds in gpiod.h, and defines
 * TRN_GPIOD_API=2 for this one (PUBLIC: the handle's members differ).
 *
 * libgpiod 2 requests lines as one request with a line configuration; the
 * three lines are one request here: power and trigger outputs driven
 * inactive, deployed an input with both-edge events. Edge events are read
 * into a buffer of one event allocated by libgpiod in trn_lgpio_open (our
 * code still allocates nothing). The chip is named as for 1.6: a path
 * ("/dev/gpiochip0"), a name ("gpiochip0"), a number ("0") or a label (every
 * /dev/gpiochipN is opened in turn and its label compared), since libgpiod 2
 * has no lookup of its own.
 */
#include "trn_port/linux_gpio.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include <gpiod.h>

#if !defined(TRN_GPIOD_API) || TRN_GPIOD_API != 2
#error "linux_gpio_v2.c is the libgpiod 2 port: build it with TRN_GPIOD_API=2"
#endif

/* Events drained or read per wait, at most (a bouncing switch ends here). */
#define TRN_LGPIO_MAX_EVENTS 4096u
/* Chips tried when the chip is given by its label (/dev/gpiochip0..N-1). */
#define TRN_LGPIO_MAX_CHIPS 64u
/* Longest chip path we build ("/dev/" + name). */
#define TRN_LGPIO_PATH_MAX 128u

static void lgpio_reset(trn_lgpio_t *g)
{
    g->chip = NULL;
    g->request = NULL;
    g->events = NULL;
    g->power_offset = 0u;
    g->trigger_offset = 0u;
    g->deployed_offset = 0u;
    g->pulse_us = 0u;
}

trn_status_t trn_lgpio_close(trn_lgpio_t *g)
{
    if (g == NULL) {
        return TRN_E_NULL;
    }
    if (g->request != NULL) {
        gpiod_line_request_release(g->request);
    }
    if (g->events != NULL) {
        gpiod_edge_event_buffer_free(g->events);
    }
    if (g->chip != NULL) {
        gpiod_chip_close(g->chip);
    }
    lgpio_reset(g);
    return TRN_OK;
}

static int all_digits(const char *s)
{
    size_t i;
    for (i = 0u; s[i] != '\0'; ++i) {
        if (s[i] < '0' || s[i] > '9') {
            return 0;
        }
    }
    return i > 0u;
}

/* Open the chip as libgpiod 1.6's gpiod_chip_open_lookup did: path, name,
 * number, then label. NULL when none matches. */
static struct gpiod_chip *chip_lookup(const char *chip)
{
    char path[TRN_LGPIO_PATH_MAX];
    struct gpiod_chip *c;
    unsigned n;
    int len;

    if (chip[0] == '/') {
        return gpiod_chip_open(chip);
    }
    if (all_digits(chip)) {
        len = snprintf(path, sizeof path, "/dev/gpiochip%s", chip);
    } else {
        len = snprintf(path, sizeof path, "/dev/%s", chip);
    }
    if (len > 0 && (size_t)len < sizeof path && strchr(chip, '/') == NULL) {
        c = gpiod_chip_open(path);
        if (c != NULL) {
            return c;
        }
    }
    /* A label: the chips in turn. */
    for (n = 0u; n < TRN_LGPIO_MAX_CHIPS; ++n) {
        struct gpiod_chip_info *info;
        int same = 0;
        (void)snprintf(path, sizeof path, "/dev/gpiochip%u", n);
        c = gpiod_chip_open(path);
        if (c == NULL) {
            continue;
        }
        info = gpiod_chip_get_info(c);
        if (info != NULL) {
            const char *label = gpiod_chip_info_get_label(info);
            same = label != NULL && strcmp(label, chip) == 0;
            gpiod_chip_info_free(info);
        }
        if (same) {
            return c;
        }
        gpiod_chip_close(c);
    }
    return NULL;
}

/* Line settings of one line: direction, initial value / edges, polarity.
 * 0 on success. */
static int settings_set(struct gpiod_line_settings *s, int output, uint8_t active_low)
{
    gpiod_line_settings_reset(s);
    if (output) {
        if (gpiod_line_settings_set_direction(s, GPIOD_LINE_DIRECTION_OUTPUT) != 0 ||
            gpiod_line_settings_set_output_value(s, GPIOD_LINE_VALUE_INACTIVE) != 0) {
            return -1;
        }
    } else if (gpiod_line_settings_set_direction(s, GPIOD_LINE_DIRECTION_INPUT) != 0 ||
               gpiod_line_settings_set_edge_detection(s, GPIOD_LINE_EDGE_BOTH) != 0) {
        return -1;
    }
    gpiod_line_settings_set_active_low(s, active_low != 0u);
    return 0;
}

/* The three lines as one request; NULL on failure (EBUSY included). */
static struct gpiod_line_request *request_lines(struct gpiod_chip *chip, const trn_lgpio_cfg_t *cfg)
{
    struct gpiod_line_settings *s = gpiod_line_settings_new();
    struct gpiod_line_config *lc = gpiod_line_config_new();
    struct gpiod_request_config *rc = gpiod_request_config_new();
    struct gpiod_line_request *req = NULL;
    unsigned int off;
    int ok = s != NULL && lc != NULL && rc != NULL;

    off = cfg->power_offset;
    ok = ok && settings_set(s, 1, cfg->power_active_low) == 0 &&
         gpiod_line_config_add_line_settings(lc, &off, 1u, s) == 0;
    off = cfg->trigger_offset;
    ok = ok && settings_set(s, 1, cfg->trigger_active_low) == 0 &&
         gpiod_line_config_add_line_settings(lc, &off, 1u, s) == 0;
    off = cfg->deployed_offset;
    ok = ok && settings_set(s, 0, cfg->deployed_active_low) == 0 &&
         gpiod_line_config_add_line_settings(lc, &off, 1u, s) == 0;
    if (ok) {
        gpiod_request_config_set_consumer(rc, cfg->consumer);
        req = gpiod_chip_request_lines(chip, rc, lc);
    }
    if (rc != NULL) {
        gpiod_request_config_free(rc);
    }
    if (lc != NULL) {
        gpiod_line_config_free(lc);
    }
    if (s != NULL) {
        gpiod_line_settings_free(s);
    }
    return req;
}

trn_status_t trn_lgpio_open(trn_lgpio_t *g, const trn_lgpio_cfg_t *cfg)
{
    struct gpiod_chip_info *info;
    size_t nlines;
    trn_status_t st;

    if (g == NULL) {
        return TRN_E_NULL;
    }
    lgpio_reset(g);
    st = trn_lgpio_cfg_check(cfg);
    if (st != TRN_OK) {
        return st;
    }
    g->chip = chip_lookup(cfg->chip);
    if (g->chip == NULL) {
        return TRN_E_IO;
    }
    info = gpiod_chip_get_info(g->chip);
    if (info == NULL) {
        (void)trn_lgpio_close(g);
        return TRN_E_IO;
    }
    nlines = gpiod_chip_info_get_num_lines(info);
    gpiod_chip_info_free(info);
    if (cfg->power_offset >= nlines || cfg->trigger_offset >= nlines ||
        cfg->deployed_offset >= nlines) {
        (void)trn_lgpio_close(g);
        return TRN_E_RANGE;
    }
    g->events = gpiod_edge_event_buffer_new(1u);
    if (g->events == NULL) {
        (void)trn_lgpio_close(g);
        return TRN_E_IO;
    }
    g->request = request_lines(g->chip, cfg);
    if (g->request == NULL) {
        (void)trn_lgpio_close(g);
        return TRN_E_IO;
    }
    g->power_offset = cfg->power_offset;
    g->trigger_offset = cfg->trigger_offset;
    g->deployed_offset = cfg->deployed_offset;
    g->pulse_us = cfg->trigger_pulse_us;
    return TRN_OK;
}

static int is_open(const trn_lgpio_t *g)
{
    return g->chip != NULL && g->request != NULL && g->events != NULL;
}

static int set_line(trn_lgpio_t *g, uint32_t offset, int active)
{
    return gpiod_line_request_set_value(
        g->request, offset, active ? GPIOD_LINE_VALUE_ACTIVE : GPIOD_LINE_VALUE_INACTIVE);
}

trn_status_t trn_lgpio_set_power(trn_lgpio_t *g, int on)
{
    if (g == NULL) {
        return TRN_E_NULL;
    }
    if (!is_open(g) || (on != 0 && on != 1)) {
        return TRN_E_ARG;
    }
    return set_line(g, g->power_offset, on) == 0 ? TRN_OK : TRN_E_IO;
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
    if (set_line(g, g->trigger_offset, 1) != 0) {
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
    if (set_line(g, g->trigger_offset, 0) != 0) {
        return TRN_E_IO;
    }
    return st;
}

/* The deployed input's logical value: 1, 0, or -1 on error. */
static int get_deployed(trn_lgpio_t *g)
{
    enum gpiod_line_value v = gpiod_line_request_get_value(g->request, g->deployed_offset);
    if (v == GPIOD_LINE_VALUE_ERROR) {
        return -1;
    }
    return v == GPIOD_LINE_VALUE_ACTIVE ? 1 : 0;
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
    v = get_deployed(g);
    if (v < 0) {
        return TRN_E_IO;
    }
    *deployed = v;
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
static int wait_event_ms(trn_lgpio_t *g, int64_t ms)
{
    if (ms < 0) {
        ms = 0;
    }
    return gpiod_line_request_wait_edge_events(g->request, ms * 1000000);
}

/* Read one pending event: 1 a rising edge of deployed, 0 another, -1 error. */
static int read_event(trn_lgpio_t *g)
{
    struct gpiod_edge_event *ev;
    if (gpiod_line_request_read_edge_events(g->request, g->events, 1u) != 1) {
        return -1;
    }
    ev = gpiod_edge_event_buffer_get_event(g->events, 0u);
    if (ev == NULL) {
        return -1;
    }
    return gpiod_edge_event_get_line_offset(ev) == g->deployed_offset &&
           gpiod_edge_event_get_event_type(ev) == GPIOD_EDGE_EVENT_RISING_EDGE;
}

trn_status_t trn_lgpio_wait_deployed(trn_lgpio_t *g, int32_t timeout_ms)
{
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
        int r = wait_event_ms(g, 0);
        if (r < 0) {
            return TRN_E_IO;
        }
        if (r == 0) {
            break;
        }
        if (read_event(g) < 0) {
            return TRN_E_IO;
        }
    }
    /* Already deployed? (Read after draining: an edge from now on is queued.) */
    v = get_deployed(g);
    if (v < 0) {
        return TRN_E_IO;
    }
    if (v != 0) {
        return TRN_OK;
    }
    deadline = now_ms() + timeout_ms;
    for (i = 0u; i < TRN_LGPIO_MAX_EVENTS; ++i) {
        int r = wait_event_ms(g, deadline - now_ms());
        if (r < 0) {
            if (errno == EINTR) {
                continue;
            }
            return TRN_E_IO;
        }
        if (r == 0) {
            return TRN_E_TIMEOUT;
        }
        r = read_event(g);
        if (r < 0) {
            return TRN_E_IO;
        }
        if (r == 1) {
            return TRN_OK; /* rising = became active (active-low applied by the kernel) */
        }
    }
    return TRN_E_TIMEOUT;
}
