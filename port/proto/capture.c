/* SPDX-License-Identifier: Apache-2.0 */
/* capture.c - stereo capture bytes, segments and reassembly (capture.h). */
#include "trn_port/capture.h"

#include "trn_port/crc.h"
#include "bytes.h"

static void set_err(trn_cap_err_t *err, trn_cap_err_t v)
{
    if (err != NULL) {
        *err = v;
    }
}

trn_status_t trn_capture_encode(const trn_capture_t *c, uint8_t *wire, size_t cap, size_t *len)
{
    size_t need, i, off;
    uint32_t crc;
    if (c == NULL || wire == NULL || len == NULL) {
        return TRN_E_NULL;
    }
    if (c->n_points > TRN_PORT_MAX_CAPTURE_POINTS) {
        return TRN_E_CAPACITY;
    }
    need = TRN_CAP_WIRE_BYTES(c->n_points);
    if (cap < need) {
        return TRN_E_WORKSPACE;
    }
    wire[0] = (uint8_t)TRN_CAP_VERSION;
    wire[1] = 0u;
    trn_put_u16le(&wire[2], c->capture_id);
    trn_put_u32le(&wire[4], c->time_ms);
    trn_put_i16le(&wire[8], c->pan_100urad);
    trn_put_i16le(&wire[10], c->tilt_100urad);
    wire[12] = c->mast_state;
    wire[13] = c->mast_faults;
    trn_put_u16le(&wire[14], c->n_points);
    off = TRN_CAP_HEADER_BYTES;
    for (i = 0u; i < (size_t)c->n_points; ++i) {
        trn_put_i16le(&wire[off], c->points[i].x_mm);
        trn_put_i16le(&wire[off + 2u], c->points[i].y_mm);
        trn_put_i16le(&wire[off + 4u], c->points[i].z_mm);
        off += TRN_CAP_POINT_BYTES;
    }
    crc = trn_crc32(wire, off);
    trn_put_u32le(&wire[off], crc);
    *len = need;
    return TRN_OK;
}

/* Header checks shared by decode and the reassembler (needs >= 16 bytes). */
static trn_cap_err_t check_header(const uint8_t *wire, size_t *expected)
{
    uint16_t n;
    if (wire[0] != (uint8_t)TRN_CAP_VERSION || wire[1] != 0u) {
        return TRN_CAP_ERR_VERSION;
    }
    n = trn_get_u16le(&wire[14]);
    if (n > TRN_PORT_MAX_CAPTURE_POINTS) {
        return TRN_CAP_ERR_TOO_MANY_POINTS;
    }
    *expected = TRN_CAP_WIRE_BYTES(n);
    return TRN_CAP_ERR_NONE;
}

/* The status of an error (never called with TRN_CAP_ERR_NONE). */
static trn_status_t err_status(trn_cap_err_t e)
{
    switch (e) {
    case TRN_CAP_ERR_MISSING:
    case TRN_CAP_ERR_DUPLICATE:
    case TRN_CAP_ERR_OUT_OF_ORDER:
    case TRN_CAP_ERR_RESTARTED: return TRN_E_SEQ;
    case TRN_CAP_ERR_TOO_MANY_POINTS: return TRN_E_CAPACITY;
    case TRN_CAP_ERR_CRC: return TRN_E_CRC;
    default: return TRN_E_FORMAT;
    }
}

trn_status_t trn_capture_decode(const uint8_t *wire, size_t len, trn_capture_t *out,
                                trn_cap_err_t *err)
{
    size_t expected = 0u, body, i, off;
    trn_cap_err_t e;
    uint16_t n;
    if (wire == NULL || out == NULL) {
        set_err(err, TRN_CAP_ERR_NONE);
        return TRN_E_NULL;
    }
    if (len < TRN_CAP_HEADER_BYTES + TRN_CAP_CRC_BYTES) {
        set_err(err, TRN_CAP_ERR_TRUNCATED);
        return TRN_E_FORMAT;
    }
    e = check_header(wire, &expected);
    if (e == TRN_CAP_ERR_NONE && len < expected) {
        e = TRN_CAP_ERR_TRUNCATED;
    }
    if (e == TRN_CAP_ERR_NONE && len > expected) {
        e = TRN_CAP_ERR_OVERFLOW;
    }
    body = expected - TRN_CAP_CRC_BYTES;
    if (e == TRN_CAP_ERR_NONE && trn_crc32(wire, body) != trn_get_u32le(&wire[body])) {
        e = TRN_CAP_ERR_CRC;
    }
    set_err(err, e);
    if (e != TRN_CAP_ERR_NONE) {
        return err_status(e);
    }
    n = trn_get_u16le(&wire[14]);
    out->capture_id = trn_get_u16le(&wire[2]);
    out->time_ms = trn_get_u32le(&wire[4]);
    out->pan_100urad = trn_get_i16le(&wire[8]);
    out->tilt_100urad = trn_get_i16le(&wire[10]);
    out->mast_state = wire[12];
    out->mast_faults = wire[13];
    out->n_points = n;
    out->crc = trn_get_u32le(&wire[body]);
    off = TRN_CAP_HEADER_BYTES;
    for (i = 0u; i < (size_t)n; ++i) {
        out->points[i].x_mm = trn_get_i16le(&wire[off]);
        out->points[i].y_mm = trn_get_i16le(&wire[off + 2u]);
        out->points[i].z_mm = trn_get_i16le(&wire[off + 4u]);
        off += TRN_CAP_POINT_BYTES;
    }
    return TRN_OK;
}

trn_status_t trn_capture_segment_count(size_t wire_len, size_t seg_payload, uint8_t *count)
{
    size_t n;
    if (count == NULL) {
        return TRN_E_NULL;
    }
    if (seg_payload == 0u || seg_payload > TRN_CAP_SEG_PAYLOAD_MAX || wire_len == 0u) {
        return TRN_E_ARG;
    }
    n = (wire_len + seg_payload - 1u) / seg_payload;
    if (n > 255u) {
        return TRN_E_SIZE;
    }
    *count = (uint8_t)n;
    return TRN_OK;
}

trn_status_t trn_capture_segment(const uint8_t *wire, size_t wire_len, size_t seg_payload,
                                 uint8_t index, uint8_t *out, size_t cap, size_t *out_len)
{
    uint8_t count = 0u;
    size_t off, take, i;
    trn_status_t st;
    if (wire == NULL || out == NULL || out_len == NULL) {
        return TRN_E_NULL;
    }
    if (wire_len < TRN_CAP_HEADER_BYTES) {
        return TRN_E_ARG;
    }
    st = trn_capture_segment_count(wire_len, seg_payload, &count);
    if (st != TRN_OK) {
        return st;
    }
    if (index >= count) {
        return TRN_E_RANGE;
    }
    off = (size_t)index * seg_payload;
    take = wire_len - off;
    if (take > seg_payload) {
        take = seg_payload;
    }
    if (cap < TRN_CAP_SEG_HEADER_BYTES + take) {
        return TRN_E_WORKSPACE;
    }
    out[0] = wire[2]; /* capture_id, already little-endian */
    out[1] = wire[3];
    out[2] = index;
    out[3] = count;
    for (i = 0u; i < take; ++i) {
        out[TRN_CAP_SEG_HEADER_BYTES + i] = wire[off + i];
    }
    *out_len = TRN_CAP_SEG_HEADER_BYTES + take;
    return TRN_OK;
}

static void rx_reset(trn_capture_rx_t *rx)
{
    rx->got = 0u;
    rx->capture_id = 0u;
    rx->next_index = 0u;
    rx->seg_count = 0u;
    rx->active = 0u;
}

trn_status_t trn_capture_rx_init(trn_capture_rx_t *rx)
{
    unsigned i;
    if (rx == NULL) {
        return TRN_E_NULL;
    }
    rx_reset(rx);
    rx->n_complete = 0u;
    for (i = 0u; i < (unsigned)TRN_CAP_ERR_COUNT; ++i) {
        rx->err_count[i] = 0u;
    }
    return TRN_OK;
}

trn_status_t trn_capture_rx_abort(trn_capture_rx_t *rx)
{
    if (rx == NULL) {
        return TRN_E_NULL;
    }
    if (rx->active != 0u) {
        rx->err_count[TRN_CAP_ERR_TRANSPORT] += 1u;
    }
    rx_reset(rx);
    return TRN_OK;
}

/* Count e; drop the capture in progress. */
static trn_status_t rx_fail(trn_capture_rx_t *rx, trn_cap_err_t e, trn_cap_err_t *err)
{
    rx->err_count[e] += 1u;
    rx_reset(rx);
    set_err(err, e);
    return err_status(e);
}

/* Where segment idx stands relative to the expected one. */
static trn_cap_err_t order_check(const trn_capture_rx_t *rx, uint16_t id, uint8_t idx, uint8_t cnt)
{
    if (rx->active == 0u) {
        return TRN_CAP_ERR_MISSING; /* segment 0 of this capture was lost */
    }
    if (id != rx->capture_id) {
        return TRN_CAP_ERR_ID_MISMATCH;
    }
    if (cnt != rx->seg_count) {
        return TRN_CAP_ERR_SEG_COUNT;
    }
    if (idx > rx->next_index) {
        return TRN_CAP_ERR_MISSING;
    }
    if (idx + 1u == (unsigned)rx->next_index) {
        return TRN_CAP_ERR_DUPLICATE;
    }
    if (idx < rx->next_index) {
        return TRN_CAP_ERR_OUT_OF_ORDER;
    }
    return TRN_CAP_ERR_NONE;
}

trn_status_t trn_capture_rx_segment(trn_capture_rx_t *rx, const uint8_t *seg, size_t len,
                                    trn_capture_t *out, int *complete, trn_cap_err_t *err)
{
    uint16_t id;
    uint8_t idx, cnt;
    size_t plen, room, take, i, expected = TRN_CAP_WIRE_MAX;
    int overlong;
    trn_cap_err_t e;
    trn_status_t restarted = TRN_OK;
    if (rx == NULL || seg == NULL || out == NULL || complete == NULL) {
        set_err(err, TRN_CAP_ERR_NONE);
        return TRN_E_NULL;
    }
    *complete = 0;
    set_err(err, TRN_CAP_ERR_NONE);
    if (len <= TRN_CAP_SEG_HEADER_BYTES) {
        return rx_fail(rx, TRN_CAP_ERR_SHORT_SEGMENT, err);
    }
    id = trn_get_u16le(&seg[0]);
    idx = seg[2];
    cnt = seg[3];
    if (cnt == 0u || idx >= cnt) {
        return rx_fail(rx, TRN_CAP_ERR_SEG_COUNT, err);
    }
    if (idx == 0u) {
        if (rx->active != 0u) {
            rx->err_count[TRN_CAP_ERR_RESTARTED] += 1u;
            set_err(err, TRN_CAP_ERR_RESTARTED);
            restarted = TRN_E_SEQ;
        }
        rx_reset(rx);
        rx->active = 1u;
        rx->capture_id = id;
        rx->seg_count = cnt;
    } else {
        e = order_check(rx, id, idx, cnt);
        if (e != TRN_CAP_ERR_NONE) {
            return rx_fail(rx, e, err);
        }
    }
    /* append what fits, then judge the header, then the length */
    plen = len - TRN_CAP_SEG_HEADER_BYTES;
    room = TRN_CAP_WIRE_MAX - rx->got;
    overlong = (plen > room) ? 1 : 0;
    take = (overlong != 0) ? room : plen;
    for (i = 0u; i < take; ++i) {
        rx->wire[rx->got + i] = seg[TRN_CAP_SEG_HEADER_BYTES + i];
    }
    rx->got += take;
    if (rx->got >= TRN_CAP_HEADER_BYTES) {
        e = check_header(rx->wire, &expected);
        if (e == TRN_CAP_ERR_NONE && trn_get_u16le(&rx->wire[2]) != id) {
            e = TRN_CAP_ERR_ID_MISMATCH;
        }
        if (e != TRN_CAP_ERR_NONE) {
            return rx_fail(rx, e, err);
        }
    }
    if (overlong != 0 || rx->got > expected) {
        return rx_fail(rx, TRN_CAP_ERR_OVERFLOW, err);
    }
    rx->next_index = (uint8_t)(idx + 1u);
    if (idx + 1u < (unsigned)cnt) {
        return restarted;
    }
    /* last segment: the whole capture must be here and valid */
    if (rx->got < TRN_CAP_HEADER_BYTES || rx->got < expected) {
        return rx_fail(rx, TRN_CAP_ERR_TRUNCATED, err);
    }
    {
        trn_status_t st = trn_capture_decode(rx->wire, rx->got, out, &e);
        if (st != TRN_OK) {
            return rx_fail(rx, e, err);
        }
    }
    rx->n_complete += 1u;
    rx_reset(rx);
    *complete = 1;
    return restarted;
}

trn_status_t trn_capture_points_m(const trn_capture_t *c, trn_vec3f_t *out, size_t capacity,
                                  size_t *n)
{
    size_t i;
    if (c == NULL || out == NULL || n == NULL) {
        return TRN_E_NULL;
    }
    if (c->n_points > TRN_PORT_MAX_CAPTURE_POINTS) {
        return TRN_E_SIZE;
    }
    if (capacity < (size_t)c->n_points) {
        return TRN_E_CAPACITY;
    }
    for (i = 0u; i < (size_t)c->n_points; ++i) {
        /* int16 and 1000 are exact in float: one correctly rounded division */
        out[i].x = (float)c->points[i].x_mm / 1000.0f;
        out[i].y = (float)c->points[i].y_mm / 1000.0f;
        out[i].z = (float)c->points[i].z_mm / 1000.0f;
    }
    *n = (size_t)c->n_points;
    return TRN_OK;
}

const char *trn_cap_err_name(trn_cap_err_t err)
{
    switch (err) {
    case TRN_CAP_ERR_NONE: return "NONE";
    case TRN_CAP_ERR_SHORT_SEGMENT: return "SHORT_SEGMENT";
    case TRN_CAP_ERR_SEG_COUNT: return "SEG_COUNT";
    case TRN_CAP_ERR_ID_MISMATCH: return "ID_MISMATCH";
    case TRN_CAP_ERR_MISSING: return "MISSING";
    case TRN_CAP_ERR_DUPLICATE: return "DUPLICATE";
    case TRN_CAP_ERR_OUT_OF_ORDER: return "OUT_OF_ORDER";
    case TRN_CAP_ERR_RESTARTED: return "RESTARTED";
    case TRN_CAP_ERR_VERSION: return "VERSION";
    case TRN_CAP_ERR_TOO_MANY_POINTS: return "TOO_MANY_POINTS";
    case TRN_CAP_ERR_OVERFLOW: return "OVERFLOW";
    case TRN_CAP_ERR_TRUNCATED: return "TRUNCATED";
    case TRN_CAP_ERR_CRC: return "CRC";
    case TRN_CAP_ERR_TRANSPORT: return "TRANSPORT";
    case TRN_CAP_ERR_COUNT:
    default: return "UNKNOWN";
    }
}
