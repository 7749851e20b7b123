/* SPDX-License-Identifier: BSD-3-Clause */
/* How much memory libcyl needs for one frame on this target: the numbers firmware sizes its
 * static buffers with. Prints a table for a 320x240 frame (or the size given as arguments). */
#include <stdio.h>
#include <stdlib.h>
#include "cyl/colortable.h"
#include "cyl/segment.h"
#include "cyl/observe.h"

int main(int argc, char **argv)
{
    uint32_t w = argc > 2 ? (uint32_t)atoi(argv[1]) : 320, h = argc > 2 ? (uint32_t)atoi(argv[2]) : 240;
    cyl_segment_params p = cyl_segment_params_default();
    uint32_t worst = cyl_segment_max_runs(w, h, &p);
    size_t frame = cyl_image_buffer_size(CYL_FMT_YUYV, w, h, 0);
    size_t typical = cyl_segment_mem_size(2048, 128), full = cyl_segment_mem_size(worst, 1024);
    size_t obs64 = 64 * sizeof(cyl_observation);
    printf("libcyl workspace for a %ux%u YUYV frame (sizeof(void*) = %u)\n", w, h, (unsigned)sizeof(void *));
    printf("  %-58s %8u B\n", "frame buffer (caller's, YUYV)", (unsigned)frame);
    printf("  %-58s %8u B\n", "colour table (cyl_colortable; may live in flash as const)", (unsigned)sizeof(cyl_colortable));
    printf("  %-58s %8u B\n", "segmentation, typical: 2048 runs, 128 blobs", (unsigned)typical);
    printf("  %-58s %8u B\n", "segmentation, never truncates: worst-case runs, 1024 blobs", (unsigned)full);
    printf("  %-58s %8u B\n", "64 observations (cyl_observation[64])", (unsigned)obs64);
    printf("  %-58s %8u B\n", "observe workspace, local estimator (default)", 0u);
    printf("  %-58s %8u B\n", "table training workspace (only while training)", (unsigned)cyl_train_workspace_size());
    printf("  sizes: cyl_run %u B, cyl_blob %u B, cyl_observation %u B, worst-case runs %u\n",
           (unsigned)sizeof(cyl_run), (unsigned)sizeof(cyl_blob), (unsigned)sizeof(cyl_observation), (unsigned)worst);
    printf("{\"workspace_typical_bytes\": %u, \"workspace_worst_bytes\": %u, \"observations64_bytes\": %u}\n",
           (unsigned)typical, (unsigned)full, (unsigned)obs64);
    return 0;
}
