/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file capture.h
 * @brief One stereo capture on the wire (docs/can-protocol.md, "Capture"):
 * a transport-independent byte format, its split into segments of at most
 * one ISO-TP message each, and a reassembler that hands a capture to the
 * algorithms only when it is complete, in order and CRC-valid.
 *
 * Capture bytes (all little-endian):
 *
 *   off  size  field
 *     0   1    version (TRN_CAP_VERSION)
 *     1   1    flags (reserved, 0)
 *     2   2    capture_id (echo of CAPTURE_CMD)
 *     4   4    time_ms, the stereo head's clock at exposure
 *     8   2    pan at exposure, int16, 1e-4 rad (latest MAST_STATUS)
 *    10   2    tilt at exposure, int16, 1e-4 rad
 *    12   1    mast state bits at exposure (TRN_MAST_ST_*)
 *    13   1    mast fault bits at exposure (TRN_MAST_FLT_*)
 *    14   2    n_points, 0..TRN_PORT_MAX_CAPTURE_POINTS
 *    16  6n    points: x, y, z int16 millimetres, camera frame
 *  16+6n  4    CRC-32 (crc.h) of bytes [0, 16+6n)
 *
 * Segment = one ISO-TP message: [capture_id u16][seg_index u8][seg_count u8]
 * followed by 1..4091 capture bytes; segments carry consecutive slices of
 * the capture bytes, index 0 first.
 *
 * Camera frame (optical): origin at the left camera's optical centre,
 * x right, y down, z forward along the boresight; millimetres, +-32.767 m.
 */
#ifndef TRN_PORT_CAPTURE_H
#define TRN_PORT_CAPTURE_H

#include <stddef.h>
#include <stdint.h>
#include "trn/mast.h"
#include "trn/status.h"
#include "trn_port/port_config.h"
#include "trn_port/isotp.h"

#ifdef __cplusplus
extern "C" {
#endif

#define TRN_CAP_VERSION 1u
#define TRN_CAP_HEADER_BYTES 16u
#define TRN_CAP_POINT_BYTES 6u
#define TRN_CAP_CRC_BYTES 4u
#define TRN_CAP_SEG_HEADER_BYTES 4u
/** Most capture bytes in one segment (an ISO-TP message of 4095 bytes). */
#define TRN_CAP_SEG_PAYLOAD_MAX (TRN_ISOTP_MAX_MSG - TRN_CAP_SEG_HEADER_BYTES)
/** Wire bytes of a capture of n points. */
#define TRN_CAP_WIRE_BYTES(n) \
    (TRN_CAP_HEADER_BYTES + TRN_CAP_POINT_BYTES * (size_t)(n) + TRN_CAP_CRC_BYTES)
/** Wire bytes of the largest capture this build accepts. */
#define TRN_CAP_WIRE_MAX TRN_CAP_WIRE_BYTES(TRN_PORT_MAX_CAPTURE_POINTS)

/** One range point, camera frame, millimetres. */
typedef struct {
    int16_t x_mm; /**< right */
    int16_t y_mm; /**< down */
    int16_t z_mm; /**< forward (range along the boresight) */
} trn_cap_point_t;

/** A decoded, validated capture. */
typedef struct {
    uint16_t capture_id;
    uint32_t time_ms;     /**< stereo-head clock at exposure */
    int16_t pan_100urad;  /**< mast pan at exposure, 1e-4 rad */
    int16_t tilt_100urad; /**< mast tilt at exposure, 1e-4 rad */
    uint8_t mast_state;   /**< TRN_MAST_ST_* at exposure */
    uint8_t mast_faults;  /**< TRN_MAST_FLT_* at exposure */
    uint16_t n_points;    /**< valid entries of points */
    uint32_t crc;         /**< the CRC-32 carried (and verified) */
    trn_cap_point_t points[TRN_PORT_MAX_CAPTURE_POINTS];
} trn_capture_t;

/** Named capture errors (index into trn_capture_rx_t.err_count). */
typedef enum {
    TRN_CAP_ERR_NONE = 0,
    TRN_CAP_ERR_SHORT_SEGMENT, /**< segment shorter than its header + 1 byte */
    TRN_CAP_ERR_SEG_COUNT,     /**< seg_count 0, seg_index >= seg_count, or seg_count changed */
    TRN_CAP_ERR_ID_MISMATCH, /**< segment of another capture_id mid-capture, or header id != segment id */
    TRN_CAP_ERR_MISSING,      /**< a segment was skipped (index above the expected one) */
    TRN_CAP_ERR_DUPLICATE,    /**< the previous segment again */
    TRN_CAP_ERR_OUT_OF_ORDER, /**< an earlier segment (not the previous) */
    TRN_CAP_ERR_RESTARTED, /**< segment 0 of a capture while another was incomplete (old one dropped) */
    TRN_CAP_ERR_VERSION,         /**< unknown version or reserved flags set */
    TRN_CAP_ERR_TOO_MANY_POINTS, /**< n_points above TRN_PORT_MAX_CAPTURE_POINTS */
    TRN_CAP_ERR_OVERFLOW,        /**< more bytes than the header announces (wrong length) */
    TRN_CAP_ERR_TRUNCATED,       /**< last segment arrived with fewer bytes than announced */
    TRN_CAP_ERR_CRC,             /**< CRC-32 mismatch */
    TRN_CAP_ERR_TRANSPORT,       /**< the transport aborted the capture (trn_capture_rx_abort) */
    TRN_CAP_ERR_COUNT
} trn_cap_err_t;

/**
 * A reassembler: the wire buffer of the largest capture and counters,
 * owned by the caller (sizeof(trn_capture_rx_t) ~ TRN_CAP_WIRE_MAX bytes).
 * Initialize with trn_capture_rx_init.
 */
typedef struct {
    uint8_t wire[TRN_CAP_WIRE_MAX];        /**< capture bytes received so far */
    size_t got;                            /**< bytes in wire */
    uint16_t capture_id;                   /**< of the capture in progress */
    uint8_t next_index;                    /**< next expected segment index */
    uint8_t seg_count;                     /**< of the capture in progress */
    uint8_t active;                        /**< 1 while a capture is in progress */
    uint32_t n_complete;                   /**< captures delivered */
    uint32_t err_count[TRN_CAP_ERR_COUNT]; /**< per trn_cap_err_t */
} trn_capture_rx_t;

/**
 * @brief Serialize a capture (computes and stores the CRC; c->crc is ignored).
 * @param[in]  c     the capture; n_points <= TRN_PORT_MAX_CAPTURE_POINTS.
 * @param[out] wire  cap bytes.
 * @param[out] len   TRN_CAP_WIRE_BYTES(c->n_points).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_CAPACITY (too many points),
 *         TRN_E_WORKSPACE (cap too small)
 */
trn_status_t trn_capture_encode(const trn_capture_t *c, uint8_t *wire, size_t cap, size_t *len);

/**
 * @brief Validate and decode complete capture bytes. out is written only
 * on TRN_OK; err (may be NULL) names the first failed check.
 * @param[in]  wire capture bytes.
 * @param[in]  len  their number.
 * @param[out] out  the capture.
 * @param[out] err  the named error, NONE on success (may be NULL).
 * @retval TRN_OK, TRN_E_NULL (wire or out)
 * @retval TRN_E_FORMAT   VERSION; TRUNCATED (len below header + CRC or
 *                        below the announced size); OVERFLOW (len above it)
 * @retval TRN_E_CAPACITY TOO_MANY_POINTS
 * @retval TRN_E_CRC      CRC
 */
trn_status_t trn_capture_decode(const uint8_t *wire, size_t len, trn_capture_t *out,
                                trn_cap_err_t *err);

/**
 * @brief Number of segments of a capture of wire_len bytes when each
 * carries at most seg_payload capture bytes.
 * @param[in]  wire_len    capture bytes.
 * @param[in]  seg_payload capture bytes per segment, 1..4091.
 * @param[out] count       segments.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (seg_payload 0 or above
 *         TRN_CAP_SEG_PAYLOAD_MAX, wire_len 0), TRN_E_SIZE (more than 255 segments)
 */
trn_status_t trn_capture_segment_count(size_t wire_len, size_t seg_payload, uint8_t *count);

/**
 * @brief Build segment `index` of capture bytes (the capture_id is read
 * from the capture header).
 * @param[out] out     cap bytes; receives the segment (one ISO-TP message).
 * @param[out] out_len its length, 5..4095.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (as trn_capture_segment_count, or
 *         wire_len < TRN_CAP_HEADER_BYTES), TRN_E_SIZE, TRN_E_RANGE (index
 *         >= count), TRN_E_WORKSPACE (cap too small)
 */
trn_status_t trn_capture_segment(const uint8_t *wire, size_t wire_len, size_t seg_payload,
                                 uint8_t index, uint8_t *out, size_t cap, size_t *out_len);

/**
 * @brief Reset a reassembler: idle, counters zero. @retval TRN_OK, TRN_E_NULL
 * @param[out] rx the reassembler.
 */
trn_status_t trn_capture_rx_init(trn_capture_rx_t *rx);

/**
 * @brief Feed one segment (one complete ISO-TP message). When it completes
 * a capture that decodes (trn_capture_decode), *out is written, *complete
 * is 1 and TRN_OK returned. On any error the capture in progress is dropped
 * (except RESTARTED, where the new capture continues), err_count[err] is
 * incremented and out is not touched: no partial data is ever visible.
 * @param[out] complete 1 when out holds a new capture, else 0.
 * @param[out] err      the named error (NONE on success); may be NULL.
 * @retval TRN_OK         segment accepted (complete says whether a capture is ready)
 * @retval TRN_E_NULL     rx, seg, out or complete NULL
 * @retval TRN_E_FORMAT   SHORT_SEGMENT, SEG_COUNT, ID_MISMATCH, VERSION, OVERFLOW, TRUNCATED
 * @retval TRN_E_SEQ      MISSING, DUPLICATE, OUT_OF_ORDER, RESTARTED
 * @retval TRN_E_CAPACITY TOO_MANY_POINTS
 * @retval TRN_E_CRC      CRC
 */
trn_status_t trn_capture_rx_segment(trn_capture_rx_t *rx, const uint8_t *seg, size_t len,
                                    trn_capture_t *out, int *complete, trn_cap_err_t *err);

/**
 * @brief The transport lost part of a capture (ISO-TP error or timeout):
 * drop the capture in progress, counting TRANSPORT if one was active.
 * @param[in,out] rx the reassembler.
 * @retval TRN_OK, TRN_E_NULL
 */
trn_status_t trn_capture_rx_abort(trn_capture_rx_t *rx);

/**
 * @brief The points of a validated capture in metres (camera frame), ready
 * for trn_mast_camera_to_map / trn_rigid_apply (mast.h) with the capture's
 * pan and tilt (trn_can_angle_from_raw): each coordinate is mm / 1000,
 * correctly rounded to float.
 * @param[in]  c    the capture.
 * @param[out] out  capacity points.
 * @param[out] n    c->n_points.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_CAPACITY (capacity < n_points, nothing
 *         written), TRN_E_SIZE (c->n_points above TRN_PORT_MAX_CAPTURE_POINTS)
 */
trn_status_t trn_capture_points_m(const trn_capture_t *c, trn_vec3f_t *out, size_t capacity,
                                  size_t *n);

/**
 * @brief Short constant name of an error ("CRC", ...). Never NULL.
 * @param[in] err any value (unknown values give "UNKNOWN").
 */
const char *trn_cap_err_name(trn_cap_err_t err);

#ifdef __cplusplus
}
#endif
#endif /* TRN_PORT_CAPTURE_H */
