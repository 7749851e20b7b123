/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl -- image views: a description of caller-owned YUV pixel memory.
 *
 * libcyl never copies or owns pixels. A cyl_image says where the planes are,
 * how they are laid out and how many bytes separate two rows (the stride).
 *
 * Pixel sampling convention: pixel (x, y) is column x (0 = left) of row y
 * (0 = top); its centre is at integer coordinates (x, y).
 */
#ifndef CYL_IMAGE_H
#define CYL_IMAGE_H

#include <stddef.h>
#include <stdint.h>
#include "cyl/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Largest accepted width or height, px (run coordinates are 16-bit). */
#define CYL_MAX_DIM 16383u

typedef enum cyl_pixfmt {
    CYL_FMT_YUYV = 1,    /* packed 4:2:2, bytes Y0 U Y1 V (V4L2 YUYV / YUY2); plane 0 only */
    CYL_FMT_UYVY = 2,    /* packed 4:2:2, bytes U Y0 V Y1 (V4L2 UYVY); plane 0 only */
    CYL_FMT_NV12 = 3,    /* planar Y (plane 0) + interleaved UV at half width and height (plane 1) */
    CYL_FMT_I420 = 4,    /* planar Y, U, V (planes 0, 1, 2); U and V at half width and height (V4L2 YU12) */
    CYL_FMT_YUV444P = 5  /* planar Y, U, V, all at full resolution (mainly for tests) */
} cyl_pixfmt;

typedef struct cyl_image {
    cyl_pixfmt format;         /* layout of the planes */
    uint32_t width;            /* px, 1..CYL_MAX_DIM (odd widths allowed: the last chroma sample is shared) */
    uint32_t height;           /* px, 1..CYL_MAX_DIM (odd heights allowed for 4:2:0) */
    const uint8_t *plane[3];   /* plane base pointers; unused planes NULL */
    size_t stride[3];          /* bytes from one row of a plane to the next, >= the row's payload bytes */
} cyl_image;

/* Region of interest, in px of the full image. width == 0 or height == 0 means the whole image. */
typedef struct cyl_roi {
    uint32_t x;       /* first column, px */
    uint32_t y;       /* first row, px */
    uint32_t width;   /* columns, px (0 = whole image) */
    uint32_t height;  /* rows, px (0 = whole image) */
} cyl_roi;

/* Fill *img for a frame in one contiguous buffer with the usual V4L2 layout:
 * packed formats use stride (0 means width rounded up to even * 2 bytes);
 * planar formats put the planes one after another with the given luma stride
 * (0 means width) and chroma strides derived from it. Returns CYL_ERR_SIZE on
 * bad dimensions. */
cyl_status cyl_image_wrap(cyl_image *img, cyl_pixfmt format, uint32_t width, uint32_t height,
                          const uint8_t *data, size_t stride);

/* Bytes a contiguous frame of this format needs with cyl_image_wrap()'s layout
 * (0 on bad dimensions or overflow). */
size_t cyl_image_buffer_size(cyl_pixfmt format, uint32_t width, uint32_t height, size_t stride);

/* Check an image view: known format, dimensions in range, planes present,
 * strides large enough for a row. Returns CYL_OK, CYL_ERR_FORMAT, CYL_ERR_SIZE or CYL_ERR_ARG. */
cyl_status cyl_image_check(const cyl_image *img);

/* Read the Y, U, V values of one pixel (no bounds check beyond the image's own). */
cyl_status cyl_image_pixel(const cyl_image *img, uint32_t x, uint32_t y,
                           uint8_t *Y, uint8_t *U, uint8_t *V);

#ifdef __cplusplus
}
#endif
#endif /* CYL_IMAGE_H */
