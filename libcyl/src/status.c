/* SPDX-License-Identifier: BSD-3-Clause */
#include "cyl/status.h"

const char *cyl_status_str(cyl_status s)
{
    switch (s) {
    case CYL_OK: return "ok";
    case CYL_TRUNCATED: return "result truncated: caller capacity reached";
    case CYL_ERR_ARG: return "invalid argument";
    case CYL_ERR_FORMAT: return "unsupported pixel format";
    case CYL_ERR_SIZE: return "invalid image size, stride or region of interest";
    case CYL_ERR_NOMEM: return "caller memory too small";
    case CYL_ERR_CLASS: return "colour class index out of range";
    case CYL_ERR_EMPTY: return "training region empty or no colour bin above threshold";
    case CYL_ERR_UNSUPPORTED: return "feature compiled out of this build (cyl/config.h)";
    case CYL_ERR_FILE_TRUNCATED: return "table file truncated";
    case CYL_ERR_FILE_MAGIC: return "not a libcyl colour table (bad magic)";
    case CYL_ERR_FILE_VERSION: return "unsupported table file version";
    case CYL_ERR_FILE_CHECKSUM: return "table file checksum mismatch (corrupt)";
    case CYL_ERR_FILE_CORRUPT: return "table file content invalid";
    case CYL_ERR_NO_RANGE: return "ray at or above the horizon: no range";
    case CYL_ERR_NUMERIC: return "non-finite value or no convergence";
    case CYL_ERR_CAMERA: return "invalid camera description";
    }
    return "unknown status";
}
