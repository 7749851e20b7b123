/* SPDX-License-Identifier: BSD-3-Clause */
#include "synth_frames.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

int canvas_alloc(canvas *c, uint32_t w, uint32_t h)
{
    size_t n = (size_t)w * h;
    c->w = w; c->h = h;
    c->y = (uint8_t *)malloc(n ? n : 1);
    c->u = (uint8_t *)malloc(n ? n : 1);
    c->v = (uint8_t *)malloc(n ? n : 1);
    if (!c->y || !c->u || !c->v) { canvas_free(c); return 0; }
    return 1;
}

void canvas_free(canvas *c)
{
    free(c->y); free(c->u); free(c->v);
    c->y = c->u = c->v = NULL;
}

void canvas_fill(canvas *c, uint8_t Y, uint8_t U, uint8_t V)
{
    size_t n = (size_t)c->w * c->h;
    memset(c->y, Y, n); memset(c->u, U, n); memset(c->v, V, n);
}

void canvas_rect(canvas *c, int32_t x, int32_t y, int32_t w, int32_t h, uint8_t Y, uint8_t U, uint8_t V)
{
    int32_t i, j;
    for (j = y < 0 ? 0 : y; j < y + h && j < (int32_t)c->h; j++)
        for (i = x < 0 ? 0 : x; i < x + w && i < (int32_t)c->w; i++) {
            size_t k = (size_t)j * c->w + (size_t)i;
            c->y[k] = Y; c->u[k] = U; c->v[k] = V;
        }
}

void canvas_ellipse(canvas *c, double cx, double cy, double ax, double ay, uint8_t Y, uint8_t U, uint8_t V)
{
    uint32_t i, j;
    for (j = 0; j < c->h; j++)
        for (i = 0; i < c->w; i++) {
            double dx = ((double)i - cx) / ax, dy = ((double)j - cy) / ay;
            if (dx * dx + dy * dy <= 1.0) {
                size_t k = (size_t)j * c->w + i;
                c->y[k] = Y; c->u[k] = U; c->v[k] = V;
            }
        }
}

static uint8_t clamp8(double v)
{
    if (v < 0) return 0;
    if (v > 255) return 255;
    return (uint8_t)(v + 0.5);
}

void canvas_noise(canvas *c, test_rng *r, double sigma_y, double sigma_c)
{
    size_t k, n = (size_t)c->w * c->h;
    for (k = 0; k < n; k++) {
        if (sigma_y > 0) c->y[k] = clamp8(c->y[k] + sigma_y * test_rng_normal(r));
        if (sigma_c > 0) {
            c->u[k] = clamp8(c->u[k] + sigma_c * test_rng_normal(r));
            c->v[k] = clamp8(c->v[k] + sigma_c * test_rng_normal(r));
        }
    }
}

void canvas_speckle(canvas *c, test_rng *r, double p, const uint8_t (*colours)[3], unsigned n)
{
    size_t k, np = (size_t)c->w * c->h;
    for (k = 0; k < np; k++)
        if (test_rng_uniform(r) < p) {
            unsigned i = (unsigned)test_rng_int(r, 0, (int64_t)n - 1);
            c->y[k] = colours[i][0]; c->u[k] = colours[i][1]; c->v[k] = colours[i][2];
        }
}

size_t canvas_format_size(const canvas *c, cyl_pixfmt fmt, size_t stride)
{
    return cyl_image_buffer_size(fmt, c->w, c->h, stride);
}

/* Rounded mean chroma over the pixels of block (bx, by) of size sx x sy. */
static uint8_t block_mean(const canvas *c, const uint8_t *p, uint32_t bx, uint32_t by, uint32_t sx, uint32_t sy)
{
    uint32_t i, j, n = 0, s = 0;
    for (j = by * sy; j < (by + 1) * sy && j < c->h; j++)
        for (i = bx * sx; i < (bx + 1) * sx && i < c->w; i++) { s += p[(size_t)j * c->w + i]; n++; }
    return (uint8_t)((s + n / 2) / n);
}

int canvas_to_format(const canvas *c, cyl_pixfmt fmt, size_t stride, uint8_t pad,
                     uint8_t *buf, size_t cap, cyl_image *img)
{
    size_t need = canvas_format_size(c, fmt, stride);
    uint32_t x, y;
    if (need == 0 || cap < need) return 0;
    memset(buf, pad, need);
    if (cyl_image_wrap(img, fmt, c->w, c->h, buf, stride) != CYL_OK) return 0;
    for (y = 0; y < c->h; y++) {
        uint8_t *r0 = (uint8_t *)img->plane[0] + (size_t)y * img->stride[0];
        for (x = 0; x < c->w; x++) {
            size_t k = (size_t)y * c->w + x;
            switch (fmt) {
            case CYL_FMT_YUYV:
                r0[2 * x] = c->y[k];
                if (!(x & 1)) { r0[2 * x + 1] = block_mean(c, c->u, x / 2, y, 2, 1); r0[2 * x + 3] = block_mean(c, c->v, x / 2, y, 2, 1); }
                break;
            case CYL_FMT_UYVY:
                r0[2 * x + 1] = c->y[k];
                if (!(x & 1)) { r0[2 * x] = block_mean(c, c->u, x / 2, y, 2, 1); r0[2 * x + 2] = block_mean(c, c->v, x / 2, y, 2, 1); }
                break;
            case CYL_FMT_NV12:
                r0[x] = c->y[k];
                if (!(x & 1) && !(y & 1)) {
                    uint8_t *r1 = (uint8_t *)img->plane[1] + (size_t)(y / 2) * img->stride[1];
                    r1[x] = block_mean(c, c->u, x / 2, y / 2, 2, 2);
                    r1[x + 1] = block_mean(c, c->v, x / 2, y / 2, 2, 2);
                }
                break;
            case CYL_FMT_I420:
                r0[x] = c->y[k];
                if (!(x & 1) && !(y & 1)) {
                    uint8_t *r1 = (uint8_t *)img->plane[1] + (size_t)(y / 2) * img->stride[1];
                    uint8_t *r2 = (uint8_t *)img->plane[2] + (size_t)(y / 2) * img->stride[2];
                    r1[x / 2] = block_mean(c, c->u, x / 2, y / 2, 2, 2);
                    r2[x / 2] = block_mean(c, c->v, x / 2, y / 2, 2, 2);
                }
                break;
            case CYL_FMT_YUV444P: {
                uint8_t *r1 = (uint8_t *)img->plane[1] + (size_t)y * img->stride[1];
                uint8_t *r2 = (uint8_t *)img->plane[2] + (size_t)y * img->stride[2];
                r0[x] = c->y[k]; r1[x] = c->u[k]; r2[x] = c->v[k];
                break;
            }
            }
        }
    }
    return 1;
}
