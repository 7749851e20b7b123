/* SPDX-License-Identifier: BSD-3-Clause */
/* An out-of-tree program against an installed libcyl: segments a frame with one orange square and
 * prints the blob and the library's version (tests/install/test_install.sh builds it). */
#include <stdio.h>
#include <string.h>

#include "cyl/segment.h"
#include "cyl/observe.h"
#include "cyl/version.h"

static unsigned char frame[64 * 48 * 2];
static unsigned char mem[1 << 16];

int main(void)
{
    cyl_colortable t;
    cyl_image img;
    cyl_segmentation seg;
    cyl_segment_params p = cyl_segment_params_default();
    cyl_camera cam;
    cyl_observe_params op = cyl_observe_params_default();
    cyl_observation obs[4];
    unsigned n = 0, x, y;
    for (y = 0; y < 48; y++)
        for (x = 0; x < 64; x++) {
            int in = x >= 20 && x < 30 && y >= 10 && y < 20;
            frame[(y * 64 + x) * 2] = 128;
            frame[(y * 64 + x) * 2 + 1] = (x & 1) ? (in ? 200 : 128) : (in ? 80 : 128);
        }
    cyl_colortable_init(&t);
    cyl_colortable_add_box(&t, 0, 0, 255, 60, 100, 180, 220);
    if (strcmp(cyl_version(), CYL_VERSION_STRING) != 0) return 1;
    if (cyl_image_wrap(&img, CYL_FMT_YUYV, 64, 48, frame, 0) != CYL_OK) return 2;
    if (cyl_segmentation_init(&seg, mem, sizeof mem, 256, 16) != CYL_OK) return 3;
    if (cyl_segment(&t, &img, &p, &seg) != CYL_OK || seg.n_blobs != 1) return 4;
    cyl_camera_init(&cam);
    cam.width = 64; cam.height = 48; cam.fx_px = cam.fy_px = 60; cam.cx_px = 32; cam.cy_px = 24;
    cam.tilt_rad = 0.3; cam.height_m = 0.3;
    if (cyl_observe(&seg, &cam, &op, NULL, 0, obs, 4, &n) != CYL_OK || n != 1) return 5;
    printf("libcyl %s: blob area %u at (%.1f, %.1f), range %.3f m\n", cyl_version(), seg.blobs[0].area,
           seg.blobs[0].cx_px, seg.blobs[0].cy_px, obs[0].range_m);
    return 0;
}
