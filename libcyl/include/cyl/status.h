/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- status codes shared by every call.
 *
 * Every libcyl function that can fail returns a cyl_status. Zero is success,
 * positive values are "success with a caveat" (the result is valid but
 * partial), negative values are errors (outputs are unspecified unless the
 * function says otherwise). cyl_status_str() gives a fixed English text.
 */
#ifndef CYL_STATUS_H
#define CYL_STATUS_H

#ifdef __cplusplus
extern "C" {
#endif

typedef enum cyl_status {
    CYL_OK = 0,                   /* success */
    CYL_TRUNCATED = 1,            /* valid but partial: caller's capacity (runs/blobs/observations) reached */

    CYL_ERR_ARG = -1,             /* NULL pointer or argument out of its documented range */
    CYL_ERR_FORMAT = -2,          /* unknown or unsupported pixel format */
    CYL_ERR_SIZE = -3,            /* image dimensions, stride or region of interest invalid */
    CYL_ERR_NOMEM = -4,           /* caller-provided memory smaller than the sizing function asks */
    CYL_ERR_CLASS = -5,           /* colour class index out of range */
    CYL_ERR_EMPTY = -6,           /* training region empty, or no UV bin passed the threshold */
    CYL_ERR_UNSUPPORTED = -7,     /* feature compiled out of this build (cyl/config.h) */

    CYL_ERR_FILE_TRUNCATED = -10, /* serialized table shorter than its format requires */
    CYL_ERR_FILE_MAGIC = -11,     /* not a libcyl colour table (magic number mismatch) */
    CYL_ERR_FILE_VERSION = -12,   /* table file of an unsupported format version */
    CYL_ERR_FILE_CHECKSUM = -13,  /* CRC-32 mismatch: the table file is corrupt */
    CYL_ERR_FILE_CORRUPT = -14,   /* well-formed checksum but invalid content (e.g. unterminated name, trailing bytes) */

    CYL_ERR_NO_RANGE = -20,       /* ray at or above the horizon: no ground range exists */
    CYL_ERR_NUMERIC = -21,        /* non-finite input or iteration did not converge */
    CYL_ERR_CAMERA = -22          /* camera description invalid (non-positive focal length, negative variance, ...) */
} cyl_status;

/* Fixed, static English description of a status code ("unknown status" for others). */
const char *cyl_status_str(cyl_status s);

#ifdef __cplusplus
}
#endif
#endif /* CYL_STATUS_H */
