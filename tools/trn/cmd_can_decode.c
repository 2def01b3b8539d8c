/* SPDX-License-Identifier: Apache-2.0 */
/* cmd_can_decode.c - `trn can-decode [--strict] [--n-cr-ms MS] [--json] LOG`:
 * decode a candump -l log of the mast / stereo-head bus
 * (docs/can-protocol.md).
 *
 * One line per frame of ours on stdout, decoded; ISO-TP data frames of the
 * capture transfer are reassembled (isotp.h, the same receiver the flight
 * processor uses) into segments and captures (capture.h), with a line per
 * completed capture or per named transfer error. Frames that are not ours
 * (other IDs, extended IDs, remote frames, CAN FD, error frames) are counted
 * and skipped. A malformed line prints `LOG:N: reason` on stderr and is
 * skipped; the exit status is then 1 after the whole log is read (with
 * --strict also for protocol errors of our messages). --json prints the same
 * events as one JSON object instead of the lines (docs/modules/cli.md).
 *
 * Three parts: can_parse (the options, through cli_parse), can_run (the log,
 * line by line, through the receivers) and the rep_* reporters, which print
 * each event as a text line or as JSON. */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "can_log.h"
#include "cli.h"
#include "commands.h"
#include "trn_port/can_msg.h"
#include "trn_port/capture.h"
#include "trn_port/isotp.h"

#define LINE_MAX_CHARS 1024
#define N_CR_MS_DEFAULT 1000L /* ISO-TP N_Cr: the receiver's consecutive-frame timeout */

typedef struct {
    const char *path; /* LOG; "-" is standard input */
    int strict;
    int json;
    long n_cr_ms;
} can_args_t;

typedef struct {
    unsigned long lines, ours, foreign, fd, error_frames, remote, malformed, bad_msgs;
    unsigned long captures_ok, capture_errors, isotp_errors;
} counts_t;

/* One decoded message of ours other than a capture data frame. */
typedef struct {
    trn_can_msg_kind_t kind;
    union {
        trn_mast_cmd_t mast_cmd;
        trn_mast_status_t mast_status;
        trn_capture_cmd_t capture_cmd;
        trn_heartbeat_t hb;
        trn_isotp_frame_t fc;
    } u;
} decoded_t;

/* Where the events go: text lines, or one JSON object on stdout. */
typedef struct {
    int json;
    json_t j;
    const char *path;
} report_t;

/* Caller-side memory of the transfer (large: static, as flight code would). */
static uint8_t g_isotp_buf[TRN_ISOTP_MAX_MSG];
static trn_isotp_rx_t g_isotp;
static trn_capture_rx_t g_caprx;
static trn_capture_t g_cap;

static const char *const k_status_bits[6] = {"MOVING",       "PAN_LIM_MIN",  "PAN_LIM_MAX",
                                             "TILT_LIM_MIN", "TILT_LIM_MAX", "IN_POSITION"};
static const char *const k_fault_bits[6] = {"PAN_STALL",   "TILT_STALL", "ENCODER",
                                            "OVERCURRENT", "OVERTEMP",   "CMD_INVALID"};
static const char *const k_modes[3] = {"HOLD", "MOVE", "STOP"};
static const char *const k_fc_status[3] = {"CTS", "WAIT", "OVFLW"};

/* ------------------------------------------------------------------------ */
/* parse                                                                      */
/* ------------------------------------------------------------------------ */

/* The options into a; returns CLI_OK, CLI_HELP (usage printed) or the exit
 * status of a usage or value error (its one line printed). */
static int can_parse(int argc, char **argv, can_args_t *a)
{
    cli_opt_t opts[] = {
        {"--strict", CLI_FLAG, &a->strict, 0, 0, 0, NULL,
         "exit status 1 also on invalid messages of ours and failed captures", 0},
        {"--n-cr-ms", CLI_LONG, &a->n_cr_ms, 1, 60000, 0, "MS",
         "ISO-TP N_Cr timeout: the longest wait for the next consecutive frame, ms", 0},
        {"--json", CLI_FLAG, &a->json, 0, 0, 0, NULL,
         "print one JSON object (every event and the summary)", 0},
        {"LOG", CLI_STRING, &a->path, 0, 0, 1, NULL, "the candump -l log; - reads standard input",
         0},
    };
    cli_cmd_t cmd = {
        "can-decode",
        "Decode a candump -l log (\"(sec.usec) ifname ID#DATA\" lines) of the mast / stereo-head\n"
        "bus: one line per frame of ours, captures reassembled from their ISO-TP frames, a\n"
        "summary line at the end.",
        "Malformed lines: 'LOG:N: reason' on stderr, exit status 1 once the whole log is read.\n"
        "The log's timestamps drive the ISO-TP timeouts.",
        opts, sizeof opts / sizeof opts[0]};
    a->path = NULL;
    a->strict = 0;
    a->json = 0;
    a->n_cr_ms = N_CR_MS_DEFAULT;
    return cli_parse(&cmd, argc, argv);
}

/* ------------------------------------------------------------------------ */
/* report                                                                     */
/* ------------------------------------------------------------------------ */

/* raw counts of 1e-4 as an exact decimal, e.g. -12345 -> "-1.2345" */
static const char *e4(int32_t raw, char buf[16])
{
    uint32_t a = (raw < 0) ? (uint32_t)(-(int64_t)raw) : (uint32_t)raw;
    snprintf(buf, 16, "%s%" PRIu32 ".%04" PRIu32, raw < 0 ? "-" : "", a / 10000u, a % 10000u);
    return buf;
}

static double si4(int32_t raw) { return (double)raw / 10000.0; }

static void print_bits(uint8_t v, const char *const names[6])
{
    int b, any = 0;
    for (b = 0; b < 6; ++b) {
        if (v & (1u << b)) {
            printf("%s%s", any ? "|" : "", names[b]);
            any = 1;
        }
    }
    if (!any) {
        printf("-");
    }
}

static void json_bits(json_t *j, const char *key, uint8_t v, const char *const names[6])
{
    int b;
    json_arr(j, key);
    for (b = 0; b < 6; ++b) {
        if (v & (1u << b)) {
            json_str(j, NULL, names[b]);
        }
    }
    json_arr_end(j);
}

static const char *node_state(uint8_t s)
{
    static const char *const n[4] = {"BOOT", "READY", "BUSY", "FAULT"};
    return s < 4 ? n[s] : "?";
}

static void rep_begin(report_t *r, const can_args_t *a)
{
    r->json = a->json;
    r->path = a->path;
    if (r->json) {
        json_begin(&r->j, stdout);
        json_str(&r->j, "log", a->path);
        json_bool(&r->j, "strict", a->strict);
        json_int(&r->j, "n_cr_ms", a->n_cr_ms);
        json_arr(&r->j, "events");
    }
}

/* A malformed line: on stderr in both modes, and an event in the JSON. */
static void rep_malformed(report_t *r, unsigned long line, const char *reason)
{
    fprintf(stderr, "%s:%lu: %s\n", r->path, line, reason);
    if (r->json) {
        json_obj(&r->j, NULL);
        json_str(&r->j, "event", "malformed");
        json_int(&r->j, "line", (long long)line);
        json_str(&r->j, "reason", reason);
        json_obj_end(&r->j);
    }
}

static void rep_timeout(report_t *r, const can_log_line_t *l, trn_isotp_err_t err, long n_cr_ms)
{
    if (!r->json) {
        printf("(%" PRIu64 ".%06" PRIu32
               ") isotp error %s: capture transfer idle for more than %ld ms\n",
               l->sec, l->usec, trn_isotp_err_name(err), n_cr_ms);
        return;
    }
    json_obj(&r->j, NULL);
    json_str(&r->j, "event", "isotp_timeout");
    json_int(&r->j, "sec", (long long)l->sec);
    json_int(&r->j, "usec", (long long)l->usec);
    json_str(&r->j, "error", trn_isotp_err_name(err));
    json_int(&r->j, "n_cr_ms", n_cr_ms);
    json_obj_end(&r->j);
}

static void rep_frame_begin(report_t *r, const can_log_line_t *l, trn_can_msg_kind_t kind)
{
    if (!r->json) {
        printf("(%" PRIu64 ".%06" PRIu32 ") %s %03" PRIX32 " %s ", l->sec, l->usec, l->ifname,
               l->frame.id, trn_can_msg_name(kind));
        return;
    }
    json_obj(&r->j, NULL);
    json_str(&r->j, "event", "frame");
    json_int(&r->j, "sec", (long long)l->sec);
    json_int(&r->j, "usec", (long long)l->usec);
    json_str(&r->j, "ifname", l->ifname);
    json_int(&r->j, "id", (long long)l->frame.id);
    json_str(&r->j, "msg", trn_can_msg_name(kind));
}

static void rep_frame_end(report_t *r)
{
    if (r->json) {
        json_obj_end(&r->j);
    }
}

static void text_msg(const decoded_t *d)
{
    char a[16], b[16], c[16];
    switch (d->kind) {
    case TRN_CAN_MSG_MAST_CMD: {
        const trn_mast_cmd_t *m = &d->u.mast_cmd;
        printf("pan=%s rad tilt=%s rad rate=%s rad/s seq=%u mode=%s\n", e4(m->pan_100urad, a),
               e4(m->tilt_100urad, b), e4(m->rate_100urad_s, c), m->seq, k_modes[m->mode]);
        break;
    }
    case TRN_CAN_MSG_MAST_STATUS: {
        const trn_mast_status_t *m = &d->u.mast_status;
        printf("pan=%s rad tilt=%s rad state=", e4(m->pan_100urad, a), e4(m->tilt_100urad, b));
        print_bits(m->state, k_status_bits);
        printf(" faults=");
        print_bits(m->faults, k_fault_bits);
        printf(" ack=%u counter=%u\n", m->cmd_seq_ack, m->counter);
        break;
    }
    case TRN_CAN_MSG_CAPTURE_CMD:
        printf("capture_id=%u max_points=%u\n", d->u.capture_cmd.capture_id,
               d->u.capture_cmd.max_points);
        break;
    case TRN_CAN_MSG_CAPTURE_FC:
        printf("FC %s bs=%u stmin=0x%02X (%" PRIu32 " us)\n", k_fc_status[d->u.fc.fs], d->u.fc.bs,
               d->u.fc.stmin, trn_isotp_stmin_us(d->u.fc.stmin));
        break;
    default: /* the two heartbeats */
        printf("state=%s counter=%u uptime=%u s\n", node_state(d->u.hb.state), d->u.hb.counter,
               d->u.hb.uptime_s);
        break;
    }
}

static void json_msg(json_t *j, const decoded_t *d)
{
    json_bool(j, "valid", 1);
    switch (d->kind) {
    case TRN_CAN_MSG_MAST_CMD:
        json_num(j, "pan_rad", si4(d->u.mast_cmd.pan_100urad));
        json_num(j, "tilt_rad", si4(d->u.mast_cmd.tilt_100urad));
        json_num(j, "rate_rad_s", si4(d->u.mast_cmd.rate_100urad_s));
        json_int(j, "seq", d->u.mast_cmd.seq);
        json_str(j, "mode", k_modes[d->u.mast_cmd.mode]);
        break;
    case TRN_CAN_MSG_MAST_STATUS:
        json_num(j, "pan_rad", si4(d->u.mast_status.pan_100urad));
        json_num(j, "tilt_rad", si4(d->u.mast_status.tilt_100urad));
        json_bits(j, "state", d->u.mast_status.state, k_status_bits);
        json_bits(j, "faults", d->u.mast_status.faults, k_fault_bits);
        json_int(j, "ack", d->u.mast_status.cmd_seq_ack);
        json_int(j, "counter", d->u.mast_status.counter);
        break;
    case TRN_CAN_MSG_CAPTURE_CMD:
        json_int(j, "capture_id", d->u.capture_cmd.capture_id);
        json_int(j, "max_points", d->u.capture_cmd.max_points);
        break;
    case TRN_CAN_MSG_CAPTURE_FC:
        json_str(j, "fs", k_fc_status[d->u.fc.fs]);
        json_int(j, "bs", d->u.fc.bs);
        json_int(j, "stmin", d->u.fc.stmin);
        json_int(j, "stmin_us", (long long)trn_isotp_stmin_us(d->u.fc.stmin));
        break;
    default: /* the two heartbeats */
        json_str(j, "state", node_state(d->u.hb.state));
        json_int(j, "counter", d->u.hb.counter);
        json_int(j, "uptime_s", d->u.hb.uptime_s);
        break;
    }
}

static void rep_msg(report_t *r, const decoded_t *d)
{
    if (r->json) {
        json_msg(&r->j, d);
    } else {
        text_msg(d);
    }
}

/* A frame with one of our IDs that its decoder refused. */
static void rep_invalid(report_t *r, const trn_can_frame_t *f)
{
    int i;
    if (!r->json) {
        printf("invalid (dlc %u:", f->dlc);
        for (i = 0; i < f->dlc; ++i) {
            printf(" %02X", f->data[i]);
        }
        printf(")\n");
        return;
    }
    {
        char hex[2 * 8 + 1];
        size_t k;
        for (k = 0; k < f->dlc && k < 8u; ++k) {
            snprintf(hex + 2u * k, 3, "%02X", f->data[k]);
        }
        hex[2u * k] = '\0';
        json_bool(&r->j, "valid", 0);
        json_int(&r->j, "dlc", f->dlc);
        json_str(&r->j, "data", hex);
    }
}

/* The ISO-TP frame of a capture data frame; fr NULL: not a valid one. */
static void rep_isotp(report_t *r, const trn_isotp_frame_t *fr)
{
    static const char *const types[4] = {"SF", "FF", "CF", "FC"};
    if (!r->json) {
        if (fr == NULL) {
            printf("invalid ISO-TP frame\n");
        } else if (fr->type == TRN_ISOTP_SF || fr->type == TRN_ISOTP_FF) {
            printf("%s len=%u\n", types[fr->type], fr->msg_len);
        } else if (fr->type == TRN_ISOTP_CF) {
            printf("CF sn=%u bytes=%u\n", fr->sn, fr->data_len);
        } else {
            printf("FC on the data id\n");
        }
        return;
    }
    json_obj(&r->j, "isotp");
    json_str(&r->j, "type", fr == NULL ? "invalid" : types[fr->type]);
    if (fr != NULL && (fr->type == TRN_ISOTP_SF || fr->type == TRN_ISOTP_FF)) {
        json_int(&r->j, "len", fr->msg_len);
    } else if (fr != NULL && fr->type == TRN_ISOTP_CF) {
        json_int(&r->j, "sn", fr->sn);
        json_int(&r->j, "bytes", fr->data_len);
    }
    json_obj_end(&r->j);
}

/* A named error of the transfer: kind "isotp" or "capture". */
static void rep_error(report_t *r, const char *kind, const char *name)
{
    if (r->json) {
        char key[32];
        snprintf(key, sizeof key, "%s_error", kind);
        json_str(&r->j, key, name);
    } else {
        printf("  %s error %s\n", kind, name);
    }
}

static void rep_segment(report_t *r, const uint8_t *msg, size_t len)
{
    unsigned id = (unsigned)(msg[0] | (msg[1] << 8));
    unsigned bytes = (unsigned)(len - TRN_CAP_SEG_HEADER_BYTES);
    if (!r->json) {
        printf("  segment id=%u index=%u/%u bytes=%u\n", id, msg[2], msg[3], bytes);
        return;
    }
    json_obj(&r->j, "segment");
    json_int(&r->j, "id", id);
    json_int(&r->j, "index", msg[2]);
    json_int(&r->j, "count", msg[3]);
    json_int(&r->j, "bytes", bytes);
    json_obj_end(&r->j);
}

static void rep_capture(report_t *r, const trn_capture_t *c)
{
    char a[16], b[16];
    if (!r->json) {
        printf("  capture id=%u points=%u time_ms=%" PRIu32
               " pan=%s rad tilt=%s rad mast_state=0x%02X "
               "mast_faults=0x%02X crc=0x%08" PRIX32 " ok\n",
               c->capture_id, c->n_points, c->time_ms, e4(c->pan_100urad, a),
               e4(c->tilt_100urad, b), c->mast_state, c->mast_faults, c->crc);
        return;
    }
    json_obj(&r->j, "capture");
    json_int(&r->j, "id", c->capture_id);
    json_int(&r->j, "points", c->n_points);
    json_int(&r->j, "time_ms", (long long)c->time_ms);
    json_num(&r->j, "pan_rad", si4(c->pan_100urad));
    json_num(&r->j, "tilt_rad", si4(c->tilt_100urad));
    json_bits(&r->j, "mast_state", c->mast_state, k_status_bits);
    json_bits(&r->j, "mast_faults", c->mast_faults, k_fault_bits);
    json_int(&r->j, "crc", (long long)c->crc);
    json_obj_end(&r->j);
}

static void rep_incomplete(report_t *r)
{
    if (r->json) {
        json_obj(&r->j, NULL);
        json_str(&r->j, "event", "incomplete_capture");
        json_obj_end(&r->j);
    } else {
        printf("log ends inside a capture transfer: incomplete capture dropped\n");
    }
}

static void rep_end(report_t *r, const counts_t *n, int proto_bad)
{
    if (!r->json) {
        printf("summary: lines=%lu ours=%lu foreign=%lu (fd=%lu error_frames=%lu remote=%lu) "
               "malformed=%lu "
               "invalid_msgs=%lu captures_ok=%lu capture_errors=%lu isotp_errors=%lu\n",
               n->lines, n->ours, n->foreign, n->fd, n->error_frames, n->remote, n->malformed,
               n->bad_msgs, n->captures_ok, n->capture_errors, n->isotp_errors);
        return;
    }
    json_arr_end(&r->j);
    json_obj(&r->j, "summary");
    json_int(&r->j, "lines", (long long)n->lines);
    json_int(&r->j, "ours", (long long)n->ours);
    json_int(&r->j, "foreign", (long long)n->foreign);
    json_int(&r->j, "fd", (long long)n->fd);
    json_int(&r->j, "error_frames", (long long)n->error_frames);
    json_int(&r->j, "remote", (long long)n->remote);
    json_int(&r->j, "malformed", (long long)n->malformed);
    json_int(&r->j, "invalid_msgs", (long long)n->bad_msgs);
    json_int(&r->j, "captures_ok", (long long)n->captures_ok);
    json_int(&r->j, "capture_errors", (long long)n->capture_errors);
    json_int(&r->j, "isotp_errors", (long long)n->isotp_errors);
    json_bool(&r->j, "protocol_errors", proto_bad);
    json_obj_end(&r->j);
    json_end(&r->j);
}

/* ------------------------------------------------------------------------ */
/* run                                                                        */
/* ------------------------------------------------------------------------ */

/* Decode a message of ours other than a capture data frame; -1: invalid. */
static int decode_msg(const trn_can_frame_t *f, trn_can_msg_kind_t kind, decoded_t *d)
{
    d->kind = kind;
    switch (kind) {
    case TRN_CAN_MSG_MAST_CMD: return trn_can_mast_cmd_decode(f, &d->u.mast_cmd) == TRN_OK ? 0 : -1;
    case TRN_CAN_MSG_MAST_STATUS:
        return trn_can_mast_status_decode(f, &d->u.mast_status) == TRN_OK ? 0 : -1;
    case TRN_CAN_MSG_CAPTURE_CMD:
        return trn_can_capture_cmd_decode(f, &d->u.capture_cmd) == TRN_OK ? 0 : -1;
    case TRN_CAN_MSG_MAST_HB:
    case TRN_CAN_MSG_STEREO_HB: return trn_can_heartbeat_decode(f, &d->u.hb) == TRN_OK ? 0 : -1;
    case TRN_CAN_MSG_CAPTURE_FC:
        return trn_isotp_decode(f->data, f->dlc, &d->u.fc) == TRN_OK && d->u.fc.type == TRN_ISOTP_FC
                   ? 0
                   : -1;
    default: return -1;
    }
}

/* A complete ISO-TP message of the capture transfer: a segment for the
 * reassembler. Returns 1 on a capture error. */
static int capture_segment(report_t *r, size_t msg_len, counts_t *n)
{
    int done = 0, bad = 0;
    trn_cap_err_t err = TRN_CAP_ERR_NONE;
    if (msg_len >= TRN_CAP_SEG_HEADER_BYTES) {
        rep_segment(r, g_isotp_buf, msg_len);
    }
    if (trn_capture_rx_segment(&g_caprx, g_isotp_buf, msg_len, &g_cap, &done, &err) != TRN_OK) {
        rep_error(r, "capture", trn_cap_err_name(err));
        ++n->capture_errors;
        bad = 1;
    }
    if (done) {
        rep_capture(r, &g_cap);
        ++n->captures_ok;
    }
    return bad;
}

/* One ISO-TP data frame: report it, feed the receiver, then the reassembler.
 * Returns 1 on a protocol error. */
static int capture_data(report_t *r, const trn_can_frame_t *f, uint32_t now_ms, counts_t *n)
{
    trn_isotp_frame_t fr;
    trn_isotp_rx_result_t res;
    int bad = 0;
    rep_isotp(r, trn_isotp_decode(f->data, f->dlc, &fr) == TRN_OK ? &fr : NULL);
    (void)trn_isotp_rx_frame(&g_isotp, f->data, f->dlc, now_ms, &res);
    if (res.events & TRN_ISOTP_EV_ERROR) {
        rep_error(r, "isotp", trn_isotp_err_name((trn_isotp_err_t)res.error));
        ++n->isotp_errors;
        bad = 1;
        if (res.error != TRN_ISOTP_ERR_UNEXPECTED_CF && res.error != TRN_ISOTP_ERR_UNEXPECTED_FC &&
            res.error != TRN_ISOTP_ERR_BAD_FRAME) {
            (void)trn_capture_rx_abort(&g_caprx); /* part of a segment was lost */
        }
    }
    if (res.events & TRN_ISOTP_EV_MESSAGE) {
        bad |= capture_segment(r, res.msg_len, n);
    }
    return bad;
}

/* One parsed frame of the log. Returns 1 on a protocol error. */
static int frame(report_t *r, const can_log_line_t *l, long n_cr_ms, counts_t *n)
{
    /* the log's clock drives the ISO-TP timeouts: a transfer idle for longer
   * than N_Cr is reported at the first later line */
    uint32_t now_ms = (uint32_t)(l->sec * 1000u + l->usec / 1000u);
    trn_isotp_rx_result_t res;
    trn_can_msg_kind_t kind;
    decoded_t d;
    int bad = 0;
    if (trn_isotp_rx_poll(&g_isotp, now_ms, &res) == TRN_E_TIMEOUT) {
        rep_timeout(r, l, (trn_isotp_err_t)res.error, n_cr_ms);
        (void)trn_capture_rx_abort(&g_caprx);
        ++n->isotp_errors;
        bad = 1;
    }
    kind = trn_can_classify(&l->frame);
    if (kind == TRN_CAN_MSG_NONE) {
        if (l->frame.flags & TRN_CAN_FLAG_RTR) {
            ++n->remote;
        }
        ++n->foreign;
        return bad;
    }
    ++n->ours;
    rep_frame_begin(r, l, kind);
    if (kind == TRN_CAN_MSG_CAPTURE_DATA) {
        bad |= capture_data(r, &l->frame, now_ms, n);
    } else if (decode_msg(&l->frame, kind, &d) == 0) {
        rep_msg(r, &d);
    } else {
        rep_invalid(r, &l->frame);
        ++n->bad_msgs;
        bad = 1;
    }
    rep_frame_end(r);
    return bad;
}

/* Every line of in; returns 1 when there was a protocol error. */
static int can_run(FILE *in, const can_args_t *a, report_t *r, counts_t *n)
{
    char line[LINE_MAX_CHARS + 2];
    int proto_bad = 0;
    while (fgets(line, sizeof line, in) != NULL) {
        can_log_line_t l;
        size_t len = strlen(line);
        ++n->lines;
        if (len > 0 && line[len - 1] != '\n' && !feof(in)) {
            char why[64];
            int c;
            snprintf(why, sizeof why, "line longer than %d characters", LINE_MAX_CHARS);
            rep_malformed(r, n->lines, why);
            ++n->malformed;
            while ((c = fgetc(in)) != EOF && c != '\n') {
            }
            continue;
        }
        can_log_parse(line, &l);
        switch (l.kind) {
        case CAN_LOG_SKIP: break;
        case CAN_LOG_MALFORMED:
            rep_malformed(r, n->lines, l.reason);
            ++n->malformed;
            break;
        case CAN_LOG_FD:
            ++n->fd;
            ++n->foreign;
            break;
        case CAN_LOG_ERROR:
            ++n->error_frames;
            ++n->foreign;
            break;
        case CAN_LOG_FRAME: proto_bad |= frame(r, &l, a->n_cr_ms, n); break;
        }
    }
    if (g_isotp.state == TRN_ISOTP_RX_RECEIVING || g_caprx.active) {
        rep_incomplete(r);
        ++n->capture_errors;
        proto_bad = 1;
    }
    return proto_bad;
}

int trn_cmd_can_decode(int argc, char **argv)
{
    can_args_t a;
    report_t r;
    counts_t n;
    FILE *in;
    int rc = can_parse(argc, argv, &a), proto_bad;
    if (rc == CLI_HELP) {
        return CLI_OK;
    }
    if (rc != CLI_OK) {
        return rc;
    }
    in = (strcmp(a.path, "-") == 0) ? stdin : fopen(a.path, "r");
    if (in == NULL) {
        return cli_fail("can-decode", "cannot open '%s'", a.path);
    }
    if (trn_isotp_rx_init(&g_isotp, g_isotp_buf, sizeof g_isotp_buf, 0, 0, (uint32_t)a.n_cr_ms) !=
            TRN_OK ||
        trn_capture_rx_init(&g_caprx) != TRN_OK) {
        if (in != stdin) {
            (void)fclose(in);
        }
        return cli_fail("can-decode", "receiver setup failed");
    }
    memset(&n, 0, sizeof n);
    rep_begin(&r, &a);
    proto_bad = can_run(in, &a, &r, &n);
    if (in != stdin) {
        (void)fclose(in);
    }
    rep_end(&r, &n, proto_bad);
    if (n.malformed > 0 || (a.strict && proto_bad)) {
        return CLI_BAD_INPUT;
    }
    return CLI_OK;
}
