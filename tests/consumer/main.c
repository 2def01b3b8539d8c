/* SPDX-License-Identifier: Apache-2.0 */
/* main.c - smallest user of an installed trn: checks that the public headers
 * are found as <trn/...h> and <trn_port/...h>, that the library links (static,
 * shared, or whatever pkg-config gives), that trn/version.h agrees with the
 * version the build system reported (EXPECT_VERSION), and, with
 * CONSUMER_PROTO, that libtrn_proto links too. Exit status 0 on success. */
#include <stdio.h>
#include <string.h>

#include "trn/status.h"
#include "trn/version.h"
#if defined(CONSUMER_PROTO)
#include "trn_port/crc.h"
#endif

int main(void)
{
    const char *msg = trn_strerror(TRN_E_ARG);

    if (msg == NULL || msg[0] == '\0') {
        fprintf(stderr, "trn_strerror(TRN_E_ARG) returned an empty string\n");
        return 1;
    }
    printf("trn_strerror(TRN_E_ARG) = \"%s\"\n", msg);
#if defined(EXPECT_VERSION)
    if (strcmp(TRN_VERSION_STRING, EXPECT_VERSION) != 0) {
        fprintf(stderr, "TRN_VERSION_STRING \"%s\", the package says \"%s\"\n", TRN_VERSION_STRING,
                EXPECT_VERSION);
        return 1;
    }
#endif
    printf("TRN_VERSION_STRING = \"%s\" (%d)\n", TRN_VERSION_STRING, TRN_VERSION_NUMBER);
#if defined(CONSUMER_PROTO)
    {
        /* CRC-32 (IEEE) check value of "123456789". */
        const uint8_t digits[9] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
        if (trn_crc32(digits, sizeof digits) != 0xCBF43926u) {
            fprintf(stderr, "trn_crc32 check value wrong\n");
            return 1;
        }
        printf("trn_crc32 check value ok\n");
    }
#endif
    return 0;
}
