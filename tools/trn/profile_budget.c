/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/profile_budget.c - see profile_budget.h. */
#include "profile_budget.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

#define PB_MAX_LINE 1024
#define PB_MAX_FIELDS 3

static int fail(char *err, size_t err_len, const char *path, long line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

static int fail(char *err, size_t err_len, const char *path, long line, const char *fmt, ...)
{
    va_list ap;
    int k = line > 0 ? snprintf(err, err_len, "%s:%ld: ", path, line)
                     : snprintf(err, err_len, "%s: ", path);
    if (k < 0 || (size_t)k >= err_len) {
        return 1;
    }
    va_start(ap, fmt);
    vsnprintf(err + k, err_len - (size_t)k, fmt, ap);
    va_end(ap);
    return 1;
}

/* Split a line (comment already cut) into at most PB_MAX_FIELDS fields in
 * place; returns the number of fields, PB_MAX_FIELDS + 1 if there are more. */
static int split(char *s, char **f)
{
    int n = 0;
    while (*s != '\0') {
        while (*s == ' ' || *s == '\t' || *s == '\r') {
            *s++ = '\0';
        }
        if (*s == '\0') {
            break;
        }
        if (n == PB_MAX_FIELDS) {
            return PB_MAX_FIELDS + 1;
        }
        f[n++] = s;
        while (*s != '\0' && *s != ' ' && *s != '\t' && *s != '\r') {
            ++s;
        }
    }
    return n;
}

int pb_parse(const char *text, const char *path, const char *const *names, size_t n,
             pb_budget_t *out, char *err, size_t err_len)
{
    const char *p = text;
    long line = 0;
    long scale_line = 0;
    long seen_line[PB_MAX_STAGES];
    size_t i;

    if (n > PB_MAX_STAGES) {
        return fail(err, err_len, path, 0, "internal: too many stages");
    }
    out->scale = 0.0;
    for (i = 0; i < PB_MAX_STAGES; ++i) {
        out->budget_ms[i] = -1.0;
        seen_line[i] = 0;
    }
    while (*p != '\0') {
        char buf[PB_MAX_LINE + 1];
        char *f[PB_MAX_FIELDS];
        const char *eol = strchr(p, '\n');
        size_t len = eol != NULL ? (size_t)(eol - p) : strlen(p);
        char *hash;
        int nf;
        double v;

        ++line;
        if (len > PB_MAX_LINE) {
            return fail(err, err_len, path, line, "line longer than %d characters", PB_MAX_LINE);
        }
        memcpy(buf, p, len);
        buf[len] = '\0';
        p = eol != NULL ? eol + 1 : p + len;
        hash = strchr(buf, '#');
        if (hash != NULL) {
            *hash = '\0';
        }
        nf = split(buf, f);
        if (nf == 0) {
            continue;
        }
        if (nf != 2) {
            return fail(err, err_len, path, line,
                        "expected two fields ('scale F' or 'STAGE MS'), got %s",
                        nf == 1 ? "one" : "more than two");
        }
        if (!cli_parse_double(f[1], &v)) {
            return fail(err, err_len, path, line, "'%s' is not a number", f[1]);
        }
        if (strcmp(f[0], "scale") == 0) {
            if (scale_line != 0) {
                return fail(err, err_len, path, line, "second 'scale' (first on line %ld)",
                            scale_line);
            }
            if (!(v >= 0.001 && v <= 100000.0)) {
                return fail(err, err_len, path, line, "scale %s outside 0.001 .. 100000", f[1]);
            }
            out->scale = v;
            scale_line = line;
            continue;
        }
        for (i = 0; i < n; ++i) {
            if (strcmp(f[0], names[i]) == 0) {
                break;
            }
        }
        if (i == n) {
            char known[512];
            size_t k, used = 0;
            known[0] = '\0';
            for (k = 0; k < n && used < sizeof known; ++k) {
                int w = snprintf(known + used, sizeof known - used, "%s%s", k ? ", " : "",
                                 names[k]);
                if (w < 0) {
                    break;
                }
                used += (size_t)w;
            }
            return fail(err, err_len, path, line, "unknown stage '%s' (known: scale, %s)", f[0],
                        known);
        }
        if (seen_line[i] != 0) {
            return fail(err, err_len, path, line, "stage '%s' again (first on line %ld)", f[0],
                        seen_line[i]);
        }
        if (!(v > 0.0 && v <= 1e7)) {
            return fail(err, err_len, path, line, "budget %s ms of '%s' outside (0, 1e7]", f[1],
                        f[0]);
        }
        out->budget_ms[i] = v;
        seen_line[i] = line;
    }
    if (scale_line == 0) {
        return fail(err, err_len, path, 0, "no 'scale F' line (the host-to-target factor)");
    }
    return 0;
}

int pb_load(const char *path, const char *const *names, size_t n, pb_budget_t *out, char *err,
            size_t err_len)
{
    FILE *fp = fopen(path, "rb");
    char *text;
    size_t got;
    int rc;
    if (fp == NULL) {
        return fail(err, err_len, path, 0, "cannot open");
    }
    text = malloc((size_t)(1u << 20) + 1u);
    if (text == NULL) {
        fclose(fp);
        return fail(err, err_len, path, 0, "out of memory");
    }
    got = fread(text, 1, (size_t)1u << 20, fp);
    if (ferror(fp) || (got == ((size_t)1u << 20) && fgetc(fp) != EOF)) {
        int too_big = !ferror(fp);
        free(text);
        fclose(fp);
        return fail(err, err_len, path, 0, too_big ? "larger than 1 MiB" : "read error");
    }
    fclose(fp);
    text[got] = '\0';
    if (strlen(text) != got) {
        free(text);
        return fail(err, err_len, path, 0, "contains a NUL byte (not a text file)");
    }
    rc = pb_parse(text, path, names, n, out, err, err_len);
    free(text);
    return rc;
}
