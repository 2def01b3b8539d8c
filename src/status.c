/* SPDX-License-Identifier: Apache-2.0 */
/* status.c - names of the trn status codes. */
#include "trn/status.h"

const char *trn_strerror(trn_status_t status)
{
    switch (status) {
    case TRN_OK: return "ok";
    case TRN_E_NULL: return "null pointer argument";
    case TRN_E_ARG: return "parameter out of range";
    case TRN_E_SIZE: return "dimension zero, too large or inconsistent";
    case TRN_E_WORKSPACE: return "workspace too small";
    case TRN_E_NODATA: return "no usable data";
    case TRN_E_RANGE: return "position or pose window off the map";
    case TRN_E_ILLCOND: return "likelihood peak flat or ridge-shaped (ill-conditioned)";
    case TRN_E_CAPACITY: return "capacity exceeded";
    case TRN_E_NOTARGET: return "no informative target";
    case TRN_E_TIMEOUT: return "timeout";
    case TRN_E_CRC: return "checksum mismatch";
    case TRN_E_SEQ: return "sequence error";
    case TRN_E_BUS: return "bus error";
    case TRN_E_IO: return "operating-system call failed";
    case TRN_E_FORMAT: return "malformed message or record";
    case TRN_E_CANCELLED: return "cancelled by the caller";
    case TRN_E_AMBIGUOUS: return "match ambiguous (failure probability above the acceptance limit)";
    case TRN_E_BUDGET: return "search node budget exhausted";
    default: return "unknown status";
    }
}
