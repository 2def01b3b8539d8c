/* SPDX-License-Identifier: Apache-2.0 */
/* can_msg.c - encode/decode of the mast and stereo-head CAN messages (can_msg.h). */
#include "trn_port/can_msg.h"

#include <math.h>

#include "bytes.h"

static int is_std_data(const trn_can_frame_t *f, uint32_t id, uint8_t dlc)
{
    return f->id == id && f->flags == 0u && f->dlc == dlc;
}

static void frame_init(trn_can_frame_t *f, uint32_t id, uint8_t dlc)
{
    unsigned i;
    f->id = id;
    f->dlc = dlc;
    f->flags = 0u;
    for (i = 0u; i < 8u; ++i) {
        f->data[i] = 0u;
    }
}

trn_can_msg_kind_t trn_can_classify(const trn_can_frame_t *f)
{
    if (f == NULL || (f->flags & (TRN_CAN_FLAG_EXT | TRN_CAN_FLAG_RTR)) != 0u) {
        return TRN_CAN_MSG_NONE;
    }
    switch (f->id) {
    case TRN_CAN_ID_MAST_CMD: return TRN_CAN_MSG_MAST_CMD;
    case TRN_CAN_ID_MAST_STATUS: return TRN_CAN_MSG_MAST_STATUS;
    case TRN_CAN_ID_CAPTURE_CMD: return TRN_CAN_MSG_CAPTURE_CMD;
    case TRN_CAN_ID_CAPTURE_DATA: return TRN_CAN_MSG_CAPTURE_DATA;
    case TRN_CAN_ID_CAPTURE_FC: return TRN_CAN_MSG_CAPTURE_FC;
    case TRN_CAN_ID_MAST_HB: return TRN_CAN_MSG_MAST_HB;
    case TRN_CAN_ID_STEREO_HB: return TRN_CAN_MSG_STEREO_HB;
    default: return TRN_CAN_MSG_NONE;
    }
}

const char *trn_can_msg_name(trn_can_msg_kind_t kind)
{
    switch (kind) {
    case TRN_CAN_MSG_MAST_CMD: return "MAST_CMD";
    case TRN_CAN_MSG_MAST_STATUS: return "MAST_STATUS";
    case TRN_CAN_MSG_CAPTURE_CMD: return "CAPTURE_CMD";
    case TRN_CAN_MSG_CAPTURE_DATA: return "CAPTURE_DATA";
    case TRN_CAN_MSG_CAPTURE_FC: return "CAPTURE_FC";
    case TRN_CAN_MSG_MAST_HB: return "MAST_HB";
    case TRN_CAN_MSG_STEREO_HB: return "STEREO_HB";
    case TRN_CAN_MSG_NONE:
    default: return "NONE";
    }
}

trn_status_t trn_can_angle_to_raw(float rad, int16_t *raw)
{
    float counts;
    if (raw == NULL) {
        return TRN_E_NULL;
    }
    if (rad != rad) {
        return TRN_E_ARG;
    }
    /* 10000 is exact in float, so rad * 10000 carries one rounding only */
    counts = rad * 10000.0f;
    /* exactly the counts that round (ties away from zero) into int16 */
    if (!(counts > -32768.5f && counts < 32767.5f)) {
        return TRN_E_ARG;
    }
    counts = (counts >= 0.0f) ? floorf(counts + 0.5f) : -floorf(-counts + 0.5f);
    *raw = (int16_t)counts;
    return TRN_OK;
}

float trn_can_angle_from_raw(int16_t raw) { return (float)raw / 10000.0f; }

trn_status_t trn_can_mast_cmd_encode(const trn_mast_cmd_t *m, trn_can_frame_t *f)
{
    if (m == NULL || f == NULL) {
        return TRN_E_NULL;
    }
    if (m->mode > (uint8_t)TRN_MAST_MODE_STOP) {
        return TRN_E_ARG;
    }
    frame_init(f, TRN_CAN_ID_MAST_CMD, (uint8_t)TRN_CAN_DLC_MAST_CMD);
    trn_put_i16le(&f->data[0], m->pan_100urad);
    trn_put_i16le(&f->data[2], m->tilt_100urad);
    trn_put_u16le(&f->data[4], m->rate_100urad_s);
    f->data[6] = m->seq;
    f->data[7] = m->mode;
    return TRN_OK;
}

trn_status_t trn_can_mast_cmd_decode(const trn_can_frame_t *f, trn_mast_cmd_t *m)
{
    if (f == NULL || m == NULL) {
        return TRN_E_NULL;
    }
    if (!is_std_data(f, TRN_CAN_ID_MAST_CMD, (uint8_t)TRN_CAN_DLC_MAST_CMD) ||
        f->data[7] > (uint8_t)TRN_MAST_MODE_STOP) {
        return TRN_E_FORMAT;
    }
    m->pan_100urad = trn_get_i16le(&f->data[0]);
    m->tilt_100urad = trn_get_i16le(&f->data[2]);
    m->rate_100urad_s = trn_get_u16le(&f->data[4]);
    m->seq = f->data[6];
    m->mode = f->data[7];
    return TRN_OK;
}

trn_status_t trn_can_mast_status_encode(const trn_mast_status_t *m, trn_can_frame_t *f)
{
    if (m == NULL || f == NULL) {
        return TRN_E_NULL;
    }
    if ((m->state & TRN_MAST_ST_RESERVED) != 0u || (m->faults & TRN_MAST_FLT_RESERVED) != 0u) {
        return TRN_E_ARG;
    }
    frame_init(f, TRN_CAN_ID_MAST_STATUS, (uint8_t)TRN_CAN_DLC_MAST_STATUS);
    trn_put_i16le(&f->data[0], m->pan_100urad);
    trn_put_i16le(&f->data[2], m->tilt_100urad);
    f->data[4] = m->state;
    f->data[5] = m->faults;
    f->data[6] = m->cmd_seq_ack;
    f->data[7] = m->counter;
    return TRN_OK;
}

trn_status_t trn_can_mast_status_decode(const trn_can_frame_t *f, trn_mast_status_t *m)
{
    if (f == NULL || m == NULL) {
        return TRN_E_NULL;
    }
    if (!is_std_data(f, TRN_CAN_ID_MAST_STATUS, (uint8_t)TRN_CAN_DLC_MAST_STATUS) ||
        (f->data[4] & TRN_MAST_ST_RESERVED) != 0u || (f->data[5] & TRN_MAST_FLT_RESERVED) != 0u) {
        return TRN_E_FORMAT;
    }
    m->pan_100urad = trn_get_i16le(&f->data[0]);
    m->tilt_100urad = trn_get_i16le(&f->data[2]);
    m->state = f->data[4];
    m->faults = f->data[5];
    m->cmd_seq_ack = f->data[6];
    m->counter = f->data[7];
    return TRN_OK;
}

trn_status_t trn_can_capture_cmd_encode(const trn_capture_cmd_t *m, trn_can_frame_t *f)
{
    if (m == NULL || f == NULL) {
        return TRN_E_NULL;
    }
    frame_init(f, TRN_CAN_ID_CAPTURE_CMD, (uint8_t)TRN_CAN_DLC_CAPTURE_CMD);
    trn_put_u16le(&f->data[0], m->capture_id);
    trn_put_u16le(&f->data[2], m->max_points);
    return TRN_OK;
}

trn_status_t trn_can_capture_cmd_decode(const trn_can_frame_t *f, trn_capture_cmd_t *m)
{
    if (f == NULL || m == NULL) {
        return TRN_E_NULL;
    }
    if (!is_std_data(f, TRN_CAN_ID_CAPTURE_CMD, (uint8_t)TRN_CAN_DLC_CAPTURE_CMD)) {
        return TRN_E_FORMAT;
    }
    m->capture_id = trn_get_u16le(&f->data[0]);
    m->max_points = trn_get_u16le(&f->data[2]);
    return TRN_OK;
}

trn_status_t trn_can_heartbeat_encode(uint32_t id, const trn_heartbeat_t *m, trn_can_frame_t *f)
{
    if (m == NULL || f == NULL) {
        return TRN_E_NULL;
    }
    if ((id != TRN_CAN_ID_MAST_HB && id != TRN_CAN_ID_STEREO_HB) ||
        m->state > (uint8_t)TRN_NODE_FAULT) {
        return TRN_E_ARG;
    }
    frame_init(f, id, (uint8_t)TRN_CAN_DLC_HEARTBEAT);
    f->data[0] = m->state;
    f->data[1] = m->counter;
    trn_put_u16le(&f->data[2], m->uptime_s);
    return TRN_OK;
}

trn_status_t trn_can_heartbeat_decode(const trn_can_frame_t *f, trn_heartbeat_t *m)
{
    if (f == NULL || m == NULL) {
        return TRN_E_NULL;
    }
    if ((!is_std_data(f, TRN_CAN_ID_MAST_HB, (uint8_t)TRN_CAN_DLC_HEARTBEAT) &&
         !is_std_data(f, TRN_CAN_ID_STEREO_HB, (uint8_t)TRN_CAN_DLC_HEARTBEAT)) ||
        f->data[0] > (uint8_t)TRN_NODE_FAULT) {
        return TRN_E_FORMAT;
    }
    m->state = f->data[0];
    m->counter = f->data[1];
    m->uptime_s = trn_get_u16le(&f->data[2]);
    return TRN_OK;
}

uint8_t trn_can_counter_gap(uint8_t prev, uint8_t now) { return (uint8_t)(now - prev - 1u); }
