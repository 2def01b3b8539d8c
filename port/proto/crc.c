/* SPDX-License-Identifier: Apache-2.0 */
/* crc.c - CRC-32/ISO-HDLC, bitwise (crc.h). */
#include "trn_port/crc.h"

uint32_t trn_crc32_update(uint32_t crc, const uint8_t *data, size_t n)
{
    uint32_t c = crc; /* the parameter stays unmodified (MISRA 17.8) */
    size_t i;
    if (data == NULL) {
        return c;
    }
    for (i = 0u; i < n; ++i) {
        unsigned bit;
        c ^= (uint32_t)data[i];
        for (bit = 0u; bit < 8u; ++bit) {
            /* mask is all ones when the low bit is set */
            uint32_t mask = 0u - (c & 1u);
            c = (c >> 1) ^ (0xEDB88320u & mask);
        }
    }
    return c;
}

uint32_t trn_crc32_final(uint32_t crc) { return crc ^ 0xFFFFFFFFu; }

uint32_t trn_crc32(const uint8_t *data, size_t n)
{
    return trn_crc32_final(trn_crc32_update(TRN_CRC32_INIT, data, n));
}
