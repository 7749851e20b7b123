/* SPDX-License-Identifier: BSD-3-Clause */
#include "cyl/config.h"
#include "cyl/image.h"
#include "internal.h"

/* Bytes of payload in one row of plane k. */
static size_t row_bytes(cyl_pixfmt f, uint32_t w, int k)
{
    size_t half = ((size_t)w + 1u) / 2u;
    switch (f) {
    case CYL_FMT_YUYV:
    case CYL_FMT_UYVY: return k == 0 ? 4u * half : 0u;
    case CYL_FMT_NV12: return k == 0 ? (size_t)w : (k == 1 ? 2u * half : 0u);
    case CYL_FMT_I420: return k == 0 ? (size_t)w : half;
    case CYL_FMT_YUV444P: return (size_t)w;
    }
    return 0;
}

/* Planes of format f; 0 for a format unknown or compiled out (CYL_CONFIG_FORMATS). */
static int n_planes(cyl_pixfmt f)
{
    if ((unsigned)f > 31u || !(CYL_CONFIG_FORMATS & CYL_FORMAT_BIT(f))) return 0;
    switch (f) {
    case CYL_FMT_YUYV: case CYL_FMT_UYVY: return 1;
    case CYL_FMT_NV12: return 2;
    case CYL_FMT_I420: case CYL_FMT_YUV444P: return 3;
    }
    return 0;
}

static uint32_t plane_rows(cyl_pixfmt f, uint32_t h, int k)
{
    if (k > 0 && (f == CYL_FMT_NV12 || f == CYL_FMT_I420)) return (h + 1u) / 2u;
    return h;
}

cyl_status cyl_image_check(const cyl_image *img)
{
    int k, np;
    if (!img) return CYL_ERR_ARG;
    np = n_planes(img->format);
    if (np == 0) return CYL_ERR_FORMAT;
    if (img->width == 0 || img->height == 0 || img->width > CYL_MAX_DIM || img->height > CYL_MAX_DIM)
        return CYL_ERR_SIZE;
    for (k = 0; k < np; k++) {
        if (!img->plane[k]) return CYL_ERR_ARG;
        if (img->stride[k] < row_bytes(img->format, img->width, k)) return CYL_ERR_SIZE;
    }
    return CYL_OK;
}

/* Strides and plane offsets of the contiguous layout; returns total size or 0. */
static size_t layout(cyl_pixfmt f, uint32_t w, uint32_t h, size_t stride, size_t st[3], size_t off[3])
{
    int k, np = n_planes(f);
    size_t total = 0;
    if (np == 0 || w == 0 || h == 0 || w > CYL_MAX_DIM || h > CYL_MAX_DIM) return 0;
    if (stride == 0) stride = row_bytes(f, w, 0);
    if (stride < row_bytes(f, w, 0) || stride > ((size_t)1 << 28)) return 0;
    for (k = 0; k < 3; k++) { st[k] = 0; off[k] = 0; }
    for (k = 0; k < np; k++) {
        /* Plane 0 and YUV444's chroma planes have the given stride; NV12's UV rows are as wide
         * as the Y rows (+1 byte for odd widths); I420's are half (the V4L2 YU12 convention). */
        size_t s = stride;
        if (k > 0 && f == CYL_FMT_NV12 && s < row_bytes(f, w, 1)) s = row_bytes(f, w, 1);
        if (k > 0 && f == CYL_FMT_I420) s = (stride + 1u) / 2u;
        if (s < row_bytes(f, w, k)) return 0;
        st[k] = s;
        off[k] = total;
        total += s * plane_rows(f, h, k); /* stride < 2^28, rows < 2^14: no overflow */
    }
    return total;
}

size_t cyl_image_buffer_size(cyl_pixfmt format, uint32_t width, uint32_t height, size_t stride)
{
    size_t st[3], off[3];
    return layout(format, width, height, stride, st, off);
}

cyl_status cyl_image_wrap(cyl_image *img, cyl_pixfmt format, uint32_t width, uint32_t height,
                          const uint8_t *data, size_t stride)
{
    size_t st[3], off[3];
    int k, np;
    if (!img || !data) return CYL_ERR_ARG;
    np = n_planes(format);
    if (np == 0) return CYL_ERR_FORMAT;
    if (layout(format, width, height, stride, st, off) == 0) return CYL_ERR_SIZE;
    img->format = format;
    img->width = width;
    img->height = height;
    for (k = 0; k < 3; k++) {
        img->plane[k] = k < np ? data + off[k] : 0;
        img->stride[k] = k < np ? st[k] : 0;
    }
    return CYL_OK;
}

cyl_status cyl_image_pixel(const cyl_image *img, uint32_t x, uint32_t y,
                           uint8_t *Y, uint8_t *U, uint8_t *V)
{
    cyl_status s = cyl_image_check(img);
    if (s != CYL_OK) return s;
    if (x >= img->width || y >= img->height || !Y || !U || !V) return CYL_ERR_ARG;
    cyl_pixel_fetch(img, x, y, Y, U, V);
    return CYL_OK;
}

int cyl_roi_resolve(const cyl_image *img, const cyl_roi *roi, cyl_roi *out)
{
    if (!roi || roi->width == 0 || roi->height == 0) {
        out->x = 0; out->y = 0; out->width = img->width; out->height = img->height;
        return 1;
    }
    if (roi->x >= img->width || roi->y >= img->height) return 0;
    if (roi->width > img->width - roi->x || roi->height > img->height - roi->y) return 0;
    *out = *roi;
    return 1;
}
