/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file isotp.h
 * @brief ISO 15765-2 (ISO-TP) on classic CAN, without an operating system:
 * a pure frame codec and a receiver state machine with caller-driven time.
 *
 * Used where the kernel's CAN_ISOTP socket is not available: the bare-metal
 * flight processor, and `trn can-decode`, which reassembles captures from
 * raw frames of a candump log. Normal addressing, classic 8-byte frames,
 * 12-bit message length (8..4095 bytes for a segmented message; the 32-bit
 * escape FF_DL = 0 of ISO 15765-2:2016 is rejected). The protocol control
 * information (PCI) is big-endian as the standard says: PCI type in the high
 * nibble of byte 0.
 *
 *   SF  [0x0L] d..        L = 1..7 data bytes          (single frame)
 *   FF  [0x1H LL] d*6     12-bit length 8..4095        (first frame, DLC 8)
 *   CF  [0x2N] d..        N = sequence number 0..15    (consecutive frame)
 *   FC  [0x3S BS ST]      S: 0 clear to send, 1 wait, 2 overflow
 *
 * Padding: encoders send the shortest frame (no padding, like the Linux
 * CAN_ISOTP default); the decoder accepts any padding bytes.
 *
 * Every error is a named trn_isotp_err_t and increments a counter in the
 * receiver; the receiver then returns to idle and nothing of the aborted
 * message is reported as a message.
 */
#ifndef TRN_PORT_ISOTP_H
#define TRN_PORT_ISOTP_H

#include <stddef.h>
#include <stdint.h>
#include "trn/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Largest ISO-TP message with a 12-bit length. */
#define TRN_ISOTP_MAX_MSG 4095u
/** Data bytes in a first frame and in a full consecutive frame. */
#define TRN_ISOTP_FF_DATA 6u
#define TRN_ISOTP_CF_DATA 7u
/** Largest single-frame payload (classic CAN). */
#define TRN_ISOTP_SF_MAX 7u

/** PCI frame types (high nibble of byte 0). */
typedef enum {
    TRN_ISOTP_SF = 0,
    TRN_ISOTP_FF = 1,
    TRN_ISOTP_CF = 2,
    TRN_ISOTP_FC = 3
} trn_isotp_type_t;

/** Flow status of a flow-control frame. */
typedef enum {
    TRN_ISOTP_FS_CTS = 0,  /**< continue to send */
    TRN_ISOTP_FS_WAIT = 1, /**< wait for another FC */
    TRN_ISOTP_FS_OVFLW = 2 /**< overflow: the receiver cannot take the message; abort */
} trn_isotp_fs_t;

/** A decoded frame: its PCI fields and where its payload lies. */
typedef struct {
    uint8_t type;     /**< trn_isotp_type_t */
    uint16_t msg_len; /**< SF: payload bytes 1..7; FF: message length 8..4095; else 0 */
    uint8_t sn;       /**< CF: sequence number 0..15 */
    uint8_t fs;       /**< FC: trn_isotp_fs_t */
    uint8_t bs;       /**< FC: block size (0 = no further FC) */
    uint8_t stmin;    /**< FC: STmin raw byte (trn_isotp_stmin_us) */
    uint8_t data_off; /**< SF/FF/CF: index of the first payload byte in the frame */
    uint8_t data_len; /**< SF/FF/CF: payload bytes in this frame (CF: all after the PCI) */
} trn_isotp_frame_t;

/** Named receiver errors (index into trn_isotp_rx_t.err_count). */
typedef enum {
    TRN_ISOTP_ERR_NONE = 0,
    TRN_ISOTP_ERR_BAD_FRAME, /**< undecodable: DLC 0, reserved PCI type, bad SF/FF length, short FC */
    TRN_ISOTP_ERR_UNEXPECTED_CF, /**< consecutive frame while idle (ignored) */
    TRN_ISOTP_ERR_WRONG_SN, /**< consecutive frame with the wrong sequence number: message aborted */
    TRN_ISOTP_ERR_OVERFLOW, /**< FF length above the buffer: FC overflow sent, message refused */
    TRN_ISOTP_ERR_INTERRUPTED, /**< SF or FF during a reception: the old message is dropped, the new one processed */
    TRN_ISOTP_ERR_TIMEOUT_CR,    /**< N_Cr: no consecutive frame within n_cr_ms: message aborted */
    TRN_ISOTP_ERR_UNEXPECTED_FC, /**< flow control on the data ID (ignored) */
    TRN_ISOTP_ERR_SHORT_CF, /**< a consecutive frame other than the last with < 7 data bytes: message aborted */
    TRN_ISOTP_ERR_COUNT
} trn_isotp_err_t;

/** Result flags of one receiver step. */
#define TRN_ISOTP_EV_MESSAGE 0x01u /**< a complete message is in buf[0..msg_len) */
#define TRN_ISOTP_EV_SEND_FC 0x02u /**< transmit fc[0..fc_dlc) on the flow-control ID now */
#define TRN_ISOTP_EV_ERROR 0x04u   /**< error holds what went wrong (counted) */

/** What one receiver step produced. */
typedef struct {
    uint8_t events;   /**< TRN_ISOTP_EV_* */
    uint8_t error;    /**< trn_isotp_err_t (when EV_ERROR) */
    uint16_t msg_len; /**< when EV_MESSAGE */
    uint8_t fc[8];    /**< when EV_SEND_FC */
    uint8_t fc_dlc;   /**< when EV_SEND_FC: 3 */
} trn_isotp_rx_result_t;

/** Receiver states. */
typedef enum { TRN_ISOTP_RX_IDLE = 0, TRN_ISOTP_RX_RECEIVING = 1 } trn_isotp_rx_state_t;

/**
 * A receiver: configuration, state and counters, all owned by the caller.
 * Initialize with trn_isotp_rx_init; do not write the fields afterwards.
 */
typedef struct {
    uint8_t *buf;        /**< caller memory of cap bytes; holds the message being received */
    uint16_t cap;        /**< buffer bytes, 7..4095 */
    uint8_t bs;          /**< block size we announce (0 = all CFs without further FC) */
    uint8_t stmin;       /**< STmin raw byte we announce */
    uint32_t n_cr_ms;    /**< N_Cr timeout: longest gap between frames of a message */
    uint8_t state;       /**< trn_isotp_rx_state_t */
    uint8_t next_sn;     /**< expected CF sequence number */
    uint8_t block_left;  /**< CFs left in the current block (bs > 0) */
    uint16_t msg_len;    /**< length of the message being received */
    uint16_t got;        /**< bytes received so far */
    uint32_t last_ms;    /**< time of the last accepted frame */
    uint32_t n_messages; /**< complete messages delivered */
    uint32_t err_count[TRN_ISOTP_ERR_COUNT]; /**< per trn_isotp_err_t */
} trn_isotp_rx_t;

/**
 * @brief Decode the PCI of one frame.
 * @param[in]  data frame bytes (dlc of them).
 * @param[in]  dlc  0..8.
 * @param[out] fr   the fields (written only on TRN_OK).
 * @retval TRN_OK
 * @retval TRN_E_NULL   data or fr NULL
 * @retval TRN_E_ARG    dlc > 8
 * @retval TRN_E_FORMAT DLC 0; PCI type 4..15; SF length 0 or longer than
 *         the frame or than 7; FF with DLC != 8 or length < 8 (incl. the
 *         32-bit escape 0); CF without payload; FC shorter than 3 bytes or
 *         flow status > 2
 */
trn_status_t trn_isotp_decode(const uint8_t *data, uint8_t dlc, trn_isotp_frame_t *fr);

/**
 * @brief Number of frames a sender needs for a message of len bytes.
 * @param[in] len message length in bytes.
 * @retval 1 for 1..7 bytes, 1 + ceil((len-6)/7) for 8..4095, 0 otherwise.
 */
uint16_t trn_isotp_frame_count(size_t len);

/**
 * @brief The index-th frame of a message as a sender emits it (stateless:
 * frame 0 is the SF or FF; frame k >= 1 is CF number k, sequence number
 * k mod 16). Flow control and timing are the sender's business.
 * @param[in]  msg   message bytes.
 * @param[in]  len   1..4095.
 * @param[in]  index 0..trn_isotp_frame_count(len)-1.
 * @param[out] out   8 bytes.
 * @param[out] dlc   bytes used in out.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_SIZE (len 0 or > 4095), TRN_E_RANGE (index too large)
 */
trn_status_t trn_isotp_encode_frame(const uint8_t *msg, size_t len, uint16_t index, uint8_t out[8],
                                    uint8_t *dlc);

/**
 * @brief Encode a flow-control frame (3 bytes).
 * @param[in]  fs    flow status, trn_isotp_fs_t.
 * @param[in]  bs    block size.
 * @param[in]  stmin STmin raw byte.
 * @param[out] out   8 bytes (bytes 3..7 zeroed).
 * @param[out] dlc   3.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (fs > 2)
 */
trn_status_t trn_isotp_encode_fc(uint8_t fs, uint8_t bs, uint8_t stmin, uint8_t out[8],
                                 uint8_t *dlc);

/**
 * @brief STmin byte to microseconds: 0x00..0x7F are milliseconds,
 * 0xF1..0xF9 are 100..900 us; reserved values mean 127 ms (ISO 15765-2).
 * @param[in] stmin the raw byte of an FC.
 * @return the separation time in microseconds.
 */
uint32_t trn_isotp_stmin_us(uint8_t stmin);

/**
 * @brief Set up a receiver over caller memory; all counters zero, idle.
 * @param[out] rx      the receiver.
 * @param[in]  buf     cap bytes, kept by rx until it is no longer used.
 * @param[in]  cap     7..4095.
 * @param[in]  bs      block size to announce.
 * @param[in]  stmin   STmin raw byte to announce (0x00..0x7F, 0xF1..0xF9).
 * @param[in]  n_cr_ms N_Cr timeout, 1..60000 ms.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_SIZE (cap), TRN_E_ARG (stmin reserved, n_cr_ms)
 */
trn_status_t trn_isotp_rx_init(trn_isotp_rx_t *rx, uint8_t *buf, size_t cap, uint8_t bs,
                               uint8_t stmin, uint32_t n_cr_ms);

/**
 * @brief Feed one frame received on the data ID at time now_ms (any
 * monotonic millisecond clock; wraps are handled). A pending N_Cr timeout is
 * applied first (as trn_isotp_rx_poll). On EV_MESSAGE the message is in
 * rx->buf until the next call.
 * @param[out] res what happened (always written when the arguments are valid).
 * @retval TRN_OK        nothing wrong (res->events may hold MESSAGE / SEND_FC)
 * @retval TRN_E_NULL    an argument NULL
 * @retval TRN_E_ARG     dlc > 8
 * @retval TRN_E_FORMAT  BAD_FRAME, UNEXPECTED_CF, UNEXPECTED_FC, SHORT_CF
 * @retval TRN_E_SEQ     WRONG_SN, INTERRUPTED
 * @retval TRN_E_CAPACITY OVERFLOW (res->events has SEND_FC with overflow status)
 * @retval TRN_E_TIMEOUT TIMEOUT_CR (the frame was then processed from idle)
 */
trn_status_t trn_isotp_rx_frame(trn_isotp_rx_t *rx, const uint8_t *data, uint8_t dlc,
                                uint32_t now_ms, trn_isotp_rx_result_t *res);

/**
 * @brief Advance time without a frame: a reception idle for more than
 * n_cr_ms is aborted (TIMEOUT_CR).
 * @param[in,out] rx     the receiver.
 * @param[in]     now_ms the caller's millisecond clock.
 * @param[out]    res    what happened.
 * @retval TRN_OK (no timeout), TRN_E_NULL, TRN_E_TIMEOUT
 */
trn_status_t trn_isotp_rx_poll(trn_isotp_rx_t *rx, uint32_t now_ms, trn_isotp_rx_result_t *res);

/**
 * @brief Short constant name of an error ("WRONG_SN", ...). Never NULL.
 * @param[in] err any value (unknown values give "UNKNOWN").
 */
const char *trn_isotp_err_name(trn_isotp_err_t err);

/* ---- sender --------------------------------------------------------------- */

/** Named sender errors (index into trn_isotp_tx_t.err_count). */
typedef enum {
    TRN_ISOTP_TX_ERR_NONE = 0,
    TRN_ISOTP_TX_ERR_TIMEOUT_BS,  /**< N_Bs: no flow control within n_bs_ms: message aborted */
    TRN_ISOTP_TX_ERR_WFT_OVERRUN, /**< more consecutive FC WAIT than max_wft: message aborted */
    TRN_ISOTP_TX_ERR_OVERFLOW,    /**< the receiver answered FC overflow: message aborted */
    TRN_ISOTP_TX_ERR_INVALID_FC, /**< undecodable FC (reserved flow status, short): message aborted */
    TRN_ISOTP_TX_ERR_UNEXPECTED_FC, /**< FC while not waiting for one (ignored) */
    TRN_ISOTP_TX_ERR_COUNT
} trn_isotp_tx_err_t;

/** Sender states. */
typedef enum {
    TRN_ISOTP_TX_IDLE = 0,    /**< nothing to send */
    TRN_ISOTP_TX_FIRST = 1,   /**< started; the SF or FF goes out at the next step */
    TRN_ISOTP_TX_WAIT_FC = 2, /**< FF or a block sent; waiting for flow control */
    TRN_ISOTP_TX_SENDING = 3  /**< sending consecutive frames, paced by STmin */
} trn_isotp_tx_state_t;

/** Result flags of one sender step. */
#define TRN_ISOTP_TX_EV_FRAME 0x01u /**< transmit frame[0..dlc) on the data ID now */
#define TRN_ISOTP_TX_EV_DONE 0x02u  /**< the last frame of the message is in this result */
#define TRN_ISOTP_TX_EV_ERROR \
    0x04u /**< error holds what went wrong (counted); message aborted unless UNEXPECTED_FC */

/** What one sender step produced. */
typedef struct {
    uint8_t events;   /**< TRN_ISOTP_TX_EV_* */
    uint8_t error;    /**< trn_isotp_tx_err_t */
    uint8_t frame[8]; /**< when EV_FRAME */
    uint8_t dlc;      /**< when EV_FRAME */
    uint32_t wake_us; /**< when nothing was sent: the earliest time the next step can act */
} trn_isotp_tx_result_t;

/**
 * A sender: configuration, state and counters, owned by the caller. The
 * message memory stays the caller's and must not change while sending.
 * Time is the caller's microsecond clock (wraps handled; 71 min period).
 */
typedef struct {
    uint32_t n_bs_us;    /**< N_Bs timeout waiting for an FC */
    uint8_t max_wft;     /**< most consecutive FC WAIT accepted */
    uint8_t state;       /**< trn_isotp_tx_state_t */
    const uint8_t *msg;  /**< the message being sent */
    uint16_t len;        /**< its length */
    uint16_t n_frames;   /**< trn_isotp_frame_count(len) */
    uint16_t next;       /**< next frame index */
    uint8_t bs;          /**< block size of the last FC CTS */
    uint8_t block_left;  /**< CFs left in the block (bs > 0) */
    uint8_t wft;         /**< consecutive FC WAIT so far */
    uint8_t paced;       /**< 1 when the next CF must respect STmin */
    uint32_t stmin_us;   /**< separation time of the last FC CTS */
    uint32_t t_ref_us;   /**< FF/block end time (WAIT_FC) or last CF time (SENDING) */
    uint32_t n_messages; /**< messages sent completely */
    uint32_t err_count[TRN_ISOTP_TX_ERR_COUNT]; /**< per trn_isotp_tx_err_t */
} trn_isotp_tx_t;

/**
 * @brief Set up a sender: idle, counters zero.
 * @param[in] n_bs_ms N_Bs, 1..60000 ms.
 * @param[in] max_wft most consecutive FC WAIT, 0..255.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (n_bs_ms)
 */
trn_status_t trn_isotp_tx_init(trn_isotp_tx_t *tx, uint32_t n_bs_ms, uint8_t max_wft);

/**
 * @brief Start sending msg (len 1..4095); the first frame goes out at the
 * next trn_isotp_tx_step. A message in progress is abandoned (not counted).
 * @param[in,out] tx  the sender.
 * @param[in]     msg the message; must stay unchanged until DONE or an abort.
 * @param[in]     len its length.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_SIZE (len)
 */
trn_status_t trn_isotp_tx_start(trn_isotp_tx_t *tx, const uint8_t *msg, size_t len);

/**
 * @brief Advance the sender to now_us: emits at most one frame (the SF/FF,
 * or the next CF once STmin has passed since the previous CF), or reports
 * the N_Bs timeout. Call again after each EV_FRAME, or at res->wake_us.
 * @param[in,out] tx     the sender.
 * @param[in]     now_us the caller's microsecond clock.
 * @param[out]    res    the frame to send and events.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_TIMEOUT (TIMEOUT_BS)
 */
trn_status_t trn_isotp_tx_step(trn_isotp_tx_t *tx, uint32_t now_us, trn_isotp_tx_result_t *res);

/**
 * @brief Feed a frame received on the flow-control ID.
 * @param[in,out] tx     the sender.
 * @param[in]     data   the received frame bytes.
 * @param[in]     dlc    0..8.
 * @param[in]     now_us the caller's microsecond clock.
 * @param[out]    res    events and error.
 * @retval TRN_OK         CTS (sending resumes) or WAIT within max_wft
 * @retval TRN_E_NULL, TRN_E_ARG (dlc > 8)
 * @retval TRN_E_FORMAT   INVALID_FC, UNEXPECTED_FC
 * @retval TRN_E_CAPACITY OVERFLOW
 * @retval TRN_E_SEQ      WFT_OVERRUN
 */
trn_status_t trn_isotp_tx_fc(trn_isotp_tx_t *tx, const uint8_t *data, uint8_t dlc, uint32_t now_us,
                             trn_isotp_tx_result_t *res);

/**
 * @brief Short constant name of a sender error ("TIMEOUT_BS", ...). Never NULL.
 * @param[in] err any value (unknown values give "UNKNOWN").
 */
const char *trn_isotp_tx_err_name(trn_isotp_tx_err_t err);

#ifdef __cplusplus
}
#endif
#endif /* TRN_PORT_ISOTP_H */
