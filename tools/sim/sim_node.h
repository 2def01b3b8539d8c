/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file sim_node.h
 * @brief The mast and stereo-head simulator (docs/modules/sim.md): one Linux
 * process on a SocketCAN interface that answers like the two real nodes of
 * docs/can-protocol.md, and can inject faults.
 *
 * Mast: MAST_CMD moves the pan-tilt toward the commanded angles at the
 * commanded rate (or rate_rad_s), MAST_STATUS every 20 ms (angles in 1e-4 rad
 * counts, moving / in_position / limit bits, seq ack, counter), MAST_HB
 * every 100 ms. Stereo head: STEREO_HB every 100 ms; on CAPTURE_CMD it takes
 * the mast's latest status as the pose at exposure (or the status at the
 * last rising edge of the trigger line, when one came since the previous
 * capture), renders range points (sim_render.h) and sends the capture as
 * segments over ISO-TP (port/proto's trn_isotp_tx_t on a raw socket, so
 * single frames can be dropped).
 *
 * Linux only; links trn, trn_proto and trn_port_linux (or its static twin).
 */
#ifndef TRN_SIM_NODE_H
#define TRN_SIM_NODE_H

#include <signal.h>
#include <stddef.h>
#include <stdint.h>
#include "sim_render.h"
#include "trn/mast.h"
#include "trn/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Faults the simulator injects (one per run). */
typedef enum {
    SIM_FAULT_NONE = 0,
    SIM_FAULT_DROP,    /**< data frame number fault_arg (0 = first) of each capture is not sent */
    SIM_FAULT_CORRUPT, /**< capture byte fault_arg (mod length) is XORed with 0x01 after the CRC */
    SIM_FAULT_SILENT,  /**< both nodes stop sending and answering fault_arg ms after start */
    SIM_FAULT_STUCK_PAN, /**< the pan axis does not move; stall fault bit after 200 ms */
    SIM_FAULT_BUS_OFF,   /**< on CAPTURE_CMD: a bus-off error frame, then nothing more is sent */
    SIM_FAULT_COUNT
} sim_fault_t;

/** Configuration (start from sim_cfg_default). */
typedef struct {
    const char *ifname;       /**< CAN interface */
    sim_dem_t dem;            /**< true terrain */
    sim_camera_t cam;         /**< stereo camera */
    trn_mast_geom_t geom;     /**< mast geometry and limits */
    trn_rover_pose_t pose;    /**< true rover pose */
    float rate_rad_s;         /**< default slew rate per axis, > 0 */
    float tol_rad;            /**< in-position tolerance, > 0 */
    uint64_t seed;            /**< range noise seed */
    uint32_t run_ms;          /**< run time, ms (0 = until *stop) */
    uint32_t seg_payload;     /**< capture bytes per segment, 1..4091 */
    uint16_t max_points;      /**< the head's own maximum (CAPTURE_CMD 0) */
    sim_fault_t fault;        /**< injected fault */
    uint32_t fault_arg;       /**< its argument (see sim_fault_t) */
    const char *trigger_path; /**< gpio-sim `value` file of the trigger line, or NULL */
} sim_cfg_t;

/** What a run did. */
typedef struct {
    uint32_t cmds;                /**< MAST_CMD frames accepted */
    uint32_t capture_cmds;        /**< CAPTURE_CMD frames received */
    uint32_t captures_sent;       /**< captures whose last frame went out */
    uint32_t triggers;            /**< rising edges seen on the trigger line */
    uint32_t triggered_exposures; /**< captures exposed at a trigger edge */
    uint32_t data_frames;         /**< ISO-TP data frames sent */
    uint32_t dropped_frames;      /**< frames not sent (DROP) */
    uint32_t corrupted;           /**< captures corrupted (CORRUPT) */
    uint32_t error_frames;        /**< error frames written (BUS_OFF) */
    uint32_t fc_received;         /**< flow-control frames */
    uint32_t tx_errors;           /**< ISO-TP sender errors (N_Bs, overflow, ...) */
    uint32_t last_points;         /**< points of the last capture */
    uint32_t last_bytes;          /**< its capture bytes */
    uint32_t last_segments;       /**< its segments */
    int16_t last_pan_100urad;     /**< its pan at exposure */
    int16_t last_tilt_100urad;    /**< its tilt at exposure */
} sim_stats_t;

/** @brief Defaults: "vcan0", no DEM, 60 x 45 deg camera 64 x 48 rays,
 * 0.5-12 m, k 0.002/m, a 1.4 m mast, pose at the origin, 0.5 rad/s,
 * tolerance 2e-3 rad, seed 1, 1020-byte segments, 4096 points, no fault.
 * @param[out] cfg the configuration (NULL ignored). */
void sim_cfg_default(sim_cfg_t *cfg);

/** @brief Short name of a fault ("drop", "corrupt", "silent", "stuck-pan",
 * "bus-off", "none"); unknown values give "none". @param[in] f the fault. */
const char *sim_fault_name(sim_fault_t f);

/**
 * @brief Run the simulator until run_ms passed or *stop became nonzero.
 * @param[in]  cfg   configuration.
 * @param[in]  stop  set asynchronously to end the run (may be NULL with run_ms > 0).
 * @param[out] stats counters (may be NULL).
 * @retval TRN_OK, TRN_E_NULL, TRN_E_ARG (configuration), TRN_E_BUS / TRN_E_IO (socket)
 */
trn_status_t sim_run(const sim_cfg_t *cfg, const volatile sig_atomic_t *stop, sim_stats_t *stats);

#ifdef __cplusplus
}
#endif
#endif /* TRN_SIM_NODE_H */
