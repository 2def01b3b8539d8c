/* SPDX-License-Identifier: Apache-2.0 */
/* isotp.c - ISO 15765-2 frame codec and receiver state machine (isotp.h). */
#include "trn_port/isotp.h"

static void res_clear(trn_isotp_rx_result_t *res)
{
    unsigned i;
    res->events = 0u;
    res->error = (uint8_t)TRN_ISOTP_ERR_NONE;
    res->msg_len = 0u;
    res->fc_dlc = 0u;
    for (i = 0u; i < 8u; ++i) {
        res->fc[i] = 0u;
    }
}

trn_status_t trn_isotp_decode(const uint8_t *data, uint8_t dlc, trn_isotp_frame_t *fr)
{
    trn_isotp_frame_t f = {0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u};
    uint8_t type;
    if (data == NULL || fr == NULL) {
        return TRN_E_NULL;
    }
    if (dlc > 8u) {
        return TRN_E_ARG;
    }
    if (dlc == 0u) {
        return TRN_E_FORMAT;
    }
    type = (uint8_t)(data[0] >> 4);
    f.type = type;
    switch (type) {
    case TRN_ISOTP_SF:
        f.msg_len = (uint16_t)(data[0] & 0x0Fu);
        if (f.msg_len == 0u || f.msg_len > TRN_ISOTP_SF_MAX || f.msg_len > (uint16_t)(dlc - 1u)) {
            return TRN_E_FORMAT;
        }
        f.data_off = 1u;
        f.data_len = (uint8_t)f.msg_len;
        break;
    case TRN_ISOTP_FF:
        if (dlc != 8u) {
            return TRN_E_FORMAT;
        }
        f.msg_len = (uint16_t)(((uint16_t)(data[0] & 0x0Fu) << 8) | (uint16_t)data[1]);
        if (f.msg_len <= TRN_ISOTP_SF_MAX) {
            return TRN_E_FORMAT;
        }
        f.data_off = 2u;
        f.data_len = (uint8_t)TRN_ISOTP_FF_DATA;
        break;
    case TRN_ISOTP_CF:
        if (dlc < 2u) {
            return TRN_E_FORMAT;
        }
        f.sn = (uint8_t)(data[0] & 0x0Fu);
        f.data_off = 1u;
        f.data_len = (uint8_t)(dlc - 1u);
        break;
    case TRN_ISOTP_FC:
        if (dlc < 3u || (data[0] & 0x0Fu) > (uint8_t)TRN_ISOTP_FS_OVFLW) {
            return TRN_E_FORMAT;
        }
        f.fs = (uint8_t)(data[0] & 0x0Fu);
        f.bs = data[1];
        f.stmin = data[2];
        break;
    default: return TRN_E_FORMAT;
    }
    *fr = f;
    return TRN_OK;
}

uint16_t trn_isotp_frame_count(size_t len)
{
    if (len == 0u || len > TRN_ISOTP_MAX_MSG) {
        return 0u;
    }
    if (len <= TRN_ISOTP_SF_MAX) {
        return 1u;
    }
    return (uint16_t)(1u + (len - TRN_ISOTP_FF_DATA + TRN_ISOTP_CF_DATA - 1u) / TRN_ISOTP_CF_DATA);
}

trn_status_t trn_isotp_encode_frame(const uint8_t *msg, size_t len, uint16_t index, uint8_t out[8],
                                    uint8_t *dlc)
{
    uint16_t n;
    size_t i, off, take;
    if (msg == NULL || out == NULL || dlc == NULL) {
        return TRN_E_NULL;
    }
    n = trn_isotp_frame_count(len);
    if (n == 0u) {
        return TRN_E_SIZE;
    }
    if (index >= n) {
        return TRN_E_RANGE;
    }
    for (i = 0u; i < 8u; ++i) {
        out[i] = 0u;
    }
    if (len <= TRN_ISOTP_SF_MAX) {
        out[0] = (uint8_t)len;
        for (i = 0u; i < len; ++i) {
            out[1u + i] = msg[i];
        }
        *dlc = (uint8_t)(len + 1u);
        return TRN_OK;
    }
    if (index == 0u) {
        out[0] = (uint8_t)(0x10u | (uint8_t)((len >> 8) & 0x0Fu));
        out[1] = (uint8_t)(len & 0xFFu);
        for (i = 0u; i < TRN_ISOTP_FF_DATA; ++i) {
            out[2u + i] = msg[i];
        }
        *dlc = 8u;
        return TRN_OK;
    }
    off = TRN_ISOTP_FF_DATA + (size_t)(index - 1u) * TRN_ISOTP_CF_DATA;
    take = len - off;
    if (take > TRN_ISOTP_CF_DATA) {
        take = TRN_ISOTP_CF_DATA;
    }
    out[0] = (uint8_t)(0x20u | (uint8_t)(index & 0x0Fu));
    for (i = 0u; i < take; ++i) {
        out[1u + i] = msg[off + i];
    }
    *dlc = (uint8_t)(take + 1u);
    return TRN_OK;
}

trn_status_t trn_isotp_encode_fc(uint8_t fs, uint8_t bs, uint8_t stmin, uint8_t out[8],
                                 uint8_t *dlc)
{
    unsigned i;
    if (out == NULL || dlc == NULL) {
        return TRN_E_NULL;
    }
    if (fs > (uint8_t)TRN_ISOTP_FS_OVFLW) {
        return TRN_E_ARG;
    }
    for (i = 0u; i < 8u; ++i) {
        out[i] = 0u;
    }
    out[0] = (uint8_t)(0x30u | fs);
    out[1] = bs;
    out[2] = stmin;
    *dlc = 3u;
    return TRN_OK;
}

uint32_t trn_isotp_stmin_us(uint8_t stmin)
{
    if (stmin <= 0x7Fu) {
        return (uint32_t)stmin * 1000u;
    }
    if (stmin >= 0xF1u && stmin <= 0xF9u) {
        return (uint32_t)(stmin - 0xF0u) * 100u;
    }
    return 127000u;
}

static int stmin_valid(uint8_t stmin)
{
    return stmin <= 0x7Fu || (stmin >= 0xF1u && stmin <= 0xF9u);
}

trn_status_t trn_isotp_rx_init(trn_isotp_rx_t *rx, uint8_t *buf, size_t cap, uint8_t bs,
                               uint8_t stmin, uint32_t n_cr_ms)
{
    unsigned i;
    if (rx == NULL || buf == NULL) {
        return TRN_E_NULL;
    }
    if (cap < TRN_ISOTP_SF_MAX || cap > TRN_ISOTP_MAX_MSG) {
        return TRN_E_SIZE;
    }
    if (!stmin_valid(stmin) || n_cr_ms == 0u || n_cr_ms > 60000u) {
        return TRN_E_ARG;
    }
    rx->buf = buf;
    rx->cap = (uint16_t)cap;
    rx->bs = bs;
    rx->stmin = stmin;
    rx->n_cr_ms = n_cr_ms;
    rx->state = (uint8_t)TRN_ISOTP_RX_IDLE;
    rx->next_sn = 0u;
    rx->block_left = 0u;
    rx->msg_len = 0u;
    rx->got = 0u;
    rx->last_ms = 0u;
    rx->n_messages = 0u;
    for (i = 0u; i < (unsigned)TRN_ISOTP_ERR_COUNT; ++i) {
        rx->err_count[i] = 0u;
    }
    return TRN_OK;
}

/* Record an error in res and the counters; the receiver goes idle when
 * abort is set. */
static void rx_error(trn_isotp_rx_t *rx, trn_isotp_rx_result_t *res, trn_isotp_err_t err, int abort)
{
    rx->err_count[err] += 1u;
    res->events |= TRN_ISOTP_EV_ERROR;
    res->error = (uint8_t)err;
    if (abort) {
        rx->state = (uint8_t)TRN_ISOTP_RX_IDLE;
        rx->got = 0u;
        rx->msg_len = 0u;
    }
}

static void rx_send_fc(const trn_isotp_rx_t *rx, trn_isotp_rx_result_t *res, uint8_t fs)
{
    /* arguments are valid by construction: fs <= 2, buffers non-NULL */
    (void)trn_isotp_encode_fc(fs, rx->bs, rx->stmin, res->fc, &res->fc_dlc);
    res->events |= TRN_ISOTP_EV_SEND_FC;
}

static void copy_in(trn_isotp_rx_t *rx, const uint8_t *src, uint8_t n)
{
    uint8_t i;
    for (i = 0u; i < n; ++i) {
        rx->buf[rx->got + i] = src[i];
    }
    rx->got = (uint16_t)(rx->got + n);
}

static int timed_out(const trn_isotp_rx_t *rx, uint32_t now_ms)
{
    return rx->state == (uint8_t)TRN_ISOTP_RX_RECEIVING &&
           (uint32_t)(now_ms - rx->last_ms) > rx->n_cr_ms;
}

trn_status_t trn_isotp_rx_poll(trn_isotp_rx_t *rx, uint32_t now_ms, trn_isotp_rx_result_t *res)
{
    if (rx == NULL || res == NULL) {
        return TRN_E_NULL;
    }
    res_clear(res);
    if (timed_out(rx, now_ms)) {
        rx_error(rx, res, TRN_ISOTP_ERR_TIMEOUT_CR, 1);
        return TRN_E_TIMEOUT;
    }
    return TRN_OK;
}

/* Start of a new message (SF or FF) while one is in progress. */
static trn_status_t interrupt_if_busy(trn_isotp_rx_t *rx, trn_isotp_rx_result_t *res)
{
    if (rx->state == (uint8_t)TRN_ISOTP_RX_RECEIVING) {
        rx_error(rx, res, TRN_ISOTP_ERR_INTERRUPTED, 1);
        return TRN_E_SEQ;
    }
    return TRN_OK;
}

static trn_status_t rx_cf(trn_isotp_rx_t *rx, const uint8_t *data, const trn_isotp_frame_t *fr,
                          uint32_t now_ms, trn_isotp_rx_result_t *res)
{
    uint8_t n;
    uint16_t left;
    if (rx->state != (uint8_t)TRN_ISOTP_RX_RECEIVING) {
        rx_error(rx, res, TRN_ISOTP_ERR_UNEXPECTED_CF, 0);
        return TRN_E_FORMAT;
    }
    if (fr->sn != rx->next_sn) {
        rx_error(rx, res, TRN_ISOTP_ERR_WRONG_SN, 1);
        return TRN_E_SEQ;
    }
    left = (uint16_t)(rx->msg_len - rx->got);
    if (left > (uint16_t)fr->data_len && fr->data_len < (uint8_t)TRN_ISOTP_CF_DATA) {
        /* only the last consecutive frame may be short */
        rx_error(rx, res, TRN_ISOTP_ERR_SHORT_CF, 1);
        return TRN_E_FORMAT;
    }
    n = (left < (uint16_t)fr->data_len) ? (uint8_t)left : fr->data_len;
    copy_in(rx, &data[fr->data_off], n);
    rx->next_sn = (uint8_t)((rx->next_sn + 1u) & 0x0Fu);
    rx->last_ms = now_ms;
    if (rx->got == rx->msg_len) {
        rx->state = (uint8_t)TRN_ISOTP_RX_IDLE;
        rx->n_messages += 1u;
        res->events |= TRN_ISOTP_EV_MESSAGE;
        res->msg_len = rx->msg_len;
        return TRN_OK;
    }
    if (rx->bs != 0u) {
        rx->block_left = (uint8_t)(rx->block_left - 1u);
        if (rx->block_left == 0u) {
            rx->block_left = rx->bs;
            rx_send_fc(rx, res, (uint8_t)TRN_ISOTP_FS_CTS);
        }
    }
    return TRN_OK;
}

trn_status_t trn_isotp_rx_frame(trn_isotp_rx_t *rx, const uint8_t *data, uint8_t dlc,
                                uint32_t now_ms, trn_isotp_rx_result_t *res)
{
    trn_isotp_frame_t fr;
    trn_status_t st = TRN_OK;
    if (rx == NULL || data == NULL || res == NULL) {
        return TRN_E_NULL;
    }
    if (dlc > 8u) {
        return TRN_E_ARG;
    }
    res_clear(res);
    if (timed_out(rx, now_ms)) {
        rx_error(rx, res, TRN_ISOTP_ERR_TIMEOUT_CR, 1);
        st = TRN_E_TIMEOUT;
    }
    if (trn_isotp_decode(data, dlc, &fr) != TRN_OK) {
        rx_error(rx, res, TRN_ISOTP_ERR_BAD_FRAME, 0);
        return (st != TRN_OK) ? st : TRN_E_FORMAT;
    }
    switch (fr.type) {
    case TRN_ISOTP_SF: {
        trn_status_t s2 = interrupt_if_busy(rx, res);
        st = (st != TRN_OK) ? st : s2;
        rx->got = 0u;
        rx->msg_len = fr.msg_len;
        copy_in(rx, &data[fr.data_off], fr.data_len);
        rx->n_messages += 1u;
        res->events |= TRN_ISOTP_EV_MESSAGE;
        res->msg_len = fr.msg_len;
        return st;
    }
    case TRN_ISOTP_FF: {
        trn_status_t s2 = interrupt_if_busy(rx, res);
        st = (st != TRN_OK) ? st : s2;
        if (fr.msg_len > rx->cap) {
            rx_error(rx, res, TRN_ISOTP_ERR_OVERFLOW, 1);
            rx_send_fc(rx, res, (uint8_t)TRN_ISOTP_FS_OVFLW);
            return (st != TRN_OK) ? st : TRN_E_CAPACITY;
        }
        rx->state = (uint8_t)TRN_ISOTP_RX_RECEIVING;
        rx->got = 0u;
        rx->msg_len = fr.msg_len;
        copy_in(rx, &data[fr.data_off], fr.data_len);
        rx->next_sn = 1u;
        rx->block_left = rx->bs;
        rx->last_ms = now_ms;
        rx_send_fc(rx, res, (uint8_t)TRN_ISOTP_FS_CTS);
        return st;
    }
    case TRN_ISOTP_CF: {
        trn_status_t s2 = rx_cf(rx, data, &fr, now_ms, res);
        return (st != TRN_OK) ? st : s2;
    }
    default: /* TRN_ISOTP_FC: decode admits no other type */
        rx_error(rx, res, TRN_ISOTP_ERR_UNEXPECTED_FC, 0);
        return (st != TRN_OK) ? st : TRN_E_FORMAT;
    }
}

const char *trn_isotp_err_name(trn_isotp_err_t err)
{
    switch (err) {
    case TRN_ISOTP_ERR_NONE: return "NONE";
    case TRN_ISOTP_ERR_BAD_FRAME: return "BAD_FRAME";
    case TRN_ISOTP_ERR_UNEXPECTED_CF: return "UNEXPECTED_CF";
    case TRN_ISOTP_ERR_WRONG_SN: return "WRONG_SN";
    case TRN_ISOTP_ERR_OVERFLOW: return "OVERFLOW";
    case TRN_ISOTP_ERR_INTERRUPTED: return "INTERRUPTED";
    case TRN_ISOTP_ERR_TIMEOUT_CR: return "TIMEOUT_CR";
    case TRN_ISOTP_ERR_UNEXPECTED_FC: return "UNEXPECTED_FC";
    case TRN_ISOTP_ERR_SHORT_CF: return "SHORT_CF";
    case TRN_ISOTP_ERR_COUNT:
    default: return "UNKNOWN";
    }
}

/* ---- sender ----------------------------------------------------------------- */

static void tx_res_clear(trn_isotp_tx_result_t *res)
{
    unsigned i;
    res->events = 0u;
    res->error = (uint8_t)TRN_ISOTP_TX_ERR_NONE;
    res->dlc = 0u;
    res->wake_us = 0u;
    for (i = 0u; i < 8u; ++i) {
        res->frame[i] = 0u;
    }
}

static void tx_idle(trn_isotp_tx_t *tx)
{
    tx->state = (uint8_t)TRN_ISOTP_TX_IDLE;
    tx->msg = NULL;
    tx->len = 0u;
    tx->n_frames = 0u;
    tx->next = 0u;
    tx->bs = 0u;
    tx->block_left = 0u;
    tx->wft = 0u;
    tx->paced = 0u;
    tx->stmin_us = 0u;
    tx->t_ref_us = 0u;
}

static void tx_error(trn_isotp_tx_t *tx, trn_isotp_tx_result_t *res, trn_isotp_tx_err_t err,
                     int abort)
{
    tx->err_count[err] += 1u;
    res->events |= TRN_ISOTP_TX_EV_ERROR;
    res->error = (uint8_t)err;
    if (abort) {
        tx_idle(tx);
    }
}

trn_status_t trn_isotp_tx_init(trn_isotp_tx_t *tx, uint32_t n_bs_ms, uint8_t max_wft)
{
    unsigned i;
    if (tx == NULL) {
        return TRN_E_NULL;
    }
    if (n_bs_ms == 0u || n_bs_ms > 60000u) {
        return TRN_E_ARG;
    }
    tx_idle(tx);
    tx->n_bs_us = n_bs_ms * 1000u;
    tx->max_wft = max_wft;
    tx->n_messages = 0u;
    for (i = 0u; i < (unsigned)TRN_ISOTP_TX_ERR_COUNT; ++i) {
        tx->err_count[i] = 0u;
    }
    return TRN_OK;
}

trn_status_t trn_isotp_tx_start(trn_isotp_tx_t *tx, const uint8_t *msg, size_t len)
{
    if (tx == NULL || msg == NULL) {
        return TRN_E_NULL;
    }
    if (len == 0u || len > TRN_ISOTP_MAX_MSG) {
        return TRN_E_SIZE;
    }
    tx_idle(tx);
    tx->msg = msg;
    tx->len = (uint16_t)len;
    tx->n_frames = trn_isotp_frame_count(len);
    tx->state = (uint8_t)TRN_ISOTP_TX_FIRST;
    return TRN_OK;
}

/* Emit frame tx->next into res (arguments valid by construction). */
static void tx_emit(trn_isotp_tx_t *tx, trn_isotp_tx_result_t *res)
{
    (void)trn_isotp_encode_frame(tx->msg, tx->len, tx->next, res->frame, &res->dlc);
    res->events |= TRN_ISOTP_TX_EV_FRAME;
    tx->next = (uint16_t)(tx->next + 1u);
    if (tx->next == tx->n_frames) {
        res->events |= TRN_ISOTP_TX_EV_DONE;
        tx->n_messages += 1u;
        tx_idle(tx);
    }
}

trn_status_t trn_isotp_tx_step(trn_isotp_tx_t *tx, uint32_t now_us, trn_isotp_tx_result_t *res)
{
    if (tx == NULL || res == NULL) {
        return TRN_E_NULL;
    }
    tx_res_clear(res);
    switch (tx->state) {
    case TRN_ISOTP_TX_FIRST:
        tx_emit(tx, res);
        if (tx->state != (uint8_t)TRN_ISOTP_TX_IDLE) {
            tx->state = (uint8_t)TRN_ISOTP_TX_WAIT_FC;
            tx->t_ref_us = now_us;
        }
        return TRN_OK;
    case TRN_ISOTP_TX_WAIT_FC:
        if ((uint32_t)(now_us - tx->t_ref_us) > tx->n_bs_us) {
            tx_error(tx, res, TRN_ISOTP_TX_ERR_TIMEOUT_BS, 1);
            return TRN_E_TIMEOUT;
        }
        res->wake_us = tx->t_ref_us + tx->n_bs_us + 1u;
        return TRN_OK;
    case TRN_ISOTP_TX_SENDING:
        if (tx->paced != 0u && (uint32_t)(now_us - tx->t_ref_us) < tx->stmin_us) {
            res->wake_us = tx->t_ref_us + tx->stmin_us;
            return TRN_OK;
        }
        tx_emit(tx, res);
        if (tx->state == (uint8_t)TRN_ISOTP_TX_IDLE) {
            return TRN_OK;
        }
        tx->t_ref_us = now_us;
        tx->paced = 1u;
        if (tx->bs != 0u) {
            tx->block_left = (uint8_t)(tx->block_left - 1u);
            if (tx->block_left == 0u) {
                tx->state = (uint8_t)TRN_ISOTP_TX_WAIT_FC;
            }
        }
        return TRN_OK;
    default: /* idle: nothing to do */ return TRN_OK;
    }
}

trn_status_t trn_isotp_tx_fc(trn_isotp_tx_t *tx, const uint8_t *data, uint8_t dlc, uint32_t now_us,
                             trn_isotp_tx_result_t *res)
{
    trn_isotp_frame_t fr;
    if (tx == NULL || data == NULL || res == NULL) {
        return TRN_E_NULL;
    }
    if (dlc > 8u) {
        return TRN_E_ARG;
    }
    tx_res_clear(res);
    if (tx->state != (uint8_t)TRN_ISOTP_TX_WAIT_FC) {
        tx_error(tx, res, TRN_ISOTP_TX_ERR_UNEXPECTED_FC, 0);
        return TRN_E_FORMAT;
    }
    if (trn_isotp_decode(data, dlc, &fr) != TRN_OK || fr.type != (uint8_t)TRN_ISOTP_FC) {
        tx_error(tx, res, TRN_ISOTP_TX_ERR_INVALID_FC, 1);
        return TRN_E_FORMAT;
    }
    if (fr.fs == (uint8_t)TRN_ISOTP_FS_OVFLW) {
        tx_error(tx, res, TRN_ISOTP_TX_ERR_OVERFLOW, 1);
        return TRN_E_CAPACITY;
    }
    if (fr.fs == (uint8_t)TRN_ISOTP_FS_WAIT) {
        tx->wft = (uint8_t)(tx->wft + 1u);
        if (tx->wft > tx->max_wft) {
            tx_error(tx, res, TRN_ISOTP_TX_ERR_WFT_OVERRUN, 1);
            return TRN_E_SEQ;
        }
        tx->t_ref_us = now_us; /* N_Bs restarts */
        return TRN_OK;
    }
    /* clear to send: the first CF of the block may go at once */
    tx->wft = 0u;
    tx->bs = fr.bs;
    tx->block_left = fr.bs;
    tx->stmin_us = trn_isotp_stmin_us(fr.stmin);
    tx->paced = 0u;
    tx->state = (uint8_t)TRN_ISOTP_TX_SENDING;
    return TRN_OK;
}

const char *trn_isotp_tx_err_name(trn_isotp_tx_err_t err)
{
    switch (err) {
    case TRN_ISOTP_TX_ERR_NONE: return "NONE";
    case TRN_ISOTP_TX_ERR_TIMEOUT_BS: return "TIMEOUT_BS";
    case TRN_ISOTP_TX_ERR_WFT_OVERRUN: return "WFT_OVERRUN";
    case TRN_ISOTP_TX_ERR_OVERFLOW: return "OVERFLOW";
    case TRN_ISOTP_TX_ERR_INVALID_FC: return "INVALID_FC";
    case TRN_ISOTP_TX_ERR_UNEXPECTED_FC: return "UNEXPECTED_FC";
    case TRN_ISOTP_TX_ERR_COUNT:
    default: return "UNKNOWN";
    }
}
