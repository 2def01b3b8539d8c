/* SPDX-License-Identifier: Apache-2.0 */
/* tools/trn/profile_budget.h - the budget file of `trn profile`.
 *
 * A text file, one statement per line; `#` starts a comment that runs to the
 * end of the line; blank lines are ignored; fields are separated by spaces
 * or tabs:
 *
 *   scale F          host-to-target factor: target ms = host ms x F
 *                    (exactly once; finite, 0.001 .. 100000)
 *   STAGE MS         the stage's budget on the target, ms (finite, > 0,
 *                    <= 1e7); STAGE one of the names `trn profile` prints;
 *                    each stage at most once; stages left out are not
 *                    checked
 *
 * Parsing is strict: an unknown word, a missing or extra field, a number that
 * is not entirely a number, a value out of range, a repeated stage or a
 * second `scale` is an error naming the file and line (`FILE:LINE: reason`);
 * a file without `scale` is an error naming the file. */
#ifndef TRN_PROFILE_BUDGET_H
#define TRN_PROFILE_BUDGET_H

#include <stddef.h>

#define PB_MAX_STAGES 16

typedef struct {
    double scale;                    /* host-to-target factor */
    double budget_ms[PB_MAX_STAGES]; /* per stage index; < 0 = no budget */
} pb_budget_t;

/* Parse text (NUL-terminated) of the file `path` against the stage names
 * names[0..n). Returns 0 on success; otherwise 1 with a one-line reason
 * ("path:line: ...") in err. */
int pb_parse(const char *text, const char *path, const char *const *names, size_t n,
             pb_budget_t *out, char *err, size_t err_len);

/* Read and parse a file (at most 1 MiB). Same return convention. */
int pb_load(const char *path, const char *const *names, size_t n, pb_budget_t *out, char *err,
            size_t err_len);

#endif
