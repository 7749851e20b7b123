/* SPDX-License-Identifier: BSD-3-Clause */
/* libcyl example: train a colour table from a region, segment a frame, print its blobs.
 *
 * Everything the core needs comes from the caller: the table (a plain struct),
 * the training workspace and the segmentation memory are static arrays here,
 * as they would be in firmware. The frame is generated: two cylinders (one
 * orange, one green) and a small orange distractor on a grey, noisy floor,
 * as a 640x480 YUYV image.
 */
#include <stdio.h>
#include <stdint.h>
#include <string.h>
#include "cyl/colortable.h"
#include "cyl/segment.h"

#define W 640
#define H 480
#define MAX_RUNS 20000
#define MAX_BLOBS 512

static uint8_t frame[W * H * 2];
static cyl_colortable table;
static uint32_t train_work[65536 + 256];
static uint8_t seg_mem[16 + MAX_RUNS * sizeof(cyl_run) + MAX_BLOBS * (sizeof(cyl_blob) + 64) + 64];

/* Deterministic noise: a 32-bit LCG. */
static uint32_t lcg = 12345u;
static int noise(int amp)
{
    lcg = lcg * 1664525u + 1013904223u;
    return (int)((lcg >> 24) % (2u * (unsigned)amp + 1u)) - amp;
}

static uint8_t clamp(int v) { return (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : v); }

/* Paint a rectangle of one YUV colour; grey noisy floor elsewhere. */
static void paint(int x0, int y0, int w, int h, int Y, int U, int V)
{
    int x, y;
    for (y = y0; y < y0 + h; y++)
        for (x = x0; x < x0 + w; x += 2) {
            uint8_t *p = frame + (size_t)y * W * 2 + (size_t)x * 2;
            p[0] = clamp(Y + noise(6)); p[1] = clamp(U + noise(4));
            p[2] = clamp(Y + noise(6)); p[3] = clamp(V + noise(4));
        }
}

int main(void)
{
    cyl_image img;
    cyl_segmentation seg;
    cyl_segment_params params = cyl_segment_params_default();
    cyl_roi orange_patch = { 102, 202, 20, 60 }, green_patch = { 402, 152, 16, 40 };
    uint8_t box[6];
    cyl_status s;
    uint32_t i;

    paint(0, 0, W, H, 120, 128, 128);          /* floor and walls */
    paint(100, 200, 24, 96, 150, 80, 190);     /* orange cylinder */
    paint(400, 150, 20, 64, 140, 60, 70);      /* green cylinder */
    paint(300, 380, 60, 6, 150, 80, 190);      /* orange clutter: a flat strip */
    cyl_image_wrap(&img, CYL_FMT_YUYV, W, H, frame, 0);

    /* Train the table as an operator would: one region per colour. */
    cyl_colortable_init(&table);
    cyl_colortable_set_class(&table, 0, "orange", 255, 128, 0);
    cyl_colortable_set_class(&table, 1, "green", 0, 200, 0);
    s = cyl_colortable_train(&table, 0, &img, &orange_patch, NULL, train_work, sizeof train_work, box);
    printf("trained orange: U %d-%d V %d-%d Y %d-%d (%s)\n", box[0], box[1], box[2], box[3], box[4], box[5], cyl_status_str(s));
    s = cyl_colortable_train(&table, 1, &img, &green_patch, NULL, train_work, sizeof train_work, box);
    printf("trained green:  U %d-%d V %d-%d Y %d-%d (%s)\n", box[0], box[1], box[2], box[3], box[4], box[5], cyl_status_str(s));

    s = cyl_segmentation_init(&seg, seg_mem, sizeof seg_mem, MAX_RUNS, MAX_BLOBS);
    if (s != CYL_OK) { printf("init: %s\n", cyl_status_str(s)); return 1; }
    s = cyl_segment(&table, &img, &params, &seg);
    printf("segment: %s, %u runs, %u blobs\n", cyl_status_str(s), (unsigned)seg.n_runs, (unsigned)seg.n_blobs);
    printf("%-7s %6s %9s %9s %17s %6s\n", "class", "area", "cx_px", "cy_px", "box x0,y0-x1,y1", "elong");
    for (i = 0; i < seg.n_blobs; i++) {
        const cyl_blob *b = &seg.blobs[i];
        printf("%-7s %6u %9.2f %9.2f %4u,%3u-%4u,%3u %6.2f\n", table.name[b->cls], (unsigned)b->area,
               b->cx_px, b->cy_px, b->x0, b->y0, b->x1, b->y1, b->elongation);
    }
    return s < 0 ? 1 : 0;
}
