/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file rover_link.h
 * @brief The rover's side of the mast / stereo-head link, as onboard
 * software would use the port (docs/modules/sim.md): heartbeats watched by
 * link monitors, pan-tilt commands until "in position", the stereo trigger
 * pulse on GPIO, the capture over the kernel's ISO-TP socket into
 * trn_capture_rx_segment. Every way a step can end is a named outcome, and a
 * capture is handed out only when it arrived whole and CRC-valid.
 *
 * Linux only; links trn_proto and trn_port_linux (or its static twin).
 */
#ifndef TRN_ROVER_LINK_H
#define TRN_ROVER_LINK_H

#include <stdint.h>
#include "trn/status.h"
#include "trn_port/can_msg.h"
#include "trn_port/capture.h"
#include "trn_port/linux_can.h"
#include "trn_port/linux_gpio.h"
#include "trn_port/link_mon.h"

#ifdef __cplusplus
extern "C" {
#endif

/** How a rover step ended. */
typedef enum {
    ROVER_OK = 0,
    ROVER_E_SILENT,       /**< a node's heartbeat stopped (link monitor: 300 ms) or never came */
    ROVER_E_MAST_FAULT,   /**< MAST_STATUS carries a fault bit (stall, encoder, ...) */
    ROVER_E_MAST_TIMEOUT, /**< not in position within the timeout */
    ROVER_E_BUS_OFF,      /**< an error frame put the controller in bus-off */
    ROVER_E_CAPTURE,      /**< the capture failed with a named trn_cap_err_t */
    ROVER_E_NO_CAPTURE,   /**< no complete capture within the timeout */
    ROVER_E_IO,           /**< a socket or GPIO call failed */
    ROVER_E_COUNT
} rover_outcome_t;

/** Configuration. */
typedef struct {
    const char *ifname;          /**< CAN interface */
    const char *gpio_chip;       /**< chip of the trigger line, or NULL: no GPIO (CAN only) */
    uint32_t trigger_offset;     /**< stereo trigger output */
    uint32_t power_offset;       /**< mast power enable output */
    uint32_t deployed_offset;    /**< mast deployed input */
    uint32_t trigger_pulse_us;   /**< pulse width */
    float rate_rad_s;            /**< MAST_CMD rate_max, rad/s; 0 = the mast's default */
    uint32_t alive_timeout_ms;   /**< wait for both heartbeats */
    uint32_t move_timeout_ms;    /**< wait for in_position */
    uint32_t capture_timeout_ms; /**< wait for the capture */
} rover_cfg_t;

/** The link (caller-owned; large: holds a capture reassembler). */
typedef struct {
    rover_cfg_t cfg;
    trn_lcan_t can;
    trn_lisotp_t tp;
    trn_lgpio_t gpio;
    int gpio_open;
    trn_link_mon_t mast_hb, stereo_hb;
    trn_mast_status_t status; /**< latest MAST_STATUS */
    int have_status;
    uint32_t status_frames;
    uint8_t seq;
    trn_capture_rx_t caprx;
    trn_cap_err_t last_cap_err;
    trn_status_t last_transport; /**< status of the last failed ISO-TP receive */
    uint32_t outcome_count[ROVER_E_COUNT];
} rover_link_t;

/** @brief Defaults: vcan0, no GPIO (trigger line 1, power 0, deployed 2,
 * 20 ms pulse), 1 s alive, 10 s move, 10 s capture. @param[out] cfg (NULL ignored). */
void rover_cfg_default(rover_cfg_t *cfg);

/** @brief Short name of an outcome ("ok", "silent", ...). @param[in] o the outcome. */
const char *rover_outcome_name(rover_outcome_t o);

/** @brief Open the raw CAN socket (status, heartbeats, commands), the
 * ISO-TP socket (rx 0x1A0, tx 0x1A1, BS 0, STmin 0, no padding) and the
 * GPIO lines (when gpio_chip is set; mast power switched on).
 * @retval TRN_OK or the failing port call's status (nothing left open). */
trn_status_t rover_open(rover_link_t *r, const rover_cfg_t *cfg);

/** @brief Close everything (mast power off). @param[in,out] r the link. */
void rover_close(rover_link_t *r);

/** @brief Wait until both nodes' heartbeats are seen.
 * @retval ROVER_OK, ROVER_E_SILENT, ROVER_E_BUS_OFF, ROVER_E_IO */
rover_outcome_t rover_wait_alive(rover_link_t *r);

/** @brief Command the pan-tilt (MOVE, repeated every 100 ms) and wait for a
 * status with this command's seq acknowledged, in_position set and moving
 * clear. Fault bits, a silent node and bus-off end the wait by name.
 * @param[in] pan_rad, tilt_rad the angles.
 * @param[out] at the status that ended the wait (may be NULL). */
rover_outcome_t rover_point(rover_link_t *r, float pan_rad, float tilt_rad, trn_mast_status_t *at);

/** @brief Keep servicing the link (status, heartbeats, monitors) for ms
 * milliseconds. The monitors time frames when they are taken from the
 * socket, so a rover that does not service it for longer than the 300 ms
 * silence threshold counts a silence even if the heartbeats were queued:
 * wait with this, not with sleep.
 * @retval ROVER_OK, ROVER_E_SILENT, ROVER_E_BUS_OFF, ROVER_E_IO */
rover_outcome_t rover_idle(rover_link_t *r, uint32_t ms);

/** @brief Send MAST_CMD STOP (new seq) and wait for a status that
 * acknowledges it with moving clear (the mast holds where it stopped).
 * @param[out] at that status (may be NULL).
 * @retval as rover_point (ROVER_E_MAST_TIMEOUT after move_timeout_ms) */
rover_outcome_t rover_stop(rover_link_t *r, trn_mast_status_t *at);

/** @brief Send one MAST_CMD MOVE without waiting (for tests of STOP).
 * @retval ROVER_OK, ROVER_E_IO */
rover_outcome_t rover_move_nowait(rover_link_t *r, float pan_rad, float tilt_rad);

/** @brief Take one capture: trigger pulse on GPIO (when configured), then
 * CAPTURE_CMD, then segments from the ISO-TP socket into the reassembler
 * until one capture completes. *out is written only on ROVER_OK. On
 * ROVER_E_CAPTURE, *err names the reassembler's error (TRANSPORT for a
 * kernel ISO-TP error, whose status is in r->last_transport).
 * @param[in] id, max_points CAPTURE_CMD fields. */
rover_outcome_t rover_capture(rover_link_t *r, uint16_t id, uint16_t max_points, trn_capture_t *out,
                              trn_cap_err_t *err);

#ifdef __cplusplus
}
#endif
#endif /* TRN_ROVER_LINK_H */
