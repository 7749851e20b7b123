/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl internal helpers (not installed). */
#ifndef CYL_INTERNAL_H
#define CYL_INTERNAL_H

#include <stddef.h>
#include <stdint.h>
#include "cyl/image.h"
#include "cyl/segment.h"

/* Little-endian field access for the file formats (host-order independent). */
static inline void cyl_put_u16(uint8_t *p, uint16_t v) { p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); }
static inline void cyl_put_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); p[2] = (uint8_t)(v >> 16); p[3] = (uint8_t)(v >> 24);
}
static inline uint16_t cyl_get_u16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }
static inline uint32_t cyl_get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

/* Resolve a ROI against an image: NULL or zero size = whole image. Returns 0 if it does not fit. */
int cyl_roi_resolve(const cyl_image *img, const cyl_roi *roi, cyl_roi *out);

/* Round a pointer up to an alignment (power of two). */
static inline void *cyl_align_ptr(void *p, size_t a)
{
    uintptr_t u = (uintptr_t)p;
    return (void *)((u + (a - 1u)) & ~(uintptr_t)(a - 1u));
}

/* Y, U, V of pixel (x, y) of a checked image; no bounds checks. */
static inline void cyl_pixel_fetch(const cyl_image *img, uint32_t x, uint32_t y,
                                   uint8_t *Y, uint8_t *U, uint8_t *V)
{
    const uint8_t *r0 = img->plane[0] + (size_t)y * img->stride[0], *r1, *r2;
    switch (img->format) {
    case CYL_FMT_YUYV:
        *Y = r0[2u * x]; *U = r0[4u * (x / 2u) + 1u]; *V = r0[4u * (x / 2u) + 3u];
        return;
    case CYL_FMT_UYVY:
        *Y = r0[2u * x + 1u]; *U = r0[4u * (x / 2u)]; *V = r0[4u * (x / 2u) + 2u];
        return;
    case CYL_FMT_NV12:
        r1 = img->plane[1] + (size_t)(y / 2u) * img->stride[1];
        *Y = r0[x]; *U = r1[2u * (x / 2u)]; *V = r1[2u * (x / 2u) + 1u];
        return;
    case CYL_FMT_I420:
        r1 = img->plane[1] + (size_t)(y / 2u) * img->stride[1];
        r2 = img->plane[2] + (size_t)(y / 2u) * img->stride[2];
        *Y = r0[x]; *U = r1[x / 2u]; *V = r2[x / 2u];
        return;
    case CYL_FMT_YUV444P:
        r1 = img->plane[1] + (size_t)y * img->stride[1];
        r2 = img->plane[2] + (size_t)y * img->stride[2];
        *Y = r0[x]; *U = r1[x]; *V = r2[x];
        return;
    }
    *Y = *U = *V = 0;
}

/* A segmentation's sampling grid: image coordinate = grid cell * step + remainder, and the grid
 * columns and rows it sampled. */
typedef struct cyl_grid {
    uint32_t sx, sy;           /* grid steps, px */
    uint32_t rx, ry;           /* remainders, px */
    int32_t gx_lo, gx_hi;      /* sampled grid columns */
    int32_t gy_lo, gy_hi;      /* sampled grid rows */
} cyl_grid;

/* The grid of seg, which must have been made from a frame of img's size: 0 if it was not (or its
 * steps are 0), 1 with *g filled. */
static inline int cyl_grid_of(const cyl_segmentation *seg, const cyl_image *img, cyl_grid *g)
{
    if (seg->frame_width != img->width || seg->frame_height != img->height || seg->x_last >= img->width ||
        seg->y_last >= img->height || seg->x_step == 0 || seg->y_step == 0)
        return 0;
    g->sx = seg->x_step;
    g->sy = seg->y_step;
    g->rx = seg->x_origin % g->sx;
    g->ry = seg->y_origin % g->sy;
    g->gx_lo = (int32_t)(seg->x_origin / g->sx);
    g->gx_hi = (int32_t)(seg->x_last / g->sx);
    g->gy_lo = (int32_t)(seg->y_origin / g->sy);
    g->gy_hi = (int32_t)(seg->y_last / g->sy);
    return 1;
}

#endif
