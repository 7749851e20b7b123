/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- colour classes and the colour lookup table (paper section 3.2-3.3).
 *
 * A pixel (Y, U, V) belongs to the set of classes whose bits are set in
 *
 *     mask = uv[U][V] & y[Y]
 *
 * uv is a 256x256 table of class bitmasks over chrominance; y is a 256-entry
 * vector of class bitmasks over brightness, so that each class has its own
 * brightness window (the paper's single window is the case where every class
 * has the same one). Class i is bit (1 << i). When a pixel matches several
 * classes, the lowest index wins (class 0 has the highest priority).
 *
 * The table is a plain struct of about 66 KiB owned by the caller (static,
 * stack or heap); nothing here allocates.
 */
#ifndef CYL_COLORTABLE_H
#define CYL_COLORTABLE_H

#include <stddef.h>
#include <stdint.h>
#include "cyl/status.h"
#include "cyl/image.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CYL_MAX_CLASSES 8      /* classes per table: one bit each of a uint8_t mask */
#define CYL_CLASS_NAME_LEN 16  /* bytes of a class name including the terminating NUL */
#define CYL_CLASS_NONE 0xFFu   /* class index of a pixel that matches no class */

typedef uint8_t cyl_mask;      /* bit i set = class i */

typedef struct cyl_colortable {
    cyl_mask uv[256][256];                            /* class bits by chrominance, indexed [U][V] */
    cyl_mask y[256];                                  /* class bits by brightness, indexed [Y] */
    char name[CYL_MAX_CLASSES][CYL_CLASS_NAME_LEN];   /* NUL-terminated class names ("" = unused) */
    uint8_t rgb[CYL_MAX_CLASSES][3];                  /* display colour of each class (overlays), 0..255 */
} cyl_colortable;

/* Empty table: no class matches any pixel, names empty, display colours grey. */
void cyl_colortable_init(cyl_colortable *t);

/* Set a class's name (truncated to CYL_CLASS_NAME_LEN-1 bytes) and display colour. */
cyl_status cyl_colortable_set_class(cyl_colortable *t, unsigned cls, const char *name,
                                    uint8_t r, uint8_t g, uint8_t b);

/* Index of the class with this exact name, or -1. */
int cyl_colortable_find_class(const cyl_colortable *t, const char *name);

/* Remove every bit of class cls from uv and y (its name and colour stay). */
cyl_status cyl_colortable_clear_class(cyl_colortable *t, unsigned cls);

/* Add an axis-aligned box to class cls: U in [u_lo, u_hi], V in [v_lo, v_hi],
 * Y in [y_lo, y_hi] (inclusive; CMVision-style thresholds). The UV rectangle and
 * the Y window are OR-ed into the table. */
cyl_status cyl_colortable_add_box(cyl_colortable *t, unsigned cls,
                                  uint8_t y_lo, uint8_t y_hi,
                                  uint8_t u_lo, uint8_t u_hi,
                                  uint8_t v_lo, uint8_t v_hi);

/* Class mask of one YUV value. */
static inline cyl_mask cyl_colortable_mask(const cyl_colortable *t, uint8_t Y, uint8_t U, uint8_t V)
{
    return (cyl_mask)(t->uv[U][V] & t->y[Y]);
}

/* Index of the lowest set bit of a mask, or CYL_CLASS_NONE for 0. */
unsigned cyl_mask_class(cyl_mask m);

/* Classify pixels into a caller buffer of class indices (CYL_CLASS_NONE for
 * none): out[r * out_stride + c] for the c-th sample of the r-th sampled row of
 * the ROI (roi NULL = whole image), sampling every x_step-th column and
 * y_step-th row (steps >= 1). Used for overlays and training feedback;
 * cyl_segment() does not need it. */
cyl_status cyl_classify(const cyl_colortable *t, const cyl_image *img, const cyl_roi *roi,
                        unsigned x_step, unsigned y_step, uint8_t *out, size_t out_stride);

/* ---- training from an image region (paper section 3.3) ---------------- */

typedef struct cyl_train_params {
    uint32_t min_bin_count;     /* a UV bin must hold at least this many region pixels (default 2) */
    double min_bin_fraction;    /* ... and at least this fraction of the region's pixels (default 0.002) */
    uint8_t uv_margin;          /* the bounding rectangle of surviving bins is grown by this many bins per side (default 3) */
    double y_lo_fraction;       /* Y window from this quantile of the surviving pixels' brightness (default 0.01) */
    double y_hi_fraction;       /* ... to this quantile (default 0.99) */
    uint8_t y_margin;           /* and widened by this many levels each side (default 16) */
} cyl_train_params;

/* The defaults above. */
cyl_train_params cyl_train_params_default(void);

/* Bytes of workspace cyl_colortable_train() needs (a UV and a Y histogram). */
size_t cyl_train_workspace_size(void);

/* Train class cls from the pixels of img inside region (NULL = whole image):
 * build the UV histogram, drop bins under the threshold, fill the bounding
 * rectangle of the surviving bins grown by uv_margin, and set the class's Y
 * window from the brightness quantiles of the surviving pixels. Adds to what
 * the class already has, so repeated calls over several images accumulate.
 * work must be at least cyl_train_workspace_size() bytes, aligned for uint32_t.
 * If box is not NULL it receives the rectangle and window added
 * (u_lo, u_hi, v_lo, v_hi, y_lo, y_hi). Returns CYL_ERR_EMPTY if no bin survives. */
cyl_status cyl_colortable_train(cyl_colortable *t, unsigned cls, const cyl_image *img,
                                const cyl_roi *region, const cyl_train_params *params,
                                void *work, size_t work_size, uint8_t box[6]);

/* ---- table files ---------------------------------------------------------
 * Format "CYLT" version 1, little-endian, fixed size CYL_TABLE_FILE_SIZE bytes:
 *   offset     size   field
 *   0          4      magic "CYLT"
 *   4          2      format version (1)
 *   6          1      number of classes (8)
 *   7          1      reserved (0)
 *   8          160    8 x { name[16] NUL-terminated, rgb[3], reserved[1] }
 *   168        256    y[256] class masks
 *   424        65536  uv[256][256] class masks, U-major
 *   65960      4      CRC-32 (IEEE 802.3, as zlib's crc32) of bytes 0..65959
 * The core only (de)serialises to memory; the tools read and write files. */
#define CYL_TABLE_FILE_VERSION 1u
#define CYL_TABLE_FILE_SIZE 65964u

/* Serialise into buf (cap >= CYL_TABLE_FILE_SIZE); *len receives the byte count. */
cyl_status cyl_colortable_save(const cyl_colortable *t, uint8_t *buf, size_t cap, size_t *len);

/* Parse a serialised table. On any error *t is left untouched. Errors:
 * CYL_ERR_FILE_TRUNCATED, _MAGIC, _VERSION, _CHECKSUM, _CORRUPT. */
cyl_status cyl_colortable_load(cyl_colortable *t, const uint8_t *buf, size_t len);

/* CRC-32 (IEEE) of a buffer, continuing from crc (start with 0). */
uint32_t cyl_crc32(uint32_t crc, const uint8_t *buf, size_t len);

#ifdef __cplusplus
}
#endif
#endif /* CYL_COLORTABLE_H */
