/* SPDX-License-Identifier: Apache-2.0 */
/* cmd_can_decode.c - `trn can-decode LOG`: decode a candump -l log of the
 * mast / stereo-head bus (docs/can-protocol.md).
 *
 * One line per frame of ours on stdout, decoded; ISO-TP data frames of the
 * capture transfer are reassembled (isotp.h, the same receiver the flight
 * processor uses) into segments and captures (capture.h), with a line per
 * completed capture or per named transfer error. Frames that are not ours
 * (other IDs, extended IDs, remote frames, CAN FD, error frames) are counted
 * and skipped. A malformed line prints `LOG:N: reason` on stderr and is
 * skipped; the exit status is then 1 after the whole log is read (with
 * --strict also for protocol errors of our messages). */
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
#define N_CR_MS_DEFAULT 1000ul /* ISO-TP N_Cr: the receiver's consecutive-frame timeout */

typedef struct {
  unsigned long lines, ours, foreign, fd, error_frames, remote, malformed, bad_msgs;
  unsigned long captures_ok, capture_errors, isotp_errors;
} counts_t;

/* Caller-side memory of the transfer (large: static, as flight code would). */
static uint8_t g_isotp_buf[TRN_ISOTP_MAX_MSG];
static trn_isotp_rx_t g_isotp;
static trn_capture_rx_t g_caprx;
static trn_capture_t g_cap;

static void usage(FILE *out) {
  fprintf(out,
          "usage: trn can-decode [--strict] [--n-cr-ms MS] LOG\n"
          "  Decode a candump -l log (\"(sec.usec) ifname ID#DATA\" lines) of the\n"
          "  mast / stereo-head bus: one line per frame of ours, captures reassembled\n"
          "  from their ISO-TP frames, a summary line at the end.\n"
          "  LOG '-' reads standard input. Malformed lines: 'LOG:N: reason' on stderr,\n"
          "  exit status 1 at the end. --strict: exit 1 also on invalid messages of\n"
          "  ours and failed captures. --n-cr-ms: ISO-TP N_Cr timeout (default %lu).\n\n",
          N_CR_MS_DEFAULT);
  cli_exit_status_help("can-decode", out);
}

/* raw counts of 1e-4 as an exact decimal, e.g. -12345 -> "-1.2345" */
static const char *e4(int32_t raw, char buf[16]) {
  uint32_t a = (raw < 0) ? (uint32_t)(-(int64_t)raw) : (uint32_t)raw;
  snprintf(buf, 16, "%s%" PRIu32 ".%04" PRIu32, raw < 0 ? "-" : "", a / 10000u, a % 10000u);
  return buf;
}

static void print_bits(uint8_t v, const char *const names[6]) {
  int b, any = 0;
  for (b = 0; b < 6; ++b) {
    if (v & (1u << b)) {
      printf("%s%s", any ? "|" : "", names[b]);
      any = 1;
    }
  }
  if (!any) printf("-");
}

static const char *node_state(uint8_t s) {
  static const char *const n[4] = {"BOOT", "READY", "BUSY", "FAULT"};
  return s < 4 ? n[s] : "?";
}

static int decode_simple(const trn_can_frame_t *f, trn_can_msg_kind_t kind) {
  static const char *const st[6] = {"MOVING", "PAN_LIM_MIN", "PAN_LIM_MAX", "TILT_LIM_MIN", "TILT_LIM_MAX",
                                    "IN_POSITION"};
  static const char *const fl[6] = {"PAN_STALL", "TILT_STALL", "ENCODER", "OVERCURRENT", "OVERTEMP",
                                    "CMD_INVALID"};
  static const char *const modes[3] = {"HOLD", "MOVE", "STOP"};
  char a[16], b[16], c[16];
  switch (kind) {
  case TRN_CAN_MSG_MAST_CMD: {
    trn_mast_cmd_t m;
    if (trn_can_mast_cmd_decode(f, &m) != TRN_OK) return -1;
    printf("pan=%s rad tilt=%s rad rate=%s rad/s seq=%u mode=%s\n", e4(m.pan_100urad, a), e4(m.tilt_100urad, b),
           e4(m.rate_100urad_s, c), m.seq, modes[m.mode]);
    return 0;
  }
  case TRN_CAN_MSG_MAST_STATUS: {
    trn_mast_status_t m;
    if (trn_can_mast_status_decode(f, &m) != TRN_OK) return -1;
    printf("pan=%s rad tilt=%s rad state=", e4(m.pan_100urad, a), e4(m.tilt_100urad, b));
    print_bits(m.state, st);
    printf(" faults=");
    print_bits(m.faults, fl);
    printf(" ack=%u counter=%u\n", m.cmd_seq_ack, m.counter);
    return 0;
  }
  case TRN_CAN_MSG_CAPTURE_CMD: {
    trn_capture_cmd_t m;
    if (trn_can_capture_cmd_decode(f, &m) != TRN_OK) return -1;
    printf("capture_id=%u max_points=%u\n", m.capture_id, m.max_points);
    return 0;
  }
  case TRN_CAN_MSG_MAST_HB:
  case TRN_CAN_MSG_STEREO_HB: {
    trn_heartbeat_t m;
    if (trn_can_heartbeat_decode(f, &m) != TRN_OK) return -1;
    printf("state=%s counter=%u uptime=%u s\n", node_state(m.state), m.counter, m.uptime_s);
    return 0;
  }
  case TRN_CAN_MSG_CAPTURE_FC: {
    trn_isotp_frame_t fr;
    static const char *const fs[3] = {"CTS", "WAIT", "OVFLW"};
    if (trn_isotp_decode(f->data, f->dlc, &fr) != TRN_OK || fr.type != TRN_ISOTP_FC) return -1;
    printf("FC %s bs=%u stmin=0x%02X (%" PRIu32 " us)\n", fs[fr.fs], fr.bs, fr.stmin, trn_isotp_stmin_us(fr.stmin));
    return 0;
  }
  default:
    return -1;
  }
}

static void print_capture(const trn_capture_t *c) {
  char a[16], b[16];
  printf("capture id=%u points=%u time_ms=%" PRIu32 " pan=%s rad tilt=%s rad mast_state=0x%02X mast_faults=0x%02X "
         "crc=0x%08" PRIX32 " ok\n",
         c->capture_id, c->n_points, c->time_ms, e4(c->pan_100urad, a), e4(c->tilt_100urad, b), c->mast_state,
         c->mast_faults, c->crc);
}

/* One ISO-TP data frame: print it, feed the receiver, then the reassembler. */
static int capture_data(const trn_can_frame_t *f, uint32_t now_ms, counts_t *n) {
  trn_isotp_frame_t fr;
  trn_isotp_rx_result_t res;
  int bad = 0;
  if (trn_isotp_decode(f->data, f->dlc, &fr) == TRN_OK) {
    switch (fr.type) {
    case TRN_ISOTP_SF: printf("SF len=%u\n", fr.msg_len); break;
    case TRN_ISOTP_FF: printf("FF len=%u\n", fr.msg_len); break;
    case TRN_ISOTP_CF: printf("CF sn=%u bytes=%u\n", fr.sn, fr.data_len); break;
    default: printf("FC on the data id\n"); break;
    }
  } else {
    printf("invalid ISO-TP frame\n");
  }
  (void)trn_isotp_rx_frame(&g_isotp, f->data, f->dlc, now_ms, &res);
  if (res.events & TRN_ISOTP_EV_ERROR) {
    printf("  isotp error %s\n", trn_isotp_err_name((trn_isotp_err_t)res.error));
    ++n->isotp_errors;
    bad = 1;
    if (res.error != TRN_ISOTP_ERR_UNEXPECTED_CF && res.error != TRN_ISOTP_ERR_UNEXPECTED_FC &&
        res.error != TRN_ISOTP_ERR_BAD_FRAME) {
      (void)trn_capture_rx_abort(&g_caprx); /* part of a segment was lost */
    }
  }
  if (res.events & TRN_ISOTP_EV_MESSAGE) {
    int done = 0;
    trn_cap_err_t err = TRN_CAP_ERR_NONE;
    trn_status_t st;
    if (res.msg_len >= TRN_CAP_SEG_HEADER_BYTES) {
      printf("  segment id=%u index=%u/%u bytes=%u\n", (unsigned)(g_isotp_buf[0] | (g_isotp_buf[1] << 8)),
             g_isotp_buf[2], g_isotp_buf[3], (unsigned)(res.msg_len - TRN_CAP_SEG_HEADER_BYTES));
    }
    st = trn_capture_rx_segment(&g_caprx, g_isotp_buf, res.msg_len, &g_cap, &done, &err);
    if (st != TRN_OK) {
      printf("  capture error %s\n", trn_cap_err_name(err));
      ++n->capture_errors;
      bad = 1;
    }
    if (done) {
      printf("  ");
      print_capture(&g_cap);
      ++n->captures_ok;
    }
  }
  return bad;
}

int trn_cmd_can_decode(int argc, char **argv) {
  const char *path = NULL;
  int strict = 0, i, proto_bad = 0;
  unsigned long n_cr_ms = N_CR_MS_DEFAULT;
  FILE *in;
  char line[LINE_MAX_CHARS + 2];
  counts_t n;

  memset(&n, 0, sizeof n);
  for (i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
      usage(stdout);
      return 0;
    } else if (strcmp(argv[i], "--strict") == 0) {
      strict = 1;
    } else if (strcmp(argv[i], "--n-cr-ms") == 0 && i + 1 < argc) {
      char *end;
      n_cr_ms = strtoul(argv[++i], &end, 10);
      if (*end != '\0' || n_cr_ms == 0 || n_cr_ms > 60000) {
        fprintf(stderr, "trn can-decode: --n-cr-ms takes 1..60000\n");
        return 2;
      }
    } else if (argv[i][0] == '-' && argv[i][1] != '\0') {
      fprintf(stderr, "trn can-decode: unknown option '%s'\n", argv[i]);
      usage(stderr);
      return 2;
    } else if (path == NULL) {
      path = argv[i];
    } else {
      usage(stderr);
      return 2;
    }
  }
  if (path == NULL) {
    usage(stderr);
    return 2;
  }
  in = (strcmp(path, "-") == 0) ? stdin : fopen(path, "r");
  if (in == NULL) {
    fprintf(stderr, "trn can-decode: cannot open '%s'\n", path);
    return 1;
  }
  if (trn_isotp_rx_init(&g_isotp, g_isotp_buf, sizeof g_isotp_buf, 0, 0, (uint32_t)n_cr_ms) != TRN_OK ||
      trn_capture_rx_init(&g_caprx) != TRN_OK) {
    fprintf(stderr, "trn can-decode: receiver setup failed\n");
    return 1;
  }

  while (fgets(line, sizeof line, in) != NULL) {
    can_log_line_t l;
    trn_can_msg_kind_t kind;
    size_t len = strlen(line);
    ++n.lines;
    if (len > 0 && line[len - 1] != '\n' && !feof(in)) {
      int c;
      fprintf(stderr, "%s:%lu: line longer than %d characters\n", path, n.lines, LINE_MAX_CHARS);
      ++n.malformed;
      while ((c = fgetc(in)) != EOF && c != '\n') {
      }
      continue;
    }
    can_log_parse(line, &l);
    switch (l.kind) {
    case CAN_LOG_SKIP: continue;
    case CAN_LOG_MALFORMED:
      fprintf(stderr, "%s:%lu: %s\n", path, n.lines, l.reason);
      ++n.malformed;
      continue;
    case CAN_LOG_FD: ++n.fd; ++n.foreign; continue;
    case CAN_LOG_ERROR: ++n.error_frames; ++n.foreign; continue;
    case CAN_LOG_FRAME: break;
    }
    {
      /* the log's clock drives the ISO-TP timeouts: a transfer idle for
       * longer than N_Cr is reported at the first later line */
      trn_isotp_rx_result_t res;
      uint32_t now_ms = (uint32_t)(l.sec * 1000u + l.usec / 1000u);
      if (trn_isotp_rx_poll(&g_isotp, now_ms, &res) == TRN_E_TIMEOUT) {
        printf("(%" PRIu64 ".%06" PRIu32 ") isotp error %s: capture transfer idle for more than %lu ms\n", l.sec,
               l.usec, trn_isotp_err_name((trn_isotp_err_t)res.error), n_cr_ms);
        (void)trn_capture_rx_abort(&g_caprx);
        ++n.isotp_errors;
        proto_bad = 1;
      }
    }
    kind = trn_can_classify(&l.frame);
    if (kind == TRN_CAN_MSG_NONE) {
      if (l.frame.flags & TRN_CAN_FLAG_RTR) ++n.remote;
      ++n.foreign;
      continue;
    }
    ++n.ours;
    printf("(%" PRIu64 ".%06" PRIu32 ") %s %03" PRIX32 " %s ", l.sec, l.usec, l.ifname, l.frame.id,
           trn_can_msg_name(kind));
    if (kind == TRN_CAN_MSG_CAPTURE_DATA) {
      uint32_t now_ms = (uint32_t)(l.sec * 1000u + l.usec / 1000u);
      proto_bad |= capture_data(&l.frame, now_ms, &n);
    } else if (decode_simple(&l.frame, kind) != 0) {
      printf("invalid (dlc %u:", l.frame.dlc);
      for (i = 0; i < l.frame.dlc; ++i) printf(" %02X", l.frame.data[i]);
      printf(")\n");
      ++n.bad_msgs;
      proto_bad = 1;
    }
  }
  if (in != stdin) fclose(in);
  if (g_isotp.state == TRN_ISOTP_RX_RECEIVING || g_caprx.active) {
    printf("log ends inside a capture transfer: incomplete capture dropped\n");
    ++n.capture_errors;
    proto_bad = 1;
  }
  printf("summary: lines=%lu ours=%lu foreign=%lu (fd=%lu error_frames=%lu remote=%lu) malformed=%lu "
         "invalid_msgs=%lu captures_ok=%lu capture_errors=%lu isotp_errors=%lu\n",
         n.lines, n.ours, n.foreign, n.fd, n.error_frames, n.remote, n.malformed, n.bad_msgs, n.captures_ok,
         n.capture_errors, n.isotp_errors);
  if (n.malformed > 0) return 1;
  if (strict && proto_bad) return 1;
  return 0;
}
