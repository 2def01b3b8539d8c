/* SPDX-License-Identifier: Apache-2.0 */
/* can_log.c - parse candump -l lines (can_log.h). */
#include "can_log.h"

#include <string.h>

static int hexval(char c)
{
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

static void malformed(can_log_line_t *out, const char *why)
{
    out->kind = CAN_LOG_MALFORMED;
    out->reason = why;
}

/* Data bytes after '#': pairs of hex digits, '.' separators allowed. */
static const char *parse_data(const char *p, trn_can_frame_t *f)
{
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
            return (p[1] == '\0' || p[1] == ' ' || p[1] == '\n' || p[1] == '\r')
                       ? "odd number of hex digits in data"
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

static const char *skip_blanks(const char *p)
{
    while (*p == ' ' || *p == '\t') {
        ++p;
    }
    return p;
}

/* "(sec.frac)" and the blanks after it; *pp moves past them. NULL, or why not. */
static const char *parse_stamp(const char **pp, uint64_t *sec, uint32_t *usec)
{
    const char *p = *pp;
    unsigned ndig = 0, frac = 0;
    *sec = 0;
    *usec = 0;
    if (*p != '(') {
        return "expected '(' and a timestamp";
    }
    ++p;
    while (*p >= '0' && *p <= '9') {
        if (++ndig > 19) {
            return "timestamp too long";
        }
        *sec = *sec * 10u + (uint64_t)(*p - '0');
        ++p;
    }
    if (ndig == 0 || *p != '.') {
        return "timestamp is not sec.usec";
    }
    ++p;
    while (*p >= '0' && *p <= '9') {
        if (frac < 6) {
            *usec = *usec * 10u + (uint32_t)(*p - '0');
        }
        ++frac;
        ++p;
    }
    if (frac == 0) {
        return "timestamp is not sec.usec";
    }
    while (frac < 6) {
        *usec *= 10u;
        ++frac;
    }
    if (*p != ')') {
        return "expected ')' after the timestamp";
    }
    ++p;
    if (*p != ' ' && *p != '\t') {
        return "expected a space after the timestamp";
    }
    *pp = skip_blanks(p);
    return NULL;
}

/* The interface name and the blanks after it. */
static const char *parse_ifname(const char **pp, can_log_line_t *out)
{
    const char *p = *pp, *q = p;
    size_t len;
    while (*q != '\0' && *q != ' ' && *q != '\t' && *q != '\n' && *q != '\r') {
        ++q;
    }
    len = (size_t)(q - p);
    if (len == 0) {
        return "missing interface name";
    }
    if (len > 16) {
        return "interface name longer than 16 characters";
    }
    memcpy(out->ifname, p, len);
    out->ifname[len] = '\0';
    *pp = skip_blanks(q);
    return NULL;
}

/* "ID#": the identifier (3 or 8 hex digits), its flags and the kind of an
 * error frame; *pp moves past the '#'. */
static const char *parse_id(const char **pp, can_log_line_t *out)
{
    const char *p = *pp;
    unsigned idlen = 0;
    uint32_t id = 0;
    while (hexval(*p) >= 0) {
        if (++idlen > 8) {
            return "CAN id longer than 8 hex digits";
        }
        id = id * 16u + (uint32_t)hexval(*p);
        ++p;
    }
    if (idlen == 0) {
        return "missing CAN id";
    }
    if (*p != '#') {
        return "expected '#' after the CAN id";
    }
    if (idlen != 3 && idlen != 8) {
        return "CAN id must have 3 (standard) or 8 (extended) hex digits";
    }
    ++p;
    if (idlen == 8) {
        if (id & 0x20000000u) {
            out->kind = CAN_LOG_ERROR; /* CAN_ERR_FLAG */
        } else if (id > 0x1FFFFFFFu) {
            return "extended CAN id above 0x1FFFFFFF";
        }
        out->frame.flags |= TRN_CAN_FLAG_EXT;
        out->frame.id = id & 0x1FFFFFFFu;
    } else {
        if (id > 0x7FFu) {
            return "standard CAN id above 0x7FF";
        }
        out->frame.id = id;
    }
    *pp = p;
    return NULL;
}

/* What follows "ID#": CAN FD (flags, data not decoded), a remote request
 * with its optional DLC, or data; then the optional direction flag of newer
 * candump versions and the end of the line. */
static const char *parse_payload(const char *p, can_log_line_t *out)
{
    if (*p == '#') {
        if (hexval(p[1]) < 0) {
            return "CAN FD frame without its flags digit";
        }
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
        if (why != NULL) {
            return why;
        }
        while (hexval(*p) >= 0 || *p == '.') {
            ++p;
        }
    }
    p = skip_blanks(p);
    if ((*p == 'R' || *p == 'T') && (p[1] == '\0' || p[1] == '\n' || p[1] == '\r' || p[1] == ' ')) {
        ++p;
    }
    while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n') {
        ++p;
    }
    if (*p != '\0') {
        return "unexpected characters after the frame";
    }
    return NULL;
}

void can_log_parse(const char *line, can_log_line_t *out)
{
    const char *p, *why;
    uint64_t sec;
    uint32_t usec;

    memset(out, 0, sizeof *out);
    out->kind = CAN_LOG_SKIP;
    p = skip_blanks(line);
    if (*p == '\0' || *p == '\n' || *p == '\r' || *p == '#') {
        return;
    }
    if ((why = parse_stamp(&p, &sec, &usec)) != NULL || (why = parse_ifname(&p, out)) != NULL ||
        (why = parse_id(&p, out)) != NULL || (why = parse_payload(p, out)) != NULL) {
        malformed(out, why);
        return;
    }
    out->sec = sec;
    out->usec = usec;
    if (out->kind == CAN_LOG_SKIP) {
        out->kind = CAN_LOG_FRAME;
    }
}
