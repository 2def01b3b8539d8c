/* SPDX-License-Identifier: Apache-2.0 */
/* sim_node.c - see sim_node.h. */
#include "sim_node.h"

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <math.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "trn_port/can_msg.h"
#include "trn_port/capture.h"
#include "trn_port/isotp.h"
#include "trn_port/linux_can.h"

/** Most rays the simulator renders per capture. */
#define SIM_RENDER_MAX 65536u
/** Iteration bound of the main loop (1 ms per idle iteration: > 11 days). */
#define SIM_MAX_ITER 1000000000u
/** Frames sent back to back before the loop looks at the bus again. */
#define SIM_BURST 64
/** Stall detection: commanded but not moving for this long. */
#define SIM_STALL_MS 200u
#define SIM_STATUS_MS 20u
#define SIM_HB_MS 100u
/** Ray rows rendered per loop iteration. */
#define SIM_ROWS_PER_STEP 2

static trn_vec3f_t g_render[SIM_RENDER_MAX];
static trn_capture_t g_cap;
static uint8_t g_wire[TRN_CAP_WIRE_MAX];
static uint8_t g_seg[TRN_ISOTP_MAX_MSG];

typedef struct {
    /* mast */
    float pan, tilt; /* true joint angles */
    float pan_cmd, tilt_cmd;
    float rate; /* current command's rate */
    int moving;
    uint8_t seq_ack, faults, status_counter, mast_hb_counter, stereo_hb_counter;
    uint32_t cmd_ms;               /* time of the last accepted MOVE */
    trn_mast_status_t last_status; /* what the last MAST_STATUS said */
    /* trigger */
    int trig_level;
    int trig_pending;
    trn_mast_status_t trig_status;
    float trig_pan, trig_tilt;
    uint32_t trig_ms;
    /* rendering, a few rows per loop iteration (heartbeats go on meanwhile) */
    int rendering;
    int32_t render_row;
    size_t render_n;
    trn_rigid_t render_T;
    uint16_t render_maxp;
    /* capture transfer */
    int sending;
    size_t wire_len;
    uint8_t seg_index, seg_count;
    uint32_t frame_no;
    trn_isotp_tx_t tx;
    /* pacing */
    uint32_t tick_ms;
    int sent_this_tick;
    /* faults */
    int off_bus; /* silent or bus-off: nothing is sent any more */
} sim_state_t;

static uint64_t now_us64(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000u + (uint64_t)ts.tv_nsec / 1000u;
}

void sim_cfg_default(sim_cfg_t *cfg)
{
    if (cfg == NULL) {
        return;
    }
    memset(cfg, 0, sizeof *cfg);
    cfg->ifname = "vcan0";
    sim_camera_default(&cfg->cam);
    sim_geom_default(&cfg->geom);
    cfg->rate_rad_s = 0.5f;
    cfg->tol_rad = 2e-3f;
    cfg->seed = 1u;
    cfg->seg_payload = 1020u;
    cfg->max_points = (uint16_t)TRN_PORT_MAX_CAPTURE_POINTS;
    cfg->fault = SIM_FAULT_NONE;
}

const char *sim_fault_name(sim_fault_t f)
{
    switch (f) {
    case SIM_FAULT_DROP: return "drop";
    case SIM_FAULT_CORRUPT: return "corrupt";
    case SIM_FAULT_SILENT: return "silent";
    case SIM_FAULT_STUCK_PAN: return "stuck-pan";
    case SIM_FAULT_BUS_OFF: return "bus-off";
    default: return "none";
    }
}

static int send_frame(trn_lcan_t *can, sim_state_t *s, uint32_t id, const uint8_t *data,
                      uint8_t len)
{
    trn_lcan_frame_t f;
    if (s->off_bus) {
        return 0;
    }
    memset(&f, 0, sizeof f);
    f.id = id;
    f.len = len;
    memcpy(f.data, data, len);
    return trn_lcan_send(can, &f, 100) == TRN_OK;
}

static int send_proto(trn_lcan_t *can, sim_state_t *s, const trn_can_frame_t *pf)
{
    return send_frame(can, s, pf->id, pf->data, pf->dlc);
}

static trn_mast_status_t make_status(const sim_cfg_t *cfg, sim_state_t *s)
{
    trn_mast_status_t st;
    int16_t raw = 0;
    memset(&st, 0, sizeof st);
    (void)trn_can_angle_to_raw(s->pan, &raw);
    st.pan_100urad = raw;
    (void)trn_can_angle_to_raw(s->tilt, &raw);
    st.tilt_100urad = raw;
    if (s->moving) {
        st.state |= TRN_MAST_ST_MOVING;
    }
    if (s->pan <= cfg->geom.pan_min_rad) {
        st.state |= TRN_MAST_ST_PAN_LIM_MIN;
    }
    if (s->pan >= cfg->geom.pan_max_rad) {
        st.state |= TRN_MAST_ST_PAN_LIM_MAX;
    }
    if (s->tilt <= cfg->geom.tilt_min_rad) {
        st.state |= TRN_MAST_ST_TILT_LIM_MIN;
    }
    if (s->tilt >= cfg->geom.tilt_max_rad) {
        st.state |= TRN_MAST_ST_TILT_LIM_MAX;
    }
    if (fabsf(s->pan - s->pan_cmd) <= cfg->tol_rad &&
        fabsf(s->tilt - s->tilt_cmd) <= cfg->tol_rad) {
        st.state |= TRN_MAST_ST_IN_POSITION;
    }
    st.faults = s->faults;
    st.cmd_seq_ack = s->seq_ack;
    st.counter = s->status_counter;
    return st;
}

/* Move the axes by at most rate * dt toward the command. */
static void slew(const sim_cfg_t *cfg, sim_state_t *s, float dt_s, uint32_t now_ms)
{
    float step = s->rate * dt_s;
    float dp = s->pan_cmd - s->pan, dtl = s->tilt_cmd - s->tilt;
    int mp = 0, mt = 0;
    if (cfg->fault != SIM_FAULT_STUCK_PAN && dp != 0.0f) {
        s->pan += dp > step ? step : (dp < -step ? -step : dp);
        mp = 1;
    }
    if (dtl != 0.0f) {
        s->tilt += dtl > step ? step : (dtl < -step ? -step : dtl);
        mt = 1;
    }
    s->moving = mp || mt;
    if (cfg->fault == SIM_FAULT_STUCK_PAN && fabsf(dp) > cfg->tol_rad &&
        now_ms - s->cmd_ms >= SIM_STALL_MS) {
        s->faults |= TRN_MAST_FLT_PAN_STALL;
    }
}

static void on_mast_cmd(const sim_cfg_t *cfg, sim_state_t *s, const trn_mast_cmd_t *m,
                        uint32_t now_ms, sim_stats_t *stats)
{
    float p = trn_can_angle_from_raw(m->pan_100urad), t = trn_can_angle_from_raw(m->tilt_100urad);
    if (m->mode == TRN_MAST_MODE_STOP) {
        s->pan_cmd = s->pan;
        s->tilt_cmd = s->tilt;
        s->seq_ack = m->seq;
        return;
    }
    if (m->mode != TRN_MAST_MODE_MOVE) {
        return;
    }
    if (p < cfg->geom.pan_min_rad || p > cfg->geom.pan_max_rad || t < cfg->geom.tilt_min_rad ||
        t > cfg->geom.tilt_max_rad) {
        s->faults |= TRN_MAST_FLT_CMD_INVALID;
        return;
    }
    s->faults &= (uint8_t)~TRN_MAST_FLT_CMD_INVALID;
    if (m->seq != s->seq_ack || p != s->pan_cmd || t != s->tilt_cmd) {
        s->cmd_ms = now_ms;
    }
    s->pan_cmd = p;
    s->tilt_cmd = t;
    s->rate = m->rate_100urad_s != 0u ? (float)m->rate_100urad_s * 1e-4f : cfg->rate_rad_s;
    s->seq_ack = m->seq;
    ++stats->cmds;
}

/* Expose, render, encode; starts the transfer. */
static void on_capture_cmd(const sim_cfg_t *cfg, sim_state_t *s, const trn_capture_cmd_t *m,
                           trn_lcan_t *can, uint32_t now_ms, sim_stats_t *stats)
{
    trn_mast_status_t at;
    trn_rigid_t T;
    size_t maxp;
    uint32_t t_ms = now_ms;
    float pan_true = s->pan, tilt_true = s->tilt;
    ++stats->capture_cmds;
    if (cfg->fault == SIM_FAULT_BUS_OFF) {
        struct can_frame ef;
        memset(&ef, 0, sizeof ef);
        ef.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
        ef.can_dlc = CAN_ERR_DLC;
        if (write(can->fd, &ef, sizeof ef) == (ssize_t)sizeof ef) {
            ++stats->error_frames;
        }
        s->off_bus = 1;
        return;
    }
    if (s->sending || s->rendering) {
        return; /* one capture at a time */
    }
    at = s->last_status;
    if (s->trig_pending) {
        at = s->trig_status;
        t_ms = s->trig_ms;
        pan_true = s->trig_pan;
        tilt_true = s->trig_tilt;
        s->trig_pending = 0;
        ++stats->triggered_exposures;
    }
    /* render at the true joint angles of the exposure (the status carries them rounded) */
    if (trn_mast_camera_to_map(&cfg->geom, &cfg->pose, pan_true, tilt_true, &T) != TRN_OK) {
        return;
    }
    memset(&g_cap, 0, sizeof g_cap);
    g_cap.capture_id = m->capture_id;
    g_cap.time_ms = t_ms;
    g_cap.pan_100urad = at.pan_100urad;
    g_cap.tilt_100urad = at.tilt_100urad;
    g_cap.mast_state = at.state;
    g_cap.mast_faults = at.faults;
    maxp = m->max_points != 0u ? m->max_points : cfg->max_points;
    if (maxp > TRN_PORT_MAX_CAPTURE_POINTS) {
        maxp = TRN_PORT_MAX_CAPTURE_POINTS;
    }
    s->render_maxp = (uint16_t)maxp;
    s->render_T = T;
    s->render_row = 0;
    s->render_n = 0u;
    s->rendering = 1;
}

/* Render the next rows; once all are done, pick the points, encode, start sending. */
static void render_step(const sim_cfg_t *cfg, sim_state_t *s, sim_rng_t *rng, sim_stats_t *stats)
{
    size_t n, i, maxp = s->render_maxp, keep;
    int32_t r1 = s->render_row + SIM_ROWS_PER_STEP;
    if (r1 > cfg->cam.rows) {
        r1 = cfg->cam.rows;
    }
    if (sim_render_rows(&cfg->dem, &cfg->cam, &s->render_T, rng, s->render_row, r1, g_render,
                        SIM_RENDER_MAX, &s->render_n) != TRN_OK) {
        s->rendering = 0;
        return;
    }
    s->render_row = r1;
    if (r1 < cfg->cam.rows) {
        return;
    }
    s->rendering = 0;
    n = s->render_n;
    keep = 0u;
    for (i = 0; i < n && keep < maxp; ++i) {
        /* evenly spread subset when there are more points than allowed */
        size_t src = n > maxp ? (size_t)((uint64_t)i * n / maxp) : i;
        double x, y, z;
        if (src >= n) {
            break;
        }
        x = (double)g_render[src].x * 1000.0;
        y = (double)g_render[src].y * 1000.0;
        z = (double)g_render[src].z * 1000.0;
        if (fabs(x) > 32767.0 || fabs(y) > 32767.0 || fabs(z) > 32767.0) {
            continue;
        }
        g_cap.points[keep].x_mm = (int16_t)lround(x);
        g_cap.points[keep].y_mm = (int16_t)lround(y);
        g_cap.points[keep].z_mm = (int16_t)lround(z);
        ++keep;
    }
    g_cap.n_points = (uint16_t)keep;
    if (trn_capture_encode(&g_cap, g_wire, sizeof g_wire, &s->wire_len) != TRN_OK ||
        trn_capture_segment_count(s->wire_len, cfg->seg_payload, &s->seg_count) != TRN_OK) {
        return;
    }
    if (cfg->fault == SIM_FAULT_CORRUPT) {
        g_wire[cfg->fault_arg % s->wire_len] ^= 0x01u;
        ++stats->corrupted;
    }
    stats->last_points = (uint32_t)keep;
    stats->last_bytes = (uint32_t)s->wire_len;
    stats->last_segments = s->seg_count;
    stats->last_pan_100urad = g_cap.pan_100urad;
    stats->last_tilt_100urad = g_cap.tilt_100urad;
    s->seg_index = 0u;
    s->frame_no = 0u;
    s->sending = 1;
}

/* Start the next segment of the capture being sent. */
static int start_segment(const sim_cfg_t *cfg, sim_state_t *s)
{
    size_t len = 0u;
    if (trn_capture_segment(g_wire, s->wire_len, cfg->seg_payload, s->seg_index, g_seg,
                            sizeof g_seg, &len) != TRN_OK) {
        return 0;
    }
    return trn_isotp_tx_start(&s->tx, g_seg, len) == TRN_OK;
}

/* Send what the ISO-TP sender allows now (at most SIM_BURST frames and the
 * pacing budget). Returns 1 if it wants to run again at once. */
static int pump_tx(const sim_cfg_t *cfg, sim_state_t *s, trn_lcan_t *can, uint32_t frames_per_ms,
                   sim_stats_t *stats)
{
    int k;
    for (k = 0; k < SIM_BURST && s->sending; ++k) {
        trn_isotp_tx_result_t res;
        uint64_t t = now_us64();
        uint32_t ms = (uint32_t)(t / 1000u);
        if (s->tx.state == TRN_ISOTP_TX_IDLE) {
            if (!start_segment(cfg, s)) {
                s->sending = 0;
                ++stats->tx_errors;
                return 0;
            }
        }
        if (frames_per_ms > 0u) {
            if (ms != s->tick_ms) {
                s->tick_ms = ms;
                s->sent_this_tick = 0;
            }
            if ((uint32_t)s->sent_this_tick >= frames_per_ms) {
                return 0;
            }
        }
        if (trn_isotp_tx_step(&s->tx, (uint32_t)t, &res) != TRN_OK ||
            (res.events & TRN_ISOTP_TX_EV_ERROR)) {
            s->sending = 0;
            ++stats->tx_errors;
            return 0;
        }
        if (!(res.events & TRN_ISOTP_TX_EV_FRAME)) {
            return 0; /* waiting for flow control or STmin */
        }
        if (cfg->fault == SIM_FAULT_DROP && s->frame_no == cfg->fault_arg) {
            ++stats->dropped_frames;
        } else if (send_frame(can, s, TRN_CAN_ID_CAPTURE_DATA, res.frame, res.dlc)) {
            ++stats->data_frames;
        }
        ++s->frame_no;
        ++s->sent_this_tick;
        if (res.events & TRN_ISOTP_TX_EV_DONE) {
            ++s->seg_index;
            if (s->seg_index >= s->seg_count) {
                s->sending = 0;
                ++stats->captures_sent;
                return 0;
            }
        }
    }
    return s->sending;
}

static int read_trigger(const char *path)
{
    char c = '?';
    int fd = open(path, O_RDONLY);
    if (fd < 0) {
        return -1;
    }
    if (read(fd, &c, 1) != 1) {
        c = '?';
    }
    close(fd);
    return c == '1' ? 1 : (c == '0' ? 0 : -1);
}

/* The mast's status every SIM_STATUS_MS and both nodes' heartbeats every
 * SIM_HB_MS (el: ms since the start). */
static void send_periodic(const sim_cfg_t *cfg, sim_state_t *s, trn_lcan_t *can, uint32_t el,
                          uint32_t *next_status, uint32_t *next_hb)
{
    trn_can_frame_t pf;
    if (el >= *next_status) {
        trn_mast_status_t ms = make_status(cfg, s);
        s->last_status = ms;
        if (!s->off_bus && trn_can_mast_status_encode(&ms, &pf) == TRN_OK &&
            send_proto(can, s, &pf)) {
            ++s->status_counter;
        }
        *next_status += SIM_STATUS_MS;
    }
    if (el >= *next_hb) {
        trn_heartbeat_t hb;
        hb.state = (uint8_t)((s->faults & (uint8_t)~TRN_MAST_FLT_CMD_INVALID) != 0u ? TRN_NODE_FAULT
                             : s->moving                                            ? TRN_NODE_BUSY
                                         : TRN_NODE_READY);
        hb.counter = s->mast_hb_counter;
        hb.uptime_s = (uint16_t)(el / 1000u);
        if (!s->off_bus && trn_can_heartbeat_encode(TRN_CAN_ID_MAST_HB, &hb, &pf) == TRN_OK &&
            send_proto(can, s, &pf)) {
            ++s->mast_hb_counter;
        }
        hb.state = (uint8_t)(s->sending ? TRN_NODE_BUSY : TRN_NODE_READY);
        hb.counter = s->stereo_hb_counter;
        if (!s->off_bus && trn_can_heartbeat_encode(TRN_CAN_ID_STEREO_HB, &hb, &pf) == TRN_OK &&
            send_proto(can, s, &pf)) {
            ++s->stereo_hb_counter;
        }
        *next_hb += SIM_HB_MS;
    }
}

/* The trigger line: a rising edge latches the mast's pose for the capture. */
static void poll_trigger(const sim_cfg_t *cfg, sim_state_t *s, uint32_t now_ms, sim_stats_t *stats)
{
    int v = read_trigger(cfg->trigger_path);
    if (v == 1 && s->trig_level == 0) {
        ++stats->triggers;
        s->trig_pending = 1;
        s->trig_status = make_status(cfg, s);
        s->trig_ms = now_ms;
        s->trig_pan = s->pan;
        s->trig_tilt = s->tilt;
    }
    if (v >= 0) {
        s->trig_level = v;
    }
}

/* One received frame: a mast command, a capture command or a flow control. */
static void on_frame(const sim_cfg_t *cfg, sim_state_t *s, trn_lcan_t *can,
                     const trn_lcan_frame_t *f, uint32_t now_ms, sim_stats_t *stats)
{
    trn_can_frame_t pf;
    memset(&pf, 0, sizeof pf);
    pf.id = f->id;
    pf.dlc = f->len;
    pf.flags = f->extended ? TRN_CAN_FLAG_EXT : 0u;
    memcpy(pf.data, f->data, 8u);
    if (s->off_bus) {
        return;
    }
    switch (trn_can_classify(&pf)) {
    case TRN_CAN_MSG_MAST_CMD: {
        trn_mast_cmd_t m;
        if (trn_can_mast_cmd_decode(&pf, &m) == TRN_OK) {
            on_mast_cmd(cfg, s, &m, now_ms, stats);
        } else {
            s->faults |= TRN_MAST_FLT_CMD_INVALID;
        }
        break;
    }
    case TRN_CAN_MSG_CAPTURE_CMD: {
        trn_capture_cmd_t m;
        if (trn_can_capture_cmd_decode(&pf, &m) == TRN_OK) {
            on_capture_cmd(cfg, s, &m, can, now_ms, stats);
        }
        break;
    }
    case TRN_CAN_MSG_CAPTURE_FC: {
        trn_isotp_tx_result_t res;
        ++stats->fc_received;
        if (trn_isotp_tx_fc(&s->tx, pf.data, pf.dlc, (uint32_t)now_us64(), &res) != TRN_OK &&
            (res.events & TRN_ISOTP_TX_EV_ERROR) && res.error != TRN_ISOTP_TX_ERR_UNEXPECTED_FC) {
            s->sending = 0;
            ++stats->tx_errors;
        }
        break;
    }
    default: break;
    }
}

static int sim_cfg_ok(const sim_cfg_t *cfg)
{
    return !(cfg->dem.heights == NULL || trn_mast_geom_check(&cfg->geom) != TRN_OK ||
             !(cfg->rate_rad_s > 0.0f) || !(cfg->tol_rad > 0.0f) || cfg->seg_payload == 0u ||
             cfg->seg_payload > TRN_CAP_SEG_PAYLOAD_MAX ||
             (size_t)cfg->cam.cols * (size_t)cfg->cam.rows > SIM_RENDER_MAX ||
             cfg->fault >= SIM_FAULT_COUNT);
}

trn_status_t sim_run(const sim_cfg_t *cfg, const volatile sig_atomic_t *stop, sim_stats_t *stats)
{
    static sim_state_t s;
    sim_stats_t local;
    trn_lcan_filter_t flt[3] = {{TRN_CAN_ID_MAST_CMD, 0x7FFu, 0u},
                                {TRN_CAN_ID_CAPTURE_CMD, 0x7FFu, 0u},
                                {TRN_CAN_ID_CAPTURE_FC, 0x7FFu, 0u}};
    trn_lcan_cfg_t cc;
    trn_lcan_t can;
    trn_status_t st;
    sim_rng_t rng;
    uint64_t t0, t_prev;
    uint32_t next_status, next_hb, iter, frames_per_ms = 4u;
    if (cfg == NULL || (stop == NULL && cfg->run_ms == 0u)) {
        return TRN_E_NULL;
    }
    if (stats == NULL) {
        stats = &local;
    }
    memset(stats, 0, sizeof *stats);
    if (!sim_cfg_ok(cfg)) {
        return TRN_E_ARG;
    }
    memset(&s, 0, sizeof s);
    s.rate = cfg->rate_rad_s;
    s.trig_level = -1;
    rng.s = cfg->seed;
    (void)trn_isotp_tx_init(&s.tx, 1000u, 10u);
    trn_lcan_cfg_default(&cc);
    cc.ifname = cfg->ifname;
    cc.filters = flt;
    cc.n_filters = 3u;
    cc.error_frames = 0u;
    st = trn_lcan_open(&can, &cc);
    if (st != TRN_OK) {
        return st;
    }
    t0 = now_us64();
    t_prev = t0;
    next_status = 0u;
    next_hb = 0u;
    s.last_status = make_status(cfg, &s);
    for (iter = 0; iter < SIM_MAX_ITER; ++iter) {
        uint64_t t = now_us64();
        uint32_t el = (uint32_t)((t - t0) / 1000u), now_ms = (uint32_t)(t / 1000u);
        trn_lcan_frame_t f;
        int32_t wait;
        int again;
        if ((stop != NULL && *stop) || (cfg->run_ms > 0u && el >= cfg->run_ms)) {
            break;
        }
        if (cfg->fault == SIM_FAULT_SILENT && el >= cfg->fault_arg) {
            s.off_bus = 1;
        }
        slew(cfg, &s, (float)(t - t_prev) * 1e-6f, now_ms);
        t_prev = t;
        send_periodic(cfg, &s, &can, el, &next_status, &next_hb);
        if (cfg->trigger_path != NULL) {
            poll_trigger(cfg, &s, now_ms, stats);
        }
        if (s.rendering) {
            render_step(cfg, &s, &rng, stats);
        }
        again = pump_tx(cfg, &s, &can, frames_per_ms, stats);
        wait = again || s.rendering ? 0 : 1;
        if (!s.sending && !s.rendering && cfg->trigger_path == NULL) {
            uint32_t nd = next_status < next_hb ? next_status : next_hb;
            wait = nd > el ? (int32_t)(nd - el) : 0;
        }
        st = trn_lcan_recv(&can, &f, wait);
        if (st == TRN_OK) {
            on_frame(cfg, &s, &can, &f, now_ms, stats);
        }
    }
    (void)trn_lcan_close(&can);
    return TRN_OK;
}
