/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file status.h
 * @brief The one error convention of trn: every fallible function returns a
 * trn_status_t, TRN_OK (0) on success and a negative named code otherwise.
 */
#ifndef TRN_STATUS_H
#define TRN_STATUS_H

#ifdef __cplusplus
extern "C" {
#endif

/** Status codes. New codes are appended; values never change meaning. */
typedef enum {
    TRN_OK = 0,      /**< success */
    TRN_E_NULL = -1, /**< a required pointer argument was NULL */
    TRN_E_ARG = -2,  /**< a parameter is out of its documented range (or NaN) */
    TRN_E_SIZE = -3, /**< a dimension is zero, too large, or inconsistent */
    TRN_E_WORKSPACE =
        -4, /**< the caller's buffer is smaller than the sizing function says, or not TRN_WS_ALIGN-aligned */
    TRN_E_NODATA = -5,     /**< the input holds no usable data (all missing / nothing occupied) */
    TRN_E_RANGE = -6,      /**< a position or pose window lies off the map */
    TRN_E_ILLCOND = -7,    /**< the likelihood peak is flat or ridge-shaped: no finite covariance */
    TRN_E_CAPACITY = -8,   /**< more items than the caller-provided capacity */
    TRN_E_NOTARGET = -9,   /**< no informative landmark exists */
    TRN_E_TIMEOUT = -10,   /**< a port operation timed out */
    TRN_E_CRC = -11,       /**< a checksum did not match */
    TRN_E_SEQ = -12,       /**< a sequence number was out of order */
    TRN_E_BUS = -13,       /**< bus error (bus-off, error-passive, overflow) */
    TRN_E_IO = -14,        /**< an operating-system call failed (port layer only) */
    TRN_E_FORMAT = -15,    /**< malformed message or record */
    TRN_E_CANCELLED = -16, /**< the caller's progress callback asked to stop */
    TRN_E_AMBIGUOUS =
        -17, /**< a match was found, but its failure probability is above the acceptance limit: not a fix */
    TRN_E_BUDGET = -18 /**< the search's node budget ran out before it could prove its answer */
} trn_status_t;

/**
 * @brief A short, constant, human-readable description of a status.
 * @param[in] status any value (unknown values give "unknown status").
 * @return a static NUL-terminated string; never NULL.
 */
const char *trn_strerror(trn_status_t status);

#ifdef __cplusplus
}
#endif
#endif /* TRN_STATUS_H */
