/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file linux_gpio.h
 * @brief Linux GPIO port (libgpiod 1.6, the Debian bookworm API, or libgpiod
 * 2.x with TRN_GPIOD_API=2, which the build defines for its users): the mast
 * power enable output, the stereo trigger output pulse and the "mast
 * deployed" input, waited on with a timeout through edge events.
 *
 * Linux only (library `trn_port_linux`). One chip, three lines, all given by
 * the configuration and all requested once by trn_lgpio_open (so a second
 * user of a line is refused at start-up, not in flight) and released by
 * trn_lgpio_close. Our code does not allocate; libgpiod allocates its chip
 * and line objects once, inside trn_lgpio_open. Values are logical: 1 means
 * "active" (power on, trigger asserted, mast deployed) whatever the
 * electrical polarity, which the *_active_low flags give.
 */
#ifndef TRN_PORT_LINUX_GPIO_H
#define TRN_PORT_LINUX_GPIO_H

#include <stdint.h>
#include "trn/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Longest trigger pulse, microseconds (1 s). */
#define TRN_LGPIO_MAX_PULSE_US 1000000u
/** Longest wait for the deployed input, ms (one hour). */
#define TRN_LGPIO_MAX_TIMEOUT_MS 3600000
/** Highest line offset accepted (a chip has at most this many + 1 lines). */
#define TRN_LGPIO_MAX_OFFSET 1023u

/** The libgpiod API the port is built for: 1 (1.6, linux_gpio.c) or 2 (2.x,
 * linux_gpio_v2.c). port/CMakeLists.txt picks it from the gpiod.h it finds
 * and makes TRN_GPIOD_API=2 a PUBLIC definition of trn_port_linux (also in
 * trn-port-linux.pc), since the handle below differs between the two. */
#ifndef TRN_GPIOD_API
#define TRN_GPIOD_API 1
#endif

struct gpiod_chip;
#if TRN_GPIOD_API == 2
struct gpiod_line_request;
struct gpiod_edge_event_buffer;
#else
struct gpiod_line;
#endif

/** Configuration. A zeroed struct is not valid (chip NULL); start from
 * trn_lgpio_cfg_default(). */
typedef struct {
    const char *chip;            /**< chip: name ("gpiochip0"), path, label or number */
    const char *consumer;        /**< label the kernel shows for our lines, non-empty */
    uint32_t power_offset;       /**< mast power enable output */
    uint32_t trigger_offset;     /**< stereo trigger output */
    uint32_t deployed_offset;    /**< "mast deployed" switch input */
    uint8_t power_active_low;    /**< 1: power is on when the line is low */
    uint8_t trigger_active_low;  /**< 1: the pulse drives the line low */
    uint8_t deployed_active_low; /**< 1: the switch reads low when deployed */
    uint32_t trigger_pulse_us;   /**< pulse width, 1..TRN_LGPIO_MAX_PULSE_US */
} trn_lgpio_cfg_t;

#if TRN_GPIOD_API == 2
/** The open lines (libgpiod 2: one request for the three). Owned by the
 * caller; open fills it, close empties it. */
typedef struct {
    struct gpiod_chip *chip;                /**< NULL when closed */
    struct gpiod_line_request *request;     /**< power, trigger (outputs), deployed (edges) */
    struct gpiod_edge_event_buffer *events; /**< one event, read by wait_deployed */
    uint32_t power_offset;                  /**< the lines' offsets on the chip */
    uint32_t trigger_offset;
    uint32_t deployed_offset;
    uint32_t pulse_us; /**< trigger pulse width */
} trn_lgpio_t;
#else
/** The open lines. Owned by the caller; open fills it, close empties it. */
typedef struct {
    struct gpiod_chip *chip;     /**< NULL when closed */
    struct gpiod_line *power;    /**< requested as output, initially inactive */
    struct gpiod_line *trigger;  /**< requested as output, initially inactive */
    struct gpiod_line *deployed; /**< requested for both-edge events */
    uint32_t pulse_us;           /**< trigger pulse width */
} trn_lgpio_t;
#endif

/**
 * @brief Defaults: chip "gpiochip0", consumer "trn", offsets 0 (power),
 * 1 (trigger), 2 (deployed), all active high, 1000 us pulse.
 * @retval TRN_OK, TRN_E_NULL.
 */
trn_status_t trn_lgpio_cfg_default(trn_lgpio_cfg_t *cfg);

/**
 * @brief Check a configuration without touching the OS.
 * @retval TRN_OK
 * @retval TRN_E_NULL cfg, chip or consumer NULL.
 * @retval TRN_E_SIZE chip or consumer empty.
 * @retval TRN_E_ARG an offset above TRN_LGPIO_MAX_OFFSET, two equal offsets, a
 *         flag not 0/1, pulse width 0 or above TRN_LGPIO_MAX_PULSE_US.
 */
trn_status_t trn_lgpio_cfg_check(const trn_lgpio_cfg_t *cfg);

/**
 * @brief Open the chip and request the three lines: power and trigger as
 * outputs driven inactive, deployed as an input with both-edge events.
 * On failure nothing stays requested and g is closed.
 * @param[out] g   the handle.
 * @param[in]  cfg the configuration.
 * @retval TRN_OK
 * @retval TRN_E_NULL, TRN_E_SIZE, TRN_E_ARG as trn_lgpio_cfg_check (g NULL: TRN_E_NULL).
 * @retval TRN_E_RANGE an offset is not below the chip's line count.
 * @retval TRN_E_IO no such chip, a line already in use (EBUSY), other failures.
 */
trn_status_t trn_lgpio_open(trn_lgpio_t *g, const trn_lgpio_cfg_t *cfg);

/**
 * @brief Release the lines (outputs return to the kernel) and close the chip.
 * A closed handle is accepted.
 * @retval TRN_OK, TRN_E_NULL.
 */
trn_status_t trn_lgpio_close(trn_lgpio_t *g);

/**
 * @brief Switch the mast power.
 * @param[in] g  an open handle.
 * @param[in] on 1 on, 0 off.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (on not 0/1, handle closed), TRN_E_IO.
 */
trn_status_t trn_lgpio_set_power(trn_lgpio_t *g, int on);

/**
 * @brief One trigger pulse: active, the configured width (monotonic clock,
 * at least that long), inactive. The line is driven inactive again even if
 * the wait is interrupted.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (closed), TRN_E_IO.
 */
trn_status_t trn_lgpio_trigger(trn_lgpio_t *g);

/**
 * @brief Read the deployed input now.
 * @param[in]  g        an open handle.
 * @param[out] deployed 1 deployed, 0 not.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (closed), TRN_E_IO.
 */
trn_status_t trn_lgpio_read_deployed(trn_lgpio_t *g, int *deployed);

/**
 * @brief Wait until the mast is deployed: returns at once if the input is
 * already active, else waits for an edge to active. Events queued before the
 * call are discarded first (a past bounce does not count).
 * @param[in] g          an open handle.
 * @param[in] timeout_ms 0..TRN_LGPIO_MAX_TIMEOUT_MS.
 * @retval TRN_OK deployed.
 * @retval TRN_E_TIMEOUT no edge to active in timeout_ms.
 * @retval TRN_E_NULL, TRN_E_ARG (timeout, closed), TRN_E_IO.
 */
trn_status_t trn_lgpio_wait_deployed(trn_lgpio_t *g, int32_t timeout_ms);

#ifdef __cplusplus
}
#endif
#endif /* TRN_PORT_LINUX_GPIO_H */
