/* SPDX-License-Identifier: Apache-2.0 */
/* tests/cli/test_cli_util.c - the `trn` option parsers, JSON writer and
 * option table (tools/trn/cli.[ch]). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "cli.h"
#include "trn/version.h"

static void test_parse_double(void **state)
{
    double v = 0.0;
    (void)state;
    assert_true(cli_parse_double("0.25", &v) && v == 0.25);
    assert_true(cli_parse_double("-1e3", &v) && v == -1000.0);
    assert_false(cli_parse_double("", &v));
    assert_false(cli_parse_double("1.5m", &v));
    assert_false(cli_parse_double(" 1", &v));
    assert_false(cli_parse_double("nan", &v));
    assert_false(cli_parse_double("inf", &v));
    assert_false(cli_parse_double("1e999", &v));
    assert_false(cli_parse_double(NULL, &v));
}

static void test_parse_integers(void **state)
{
    long l = 0;
    uint64_t u = 0;
    (void)state;
    assert_true(cli_parse_long("-42", &l) && l == -42);
    assert_false(cli_parse_long("4.0", &l));
    assert_false(cli_parse_long("99999999999999999999999", &l));
    assert_true(cli_parse_u64("18446744073709551615", &u) && u == UINT64_MAX);
    assert_false(cli_parse_u64("18446744073709551616", &u));
    assert_false(cli_parse_u64("-1", &u));
    assert_false(cli_parse_u64("+1", &u));
    assert_false(cli_parse_u64("", &u));
}

static void test_parse_xy(void **state)
{
    double x = 0.0, y = 0.0;
    (void)state;
    assert_true(cli_parse_xy("1014.5,-2.25", &x, &y) && x == 1014.5 && y == -2.25);
    assert_false(cli_parse_xy("1,2,3", &x, &y));
    assert_false(cli_parse_xy("1", &x, &y));
    assert_false(cli_parse_xy(",2", &x, &y));
    assert_false(cli_parse_xy("1,", &x, &y));
    assert_false(cli_parse_xy("1;2", &x, &y));
    assert_false(cli_parse_xy("1,nan", &x, &y));
}

/* Everything the writer printed, from a temporary file. */
static void slurp(FILE *f, char *buf, size_t n)
{
    size_t got;
    rewind(f);
    got = fread(buf, 1, n - 1, f);
    buf[got] = '\0';
}

static void test_json(void **state)
{
    char buf[512];
    json_t j;
    FILE *f = tmpfile();
    (void)state;
    assert_non_null(f);
    json_begin(&j, f);
    json_str(&j, "s", "a\"b\\c\nd\te\001f");
    json_num(&j, "x", 0.1);
    json_num(&j, "nan", NAN);
    json_num(&j, "inf", -INFINITY);
    json_int(&j, "n", -7);
    json_bool(&j, "t", 1);
    json_obj(&j, "o");
    json_num(&j, "y", 1e-300);
    json_obj_end(&j);
    json_end(&j);
    slurp(f, buf, sizeof buf);
    fclose(f);
    /* json_begin writes the version first: every JSON object of `trn` has it. */
    assert_string_equal(
        buf,
        "{\"version\": \"" TRN_VERSION_STRING
        "\", \"s\": \"a\\\"b\\\\c\\nd\\te\\u0001f\", \"x\": 0.1, \"nan\": null, \"inf\": null, "
        "\"n\": -7, \"t\": true, \"o\": {\"y\": 1e-300}}\n");
}

static void test_exit_status_help(void **state)
{
    char buf[512];
    FILE *f = tmpfile();
    (void)state;
    assert_non_null(f);
    cli_exit_status_help("terrain", f);
    slurp(f, buf, sizeof buf);
    fclose(f);
    assert_string_equal(buf,
                        "exit status: 0 ok, 1 bad input (one line on stderr), 2 usage error\n");
    f = tmpfile();
    assert_non_null(f);
    cli_exit_status_help("select", f);
    slurp(f, buf, sizeof buf);
    fclose(f);
    assert_non_null(strstr(buf, ", 3 no informative target\n"));
    f = tmpfile();
    assert_non_null(f);
    cli_exit_status_help(NULL, f); /* trn --help: every status */
    slurp(f, buf, sizeof buf);
    fclose(f);
    assert_non_null(strstr(buf, "0 ok"));
    assert_non_null(strstr(buf, "2 usage error"));
    assert_non_null(strstr(buf, "3 no result"));
    assert_non_null(strstr(buf, "no informative target (select field)"));
    assert_non_null(strstr(buf, "over its budget (--check) (profile)"));
    f = tmpfile();
    assert_non_null(f);
    cli_exit_status_help("fiel", f); /* whole words only */
    slurp(f, buf, sizeof buf);
    fclose(f);
    assert_null(strstr(buf, ", 3 "));
}

static void test_option_table(void **state)
{
    const char *out = NULL;
    long n = 5;
    double c = 1.0, xy[2] = {0, 0};
    int flag = 0;
    cli_opt_t opts[] = {
        {"--out", CLI_STRING, &out, 0, 0, 1, "F", "out", 0},
        {"--n", CLI_LONG, &n, 1, 10, 0, "N", "n", 0},
        {"--c", CLI_DOUBLE, &c, 0.5, 2.0, 0, "C", "c", 0},
        {"--xy", CLI_XY, xy, 0, 0, 0, "X,Y", "xy", 0},
        {"--flag", CLI_FLAG, &flag, 0, 0, 0, NULL, "flag", 0},
    };
    cli_cmd_t cmd = {"t", "test", NULL, opts, 5};
    char *ok[] = {"t", "--out", "f.tif", "--n=7", "--c", "2", "--xy", "3,4", "--flag"};
    char *range[] = {"t", "--out", "f", "--n", "11"};
    char *unknown[] = {"t", "--out", "f", "--m", "1"};
    char *missing[] = {"t", "--n", "3"};
    char *novalue[] = {"t", "--out"};
    (void)state;
    assert_int_equal(cli_parse(&cmd, 9, ok), CLI_OK);
    assert_string_equal(out, "f.tif");
    assert_true(n == 7 && c == 2.0 && xy[0] == 3.0 && xy[1] == 4.0 && flag == 1);
    assert_int_equal(cli_parse(&cmd, 5, range), CLI_BAD_INPUT);
    assert_int_equal(n, 7); /* unchanged on error */
    assert_int_equal(cli_parse(&cmd, 5, unknown), CLI_USAGE);
    assert_int_equal(cli_parse(&cmd, 3, missing), CLI_USAGE);
    assert_int_equal(cli_parse(&cmd, 2, novalue), CLI_USAGE);
}

/* Positional entries (a name without '-'): filled in table order, "-" is an
 * argument, "-x" an unknown option, "--" ends the options, too many or too
 * few are usage errors; a table without them rejects any argument. */
static void test_positional(void **state)
{
    const char *in = NULL, *out = NULL;
    long n = 1;
    int flag = 0;
    cli_opt_t opts[] = {
        {"--n", CLI_LONG, &n, 1, 10, 0, "N", "n", 0},
        {"--flag", CLI_FLAG, &flag, 0, 0, 0, NULL, "flag", 0},
        {"IN", CLI_STRING, &in, 0, 0, 1, NULL, "input", 0},
        {"OUT", CLI_STRING, &out, 0, 0, 0, NULL, "output", 0},
    };
    cli_cmd_t cmd = {"t", "test", NULL, opts, 4};
    char *both[] = {"t", "a.log", "--n", "3", "b.out", "--flag"};
    char *stdin_arg[] = {"t", "-"};
    char *dashdash[] = {"t", "--flag", "--", "--n", "-y"};
    char *three[] = {"t", "a", "b", "c"};
    char *none[] = {"t", "--flag"};
    char *single_dash[] = {"t", "-x", "a"};
    char *empty[] = {"t", ""};
    char *by_name[] = {"t", "--IN", "a"};
    char buf[2048];
    FILE *f;
    cli_opt_t plain[] = {{"--n", CLI_LONG, &n, 1, 10, 0, "N", "n", 0}};
    cli_cmd_t no_pos = {"u", "test", NULL, plain, 1};
    char *stray[] = {"u", "a"};
    char *stray_dash[] = {"u", "--"};
    (void)state;
    assert_int_equal(cli_parse(&cmd, 6, both), CLI_OK);
    assert_string_equal(in, "a.log");
    assert_string_equal(out, "b.out");
    assert_true(n == 3 && flag == 1 && opts[2].seen && opts[3].seen);
    out = NULL;
    assert_int_equal(cli_parse(&cmd, 2, stdin_arg), CLI_OK);
    assert_string_equal(in, "-");
    assert_null(out);
    assert_false(opts[3].seen);
    assert_int_equal(cli_parse(&cmd, 5, dashdash), CLI_OK);
    assert_string_equal(in, "--n");
    assert_string_equal(out, "-y");
    assert_int_equal(cli_parse(&cmd, 4, three), CLI_USAGE);
    assert_int_equal(cli_parse(&cmd, 2, none), CLI_USAGE);
    assert_int_equal(cli_parse(&cmd, 3, single_dash), CLI_USAGE);
    assert_int_equal(cli_parse(&cmd, 2, empty), CLI_BAD_INPUT);
    assert_int_equal(cli_parse(&cmd, 3, by_name), CLI_USAGE);
    assert_ptr_equal(cli_find(opts, 4, "IN"), &opts[2]);
    assert_int_equal(cli_parse(&no_pos, 2, stray), CLI_USAGE);
    assert_int_equal(cli_parse(&no_pos, 2, stray_dash), CLI_USAGE);
    /* usage: options, then the arguments ([OUT]: optional); an arguments list */
    f = tmpfile();
    assert_non_null(f);
    cli_usage(&cmd, f);
    slurp(f, buf, sizeof buf);
    fclose(f);
    assert_non_null(strstr(buf, "usage: trn t [--n N] [--flag] IN [OUT]\n"));
    assert_non_null(strstr(buf, "arguments:\n  IN "));
    assert_non_null(strstr(buf, "options:\n  --n N"));
    f = tmpfile();
    assert_non_null(f);
    cli_usage(&no_pos, f);
    slurp(f, buf, sizeof buf);
    fclose(f);
    assert_null(strstr(buf, "arguments:"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse_double),     cmocka_unit_test(test_parse_integers),
        cmocka_unit_test(test_parse_xy),         cmocka_unit_test(test_json),
        cmocka_unit_test(test_exit_status_help), cmocka_unit_test(test_option_table),
        cmocka_unit_test(test_positional),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
