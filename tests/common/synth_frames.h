/* SPDX-License-Identifier: BSD-3-Clause */
/* Synthetic YUV frames for tests and benchmarks: draw on a full-resolution
 * YUV canvas, then convert to any libcyl pixel format with any stride. */
#ifndef CYL_TEST_SYNTH_FRAMES_H
#define CYL_TEST_SYNTH_FRAMES_H
#include <stddef.h>
#include <stdint.h>
#include "cyl/image.h"
#include "rng.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct canvas { uint32_t w, h; uint8_t *y, *u, *v; } canvas;

int canvas_alloc(canvas *c, uint32_t w, uint32_t h);   /* 0 on failure */
void canvas_free(canvas *c);
void canvas_fill(canvas *c, uint8_t Y, uint8_t U, uint8_t V);
/* Clipped rectangle [x, x+w) x [y, y+h). */
void canvas_rect(canvas *c, int32_t x, int32_t y, int32_t w, int32_t h, uint8_t Y, uint8_t U, uint8_t V);
/* Clipped filled ellipse centred at (cx, cy) with semi-axes (ax, ay). */
void canvas_ellipse(canvas *c, double cx, double cy, double ax, double ay, uint8_t Y, uint8_t U, uint8_t V);
/* Add Gaussian noise of sigma levels to Y and sigma_c to U and V (clamped to 0..255). */
void canvas_noise(canvas *c, test_rng *r, double sigma_y, double sigma_c);
/* Set a fraction p of pixels to a random one of n colours (YUV triplets). */
void canvas_speckle(canvas *c, test_rng *r, double p, const uint8_t (*colours)[3], unsigned n);

/* Bytes needed to hold the canvas as `fmt` with luma row stride `stride`
 * (0 = tight), in the contiguous layout of cyl_image_wrap(). */
size_t canvas_format_size(const canvas *c, cyl_pixfmt fmt, size_t stride);
/* Convert (chroma of 4:2:x formats = the rounded mean of the covered pixels);
 * padding bytes are filled with `pad`. Fills *img. Returns 0 on failure. */
int canvas_to_format(const canvas *c, cyl_pixfmt fmt, size_t stride, uint8_t pad,
                     uint8_t *buf, size_t cap, cyl_image *img);

#ifdef __cplusplus
}
#endif
#endif
