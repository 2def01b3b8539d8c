/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/main.c - the `trn` host command line: `trn <subcommand> ...`.
 *
 * Subcommands are listed in commands.def (one line each) and live in
 * cmd_<name>.c. This file only dispatches. */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "trn/trn.h"
#include "trn/version.h"

typedef struct {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *summary;
} command_t;

static int cmd_version(int argc, char **argv);

static const command_t k_commands[] = {
#define TRN_COMMAND(sym, name, summary) {name, trn_cmd_##sym, summary},
#include "commands.def"
#undef TRN_COMMAND
    {"version", cmd_version, "print the trn version"},
};

#define N_COMMANDS (sizeof k_commands / sizeof k_commands[0])

static void usage(FILE *out)
{
    size_t i;
    fprintf(
        out,
        "usage: trn <command> [options]   (trn <command> --help for its options)\n\ncommands:\n");
    for (i = 0; i < N_COMMANDS; ++i) {
        fprintf(out, "  %-12s %s\n", k_commands[i].name, k_commands[i].summary);
    }
    fprintf(out, "\noptions:\n  --version    print the trn version (also `trn version`)\n"
                 "  --help       this text\n\n");
    cli_exit_status_help(NULL, out);
}

/* `trn --help-markdown`: the index of the command-line reference
 * (docs/cli/README.md), one line per command linking its page. */
static void usage_markdown(FILE *out)
{
    size_t i;
    fprintf(out, "<!-- Generated from tools/trn/commands.def by tools/docs/gen_cli_reference.py "
                 "(`trn --help-markdown`).\n     Do not edit: the test command checks it is "
                 "current. -->\n");
    fprintf(out, "# The `trn` command line\n\n`trn <command> [options]`; `trn <command> --help` "
                 "prints the same as its page.\nPositions `X,Y` are map metres from the DEM's "
                 "geotransform; every DEM argument is any raster\nGDAL reads (band 1 by default; "
                 "no-data and NaN mean \"not seen\"); `--json` prints one JSON object\nwhose "
                 "first key is `\"version\"`.\n\n| command | what it does |\n| --- | --- |\n");
    for (i = 0; i < N_COMMANDS; ++i) {
        if (k_commands[i].run == cmd_version) {
            fprintf(out, "| `%s` | %s |\n", k_commands[i].name, k_commands[i].summary);
        } else {
            fprintf(out, "| [`%s`](%s.md) | %s |\n", k_commands[i].name, k_commands[i].name,
                    k_commands[i].summary);
        }
    }
    fprintf(out, "\nOptions of `trn` itself: `--version` (also `trn version`), `--help`.\n\n"
                 "## Exit status\n\n");
    cli_exit_status_help(NULL, out);
}

static int cmd_version(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    printf("trn %s\n", TRN_VERSION_STRING);
    return 0;
}

int main(int argc, char **argv)
{
    size_t i;
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0 ||
        strcmp(argv[1], "help") == 0) {
        usage(stdout);
        return 0;
    }
    if (strcmp(argv[1], "--help-markdown") == 0) {
        usage_markdown(stdout);
        return 0;
    }
    if (strcmp(argv[1], "--version") == 0) {
        return cmd_version(argc - 1, argv + 1);
    }
    for (i = 0; i < N_COMMANDS; ++i) {
        if (strcmp(argv[1], k_commands[i].name) == 0) {
            return k_commands[i].run(argc - 1, argv + 1);
        }
    }
    fprintf(stderr, "trn: unknown command '%s' (trn --help lists them)\n", argv[1]);
    return 2;
}
