/* SPDX-License-Identifier: Apache-2.0 */
/* rover_link.c - see rover_link.h. */
#include "rover_link.h"

#include <string.h>
#include <time.h>

#define ROVER_CMD_REPEAT_MS 100u
#define ROVER_HB_SILENT_MS 300u
/** Iteration bound of every wait (each iteration waits >= 1 ms or handles a frame). */
#define ROVER_MAX_ITER 10000000u

static uint8_t g_segbuf[TRN_ISOTP_MAX_MSG];

static uint32_t now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint32_t)((uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u);
}

void rover_cfg_default(rover_cfg_t *cfg)
{
    if (cfg == NULL) {
        return;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->ifname = "vcan0";
    cfg->gpio_chip = NULL;
    cfg->power_offset = 0u;
    cfg->trigger_offset = 1u;
    cfg->deployed_offset = 2u;
    cfg->trigger_pulse_us = 20000u;
    cfg->alive_timeout_ms = 1000u;
    cfg->move_timeout_ms = 10000u;
    cfg->capture_timeout_ms = 10000u;
}

const char *rover_outcome_name(rover_outcome_t o)
{
    switch (o) {
    case ROVER_OK: return "ok";
    case ROVER_E_SILENT: return "silent";
    case ROVER_E_MAST_FAULT: return "mast_fault";
    case ROVER_E_MAST_TIMEOUT: return "mast_timeout";
    case ROVER_E_BUS_OFF: return "bus_off";
    case ROVER_E_CAPTURE: return "capture";
    case ROVER_E_NO_CAPTURE: return "no_capture";
    case ROVER_E_IO: return "io";
    default: return "unknown";
    }
}

trn_status_t rover_open(rover_link_t *r, const rover_cfg_t *cfg)
{
    trn_lcan_filter_t flt[3] = {{TRN_CAN_ID_MAST_STATUS, 0x7FFu, 0u},
                                {TRN_CAN_ID_MAST_HB, 0x7FFu, 0u},
                                {TRN_CAN_ID_STEREO_HB, 0x7FFu, 0u}};
    trn_lcan_cfg_t cc;
    trn_lisotp_cfg_t tc;
    trn_status_t st;
    if (r == NULL || cfg == NULL || cfg->ifname == NULL) {
        return TRN_E_NULL;
    }
    memset(r, 0, sizeof *r);
    r->cfg = *cfg;
    r->can.fd = -1;
    r->tp.fd = -1;
    (void)trn_link_mon_init(&r->mast_hb, ROVER_HB_SILENT_MS);
    (void)trn_link_mon_init(&r->stereo_hb, ROVER_HB_SILENT_MS);
    (void)trn_capture_rx_init(&r->caprx);
    trn_lcan_cfg_default(&cc);
    cc.ifname = cfg->ifname;
    cc.filters = flt;
    cc.n_filters = 3u;
    st = trn_lcan_open(&r->can, &cc);
    if (st != TRN_OK) {
        return st;
    }
    trn_lisotp_cfg_default(&tc);
    tc.ifname = cfg->ifname;
    tc.rx_id = TRN_CAN_ID_CAPTURE_DATA;
    tc.tx_id = TRN_CAN_ID_CAPTURE_FC;
    tc.tx_padding = 0u;
    st = trn_lisotp_open(&r->tp, &tc);
    if (st != TRN_OK) {
        (void)trn_lcan_close(&r->can);
        return st;
    }
    if (cfg->gpio_chip != NULL) {
        trn_lgpio_cfg_t gc;
        trn_lgpio_cfg_default(&gc);
        gc.chip = cfg->gpio_chip;
        gc.consumer = "trn-rover";
        gc.power_offset = cfg->power_offset;
        gc.trigger_offset = cfg->trigger_offset;
        gc.deployed_offset = cfg->deployed_offset;
        gc.trigger_pulse_us = cfg->trigger_pulse_us;
        st = trn_lgpio_open(&r->gpio, &gc);
        if (st == TRN_OK) {
            st = trn_lgpio_set_power(&r->gpio, 1);
        }
        if (st != TRN_OK) {
            (void)trn_lgpio_close(&r->gpio);
            (void)trn_lisotp_close(&r->tp);
            (void)trn_lcan_close(&r->can);
            return st;
        }
        r->gpio_open = 1;
    }
    return TRN_OK;
}

void rover_close(rover_link_t *r)
{
    if (r == NULL) {
        return;
    }
    if (r->gpio_open) {
        (void)trn_lgpio_set_power(&r->gpio, 0);
        (void)trn_lgpio_close(&r->gpio);
        r->gpio_open = 0;
    }
    (void)trn_lisotp_close(&r->tp);
    (void)trn_lcan_close(&r->can);
}

static rover_outcome_t done(rover_link_t *r, rover_outcome_t o)
{
    ++r->outcome_count[o];
    return o;
}

/* Handle one received frame: status and heartbeats. */
static void on_frame(rover_link_t *r, const trn_lcan_frame_t *f, uint32_t t)
{
    trn_can_frame_t pf;
    memset(&pf, 0, sizeof pf);
    pf.id = f->id;
    pf.dlc = f->len;
    pf.flags = f->extended ? TRN_CAN_FLAG_EXT : 0u;
    memcpy(pf.data, f->data, 8u);
    switch (trn_can_classify(&pf)) {
    case TRN_CAN_MSG_MAST_STATUS: {
        trn_mast_status_t m;
        if (trn_can_mast_status_decode(&pf, &m) == TRN_OK) {
            r->status = m;
            r->have_status = 1;
            ++r->status_frames;
        }
        break;
    }
    case TRN_CAN_MSG_MAST_HB:
    case TRN_CAN_MSG_STEREO_HB: {
        trn_heartbeat_t hb;
        if (trn_can_heartbeat_decode(&pf, &hb) == TRN_OK) {
            (void)trn_link_mon_frame(f->id == TRN_CAN_ID_MAST_HB ? &r->mast_hb : &r->stereo_hb,
                                     hb.counter, t, NULL, NULL);
        }
        break;
    }
    default: break;
    }
}

/* Receive raw frames: wait up to wait_ms for the first, then take every
 * frame already queued (at most ROVER_DRAIN), and only then judge the link
 * monitors, so a backlog (the rover was busy) never looks like a silence.
 * Bus-off and silence end by name. */
#define ROVER_DRAIN 256
static rover_outcome_t service(rover_link_t *r, int32_t wait_ms)
{
    int k;
    uint32_t t = now_ms();
    for (k = 0; k < ROVER_DRAIN; ++k) {
        trn_lcan_frame_t f;
        trn_status_t st = trn_lcan_recv(&r->can, &f, k == 0 ? wait_ms : 0);
        t = now_ms();
        if (st == TRN_E_TIMEOUT) {
            break;
        }
        if (st == TRN_E_BUS) {
            if (r->can.bus.state == TRN_LCAN_BUS_OFF) {
                return ROVER_E_BUS_OFF;
            }
            continue;
        }
        if (st != TRN_OK) {
            return ROVER_E_IO;
        }
        on_frame(r, &f, t);
    }
    (void)trn_link_mon_poll(&r->mast_hb, t, NULL);
    (void)trn_link_mon_poll(&r->stereo_hb, t, NULL);
    if (r->mast_hb.state == TRN_LINK_SILENT || r->stereo_hb.state == TRN_LINK_SILENT) {
        return ROVER_E_SILENT;
    }
    return ROVER_OK;
}

rover_outcome_t rover_idle(rover_link_t *r, uint32_t ms)
{
    uint32_t t0, it;
    if (r == NULL) {
        return ROVER_E_IO;
    }
    t0 = now_ms();
    for (it = 0; it < ROVER_MAX_ITER && now_ms() - t0 < ms; ++it) {
        rover_outcome_t o = service(r, 5);
        if (o != ROVER_OK) {
            return done(r, o);
        }
    }
    return ROVER_OK;
}

rover_outcome_t rover_wait_alive(rover_link_t *r)
{
    uint32_t t0, it;
    if (r == NULL) {
        return ROVER_E_IO;
    }
    t0 = now_ms();
    for (it = 0; it < ROVER_MAX_ITER; ++it) {
        rover_outcome_t o = service(r, 5);
        if (o != ROVER_OK) {
            return done(r, o);
        }
        if (r->mast_hb.state == TRN_LINK_ALIVE && r->stereo_hb.state == TRN_LINK_ALIVE) {
            return done(r, ROVER_OK);
        }
        if (now_ms() - t0 >= r->cfg.alive_timeout_ms) {
            return done(r, ROVER_E_SILENT);
        }
    }
    return done(r, ROVER_E_SILENT);
}

/* Build MAST_CMD (new seq) as a port frame. */
static int make_cmd(rover_link_t *r, float pan_rad, float tilt_rad, uint8_t mode,
                    trn_mast_cmd_t *cmd, trn_lcan_frame_t *f)
{
    trn_can_frame_t pf;
    float rate = r->cfg.rate_rad_s * 1e4f;
    memset(cmd, 0, sizeof *cmd);
    if (trn_can_angle_to_raw(pan_rad, &cmd->pan_100urad) != TRN_OK ||
        trn_can_angle_to_raw(tilt_rad, &cmd->tilt_100urad) != TRN_OK ||
        !(rate >= 0.0f && rate <= 65535.0f)) {
        return 0;
    }
    cmd->rate_100urad_s = (uint16_t)(rate + 0.5f);
    cmd->seq = ++r->seq;
    cmd->mode = mode;
    if (trn_can_mast_cmd_encode(cmd, &pf) != TRN_OK) {
        return 0;
    }
    memset(f, 0, sizeof *f);
    f->id = pf.id;
    f->len = pf.dlc;
    memcpy(f->data, pf.data, 8u);
    return 1;
}

rover_outcome_t rover_move_nowait(rover_link_t *r, float pan_rad, float tilt_rad)
{
    trn_mast_cmd_t cmd;
    trn_lcan_frame_t f;
    if (r == NULL) {
        return ROVER_E_IO;
    }
    if (!make_cmd(r, pan_rad, tilt_rad, TRN_MAST_MODE_MOVE, &cmd, &f) ||
        trn_lcan_send(&r->can, &f, 100) != TRN_OK) {
        return done(r, ROVER_E_IO);
    }
    return ROVER_OK;
}

rover_outcome_t rover_stop(rover_link_t *r, trn_mast_status_t *at)
{
    trn_mast_cmd_t cmd;
    trn_lcan_frame_t f;
    uint32_t t0, it, frames0;
    if (r == NULL) {
        return ROVER_E_IO;
    }
    if (!make_cmd(r, 0.0f, 0.0f, TRN_MAST_MODE_STOP, &cmd, &f) ||
        trn_lcan_send(&r->can, &f, 100) != TRN_OK) {
        return done(r, ROVER_E_IO);
    }
    t0 = now_ms();
    frames0 = r->status_frames;
    for (it = 0; it < ROVER_MAX_ITER; ++it) {
        rover_outcome_t o = service(r, 5);
        if (o != ROVER_OK) {
            return done(r, o);
        }
        if (r->have_status && r->status_frames != frames0 && r->status.cmd_seq_ack == cmd.seq &&
            !(r->status.state & TRN_MAST_ST_MOVING)) {
            if (at != NULL) {
                *at = r->status;
            }
            return done(r, r->status.faults != 0u ? ROVER_E_MAST_FAULT : ROVER_OK);
        }
        if (now_ms() - t0 >= r->cfg.move_timeout_ms) {
            return done(r, ROVER_E_MAST_TIMEOUT);
        }
    }
    return done(r, ROVER_E_MAST_TIMEOUT);
}

rover_outcome_t rover_point(rover_link_t *r, float pan_rad, float tilt_rad, trn_mast_status_t *at)
{
    trn_mast_cmd_t cmd;
    trn_lcan_frame_t f;
    uint32_t t0, t_sent, it, frames0;
    if (r == NULL) {
        return ROVER_E_IO;
    }
    if (!make_cmd(r, pan_rad, tilt_rad, TRN_MAST_MODE_MOVE, &cmd, &f)) {
        return done(r, ROVER_E_IO);
    }
    t0 = now_ms();
    t_sent = t0;
    frames0 = r->status_frames;
    if (trn_lcan_send(&r->can, &f, 100) != TRN_OK) {
        return done(r, ROVER_E_IO);
    }
    for (it = 0; it < ROVER_MAX_ITER; ++it) {
        rover_outcome_t o = service(r, 5);
        uint32_t t = now_ms();
        if (o != ROVER_OK) {
            return done(r, o);
        }
        if (r->have_status && r->status_frames != frames0) {
            if (r->status.faults != 0u) {
                if (at != NULL) {
                    *at = r->status;
                }
                return done(r, ROVER_E_MAST_FAULT);
            }
            if (r->status.cmd_seq_ack == cmd.seq && (r->status.state & TRN_MAST_ST_IN_POSITION) &&
                !(r->status.state & TRN_MAST_ST_MOVING)) {
                if (at != NULL) {
                    *at = r->status;
                }
                return done(r, ROVER_OK);
            }
        }
        if (t - t0 >= r->cfg.move_timeout_ms) {
            if (at != NULL) {
                *at = r->status;
            }
            return done(r, ROVER_E_MAST_TIMEOUT);
        }
        if (t - t_sent >= ROVER_CMD_REPEAT_MS) {
            if (trn_lcan_send(&r->can, &f, 100) != TRN_OK) {
                return done(r, ROVER_E_IO);
            }
            t_sent = t;
        }
    }
    return done(r, ROVER_E_MAST_TIMEOUT);
}

rover_outcome_t rover_capture(rover_link_t *r, uint16_t id, uint16_t max_points, trn_capture_t *out,
                              trn_cap_err_t *err)
{
    trn_capture_cmd_t cmd;
    trn_can_frame_t pf;
    trn_lcan_frame_t f;
    uint32_t t0, it;
    if (r == NULL || out == NULL || err == NULL) {
        return ROVER_E_IO;
    }
    *err = TRN_CAP_ERR_NONE;
    if (r->gpio_open && trn_lgpio_trigger(&r->gpio) != TRN_OK) {
        return done(r, ROVER_E_IO);
    }
    cmd.capture_id = id;
    cmd.max_points = max_points;
    if (trn_can_capture_cmd_encode(&cmd, &pf) != TRN_OK) {
        return done(r, ROVER_E_IO);
    }
    memset(&f, 0, sizeof f);
    f.id = pf.id;
    f.len = pf.dlc;
    memcpy(f.data, pf.data, 8u);
    if (trn_lcan_send(&r->can, &f, 100) != TRN_OK) {
        return done(r, ROVER_E_IO);
    }
    t0 = now_ms();
    for (it = 0; it < ROVER_MAX_ITER; ++it) {
        size_t len = 0u;
        int complete = 0;
        trn_cap_err_t e = TRN_CAP_ERR_NONE;
        trn_status_t st;
        rover_outcome_t o = service(r, 0);
        if (o != ROVER_OK) {
            (void)trn_capture_rx_abort(&r->caprx);
            return done(r, o);
        }
        st = trn_lisotp_recv(&r->tp, g_segbuf, sizeof g_segbuf, &len, 5);
        if (st == TRN_OK) {
            st = trn_capture_rx_segment(&r->caprx, g_segbuf, len, out, &complete, &e);
            if (e != TRN_CAP_ERR_NONE && e != TRN_CAP_ERR_RESTARTED) {
                *err = e;
                r->last_cap_err = e;
                return done(r, ROVER_E_CAPTURE);
            }
            if (st == TRN_OK && complete) {
                return done(r, ROVER_OK);
            }
        } else if (st != TRN_E_TIMEOUT) {
            r->last_transport = st;
            (void)trn_capture_rx_abort(&r->caprx);
            *err = TRN_CAP_ERR_TRANSPORT;
            r->last_cap_err = TRN_CAP_ERR_TRANSPORT;
            return done(r, ROVER_E_CAPTURE);
        }
        if (now_ms() - t0 >= r->cfg.capture_timeout_ms) {
            (void)trn_capture_rx_abort(&r->caprx);
            return done(r, ROVER_E_NO_CAPTURE);
        }
    }
    return done(r, ROVER_E_NO_CAPTURE);
}
