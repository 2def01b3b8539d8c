/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file can_msg.h
 * @brief The mast / stereo-head CAN messages (docs/can-protocol.md,
 * port/proto/trn_mast.dbc): classic CAN 2.0A frames, 11-bit IDs, every
 * multi-byte signal little-endian (Intel, DBC "@1"), packed and unpacked
 * with shifts only, so the code is right on any processor byte order.
 *
 * Message structs hold the exact integers of the wire ("raw" values, with
 * the unit of one count in the field name); trn_can_angle_to_raw and
 * trn_can_angle_from_raw convert angles. Encoders reject values the wire
 * cannot carry (TRN_E_ARG); decoders reject frames that are not exactly the
 * message (wrong ID, extended or remote frame, wrong DLC, reserved bits or
 * enumeration values out of range) with TRN_E_FORMAT, and never write a
 * partially decoded message (out is written only on TRN_OK).
 */
#ifndef TRN_PORT_CAN_MSG_H
#define TRN_PORT_CAN_MSG_H

#include <stddef.h>
#include <stdint.h>
#include "trn/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- identifiers (11-bit) ----------------------------------------------- */
#define TRN_CAN_ID_MAST_CMD 0x120u     /**< rover -> mast: pan-tilt position command */
#define TRN_CAN_ID_MAST_STATUS 0x121u  /**< mast -> all: actual angles, flags, counter */
#define TRN_CAN_ID_CAPTURE_CMD 0x130u  /**< rover -> stereo head: take one capture */
#define TRN_CAN_ID_CAPTURE_DATA 0x1A0u /**< stereo head -> rover: ISO-TP data (SF/FF/CF) */
#define TRN_CAN_ID_CAPTURE_FC 0x1A1u   /**< rover -> stereo head: ISO-TP flow control */
#define TRN_CAN_ID_MAST_HB 0x701u      /**< mast heartbeat */
#define TRN_CAN_ID_STEREO_HB 0x702u    /**< stereo-head heartbeat */

/* ---- DLCs ---------------------------------------------------------------- */
#define TRN_CAN_DLC_MAST_CMD 8u
#define TRN_CAN_DLC_MAST_STATUS 8u
#define TRN_CAN_DLC_CAPTURE_CMD 4u
#define TRN_CAN_DLC_HEARTBEAT 4u

/** One angle count: 1e-4 rad (100 microradians); int16 spans +-3.2767 rad. */
#define TRN_CAN_ANGLE_RAD_PER_COUNT 1.0e-4f

/** A classic CAN frame as the port layer sees it (no FD). */
typedef struct {
    uint32_t id;     /**< 11-bit (or 29-bit with TRN_CAN_FLAG_EXT) identifier */
    uint8_t dlc;     /**< data length, 0..8 */
    uint8_t flags;   /**< TRN_CAN_FLAG_* */
    uint8_t data[8]; /**< payload; bytes >= dlc are don't-care */
} trn_can_frame_t;

#define TRN_CAN_FLAG_EXT 0x01u /**< 29-bit identifier */
#define TRN_CAN_FLAG_RTR 0x02u /**< remote transmission request */

/** MAST_CMD mode byte. */
typedef enum {
    TRN_MAST_MODE_HOLD = 0, /**< hold the current position, ignore the angles */
    TRN_MAST_MODE_MOVE = 1, /**< move to (pan, tilt) at up to rate */
    TRN_MAST_MODE_STOP = 2  /**< stop now (decelerate and hold) */
} trn_mast_mode_t;

/** MAST_CMD (0x120, DLC 8). */
typedef struct {
    int16_t
        pan_100urad; /**< commanded pan, 1e-4 rad, + = left (counterclockwise seen from above) */
    int16_t tilt_100urad;    /**< commanded tilt, 1e-4 rad, + = up */
    uint16_t rate_100urad_s; /**< largest axis rate, 1e-4 rad/s; 0 = the mast's default */
    uint8_t seq;             /**< command sequence, incremented per new command (wraps) */
    uint8_t mode;            /**< trn_mast_mode_t */
} trn_mast_cmd_t;

/* MAST_STATUS state bits (byte 4) */
#define TRN_MAST_ST_MOVING 0x01u       /**< an axis is moving */
#define TRN_MAST_ST_PAN_LIM_MIN 0x02u  /**< pan at its minimum limit switch */
#define TRN_MAST_ST_PAN_LIM_MAX 0x04u  /**< pan at its maximum limit switch */
#define TRN_MAST_ST_TILT_LIM_MIN 0x08u /**< tilt at its minimum limit switch */
#define TRN_MAST_ST_TILT_LIM_MAX 0x10u /**< tilt at its maximum limit switch */
#define TRN_MAST_ST_IN_POSITION 0x20u  /**< both axes within tolerance of the last command */
#define TRN_MAST_ST_RESERVED 0xC0u     /**< must be zero */
/* MAST_STATUS fault bits (byte 5) */
#define TRN_MAST_FLT_PAN_STALL 0x01u   /**< pan commanded but not moving (stuck axis) */
#define TRN_MAST_FLT_TILT_STALL 0x02u  /**< tilt commanded but not moving */
#define TRN_MAST_FLT_ENCODER 0x04u     /**< an angle encoder failed; angles invalid */
#define TRN_MAST_FLT_OVERCURRENT 0x08u /**< motor overcurrent, drives off */
#define TRN_MAST_FLT_OVERTEMP 0x10u    /**< motor or driver overtemperature */
#define TRN_MAST_FLT_CMD_INVALID 0x20u /**< last command rejected (outside limits, bad mode) */
#define TRN_MAST_FLT_RESERVED 0xC0u    /**< must be zero */

/** MAST_STATUS (0x121, DLC 8). */
typedef struct {
    int16_t pan_100urad;  /**< measured pan, 1e-4 rad */
    int16_t tilt_100urad; /**< measured tilt, 1e-4 rad */
    uint8_t state;        /**< TRN_MAST_ST_* bits */
    uint8_t faults;       /**< TRN_MAST_FLT_* bits */
    uint8_t cmd_seq_ack;  /**< seq of the last accepted MAST_CMD */
    uint8_t counter;      /**< +1 per status frame (wraps); gaps = lost frames */
} trn_mast_status_t;

/** CAPTURE_CMD (0x130, DLC 4). */
typedef struct {
    uint16_t capture_id; /**< echoed in the capture; 0 is valid */
    uint16_t max_points; /**< most points to send; 0 = the head's own maximum */
} trn_capture_cmd_t;

/** Heartbeat node state. */
typedef enum {
    TRN_NODE_BOOT = 0,  /**< starting, not ready for commands */
    TRN_NODE_READY = 1, /**< idle, accepts commands */
    TRN_NODE_BUSY = 2,  /**< moving / capturing / sending */
    TRN_NODE_FAULT = 3  /**< faulted; see its status message */
} trn_node_state_t;

/** MAST_HB (0x701) and STEREO_HB (0x702), DLC 4. */
typedef struct {
    uint8_t state;     /**< trn_node_state_t */
    uint8_t counter;   /**< +1 per heartbeat (wraps) */
    uint16_t uptime_s; /**< seconds since node boot (wraps after 18.2 h) */
} trn_heartbeat_t;

/** Which of our messages a frame is. */
typedef enum {
    TRN_CAN_MSG_NONE = 0, /**< not one of ours */
    TRN_CAN_MSG_MAST_CMD,
    TRN_CAN_MSG_MAST_STATUS,
    TRN_CAN_MSG_CAPTURE_CMD,
    TRN_CAN_MSG_CAPTURE_DATA, /**< ISO-TP data frame of a capture (isotp.h, capture.h) */
    TRN_CAN_MSG_CAPTURE_FC,   /**< ISO-TP flow control (isotp.h) */
    TRN_CAN_MSG_MAST_HB,
    TRN_CAN_MSG_STEREO_HB
} trn_can_msg_kind_t;

/**
 * @brief Which of our messages a frame's identifier names (by ID and frame
 * format only; the DLC is checked by the decoders).
 * @param[in] f the frame; NULL gives TRN_CAN_MSG_NONE.
 * @return the kind, TRN_CAN_MSG_NONE for extended, remote or foreign frames.
 */
trn_can_msg_kind_t trn_can_classify(const trn_can_frame_t *f);

/**
 * @brief Short constant name of a kind ("MAST_CMD", ...; "NONE"). Never NULL.
 * @param[in] kind any value (unknown values give "NONE").
 */
const char *trn_can_msg_name(trn_can_msg_kind_t kind);

/**
 * @brief Angle in radians to wire counts (1e-4 rad), rounded to nearest
 * (ties away from zero).
 * @param[in]  rad angle.
 * @param[out] raw counts.
 * @retval TRN_OK
 * @retval TRN_E_NULL raw is NULL
 * @retval TRN_E_ARG  rad is NaN or rounds outside [-32768, 32767] counts
 */
trn_status_t trn_can_angle_to_raw(float rad, int16_t *raw);

/**
 * @brief Wire counts to radians (exact to float rounding: raw * 1e-4).
 * @param[in] raw angle counts (1e-4 rad).
 * @return raw * 1e-4 rad.
 */
float trn_can_angle_from_raw(int16_t raw);

/**
 * @brief Encode MAST_CMD.
 * @param[in]  m   the command.
 * @param[out] f   the frame (id, dlc 8, flags 0, data).
 * @retval TRN_OK, TRN_E_NULL (m or f NULL), TRN_E_ARG (mode not a trn_mast_mode_t)
 */
trn_status_t trn_can_mast_cmd_encode(const trn_mast_cmd_t *m, trn_can_frame_t *f);

/**
 * @brief Decode MAST_CMD.
 * @param[in]  f the frame.
 * @param[out] m the command (written only on TRN_OK).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_FORMAT (not 0x120 standard data frame
 *         with DLC 8, or mode out of range)
 */
trn_status_t trn_can_mast_cmd_decode(const trn_can_frame_t *f, trn_mast_cmd_t *m);

/**
 * @brief Encode MAST_STATUS.
 * @param[in]  m the status.
 * @param[out] f the frame (id 0x121, dlc 8, flags 0).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (reserved state or fault bits set)
 */
trn_status_t trn_can_mast_status_encode(const trn_mast_status_t *m, trn_can_frame_t *f);

/**
 * @brief Decode MAST_STATUS.
 * @param[in]  f the frame.
 * @param[out] m the status (written only on TRN_OK).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_FORMAT (ID, format, DLC != 8, reserved bits set)
 */
trn_status_t trn_can_mast_status_decode(const trn_can_frame_t *f, trn_mast_status_t *m);

/**
 * @brief Encode CAPTURE_CMD.
 * @param[in]  m the command.
 * @param[out] f the frame (id 0x130, dlc 4, flags 0).
 * @retval TRN_OK, TRN_E_NULL
 */
trn_status_t trn_can_capture_cmd_encode(const trn_capture_cmd_t *m, trn_can_frame_t *f);

/**
 * @brief Decode CAPTURE_CMD.
 * @param[in]  f the frame.
 * @param[out] m the command (written only on TRN_OK).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_FORMAT (ID, format, DLC != 4)
 */
trn_status_t trn_can_capture_cmd_decode(const trn_can_frame_t *f, trn_capture_cmd_t *m);

/**
 * @brief Encode a heartbeat of the mast (id TRN_CAN_ID_MAST_HB) or of the
 * stereo head (TRN_CAN_ID_STEREO_HB).
 * @param[in]  id TRN_CAN_ID_MAST_HB or TRN_CAN_ID_STEREO_HB.
 * @param[in]  m  the heartbeat.
 * @param[out] f  the frame (dlc 4, flags 0).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (id is neither heartbeat ID, or
 *         state not a trn_node_state_t)
 */
trn_status_t trn_can_heartbeat_encode(uint32_t id, const trn_heartbeat_t *m, trn_can_frame_t *f);

/**
 * @brief Decode either heartbeat (the frame's ID tells which node).
 * @param[in]  f the frame (either heartbeat ID).
 * @param[out] m the heartbeat (written only on TRN_OK).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_FORMAT (not a heartbeat ID, format,
 *         DLC != 4, state out of range)
 */
trn_status_t trn_can_heartbeat_decode(const trn_can_frame_t *f, trn_heartbeat_t *m);

/**
 * @brief Frames lost between two consecutive counters of one message:
 * (uint8_t)(now - prev - 1), 0 when now follows prev, 255 for a repeat.
 * @param[in] prev counter of the previous frame.
 * @param[in] now  counter of this frame.
 */
uint8_t trn_can_counter_gap(uint8_t prev, uint8_t now);

#ifdef __cplusplus
}
#endif
#endif /* TRN_PORT_CAN_MSG_H */
