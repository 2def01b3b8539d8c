/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/cli.h - what every `trn` subcommand shares: strict option
 * parsing from a table, the one-line error convention, a JSON writer and a
 * progress bar.
 *
 * Exit statuses (every subcommand):
 *   0  success
 *   1  bad input: a value that is not a number or is out of range, an
 *      unreadable or unsuitable file, a position off the map ...; one line
 *      `trn <cmd>: <reason>` on stderr
 *   2  usage: unknown option, option without its value, a required option
 *      missing, a stray positional argument; one line plus a pointer to --help
 *   3  no result (select, field: no informative target; profile --check: a
 *      stage over its budget)
 * `--help` / `-h` prints the subcommand's usage on stdout, with the statuses
 * that subcommand uses (cli_exit_status_help), and exits 0; `--help-markdown`
 * prints the same as the command's reference page (docs/cli/).
 *
 * Every JSON object the tool prints starts with "version" (json_begin), the
 * version of trn/version.h. */
#ifndef TRN_CLI_H
#define TRN_CLI_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#define CLI_OK 0
#define CLI_BAD_INPUT 1
#define CLI_USAGE 2
#define CLI_NO_RESULT 3
#define CLI_HELP (-1) /* cli_parse: --help was printed; exit 0 */

typedef enum {
    CLI_FLAG,   /* no value; dst is int, set to 1 */
    CLI_STRING, /* dst is const char *, points into argv */
    CLI_LONG,   /* dst is long, integer in [lo, hi] */
    CLI_U64,    /* dst is uint64_t, decimal, any value 0..2^64-1 */
    CLI_DOUBLE, /* dst is double, finite, in [lo, hi] */
    CLI_XY      /* dst is double[2], "X,Y" both finite (range not checked) */
} cli_kind_t;

/* An entry whose name does not start with '-' ("LOG") is a positional
 * argument: cli_parse fills such entries in table order from the arguments
 * that are not options ("-" included), with the same kinds and checks as an
 * option's value; `required` makes it mandatory, and `--` ends the options
 * (only for a command with positional entries). A command without them
 * rejects every non-option argument as before ("unexpected argument"). */
typedef struct {
    const char *name; /* "--out", or "LOG" for a positional argument */
    cli_kind_t kind;
    void *dst;
    double lo, hi; /* range of CLI_LONG / CLI_DOUBLE (inclusive) */
    int required;
    const char *metavar; /* "FILE.tif", "N", "X,Y" */
    const char *help;    /* one line; --help appends " (default V)" from *dst as it
                          was before parsing, unless the text says "default" */
    int seen;            /* set by cli_parse */
} cli_opt_t;

typedef struct {
    const char *name;    /* "terrain" */
    const char *summary; /* one line */
    const char *details; /* extra paragraph after the options, or NULL */
    cli_opt_t *opts;
    size_t n_opts;
} cli_cmd_t;

/* Parse argv (argv[0] is the subcommand name). Returns CLI_OK, CLI_HELP
 * (usage printed on stdout), CLI_BAD_INPUT or CLI_USAGE (message printed). */
int cli_parse(cli_cmd_t *cmd, int argc, char **argv);

/* The option named name ("--prior") among opts[0..n), or NULL: options are
 * looked up by name, never by position in a table. */
cli_opt_t *cli_find(cli_opt_t *opts, size_t n, const char *name);

/* Remove the entries named in names (NULL-terminated) from opts[0..n),
 * keeping the others in order; returns the new count. For a table built from
 * shared parts (mapopt_cli) whose options a command does not read. */
size_t cli_remove(cli_opt_t *opts, size_t n, const char *const *names);

/* Print the usage of cmd (synopsis, options with defaults and ranges). */
void cli_usage(const cli_cmd_t *cmd, FILE *out);

/* The same, as the command's Markdown reference page (docs/cli/<cmd>.md):
 * synopsis, a table of the arguments and options (value, meaning, default,
 * range), the details and the exit statuses. `trn <cmd> --help-markdown`
 * prints it (cli_parse, like --help); tools/docs/gen_cli_reference.py writes
 * the pages from it. */
void cli_usage_markdown(const cli_cmd_t *cmd, FILE *out);

/* The "exit status: ..." line(s) of `trn <cmd> --help`: 0, 1 and 2 for
 * every command, 3 with its meaning for the commands that use it. cmd NULL:
 * every status of the tool (`trn --help`). */
void cli_exit_status_help(const char *cmd, FILE *out);

/* The stream of the one-line error messages (cli_fail, cli_parse's usage
 * errors, a command's own parse errors): stderr, unless set. A binding calling
 * a command's parse in-process sets its own stream (NULL: back to stderr); the
 * setting is process-wide, so such a caller serialises its parses. */
void cli_set_message_stream(FILE *f);
FILE *cli_message_stream(void);

/* The option table of cmd as one JSON object: "command", "summary" and
 * "options", each with "name", "kind" (flag, string, integer, u64, number,
 * xy), "metavar", "help", "default" and "range" (the texts --help shows after
 * the help, without brackets; "" when it shows none) and "required". */
void cli_help_json(const cli_cmd_t *cmd, FILE *out);

/* When set (not NULL), --help writes cli_help_json into f instead of the
 * usage on stdout (cli_parse still returns CLI_HELP): how a binding reads a
 * command's table for its docstrings. Process-wide, like the message stream. */
void cli_set_help_json_stream(FILE *f);

/* Print `trn <cmd>: <reason>` (one line) on cli_message_stream() (stderr);
 * returns CLI_BAD_INPUT. */
int cli_fail(const char *cmd, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Strict parsers (exposed for tests and for commands with custom values).
 * Each returns 1 on success, 0 when the text is not entirely one value. */
int cli_parse_double(const char *s, double *out);
int cli_parse_long(const char *s, long *out);
int cli_parse_u64(const char *s, uint64_t *out);
int cli_parse_xy(const char *s, double *x, double *y);

/* ---- JSON writer: one object on one line, keys in call order. ---------- */
typedef struct {
    FILE *out;
    int depth;
    int first[8]; /* nothing written yet at this depth */
} json_t;

void json_begin(json_t *j, FILE *out);     /* {"version": TRN_VERSION_STRING */
void json_end(json_t *j);                  /* "}\n" */
void json_obj(json_t *j, const char *key); /* "key": { */
void json_obj_end(json_t *j);              /* } */
/* Arrays: json_arr(j, "key") "[", elements with key NULL (json_obj(j, NULL),
 * json_num(j, NULL, v) ...), json_arr_end "]". */
void json_arr(json_t *j, const char *key);
void json_arr_end(json_t *j);
void json_str(json_t *j, const char *key, const char *v);
void json_num(json_t *j, const char *key, double v); /* non-finite -> null */
void json_int(json_t *j, const char *key, long long v);
void json_bool(json_t *j, const char *key, int v);
/* Write s as a JSON string literal (quotes, escapes, control characters). */
void json_write_string(FILE *out, const char *s);

/* ---- progress bar on stderr, drawn only when stderr is a terminal ------- */
typedef struct {
    int active; /* isatty(2) */
    const char *label;
    long total;
    int last_permille;
} progress_t;

void progress_begin(progress_t *p, const char *label, long total);
void progress_update(progress_t *p, long done);
void progress_end(progress_t *p);

/* A bar begun on its first update: the progress callback handed to a
 * command's run (cmd_run.h), so nothing is drawn when the run fails before
 * its work starts. progress_lazy_update(ctx = progress_lazy_t *, done, total)
 * begins it with label and total, then updates; progress_lazy_end ends it if
 * it was begun. */
typedef struct {
    progress_t bar;
    const char *label;
    int begun;
} progress_lazy_t;

void progress_lazy_init(progress_lazy_t *p, const char *label);
void progress_lazy_update(void *ctx, long done, long total);
void progress_lazy_end(progress_lazy_t *p);

#endif /* TRN_CLI_H */
