/* SPDX-License-Identifier: Apache-2.0 */
/* main.c - smallest user of an installed trn: checks that the public header is
 * found as <trn/status.h> and that libtrn.a links. Exit status 0 on success. */
#include <stdio.h>

#include "trn/status.h"

int main(void)
{
    const char *msg = trn_strerror(TRN_E_ARG);

    if (msg == NULL || msg[0] == '\0') {
        fprintf(stderr, "trn_strerror(TRN_E_ARG) returned an empty string\n");
        return 1;
    }
    printf("trn_strerror(TRN_E_ARG) = \"%s\"\n", msg);
    return 0;
}
