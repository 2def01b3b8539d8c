/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/cli.c - option parsing, errors, JSON and progress for `trn`. */
#define _POSIX_C_SOURCE 200809L /* isatty */
#include "cli.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "trn/version.h"

/* ------------------------------------------------------------------------ */
/* strict value parsers                                                       */
/* ------------------------------------------------------------------------ */

int cli_parse_double(const char *s, double *out)
{
    char *end = NULL;
    double v;
    if (s == NULL || *s == '\0' || *s == ' ' || *s == '\t') {
        return 0;
    }
    errno = 0;
    v = strtod(s, &end);
    if (end == s || *end != '\0' || errno == ERANGE || !isfinite(v)) {
        return 0;
    }
    *out = v;
    return 1;
}

int cli_parse_long(const char *s, long *out)
{
    char *end = NULL;
    long v;
    if (s == NULL || *s == '\0' || *s == ' ' || *s == '\t') {
        return 0;
    }
    errno = 0;
    v = strtol(s, &end, 10);
    if (end == s || *end != '\0' || errno == ERANGE) {
        return 0;
    }
    *out = v;
    return 1;
}

int cli_parse_u64(const char *s, uint64_t *out)
{
    uint64_t v = 0;
    size_t i;
    if (s == NULL || *s == '\0') {
        return 0;
    }
    for (i = 0; s[i] != '\0'; ++i) {
        unsigned d;
        if (s[i] < '0' || s[i] > '9' || i >= 20) {
            return 0;
        }
        d = (unsigned)(s[i] - '0');
        if (v > (UINT64_MAX - d) / 10u) {
            return 0; /* overflow */
        }
        v = v * 10u + d;
    }
    *out = v;
    return 1;
}

int cli_parse_xy(const char *s, double *x, double *y)
{
    char buf[128];
    const char *comma;
    size_t n;
    if (s == NULL) {
        return 0;
    }
    comma = strchr(s, ',');
    if (comma == NULL || strchr(comma + 1, ',') != NULL) {
        return 0;
    }
    n = (size_t)(comma - s);
    if (n == 0 || n >= sizeof buf) {
        return 0;
    }
    memcpy(buf, s, n);
    buf[n] = '\0';
    return cli_parse_double(buf, x) && cli_parse_double(comma + 1, y);
}

/* ------------------------------------------------------------------------ */
/* errors and usage                                                           */
/* ------------------------------------------------------------------------ */

/* Where the one-line errors go: stderr unless a binding redirected them. */
static FILE *cli_msg_stream = NULL;

void cli_set_message_stream(FILE *f) { cli_msg_stream = f; }

FILE *cli_message_stream(void) { return cli_msg_stream != NULL ? cli_msg_stream : stderr; }

int cli_fail(const char *cmd, const char *fmt, ...)
{
    va_list ap;
    FILE *out = cli_message_stream();
    fprintf(out, "trn %s: ", cmd);
    va_start(ap, fmt);
    vfprintf(out, fmt, ap);
    va_end(ap);
    fputc('\n', out);
    return CLI_BAD_INPUT;
}

static int usage_error(const cli_cmd_t *cmd, const char *what, const char *arg)
{
    fprintf(cli_message_stream(), "trn %s: %s '%s' (trn %s --help)\n", cmd->name, what, arg,
            cmd->name);
    return CLI_USAGE;
}

static void range_text(const cli_opt_t *o, char *buf, size_t n)
{
    buf[0] = '\0';
    if (o->kind == CLI_LONG) {
        snprintf(buf, n, " [%.0f..%.0f]", o->lo, o->hi);
    } else if (o->kind == CLI_DOUBLE) {
        snprintf(buf, n, " [%g..%g]", o->lo, o->hi);
    }
}

/* The default V of an option, from its variable (its value before parsing:
 * the default the command set, from the core's *_cfg_default where there is
 * one), into buf; 0 (buf "") when the help text speaks of its default itself
 * (a sentinel value meaning "chosen later") or there is none. */
static int default_value(const cli_opt_t *o, char *buf, size_t n)
{
    buf[0] = '\0';
    if (o->required || o->dst == NULL || (o->help != NULL && strstr(o->help, "default") != NULL)) {
        return 0;
    }
    switch (o->kind) {
    case CLI_LONG: snprintf(buf, n, "%ld", *(const long *)o->dst); break;
    case CLI_U64: snprintf(buf, n, "%llu", (unsigned long long)*(const uint64_t *)o->dst); break;
    case CLI_DOUBLE: snprintf(buf, n, "%g", *(const double *)o->dst); break;
    case CLI_XY:
        snprintf(buf, n, "%g,%g", ((const double *)o->dst)[0], ((const double *)o->dst)[1]);
        break;
    case CLI_STRING:
        if (*(const char *const *)o->dst != NULL) {
            snprintf(buf, n, "%s", *(const char *const *)o->dst);
        }
        break;
    case CLI_FLAG: break;
    }
    return buf[0] != '\0';
}

/* " (default V)", or "" without a default (default_value). */
static void default_text(const cli_opt_t *o, char *buf, size_t n)
{
    char v[96];
    buf[0] = '\0';
    if (default_value(o, v, sizeof v)) {
        snprintf(buf, n, " (default %s)", v);
    }
}

/* 1 if o is a positional argument ("LOG"), not an option ("--out"). */
static int is_positional(const cli_opt_t *o) { return o->name[0] != '-'; }

static void usage_line(const cli_opt_t *o, FILE *out)
{
    char head[64], range[64], dflt[128];
    snprintf(head, sizeof head, "%s%s%s", o->name, o->metavar ? " " : "",
             o->metavar ? o->metavar : "");
    range_text(o, range, sizeof range);
    default_text(o, dflt, sizeof dflt);
    fprintf(out, "  %-22s %s%s%s\n", head, o->help, dflt, range);
}

/* "trn CMD [--opt V] ... ARG\n": options first, then positional arguments;
 * returns 1 if cmd has positional arguments. */
static int cli_usage_synopsis(const cli_cmd_t *cmd, FILE *out)
{
    size_t i;
    int pass, any_pos = 0;
    fprintf(out, "trn %s", cmd->name);
    for (pass = 0; pass < 2; ++pass) {
        for (i = 0; i < cmd->n_opts; ++i) {
            const cli_opt_t *o = &cmd->opts[i];
            if (is_positional(o) != pass) {
                continue;
            }
            any_pos |= pass;
            fprintf(out, " %s%s%s%s%s", o->required ? "" : "[", o->name, o->metavar ? " " : "",
                    o->metavar ? o->metavar : "", o->required ? "" : "]");
        }
    }
    fputc('\n', out);
    return any_pos;
}

void cli_usage(const cli_cmd_t *cmd, FILE *out)
{
    size_t i;
    int any_pos;
    fprintf(out, "usage: ");
    any_pos = cli_usage_synopsis(cmd, out);
    fprintf(out, "\n%s\n\n", cmd->summary);
    if (any_pos) {
        fprintf(out, "arguments:\n");
        for (i = 0; i < cmd->n_opts; ++i) {
            if (is_positional(&cmd->opts[i])) {
                usage_line(&cmd->opts[i], out);
            }
        }
        fputc('\n', out);
    }
    fprintf(out, "options:\n");
    for (i = 0; i < cmd->n_opts; ++i) {
        if (!is_positional(&cmd->opts[i])) {
            usage_line(&cmd->opts[i], out);
        }
    }
    fprintf(out, "  %-22s %s\n", "--help", "this text");
    if (cmd->details != NULL) {
        fprintf(out, "\n%s\n", cmd->details);
    }
    fputc('\n', out);
    cli_exit_status_help(cmd->name, out);
}

/* s with '|' escaped, for a Markdown table cell. */
static void md_cell(const char *s, FILE *out)
{
    for (; s != NULL && *s != '\0'; ++s) {
        if (*s == '|') {
            fputc('\\', out);
        }
        fputc(*s, out);
    }
}

/* One table row of option o: | `name` | `METAVAR` | help | default | range | */
static void md_row(const cli_opt_t *o, FILE *out)
{
    char range[64], dflt[96];
    const char *d;
    range_text(o, range, sizeof range);
    if (default_value(o, dflt, sizeof dflt)) {
        d = dflt;
    } else if (o->required) {
        d = "required";
    } else if (o->help != NULL && strstr(o->help, "default") != NULL) {
        d = "see the description";
    } else {
        d = "-";
    }
    fprintf(out, "| `%s` | ", o->name);
    if (o->metavar != NULL) {
        fputc('`', out);
        md_cell(o->metavar, out);
        fputc('`', out);
    }
    fprintf(out, " | ");
    md_cell(o->help, out);
    fprintf(out, " | ");
    md_cell(d, out);
    fprintf(out, " | %s |\n", range[0] != '\0' ? range + 1 : "");
}

void cli_usage_markdown(const cli_cmd_t *cmd, FILE *out)
{
    size_t i;
    int pass;
    fprintf(out,
            "<!-- Generated from the option table of `trn %s` (tools/trn/), the table that prints "
            "its --help,\n     by tools/docs/gen_cli_reference.py. Do not edit: the test command "
            "checks it is current. -->\n",
            cmd->name);
    fprintf(out, "# trn %s\n\n%s\n\n## Synopsis\n\n```\n", cmd->name, cmd->summary);
    cli_usage_synopsis(cmd, out);
    fprintf(out, "```\n");
    for (pass = 1; pass >= 0; --pass) { /* positional arguments, then options */
        int any = 0;
        for (i = 0; i < cmd->n_opts; ++i) {
            const cli_opt_t *o = &cmd->opts[i];
            if (is_positional(o) != pass) {
                continue;
            }
            if (!any) {
                fprintf(out,
                        "\n## %s\n\n| %s | value | meaning | default | range |\n"
                        "| --- | --- | --- | --- | --- |\n",
                        pass ? "Arguments" : "Options", pass ? "argument" : "option");
                any = 1;
            }
            md_row(o, out);
        }
        if (!pass) {
            if (!any) {
                fprintf(out, "\n## Options\n\n| option | value | meaning | default | range |\n"
                             "| --- | --- | --- | --- | --- |\n");
            }
            fprintf(out, "| `--help` |  | this text |  |  |\n");
        }
    }
    if (cmd->details != NULL) {
        fprintf(out, "\n## Details\n\n%s\n", cmd->details);
    }
    fprintf(out, "\n## Exit status\n\n");
    cli_exit_status_help(cmd->name, out);
}

/* The commands that exit 3 (CLI_NO_RESULT), and what it means for them. */
static const struct {
    const char *cmds; /* space-separated */
    const char *meaning;
} k_exit3[] = {
    {"select field", "no informative target"},
    {"profile", "a stage over its budget (--check)"},
};

/* 1 if name is one of the space-separated words of list. */
static int in_list(const char *name, const char *list)
{
    size_t n = strlen(name);
    const char *p = list;
    while ((p = strstr(p, name)) != NULL) {
        if ((p == list || p[-1] == ' ') && (p[n] == '\0' || p[n] == ' ')) {
            return 1;
        }
        p += n;
    }
    return 0;
}

void cli_exit_status_help(const char *cmd, FILE *out)
{
    size_t i;
    fprintf(out, "exit status: 0 ok, 1 bad input (one line on stderr), 2 usage error");
    for (i = 0; i < sizeof k_exit3 / sizeof k_exit3[0]; ++i) {
        if (cmd == NULL) {
            fprintf(out, "%s%s (%s)", i == 0 ? ",\n  3 no result: " : "; ", k_exit3[i].meaning,
                    k_exit3[i].cmds);
        } else if (in_list(cmd, k_exit3[i].cmds)) {
            fprintf(out, ", 3 %s", k_exit3[i].meaning);
        }
    }
    fputc('\n', out);
}

static int set_value(const cli_cmd_t *cmd, cli_opt_t *o, const char *v)
{
    switch (o->kind) {
    case CLI_FLAG: *(int *)o->dst = 1; return CLI_OK;
    case CLI_STRING:
        if (*v == '\0') {
            return cli_fail(cmd->name, "%s: empty value", o->name);
        }
        *(const char **)o->dst = v;
        return CLI_OK;
    case CLI_LONG: {
        long x;
        if (!cli_parse_long(v, &x)) {
            return cli_fail(cmd->name, "%s: '%s' is not an integer", o->name, v);
        }
        if ((double)x < o->lo || (double)x > o->hi) {
            return cli_fail(cmd->name, "%s: %ld is out of range [%.0f..%.0f]", o->name, x, o->lo,
                            o->hi);
        }
        *(long *)o->dst = x;
        return CLI_OK;
    }
    case CLI_U64: {
        uint64_t x;
        if (!cli_parse_u64(v, &x)) {
            return cli_fail(cmd->name, "%s: '%s' is not an unsigned 64-bit integer", o->name, v);
        }
        *(uint64_t *)o->dst = x;
        return CLI_OK;
    }
    case CLI_DOUBLE: {
        double x;
        if (!cli_parse_double(v, &x)) {
            return cli_fail(cmd->name, "%s: '%s' is not a finite number", o->name, v);
        }
        if (x < o->lo || x > o->hi) {
            return cli_fail(cmd->name, "%s: %g is out of range [%g..%g]", o->name, x, o->lo, o->hi);
        }
        *(double *)o->dst = x;
        return CLI_OK;
    }
    case CLI_XY: {
        double *xy = (double *)o->dst;
        if (!cli_parse_xy(v, &xy[0], &xy[1])) {
            return cli_fail(cmd->name, "%s: '%s' is not a pair X,Y of finite numbers", o->name, v);
        }
        return CLI_OK;
    }
    }
    return cli_fail(cmd->name, "%s: internal error (option kind)", o->name);
}

cli_opt_t *cli_find(cli_opt_t *opts, size_t n, const char *name)
{
    size_t k;
    for (k = 0; k < n; ++k) {
        if (strcmp(opts[k].name, name) == 0) {
            return &opts[k];
        }
    }
    return NULL;
}

size_t cli_remove(cli_opt_t *opts, size_t n, const char *const *names)
{
    size_t k, out = 0, i;
    for (k = 0; k < n; ++k) {
        int drop = 0;
        for (i = 0; names != NULL && names[i] != NULL; ++i) {
            drop |= strcmp(opts[k].name, names[i]) == 0;
        }
        if (!drop) {
            opts[out++] = opts[k];
        }
    }
    return out;
}

/* A non-option argument a ("-" included): the next positional entry of cmd
 * takes it. For a command with positional entries "-x" is an unknown option
 * unless it comes after `--` (only_pos). */
static int take_positional(cli_cmd_t *cmd, const char *a, int only_pos)
{
    cli_opt_t *o = NULL;
    size_t k;
    int has_pos = 0, rc;
    for (k = 0; k < cmd->n_opts; ++k) {
        if (is_positional(&cmd->opts[k])) {
            has_pos = 1;
            if (o == NULL && !cmd->opts[k].seen) {
                o = &cmd->opts[k];
            }
        }
    }
    if (has_pos && !only_pos && a[0] == '-' && a[1] != '\0') {
        return usage_error(cmd, "unknown option", a);
    }
    if (o == NULL) {
        return usage_error(cmd, "unexpected argument", a);
    }
    rc = set_value(cmd, o, a);
    if (rc == CLI_OK) {
        o->seen = 1;
    }
    return rc;
}

/* Where --help writes the table as JSON instead of the usage (a binding's
 * docstrings), or NULL. */
static FILE *cli_help_json_stream = NULL;

void cli_set_help_json_stream(FILE *f) { cli_help_json_stream = f; }

static const char *kind_name(cli_kind_t k)
{
    switch (k) {
    case CLI_FLAG: return "flag";
    case CLI_STRING: return "string";
    case CLI_LONG: return "integer";
    case CLI_U64: return "u64";
    case CLI_DOUBLE: return "number";
    case CLI_XY: return "xy";
    }
    return "?";
}

void cli_help_json(const cli_cmd_t *cmd, FILE *out)
{
    json_t j;
    size_t i;
    json_begin(&j, out);
    json_str(&j, "command", cmd->name);
    json_str(&j, "summary", cmd->summary);
    json_arr(&j, "options");
    for (i = 0; i < cmd->n_opts; ++i) {
        const cli_opt_t *o = &cmd->opts[i];
        char range[64], dflt[128];
        size_t n;
        range_text(o, range, sizeof range);
        default_text(o, dflt, sizeof dflt);
        json_obj(&j, NULL);
        json_str(&j, "name", o->name);
        json_str(&j, "kind", kind_name(o->kind));
        json_str(&j, "metavar", o->metavar != NULL ? o->metavar : "");
        json_str(&j, "help", o->help != NULL ? o->help : "");
        /* the " (default V)" and " [lo..hi]" of the usage line, without their brackets */
        n = strlen(dflt);
        if (n > 11 && dflt[n - 1] == ')') {
            dflt[n - 1] = '\0';
            json_str(&j, "default", dflt + 10);
        } else {
            json_str(&j, "default", "");
        }
        n = strlen(range);
        if (n > 3 && range[n - 1] == ']') {
            range[n - 1] = '\0';
            json_str(&j, "range", range + 2);
        } else {
            json_str(&j, "range", "");
        }
        json_bool(&j, "required", o->required != 0);
        json_obj_end(&j);
    }
    json_arr_end(&j);
    json_end(&j);
}

int cli_parse(cli_cmd_t *cmd, int argc, char **argv)
{
    int i, has_pos = 0, only_pos = 0;
    size_t k;
    for (k = 0; k < cmd->n_opts; ++k) {
        cmd->opts[k].seen = 0;
        has_pos |= is_positional(&cmd->opts[k]);
    }
    /* --help anywhere (before a `--` ending the options of a command with
   * positional arguments): the usage with the defaults, before any value is set */
    for (i = 1; i < argc && !(has_pos && strcmp(argv[i], "--") == 0); ++i) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            if (cli_help_json_stream != NULL) {
                cli_help_json(cmd, cli_help_json_stream);
            } else {
                cli_usage(cmd, stdout);
            }
            return CLI_HELP;
        }
        if (strcmp(argv[i], "--help-markdown") == 0) { /* the reference page, docs/cli/ */
            cli_usage_markdown(cmd, stdout);
            return CLI_HELP;
        }
    }
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i];
        const char *eq;
        const char *val = NULL;
        size_t name_len;
        cli_opt_t *o = NULL;
        int rc;
        if (has_pos && !only_pos && strcmp(a, "--") == 0) {
            only_pos = 1; /* `--`: the rest are positional arguments */
            continue;
        }
        if (only_pos || strncmp(a, "--", 2) != 0) {
            rc = take_positional(cmd, a, only_pos);
            if (rc != CLI_OK) {
                return rc;
            }
            continue;
        }
        eq = strchr(a, '=');
        name_len = eq != NULL ? (size_t)(eq - a) : strlen(a);
        for (k = 0; k < cmd->n_opts; ++k) {
            if (strlen(cmd->opts[k].name) == name_len &&
                strncmp(cmd->opts[k].name, a, name_len) == 0) {
                o = &cmd->opts[k];
                break;
            }
        }
        if (o == NULL) {
            return usage_error(cmd, "unknown option", a);
        }
        if (o->seen) {
            return usage_error(cmd, "option given twice:", o->name);
        }
        if (o->kind == CLI_FLAG) {
            if (eq != NULL) {
                return usage_error(cmd, "option takes no value:", o->name);
            }
        } else if (eq != NULL) {
            val = eq + 1;
        } else if (i + 1 < argc) {
            val = argv[++i];
        } else {
            return usage_error(cmd, "missing value for", o->name);
        }
        rc = set_value(cmd, o, val);
        if (rc != CLI_OK) {
            return rc;
        }
        o->seen = 1;
    }
    for (k = 0; k < cmd->n_opts; ++k) {
        if (cmd->opts[k].required && !cmd->opts[k].seen) {
            return usage_error(
                cmd, is_positional(&cmd->opts[k]) ? "missing argument" : "missing required option",
                cmd->opts[k].name);
        }
    }
    return CLI_OK;
}

/* ------------------------------------------------------------------------ */
/* JSON                                                                        */
/* ------------------------------------------------------------------------ */

void json_write_string(FILE *out, const char *s)
{
    const unsigned char *p = (const unsigned char *)(s != NULL ? s : "");
    fputc('"', out);
    for (; *p != '\0'; ++p) {
        switch (*p) {
        case '"': fputs("\\\"", out); break;
        case '\\': fputs("\\\\", out); break;
        case '\n': fputs("\\n", out); break;
        case '\r': fputs("\\r", out); break;
        case '\t': fputs("\\t", out); break;
        case '\b': fputs("\\b", out); break;
        case '\f': fputs("\\f", out); break;
        default:
            if (*p < 0x20 || *p == 0x7f) {
                fprintf(out, "\\u%04x", (unsigned)*p);
            } else {
                fputc((int)*p, out); /* UTF-8 bytes pass through */
            }
        }
    }
    fputc('"', out);
}

static void json_key(json_t *j, const char *key)
{
    if (!j->first[j->depth]) {
        fputs(", ", j->out);
    }
    j->first[j->depth] = 0;
    if (key != NULL) {
        json_write_string(j->out, key);
        fputs(": ", j->out);
    }
}

void json_begin(json_t *j, FILE *out)
{
    j->out = out;
    j->depth = 0;
    j->first[0] = 1;
    fputc('{', out);
    json_str(j, "version", TRN_VERSION_STRING);
}

void json_end(json_t *j)
{
    fputs("}\n", j->out);
    fflush(j->out);
}

void json_obj(json_t *j, const char *key)
{
    json_key(j, key);
    fputc('{', j->out);
    if (j->depth + 1 < (int)(sizeof j->first / sizeof j->first[0])) {
        j->depth++;
    }
    j->first[j->depth] = 1;
}

void json_obj_end(json_t *j)
{
    fputc('}', j->out);
    if (j->depth > 0) {
        j->depth--;
    }
}

void json_arr(json_t *j, const char *key)
{
    json_key(j, key);
    fputc('[', j->out);
    if (j->depth + 1 < (int)(sizeof j->first / sizeof j->first[0])) {
        j->depth++;
    }
    j->first[j->depth] = 1;
}

void json_arr_end(json_t *j)
{
    fputc(']', j->out);
    if (j->depth > 0) {
        j->depth--;
    }
}

void json_str(json_t *j, const char *key, const char *v)
{
    json_key(j, key);
    json_write_string(j->out, v);
}

void json_num(json_t *j, const char *key, double v)
{
    json_key(j, key);
    if (isfinite(v)) {
        /* Shortest of %.15g..%.17g that reads back as the same double. */
        char buf[40];
        int prec;
        for (prec = 15; prec <= 17; ++prec) {
            snprintf(buf, sizeof buf, "%.*g", prec, v);
            if (strtod(buf, NULL) == v) {
                break;
            }
        }
        fputs(buf, j->out);
    } else {
        fputs("null", j->out);
    }
}

void json_int(json_t *j, const char *key, long long v)
{
    json_key(j, key);
    fprintf(j->out, "%lld", v);
}

void json_bool(json_t *j, const char *key, int v)
{
    json_key(j, key);
    fputs(v ? "true" : "false", j->out);
}

/* ------------------------------------------------------------------------ */
/* progress bar                                                                */
/* ------------------------------------------------------------------------ */

#define BAR_WIDTH 40

void progress_begin(progress_t *p, const char *label, long total)
{
    p->active = isatty(2) ? 1 : 0;
    p->label = label;
    p->total = total > 0 ? total : 1;
    p->last_permille = -1;
    progress_update(p, 0);
}

void progress_update(progress_t *p, long done)
{
    int permille, filled, i;
    if (!p->active) {
        return;
    }
    if (done < 0) {
        done = 0;
    }
    if (done > p->total) {
        done = p->total;
    }
    permille = (int)((double)done * 1000.0 / (double)p->total);
    if (permille == p->last_permille) {
        return;
    }
    p->last_permille = permille;
    filled = permille * BAR_WIDTH / 1000;
    fprintf(stderr, "\r%s [", p->label);
    for (i = 0; i < BAR_WIDTH; ++i) {
        fputc(i < filled ? '#' : '.', stderr);
    }
    fprintf(stderr, "] %5.1f%%", (double)permille / 10.0);
    fflush(stderr);
}

void progress_end(progress_t *p)
{
    if (!p->active) {
        return;
    }
    progress_update(p, p->total);
    fputc('\n', stderr);
    fflush(stderr);
}

void progress_lazy_init(progress_lazy_t *p, const char *label)
{
    p->label = label;
    p->begun = 0;
}

void progress_lazy_update(void *ctx, long done, long total)
{
    progress_lazy_t *p = ctx;
    if (!p->begun) {
        progress_begin(&p->bar, p->label, total);
        p->begun = 1;
    }
    p->bar.total = total > 0 ? total : 1;
    progress_update(&p->bar, done);
}

void progress_lazy_end(progress_lazy_t *p)
{
    if (p->begun) {
        progress_end(&p->bar);
    }
}
