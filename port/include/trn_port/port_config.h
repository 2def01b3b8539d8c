/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file port_config.h
 * @brief Compile-time maxima of the port layer's protocol code (port/proto).
 *
 * Same scheme as trn/trn_config.h: if TRN_PORT_USER_CONFIG_H is defined,
 * that header is read first and may override any value; every value here is
 * a guarded default; an inconsistent value stops the build with #error.
 */
#ifndef TRN_PORT_CONFIG_H
#define TRN_PORT_CONFIG_H

#ifdef TRN_PORT_USER_CONFIG_H
#include TRN_PORT_USER_CONFIG_H
#endif

/**
 * Largest number of range points in one stereo capture (the reassembly
 * buffer and the decoded capture are sized from it). 6 bytes per point on
 * the wire and 6 decoded; default 4096 points = 24.6 kB
 * wire buffer + 24.6 kB decoded. It sizes trn_capture_t and
 * trn_capture_rx_t, so every file that includes capture.h must see the
 * same value: set it for the whole build (CMake cache variable
 * TRN_PORT_MAX_CAPTURE_POINTS, which port/proto adds as a PUBLIC define).
 */
#ifndef TRN_PORT_MAX_CAPTURE_POINTS
#define TRN_PORT_MAX_CAPTURE_POINTS 4096
#endif

#if TRN_PORT_MAX_CAPTURE_POINTS < 1 || TRN_PORT_MAX_CAPTURE_POINTS > 65535
#error "TRN_PORT_MAX_CAPTURE_POINTS must be in [1, 65535] (uint16 point count on the wire)"
#endif

#endif /* TRN_PORT_CONFIG_H */
