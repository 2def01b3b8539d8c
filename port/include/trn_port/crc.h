/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file crc.h
 * @brief CRC-32 of a stereo capture (docs/can-protocol.md, "Capture CRC").
 *
 * The CRC is CRC-32/ISO-HDLC (the Ethernet / zlib CRC): polynomial
 * 0x04C11DB7 processed LSB-first (reflected, 0xEDB88320), initial value
 * 0xFFFFFFFF, final XOR 0xFFFFFFFF. Check value: CRC of the nine ASCII
 * bytes "123456789" is 0xCBF43926. Computed bitwise (no table): pure,
 * no state, the same on every byte order.
 */
#ifndef TRN_PORT_CRC_H
#define TRN_PORT_CRC_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Initial running value for trn_crc32_update. */
#define TRN_CRC32_INIT 0xFFFFFFFFu

/**
 * @brief Feed bytes into a running CRC-32 (reflected register, not yet
 * final-XORed). Start with TRN_CRC32_INIT, finish with trn_crc32_final.
 * @param[in] crc  running value.
 * @param[in] data n bytes; may be NULL only when n == 0.
 * @param[in] n    number of bytes.
 * @return the new running value (crc unchanged when data is NULL).
 */
uint32_t trn_crc32_update(uint32_t crc, const uint8_t *data, size_t n);

/**
 * @brief Final XOR of a running CRC-32: the value carried on the wire.
 * @param[in] crc running value.
 * @return crc ^ 0xFFFFFFFF.
 */
uint32_t trn_crc32_final(uint32_t crc);

/**
 * @brief CRC-32 of one buffer (update from TRN_CRC32_INIT, then final).
 * @param[in] data n bytes (may be NULL when n == 0).
 * @param[in] n    number of bytes.
 * @return the CRC-32 as carried on the wire.
 */
uint32_t trn_crc32(const uint8_t *data, size_t n);

#ifdef __cplusplus
}
#endif
#endif /* TRN_PORT_CRC_H */
