/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- colour classes and the colour lookup table (paper section 3.2-3.3).
 *
 * A pixel (Y, U, V) belongs to the set of classes whose bits are set in
 *
 *     mask = uv[U][V] & y[Y] & yuv[Y >> 3][U >> 2][V >> 2]
 *
 * uv is a 256x256 table of class bitmasks over chrominance; y is a 256-entry
 * vector of class bitmasks over brightness, so that each class has its own
 * brightness window (the paper's single window is the case where every class
 * has the same one). yuv is a quantised 3-D table (32 brightness x 64 x 64
 * chroma cells) in which a class's chroma may depend on brightness, as real
 * colours do under changing illumination; the learned classes of
 * cyl/colorlearn.h live there. A class made of boxes (the paper's method,
 * cyl_colortable_add_box) keeps its bit set in every yuv cell; a learned class
 * keeps its bit set in every y entry and its uv bits are the yuv cells'
 * projection, so the uv table alone still says which chroma can be coloured
 * (the segmentation's background skip reads only uv).
 * Class i is bit (1 << i). When a pixel matches several classes, the lowest
 * index wins (class 0 has the highest priority); learning resolves overlaps
 * between learned classes by likelihood before they reach the table.
 *
 * The table is a plain struct of about 193 KiB owned by the caller (static,
 * stack, heap or const in flash); nothing here allocates.
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

/* The 3-D table's quantisation: Y >> CYL_YUV_YSHIFT, U and V >> CYL_YUV_CSHIFT. */
#define CYL_YUV_YSHIFT 3u
#define CYL_YUV_CSHIFT 2u
#define CYL_YUV_NY (256u >> CYL_YUV_YSHIFT)   /* 32 brightness cells, 8 levels each */
#define CYL_YUV_NC (256u >> CYL_YUV_CSHIFT)   /* 64 cells per chroma axis, 4 levels each */
#define CYL_YUV_CELLS (CYL_YUV_NY * CYL_YUV_NC * CYL_YUV_NC)  /* 131072 */

typedef struct cyl_colortable {
    cyl_mask uv[256][256];                            /* class bits by chrominance, indexed [U][V] */
    cyl_mask y[256];                                  /* class bits by brightness, indexed [Y] */
    cyl_mask yuv[CYL_YUV_NY][CYL_YUV_NC][CYL_YUV_NC]; /* class bits by quantised colour, indexed
                                                         [Y >> 3][U >> 2][V >> 2] (all ones for box classes) */
    uint8_t lookup;                                   /* CYL_LOOKUP_* bits: which parts of the rule can
                                                         reject a pixel (segmentation skips the others);
                                                         kept by every function here; after writing uv, y
                                                         or yuv directly, call cyl_colortable_refresh() */
    uint8_t weak_of[CYL_MAX_CLASSES];                 /* CYL_CLASS_NONE, or the class whose weak evidence
                                                         this class is: segmentation joins its pixels to
                                                         that class's blobs where they touch and drops
                                                         them elsewhere (hysteresis; see cyl/segment.h) */
    cyl_mask live;                                    /* classes that can match some pixel; read only when
                                                         lookup is CYL_LOOKUP_YUV alone (set by
                                                         cyl_colortable_refresh()) */
    uint8_t chroma_any[2][16];                        /* coarse chroma map for the vector background skip:
                                                         bit (U >> 4) & 7 of chroma_any[U >> 7][V >> 4] is
                                                         set when some uv[U'][V'] with U' >> 4 == U >> 4 and
                                                         V' >> 4 == V >> 4 is non-zero (16x16 blocks of 16
                                                         levels); a superset is correct, a missing bit is
                                                         not; kept by every function here and by
                                                         cyl_colortable_refresh() */
    uint8_t inner_lo[CYL_MAX_CLASSES][3];             /* a box of colours certainly of each class, for the
                                                         vector run extension: every (Y, U, V) with
                                                         inner_lo[c][k] <= (Y, U, V)[k] <= inner_hi[c][k]
                                                         (k = 0, 1, 2) has class c (the lowest bit of its
                                                         mask); empty (a lo above its hi) when not known.
                                                         A smaller box is correct, a larger one is not. Set
                                                         by cyl_colortable_refresh(); the editing functions
                                                         here empty the boxes an edit may invalidate */
    uint8_t inner_hi[CYL_MAX_CLASSES][3];             /* the box's upper corner (Y, U, V), inclusive */
    char name[CYL_MAX_CLASSES][CYL_CLASS_NAME_LEN];   /* NUL-terminated class names ("" = unused) */
    uint8_t rgb[CYL_MAX_CLASSES][3];                  /* display colour of each class (overlays), 0..255 */
} cyl_colortable;

#define CYL_LOOKUP_UV_Y 1u   /* uv[U][V] & y[Y] can reject a pixel the 3-D table accepts */
#define CYL_LOOKUP_YUV 2u    /* the 3-D table can reject a pixel */

/* Empty table: no class matches any pixel (uv and y zero, yuv all ones), names
 * empty, display colours grey. */
void cyl_colortable_init(cyl_colortable *t);

/* Set a class's name (truncated to CYL_CLASS_NAME_LEN-1 bytes) and display colour. */
cyl_status cyl_colortable_set_class(cyl_colortable *t, unsigned cls, const char *name,
                                    uint8_t r, uint8_t g, uint8_t b);

/* Index of the class with this exact name, or -1. */
int cyl_colortable_find_class(const cyl_colortable *t, const char *name);

/* Make class weak the weak evidence of class strong (CYL_CLASS_NONE: an ordinary class
 * again). A weak class cannot itself have a weak class, nor be its own. CYL_ERR_CLASS,
 * CYL_ERR_ARG. */
cyl_status cyl_colortable_set_weak(cyl_colortable *t, unsigned weak, unsigned strong);

/* Remove class cls's colours: its bits in uv and y are cleared and its yuv bits
 * set again, so that it matches nothing and boxes can be added afresh (its name
 * and colour stay). */
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
    return (cyl_mask)(t->uv[U][V] & t->y[Y] &
                      t->yuv[Y >> CYL_YUV_YSHIFT][U >> CYL_YUV_CSHIFT][V >> CYL_YUV_CSHIFT]);
}

/* 1 if any class has a brightness-dependent (3-D) part, i.e. some yuv cell is not all ones. */
int cyl_colortable_has_yuv(const cyl_colortable *t);

/* Recompute t->lookup, t->live, t->chroma_any and the inner boxes from the table's contents
 * (after editing uv, y or yuv by hand, and after cyl_colortable_add_box() for the fastest
 * segmentation: adding a box empties the inner boxes of the classes after it, which is correct
 * but leaves their runs to the exact per-pixel test; loading a table file refreshes it).
 * A lookup field with extra bits set is still correct, only slower; one with a bit
 * missing makes segmentation disagree with cyl_colortable_mask(). */
void cyl_colortable_refresh(cyl_colortable *t);

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
 * Format "CYLT", little-endian. Version 1, fixed size CYL_TABLE_FILE_SIZE bytes:
 *   offset     size   field
 *   0          4      magic "CYLT"
 *   4          2      format version (1)
 *   6          1      number of classes (8)
 *   7          1      reserved (0)
 *   8          160    8 x { name[16] NUL-terminated, rgb[3], reserved[1] (0) }
 *   168        256    y[256] class masks
 *   424        65536  uv[256][256] class masks, U-major
 *   65960      4      CRC-32 (IEEE 802.3, as zlib's crc32) of bytes 0..65959
 * The core only (de)serialises to memory; the tools read and write files. */
#define CYL_TABLE_FILE_VERSION 1u
#define CYL_TABLE_FILE_SIZE 65964u

/* Version 2 (CYL_TABLE_FILE_SIZE_V2 bytes) is version 1 with each class record's
 * last byte holding 1 + weak_of (0: an ordinary class) and the 3-D table
 * inserted before the CRC:
 *   65960      131072 yuv[32][64][64] class masks, Y-major, then U, then V
 *   197032     4      CRC-32 of bytes 0..197031
 * A version-1 file loads as a table whose yuv cells are all ones. */
#define CYL_TABLE_FILE_VERSION_V2 2u
#define CYL_TABLE_FILE_SIZE_V2 197036u
#define CYL_TABLE_FILE_MAX_SIZE CYL_TABLE_FILE_SIZE_V2   /* the largest file any version has */

/* Serialise into buf: version 1 when no class has a 3-D part or weak class (so older readers
 * still load it), version 2 otherwise. cap must be at least the size written
 * (CYL_TABLE_FILE_MAX_SIZE always suffices); *len receives the byte count. */
cyl_status cyl_colortable_save(const cyl_colortable *t, uint8_t *buf, size_t cap, size_t *len);

/* Parse a serialised table, version 1 or 2. On any error *t is left untouched. Errors:
 * CYL_ERR_FILE_TRUNCATED, _MAGIC, _VERSION, _CHECKSUM, _CORRUPT. */
cyl_status cyl_colortable_load(cyl_colortable *t, const uint8_t *buf, size_t len);

/* CRC-32 (IEEE) of a buffer, continuing from crc (start with 0). */
uint32_t cyl_crc32(uint32_t crc, const uint8_t *buf, size_t len);

#ifdef __cplusplus
}
#endif
#endif /* CYL_COLORTABLE_H */
