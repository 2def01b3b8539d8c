/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file link_mon.h
 * @brief Liveness and loss of one periodic CAN message that carries a
 * counter (MAST_HB, STEREO_HB, MAST_STATUS; docs/can-protocol.md): a silent
 * node, lost frames and repeated frames, each a named event with a counter.
 *
 * Pure and caller-timed: feed every received counter with the current
 * millisecond time (trn_link_mon_frame) and poll periodically
 * (trn_link_mon_poll). States: NEVER_SEEN -> ALIVE <-> SILENT. A node is
 * SILENT once more than timeout_ms passed since its last frame
 * (docs/can-protocol.md: 3 missed heartbeats = 300 ms).
 */
#ifndef TRN_PORT_LINK_MON_H
#define TRN_PORT_LINK_MON_H

#include <stdint.h>
#include "trn/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Monitor states. */
typedef enum { TRN_LINK_NEVER_SEEN = 0, TRN_LINK_ALIVE = 1, TRN_LINK_SILENT = 2 } trn_link_state_t;

/** Event flags of one call. */
#define TRN_LINK_EV_FIRST 0x01u     /**< first frame ever */
#define TRN_LINK_EV_GAP 0x02u       /**< frames were lost before this one (see gap) */
#define TRN_LINK_EV_REPEAT 0x04u    /**< the same counter again (a repeated frame) */
#define TRN_LINK_EV_SILENT 0x08u    /**< the node just became silent */
#define TRN_LINK_EV_RECOVERED 0x10u /**< a frame after a silence */

/** A monitor; fields are read-only for the caller after init. */
typedef struct {
    uint32_t timeout_ms;   /**< silence threshold */
    uint8_t state;         /**< trn_link_state_t */
    uint8_t last_counter;  /**< counter of the last frame */
    uint32_t last_ms;      /**< time of the last frame */
    uint32_t n_frames;     /**< frames fed */
    uint32_t n_lost;       /**< frames lost, summed over gaps (while alive) */
    uint32_t n_gaps;       /**< gap events */
    uint32_t n_repeats;    /**< repeat events */
    uint32_t n_silences;   /**< silent events */
    uint32_t n_recoveries; /**< recovered events */
} trn_link_mon_t;

/**
 * @brief Reset a monitor (NEVER_SEEN, counters zero).
 * @param[in] timeout_ms 1..600000.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (timeout_ms)
 */
trn_status_t trn_link_mon_init(trn_link_mon_t *m, uint32_t timeout_ms);

/**
 * @brief A frame with counter `counter` arrived at now_ms. A silence still
 * pending is reported first (as trn_link_mon_poll). Gaps are not counted
 * across a silence or on the first frame (the counter is unknown then).
 * @param[out] events TRN_LINK_EV_* (may be NULL).
 * @param[out] gap    frames lost before this one (may be NULL).
 * @retval TRN_OK      in sequence (or first / recovered)
 * @retval TRN_E_NULL  m NULL
 * @retval TRN_E_SEQ   GAP or REPEAT
 */
trn_status_t trn_link_mon_frame(trn_link_mon_t *m, uint8_t counter, uint32_t now_ms,
                                uint8_t *events, uint8_t *gap);

/**
 * @brief Advance time: ALIVE becomes SILENT (once) after timeout_ms without
 * a frame. NEVER_SEEN stays NEVER_SEEN (the caller decides how long a node
 * may take to boot).
 * @param[in,out] m      the monitor.
 * @param[in]     now_ms the caller's millisecond clock.
 * @param[out]    events TRN_LINK_EV_SILENT or 0 (may be NULL).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_TIMEOUT (just became silent; events has SILENT)
 */
trn_status_t trn_link_mon_poll(trn_link_mon_t *m, uint32_t now_ms, uint8_t *events);

#ifdef __cplusplus
}
#endif
#endif /* TRN_PORT_LINK_MON_H */
