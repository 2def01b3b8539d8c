/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file linux_can.h
 * @brief Linux SocketCAN port: classic CAN on a raw socket (filters, receive
 * with a timeout, error frames reported as bus status, drop counting) and
 * ISO-TP messages on the kernel's can-isotp socket.
 *
 * Linux only (library `trn_port_linux`). Names carry an `l` (trn_lcan_,
 * trn_lisotp_) to keep them apart from the target-independent protocol code
 * of port/proto. The handles are plain structs the caller owns; nothing here
 * allocates. Every function checks its arguments and returns a named
 * trn_status_t; a failed open leaves the handle closed (fd = -1) and a failed
 * receive writes nothing to the caller's frame or buffer except where stated.
 *
 * Timeouts are in milliseconds: 0 means "poll once, do not wait", the maximum
 * is TRN_LCAN_MAX_TIMEOUT_MS; waiting is on poll(2) against a monotonic
 * deadline (EINTR resumes with the remaining time).
 */
#ifndef TRN_PORT_LINUX_CAN_H
#define TRN_PORT_LINUX_CAN_H

#include <stddef.h>
#include <stdint.h>
#include "trn/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Most acceptance filters one raw socket takes. */
#define TRN_LCAN_MAX_FILTERS 16u
/** Longest timeout any call accepts, ms (one hour). */
#define TRN_LCAN_MAX_TIMEOUT_MS 3600000
/** Largest standard (11-bit) identifier. */
#define TRN_LCAN_SFF_MAX 0x7FFu
/** Largest extended (29-bit) identifier. */
#define TRN_LCAN_EFF_MAX 0x1FFFFFFFu
/** Longest interface name, bytes without the NUL (the kernel's IFNAMSIZ-1). */
#define TRN_LCAN_IFNAME_MAX 15u
/** Largest ISO-TP message the port sends or receives, bytes (ISO 15765-2 with
 * the 32-bit first-frame length escape; Debian's 6.1 kernel takes up to 66000). */
#define TRN_LISOTP_MAX_MSG 65536u

/** One classic CAN data frame (remote frames are not used by trn). */
typedef struct {
    uint32_t id;      /**< identifier: <= TRN_LCAN_SFF_MAX, or <= TRN_LCAN_EFF_MAX if extended */
    uint8_t extended; /**< 1: 29-bit identifier, 0: 11-bit */
    uint8_t len;      /**< data bytes, 0..8 */
    uint8_t data[8];  /**< payload; bytes past len are unspecified on receive */
} trn_lcan_frame_t;

/** Acceptance filter: a frame passes if (frame id & mask) == (id & mask) and
 * its format (standard/extended) equals `extended`. */
typedef struct {
    uint32_t id;      /**< identifier to match, in range for its format */
    uint32_t mask;    /**< bits that must match, in range for its format */
    uint8_t extended; /**< 1: match extended frames only, 0: standard only */
} trn_lcan_filter_t;

/** Controller state as told by error frames (ISO 11898-1 fault confinement). */
typedef enum {
    TRN_LCAN_ERROR_ACTIVE = 0,  /**< normal operation (also after a restart) */
    TRN_LCAN_ERROR_WARNING = 1, /**< an error counter reached 96 */
    TRN_LCAN_ERROR_PASSIVE = 2, /**< an error counter reached 128 */
    TRN_LCAN_BUS_OFF = 3        /**< transmit error counter passed 255: node is off the bus */
} trn_lcan_state_t;

/** What the port knows about the bus; updated by every receive call. */
typedef struct {
    trn_lcan_state_t state;     /**< state after the last error frame */
    uint32_t error_frames;      /**< error frames received since open */
    uint32_t last_error_class;  /**< CAN_ERR_* class bits (linux/can/error.h) of the last one */
    uint8_t last_error_data[8]; /**< its 8 data bytes (controller / protocol detail) */
    uint32_t rx_drops;          /**< frames the kernel dropped on this socket (SO_RXQ_OVFL) */
    uint32_t ctrl_overflows;    /**< error frames reporting a controller rx/tx overflow */
} trn_lcan_bus_t;

/** Configuration of a raw CAN socket. A zeroed struct is not valid (ifname
 * NULL); start from trn_lcan_cfg_default(). */
typedef struct {
    const char *ifname;               /**< interface, e.g. "can0"; 1..TRN_LCAN_IFNAME_MAX chars */
    const trn_lcan_filter_t *filters; /**< n_filters filters; NULL with 0 = every data frame */
    size_t n_filters;                 /**< 0..TRN_LCAN_MAX_FILTERS */
    int32_t rcvbuf_bytes;             /**< SO_RCVBUF; 0 = kernel default, else 1..(1 << 24) */
    uint8_t recv_own;                 /**< 1: also receive frames this socket sent (tests) */
    uint8_t error_frames;             /**< 1 (default): subscribe to all error frames */
} trn_lcan_cfg_t;

/** An open raw CAN socket. Owned by the caller; open fills it, close empties it. */
typedef struct {
    int fd;             /**< socket, -1 when closed */
    trn_lcan_bus_t bus; /**< bus status, see trn_lcan_bus_status() */
} trn_lcan_t;

/**
 * @brief Defaults: ifname "can0", no filter (all data frames), kernel receive
 * buffer, own frames not received, error frames on.
 * @param[out] cfg the configuration to fill.
 * @retval TRN_OK, TRN_E_NULL (cfg NULL).
 */
trn_status_t trn_lcan_cfg_default(trn_lcan_cfg_t *cfg);

/**
 * @brief Check a configuration without touching the OS.
 * @param[in] cfg the configuration.
 * @retval TRN_OK
 * @retval TRN_E_NULL cfg or cfg->ifname NULL, or filters NULL with n_filters > 0.
 * @retval TRN_E_SIZE ifname empty or longer than TRN_LCAN_IFNAME_MAX, n_filters
 *         above TRN_LCAN_MAX_FILTERS.
 * @retval TRN_E_ARG a filter id/mask out of range for its format, a flag not
 *         0/1, rcvbuf_bytes negative or above 1 << 24.
 */
trn_status_t trn_lcan_cfg_check(const trn_lcan_cfg_t *cfg);

/**
 * @brief Open a raw CAN socket on cfg->ifname, install the filters, enable
 * error frames and drop counting, bind. Every setsockopt is checked.
 * @param[out] can the handle (fd = -1 and status zeroed on failure).
 * @param[in]  cfg  the configuration (trn_lcan_cfg_check rules).
 * @retval TRN_OK
 * @retval TRN_E_NULL, TRN_E_SIZE, TRN_E_ARG as trn_lcan_cfg_check (can NULL: TRN_E_NULL).
 * @retval TRN_E_BUS the interface does not exist.
 * @retval TRN_E_IO any other failing system call.
 */
trn_status_t trn_lcan_open(trn_lcan_t *can, const trn_lcan_cfg_t *cfg);

/**
 * @brief Close the socket (a closed handle is accepted and left closed).
 * @param[in,out] can the handle.
 * @retval TRN_OK, TRN_E_NULL (can NULL), TRN_E_IO (close failed; the handle is closed anyway).
 */
trn_status_t trn_lcan_close(trn_lcan_t *can);

/**
 * @brief Send one data frame, waiting up to timeout_ms for room in the
 * interface's transmit queue.
 * @param[in,out] can        an open handle.
 * @param[in]     frame      the frame (id in range for its format, len 0..8).
 * @param[in]     timeout_ms 0..TRN_LCAN_MAX_TIMEOUT_MS.
 * @retval TRN_OK the kernel took the whole frame.
 * @retval TRN_E_NULL, TRN_E_ARG (bad frame or timeout, handle closed).
 * @retval TRN_E_TIMEOUT the queue stayed full (ENOBUFS) for timeout_ms.
 * @retval TRN_E_BUS the interface is down or gone.
 * @retval TRN_E_IO any other failing system call.
 */
trn_status_t trn_lcan_send(trn_lcan_t *can, const trn_lcan_frame_t *frame, int32_t timeout_ms);

/**
 * @brief Receive the next data frame, waiting up to timeout_ms.
 *
 * An error frame is never returned as data: it updates can->bus (state, class,
 * counters) and ends the call with TRN_E_BUS, so the caller sees every bus
 * event in order. The SO_RXQ_OVFL drop count rides on each frame and is
 * copied into can->bus.rx_drops (the frame itself is returned normally). The
 * kernel stamps a frame with the count at the time it queued it, so frames
 * lost after the last queued one show with the next frame received.
 * @param[in,out] can        an open handle.
 * @param[out]    frame      the frame (written only on TRN_OK).
 * @param[in]     timeout_ms 0..TRN_LCAN_MAX_TIMEOUT_MS.
 * @retval TRN_OK a data frame is in *frame.
 * @retval TRN_E_NULL, TRN_E_ARG (timeout out of range, handle closed).
 * @retval TRN_E_TIMEOUT nothing arrived in timeout_ms.
 * @retval TRN_E_BUS an error frame arrived (see trn_lcan_bus_status), or the
 *         interface went down.
 * @retval TRN_E_FORMAT the kernel delivered something that is not a classic frame.
 * @retval TRN_E_IO a failing system call.
 */
trn_status_t trn_lcan_recv(trn_lcan_t *can, trn_lcan_frame_t *frame, int32_t timeout_ms);

/**
 * @brief Copy the bus status.
 * @param[in]  can an open or closed handle.
 * @param[out] bus the copy.
 * @retval TRN_OK, TRN_E_NULL.
 */
trn_status_t trn_lcan_bus_status(const trn_lcan_t *can, trn_lcan_bus_t *bus);

/**
 * @brief Decode one error frame's identifier bits and data into a bus status
 * update (pure; used by trn_lcan_recv, exposed for tests).
 *
 * Bus-off (CAN_ERR_BUSOFF) gives TRN_LCAN_BUS_OFF; a controller error
 * (CAN_ERR_CRTL) with an rx/tx passive bit in data[1] gives
 * TRN_LCAN_ERROR_PASSIVE, with a warning bit TRN_LCAN_ERROR_WARNING, with
 * CAN_ERR_CRTL_ACTIVE TRN_LCAN_ERROR_ACTIVE; CAN_ERR_RESTARTED gives
 * TRN_LCAN_ERROR_ACTIVE. Other classes (protocol, ack, arbitration lost, ...)
 * keep the state and are only recorded. Counters are incremented.
 * @param[in,out] bus      the status to update.
 * @param[in]     err_bits can_id without CAN_ERR_FLAG (class bits, CAN_ERR_MASK).
 * @param[in]     data     the frame's 8 data bytes.
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (bits outside CAN_ERR_MASK).
 */
trn_status_t trn_lcan_decode_error(trn_lcan_bus_t *bus, uint32_t err_bits, const uint8_t data[8]);

/** Configuration of an ISO-TP (ISO 15765-2) socket with normal addressing. */
typedef struct {
    const char *ifname; /**< interface; 1..TRN_LCAN_IFNAME_MAX chars */
    uint32_t tx_id;     /**< identifier this node sends on */
    uint32_t rx_id;     /**< identifier this node receives on (!= tx_id) */
    uint8_t extended;   /**< 1: both are 29-bit identifiers */
    uint8_t block_size; /**< BS announced in our flow control frames, 0 = no limit */
    uint8_t stmin;      /**< STmin announced, ISO coding: 0x00..0x7F ms, 0xF1..0xF9 100..900 us */
    uint8_t tx_padding; /**< 1: pad sent frames to 8 bytes with pad_byte */
    uint8_t pad_byte;   /**< padding content */
    uint32_t frame_txtime_us; /**< gap between our consecutive frames, us (0..100000; 0 = none) */
} trn_lisotp_cfg_t;

/** An open ISO-TP socket. */
typedef struct {
    int fd; /**< socket, -1 when closed */
} trn_lisotp_t;

/**
 * @brief Defaults: "can0", tx 0x7E0, rx 0x7E8, standard ids, BS 0, STmin 0,
 * padding on with 0xCC, frame_txtime 0.
 * @retval TRN_OK, TRN_E_NULL.
 */
trn_status_t trn_lisotp_cfg_default(trn_lisotp_cfg_t *cfg);

/**
 * @brief Check an ISO-TP configuration without touching the OS.
 * @retval TRN_OK, TRN_E_NULL (cfg or ifname), TRN_E_SIZE (ifname length),
 *         TRN_E_ARG (an id out of range, tx_id == rx_id, a flag not 0/1, an
 *         STmin code ISO 15765-2 reserves, frame_txtime_us above 100000).
 */
trn_status_t trn_lisotp_cfg_check(const trn_lisotp_cfg_t *cfg);

/**
 * @brief Open and bind a can-isotp socket (non-blocking; the calls below wait
 * with poll). Every setsockopt is checked.
 * @retval TRN_OK, as trn_lisotp_cfg_check, TRN_E_BUS (no such interface, or the
 *         kernel lacks CAN_ISOTP: EPROTONOSUPPORT), TRN_E_IO (other failures).
 */
trn_status_t trn_lisotp_open(trn_lisotp_t *tp, const trn_lisotp_cfg_t *cfg);

/**
 * @brief Close (a closed handle is accepted).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_IO.
 */
trn_status_t trn_lisotp_close(trn_lisotp_t *tp);

/**
 * @brief Send one message and wait until the kernel has sent all of it
 * (flow control included) or failed, at most timeout_ms in all.
 *
 * On TRN_E_TIMEOUT the kernel may still be sending: the peer receives the
 * whole message or, if the kernel's own N_Bs/N_Cr timers fire, nothing.
 * @param[in,out] tp         an open handle.
 * @param[in]     msg        the message.
 * @param[in]     len        1..TRN_LISOTP_MAX_MSG bytes.
 * @param[in]     timeout_ms 0..TRN_LCAN_MAX_TIMEOUT_MS.
 * @retval TRN_OK sent.
 * @retval TRN_E_NULL, TRN_E_ARG (timeout, closed handle), TRN_E_SIZE (len).
 * @retval TRN_E_TIMEOUT not done in timeout_ms, or no flow control from the
 *         peer (kernel ECOMM/ETIMEDOUT).
 * @retval TRN_E_CAPACITY the peer's flow control said overflow (EMSGSIZE).
 * @retval TRN_E_FORMAT malformed flow control or padding (EBADMSG).
 * @retval TRN_E_BUS interface down or gone.
 * @retval TRN_E_IO other failures.
 */
trn_status_t trn_lisotp_send(trn_lisotp_t *tp, const uint8_t *msg, size_t len, int32_t timeout_ms);

/**
 * @brief Receive one complete message, waiting up to timeout_ms.
 *
 * The kernel hands over only whole, in-sequence messages; reception errors it
 * detected since the last call are reported instead (and consumed).
 * @param[in,out] tp         an open handle.
 * @param[out]    buf        cap bytes; written only on TRN_OK.
 * @param[in]     cap        1..TRN_LISOTP_MAX_MSG.
 * @param[out]    len        the message length (on TRN_OK and TRN_E_CAPACITY).
 * @param[in]     timeout_ms 0..TRN_LCAN_MAX_TIMEOUT_MS.
 * @retval TRN_OK a message of *len bytes is in buf.
 * @retval TRN_E_NULL, TRN_E_ARG, TRN_E_SIZE (cap).
 * @retval TRN_E_TIMEOUT nothing complete in timeout_ms, or the sender stopped
 *         mid-message (kernel ETIMEDOUT, N_Cr).
 * @retval TRN_E_SEQ a consecutive frame arrived out of sequence (EILSEQ).
 * @retval TRN_E_FORMAT wrong padding or layout (EBADMSG).
 * @retval TRN_E_CAPACITY the message was longer than cap (it is discarded;
 *         *len gives its length).
 * @retval TRN_E_BUS interface down or gone.
 * @retval TRN_E_IO other failures.
 */
trn_status_t trn_lisotp_recv(trn_lisotp_t *tp, uint8_t *buf, size_t cap, size_t *len,
                             int32_t timeout_ms);

/**
 * @brief The status a kernel errno means for this port (pure; exposed for tests).
 * ETIMEDOUT/ECOMM -> TRN_E_TIMEOUT, EILSEQ -> TRN_E_SEQ, EBADMSG -> TRN_E_FORMAT,
 * EMSGSIZE -> TRN_E_CAPACITY, ENETDOWN/ENODEV/ENXIO/ENETUNREACH ->
 * TRN_E_BUS, anything else -> TRN_E_IO.
 * @param[in] err an errno value (0 gives TRN_OK).
 * @return the status.
 */
trn_status_t trn_lcan_status_from_errno(int err);

#ifdef __cplusplus
}
#endif
#endif /* TRN_PORT_LINUX_CAN_H */
