/* SPDX-License-Identifier: Apache-2.0 */
/* can_log.c - parse candump -l lines (can_log.h). */
#include "can_log.h"

#include <string.h>

static int hexval(char c) {
  if (c >= '0' && c <= '9') {
    return c - '0';
  }
  if (c >= 'a' && c <= 'f') {
    return c - 'a' + 10;
  }
  if (c >= 'A' && c <= 'F') {
    return c - 'A' + 10;
  }
  return -1;
}

static void malformed(can_log_line_t *out, const char *why) {
  out->kind = CAN_LOG_MALFORMED;
  out->reason = why;
}

/* Data bytes after '#': pairs of hex digits, '.' separators allowed. */
static const char *parse_data(const char *p, trn_can_frame_t *f) {
  unsigned n = 0;
  while (*p != '\0' && *p != ' ' && *p != '\t' && *p != '\n' && *p != '\r') {
    int hi, lo;
    if (*p == '.') {
      ++p;
      continue;
    }
    hi = hexval(p[0]);
    if (hi < 0) {
      return "bad hex digit in data";
    }
    lo = hexval(p[1]);
    if (lo < 0) {
      return (p[1] == '\0' || p[1] == ' ' || p[1] == '\n' || p[1] == '\r') ? "odd number of hex digits in data"
                                                                           : "bad hex digit in data";
    }
    if (n >= 8u) {
      return "more than 8 data bytes (classic CAN)";
    }
    f->data[n++] = (uint8_t)(hi * 16 + lo);
    p += 2;
  }
  f->dlc = (uint8_t)n;
  return NULL;
}

void can_log_parse(const char *line, can_log_line_t *out) {
  const char *p = line, *q;
  uint64_t sec = 0;
  uint32_t usec = 0;
  unsigned ndig = 0, idlen = 0, frac = 0;
  uint32_t id = 0;
  size_t len;

  memset(out, 0, sizeof *out);
  out->kind = CAN_LOG_SKIP;
  while (*p == ' ' || *p == '\t') {
    ++p;
  }
  if (*p == '\0' || *p == '\n' || *p == '\r' || *p == '#') {
    return;
  }

  /* (sec.frac) */
  if (*p != '(') { malformed(out, "expected '(' and a timestamp"); return; }
  ++p;
  while (*p >= '0' && *p <= '9') {
    if (++ndig > 19) { malformed(out, "timestamp too long"); return; }
    sec = sec * 10u + (uint64_t)(*p - '0');
    ++p;
  }
  if (ndig == 0 || *p != '.') { malformed(out, "timestamp is not sec.usec"); return; }
  ++p;
  while (*p >= '0' && *p <= '9') {
    if (frac < 6) {
      usec = usec * 10u + (uint32_t)(*p - '0');
    }
    ++frac;
    ++p;
  }
  if (frac == 0) { malformed(out, "timestamp is not sec.usec"); return; }
  while (frac < 6) {
    usec *= 10u;
    ++frac;
  }
  if (*p != ')') { malformed(out, "expected ')' after the timestamp"); return; }
  ++p;
  if (*p != ' ' && *p != '\t') { malformed(out, "expected a space after the timestamp"); return; }
  while (*p == ' ' || *p == '\t') {
    ++p;
  }

  /* interface */
  q = p;
  while (*q != '\0' && *q != ' ' && *q != '\t' && *q != '\n' && *q != '\r') {
    ++q;
  }
  len = (size_t)(q - p);
  if (len == 0) { malformed(out, "missing interface name"); return; }
  if (len > 16) { malformed(out, "interface name longer than 16 characters"); return; }
  memcpy(out->ifname, p, len);
  out->ifname[len] = '\0';
  p = q;
  while (*p == ' ' || *p == '\t') {
    ++p;
  }

  /* ID#... */
  while (hexval(*p) >= 0) {
    if (++idlen > 8) { malformed(out, "CAN id longer than 8 hex digits"); return; }
    id = id * 16u + (uint32_t)hexval(*p);
    ++p;
  }
  if (idlen == 0) { malformed(out, "missing CAN id"); return; }
  if (*p != '#') { malformed(out, "expected '#' after the CAN id"); return; }
  if (idlen != 3 && idlen != 8) { malformed(out, "CAN id must have 3 (standard) or 8 (extended) hex digits"); return; }
  ++p;
  if (idlen == 8) {
    if (id & 0x20000000u) {
      out->kind = CAN_LOG_ERROR; /* CAN_ERR_FLAG */
    } else if (id > 0x1FFFFFFFu) {
      { malformed(out, "extended CAN id above 0x1FFFFFFF"); return; }
    }
    out->frame.flags |= TRN_CAN_FLAG_EXT;
    out->frame.id = id & 0x1FFFFFFFu;
  } else {
    if (id > 0x7FFu) { malformed(out, "standard CAN id above 0x7FF"); return; }
    out->frame.id = id;
  }
  if (*p == '#') {
    /* CAN FD: one flags nibble, then data (not decoded) */
    if (hexval(p[1]) < 0) { malformed(out, "CAN FD frame without its flags digit"); return; }
    out->kind = (out->kind == CAN_LOG_ERROR) ? CAN_LOG_ERROR : CAN_LOG_FD;
    p += 2;
    while (hexval(*p) >= 0 || *p == '.') {
      ++p;
    }
  } else if (*p == 'R' || *p == 'r') {
    out->frame.flags |= TRN_CAN_FLAG_RTR;
    ++p;
    if (*p >= '0' && *p <= '8') {
      out->frame.dlc = (uint8_t)(*p - '0');
      ++p;
    }
  } else {
    const char *why = parse_data(p, &out->frame);
    if (why != NULL) { malformed(out, why); return; }
    while (hexval(*p) >= 0 || *p == '.') {
      ++p;
    }
  }
  /* optional direction flag of newer candump versions, then the end */
  while (*p == ' ' || *p == '\t') {
    ++p;
  }
  if ((*p == 'R' || *p == 'T') && (p[1] == '\0' || p[1] == '\n' || p[1] == '\r' || p[1] == ' ')) {
    ++p;
  }
  while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n') {
    ++p;
  }
  if (*p != '\0') { malformed(out, "unexpected characters after the frame"); return; }
  out->sec = sec;
  out->usec = usec;
  if (out->kind == CAN_LOG_SKIP) {
    out->kind = CAN_LOG_FRAME;
  }
}
