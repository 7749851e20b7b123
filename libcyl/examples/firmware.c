/* SPDX-License-Identifier: BSD-3-Clause */
/* A firmware's use of libcyl, linked bare-metal for a Cortex-M4 by `make cross` (newlib-nano, no
 * system calls, --gc-sections) to measure what a firmware keeps of the library: load a colour
 * table, then per frame segment it and observe the blobs, all in static memory. It is linked, not
 * run: the frame would come from the camera's DMA. */
#include "cyl/camera.h"
#include "cyl/colortable.h"
#include "cyl/image.h"
#include "cyl/observe.h"
#include "cyl/segment.h"

#define W 320
#define H 240

static uint8_t frame[W * H * 2];            /* YUYV, filled by the camera */
static uint8_t seg_mem[51216];              /* cyl_segment_mem_size(2048, 128) on 32-bit ARM
                                               (libcyl/examples/workspace.c prints it) */
static cyl_colortable table;
static cyl_observation obs[64];
extern const uint8_t table_file[];          /* a CYLT file in flash */
extern const unsigned table_file_len;
volatile uint32_t n_seen;                   /* what the firmware would send on */

int main(void)
{
    cyl_segmentation seg;
    cyl_image img;
    cyl_camera cam;
    cyl_observe_params p = cyl_observe_params_default();
    uint32_t n = 0;
    if (cyl_colortable_load(&table, table_file, table_file_len) != CYL_OK) return 1;
    cyl_camera_init(&cam);
    if (cyl_image_wrap(&img, CYL_FMT_YUYV, W, H, frame, 0) != CYL_OK) return 2;
    if (cyl_segmentation_init(&seg, seg_mem, sizeof seg_mem, 2048, 128) != CYL_OK) return 3;
    for (;;) {
        if (cyl_segment(&table, &img, 0, &seg) != CYL_OK) continue;
        /* the default (local) estimator needs no workspace: cyl_observe_work_size() is 0 */
        if (cyl_observe(&seg, &cam, &p, 0, 0, obs, 64, &n) == CYL_OK) n_seen = n;
    }
}

const uint8_t table_file[16] = {0};
const unsigned table_file_len = 16;
