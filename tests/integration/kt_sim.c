/* SPDX-License-Identifier: Apache-2.0 */
/*
 * kt_sim.c - the rover's link (tools/sim/rover_link.h: port/linux + port/proto)
 * against the mast and stereo-head simulator (tools/sim/sim_node.h) on vcan,
 * run in the VM.
 *
 * Round trips of every message: heartbeats of both nodes (consecutive
 * counters), MAST_CMD -> MAST_STATUS (angles reached at the default slew
 * rate and at the command's rate_max, seq acknowledged, STOP mid-move holds
 * between start and target), a command outside the limits
 * (flt_cmd_invalid), CAPTURE_CMD -> capture over ISO-TP with flow control
 * (id echoed, pose at exposure = the status, max_points honoured, the
 * simulator's own counts). Each injected fault ends in its named outcome
 * with its counter incremented and no capture handed out: a dropped frame
 * (kernel EILSEQ -> TRANSPORT), a corrupted byte (CRC), a silent node, a
 * stuck pan axis (flt_pan_stall), bus-off (error frame -> BUS_OFF).
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "ktest.h"
#include "rover_link.h"
#include "simrun.h"
#include "synth.h"

enum { DEM_N = 256 };
static const char *ifname;
static float g_dem[DEM_N * DEM_N];
static synth_rock_t g_rocks[2000];
static rover_link_t g_rover;
static trn_capture_t g_cap;

static sim_cfg_t base_cfg(void)
{
    sim_cfg_t c;
    sim_cfg_default(&c);
    c.ifname = ifname;
    c.dem.heights = g_dem;
    c.dem.width = DEM_N;
    c.dem.height = DEM_N;
    c.dem.cell_m = 0.05f;
    c.pose.x_m = 6.4f;
    c.pose.y_m = 6.4f;
    c.pose.heading_rad = 0.3f;
    c.run_ms = 30000u;
    return c;
}

static int rover_up(void)
{
    rover_cfg_t rc;
    rover_cfg_default(&rc);
    rc.ifname = ifname;
    rc.move_timeout_ms = 8000u;
    rc.capture_timeout_ms = 8000u;
    return rover_open(&g_rover, &rc) == TRN_OK;
}

/* Sentinel capture: a failed capture must leave it untouched. */
static void poison(void) { memset(&g_cap, 0xA5, sizeof g_cap); }

static int untouched(void)
{
    const uint8_t *p = (const uint8_t *)&g_cap;
    size_t i;
    for (i = 0; i < sizeof g_cap; ++i) {
        if (p[i] != 0xA5u) {
            return 0;
        }
    }
    return 1;
}

static void heartbeats_and_status(void)
{
    sim_cfg_t c = base_cfg();
    simrun_t s;
    trn_mast_status_t at;
    long long t0;
    uint32_t f0;
    KT_CHECK(simrun_start(&s, &c) == 0);
    KT_CHECK(rover_up());
    KT_CHECK(rover_wait_alive(&g_rover) == ROVER_OK);
    /* 0.5 rad of pan at 0.5 rad/s: about a second */
    f0 = g_rover.status_frames;
    t0 = kt_now_ms();
    KT_CHECK(rover_point(&g_rover, 0.5f, -0.3f, &at) == ROVER_OK);
    printf("KT-INFO slew 0.5 rad: %lld ms, %u status frames\n", kt_now_ms() - t0,
           g_rover.status_frames - f0);
    KT_CHECK(kt_now_ms() - t0 >= 900);
    KT_CHECK(abs(at.pan_100urad - 5000) <= 20 && abs(at.tilt_100urad + 3000) <= 20);
    KT_CHECK(at.cmd_seq_ack == g_rover.seq);
    KT_CHECK((at.state & TRN_MAST_ST_IN_POSITION) && !(at.state & TRN_MAST_ST_MOVING) &&
             at.faults == 0u);
    /* a second command, back */
    KT_CHECK(rover_point(&g_rover, 0.0f, -0.3f, &at) == ROVER_OK);
    KT_CHECK(abs(at.pan_100urad) <= 20 && at.cmd_seq_ack == g_rover.seq);
    /* outside the limits (tilt max 0.8 rad): rejected by name */
    KT_CHECK(rover_point(&g_rover, 0.0f, 1.0f, &at) == ROVER_E_MAST_FAULT);
    KT_CHECK(at.faults == TRN_MAST_FLT_CMD_INVALID);
    /* rate_max: 0.5 rad at 1 rad/s takes about half the time of the default 0.5 rad/s */
    g_rover.cfg.rate_rad_s = 1.0f;
    t0 = kt_now_ms();
    KT_CHECK(rover_point(&g_rover, 0.5f, -0.3f, &at) == ROVER_OK);
    printf("KT-INFO slew 0.5 rad at rate_max 1 rad/s: %lld ms\n", kt_now_ms() - t0);
    KT_CHECK(kt_now_ms() - t0 >= 450 && kt_now_ms() - t0 < 850);
    KT_CHECK(abs(at.pan_100urad - 5000) <= 20);
    g_rover.cfg.rate_rad_s = 0.0f;
    /* STOP mid-move: the mast holds between start and target */
    KT_CHECK(rover_move_nowait(&g_rover, -1.5f, -0.3f) == ROVER_OK);
    KT_CHECK(rover_idle(&g_rover, 600u) == ROVER_OK);
    KT_CHECK(rover_stop(&g_rover, &at) == ROVER_OK);
    KT_CHECK(at.pan_100urad < 4500 && at.pan_100urad > -10000 && at.cmd_seq_ack == g_rover.seq);
    KT_CHECK((at.state & TRN_MAST_ST_IN_POSITION) && !(at.state & TRN_MAST_ST_MOVING));
    /* heartbeats: every counter consecutive, nothing lost, nobody silent */
    KT_CHECK(g_rover.mast_hb.n_frames >= 10u && g_rover.stereo_hb.n_frames >= 10u);
    KT_CHECK(g_rover.mast_hb.n_gaps == 0u && g_rover.stereo_hb.n_gaps == 0u);
    KT_CHECK(g_rover.mast_hb.n_silences == 0u && g_rover.stereo_hb.n_silences == 0u);
    rover_close(&g_rover);
    KT_CHECK(simrun_stop(&s) == 0);
    KT_CHECK(s.stats.cmds >= 2u);
}

static void capture_round_trip(void)
{
    sim_cfg_t c = base_cfg();
    simrun_t s;
    trn_mast_status_t at;
    trn_cap_err_t e = TRN_CAP_ERR_COUNT;
    uint16_t pts_full;
    KT_CHECK(simrun_start(&s, &c) == 0);
    KT_CHECK(rover_up());
    KT_CHECK(rover_wait_alive(&g_rover) == ROVER_OK);
    KT_CHECK(rover_point(&g_rover, 0.2f, -0.45f, &at) == ROVER_OK);
    KT_CHECK(rover_capture(&g_rover, 0x1234u, 0u, &g_cap, &e) == ROVER_OK);
    KT_CHECK(e == TRN_CAP_ERR_NONE);
    KT_CHECK(g_cap.capture_id == 0x1234u);
    KT_CHECK(g_cap.pan_100urad == at.pan_100urad && g_cap.tilt_100urad == at.tilt_100urad);
    KT_CHECK(g_cap.mast_faults == 0u && (g_cap.mast_state & TRN_MAST_ST_IN_POSITION));
    KT_CHECK(g_cap.n_points > 1000u);
    pts_full = g_cap.n_points;
    /* max_points honoured */
    KT_CHECK(rover_capture(&g_rover, 7u, 500u, &g_cap, &e) == ROVER_OK);
    KT_CHECK(g_cap.capture_id == 7u && g_cap.n_points == 500u);
    KT_CHECK(g_rover.caprx.n_complete == 2u);
    rover_close(&g_rover);
    KT_CHECK(simrun_stop(&s) == 0);
    KT_CHECK(s.stats.captures_sent == 2u && s.stats.capture_cmds == 2u);
    KT_CHECK(s.stats.last_points == 500u);
    KT_CHECK(s.stats.fc_received ==
             s.stats.last_segments + (uint32_t)((TRN_CAP_WIRE_BYTES(pts_full) + 1019u) / 1020u));
    printf("KT-INFO capture: %u points full, %u data frames for both, %u flow controls\n", pts_full,
           s.stats.data_frames, s.stats.fc_received);
}

/* One capture under a fault; returns the rover's outcome and error. */
static rover_outcome_t faulty_capture(sim_fault_t f, uint32_t arg, trn_cap_err_t *e, simrun_t *s)
{
    sim_cfg_t c = base_cfg();
    trn_mast_status_t at;
    rover_outcome_t o;
    c.fault = f;
    c.fault_arg = arg;
    KT_CHECK(simrun_start(s, &c) == 0);
    KT_CHECK(rover_up());
    KT_CHECK(rover_wait_alive(&g_rover) == ROVER_OK);
    KT_CHECK(rover_point(&g_rover, 0.0f, -0.45f, &at) == ROVER_OK);
    poison();
    o = rover_capture(&g_rover, 9u, 1000u, &g_cap, e);
    KT_CHECK(untouched());
    KT_CHECK(g_rover.caprx.n_complete == 0u);
    return o;
}

static void fault_dropped_frame(void)
{
    /* 1000 points = 6020 bytes = 6 segments (5 x 1024 + 924 bytes on ISO-TP):
     * frame 5 of the last segment */
    uint32_t per_seg = trn_isotp_frame_count(1024u);
    trn_cap_err_t e = TRN_CAP_ERR_NONE;
    simrun_t s;
    KT_CHECK(per_seg == 147u);
    KT_CHECK(faulty_capture(SIM_FAULT_DROP, 5u * per_seg + 5u, &e, &s) == ROVER_E_CAPTURE);
    KT_CHECK(e == TRN_CAP_ERR_TRANSPORT);
    KT_ST(g_rover.last_transport, TRN_E_SEQ); /* kernel: EILSEQ */
    KT_CHECK(g_rover.caprx.err_count[TRN_CAP_ERR_TRANSPORT] == 1u);
    rover_close(&g_rover);
    KT_CHECK(simrun_stop(&s) == 0);
    KT_CHECK(s.stats.dropped_frames == 1u);
}

static void fault_corrupted_byte(void)
{
    trn_cap_err_t e = TRN_CAP_ERR_NONE;
    simrun_t s;
    KT_CHECK(faulty_capture(SIM_FAULT_CORRUPT, 1234u, &e, &s) == ROVER_E_CAPTURE);
    KT_CHECK(e == TRN_CAP_ERR_CRC);
    KT_CHECK(g_rover.caprx.err_count[TRN_CAP_ERR_CRC] == 1u);
    rover_close(&g_rover);
    KT_CHECK(simrun_stop(&s) == 0);
    KT_CHECK(s.stats.corrupted == 1u && s.stats.captures_sent == 1u);
}

static void fault_bus_off(void)
{
    trn_cap_err_t e = TRN_CAP_ERR_NONE;
    simrun_t s;
    KT_CHECK(faulty_capture(SIM_FAULT_BUS_OFF, 0u, &e, &s) == ROVER_E_BUS_OFF);
    KT_CHECK(g_rover.can.bus.state == TRN_LCAN_BUS_OFF);
    KT_CHECK(g_rover.can.bus.error_frames == 1u);
    KT_CHECK(g_rover.outcome_count[ROVER_E_BUS_OFF] == 1u);
    rover_close(&g_rover);
    KT_CHECK(simrun_stop(&s) == 0);
    KT_CHECK(s.stats.error_frames == 1u && s.stats.data_frames == 0u);
}

static void fault_silent_node(void)
{
    sim_cfg_t c = base_cfg();
    simrun_t s;
    trn_mast_status_t at;
    long long t0;
    c.fault = SIM_FAULT_SILENT;
    c.fault_arg = 1500u;
    KT_CHECK(simrun_start(&s, &c) == 0);
    KT_CHECK(rover_up());
    KT_CHECK(rover_wait_alive(&g_rover) == ROVER_OK);
    /* a long move (2.5 rad at 0.5 rad/s): the nodes fall silent on the way */
    t0 = kt_now_ms();
    KT_CHECK(rover_point(&g_rover, 2.5f, 0.0f, &at) == ROVER_E_SILENT);
    printf("KT-INFO silent: detected after %lld ms of the move\n", kt_now_ms() - t0);
    KT_CHECK(g_rover.mast_hb.n_silences == 1u && g_rover.stereo_hb.n_silences == 1u);
    KT_CHECK(g_rover.outcome_count[ROVER_E_SILENT] == 1u);
    rover_close(&g_rover);
    KT_CHECK(simrun_stop(&s) == 0);
}

static void fault_stuck_pan(void)
{
    sim_cfg_t c = base_cfg();
    simrun_t s;
    trn_mast_status_t at;
    c.fault = SIM_FAULT_STUCK_PAN;
    KT_CHECK(simrun_start(&s, &c) == 0);
    KT_CHECK(rover_up());
    KT_CHECK(rover_wait_alive(&g_rover) == ROVER_OK);
    KT_CHECK(rover_point(&g_rover, 0.6f, -0.2f, &at) == ROVER_E_MAST_FAULT);
    KT_CHECK(at.faults & TRN_MAST_FLT_PAN_STALL);
    KT_CHECK(at.pan_100urad == 0);
    KT_CHECK(g_rover.outcome_count[ROVER_E_MAST_FAULT] == 1u);
    rover_close(&g_rover);
    KT_CHECK(simrun_stop(&s) == 0);
}

int main(void)
{
    synth_terrain_t terr;
    ifname = kt_env("TRN_CAN_IF", "vcan0");
    synth_make(&terr, g_rocks, 1500u, DEM_N * 0.05, 0.05, 0.3, 0.5, 0.2, 21u);
    synth_render(&terr, g_dem, DEM_N, DEM_N, 0.0, 0.0, 0.05);
    KT_RUN(heartbeats_and_status);
    KT_RUN(capture_round_trip);
    KT_RUN(fault_dropped_frame);
    KT_RUN(fault_corrupted_byte);
    KT_RUN(fault_bus_off);
    KT_RUN(fault_silent_node);
    KT_RUN(fault_stuck_pan);
    return kt_finish("kt_sim");
}
